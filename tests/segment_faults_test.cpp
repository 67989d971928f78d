// The fault catalogue of a segment (docs/segment.md, "Fault catalogue"): each scripted fault
// breaks one rule, and the bus check counts exactly that violation. The rules (EN 50170 /
// IEC 61158-4-3, docs/timing.md): an answer starts no sooner than min TSDR (11 bit times) and no
// later than the slot time TSL after the request's end; a request or token follows at least TSYN
// (33 bit times) of idle; the answer comes from the station asked, to the master that asked; a
// frame's FCS is the sum of DA..DU; the token-lost timeout is TTO = TSL x (6 + 2 x n) for the
// master of address n; only the token holder sends, and after its TTR it starts no new message
// cycle; two drivers at once are a collision.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "bus_check.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/fdl.hpp"
#include "responder.hpp"
#include "segment.hpp"

namespace dpc31 {
namespace {

constexpr std::uint32_t kBaud = 1'500'000;
constexpr std::uint64_t kTsyn = 33;
constexpr std::uint64_t kSlot = 100;
constexpr std::uint64_t kTtr = 2000;

std::vector<std::uint8_t> bytes_of(const fdl::Frame& f) { return fdl::encode(f); }
std::vector<std::uint8_t> fdl_status(std::uint8_t da, std::uint8_t sa) {
  return bytes_of(
      fdl::make_frame(da, sa, fdl::make_request_fc(fdl::Function::FDL_Status, false, false)));
}
// An FDL_Status answer: SD1, "passive station".
std::vector<std::uint8_t> status_answer(std::uint8_t da, std::uint8_t sa) {
  return bytes_of(fdl::make_frame(da, sa, fdl::make_response_fc(fdl::Response::OK)));
}

// A line with a master (2), a scripted station and, if asked, a spc3 at address 5.
struct Faults {
  // ttr = 0: a line without a token (one master); else masters 2 and 3 share it.
  explicit Faults(bool with_chip = false, std::uint64_t ttr = 0)
      : seg(kBaud),
        timing_{seg.bit_cycles(),
                11,
                kSlot,
                kTsyn,
                ttr,
                ttr == 0 ? std::vector<std::uint8_t>{2} : std::vector<std::uint8_t>{2, 3}},
        check(timing_, [this](const LogRecord& r) { log.push_back(r); }) {
    if (with_chip) {
      ResponderConfig rc;
      rc.slave.address = 5;
      user = std::make_unique<Responder>(rc);
      chip = seg.add_chip("spc3", ChipOptions{Profile::spc3});
      DirectBus bus(seg.chip(chip));
      user->init(bus);
      seg.set_firmware(chip, [this](BusPort& b) { user->isr(b); });
    }
    master = seg.add_sender("master 2");
    rogue = seg.add_sender("rogue");
    check.watch(seg);
  }
  std::uint64_t bits(std::uint64_t n) const { return n * seg.bit_cycles(); }
  // The line quiet to `cycle`, every telegram handed to the check.
  void settle(std::uint64_t cycle) {
    seg.run_until(cycle);
    seg.flush();
    check.idle_until(seg.cycle());
  }
  // FDL_Status from master 2 to station 5 until the chips have found the rate (their baud
  // search) and station 5 answers; the line then stands idle for good.
  void find_rate() {
    for (int i = 0; i < dpc31::kStartupTries; ++i) {
      const std::uint64_t end = seg.send(master, fdl_status(5, 2), seg.cycle() + bits(kTsyn));
      seg.run_until(end + bits(kSlot + 20));
      if (seg.chip(chip).wd_state() != WdState::Baud_Search) break;
    }
    settle(seg.cycle() + bits(200));
    check = BusCheck(timing_, [this](const LogRecord& r) { log.push_back(r); });
    check.watch(seg);
    log.clear();
  }
  // Master 2 asks station 20 for its FDL status; the rogue answers `answer` `delay` bit times
  // after the request's end.
  void ask_and_answer(const std::vector<std::uint8_t>& answer, std::uint64_t delay) {
    const std::uint64_t end = seg.send(master, fdl_status(20, 2), bits(100));
    seg.send(rogue, answer, end + bits(delay));
    settle(end + bits(400));
  }
  // Everything but `v` is zero, `v` is n.
  void expect_only(BusViolation v, std::uint64_t n) {
    for (std::size_t k = 0; k < kBusViolationKinds; ++k) {
      const auto kind = static_cast<BusViolation>(k);
      EXPECT_EQ(check.count(kind), kind == v ? n : 0) << bus_violation_name(kind);
    }
    EXPECT_FALSE(log.empty());
  }
  Segment seg;
  BusTiming timing_;
  BusCheck check;
  std::vector<LogRecord> log;
  std::unique_ptr<Responder> user;
  std::size_t chip = 0;
  std::size_t master = 0;
  std::size_t rogue = 0;
};

TEST(SegmentFaults, AStationThatAnswersLate) {
  Faults f;
  // TSL + 1 bit after the request's end: one bit too late.
  f.ask_and_answer(status_answer(2, 20), kSlot + 1);
  f.expect_only(BusViolation::late_answer, 1);
}

TEST(SegmentFaults, AnAnswerAtTheSlotTimeIsInTime) {
  Faults f;
  f.ask_and_answer(status_answer(2, 20), kSlot);
  EXPECT_EQ(f.check.total(), 0U);
}

// The answer window ends at the slot time (docs/timing.md, "The master's wait"): a telegram
// starting later is no answer to the request. The request (6 characters of 11 bit times) starts
// at 100 bit times and ends at 166; `delay` counts from there.
constexpr std::uint64_t kRequestEnd = 100 + 6 * 11;

// The asked station's own answer is late until the asker may send again, TSYN after the slot time
// (docs/segment.md, `late_answer`): at TSL + TSYN - 1 = 132 bit times, still late.
TEST(SegmentFaults, TheAskedStationsAnswerIsLateUntilTheAskerMaySendAgain) {
  Faults f;
  f.ask_and_answer(status_answer(2, 20), kSlot + kTsyn - 1);
  f.expect_only(BusViolation::late_answer, 1);
  ASSERT_EQ(f.log.size(), 1U);
  EXPECT_EQ(f.log[0].cycle, f.bits(kRequestEnd + kSlot + kTsyn - 1));
  EXPECT_EQ(f.log[0].text,
            "bus: late_answer: answer to station 20 132 bit times after the request (slot time "
            "100)");
}

// An answer `after` bit times past the request's end that the check counts as one unsolicited
// telegram, with its one log line at the answer's start.
void expect_one_unsolicited(const std::vector<std::uint8_t>& answer, std::uint64_t after,
                            const std::string& line) {
  Faults f;
  f.ask_and_answer(answer, after);
  f.expect_only(BusViolation::unsolicited, 1);
  ASSERT_EQ(f.log.size(), 1U);
  EXPECT_EQ(f.log[0].cycle, f.bits(kRequestEnd + after));
  EXPECT_EQ(f.log[0].text, line);
}

// From TSL + TSYN on it is an answer nobody asked for.
TEST(SegmentFaults, TheAskedStationsAnswerFromTheSlotTimePlusTsynIsUnsolicited) {
  expect_one_unsolicited(status_answer(2, 20), kSlot + kTsyn,
                         "bus: unsolicited: an answer from station 20 nobody asked for");
}

// Another station's telegram after the slot time is not the request's wrong answer: unsolicited.
TEST(SegmentFaults, AnotherStationsAnswerAfterTheSlotTimeIsUnsolicited) {
  expect_one_unsolicited(status_answer(2, 21), kSlot + 1,
                         "bus: unsolicited: an answer from station 21 nobody asked for");
}

// An SC from TSL + TSYN on is unsolicited too: it carries no address (EN 50170: the single
// character E5h), so its sender is named, as short_tsyn names it (review B, finding 6). Before, the
// line said "an answer from station 0".
TEST(SegmentFaults, AnUnsolicitedScNamesItsSender) {
  expect_one_unsolicited({fdl::SC}, kSlot + kTsyn,
                         "bus: unsolicited: an SC from rogue nobody asked for");
}

// A telegram that does not decode after the slot time is one bad frame, no late answer.
TEST(SegmentFaults, ABrokenTelegramAfterTheSlotTimeIsOneBadFrame) {
  Faults f;
  std::vector<std::uint8_t> request = fdl_status(9, 2);
  ++request[request.size() - 2];  // SD1: SD DA SA FC FCS ED
  f.ask_and_answer(request, kSlot + 1);
  f.expect_only(BusViolation::bad_frame, 1);
  ASSERT_EQ(f.log.size(), 1U);
  const std::uint64_t at = f.bits(kRequestEnd + kSlot + 1);
  EXPECT_EQ(f.log[0].cycle, at);
  EXPECT_EQ(f.log[0].text, fmt::format("bus: bad_frame: 6 bytes from cycle {} do not decode ({})",
                                       at, fdl::error_name(fdl::Error::bad_fcs)));
}

// docs/timing.md "Telegrams": a bad character "discards the telegram" whatever its bytes read, so
// the line's view of a request with a parity error in its FCS (character 3: FDL_Status is SD DA
// SA FC FCS ED) is a bad frame, no request: the good answer 11 bit times after it answers nothing.
TEST(SegmentFaults, AParityErrorMakesATelegramABadFrameOnTheLine) {
  Faults f;
  std::vector<LineTelegram> line;
  f.seg.on_telegram = [&f, &line](const LineTelegram& t) {
    line.push_back(t);
    f.check.telegram(t, f.seg.name(t.from));
  };
  const std::uint64_t start = f.bits(100);
  const std::uint64_t end =
      f.seg.send(f.master, fdl_status(20, 2), start, UartFault{3, UartFault::Kind::parity});
  f.seg.send(f.rogue, status_answer(2, 20), end + f.bits(11));
  f.settle(end + f.bits(400));
  ASSERT_EQ(line.size(), 2U);
  EXPECT_EQ(line[0].fault.kind, UartFault::Kind::parity);
  EXPECT_EQ(line[0].fault.char_index, 3);
  EXPECT_EQ(line[0].bytes, fdl_status(20, 2));  // the bytes read well
  EXPECT_EQ(line[1].fault.kind, UartFault::Kind::none);
  for (std::size_t k = 0; k < kBusViolationKinds; ++k) {
    const auto kind = static_cast<BusViolation>(k);
    const bool counted = kind == BusViolation::bad_frame || kind == BusViolation::unsolicited;
    EXPECT_EQ(f.check.count(kind), counted ? 1U : 0U) << bus_violation_name(kind);
  }
  ASSERT_EQ(f.log.size(), 2U);
  EXPECT_EQ(f.log[0].text,
            fmt::format("bus: bad_frame: 6 bytes from cycle {} do not decode (character 3: "
                        "parity error)",
                        start));
  EXPECT_EQ(f.log[1].text, "bus: unsolicited: an answer from station 20 nobody asked for");
}

TEST(SegmentFaults, AStationThatAnswersEarly) {
  Faults f;
  // 10 bit times: one short of min TSDR (11).
  f.ask_and_answer(status_answer(2, 20), 10);
  f.expect_only(BusViolation::early_answer, 1);
}

TEST(SegmentFaults, ABabblingStationIsCountedEveryTimeButLogsStayBounded) {
  Faults f;
  std::uint64_t at = f.bits(100);
  constexpr int kBabble = 3000;
  for (int i = 0; i < kBabble; ++i) {
    at = f.seg.send(f.rogue, status_answer(2, 21), at) + f.bits(kTsyn);
  }
  f.settle(at + f.bits(100));
  f.check.flush();
  f.expect_only(BusViolation::unsolicited, kBabble);
  // One line per distinct text, then the limiter's bound (LogLimiter::kBurst per window).
  EXPECT_LE(f.log.size(), LogLimiter::kBurst + 2);
}

TEST(SegmentFaults, TwoStationsWithOneAddressCollide) {
  Faults f(true);
  ResponderConfig rc;
  rc.slave.address = 5;
  Responder twin(rc);
  const std::size_t second = f.seg.add_chip("dpc31", ChipOptions{Profile::dpc31});
  DirectBus bus(f.seg.chip(second));
  twin.init(bus);
  f.seg.set_firmware(second, [&twin](BusPort& b) { twin.isr(b); });
  f.find_rate();
  const std::size_t before = f.seg.collisions().size();
  const std::uint64_t end = f.seg.send(f.master, fdl_status(5, 2), f.seg.cycle() + f.bits(kTsyn));
  f.settle(end + f.bits(400));
  // Both answer at end + 11 T (docs/timing.md): the second driver collides at that cycle.
  ASSERT_EQ(f.seg.collisions().size(), before + 1);
  EXPECT_EQ(f.seg.collisions().back().cycle, end + f.bits(11));
  EXPECT_EQ(f.check.count(BusViolation::collision), 1U);
  EXPECT_NE(f.log.front().text.find("dpc31 drove the line while spc3 had it"), std::string::npos);
}

TEST(SegmentFaults, AStationDrivingIntoAnAnswerCollides) {
  Faults f(true);
  f.find_rate();
  const std::uint64_t end = f.seg.send(f.master, fdl_status(5, 2), f.seg.cycle() + f.bits(kTsyn));
  // The spc3 answers from end + 11 T; the rogue starts 2 bit times into it.
  f.seg.run_until(end + f.bits(13));
  f.seg.send(f.rogue, status_answer(2, 9), end + f.bits(13));
  f.settle(end + f.bits(400));
  ASSERT_EQ(f.seg.collisions().size(), 1U);
  EXPECT_EQ(f.seg.collisions()[0].cycle, end + f.bits(13));
  EXPECT_EQ(f.seg.name(f.seg.collisions()[0].first), "spc3");
  EXPECT_EQ(f.seg.name(f.seg.collisions()[0].second), "rogue");
  // The spc3's answer stays whole and in time: only the collision is a violation.
  f.expect_only(BusViolation::collision, 1);
}

TEST(SegmentFaults, ALostToken) {
  Faults f(false, kTtr);
  // Master 2 passes the token to 3, which is not there: the line stays idle.
  const std::uint64_t end = f.seg.send(f.master, bytes_of(fdl::token(3, 2)), f.bits(100));
  const std::uint64_t tto = f.bits(kSlot * (6 + 2 * 2));  // the lowest master, address 2
  f.settle(end + tto - 1);
  EXPECT_EQ(f.check.count(BusViolation::token_lost), 0U);
  f.settle(end + tto);
  f.expect_only(BusViolation::token_lost, 1);
  EXPECT_EQ(f.log.front().cycle, end + tto);
}

TEST(SegmentFaults, AForeignMasterThatNeverPassesTheToken) {
  Faults f(false, kTtr);
  const std::uint64_t got = f.seg.send(f.master, bytes_of(fdl::token(3, 2)), f.bits(100));
  // Master 3 (the rogue) polls station 40 over and over and never passes the token on.
  std::uint64_t at = got + f.bits(kTsyn);
  std::uint64_t late = 0;
  for (int i = 0; i < 40; ++i) {
    if (i > 0 && at > got + f.bits(kTtr)) ++late;  // a new message cycle after TTR
    const std::uint64_t end = f.seg.send(f.rogue, fdl_status(40, 3), at);
    at = end + f.bits(kSlot) + f.bits(kTsyn);
  }
  f.settle(at);
  ASSERT_GT(late, 0U);
  f.expect_only(BusViolation::token_hold, late);
}

// TTH = TTR - TRR (docs/segment.md, "The token"): at its second visit the rogue master 3 got the
// token 900 bit times after its first (TRR 900), so it may start cycles only within TTH = 2000 -
// 900 = 1100 bit times of the token's end. Its unanswered FDL_Status requests (6 characters, 66
// T, then the slot time 100 and TSYN 33: one every 199 bit times) start 33, 232, ..., 1028, 1227
// and 1426 bit times after it: the last two are late (the audit s28 aud2, finding 2: the check
// allowed a whole TTR from the arrival, and counted none here).
TEST(SegmentFaults, AMasterThatHoldsTheTokenPastTthAfterAShortRotation) {
  Faults f(false, kTtr);
  const std::uint64_t first = f.seg.send(f.master, bytes_of(fdl::token(3, 2)), f.bits(100));
  const std::uint64_t polled = f.seg.send(f.rogue, fdl_status(40, 3), first + f.bits(kTsyn));
  f.seg.send(f.rogue, bytes_of(fdl::token(2, 3)), polled + f.bits(kSlot + kTsyn));
  // Master 2's token to 3 again, ending 900 bit times after the first one's end.
  const std::uint64_t second =
      f.seg.send(f.master, bytes_of(fdl::token(3, 2)), first + f.bits(900 - 33));
  ASSERT_EQ(second, first + f.bits(900));
  std::uint64_t at = second + f.bits(kTsyn);
  for (int i = 0; i < 8; ++i) {
    const std::uint64_t end = f.seg.send(f.rogue, fdl_status(40, 3), at);
    at = end + f.bits(kSlot + kTsyn);
  }
  f.settle(at);
  f.expect_only(BusViolation::token_hold, 2);
  EXPECT_EQ(f.log.front().cycle, second + f.bits(1227));
  EXPECT_EQ(f.log.front().text,
            "bus: token_hold: station 3 started a message cycle 1227 bit times after it got the "
            "token (TTH 1100 = TTR 2000 - TRR 900)");
}

TEST(SegmentFaults, AShortTsyn) {
  Faults f(true);
  f.find_rate();
  const std::uint32_t no_sync = f.seg.chip(f.chip).fdl_counters().no_sync;
  const std::uint64_t end = f.seg.send(f.master, fdl_status(30, 2), f.seg.cycle() + f.bits(kTsyn));
  f.seg.send(f.master, fdl_status(5, 2), end + f.bits(kTsyn - 1));  // one bit short
  f.settle(end + f.bits(400));
  f.expect_only(BusViolation::short_tsyn, 1);
  // The chip holds the same rule: it did not take the request (docs/timing.md, TSYN).
  EXPECT_EQ(f.seg.chip(f.chip).fdl_counters().no_sync, no_sync + 1);
}

TEST(SegmentFaults, ATruncatedAnswer) {
  Faults f;
  std::vector<std::uint8_t> answer = status_answer(2, 20);
  answer.resize(4);
  f.ask_and_answer(answer, 11);
  f.expect_only(BusViolation::bad_frame, 1);
}

TEST(SegmentFaults, ACorruptedFcs) {
  Faults f;
  std::vector<std::uint8_t> answer = status_answer(2, 20);
  ++answer[answer.size() - 2];  // SD1: SD DA SA FC FCS ED
  f.ask_and_answer(answer, 11);
  f.expect_only(BusViolation::bad_frame, 1);
  EXPECT_NE(f.log.front().text.find(std::string(fdl::error_name(fdl::Error::bad_fcs))),
            std::string::npos);
}

TEST(SegmentFaults, AStationThatAnswersForAnotherAddress) {
  Faults f;
  f.ask_and_answer(status_answer(2, 21), 11);
  f.expect_only(BusViolation::wrong_responder, 1);
}

TEST(SegmentFaults, ADuplicateToken) {
  Faults f(false, kTtr);
  const std::uint64_t end = f.seg.send(f.master, bytes_of(fdl::token(3, 2)), f.bits(100));
  // Master 2 passed the token to 3 and still sends a request (SDN: no answer due).
  f.seg.send(f.master,
             bytes_of(fdl::make_frame(fdl::kBroadcast, 2,
                                      fdl::make_request_fc(fdl::Function::SDN_high, false, false),
                                      {0, 0}, std::uint8_t{58}, std::uint8_t{62})),
             end + f.bits(kTsyn));
  f.settle(end + f.bits(400));
  f.expect_only(BusViolation::duplicate_token, 1);
}

// A request or token from a station that does not hold the token is a second token on the line,
// whether or not the station is one of the masters named (EN 50170: a station that sends a token
// or a request acts as a master; docs/segment.md, `duplicate_token`). Master 2 passes the token
// to 3 (3 characters: 33 bit times from 100); 9, no master named, sends a request TSYN later.
// 3 has shown no activity: master 2 still holds the token (until the thirty-fourth session the
// line named 3, which had not taken it).
TEST(SegmentFaults, ARequestFromAStationThatIsNoMasterIsADuplicateToken) {
  Faults f(false, kTtr);
  const std::uint64_t end = f.seg.send(f.master, bytes_of(fdl::token(3, 2)), f.bits(100));
  ASSERT_EQ(end, f.bits(100 + 33));
  f.seg.send(f.rogue, fdl_status(40, 9), end + f.bits(kTsyn));
  f.settle(end + f.bits(kTsyn + 66 + 50));
  f.expect_only(BusViolation::duplicate_token, 1);
  ASSERT_EQ(f.log.size(), 1U);
  EXPECT_EQ(f.log[0].cycle, end + f.bits(kTsyn));
  EXPECT_EQ(f.log[0].text, "bus: duplicate_token: station 9 sent while station 2 holds the token");
}

// EN 50170 / IEC 61158-4-3 token passing (docs/segment.md, "The token"): the passer watches the
// line for the slot time after its token; when the addressee shows no activity it passes the
// token again, or to the station after. Master 2 passes the token to 9 (nobody there: DC 09 02, 33
// T, from 100 T), again TSL + 1 bit later, then to master 3 (the rogue in its name), which takes
// it (its own token back to 2, TSYN after). Nothing is a violation (s34 audit aSeg finding 1: the
// retry and the pass to 3 were each a duplicate_token, 9 said to hold the token).
TEST(SegmentFaults, ATokenPassedAgainAfterASilentSlotTimeIsNoDuplicateToken) {
  Faults f(false, kTtr);
  const std::uint64_t first = f.seg.send(f.master, bytes_of(fdl::token(9, 2)), f.bits(100));
  const std::uint64_t again =
      f.seg.send(f.master, bytes_of(fdl::token(9, 2)), first + f.bits(kSlot + 1));
  const std::uint64_t to3 =
      f.seg.send(f.master, bytes_of(fdl::token(3, 2)), again + f.bits(kSlot + 1));
  f.seg.send(f.rogue, bytes_of(fdl::token(2, 3)), to3 + f.bits(kTsyn));
  f.settle(to3 + f.bits(kTsyn + 33 + 50));
  EXPECT_EQ(f.check.total(), 0U) << (f.log.empty() ? "" : f.log.front().text);
}

// The passer's own request inside the slot time after its token is a second token: the addressee
// may still take it then (master 2's SDN 40 T after its token to 3, slot time 100).
TEST(SegmentFaults, ThePassersRequestInsideTheSlotTimeIsADuplicateToken) {
  Faults f(false, kTtr);
  const std::uint64_t end = f.seg.send(f.master, bytes_of(fdl::token(3, 2)), f.bits(100));
  f.seg.send(f.master, fdl_status(40, 2), end + f.bits(40));
  f.settle(end + f.bits(400));
  f.expect_only(BusViolation::duplicate_token, 1);
  EXPECT_EQ(f.log[0].cycle, end + f.bits(40));
  EXPECT_EQ(f.log[0].text,
            "bus: duplicate_token: station 2 sent 40 bit times after its token to station 3, "
            "inside the slot time (100) in which that station may take it");
}

// A lost token is gone (docs/segment.md, "The token"): the same master's next request claims a
// new one, held from TSYN before it. Master 2 claims with FDL_Status to 40 from 100 T (held from
// 67 T; 66 T, unanswered), the line idles: token_lost at its end + TTO = 166 + 100 x (6 + 2 x 2) =
// 1166 T. Its next request at 2100 T is 2033 T after the old claim, past TTH = TTR 2000, but it
// is a new claim's first cycle (s34 audit aSeg finding 3: it was a token_hold).
TEST(SegmentFaults, TheRequestAfterALostTokenClaimsAFreshOne) {
  Faults f(false, kTtr);
  const std::uint64_t end = f.seg.send(f.master, fdl_status(40, 2), f.bits(100));
  ASSERT_EQ(end, f.bits(166));
  f.settle(f.bits(2000));
  f.seg.send(f.master, fdl_status(40, 2), f.bits(2100));
  f.settle(f.bits(2400));
  f.expect_only(BusViolation::token_lost, 1);
  EXPECT_EQ(f.log[0].cycle, f.bits(1166));
}

// A station answering after TSL + TSYN drives into its asker's next request, sent then (docs/
// timing.md "The master's wait"; docs/segment.md "Bus checks"). Master 2 asks 20 (FDL_Status, 66
// T from 100 T: its end E = 166 T), asks 21 at E + 133 T; the rogue answers for 20 (an SD2 of 17
// characters) at E + 134 T: a collision there, rogue the second driver, and its telegram, begun
// 134 T after the request to 20, is unsolicited. What the line hears of it after the request to
// 21 is its rest, counted no more (s34 audit aSeg finding 4: a bad_frame and an early_answer "to
// station 21" blamed the late station for answering early).
TEST(SegmentFaults, AnAnswerAfterTslPlusTsynIsACollisionAndUnsolicitedOnce) {
  Faults f(false);
  const std::uint64_t end = f.seg.send(f.master, fdl_status(20, 2), f.bits(100));
  ASSERT_EQ(end, f.bits(166));
  f.seg.send(f.master, fdl_status(21, 2), end + f.bits(kSlot + kTsyn));
  f.seg.send(f.rogue,
             bytes_of(fdl::make_frame(2, 20, fdl::make_response_fc(fdl::Response::OK),
                                      {1, 2, 3, 4, 5, 6, 7, 8})),
             end + f.bits(kSlot + kTsyn + 1));
  f.settle(end + f.bits(600));
  ASSERT_EQ(f.seg.collisions().size(), 1U);
  EXPECT_EQ(f.seg.collisions()[0].cycle, end + f.bits(134));
  EXPECT_EQ(f.check.count(BusViolation::collision), 1U);
  EXPECT_EQ(f.check.count(BusViolation::unsolicited), 1U);
  EXPECT_EQ(f.check.total(), 2U);
  ASSERT_EQ(f.log.size(), 2U);
  EXPECT_EQ(f.log[1].cycle, end + f.bits(134));
  EXPECT_EQ(f.log[1].text,
            "bus: unsolicited: a telegram from rogue nobody asked for, begun 134 bit times after "
            "the request to station 20 (slot time 100), lost in the collision");
}

// The same collision when the second driver's telegram is a request or a token (review s34 rev1
// finding 3; docs/segment.md "Bus checks", `unsolicited`): no answer, so not one nobody asked
// for; the collision alone says it. Begun 134 T after the request to 20 as above, where an
// answer was unsolicited.
TEST(SegmentFaults, ARequestOrTokenLostInACollisionIsNoUnsolicitedAnswer) {
  for (const std::vector<std::uint8_t>& lost : {fdl_status(22, 3), bytes_of(fdl::token(4, 3))}) {
    Faults f(false);
    const std::uint64_t end = f.seg.send(f.master, fdl_status(20, 2), f.bits(100));
    f.seg.send(f.master, fdl_status(21, 2), end + f.bits(kSlot + kTsyn));
    f.seg.send(f.rogue, lost, end + f.bits(kSlot + kTsyn + 1));
    f.settle(end + f.bits(600));
    ASSERT_EQ(f.seg.collisions().size(), 1U);
    EXPECT_FALSE(f.seg.collisions()[0].answer);
    f.expect_only(BusViolation::collision, 1);
    ASSERT_EQ(f.log.size(), 1U);
    EXPECT_EQ(f.log[0].text, "bus: collision: rogue drove the line while master 2 had it");
  }
}

}  // namespace
}  // namespace dpc31
