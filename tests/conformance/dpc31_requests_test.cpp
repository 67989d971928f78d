// The DPC31 on its own interface (manual-quotes.md, "dpc31 registers ..." and "dpc31 user
// watchdog ..."): requests through the Instruction_Queue, answers through the Indication_Queue,
// the DPS_User_Watchdog on its 10 ms time base, Set_Prm shorter than 7 bytes, byte 13. Driven
// only over the bus and the wire. Cycles per docs/timing.md and docs/dpc31.md: a request acts at
// the completion cycle of the InstQ_Wr write; 10 ms = 480 000 clocks at 48 MHz.
#include "conformance.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/dpc31_regs.h"
#include "dpc31/regdesc.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

constexpr std::uint8_t kInstSeg = 0xF8;  // 1F00h: above everything the Responder allocates
constexpr std::uint8_t kIndSeg = 0xFA;   // 1F40h
constexpr std::uint32_t kInst = 0x1F00;
constexpr std::uint32_t kInd = 0x1F40;
constexpr std::uint64_t k10ms = 480'000;

std::uint32_t at(const Chip& c, RegId id) { return static_cast<std::uint32_t>(c.addr_of(id)); }
std::uint8_t rd(Chip& c, RegId id) { return c.read(at(c, id)); }
void wr(Chip& c, RegId id, std::uint8_t v) { c.write(at(c, id), v); }
std::uint16_t irr(Chip& c) {
  const std::uint8_t lo = c.read(at(c, RegId::Int_Req_Reg));
  return static_cast<std::uint16_t>(lo | c.read(at(c, RegId::Int_Req_Reg) + 1) << 8);
}

// The user's side of the queues, as firmware written to the DPC31 manual would do it: rings at
// 1F00h / 1F40h, or those of the Responder that started the chip (MAC_Start) if it set them up.
struct Queues {
  Chip& c;
  std::uint8_t inst_len;
  std::uint8_t ind_len;
  std::uint8_t inst_wr = 0;
  std::uint32_t inst = kInst;
  std::uint32_t ind = kInd;

  Queues(Chip& chip, std::uint8_t il = 4, std::uint8_t nl = 4)
      : c(chip), inst_len(il), ind_len(nl) {
    if (c.peek(at(c, RegId::InstQ_Len)) != 0) {
      const unsigned shift = c.profile().segment_shift;
      inst_len = c.peek(at(c, RegId::InstQ_Len));
      ind_len = c.peek(at(c, RegId::IndQ_Len));
      inst_wr = c.peek(at(c, RegId::InstQ_Wr));
      inst = static_cast<std::uint32_t>(c.peek(at(c, RegId::InstQ_Base))) << shift;
      ind = static_cast<std::uint32_t>(c.peek(at(c, RegId::IndQ_Base))) << shift;
      return;
    }
    wr(c, RegId::InstQ_Base, kInstSeg);
    wr(c, RegId::InstQ_Len, inst_len);
    wr(c, RegId::IndQ_Base, kIndSeg);
    wr(c, RegId::IndQ_Len, ind_len);
  }
  // Writes one entry, then InstQ_Wr past it; returns the cycle the request acted (the
  // completion of the InstQ_Wr write).
  std::uint64_t request(std::uint8_t code, std::uint8_t param = 0) {
    c.write(inst + inst_wr * 2u, code);
    c.write(inst + inst_wr * 2u + 1, param);
    inst_wr = static_cast<std::uint8_t>((inst_wr + 1) % inst_len);
    wr(c, RegId::InstQ_Wr, inst_wr);
    return c.cycle();
  }
  std::pair<std::uint8_t, std::uint8_t> indication(std::uint8_t i) {
    return {c.read(ind + i * 2u), c.read(ind + i * 2u + 1)};
  }
};

// A dpc31 on the bench with nothing but its queues set up (log off).
struct Bare {
  Chip c{{Profile::dpc31}};
  Queues q;
  explicit Bare(std::uint8_t ind_len = 4) : q((c.set_log_sink(nullptr), c), 4, ind_len) {}

