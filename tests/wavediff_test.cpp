// dpc31 wavediff (docs/wavediff.md). Waveforms are generated here from small models or read from
// tests/data/wavediff/; every expected time, cycle and value is worked out by hand in the comment
// next to it.
#include "wavediff_model.hpp"

using namespace wavediff_test;

// ---------------------------------------------------------------------------------------------

TEST(WavediffBasic, IdenticalFilesExitZero) {
  Dir d;
  const Model m = counter(12);
  const auto a = d.write("a.vcd", render(m, {}));
  // Same run, other identifier codes and declaration order: a textual diff would differ.
  Style other;
  other.id_base = 40;
  other.reverse = true;
  const auto b = d.write("b.vcd", render(m, other));
  ASSERT_NE(slurp(a), slurp(b));
  const Outcome r = run_opts(opts(a, b));
  EXPECT_EQ(r.rc, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("compared 3 signals: 0 differ"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("result: same"), std::string::npos);
  EXPECT_EQ(run_opts(opts(a, a)).rc, 0);
}

TEST(WavediffBasic, OneBitDifferenceAtKnownTime) {
  Dir d;
  // flag is bit 2 of k+1 (k+1 = 4..7 set it): it rises at edge 3 (t = 35) and falls at edge 7
  // (t = 75), and k+1 = 9, 10 keep it 0. In B it rises at edge 3 too but never falls: the first
  // difference is at 75 ns, A=0 B=1, last common 1, and it lasts to the end.
  Model ma = counter(10);
  Model mb = counter(10);
  for (auto& [t, ch] : mb.at) {
    std::erase_if(ch, [t = t](const auto& c) { return c.first == 2 && t >= 75; });
  }
  const auto a = d.write("a.vcd", render(ma, {}));
  const auto b = d.write("b.vcd", render(mb, {}));
  Options o = opts(a, b);
  o.json_file = d.file("r.json");
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("first divergence: top.flag at 75ns (A #75, B #75): A=0 B=1, last common 1"),
            std::string::npos)
      << r.out;
  const auto j = nlohmann::json::parse(slurp(o.json_file));
  EXPECT_EQ(j["result"], "different");
  EXPECT_EQ(j["exit_code"], 1);
  EXPECT_EQ(j["first_divergence"]["signal"], "top.flag");
  EXPECT_EQ(j["first_divergence"]["time"], 75);
  EXPECT_EQ(j["first_divergence"]["time_text"], "75ns");
  EXPECT_EQ(j["first_divergence"]["a"], "0");
  EXPECT_EQ(j["first_divergence"]["b"], "1");
  EXPECT_EQ(j["first_divergence"]["last_common"], "1");
  EXPECT_EQ(j["first_divergence"]["open"], true);
  ASSERT_EQ(j["signals"].size(), 1u);
  EXPECT_EQ(j["signals"][0]["count"], 1);
}

TEST(WavediffBasic, VectorDifferenceGroupedPerSignal) {
  Dir d;
  // cnt differs at edges 2 and 7 (t = 25 and 75), each for one edge: two divergences, and a
  // 1-bit flag nowhere.
  const auto a = d.write("a.vcd", render(counter(10), {}));
  const auto b = d.write(
      "b.vcd", render(counter(10, 10,
                              [](int k) {
                                return k == 2 || k == 7 ? 0xAAu : static_cast<std::uint64_t>(k + 1);
                              }),
                      {}));
  const Report r = compare(opts(a, b));
  ASSERT_EQ(r.diffs.size(), 1u);
  const SignalDiff& s = r.diffs[0];
  EXPECT_EQ(s.name, "top.cnt");
  EXPECT_EQ(s.count, 2u);
  EXPECT_EQ(s.first.at.time, 25u);
  EXPECT_EQ(s.first.a, "00000011");
  EXPECT_EQ(s.first.b, "10101010");
  EXPECT_EQ(s.first.last_common, "00000010");
  EXPECT_FALSE(s.first.open);
  EXPECT_EQ(s.last.time, 75u);
}

