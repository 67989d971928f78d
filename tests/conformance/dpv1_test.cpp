// The VPC3+'s PROFIBUS DP extensions (DPV1), chapter 7 of the VPC3+C User Manual Rev 1.03
// pp. 53-56 (VPC3+S Rev 1.04 pp. 59-63), as shared/reference/manual-quotes.md ("DPV1") quotes
// it: one test per sentence, driven through the wire (the built-in master's telegrams), the bus
// (the test is the firmware: it lays out the SAP list and buffers and answers) and the X/INT pin.
// Cycles from docs/timing.md: a request is acted on at the stop-bit sample of its last character
// (request end - T + T/2); an answer starts max(11, MinTSDR) = 11 bit times after the request's
// end (MinTSDR_Val 0Bh) and ends 11 bit times per character later. Where the manual is silent
// the test says "modelled" and names the row of docs/decisions.md ("DPV1").
#include "dpc31/dpv1.hpp"

#include <algorithm>
#include <string>

#include "user_side.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

namespace hd = dpv1::header;

// The firmware's layout (8-byte segments): the SAP list, two indication buffers, one response
// buffer, each a 4-byte header and up to 240 data bytes.
constexpr std::uint32_t kList = 0x400, kInd0 = 0x500, kInd1 = 0x600, kResp = 0x700;
constexpr std::uint8_t seg(std::uint32_t a) { return static_cast<std::uint8_t>(a >> 3); }
constexpr std::uint8_t kC1 = 51;  // MSAC_C1: the master's SSAP and our SAP
constexpr std::uint8_t kMaster = 2, kSlave = 5;
const Bytes kRead = {0x5E, 0x00, 0x01, 0x04};  // MSAC_C1 Read slot 0 index 1, 4 bytes

struct Entry {
  std::uint8_t sap = kC1;
  std::uint8_t sa = 0x7F;  // "The default value for this entry is 7FH."
  std::uint8_t ssap = 0x7F;
  std::uint8_t service = 0x00;  // "00 = all FDL services allowed"
  std::uint8_t ind0 = seg(kInd0);
  std::uint8_t ind1 = seg(kInd1);
  std::uint8_t resp = seg(kResp);
};

// The firmware does not require Fail_Safe (Spec_Clear_Mode = 0) unless a test says so.
ResponderConfig with_prm(Bytes user_prm) {
  ResponderConfig rc;
  rc.slave.user_prm = std::move(user_prm);
  rc.spec_clear_mode = false;
  return rc;
}

struct Dpv1 : Bare {
  std::vector<std::uint64_t> irq_on;  // X/INT rising edges
  std::vector<std::string> log;       // the chip's log lines

