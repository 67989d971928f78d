// One chip running an example firmware (firmware/, docs/firmware.md) on its host CPU against
// the built-in master, for the conformance tests of seeds 000 (DO4) and 001 (CNT2). The module
// is observed as its user sees it: its ports (the output terminals, the hold lines) with the
// cycle of each change, and its inputs on the wire.
#pragma once

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "../firmware_bench.hpp"
#include "conformance.hpp"
#include "dp_master.hpp"
#include "firmware_host.hpp"

namespace conformance {

// A slave parameterised as the module's GSD says (ident, Cfg, user parameters).
using firmware_bench::gsd_slave;

// A port write as (value, cycle).
using ValueAt = std::pair<std::uint32_t, std::uint64_t>;
using Writes = std::vector<ValueAt>;

struct FirmwareBench {
  FirmwareBench(dpc31::Profile p, const dpc31_firmware& fw, dpc31::SlaveConfig slave,
                std::uint32_t baud = 1'500'000)
      : chip({p, dpc31::BusMode::intel, 0}),
        host(fw),
        master(chip, dpc31::MasterConfig{2, baud, 100, 33}, slave) {
    chip.set_log_sink(nullptr);
    dpc31::DirectBus bus(chip);
    host.init(bus, slave.address);
    master.set_firmware([this](dpc31::BusPort& b) { host.isr(b); });
  }
  // Port writes of `port` after cycle `after` (exclusive).
  [[nodiscard]] std::vector<dpc31::FirmwareHost::PortWrite> writes(unsigned port,
                                                                   std::uint64_t after = 0) const {
    std::vector<dpc31::FirmwareHost::PortWrite> v;
    for (const auto& w : host.port_writes()) {
      if (w.port == port && w.cycle > after) v.push_back(w);
    }
    return v;
  }
  // The same as (value, cycle) pairs, for one EXPECT_EQ against the expected writes.
  [[nodiscard]] std::vector<ValueAt> values_at(unsigned port, std::uint64_t after = 0) const {
    std::vector<ValueAt> v;
    for (const auto& w : writes(port, after)) v.emplace_back(w.value, w.cycle);
    return v;
  }
  [[nodiscard]] std::optional<dpc31::FirmwareHost::PortWrite> last(unsigned port) const {
    const auto v = writes(port);
    if (v.empty()) return std::nullopt;
    return v.back();
  }
  [[nodiscard]] std::uint64_t acted(const dpc31::Exchange& ex) const {
    return ex.request_end - master.bit_cycles() + master.bit_cycles() / 2;
  }
  dpc31::Chip chip;
  dpc31::FirmwareHost host;
  dpc31::DpMaster master;
};

// docs/firmware.md "Output latency": the DX_Out ISR starts in the cycle the Data_Exchange is
// acted on (X/INT active at once, docs/timing.md) and writes a port after 4 + N bus accesses of
// 4 clocks (Int_Reg x2, Next_Dout_Buffer_Cmd, the U pointer cell, the N output bytes): DO4 has
// 2 output bytes, CNT2 6.
inline constexpr std::uint64_t kPortLatency = (4 + 2) * 4;
inline constexpr std::uint64_t kCnt2PortLatency = (4 + 6) * 4;

}  // namespace conformance
