// PulseView session setups (.pvs) for the logic-analyser form of a waveform (docs/waveforms.md,
// "PulseView"): opened with the VCD, they stack the UART decoder (8E1, the bus's rate) and ours,
// PROFIBUS DP (lib/sigrok/profibus_dp), on its RxD and TxD.
#pragma once

#include <cstdint>
#include <string>

namespace dpc31::wave {

// The setup's text, as PulseView 0.4.2 reads it (QSettings' INI format): the UART decoder at
// `baud` with even parity on the channels named `rx` and `tx` ("" = none) and PROFIBUS DP
// stacked on it.
std::string pulseview_session_text(std::uint32_t baud, const std::string& rx,
                                   const std::string& tx);

}  // namespace dpc31::wave
