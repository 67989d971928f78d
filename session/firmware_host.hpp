// A C firmware (dpc31/dpc31_firmware.h: a built-in one of firmware/, or a plug-in) on the host
// CPU of one chip: its init runs as main()'s set-up with direct bus accesses, then its main loop
// and its ISR on the host CPU (cpu.hpp). Every access goes through the C HAL's driver-shaped
// functions and costs its bus cycles; the board hooks (board.hpp) act on this host.
//
// Every FirmwareHost is an instance of its firmware of its own, so any number of stations run the
// same firmware or different ones at once: a built-in firmware (firmware.h) gets its instance
// memory here; a plug-in, which keeps its state in C globals as a driver on silicon does, runs in
// a private copy of its library (plugin_copy; docs/decisions.md). A station's firmware is
// `FirmwareHost host(find_firmware(spec)); host.init(bus, address);` then `host.program()` on its
// host CPU.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "board.hpp"
#include "cpu.hpp"
#include "dp_master.hpp"
#include "dpc31/dpc31_firmware.h"
#include "dpc31/hal.hpp"
#include "vocabulary.hpp"

struct dpc31_builtin;  // firmware.h

namespace dpc31 {

// The firmware did something the emulator cannot go on with (a reset of a started chip, a
// misuse of the C HAL such as a NULL buffer).
class FirmwareError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a door tells of an Intel HEX image given where a plug-in is named (docs/bring-up.md,
// section 3): how to run it where that door has a CPU, else that it cannot run one.
inline constexpr std::string_view kHexAtCpuDoor =
    "add --cpu 80c32 (in a scenario: cpu 80c32 firmware FILE)";
inline constexpr std::string_view kHexAtSegment =
    "a segment's station cannot run an 80C32 image (docs/segment.md); one chip runs it: `dpc31 "
    "run` with the header cpu 80c32 firmware FILE, or --cpu 80c32 at `dpc31 bridge` and `dpc31 "
    "serve`";
// The same for a command without a CPU (`dpc31 demo`, `dpc31 soak`).
[[nodiscard]] std::string hex_at_command(std::string_view command);

// A firmware by what the user wrote: a plug-in path (it contains '/' or ends in ".so") or the
// name of a built-in one (DO4, CNT2). Throws FirmwareError with one line when there is none or
// the plug-in fails its checks (load, symbol, ABI version, required fields); an Intel HEX image
// there is said so, with `hex_remedy` (this door's words).
const dpc31_firmware& find_firmware(const std::string& spec,
                                    std::string_view hex_remedy = kHexAtCpuDoor);
[[nodiscard]] bool is_plugin_path(const std::string& spec);
// The built-in names, "DO4, CNT2".
[[nodiscard]] std::string builtin_firmware_names();
// `base` with the firmware's GSD defaults a master is configured with: Ident_Number, Cfg,
// input/output lengths, User_Prm (what a scenario's `firmware` line sets).
[[nodiscard]] SlaveConfig with_gsd_defaults(const dpc31_firmware& fw, SlaveConfig base = {});
// Why a descriptor cannot run (empty: it can).
[[nodiscard]] std::string descriptor_problem(const dpc31_firmware* fw);
// A private copy of the plug-in `fw` belongs to (the library loaded again from the file that was
// checked, its globals its own) for one station, given back when the last owner lets go: a copy
// nobody holds is the next station's. A descriptor of no loaded plug-in (a built-in, one a
// program defines itself) is returned as it is. Throws FirmwareError when a copy cannot load.
[[nodiscard]] std::shared_ptr<const dpc31_firmware> plugin_copy(const dpc31_firmware& fw);

// The values hardware input `name` of `fw` takes, named by the input: a built-in firmware's
// (firmware.h, hw_ranges) are known before the run (a scenario's `hw` line is checked when it is
// parsed); a plug-in's only its hw_input knows (nullopt), as for a name `fw` has not.
[[nodiscard]] std::optional<ValueRange> builtin_hw_range(const dpc31_firmware& fw,
                                                         std::string_view name);

class FirmwareHost final : private board::Hooks {
 public:
  explicit FirmwareHost(const dpc31_firmware& fw);

  // The firmware's fault lines and the hang guard's name the station too ("station 5: firmware
  // DO4: ...", as on a segment, where several stations may run one firmware); before init.
  void name_station(std::uint8_t address);
  // main()'s set-up: the firmware configures and starts the chip.
  void init(BusPort& bus, std::uint8_t station_address);
  // The ISR and one pass of the main loop, as the host CPU runs them.
  void isr(BusPort& bus);
  void main_step(BusPort& bus);
  // What the host CPU runs after init: the ISR (if any), the main loop (if any), the board's
  // interrupt input. `after` (may be empty) runs after each ISR and main-loop pass.
  [[nodiscard]] Cpu::Program program(const Cpu::Isr& after = {});
  // A hardware input of the module (cnt2: "count1", "event2"): empty on success, else why not.
  std::string hw_input(const std::string& name, std::uint32_t value);

  struct PortWrite {
    std::uint64_t cycle;
    unsigned port;
    std::uint32_t value;
  };
  [[nodiscard]] const dpc31_firmware& firmware() const { return fw_; }
  // A built-in firmware's instance (its type per firmware.h: do4, cnt2), for tests and debuggers;
  // nullptr for a plug-in.
  [[nodiscard]] void* instance() const { return self_.get(); }
  [[nodiscard]] const std::vector<PortWrite>& port_writes() const { return writes_; }
  // port_writes() handed over and forgotten (a long run's memory stays flat).
  [[nodiscard]] std::vector<PortWrite> take_port_writes() { return std::exchange(writes_, {}); }
  // A port's current value (0 before the first write); -1 for an unknown name.
  [[nodiscard]] std::int64_t port(const std::string& name) const;
  [[nodiscard]] std::string port_name(unsigned port) const;
  [[nodiscard]] bool interrupts_enabled() const { return int_enabled_; }
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
  class Entered;  // the HAL, the board hooks and the bus of one call into the firmware
  class InitBus;  // init's bus: progress for the hang guard, interrupts served in its waits
  void reset_line(bool asserted) override;
  void int_enable(bool enabled) override;
  void wait_1ms() override;
  [[nodiscard]] const std::string& hang_name() const override { return name_; }

  const dpc31_firmware& fw_;
  // "firmware NAME", or "station N: firmware NAME": what its fault and hang lines begin with.
  std::string name_;
  const dpc31_builtin* builtin_;               // a built-in: its entry points on self_
  std::unique_ptr<std::max_align_t[]> self_;   // the built-in's instance
  std::shared_ptr<const dpc31_firmware> run_;  // else the plug-in copy this station runs
  hal::PortSink sink_;
  hal::ErrorSink errors_;        // a HAL misuse in the firmware's calls: FirmwareError
  hal::ErrorSink input_errors_;  // the same in hw_input, which runs with no chip selected
  std::vector<PortWrite> writes_;
  std::vector<std::uint32_t> values_;
  BusPort* bus_ = nullptr;   // the bus of the call into the firmware in progress
  bool int_enabled_ = true;  // the board's interrupt input: enabled when the firmware starts
};

}  // namespace dpc31
