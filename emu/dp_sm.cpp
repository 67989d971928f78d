// DP state machine: the services the ASIC answers by itself and the user's verdict on Set_Prm
// and Chk_Cfg (User_Prm/Cfg_Data_(Not_)Okay), SSA_Buffer_Free_Cmd. New_Prm_Data / New_Cfg_Data
// are cleared here, never through IAR. Decisions where the manuals are silent: docs/decisions.md.
#include <algorithm>
#include <utility>

#include "core.hpp"

namespace dpc31 {

namespace {

// Dis_Start_Control and Dis_Stop_Control, which Spec_User_Prm_Byte overwrites.
constexpr std::uint16_t kDis_Start_Stop =
    fields::Mode_Reg0::Dis_Start_Control | fields::Mode_Reg0::Dis_Stop_Control;

// Set_Prm Station_Status (DU byte 0) and Spec_User_Prm_Byte (DU byte 7, SPC3).
constexpr std::uint8_t kLock_Req = 0x80;
constexpr std::uint8_t kUnlock_Req = 0x40;
constexpr std::uint8_t kSync_Req = 0x20;
constexpr std::uint8_t kFreeze_Req = 0x10;
constexpr std::uint8_t kWD_On = 0x08;
constexpr std::uint8_t kStation_Status_Reserved = 0x07;
constexpr std::uint8_t kSpec_WD_Base_1ms = 0x04;
constexpr std::size_t kMinPrmLength = 7;
constexpr std::size_t kMaxBufferLength = 244;

// Diag buffer byte 0 as the user writes it.
constexpr std::uint8_t kDiag_Ext_Diag = 0x01;
constexpr std::uint8_t kDiag_Stat_Diag = 0x02;
constexpr std::uint8_t kDiag_Ext_Diag_Overflow = 0x04;
constexpr std::size_t kStandardDiagBytes = 6;

enum class Verdict { ok, not_ok };

template <Handshake DpStateMachine::*Which>
std::uint16_t handshake_preview(const ChipCore& c) {
  return (c.dp.*Which).preview();
}

void prm_done(ChipCore& c, Verdict v) {
  c.latch[ChipCore::idx(RegId::Int_Req_Reg)] &= static_cast<std::uint16_t>(~irq::New_Prm_Data);
  c.dp.prm_fault = v == Verdict::not_ok;
  if (v == Verdict::not_ok) {
    c.leave_master();
    return;
  }
  // The parameters are accepted: the DP watchdog runs with the new TWD from now on.
  c.watchdog_parameterise(c.dp.prm_wd_on, c.dp.prm_wd_fact1, c.dp.prm_wd_fact2, c.dp.prm_wd_1ms);
  if (c.dp.state == DpState::Wait_Prm) c.dp.state = DpState::Wait_Cfg;
}

// SPC3 p.31: "the transition to 'DATA_EX' takes place immediately, if no Din_buffer is present
// (R_Len_Din_Puf = 00H) ..." — otherwise (the sentence is cut off in every copy; modelled) at
// the user's next New_Din_Buffer_Cmd, so the first answer in Data_Exchange carries the user's
// inputs. VPC3+ and DPC31: at once.
void enter_data_exchange(ChipCore& c) {
  if (c.prof->id == Profile::spc3 && c.cell(RegId::R_Len_Din_Buf) != 0) {
    c.dp.dx_on_new_din = true;
    return;
  }
  c.dp.state = DpState::Data_Exchange;
  c.raise(irq::Go_Leave_Data_Exchange);
}

void cfg_done(ChipCore& c, Verdict v) {
  c.latch[ChipCore::idx(RegId::Int_Req_Reg)] &= static_cast<std::uint16_t>(~irq::New_Cfg_Data);
  c.dp.cfg_fault = v == Verdict::not_ok;
  if (v == Verdict::not_ok) {
    c.leave_master();
    return;
  }
  if ((c.latch[ChipCore::idx(RegId::Mode_Reg1)] & fields::Mode_Reg1::En_Change_Cfg_Buffer) != 0) {
    // Get_Cfg answers the new configuration from now on.
    c.swap_cells(RegId::R_Cfg_Buf_Ptr, RegId::R_Read_Cfg_Buf_Ptr);
  }
  if (c.dp.state == DpState::Wait_Cfg) enter_data_exchange(c);
}

template <Handshake DpStateMachine::*Which, void (*Done)(ChipCore&, Verdict), Verdict V,
          std::uint16_t Event>
std::uint16_t handshake_command(ChipCore& c) {
  bool done = false;
  const std::uint8_t r = (c.dp.*Which).answer(done);
  if (done) Done(c, V);
  // Nothing pending (a Leave_Master discarded the telegram before the user's verdict): the read
  // completes all the same and its event goes (docs/timing.md). Kept, it could never be cleared
  // (Int_Ack_Reg ignores it) and X/INT would stay active for good.
  if (r == kHandshakeNotAllowed) {
    c.latch[ChipCore::idx(RegId::Int_Req_Reg)] &= static_cast<std::uint16_t>(~Event);
  }
  return r;
}

using fdl::Frame;
using fdl::Response;

// The answer to a request with SAPs: DA/SA swapped, DSAP = the master's SSAP, SSAP = ours.
Frame sap_answer(const ChipCore& c, const Frame& req, Response code, std::vector<std::uint8_t> du) {
  Frame f = fdl::make_frame(req.sa, c.dp.station, fdl::make_response_fc(code), std::move(du),
                            req.ssap, req.dsap);
  return f;
}

Frame short_answer(const ChipCore& c, const Frame& req, Response code) {
  return fdl::make_frame(req.sa, c.dp.station, fdl::make_response_fc(code));
}

}  // namespace

void install_dp_sm_hooks(HookTable& h) {
  auto set = [&h](RegId id, auto read, auto command) {
    h[ChipCore::idx(id)].read = read;
    h[ChipCore::idx(id)].command = command;
  };
  set(RegId::User_Prm_Data_Okay, handshake_preview<&DpStateMachine::prm>,
      handshake_command<&DpStateMachine::prm, prm_done, Verdict::ok, irq::New_Prm_Data>);
  set(RegId::User_Prm_Data_Not_Okay, handshake_preview<&DpStateMachine::prm>,
      handshake_command<&DpStateMachine::prm, prm_done, Verdict::not_ok, irq::New_Prm_Data>);
  set(RegId::User_Cfg_Data_Okay, handshake_preview<&DpStateMachine::cfg>,
      handshake_command<&DpStateMachine::cfg, cfg_done, Verdict::ok, irq::New_Cfg_Data>);
  set(RegId::User_Cfg_Data_Not_Okay, handshake_preview<&DpStateMachine::cfg>,
      handshake_command<&DpStateMachine::cfg, cfg_done, Verdict::not_ok, irq::New_Cfg_Data>);
  set(
      RegId::SSA_Buffer_Free_Cmd, [](const ChipCore&) -> std::uint16_t { return 0; },
      [](ChipCore& c) -> std::uint16_t {
        c.dp.ssa_free = true;  // SAP55 accepts Set_Slave_Add again
        return 0;
      });
}

// --- buffers in RAM, as the ASIC sees them ---

void ChipCore::set_cell(RegId id, std::uint8_t v) {
  mem[static_cast<std::uint32_t>(reg(id)->read_addr)] = v;
}

void ChipCore::swap_cells(RegId a, RegId b) {
  const std::uint8_t va = cell(a);
  set_cell(a, cell(b));
  set_cell(b, va);
}

void ChipCore::write_buffer(RegId ptr_cell, std::span<const std::uint8_t> bytes) {
  const std::uint32_t base = buffer_addr(ptr_cell);
  for (std::size_t i = 0; i < bytes.size(); ++i)
    ram_write(base + static_cast<std::uint32_t>(i), bytes[i]);
}

std::vector<std::uint8_t> ChipCore::read_buffer(RegId ptr_cell, std::size_t len) {
  const std::uint32_t base = buffer_addr(ptr_cell);
  std::vector<std::uint8_t> out(len);
  for (std::size_t i = 0; i < len; ++i) out[i] = ram_read(base + static_cast<std::uint32_t>(i));
  return out;
}

// A telegram is received into the Aux buffer R_Aux_Buf_Sel selects and, when it fits, the Aux
// and target buffers are exchanged (pointer cells swap) and the length cell written.
bool ChipCore::receive_via_aux(std::uint16_t sel, RegId target_ptr, RegId len_cell,
                               std::span<const std::uint8_t> du) {
  const bool aux2 = (cell(RegId::R_Aux_Buf_Sel) & sel) != 0;
  const RegId aux_ptr = aux2 ? RegId::R_Aux_Buf_Ptr2 : RegId::R_Aux_Buf_Ptr1;
  const RegId aux_len = aux2 ? RegId::R_Len_Cntrl_Buf2 : RegId::R_Len_Cntrl_Buf1;
  if (du.size() > cell(aux_len)) return false;
  write_buffer(aux_ptr, du);
  swap_cells(aux_ptr, target_ptr);
  set_cell(len_cell, static_cast<std::uint8_t>(du.size()));
  return true;
}

// --- the services ---

std::optional<fdl::Frame> ChipCore::dp_service(const fdl::Frame& req) {
  ++counters.requests;
  const bool broadcast = req.da == fdl::kBroadcast;
  const fdl::Function fn = fdl::request_function(req.fc);
  const bool wants_answer =
      !broadcast && (fn == fdl::Function::SRD_low || fn == fdl::Function::SRD_high ||
                     fn == fdl::Function::FDL_Status);
  // FCB/FCV (EN 50170): the same FCB again from the same master means our answer was lost.
  if (!broadcast && fdl::fcv(req.fc) && dp.fcb_valid && dp.last_master == req.sa &&
      dp.last_fcb == fdl::fcb(req.fc) && !dp.last_response.empty()) {
    ++counters.repeated;
    // SPC3 p.36 (Rd_Outp: "If there is a buffer change from 'N' to 'U' ... between the first
    // call-up and the repetition, the new output data is sent during the repetition") and
    // DPC31 p.33 (Rd_Inp, U -> N -> D): these two answer from the buffers as they are now.
    if (req.dsap &&
        (fdl::sap_number(*req.dsap) == sap::Rd_Inp || fdl::sap_number(*req.dsap) == sap::Rd_Outp)) {
      std::optional<Frame> fresh = read_io(req);
      if (fresh) dp.last_response = fdl::encode(*fresh);
      return fresh;
    }
    return fdl::decode(dp.last_response).frame;
  }
  std::optional<Frame> answer;
  if (fn == fdl::Function::FDL_Status && !req.dsap) {
    answer = short_answer(*this, req, Response::OK);
  } else if (!mode0(fields::Mode_Reg0::DP_Mode)) {
    // Mode_Reg0: "DP_MODE: 0 = DP_Mode is disabled. 1 = DP_Mode is enabled. SPC3 sets up all
    // DP_SAPs." Without it no DP SAP (nor Data_Exchange's default SAP) exists: the chip is a
    // plain FDL station that answers FDL_Status and refuses the rest with RS (modelled).
    ++counters.unknown_sap;
    log(LogLevel::info, "request from {} with DP_Mode = 0: no DP SAP set up (RS)", req.sa);
    if (fn == fdl::Function::SRD_low || fn == fdl::Function::SRD_high)
      answer = short_answer(*this, req, Response::RS);
  } else if (fn != fdl::Function::SRD_low && fn != fdl::Function::SRD_high &&
             fn != fdl::Function::SDN_low && fn != fdl::Function::SDN_high) {
    ++counters.unsupported_function;
    log(LogLevel::info, "FC {:#04x} from {}: function not served by a DP slave", req.fc, req.sa);
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
          ++counters.no_resource;
          answer = short_answer(*this, req, Response::RR);
          break;
        }
        answer =
            sap_answer(*this, req, Response::DL,
                       read_buffer(RegId::R_Read_Cfg_Buf_Ptr, cell(RegId::R_Len_Read_Cfg_Data)));
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
      default:
        ++counters.unknown_sap;
        log(LogLevel::info, "DSAP {} from {}: not served (RS)", fdl::sap_number(*req.dsap), req.sa);
        answer = short_answer(*this, req, Response::RS);
        break;
    }
  }
  if (!wants_answer || !answer) return std::nullopt;
  dp.fcb_valid = fdl::fcv(req.fc);
  dp.last_fcb = fdl::fcb(req.fc);
  dp.last_master = req.sa;
  dp.last_response = fdl::encode(*answer);
  return answer;
}

