// DP slave state machine: the user's side of the Prm / Cfg / SSA handshakes (chip-facts §5.4,
// §6). The OK / Not_OK command reads answer 00 finished, 01 conflict, 11 not allowed.
#pragma once

#include <cstdint>

#include "dpc31/chip.hpp"

namespace dpc31 {

inline constexpr std::uint8_t kHandshakeFinished = 0x00;
inline constexpr std::uint8_t kHandshakeConflict = 0x01;
inline constexpr std::uint8_t kHandshakeNotAllowed = 0x03;

// One pending telegram awaiting the user's verdict (Set_Prm or Chk_Cfg).
struct Handshake {
  bool pending = false;        // a telegram is waiting for OK / Not_OK
  bool newer_arrived = false;  // another one came while the user was checking

  void arrived() {
    if (pending) newer_arrived = true;
    pending = true;
  }
  // The result of an OK / Not_OK read; `done` tells whether the handshake completed.
  std::uint8_t answer(bool& done) {
    done = false;
    if (!pending) return kHandshakeNotAllowed;
    if (newer_arrived) {
      newer_arrived = false;  // the user re-validates the newer buffer
      return kHandshakeConflict;
    }
    pending = false;
    done = true;
    return kHandshakeFinished;
  }
  [[nodiscard]] std::uint8_t preview() const {
    if (!pending) return kHandshakeNotAllowed;
    return newer_arrived ? kHandshakeConflict : kHandshakeFinished;
  }
};

struct DpStateMachine {
  DpState state = DpState::Wait_Prm;
  Handshake prm;
  Handshake cfg;
  bool ssa_free = true;    // SAP55 enabled (SSA buffer free)
  bool prm_fault = false;  // the user rejected Set_Prm (diag Prm_Fault)
  bool cfg_fault = false;  // the user rejected Chk_Cfg (diag Cfg_Fault)
  void reset() { *this = DpStateMachine{}; }
};

}  // namespace dpc31
