// Internal state of one chip: the register file storage, RAM, and every hardware block
// (docs/architecture.md, "The chip's blocks"). Blocks keep their own state in small structs and
// attach behaviour to registers through hooks (install_*_hooks), next to the block they belong
// to; their timers are engine timers (timer.hpp). Reached from outside the emulator only through
// dpc31::Chip, and by the block-level tools and tests through emu/harness.hpp.
#pragma once

#include <fmt/format.h>

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "block_event.hpp"
#include "buffers.hpp"
#include "dp_services.hpp"
#include "dp_sm.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/fifo.hpp"
#include "dpc31/reg_fields.hpp"
#include "dpc31/reg_ids.hpp"
#include "dpc31/regdesc.hpp"
#include "irq.hpp"
#include "mac.hpp"
#include "watchdog.hpp"

namespace dpc31 {

struct ChipCore;

// Behaviour attached to one register (keyed by the RegId that is accessed, port or latch).
struct RegHooks {
  // Derived read side without side effects (for command reads: the result they would give).
  std::uint16_t (*read)(const ChipCore&) = nullptr;
  // Command reads: perform the command, return its result.
  std::uint16_t (*command)(ChipCore&) = nullptr;
  // After the access-policy rule: may change what is stored (veto, keep events).
  std::uint16_t (*pre_write)(ChipCore&, std::uint16_t old, std::uint16_t next) = nullptr;
  // After the store: actions of the write (Start, EOI, Go_Offline).
  void (*post_write)(ChipCore&, std::uint16_t old, std::uint16_t now) = nullptr;
};

using HookTable = std::array<RegHooks, kRegIdCount>;

void install_irq_hooks(HookTable& h);
void install_mode_hooks(HookTable& h);
void install_buffer_hooks(HookTable& h);
void install_dp_sm_hooks(HookTable& h);

inline constexpr std::uint16_t kNoReg = 0xFFFF;

// Several parties watch the chip (the scenario runner, waveform and capture writers, the
// built-in master): each observer is a list. Adding an empty function clears the list.
template <typename... A>
struct Observers {
  std::vector<std::function<void(A...)>> fns;
  explicit operator bool() const { return !fns.empty(); }
  void operator()(A... a) const {
    for (const auto& f : fns) f(a...);
  }
  void add(std::function<void(A...)> f) {
    if (f) {
      fns.push_back(std::move(f));
    } else {
      fns.clear();
    }
  }
};

struct ChipCore {
  ChipCore(const ChipOptions& opt);

  const ProfileDesc* prof;
  BusMode bus;
  std::optional<Vpc3Variant> variant;  // vpc3plus only (ChipOptions::variant)
  std::uint8_t release;                // Status_Reg bits 15..12: the profile's, or the variant
  std::uint32_t clock_hz;
  Engine engine;
  std::uint64_t now = 0;
  // RxD edges driven for later cycles. Kept here, not in the receiver, so they survive a
  // receiver (re)configure (Baud_Search switching the rate, Start).
  Fifo<std::pair<std::uint64_t, bool>> rxd_pending;
  bool rxd_level = true;  // the RxD line (per-cycle engine)
  // Event engine: no deadline falls before this cycle (a lower bound; 0 = unknown; always 0 in the
  // per-cycle engine). Lets a bus access that crosses no deadline skip the search for the next
  // event.
  std::uint64_t quiet_until = 0;
  bool stop = false;  // Chip::request_stop

  std::array<std::uint16_t, kRegIdCount> latch{};
  std::vector<std::uint8_t> mem;      // 2^address_bits bytes; only RAM regions are used as RAM
  std::vector<std::uint16_t> rd_map;  // address -> index into prof->regs (kNoReg = none)
  std::vector<std::uint16_t> wr_map;
  std::vector<std::uint16_t> region_map;  // address -> index into prof->regions (kNoReg)
  std::array<std::uint16_t, kRegIdCount> reg_index{};  // RegId -> index into prof->regs
  HookTable hooks{};

