#pragma once

#include <cstdio>
#include <optional>
#include <string>

#include "dpc31/chip.hpp"

namespace dpc31::cli {

// `dpc31 demo`: a scripted register-level session (start the chip, raise, mask, acknowledge and
// EOI interrupts, every access and X/INT edge with its cycle), then a DP session with the DO4
// example firmware (or `firmware`: a built-in name or a plug-in path; "" is refused as unknown),
// its waveform and capture written to `out_dir`, or if that is empty (not given) to a new private
// directory TMPDIR/dpc31-demo-XXXXXX (mkdtemp), whose name it prints: the full VCD, a second VCD
// for logic-analyser tools (docs/waveforms.md) and the pcapng. `timescale` (none: the forms'
// defaults; "" is refused as any bad unit) is the unit of both waveforms.
int run_demo(ChipOptions opt, const std::string& out_dir,
             const std::optional<std::string>& firmware,
             const std::optional<std::string>& timescale, std::FILE* out);

}  // namespace dpc31::cli
