// The chip's bus side: the CPU's accesses through the address decode of the register file, the
// registers' hooks (installed by each block next to its behaviour) and QEMU's write rule over the
// per-bit policies of the description, plus the side-effect-free debugger path.
#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "core.hpp"

namespace dpc31 {

ChipCore::ChipCore(const ChipOptions& opt)
    : variant(opt.variant),
      clock{opt.engine, opt.clock_hz != 0 ? opt.clock_hz : chip_timing().clock_hz},
      signals(clock),
      regs(profile_desc(opt.profile), opt.bus, signals),
      irq(clock, regs, signals, opt.irq_controller),
      buffers(regs, irq),
      watchdog(clock, regs, irq, signals),
      sap_list(regs, irq, signals),
      dp(regs, irq, buffers, watchdog, sap_list, counters, signals),
      mac(clock, regs, dp, watchdog, counters, signals),
      mode(clock, regs, irq, buffers, dp, watchdog, mac, signals,
           opt.variant ? static_cast<std::uint8_t>(*opt.variant)
                       : profile_desc(opt.profile).release),
      requests(clock, regs, irq, dp, mode, signals) {
  if (variant && prof().id != Profile::vpc3plus) {
    throw std::invalid_argument(
        fmt::format("a VPC3+ variant ({}) on the {} profile: only vpc3plus has variants",
                    vpc3_variant_name(*variant), prof().name));
  }
  if (opt.irq_controller == IrqController::c31 && prof().id != Profile::dpc31) {
    throw std::invalid_argument(
        fmt::format("the C31's interrupt controller on the {} profile: only the dpc31 has a C31 "
                    "core",
                    prof().name));
  }
  // A RAM access violation takes a started chip offline, as MAC_Stop does; the lockstep's RTL
  // learns it from the same block event (it does not decode addresses beyond the RAM).
  regs.on_violation = [this] {
    signals.emit(BlockEvent::Kind::mac_stop);
    mode.go_offline("RAM access violation");
  };
  irq.install_hooks(hooks);
  mode.install_hooks(hooks);
  buffers.install_hooks(hooks);
  dp.install_hooks(hooks);
  requests.install_hooks(hooks);
  // Every derived value the description promises must have a block that computes it.
  for (const RegDesc& r : prof().regs) {
    const RegHooks& h = hooks[RegisterFile::idx(r.id)];
    const bool modelled = (r.mask() & ~r.rsvd & ~r.unimp) != 0;
    if (r.kind == Kind::derived && modelled && h.read == nullptr) {
      throw std::logic_error(fmt::format("{}: derived register without a read hook", r.name));
    }
    if (r.cmd != 0 && h.command == nullptr) {
      throw std::logic_error(fmt::format("{}: command register without a command hook", r.name));
    }
  }
  build_plain_path();
  reset();
}

// The plain path: what the description marks plain (RegDesc::plain) and no block hooked. The
// per-cycle engine keeps only the reference path, so the engine equality tests (Engine.*,
// PlainPath.*) compare the two.
void ChipCore::build_plain_path() {
  const std::size_t size = std::size_t{1} << prof().address_bits;
  plain_rd_.assign(size, 0);
  plain_wr_.assign(size, 0);
  plain_lanes_.clear();
  if (clock.engine != Engine::event) return;
  const auto lane_of = [&](const RegDesc& r, std::int32_t base, std::uint32_t a) {
    return r.placement(regs.bus())[a - static_cast<std::uint32_t>(base)];
  };
  const auto add_lane = [&](PlainLane l) {
    plain_lanes_.push_back(l);
    return static_cast<std::uint16_t>(kPlainLane | (plain_lanes_.size() - 1));
  };
  std::vector<bool> ram_rd(size + 1, false);
  std::vector<bool> ram_wr(size + 1, false);
  for (std::uint32_t a = 0; a < size; ++a) {
    const std::uint16_t region = regs.region_index(a);
    const bool ram =
        region != kNoReg && prof().regions[region].ram && !prof().regions[region].reserved;
    if (const std::uint16_t i = regs.read_index(a); i == kNoReg) {
      ram_rd[a] = ram;
    } else if (const RegDesc& r = prof().regs[i]; r.kind == Kind::cell) {
      ram_rd[a] = r.plain != 0;
    } else if (const RegHooks& h = hooks[RegisterFile::idx(r.id)];
               h.read == nullptr && h.command == nullptr) {
      const unsigned lane = lane_of(r, r.read_addr, a);
      if ((r.plain >> lane & 1u) != 0) {
        plain_rd_[a] = add_lane({r.id, static_cast<std::uint16_t>(r.mask() & ~r.rsvd), 0,
                                 static_cast<std::uint8_t>(8 * lane), false});
      }
    }
    if (const std::uint16_t i = regs.write_index(a); i == kNoReg) {
      ram_wr[a] = ram;
    } else if (const RegDesc& r = prof().regs[i]; r.kind == Kind::cell) {
      ram_wr[a] = r.plain != 0 && hooks[RegisterFile::idx(r.id)].post_write == nullptr;
    } else if (const RegHooks& h = hooks[RegisterFile::idx(r.id)];
               h.pre_write == nullptr && h.post_write == nullptr) {
      const unsigned lane = lane_of(r, r.write_addr, a);
      const auto bits = static_cast<std::uint16_t>(0xFFu << (8 * lane));
      if ((r.plain >> lane & 1u) != 0) {
        plain_wr_[a] = add_lane(
            {r.target, static_cast<std::uint16_t>((r.rw | r.wo) & bits),
             static_cast<std::uint16_t>(r.rsvd & bits), static_cast<std::uint8_t>(8 * lane),
             r.target == RegId::Int_Req_Reg || r.target == RegId::Int_Mask_Reg});
      }
    }
  }
  // RAM: the number of plain RAM bytes from each address on (a block's one check).
  std::uint16_t run_rd = 0;
  std::uint16_t run_wr = 0;
  for (std::size_t a = size; a-- > 0;) {
    run_rd = ram_rd[a] ? static_cast<std::uint16_t>(std::min<int>(run_rd + 1, kPlainLane - 1)) : 0;
    run_wr = ram_wr[a] ? static_cast<std::uint16_t>(std::min<int>(run_wr + 1, kPlainLane - 1)) : 0;
    if (run_rd != 0) plain_rd_[a] = run_rd;
    if (run_wr != 0) plain_wr_[a] = run_wr;
  }
}

std::size_t ChipCore::ram_run(const std::vector<std::uint16_t>& table, std::uint32_t addr,
                              std::size_t len) const {
  const std::uint32_t end = regs.undecoded_end();
  if (addr >= end) return 0;
  const std::uint16_t p = table[addr];
  if (p >= kPlainLane) return 0;
  return std::min<std::size_t>({len, p, end - addr});
}

// Whole accesses that end before quiet_until: no event can act inside them (docs/engine.md).
std::size_t ChipCore::quiet_accesses() const {
  if (clock.quiet_until <= clock.now || watched()) return 0;
  return (clock.quiet_until - clock.now - 1) / prof().bus_access_cycles;
}

std::size_t ChipCore::quiet_ram_run(std::uint32_t addr, std::size_t len, bool write) const {
  return std::min(ram_run(write ? plain_wr_ : plain_rd_, addr, len), quiet_accesses());
}

void ChipCore::bus_write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes) {
  while (!bytes.empty()) {
    std::size_t k = quiet_ram_run(addr, bytes.size(), true);
    if (k == 0) {
      bus_write(addr, bytes.front());
      k = 1;
    } else {
      std::memcpy(regs.mem_at(addr), bytes.data(), k);
      clock.now += k * prof().bus_access_cycles;
    }
    addr += static_cast<std::uint32_t>(k);
    bytes = bytes.subspan(k);
  }
}