  explicit Dpv1(Bytes user_prm = {0x80, 0x00, 0x00}, Profile p = Profile::vpc3plus)
      : Bare(p, 12'000'000, with_prm(std::move(user_prm))) {
    chip.on_irq_change([this](std::uint64_t c, bool active) {
      if (active) irq_on.push_back(c);
    });
    chip.set_log_sink([this](const LogRecord& r) { log.push_back(r.text); });
  }
  [[nodiscard]] bool logged(const std::string& text) const {
    return std::find(log.begin(), log.end(), text) != log.end();
  }
  // "The SAP-List is set up by the user while Offline" (p.54): Go_Offline, the list at 17h, the
  // buffer headers (Max_Length), FDL_Ind and Poll_End_Ind unmasked, Start.
  void set_up(const std::vector<Entry>& entries, std::uint8_t max_len = 240) {
    testutil::user_go_offline(chip);
    chip.write(addr(chip, RegId::R_FDL_SAP_List_Ptr), seg(kList));
    std::uint32_t a = kList;
    for (const Entry& e : entries) {
      for (const std::uint8_t v : {e.sap, e.sa, e.ssap, e.service, e.ind0, e.ind1, e.resp})
        chip.write(a++, v);
    }
    chip.write(a, 0xFF);  // "the last entry FFH"
    for (const std::uint32_t buf : {kInd0, kInd1, kResp}) {
      chip.write(buf + hd::Control, 0x00);
      chip.write(buf + hd::Max_Length, max_len);
    }
    chip.write(addr(chip, RegId::Int_Mask_Reg) + 1, 0x00);  // Intel: bits 15..8 all enabled
    testutil::user_start(chip);
    found_again();
  }
  // The SAP list set up, then the start-up with the test as the user (start_by_hand).
  void online(const std::vector<Entry>& entries, std::uint8_t max_len = 240) {
    set_up(entries, max_len);
    start_by_hand(*this);
  }
  // Mode_Reg0.Set_Ext_Prm_Supported (with DP_Mode) set while Offline, then Start.
  void set_ext_prm_supported() {
    testutil::user_go_offline(chip);
    chip.write(addr(chip, RegId::Mode_Reg0) + 1, 0x09);
    testutil::user_start(chip);
    found_again();
  }
  // With Set_Ext_Prm_Supported: the master's Set_Prm and the user's User_Prm_Data_Okay, so the
  // slave is in Wait_Cfg, where a Set_Ext_Prm is taken (p.54).
  void wait_cfg_for_set_ext_prm() {
    set_ext_prm_supported();
    ASSERT_TRUE(master.fdl_status().answer);
    master.set_prm();
    ASSERT_EQ(chip.read(0x0E), 0x00);  // User_Prm_Data_Okay
  }
  // After a Start the chip searches the baud rate again: FDL_Status until it answers.
  void found_again() {
    for (int i = 0; i < 20 && !master.fdl_status().answer; ++i) {
    }
  }
  // Every pending event acknowledged (New_Prm/Cfg_Data go with their OK reads).
  void ack_all() {
    const std::uint16_t ir = irr(chip);
    chip.write(addr(chip, RegId::Int_Ack_Reg), static_cast<std::uint8_t>(ir));
    chip.write(addr(chip, RegId::Int_Ack_Reg) + 1, static_cast<std::uint8_t>(ir >> 8));
  }
  // An SRD from SSAP `ssap` to SAP `dsap`, FCV = 0 unless `fc` says otherwise.
  Exchange srd(std::uint8_t dsap, Bytes du, std::uint8_t ssap = kC1,
               std::uint8_t fc = fdl::make_request_fc(fdl::Function::SRD_high, false, false),
               std::uint8_t from = kMaster) {
    return master.transact(fdl::make_frame(master.target(), from, fc, std::move(du), dsap, ssap));
  }
  // The user answers: IND taken, the response into the response buffer, RESP with USER.
  void respond(const Bytes& data, std::uint8_t fc = 0x08,
               std::uint8_t control = hd::USER | hd::RESP) {
    for (std::size_t i = 0; i < data.size(); ++i)
      chip.write(kResp + hd::kBytes + static_cast<std::uint32_t>(i), data[i]);
    chip.write(kResp + hd::Length, static_cast<std::uint8_t>(data.size()));
    chip.write(kResp + hd::Function_Code, fc);
    chip.write(kResp + hd::Control, control);
  }
  [[nodiscard]] std::uint64_t answer_at(const Exchange& ex) const {
    return ex.request_end + 11 * T();
  }
};

Bytes sc() { return {0xE5}; }
Bytes short_fc(std::uint8_t fc) { return wire(fdl::make_frame(kMaster, kSlave, fc)); }

// Slave_Diag Station_Status_1 bit 6 Prm_Fault (chip-facts §8).
bool prm_fault(Bare& b) {
  const Exchange d = b.master.slave_diag();
  return d.answer && !d.answer->du.empty() && (d.answer->du[0] & 0x40) != 0;
}

// --- 7.1 Set_(Ext_)Prm ---

// p.53: "The PROFIBUS DP extensions require three bytes to implement the new parameterization
// function." A Set_Prm with DPV1_Enable and DPV1_Status_1..3 is taken, the three bytes in the
// Prm buffer as sent; with DPV1_Enable but without bytes 8 and 9 it is refused: Prm_Fault
// (modelled).
TEST(Dpv1SetPrm, ExtensionsRequireThreeBytes) {
  Dpv1 b({0x80, 0x24, 0x08});
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  EXPECT_EQ(irr(b.chip) & irq::New_Prm_Data, irq::New_Prm_Data);
  EXPECT_EQ(read_ram(b.chip, buffer_base(b.chip, RegId::R_Prm_Buf_Ptr) + 7, 3),
            (Bytes{0x80, 0x24, 0x08}));
  Dpv1 c({0x80});
  ASSERT_TRUE(c.master.fdl_status().answer);
  c.master.set_prm();
  EXPECT_EQ(irr(c.chip) & irq::New_Prm_Data, 0);
  EXPECT_TRUE(prm_fault(c));
}

// p.53: "If the extensions are used, the bit Spec_Clear_Mode in Mode Register 0 serves as
// Fail_Safe_required. ... If the DP-Slave requires Fail_Safe but the DP-Master doesn't the
// Prm_Fault bit is set."
TEST(Dpv1SetPrm, SpecClearModeRequiresFailSafe) {
  ResponderConfig rc = with_prm({0x80, 0x00, 0x00});
  rc.spec_clear_mode = true;  // "Fail_Safe_required"
  Bare b(Profile::vpc3plus, 12'000'000, rc);
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  EXPECT_EQ(irr(b.chip) & irq::New_Prm_Data, 0);
  EXPECT_TRUE(prm_fault(b));
  b.master.slave().user_prm = {0xC0, 0x00, 0x00};  // DPV1_Enable, Fail_Safe
  b.master.set_prm();
  EXPECT_EQ(irr(b.chip) & irq::New_Prm_Data, irq::New_Prm_Data);
}

