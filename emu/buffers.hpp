// Buffer state machines (chip-facts §5): Dout and Din rotate three buffers through the states
// D (ASIC side), N (next), U (user) and F (free); Diag hands two buffers between user and ASIC.
// Buffer numbers are 1..3 (Dout_Buf_Ptr1..3), 0 = Nil, exactly as in the *_Buffer_SM bytes.
#pragma once

#include <cstdint>

namespace dpc31 {

struct BufferRing {
  std::uint8_t d = 1, n = 0, u = 2, f = 3;

  // F 7:6, U 5:4, N 3:2, D 1:0.
  [[nodiscard]] std::uint8_t sm() const {
    return static_cast<std::uint8_t>(f << 6 | u << 4 | n << 2 | d);
  }
  // The buffer that was in D goes to N; the previous N (never fetched) or else F becomes D.
  // One of N and F is Nil at any time, so no buffer is ever lost.
  void d_to_n() {
    const std::uint8_t old_n = n;
    n = d;
    if (old_n != 0) {
      d = old_n;
    } else {
      d = f;
      f = 0;
    }
  }
  // The buffer in N goes to U; the old U becomes free. No-op when N is Nil.
  bool n_to_u() {
    if (n == 0) return false;
    f = u;
    u = n;
    n = 0;
    return true;
  }
  // The user's U goes to N; the old N (never sent) or else F becomes the new U.
  void u_to_n() {
    const std::uint8_t old_n = n;
    n = u;
    if (old_n != 0) {
      u = old_n;
    } else {
      u = f;
      f = 0;
    }
  }
  // Before sending: N (new inputs) goes to D; the old D becomes free. No-op when N is Nil.
  bool n_to_d() {
    if (n == 0) return false;
    f = d;
    d = n;
    n = 0;
    return true;
  }
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
  void reset() { *this = BufferUnit{}; }
};

}  // namespace dpc31
