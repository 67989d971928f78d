#include "cpu51_module.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <sstream>

#include "dpc31/reg_ids.hpp"
#include "mcs51/ihex.hpp"
#include "textfile.hpp"
#include "vocabulary.hpp"
#include "whole_number.hpp"

namespace dpc31 {

std::string Cpu51Module::serial_text(bool c31, std::uint8_t data) {
  return fmt::format(
      "{} serial port: sent {:#04x}{}", c31 ? "C31" : "80C32", data,
      data >= 0x20 && data < 0x7F ? fmt::format(" '{}'", static_cast<char>(data)) : std::string());
}

namespace {

constexpr std::size_t kMaxHexBytes = 4u << 20;  // 64 KB of code is about 180 KB of HEX
// A map only names places: one larger than this is not read, and the run says so (its addresses
// unnamed) instead of stopping.
constexpr std::uintmax_t kMaxMapBytes = 4u << 20;

// A shipped scenario names its image beside it (traces/do4_80c32.scn: do4_80c32.ihx), but the
// build writes the image and a copy of the scenario to build/firmware/mcs51/ (docs/cpu.md): where
// this program is such a build's (build/bin/dpc31) and that directory holds an image of the
// missing one's name, the message points there; elsewhere (installed, Python) it says nothing more.
std::string built_image_hint(const std::string& hex) {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const std::filesystem::path built = exe.parent_path().parent_path() / "firmware" / "mcs51" /
                                      std::filesystem::path(hex).filename();
  if (!std::filesystem::is_regular_file(built, ec)) return {};
  return fmt::format(" (the build made {}: run the scenario's copy beside it, docs/cpu.md)",
                     built.string());
}

// SDCC's map: the code symbols are the lines "C:   0000203C  _do4_init   do4".
void read_map(const std::string& text, std::map<std::uint16_t, std::string>& out) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream l(line);
    std::string area, addr, name;
    if (!(l >> area >> addr >> name) || area != "C:" || name.size() < 2 || name[0] != '_') {
      continue;
    }
    unsigned long v = 0;
    try {
      v = std::stoul(addr, nullptr, 16);
    } catch (const std::exception&) {
      continue;
    }
    if (v <= 0xFFFF) out.emplace(static_cast<std::uint16_t>(v), name.substr(1));
  }
}

}  // namespace

std::string_view cpu_core(std::string_view word) {
  for (const std::string_view core : {std::string_view("80c32"), std::string_view("c31")}) {
    if (std::equal(word.begin(), word.end(), core.begin(), core.end(),
                   [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == b; }))
      return core;
  }
  return {};
}

std::string names_problem(const std::vector<std::string>& names, std::string_view what) {
  const auto word = [](const std::string& n) {
    const auto letter = [](char c) {
      return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
    };
    return !n.empty() && letter(n[0]) && std::all_of(n.begin(), n.end(), [&](char c) {
      return letter(c) || (c >= '0' && c <= '9');
    });
  };
  const std::string_view article = what.starts_with('i') ? "an" : "a";
  for (auto n = names.begin(); n != names.end(); ++n) {
    if (n->empty()) return fmt::format("an empty {} name", what);
    if (!word(*n)) {
      return fmt::format(
          "{} '{}': {} {} name is letters, digits and '_', not starting with a digit", what,
          shown(*n), article, what);
    }
    if (std::find(names.begin(), n, *n) != n) return fmt::format("{} '{}' named twice", what, *n);
  }
  return {};
}

std::string Cpu51Config::ports_problem() const { return names_problem(ports, "port"); }

const std::vector<std::string>& Cpu51Config::default_ports() {
  static const std::vector<std::string> names{"outputs", "modul_ok"};
  return names;
}

const std::vector<std::string>& Cpu51Config::latch_ports() const {
  static const std::vector<std::string> none;
  return c31 ? none : ports.empty() ? default_ports() : ports;
}

std::string Cpu51Config::latch_problem() const {
  if (latch + latch_ports().size() <= base || latch >= base + kCpu51Window) return {};
  return fmt::format("the chip's window covers the output latch at {:#06x}", latch);
}

std::string Cpu51Config::chip_problem(const ChipOptions& chip) const {
  if (c31) {
    return chip.irq_controller == IrqController::c31
               ? ""
               : "the C31 serves its own interrupt controller: irq-controller external contradicts "
                 "it";
  }
  if (chip.bus != BusMode::intel) {
    return "the 80C32 drives the chip in Intel mode (its multiplexed bus): not on the Motorola "
           "bus";
  }
  if (chip.irq_controller == IrqController::c31) {
    return "the 80C32 takes X/INT on INT0, which the C31's interrupt controller leaves inactive: "
           "its firmware would never be interrupted";
  }
  return {};
}