std::optional<fdl::Frame> ChipCore::set_prm(const fdl::Frame& req) {
  const std::vector<std::uint8_t>& du = req.du;
  if (du.size() < kMinPrmLength || du.size() > kMaxBufferLength) {
    log(LogLevel::info, "Set_Prm with {} bytes: Prm_Fault", du.size());
    prm_fault();
    return fdl::sc();
  }
  const std::uint8_t status = du[0];
  if (dp.master_add != 0xFF && dp.master_add != req.sa) {
    // Locked by another master (its diag shows Master_Add): whatever the lock bits say, this
    // master never re-parameterises, unlocks or changes min TSDR.
    ++counters.not_allowed;
    log(LogLevel::info, "Set_Prm from master {} while locked by {}: ignored", req.sa,
        dp.master_add);
    return fdl::sc();
  }
  const bool check_reserved =
      prof->id != Profile::vpc3plus ||
      (latch[idx(RegId::Mode_Reg2)] & fields::Mode_Reg2::No_Check_Prm_Reserved) == 0;
  const std::uint16_t ident =
      static_cast<std::uint16_t>(cell(RegId::R_Ident_High) << 8 | cell(RegId::R_Ident_Low));
  const std::uint16_t asked = static_cast<std::uint16_t>(du[4] << 8 | du[5]);
  const char* fault = nullptr;
  if (asked != ident) fault = "Ident_Number differs";
  if (check_reserved && (status & kStation_Status_Reserved) != 0)
    fault = "reserved Station_Status bits";
  if ((status & kSync_Req) != 0 && !mode0(fields::Mode_Reg0::Sync_Supported))
    fault = "Sync_Req but Sync not supported";
  if ((status & kFreeze_Req) != 0 && !mode0(fields::Mode_Reg0::Freeze_Supported))
    fault = "Freeze_Req but Freeze not supported";
  const bool lock = (status & kLock_Req) != 0;
  const bool unlock = (status & kUnlock_Req) != 0;
  // Lock_Req = Unlock_Req = 0 and the unlock codes adopt no parameters: only the Ident_Number
  // check applies to them.
  if (!lock || unlock) fault = asked != ident ? "Ident_Number differs" : nullptr;
  if (fault != nullptr) {
    log(LogLevel::info, "Set_Prm from {}: {}: Prm_Fault", req.sa, fault);
    prm_fault();
    return fdl::sc();
  }
  // CP 5613/5614 DP Base manual p.198-199: 00 "The min TSDR is overwritten when parameters are
  // assigned. All other parameters remain unchanged." (0 keeps it, as for a lock: modelled)
  if (!lock && !unlock) {
    if (du[3] != 0) dp.min_tsdr = du[3];
    log(LogLevel::info, "Set_Prm from {} without Lock_Req / Unlock_Req: min TSDR only", req.sa);
    return fdl::sc();
  }
  // 01 and 11: "released for other masters": the slave leaves this master (Wait_Prm, Master_Add
  // FFh) and nobody is monitored any more.
  if (unlock) {
    log(LogLevel::info, "Set_Prm from {} with Unlock_Req: released for other masters", req.sa);
    if (dp.state != DpState::Wait_Prm || dp.prm.pending) {
      emit(BlockEvent::Kind::leave_master);
      leave_master();
    }
    dp.master_add = 0xFF;
    watchdog_release();
    return fdl::sc();
  }
  const bool aux2 = (cell(RegId::R_Aux_Buf_Sel) & fields::R_Aux_Buf_Sel::Set_Prm) != 0;
  if (du.size() > cell(aux2 ? RegId::R_Len_Cntrl_Buf2 : RegId::R_Len_Cntrl_Buf1)) {
    ++counters.no_resource;
    return short_answer(*this, req, Response::RR);
  }
  // A new parameterisation starts the DP state machine over (outputs to the safe state). One
  // that arrives while the user is still checking the previous one in Wait_Prm is a newer
  // telegram for the same check: the verdict read answers 01 (conflict).
  if (dp.state != DpState::Wait_Prm) {
    emit(BlockEvent::Kind::leave_master);
    leave_master();
  }
  // 10: "disabled for other masters, all parameters are adopted (exception: min TSDR = 0)";
  // "The Group_Ident is accepted only when the Lock_Req bit is set."
  dp.master_add = req.sa;
  dp.group_ident = du[6];
  if (du[3] != 0) dp.min_tsdr = du[3];
  if (mode0(fields::Mode_Reg0::DP_Mode) && du.size() > 7) {
    // Spec_User_Prm_Byte overwrites Dis_Start_Control / Dis_Stop_Control in DP mode.
    std::uint16_t& m0 = latch[idx(RegId::Mode_Reg0)];
    emit(BlockEvent::Kind::dis, du[7] & kDis_Start_Stop);
    m0 = static_cast<std::uint16_t>((m0 & ~kDis_Start_Stop) | (du[7] & kDis_Start_Stop));
  }
  const bool wd_1ms = prof->id == Profile::vpc3plus
                          ? mode0(fields::Mode_Reg0::WD_Base)
                          : du.size() > 7 && (du[7] & kSpec_WD_Base_1ms) != 0;
  // DP_Control starts with these only once the user accepts them (User_Prm_Data_Okay).
  dp.prm_wd_on = (status & kWD_On) != 0;
  dp.prm_wd_fact1 = du[1];
  dp.prm_wd_fact2 = du[2];
  dp.prm_wd_1ms = wd_1ms;
  receive_via_aux(fields::R_Aux_Buf_Sel::Set_Prm, RegId::R_Prm_Buf_Ptr, RegId::R_Len_Prm_Data, du);
  emit(BlockEvent::Kind::prm);
  prm_accepted();
  return fdl::sc();
}

