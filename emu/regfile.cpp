// Register file and RAM: the latches, the cells, the address decode and the ASIC's own RAM
// accesses. The CPU's accesses (hooks, QEMU's write rule) are the chip's bus side, emu/bus.cpp.
#include "regfile.hpp"

#include <algorithm>

namespace dpc31 {

RegisterFile::RegisterFile(const ProfileDesc& prof, BusMode bus, const Signals& sig)
    : prof_(&prof), bus_(bus), sig_(&sig) {
  const std::size_t size = std::size_t{1} << prof.address_bits;
  s_.mem.assign(size, 0);
  rd_map_.assign(size, kNoReg);
  wr_map_.assign(size, kNoReg);
  region_map_.assign(size, kNoReg);
  reg_index_.fill(kNoReg);
  for (std::size_t i = 0; i < prof.regs.size(); ++i) {
    const RegDesc& r = prof.regs[i];
    reg_index_[idx(r.id)] = static_cast<std::uint16_t>(i);
    for (int b = 0; b < r.bytes(); ++b) {
      if (r.read_addr >= 0)
        rd_map_[static_cast<std::size_t>(r.read_addr + b)] = static_cast<std::uint16_t>(i);
      if (r.write_addr >= 0)
        wr_map_[static_cast<std::size_t>(r.write_addr + b)] = static_cast<std::uint16_t>(i);
    }
  }
  for (std::size_t i = 0; i < prof.regions.size(); ++i) {
    for (std::uint32_t a = prof.regions[i].begin; a < prof.regions[i].end && a < size; ++a) {
      region_map_[a] = static_cast<std::uint16_t>(i);
    }
  }
  for (const RegionDesc& r : prof.regions) {  // in address order
    if (r.begin == registers_end_ && !r.ram) registers_end_ = r.end;
  }
}

void RegisterFile::reset() {
  s_.latch.fill(0);
  std::fill(s_.mem.begin(), s_.mem.end(), std::uint8_t{0});
  s_.large_ram = false;
  s_.ram_access_violation = false;
  for (const RegDesc& r : prof_->regs) {
    if (!r.has_reset) continue;
    if (r.kind == Kind::latch || (r.kind == Kind::derived && r.unimp != 0)) {
      latch(r.id) = r.reset;
    } else if (r.kind == Kind::cell) {
      set_cell16(r, r.reset);
    }
  }
}

std::uint16_t RegisterFile::cell16(const RegDesc& r) const {
  const auto base = static_cast<std::uint32_t>(r.read_addr);
  if (r.width == 8) return s_.mem[base];
  const std::uint8_t* p = r.placement(bus_);
  return static_cast<std::uint16_t>(s_.mem[base] << (8 * p[0]) | s_.mem[base + 1] << (8 * p[1]));
}

void RegisterFile::set_cell16(const RegDesc& r, std::uint16_t v) {
  const auto base = static_cast<std::uint32_t>(r.read_addr);
  if (r.width == 8) {
    s_.mem[base] = static_cast<std::uint8_t>(v);
    return;
  }
  const std::uint8_t* p = r.placement(bus_);
  s_.mem[base] = static_cast<std::uint8_t>(v >> (8 * p[0]));
  s_.mem[base + 1] = static_cast<std::uint8_t>(v >> (8 * p[1]));
}

std::uint8_t RegisterFile::cell(RegId id) const {
  return s_.mem[static_cast<std::uint32_t>(reg(id)->read_addr)];
}

void RegisterFile::set_cell(RegId id, std::uint8_t v) {
  s_.mem[static_cast<std::uint32_t>(reg(id)->read_addr)] = v;
}

void RegisterFile::swap_cells(RegId a, RegId b) {
  const std::uint8_t va = cell(a);
  set_cell(a, cell(b));
  set_cell(b, va);
}

std::uint32_t RegisterFile::segment_shift() const {
  return s_.large_ram ? prof_->segment_shift_large : prof_->segment_shift;
}

std::uint32_t RegisterFile::buffer_addr(RegId ptr_cell) const {
  return static_cast<std::uint32_t>(cell(ptr_cell)) << segment_shift();
}

void RegisterFile::note_buffer(RegId ptr_cell, std::uint32_t base, std::size_t len) {
  if (len != 0 && over_registers(base)) note_buffer(reg(ptr_cell)->name, cell(ptr_cell), base);
}

void RegisterFile::note_buffer(std::string_view name, std::uint8_t value, std::uint32_t base) {
  switch (over_registers_.note(base)) {
    case FoldedLog::Line::first:
      sig_->log(LogLevel::warn,
                "{} = {:02X}h puts its buffer at {:#05x}, over the registers (below {:#05x}): the "
                "chip keeps its bytes in RAM the CPU does not see there (modelled); further such "
                "uses are counted",
                name, value, base, registers_end_);
      break;
    case FoldedLog::Line::address:
      sig_->log(LogLevel::warn, "{} = {:02X}h puts its buffer at {:#05x}, over the registers", name,
                value, base);
      break;
    case FoldedLog::Line::count:
      sig_->log(LogLevel::warn,
                "{} uses of buffers over the registers so far (the latest: {} at {:#05x})",
                over_registers_.count, name, base);
      break;
    case FoldedLog::Line::none:
      break;
  }
}

void RegisterFile::clear_buffer(RegId ptr_cell, std::size_t len) {
  const std::uint32_t base = buffer_addr(ptr_cell);
  note_buffer(ptr_cell, base, len);
  for (std::size_t i = 0; i < len; ++i) ram_write(base + static_cast<std::uint32_t>(i), 0);
}

void RegisterFile::ram_write(std::uint32_t addr, std::uint8_t v) {
  bool violation = false;
  const std::uint32_t a = decode(addr, violation);
  if (violation) note_violation(addr, a);
  s_.mem[a] = v;
}

std::uint8_t RegisterFile::ram_read(std::uint32_t addr) {
  bool violation = false;
  const std::uint32_t a = decode(addr, violation);
  if (violation) note_violation(addr, a);
  return s_.mem[a];
}

void RegisterFile::write_buffer(RegId ptr_cell, std::span<const std::uint8_t> bytes) {
  const std::uint32_t base = buffer_addr(ptr_cell);
  note_buffer(ptr_cell, base, bytes.size());
  for (std::size_t i = 0; i < bytes.size(); ++i)
    ram_write(base + static_cast<std::uint32_t>(i), bytes[i]);
}

void RegisterFile::read_buffer(RegId ptr_cell, std::size_t len, std::vector<std::uint8_t>& out) {
  const std::uint32_t base = buffer_addr(ptr_cell);
  note_buffer(ptr_cell, base, len);
  out.resize(len);
  for (std::size_t i = 0; i < len; ++i) out[i] = ram_read(base + static_cast<std::uint32_t>(i));
}

void RegisterFile::note_violation(std::uint32_t addr, std::uint32_t mapped) {
  // One line while Status bit 3 stands (until the next Start): a block past the RAM is one
  // mistake, not a line per byte, and the first address is the one to look at.
  if (!s_.ram_access_violation) {
    sig_->log(LogLevel::warn,
              "RAM access violation at {:#05x}: beyond the {} bytes of RAM, wraps to {:#05x} "
              "(further ones are not logged until Start clears Status bit 3)",
              addr, s_.large_ram ? prof_->ram_size_large : prof_->ram_size, mapped);
  }
  s_.ram_access_violation = true;
  if (on_violation) on_violation();
}

}  // namespace dpc31