void ChipCore::bus_read_block(std::uint32_t addr, std::span<std::uint8_t> out) {
  while (!out.empty()) {
    std::size_t k = quiet_ram_run(addr, out.size(), false);
    if (k == 0) {
      out.front() = bus_read(addr);
      k = 1;
    } else {
      std::memcpy(out.data(), regs.mem_at(addr), k);
      clock.now += k * prof().bus_access_cycles;
    }
    addr += static_cast<std::uint32_t>(k);
    out = out.subspan(k);
  }
}

void ChipCore::bus_fill(std::uint32_t addr, std::uint8_t value, std::size_t len) {
  while (len != 0) {
    std::size_t k = quiet_ram_run(addr, len, true);
    if (k == 0) {
      bus_write(addr, value);
      k = 1;
    } else {
      std::memset(regs.mem_at(addr), value, k);
      clock.now += k * prof().bus_access_cycles;
    }
    addr += static_cast<std::uint32_t>(k);
    len -= k;
  }
}

bool ChipCore::bus_equal(std::uint32_t a, std::uint32_t b, std::size_t len) {
  for (std::size_t i = 0; i < len;) {
    const auto ai = a + static_cast<std::uint32_t>(i);
    const auto bi = b + static_cast<std::uint32_t>(i);
    // Two accesses per pair.
    const std::size_t k = std::min(
        {ram_run(plain_rd_, ai, len - i), ram_run(plain_rd_, bi, len - i), quiet_accesses() / 2});
    if (k == 0) {
      const std::uint8_t first = bus_read(ai);  // this order on the bus
      if (first != bus_read(bi)) return false;
      ++i;
      continue;
    }
    const std::uint8_t* pa = regs.mem_at(ai);
    const auto diff =
        static_cast<std::size_t>(std::mismatch(pa, pa + k, regs.mem_at(bi)).first - pa);
    if (diff < k) {
      clock.now += 2 * (diff + 1) * prof().bus_access_cycles;
      return false;
    }
    clock.now += 2 * k * prof().bus_access_cycles;
    i += k;
  }
  return true;
}