// A Set_Prm that failed the ASIC's checks.
void ChipCore::prm_fault() {
  emit(BlockEvent::Kind::prm_fault);
  leave_master();
  dp.prm_fault = true;
}

// The Prm buffer holds a new, checked Set_Prm: the faults are reported no more, the user's turn.
void ChipCore::prm_accepted() {
  dp.prm_fault = dp.cfg_fault = dp.not_supported = false;
  dp.dx_on_new_din = false;  // the new parameters need their verdicts again
  dp.prm.arrived();
  raise(irq::New_Prm_Data);
}

// The Cfg buffer holds a new Chk_Cfg: leave Data_Exchange until the user has checked it.
void ChipCore::cfg_accepted() {
  if (dp.state == DpState::Data_Exchange) {
    dp.state = DpState::Wait_Cfg;
    raise(irq::Go_Leave_Data_Exchange);
  }
  dp.dx_on_new_din = false;  // the new configuration needs its verdict again
  dp.cfg.arrived();
  raise(irq::New_Cfg_Data);
}

std::optional<fdl::Frame> ChipCore::chk_cfg(const fdl::Frame& req) {
  // DPC31 p.28: "This service is accepted by DPS in any DP mode. If the Check_Config message does
  // not come from 'Master_Add' i.e., the locking master, DPS ignores this message."
  if (req.sa != dp.master_add) {
    ++counters.not_allowed;
    log(LogLevel::info, "Chk_Cfg from {}: not the locking master: ignored", req.sa);
    return fdl::sc();
  }
  if (req.du.empty() || req.du.size() > kMaxBufferLength ||
      !receive_via_aux(fields::R_Aux_Buf_Sel::Chk_Cfg, RegId::R_Cfg_Buf_Ptr, RegId::R_Len_Cfg_Data,
                       req.du)) {
    ++counters.no_resource;
    return short_answer(*this, req, Response::RR);
  }
  emit(BlockEvent::Kind::cfg);
  cfg_accepted();
  return fdl::sc();
}