TEST(WavediffTimescale, PsAndNsOfTheSameRunAreTheSame) {
  Dir d;
  const Model m = counter(12);
  const auto ns = d.write("ns.vcd", render(m, {}));
  Style ps;
  ps.timescale = "1 ps";
  ps.mult = 1000;
  const auto p = d.write("ps.vcd", render(m, ps));
  Style hps;
  hps.timescale = "100ps";
  hps.mult = 10;
  const auto h = d.write("100ps.vcd", render(m, hps));
  EXPECT_EQ(run_opts(opts(ns, p)).rc, 0);
  EXPECT_EQ(run_opts(opts(p, ns)).rc, 0);
  EXPECT_EQ(run_opts(opts(h, ns)).rc, 0);
  // A difference is reported in the coarser unit and in each file's own units.
  const auto pd = d.write("ps_diff.vcd", render(counter(12, 10, cnt_aa_at_7), ps));
  const Report r = compare(opts(ns, pd));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.pow, 6);                       // 1 ns
  EXPECT_EQ(r.diffs[0].first.at.time, 75u);  // 75 ns
  EXPECT_EQ(time_text(75, r.pow), "75ns");
  EXPECT_EQ(file_time(75, r.pow, r.pow_a), "75");
  EXPECT_EQ(file_time(75, r.pow, r.pow_b), "75000");
  EXPECT_EQ(file_time(1500, 3, 6), "1.5");
}

// The finer file's changes that round to one time of the coarser unit are applied together: B's a
// at 10 ns and b at 10.4 ns are both at #10 of A; the diff VCD got #10 twice, with b differing
// between them.
TEST(WavediffTimescale, ChangesAtOneCommonTimeAreOnePoint) {
  Dir d;
  const std::string head =
      "$timescale {} $end\n$scope module top $end\n$var wire 1 ! a $end\n$var wire 1 \" b "
      "$end\n$upscope $end\n$enddefinitions $end\n#0\n0!\n0\"\n";
  const auto a = d.write("a.vcd", fmt::format(fmt::runtime(head), "1ns") + "#10\n1!\n1\"\n#20\n");
  const auto b = d.write(
      "b.vcd", fmt::format(fmt::runtime(head), "1ps") + "#10000\n1!\n#10400\n1\"\n#20000\n");
  Options o = opts(a, b);
  o.diff_vcd = d.file("diff.vcd");
  EXPECT_TRUE(compare(o).same());
  const std::string v = slurp(o.diff_vcd);
  EXPECT_EQ(v.find("#10\n"), v.rfind("#10\n")) << v;
}

namespace {
// A file in picoseconds: model time x 1000.
Style picoseconds() {
  Style ps;
  ps.timescale = "1ps";
  ps.mult = 1000;
  return ps;
}
}  // namespace

TEST(WavediffClock, DifferentTimeBasesSampleTheSame) {
  Dir d;
  // A: period 10 ns in a 1 ns file; B: period 20 ns in a 1 ps file. Event mode sees differences
  // everywhere; on the clock the two runs are the same, cycle by cycle.
  const auto a = d.write("a.vcd", render(counter(12), {}));
  const auto b = d.write("b.vcd", render(counter(12, 20), picoseconds()));
  EXPECT_EQ(run_opts(opts(a, b)).rc, 1);
  Options o = opts(a, b);
  o.clock_a = "top.clk";
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 0) << r.out << r.err;
  const Report rep = compare(o);
  EXPECT_EQ(rep.edges, 12u);
  EXPECT_EQ(rep.compared, 2u);  // cnt and flag; the clock itself is not compared
}

