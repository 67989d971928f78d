// The built-in master's DPV1 side (session/dpv1_master.hpp) against the built-in user side's
// (session/responder_dpv1.hpp) on a VPC3+ at 12 Mbaud, driven only through the wire (the master)
// and watched on the X/INT pin. Cycles from docs/timing.md (T = 4 clocks, 11 bits a character, an
// answer 11 T after the request's end, the next request 33 T after the answer's end) and the
// rules of docs/dpv1.md ("The master's side"); the derivation of each number is beside it.
#include "dpv1_master.hpp"

#include <gtest/gtest.h>

#include "dpc31/dp.hpp"
#include "responder.hpp"
#include "scenario.hpp"

using namespace dpc31;

namespace {

constexpr std::uint64_t kWork = 1440;  // 30 us of the user side's work per request

ResponderConfig config(std::uint64_t work) {
  ResponderConfig rc;
  rc.slave.user_prm = {0xC0, 0x00, 0x00};  // DPV1_Enable, Fail_Safe
  rc.dpv1.records = {{0, 1, {0x11, 0x22, 0x33, 0x44}}};
  rc.dpv1.work_cycles = work;
  return rc;
}

struct Rig {
  Chip chip{ChipOptions{Profile::vpc3plus, BusMode::intel, 0}};
  Responder user;
  DpMaster master;
  Dpv1Master dpv1;
  std::vector<std::uint64_t> irq_on;  // X/INT rising edges

  explicit Rig(std::uint64_t work = kWork, Dpv1Rules rules = {})
      : user(config(work)),
        master(chip, MasterConfig{2, 12'000'000, 100, 33}, config(work).slave),
        dpv1(chip, master, rules) {
    DirectBus bus(chip);
    user.init(bus);
    master.set_firmware([this](BusPort& b) { user.isr(b); });
    chip.on_irq_change([this](std::uint64_t c, bool active) {
      if (active) irq_on.push_back(c);
    });
  }
  void start() {
    ASSERT_TRUE(master.startup());
    master.idle(200);  // the firmware's last ISR done, the bus idle for the next request
    irq_on.clear();
  }
};

// A Read answered on the third poll (dpv1_c1_vpc3plus.scn derives it): request t0..t0+660, SC,
// polls acted on at t0+1362 and t0+2066 (SC: the user side's response is in at t0+2186), the
// third poll's answer (19 chars) ends at t0+3652. X/INT rises twice: FDL_Ind at the request's
// acted-on cycle t0+658, Poll_End_Ind at the response's end t0+3652 — the polls raise nothing
// ("Polling telegrams do not produce interrupts", VPC3+C p.56).
TEST(Dpv1Master, ReadPollsWithoutInterrupts) {
  Rig r;
  r.start();
  const std::size_t before = r.master.history().size();
  const Dpv1Answer a = r.dpv1.read(0, 1, 4);
  const std::uint64_t t0 = a.start;
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::positive);
  EXPECT_EQ(a.du, (pdu::Bytes{0x5E, 0x00, 0x01, 0x04, 0x11, 0x22, 0x33, 0x44}));
  EXPECT_EQ(a.polls, 2u);
  EXPECT_EQ(a.end, t0 + 3652);
  EXPECT_EQ(r.master.history().size() - before, 4u);  // request, 3 polls
  // Every poll an SRD without data from SAP 51 to SAP 51, each with a new FCB.
  for (std::size_t i = before + 1; i < r.master.history().size(); ++i) {
    const fdl::Frame& p = r.master.history()[i].request;
    EXPECT_TRUE(p.du.empty());
    EXPECT_EQ(p.dsap, sap::MSAC_C1);
    EXPECT_EQ(p.ssap, sap::MSAC_C1);
    EXPECT_NE(fdl::fcb(p.fc), fdl::fcb(r.master.history()[i - 1].request.fc));
  }
  r.master.idle(200);
  EXPECT_EQ(r.irq_on, (std::vector<std::uint64_t>{t0 + 658, t0 + 3652}));
}

// The response time-out (C1_Response_Timeout 1 = 10 ms = 480 000 clocks from the request's
// start): a user side that works 1 s. The request's SC ends at t0+748, poll n's SC at
// t0+748+704n; the master gives up at the first SC at or past 480 000: n = 681 (t0+480 172).
TEST(Dpv1Master, ResponseTimeOut) {
  Dpv1Rules rules;
  rules.c1_response_timeout = 1;
  Rig r(48'000'000, rules);
  r.start();
  const Dpv1Answer a = r.dpv1.read(0, 1, 4);
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::timeout);
  EXPECT_EQ(a.polls, 681u);
  EXPECT_EQ(a.end, a.start + 748 + 704 * 681);
}

// A request nobody answers (the slave addressed as 9) is sent 1 + retries times, unchanged (the
// same FCB), then the service fails: no_answer, and no poll follows.
TEST(Dpv1Master, NoAnswerAfterRetries) {
  Dpv1Rules rules;
  rules.retries = 2;
  Rig r(kWork, rules);
  r.start();
  r.master.set_target(9);
  const std::size_t before = r.master.history().size();
  const Dpv1Answer a = r.dpv1.write(0, 1, {1, 2, 3, 4});
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::no_answer);
  ASSERT_EQ(r.master.history().size() - before, 3u);
  for (std::size_t i = before; i < r.master.history().size(); ++i) {
    EXPECT_EQ(r.master.history()[i].request, r.master.history()[before].request);
  }
}