// p.53: "Whether the DP-Master supports the Fail_Safe mode or not is indicated by the telegram
// bit." A master with Fail_Safe sends Data_Exchange without outputs in Clear: taken (the inputs
// come back), where without Fail_Safe and Spec_Clear_Mode it is refused with RS.
TEST(Dpv1SetPrm, FailSafeAcceptsDataExchangeWithoutOutputs) {
  Dpv1 b({0xC0, 0x00, 0x00});
  start_by_hand(b, {0x11, 0x22, 0x33, 0x44});
  const Exchange ex = b.master.data_exchange({});
  ASSERT_TRUE(ex.answer);
  EXPECT_EQ(ex.answer->du, (Bytes{0x11, 0x22, 0x33, 0x44}));
  Dpv1 c({0x80, 0x00, 0x00});
  start_by_hand(c, {0x11, 0x22, 0x33, 0x44});
  EXPECT_EQ(wire(c.master.data_exchange({}).answer), short_fc(kFcRS));
}

// p.53: "If redundancy should be supported, the PrmCmd_Supported bit in Mode Register 0 must be
// set." PrmCmd (DPV1_Status_3 bit 7) without it: Prm_Fault (modelled).
TEST(Dpv1SetPrm, PrmCmdNeedsPrmCmdSupported) {
  Dpv1 b({0x80, 0x00, 0x80});
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  EXPECT_TRUE(prm_fault(b));
}

// p.53: "the parameterization data must be packed in a Structured_Prm_Data block ... The bit
// Prm_Structure indicates this." The chip takes it as it is; the blocks are the user's.
TEST(Dpv1SetPrm, PrmStructureIsPassedToTheUser) {
  Dpv1 b({0x80, 0x00, 0x08, 0x05, 0x02, 0x00, 0x00, 0xAB});
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  EXPECT_EQ(b.chip.read(addr(b.chip, RegId::R_Len_Prm_Data)), 15);
  EXPECT_EQ(read_ram(b.chip, buffer_base(b.chip, RegId::R_Prm_Buf_Ptr) + 9, 6),
            (Bytes{0x08, 0x05, 0x02, 0x00, 0x00, 0xAB}));
}

// p.53, Figure 7-1: DPV1_Status_1 bit 2 WD_Base ("The bits of the Spec_User_Prm_Byte are
// included"): with DPV1 the master's WD_Base sets the 1 ms base (Mode_Reg0.WD_Base stays 0):
// TWD = 1 ms x 10 x 10 = 4 800 000 clocks after the locking master's last request (modelled).
TEST(Dpv1SetPrm, WdBaseFromDpv1Status1) {
  Dpv1 b({0x84, 0x00, 0x00});
  start_by_hand(b);
  b.ack_all();
  const std::uint64_t last = b.acted(b.master.history().back());
  b.irq_on.clear();
  b.master.idle(6'000'000);
  ASSERT_FALSE(b.irq_on.empty());
  EXPECT_EQ(b.irq_on.front(), last + 4'800'000);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
}

// p.54 (manual-quotes.md): Set_Ext_Prm (SAP 53) "is taken only in Wait_Cfg after a Set_Prm and
// before Chk_Cfg, needs Set_Ext_Prm_Supported in Mode_Reg0 and raises New_Ext_Prm_Data". Its data
// go into the Prm buffer (p.42: Set_(Ext_)Prm through the Aux buffers) and the
// User_Prm_Data_Okay read answers it (00h, New_Ext_Prm_Data cleared), the state stays Wait_Cfg.
TEST(Dpv1SetExtPrm, TakenInWaitCfgWithSetExtPrmSupported) {
  Dpv1 b;
  b.set_ext_prm_supported();
  ASSERT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(wire(b.master.set_ext_prm({0x07, 0x81}).answer), short_fc(kFcRS));  // Wait_Prm
  b.master.set_prm();
  ASSERT_EQ(b.chip.read(0x0E), 0x00);
  const Exchange ex = b.master.set_ext_prm({0x07, 0x81, 0x00, 0x00, 0x42});
  EXPECT_EQ(wire(ex.answer), sc());
  EXPECT_EQ(irr(b.chip) & irq::New_Ext_Prm_Data, irq::New_Ext_Prm_Data);
  EXPECT_EQ(b.chip.read(addr(b.chip, RegId::R_Len_Prm_Data)), 5);
  EXPECT_EQ(read_ram(b.chip, buffer_base(b.chip, RegId::R_Prm_Buf_Ptr), 5),
            (Bytes{0x07, 0x81, 0x00, 0x00, 0x42}));
  EXPECT_EQ(b.chip.read(0x0E), 0x00);  // User_Prm_Data_Okay: finished
  EXPECT_EQ(irr(b.chip) & irq::New_Ext_Prm_Data, 0);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Cfg);
  b.master.chk_cfg();
  EXPECT_EQ(wire(b.master.set_ext_prm({0x07, 0x81}).answer), short_fc(kFcRS));  // after Chk_Cfg
}