TEST(WavediffClock, DifferenceAtEdgeSevenIsCycleSeven) {
  Dir d;
  const auto a = d.write("a.vcd", render(counter(12), {}));
  const auto b = d.write("b.vcd", render(counter(12, 20, cnt_aa_at_7), picoseconds()));
  Options o = opts(a, b);
  o.clock_a = "top.clk";
  o.json_file = d.file("r.json");
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 1) << r.out;
  // Edge 7 (counting from 0): A at 10*7+5 = 75 ns, B at 20*7+10 = 150 ns = 150000 ps. The values
  // sampled after the edge: A 8, B 0xAA; before it both had 7. Times in the coarser unit, ns.
  EXPECT_NE(r.out.find("first divergence: top.cnt at cycle 7 (A 75ns, #75; B 150ns, "
                       "#150000): A=00001000 (0x08) B=10101010 (0xaa), last common 00000111"),
            std::string::npos)
      << r.out;
  const auto j = nlohmann::json::parse(slurp(o.json_file));
  EXPECT_EQ(j["mode"], "clock");
  EXPECT_EQ(j["first_divergence"]["cycle"], 7);
  EXPECT_EQ(j["first_divergence"]["time_a"], "75");
  EXPECT_EQ(j["first_divergence"]["time_b"], "150000");
  EXPECT_EQ(j["signals"][0]["count"], 1);
  EXPECT_EQ(j["first_divergence"]["open"], false);

  // Falling edges: falling edge j is at 10(j+1) in A; the one at 80 (j = 7) sees 8 vs 0xAA.
  o.edge = Edge::falling;
  Report rf = compare(o);
  ASSERT_EQ(rf.diffs.size(), 1u);
  EXPECT_EQ(rf.diffs[0].first.at.cycle, 7u);
  // Both edges: rising k is edge 2k, so rising 7 is cycle 14.
  o.edge = Edge::both;
  Report rb = compare(o);
  ASSERT_EQ(rb.diffs.size(), 1u);
  EXPECT_EQ(rb.diffs[0].first.at.cycle, 14u);
  EXPECT_EQ(rb.diffs[0].count, 1u);
}

TEST(WavediffClock, ClockNamedDifferentlyInB) {
  Dir d;
  const auto a = d.write("a.vcd", render(counter(12), {}));
  Style s;
  s.rename["top.clk"] = "top.clock";
  const auto b = d.write("b.vcd", render(counter(12), s));
  Options o = opts(a, b);
  o.clock_a = "top.clk";
  o.clock_b = "top.clock";
  EXPECT_EQ(run_opts(o).rc, 0);
  // B with fewer edges: a difference of its own.
  const auto b11 = d.write("b11.vcd", render(counter(11), s));
  o.file_b = b11;
  const Report r = compare(o);
  ASSERT_EQ(r.structural.size(), 1u);
  EXPECT_EQ(r.structural[0].what, "clock: B has only 11 rising edges, A has more");
  EXPECT_FALSE(r.same());
}

TEST(WavediffVector, SplitBitsAgainstVector) {
  Dir d;
  const auto a = d.write("a.vcd", render(counter(12), {}));
  Style split;
  split.split = true;
  split.id_base = 7;
  const auto b = d.write("b.vcd", render(counter(12), split));
  EXPECT_NE(slurp(b).find("$var wire 1 ) cnt [7] $end"), std::string::npos);
  EXPECT_EQ(run_opts(opts(a, b)).rc, 0);
  EXPECT_EQ(run_opts(opts(b, a)).rc, 0);
  const auto bd = d.write("bd.vcd", render(counter(12, 10, cnt_aa_at_7), split));
  const Report r = compare(opts(a, bd));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].name, "top.cnt");
  EXPECT_EQ(r.diffs[0].first.b, "10101010");
  EXPECT_EQ(r.compared, 3u);
}