// The six standard bytes are the ASIC's; the rest of the buffer is the user's.
std::optional<fdl::Frame> ChipCore::slave_diag(const fdl::Frame& req) {
  static constexpr RegId kPtr[] = {RegId::R_Diag_Buf_Ptr1, RegId::R_Diag_Buf_Ptr2};
  static constexpr RegId kLen[] = {RegId::R_Len_Diag_Buf1, RegId::R_Len_Diag_Buf2};
  int k = buffers.diag.buf[0] == DiagState::Asic ? 0 : 1;
  if (buffers.diag.buf[k] != DiagState::Asic)
    k = buffers.diag.buf[0] == DiagState::Asic_Send_Mode ? 0 : 1;
  const std::size_t len =
      std::clamp<std::size_t>(cell(kLen[k]), kStandardDiagBytes, kMaxBufferLength);
  std::vector<std::uint8_t> du = read_buffer(kPtr[k], len);
  const std::uint8_t user = du[0];
  du[0] = static_cast<std::uint8_t>((dp.state != DpState::Data_Exchange ? 0x02 : 0) |
                                    (dp.cfg_fault ? 0x04 : 0) | (user & kDiag_Ext_Diag ? 0x08 : 0) |
                                    (dp.not_supported ? 0x10 : 0) | (dp.prm_fault ? 0x40 : 0));
  du[1] = static_cast<std::uint8_t>(
      (dp.state == DpState::Wait_Prm ? 0x01 : 0) | (user & kDiag_Stat_Diag ? 0x02 : 0) | 0x04 |
      (timers.dp_wd_on ? 0x08 : 0) | (dp.freeze_mode ? 0x10 : 0) | (dp.sync_mode ? 0x20 : 0));
  du[2] = (user & kDiag_Ext_Diag_Overflow) != 0 ? 0x80 : 0x00;
  du[3] = dp.master_add;
  du[4] = cell(RegId::R_Ident_High);
  du[5] = cell(RegId::R_Ident_Low);
  emit(BlockEvent::Kind::diag_begin);
  diag_send_begin();
  diag_in_flight = true;
  dp.diag_requester = req.sa;
  return sap_answer(*this, req, Response::DL, std::move(du));
}

