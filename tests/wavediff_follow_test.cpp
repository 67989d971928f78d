// The equal-bytes fast path of dpc31 wavediff (docs/wavediff.md, "Equal stretches"): where both
// files' bytes agree and every value does, B's steps are taken from A's. The reference is the
// same comparison with Options::follow_equal_bytes off: every report here must equal it field by
// field (times, signals, values, last common values, counts), and the fast path must have been
// taken (Report::followed). The differences sit where the readers' reads end (1 MiB, the read
// buffer's size), on both sides of that boundary, with headers of equal and of unequal length
// (the two buffers then end at different places in the body).
#include "wavediff_model.hpp"

using namespace wavediff_test;

namespace {

constexpr std::size_t kRead = std::size_t{1} << 20;  // vcd_reader.cpp's kBufSize

void expect_same_report(const Report& fast, const Report& ref) {
  EXPECT_EQ(fast.compared, ref.compared);
  EXPECT_EQ(fast.only_a, ref.only_a);
  EXPECT_EQ(fast.only_b, ref.only_b);
  ASSERT_EQ(fast.diffs.size(), ref.diffs.size());
  for (std::size_t i = 0; i < ref.diffs.size(); ++i) {
    const SignalDiff& f = fast.diffs[i];
    const SignalDiff& r = ref.diffs[i];
    SCOPED_TRACE(r.name);
    EXPECT_EQ(f.name, r.name);
    EXPECT_EQ(f.count, r.count);
    EXPECT_EQ(f.first.at.time, r.first.at.time);
    EXPECT_EQ(f.first.a, r.first.a);
    EXPECT_EQ(f.first.b, r.first.b);
    EXPECT_EQ(f.first.last_common, r.first.last_common);
    EXPECT_EQ(f.first.open, r.first.open);
    EXPECT_EQ(f.last.time, r.last.time);
  }
  EXPECT_EQ(ref.followed, 0u);
}

Report run_both(const std::string& a, const std::string& b, Report& ref) {
  Options o = opts(a, b);
  o.follow_equal_bytes = false;
  ref = compare(o);
  o.follow_equal_bytes = true;
  return compare(o);
}

// The synthetic body (lib/wavediff/synthetic_vcd.cpp, no differences) of about 3 MiB after a
// header of our own; `date` changes the header's length.
std::string body_text() {
  Dir d;
  SyntheticVcd spec;
  spec.steps = 30'000;
  std::string error;
  const std::string a = d.file("a.vcd");
  EXPECT_TRUE(write_synthetic_vcd_pair(a, d.file("b.vcd"), spec, error)) << error;
  const std::string all = slurp(a);
  const std::string end = "$enddefinitions $end\n";
  return all.substr(all.find(end) + end.size());
}

// The synthetic header (the same codes), with a $date of `date_len` characters: it places the
// body's bytes in the file.
std::string header(std::size_t date_len) {
  std::string s = "$date " + std::string(date_len, 'd') + " $end\n";
  s += "$timescale 1ps $end\n$scope module top $end\n";
  s += "$var wire 1 ! clk $end\n";
  for (int i = 0; i < 32; ++i) s += fmt::format("$var wire 1 {} s{} $end\n", char('"' + i), i);
  for (int i = 0; i < 32; ++i) {
    s += fmt::format("$var wire 16 {} v{} [15:0] $end\n", char('"' + 32 + i), i);
  }
  return s + "$upscope $end\n$enddefinitions $end\n";
}

// The time of the step that holds body offset `at`: the last "#t" line that starts before it.
std::uint64_t time_at(const std::string& body, std::size_t at) {
  const std::size_t hash = body.rfind("\n#", at);
  return std::stoull(body.substr(hash + 2, body.find('\n', hash + 1) - hash - 2));
}

// The first value character ('0' or '1' of a scalar change or a vector's digit) at or after `at`.
std::size_t value_at_or_after(const std::string& body, std::size_t at) {
  for (;; ++at) {
    const std::size_t line = body.rfind('\n', at - 1) + 1;
    const bool scalar = at == line;
    const bool digit = body[line] == 'b' && at > line && at < body.find(' ', line);
    if ((body[at] == '0' || body[at] == '1') && (scalar || digit)) return at;
  }
}

// The $date length that puts body offset `at` at file offset `file_at`.
std::size_t date_for(std::size_t at, std::size_t file_at) {
  return file_at - at - header(0).size();
}

}  // namespace

