// What firmware sees of the chip: its parallel bus (BusPort), plain synchronous access
// (DirectBus), and which bus the C HAL's access functions reach on the calling thread
// (hal::Selection, hal.hpp). The host CPU that runs firmware behind it is in session/cpu.hpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>

#include "dpc31/chip.hpp"

namespace dpc31 {

// What firmware sees: the parallel bus of the chip.
class BusPort {
 public:
  virtual ~BusPort() = default;
  virtual std::uint8_t read(std::uint32_t addr) = 0;
  virtual void write(std::uint32_t addr, std::uint8_t value) = 0;
  // Block transfers (Chip::write_block & co.): the same accesses as byte by byte, which is what
  // these defaults make.
  virtual void write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes);
  virtual void read_block(std::uint32_t addr, std::span<std::uint8_t> out);
  virtual void fill(std::uint32_t addr, std::uint8_t value, std::size_t len);
  virtual bool equal(std::uint32_t a, std::uint32_t b, std::size_t len);
  // The CPU spends `cycles` clocks without a bus access (a busy wait, a pass of a loop).
  virtual void idle(std::uint64_t cycles) = 0;
  [[nodiscard]] virtual const Chip& chip() const = 0;
  [[nodiscard]] std::uint64_t cycle() const { return chip().cycle(); }
};

// Synchronous access (init code, tests): each access simply takes its 4 clocks.
namespace hal {
// A port write of the firmware: (cycle, port, value).
using PortSink = std::function<void(std::uint64_t, unsigned, std::uint32_t)>;
// A host's answer to a misuse of the C HAL by the firmware it runs (a NULL buffer, no chip):
// it gets the message and throws (a firmware fault); if it returns, the process aborts.
using ErrorSink = std::function<void(const char* message)>;
// What the C HAL's access functions reach on the calling thread (hal.hpp, hal::Scope).
struct Selection {
  BusPort* bus = nullptr;
  const PortSink* ports = nullptr;
  // The chip core behind `bus` when `bus` is a C HAL handle's own DirectBus (dpc31_select):
  // Vpc3Read and Vpc3Write call it inline, the same access without the bus's calls.
  ChipCore* core = nullptr;
  // Takes the place of the process's error handler (dpc31_set_error_handler); nullptr: none.
  const ErrorSink* errors = nullptr;
};
// Installs `s` and returns the selection it replaces.
Selection exchange_selection(Selection s);
}  // namespace hal

class DirectBus final : public BusPort {
 public:
  explicit DirectBus(Chip& c) : chip_(c) {}
  std::uint8_t read(std::uint32_t addr) override { return chip_.read(addr); }
  void write(std::uint32_t addr, std::uint8_t value) override { chip_.write(addr, value); }
  void write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes) override {
    chip_.write_block(addr, bytes);
  }
  void read_block(std::uint32_t addr, std::span<std::uint8_t> out) override {
    chip_.read_block(addr, out);
  }
  void fill(std::uint32_t addr, std::uint8_t value, std::size_t len) override {
    chip_.fill(addr, value, len);
  }
  bool equal(std::uint32_t a, std::uint32_t b, std::size_t len) override {
    return chip_.equal(a, b, len);
  }
  void idle(std::uint64_t cycles) override { chip_.step(cycles); }
  [[nodiscard]] const Chip& chip() const override { return chip_; }

 private:
  Chip& chip_;
};

}  // namespace dpc31
