// A stimulus trace of `dpc31 cosim` (lockstep.hpp) read with its header, and the header lines a
// trace written for your RTL carries (cosim_trace.cpp).
#pragma once

#include <cstdint>
#include <string>

#include "cosim.hpp"
#include "lockstep.hpp"

namespace dpc31::cli {

// The header lines that name your RTL (none for the built-in models), as take_trace_header reads
// them: the real paths, so the trace replays from any directory.
std::string rtl_header(const CosimOptions& o);

// A stimulus trace file (lockstep.hpp), read like the emulator's own text files: missing,
// a directory, empty or cut off is one line "FILE: reason" / "FILE:LINE: reason"; its header
// sets the profile, bus, variant, mutant and RTL in `o`, and `seed` (0 where it names none).
bool read_stimulus(const std::string& path, cosim::Stimulus& s, CosimOptions& o,
                   std::uint64_t& seed, std::string& error);

}  // namespace dpc31::cli
