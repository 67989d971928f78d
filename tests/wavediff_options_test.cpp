// dpc31 wavediff (docs/wavediff.md), its options and outputs: tolerance, X/Z policies, windows,
// the diff VCD and WaveDrom outputs, malformed input, FST, the hand-written data pair, the command
// line and streaming. Every expected time, cycle and value is worked out by hand next to it.
#include "run_command.hpp"
#include "wavediff_model.hpp"

using namespace wavediff_test;

TEST(WavediffTolerance, ShiftedEdgesInTimeAndCycles) {
  Dir d;
  const std::string head =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! d $end\n"
      "$var wire 1 \" clk $end\n$upscope $end\n$enddefinitions $end\n";
  // A: d rises at 100, falls at 200. B: 3 ns later each time. Differences [100,103) and
  // [200,203): 3 ns each.
  const auto a = d.write("a.vcd", head + "#0\n0!\n#100\n1!\n#200\n0!\n#300\n");
  const auto b = d.write("b.vcd", head + "#0\n0!\n#103\n1!\n#203\n0!\n#300\n");
  Options o = opts(a, b);
  Report r = compare(o);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].count, 2u);
  EXPECT_EQ(r.diffs[0].first.at.time, 100u);
  EXPECT_EQ(r.diffs[0].last.time, 200u);
  o.tolerance_fs = 5'000'000;  // 5 ns
  EXPECT_EQ(run_opts(o).rc, 0);
  o.tolerance_fs = 3'000'000;  // exactly the shift: still within
  EXPECT_EQ(run_opts(o).rc, 0);
  o.tolerance_fs = 2'000'000;
  EXPECT_EQ(run_opts(o).rc, 1);
  // B stuck at 1: different over [0,100) (dropped with a 1 us tolerance) and from 200 to the
  // end, which never goes away and is reported whatever the tolerance.
  const auto c = d.write("c.vcd", head + "#0\n1!\n#300\n");
  o.file_b = c;
  o.tolerance_fs = 1'000'000'000;
  r = compare(o);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].count, 1u);
  EXPECT_EQ(r.diffs[0].first.at.time, 200u);
  EXPECT_TRUE(r.diffs[0].first.open);

  // Clock mode: A's d rises at edge 5 (sampled 1 from cycle 5), B's at edge 6: one cycle.
  std::string ca = head + "#0\n0!\n0\"\n";
  std::string cb = ca;
  for (int k = 0; k < 10; ++k) {
    ca += fmt::format("#{}\n1\"\n{}", 10 * k + 5, k == 5 ? "1!\n" : "");
    cb += fmt::format("#{}\n1\"\n{}", 10 * k + 5, k == 6 ? "1!\n" : "");
    ca += fmt::format("#{}\n0\"\n", 10 * k + 10);
    cb += fmt::format("#{}\n0\"\n", 10 * k + 10);
  }
  Options oc = opts(d.write("ca.vcd", ca), d.write("cb.vcd", cb));
  oc.clock_a = "top.clk";
  r = compare(oc);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].first.at.cycle, 5u);
  EXPECT_EQ(r.diffs[0].first.a, "1");
  EXPECT_EQ(r.diffs[0].first.b, "0");
  oc.tolerance_cycles = 1;
  EXPECT_EQ(run_opts(oc).rc, 0);
  // Tolerance of the wrong kind for the mode: bad input.
  oc.tolerance_fs = 1000;
  EXPECT_EQ(run_opts(oc).rc, 2);
  // An option of clock mode without --clock: the library's message is bare (Python raises it as
  // it is), its report prefixes the command's name once (docs/bad-input.md).
  for (const bool clock_b : {true, false}) {
    Options e = opts(oc.file_a, oc.file_b);
    if (clock_b) e.clock_b = "top.clk";
    if (!clock_b) e.tolerance_cycles = 1;
    const std::string what =
        clock_b ? "--clock-b requires --clock" : "--tolerance-cycles requires --clock";
    try {
      (void)compare(e);
      ADD_FAILURE() << what;
    } catch (const OptionError& x) {
      EXPECT_EQ(std::string(x.what()), what);
    }
    const Outcome r = run_opts(e);
    EXPECT_EQ(r.rc, 2);
    EXPECT_EQ(r.err, "dpc31 wavediff: " + what + "\n");
  }
  // A --json that cannot be written: the file's own style, as --diff-vcd's and --wavedrom's (the
  // file's name first, no prefix; docs/decisions.md), nothing compared.
  Options j = opts(oc.file_a, oc.file_b);
  j.json_file = d.file("no/such/dir/r.json");
  const Outcome rj = run_opts(j);
  EXPECT_EQ(rj.rc, 2);
  EXPECT_EQ(rj.out, "");
  EXPECT_TRUE(rj.err.starts_with(j.json_file + ": cannot create the temporary file ")) << rj.err;
  EXPECT_EQ(rj.err.find("dpc31 wavediff: "), std::string::npos) << rj.err;
}