std::optional<fdl::Frame> ChipCore::read_io(const fdl::Frame& req) {
  if (dp.state != DpState::Data_Exchange) {
    ++counters.not_allowed;
    return short_answer(*this, req, Response::RS);
  }
  if (!req.du.empty()) {  // DPC31 p.33: request data length != 0: "no resource"
    ++counters.no_resource;
    return short_answer(*this, req, Response::RR);
  }
  if (fdl::sap_number(*req.dsap) == sap::Rd_Inp) {
    emit(BlockEvent::Kind::din);
    inputs_due();
    return sap_answer(*this, req, Response::DL,
                      read_buffer(din_ptr(buffers.din.d), cell(RegId::R_Len_Din_Buf)));
  }
  // Read_Outputs is served from the user's U buffer.
  return sap_answer(*this, req, Response::DL,
                    read_buffer(dout_ptr(buffers.dout.u), cell(RegId::R_Len_Dout_Buf)));
}

std::optional<fdl::Frame> ChipCore::set_slave_add(const fdl::Frame& req) {
  const std::vector<std::uint8_t>& du = req.du;
  const std::uint16_t ident =
      static_cast<std::uint16_t>(cell(RegId::R_Ident_High) << 8 | cell(RegId::R_Ident_Low));
  if (cell(RegId::R_SSA_Buf_Ptr) == 0 || dp.no_add_change ||
      cell(RegId::R_Real_No_Add_Change) == 0xFF || dp.state != DpState::Wait_Prm) {
    ++counters.not_allowed;  // SAP55 off, address frozen, or not in Wait_Prm
    return short_answer(*this, req, Response::RS);
  }
  if (!dp.ssa_free) {
    ++counters.no_resource;  // the user has not freed the SSA buffer yet
    return short_answer(*this, req, Response::RR);
  }
  if (du.size() < 4 || du.size() > kMaxBufferLength || du[0] > 125 ||
      static_cast<std::uint16_t>(du[1] << 8 | du[2]) != ident) {
    ++counters.not_allowed;
    log(LogLevel::info, "Set_Slave_Add from {}: bad address or Ident_Number: ignored", req.sa);
    return fdl::sc();
  }
  if (!receive_via_aux(fields::R_Aux_Buf_Sel::Set_Slave_Adr, RegId::R_SSA_Buf_Ptr,
                       RegId::R_Len_SSA_Data, du)) {
    ++counters.no_resource;
    return short_answer(*this, req, Response::RR);
  }
  Frame ack = fdl::sc();
  log(LogLevel::info, "Set_Slave_Add: station {} -> {}", dp.station, du[0]);
  dp.station = du[0];  // the chip answers at the new address from now on
  dp.no_add_change = du[3] != 0;
  emit(BlockEvent::Kind::ssa);
  ssa_accepted();
  return ack;
}