bool load_cpu51_image(const Cpu51Config& cfg, Cpu51Image& image, std::string& error) {
  std::string text;
  // The reader's reason names no file: the message is FILE: reason.
  if (!read_text_file(cfg.hex, kMaxHexBytes, "Intel HEX", text, error)) {
    std::error_code ec;
    const std::string hint =
        std::filesystem::exists(cfg.hex, ec) ? std::string() : built_image_hint(cfg.hex);
    error = fmt::format("{}: {}{}", cfg.hex, error, hint);
    return false;
  }
  mcs51::HexImage hex;
  std::string why;
  if (!mcs51::parse_ihex(text, hex, why)) {
    // parse_ihex says "line N: reason"; the message is FILE:N: reason.
    error = why.starts_with("line ") ? fmt::format("{}:{}", cfg.hex, why.substr(5))
                                     : fmt::format("{}: {}", cfg.hex, why);
    return false;
  }
  image.code = std::move(hex.bytes);
  image.used = std::move(hex.used);
  image.size = hex.size;
  if (cfg.c31 && std::find(image.used.begin() + (0x2000 - cfg.code), image.used.end(), true) !=
                     image.used.end()) {
    error = fmt::format("{}: the image does not fit the C31's code area ({:04X}h..1FFFh)", cfg.hex,
                        cfg.code);
    return false;
  }
  if (const std::string map = cpu51_map_path(cfg.hex); !map.empty()) {
    image.map_file = map;
    std::error_code ec;
    // A FIFO or a device (no size) is read_text_file's to refuse, with the descriptor it opens.
    if (const std::uintmax_t n = std::filesystem::file_size(map, ec); !ec && n > kMaxMapBytes) {
      image.map_too_large = true;
      return true;
    }
    std::string mtext;
    if (!read_text_file(map, kMaxMapBytes, "SDCC map", mtext, error)) {
      // A dangling link: "no such file" would contradict the listing that shows it.
      if (std::filesystem::is_symlink(map, ec) && !std::filesystem::exists(map, ec))
        error = "a symbolic link to a missing file";
      error = fmt::format("{}: {}", map, error);
      return false;
    }
    read_map(mtext, image.symbols);
  }
  return true;
}

std::string cpu51_map_path(const std::string& hex) {
  std::filesystem::path map(hex);
  map.replace_extension(".map");
  // Anything there is the map (a directory, a dangling link): its reader says why it cannot be
  // read, where skipping it would hide that the names are gone.
  std::error_code ec;
  return std::filesystem::symlink_status(map, ec).type() == std::filesystem::file_type::not_found
             ? std::string()
             : map.string();
}

std::string code_name(const Cpu51Image& image, std::uint16_t pc) {
  auto it = image.symbols.upper_bound(pc);
  if (it == image.symbols.begin()) return fmt::format("{:04X}h", pc);
  --it;
  return pc == it->first ? it->second : fmt::format("{}+0x{:x}", it->second, pc - it->first);
}

std::string symbols_text(const Cpu51Image& image) {
  if (image.map_file.empty()) return "";
  if (image.map_too_large) {
    return fmt::format(", {} not read (more than {} bytes): code addresses unnamed", image.map_file,
                       kMaxMapBytes);
  }
  if (image.symbols.empty()) {
    return fmt::format(", no code symbols in {} (no SDCC 'C:' line): code addresses unnamed",
                       image.map_file);
  }
  return fmt::format(", symbols from {}", image.map_file);
}

namespace {

// "4096" or "0x1000" within lo..hi.
bool parse_address(std::string_view s, std::uint32_t lo, std::uint32_t hi, std::uint32_t& v) {
  std::uint64_t n = 0;
  if (numbers::parse_whole(s, n) != std::errc{} || n < lo || n > hi) return false;
  v = static_cast<std::uint32_t>(n);
  return true;
}

}  // namespace

