// Buffer state machines: the *_Buffer_SM reads, the user's command reads (New_Din_Buffer_Cmd,
// Next_Dout_Buffer_Cmd, New_Diag_Buffer_Cmd) and the ASIC's side (outputs received, clear, inputs
// fetched, diag sent).
#include "buffers.hpp"

namespace dpc31 {

namespace {

constexpr std::uint8_t kStat_Diag = 0x02;  // diag buffer byte 0

using State = BufferUnit::State;

// User: the filled U goes to N; the answer names the new U.
std::uint16_t new_din(State& b) {
  b.din.u_to_n();
  return b.din.u;
}

// User: fetch the newest outputs (N -> U) if there are any. dpc31 with N_Cl: the clear buffer C
// (the user's substitute values) is exchanged with U instead.
std::uint16_t next_dout(State& b) {
  std::uint8_t r = 0;
  if (b.n_cl) {
    // The substitute values supersede outputs received before the Clear: N is freed unseen.
    b.n_cl = false;
    b.dout.drop_n();
    b.n_cleared = false;
    b.c_swap_pending = true;
    b.u_cleared = true;
    r = fields::Next_Dout_Buffer_Cmd::State_U_Buffer;
  } else if (b.dout.n_to_u()) {
    b.u_cleared = b.n_cleared;
    b.n_cleared = false;
    r = fields::Next_Dout_Buffer_Cmd::State_U_Buffer;
  }
  return static_cast<std::uint8_t>(
      r | (b.u_cleared ? fields::Next_Dout_Buffer_Cmd::U_Buffer_Cleared : 0) | b.dout.u);
}

// User: hand the prepared diag buffer to the ASIC. The ASIC's previous buffer comes back at
// once unless it is being sent right now; then the answer is 00 (both with the ASIC) and it
// comes back when the send ends (diag_send_end).
std::uint16_t new_diag(State& b, bool& changed) {
  changed = false;
  for (int k = 0; k < 2; ++k) {
    if (b.diag.buf[k] != DiagState::User) continue;
    DiagState& other = b.diag.buf[1 - k];
    b.diag.buf[k] = DiagState::Asic;
    b.diag_flag = true;
    if (other == DiagState::Asic) {
      other = DiagState::User;
      changed = true;
      return static_cast<std::uint16_t>(2 - k);  // 01 = buffer 1, 10 = buffer 2
    }
    return 0;
  }
  return 0;
}

}  // namespace

// New_Din_Buffer_Cmd is the DP state machine's (DpStateMachine::install_hooks).
void BufferUnit::install_hooks(HookTable& h) {
  auto at = [&h, this](RegId id) -> RegHooks& { return bind_hooks(h, id, *this); };
  at(RegId::Din_Buffer_SM).read = [](const void* b) -> std::uint16_t {
    return self<BufferUnit>(b).din_sm();
  };
  at(RegId::Dout_Buffer_SM).read = [](const void* b) -> std::uint16_t {
    return self<BufferUnit>(b).dout_sm();
  };
  at(RegId::Diag_Buffer_SM).read = [](const void* b) -> std::uint16_t {
    return self<BufferUnit>(b).diag_sm();
  };
  at(RegId::Next_Dout_Buffer_Cmd).read = [](const void* b) {
    return self<BufferUnit>(b).next_dout_preview();
  };
  at(RegId::Next_Dout_Buffer_Cmd).command = [](void* b) {
    return self<BufferUnit>(b).next_dout_cmd();
  };
  at(RegId::New_Diag_Buffer_Cmd).read = [](const void* b) {
    return self<BufferUnit>(b).new_diag_preview();
  };
  at(RegId::New_Diag_Buffer_Cmd).command = [](void* b) {
    return self<BufferUnit>(b).new_diag_cmd();
  };
}

std::uint8_t BufferUnit::dout_sm() const {
  if (regs_.id() != Profile::dpc31) return s_.dout.sm();
  namespace f = fields::Dout_Buffer_SM;
  return static_cast<std::uint8_t>((s_.n_cl ? f::N_Cl : 0) | (s_.dout.sm() & (f::D | f::N | f::U)));
}

std::uint16_t BufferUnit::new_din_cmd() { return new_din(s_); }

std::uint16_t BufferUnit::new_din_preview() const {
  State copy = s_;
  return new_din(copy);
}

std::uint16_t BufferUnit::next_dout_cmd() {
  const std::uint16_t r = next_dout(s_);
  if (s_.c_swap_pending) {
    s_.c_swap_pending = false;
    regs_.swap_cells(RegId::R_Dout_Buf_Ptr_C, dout_ptr(s_.dout.u));
  }
  return r;
}

std::uint16_t BufferUnit::next_dout_preview() const {
  State copy = s_;
  return next_dout(copy);
}

std::uint16_t BufferUnit::new_diag_cmd() {
  bool changed = false;
  const std::uint16_t r = new_diag(s_, changed);
  if (changed) irq_.raise(irq::Diag_Buffer_Changed);
  return r;
}

std::uint16_t BufferUnit::new_diag_preview() const {
  State copy = s_;
  bool changed = false;
  return new_diag(copy, changed);
}

void BufferUnit::dout_received() {
  s_.dout.d_to_n();
  s_.n_cl = false;  // newer real outputs win over a clear the user has not fetched yet
  s_.n_cleared = false;
  s_.d_fresh = false;
  irq_.raise(irq::DX_Out);
}

RegId BufferUnit::dout_ptr(std::uint8_t buffer) {
  static constexpr RegId kPtr[] = {RegId::R_Dout_Buf_Ptr1, RegId::R_Dout_Buf_Ptr2,
                                   RegId::R_Dout_Buf_Ptr3};
  return kPtr[buffer - 1];
}

RegId BufferUnit::din_ptr(std::uint8_t buffer) {
  static constexpr RegId kPtr[] = {RegId::R_Din_Buf_Ptr1, RegId::R_Din_Buf_Ptr2,
                                   RegId::R_Din_Buf_Ptr3};
  return kPtr[buffer - 1];
}

RegId BufferUnit::newest_dout_ptr() const {
  return dout_ptr(s_.d_fresh ? s_.dout.d : s_.dout.n != 0 ? s_.dout.n : s_.dout.u);
}

// Clear_Data and the fail-safe Data_Exchange without outputs. SPC3 / VPC3+: D is cleared and
// passed on. dpc31: D's memory is left alone ("not deleted and ... not changed"), but outputs a
// Sync holds there are older than the clear: no later Sync or Unsync hands them over. N_Cl makes
// the next fetch hand over the C buffer.
void BufferUnit::failsafe_clear() {
  if (regs_.id() != Profile::dpc31) {
    dout_clear();
    return;
  }
  s_.d_fresh = false;
  // Once per clear: until real outputs arrive, a further clear changes nothing.
  if (s_.in_clear) return;
  s_.in_clear = true;
  s_.n_cl = true;
  irq_.raise(irq::DX_Out);
}

void BufferUnit::dout_clear() {
  regs_.clear_buffer(dout_ptr(s_.dout.d), regs_.cell(RegId::R_Len_Dout_Buf));
  s_.dout.d_to_n();
  s_.n_cleared = true;
  s_.d_fresh = false;
  irq_.raise(irq::DX_Out);
}

std::uint8_t BufferUnit::din_fetch() {
  s_.din.n_to_d();
  return s_.din.d;
}

void BufferUnit::diag_send_begin() {
  for (DiagState& s : s_.diag.buf) {
    if (s == DiagState::Asic) {
      s = DiagState::Asic_Send_Mode;
      return;
    }
  }
}

int BufferUnit::sending_diag() const {
  const int k = s_.diag.buf[0] == DiagState::Asic ? 0 : 1;
  if (s_.diag.buf[k] == DiagState::Asic) return k;
  return s_.diag.buf[0] == DiagState::Asic_Send_Mode ? 0 : 1;
}

bool BufferUnit::sent_diag_has_stat_diag() const {
  static constexpr RegId kPtr[] = {RegId::R_Diag_Buf_Ptr1, RegId::R_Diag_Buf_Ptr2};
  for (int k = 0; k < 2; ++k) {
    if (s_.diag.buf[k] == DiagState::Asic_Send_Mode)
      return (regs_.mem(regs_.buffer_addr(kPtr[k])) & kStat_Diag) != 0;
  }
  return false;
}

// Diag_Flag stays set while the sent buffer says Stat_Diag, and when the user handed a newer
// buffer over meanwhile: the master fetched the old one, not the current one (SPC3 p.32: cleared
// when "the relevant master" fetched).
void BufferUnit::diag_send_end(bool stat_diag) {
  for (int k = 0; k < 2; ++k) {
    if (s_.diag.buf[k] != DiagState::Asic_Send_Mode) continue;
    if (s_.diag.buf[1 - k] == DiagState::Asic) {  // the user handed a newer one meanwhile
      s_.diag.buf[k] = DiagState::User;
      irq_.raise(irq::Diag_Buffer_Changed);
    } else {
      s_.diag_flag = stat_diag;
      s_.diag.buf[k] = DiagState::Asic;
    }
    return;
  }
}

void BufferUnit::outputs_received(bool sync_mode) {
  s_.d_fresh = true;
  s_.in_clear = false;              // the master has left Clear
  if (!sync_mode) dout_received();  // in Sync mode D holds the data until the next Sync
}

void BufferUnit::inputs_due(bool freeze_mode) {
  if (!freeze_mode) din_fetch();
}

}  // namespace dpc31
