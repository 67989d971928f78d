// A C firmware (firmware/, firmware.h) on the host CPU of one chip: its init runs as main()
// with direct bus accesses, its ISR on the host CPU (a coroutine) whenever X/INT is active
// (cpu.hpp). Every access goes through the C HAL's driver-shaped functions and costs its bus
// cycles.
//
// The example firmwares keep their state in C globals, as on silicon: one FirmwareHost per
// firmware image is alive at a time in a process.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cpu.hpp"
#include "dpc31/hal.hpp"
#include "firmware.h"

namespace dpc31 {

class FirmwareHost {
 public:
  explicit FirmwareHost(const dpc31_firmware& fw);

  // main(): the firmware sets up and starts the chip.
  void init(BusPort& bus, std::uint8_t station_address);
  // The ISR, as the host CPU runs it (DpMaster::set_firmware, Cpu).
  void isr(BusPort& bus);
  // A hardware input of the module (cnt2: "count1", "event2"): empty on success, else why not.
  std::string hw_input(const std::string& name, std::uint32_t value);

  struct PortWrite {
    std::uint64_t cycle;
    unsigned port;
    std::uint32_t value;
  };
  [[nodiscard]] const dpc31_firmware& firmware() const { return fw_; }
  [[nodiscard]] const std::vector<PortWrite>& port_writes() const { return writes_; }
  // A port's current value (0 before the first write); -1 for an unknown name.
  [[nodiscard]] std::int64_t port(const std::string& name) const;
  [[nodiscard]] std::string port_name(unsigned port) const;
  // Int_Reg at every ISR entry (peeked: no bus time), for `expect irr_bit`.
  std::vector<std::pair<std::uint64_t, std::uint16_t>> interrupts;
  // Extra observer of port writes (the bridge's log, tests).
  hal::PortSink on_port;
  // Forgets port_writes() and interrupts (the port values stay): a long-running host (the
  // bridge) calls it so memory does not grow with time.
  void clear_history() {
    writes_.clear();
    interrupts.clear();
  }

 private:
  const dpc31_firmware& fw_;
  hal::PortSink sink_;
  std::vector<PortWrite> writes_;
  std::vector<std::uint32_t> values_;
};

}  // namespace dpc31