TEST(WavediffXz, StrictWildcardZero) {
  Dir d;
  const std::string head =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! d $end\n"
      "$var wire 4 \" v [3:0] $end\n$upscope $end\n$enddefinitions $end\n";
  auto cmp = [&](const std::string& a, const std::string& b, XzPolicy p) {
    Options o = opts(d.write("a.vcd", head + a), d.write("b.vcd", head + b));
    o.xz = p;
    return run_opts(o).rc;
  };
  // d: x in A where B has 1; then both 1.
  const std::string a1 = "#0\nx!\nb0000 \"\n#10\n1!\n";
  const std::string b1 = "#0\n1!\nb0000 \"\n#10\n1!\n";
  EXPECT_EQ(cmp(a1, b1, XzPolicy::strict), 1);
  EXPECT_EQ(cmp(a1, b1, XzPolicy::wildcard), 0);
  EXPECT_EQ(cmp(a1, b1, XzPolicy::zero), 1);  // x reads 0, B has 1
  // x against 0: the same under zero.
  const std::string b0 = "#0\n0!\nb0000 \"\n#10\n1!\n";
  EXPECT_EQ(cmp(a1, b0, XzPolicy::zero), 0);
  EXPECT_EQ(cmp(a1, b0, XzPolicy::strict), 1);
  // z against x: different when strict, same otherwise.
  const std::string az = "#0\nz!\nb0000 \"\n";
  const std::string ax = "#0\nx!\nb0000 \"\n";
  EXPECT_EQ(cmp(az, ax, XzPolicy::strict), 1);
  EXPECT_EQ(cmp(az, ax, XzPolicy::wildcard), 0);
  EXPECT_EQ(cmp(az, ax, XzPolicy::zero), 0);
  // Vectors bit by bit: 1x0z against 1100 and 1000.
  const std::string av = "#0\n0!\nb1x0z \"\n";
  const std::string b1100 = "#0\n0!\nb1100 \"\n";
  const std::string b1000 = "#0\n0!\nb1000 \"\n";
  EXPECT_EQ(cmp(av, b1100, XzPolicy::strict), 1);
  EXPECT_EQ(cmp(av, b1100, XzPolicy::wildcard), 0);
  EXPECT_EQ(cmp(av, b1100, XzPolicy::zero), 1);  // 1000 against 1100
  EXPECT_EQ(cmp(av, b1000, XzPolicy::zero), 0);
  // Extension: "bx" fills the vector with x; "b1" with zeros on the left.
  EXPECT_EQ(cmp("#0\n0!\nbx \"\n", "#0\n0!\nbxxxx \"\n", XzPolicy::strict), 0);
  EXPECT_EQ(cmp("#0\n0!\nb1 \"\n", "#0\n0!\nb0001 \"\n", XzPolicy::strict), 0);
}

