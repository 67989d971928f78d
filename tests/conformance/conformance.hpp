// Shared set-up of the conformance tests: a chip, the minimal user side (Responder) and the
// built-in master on RxD/TxD, with the bit time T = round(48 MHz / baud) of docs/timing.md.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "../../emu/dp_master.hpp"
#include "../../emu/responder.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/reg_ids.hpp"
#include "test_util.hpp"

namespace conformance {

using Bytes = std::vector<std::uint8_t>;

inline std::uint32_t T_of(std::uint32_t baud) {
  return static_cast<std::uint32_t>((48'000'000u + baud / 2) / baud);
}

// A DP slave on the wire: the chip, the user side and a class-1 master (address 2).
struct Bench {
  dpc31::Chip chip;
  dpc31::Responder user;
  dpc31::DpMaster master;

  explicit Bench(dpc31::Profile p, std::uint32_t baud = 1'500'000, dpc31::ResponderConfig rc = {},
                 dpc31::BusMode bus = dpc31::BusMode::intel, std::uint8_t master_address = 2)
      : chip({p, bus, 0}),
        user(rc),
        master(init(chip, user), dpc31::MasterConfig{master_address, baud, 100, 33},
               user_slave(rc)) {
    master.set_firmware([this](dpc31::BusPort& c) { user.isr(c); });
  }
  static dpc31::SlaveConfig user_slave(const dpc31::ResponderConfig& rc) { return rc.slave; }
  static dpc31::Chip& init(dpc31::Chip& c, dpc31::Responder& u) {
    c.set_log_sink(nullptr);
    if (u.inputs.empty()) u.inputs = {0xA1, 0xA2, 0xA3, 0xA4};
    dpc31::DirectBus bus(c);
    u.init(bus);
    return c;
  }
  [[nodiscard]] std::uint32_t T() const { return master.bit_cycles(); }
  // The cycle a request is acted on: the stop-bit sample of its last character (timing.md).
  [[nodiscard]] std::uint64_t acted(const dpc31::Exchange& ex) const {
    return ex.request_end - T() + T() / 2;
  }
};

inline Bytes wire(const std::optional<dpc31::fdl::Frame>& f) {
  return f ? dpc31::fdl::encode(*f) : Bytes{};
}

}  // namespace conformance