  // R_User_WD_Value = `value`, then "DPS_User WD, Enable": the cycle the request was executed.
  std::uint64_t enable_user_wd(std::uint8_t value) {
    c.write(at(c, RegId::R_User_WD_Value), value);
    return q.request(request::DPS_User_Wd, request::Wd_Enable);
  }
  std::uint8_t indications() { return c.peek(at(c, RegId::IndQ_Wr)); }
};

bool started(Chip& c) { return (rd(c, RegId::Status_Reg) & 0x01) != 0; }

// Baud_Search has found the master's rate once an FDL_Status is answered.
void until_answered(Bench& b) {
  // Enough FDL_Status for the baud search from Start at every rate (docs/timing.md).
  for (int i = 0; i < dpc31::kStartupTries && !b.master.fdl_status().answer; ++i) {
  }
}

}  // namespace

// DPC31 Table 5.1-3: "MAC_Start 10h: MAC enters Pas_Idle". The MAC reads the request and moves
// InstQ_Rd past it (p.22: InstQ_Rd is written by the MAC).
TEST(Dpc31Requests, MacStartEntersPassiveIdle) {
  Bare bare;
  Chip& c = bare.c;
  Queues& q = bare.q;
  std::vector<std::pair<std::uint64_t, bool>> line;
  c.on_irq_change([&](std::uint64_t cy, bool a) { line.emplace_back(cy, a); });
  c.write(at(c, RegId::Int_Mask_Reg), 0xFF);
  c.write(at(c, RegId::Int_Mask_Reg) + 1, static_cast<std::uint8_t>(~irq::DX_Out >> 8));
  EXPECT_FALSE(started(c));
  const std::uint64_t s = q.request(request::MAC_Start);
  // Power-on clears the outputs and hands them over with DX_Out at the start (as Start_SPC3).
  ASSERT_FALSE(line.empty());
  EXPECT_EQ(line.back(), std::make_pair(s, true));
  EXPECT_TRUE(started(c));
  EXPECT_EQ(rd(c, RegId::InstQ_Rd), 1);
  EXPECT_EQ(c.wd_state(), WdState::Baud_Search);
  EXPECT_EQ(c.dp_state(), DpState::Wait_Prm);
}

// Table 5.1-3: "MAC_Stop 11h: MAC enters Offline", "confirmed to the user by an entry in the
// Indication_Queue" (§5.1.3), after it has been executed: the entry is there, IndQ_Wr has moved
// and the Indication interrupt is latched, all at the cycle the MAC went Offline.
TEST(Dpc31Requests, MacStopIsConfirmedInTheIndicationQueue) {
  Bare bare;
  Chip& c = bare.c;
  Queues& q = bare.q;
  q.request(request::MAC_Start);
  ASSERT_TRUE(started(c));
  std::uint64_t indication_at = 0;
  c.on_irq_change([&](std::uint64_t cy, bool a) {
    if (a) indication_at = cy;
  });
  c.write(at(c, RegId::Int_Mask_Reg), static_cast<std::uint8_t>(~irq::Indication));
  c.write(at(c, RegId::Int_Mask_Reg) + 1, 0xFF);
  const std::uint64_t s = q.request(request::MAC_Stop);
  EXPECT_EQ(indication_at, s);
  EXPECT_FALSE(started(c));
  EXPECT_EQ(rd(c, RegId::IndQ_Wr), 1);
  EXPECT_EQ(q.indication(0), std::make_pair(request::MAC_Stop, request::Stop_Confirmed));
  EXPECT_EQ(irr(c) & (irq::Indication | irq::MAC_Reset), irq::Indication | irq::MAC_Reset);
}

// Table 5.1-3: User_Leave_Master 15h: the DP state machine leaves the master (Wait_Prm) and
// reports leaving Data_Exchange.
TEST(Dpc31Requests, UserLeaveMasterReturnsToWaitPrm) {
  Bench b(Profile::dpc31);
  Queues q(b.chip);
  ASSERT_TRUE(b.master.startup());
  ASSERT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  ASSERT_EQ(irr(b.chip) & irq::Go_Leave_Data_Exchange, 0);  // the ISR acknowledged the entry
  q.request(request::User_Leave_Master);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_NE(irr(b.chip) & irq::Go_Leave_Data_Exchange, 0);
}

