// The invariant checker (invariants.hpp) on real runs (no report) and on deliberately wrong
// states and histories (a report naming the broken invariant), so that none of its checks is
// vacuous.
#include "invariants.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cpu.hpp"
#include "dp_master.hpp"
#include "harness.hpp"
#include "responder.hpp"

namespace {

using dpc31::BusMode;
using dpc31::Chip;
using dpc31::DpState;
using dpc31::Profile;
using dpc31::RegId;
using dpc31::fuzz::InvariantChecker;

struct Collected {
  std::vector<std::string> messages;
  InvariantChecker::Report sink() {
    return [this](const std::string& m) { messages.push_back(m); };
  }
  [[nodiscard]] bool any_containing(const std::string& s) const {
    for (const auto& m : messages) {
      if (m.find(s) != std::string::npos) return true;
    }
    return false;
  }
};

// A chip started by the responder (Wait_Prm, Baud_Search at 12 Mbaud), the checker attached first.
struct Started {
  explicit Started(Profile p = Profile::spc3) : chip({p, BusMode::intel}), checker(seen.sink()) {
    checker.attach(chip, true);
    dpc31::DirectBus bus(chip);
    user.init(bus);
  }
  std::uint32_t addr(RegId id) const { return static_cast<std::uint32_t>(chip.addr_of(id)); }
  Collected seen;
  Chip chip;
  InvariantChecker checker;
  dpc31::Responder user{dpc31::ResponderConfig{}};
};

// FDL_Status from master 2 to station 5 (SD1, FC 49h, FCS 50h).
const std::vector<std::uint8_t> kFdlStatus = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};

TEST(Invariants, WholeStartUpAndDataExchangeHoldEveryInvariant) {
  for (Profile p : dpc31::kAllProfiles) {
    Collected seen;
    Chip chip({p, BusMode::intel});
    InvariantChecker checker(seen.sink());
    checker.attach(chip, true);
    dpc31::Responder user{dpc31::ResponderConfig{}};
    dpc31::DirectBus bus(chip);
    user.init(bus);
    dpc31::DpMaster master(chip, dpc31::MasterConfig{}, dpc31::SlaveConfig{});
    master.set_firmware([&](dpc31::BusPort& b) { user.isr(b); });
    ASSERT_TRUE(master.startup());
    ASSERT_TRUE(master.data_exchange({1, 2, 3, 4}).answer);
    master.global_control(0x02);  // Clear_Data
    master.idle(100'000'000);     // the DP watchdog expires: Leave_Master
    EXPECT_EQ(chip.dp_state(), DpState::Wait_Prm);
    EXPECT_TRUE(seen.messages.empty()) << seen.messages.front();
    // Every event and bus access of the session: some 460-480 (TxD bits are no events since the
    // master takes them in batches, docs/engine.md "Characters on TxD").
    EXPECT_GT(checker.checks(), 400u);
    EXPECT_GE(checker.answers_checked(), 5u);
  }
}

TEST(Invariants, XintWithAHiddenInactiveTimeIsReported) {
  Started s;
  s.chip.step(100);
  ASSERT_TRUE(s.chip.irq_active());  // DX_Out of the Start, unmasked by the responder
  s.checker.check();
  ASSERT_TRUE(s.seen.messages.empty());
  // The model holds the line inactive although nobody wrote EOI.
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).irq).eoi.at = s.chip.cycle() + 1000;
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("X/INT")) << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, XintActiveDuringAnEoiInactiveTimeIsReported) {
  Started s;
  s.chip.step(100);
  ASSERT_TRUE(s.chip.irq_active());
  // The checker sees an EOI write that the model did not act on.
  s.checker.on_block({dpc31::BlockEvent::Kind::write,
                      static_cast<std::uint16_t>(s.addr(RegId::Mode_Reg1_S)), 0x02});
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("X/INT")) << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, XintPinAgainstIrqActivityIsReported) {
  Started s;
  s.chip.step(100);
  // IRR changed behind the line's back: the level reported last no longer fits IR.
  dpc31::harness::core(s.chip).regs.latch(RegId::Int_Req_Reg) = 0;
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("X/INT")) << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, BufferNamedTwiceIsReported) {
  Started s;
  s.checker.check();
  ASSERT_TRUE(s.seen.messages.empty());
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).buffers).dout.u =
      dpc31::BlockAccess::state(dpc31::harness::core(s.chip).buffers).dout.d;
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("Dout_Buffer_SM")) << ::testing::PrintToString(s.seen.messages);
  s.seen.messages.clear();
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).buffers).din.n =
      dpc31::BlockAccess::state(dpc31::harness::core(s.chip).buffers).din.f;
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("Din_Buffer_SM")) << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, BothDiagBuffersWithTheUserIsReported) {
  Started s;
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).buffers).diag.buf[0] =
      dpc31::DiagState::User;
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).buffers).diag.buf[1] =
      dpc31::DiagState::User;
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("Diag_Buffer_SM")) << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, PointerCellChangedByTheAsicIsReportedAUserWriteIsNot) {
  Started s;
  const std::uint32_t prm = s.addr(RegId::R_Prm_Buf_Ptr);
  // The user may write the cells (a driver's init does).
  s.chip.write(prm, static_cast<std::uint8_t>(s.chip.peek(prm) + 1));
  EXPECT_TRUE(s.seen.messages.empty()) << s.seen.messages.front();
  // The ASIC may only swap them: a changed value without a user write is a lost buffer.
  s.chip.poke(prm, static_cast<std::uint8_t>(s.chip.peek(prm) + 1));
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("pointer cells")) << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, UndocumentedDpTransitionsAreReported) {
  Started s;
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).dp).state =
      DpState::Data_Exchange;  // straight from Wait_Prm
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("Wait_Prm -> Data_Exchange is not a documented transition"))
      << ::testing::PrintToString(s.seen.messages);
  s.seen.messages.clear();
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).dp).state = DpState::Wait_Prm;
  s.checker.check();
  EXPECT_FALSE(s.seen.any_containing("Data_Exchange -> Wait_Prm is not"));  // always allowed
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).dp).state = DpState::Wait_Cfg;
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("without a User_Prm_Data_Okay read"))
      << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, DataExchangeWithoutGoLeaveIsReported) {
  Started s;
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).dp).state = DpState::Wait_Cfg;
  s.checker.on_block({dpc31::BlockEvent::Kind::read,
                      static_cast<std::uint16_t>(s.addr(RegId::User_Prm_Data_Okay)), 0});
  s.checker.check();
  ASSERT_TRUE(s.seen.messages.empty()) << s.seen.messages.front();
  dpc31::BlockAccess::state(dpc31::harness::core(s.chip).dp).state = DpState::Data_Exchange;
  dpc31::harness::core(s.chip).regs.latch(RegId::Int_Req_Reg) &=
      static_cast<std::uint16_t>(~dpc31::irq::Go_Leave_Data_Exchange);
  dpc31::harness::core(s.chip).irq.update_line();
  s.checker.on_block({dpc31::BlockEvent::Kind::read,
                      static_cast<std::uint16_t>(s.addr(RegId::User_Cfg_Data_Okay)), 0});
  s.checker.check();
  EXPECT_TRUE(s.seen.any_containing("without Go_Leave_Data_Exchange"))
      << ::testing::PrintToString(s.seen.messages);
}