std::string apply_cpu51_choice(const Cpu51Choice& choice, ChipOptions& chip, Cpu51Config& cfg,
                               Cpu51Image& image) {
  const std::string_view spec = choice.cpu;
  const std::size_t colon = spec.find(':');
  const std::string_view core = cpu_core(spec.substr(0, colon));
  std::uint32_t hz = 24'000'000;
  if (core.empty() ||
      (colon != std::string_view::npos &&
       !parse_address(spec.substr(colon + 1), static_cast<std::uint32_t>(kCpuClock.min),
                      static_cast<std::uint32_t>(kCpuClock.max), hz))) {
    return fmt::format("--cpu '{}' must be 80c32[:HZ] or c31[:HZ] (HZ {}..{})", spec, kCpuClock.min,
                       kCpuClock.max);
  }
  cfg.hz = hz;
  cfg.hex = choice.firmware;
  cfg.c31 = core == "c31";
  std::uint32_t v = 0;
  if (cfg.c31) {
    if (chip.profile != Profile::dpc31) {
      return "--cpu c31 is for --profile dpc31: only the DPC31 has a C31 core";
    }
    if (choice.irq_controller == "external") {
      return "--cpu c31 serves the C31's interrupt controller: --irq-controller external "
             "contradicts it";
    }
    if (!choice.board_address.empty()) {
      return "--board-address is the 80C32 board's: the C31's XDATA is the chip's own space";
    }
    chip.irq_controller = IrqController::c31;
    if (!choice.code.empty()) {
      // The code area lies in the RAM's user area (docs/dpc31.md, "The C31").
      if (!parse_address(choice.code, kC31Code.min, kC31Code.max, v)) {
        return fmt::format("--code '{}' must be an address 0x08A0..0x1FFF (decimal or 0x hex)",
                           choice.code);
      }
      cfg.code = static_cast<std::uint16_t>(v);
    }
    if (!choice.ports.empty()) return "--ports is the 80C32 board's output latch: the C31 has none";
  } else {
    if (!choice.code.empty()) return "--code is the C31's (--cpu c31)";
    // The latch bytes from 4000h on, named as the scenario's `ports=` names them; none given:
    // Cpu51Config::default_ports(), as the scenario's.
    const std::string& ports = choice.ports;
    cfg.ports.clear();
    for (std::size_t at = 0, end = 0; !ports.empty() && end != std::string_view::npos;
         at = end + 1) {
      end = ports.find(',', at);
      cfg.ports.emplace_back(ports.substr(at, end == std::string_view::npos ? end : end - at));
    }
    if (const std::string why = cfg.ports_problem(); !why.empty())
      return fmt::format("--ports '{}': {}", shown(ports), why);
    if (!choice.board_address.empty()) {
      if (!parse_address(choice.board_address, 0, 0x10000 - kCpu51Window, v)) {
        return fmt::format(
            "--board-address '{}' must be an address 0..0xF000 (decimal or 0x hex): the "
            "chip's 4 KB window lies in XDATA",
            choice.board_address);
      }
      cfg.base = static_cast<std::uint16_t>(v);
    }
    if (const std::string why = cfg.latch_problem(); !why.empty()) {
      return fmt::format("--board-address {:#06x}: {}", cfg.base, why);
    }
  }
  if (const std::string why = cfg.chip_problem(chip); !why.empty()) {
    return fmt::format("--cpu {}: {}", core, why);
  }
  std::string why;
  if (!load_cpu51_image(cfg, image, why)) return why;
  return {};
}

Cpu51Module::Cpu51Module(Chip& chip, const Cpu51Config& cfg, const Cpu51Image& image,
                         std::uint8_t station_address)
    : cfg_(cfg),
      board_(cfg.c31 ? std::make_unique<Cpu51Board>(chip, cfg.hz, Cpu51Board::C31{cfg.code})
                     : std::make_unique<Cpu51Board>(chip, cfg.hz, cfg.base)),
      values_(cfg.latch_ports().size(), 0) {
  if (cfg.c31)
    board_->load_c31_code(image.code, image.used);  // fits: load_cpu51_image checked it
  else
    board_->cpu().load_code(0, image.code);
  board_->cpu().set_port_input(1, station_address);  // the address switch
  board_->on_ram_write = [this](std::uint16_t addr, std::uint8_t value, std::uint64_t cycle) {
    if (addr < cfg_.latch || addr >= cfg_.latch + values_.size()) return;
    const unsigned port = addr - cfg_.latch;
    values_[port] = value;
    writes_.push_back({cycle, port, value});
    if (on_port) on_port(cycle, port, value);
  };
  chip.on_irq_change([this, &chip](std::uint64_t cycle, bool active) {
    if (active) interrupts.emplace_back(cycle, chip.peek_reg(RegId::Int_Req_Reg));
  });
  // TI is set in machine cycle m (the core's cycle count after it): its end, in chip cycles.
  board_->cpu().on_serial_tx = [this](std::uint8_t data, bool, std::uint64_t machine_cycle) {
    if (on_serial) on_serial(board_->chip_cycle_of(machine_cycle * mcs51::clocks_per_cycle), data);
  };
}

std::int64_t Cpu51Module::port(const std::string& name) const {
  const std::vector<std::string>& names = cfg_.latch_ports();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return values_[i];
  }
  return -1;
}

std::string Cpu51Module::port_name(unsigned port) const {
  return cfg_.latch_ports()[port];  // on_ram_write records the named bytes only
}

}  // namespace dpc31