TEST(WavediffWindow, StartAndEndInTimeAndCycles) {
  Dir d;
  // cnt differs from 75 to 85 ns (edge 7 only).
  const auto [a, b] = counters_aa_at_7(d);
  Options o = opts(a, b);
  std::string why;
  Bound bd;
  ASSERT_TRUE(parse_bound("70ns", bd, why));
  o.end = bd;
  EXPECT_EQ(run_opts(o).rc, 0);
  o.end.reset();
  ASSERT_TRUE(parse_bound("0.09us", bd, why));  // 90 ns
  EXPECT_EQ(bd.value, 90'000'000u);
  o.start = bd;
  EXPECT_EQ(run_opts(o).rc, 0);
  // Starting inside the difference: reported at the start of the window, 78 ns.
  ASSERT_TRUE(parse_bound("78ns", bd, why));
  o.start = bd;
  Report r = compare(o);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].first.at.time, 78u);
  // Cycles in clock mode.
  o.start.reset();
  o.clock_a = "top.clk";
  ASSERT_TRUE(parse_bound("c6", bd, why));
  o.end = bd;
  EXPECT_EQ(run_opts(o).rc, 0);
  ASSERT_TRUE(parse_bound("c8", bd, why));
  o.end.reset();
  o.start = bd;
  EXPECT_EQ(run_opts(o).rc, 0);
  ASSERT_TRUE(parse_bound("c7", bd, why));
  o.start = bd;
  o.end = bd;
  r = compare(o);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].first.at.cycle, 7u);
  EXPECT_EQ(r.edges, 1u);
  // Parsing.
  EXPECT_FALSE(parse_bound("100", bd, why));
  EXPECT_FALSE(parse_bound("5 parsecs", bd, why));
  EXPECT_FALSE(parse_bound("1.5fs", bd, why));
  EXPECT_FALSE(parse_bound("cx", bd, why));
  ASSERT_TRUE(parse_bound("2us", bd, why));
  EXPECT_EQ(bd.value, 2'000'000'000u);
  ASSERT_TRUE(parse_bound("5ms", bd, why));
  EXPECT_EQ(bd.value, 5'000'000'000'000u);
  // Cycle bounds need a clock.
  o.clock_a.clear();
  EXPECT_EQ(run_opts(o).rc, 2);
}

TEST(WavediffOutputs, DiffVcdParsesBack) {
  Dir d;
  const auto [a, b] = counters_aa_at_7(d);
  Options o = opts(a, b);
  o.diff_vcd = d.file("diff.vcd");
  EXPECT_EQ(run_opts(o).rc, 1);
  auto r = open_wave(o.diff_vcd);
  EXPECT_EQ(r->timescale_pow(), 6);
  std::map<std::string, std::uint32_t> slot;
  for (const Var& v : r->vars()) slot[v.name] = v.slot;
  for (const char* n : {"a.top.clk", "a.top.cnt", "a.top.flag", "b.top.clk", "b.top.cnt",
                        "b.top.flag", "diff.top.clk", "diff.top.cnt", "diff.top.flag"}) {
    EXPECT_EQ(slot.count(n), 1u) << n;
  }
  EXPECT_EQ(slot.size(), 9u);
  // Walk it: the flag of cnt is 1 exactly from 75 to 85 ns; a and b carry the two values.
  std::map<std::uint64_t, std::string> flag;
  std::map<std::uint64_t, std::string> bval;
  while (r->has_next()) {
    r->step();
    flag[r->time()] = r->slots()[slot["diff.top.cnt"]].bits;
    bval[r->time()] = r->slots()[slot["b.top.cnt"]].bits;
    EXPECT_EQ(r->slots()[slot["diff.top.clk"]].bits, "0");
  }
  EXPECT_EQ(flag[70], "0");
  EXPECT_EQ(flag[75], "1");
  EXPECT_EQ(flag[80], "1");
  EXPECT_EQ(flag[85], "0");
  EXPECT_EQ(bval[75], "10101010");
  EXPECT_EQ(flag.rbegin()->first, 120u);

  // Clock mode: the time axis is A's edge times, with the cycle number beside it.
  o.clock_a = "top.clk";
  EXPECT_EQ(run_opts(o).rc, 1);
  auto rc = open_wave(o.diff_vcd);
  std::uint32_t cyc = 0;
  std::uint32_t f = 0;
  for (const Var& v : rc->vars()) {
    if (v.name == "wavediff.cycle") cyc = v.slot;
    if (v.name == "diff.top.cnt") f = v.slot;
  }
  std::map<std::uint64_t, std::string> cycles;
  std::map<std::uint64_t, std::string> flags;
  while (rc->has_next()) {
    rc->step();
    cycles[rc->time()] = rc->slots()[cyc].bits;
    flags[rc->time()] = rc->slots()[f].bits;
  }
  EXPECT_EQ(cycles.size(), 12u);
  EXPECT_EQ(cycles[75], bin(7, 32));
  EXPECT_EQ(flags[75], "1");
  EXPECT_EQ(flags[85], "0");
}

