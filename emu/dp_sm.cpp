// DP state machine: the services the ASIC answers by itself and the user's verdict on Set_Prm
// and Chk_Cfg (User_Prm/Cfg_Data_(Not_)Okay), SSA_Buffer_Free_Cmd. New_Prm_Data / New_Cfg_Data
// are cleared here, never through IAR. Decisions where the manuals are silent: docs/decisions.md.
#include "dp_sm.hpp"

#include <algorithm>
#include <array>
#include <utility>

#include "dpc31/dpv1.hpp"
#include "dpc31/pdu.hpp"

namespace dpc31 {

namespace {

// Dis_Start_Control and Dis_Stop_Control, which Spec_User_Prm_Byte overwrites.
constexpr std::uint16_t kDis_Start_Stop =
    fields::Mode_Reg0::Dis_Start_Control | fields::Mode_Reg0::Dis_Stop_Control;

constexpr std::uint16_t kSsaNotAllowed = 0x03;  // DPC31 User_SSA_OK Cmd 11 (p.26)
constexpr std::size_t kMinPrmLength = pdu::SetPrm::kStandard;
constexpr std::size_t kMaxBufferLength = 244;

// Diag buffer byte 0 as the user writes it.
constexpr std::uint8_t kDiag_Ext_Diag = 0x01;
constexpr std::uint8_t kDiag_Stat_Diag = 0x02;
constexpr std::uint8_t kDiag_Ext_Diag_Overflow = 0x04;
constexpr std::uint8_t kDiag_User_Bits = kDiag_Ext_Diag | kDiag_Stat_Diag | kDiag_Ext_Diag_Overflow;
constexpr std::size_t kStandardDiagBytes = pdu::SlaveDiag::kStandard;

}  // namespace

// The user's verdict read on a pending Set_Prm or Chk_Cfg: the handshake's answer, and on a
// completed one its event cleared (here, never through IAR) before `accepted` or a Leave_Master
// acts. Nothing pending (a Leave_Master discarded the telegram before the user's verdict): the
// read completes all the same and its event goes (docs/timing.md). Kept, it could never be
// cleared (Int_Ack_Reg ignores it) and X/INT would stay active for good.
template <typename Accepted>
std::uint16_t DpStateMachine::verdict(Handshake& h, std::uint16_t event, bool& fault, Verdict v,
                                      Accepted accepted) {
  bool done = false;
  const std::uint8_t r = h.answer(done);
  if (done || r == kHandshakeNotAllowed)
    regs_.latch(RegId::Int_Req_Reg) &= static_cast<std::uint16_t>(~event);
  if (done) {
    fault = v == Verdict::not_ok;
    if (fault) {
      leave_master();
    } else {
      accepted();
    }
  }
  return r;
}

// The same reads answer a Set_Ext_Prm (VPC3+, New_Ext_Prm_Data): accepting it only lets a Cfg OK
// that waits for it enter Data_Exchange.
std::uint16_t DpStateMachine::prm_verdict(Verdict v) {
  const bool ext = s_.ext_prm;
  const std::uint16_t r = verdict(
      s_.prm, ext ? irq::New_Ext_Prm_Data : irq::New_Prm_Data, s_.prm_fault, v, [this, ext] {
        if (ext) {
          // The last parameter telegram acknowledged: a Cfg OK given meanwhile takes effect now.
          if (s_.dx_deferred && s_.state == DpState::Wait_Cfg) {
            s_.dx_deferred = false;
            enter_data_exchange();
          }
          return;
        }
        // The parameters are accepted: the DP watchdog runs with the new TWD from now on.
        watchdog_.parameterise(s_.prm_wd_on, s_.prm_wd_fact1, s_.prm_wd_fact2, s_.prm_wd_1ms);
        if (s_.state == DpState::Wait_Prm) s_.state = DpState::Wait_Cfg;
      });
  if (!s_.prm.pending) s_.ext_prm = false;
  return r;
}

// SPC3 p.31: "the transition to 'DATA_EX' takes place immediately, if no Din_buffer is present
// (R_Len_Din_Puf = 00H) ..." — otherwise (the sentence is cut off in every copy; modelled) at
// the user's next New_Din_Buffer_Cmd, so the first answer in Data_Exchange carries the user's
// inputs. VPC3+C p.48: "the VPC3+C does not go to DATA-EXCH before all parameter telegrams and
// configuration telegrams have been acknowledged": a Set_Ext_Prm's verdict pending (the only Prm
// verdict Wait_Cfg can have), at that verdict. Otherwise at once.
void DpStateMachine::enter_data_exchange() {
  if (s_.prm.pending || (regs_.id() == Profile::spc3 && regs_.cell(RegId::R_Len_Din_Buf) != 0)) {
    s_.dx_deferred = true;
    din_wait_.since = sig_.clock->now;
    return;
  }
  s_.state = DpState::Data_Exchange;
  irq_.raise(irq::Go_Leave_Data_Exchange);
}

std::uint16_t DpStateMachine::cfg_verdict(Verdict v) {
  return verdict(s_.cfg, irq::New_Cfg_Data, s_.cfg_fault, v, [this] {
    if ((regs_.latch(RegId::Mode_Reg1) & fields::Mode_Reg1::En_Change_Cfg_Buffer) != 0) {
      // Get_Cfg answers the new configuration from now on.
      regs_.swap_cells(RegId::R_Cfg_Buf_Ptr, RegId::R_Read_Cfg_Buf_Ptr);
    }
    if (s_.state == DpState::Wait_Cfg) enter_data_exchange();
  });
}

using fdl::Frame;
using fdl::Response;

// The answer to a request with SAPs: DA/SA swapped, DSAP = the master's SSAP, SSAP = ours.
Frame DpStateMachine::sap_answer(const Frame& req, Response code,
                                 std::vector<std::uint8_t> du) const {
  return fdl::make_frame(req.sa, s_.station, fdl::make_response_fc(code), std::move(du), req.ssap,
                         req.dsap);
}

// One rule for every length cell an answer is read by (R_Len_Din_Buf, R_Len_Dout_Buf,
// R_Len_Read_Cfg_Data, R_Len_Diag_Buf1/2): a DP data unit carries at most 244 bytes (chip-facts
// §1.2), so a cell beyond it sends the buffer's first 244, and the log says so once per cell and
// value (modelled: the manuals give the cells' limits, not what the chip does past them).
std::size_t DpStateMachine::answer_length(RegId len_cell) {
  const std::uint8_t len = regs_.cell(len_cell);
  auto& [cell, logged] = *std::find_if(over_long_.begin(), over_long_.end(),
                                       [len_cell](const auto& c) { return c.first == len_cell; });
  if (len <= kMaxBufferLength) {
    logged = 0;
    return len;
  }
  if (logged != len) {
    logged = len;
    sig_.log(LogLevel::warn,
             "{} = {}: beyond the {} bytes of a DP data unit: the answer sends the buffer's first "
             "{} (modelled)",
             regs_.reg(cell)->name, len, kMaxBufferLength, kMaxBufferLength);
  }
  return kMaxBufferLength;
}

Frame DpStateMachine::short_answer(const Frame& req, Response code) const {
  return fdl::make_frame(req.sa, s_.station, fdl::make_response_fc(code));
}

namespace {

// The command read of a verdict register: the handshake `Handshake` with verdict `v`.
template <std::uint16_t (DpStateMachine::*Handshake)(DpStateMachine::Verdict),
          DpStateMachine::Verdict v>
std::uint16_t verdict_command(void* b) {
  return (self<DpStateMachine>(b).*Handshake)(v);
}

}  // namespace

void DpStateMachine::install_hooks(HookTable& h) {
  using V = DpStateMachine::Verdict;
  auto at = [&h, this](RegId id) -> RegHooks& { return bind_hooks(h, id, *this); };
  auto prm_preview = [](const void* b) { return self<DpStateMachine>(b).prm_preview(); };
  auto cfg_preview = [](const void* b) { return self<DpStateMachine>(b).cfg_preview(); };
  at(RegId::User_Prm_Data_Okay).read = prm_preview;
  at(RegId::User_Prm_Data_Okay).command = verdict_command<&DpStateMachine::prm_verdict, V::ok>;
  at(RegId::User_Prm_Data_Not_Okay).read = prm_preview;
  at(RegId::User_Prm_Data_Not_Okay).command =
      verdict_command<&DpStateMachine::prm_verdict, V::not_ok>;
  at(RegId::User_Cfg_Data_Okay).read = cfg_preview;
  at(RegId::User_Cfg_Data_Okay).command = verdict_command<&DpStateMachine::cfg_verdict, V::ok>;
  at(RegId::User_Cfg_Data_Not_Okay).read = cfg_preview;
  at(RegId::User_Cfg_Data_Not_Okay).command =
      verdict_command<&DpStateMachine::cfg_verdict, V::not_ok>;
  // The DPC31's User_SSA_OK Cmd answers 00 User_SSA_Finished or 11 Not_Allowed (DPC31 p.26;
  // which one when: modelled); the SPC3's SSA_Buffer_Free_Cmd reads don't care (00h).
  at(RegId::SSA_Buffer_Free_Cmd).read = [](const void* b) -> std::uint16_t {
    const DpStateMachine& dp = self<DpStateMachine>(b);
    return dp.regs_.id() == Profile::dpc31 && dp.ssa_free() ? kSsaNotAllowed : 0;
  };
  at(RegId::SSA_Buffer_Free_Cmd).command = [](void* b) -> std::uint16_t {
    DpStateMachine& dp = self<DpStateMachine>(b);
    const bool pending = !dp.ssa_free();
    dp.ssa_buffer_free();
    return dp.regs_.id() == Profile::dpc31 && !pending ? kSsaNotAllowed : 0;
  };
  at(RegId::MinTSDR_Val).post_write = [](void* b, std::uint16_t, std::uint16_t, std::uint16_t) {
    self<DpStateMachine>(b).user_min_tsdr_set();
  };
  // The user hands the inputs over: the buffers' exchange, then the state machine's step.
  at(RegId::New_Din_Buffer_Cmd).read = [](const void* b) {
    return self<DpStateMachine>(b).buffers_.new_din_preview();
  };
  at(RegId::New_Din_Buffer_Cmd).command = [](void* b) {
    DpStateMachine& dp = self<DpStateMachine>(b);
    const std::uint16_t r = dp.buffers_.new_din_cmd();
    dp.din_handed_over();
    return r;
  };
}

// A telegram is received into the Aux buffer R_Aux_Buf_Sel selects and, when it fits, the Aux
// and target buffers are exchanged (pointer cells swap) and the length cell written.
bool DpStateMachine::receive_via_aux(std::uint16_t sel, RegId target_ptr, RegId len_cell,
                                     std::span<const std::uint8_t> du) {
  const bool aux2 = (regs_.cell(RegId::R_Aux_Buf_Sel) & sel) != 0;
  const RegId aux_ptr = aux2 ? RegId::R_Aux_Buf_Ptr2 : RegId::R_Aux_Buf_Ptr1;
  const RegId aux_len = aux2 ? RegId::R_Len_Cntrl_Buf2 : RegId::R_Len_Cntrl_Buf1;
  if (du.size() > regs_.cell(aux_len)) return false;
  regs_.write_buffer(aux_ptr, du);
  regs_.swap_cells(aux_ptr, target_ptr);
  regs_.set_cell(len_cell, static_cast<std::uint8_t>(du.size()));
  return true;
}

// --- the services ---

bool DpStateMachine::service(const fdl::Frame& req) {
  ++counters_.requests;
  const bool broadcast = req.da == fdl::kBroadcast;
  const fdl::Function fn = fdl::request_function(req.fc);
  const bool wants_answer =
      !broadcast && (fn == fdl::Function::SRD_low || fn == fdl::Function::SRD_high ||
                     fn == fdl::Function::FDL_Status);
  // FCB/FCV (EN 50170): the same FCB again from the same master means our answer was lost.
  if (!broadcast && fdl::fcv(req.fc) && s_.fcb_valid && s_.last_master == req.sa &&
      s_.last_fcb == fdl::fcb(req.fc) && !s_.last_response.empty()) {
    ++counters_.repeated;
    // SPC3 p.36 (Rd_Outp: "If there is a buffer change from 'N' to 'U' ... between the first
    // call-up and the repetition, the new output data is sent during the repetition") and
    // DPC31 p.33 (Rd_Inp, U -> N -> D): these two answer from the buffers as they are now.
    const bool io = req.dsap && (fdl::sap_number(*req.dsap) == sap::Rd_Inp ||
                                 fdl::sap_number(*req.dsap) == sap::Rd_Outp);
    // Named in the log: an RS or an old response with no reason would be a riddle (the log's
    // limiter bounds a master that repeats for ever).
    sig_.log(LogLevel::info, "FCB repeat from {}: {}", req.sa,
             io ? "answered from the buffers as they are now" : "the previous answer again");
    if (io) {
      std::optional<Frame> fresh = read_io(req);
      if (!fresh) return false;
      fdl::encode(*fresh, s_.last_response);
      du_ = std::move(fresh->du);
      return true;
    }
    return true;  // the answer before, as it was sent
  }
  std::optional<Frame> answer;
  if (fn == fdl::Function::FDL_Status && !req.dsap) {
    answer = short_answer(req, Response::OK);
  } else if (!regs_.mode0(fields::Mode_Reg0::DP_Mode)) {
    // Mode_Reg0: "DP_MODE: 0 = DP_Mode is disabled. 1 = DP_Mode is enabled. SPC3 sets up all
    // DP_SAPs." Without it no DP SAP (nor Data_Exchange's default SAP) exists: the chip is a
    // plain FDL station that answers FDL_Status and refuses the rest with RS (modelled).
    ++counters_.unknown_sap;
    sig_.log(LogLevel::info, "request from {} with DP_Mode = 0: no DP SAP set up ({})", req.sa,
             refusal_on_line(req, "RS"));
    if (fn == fdl::Function::SRD_low || fn == fdl::Function::SRD_high)
      answer = short_answer(req, Response::RS);
  } else if (fn != fdl::Function::SRD_low && fn != fdl::Function::SRD_high &&
             fn != fdl::Function::SDN_low && fn != fdl::Function::SDN_high) {
    ++counters_.unsupported_function;
    sig_.log(LogLevel::info, "FC {:#04x} from {}: function not served by a DP slave", req.fc,
             req.sa);
  } else if (!req.dsap) {
    answer = data_exchange(req);
  } else {
    switch (fdl::sap_number(*req.dsap)) {
      case sap::Set_Prm:
        answer = set_prm(req);
        break;
      case sap::Chk_Cfg:
        answer = chk_cfg(req);
        break;
      case sap::Slave_Diag:
        answer = slave_diag(req);
        break;
      case sap::Get_Cfg:
        // DPC31 p.33: "accepted in all modes. If the call message contains request data, the
        // MAC acknowledges with 'no resource'."
        if (!req.du.empty()) {
          ++counters_.no_resource;
          answer = short_answer(req, Response::RR);
          break;
        }
        regs_.read_buffer(RegId::R_Read_Cfg_Buf_Ptr, answer_length(RegId::R_Len_Read_Cfg_Data),
                          du_);
        answer = sap_answer(req, Response::DL, std::move(du_));
        break;
      case sap::Rd_Inp:
      case sap::Rd_Outp:
        answer = read_io(req);
        break;
      case sap::Global_Control:
        global_control(req);
        break;
      case sap::Set_Slave_Add:
        answer = set_slave_add(req);
        break;
      case sap::Set_Ext_Prm:
        answer = set_ext_prm(req);
        break;
      default:
        answer = sap_list_answer(req, !broadcast && fdl::sap_number(*req.dsap) <= sap::kSapListLast
                                          ? sap_list_.request(req)
                                          : SapListAnswer{});
        break;
    }
  }
  if (!wants_answer || !answer) return false;
  s_.fcb_valid = fdl::fcv(req.fc);
  s_.last_fcb = fdl::fcb(req.fc);
  s_.last_master = req.sa;
  fdl::encode(*answer, s_.last_response);  // encoded once: sent and kept for a repetition
  du_ = std::move(answer->du);
  return true;
}

std::optional<fdl::Frame> DpStateMachine::set_prm(const fdl::Frame& req) {
  const std::vector<std::uint8_t>& du = req.du;
  if (du.size() < kMinPrmLength && regs_.id() == Profile::dpc31) {
    // DPC31 p.26: "the message has to have at least a length of >= 7 bytes; otherwise, it is
    // ignored" (acknowledged, nothing changes, as the other ignored Set_Prm).
    sig_.log(LogLevel::info, "Set_Prm with {} bytes: ignored", du.size());
    return fdl::sc();
  }
  if (du.size() < kMinPrmLength || du.size() > kMaxBufferLength) {
    sig_.log(LogLevel::info, "Set_Prm with {} bytes: Prm_Fault", du.size());
    prm_fault();
    return fdl::sc();
  }
  // The data unit by its named fields (include/dpc31/pdu.hpp); 7 bytes at least, checked above.
  const pdu::SetPrm prm = *pdu::SetPrm::parse(du);
  const std::uint8_t status = prm.station_status;
  // Byte 7: the Spec_User_Prm_Byte, or DPV1_Status_1 (its bits included, VPC3+C p.53).
  const std::uint8_t spec = prm.status(1);
  if (locked_by_another(req.sa)) {
    // Locked by another master (its diag shows Master_Add): whatever the lock bits say, this
    // master never re-parameterises, unlocks or changes min TSDR.
    ++counters_.not_allowed;
    sig_.log(LogLevel::info, "Set_Prm from master {} while locked by {}: ignored", req.sa,
             s_.master_add);
    return fdl::sc();
  }
  const bool check_reserved =
      regs_.id() != Profile::vpc3plus ||
      (regs_.latch(RegId::Mode_Reg2) & fields::Mode_Reg2::No_Check_Prm_Reserved) == 0;
  const std::uint16_t ident = static_cast<std::uint16_t>(regs_.cell(RegId::R_Ident_High) << 8 |
                                                         regs_.cell(RegId::R_Ident_Low));
  const std::uint16_t asked = prm.ident;
  const char* fault = nullptr;
  if (asked != ident) fault = "Ident_Number differs";
  if (check_reserved && (status & pdu::SetPrm::Station_Status_Reserved) != 0)
    fault = "reserved Station_Status bits";
  if ((status & pdu::SetPrm::Sync_Req) != 0 && !regs_.mode0(fields::Mode_Reg0::Sync_Supported))
    fault = "Sync_Req but Sync not supported";
  if ((status & pdu::SetPrm::Freeze_Req) != 0 && !regs_.mode0(fields::Mode_Reg0::Freeze_Supported))
    fault = "Freeze_Req but Freeze not supported";
  const bool dpv1 = prm.dpv1();
  if (dpv1 && regs_.id() == Profile::dpc31) {
    // The DPC31's DPV1 interface is not public (docs/dpc31.md): refused, never ignored.
    fault = "DPV1_Enable: the DPC31's DPV1 is not modelled";
  } else if (dpv1 && regs_.id() == Profile::vpc3plus) {
    if (const char* f = dpv1_prm_fault(prm); f != nullptr) fault = f;
  }
  const bool lock = (status & pdu::SetPrm::Lock_Req) != 0;
  const bool unlock = (status & pdu::SetPrm::Unlock_Req) != 0;
  // Lock_Req = Unlock_Req = 0 and the unlock codes adopt no parameters: only the Ident_Number
  // check applies to them.
  if (!lock || unlock) fault = asked != ident ? "Ident_Number differs" : nullptr;
  if (fault != nullptr) {
    sig_.log(LogLevel::info, "Set_Prm from {}: {}: Prm_Fault", req.sa, fault);
    prm_fault();
    return fdl::sc();
  }
  // CP 5613/5614 DP Base manual p.198-199: 00 "The min TSDR is overwritten when parameters are
  // assigned. All other parameters remain unchanged." (0 keeps it, as for a lock: modelled)
  if (!lock && !unlock) {
    if (prm.min_tsdr != 0) s_.min_tsdr = prm.min_tsdr;
    sig_.log(LogLevel::info, "Set_Prm from {} without Lock_Req / Unlock_Req: min TSDR only",
             req.sa);
    return fdl::sc();
  }
  // 01 and 11: "released for other masters": the slave leaves this master (Wait_Prm, Master_Add
  // FFh) and nobody is monitored any more.
  if (unlock) {
    sig_.log(LogLevel::info, "Set_Prm from {} with Unlock_Req: released for other masters", req.sa);
    if (s_.state != DpState::Wait_Prm || s_.prm.pending) {
      sig_.emit(BlockEvent::Kind::leave_master);
      leave_master();
    }
    s_.master_add = pdu::SlaveDiag::kNoMaster;
    watchdog_.release();
    return fdl::sc();
  }
  const bool aux2 = (regs_.cell(RegId::R_Aux_Buf_Sel) & fields::R_Aux_Buf_Sel::Set_Prm) != 0;
  if (du.size() > regs_.cell(aux2 ? RegId::R_Len_Cntrl_Buf2 : RegId::R_Len_Cntrl_Buf1)) {
    ++counters_.no_resource;
    return short_answer(req, Response::RR);
  }
  // A new parameterisation starts the DP state machine over (outputs to the safe state). One
  // that arrives while the user is still checking the previous one in Wait_Prm is a newer
  // telegram for the same check: the verdict read answers 01 (conflict).
  if (s_.state != DpState::Wait_Prm) {
    sig_.emit(BlockEvent::Kind::leave_master);
    leave_master();
  }
  // 10: "disabled for other masters, all parameters are adopted (exception: min TSDR = 0)";
  // "The Group_Ident is accepted only when the Lock_Req bit is set."
  s_.master_add = req.sa;
  s_.group_ident = prm.group_ident;
  if (prm.min_tsdr != 0) s_.min_tsdr = prm.min_tsdr;
  // DPC31: byte 13 (DPV1_Status_1) "is permanently reserved for the DPC31": bits 7 DPV1_Enable,
  // 6 Failsafe, 2 WD_Base, the others reserved (p.26), so no Dis_Start / Dis_Stop there.
  if (regs_.mode0(fields::Mode_Reg0::DP_Mode) && du.size() > 7 && regs_.id() != Profile::dpc31) {
    // Spec_User_Prm_Byte overwrites Dis_Start_Control / Dis_Stop_Control in DP mode.
    std::uint16_t& m0 = regs_.latch(RegId::Mode_Reg0);
    sig_.emit(BlockEvent::Kind::dis, spec & kDis_Start_Stop);
    m0 = static_cast<std::uint16_t>((m0 & ~kDis_Start_Stop) | (spec & kDis_Start_Stop));
  }
  // VPC3+: Mode_Reg0.WD_Base, or with DPV1 the master's DPV1_Status_1.WD_Base (p.53: "The bits
  // of the Spec_User_Prm_Byte are included"; modelled).
  const bool telegram_1ms = (spec & dpv1::status1::WD_Base) != 0;
  const bool wd_1ms = regs_.id() != Profile::vpc3plus || dpv1
                          ? telegram_1ms
                          : regs_.mode0(fields::Mode_Reg0::WD_Base);
  // DP_Control starts with these only once the user accepts them (User_Prm_Data_Okay).
  s_.prm_wd_on = (status & pdu::SetPrm::WD_On) != 0;
  s_.prm_wd_fact1 = prm.wd_fact1;
  s_.prm_wd_fact2 = prm.wd_fact2;
  s_.prm_wd_1ms = wd_1ms;
  // DPC31 byte 13 Failsafe; VPC3+ DPV1_Status_1.Fail_Safe: Data_Exchange without outputs.
  s_.failsafe = (regs_.id() == Profile::dpc31 || dpv1) && (spec & dpv1::status1::Fail_Safe) != 0;
  if (regs_.id() == Profile::vpc3plus) sap_list_.enable(dpv1);
  receive_via_aux(fields::R_Aux_Buf_Sel::Set_Prm, RegId::R_Prm_Buf_Ptr, RegId::R_Len_Prm_Data, du);
  sig_.emit(BlockEvent::Kind::prm);
  prm_accepted();
  return fdl::sc();
}

// A Set_Prm that failed the ASIC's checks.
void DpStateMachine::prm_fault() {
  sig_.emit(BlockEvent::Kind::prm_fault);
  leave_master();
  s_.prm_fault = true;
}

// The Prm buffer holds a new, checked Set_Prm: the faults are reported no more, the user's turn.
void DpStateMachine::prm_accepted() {
  s_.prm_fault = s_.cfg_fault = s_.not_supported = false;
  s_.ext_prm = false;
  s_.dx_deferred = false;  // the new parameters need their verdicts again
  s_.prm.arrived();
  irq_.raise(irq::New_Prm_Data);
}

// The Cfg buffer holds a new Chk_Cfg: leave Data_Exchange until the user has checked it.
void DpStateMachine::cfg_accepted() {
  if (s_.state == DpState::Data_Exchange) {
    s_.state = DpState::Wait_Cfg;
    irq_.raise(irq::Go_Leave_Data_Exchange);
  }
  s_.dx_deferred = false;  // the new configuration needs its verdict again
  s_.cfg.arrived();
  irq_.raise(irq::New_Cfg_Data);
}

std::optional<fdl::Frame> DpStateMachine::chk_cfg(const fdl::Frame& req) {
  // DPC31 p.28: "This service is accepted by DPS in any DP mode. If the Check_Config message does
  // not come from 'Master_Add' i.e., the locking master, DPS ignores this message."
  if (req.sa != s_.master_add) {
    ++counters_.not_allowed;
    // Unlocked (a refused Set_Prm, a Leave_Master): the reason is the missing Set_Prm.
    if (s_.master_add == pdu::SlaveDiag::kNoMaster)
      sig_.log(LogLevel::info,
               "Chk_Cfg from {}: no master has locked the slave (Master_Add FFh: not "
               "parameterised): ignored",
               req.sa);
    else
      sig_.log(LogLevel::info, "Chk_Cfg from {}: not the locking master: ignored", req.sa);
    return fdl::sc();
  }
  if (req.du.empty() || req.du.size() > kMaxBufferLength ||
      !receive_via_aux(fields::R_Aux_Buf_Sel::Chk_Cfg, RegId::R_Cfg_Buf_Ptr, RegId::R_Len_Cfg_Data,
                       req.du)) {
    ++counters_.no_resource;
    return short_answer(req, Response::RR);
  }
  sig_.emit(BlockEvent::Kind::cfg);
  cfg_accepted();
  return fdl::sc();
}

// The six standard bytes are the ASIC's; the rest of the buffer is the user's.
std::optional<fdl::Frame> DpStateMachine::slave_diag(const fdl::Frame& req) {
  static constexpr RegId kPtr[] = {RegId::R_Diag_Buf_Ptr1, RegId::R_Diag_Buf_Ptr2};
  static constexpr RegId kLen[] = {RegId::R_Len_Diag_Buf1, RegId::R_Len_Diag_Buf2};
  const int k = buffers_.sending_diag();
  const std::size_t len = std::max(answer_length(kLen[k]), kStandardDiagBytes);
  regs_.read_buffer(kPtr[k], len, du_);
  const std::uint8_t user = du_[0];
  using D = pdu::SlaveDiag;
  du_[0] = static_cast<std::uint8_t>(
      (s_.state != DpState::Data_Exchange ? D::St1_Station_Not_Ready : 0) |
      (s_.cfg_fault ? D::St1_Cfg_Fault : 0) | (user & kDiag_Ext_Diag ? D::St1_Ext_Diag : 0) |
      (s_.not_supported ? D::St1_Not_Supported : 0) | (s_.prm_fault ? D::St1_Prm_Fault : 0));
  du_[1] = static_cast<std::uint8_t>((s_.state == DpState::Wait_Prm ? D::St2_Prm_Req : 0) |
                                     (user & kDiag_Stat_Diag ? D::St2_Stat_Diag : 0) |
                                     D::St2_Always_1 | (watchdog_.dp_wd_on() ? D::St2_WD_On : 0) |
                                     (s_.freeze_mode ? D::St2_Freeze_Mode : 0) |
                                     (s_.sync_mode ? D::St2_Sync_Mode : 0));
  du_[2] = (user & kDiag_Ext_Diag_Overflow) != 0 ? D::St3_Ext_Diag_Overflow : 0x00;
  du_[3] = s_.master_add;
  du_[4] = regs_.cell(RegId::R_Ident_High);
  du_[5] = regs_.cell(RegId::R_Ident_Low);
  // The standard bytes also fill the buffer's space holders, where a driver reads Master_Add
  // (byte 3: the Profichip driver's VPC3_GetMasterAddress). SPC3 p.33: "The first 6 bytes are
  // space holders, except for the three least significant bit positions in the first byte. ...
  // When sending, SPC3 pre-processes the first six bytes corresponding to the standard." VPC3+S
  // p.52: "The Ext_Diag_Data must be entered into the buffers after the VPC3+S internal diagnosis
  // data." The user's three bits stay: a buffer sent again takes them from there.
  std::array<std::uint8_t, kStandardDiagBytes> held{};
  std::copy_n(du_.begin(), kStandardDiagBytes, held.begin());
  held[0] = static_cast<std::uint8_t>((du_[0] & ~kDiag_User_Bits) | (user & kDiag_User_Bits));
  regs_.write_buffer(kPtr[k], held);
  sig_.emit(BlockEvent::Kind::diag_begin);
  buffers_.diag_send_begin();
  s_.diag_in_flight = true;
  s_.diag_requester = req.sa;
  note_din_wait(req, "Slave_Diag with Station_Not_Ready");
  return sap_answer(req, Response::DL, std::move(du_));
}

std::optional<fdl::Frame> DpStateMachine::read_io(const fdl::Frame& req) {
  if (s_.state != DpState::Data_Exchange) {
    ++counters_.not_allowed;
    return short_answer(req, Response::RS);
  }
  if (!req.du.empty()) {  // DPC31 p.33: request data length != 0: "no resource"
    ++counters_.no_resource;
    return short_answer(req, Response::RR);
  }
  if (fdl::sap_number(*req.dsap) == sap::Rd_Inp) {
    sig_.emit(BlockEvent::Kind::din);
    buffers_.inputs_due(s_.freeze_mode);
    regs_.read_buffer(buffers_.din_d_ptr(), answer_length(RegId::R_Len_Din_Buf), du_);
  } else {
    // Read_Outputs is served from the user's U buffer.
    regs_.read_buffer(buffers_.dout_u_ptr(), answer_length(RegId::R_Len_Dout_Buf), du_);
  }
  return sap_answer(req, Response::DL, std::move(du_));
}

std::optional<fdl::Frame> DpStateMachine::set_slave_add(const fdl::Frame& req) {
  const std::vector<std::uint8_t>& du = req.du;
  const std::uint16_t ident = static_cast<std::uint16_t>(regs_.cell(RegId::R_Ident_High) << 8 |
                                                         regs_.cell(RegId::R_Ident_Low));
  if (regs_.cell(RegId::R_SSA_Buf_Ptr) == 0 || s_.no_add_change ||
      regs_.cell(RegId::R_Real_No_Add_Change) == 0xFF || s_.state != DpState::Wait_Prm) {
    ++counters_.not_allowed;  // SAP55 off, address frozen, or not in Wait_Prm
    return short_answer(req, Response::RS);
  }
  if (!s_.ssa_free) {
    ++counters_.no_resource;  // the user has not freed the SSA buffer yet
    return short_answer(req, Response::RR);
  }
  if (du.size() < 4 || du.size() > kMaxBufferLength || du[0] > 125 ||
      static_cast<std::uint16_t>(du[1] << 8 | du[2]) != ident) {
    ++counters_.not_allowed;
    sig_.log(LogLevel::info, "Set_Slave_Add from {}: bad address or Ident_Number: ignored", req.sa);
    return fdl::sc();
  }
  if (!receive_via_aux(fields::R_Aux_Buf_Sel::Set_Slave_Adr, RegId::R_SSA_Buf_Ptr,
                       RegId::R_Len_SSA_Data, du)) {
    ++counters_.no_resource;
    return short_answer(req, Response::RR);
  }
  Frame ack = fdl::sc();
  sig_.log(LogLevel::info, "Set_Slave_Add: station {} -> {}", s_.station, du[0]);
  s_.station = du[0];  // the chip answers at the new address from now on
  s_.no_add_change = du[3] != 0;
  sig_.emit(BlockEvent::Kind::ssa);
  ssa_accepted();
  return ack;
}

// The user handed new inputs over (New_Din_Buffer_Cmd): an SPC3 waiting after Cfg OK enters
// Data_Exchange now (a VPC3+ waiting for a Set_Ext_Prm's verdict goes on waiting).
void DpStateMachine::din_handed_over() {
  if (!waits_for_din()) return;
  s_.dx_deferred = false;
  s_.state = DpState::Data_Exchange;
  irq_.raise(irq::Go_Leave_Data_Exchange);
}

void DpStateMachine::ssa_accepted() {
  s_.ssa_free = false;
  irq_.raise(irq::New_SSA_Data);
}

// An SPC3 firmware that gives its Cfg OK but never reads New_Din_Buffer_Cmd keeps the chip in
// Wait_Cfg for good, and its master sees only "not ready". A user side hands its inputs over
// within its ISR for the Cfg verdict; a master still refused kDinWaitMs after that verdict (the
// time the built-in master gives a Prm check, docs/decisions.md) waits for a read that is not
// coming: the log says so, once per chip (docs/bring-up.md, section 7). Only the SPC3 waits so
// (waits_for_din): the VPC3+ and the DPC31 enter Data_Exchange at the Cfg OK itself.
void DpStateMachine::note_din_wait(const fdl::Frame& req, const char* answered) {
  if (din_wait_.said || !waits_for_din() || req.sa != s_.master_add ||
      sig_.clock->now - din_wait_.since < sig_.clock->cycles_for_us(kDinWaitMs * 1000))
    return;
  din_wait_.said = true;
  sig_.log(LogLevel::warn,
           "master {} is refused ({}): the SPC3 is still in Wait_Cfg at least {} ms after "
           "User_Cfg_Data_Okay, because the firmware has not read New_Din_Buffer_Cmd since; with "
           "R_Len_Din_Buf = {} it enters Data_Exchange only at that read (SPC3 p.31, modelled). "
           "Hand the inputs over once after User_Cfg_Data_Okay: write them into the U buffer, "
           "then read New_Din_Buffer_Cmd (docs/bring-up.md)",
           req.sa, answered, kDinWaitMs, regs_.cell(RegId::R_Len_Din_Buf));
}

std::optional<fdl::Frame> DpStateMachine::data_exchange(const fdl::Frame& req) {
  if (s_.state != DpState::Data_Exchange || req.sa != s_.master_add) {
    ++counters_.not_allowed;
    note_din_wait(req, "Data_Exchange answered RS");
    return short_answer(req, Response::RS);
  }
  sig_.emit(BlockEvent::Kind::dx);
  if (!user_watchdog_tick()) return std::nullopt;
  const std::size_t out_len = regs_.cell(RegId::R_Len_Dout_Buf);
  if (req.du.size() == out_len) {
    if (dx_out_wanted(req.du)) {
      regs_.write_buffer(buffers_.dout_d_ptr(), req.du);
      sig_.emit(BlockEvent::Kind::dout);
      buffers_.outputs_received(s_.sync_mode);
    }
  } else if (req.du.empty() && (regs_.mode0(fields::Mode_Reg0::Spec_Clear_Mode) || s_.failsafe)) {
    sig_.emit(BlockEvent::Kind::failsafe);
    buffers_.failsafe_clear();  // fail-safe: the master sends no outputs while in Clear
  } else {
    ++counters_.not_allowed;
    sig_.log(LogLevel::info, "Data_Exchange with {} output bytes, {} configured: RS", req.du.size(),
             out_len);
    return short_answer(req, Response::RS);
  }
  sig_.emit(BlockEvent::Kind::din);
  buffers_.inputs_due(s_.freeze_mode);
  const std::size_t in_len = answer_length(RegId::R_Len_Din_Buf);
  const Response code = buffers_.diag_flag() ? Response::DH : Response::DL;
  if (in_len == 0) return code == Response::DL ? fdl::sc() : short_answer(req, code);
  regs_.read_buffer(buffers_.din_d_ptr(), in_len, du_);
  return fdl::make_frame(req.sa, s_.station, fdl::make_response_fc(code), std::move(du_));
}

// VPC3+ Mode_Reg2 DX_Int_Mode = 0 (the default): "DX Interrupt only generated, if DOUT length not
// 0"; Mode_Reg3 DX_Int_Mode_2 = 1: "DX_Out interrupt is only generated, if received data is not
// equal to current data" (Profichip DpCfg.h). The current data are the newest outputs the ASIC
// holds: D while a Sync holds them, else N, else U. Without the interrupt the outputs are not
// passed on either: the user already has them (modelled).
bool DpStateMachine::dx_out_wanted(std::span<const std::uint8_t> outputs) {
  if (regs_.id() != Profile::vpc3plus) return true;
  if (outputs.empty() && (regs_.latch(RegId::Mode_Reg2) & fields::Mode_Reg2::DX_Int_Mode) == 0)
    return false;
  if ((regs_.latch(RegId::Mode_Reg3) & fields::Mode_Reg3::DX_Int_Mode_2) == 0) return true;
  regs_.read_buffer(buffers_.newest_dout_ptr(), outputs.size(), du_);
  return !std::equal(outputs.begin(), outputs.end(), du_.begin());
}

// Each Data_Exchange counts the user watchdog down; Res_User_WD reloads it. False: expired.
bool DpStateMachine::user_watchdog_tick() {
  std::uint16_t& m1 = regs_.latch(RegId::Mode_Reg1);
  if ((m1 & fields::Mode_Reg1::Res_User_WD) != 0) {
    m1 = static_cast<std::uint16_t>(m1 & ~fields::Mode_Reg1::Res_User_WD);
    s_.user_wd = regs_.cell16(*regs_.reg(RegId::R_User_WD_Value));
    s_.user_wd_armed = true;
    return true;
  }
  if (!s_.user_wd_armed) return true;
  if (s_.user_wd > 0) --s_.user_wd;
  if (s_.user_wd != 0) return true;
  sig_.log(LogLevel::info, "user watchdog expired: Leave_Master");
  sig_.emit(BlockEvent::Kind::leave_master);
  leave_master();
  return false;
}

void DpStateMachine::dp_control_expired() {
  leave_master();
  // DPC31 p.26: "The SSA_State_Machine is reset also when ... the watchdog has expired in the
  // mode 'DP_Control'": SAP55 takes a Set_Slave_Add again.
  if (regs_.id() == Profile::dpc31) s_.ssa_free = true;
}

void DpStateMachine::response_sent() {
  sap_list_.response_sent();
  if (!s_.diag_in_flight) return;
  s_.diag_in_flight = false;
  // Diag_Flag is cleared when "the relevant master" fetched (SPC3 p.32): the locking master, or
  // any master while none holds the lock. Another master's fetch leaves it as it is.
  const bool relevant =
      s_.master_add == pdu::SlaveDiag::kNoMaster || s_.diag_requester == s_.master_add;
  const bool flag = relevant ? buffers_.sent_diag_has_stat_diag() : buffers_.diag_flag();
  sig_.emit(BlockEvent::Kind::diag_end, flag ? 1 : 0);
  buffers_.diag_send_end(flag);
}

}  // namespace dpc31

namespace dpc31 {

void DpStateMachine::start() {
  s_ = State{};
  sap_list_.reset();
  s_.started = true;
  buffers_.end_clear();
  s_.station = regs_.cell(RegId::R_TS_Adr);
  s_.no_add_change = regs_.cell(RegId::R_Real_No_Add_Change) == 0xFF;
}

void DpStateMachine::leave_master() {
  if (!s_.started) return;
  const DpState was = s_.state;
  s_.state = DpState::Wait_Prm;
  s_.prm = Handshake{};
  s_.cfg = Handshake{};
  s_.ext_prm = false;
  s_.master_add = pdu::SlaveDiag::kNoMaster;  // unlocked: any master may parameterise us again
  s_.sync_mode = false;
  s_.freeze_mode = false;
  s_.user_wd_armed = false;
  s_.fcb_valid = false;
  s_.dx_deferred = false;
  watchdog_.master_left();
  buffers_.end_clear();
  sig_.log(LogLevel::info, "Leave_Master: DP state -> Wait_Prm");
  if (was == DpState::Data_Exchange) irq_.raise(irq::Go_Leave_Data_Exchange);
  buffers_.dout_clear();
}

}  // namespace dpc31