void ChipCore::reset(std::uint64_t at) {
  clock.now = at;
  clock.quiet_until = 0;
  regs.reset();
  buffers.reset();
  dp.reset();
  watchdog.power_on();
  mode.reset();
  mac.reset();
  requests.reset();
  counters = FdlCounters{};
  written_bits = 0;
  irq.reset();  // last: X/INT from the reset registers
}

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

std::uint16_t ChipCore::reg_value(RegId id) const {
  const RegDesc* r = regs.reg(id);
  if (r == nullptr) return 0;
  const RegHooks& h = hooks[RegisterFile::idx(id)];
  switch (r->kind) {
    case Kind::cell:
      return regs.cell16(*r);
    case Kind::reserved:
      return 0;
    case Kind::port:
      return regs.latch(r->target);
    case Kind::latch:
    case Kind::derived:
      break;
  }
  const std::uint16_t v = h.read != nullptr ? h.read(h.block) : regs.latch(id);
  return static_cast<std::uint16_t>(v & r->mask() & ~r->rsvd);
}

std::uint32_t ChipCore::begin_access(std::uint32_t addr, std::string_view what) {
  if ((addr >> prof().address_bits) != 0) [[unlikely]]
    note_beyond_bus(addr, what);
  bool violation = false;
  const std::uint32_t a = regs.decode(addr, violation);
  if (violation) [[unlikely]] {
    regs.note_violation(addr, a);
    // Its MAC_Reset shows on X/INT at the access's completion: a RAM access has no hook after
    // which the line would be looked at (docs/timing.md, "Order within one cycle", step 6).
    irq.update_line();
  }
  return a;
}

std::uint8_t ChipCore::bus_read_ref(std::uint32_t addr) {
  signals.emit(BlockEvent::Kind::read, static_cast<std::uint16_t>(addr));
  if (signals.bus) signals.bus(clock.now, BusAccess{false, static_cast<std::uint16_t>(addr), 0});
  const std::uint8_t v = read_now(addr);
  signals.state(clock.now);
  return v;
}