TEST(WavediffOutputs, WavedromAroundTheFirstDivergence) {
  Dir d;
  const auto [a, b] = counters_aa_at_7(d);
  Options o = opts(a, b);
  o.wavedrom = d.file("w.json");
  o.wavedrom_window = 3;
  EXPECT_EQ(run_opts(o).rc, 1);
  const auto j = nlohmann::json::parse(slurp(o.wavedrom));
  ASSERT_TRUE(j.contains("signal"));
  const auto& s = j["signal"];
  ASSERT_EQ(s.size(), 4u);
  // Events are every 5 ns; three before 75, 75, three after.
  EXPECT_EQ(s[0]["name"], "time");
  EXPECT_EQ(s[0]["data"], nlohmann::json({"60ns", "65ns", "70ns", "75ns", "80ns", "85ns", "90ns"}));
  EXPECT_EQ(s[1]["name"], "top.cnt (a)");
  EXPECT_EQ(s[1]["wave"], "==.=.=.");  // 6, 7, 7, 8, 8, 9, 9
  EXPECT_EQ(s[1]["data"], nlohmann::json({"0x06", "0x07", "0x08", "0x09"}));
  EXPECT_EQ(s[2]["name"], "top.cnt (b)");
  EXPECT_EQ(s[2]["data"], nlohmann::json({"0x06", "0x07", "0xaa", "0x09"}));
  EXPECT_EQ(s[3]["name"], "top.cnt (diff)");
  EXPECT_EQ(s[3]["wave"], "0..1.0.");
  EXPECT_EQ(j["head"]["text"], "first divergence: top.cnt at 75ns");

  // Clock mode: cycles 4..10 around cycle 7.
  o.clock_a = "top.clk";
  EXPECT_EQ(run_opts(o).rc, 1);
  const auto jc = nlohmann::json::parse(slurp(o.wavedrom));
  EXPECT_EQ(jc["signal"][0]["name"], "cycle");
  EXPECT_EQ(jc["signal"][0]["data"], nlohmann::json({"4", "5", "6", "7", "8", "9", "10"}));
  EXPECT_EQ(jc["signal"][3]["wave"], "0..10..");
}

