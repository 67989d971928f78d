// A module whose firmware runs on an 80C32 beside the chip (docs/cpu.md, "DO4 on the 80C32"): an
// Intel HEX image (SDCC's or Keil's) and, when it lies beside it, SDCC's map, loaded as data; the
// board (Cpu51Board) with the chip's window at `base`, the address switch on port 1 and the
// module's output latch in XDATA at `latch` + port.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cpu51_board.hpp"
#include "cpu51_config.hpp"
#include "dpc31/chip.hpp"

namespace dpc31 {

// What was loaded: the code image and the map's code symbols (address -> name, without SDCC's
// leading underscore).
struct Cpu51Image {
  std::vector<std::uint8_t> code;
  std::vector<bool> used;  // the addresses the image gives
  std::uint32_t size = 0;
  std::map<std::uint16_t, std::string> symbols;
  std::string map_file;        // empty: no map beside the HEX file
  bool map_too_large = false;  // map_file not read (symbols_text says so)
};

// Reads cfg.hex (and FILE.map beside it, if there is one). False with one line in `error`:
// "FILE:LINE: reason" for a bad record, "FILE: reason" when it (or the map) cannot be read; a map
// over 4 MiB is skipped (map_too_large), not refused.
bool load_cpu51_image(const Cpu51Config& cfg, Cpu51Image& image, std::string& error);

// The SDCC map that load_cpu51_image reads beside the image `hex` (FILE.map), or "" if there is
// none: an input of the command too.
std::string cpu51_map_path(const std::string& hex);

// "dps_isr+0x1c" for a code address (hex alone without a symbol below it).
std::string code_name(const Cpu51Image& image, std::uint16_t pc);

// Where the names come from, for a run's first line: "" without a map, ", symbols from F.map",
// ", no code symbols in F.map ..." for a map that gives none (not SDCC's, or cut short), or ",
// F.map not read (more than N bytes) ...": the run goes on with addresses, and says why.
std::string symbols_text(const Cpu51Image& image);

// The CPU of the command lines (`dpc31 bridge`, `dpc31 serve`; docs/cpu.md, "Bring your own
// binary"): --cpu 80c32[:HZ] or c31[:HZ], --firmware FILE.ihx, --code A (the C31's code area),
// --board-address A (the chip's window in the 80C32's XDATA); the addresses decimal or 0x hex.
struct Cpu51Choice {
  std::string cpu;             // empty: no CPU
  std::string firmware;        // the Intel HEX image
  std::string code;            // empty: 1000h
  std::string board_address;   // empty: 8000h
  std::string ports;           // the 80C32 board's latch bytes by name; empty: DO4's
  std::string irq_controller;  // --irq-controller as given (empty: none)
};
// The choice of a command's options: `dpc31 bridge`'s and `dpc31 serve`'s have the same names
// (cpu, firmware, code, board_address, ports, chip.irq_controller).
template <class Options>
Cpu51Choice cpu51_choice_of(const Options& o) {
  return {.cpu = o.cpu,
          .firmware = o.firmware,
          .code = o.code,
          .board_address = o.board_address,
          .ports = o.ports,
          .irq_controller = o.chip.irq_controller};
}
// Fills `cfg` and reads the image. `c31` needs the dpc31 and makes
// `chip` serve the C31's interrupt controller, as the scenario header `cpu c31` does (an explicit
// --irq-controller external contradicts it). "" or the one-line complaint (FILE:LINE: reason for
// a bad HEX record).
std::string apply_cpu51_choice(const Cpu51Choice& choice, ChipOptions& chip, Cpu51Config& cfg,
                               Cpu51Image& image);

class Cpu51Module {
 public:
  Cpu51Module(Chip& chip, const Cpu51Config& cfg, const Cpu51Image& image,
              std::uint8_t station_address);

  Cpu51Board& board() { return *board_; }
  void run_until(std::uint64_t chip_cycle) { board_->run_until(chip_cycle); }

  struct PortWrite {
    std::uint64_t cycle;
    unsigned port;
    std::uint32_t value;
  };
  [[nodiscard]] const std::vector<PortWrite>& port_writes() const { return writes_; }
  // A port's current value (0 before the first write); -1 for an unknown name.
  [[nodiscard]] std::int64_t port(const std::string& name) const;
  [[nodiscard]] std::string port_name(unsigned port) const;
  // Int_Req_Reg whenever X/INT goes active (peeked: no bus time), for `expect irr_bit`.
  std::vector<std::pair<std::uint64_t, std::uint16_t>> interrupts;
  std::function<void(std::uint64_t cycle, unsigned port, std::uint32_t value)> on_port;
  // A character the serial port sent (SBUF, its TI set at `cycle`; docs/cpu.md, "Serial port").
  std::function<void(std::uint64_t cycle, std::uint8_t data)> on_serial;
  // How the walk and the bridge's log say one: "80C32 serial port: sent 0x41 'A'" (the printable
  // ASCII character quoted; "C31" for the DPC31's).
  [[nodiscard]] static std::string serial_text(bool c31, std::uint8_t data);
  // Forgets port_writes() and interrupts (the port values stay), as FirmwareHost's.
  void clear_history() {
    writes_.clear();
    interrupts.clear();
  }

 private:
  const Cpu51Config& cfg_;
  std::unique_ptr<Cpu51Board> board_;
  std::vector<PortWrite> writes_;
  std::vector<std::uint32_t> values_;
};

}  // namespace dpc31
