// Logs that never flood (docs/decisions.md, "Logs that never flood"): dpc31::LogLimiter, and the
// chip's log of unmapped accesses, driven through the bus as a firmware written for another chip
// would.
#include "dpc31/log.hpp"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "dpc31/chip.hpp"
#include "test_util.hpp"

using namespace dpc31;

namespace {

std::vector<std::string> feed(LogLimiter& l, std::uint64_t cycle, const std::string& text) {
  return l.add(cycle, text);
}

}  // namespace

// The count said when another line comes (or at the end) names the repeats' own cycles, not
// the cycle of the line that ends them.
TEST(LogLimiter, RepeatsAreFoldedAndCountedAtPowersOfTen) {
  LogLimiter l;
  EXPECT_EQ(feed(l, 0, "a"), std::vector<std::string>{"a"});
  for (int i = 1; i < 10; ++i) EXPECT_TRUE(feed(l, i, "a").empty()) << i;
  EXPECT_EQ(feed(l, 10, "a"), std::vector<std::string>{"last line repeated 10 times so far"});
  for (int i = 11; i < 13; ++i) EXPECT_TRUE(feed(l, i, "a").empty());
  // Another line: the repeats not yet said, then the line.
  EXPECT_EQ(feed(l, 500, "b"),
            (std::vector<std::string>{"last line repeated 12 times, cycles 1 to 12", "b"}));
  EXPECT_EQ(feed(l, 600, "a"), std::vector<std::string>{"a"});
  EXPECT_TRUE(feed(l, 700, "a").empty());
  EXPECT_EQ(l.flush(), std::vector<std::string>{"last line repeated 1 times, at cycle 700"});
  EXPECT_TRUE(l.flush().empty());
}

TEST(LogLimiter, AtMostBurstLinesPerWindowAndOneLineForTheRest) {
  LogLimiter l(3, 100);
  EXPECT_EQ(feed(l, 0, "1").size(), 1u);
  EXPECT_EQ(feed(l, 10, "2").size(), 1u);
  EXPECT_EQ(feed(l, 20, "3").size(), 1u);
  EXPECT_TRUE(feed(l, 30, "4").empty());  // the fourth in cycles 0..99
  EXPECT_TRUE(feed(l, 99, "5").empty());
  EXPECT_EQ(l.left_out(), 2u);
  // Cycle 100 opens the next window: what was left out is said first.
  EXPECT_EQ(feed(l, 100, "6"),
            (std::vector<std::string>{
                "2 log lines left out in the 100 cycles before (at most 3 a window)", "6"}));
  EXPECT_EQ(feed(l, 250, "7").size(), 1u);  // a window later, nothing owed
  EXPECT_EQ(feed(l, 251, "8").size(), 1u);
  EXPECT_EQ(feed(l, 252, "9").size(), 1u);
  EXPECT_TRUE(feed(l, 253, "10").empty());
  EXPECT_EQ(l.flush(), std::vector<std::string>{"1 log lines left out (at most 3 in 100 cycles)"});
}