TEST(WavediffMalformed, OneLineErrorWithFileAndLine) {
  Dir d;
  const std::string good = render(counter(2), {});
  const auto ok = d.write("ok.vcd", good);
  struct Case {
    const char* name;
    std::string content;
    std::string expect;  // after "file:"
  };
  const std::string head =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! a $end\n"
      "$var wire 4 \" v [3:0] $end\n$upscope $end\n$enddefinitions $end\n";  // 6 lines
  const std::vector<Case> cases = {
      {"empty", "", "1: empty file"},
      {"blank", "  \n\n", "1: empty file"},
      {"truncated_header", "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! a $end\n",
       "3: truncated: end of file in the header (no $enddefinitions)"},
      {"truncated_var", "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! a",
       "3: truncated: end of file inside $var (from line 3)"},
      {"truncated_line", head + "#0\n0!\nb0000 \"\n#10\n1!\nb0101 \"",
       "12: truncated: the last line has no end of line"},
      {"truncated_vector", head + "#0\n0!\nb0000 \"\n#10\nb0101\n",
       "11: truncated: vector value without identifier"},
      {"truncated_dumpvars", head + "#0\n$dumpvars\n0!\n",
       "9: truncated: $dumpvars from line 8 not closed by $end"},
      {"undeclared", head + "#0\n0!\n#5\n1%\n", "10: undeclared identifier '%'"},
      {"bad_timescale", "$timescale 3 ns $end\n$enddefinitions $end\n",
       "1: bad timescale '3ns' (1, 10 or 100 of s ms us ns ps fs)"},
      {"bad_timescale_unit", "$timescale 1 ks $end\n$enddefinitions $end\n",
       "1: bad timescale '1ks' (1, 10 or 100 of s ms us ns ps fs)"},
      {"backwards", head + "#0\n0!\n#20\n1!\n#10\n0!\n", "11: time goes backwards (#10 after 20)"},
      {"garbage", head + "#0\n0!\nhello world\n", "9: unexpected 'hello'"},
      {"garbage_vector", head + "#0\nb01q2 \"\n", "8: bad vector value 'b01q2'"},
      {"garbage_time", head + "#0\n0!\n#1x\n", "9: bad time '#1x'"},
      {"garbage_header", "hello\n", "1: unexpected 'hello' in the header"},
      {"too_wide", head + "#0\nb10000 \"\n", "8: value of 5 bits for '\"' declared with 4"},
  };
  for (const Case& c : cases) {
    const auto f = d.write(std::string(c.name) + ".vcd", c.content);
    for (bool as_a : {true, false}) {
      const Outcome r = run_opts(as_a ? opts(f, ok) : opts(ok, f));
      EXPECT_EQ(r.rc, 2) << c.name;
      EXPECT_EQ(r.err, f + ":" + c.expect + "\n") << c.name;
      EXPECT_EQ(r.out, "") << c.name;
    }
  }
  const Outcome m = run_opts(opts(d.file("missing.vcd"), ok));
  EXPECT_EQ(m.rc, 2);
  EXPECT_EQ(m.err, d.file("missing.vcd") + ":0: cannot open: No such file or directory\n");
  const Outcome dir = run_opts(opts(ok, d.file("")));
  EXPECT_EQ(dir.rc, 2);
  // Not an FST although it starts like one.
  const auto fake = d.write("fake.fst", std::string("\0garbage", 8));
  const Outcome ff = run_opts(opts(fake, ok));
  EXPECT_EQ(ff.rc, 2);
  EXPECT_EQ(ff.err, fake + ":0: not a readable FST file\n");
}

TEST(WavediffFst, VcdAgainstItsVcd2fstConversion) {
  Dir d;
  const std::string tool = vcd2fst();
  ASSERT_TRUE(fs::exists(tool)) << "vcd2fst not found: install Debian's gtkwave (setup.sh does)";
  const auto a = d.write("a.vcd", render(counter(40, 10, nullptr, true), {}));
  const auto f = d.file("a.fst");
  ASSERT_EQ(spawn({tool, a, f}), 0);
  EXPECT_EQ(run_opts(opts(a, f)).rc, 0);
  EXPECT_EQ(run_opts(opts(f, a)).rc, 0);
  EXPECT_EQ(run_opts(opts(f, f)).rc, 0);
  {
    auto r = open_wave(f);
    EXPECT_STREQ(r->format(), "fst");
    EXPECT_EQ(r->timescale_pow(), 6);
  }
  // A difference against the FST: the same time and values as VCD against VCD.
  const auto b = d.write("b.vcd", render(counter(40, 10, cnt_aa_at_7, true), {}));
  const Report r = compare(opts(f, b));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].name, "top.cnt");
  EXPECT_EQ(r.diffs[0].first.at.time, 75u);
  EXPECT_EQ(r.diffs[0].first.a, "00001000");
  EXPECT_EQ(r.diffs[0].first.b, "10101010");
  // Split bits and another timescale through FST too, in clock mode against a 1 ps VCD.
  Style split;
  split.split = true;
  split.timescale = "10ps";
  split.mult = 100;
  const auto s = d.write("s.vcd", render(counter(40, 10, nullptr, true), split));
  const auto sf = d.file("s.fst");
  ASSERT_EQ(spawn({tool, s, sf}), 0);
  EXPECT_EQ(run_opts(opts(a, sf)).rc, 0);
  Options oc = opts(sf, b);
  oc.clock_a = "top.clk";
  const Report rc = compare(oc);
  ASSERT_EQ(rc.diffs.size(), 1u);
  EXPECT_EQ(rc.diffs[0].first.at.cycle, 7u);
  // --end lets the FST reader stop early; the result is the same.
  Options oe = opts(f, b);
  Bound e;
  std::string why;
  ASSERT_TRUE(parse_bound("100ns", e, why));
  oe.end = e;
  EXPECT_EQ(compare(oe).diffs.size(), 1u);
}