TEST(WavediffVector, AscendingRangeKeepsBitOrder) {
  Dir d;
  // v [0:3] = b0001 means v[0]=0 v[1]=0 v[2]=0 v[3]=1; B gives the bits one by one.
  const auto a = d.write("a.vcd",
                         "$timescale 1ns $end\n$scope module top $end\n"
                         "$var wire 4 ! v [0:3] $end\n$upscope $end\n$enddefinitions $end\n"
                         "#0\nb0001 !\n#10\nb0011 !\n");
  const auto b = d.write("b.vcd",
                         "$timescale 1ns $end\n$scope module top $end\n"
                         "$var wire 1 a v [0] $end\n$var wire 1 b v [1] $end\n"
                         "$var wire 1 c v [2] $end\n$var wire 1 d v [3] $end\n"
                         "$upscope $end\n$enddefinitions $end\n"
                         "#0\n0a\n0b\n0c\n1d\n#10\n1c\n");
  const Outcome r = run_opts(opts(a, b));
  EXPECT_EQ(r.rc, 0) << r.out;
}

TEST(WavediffAlias, EveryNameOfAnIdGetsTheValues) {
  Dir d;
  // In A, top.a and top.u.a_copy are one id ('!'); in B they are two ids.
  const std::string head_a =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! a $end\n"
      "$scope module u $end\n$var wire 1 ! a_copy $end\n$upscope $end\n$upscope $end\n"
      "$enddefinitions $end\n";
  const auto a = d.write("a.vcd", head_a + "#0\n0!\n#10\n1!\n#20\n0!\n");
  const std::string head_b =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 x a $end\n"
      "$scope module u $end\n$var wire 1 y a_copy $end\n$upscope $end\n$upscope $end\n"
      "$enddefinitions $end\n";
  const auto b = d.write("b.vcd", head_b + "#0\n0x\n0y\n#10\n1x\n1y\n#20\n0x\n0y\n");
  EXPECT_EQ(run_opts(opts(a, b)).rc, 0);
  EXPECT_EQ(run_opts(opts(b, a)).rc, 0);
  // B's copy stays 1 at 20: only top.u.a_copy differs, from 20 ns.
  const auto b2 = d.write("b2.vcd", head_b + "#0\n0x\n0y\n#10\n1x\n1y\n#20\n0x\n");
  const Report r = compare(opts(a, b2));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].name, "top.u.a_copy");
  EXPECT_EQ(r.diffs[0].first.at.time, 20u);
  EXPECT_EQ(r.compared, 2u);
}