// The user handed new inputs over (New_Din_Buffer_Cmd): an SPC3 waiting after Cfg OK enters
// Data_Exchange now.
void ChipCore::din_handed_over() {
  if (!dp.dx_on_new_din || dp.state != DpState::Wait_Cfg) return;
  dp.dx_on_new_din = false;
  dp.state = DpState::Data_Exchange;
  raise(irq::Go_Leave_Data_Exchange);
}

void ChipCore::ssa_accepted() {
  dp.ssa_free = false;
  raise(irq::New_SSA_Data);
}

std::optional<fdl::Frame> ChipCore::data_exchange(const fdl::Frame& req) {
  if (dp.state != DpState::Data_Exchange || req.sa != dp.master_add) {
    ++counters.not_allowed;
    return short_answer(*this, req, Response::RS);
  }
  emit(BlockEvent::Kind::dx);
  if (!user_watchdog_tick()) return std::nullopt;
  const std::size_t out_len = cell(RegId::R_Len_Dout_Buf);
  if (req.du.size() == out_len) {
    if (dx_out_wanted(req.du)) {
      write_buffer(dout_ptr(buffers.dout.d), req.du);
      emit(BlockEvent::Kind::dout);
      outputs_received();
    }
  } else if (req.du.empty() && mode0(fields::Mode_Reg0::Spec_Clear_Mode)) {
    emit(BlockEvent::Kind::failsafe);
    failsafe_clear();  // fail-safe: the master sends no outputs while in Clear
  } else {
    ++counters.not_allowed;
    log(LogLevel::info, "Data_Exchange with {} output bytes, {} configured: RS", req.du.size(),
        out_len);
    return short_answer(*this, req, Response::RS);
  }
  emit(BlockEvent::Kind::din);
  inputs_due();
  const std::size_t in_len = cell(RegId::R_Len_Din_Buf);
  const Response code = buffers.diag_flag ? Response::DH : Response::DL;
  if (in_len == 0) return code == Response::DL ? fdl::sc() : short_answer(*this, req, code);
  return fdl::make_frame(req.sa, dp.station, fdl::make_response_fc(code),
                         read_buffer(din_ptr(buffers.din.d), in_len));
}