TEST(WavediffData, HandWrittenPairWithStripMapAndSplitBits) {
  // tests/data/wavediff: an emulator-style dump (tb.dut, 1 ns, vectors, an alias) and an
  // RTL-style dump (TOP, 1 ps, split bits, other names and id codes) of the same 6 cycles.
  const std::string dir = WAVEDIFF_DATA;
  Options o = opts(dir + "/emu.vcd", dir + "/rtl.vcd");
  o.strip_auto = true;
  o.map_file = dir + "/emu_rtl.map";
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("compared 6 signals: 0 differ, 0 only in A, 0 only in B"), std::string::npos)
      << r.out;
  o.clock_a = "clk";
  EXPECT_EQ(run_opts(o).rc, 0);
  // The RTL dump with a bug: x_int falls at edge 4 instead of edge 3, so the samples of cycle 3
  // differ (A 0, B 1) and agree again from cycle 4.
  o.file_b = dir + "/rtl_late_irq.vcd";
  const Outcome late = run_opts(o);
  EXPECT_EQ(late.rc, 1);
  EXPECT_NE(late.out.find("first divergence: x_int at cycle 3 (A 70ns, #70; B 70ns, "
                          "#70000): A=0 B=1, last common 1"),
            std::string::npos)
      << late.out;
  o.tolerance_cycles = 1;
  EXPECT_EQ(run_opts(o).rc, 0);
}

// Clock mode names each edge by its own time in its file (s34 audit, finding 11: B's time was the
// common time in B's units, rounded). A: 1 ns, clk rises at #5, #15, #25; B: 1 ps, the same
// clock 645 ps later in each period (#5645, #15645, #25645: 5.645 ns, common time 6 ns). d
// differs at the second edge (cycle 1): "B 16ns, #15645", not #16000.
TEST(WavediffReport, ClockModeGivesEachFilesOwnEdgeTime) {
  Dir d;
  const auto head = [](const char* unit) {
    return std::string("$timescale ") + unit +
           " $end\n$scope module top $end\n$var wire 1 ! d $end\n"
           "$var wire 1 \" clk $end\n$upscope $end\n$enddefinitions $end\n";
  };
  const auto a = d.write("a.vcd", head("1ns") +
                                      "#0\n0!\n0\"\n#5\n1\"\n#10\n0\"\n#15\n1\"\n#20\n0\"\n"
                                      "#25\n1\"\n#30\n0\"\n");
  const auto b = d.write("b.vcd", head("1ps") +
                                      "#0\n0!\n0\"\n#5645\n1\"\n#10000\n1!\n0\"\n#15645\n1\"\n"
                                      "#20000\n0\"\n#25645\n1\"\n#30000\n0\"\n");
  Options o = opts(a, b);
  o.clock_a = "top.clk";
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_NE(r.out.find("first divergence: top.d at cycle 1 (A 15ns, #15; B 16ns, #15645): A=0 B=1"),
            std::string::npos)
      << r.out;
}

// docs/wavediff.md, "Report": its command, run in tests/data/wavediff as it says, prints exactly
// the report it shows, exit 1 (different; the divergence worked out in the test above).
TEST(WavediffCli, TheReportExampleOfTheDocs) {
  const std::string doc = slurp(std::string(WAVEDIFF_DATA) + "/../../../docs/wavediff.md");
  const std::size_t report = doc.find("\n## Report\n");
  const std::size_t cmd = doc.find("```sh\ndpc31 ", report) + 6;
  const std::size_t cmd_end = doc.find('\n', cmd);
  const std::size_t out = doc.find("```\n", cmd_end) + 4;
  const std::size_t out_from = doc.find("```\n", out) + 4;
  const std::size_t out_to = doc.find("```", out_from);
  ASSERT_NE(report, std::string::npos);
  ASSERT_NE(out_to, std::string::npos);
  const std::string command = doc.substr(cmd, cmd_end - cmd);
  const auto r = testutil::run_command(fmt::format("cd {} && {} {} 2>&1", WAVEDIFF_DATA, DPC31_CLI,
                                                   command.substr(command.find(' ') + 1)));
  EXPECT_EQ(r.rc, 1) << command;
  EXPECT_EQ(r.out, doc.substr(out_from, out_to - out_from)) << command;
}

