// One chip, composed of its blocks (docs/architecture.md, "The chip's blocks"). Each block is a
// class with its own private state and a small interface, named as the datasheet names it, and
// gets references to the blocks it drives at construction: a received telegram goes
// Mac -> DpStateMachine -> BufferUnit / InterruptController / Watchdog, never back up. What the
// blocks share is infrastructure, not behaviour: the Clock (time and timers, timer.hpp), the
// Signals (log and observers, signals.hpp) and the RegisterFile (latches and RAM, regfile.hpp).
// ChipCore wires them: the CPU's bus side with the registers' hooks (bus.cpp) and the engine that
// advances time (engine.cpp). Reached from outside the emulator only through dpc31::Chip, and by
// the block-level tools and tests through emu/harness.hpp.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "buffers.hpp"
#include "dp_sm.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/reg_fields.hpp"
#include "dpc31/reg_ids.hpp"
#include "dpc31/regdesc.hpp"
#include "irq.hpp"
#include "mac.hpp"
#include "mode.hpp"
#include "reg_hooks.hpp"
#include "regfile.hpp"
#include "requests.hpp"
#include "signals.hpp"
#include "timer.hpp"
#include "watchdog.hpp"

namespace dpc31 {

struct ChipCore;

struct ChipCore {
  explicit ChipCore(const ChipOptions& opt);
  // The blocks hold references to each other: a chip stays where it was built.
  ChipCore(const ChipCore&) = delete;
  ChipCore& operator=(const ChipCore&) = delete;

  std::optional<Vpc3Variant> variant;  // vpc3plus only (ChipOptions::variant)
  Clock clock;
  Signals signals;
  RegisterFile regs;
  InterruptController irq;
  BufferUnit buffers;
  Watchdog watchdog;
  FdlCounters counters;
  SapList sap_list;  // vpc3plus: DPV1's SAP list (docs/dpv1.md)
  DpStateMachine dp;
  Mac mac;
  ModeRegisters mode;
  RequestInterface requests;  // dpc31: the Instruction_Queue and Indication_Queue
  HookTable hooks{};
  bool stop = false;               // Chip::request_stop
  std::uint16_t written_bits = 0;  // the lane-aligned value of the write the hooks are serving
  // Accesses a driver for another chip makes over and over (bus.cpp): a log, not chip state.
  FoldedLog unmapped;
  FoldedLog beyond_bus;  // addresses with bits above the profile's address bus

  [[nodiscard]] const ProfileDesc& prof() const { return regs.profile(); }
  // The hardware reset: every block in its reset state, the time line from `at` (0: its own;
  // a platform's instant: Chip::reset(cycle)).
  void reset(std::uint64_t at = 0);

  // --- the CPU's bus side (bus.cpp): decode, the hooks, QEMU's write rule ---
  // 4 clocks, then the access: the plain path inline, everything else out of line.
  std::uint8_t bus_read(std::uint32_t addr) {
    advance(prof().bus_access_cycles);
    if (std::uint8_t v = 0; !watched() && plain_read(addr, v)) return v;
    return bus_read_ref(addr);
  }
  void bus_write(std::uint32_t addr, std::uint8_t value) {
    advance(prof().bus_access_cycles);
    if (!watched() && plain_write(addr, value)) return;
    bus_write_ref(addr, value);
  }
  // The access itself, in the current cycle (the lockstep harness strobes it per cycle).
  std::uint8_t read_now(std::uint32_t addr);
  void write_now(std::uint32_t addr, std::uint8_t value);
  void note_unmapped(std::uint32_t a, std::string_view access);
  void note_beyond_bus(std::uint32_t addr, std::string_view what);
  [[nodiscard]] std::uint8_t peek(std::uint32_t addr) const;
  bool poke(std::uint32_t addr, std::uint8_t value);
  // The latch a poke of `value` at addr stores into and its whole value after it (Chip::poke
  // checks it against the run state first); nullopt where the poke reaches no latch.
  struct PokedLatch {
    RegId id;
    std::uint16_t value;
  };
  [[nodiscard]] std::optional<PokedLatch> poked_latch(std::uint32_t addr, std::uint8_t value) const;
  // The one store of a poked latch (byte poke and poke_reg): masked, VPC3+ Mode_Reg2's RAM
  // decode follows, X/INT follows.
  void poke_latch(RegId id, std::uint16_t value);
  [[nodiscard]] std::uint16_t reg_value(RegId id) const;  // storage or derived (no side effect)
  // Block transfers (docs/timing.md, "Block transfers"): byte i at addr + i, each access as
  // bus_read / bus_write makes it, in order; runs of plain RAM that no event interrupts move at
  // once. bus_equal reads a[i], then b[i], and stops after the first pair that differs.
  void bus_write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes);
  void bus_read_block(std::uint32_t addr, std::span<std::uint8_t> out);
  void bus_fill(std::uint32_t addr, std::uint8_t value, std::size_t len);
  bool bus_equal(std::uint32_t a, std::uint32_t b, std::size_t len);
  // Of the next `len` accesses to addr, addr + 1, ...: how many are plain RAM accesses that end
  // before the next event (0 in the per-cycle engine and while an access is watched).
  [[nodiscard]] std::size_t quiet_ram_run(std::uint32_t addr, std::size_t len, bool write) const;