// Drives `bytes` 40 idle bit times from now at the chip's rate, then runs until it is answered.
void request(Started& s, const std::vector<std::uint8_t>& bytes, dpc31::UartFault fault = {}) {
  const std::uint32_t t = s.chip.bit_cycles();
  const std::uint64_t end = dpc31::send_on_rxd(s.chip, bytes, s.chip.cycle() + 40ull * t, t, fault);
  s.chip.step(end + 200ull * t - s.chip.cycle());
}

TEST(Invariants, AnAnswerToAGoodRequestPasses) {
  Started s;
  request(s, kFdlStatus);
  EXPECT_EQ(s.checker.answers_checked(), 1u);  // the chip answered, the checker agreed
  EXPECT_TRUE(s.seen.messages.empty()) << s.seen.messages.front();
}

// The chip (rightly) does not answer these; the checker is shown an answer as a broken MAC would
// send it, 11 bit times after the request.
void answer_anyway(Started& s) {
  const std::uint64_t start = s.chip.cycle();
  s.checker.on_answer({true, {0xE5}, start, start + 11ull * s.chip.bit_cycles()});
}

TEST(Invariants, AnAnswerToABadFcsIsReported) {
  Started s;
  std::vector<std::uint8_t> bad = kFdlStatus;
  bad[4] ^= 0x01;
  request(s, bad);
  EXPECT_EQ(s.checker.answers_checked(), 0u);
  answer_anyway(s);
  EXPECT_TRUE(s.seen.any_containing("valid request frame"))
      << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, AnAnswerToAParityErrorIsReported) {
  Started s;
  request(s, kFdlStatus, {2, dpc31::UartFault::Kind::parity});
  EXPECT_EQ(s.checker.answers_checked(), 0u);
  answer_anyway(s);
  EXPECT_TRUE(s.seen.any_containing("(parity!)")) << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, AnAnswerWithoutAnyRequestIsReported) {
  Started s;
  s.chip.step(100'000);  // longer than any request that could have begun before attach
  answer_anyway(s);
  EXPECT_TRUE(s.seen.any_containing("no request")) << ::testing::PrintToString(s.seen.messages);
}

TEST(Invariants, DefaultReportAbortsWithTheMessage) {
  EXPECT_DEATH(
      {
        Started s;
        InvariantChecker strict;
        strict.attach(s.chip);
        dpc31::BlockAccess::state(dpc31::harness::core(s.chip).dp).state = DpState::Data_Exchange;
        strict.check();
      },
      "invariant violated at cycle [0-9]+: DP state Wait_Prm -> Data_Exchange");
}

TEST(Invariants, ValidRequestFrameIsItsOwnFdlCheck) {
  EXPECT_TRUE(dpc31::fuzz::valid_request_frame(kFdlStatus.data(), kFdlStatus.size()));
  std::vector<std::uint8_t> v = kFdlStatus;
  v[5] = 0x17;  // ED
  EXPECT_FALSE(dpc31::fuzz::valid_request_frame(v.data(), v.size()));
  v = kFdlStatus;
  v[3] = 0x09;  // a response FC, not a request
  v[4] = 0x10;
  EXPECT_FALSE(dpc31::fuzz::valid_request_frame(v.data(), v.size()));
  // SD2: Set_Prm-like, LE = 5 (DA SA FC DSAP SSAP)
  const std::vector<std::uint8_t> sd2 = {0x68, 0x05, 0x05, 0x68, 0x85, 0x82,
                                         0x6D, 0x3D, 0x3E, 0xEF, 0x16};
  EXPECT_TRUE(dpc31::fuzz::valid_request_frame(sd2.data(), sd2.size()));
  std::vector<std::uint8_t> le = sd2;
  le[2] = 0x06;  // LEr differs
  EXPECT_FALSE(dpc31::fuzz::valid_request_frame(le.data(), le.size()));
}

}  // namespace
