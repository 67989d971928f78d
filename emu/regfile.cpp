// Register file and RAM: address decode, QEMU's write/read rule over the per-bit policies of the
// description, and the side-effect-free debugger path. Behaviour of single registers lives in
// the hooks of their blocks (irq.cpp, mode.cpp, buffers.cpp, dp_sm.cpp).
#include <stdexcept>
#include <string>

#include "core.hpp"

namespace dpc31 {

namespace {

std::string field_names(const RegDesc& r, std::uint16_t mask) {
  std::string out;
  for (const FieldDesc& f : r.fields) {
    const auto fm = static_cast<std::uint16_t>(((1u << f.width) - 1u) << f.lsb);
    if ((fm & mask) == 0) continue;
    if (!out.empty()) out += ", ";
    out += f.name;
  }
  return out.empty() ? std::string("reserved") : out;
}

}  // namespace

ChipCore::ChipCore(const ChipOptions& opt)
    : prof(&profile_desc(opt.profile)),
      bus(opt.bus),
      variant(opt.variant),
      release(opt.variant ? static_cast<std::uint8_t>(*opt.variant) : prof->release),
      clock_hz(opt.clock_hz != 0 ? opt.clock_hz : chip_timing().clock_hz),
      engine(opt.engine),
      sink(stderr_sink()) {
  if (variant && prof->id != Profile::vpc3plus) {
    throw std::invalid_argument(
        fmt::format("a VPC3+ variant ({}) on the {} profile: only vpc3plus has variants",
                    vpc3_variant_name(*variant), prof->name));
  }
  const std::size_t size = std::size_t{1} << prof->address_bits;
  mem.assign(size, 0);
  rd_map.assign(size, kNoReg);
  wr_map.assign(size, kNoReg);
  region_map.assign(size, kNoReg);
  reg_index.fill(kNoReg);
  for (std::size_t i = 0; i < prof->regs.size(); ++i) {
    const RegDesc& r = prof->regs[i];
    reg_index[idx(r.id)] = static_cast<std::uint16_t>(i);
    for (int b = 0; b < r.bytes(); ++b) {
      if (r.read_addr >= 0)
        rd_map[static_cast<std::size_t>(r.read_addr + b)] = static_cast<std::uint16_t>(i);
      if (r.write_addr >= 0)
        wr_map[static_cast<std::size_t>(r.write_addr + b)] = static_cast<std::uint16_t>(i);
    }
  }
  for (std::size_t i = 0; i < prof->regions.size(); ++i) {
    for (std::uint32_t a = prof->regions[i].begin; a < prof->regions[i].end && a < size; ++a) {
      region_map[a] = static_cast<std::uint16_t>(i);
    }
  }
  install_irq_hooks(hooks);
  install_mode_hooks(hooks);
  install_buffer_hooks(hooks);
  install_dp_sm_hooks(hooks);
  // Every derived value the description promises must have a block that computes it.
  for (const RegDesc& r : prof->regs) {
    const RegHooks& h = hooks[idx(r.id)];
    const bool modelled = (r.mask() & ~r.rsvd & ~r.unimp) != 0;
    if (r.kind == Kind::derived && modelled && h.read == nullptr) {
      throw std::logic_error(fmt::format("{}: derived register without a read hook", r.name));
    }
    if (r.cmd != 0 && h.command == nullptr) {
      throw std::logic_error(fmt::format("{}: command register without a command hook", r.name));
    }
  }
  reset();
}

void ChipCore::reset() {
  reset_time();
  latch.fill(0);
  std::fill(mem.begin(), mem.end(), std::uint8_t{0});
  irq.reset();
  buffers.reset();
  dp.reset();
  timers.reset();
  mac.reset();
  rxd_pending.clear();
  rxd_level = true;
  mac_listen(0);  // listening at 12 Mbaud, for the offline count
  counters = FdlCounters{};
  diag_in_flight = false;
  baud_code = 0;
  started = false;
  ram_access_violation = false;
  large_ram = false;
  for (const RegDesc& r : prof->regs) {
    if (!r.has_reset) continue;
    if (r.kind == Kind::latch || (r.kind == Kind::derived && r.unimp != 0)) {
      latch[idx(r.id)] = r.reset;
    } else if (r.kind == Kind::cell) {
      set_cell16(r, r.reset);
    }
  }
  irq_line = irq_active();
}

const RegDesc* ChipCore::reg(RegId id) const {
  const std::uint16_t i = reg_index[idx(id)];
  return i == kNoReg ? nullptr : &prof->regs[i];
}

std::uint16_t ChipCore::cell16(const RegDesc& r) const {
  const auto base = static_cast<std::uint32_t>(r.read_addr);
  if (r.width == 8) return mem[base];
  const std::uint8_t* p = r.placement(bus);
  return static_cast<std::uint16_t>(mem[base] << (8 * p[0]) | mem[base + 1] << (8 * p[1]));
}

void ChipCore::set_cell16(const RegDesc& r, std::uint16_t v) {
  const auto base = static_cast<std::uint32_t>(r.read_addr);
  if (r.width == 8) {
    mem[base] = static_cast<std::uint8_t>(v);
    return;
  }
  const std::uint8_t* p = r.placement(bus);
  mem[base] = static_cast<std::uint8_t>(v >> (8 * p[0]));
  mem[base + 1] = static_cast<std::uint8_t>(v >> (8 * p[1]));
}

std::uint8_t ChipCore::cell(RegId id) const {
  return mem[static_cast<std::uint32_t>(reg(id)->read_addr)];
}

std::uint32_t ChipCore::segment_shift() const {
  return large_ram ? prof->segment_shift_large : prof->segment_shift;
}

void ChipCore::clear_ram(std::uint32_t begin, std::uint32_t len) {
  for (std::uint32_t i = 0; i < len; ++i) ram_write(begin + i, 0);
}

// The ASIC's own RAM accesses (buffers): the same address decode and violation as the bus.
void ChipCore::ram_write(std::uint32_t addr, std::uint8_t v) {
  bool violation = false;
  const std::uint32_t a = decode(addr, violation);
  if (violation) note_violation(addr, a);
  mem[a] = v;
}

std::uint8_t ChipCore::ram_read(std::uint32_t addr) {
  bool violation = false;
  const std::uint32_t a = decode(addr, violation);
  if (violation) note_violation(addr, a);
  return mem[a];
}

std::uint32_t ChipCore::decode(std::uint32_t addr, bool& violation) const {
  const std::uint32_t a = addr & ((1u << prof->address_bits) - 1u);
  violation = prof->violation_from != 0 && a >= prof->violation_from && !large_ram;
  return violation ? a - prof->violation_subtract : a;
}

void ChipCore::note_violation(std::uint32_t addr, std::uint32_t mapped) {
  log(LogLevel::warn,
      "RAM access violation at {:#05x}: beyond the {} bytes of RAM, wraps to {:#05x}", addr,
      large_ram ? prof->ram_size_large : prof->ram_size, mapped);
  ram_access_violation = true;
  if (started) go_offline();
}

std::uint16_t ChipCore::reg_value(RegId id) const {
  const RegDesc* r = reg(id);
  if (r == nullptr) return 0;
  const RegHooks& h = hooks[idx(id)];
  switch (r->kind) {
    case Kind::cell:
      return cell16(*r);
    case Kind::reserved:
      return 0;
    case Kind::port:
      return latch[idx(r->target)];
    case Kind::latch:
    case Kind::derived:
      break;
  }
  const std::uint16_t v = h.read != nullptr ? h.read(*this) : latch[idx(id)];
  return static_cast<std::uint16_t>(v & r->mask() & ~r->rsvd);
}

std::uint32_t ChipCore::begin_access(std::uint32_t addr, std::string_view what) {
  if ((addr >> prof->address_bits) != 0) [[unlikely]] {
    log(LogLevel::warn, "{} at {:#x}: beyond the {}-bit address bus, upper bits ignored", what,
        addr, prof->address_bits);
  }
  bool violation = false;
  const std::uint32_t a = decode(addr, violation);
  if (violation) [[unlikely]]
    note_violation(addr, a);
  return a;
}

std::uint8_t ChipCore::bus_read(std::uint32_t addr) {
  advance(prof->bus_access_cycles);
  emit(BlockEvent::Kind::read, static_cast<std::uint16_t>(addr));
  if (bus_observer) bus_observer(now, BusAccess{false, static_cast<std::uint16_t>(addr), 0});
  const std::uint8_t v = read_now(addr);
  state_observer(now);
  return v;
}

void ChipCore::bus_write(std::uint32_t addr, std::uint8_t value) {
  advance(prof->bus_access_cycles);
  emit(BlockEvent::Kind::write, static_cast<std::uint16_t>(addr), value);
  if (bus_observer) bus_observer(now, BusAccess{true, static_cast<std::uint16_t>(addr), value});
  write_now(addr, value);
  state_observer(now);
}

std::uint8_t ChipCore::read_now(std::uint32_t addr) {
  const std::uint32_t a = begin_access(addr, "read");
  const std::uint16_t i = rd_map[a];
  if (i == kNoReg) {
    const std::uint16_t region = region_map[a];
    if (region != kNoReg && prof->regions[region].ram) {
      if (prof->regions[region].reserved) {
        log(LogLevel::info, "read of {} at {:#06x}", prof->regions[region].name, a);
      }
      return mem[a];
    }
    log(LogLevel::warn, "read of unmapped address {:#06x} ({}): reads 00h", a,
        region != kNoReg ? prof->regions[region].name : std::string_view("no region"));
    return 0;
  }
  const RegDesc& r = prof->regs[i];
  const std::uint32_t offset = a - static_cast<std::uint32_t>(r.read_addr);
  switch (r.kind) {
    case Kind::cell:
      if (r.reserved) log(LogLevel::info, "read of reserved cell {} at {:#06x}", r.name, a);
      return mem[a];
    case Kind::reserved:
      log(LogLevel::warn, "read of reserved {} at {:#06x}: reads 00h", r.name, a);
      return 0;
    case Kind::port:  // ports have no read side
    case Kind::latch:
    case Kind::derived:
      break;
  }
  const RegHooks& h = hooks[idx(r.id)];
  std::uint16_t v = 0;
  if (h.command != nullptr) {
    v = h.command(*this);
    update_irq_line();
  } else {
    v = h.read != nullptr ? h.read(*this) : latch[idx(r.id)];  // reg_value for these kinds
  }
  v = static_cast<std::uint16_t>(v & r.mask() & ~r.rsvd);
  if (r.unimp != 0)
    log(LogLevel::info, "read of {}: behaviour not modelled, reads the stored value", r.name);
  return static_cast<std::uint8_t>(v >> (8 * r.placement(bus)[offset]));
}

void ChipCore::write_now(std::uint32_t addr, std::uint8_t value) {
  const std::uint32_t a = begin_access(addr, "write");
  const std::uint16_t i = wr_map[a];
  if (i == kNoReg) {
    const std::uint16_t region = region_map[a];
    if (region != kNoReg && prof->regions[region].ram) {
      if (prof->regions[region].reserved) {
        log(LogLevel::info, "write {:02X}h to {} at {:#06x}", value, prof->regions[region].name, a);
      }
      mem[a] = value;
      return;
    }
    log(LogLevel::warn, "write {:02X}h to unmapped address {:#06x} ({}): ignored", value, a,
        region != kNoReg ? prof->regions[region].name : std::string_view("no region"));
    return;
  }
  const RegDesc& r = prof->regs[i];
  switch (r.kind) {
    case Kind::cell:
      if (r.reserved)
        log(LogLevel::info, "write {:02X}h to reserved cell {} at {:#06x}", value, r.name, a);
      mem[a] = value;
      return;
    case Kind::reserved:
      log(LogLevel::warn, "write {:02X}h to reserved {} at {:#06x}: ignored", value, r.name, a);
      return;
    case Kind::derived:  // derived values have no write side
    case Kind::latch:
    case Kind::port:
      break;
  }
  write_reg(r, a - static_cast<std::uint32_t>(r.write_addr), value);
}

// QEMU's rule (anchors §2.3), per byte lane: storage bits take the written value, W1C / W1S bits
// act on the target, reserved / ignored / read-only bits keep their value.
void ChipCore::write_reg(const RegDesc& r, std::uint32_t offset, std::uint8_t value) {
  const unsigned shift = 8u * r.placement(bus)[offset];
  const auto lane = static_cast<std::uint16_t>(0xFFu << shift);
  const auto w = static_cast<std::uint16_t>(value << shift);
  const std::size_t t = idx(r.target);
  const std::uint16_t old = latch[t];
  const auto store = static_cast<std::uint16_t>((r.rw | r.wo | r.unimp) & lane);
  auto next = static_cast<std::uint16_t>((old & ~store) | (w & store));
  next = static_cast<std::uint16_t>(next & ~(w & r.w1c));
  next = static_cast<std::uint16_t>(next | (w & r.w1s));
  // QEMU's rule: a write that would change a reserved bit is a guest error. What the write would
  // make of a reserved bit follows the register's own action: a reset or acknowledge port would
  // clear it, a set port set it, storage take the written value. So FFh to Mode_Reg1_R or
  // Int_Ack_Reg, where the reserved target bits are 0 already, changes nothing and is no error.
  const auto would = static_cast<std::uint16_t>(r.w1c != 0 ? old & ~w : r.w1s != 0 ? old | w : w);
  const auto rsvd_change = static_cast<std::uint16_t>((would ^ old) & r.rsvd & lane);
  if (rsvd_change != 0) {
    log(LogLevel::warn, "{}: write would change reserved bits {:#06x}: ignored", r.name,
        rsvd_change);
  }
  if ((w & r.ign) != 0) {
    log(LogLevel::info, "{}: {} not changed by this register (bits {:#06x})", r.name,
        field_names(r, w & r.ign), w & r.ign);
  }
  if ((r.unimp & lane) != 0) log(LogLevel::info, "{}: stored, behaviour not modelled", r.name);
  const RegHooks& h = hooks[idx(r.id)];
  written_bits = w;
  if (h.pre_write != nullptr) next = h.pre_write(*this, old, next);
  latch[t] = next;
  if (h.post_write != nullptr) h.post_write(*this, old, next);
  latch[t] = static_cast<std::uint16_t>(latch[t] & ~r.pulse);
  update_irq_line();
}

std::uint8_t ChipCore::peek(std::uint32_t addr) const {
  bool violation = false;
  const std::uint32_t a = decode(addr, violation);
  const std::uint16_t i = rd_map[a];
  if (i == kNoReg) {
    const std::uint16_t region = region_map[a];
    return region != kNoReg && prof->regions[region].ram ? mem[a] : std::uint8_t{0};
  }
  const RegDesc& r = prof->regs[i];
  if (r.kind == Kind::cell) return mem[a];
  const std::uint16_t v = reg_value(r.id);
  return static_cast<std::uint8_t>(
      v >> (8 * r.placement(bus)[a - static_cast<std::uint32_t>(r.read_addr)]));
}

bool ChipCore::poke(std::uint32_t addr, std::uint8_t value) {
  bool violation = false;
  const std::uint32_t a = decode(addr, violation);
  const std::uint16_t i = rd_map[a];
  if (i == kNoReg) {
    const std::uint16_t region = region_map[a];
    if (region == kNoReg || !prof->regions[region].ram) return false;
    mem[a] = value;
    return true;
  }
  const RegDesc& r = prof->regs[i];
  if (r.kind == Kind::cell) {
    mem[a] = value;
    return true;
  }
  if (r.kind != Kind::latch) return false;
  const unsigned shift = 8u * r.placement(bus)[a - static_cast<std::uint32_t>(r.read_addr)];
  std::uint16_t& s = latch[idx(r.id)];
  s = static_cast<std::uint16_t>((s & ~(0xFFu << shift)) | (value << shift));
  update_irq_line();
  return true;
}

}  // namespace dpc31