TEST(Dpv1SetExtPrm, WithoutSetExtPrmSupportedRs) {
  Dpv1 b;
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  ASSERT_EQ(b.chip.read(0x0E), 0x00);
  EXPECT_EQ(wire(b.master.set_ext_prm({0x07, 0x81}).answer), short_fc(kFcRS));
  EXPECT_EQ(irr(b.chip) & irq::New_Ext_Prm_Data, 0);
}

// p.48 (manual-quotes.md, "Cfg OK goes to Data_Exchange at once"): "During start-up, the VPC3+C
// does not go to DATA-EXCH before all parameter telegrams and configuration telegrams have been
// acknowledged"; p.43: "immediately, if trigger counters for the parameter telegrams and
// configuration telegrams are at 0". A Cfg OK while a Set_Ext_Prm waits for its verdict keeps
// Wait_Cfg (its read answers 00h, New_Cfg_Data cleared); meanwhile a Data_Exchange gets RS and
// the diag Station_Not_Ready, as in Wait_Cfg. The Set_Ext_Prm's User_Prm_Data_Okay then enters
// Data_Exchange at its completion cycle, with Go/Leave_Data_Exchange, as the Cfg OK would have
// (docs/timing.md "Command reads"). Audit s30 a-dpv1 finding 1: the Cfg OK entered at once.
TEST(Dpv1SetExtPrm, CfgOkWaitsForTheSetExtPrmVerdict) {
  Dpv1 b;
  b.wait_cfg_for_set_ext_prm();
  ASSERT_EQ(wire(b.master.set_ext_prm({0x07, 0x81, 0x00, 0x00, 0x42}).answer), sc());
  EXPECT_EQ(wire(b.master.chk_cfg().answer), sc());
  EXPECT_EQ(b.chip.read(0x10), 0x00);  // User_Cfg_Data_Okay: finished
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Cfg);
  EXPECT_EQ(irr(b.chip) & (irq::New_Cfg_Data | irq::Go_Leave_Data_Exchange), 0);
  EXPECT_EQ(wire(b.master.data_exchange({0, 0, 0, 0}).answer), short_fc(kFcRS));
  const Exchange d = b.master.slave_diag();
  ASSERT_TRUE(d.answer);
  EXPECT_EQ(d.answer->du[0], 0x02);  // Station_Not_Ready only
  std::uint64_t verdict_at = 0, dx_at = 0;
  b.chip.on_bus_access([&](std::uint64_t c, const BusAccess& a) {
    if (!a.write && a.addr == 0x0E) verdict_at = c;
  });
  b.chip.on_state_change([&](std::uint64_t c) {
    if (dx_at == 0 && b.chip.dp_state() == DpState::Data_Exchange) dx_at = c;
  });
  EXPECT_EQ(b.chip.read(0x0E), 0x00);  // the Set_Ext_Prm's verdict
  EXPECT_NE(verdict_at, 0u);
  EXPECT_EQ(dx_at, verdict_at);
  EXPECT_EQ(irr(b.chip) & (irq::New_Ext_Prm_Data | irq::Go_Leave_Data_Exchange),
            irq::Go_Leave_Data_Exchange);
  const Exchange dx = b.master.data_exchange({0, 0, 0, 0});
  ASSERT_TRUE(dx.answer);
  EXPECT_EQ(dx.answer->fc, kFcDL);
}

// The same wait (p.48), the other verdicts (modelled, docs/decisions.md "The thirtieth session:
// s30-dpv1chip"): the Set_Ext_Prm's User_Prm_Data_Not_Okay goes to Wait_Prm with Prm_Fault and
// no Go/Leave_Data_Exchange (Data_Exchange was never entered); a Chk_Cfg while the Cfg OK waits
// is a new configuration (SC, New_Cfg_Data): the Set_Ext_Prm's Okay then leaves the chip in
// Wait_Cfg until the new one's Cfg OK.
TEST(Dpv1SetExtPrm, WaitingCfgOkEndsWithNotOkayOrANewChkCfg) {
  Dpv1 b;
  b.wait_cfg_for_set_ext_prm();
  ASSERT_EQ(wire(b.master.set_ext_prm({0x07, 0x81}).answer), sc());
  b.master.chk_cfg();
  ASSERT_EQ(b.chip.read(0x10), 0x00);
  b.ack_all();
  EXPECT_EQ(b.chip.read(0x0F), 0x00);  // User_Prm_Data_Not_Okay: finished
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(irr(b.chip) & irq::Go_Leave_Data_Exchange, 0);
  EXPECT_TRUE(prm_fault(b));

  b.master.set_prm();
  ASSERT_EQ(b.chip.read(0x0E), 0x00);
  ASSERT_EQ(wire(b.master.set_ext_prm({0x07, 0x81}).answer), sc());
  b.master.chk_cfg();
  ASSERT_EQ(b.chip.read(0x10), 0x00);  // Cfg OK: waits for the Set_Ext_Prm's verdict
  EXPECT_EQ(wire(b.master.chk_cfg().answer), sc());
  EXPECT_EQ(irr(b.chip) & irq::New_Cfg_Data, irq::New_Cfg_Data);
  EXPECT_EQ(b.chip.read(0x0E), 0x00);  // the Set_Ext_Prm accepted: the new Cfg still unchecked
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Cfg);
  EXPECT_EQ(b.chip.read(0x10), 0x00);
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
}

