// A bus port that makes every block transfer byte by byte (BusPort's own block functions) on
// another bus port: firmware that copies buffers one access per byte, as the drivers' loops of
// Vpc3Read / Vpc3Write do. The reference the block transfers are tested against
// (tests/block_test.cpp) and the byte-by-byte firmware of benchmark row b' (bench/).
#pragma once

#include <cstdint>

#include "dpc31/bus_port.hpp"

namespace dpc31 {

class BytewiseBus final : public BusPort {
 public:
  explicit BytewiseBus(BusPort& b) : b_(b) {}
  std::uint8_t read(std::uint32_t addr) override { return b_.read(addr); }
  void write(std::uint32_t addr, std::uint8_t value) override { b_.write(addr, value); }
  void idle(std::uint64_t cycles) override { b_.idle(cycles); }
  [[nodiscard]] const Chip& chip() const override { return b_.chip(); }

 private:
  BusPort& b_;
};

}  // namespace dpc31