// The reader looks identifier codes of 1 to 3 characters from '!' to '~' up in a direct table
// (one tier per length) and every other code in a fallback table. The same model written with
// codes at the table's edges ('!' first, '~' last of each tier), with 4- to 16-character codes and
// with codes of other bytes must read the same: against a mutant in which signal i differs from
// time 2i+1 to 2i+2 only, each gives one divergence per signal with the same values.
TEST(WavediffIds, DirectTableAndFallbackCodesReadTheSame) {
  Dir d;
  const int widths[] = {1, 4, 1, 8, 16, 1, 12, 3, 1, 20, 2, 1, 9, 5};
  constexpr int kSigs = 14;
  auto value = [&](int i, std::uint64_t t, bool mutant) {
    const int w = widths[i];
    std::string v = bin((t / static_cast<std::uint64_t>(i % 3 + 1)) * 2654435761u + 7u * i, w);
    if (i % 5 == 4 && t % 4 == 0) v[0] = 'z';  // x and z go through the vector path too
    if (i % 5 == 2 && t % 3 == 0) v[static_cast<std::size_t>(w) - 1] = 'x';
    if (mutant && t == 2u * static_cast<std::uint64_t>(i) + 1) {
      char& c = v.back();
      c = c == '1' ? '0' : '1';
    }
    return v;
  };
  auto model = [&](bool mutant) {
    Model m;
    for (int i = 0; i < kSigs; ++i) m.sigs.push_back({fmt::format("top.s{}", i), widths[i]});
    m.sigs.push_back({"top.level", 64, true});
    for (std::uint64_t t = 0; t < 40; ++t) {
      for (int i = 0; i < kSigs; ++i) m.set(t, i, value(i, t, mutant));
      const bool bump = mutant && t == 2u * kSigs + 1;  // the real differs at 29 only
      m.set(t, kSigs, fmt::format("{}", 0.25 * static_cast<double>(t / 2) + (bump ? 1 : 0)));
    }
    return m;
  };
  Style short_codes;  // tiers 1, 2, 3 and both ends of each
  short_codes.codes = {"!",   "~",   "!!", "~~", "!~", "~!", "!!!", "~~~",
                       "~!!", "!~~", "\"", "}",  "a",  "zz", "q5"};
  Style long_codes;  // packed fallback up to 8 characters, map beyond
  long_codes.codes = {"!!!!",      "~~~~",  "!!!!!",   "~~~~~~~~",  "!~~~~~~~~", "abcdefghijklmnop",
                      "long_code", "!!!!~", "~!!!",    "!!!!!!!!!", "~!~!",      "zzzz",
                      "~~~~~",     "q5q5",  "\"\"\"\""};
  Style other_bytes;  // short codes outside '!'..'~': the fallback as well
  other_bytes.codes = {"\x7f",  "\xc3\xa9", "\x80",         "\xff\xff",     "!\x7f",
                       "\x7f!", "~\x80~",   "\xe2\x82\xac", "\x7f\x7f\x7f", "a\xff",
                       "\x81",  "\xfe",     "\x7f~",        "\x80\x80",     "\x9f"};
  const Model a = model(false);
  const auto f_short = d.write("short.vcd", render(a, short_codes));
  const auto fl = d.write("long.vcd", render(a, long_codes));
  const auto fo = d.write("other.vcd", render(a, other_bytes));
  const auto fm = d.write("mutant.vcd", render(model(true), {}));
  EXPECT_EQ(run_opts(opts(f_short, fl)).rc, 0);
  EXPECT_EQ(run_opts(opts(fl, fo)).rc, 0);
  EXPECT_EQ(run_opts(opts(fo, f_short)).rc, 0);
  auto text = [](const Report& r) {
    std::string out = fmt::format("compared {}\n", r.compared);
    for (const SignalDiff& s : r.diffs) {
      out += fmt::format("{} {} {} {} {} {} {} {}\n", s.name, s.count, s.first.at.time, s.first.a,
                         s.first.b, s.first.last_common.value_or("-"), s.first.open, s.last.time);
    }
    return out;
  };
  const Report rs = compare(opts(f_short, fm));
  ASSERT_EQ(rs.diffs.size(), static_cast<std::size_t>(kSigs + 1)) << text(rs);
  EXPECT_EQ(rs.compared, static_cast<std::size_t>(kSigs + 1));
  for (int i = 0; i < kSigs; ++i) {
    const SignalDiff& sd = rs.diffs[static_cast<std::size_t>(i)];
    const std::uint64_t t = 2u * static_cast<std::uint64_t>(i) + 1;
    EXPECT_EQ(sd.name, fmt::format("top.s{}", i));
    EXPECT_EQ(sd.count, 1u) << sd.name;
    EXPECT_EQ(sd.first.at.time, t) << sd.name;
    EXPECT_EQ(sd.first.a, value(i, t, false)) << sd.name;
    EXPECT_EQ(sd.first.b, value(i, t, true)) << sd.name;
    EXPECT_FALSE(sd.first.open) << sd.name;
  }
  EXPECT_EQ(rs.diffs[kSigs].name, "top.level");
  EXPECT_EQ(rs.diffs[kSigs].first.at.time, 29u);
  EXPECT_EQ(rs.diffs[kSigs].first.a, "3.5");  // 0.25 * 14
  EXPECT_EQ(rs.diffs[kSigs].first.b, "4.5");
  EXPECT_EQ(text(compare(opts(fl, fm))), text(rs));
  EXPECT_EQ(text(compare(opts(fo, fm))), text(rs));
  // With the sides swapped as well (B's reader uses the table).
  EXPECT_EQ(text(compare(opts(fm, f_short))), text(compare(opts(fm, fl))));
  // An undeclared code in each tier and in the fallback is still an error with its line (the
  // one after "#0" and "1!", which follow the header).
  Model one;
  one.sigs = {{"top.a", 1}};  // declared as '!'
  const std::string head = render(one, short_codes);
  const auto head_lines = static_cast<std::size_t>(std::count(head.begin(), head.end(), '\n'));
  // (A control character is quoted as \xHH in the error line, docs/bad-input.md.)
  for (const auto& [id, shown] :
       std::initializer_list<std::pair<const char*, const char*>>{{"~", "~"},
                                                                  {"!!", "!!"},
                                                                  {"~~~", "~~~"},
                                                                  {"!!!!", "!!!!"},
                                                                  {"~~~~~~~~~", "~~~~~~~~~"},
                                                                  {"\x7f", "\\x7F"}}) {
    const auto f = d.write("undeclared.vcd", head + "#0\n1!\n1" + std::string(id) + "\n");
    const Outcome r = run_opts(opts(f, f));
    EXPECT_EQ(r.rc, 2) << id;
    EXPECT_EQ(r.err, fmt::format("{}:{}: undeclared identifier '{}'\n", f, head_lines + 3, shown));
  }
}