void ChipCore::bus_write_ref(std::uint32_t addr, std::uint8_t value) {
  signals.emit(BlockEvent::Kind::write, static_cast<std::uint16_t>(addr), value);
  if (signals.bus) signals.bus(clock.now, BusAccess{true, static_cast<std::uint16_t>(addr), value});
  write_now(addr, value);
  signals.state(clock.now);
}

namespace {

// Where the other profiles have a register at `a` (a firmware written for another chip is the
// usual reason for unmapped accesses): "; on spc3 it is Int_Reg, ..." or "".
std::string other_profiles_at(Profile self, std::uint32_t a, bool write) {
  std::string s;
  for (const Profile p : kAllProfiles) {
    if (p == self) continue;
    for (const RegDesc& r : profile_desc(p).regs) {
      const std::int32_t base = write ? r.write_addr : r.read_addr;
      if (base < 0 || a < static_cast<std::uint32_t>(base) ||
          a >= static_cast<std::uint32_t>(base) + r.width / 8u)
        continue;
      s += fmt::format("{} {} it is {}", s.empty() ? "; on" : ", on", profile_desc(p).name, r.name);
      break;
    }
  }
  return s;
}

}  // namespace

void ChipCore::note_unmapped(std::uint32_t a, std::string_view access) {
  const FoldedLog::Line line = unmapped.note(a);
  if (line == FoldedLog::Line::none) return;
  const std::uint16_t region = regs.region_index(a);
  const std::string_view where =
      region != kNoReg ? prof().regions[region].name : std::string_view("no region");
  const bool write = access.starts_with("write");
  const std::string_view result = write ? "ignored" : "reads 00h";
  switch (line) {
    case FoldedLog::Line::first:
      signals.log(LogLevel::warn,
                  "{} unmapped address {:#06x} ({}): {}{}; a firmware written for another chip? "
                  "(--profile, --variant); further unmapped accesses are counted",
                  access, a, where, result, other_profiles_at(prof().id, a, write));
      break;
    case FoldedLog::Line::address:
      signals.log(LogLevel::warn, "{} unmapped address {:#06x} ({}): {}", access, a, where, result);
      break;
    case FoldedLog::Line::count:
      signals.log(LogLevel::warn,
                  "{} accesses to unmapped addresses so far (the latest: {} {:#06x})",
                  unmapped.count, access, a);
      break;
    case FoldedLog::Line::none:
      break;
  }
}

void ChipCore::note_beyond_bus(std::uint32_t addr, std::string_view what) {
  const unsigned bits = prof().address_bits;
  switch (beyond_bus.note(addr)) {
    case FoldedLog::Line::first:
      signals.log(LogLevel::warn,
                  "{} at {:#x}: beyond the {}-bit address bus, upper bits ignored; a firmware "
                  "written for another chip? (--profile, --variant); further accesses beyond the "
                  "bus are counted",
                  what, addr, bits);
      break;
    case FoldedLog::Line::address:
      signals.log(LogLevel::warn, "{} at {:#x}: beyond the {}-bit address bus, upper bits ignored",
                  what, addr, bits);
      break;
    case FoldedLog::Line::count:
      signals.log(LogLevel::warn,
                  "{} accesses beyond the {}-bit address bus so far (the latest: {} at {:#x})",
                  beyond_bus.count, bits, what, addr);
      break;
    case FoldedLog::Line::none:
      break;
  }
}