  IrqController irq;
  BufferUnit buffers;
  DpStateMachine dp;
  Timers timers;
  Mac mac;
  bool started = false;
  bool ram_access_violation = false;
  bool large_ram = false;      // VPC3+ 4kB_Mode
  std::uint8_t baud_code = 0;  // Status_Reg bits 11..8 (0 = 12 Mbaud, where Baud_Search starts)

  FdlCounters counters;
  std::uint16_t written_bits = 0;  // the lane-aligned value of the write the hooks are serving
  bool diag_in_flight = false;     // a Slave_Diag answer is being sent

  LogSink sink;
  Observers<std::uint64_t, bool> irq_observer;
  Observers<std::uint64_t, bool> txd_observer;
  Observers<std::uint64_t, bool> rxd_observer;  // edges as they are driven (possibly ahead of time)
  Observers<const Telegram&> telegram_observer;
  Observers<std::uint64_t, const BlockEvent&> block_observer;
  Observers<std::uint64_t, const BusAccess&> bus_observer;
  Observers<std::uint64_t> state_observer;  // after every event and every bus access
  // Reports a protocol-side action on the blocks (call sites only, never inside the actions).
  void emit(BlockEvent::Kind k, std::uint16_t value = 0, std::uint8_t data = 0) const {
    if (block_observer) block_observer(now, BlockEvent{k, value, data});
  }
  bool irq_line = false;  // last computed interrupt activity (for change notifications)
  // dpc31 port PB3 with Enable_DX_Out_Port (C31_Control bit 0): high from the DX_Out of a
  // Global_Control with Sync until the user acknowledges DX_Out (seed 003, p.32).
  bool pb3 = false;
  Observers<std::uint64_t, bool> pb3_observer;
  void set_pb3(bool level) {
    if (pb3 == level) return;
    pb3 = level;
    if (pb3_observer) pb3_observer(now, level);
  }

  // --- register file (regfile.cpp) ---
  void reset();
  std::uint8_t bus_read(std::uint32_t addr);  // 4 clocks, then the access
  void bus_write(std::uint32_t addr, std::uint8_t value);
  // The access itself, in the current cycle (the lockstep harness strobes it per cycle).
  std::uint8_t read_now(std::uint32_t addr);
  void write_now(std::uint32_t addr, std::uint8_t value);
  std::uint8_t peek(std::uint32_t addr) const;
  bool poke(std::uint32_t addr, std::uint8_t value);
  [[nodiscard]] const RegDesc* reg(RegId id) const;
  [[nodiscard]] std::uint16_t cell16(const RegDesc& r) const;
  void set_cell16(const RegDesc& r, std::uint16_t v);
  [[nodiscard]] std::uint16_t reg_value(RegId id) const;  // storage or derived (no side effect)

  // --- time (engine.cpp: both engines, docs/engine.md) ---
  enum class Stop : std::uint8_t { never, on_irq, on_irq_or_request };
  // Advances time; with Stop::on_irq it stops right after the event that makes the interrupt
  // active and returns true (also after Chip::request_stop with on_irq_or_request).
  bool advance(std::uint64_t cycles, Stop stop_at = Stop::never) {
    const std::uint64_t end = now + cycles;
    if (end < quiet_until) {  // the common bus access: no deadline inside it (event engine)
      now = end;
      return false;
    }
    return advance_to(end, stop_at);
  }
  bool advance_to(std::uint64_t end, Stop stop_at);
  void reset_time();  // cycle 0
  // Whatever sets a deadline (arm, the MAC's receiver and transmitter) reports it here: the event
  // engine's bus accesses then look for it (quiet_until).
  void note_deadline(std::uint64_t at);
  bool advance_events(std::uint64_t end, Stop stop_at);
  bool advance_clocks(std::uint64_t end, Stop stop_at);
  // Event engine: the earliest deadline (the per-cycle engine: the next clock).
  [[nodiscard]] std::uint64_t next_event() const;
  [[nodiscard]] std::uint64_t next_event_but_user_timer() const;
  void skip_quiet_user_ticks(std::uint64_t bound);
  void process_events();
  void clock();  // per-cycle engine: one clock, everything in the order of docs/timing.md
  [[nodiscard]] std::uint64_t cycles_for_us(std::uint64_t us) const;
  // The cycle the running watchdog expires (kNever: none), from the engine's own state.
  [[nodiscard]] std::uint64_t watchdog_due() const { return due(timers.watchdog); }
  // The timers of the blocks (timer.hpp): each engine keeps them its own way (deadline or
  // counter); the blocks only arm them and ask.
  void arm(Timer& t, std::uint64_t cycles);          // fires `cycles` clocks from now; kNever: off
  [[nodiscard]] bool reached(const Timer& t) const;  // fires now (or has fired, not re-armed)
  [[nodiscard]] bool running(const Timer& t) const;  // armed and not yet reached
  [[nodiscard]] std::uint64_t due(const Timer& t) const;  // the cycle it fires (kNever: off)
  void arm_search_window();
  void stop_search_window();
  void drive_rxd(std::uint64_t cycle, bool level);