TEST(WavediffCli, ThroughTheDpc31Binary) {
  Dir d;
  const auto [a, b] = counters_aa_at_7(d);
  const std::string cli = DPC31_CLI;
  EXPECT_EQ(spawn({cli, "wavediff", a, a}), 0);
  const auto out = d.file("out.txt");
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--json", d.file("r.json")}, nullptr, out), 1);
  EXPECT_NE(slurp(out).find("first divergence: top.cnt at 75ns"), std::string::npos);
  EXPECT_EQ(nlohmann::json::parse(slurp(d.file("r.json")))["first_divergence"]["time"], 75);
  // Repeated --include before the positionals.
  EXPECT_EQ(spawn({cli, "wavediff", "--include", "top.clk", "--include", "top.f*", a, b}), 0);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--exclude", "*cnt"}), 0);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--clock", "top.clk", "--end", "c6"}), 0);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--tolerance", "10ns"}), 0);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--tolerance", "10"}, nullptr, out), 2);
  EXPECT_EQ(slurp(out),
            "dpc31 wavediff: --tolerance: '10' is not a time (a number and s, ms, us, ns, ps or "
            "fs; e.g. 100ns)\n");
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--xz", "maybe"}), 2);
  EXPECT_EQ(spawn({cli, "wavediff", a}), 2);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--start", "c3"}, nullptr, out), 2);
  EXPECT_EQ(slurp(out), "dpc31 wavediff: cycle bounds (c123) need --clock\n");
  EXPECT_EQ(spawn({cli, "wavediff", a, d.file("nope.vcd")}, nullptr, out), 2);
  EXPECT_EQ(slurp(out), d.file("nope.vcd") + ":0: cannot open: No such file or directory\n");
  // The same parser in-process.
  CLI::App app;
  CliArgs args;
  add_subcommand(app, args);
  std::vector<std::string> argv = {"wavediff", a,         b,         "--clock", "top.clk",
                                   "--edge",   "falling", "--start", "c2",      "--xz",
                                   "zero",     "--strip", "auto"};
  std::reverse(argv.begin(), argv.end());
  app.parse(argv);
  EXPECT_EQ(args.opt.file_a, a);
  EXPECT_EQ(args.opt.clock_a, "top.clk");
  EXPECT_EQ(args.edge, "falling");
  EXPECT_EQ(args.start, "c2");
  EXPECT_EQ(args.strip, "auto");
}

// ---------------------------------------------------------------------------------------------
// Streaming: memory does not grow with the file.

TEST(WavediffStreaming, FiftyMegabytesInBoundedMemory) {
  Dir d;
  const auto a = d.file("big_a.vcd");
  const auto b = d.file("big_b.vcd");
  std::string error;
  // One bit of one vector differs at step 400000.
  ASSERT_TRUE(write_synthetic_vcd_pair(a, b, {520'000, {400'000}}, error)) << error;
  const auto size = fs::file_size(a);
  EXPECT_GT(size, 50'000'000u);
  long rss = 0;
  const auto out = d.file("out.txt");
  const int rc = spawn({DPC31_CLI, "wavediff", a, b, "--json", d.file("r.json")}, &rss, out);
  EXPECT_EQ(rc, 1) << slurp(out);
  const auto j = nlohmann::json::parse(slurp(d.file("r.json")));
  EXPECT_EQ(j["first_divergence"]["time"], 4'000'000);  // step 400000 at 10 ps a step
  // wait4's peak RSS of the child also counts what the forked test process had resident (a few
  // MiB), so this is an upper bound; under AddressSanitizer that is the shadow memory: no bound.
#if !defined(__SANITIZE_ADDRESS__)
  EXPECT_LT(rss, 64 * 1024) << "peak RSS " << rss << " KiB";
#endif
  // Throughput is measured in bench/bench_wavediff.cpp (BM_WavediffLargePair), not here.
}
