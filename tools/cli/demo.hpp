#pragma once

#include <cstdio>

#include "dpc31/chip.hpp"

namespace dpc31::cli {

// The scripted register-level session of `dpc31 demo`: start the chip, raise, mask, acknowledge
// and EOI interrupts, printing every access and every X/INT edge with its cycle.
int run_demo(ChipOptions opt, std::FILE* out);

}  // namespace dpc31::cli
