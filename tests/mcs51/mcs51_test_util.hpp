// A CPU with a program at 0000h, for the core's unit tests.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <vector>

#include "mcs51/cpu.hpp"

namespace mcs51::test {

inline Cpu with_code(std::initializer_list<std::uint8_t> code, std::uint16_t at = 0) {
  Cpu cpu;
  std::vector<std::uint8_t> bytes(code);
  cpu.load_code(at, bytes);
  cpu.set_pc(at);
  return cpu;
}

// Steps `n` instructions; the machine cycles they took.
inline unsigned steps(Cpu& cpu, unsigned n) {
  unsigned cycles = 0;
  for (unsigned i = 0; i < n; ++i) cycles += cpu.step().cycles;
  return cycles;
}

}  // namespace mcs51::test