// A vector value is used in place in the read buffer (1 MiB) unless reading its identifier
// refills the buffer. The same changes, placed at every offset around the end of the first
// buffer by a header comment, read the same as without the comment; nine-valued letters
// (normalised into a copy) as well.
TEST(WavediffIds, VectorValuesAcrossTheReadBuffersEnd) {
  Dir d;
  const std::string decl =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 20 ~ v [19:0] $end\n"
      "$var wire 12 !!!!!!!!! w [11:0] $end\n$var wire 1 !! c $end\n$upscope $end\n"
      "$enddefinitions $end\n";
  std::string body;
  for (std::uint64_t t = 0; t < 64; ++t) {
    body += fmt::format("#{}\nb{} ~\n", t, bin(t * 40503u + 1, 20));
    body += t % 5 == 3 ? "bUWXZ-HL10101 !!!!!!!!!\n" : fmt::format("b{} !!!!!!!!!\n", bin(t, 12));
    body += fmt::format("{}!!\n", t & 1);
  }
  // A trailer of more than 1 MiB: the refill overwrites the whole buffer, so that a vector value
  // that had been left there would be lost.
  std::string trailer = "$comment";
  while (trailer.size() < (std::size_t{1} << 20) + 4096) trailer += " trailer";
  body += trailer + " $end\n";
  const auto ref = d.write("ref.vcd", decl + body);
  // The changes are about 3.5 KB: with a comment of `pad` bytes they start at 1 MiB - 1500 -
  // shift.
  const std::size_t pad = (std::size_t{1} << 20) - 1500 - decl.size();
  std::string comment;
  for (std::size_t shift = 0; shift < 48; ++shift) {
    comment = "$comment";
    while (comment.size() < pad - shift - 6) comment += " padding";
    comment.resize(pad - shift - 6, '_');
    comment += " $end\n";
    const auto f = d.write("shifted.vcd", comment + decl + body);
    const Outcome r = run_opts(opts(f, ref));
    EXPECT_EQ(r.rc, 0) << "shift " << shift << ": " << r.out << r.err;
  }
  // The comparison sees a difference in the same setting (so the loop above can fail).
  std::string other = body;
  const std::size_t at = other.find("#40\nb") + 5;  // v's leftmost bit at 40
  other[at] = other[at] == '0' ? '1' : '0';
  const auto f = d.write("shifted.vcd", comment + decl + other);
  const Report r = compare(opts(f, ref));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].name, "top.v");
  EXPECT_EQ(r.diffs[0].first.at.time, 40u);
  // The nine-valued letters as documented: U W X - read as x, Z as z, H L as 1 0.
  const auto nine = d.write("nine.vcd", decl + "#0\nbUWXZ-HL10101 !!!!!!!!!\n");
  EXPECT_EQ(run_opts(opts(nine, d.write("xz.vcd", decl + "#0\nbxxxzx1010101 !!!!!!!!!\n"))).rc, 0);
  EXPECT_EQ(run_opts(opts(nine, d.write("xz1.vcd", decl + "#0\nbxxxzx1010100 !!!!!!!!!\n"))).rc, 1);
}