// VPC3+ Mode_Reg2 DX_Int_Mode = 0 (the default): "DX Interrupt only generated, if DOUT length not
// 0"; Mode_Reg3 DX_Int_Mode_2 = 1: "DX_Out interrupt is only generated, if received data is not
// equal to current data" (Profichip DpCfg.h). The current data are the newest outputs the ASIC
// holds: D while a Sync holds them, else N, else U. Without the interrupt the outputs are not
// passed on either: the user already has them (modelled).
bool ChipCore::dx_out_wanted(std::span<const std::uint8_t> outputs) {
  if (prof->id != Profile::vpc3plus) return true;
  if (outputs.empty() && (latch[idx(RegId::Mode_Reg2)] & fields::Mode_Reg2::DX_Int_Mode) == 0)
    return false;
  if ((latch[idx(RegId::Mode_Reg3)] & fields::Mode_Reg3::DX_Int_Mode_2) == 0) return true;
  const std::uint8_t current = buffers.d_fresh       ? buffers.dout.d
                               : buffers.dout.n != 0 ? buffers.dout.n
                                                     : buffers.dout.u;
  const std::vector<std::uint8_t> now = read_buffer(dout_ptr(current), outputs.size());
  return !std::equal(outputs.begin(), outputs.end(), now.begin());
}