// p.31: "The DPS_User_Watchdog is an internal 16bit RAM cell ... started by a user-parameterized
// value 'DPS_User WD Value 15..0', and is decremented every 10 msec. If the timer reaches the
// value '0000h', DPS ... executes 'Leave_Master', locks the DPS_User WD, and enters the event
// 'DPS_User_WD Expired' in the Indication_Queue." Value 3, enabled at e: decrements at e + 10,
// e + 20 and e + 30 ms; the last reaches 0000h.
TEST(Dpc31Requests, DpsUserWdExpiresAfterItsValueTimes10ms) {
  Bench b(Profile::dpc31);
  Queues q(b.chip);
  ASSERT_TRUE(b.master.startup());
  b.chip.write(at(b.chip, RegId::R_User_WD_Value), 3);
  b.chip.write(at(b.chip, RegId::R_User_WD_Value) + 1, 0);
  const std::uint64_t e = q.request(request::DPS_User_Wd, request::Wd_Enable);
  b.chip.step(e + 3 * k10ms - 1 - b.chip.cycle());
  EXPECT_EQ(b.chip.peek(at(b.chip, RegId::IndQ_Wr)), 0);
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  b.chip.step(1);  // e + 30 ms
  EXPECT_EQ(b.chip.peek(at(b.chip, RegId::IndQ_Wr)), 1);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(q.indication(0), std::make_pair(request::DPS_User_Wd, request::Wd_Expired));
}

// "In the case of the SPC3, the processor is monitored via a counter" (p.31): on the DPC31 the
// Data_Exchange telegrams do not count the user watchdog down, whatever Mode_Reg1's
// Res_User_WD says.
TEST(Dpc31Requests, DataExchangeTelegramsDoNotCountTheUserWatchdog) {
  ResponderConfig rc;
  rc.user_watchdog = true;
  rc.user_wd_value = 2;
  Bench b(Profile::dpc31, 1'500'000, rc);
  ASSERT_TRUE(b.master.startup());
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(b.master.data_exchange({1, 2, 3, 4}).answer);
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
}

// "transfer 'DPS_User WD, Reset' via the request interface" retriggers it: Reset at e + 15 ms
// reloads 2, so the decrements at e + 20 and e + 30 ms reach 0000h at e + 30 ms (the 10 ms
// phase set by Enable stays: modelled, docs/dpc31.md).
TEST(Dpc31Requests, DpsUserWdResetReloadsTheValue) {
  Bare bare;
  Chip& c = bare.c;
  const std::uint64_t e = bare.enable_user_wd(2);
  c.step(e + 15 * k10ms / 10 - c.cycle());
  bare.q.request(request::DPS_User_Wd, request::Wd_Reset);
  c.step(e + 3 * k10ms - 1 - c.cycle());
  EXPECT_EQ(bare.indications(), 0);
  c.step(1);
  EXPECT_EQ(bare.indications(), 1);
}

// "This timer can be enabled or disabled any time via the request interface": disabled, it
// never expires.
TEST(Dpc31Requests, DpsUserWdDisableStopsIt) {
  Bare bare;
  bare.enable_user_wd(1);
  bare.q.request(request::DPS_User_Wd, request::Wd_Disable);
  bare.c.step(10 * k10ms);
  EXPECT_EQ(bare.indications(), 0);
}

// "locks the DPS_User WD": after an expiry Enable does nothing until a Reset; Reset then Enable
// starts it again from its value.
TEST(Dpc31Requests, DpsUserWdIsLockedAfterExpiryUntilReset) {
  Bare bare;
  Chip& c = bare.c;
  Queues& q = bare.q;
  bare.enable_user_wd(1);
  c.step(k10ms);
  ASSERT_EQ(bare.indications(), 1);
  q.request(request::DPS_User_Wd, request::Wd_Enable);  // locked: ignored
  c.step(2 * k10ms);
  EXPECT_EQ(bare.indications(), 1);
  q.request(request::DPS_User_Wd, request::Wd_Reset);
  const std::uint64_t e = q.request(request::DPS_User_Wd, request::Wd_Enable);
  c.step(e + k10ms - c.cycle());
  EXPECT_EQ(bare.indications(), 2);
}