std::uint8_t ChipCore::read_now(std::uint32_t addr) {
  const std::uint32_t a = begin_access(addr, "read");
  const std::uint16_t i = regs.read_index(a);
  if (i == kNoReg) {
    const std::uint16_t region = regs.region_index(a);
    if (region != kNoReg && prof().regions[region].ram) {
      if (prof().regions[region].reserved) {
        signals.log(LogLevel::info, "read of {} at {:#06x}", prof().regions[region].name, a);
      }
      return regs.mem(a);
    }
    note_unmapped(a, "read of");
    return 0;
  }
  const RegDesc& r = prof().regs[i];
  const std::uint32_t offset = a - static_cast<std::uint32_t>(r.read_addr);
  switch (r.kind) {
    case Kind::cell:
      if (r.reserved) signals.log(LogLevel::info, "read of reserved cell {} at {:#06x}", r.name, a);
      return regs.mem(a);
    case Kind::reserved:
      signals.log(LogLevel::warn, "read of reserved {} at {:#06x}: reads 00h", r.name, a);
      return 0;
    case Kind::port:  // ports have no read side
    case Kind::latch:
    case Kind::derived:
      break;
  }
  const RegHooks& h = hooks[RegisterFile::idx(r.id)];
  std::uint16_t v = 0;
  if (h.command != nullptr) {
    v = h.command(h.block);
    irq.update_line();
  } else {
    v = h.read != nullptr ? h.read(h.block) : regs.latch(r.id);  // reg_value for these kinds
  }
  v = static_cast<std::uint16_t>(v & r.mask() & ~r.rsvd);
  if (unimp_news(r, v))
    signals.log(LogLevel::info, "read of {}: behaviour not modelled, reads the stored value",
                r.name);
  return static_cast<std::uint8_t>(v >> (8 * r.placement(regs.bus())[offset]));
}

// UNIMP bits (docs/registers.md) are news in a register of nothing else, at every access, and
// elsewhere when an access carries a 1 in one (`ones`: the bits read, or written as 1): a
// driver's Mode_Reg0 write that leaves MinTSDR, Early_Rdy and Spec_Prm_Buf_Mode 0 is not.
bool ChipCore::unimp_news(const RegDesc& r, std::uint16_t ones) const {
  const bool only_unimp = r.unimp != 0 && (r.mask() & ~r.rsvd & ~r.unimp) == 0;
  return only_unimp || (ones & regs.reg(r.target)->unimp) != 0;
}

void ChipCore::write_now(std::uint32_t addr, std::uint8_t value) {
  const std::uint32_t a = begin_access(addr, "write");
  const std::uint16_t i = regs.write_index(a);
  if (i == kNoReg) {
    const std::uint16_t region = regs.region_index(a);
    if (region != kNoReg && prof().regions[region].ram) {
      if (prof().regions[region].reserved) {
        signals.log(LogLevel::info, "write {:02X}h to {} at {:#06x}", value,
                    prof().regions[region].name, a);
      }
      regs.set_mem(a, value);
      return;
    }
    note_unmapped(a, fmt::format("write {:02X}h to", value));
    return;
  }
  const RegDesc& r = prof().regs[i];
  switch (r.kind) {
    case Kind::cell: {
      if (r.reserved)
        signals.log(LogLevel::info, "write {:02X}h to reserved cell {} at {:#06x}", value, r.name,
                    a);
      regs.set_mem(a, value);
      // A cell is RAM; a few start an action when written (the DPC31's InstQ_Wr).
      const RegHooks& h = hooks[RegisterFile::idx(r.id)];
      if (h.post_write != nullptr) {
        h.post_write(h.block, 0, value, value);
        irq.update_line();
      }
      return;
    }
    case Kind::reserved:
      signals.log(LogLevel::warn, "write {:02X}h to reserved {} at {:#06x}: ignored", value, r.name,
                  a);
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
  const unsigned shift = 8u * r.placement(regs.bus())[offset];
  const auto lane = static_cast<std::uint16_t>(0xFFu << shift);
  const auto w = static_cast<std::uint16_t>(value << shift);
  const std::uint16_t old = regs.latch(r.target);
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
    signals.log(LogLevel::warn, "{}: write would change reserved bits {:#06x}: ignored", r.name,
                rsvd_change);
  }
  // Documented as no effect when written: a driver's standard writes (FFFFh to Int_Ack_Reg, an
  // SPC3 driver's Res_User_WD on a DPC31) are no news, so debug.
  if ((w & r.ign) != 0) {
    signals.log(LogLevel::debug, "{}: {} not changed by this register (bits {:#06x})", r.name,
                field_names(r, w & r.ign), w & r.ign);
  }
  const RegHooks& h = hooks[RegisterFile::idx(r.id)];
  written_bits = w;
  if (h.pre_write != nullptr) next = h.pre_write(h.block, old, next);
  // The UNIMP bits the write leaves 1 or changes; a set port's (VPC3+ Mode_Reg1_S: En_Chk_SSAP,
  // its target's bit) only where it writes a 1, a reset port's where it clears a 1: their other
  // writes (each EOI, each Res_User_WD, a driver's FFh reset) do not touch them.
  const auto port = static_cast<std::uint16_t>(r.w1s | r.w1c);
  const auto touched =
      static_cast<std::uint16_t>((w & r.w1s) | (w & r.w1c & old) | ((next | (next ^ old)) & ~port));
  const auto unimp = static_cast<std::uint16_t>(touched & lane & regs.reg(r.target)->unimp);
  if (unimp_news(r, unimp)) {
    signals.log(LogLevel::info, "{}: {} stored, behaviour not modelled", r.name,
                field_names(r, unimp != 0 ? unimp : static_cast<std::uint16_t>(r.unimp & lane)));
  }
  regs.latch(r.target) = next;
  if (h.post_write != nullptr) h.post_write(h.block, old, next, w);
  regs.latch(r.target) = static_cast<std::uint16_t>(regs.latch(r.target) & ~r.pulse);
  irq.update_line();
}