// Set_Ext_Prm from a master that does not lock the slave is ignored (SC) in every state, as its
// Set_Prm and Chk_Cfg are ("If the Check_Config message does not come from 'Master_Add' ...
// DPS ignores this message", DPC31 p.28): before the state is looked at (modelled,
// docs/decisions.md "The twenty-eighth session"). The locking master's is refused with RS outside
// "Wait_Cfg after a Set_Prm and before Chk_Cfg" (p.54) and while its earlier one waits for its
// verdict, each with its reason in the log; an empty one gets RR, as an empty Chk_Cfg (modelled),
// and a log line (audit s28 aud1, findings 4 and 5: station 7 got RS, the pending verdict was
// logged as "not between Set_Prm and Chk_Cfg", the empty one was not logged).
TEST(Dpv1SetExtPrm, AnotherMasterIsIgnoredAndEveryRefusalLogsItsReason) {
  Dpv1 b;
  b.wait_cfg_for_set_ext_prm();
  const auto ext = [&](std::uint8_t from, Bytes du) {
    return wire(b.srd(sap::Set_Ext_Prm, std::move(du), 62,
                      fdl::make_request_fc(fdl::Function::SRD_high, false, false), from)
                    .answer);
  };
  EXPECT_EQ(ext(kMaster, {}), short_fc(kFcRR));
  EXPECT_TRUE(b.logged("Set_Ext_Prm from 2: no data (RR)"));
  EXPECT_EQ(ext(kMaster, {0x07, 0x81}), sc());  // its verdict pending
  EXPECT_EQ(ext(kMaster, {0x07, 0x82}), short_fc(kFcRS));
  EXPECT_TRUE(b.logged("Set_Ext_Prm from 2: an earlier Set_Ext_Prm waits for its verdict (RS)"));
  EXPECT_EQ(ext(7, {0x04, 0x05}), sc());
  EXPECT_TRUE(b.logged("Set_Ext_Prm from 7: not the locking master: ignored"));
  EXPECT_EQ(b.chip.read(0x0E), 0x00);  // the verdict
  b.master.chk_cfg();
  EXPECT_EQ(ext(9, {0x04, 0x05}), sc());  // a Chk_Cfg came: past Wait_Cfg's window
  EXPECT_TRUE(b.logged("Set_Ext_Prm from 9: not the locking master: ignored"));
  EXPECT_EQ(ext(kMaster, {0x07, 0x81}), short_fc(kFcRS));
  EXPECT_TRUE(b.logged("Set_Ext_Prm from 2: not between Set_Prm and Chk_Cfg (RS)"));
  EXPECT_EQ(read_ram(b.chip, buffer_base(b.chip, RegId::R_Prm_Buf_Ptr), 2), (Bytes{0x07, 0x81}));
}

// --- 7.2 the SAP list ---

// p.54: "The new communication features are enabled with DPV1_Enable in the Set_Prm telegram."
// Without it a listed SAP is not served (RS); with it the request is taken.
TEST(Dpv1SapList, EnabledByDpv1Enable) {
  Dpv1 off({0x00, 0x00, 0x00});
  off.online({Entry{}});
  EXPECT_EQ(wire(off.srd(kC1, kRead).answer), short_fc(kFcRS));
  Dpv1 on;
  on.online({Entry{}});
  EXPECT_EQ(wire(on.srd(kC1, kRead).answer), sc());
}

// p.54: the SAP list, 7 bytes an entry from the segment in 17H, "the last entry FFH": an entry
// behind the FFh is not in the list.
TEST(Dpv1SapList, EndsAtFFh) {
  Dpv1 b;
  b.set_up({Entry{50}, Entry{kC1}});
  b.chip.write(kList + 7, 0xFF);  // the list ends after SAP 50
  start_by_hand(b);
  EXPECT_EQ(wire(b.srd(kC1, kRead).answer), short_fc(kFcRS));
  EXPECT_EQ(wire(b.srd(50, {0x5C, 0x00, 0x00, 0x00}, 50).answer), sc());
}