// An unknown request code is skipped (logged) and the MAC goes on with the next entry; a
// pointer outside the queue executes nothing (docs/dpc31.md, modelled).
TEST(Dpc31Requests, UnknownCodeIsSkippedAndBadPointerExecutesNothing) {
  Bare bare;
  Chip& c = bare.c;
  std::vector<std::string> log;
  c.set_log_sink([&](const LogRecord& r) { log.push_back(r.text); });
  c.write(kInst, 0x7F);
  c.write(kInst + 1, 0x00);
  c.write(kInst + 2, request::MAC_Start);
  c.write(kInst + 3, 0x00);
  wr(c, RegId::InstQ_Wr, 2);
  EXPECT_EQ(rd(c, RegId::InstQ_Rd), 2);
  EXPECT_TRUE(started(c));
  EXPECT_TRUE(std::any_of(log.begin(), log.end(), [](const std::string& s) {
    return s.find("unknown request code 7Fh") != std::string::npos;
  }));
  c.write(kInst + 4, request::MAC_Stop);
  wr(c, RegId::InstQ_Wr, 9);  // InstQ_Len is 4
  EXPECT_EQ(rd(c, RegId::InstQ_Rd), 2);
  EXPECT_TRUE(started(c));
}

// One entry always stays empty (p.22): a queue of 2 entries holds one indication; the second is
// lost (logged), IndQ_Wr stays, until the user has read the first.
TEST(Dpc31Requests, FullIndicationQueueLosesTheIndication) {
  Bare bare(2);
  Chip& c = bare.c;
  Queues& q = bare.q;
  q.request(request::MAC_Stop);
  EXPECT_EQ(rd(c, RegId::IndQ_Wr), 1);
  q.request(request::MAC_Stop);
  EXPECT_EQ(rd(c, RegId::IndQ_Wr), 1);
  wr(c, RegId::IndQ_Rd, 1);  // the user read entry 0
  q.request(request::MAC_Stop);
  EXPECT_EQ(rd(c, RegId::IndQ_Wr), 0);
  EXPECT_EQ(q.indication(1), std::make_pair(request::MAC_Stop, request::Stop_Confirmed));
}

// Table 5.1-3: MAC_New_TRDY 12h "Transfer of TRDY": the parameter becomes the ready time
// MinTSDR; the next answer starts max(11, MinTSDR) = 30 bit times after the request's end.
TEST(Dpc31Requests, MacNewTrdyTransfersTheReadyTime) {
  Bench b(Profile::dpc31);
  Queues q(b.chip);
  until_answered(b);
  q.request(request::MAC_New_TRDY, 30);
  const Exchange st = b.master.fdl_status();
  ASSERT_TRUE(st.answer);
  EXPECT_EQ(st.answer_start, st.request_end + 30u * b.T());
}

// "Transfer of TRDY" also after a master's Set_Prm that carried a min TSDR (byte 3, 20): the
// request is newer and wins (docs/timing.md, answer: the MinTSDR set last). A later Set_Prm with
// byte 3 = 0 keeps it ("0 = no change", chip-facts §8), one with 25 wins again, from its own SC on.
TEST(Dpc31Requests, MacNewTrdyWinsOverAnEarlierSetPrmMinTsdr) {
  ResponderConfig rc;
  rc.slave.min_tsdr = 20;
  Bench b(Profile::dpc31, 1'500'000, rc);
  Queues q(b.chip);
  ASSERT_TRUE(b.master.startup());
  const Exchange before = b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  EXPECT_EQ(before.answer_start, before.request_end + 20u * b.T());
  q.request(request::MAC_New_TRDY, 40);
  const Exchange after = b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  ASSERT_TRUE(after.answer);
  EXPECT_EQ(after.answer_start, after.request_end + 40u * b.T());
  b.master.slave().min_tsdr = 0;
  const Exchange keep = b.master.set_prm();
  EXPECT_EQ(keep.answer_start, keep.request_end + 40u * b.T());
  b.master.slave().min_tsdr = 25;
  const Exchange again = b.master.set_prm();
  EXPECT_EQ(again.answer_start, again.request_end + 25u * b.T());
}