  // --- MAC (mac.cpp: the event engine's mac_process and the per-cycle engine's mac_clock) ---
  void mac_start_search();
  void mac_listen(std::uint8_t code);  // receive at kBaudRates[code] from now on
  void mac_search_next();
  void mac_truncated();
  void mac_txd(std::uint64_t cycle, bool level);
  void mac_tx_done();
  [[nodiscard]] bool mac_tx_busy() const;
  void mac_tx_catch_up();  // event engine: TxD edges due by now onto the pin
  void watch_txd(std::function<void(std::uint64_t, bool)> cb);  // Chip::on_txd
  [[nodiscard]] bool txd_level() const;  // TxD now, also with edges not yet taken
  void mac_stop();
  void mac_char(const UartChar& c);
  void mac_frame(const fdl::Frame& f, const UartChar& last);
  void mac_send(const fdl::Frame& f, std::uint64_t request_end);
  void mac_process();  // receiver, frame timeout, search, transmitter: whatever is due now
  void mac_clock();    // per-cycle engine: the same, one clock
  [[nodiscard]] std::uint64_t mac_deadline() const;

  // --- interrupt controller and X/INT, the EOI inactive time (irq.cpp) ---
  void raise(std::uint16_t bits);
  void update_irq_line();
  [[nodiscard]] bool irq_active() const;
  void end_of_interrupt();  // EOI: the inactive time starts

  // --- mode and state, the user timer (mode.cpp) ---
  void start();
  void go_offline();
  void leave_master();
  [[nodiscard]] std::uint16_t status() const;
  [[nodiscard]] std::uint32_t user_timer_period() const;
  void user_timer_tick();  // the User_Timer_Clock tick (its timer reached now)

  // --- buffers, ASIC side (buffers.cpp) ---
  void dout_received();
  void dout_clear();
  std::uint8_t din_fetch();
  void diag_send_begin();
  void diag_send_end(bool stat_diag);
  [[nodiscard]] bool sent_diag_has_stat_diag() const;
  void outputs_received();  // Data_Exchange wrote the outputs into D
  void inputs_due();        // about to send inputs
  void ssa_accepted();
  void failsafe_clear();
  [[nodiscard]] std::uint32_t buffer_addr(RegId ptr_cell) const;
  [[nodiscard]] static RegId dout_ptr(std::uint8_t buffer);  // 1..3
  [[nodiscard]] static RegId din_ptr(std::uint8_t buffer);

