#pragma once

#include "core.hpp"
#include "dut.hpp"

namespace dpc31::cosim {

// The compared outputs of a chip's blocks (the live chip in session mode, or the C++ Dut).
Outputs block_outputs(const ChipCore& c, std::uint8_t rdata);

}  // namespace dpc31::cosim
