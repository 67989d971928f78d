// dpc31 bridge, in process: the engine (client bytes -> RxD after TSYN, TxD -> bytes, cycle-exact),
// the telegram summaries of its log, the pty's hang-up and reset handling, the symlink rules.
// The end-to-end tests with the real binary and a master on the pty are in bridge_test.py.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "../lib/bridge/engine.hpp"
#include "../lib/bridge/pacing.hpp"
#include "../lib/bridge/pty.hpp"
#include "baud_search.hpp"
#include "bridge_engine_record.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/fdl_counters.hpp"
#include "firmware_host.hpp"

namespace {

using Bytes = std::vector<std::uint8_t>;
using dpc31::bridge::Engine;
using Line = testutil::LogLine;
using testutil::Sent;

constexpr std::uint32_t kT = 2500;  // bit time at 19200 baud, 48 MHz

Bytes sd1(std::uint8_t da, std::uint8_t sa, std::uint8_t fc) {
  return dpc31::fdl::encode(dpc31::fdl::make_frame(da, sa, fc));
}

const Bytes kFdlStatus = sd1(5, 2, 0x49);
const Bytes kStatusOk = {0x10, 0x02, 0x05, 0x00, 0x07, 0x16};

class BridgeEngine : public ::testing::Test, protected testutil::EngineRecord {
 protected:
  void SetUp() override { make(dpc31::bridge::LogDetail::telegrams); }
  void make(dpc31::bridge::LogDetail detail, std::uint32_t baud = 19200) {
    dpc31::bridge::Setup s;
    s.firmware = dpc31_find_firmware("DO4");
    s.baud = baud;
    s.log_detail = detail;
    EngineRecord::make(s);
  }

  // FDL_Status until the chip's baud search has found the rate: within one round of it
  // (docs/timing.md, "Baud_Search"; 453 requests back to back at 1.5 Mbaud from Start).
  void find_slave() {
    const std::uint64_t from = engine_->cycle();
    while (engine_->cycle() - from <= testutil::kBaudSearchRound) {
      const Bytes a = exchange(kFdlStatus);
      if (!a.empty()) {
        ASSERT_EQ(a, kStatusOk);
        return;
      }
    }
    FAIL() << "FDL_Status never answered";
  }

  // The NOTE lines from cycle `from` on, once every held line is out (the end of the run).
  std::vector<std::string> notes_since(std::uint64_t from) {
    engine_->flush_log();
    std::vector<std::string> notes;
    for (const Line& l : tagged("NOTE")) {
      if (l.cycle >= from) notes.push_back(l.text);
    }
    return notes;
  }
  // The events level's line at the first of a run of unanswered requests.
  static constexpr const char* kRunOpened =
      "no answer within the slot time (the next ones are counted until an answer)";