TEST(WavediffMap, RenamesFromAMappingFile) {
  Dir d;
  const auto a = d.write("a.vcd", render(counter(12), {}));
  Style s;
  s.rename = {{"top.cnt", "top.count"}, {"top.flag", "top.flg"}};
  const auto b = d.write("b.vcd", render(counter(12), s));
  const auto map = d.write("names.map",
                           "# renames between the two dumps\n"
                           "\n"
                           "top.cnt = top.count\n"
                           "  top.flag=top.flg   # trailing comment\n");
  Options o = opts(a, b);
  const Report plain = compare(o);
  EXPECT_EQ(plain.only_a, (std::vector<std::string>{"top.cnt", "top.flag"}));
  EXPECT_EQ(plain.only_b, (std::vector<std::string>{"top.count", "top.flg"}));
  EXPECT_EQ(run_opts(o).rc, 1);
  o.ignore_missing = true;
  EXPECT_EQ(run_opts(o).rc, 0);
  o.ignore_missing = false;
  o.map_file = map;
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 0) << r.out << r.err;
  EXPECT_EQ(r.err, "");
  // The mapped name also joins split bits: top.count[7..0] in B against top.cnt in A.
  s.split = true;
  o.file_b = d.write("bs.vcd", render(counter(12), s));
  EXPECT_EQ(run_opts(o).rc, 0);
  // A difference is reported under A's name, with B's name beside it.
  o.file_b = d.write("bd.vcd", render(counter(12, 10, cnt_aa_at_7), s));
  const Outcome rd = run_opts(o);
  EXPECT_EQ(rd.rc, 1);
  EXPECT_NE(rd.out.find("  top.cnt (B top.count): 1 divergence, first at 75ns"), std::string::npos)
      << rd.out;
}

TEST(WavediffMap, ErrorsNameFileAndLine) {
  Dir d;
  const auto a = d.write("a.vcd", render(counter(3), {}));
  Options o = opts(a, a);
  o.map_file = d.write("bad.map", "# ok\ntop.cnt = top.count\ntop.flag top.flg\n");
  Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, o.map_file + ":3: expected 'nameA = nameB'\n");
  o.map_file = d.write("dup.map", "top.cnt = top.count\n\ntop.cnt = top.other\n");
  r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, o.map_file + ":3: 'top.cnt' is already mapped on line 1\n");
  o.map_file = d.file("missing.map");
  r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, o.map_file + ":0: cannot open: No such file or directory\n");
  // A name that is in neither file: a warning with file:line, not an error.
  o.map_file = d.write("unused.map", "top.nothere = top.neither\n");
  r = run_opts(o);
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.err, o.map_file + ":1: warning: no signal 'top.nothere' in A\n" + o.map_file +
                       ":1: warning: no signal 'top.neither' in B\n");
  // Whole names, however long (review B, finding 8): two of 44 characters that share their first
  // 40 are two warnings that tell them apart. Before, both were cut to the same 40 and "...".
  const std::string stem = "tb.dut.u_dpc31_core.u_fdl.u_uart.rx_stat";  // 40 characters
  o.map_file = d.write("long.map", stem + "e_q = top.x1\n" + stem + "e_d = top.x2\n");
  r = run_opts(o);
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.err, o.map_file + ":1: warning: no signal '" + stem + "e_q' in A\n" + o.map_file +
                       ":1: warning: no signal 'top.x1' in B\n" + o.map_file +
                       ":2: warning: no signal '" + stem + "e_d' in A\n" + o.map_file +
                       ":2: warning: no signal 'top.x2' in B\n");
}

