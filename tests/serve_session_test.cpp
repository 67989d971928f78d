// The `dpc31 serve` interpreter in-process (docs/protocol.md): one Session executing command
// lines against its chip, without a socket in between.
#include "serve_session.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <vector>

#include "baud_search.hpp"
#include "cpu.hpp"
#include "dpc31/chip.hpp"
#include "responder.hpp"
#include "serve_client.hpp"
#include "test_util.hpp"

using testutil::starts_with;

namespace {

struct LocalSession {
  std::vector<std::string> lines;
  dpc31::serve::ClientState client;
  dpc31::serve::Session s{{},
                          [this](const dpc31::serve::AsyncLine& l) { lines.push_back(l.text); }};
  std::string operator()(std::string_view line) { return s.execute(line, client).reply; }
  std::vector<std::string> telegrams() const {
    std::vector<std::string> t;
    for (const auto& l : lines) {
      if (starts_with(l, "! telegram ")) t.push_back(l);
    }
    return t;
  }
};

TEST(ServeSession, InjectDefaultsTo12MbaudWhileSearching) {
  LocalSession s;
  EXPECT_EQ(s("inject 10 05 02 49 50 16"), "OK 132 396");  // T = 4, TSYN 33 bits
  // The next one queues behind the first.
  EXPECT_EQ(s("inject 100502495016"), fmt::format("OK {} {}", 396 + 132, 396 + 132 + 264));
  EXPECT_EQ(s("inject 10 baud=1500000 idle=40"),
            fmt::format("OK {} {}", 792 + 40 * 32, 792 + 40 * 32 + 11 * 32));
  EXPECT_EQ(s("step 100000"), "OK 100000");
  // Both FDL_Status requests were heard (the chip is not started: it only listens).
  EXPECT_EQ(s.telegrams(), (std::vector<std::string>{"! telegram 132 396 rx 100502495016",
                                                     "! telegram 528 792 rx 100502495016"}));
}

// A range error names the range the docs give (docs/protocol.md): a block of 1..4096 bytes, a
// baud rate whose bit time is at least one clock (48 MHz: 1..48000000).
TEST(ServeSession, RangeErrorsNameTheRange) {
  LocalSession s;
  EXPECT_EQ(s("peekblock 0 0"), "ERR range length 0 is out of range (1..4096)");
  EXPECT_EQ(s("readblock 0 4097"), "ERR range length 4097 is out of range (1..4096)");
  EXPECT_EQ(s("inject 10 baud=0"), "ERR range baud 0 is out of range (1..48000000)");
  EXPECT_EQ(s("inject 10 baud=48000001"), "ERR range baud 48000001 is out of range (1..48000000)");
  EXPECT_EQ(s("inject 10 baud=96000000"), "ERR range baud 96000000 is out of range (1..48000000)");
  EXPECT_EQ(s("inject 10 baud=48000000"), "OK 33 44");  // one clock per bit
}

// The protocol reads numbers as every door does (docs/protocol.md "Numbers", docs/security.md):
// a leading zero is decimal, never octal; 0x is hex.
TEST(ServeSession, ALeadingZeroIsDecimal) {
  LocalSession s;
  EXPECT_EQ(s("step 010"), "OK 10");
  EXPECT_EQ(s("step 0x0A"), "OK 20");
  EXPECT_EQ(s("step 09"), "OK 29");
}

TEST(ServeSession, InjectUsesTheDetectedRate) {
  LocalSession s;
  dpc31::DirectBus bus(s.s.chip());
  dpc31::Responder r({});
  r.init(bus);
  const std::uint64_t now = s.s.chip().cycle();
  // 1.5 Mbaud is heard in its search window; afterwards inject defaults to it (T = 32).
  const std::uint64_t window = now + testutil::baud_search_opens(1'500'000);
  EXPECT_EQ(s(fmt::format("step {}", window - now)), fmt::format("OK {}", window));
  EXPECT_EQ(s("inject_fdl 5 2 0x49 baud=1500000"),
            fmt::format("OK {} {}", window + 33 * 32, window + 33 * 32 + 6 * 11 * 32));
  EXPECT_EQ(s("step 20000"), fmt::format("OK {}", window + 20000));
  EXPECT_NE(s("status").find("wd=Baud_Control baud=1500000"), std::string::npos);
  const std::uint64_t c = s.s.chip().cycle();
  EXPECT_EQ(s("inject_fdl 5 2 0x49"),
            fmt::format("OK {} {}", c + 33 * 32, c + 33 * 32 + 6 * 11 * 32));
}

TEST(ServeSession, InjectedFaultsAreCounted) {
  LocalSession s;
  EXPECT_EQ(s("inject 10 05 02 49 50 16 fault=parity:2"), "OK 132 396");
  EXPECT_EQ(s("step 1000"), "OK 1000");
  EXPECT_NE(s("counters").find(" parity=1 "), std::string::npos);
  EXPECT_TRUE(s.telegrams().empty());  // a broken telegram is not reported
}

TEST(ServeSession, RunUntilIrqIsLevelTriggered) {
  LocalSession s;
  EXPECT_EQ(s("run_until_irq 500"), "OK timeout 500");
  EXPECT_EQ(s("write 0x04 0xFE"), "OK");
  EXPECT_EQ(s("write 0x00 0x01"), "OK");
  EXPECT_EQ(s.lines.back(), "! irq 508 1");
  EXPECT_EQ(s("run_until_irq 500"), "OK irq 508");  // already active: at once
  EXPECT_EQ(s("reset"), "OK 0");
  EXPECT_EQ(s.lines.back(), "! irq 0 0");              // reset ends it; the clients are told
  EXPECT_EQ(s("peek_reg Int_Mask_Reg"), "OK 0x3f3f");  // all defined bits (dpc31) masked again
  EXPECT_EQ(s("addr Status_Reg"), "OK 0x0874");        // the dpc31's status display (docs/dpc31.md)
}

TEST(ServeSession, LogLinesFollowTheClientsLevel) {
  LocalSession s;
  EXPECT_EQ(s("log warn"), "OK");
  EXPECT_EQ(s.client.log_level, dpc31::LogLevel::warn);
  EXPECT_EQ(s("read 0x18"), "OK 0x00");
  ASSERT_EQ(s.lines.size(), 1u);  // emitted; the server filters per client
  EXPECT_EQ(s.lines[0],
            "! log 4 warn read of unmapped address 0x0018 (register area (unused)): reads 00h; "
            "on spc3 it is R_User_WD_Value, on vpc3plus it is R_User_WD_Value; a firmware "
            "written for another chip? (--profile, --variant); further unmapped accesses are "
            "counted");
  EXPECT_EQ(s("log info"), "OK");
  EXPECT_EQ(s.client.log_level, dpc31::LogLevel::info);
  EXPECT_EQ(s("log off"), "OK");
  EXPECT_FALSE(s.client.log_level);
  // No client asks for the log: the chip's sink shows nothing, so nothing is emitted (an unmapped
  // address's own line, docs/decisions.md "Logs that never flood").
  EXPECT_EQ(s("read 0x19"), "OK 0x00");
  EXPECT_EQ(s.lines.size(), 1u);
}

// The chip's log folds repeats as the lowest level a client asked for shows it (Chip::
// set_log_sink; docs/protocol.md, `log`): with `log debug` a debug line ends the info line's
// repeats and their count comes right after the info line; with `log info` alone the debug lines
// are not formatted and the info line's repeats fold across them. An info line: a read of RAM the
// user must not touch; a debug line: an Int_Ack_Reg write of a bit it does not change (emu/
// bus.cpp). Each access costs 4 clocks and logs at its end (docs/timing.md); `log off` hands over
// the count still owed, at the chip's cycle then (24).
TEST(ServeSession, RepeatCountsFollowTheLowestLevelAsked) {
  for (const std::string level : {"debug", "info"}) {
    SCOPED_TRACE(level);
    LocalSession s;
    const testutil::RepeatableLogLines l(s.s.chip().profile());
    ASSERT_NE(l.info_read, 0u);
    ASSERT_NE(l.debug_write, 0u);
    const std::string info = fmt::format("read {:#x}", l.info_read);
    const std::string debug = fmt::format("write {:#x} {:#x}", l.debug_write, l.debug_value);
    EXPECT_EQ(s("log " + level), "OK");
    for (const std::string& line : {info, info, debug, debug, info, info})
      EXPECT_TRUE(starts_with(s(line), "OK")) << line;
    EXPECT_EQ(s("log off"), "OK");
    ASSERT_FALSE(s.lines.empty());
    const std::string remark_line = s.lines[0].substr(s.lines[0].find(" info ") + 6);
    std::vector<std::string> want;
    if (level == "debug") {
      ASSERT_EQ(s.lines.size(), 6u);
      const std::string debug_line = s.lines[2].substr(s.lines[2].find(" debug ") + 7);
      want = {
          "! log 4 info " + remark_line,  "! log 12 info last line repeated 1 times, at cycle 8",
          "! log 12 debug " + debug_line, "! log 20 debug last line repeated 1 times, at cycle 16",
          "! log 20 info " + remark_line, "! log 24 info last line repeated 1 times, at cycle 24"};
    } else {
      want = {"! log 4 info " + remark_line,
              "! log 24 info last line repeated 3 times, cycles 8 to 24"};
    }
    EXPECT_EQ(s.lines, want);
  }
}

TEST(ServeSession, InjectQueueCountsWhatIsAheadOfTheChip) {
  LocalSession s;
  EXPECT_EQ(s("inject 10 05 02 49 50 16"), "OK 132 396");
  EXPECT_EQ(s("inject 10 05 02 49 50 16"), "OK 528 792");
  EXPECT_EQ(s.s.inject_queue_bytes(), 12u);
  EXPECT_EQ(s.s.inject_queue_telegrams(), 2u);
  EXPECT_EQ(s("step 396"), "OK 396");  // the first one's END reached
  EXPECT_EQ(s.s.inject_queue_telegrams(), 1u);
  EXPECT_EQ(s("reset"), "OK 0");
  EXPECT_EQ(s.s.inject_queue_bytes(), 0u);
  EXPECT_EQ(s("save x"),
            "ERR denied file commands are disabled: the server was started without --state-dir");
}

TEST(ServeSession, BlocksAndPoke) {
  LocalSession s;
  EXPECT_EQ(s("writeblock 0x900 0102 03 0405"), "OK");
  EXPECT_EQ(s("cycle"), "OK 20");
  EXPECT_EQ(s("readblock 0x900 5"), "OK 0102030405");
  EXPECT_EQ(s("cycle"), "OK 40");
  EXPECT_EQ(s("pokeblock 0x902 AaBb"), "OK");
  EXPECT_EQ(s("peekblock 0x900 5"), "OK 0102AABB05");
  EXPECT_EQ(s("cycle"), "OK 40");
  EXPECT_TRUE(starts_with(s("poke 0x02 1"), "ERR no_storage "));  // Int_Reg is derived
}

}  // namespace