TEST(WavediffFollow, SyntheticPairReportsWhatTheReferencePathReports) {
  Dir d;
  SyntheticVcd spec;
  spec.steps = 40'000;  // about 4 MB each
  spec.diff_steps = {0, 1, 9'999, 10'000, 20'000, 39'990, 39'999};
  std::string error;
  const std::string a = d.file("a.vcd");
  const std::string b = d.file("b.vcd");
  ASSERT_TRUE(write_synthetic_vcd_pair(a, b, spec, error)) << error;
  Report ref;
  const Report fast = run_both(a, b, ref);
  // Each flip is a difference of one bus from the step it is in (time 10 ps per step), lasting
  // until that bus is written again: seven stretches, the first at step 0.
  std::uint64_t stretches = 0;
  for (const SignalDiff& s : ref.diffs) stretches += s.count;
  EXPECT_EQ(stretches, 7u);
  ASSERT_FALSE(ref.diffs.empty());
  EXPECT_EQ(ref.diffs[0].first.at.time, 0u);
  expect_same_report(fast, ref);
  EXPECT_GT(fast.followed, 39'000u);  // all but the steps around the differences
}

TEST(WavediffFollow, DifferenceAtTheEndOfARead) {
  const std::string body = body_text();
  for (const std::size_t longer_b : {0, 11}) {
    // The byte that differs is the last one of A's first read of the file, the first one of its
    // second read, or next to them; with B's header longer, B's reads end elsewhere.
    for (const std::size_t file_at : {kRead - 2, kRead - 1, kRead, kRead + 1, 2 * kRead}) {
      const std::size_t at = value_at_or_after(body, file_at - header(0).size() - 64);
      const std::string ha = header(date_for(at, file_at));
      const std::string hb = header(date_for(at, file_at) + longer_b);
      ASSERT_EQ(ha.size() + at, file_at);
      SCOPED_TRACE(fmt::format("header lengths {} / {}, body offset {}", ha.size(), hb.size(), at));
      std::string bb = body;
      bb[at] = bb[at] == '0' ? '1' : '0';
      Dir d;
      const std::string a = d.write("a.vcd", ha + body);
      const std::string b = d.write("b.vcd", hb + bb);
      Report ref;
      const Report fast = run_both(a, b, ref);
      ASSERT_FALSE(ref.diffs.empty());
      EXPECT_EQ(ref.diffs[0].first.at.time, time_at(body, at));
      expect_same_report(fast, ref);
      EXPECT_GT(fast.followed, 25'000u);
    }
  }
}

TEST(WavediffFollow, DifferenceInATimeOrAnIdentifierAtTheEndOfARead) {
  const std::string body = body_text();
  // A time token whose last digit is the last byte of the first read, one unit later in B (its
  // step and the next one move); and a scalar change whose identifier code is that byte, another
  // 1-bit signal in B.
  const std::size_t hash = body.find("\n#", kRead - header(0).size() - 64) + 1;
  const std::size_t digits_end = body.find('\n', hash);
  const std::uint64_t t = std::stoull(body.substr(hash + 1, digits_end - hash - 1));
  std::string later = body;
  later.replace(hash + 1, digits_end - hash - 1, std::to_string(t + 1));
  const std::size_t scalar = body.find("\n0", kRead - header(0).size() - 64) + 1;
  std::string other_id = body;
  other_id[scalar + 1] = other_id[scalar + 1] == '"' ? '#' : '"';  // s0 <-> s1
  for (const auto& [bb, last] :
       {std::pair{&later, digits_end - 1}, std::pair{&other_id, scalar + 1}}) {
    const std::string h = header(date_for(last, kRead - 1));
    ASSERT_EQ(h.size() + last, kRead - 1);
    Dir d;
    const std::string a = d.write("a.vcd", h + body);
    const std::string b = d.write("b.vcd", h + *bb);
    Report ref;
    const Report fast = run_both(a, b, ref);
    ASSERT_FALSE(ref.diffs.empty());
    expect_same_report(fast, ref);
    EXPECT_GT(fast.followed, 0u);
  }
}

TEST(WavediffFollow, NotTakenWhenTheCodesDifferOrADiffVcdIsWritten) {
  Dir d;
  const Model m = counter(40);
  const auto a = d.write("a.vcd", render(m, {}));
  Style other;
  other.id_base = 40;  // the same signals under other identifier codes
  const auto b = d.write("b.vcd", render(m, other));
  Report ref;
  EXPECT_EQ(run_both(a, b, ref).followed, 0u);
  EXPECT_TRUE(ref.same());
  const auto c = d.write("c.vcd", render(m, {}));
  Options o = opts(a, c);
  EXPECT_GT(compare(o).followed, 0u);
  o.diff_vcd = d.file("d.vcd");  // every point goes to the diff VCD: nothing is skipped
  EXPECT_EQ(compare(o).followed, 0u);
}