// p.55: "Request_SA: The source address of a request is compared with this value. At
// differences, the VPC3+C response with 'no service activated' (RS). The default value for this
// entry is 7FH."
TEST(Dpv1SapList, RequestSaMismatchRs) {
  Entry e;
  e.sa = 3;
  Dpv1 b;
  b.online({e});
  EXPECT_EQ(wire(b.srd(kC1, kRead).answer), short_fc(kFcRS));  // from master 2
  EXPECT_EQ(b.chip.read(kInd0 + hd::Control), 0x00);
  const std::uint8_t fc = fdl::make_request_fc(fdl::Function::SRD_high, false, false);
  EXPECT_EQ(wire(b.srd(kC1, kRead, kC1, fc, 3).answer), sc());  // from master 3
}

// p.55: "Request_SSAP: The source SAP of a request is compared with this value. At differences,
// the VPC3+C response with 'no service activated' (RS)."
TEST(Dpv1SapList, RequestSsapMismatchRs) {
  Entry e;
  e.ssap = kC1;
  Dpv1 b;
  b.online({e});
  EXPECT_EQ(wire(b.srd(kC1, kRead, 50).answer), short_fc(kFcRS));
  EXPECT_EQ(wire(b.srd(kC1, kRead, kC1).answer), sc());
}

// p.55: "Service_Supported: Indicates the permitted FDL service. 00 = all FDL services allowed."
// The other codes as the Profichip driver uses them (modelled): 09h SRD low priority only, so an
// SRD with high priority gets RS.
TEST(Dpv1SapList, ServiceSupportedRestrictsTheFdlService) {
  Entry e;
  e.service = dpv1::service::SRD_L;
  Dpv1 b;
  b.online({e});
  EXPECT_EQ(wire(b.srd(kC1, kRead).answer), short_fc(kFcRS));  // SRD high
  EXPECT_EQ(wire(b.srd(kC1, kRead, kC1, fdl::make_request_fc(fdl::Function::SRD_low, false, false))
                     .answer),
            sc());
}

// p.56: "A received telegram is compared with the values in the SAP-List. If this check is
// positive, the telegram is stored in an Indication-Buffer with the INUSE bit set. ... After
// finishing the processing of the incoming telegram, the INUSE bit is reset and the bits USER and
// IND are set by VPC3+C. Now the FDL_Ind interrupt is generated." p.55/56: the 4-byte header
// (Max_Length, Length, Function Code) and the data block. FDL_Ind (X/INT) at the cycle the request
// is acted on; the request answered SC 11 bit times after its end.
TEST(Dpv1Processing, IndicationStoredThenHandedOverWithFdlInd) {
  Dpv1 b;
  b.online({Entry{}});
  b.ack_all();
  b.irq_on.clear();
  const Exchange ex = b.srd(kC1, kRead);
  EXPECT_EQ(wire(ex.answer), sc());
  EXPECT_EQ(ex.answer_start, b.answer_at(ex));
  ASSERT_EQ(b.irq_on.size(), 1u);
  EXPECT_EQ(b.irq_on[0], b.acted(ex));
  EXPECT_EQ(irr(b.chip), irq::FDL_Ind);
  EXPECT_EQ(read_ram(b.chip, kInd0, 8),
            (Bytes{hd::USER | hd::IND, 240, 4, 0x4D, 0x5E, 0x00, 0x01, 0x04}));
}

// p.56: "... or if no free buffer is available with 'no resource' (RR)." Two indication buffers:
// the second request goes to Ind_Buf_Ptr[1], the third finds none free.
TEST(Dpv1Processing, NoFreeIndicationBufferRr) {
  Dpv1 b;
  b.online({Entry{}});
  EXPECT_EQ(wire(b.srd(kC1, kRead).answer), sc());
  EXPECT_EQ(wire(b.srd(kC1, {0x5E, 0x00, 0x02, 0x04}).answer), sc());
  EXPECT_EQ(read_ram(b.chip, kInd1, 6), (Bytes{hd::USER | hd::IND, 240, 4, 0x4D, 0x5E, 0x00}));
  EXPECT_EQ(wire(b.srd(kC1, kRead).answer), short_fc(kFcRR));
  EXPECT_TRUE(b.logged("SAP 51 from 2: no free indication buffer for 4 bytes (RR)"));
}

// A buffer the chip holds (INUSE) is not free either: RR.
TEST(Dpv1Processing, InuseBufferIsNotFree) {
  Entry e;
  e.ind1 = 0x00;  // one indication buffer
  Dpv1 b;
  b.set_up({e});
  b.chip.write(kInd0 + hd::Control, hd::INUSE);
  start_by_hand(b);
  EXPECT_EQ(wire(b.srd(kC1, kRead).answer), short_fc(kFcRR));
}

// p.56: "Polling telegrams do not produce interrupts." A poll (SRD without data) before the user
// answers gets SC and raises nothing.
TEST(Dpv1Processing, PollsRaiseNoInterrupt) {
  Dpv1 b;
  b.online({Entry{}});
  b.srd(kC1, kRead);
  b.ack_all();
  b.irq_on.clear();
  for (int i = 0; i < 3; ++i) {
    const Exchange poll = b.srd(kC1, {});
    EXPECT_EQ(wire(poll.answer), sc());
    EXPECT_EQ(poll.answer_start, b.answer_at(poll));
  }
  EXPECT_TRUE(b.irq_on.empty());
  EXPECT_EQ(irr(b.chip), 0);
}