// Each Data_Exchange counts the user watchdog down; Res_User_WD reloads it. False: expired.
bool ChipCore::user_watchdog_tick() {
  std::uint16_t& m1 = latch[idx(RegId::Mode_Reg1)];
  if ((m1 & fields::Mode_Reg1::Res_User_WD) != 0) {
    m1 = static_cast<std::uint16_t>(m1 & ~fields::Mode_Reg1::Res_User_WD);
    dp.user_wd = cell16(*reg(RegId::R_User_WD_Value));
    dp.user_wd_armed = true;
    return true;
  }
  if (!dp.user_wd_armed) return true;
  if (dp.user_wd > 0) --dp.user_wd;
  if (dp.user_wd != 0) return true;
  log(LogLevel::info, "user watchdog expired: Leave_Master");
  emit(BlockEvent::Kind::leave_master);
  leave_master();
  return false;
}

void ChipCore::dp_response_sent() {
  if (!diag_in_flight) return;
  diag_in_flight = false;
  // Diag_Flag is cleared when "the relevant master" fetched (SPC3 p.32): the locking master, or
  // any master while none holds the lock. Another master's fetch leaves it as it is.
  const bool relevant = dp.master_add == 0xFF || dp.diag_requester == dp.master_add;
  const bool flag = relevant ? sent_diag_has_stat_diag() : buffers.diag_flag;
  emit(BlockEvent::Kind::diag_end, flag ? 1 : 0);
  diag_send_end(flag);
}

}  // namespace dpc31

namespace dpc31 {

namespace {

template <typename Ar, typename S>
void handshake_fields(Ar& ar, S& s) {
  static_assert(snap::member_count<Handshake>() == 2, "a new member: add it here");
  ar(s.pending);
  ar(s.newer_arrived);
}

template <typename Ar, typename S>
void members(Ar& ar, S& s) {
  static_assert(snap::member_count<DpStateMachine>() == 26, "a new member: add it here");
  ar.bounded(s.state, DpState::Data_Exchange);
  handshake_fields(ar, s.prm);
  handshake_fields(ar, s.cfg);
  ar(s.ssa_free);
  ar(s.prm_fault);
  ar(s.cfg_fault);
  ar(s.not_supported);
  ar(s.station);
  ar(s.no_add_change);
  ar(s.master_add);
  ar(s.group_ident);
  ar(s.min_tsdr);
  ar(s.prm_wd_on);
  ar(s.prm_wd_fact1);
  ar(s.prm_wd_fact2);
  ar(s.prm_wd_1ms);
  ar(s.dx_on_new_din);
  ar(s.diag_requester);
  ar(s.sync_mode);
  ar(s.freeze_mode);
  ar(s.user_wd_armed);
  ar(s.user_wd);
  ar(s.fcb_valid);
  ar(s.last_fcb);
  ar(s.last_master);
  ar.byte_vector(s.last_response, fdl::kMaxFrameLength);
}

}  // namespace

void save_state(snap::Writer& w, const DpStateMachine& s) {
  w.section("DPSM");
  members(w, s);
}

void load_state(snap::Reader& r, DpStateMachine& s) {
  r.section("DPSM");
  members(r, s);
}

}  // namespace dpc31