  // --- time (engine.cpp: both engines, docs/engine.md) ---
  enum class Stop : std::uint8_t { never, on_irq, on_irq_or_request };
  // Advances time; with Stop::on_irq it stops right after the event that makes the interrupt
  // active and returns true (also after Chip::request_stop with on_irq_or_request).
  bool advance(std::uint64_t cycles, Stop stop_at = Stop::never) {
    // Time ends at Chip::kLastCycle, far below kNever, the deadline of a timer that is off: a step
    // to kNever would fire every such timer, one past it wrap to 0.
    const std::uint64_t end = Chip::cycle_after(clock.now, cycles);
    if (end < clock.quiet_until) {  // the common bus access: no deadline inside it (event engine)
      clock.now = end;
      return false;
    }
    return advance_to(end, stop_at);
  }
  bool advance_to(std::uint64_t end, Stop stop_at);
  // Event engine: the earliest deadline (the per-cycle engine: the next clock).
  [[nodiscard]] std::uint64_t next_event() const;
  // next_event() without a quiet verdict of a telegram heard whole (Chip::line_deadline).
  [[nodiscard]] std::uint64_t line_event() const;

 private:
  bool advance_events(std::uint64_t end, Stop stop_at);
  bool advance_clocks(std::uint64_t end, Stop stop_at);
  [[nodiscard]] std::uint64_t next_event_but_user_timer(bool for_line = false) const;
  void process_events();
  template <bool kPerCycle>
  void run_due();
  void tick();  // per-cycle engine: one clock, everything in the order of docs/timing.md
  void watchdog_expired();
  std::uint32_t begin_access(std::uint32_t addr, std::string_view what);
  void write_reg(const RegDesc& r, std::uint32_t offset, std::uint8_t value);
  [[nodiscard]] bool unimp_news(const RegDesc& r, std::uint16_t ones) const;

  // The plain path (bus.cpp, docs/engine.md "Plain accesses"): the accesses the description
  // (RegDesc::plain) and the installed hooks make straight loads and stores. Per address: 0 the
  // reference path, 1..kPlainLane - 1 plain RAM with that many plain RAM bytes from there on,
  // kPlainLane | i the lane plain_lanes_[i] of a latch. The event engine only.
  static constexpr std::uint16_t kPlainLane = 0x8000;
  struct PlainLane {
    RegId latch;         // read: the register; write: its target
    std::uint16_t mask;  // read: the bits that read as stored; write: the bits that store
    std::uint16_t rsvd;  // write: reserved bits of the lane (a change takes the reference path)
    std::uint8_t shift;  // the lane's bit position in the bus mode
    bool irq;            // write: the latch is IRR or IMR (X/INT follows it)
  };
  void build_plain_path();
  [[nodiscard]] bool watched() const { return signals.bus || signals.block || signals.state; }
  bool plain_read(std::uint32_t addr, std::uint8_t& v) const {
    if (addr >= regs.undecoded_end()) return false;
    const std::uint16_t p = plain_rd_[addr];
    if (p == 0) return false;
    if (p < kPlainLane) {
      v = regs.mem(addr);
      return true;
    }
    const PlainLane& l = plain_lanes_[p & ~kPlainLane];
    v = static_cast<std::uint8_t>((regs.latch(l.latch) & l.mask) >> l.shift);
    return true;
  }
  // write_reg's rule for a lane without W1C, W1S, IGN, UNIMP, pulse bits or hooks: storage takes
  // the written bits. X/INT is looked at only when IRR or IMR changed: nothing else here moves it.
  bool plain_write(std::uint32_t addr, std::uint8_t value) {
    if (addr >= regs.undecoded_end()) return false;
    const std::uint16_t p = plain_wr_[addr];
    if (p == 0) return false;
    if (p < kPlainLane) {
      regs.set_mem(addr, value);
      return true;
    }
    const PlainLane& l = plain_lanes_[p & ~kPlainLane];
    std::uint16_t& stored = regs.latch(l.latch);
    const auto w = static_cast<std::uint16_t>(value << l.shift);
    if (((w ^ stored) & l.rsvd) != 0) return false;  // the reference path logs it
    const auto next = static_cast<std::uint16_t>((stored & ~l.mask) | (w & l.mask));
    written_bits = w;
    if (next == stored) return true;
    stored = next;
    if (l.irq) irq.update_line();
    return true;
  }
  // The reference path: the observers, decode, hooks, QEMU's write rule.
  std::uint8_t bus_read_ref(std::uint32_t addr);
  void bus_write_ref(std::uint32_t addr, std::uint8_t value);
  [[nodiscard]] std::size_t ram_run(const std::vector<std::uint16_t>& table, std::uint32_t addr,
                                    std::size_t len) const;
  [[nodiscard]] std::size_t quiet_accesses() const;
  std::vector<std::uint16_t> plain_rd_;
  std::vector<std::uint16_t> plain_wr_;
  std::vector<PlainLane> plain_lanes_;
};

}  // namespace dpc31