std::uint8_t ChipCore::peek(std::uint32_t addr) const {
  bool violation = false;
  const std::uint32_t a = regs.decode(addr, violation);
  const std::uint16_t i = regs.read_index(a);
  if (i == kNoReg) {
    const std::uint16_t region = regs.region_index(a);
    return region != kNoReg && prof().regions[region].ram ? regs.mem(a) : std::uint8_t{0};
  }
  const RegDesc& r = prof().regs[i];
  if (r.kind == Kind::cell) return regs.mem(a);
  const std::uint16_t v = reg_value(r.id);
  return static_cast<std::uint8_t>(
      v >> (8 * r.placement(regs.bus())[a - static_cast<std::uint32_t>(r.read_addr)]));
}

std::optional<ChipCore::PokedLatch> ChipCore::poked_latch(std::uint32_t addr,
                                                          std::uint8_t value) const {
  bool violation = false;
  const std::uint32_t a = regs.decode(addr, violation);
  const std::uint16_t i = regs.read_index(a);
  if (i == kNoReg || prof().regs[i].kind != Kind::latch) return std::nullopt;
  const RegDesc& r = prof().regs[i];
  const unsigned shift = 8u * r.placement(regs.bus())[a - static_cast<std::uint32_t>(r.read_addr)];
  const std::uint16_t s = regs.latch(r.id);
  return PokedLatch{r.id, static_cast<std::uint16_t>((s & ~(0xFFu << shift)) | (value << shift))};
}

void ChipCore::poke_latch(RegId id, std::uint16_t value) {
  regs.latch(id) = static_cast<std::uint16_t>(value & regs.reg(id)->mask());
  if (id == RegId::Mode_Reg2) regs.follow_mode2(regs.latch(id));
  irq.update_line();
}

bool ChipCore::poke(std::uint32_t addr, std::uint8_t value) {
  if (const auto l = poked_latch(addr, value)) {
    poke_latch(l->id, l->value);
    return true;
  }
  bool violation = false;
  const std::uint32_t a = regs.decode(addr, violation);
  const std::uint16_t i = regs.read_index(a);
  if (i == kNoReg) {
    const std::uint16_t region = regs.region_index(a);
    if (region == kNoReg || !prof().regions[region].ram) return false;
    regs.set_mem(a, value);
    return true;
  }
  if (prof().regs[i].kind != Kind::cell) return false;
  regs.set_mem(a, value);
  return true;
}

}  // namespace dpc31
