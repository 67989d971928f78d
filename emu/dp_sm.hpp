// DP slave state machine (chip-facts §5.4, §6): Wait_Prm -> Wait_Cfg -> Data_Exchange, the
// services the ASIC answers by itself (Set_Prm, Chk_Cfg, Slave_Diag, Get_Cfg, Rd_Inp, Rd_Outp,
// Set_Slave_Add, Data_Exchange, FDL_Status) and the user's Prm / Cfg / SSA handshakes, whose
// OK / Not_OK reads answer 00 finished, 01 conflict, 11 not allowed.
#pragma once

#include <cstdint>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/dp.hpp"
#include "snapshot.hpp"

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
  bool ssa_free = true;            // SAP55 enabled (SSA buffer free)
  bool prm_fault = false;          // diag St1 Prm_Fault
  bool cfg_fault = false;          // diag St1 Cfg_Fault
  bool not_supported = false;      // diag St1 Not_Supported (reserved Global_Control bits, ...)
  std::uint8_t station = 0;        // own address: R_TS_Adr at Start, changed by Set_Slave_Add
  bool no_add_change = false;      // Real_No_Add_Change adopted from Set_Slave_Add
  std::uint8_t master_add = 0xFF;  // the master that locked us (FFh: not parameterised)
  std::uint8_t group_ident = 0;
  std::uint8_t min_tsdr = 0;  // from Set_Prm byte 3; 0 = MinTSDR_Val
  // The watchdog parameters of the Set_Prm the user is checking: DP_Control starts with them at
  // User_Prm_Data_Okay, not when the telegram arrives.
  bool prm_wd_on = false;
  std::uint8_t prm_wd_fact1 = 0;
  std::uint8_t prm_wd_fact2 = 0;
  bool prm_wd_1ms = false;
  // SPC3 with a Din buffer: Cfg OK given, Data_Exchange at the user's next New_Din_Buffer_Cmd.
  bool dx_on_new_din = false;
  std::uint8_t diag_requester = 0xFF;  // the master whose Slave_Diag answer is being sent
  bool sync_mode = false;
  bool freeze_mode = false;
  // User watchdog: armed by Res_User_WD, counts Data_Exchange telegrams down.
  bool user_wd_armed = false;
  std::uint16_t user_wd = 0;
  // FCB/FCV: a repeated request (same master, FCV = 1, same FCB) gets the previous answer again.
  bool fcb_valid = false;
  bool last_fcb = false;
  std::uint8_t last_master = 0xFF;
  std::vector<std::uint8_t> last_response;

  void reset() { *this = DpStateMachine{}; }
};

void save_state(snap::Writer& w, const DpStateMachine& s);
void load_state(snap::Reader& r, DpStateMachine& s);

}  // namespace dpc31
