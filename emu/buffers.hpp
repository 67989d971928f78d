// Buffer state machines (chip-facts §5): Dout and Din rotate three buffers through the states
// D (ASIC side), N (next), U (user) and F (free); Diag hands two buffers between user and ASIC.
// Buffer numbers are 1..3 (Dout_Buf_Ptr1..3), 0 = Nil, exactly as in the *_Buffer_SM bytes.
#pragma once

#include <cstdint>

#include "irq.hpp"
#include "reg_hooks.hpp"
#include "regfile.hpp"

namespace dpc31 {

struct BufferRing {
  std::uint8_t d = 1, n = 0, u = 2, f = 3;

  // F 7:6, U 5:4, N 3:2, D 1:0.
  [[nodiscard]] std::uint8_t sm() const {
    return static_cast<std::uint8_t>(f << 6 | u << 4 | n << 2 | d);
  }
  // A side (D for the ASIC, U for the user) hands its buffer to N. It gets back the previous N
  // if that was never taken, else the free buffer. One of N and F is Nil at any time, so no
  // buffer is ever lost.
  void hand_to_n(std::uint8_t& side) {
    const std::uint8_t old_n = n;
    n = side;
    if (old_n != 0) {
      side = old_n;
    } else {
      side = f;
      f = 0;
    }
  }
  // A side takes the buffer in N; its old buffer becomes free. No-op when N is Nil.
  bool take_from_n(std::uint8_t& side) {
    if (n == 0) return false;
    f = side;
    side = n;
    n = 0;
    return true;
  }
  // The buffer in N is freed unseen (dpc31: outputs older than a Clear).
  void drop_n() {
    if (n == 0) return;
    f = n;
    n = 0;
  }
  // Dout: the ASIC passes received outputs on, the user fetches them.
  void d_to_n() { hand_to_n(d); }
  bool n_to_u() { return take_from_n(u); }
  // Din: the user passes new inputs on, the ASIC takes them before sending.
  void u_to_n() { hand_to_n(u); }
  bool n_to_d() { return take_from_n(d); }
};

// Diag buffer states (Diag_Buffer_SM fields).
enum class DiagState : std::uint8_t { Nil = 0, User = 1, Asic = 2, Asic_Send_Mode = 3 };

struct DiagPair {
  DiagState buf[2] = {DiagState::User, DiagState::Asic};
  [[nodiscard]] std::uint8_t sm() const {
    return static_cast<std::uint8_t>(static_cast<unsigned>(buf[1]) << 2 |
                                     static_cast<unsigned>(buf[0]));
  }
};

class BufferUnit {
 public:
  struct State {
    BufferRing dout;
    BufferRing din;
    DiagPair diag;
    bool n_cleared = false;  // the buffer in N was cleared by the ASIC
    bool u_cleared = false;  // the buffer in U was cleared by the ASIC
    bool diag_flag = false;  // Status_Reg.Diag_Flag
    bool n_cl = false;       // dpc31: the clear buffer C is due at the next fetch
    bool d_fresh = false;    // D holds outputs not yet passed on (Sync mode holds them there)
    bool c_swap_pending = false;
    // dpc31: the current clear has been signalled (N_Cl, DX_Out); further Clear_Data and
    // fail-safe exchanges change nothing until real outputs arrive ("once per clear").
    bool in_clear = false;
  };

  BufferUnit(RegisterFile& regs, InterruptController& irq) : regs_(regs), irq_(irq) {}
  void reset() { s_ = State{}; }
  // Binds the hooks of the registers this block owns (reg_hooks.hpp).
  void install_hooks(HookTable& h);

  // The *_Buffer_SM bytes.
  [[nodiscard]] std::uint8_t din_sm() const { return s_.din.sm(); }
  [[nodiscard]] std::uint8_t dout_sm() const;  // dpc31: N_Cl in bit 7, F not shown
  [[nodiscard]] std::uint8_t diag_sm() const { return s_.diag.sm(); }
  [[nodiscard]] std::uint8_t dout_ring_sm() const { return s_.dout.sm(); }  // with F, as probed

  // The user's command reads: perform (cmd) or tell what they would answer (preview).
  std::uint16_t new_din_cmd();
  [[nodiscard]] std::uint16_t new_din_preview() const;
  std::uint16_t next_dout_cmd();
  [[nodiscard]] std::uint16_t next_dout_preview() const;
  std::uint16_t new_diag_cmd();
  [[nodiscard]] std::uint16_t new_diag_preview() const;

  // The ASIC's side.
  void dout_received();                   // D -> N, DX_Out
  void dout_clear();                      // clear D, D -> N, DX_Out
  void failsafe_clear();                  // Clear_Data / fail-safe exchange (per profile)
  void outputs_received(bool sync_mode);  // Data_Exchange wrote the outputs into D
  void inputs_due(bool freeze_mode);      // about to send inputs
  std::uint8_t din_fetch();               // N -> D if new; the D buffer
  void diag_send_begin();
  void diag_send_end(bool stat_diag);
  [[nodiscard]] bool sent_diag_has_stat_diag() const;
  [[nodiscard]] bool diag_flag() const { return s_.diag_flag; }
  [[nodiscard]] bool d_fresh() const { return s_.d_fresh; }
  // dpc31: Start and Leave_Master end a clear: no clear buffer due, the next Clear_Data counts.
  void end_clear() {
    s_.n_cl = false;
    s_.in_clear = false;
  }
  // The RAM pointer cells of the buffers the DP services answer from.
  [[nodiscard]] RegId din_d_ptr() const { return din_ptr(s_.din.d); }
  [[nodiscard]] RegId dout_u_ptr() const { return dout_ptr(s_.dout.u); }
  [[nodiscard]] RegId dout_d_ptr() const { return dout_ptr(s_.dout.d); }
  // The newest outputs the ASIC holds: D while a Sync holds them, else N, else U.
  [[nodiscard]] RegId newest_dout_ptr() const;
  // The diag buffer the ASIC sends (its pointer and length cells).
  [[nodiscard]] int sending_diag() const;
  [[nodiscard]] static RegId dout_ptr(std::uint8_t buffer);  // 1..3
  [[nodiscard]] static RegId din_ptr(std::uint8_t buffer);

 private:
  friend struct BlockAccess;
  RegisterFile& regs_;
  InterruptController& irq_;
  State s_;
};

}  // namespace dpc31
