// Buffer state machines (chip-facts §5): Dout and Din rotate three buffers through the states
// D (ASIC side), N (next), U (user) and F (free); Diag hands two buffers between user and ASIC.
// Buffer numbers are 1..3 (Dout_Buf_Ptr1..3), 0 = Nil, exactly as in the *_Buffer_SM bytes.
#pragma once

#include <cstdint>

#include "snapshot.hpp"

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

struct BufferUnit {
  BufferRing dout;
  BufferRing din;
  DiagPair diag;
  bool n_cleared = false;  // the buffer in N was cleared by the ASIC
  bool u_cleared = false;  // the buffer in U was cleared by the ASIC
  bool diag_flag = false;  // Status_Reg.Diag_Flag
  bool n_cl = false;       // dpc31: the clear buffer C is due at the next fetch
  bool d_fresh = false;    // D holds outputs not yet passed on (Sync mode holds them there)
  bool c_swap_pending = false;
  // dpc31: the current clear has been signalled (N_Cl, DX_Out); further Clear_Data and fail-safe
  // exchanges change nothing until real outputs arrive ("once per clear").
  bool in_clear = false;
  [[nodiscard]] bool dout_n_pending() const { return dout.n != 0 || n_cl; }
  // dpc31: Start and Leave_Master end a clear: no clear buffer due, the next Clear_Data counts.
  void end_clear() {
    n_cl = false;
    in_clear = false;
  }
  void reset() { *this = BufferUnit{}; }
};

void save_state(snap::Writer& w, const BufferUnit& s);
void load_state(snap::Reader& r, BufferUnit& s);

}  // namespace dpc31