TEST(WavediffStrip, ExplicitAndAutomaticTopScopes) {
  Dir d;
  Style sa;
  sa.prefix = "tb.dut";
  Style sb;
  sb.prefix = "TOP";
  const auto a = d.write("a.vcd", render(counter(12), sa));
  const auto b = d.write("b.vcd", render(counter(12), sb));
  Options o = opts(a, b);
  const Report none = compare(o);
  EXPECT_EQ(none.compared, 0u);
  EXPECT_EQ(none.only_a.size(), 3u);
  EXPECT_EQ(run_opts(o).rc, 1);
  // No pair with --ignore-missing is no comparison at all: an error naming both files, not
  // "same" (docs/wavediff.md, "Matching signals" 6); the CLI binary says the same, exit 2.
  const std::string nothing = "dpc31 wavediff: no signals to compare: no signal of " + a +
                              " matched one of " + b +
                              " (check --strip, --map and --include/--exclude)\n";
  o.ignore_missing = true;
  const Outcome ignored = run_opts(o);
  EXPECT_EQ(ignored.rc, 2);
  EXPECT_EQ(ignored.out, "");
  EXPECT_EQ(ignored.err, nothing);
  EXPECT_THROW(compare(o), InputError);
  const auto out = d.file("out.txt");
  EXPECT_EQ(spawn({DPC31_CLI, "wavediff", a, b, "--ignore-missing"}, nullptr, out), 2);
  EXPECT_EQ(slurp(out), nothing);
  EXPECT_EQ(spawn({DPC31_CLI, "wavediff", b, b, "--exclude", "*"}, nullptr, out), 2);
  EXPECT_EQ(slurp(out), "dpc31 wavediff: no signals to compare: no signal of " + b +
                            " matched one of " + b +
                            " (check --strip, --map and --include/--exclude)\n");
  o.ignore_missing = false;
  o.strip_a = "tb.dut";
  o.strip_b = "TOP";
  EXPECT_EQ(run_opts(o).rc, 0);
  o.strip_a.clear();
  o.strip_b.clear();
  o.strip_auto = true;
  const Report aut = compare(o);
  EXPECT_EQ(aut.compared, 3u);
  EXPECT_TRUE(aut.same());
  // Only one side wrapped: auto strips that side only.
  o.file_b = d.write("plain.vcd", render(counter(12), {}));
  EXPECT_EQ(compare(o).compared, 3u);
  o.strip_auto = false;
  o.strip_a = "tb.nothere";
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, a + ":0: no signal under scope 'tb.nothere'\n");
}

TEST(WavediffFilter, IncludeAndExcludeGlobs) {
  Dir d;
  Model ma = counter(10);
  Model mb = counter(10);
  ma.sigs.push_back({"top.dbg_state", 2});
  mb.sigs.push_back({"top.dbg_state", 2});
  ma.set(30, 3, "01");
  mb.set(30, 3, "10");  // differs from 30 ns on
  const auto a = d.write("a.vcd", render(ma, {}));
  const auto b = d.write("b.vcd", render(mb, {}));
  Options o = opts(a, b);
  EXPECT_EQ(run_opts(o).rc, 1);
  o.exclude = {"*.dbg_*"};
  Report r = compare(o);
  EXPECT_EQ(r.compared, 3u);
  EXPECT_TRUE(r.same());
  o.exclude.clear();
  o.include = {"top.d?g*"};
  r = compare(o);
  EXPECT_EQ(r.compared, 1u);
  ASSERT_EQ(r.diffs.size(), 1u);
  // dbg_state is first set at 30 ns; before that both are x (equal).
  EXPECT_EQ(r.diffs[0].first.at.time, 30u);
  o.include = {"top.cn?", "top.f???"};  // not top.clk
  r = compare(o);
  EXPECT_EQ(r.compared, 2u);
  EXPECT_TRUE(r.same());
  EXPECT_TRUE(glob_match("top.cnt[3]", "top.cnt[3]"));  // brackets are literal
  EXPECT_FALSE(glob_match("top.cnt[3]", "top.cnt3"));
  EXPECT_TRUE(glob_match("*", "a.b.c"));
  EXPECT_FALSE(glob_match("a?", "a"));
}