// p.56: "The RESP bit indicates response data, provided by the user in the Response-Buffer. The
// Poll_End_Ind interrupt is set after the Response-Buffer is sent. Also bits RESP and USER are
// cleared." p.55: Response_Sent "1 = Response sent". The poll after RESP is answered with the
// response (FC from the header, DSAP = the master's SSAP, SSAP = ours), 11 bit times after the
// poll; Poll_End_Ind at the end of its last stop bit, 11 bit times per character later.
TEST(Dpv1Processing, ResponseSentThenPollEndInd) {
  Dpv1 b;
  b.online({Entry{}});
  b.srd(kC1, kRead);
  b.chip.write(kInd0 + hd::Control, hd::USER);  // the user takes the indication
  const Bytes data = {0x5E, 0x00, 0x01, 0x04, 0xDE, 0xAD, 0xBE, 0xEF};
  b.respond(data);
  b.ack_all();
  b.irq_on.clear();
  const Exchange poll = b.srd(kC1, {});
  const Bytes expect = wire(fdl::make_frame(kMaster, kSlave, 0x08, data, kC1, kC1));
  EXPECT_EQ(wire(poll.answer), expect);
  EXPECT_EQ(poll.answer_start, b.answer_at(poll));
  const std::uint64_t end = poll.answer_start + 11ull * b.T() * expect.size();
  EXPECT_EQ(poll.answer_end, end);
  EXPECT_EQ(irr(b.chip), irq::Poll_End_Ind);  // the bus reads take the chip past `end`
  ASSERT_EQ(b.irq_on.size(), 1u);
  EXPECT_EQ(b.irq_on[0], end);
  EXPECT_EQ(b.chip.read(kResp + hd::Control), 0x00);  // RESP and USER cleared
  EXPECT_EQ(b.chip.read(kList) & 0x80, 0x80);         // Response_Sent
  EXPECT_EQ(b.chip.read(kList) & 0x3F, kC1);
  EXPECT_EQ(wire(b.srd(kC1, {}).answer), sc());  // nothing more to send
}

// Modelled (docs/decisions.md, DPV1): RESP without USER is no response; the poll gets SC.
TEST(Dpv1Processing, RespWithoutUserIsNoResponse) {
  Dpv1 b;
  b.online({Entry{}});
  b.srd(kC1, kRead);
  b.respond({0x5E, 0x00, 0x01, 0x00}, 0x08, hd::RESP);
  EXPECT_EQ(wire(b.srd(kC1, {}).answer), sc());
}

// Modelled: a response Length beyond Max_Length sends Max_Length bytes.
TEST(Dpv1Processing, ResponseLongerThanMaxLengthIsCut) {
  Dpv1 b;
  b.online({Entry{}}, 4);
  b.srd(kC1, kRead);
  b.respond({0x5E, 0x00, 0x01, 0x04, 0x01, 0x02});
  EXPECT_EQ(b.srd(kC1, {}).answer->du, (Bytes{0x5E, 0x00, 0x01, 0x04}));
}

// Modelled: request data longer than the buffer's Max_Length get RR and no indication. The log
// names that cause, not p.56's other one (audit s28 aud1, finding 6: it said "no free indication
// buffer" with both buffers free).
TEST(Dpv1Processing, RequestLongerThanMaxLengthRr) {
  Dpv1 b;
  b.online({Entry{}}, 3);
  b.ack_all();
  EXPECT_EQ(wire(b.srd(kC1, kRead).answer), short_fc(kFcRR));
  EXPECT_EQ(irr(b.chip), 0);
  EXPECT_TRUE(b.logged("SAP 51 from 2: 4 bytes, more than Max_Length 3 (RR)"));
}

// docs/dpv1.md: "SDN requests are not answered", nor is a broadcast (the SAP list serves none):
// their refusals are logged as what the line carries, no answer, not as an RS or RR never sent
// (audit s28 aud1, finding 8). Both buffers taken: an SDN finds none free; a broadcast SDN.
TEST(Dpv1Processing, RefusedSdnAndBroadcastAreLoggedWithoutAnAnswer) {
  Dpv1 b;
  b.online({Entry{}});
  b.srd(kC1, kRead);
  b.srd(kC1, kRead);
  const std::uint8_t sdn = fdl::make_request_fc(fdl::Function::SDN_high, false, false);
  EXPECT_FALSE(b.srd(kC1, kRead, kC1, sdn).answer);
  EXPECT_TRUE(b.logged("SAP 51 from 2: no free indication buffer for 4 bytes (SDN: no answer)"));
  EXPECT_FALSE(
      b.master.transact(fdl::make_frame(fdl::kBroadcast, kMaster, sdn, kRead, kC1, kC1)).answer);
  EXPECT_TRUE(b.logged("DSAP 51 from 2: not served (broadcast: no answer)"));
}

