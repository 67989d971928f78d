// Chip-session mode: the full C++ chip runs a DP scenario (protocol engine, built-in master,
// firmware); its block events and the CPU's bus accesses are recorded per cycle and drive the
// RTL in lockstep with the C++ blocks; at the end the replayed blocks must also equal the live
// chip's own.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lockstep.hpp"

namespace dpc31::cosim {

struct Session {
  DutOptions options;
  std::vector<std::pair<std::uint64_t, Inputs>> events;  // stimulus index (= chip cycle - 1)
  std::uint64_t cycles = 0;                              // the session's length
  Outputs chip_final;                                    // the live chip's blocks at the end
  // The scenario's expects that failed ("FILE:LINE: expected X, got Y", as `dpc31 run` says).
  std::vector<std::string> scenario_failures;
  // The first cycle whose block events came in an order its inputs cannot carry (requests of one
  // InstQ_Wr write other than in the order User_Leave_Master, MAC_Stop, MAC_Start), else empty.
  std::string unreplayable;
};

// Records the chip's block events and bus accesses into `out` from its current cycle on, until
// end_recording, which also takes the chip's blocks as `out.chip_final`.
void begin_recording(Chip& chip, Session& out);
void end_recording(Chip& chip, Session& out);

// Loads and plays the scenario. False (with a one-line error) if it does not load, or if its
// firmware faults or hangs: at the scenario's `firmware` line in its init, then at the step it
// runs in ("FILE:LINE: KEYWORD", as `dpc31 run` names it).
bool record_session(const std::string& scenario_path, Session& out, std::string& error);

// The recorded block events and bus accesses as a stimulus of the session's length: run_lockstep
// over it meets the divergence run_session meets first, and shrink and the trace files take it.
Stimulus session_stimulus(const Session& s);

// Lockstep of C++ blocks and RTL over the recorded session, then the replay against the chip.
RunResult run_session(const Session& s, std::string_view mutant = "");

}  // namespace dpc31::cosim
