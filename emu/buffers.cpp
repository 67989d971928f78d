// Buffer state machine hooks: the *_Buffer_SM reads, the user's command reads
// (New_Din_Buffer_Cmd, Next_Dout_Buffer_Cmd, New_Diag_Buffer_Cmd) and the ASIC's side
// (outputs received, clear, inputs fetched, diag sent).
#include "core.hpp"

namespace dpc31 {

namespace {

constexpr std::uint8_t kStat_Diag = 0x02;  // diag buffer byte 0

std::uint16_t din_sm(const ChipCore& c) { return c.buffers.din.sm(); }
// dpc31: bit 7 is N_Cl and F (always the one buffer D, N, U leave) is not shown.
std::uint16_t dout_sm(const ChipCore& c) {
  if (c.prof->id != Profile::dpc31) return c.buffers.dout.sm();
  namespace f = fields::Dout_Buffer_SM;
  return static_cast<std::uint16_t>((c.buffers.n_cl ? f::N_Cl : 0) |
                                    (c.buffers.dout.sm() & (f::D | f::N | f::U)));
}
std::uint16_t diag_sm(const ChipCore& c) { return c.buffers.diag.sm(); }

// User: the filled U goes to N; the answer names the new U.
std::uint16_t new_din(BufferUnit& b) {
  b.din.u_to_n();
  return b.din.u;
}

// User: fetch the newest outputs (N -> U) if there are any. dpc31 with N_Cl: the clear buffer C
// (the user's substitute values) is exchanged with U instead.
std::uint16_t next_dout(BufferUnit& b) {
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
// comes back when the send ends (asic_diag_send_end).
std::uint16_t new_diag(BufferUnit& b, bool& changed) {
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

template <std::uint16_t (*Op)(BufferUnit&)>
std::uint16_t preview(const ChipCore& c) {
  BufferUnit copy = c.buffers;
  return Op(copy);
}

std::uint16_t new_diag_preview(const ChipCore& c) {
  BufferUnit copy = c.buffers;
  bool changed = false;
  return new_diag(copy, changed);
}

std::uint16_t new_diag_cmd(ChipCore& c) {
  bool changed = false;
  const std::uint16_t r = new_diag(c.buffers, changed);
  if (changed) c.raise(irq::Diag_Buffer_Changed);
  return r;
}

}  // namespace

void install_buffer_hooks(HookTable& h) {
  h[ChipCore::idx(RegId::Din_Buffer_SM)].read = din_sm;
  h[ChipCore::idx(RegId::Dout_Buffer_SM)].read = dout_sm;
  h[ChipCore::idx(RegId::Diag_Buffer_SM)].read = diag_sm;
  h[ChipCore::idx(RegId::New_Din_Buffer_Cmd)].read = preview<new_din>;
  h[ChipCore::idx(RegId::New_Din_Buffer_Cmd)].command = [](ChipCore& c) {
    const std::uint16_t r = new_din(c.buffers);
    c.din_handed_over();
    return r;
  };
  h[ChipCore::idx(RegId::Next_Dout_Buffer_Cmd)].read = preview<next_dout>;
  h[ChipCore::idx(RegId::Next_Dout_Buffer_Cmd)].command = [](ChipCore& c) {
    const std::uint16_t r = next_dout(c.buffers);
    if (c.buffers.c_swap_pending) {
      c.buffers.c_swap_pending = false;
      c.swap_cells(RegId::R_Dout_Buf_Ptr_C, ChipCore::dout_ptr(c.buffers.dout.u));
    }
    return r;
  };
  h[ChipCore::idx(RegId::New_Diag_Buffer_Cmd)].read = new_diag_preview;
  h[ChipCore::idx(RegId::New_Diag_Buffer_Cmd)].command = new_diag_cmd;
}

std::uint32_t ChipCore::buffer_addr(RegId ptr_cell) const {
  return static_cast<std::uint32_t>(cell(ptr_cell)) << segment_shift();
}

void ChipCore::dout_received() {
  buffers.dout.d_to_n();
  buffers.n_cl = false;  // newer real outputs win over a clear the user has not fetched yet
  buffers.n_cleared = false;
  buffers.d_fresh = false;
  raise(irq::DX_Out);
}

RegId ChipCore::dout_ptr(std::uint8_t buffer) {
  static constexpr RegId kPtr[] = {RegId::R_Dout_Buf_Ptr1, RegId::R_Dout_Buf_Ptr2,
                                   RegId::R_Dout_Buf_Ptr3};
  return kPtr[buffer - 1];
}

RegId ChipCore::din_ptr(std::uint8_t buffer) {
  static constexpr RegId kPtr[] = {RegId::R_Din_Buf_Ptr1, RegId::R_Din_Buf_Ptr2,
                                   RegId::R_Din_Buf_Ptr3};
  return kPtr[buffer - 1];
}

// Clear_Data and the fail-safe Data_Exchange without outputs. SPC3 / VPC3+: D is cleared and
// passed on. dpc31: D is left alone; N_Cl makes the next fetch hand over the C buffer.
void ChipCore::failsafe_clear() {
  if (prof->id != Profile::dpc31) {
    dout_clear();
    return;
  }
  // Once per clear: until real outputs arrive, a further clear changes nothing.
  if (buffers.in_clear) return;
  buffers.in_clear = true;
  buffers.n_cl = true;
  raise(irq::DX_Out);
}

void ChipCore::dout_clear() {
  clear_ram(buffer_addr(dout_ptr(buffers.dout.d)), cell(RegId::R_Len_Dout_Buf));
  buffers.dout.d_to_n();
  buffers.n_cleared = true;
  buffers.d_fresh = false;
  raise(irq::DX_Out);
}

std::uint8_t ChipCore::din_fetch() {
  buffers.din.n_to_d();
  return buffers.din.d;
}

void ChipCore::diag_send_begin() {
  for (DiagState& s : buffers.diag.buf) {
    if (s == DiagState::Asic) {
      s = DiagState::Asic_Send_Mode;
      return;
    }
  }
}

bool ChipCore::sent_diag_has_stat_diag() const {
  static constexpr RegId kPtr[] = {RegId::R_Diag_Buf_Ptr1, RegId::R_Diag_Buf_Ptr2};
  for (int k = 0; k < 2; ++k) {
    if (buffers.diag.buf[k] == DiagState::Asic_Send_Mode)
      return (mem[buffer_addr(kPtr[k])] & kStat_Diag) != 0;
  }
  return false;
}

// Diag_Flag stays set while the sent buffer says Stat_Diag.
void ChipCore::diag_send_end(bool stat_diag) {
  for (int k = 0; k < 2; ++k) {
    if (buffers.diag.buf[k] != DiagState::Asic_Send_Mode) continue;
    buffers.diag_flag = stat_diag;
    if (buffers.diag.buf[1 - k] == DiagState::Asic) {  // the user handed a newer one meanwhile
      buffers.diag.buf[k] = DiagState::User;
      raise(irq::Diag_Buffer_Changed);
    } else {
      buffers.diag.buf[k] = DiagState::Asic;
    }
    return;
  }
}

void ChipCore::outputs_received() {
  buffers.d_fresh = true;
  buffers.in_clear = false;            // the master has left Clear
  if (!dp.sync_mode) dout_received();  // in Sync mode D holds the data until the next Sync
}

void ChipCore::inputs_due() {
  if (!dp.freeze_mode) din_fetch();
}

}  // namespace dpc31

namespace dpc31 {

namespace {

template <typename Ar, typename S>
void ring_fields(Ar& ar, S& s) {
  static_assert(snap::member_count<BufferRing>() == 4, "a new member: add it here");
  ar.bounded(s.d, std::uint8_t{3});
  ar.bounded(s.n, std::uint8_t{3});
  ar.bounded(s.u, std::uint8_t{3});
  ar.bounded(s.f, std::uint8_t{3});
}

template <typename Ar, typename S>
void members(Ar& ar, S& s) {
  static_assert(snap::member_count<BufferUnit>() == 10, "a new member: add it here");
  static_assert(snap::member_count<DiagPair>() == 2, "a new member: add it here");
  ring_fields(ar, s.dout);
  ring_fields(ar, s.din);
  ar.bounded(s.diag.buf[0], DiagState::Asic_Send_Mode);
  ar.bounded(s.diag.buf[1], DiagState::Asic_Send_Mode);
  ar(s.n_cleared);
  ar(s.u_cleared);
  ar(s.diag_flag);
  ar(s.n_cl);
  ar(s.d_fresh);
  ar(s.c_swap_pending);
  ar(s.in_clear);
}

// D and U always hold a buffer, exactly one of N and F is Nil, no buffer is held twice: the
// pointer cells are indexed by these numbers.
bool valid_ring(const BufferRing& b) {
  const bool n_nil = b.n == 0;
  const bool f_nil = b.f == 0;
  const std::uint8_t third = n_nil ? b.f : b.n;
  return b.d != 0 && b.u != 0 && n_nil != f_nil && b.d != b.u && third != b.d && third != b.u;
}

}  // namespace

void save_state(snap::Writer& w, const BufferUnit& s) {
  w.section("BUFS");
  members(w, s);
}

void load_state(snap::Reader& r, BufferUnit& s) {
  r.section("BUFS");
  members(r, s);
  if (!valid_ring(s.dout) || !valid_ring(s.din)) r.fail("Dout or Din ring is not buffers 1..3");
}

}  // namespace dpc31