// Modelled: Ind_Buf_Ptr[0] = 00h is a SAP not activated (the Profichip driver switches its SAP 49
// off so): RS.
TEST(Dpv1Processing, NoIndicationBufferRs) {
  Entry e;
  e.ind0 = 0x00;
  Dpv1 b;
  b.online({e});
  EXPECT_EQ(wire(b.srd(kC1, kRead).answer), short_fc(kFcRS));
}

// Modelled (EN 50170's repetition): a poll repeated with the same FCB (FCV = 1) after its response
// was lost gets the same response again, without a second Poll_End_Ind.
TEST(Dpv1Processing, RepeatedPollGetsTheSameResponse) {
  Dpv1 b;
  b.online({Entry{}});
  const auto fc = [](bool fcb) { return fdl::make_request_fc(fdl::Function::SRD_high, fcb, true); };
  b.srd(kC1, kRead, kC1, fc(true));  // the master's last FCB (Chk_Cfg) was 0
  b.respond({0x5E, 0x00, 0x01, 0x01, 0x77});
  const Exchange first = b.srd(kC1, {}, kC1, fc(false));
  ASSERT_EQ(first.answer->du, (Bytes{0x5E, 0x00, 0x01, 0x01, 0x77}));
  b.ack_all();
  b.irq_on.clear();
  const Exchange again = b.srd(kC1, {}, kC1, fc(false));
  EXPECT_EQ(wire(again.answer), wire(first.answer));
  EXPECT_TRUE(b.irq_on.empty());
  EXPECT_EQ(wire(b.srd(kC1, {}, kC1, fc(true)).answer), sc());  // the next poll: nothing left
}

// EN 50170's repetition (modelled): a request from the master of the last answer with FCV = 1 and
// that answer's FCB gets the previous answer again, whatever it asks. The chip's log names it at
// the cycle the request is acted on, as every other RS has its line (audit s30 a-dpv1, finding 9:
// scn/bis_b.scn, a raw request to a closed SAP with FCB 1 before a Read with FCB 1, showed the
// Read's RS with no reason). The same line again folds into the log's repeat count: a master
// that repeats for ever cannot flood the log (LogLimiter).
TEST(Dpv1Processing, AnFcbRepeatIsNamedInTheLog) {
  Dpv1 b;
  b.online({Entry{}});
  std::vector<LogRecord> lines;
  b.chip.set_log_sink([&lines](const LogRecord& r) { lines.push_back(r); });
  const std::uint8_t fcb1 = fdl::make_request_fc(fdl::Function::SRD_high, true, true);
  // The master's last FCB (Chk_Cfg) was 0: this one is new. SAP 40 is not in the list.
  EXPECT_EQ(wire(b.srd(40, kRead, 48, fcb1).answer), short_fc(kFcRS));
  b.ack_all();
  b.irq_on.clear();
  std::vector<std::uint64_t> acted;
  for (int i = 0; i < 3; ++i) {
    const Exchange read = b.srd(kC1, kRead, kC1, fcb1);
    EXPECT_EQ(wire(read.answer), short_fc(kFcRS));  // the previous answer, not SC
    acted.push_back(b.acted(read));
  }
  EXPECT_TRUE(b.irq_on.empty());  // nothing stored: no FDL_Ind
  EXPECT_EQ(b.chip.fdl_counters().repeated, 3u);
  std::vector<std::uint64_t> at;
  for (const LogRecord& r : lines) {
    if (r.text == "FCB repeat from 2: the previous answer again") {
      EXPECT_EQ(r.level, LogLevel::info);
      at.push_back(r.cycle);
    }
  }
  EXPECT_EQ(at, std::vector<std::uint64_t>{acted[0]});
}

// --- profiles ---

// docs/dpc31.md: the DPC31's DPV1 interface is not public; DPV1_Enable in its byte 13 is refused
// with Prm_Fault, never ignored.
TEST(Dpv1Profiles, Dpc31RefusesDpv1EnableWithPrmFault) {
  Dpv1 b({0x80, 0x00, 0x00}, Profile::dpc31);
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  EXPECT_TRUE(prm_fault(b));
}

// The SPC3 has no DPV1 (SPC3 manual: bytes 7.3-7.7 of Spec_User_Prm_Byte reserved): SAP 51 is
// not served.
TEST(Dpv1Profiles, Spc3HasNoSapList) {
  Dpv1 b({0x00}, Profile::spc3);
  start_by_hand(b, {0x01, 0x02, 0x03, 0x04});
  EXPECT_EQ(wire(b.srd(kC1, kRead).answer), short_fc(kFcRS));
}

}  // namespace