// The negative response is parsed as such: a Write of the wrong length.
TEST(Dpv1Master, NegativeResponse) {
  Rig r;
  r.start();
  const Dpv1Answer a = r.dpv1.write(0, 1, {1, 2});
  ASSERT_EQ(a.outcome, Dpv1Answer::Outcome::negative);
  EXPECT_EQ(a.error, (pdu::ErrorResponse{pdu::Function::Write, pdu::Error_Decode_DPV1,
                                         pdu::error::Write_Length_Error, 0}));
  EXPECT_EQ(r.user.dpv1()->records().front().data, (pdu::Bytes{0x11, 0x22, 0x33, 0x44}));
}

// MSAC_C2: Initiate gets the connection's SAP from the resource manager; Read on it; Abort closes
// it on both sides (a new Initiate is taken); without a request for Send_Timeout the user side
// closes it (its SAP answers RS).
TEST(Dpv1Master, ClassTwoConnection) {
  Rig r;
  r.start();
  pdu::Initiate req;
  req.send_timeout = 1;  // 10 ms
  Dpv1Answer a = r.dpv1.initiate(req);
  ASSERT_EQ(a.outcome, Dpv1Answer::Outcome::positive);
  ASSERT_EQ(r.dpv1.c2_sap(), std::optional<std::uint8_t>(40));
  a = r.dpv1.c2_read(0, 1, 2);
  EXPECT_EQ(a.du, (pdu::Bytes{0x5E, 0x00, 0x01, 0x02, 0x11, 0x22}));
  a = r.dpv1.c2_abort({0, 2, 3, 0});
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::positive);
  EXPECT_FALSE(r.dpv1.c2_sap());
  a = r.dpv1.initiate(req);
  ASSERT_EQ(a.outcome, Dpv1Answer::Outcome::positive);
  r.master.idle(48'000 * 15);
  EXPECT_EQ(r.user.dpv1()->timeouts, 1u);
  a = r.dpv1.c2_idle();
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::refused);
}

// `expect dpv1 sc` (docs/scenario-format.md, "DPV1"): the Abort gets SC and no response; a check
// of another outcome fails and says what came.
TEST(Dpv1Scenario, AbortIsCheckedAsSc) {
  const char* text =
      "profile vpc3plus\nslave user_prm=C0,00,00\nrecord slot=0 index=1 data=01\nstartup\n"
      "c2_initiate\nexpect dpv1 sc   # the Initiate response: fails\nc2_abort\nexpect dpv1 sc\n"
      "expect dpv1 refused   # fails\n";
  Scenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_scenario(text, "t.scn", s, err)) << err.text();
  std::vector<std::string> errors;
  const ScenarioOutcome o =
      run_scenario(s, {}, [&](const std::string& line) { errors.push_back(line); });
  EXPECT_EQ(o.passed, 1u);
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_TRUE(errors[0].starts_with("t.scn:6: expected dpv1 sc sc, got 57 ")) << errors[0];
  EXPECT_EQ(errors[1], "t.scn:9: expected dpv1 refused refused, got SC after 0 polls");
}

// Bad DPV1 lines are parse errors with their line (docs/scenario-format.md, "DPV1"): nothing
// runs.
TEST(Dpv1Scenario, ParseErrorsNameTheLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"profile spc3\nrecord slot=0 index=1 data=01\n",
       "t.scn:2: 'record' needs 'profile vpc3plus' before it: only the VPC3+ has DPV1"},
      {"profile vpc3plus\nstartup\ndpv1_read slot=0 index=1\n",
       "t.scn:3: dpv1_read needs slot=N index=N length=N"},
      {"profile vpc3plus\nstartup\nexpect dpv1 error 80,B0\n",
       "t.scn:3: expect dpv1 error: three bytes, Error_Decode,Error_Code_1,Error_Code_2"},
      {"profile vpc3plus\ncorrupt parity\ndpv1_read slot=0 index=1 length=4\n",
       "t.scn:2: the next action ('dpv1_read', line 3) sends no request to damage"},
      {"profile vpc3plus\nrecord slot=0 index=1 data=01\nrecord slot=0 index=1 data=02\n",
       "t.scn:3: record slot=0 index=1 given twice"},
      {"profile vpc3plus\nalarm_ack slot=0 type=1\n",
       "t.scn:2: alarm_ack needs slot=N type=N seq=N"},
      // The Specifier's bits 1..0 (docs/dpv1.md: Seq_Nr << 3 | Add_Ack << 2 | bits 1..0).
      {"profile vpc3plus\nalarm_ack slot=0 type=1 seq=0 spec=5\n",
       "t.scn:2: spec 5 out of range (0..3)"},
  };
  for (const auto& [text, want] : cases) {
    Scenario s;
    ScenarioError err;
    EXPECT_FALSE(parse_scenario(text, "t.scn", s, err)) << text;
    EXPECT_EQ(err.text(), want);
  }
  // A Reason_Code beyond its 4 bits.
  Scenario s;
  ScenarioError err;
  EXPECT_FALSE(parse_scenario("profile vpc3plus\nc2_abort reason=16\n", "t.scn", s, err));
  EXPECT_EQ(err.line, 2);
}

}  // namespace