  // A DP start-up of DO4 as a master writes it, each request as soon as the last answer is in
  // (docs/bridge.md: DO4's GSD defaults; watchdog 100 x 10 x 10 ms), then `exchanges`
  // Data_Exchanges of 05 01.
  void start_up(int exchanges) {
    find_slave();
    bool fcb = true;  // the first SRD after FDL_Status has FCB = 1
    const auto srd = [&](Bytes du, std::optional<std::uint8_t> dsap) {
      const auto fc = static_cast<std::uint8_t>(fcb ? 0x7D : 0x5D);
      fcb = !fcb;
      const auto ssap = dsap ? std::optional<std::uint8_t>(62) : std::nullopt;
      return exchange(dpc31::fdl::encode(dpc31::fdl::make_frame(5, 2, fc, du, dsap, ssap)));
    };
    EXPECT_FALSE(srd({}, 60).empty());
    EXPECT_EQ(srd({0x88, 0x64, 0x0A, 0x00, 0x0D, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00}, 61),
              Bytes{0xE5});
    EXPECT_EQ(srd({0x21, 0x10}, 62), Bytes{0xE5});
    EXPECT_FALSE(srd({}, 60).empty());
    for (int i = 0; i < exchanges; ++i) EXPECT_FALSE(srd({0x05, 0x01}, std::nullopt).empty());
    engine_->run_until(engine_->cycle() + 48'000'000 / 10);
    engine_->flush_log();
  }
};

TEST_F(BridgeEngine, AnswersFdlStatusOnceTheBaudSearchReachesTheRate) {
  find_slave();
  const std::vector<Line> rx = tagged("RxD");
  const std::vector<Line> tx = tagged("TxD");
  ASSERT_EQ(tx.size(), 1u);
  // The answered request: its 6 characters, then MinTSDR = 11 bit times, then the answer.
  EXPECT_EQ(tx[0].cycle, rx.back().cycle + (6 * 11 + 11) * kT);
  EXPECT_EQ(tx[0].text, "10 02 05 00 07 16  | OK 5->2");
  EXPECT_EQ(rx.back().text, "10 05 02 49 50 16  | FDL_Status 2->5");
  // Unanswered ones: the next request follows TSYN after the slot time (100 bits) ran out.
  ASSERT_GE(rx.size(), 2u);
  EXPECT_EQ(rx[1].cycle - rx[0].cycle, (33 + 66 + 100) * kT);
  EXPECT_EQ(engine_->chip().wd_state(), dpc31::WdState::Baud_Control);
}

// docs/bridge.md, "The log": every line names its station: the master's requests, the slave's
// answers and its own events (slave5: --address 5), the bridge's notes.
TEST_F(BridgeEngine, EveryLogLineNamesItsStation) {
  start_up(2);
  ASSERT_FALSE(lines_.empty());
  for (const Line& l : lines_) {
    const std::string want = l.tag == "RxD"                      ? "master"
                             : l.tag == "NOTE" || l.tag == "LOG" ? "bridge"
                                                                 : "slave5";
    EXPECT_EQ(l.station, want) << l.tag << " " << l.text;
  }
  ASSERT_EQ(engine_->stations().size(), 1u);
  EXPECT_EQ(engine_->stations()[0].name, "slave5");
}

// The line as --pcap captures it: each request with the cycles of its first start bit and last
// stop bit (6 characters of 11 bits: 66 bit times), then the answer MinTSDR = 11 bit times after
// it (docs/timing.md), 6 characters long, sent by the station.
TEST_F(BridgeEngine, LineTelegramsCarryTheirCyclesAndSender) {
  find_slave();
  ASSERT_GE(line_.size(), 2u);
  const Sent& req = line_[line_.size() - 2];
  const Sent& ans = line_.back();
  EXPECT_EQ(req.sender, "master");
  EXPECT_EQ(req.bytes, kFdlStatus);
  EXPECT_EQ(req.end - req.start, 6u * 11 * kT);
  EXPECT_EQ(ans.sender, "slave5");
  EXPECT_EQ(ans.bytes, kStatusOk);
  EXPECT_EQ(ans.start, req.end + 11 * kT);
  EXPECT_EQ(ans.end - ans.start, 6u * 11 * kT);
  EXPECT_EQ(ans.start, tagged("TxD").back().cycle);
  // Every unanswered request before it is on the line too, the master's, in start order.
  for (std::size_t i = 0; i + 2 < line_.size(); ++i) {
    EXPECT_EQ(line_[i].sender, "master");
    EXPECT_LT(line_[i].start, line_[i + 1].start);
  }
}

TEST_F(BridgeEngine, EveryRequestWaitsTsynAfterTheLastAnswer) {
  find_slave();
  const std::uint64_t answer_start = tagged("TxD").back().cycle;
  const Bytes diag = exchange(dpc31::fdl::encode(
      dpc31::fdl::make_frame(5, 2, 0x7D, {}, std::uint8_t{60}, std::uint8_t{62})));
  EXPECT_EQ(diag, (Bytes{0x68, 0x0B, 0x0B, 0x68, 0x82, 0x85, 0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00,
                         0xFF, 0x0D, 0x04, 0xA0, 0x16}));
  EXPECT_EQ(tagged("RxD").back().cycle, answer_start + (6 * 11 + 33) * kT);
}

// A late answer is on the line until its end, which the chip knew when it armed it: a request
// the client writes while it is there waits TSYN after its end (docs/timing.md "Telegrams": TSYN
// of idle before every request), on the single chip's line as on a segment's
// (BridgeSegment.ALateAnswerIsItsStationsAndTheNextRequestWaitsForItsEnd). The single chip's
// bridge started it at once, into the late answer.
TEST_F(BridgeEngine, ARequestWrittenDuringALateAnswerWaitsTsynAfterItsEnd) {
  find_slave();
  const auto sd2 = [](std::uint8_t fc, Bytes du, std::uint8_t dsap) {
    return dpc31::fdl::encode(dpc31::fdl::make_frame(5, 2, fc, std::move(du), dsap, 62));
  };
  EXPECT_FALSE(exchange(sd2(0x7D, {}, 60)).empty());  // Slave_Diag, FCB 1
  // Set_Prm with MinTSDR 255 bit times: its own SC comes at the new MinTSDR (docs/timing.md),
  // past the slot time of 100 bits, so the client has no answer.
  EXPECT_TRUE(
      exchange(sd2(0x5D, {0x88, 0x64, 0x0A, 0xFF, 0x0D, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00}, 61))
          .empty());
  const std::size_t k = line_.size() - 1;
  const Sent prm = line_[k];
  ASSERT_EQ(prm.sender, "master");
  ASSERT_EQ(prm.bytes.size(), 22u);  // SD2: 4 + DA SA FC DSAP SSAP + 11 + FCS ED
  // The client writes FDL_Status while the late SC (one character, 255..266 bit times after the
  // Set_Prm's end) is on the line.
  engine_->run_until(prm.end + 258 * kT);
  const std::uint64_t written = engine_->cycle();
  ASSERT_LT(written, prm.end + 266 * kT);
  engine_->feed(kFdlStatus);
  EXPECT_TRUE(engine_->settle(48'000'000));
  engine_->flush_log();
  ASSERT_GE(line_.size(), k + 3);
  const Sent& late = line_[k + 1];
  const Sent& req = line_[k + 2];
  EXPECT_EQ(late.sender, "slave5");
  EXPECT_EQ(late.bytes, Bytes{0xE5});
  EXPECT_EQ(late.start, prm.end + 255 * kT);
  EXPECT_EQ(late.end, prm.end + 266 * kT);
  EXPECT_EQ(req.sender, "master");
  EXPECT_EQ(req.bytes, kFdlStatus);
  EXPECT_EQ(req.start, prm.end + (266 + 33) * kT);
}

TEST_F(BridgeEngine, SplitsTelegramsWrittenTogetherAndSendsEachAfterTsyn) {
  find_slave();
  // Global_Control (SDN broadcast: no answer) and FDL_Status in one write.
  Bytes both = dpc31::fdl::encode(
      dpc31::fdl::make_frame(127, 2, 0x46, {0x00, 0x00}, std::uint8_t{58}, std::uint8_t{62}));
  const std::size_t gc_len = both.size();
  both.insert(both.end(), kFdlStatus.begin(), kFdlStatus.end());
  const std::size_t before = tagged("RxD").size();
  EXPECT_EQ(exchange(both), kStatusOk);
  const std::vector<Line> rx = tagged("RxD");
  ASSERT_EQ(rx.size(), before + 2);
  EXPECT_NE(rx[before].text.find("Global_Control 2->127 SDN_high SAP 62->58 DU 00 00"),
            std::string::npos)
      << rx[before].text;
  EXPECT_EQ(rx[before + 1].cycle, rx[before].cycle + (gc_len * 11 + 33) * kT);
}

TEST_F(BridgeEngine, AnIncompleteTelegramWaitsForItsRest) {
  find_slave();
  engine_->feed(Bytes(kFdlStatus.begin(), kFdlStatus.begin() + 3));
  EXPECT_TRUE(engine_->partial());
  EXPECT_FALSE(engine_->busy());
  EXPECT_EQ(exchange(Bytes(kFdlStatus.begin() + 3, kFdlStatus.end())), kStatusOk);
  EXPECT_FALSE(engine_->partial());
}

TEST_F(BridgeEngine, BrokenBytesGoOnTheBusAsTheyCame) {
  find_slave();
  const std::uint32_t bad_sd = engine_->chip().fdl_counters().bad_sd;
  const std::uint32_t bad_fcs = engine_->chip().fdl_counters().bad_fcs;
  EXPECT_TRUE(exchange({0xFF}).empty());
  Bytes wrong = kFdlStatus;
  wrong[4] ^= 1;
  EXPECT_TRUE(exchange(wrong).empty());
  // A flushed half telegram is sent as it is, too.
  engine_->feed(Bytes(kFdlStatus.begin(), kFdlStatus.begin() + 2));
  engine_->flush_partial();
  EXPECT_TRUE(engine_->settle(48'000'000));
  EXPECT_TRUE(engine_->take_output().empty());
  EXPECT_EQ(engine_->chip().fdl_counters().bad_sd, bad_sd + 1);
  EXPECT_EQ(engine_->chip().fdl_counters().bad_fcs, bad_fcs + 1);
  const std::vector<Line> rx = tagged("RxD");
  ASSERT_GE(rx.size(), 3u);
  EXPECT_EQ(rx[rx.size() - 3].text, "FF  | broken telegram (bad_sd)");
  EXPECT_EQ(rx[rx.size() - 2].text, "10 05 02 49 51 16  | broken telegram (bad_fcs)");
  EXPECT_EQ(rx[rx.size() - 1].text, "10 05  | broken telegram (truncated)");
  // And the slave still answers.
  EXPECT_EQ(exchange(kFdlStatus), kStatusOk);
}

// A client that writes garbage as fast as it can (issue 14, finding 8): 1 MiB of FF bytes, which
// cannot start a telegram, in 4 KiB writes 20 ms of chip time apart. What the bus cannot carry
// is dropped and reported at most once a second of chip time; consecutive garbage goes on the
// bus in runs of at most 256 bytes, one log line each. Every byte is accounted for: carried,
// dropped, or discarded when the client closes.
TEST_F(BridgeEngine, AGarbageFloodIsLoggedInAFewLinesAndDiscardedWithItsClient) {
  find_slave();
  lines_.clear();
  const Bytes piece(4096, 0xFF);
  const std::uint64_t start = engine_->cycle();
  for (int i = 0; i < 256; ++i) {
    engine_->feed(piece);
    engine_->run_until(engine_->cycle() + 48'000'000 / 50);
  }
  const std::uint64_t seconds = (engine_->cycle() - start) / 48'000'000;
  engine_->client_gone();
  const auto number_before = [](const std::string& text, const std::string& what) {
    const auto at = text.find(what);
    return at == std::string::npos ? std::uint64_t{0}
                                   : std::stoull(text.substr(text.rfind('(', at) + 1));
  };
  std::uint64_t dropped = 0;
  std::uint64_t dropped_lines = 0;
  std::uint64_t discarded = 0;
  for (const Line& l : tagged("NOTE")) {
    if (l.text.find(" bytes dropped in the last ") != std::string::npos) {
      ++dropped_lines;
      dropped += std::stoull(l.text);
    }
    discarded += number_before(l.text, " bytes) dropped: they had not reached the bus");
  }
  // The runs are alike: the log folds a run equal to the one before (docs/bridge.md, "The log")
  // and says how many times it repeated.
  std::uint64_t carried = 0;
  std::uint64_t run = 0;      // bytes of the last RxD line
  std::uint64_t repeats = 0;  // of it, the most a LOG line has said
  for (const Line& l : lines_) {
    if (l.tag == "LOG" && l.text.starts_with("last line repeated ")) {
      repeats = std::max<std::uint64_t>(repeats, std::stoull(l.text.substr(19)));
    } else if (l.tag == "RxD") {
      carried += run * repeats;
      repeats = 0;
      const std::string hex = l.text.substr(0, l.text.find("  |"));
      run = (hex.size() + 1) / 3;
      EXPECT_LE(run, dpc31::bridge::kMaxGarbageRun) << l.text.substr(0, 80);
      carried += run;
    }
  }
  carried += run * repeats;
  EXPECT_EQ(carried + dropped + discarded, 256u * 4096u);
  EXPECT_GT(dropped, 900'000u);
  EXPECT_LE(dropped_lines, seconds + 2) << seconds << " s";
  EXPECT_LT(lines_.size(), 200u);  // before: a line per dropped byte
  // Gone with the client: only what is on the line still finishes (one run at most).
  const std::uint64_t closed = engine_->cycle();
  EXPECT_TRUE(engine_->settle(48'000'000));
  EXPECT_LE(engine_->cycle() - closed, (dpc31::bridge::kMaxGarbageRun * 11 + 100) * kT);
}

// The drop line says what is true (docs/bridge.md, "One request at a time": one line a second of
// chip time at most, "N bytes dropped in the last T ms"): one byte is "1 byte"; T runs from the
// first byte it counts, rounded up, so a drop reported in its own cycle is "in the last 1 ms" (it
// said "1 bytes ... in the last 0 ms"), and one 1001.5 ms ago (48 072 000 clocks at 48 MHz,
// docs/timing.md) "in the last 1002 ms" (it said 1001).
TEST_F(BridgeEngine, TheDropLineCountsItsBytesAndTheTimeTheyTook) {
  engine_->run_until(48'000'000);  // a second since the start: the first drop is reported at once
  lines_.clear();
  // Nothing carried yet: the queue holds kMaxQueuedBytes, the next byte is dropped.
  engine_->feed(Bytes(dpc31::bridge::kMaxQueuedBytes, 0xFF));
  const std::uint64_t first = engine_->cycle();
  engine_->feed(Bytes{0xFF});
  engine_->feed(Bytes{0xFF, 0xFF});  // within a second of that report: counted for the next one
  engine_->run_until(first + 48'072'000);
  engine_->flush_log();
  std::vector<std::pair<std::uint64_t, std::string>> drops;
  for (const Line& l : tagged("NOTE")) {
    if (l.text.find(" dropped in the last ") != std::string::npos)
      drops.emplace_back(l.cycle, l.text);
  }
  const std::string why = " ms: the client writes faster than the bus carries";
  EXPECT_EQ(drops, (std::vector<std::pair<std::uint64_t, std::string>>{
                       {first, "1 byte dropped in the last 1" + why},
                       {first + 48'072'000, "2 bytes dropped in the last 1002" + why}}));
}

// The next master after such a flood is answered within one round of the baud search (the
// flood fixed no rate, so Baud_Control has expired): docs/timing.md, Baud_Search: max(4096 bit
// times, 20 ms) at each of the 10 rates, 12 M first (tests/baud_search.hpp). Plus one unanswered
// FDL_Status period (66 + slot 100 + TSYN 33 bit times) for the request in progress when the
// search reaches 19200 baud.
TEST_F(BridgeEngine, TheNextMasterAfterAFloodIsAnsweredWithinOneBaudSearchRound) {
  find_slave();
  for (int i = 0; i < 256; ++i) {
    engine_->feed(Bytes(4096, 0xFF));
    engine_->run_until(engine_->cycle() + 48'000'000 / 50);
  }
  EXPECT_EQ(engine_->chip().wd_state(), dpc31::WdState::Baud_Search);
  engine_->client_gone();
  const std::uint64_t closed = engine_->cycle();
  constexpr std::uint64_t kRound = testutil::kBaudSearchRound;
  constexpr std::uint64_t kPeriod = (66 + 100 + 33) * kT;
  for (int i = 0; i < 1000 && engine_->cycle() - closed <= kRound + 2 * kPeriod; ++i) {
    if (exchange(kFdlStatus) == kStatusOk) break;
  }
  const std::vector<Line> tx = tagged("TxD");
  ASSERT_FALSE(tx.empty());
  EXPECT_EQ(tx.back().text, "10 02 05 00 07 16  | OK 5->2");
  EXPECT_GT(tx.back().cycle, closed);
  EXPECT_LE(tx.back().cycle - closed, kRound + kPeriod + (dpc31::bridge::kMaxGarbageRun * 11) * kT);
}

TEST_F(BridgeEngine, TimePassesWithoutClientAndStatesAreLogged) {
  const std::uint64_t c0 = engine_->cycle();
  engine_->run_until(c0 + 48'000'000);  // one second of silence
  EXPECT_GE(engine_->cycle(), c0 + 48'000'000);
  EXPECT_TRUE(engine_->take_output().empty());
  ASSERT_FALSE(lines_.empty());
  EXPECT_EQ(lines_.front().tag, "CHIP");  // Start_SPC3 by the firmware's main()
}

// The log's lines come in cycle order (issue 18 item 4): a request is known up to TSYN before it
// goes on RxD and an answer only at its end, yet what happens meanwhile (the bridge's notes, the
// firmware's port writes, state changes) carries its own cycle.
TEST_F(BridgeEngine, LinesComeInCycleOrder) {
  find_slave();
  const std::uint64_t answer = tagged("TxD").back().cycle;
  // A request written right after an answer: its RxD line is known TSYN ahead; a note (the
  // client went away, say) comes before it.
  engine_->feed(kFdlStatus);
  engine_->run_until(engine_->cycle() + kT);
  engine_->note("in the TSYN wait");
  EXPECT_TRUE(engine_->settle(48'000'000));
  engine_->flush_log();
  ASSERT_GE(lines_.size(), 3u);
  const Line& rx = lines_[lines_.size() - 2];
  const Line& note = lines_[lines_.size() - 3];
  EXPECT_EQ(note.text, "in the TSYN wait");
  EXPECT_EQ(rx.tag, "RxD");
  EXPECT_EQ(rx.cycle, answer + (6 * 11 + 33) * kT);  // TSYN after the answer's 6 characters
  EXPECT_LT(note.cycle, rx.cycle);
  EXPECT_EQ(lines_.back().tag, "TxD");
  // A whole start-up at 1.5 Mbaud.
  make(dpc31::bridge::LogDetail::telegrams, 1'500'000);
  start_up(5);
  ASSERT_FALSE(tagged("PORT").empty());
  ASSERT_FALSE(tagged("STATE").empty());
  ASSERT_GE(tagged("TxD").size(), 10u);
  for (std::size_t i = 1; i < lines_.size(); ++i) {
    EXPECT_LE(lines_[i - 1].cycle, lines_[i].cycle)
        << lines_[i - 1].tag << " " << lines_[i - 1].text << " / " << lines_[i].tag << " "
        << lines_[i].text;
  }
}

// The default level (events): state changes and faults, no line for a healthy telegram and a
// PORT line only when the value changes.
TEST_F(BridgeEngine, EventsLevelLogsStateChangesAndFaultsOnly) {
  make(dpc31::bridge::LogDetail::events);
  start_up(50);
  EXPECT_TRUE(tagged("RxD").empty());
  EXPECT_TRUE(tagged("TxD").empty());
  // DO4 writes its outputs at every Data_Exchange; logged: the power-on value and 05 once.
  std::vector<std::string> outputs;
  for (const Line& l : tagged("PORT")) {
    if (l.text.rfind("DO4 outputs", 0) == 0) outputs.push_back(l.text);
  }
  EXPECT_EQ(outputs.back(), "DO4 outputs = 0x05");
  EXPECT_EQ(std::count(outputs.begin(), outputs.end(), "DO4 outputs = 0x05"), 1);
  EXPECT_FALSE(tagged("STATE").empty());
  // The FDL_Status requests of the baud search: one line when the first goes unanswered, one
  // when a request is answered again.
  const std::vector<Line> notes = tagged("NOTE");
  ASSERT_EQ(notes.size(), 2u);
  EXPECT_EQ(notes[0].text,
            "no answer within the slot time (the next ones are counted until an answer)");
  EXPECT_EQ(notes[1].text.rfind("answered again, after ", 0), 0u) << notes[1].text;
  EXPECT_LT(lines_.size(), 20u);
  // A fault is logged: bytes that are no telegram.
  lines_.clear();
  EXPECT_TRUE(exchange({0xFF}).empty());
  engine_->flush_log();
  const std::vector<Line> rx = tagged("RxD");
  ASSERT_EQ(rx.size(), 1u);
  EXPECT_EQ(rx[0].text, "FF  | broken telegram (bad_sd)");
}

// A run of unanswered requests is two lines at the events level also when it is one request long
// (an outside report: the run of one was never closed, its "counted until an answer" left open).
TEST_F(BridgeEngine, EventsLevelClosesEveryRunOfUnansweredRequests) {
  make(dpc31::bridge::LogDetail::events);
  find_slave();
  const std::uint64_t from = engine_->cycle();
  const Bytes absent = sd1(9, 2, 0x49);  // FDL_Status to a station nobody has
  EXPECT_TRUE(exchange(absent).empty());
  for (int i = 0; i < 20; ++i) EXPECT_EQ(exchange(kFdlStatus), kStatusOk);
  EXPECT_TRUE(exchange(absent).empty());
  EXPECT_TRUE(exchange(absent).empty());
  EXPECT_EQ(exchange(kFdlStatus), kStatusOk);
  EXPECT_EQ(
      notes_since(from),
      (std::vector<std::string>{kRunOpened, "answered again, after 1 request without an answer",
                                kRunOpened, "answered again, after 2 requests without an answer"}));
}

// A run never answered is counted when it ends otherwise: the client goes away, or the bridge
// stops (audit s30 a-master, finding 8: "counted until an answer", and no answer came, so the
// count was never written). docs/bridge.md, "The log".
TEST_F(BridgeEngine, EventsLevelCountsARunThatEndsWithoutAnAnswer) {
  make(dpc31::bridge::LogDetail::events);
  find_slave();
  const std::uint64_t from = engine_->cycle();
  const Bytes absent = sd1(9, 2, 0x49);  // FDL_Status to a station nobody has
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(exchange(absent).empty());
  engine_->client_gone();
  for (int i = 0; i < 2; ++i) EXPECT_TRUE(exchange(absent).empty());
  EXPECT_EQ(notes_since(from),
            (std::vector<std::string>{
                kRunOpened, "3 requests without an answer, then the client went away", kRunOpened,
                "2 requests without an answer, then the bridge stopped"}));
}

// Garbage on the pty at the line's own speed (issue 29: 41.5 MB of log in 10 s): every broken
// telegram differs from the one before, so only the log's bound holds it (docs/bridge.md, "The
// log"): at most LogLimiter::kBurst lines per 48 000 000 cycles at the events level, and one LOG
// line per window with how many were left out.
TEST_F(BridgeEngine, GarbageOnThePtyKeepsTheLogBounded) {
  make(dpc31::bridge::LogDetail::events, 1'500'000);
  constexpr std::uint64_t kWindow = dpc31::LogLimiter::kWindow;
  const std::uint64_t start = engine_->cycle();
  std::uint64_t sent = 0;
  for (std::uint32_t i = 0; engine_->cycle() < start + 3 * kWindow; ++i) {
    // 3 characters that are no telegram and start none (20h..5Fh: no start delimiter), each run
    // unlike the one before; then 100 idle bit times at 1.5 Mbaud.
    engine_->feed(Bytes{0x01, static_cast<std::uint8_t>(0x20 + i % 64),
                        static_cast<std::uint8_t>(0x20 + (i / 64) % 64)});
    engine_->run_until(engine_->cycle() + 100 * 32);
    ++sent;
  }
  engine_->flush_log();
  const std::vector<Line> rx = tagged("RxD");
  const std::vector<Line> left = tagged("LOG");
  EXPECT_GT(sent, 40'000u);
  // Four windows touched (the run starts inside the first): kBurst lines each at most.
  EXPECT_LE(lines_.size(), 4 * (dpc31::LogLimiter::kBurst + 1));
  EXPECT_GE(rx.size(), 3 * (dpc31::LogLimiter::kBurst - 10));  // the rest: STATE, NOTE lines
  std::uint64_t said = 0;
  std::size_t windows = 0;
  for (const Line& l : left) {
    if (l.text.find(" log lines left out") == std::string::npos) continue;
    said += std::stoull(l.text);  // "N log lines left out ..."
    ++windows;
  }
  EXPECT_GE(windows, 3u);
  // Every broken telegram is either a line or counted.
  EXPECT_EQ(rx.size() + said, sent);
}

// docs/bring-up.md, section 7: an SPC3 whose firmware gives its Cfg verdict but never reads
// New_Din_Buffer_Cmd (tests/input_only_plugin.c built with FORGETS_DIN) stays in Wait_Cfg, and
// the bridge's log carries the chip's line about it once, as every chip line: a CHIP line of
// slave5. At 19 200 baud a Slave_Diag poll comes every 352 bit times (18.3 ms), the first 176
// bit times (9.2 ms) after the Chk_Cfg is acted on (its SC after TSDR 11, 11 bits, idle 33, the
// request's 121): the second poll is the first 10 ms past the verdict.
TEST_F(BridgeEngine, AnSpc3FirmwareThatNeverReadsNewDinBufferCmdIsToldOnceInTheLog) {
  dpc31::bridge::Setup s;
  s.chip.profile = dpc31::Profile::spc3;
  s.firmware = &dpc31::find_firmware(PLUGIN_FORGETS_DIN);
  EngineRecord::make(s);
  find_slave();
  bool fcb = true;  // the first SRD after FDL_Status has FCB = 1
  const auto srd = [&](Bytes du, std::uint8_t dsap) {
    const auto fc = static_cast<std::uint8_t>(fcb ? 0x7D : 0x5D);
    fcb = !fcb;
    return exchange(dpc31::fdl::encode(dpc31::fdl::make_frame(5, 2, fc, du, dsap, 62)));
  };
  // The plug-in's GSD defaults: Ident 0E10h, Cfg 10, the Spec_User_Prm_Byte 00.
  EXPECT_EQ(srd({0x88, 0x0A, 0x0A, 0x00, 0x0E, 0x10, 0x00, 0x00}, 61), Bytes{0xE5});
  EXPECT_EQ(srd({0x10}, 62), Bytes{0xE5});
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(srd({}, 60).empty());
  EXPECT_EQ(engine_->chip().dp_state(), dpc31::DpState::Wait_Cfg);
  engine_->flush_log();
  std::size_t said = 0;
  for (const Line& l : tagged("CHIP")) {
    if (l.text.starts_with("master 2 is refused (Slave_Diag with Station_Not_Ready): the SPC3 is "
                           "still in Wait_Cfg at least 10 ms after User_Cfg_Data_Okay")) {
      EXPECT_EQ(l.station, "slave5");
      ++said;
    }
  }
  EXPECT_EQ(said, 1u);
}

TEST(BridgeSummary, NamesServicesAndAnswers) {
  using dpc31::bridge::telegram_summary;
  using dpc31::fdl::encode;
  using dpc31::fdl::make_frame;
  EXPECT_EQ(telegram_summary(Bytes{0xE5}), "SC (short acknowledge)");
  EXPECT_EQ(telegram_summary(Bytes{0xDC, 0x02, 0x02}), "token 2->2");
  EXPECT_EQ(telegram_summary(encode(make_frame(5, 2, 0x5D, {0x05, 0x01}))),
            "Data_Exchange 2->5 SRD_high FCB 0 DU 05 01");
  EXPECT_EQ(telegram_summary(
                encode(make_frame(5, 2, 0x7D, {0x21, 0x10}, std::uint8_t{62}, std::uint8_t{62}))),
            "Chk_Cfg 2->5 SRD_high FCB 1 SAP 62->62 DU 21 10");
  EXPECT_EQ(telegram_summary(encode(make_frame(2, 5, 0x0A, {0x51}))), "DH 5->2 DU 51");
  EXPECT_EQ(telegram_summary(Bytes{}), "empty");
  EXPECT_EQ(telegram_summary(Bytes{0x68, 0x05}), "broken telegram (truncated)");
}

// --- the pty ---

termios eight_e1(int fd, speed_t speed) {
  termios t{};
  EXPECT_EQ(tcgetattr(fd, &t), 0);
  cfmakeraw(&t);
  t.c_cflag = CS8 | PARENB | CREAD | CLOCAL;
  cfsetspeed(&t, speed);
  return t;
}

TEST(BridgePty, HangUpResetAndTheNextClientSetsTheSameSpeed) {
  dpc31::bridge::Pty pty;
  EXPECT_FALSE(pty.client_open());  // opened and closed once: hang-up until a client comes
  EXPECT_FALSE(pty.changed());
  EXPECT_EQ(pty.speed(), 38400u);

  int c = ::open(pty.slave_name().c_str(), O_RDWR | O_NOCTTY);
  ASSERT_GE(c, 0);
  EXPECT_TRUE(pty.client_open());
  termios t = eight_e1(c, B19200);
  EXPECT_EQ(tcsetattr(c, TCSANOW, &t), 0) << std::strerror(errno);
  EXPECT_TRUE(pty.changed());
  EXPECT_EQ(pty.speed(), 19200u);
  // The chip's answer, never read by this client.
  const unsigned char answer[] = {0x10, 0x02, 0x05, 0x00, 0x07, 0x16};
  EXPECT_EQ(pty.write(answer, sizeof answer), sizeof answer);
  const unsigned char req[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
  ASSERT_EQ(::write(c, req, sizeof req), static_cast<ssize_t>(sizeof req));
  unsigned char buf[64];
  EXPECT_EQ(pty.read(buf, sizeof buf), static_cast<long>(sizeof req));
  EXPECT_EQ(pty.read(buf, sizeof buf), 0);  // nothing more, client still there
  ::close(c);
  EXPECT_FALSE(pty.client_open());
  EXPECT_EQ(pty.read(buf, sizeof buf), -1);  // EIO: hang-up

  pty.reset();
  EXPECT_FALSE(pty.changed());
  EXPECT_EQ(pty.speed(), 38400u);
  c = ::open(pty.slave_name().c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(c, 0);
  t = eight_e1(c, B19200);
  EXPECT_EQ(tcsetattr(c, TCSANOW, &t), 0) << std::strerror(errno);
  EXPECT_EQ(::read(c, buf, sizeof buf), -1);  // the old answer was flushed
  EXPECT_EQ(errno, EAGAIN);
  termios now{};
  ASSERT_EQ(tcgetattr(c, &now), 0);
  EXPECT_EQ(now.c_lflag & (ECHO | ICANON), 0u);  // raw: the client's bytes never come back
  ::close(c);
}

TEST(BridgePty, SymlinkRules) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("dpc31-bridge-test-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string link = (dir / "dp0").string();
  // New, then replaced (a stale one), then removed only while it is still ours.
  EXPECT_EQ(dpc31::bridge::make_link(link, "/dev/pts/999999"), "");
  EXPECT_EQ(dpc31::bridge::make_link(link, "/dev/pts/1"), "");
  EXPECT_EQ(std::filesystem::read_symlink(link).string(), "/dev/pts/1");
  dpc31::bridge::remove_link(link, "/dev/pts/2");
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  dpc31::bridge::remove_link(link, "/dev/pts/1");
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(link)));
  // A regular file is never replaced.
  const std::string file = (dir / "file").string();
  std::ofstream(file) << "keep\n";
  EXPECT_NE(dpc31::bridge::make_link(file, "/dev/pts/1").find("not a symlink"), std::string::npos);
  EXPECT_TRUE(std::filesystem::is_regular_file(file));
  // A symlink that is not a pty's (a user's own: a dotfile, /dev/stdout) is refused and kept as
  // it was, dangling or not (docs/bridge.md, "The symlink").
  for (const std::string& to : {file, std::string("/proc/self/fd/1"), (dir / "gone").string()}) {
    const std::string own = (dir / "own").string();
    std::filesystem::remove(own);
    std::filesystem::create_symlink(to, own);
    EXPECT_EQ(
        dpc31::bridge::make_link(own, "/dev/pts/1"),
        own + " is a symlink to " + to + ", not to a pty in /dev/pts/: refusing to replace it");
    EXPECT_EQ(std::filesystem::read_symlink(own).string(), to);
  }
  std::filesystem::remove_all(dir);
}

// docs/bridge.md, "Pacing", free: "Between exchanges chip time advances with the wall clock, so
// chip time runs ahead of wall time by the sum of the exchanges' durations". The loop's turns
// with a client take a little longer than their 1 ms wait (the poll's own overhead); each kept
// only 1 ms of chip time, and chip time ran at about 0.9 of the wall clock's (audit s30 a-master,
// finding 7). Made-up times: 1000 turns 1.08 ms apart at 48 MHz, 51 840 cycles each, and one
// exchange of 96 000 cycles (2 ms) in the middle that takes no wall time.
TEST(BridgePacing, FreeChipTimeKeepsUpWithTheWallClockBetweenExchanges) {
  using namespace std::chrono_literals;
  dpc31::bridge::Pacing pacing(false, 48'000'000, 5ms);
  const auto t0 = dpc31::bridge::Pacing::Clock::time_point{} + 1h;
  pacing.anchor(t0, 0);
  std::uint64_t chip = 0;
  for (int turn = 1; turn <= 1000; ++turn) {
    const auto now = t0 + turn * 1080us;
    chip = std::max(chip, pacing.target(now, 1ms, chip));
    if (turn == 500) {
      chip += 96'000;  // settle(): the exchange, at no wall time
      pacing.anchor(now, chip);
    }
  }
  EXPECT_EQ(chip, 1000u * 51'840 + 96'000);
}

// A turn runs at most its bound (5 ms: 240 000 cycles): free drops what is left (no debt), realtime
// catches it up over the next turns (docs/bridge.md, "Pacing").
TEST(BridgePacing, ABoundedTurnFreeDropsTheRestRealtimeCatchesUp) {
  using namespace std::chrono_literals;
  const auto t0 = dpc31::bridge::Pacing::Clock::time_point{} + 1h;
  dpc31::bridge::Pacing free(false, 48'000'000, 5ms);
  free.anchor(t0, 0);
  EXPECT_EQ(free.target(t0 + 20ms, 1ms, 0), 240'000u);        // 20 ms due: 5 ms run
  EXPECT_EQ(free.target(t0 + 21ms, 1ms, 240'000), 288'000u);  // then 1 ms later: 1 ms more
  dpc31::bridge::Pacing realtime(true, 48'000'000, 5ms);
  realtime.anchor(t0, 0);
  EXPECT_EQ(realtime.target(t0 + 20ms, 1ms, 0), 240'000u);        // 21 ms due (to the wake-up)
  EXPECT_EQ(realtime.target(t0 + 21ms, 1ms, 240'000), 480'000u);  // 22 ms due: 5 ms more
  EXPECT_EQ(realtime.wall_cycle(t0 + 21ms), 1'008'000u);
}

}  // namespace
