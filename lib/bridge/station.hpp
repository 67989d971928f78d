// The stations of `dpc31 bridge` (docs/bridge.md, "Several slaves"): how each station's user side
// is made (one function for the single slave and for every --slave) and which sets of stations
// one line refuses.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "cpu.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/dpc31_firmware.h"
#include "firmware_host.hpp"
#include "responder.hpp"

namespace dpc31::bridge {

// The FIRMWARE of `--slave ADDR:responder`: the built-in user side instead of a firmware.
inline constexpr std::string_view kResponderName = "responder";

// One station of a segment (--slave ADDR:FIRMWARE[:PROFILE[:VARIANT]][:user_wd=1]...).
struct SlaveSpec {
  std::uint8_t address = 5;
  ChipOptions chip;
  const dpc31_firmware* firmware = nullptr;  // nullptr: the built-in user side (responder)
  // The built-in user side's user watchdog (`user_wd=1`, `user_wd_value=N`), as a segment
  // scenario's `station` gives it; a firmware serves its own.
  bool user_watchdog = false;
  std::uint16_t user_wd_value = ResponderConfig{}.user_wd_value;
};

// A station's user side once made: a firmware on the host CPU, or the built-in user side
// (`Responder`: ident 0C31h, Cfg 13 23, 4 bytes in and out, its inputs the outputs it last
// fetched: a loop-back a master can check its own data with).
struct UserSide {
  std::unique_ptr<FirmwareHost> firmware;
  std::unique_ptr<Responder> responder;
  Cpu::Program program;  // what the station's host CPU runs after the init
  [[nodiscard]] std::string_view name() const;
};

// Makes the user side of the chip of station `s` and runs its init (which configures and starts
// the chip): the one place a station's firmware is made. `on_segment`: one of the `--slave`s (the
// hang guard names its station).
UserSide make_user_side(Chip& chip, const SlaveSpec& s, bool on_segment);

// Why these stations cannot share one line ("" when they can): two at one address. Any number
// of stations may run firmware, the same or another: each FirmwareHost is an instance of its own
// (docs/firmware.md, "Instances"). One line, for the CLI's exit 2.
[[nodiscard]] std::string stations_problem(std::span<const SlaveSpec> slaves);

}  // namespace dpc31::bridge
