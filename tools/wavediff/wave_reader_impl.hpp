// Internal: the two reader factories behind open_wave().
#pragma once

#include "wave_reader.hpp"

namespace dpc31::wavediff {

std::unique_ptr<WaveReader> open_vcd(const std::string& path);
std::unique_ptr<WaveReader> open_fst(const std::string& path);

}  // namespace dpc31::wavediff