// A firmware written for the SPC3 on the dpc31 profile polls Status_Reg (04H/05H on the SPC3,
// SPC3 manual p.24; unmapped on the dpc31, docs/dpc31.md): one line with the likely cause, then a
// count at 10, 100, 1000, ... accesses (the bridge once wrote 1.27 M such lines in 2 s).
TEST(LogLimiter, UnmappedPollingGivesOneHintAndThenCounts) {
  Chip c({Profile::dpc31, BusMode::intel});
  testutil::LogCapture log;
  log.attach(c);
  for (int i = 0; i < 100'000; ++i) EXPECT_EQ(c.read(0x05), 0);
  ASSERT_EQ(log.records.size(), 6u);  // the hint; 10, 100, 1 000, 10 000 and 100 000 so far
  EXPECT_NE(log.records[0].text.find("read of unmapped address 0x0005"), std::string::npos);
  EXPECT_NE(log.records[0].text.find("on spc3 it is Status_Reg"), std::string::npos)
      << log.records[0].text;
  EXPECT_NE(log.records[0].text.find("--profile"), std::string::npos);
  EXPECT_EQ(log.records[1].text,
            "10 accesses to unmapped addresses so far (the latest: read of 0x0005)");
  EXPECT_EQ(log.records[5].text,
            "100000 accesses to unmapped addresses so far (the latest: read of 0x0005)");
  EXPECT_EQ(log.records[0].cycle, 4u);  // the first access's 4 clocks (docs/timing.md)
}

// An address beyond the bus (a VPC3+ driver's 16-bit register at 0x802 polled on the SPC3, whose
// bus has 11 bits) folds as unmapped ones do: the hint, a line per address for the first few,
// then a count at 10, 100, 1000, ... accesses (it was a line per access, 1000 a second).
TEST(LogLimiter, BeyondTheAddressBusGivesOneHintAndThenCounts) {
  Chip c({Profile::spc3, BusMode::intel});
  testutil::LogCapture log;
  log.attach(c);
  for (int i = 0; i < 50'000; ++i) {
    c.read(0x802);
    c.read(0x803);
  }
  ASSERT_EQ(log.records.size(), 7u);  // the hint, 0x803; 10, 100, 1 000, 10 000 and 100 000
  EXPECT_EQ(log.records[0].text,
            "read at 0x802: beyond the 11-bit address bus, upper bits ignored; a firmware written "
            "for another chip? (--profile, --variant); further accesses beyond the bus are "
            "counted");
  EXPECT_EQ(log.records[1].text,
            "read at 0x803: beyond the 11-bit address bus, upper bits ignored");
  EXPECT_EQ(log.records[2].text,
            "10 accesses beyond the 11-bit address bus so far (the latest: read at 0x803)");
  EXPECT_EQ(log.records[6].text,
            "100000 accesses beyond the 11-bit address bus so far (the latest: read at 0x803)");
}

// Remarks at one level never crowd out another's lines: each level has its own bound. On the
// dpc31 (its internal work cells are RAM the user must not touch: an info line per access).
TEST(LogLimiter, ChipLogIsBoundedPerLevel) {
  {
    Chip c({Profile::dpc31, BusMode::intel});
    testutil::LogCapture log;
    log.attach(c);
    std::vector<std::uint32_t> reserved;  // registers that read 00h with a warning
    for (const RegDesc& r : c.profile().regs)
      if (r.kind == Kind::reserved && r.read_addr >= 0)
        reserved.push_back(static_cast<std::uint32_t>(r.read_addr));
    std::uint32_t remark = 0;  // RAM the user must not touch: read with an info line
    for (const RegionDesc& g : c.profile().regions)
      if (g.ram && g.reserved) remark = g.begin;
    ASSERT_GE(reserved.size(), 2u);
    ASSERT_NE(remark, 0u);
    // Two alternating warnings: no repeats to fold, so only the window bounds them.
    for (int i = 0; i < 5000; ++i) {
      c.read(reserved[0]);
      c.read(reserved[1]);
    }
    c.read(remark);  // an info line after the flood of warnings
    std::size_t info = 0;
    std::size_t warn = 0;
    for (const LogRecord& r : log.records) (r.level == LogLevel::info ? info : warn) += 1;
    EXPECT_EQ(warn, LogLimiter::kBurst);
    EXPECT_EQ(info, 1u);
    c.set_log_sink(nullptr);  // the end of the run: what the warn limiter owes is said
    ASSERT_EQ(log.records.size(), LogLimiter::kBurst + 2);
    EXPECT_EQ(log.records.back().text,
              fmt::format("{} log lines left out (at most {} in {} cycles)",
                          10000 - LogLimiter::kBurst, LogLimiter::kBurst, LogLimiter::kWindow));
  }
}

// The default sink shows warnings and errors only, so the chip does not format the debug and
// info lines it would drop (docs/decisions.md, "Logs that never flood"): they count against no
// window, and a sink set later gets its first one, also after a snapshot is loaded (the sink and
// what it shows are attachments, not state).
TEST(LogLimiter, LinesTheDefaultSinkDropsAreNotCountedForALaterSink) {
  Chip c({Profile::dpc31, BusMode::intel});
  std::uint32_t remark = 0;  // RAM the user must not touch: read with an info line
  for (const RegionDesc& g : c.profile().regions)
    if (g.ram && g.reserved) remark = g.begin;
  ASSERT_NE(remark, 0u);
  // More info lines than a window lets through, none a repeat, under the default sink.
  for (std::uint32_t i = 0; i < LogLimiter::kBurst + 10; ++i) c.read(remark + (i & 1));
  testutil::LogCapture log;
  log.attach(c);
  c.read(remark);
  ASSERT_EQ(log.records.size(), 1u);
  EXPECT_EQ(log.records[0].level, LogLevel::info);
  c.load_state(c.save_state());
  c.read(remark + 1);
  ASSERT_EQ(log.records.size(), 2u);
  EXPECT_EQ(log.records[1].level, LogLevel::info);
}

// s33 audit finding 2: the repeat count is the log's, whatever the level. An info line repeated,
// then a warning: the count comes before the warning (docs/scenario-format.md, "The walk": "comes
// with the chip's next different line"), not at the run's end after it; and the info line after
// the warning is no repeat. Each read costs 4 clocks and logs at its end (docs/timing.md).
TEST(LogLimiter, ALineOfAnotherLevelEndsTheRepeats) {
  Chip c({Profile::dpc31, BusMode::intel});
  testutil::LogCapture log;
  log.attach(c);
  std::uint32_t warned = 0;  // a reserved register: reads 00h with a warning
  for (const RegDesc& r : c.profile().regs)
    if (r.kind == Kind::reserved && r.read_addr >= 0)
      warned = static_cast<std::uint32_t>(r.read_addr);
  std::uint32_t remark = 0;  // RAM the user must not touch: read with an info line
  for (const RegionDesc& g : c.profile().regions)
    if (g.ram && g.reserved) remark = g.begin;
  ASSERT_NE(warned, 0u);
  ASSERT_NE(remark, 0u);
  for (int i = 0; i < 3; ++i) c.read(remark);  // cycles 4, 8, 12
  c.read(warned);                              // 16
  c.read(remark);                              // 20
  c.set_log_sink(nullptr);
  ASSERT_EQ(log.records.size(), 4u);
  EXPECT_EQ(log.records[0].cycle, 4u);
  EXPECT_EQ(log.records[1].level, LogLevel::info);
  EXPECT_EQ(log.records[1].text, "last line repeated 2 times, cycles 8 to 12");
  EXPECT_EQ(log.records[1].cycle, 16u);
  EXPECT_EQ(log.records[2].level, LogLevel::warn);
  EXPECT_EQ(log.records[2].cycle, 16u);
  EXPECT_EQ(log.records[3].text, log.records[0].text);
  EXPECT_EQ(log.records[3].cycle, 20u);
}

namespace {

// An info line and a debug line, both repeatable (testutil::RepeatableLogLines), and a chip to log
// them. Each access costs 4 clocks and logs at its end (docs/timing.md).
struct InfoAndDebug {
  Chip c{{Profile::dpc31, BusMode::intel}};
  testutil::RepeatableLogLines lines{c.profile()};
  InfoAndDebug() {
    EXPECT_NE(lines.info_read, 0u);
    EXPECT_NE(lines.debug_write, 0u);
  }
  void info() { c.read(lines.info_read); }
  void debug() { c.write(lines.debug_write, lines.debug_value); }
};

std::vector<std::string> shown(const std::vector<LogRecord>& records) {
  std::vector<std::string> out;
  for (const LogRecord& r : records) out.push_back(log_line(r));
  return out;
}

}  // namespace

// The repeats are the log's as its sink sees it (syslogd's "last message repeated"; docs/
// decisions.md, s34-left): a sink that shows debug lines (Chip::set_log_sink(sink): every level)
// sees a debug line end the info line's repeats, and an info line end the debug line's; each
// count comes right after the line it counts. Info at 4 and 8, debug at 12 and 16, info at 20 and
// 24; the last count when the sink is replaced, at 24.
TEST(LogLimiter, ADebugLineTheSinkShowsEndsTheRepeatsBeforeIt) {
  InfoAndDebug d;
  testutil::LogCapture log;
  log.attach(d.c);
  d.info();   // 4
  d.info();   // 8
  d.debug();  // 12
  d.debug();  // 16
  d.info();   // 20
  d.info();   // 24
  d.c.set_log_sink(nullptr);
  ASSERT_EQ(log.records.size(), 6u);
  const std::string& info = log.records[0].text;
  const std::string& debug = log.records[2].text;
  EXPECT_EQ(shown(log.records), (std::vector<std::string>{
                                    "[cycle 4] info: " + info,
                                    "[cycle 12] info: last line repeated 1 times, at cycle 8",
                                    "[cycle 12] debug: " + debug,
                                    "[cycle 20] debug: last line repeated 1 times, at cycle 16",
                                    "[cycle 20] info: " + info,
                                    "[cycle 24] info: last line repeated 1 times, at cycle 24",
                                }));
}

// A sink that shows no debug lines (Chip::set_log_sink(sink, LogLevel::info), as the scenario
// walk and the bridge log) keeps the info line's fold across them: the chip does not even format
// them (s33-hal's concern: a firmware's per-interrupt debug line would otherwise end every fold).
// The same accesses: one info line, then one count of its three repeats.
TEST(LogLimiter, ADebugLineTheSinkDoesNotShowKeepsTheFold) {
  InfoAndDebug d;
  std::vector<LogRecord> records;
  d.c.set_log_sink([&records](const LogRecord& r) { records.push_back(r); }, LogLevel::info);
  d.info();
  d.info();
  d.debug();
  d.debug();
  d.info();
  d.info();
  d.c.set_log_sink(nullptr);
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(shown(records), (std::vector<std::string>{
                                "[cycle 4] info: " + records[0].text,
                                "[cycle 24] info: last line repeated 3 times, cycles 8 to 24"}));
}