// DPC31 p.26 §5.2.2: "the message has to have at least a length of >= 7 bytes; otherwise, it is
// ignored": acknowledged, no Prm_Fault in the diagnosis, no New_Prm_Data, still Wait_Prm.
TEST(Dpc31Requests, SetPrmShorterThanSevenBytesIsIgnored) {
  Bench b(Profile::dpc31);
  until_answered(b);
  const std::size_t irqs = b.user.interrupts.size();
  // Set_Prm (SAP 61 from SAP 62) with Lock_Req and WD_On, six bytes: no Group_Ident. FCV 0: no
  // FCB bookkeeping to disturb the master's own.
  const fdl::Frame req = fdl::make_frame(
      b.master.target(), 2, fdl::make_request_fc(fdl::Function::SRD_high, false, false),
      {0x88, 0x01, 0x01, 0x0B, 0x12, 0x34}, 61, 62);
  const Exchange ex = b.master.transact(req);
  EXPECT_EQ(wire(ex.answer), Bytes{0xE5});
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  for (std::size_t k = irqs; k < b.user.interrupts.size(); ++k)
    EXPECT_EQ(b.user.interrupts[k].second & irq::New_Prm_Data, 0);
  const Exchange diag = b.master.slave_diag();
  ASSERT_TRUE(diag.answer);
  ASSERT_GE(diag.answer->du.size(), 6u) << ::testing::PrintToString(wire(diag.answer));
  EXPECT_EQ(diag.answer->du[0] & 0x40, 0) << "Prm_Fault";
}

// p.26: "Byte 13 is permanently reserved for the DPC31" (DPV1_Enable, Failsafe, WD_Base, the
// others reserved): its bits 0 and 1 do not overwrite Dis_Start_Control / Dis_Stop_Control as
// the SPC3's Spec_User_Prm_Byte does.
TEST(Dpc31Requests, Byte13DoesNotSetDisStartOrDisStop) {
  Bench b(Profile::dpc31);
  b.master.slave().user_prm = {0x03};
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(rd(b.chip, RegId::Mode_Reg0) & 0x03, 0);
}

// p.26: byte 13 bit 6 Failsafe: with it the DPC31 accepts Data_Exchange without outputs (the
// fail-safe exchange of seed 003) even when Mode_Reg0's Spec_Clear_Mode is 0; without it such an
// exchange is refused (RS) as a wrong output length.
TEST(Dpc31Requests, Byte13FailsafeAcceptsDataExchangeWithoutOutputs) {
  for (const bool failsafe : {true, false}) {
    ResponderConfig rc;
    rc.spec_clear_mode = false;
    Bench b(Profile::dpc31, 1'500'000, rc);
    b.master.slave().user_prm = {static_cast<std::uint8_t>(failsafe ? 0x40 : 0x00)};
    ASSERT_TRUE(b.master.startup());
    const Exchange dx = b.master.data_exchange({});
    ASSERT_TRUE(dx.answer);
    if (failsafe) {
      // SD2 answer with the four inputs, DL (seed 003 p.33: the inputs still come back).
      EXPECT_EQ(wire(dx.answer).at(0), 0x68) << "failsafe";
    } else {
      EXPECT_EQ(fdl::response_code(dx.answer->fc), fdl::Response::RS);
    }
  }
}

