#include "cpu51_module.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "dpc31/reg_ids.hpp"
#include "mcs51/ihex.hpp"
#include "textfile.hpp"

namespace dpc31 {

namespace {

constexpr std::size_t kMaxHexBytes = 4u << 20;  // 64 KB of code is about 180 KB of HEX

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

bool load_cpu51_image(const Cpu51Config& cfg, Cpu51Image& image, std::string& error) {
  std::string text;
  if (!read_text_file(cfg.hex, kMaxHexBytes, "Intel HEX", text, error)) return false;
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
  std::filesystem::path map(cfg.hex);
  map.replace_extension(".map");
  std::error_code ec;
  if (std::filesystem::is_regular_file(map, ec)) {
    std::string mtext;
    if (!read_text_file(map.string(), kMaxHexBytes, "SDCC map", mtext, error)) return false;
    read_map(mtext, image.symbols);
    image.map_file = map.string();
  }
  return true;
}

std::string code_name(const Cpu51Image& image, std::uint16_t pc) {
  auto it = image.symbols.upper_bound(pc);
  if (it == image.symbols.begin()) return fmt::format("{:04X}h", pc);
  --it;
  return pc == it->first ? it->second : fmt::format("{}+0x{:x}", it->second, pc - it->first);
}

Cpu51Module::Cpu51Module(Chip& chip, const Cpu51Config& cfg, const Cpu51Image& image,
                         std::uint8_t station_address)
    : cfg_(cfg),
      board_(cfg.c31 ? std::make_unique<Cpu51Board>(chip, cfg.hz, Cpu51Board::C31{cfg.code})
                     : std::make_unique<Cpu51Board>(chip, cfg.hz, cfg.base)),
      values_(cfg.ports.size(), 0) {
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
}

std::int64_t Cpu51Module::port(const std::string& name) const {
  for (std::size_t i = 0; i < cfg_.ports.size(); ++i) {
    if (cfg_.ports[i] == name) return values_[i];
  }
  return -1;
}

std::string Cpu51Module::port_name(unsigned port) const {
  return port < cfg_.ports.size() ? cfg_.ports[port] : fmt::format("latch{}", port);
}

}  // namespace dpc31