  // --- DP services (dp_sm.cpp, global_control.cpp) ---
  // An error-free request for us (or broadcast) arrived now: act, and return the answer to send.
  std::optional<fdl::Frame> dp_service(const fdl::Frame& req);
  void dp_response_sent();  // our answer's last stop bit is out
  std::optional<fdl::Frame> set_prm(const fdl::Frame& req);
  std::optional<fdl::Frame> chk_cfg(const fdl::Frame& req);
  std::optional<fdl::Frame> slave_diag(const fdl::Frame& req);
  std::optional<fdl::Frame> read_io(const fdl::Frame& req);
  std::optional<fdl::Frame> set_slave_add(const fdl::Frame& req);
  std::optional<fdl::Frame> data_exchange(const fdl::Frame& req);
  void global_control(const fdl::Frame& req);
  void apply_global_control(std::uint8_t command);
  void prm_accepted();
  void din_handed_over();
  // VPC3+ DX_Int_Mode / DX_Int_Mode_2: whether these received outputs raise DX_Out.
  bool dx_out_wanted(std::span<const std::uint8_t> outputs);  // New_Din_Buffer_Cmd: the SPC3's
                                                              // delayed entry into Data_Exchange
  void prm_fault();
  void cfg_accepted();
  bool user_watchdog_tick();
  bool receive_via_aux(std::uint16_t sel, RegId target_ptr, RegId len_cell,
                       std::span<const std::uint8_t> du);
  void set_cell(RegId id, std::uint8_t v);
  void swap_cells(RegId a, RegId b);
  void write_buffer(RegId ptr_cell, std::span<const std::uint8_t> bytes);
  std::vector<std::uint8_t> read_buffer(RegId ptr_cell, std::size_t len);
  void ram_write(std::uint32_t addr, std::uint8_t v);
  std::uint8_t ram_read(std::uint32_t addr);

  // --- watchdogs (watchdog.cpp) ---
  void watchdog_parameterise(bool wd_on, std::uint8_t f1, std::uint8_t f2, bool base_1ms);
  // An error-free telegram from `master` to our address: Baud_Control restarts for any station,
  // DP_Control only for the locking master (Master_Add).
  void watchdog_retrigger(std::uint8_t master);
  // Unlocked (Set_Prm Unlock_Req): no master to monitor, DP_Control -> Baud_Control.
  void watchdog_release();
  void watchdog_expired();
  void baud_found(std::uint8_t code);
  [[nodiscard]] bool mode0(std::uint16_t bit) const {
    return (latch[idx(RegId::Mode_Reg0)] & bit) != 0;
  }

  // --- RAM used by the blocks (the ASIC's own accesses) ---
  [[nodiscard]] std::uint32_t segment_shift() const;
  [[nodiscard]] std::uint8_t cell(RegId id) const;  // 8-bit organisational cell
  void clear_ram(std::uint32_t begin, std::uint32_t len);

  template <typename... Args>
  void log(LogLevel level, fmt::format_string<Args...> f, Args&&... args) const {
    if (sink) sink(LogRecord{now, level, fmt::format(f, std::forward<Args>(args)...)});
  }

  static constexpr std::size_t idx(RegId id) { return static_cast<std::size_t>(id); }

 private:
  std::uint32_t decode(std::uint32_t addr, bool& violation) const;
  // Address-bus width, RAM access violation: the decoded address.
  std::uint32_t begin_access(std::uint32_t addr, std::string_view what);
  void note_violation(std::uint32_t addr, std::uint32_t mapped);
  void write_reg(const RegDesc& r, std::uint32_t offset, std::uint8_t value);
};

// ---- the engine's timer operations (timer.hpp), inline for the hot paths; the engines
// themselves are in engine.cpp ----

// Whatever sets a deadline tells the engine: a bus access must not run past it.
inline void ChipCore::note_deadline(std::uint64_t at) {
  if (at < quiet_until) quiet_until = 0;
}

inline void ChipCore::arm(Timer& t, std::uint64_t cycles) {
  if (engine == Engine::event) {
    t.at = cycles == kNever ? kNever : now + cycles;
    note_deadline(t.at);
  } else {
    t.left = cycles;
  }
}

inline bool ChipCore::reached(const Timer& t) const {
  return engine == Engine::event ? t.at <= now : t.left == 0;
}

inline bool ChipCore::running(const Timer& t) const {
  return engine == Engine::event ? now < t.at : t.left != 0;
}

inline std::uint64_t ChipCore::due(const Timer& t) const {
  if (engine == Engine::event) return t.at;
  return t.left == kNever ? kNever : now + t.left;
}

}  // namespace dpc31