// p.26: the "User_SSA_OK Cmd" read answers 00 User_SSA_Finished, 01 SSA_Conflict, 11
// Not_Allowed, 10 not possible. After a Set_Slave_Add (New_SSA_Data) it finishes (00) and SAP55
// takes the next one; with none pending it answers 11 (which code when: docs/dpc31.md).
TEST(Dpc31Requests, UserSsaOkFinishesAPendingSetSlaveAddAndRefusesWithoutOne) {
  Bench b(Profile::dpc31);
  AckOnly user;
  b.master.set_firmware([&user](BusPort& c) { user.isr(c); });
  until_answered(b);
  const std::uint32_t ssa_ok = at(b.chip, RegId::SSA_Buffer_Free_Cmd);
  EXPECT_EQ(b.chip.addr_of(RegId::SSA_Buffer_Free_Cmd),
            find_reg(b.chip.profile(), "User_SSA_OK_Cmd")->read_addr);
  EXPECT_EQ(b.chip.read(ssa_ok), 0x03);
  EXPECT_EQ(wire(b.master.set_slave_address(9, false).answer), Bytes{0xE5});
  b.master.set_target(9);
  EXPECT_EQ(b.chip.read(ssa_ok), 0x00);
  EXPECT_EQ(b.chip.read(ssa_ok), 0x03);
  EXPECT_EQ(wire(b.master.set_slave_address(10, false).answer), Bytes{0xE5});
}

// p.26: "The SSA_State_Machine is reset also when ... the watchdog has expired in the mode
// 'DP_Control'." The Responder never reads User_SSA_OK, so after a Set_Slave_Add SAP55 refuses the
// next one (RR: the buffer is not free); the DP watchdog (TWD = 10 ms x 10 x 10 = 1 s) expiring
// in DP_Control opens it again: the next Set_Slave_Add is taken (SC), and User_SSA_OK finishes it
// (00). (Before, a DP_Control expiry left SAP55 closed: RR.)
TEST(Dpc31Requests, DpControlExpiryResetsTheSsaStateMachine) {
  Bench b(Profile::dpc31);
  until_answered(b);
  ASSERT_EQ(wire(b.master.set_slave_address(9, false).answer), Bytes{0xE5});
  b.master.set_target(9);
  const Exchange refused = b.master.set_slave_address(10, false);
  ASSERT_TRUE(refused.answer);
  EXPECT_EQ(fdl::response_code(refused.answer->fc), fdl::Response::RR);
  ASSERT_TRUE(b.master.startup());
  ASSERT_EQ(b.chip.wd_state(), WdState::DP_Control);
  b.master.idle(48'000'000ull + 48'000);
  ASSERT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  ASSERT_EQ(b.chip.wd_state(), WdState::Baud_Control);  // DP_Control expired
  EXPECT_EQ(wire(b.master.set_slave_address(10, false).answer), Bytes{0xE5});
  EXPECT_EQ(b.chip.read(at(b.chip, RegId::SSA_Buffer_Free_Cmd)), 0x00);  // User_SSA_Finished
}

// Table 5.2-8 / p.26 name the user's commands User_New_Dout, User_New_Din and User_SSA_OK: the
// register description knows them under those names at the commands' (modelled) addresses, and
// the C header defines them (DPC31_User_New_Dout_Cmd, ...).
TEST(Dpc31Requests, ManualNamesReachTheCommands) {
  const ProfileDesc& p = profile_desc(Profile::dpc31);
  const std::pair<const char*, RegId> names[] = {{"User_New_Dout_Cmd", RegId::Next_Dout_Buffer_Cmd},
                                                 {"User_New_Din_Cmd", RegId::New_Din_Buffer_Cmd},
                                                 {"User_SSA_OK_Cmd", RegId::SSA_Buffer_Free_Cmd}};
  for (const auto& [name, id] : names) {
    const RegDesc* r = find_reg(p, name);
    ASSERT_NE(r, nullptr) << name;
    EXPECT_EQ(r->id, id) << name;
  }
  EXPECT_EQ(DPC31_User_New_Dout_Cmd, 0x000Bu);
  EXPECT_EQ(DPC31_User_New_Din_Cmd, 0x0009u);
  EXPECT_EQ(DPC31_User_SSA_OK_Cmd, 0x0014u);
  EXPECT_EQ(DPC31_User_New_Dout_Cmd_U_Buffer_Cleared_Msk, 0x08u);
  EXPECT_EQ(find_reg(profile_desc(Profile::spc3), "User_New_Dout_Cmd"), nullptr);
}
