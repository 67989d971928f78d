// The host CPU that runs firmware against the chip. Firmware is level-triggered on X/INT and
// makes ordinary bus accesses (4 clocks each); it runs on its own thread, but strictly one side
// at a time (a baton), so a run is deterministic. The bus side (the DP master) and the firmware
// interleave at the granularity of one bus access: an ISR never holds the bus side back.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <thread>

#include "dpc31/chip.hpp"

namespace dpc31 {

// What firmware sees: the parallel bus of the chip.
class BusPort {
 public:
  virtual ~BusPort() = default;
  virtual std::uint8_t read(std::uint32_t addr) = 0;
  virtual void write(std::uint32_t addr, std::uint8_t value) = 0;
  [[nodiscard]] virtual const Chip& chip() const = 0;
  [[nodiscard]] std::uint64_t cycle() const { return chip().cycle(); }
};

// Synchronous access (init code, tests): each access simply takes its 4 clocks.
class DirectBus final : public BusPort {
 public:
  explicit DirectBus(Chip& c) : chip_(c) {}
  std::uint8_t read(std::uint32_t addr) override { return chip_.read(addr); }
  void write(std::uint32_t addr, std::uint8_t value) override { chip_.write(addr, value); }
  [[nodiscard]] const Chip& chip() const override { return chip_; }

 private:
  Chip& chip_;
};

class Cpu final : public BusPort {
 public:
  using Isr = std::function<void(BusPort&)>;
  Cpu(Chip& chip, Isr isr);
  ~Cpu() override;
  Cpu(const Cpu&) = delete;
  Cpu& operator=(const Cpu&) = delete;

  // Bus side: advance the chip to `cycle`, running the ISR whenever X/INT is active. The last
  // firmware access may end up to 3 clocks after `cycle` (an access is never split). Returns
  // early when Chip::request_stop is pending (the caller clears it).
  void run_until(std::uint64_t cycle);

  // Firmware side (called from the ISR).
  std::uint8_t read(std::uint32_t addr) override;
  void write(std::uint32_t addr, std::uint8_t value) override;
  [[nodiscard]] const Chip& chip() const override { return chip_; }

 private:
  void body();
  void gate();              // firmware: wait for the bus side's grant before an access
  void hand_to_firmware();  // bus side: let the firmware run until it yields
  void hand_to_bus_side();  // firmware: give the baton back

  Chip& chip_;
  Isr isr_;
  // The baton: whoever does not hold it waits on it (C++20 atomic wait on a 32-bit value: a
  // futex, no mutex). in_isr_ and stop_ are written before the baton changes hands, read after.
  enum Turn : std::uint32_t { kBusSide, kFirmware };
  std::atomic<std::uint32_t> turn_{kBusSide};
  bool in_isr_ = false;
  bool stop_ = false;
  std::uint64_t limit_ = 0;
  std::thread thread_;
};

}  // namespace dpc31
