// The chip: one SPC3, VPC3+ or DPC31 as firmware sees it on its parallel bus.
//
// Time is a 64-bit count of chip clocks since reset (docs/timing.md). Bus accesses cost
// bus_access_cycles() clocks each and take effect at the end of the access; peek/poke are the
// debugger's path: no time, no side effects.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "dpc31/fdl.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/log.hpp"
#include "dpc31/reg_fields.hpp"
#include "dpc31/reg_ids.hpp"
#include "dpc31/regdesc.hpp"
#include "dpc31/snapshot.hpp"
#include "dpc31/uart.hpp"

namespace dpc31 {

// How time advances (docs/engine.md). Both engines give the same observable results; per_cycle
// evaluates every clock as RTL would and is the reference the event engine is checked against.
enum class Engine : std::uint8_t { event = 0, per_cycle = 1 };

// The VPC3+ variants, as the ASIC type in Status_Reg bits 15..12 tells them apart (the
// Profichip driver's dp_if.h: AT_MASK F0h of the high status byte, AT_VPC3B B0h, AT_VPC3C C0h,
// AT_VPC3S E0h). The value is that nibble. Only the nibble differs in the model.
enum class Vpc3Variant : std::uint8_t { b = 0xB, c = 0xC, s = 0xE };
inline constexpr Vpc3Variant kAllVpc3Variants[] = {Vpc3Variant::b, Vpc3Variant::c, Vpc3Variant::s};
// "b", "c", "s" (the names the CLI, the C HAL and scenario files use).
bool parse_vpc3_variant(std::string_view s, Vpc3Variant& out);
std::string_view vpc3_variant_name(Vpc3Variant v);

// The DPC31 has its interrupt controller twice, at the same addresses: one for the external
// processor (it drives the X/INT pin) and one for the internal C31 core (docs/dpc31.md,
// "Two interrupt controllers"). The user's bus reaches one of them; SPC3 and VPC3+ have only
// the external one.
enum class IrqController : std::uint8_t { external = 0, c31 = 1 };
// "external", "c31" (the names the CLI, scenario and trace files use).
bool parse_irq_controller(std::string_view s, IrqController& out);
std::string_view irq_controller_name(IrqController c);

struct ChipOptions {
  Profile profile = Profile::dpc31;
  BusMode bus = BusMode::intel;
  std::uint32_t clock_hz = 0;  // 0 = the description's default (48 MHz)
  Engine engine = Engine::event;
  // vpc3plus only (the Chip constructor throws std::invalid_argument for another profile);
  // unset = VPC3+C, the description's reset value of Status_Reg (docs/decisions.md).
  std::optional<Vpc3Variant> variant = std::nullopt;
  // The interrupt controller the bus reaches: c31 on the dpc31 only (else the constructor throws
  // std::invalid_argument).
  IrqController irq_controller = IrqController::external;
};

// DP slave state machine (Status_Reg bits 5:4).
enum class DpState : std::uint8_t { Wait_Prm = 0, Wait_Cfg = 1, Data_Exchange = 2 };
// Watchdog state machine (Status_Reg bits 7:6).
enum class WdState : std::uint8_t { Baud_Search = 0, Baud_Control = 1, DP_Control = 2 };

// Interrupt bits (Int_Req_Reg, the same in all profiles): the generated field masks.
namespace irq {
inline constexpr std::uint16_t MAC_Reset = fields::Int_Req_Reg::MAC_Reset;
inline constexpr std::uint16_t Go_Leave_Data_Exchange = fields::Int_Req_Reg::Go_Leave_Data_Exchange;
inline constexpr std::uint16_t Baudrate_Detect = fields::Int_Req_Reg::Baudrate_Detect;
inline constexpr std::uint16_t WD_DP_Control_Timeout = fields::Int_Req_Reg::WD_DP_Control_Timeout;
inline constexpr std::uint16_t User_Timer_Clock = fields::Int_Req_Reg::User_Timer_Clock;
inline constexpr std::uint16_t Indication = fields::Int_Req_Reg::Indication;  // DPC31 only
inline constexpr std::uint16_t New_Ext_Prm_Data =
    fields::Int_Req_Reg::New_Ext_Prm_Data;  // VPC3+ only
inline constexpr std::uint16_t New_GC_Command = fields::Int_Req_Reg::New_GC_Command;
inline constexpr std::uint16_t New_SSA_Data = fields::Int_Req_Reg::New_SSA_Data;
inline constexpr std::uint16_t New_Cfg_Data = fields::Int_Req_Reg::New_Cfg_Data;
inline constexpr std::uint16_t New_Prm_Data = fields::Int_Req_Reg::New_Prm_Data;
inline constexpr std::uint16_t Diag_Buffer_Changed = fields::Int_Req_Reg::Diag_Buffer_Changed;
inline constexpr std::uint16_t DX_Out = fields::Int_Req_Reg::DX_Out;
inline constexpr std::uint16_t Poll_End_Ind = fields::Int_Req_Reg::Poll_End_Ind;  // VPC3+ only
inline constexpr std::uint16_t FDL_Ind = fields::Int_Req_Reg::FDL_Ind;            // VPC3+ only
}  // namespace irq

// A telegram on the bus, as the chip received or sent it (for logs and captures).
struct Telegram {
  bool from_chip;                   // sent by the chip (TxD) or received (RxD)
  std::vector<std::uint8_t> bytes;  // as on the wire, SD to ED
  std::uint64_t start;              // first start bit
  std::uint64_t end;                // end of the last stop bit
};

// A CPU bus access, reported in the cycle it completes, just before it acts (a command read's
// result is what peek gives then).
struct BusAccess {
  bool write;
  std::uint16_t addr;
  std::uint8_t data;  // writes only
};

// What the waveform and the tests watch of the chip's inside, in one look (no time passes, no
// side effects): the state signals the VCD records (dpc31 run --vcd).
struct ChipProbe {
  DpState dp_state;
  WdState wd_state;
  std::uint8_t baud_code;  // Status_Reg bits 11..8 (0 = 12 Mbaud)
  std::uint16_t irr;       // Int_Req_Reg
  // The buffer state machines as the SPC3 shows them in *_Buffer_SM (the dpc31's read of
  // Dout_Buffer_SM shows N_Cl in bit 7 instead of F).
  std::uint8_t dout_buffer_sm;
  std::uint8_t din_buffer_sm;
  std::uint8_t diag_buffer_sm;
};

// A telegram's characters and what a MAC's frame assembler makes of them from the first one on:
// computed once (make) and heard by many chips (Chip::hear_telegram, a segment's stations).
struct HeardFrame {
  std::vector<std::uint8_t> bytes;
  // The character of the assembler's verdict (complete, error), or the last one.
  std::size_t verdict = 0;
  fdl::Assembler frame;  // after bytes[0..verdict]
  fdl::Decoded decoded;  // fdl::decode of the frame, when complete
  static std::shared_ptr<const HeardFrame> make(std::span<const std::uint8_t> bytes);
  // make() in place: the vectors keep their capacity.
  void fill(std::span<const std::uint8_t> chars);
};

// HeardFrame::make for a sender of many telegrams (a segment: every request and answer): a frame
// nobody holds any more (its chips heard the next one, its log entry is gone) is filled again in
// place, which spares its allocations; the oldest handed out is tried first.
class HeardFramePool {
 public:
  std::shared_ptr<const HeardFrame> make(std::span<const std::uint8_t> bytes);

 private:
  std::vector<std::shared_ptr<HeardFrame>> frames_;  // in the order handed out, from next_ on
  std::size_t next_ = 0;
};

// A run of telegrams heard whole, each on the line right after the one before it, the first
// right after one the chip heard whole and took: what their verdicts do in a chip none of them
// addresses, while it shows none of them (may_hear_later), summed once by the line for every such
// chip (a segment's telegram log, docs/segment.md "The fold"). Chip::hear_run takes it.
struct HeardRun {
  std::uint64_t first_start = 0;  // the first telegram's start bit ...
  std::uint64_t first_idle = 0;   // ... and the idle bit times before it on the line
  // What the verdicts count in a started chip and in one offline, but the first telegram's
  // no_sync (counted unless the chip skips already: its own state).
  FdlCounters started;
  FdlCounters offline;
  bool skipping = false;  // after the run: the MAC waits for TSYN
  // The run's last telegram after TSYN (the framing after it: its assembler), or none.
  const HeardFrame* synced = nullptr;
  // The run's last character: its start, its byte and the idle bit times before it (a telegram
  // of one character; 0 otherwise).
  std::uint64_t last_start = 0;
  std::uint8_t last_byte = 0;
  std::uint64_t last_idle = 0;
  std::uint32_t bit_cycles = 0;
};

// An observer of the chip as one of its on_* calls registered it (Chip::remove_txd_chars).
using ObserverId = std::uint64_t;

struct ChipCore;
struct ChipAccess;  // the emulator's harness interface (emu/harness.hpp), not part of the API

class Chip {
 public:
  explicit Chip(ChipOptions opt = {});
  ~Chip();
  Chip(const Chip&) = delete;
  Chip& operator=(const Chip&) = delete;
  Chip(Chip&&) noexcept;
  Chip& operator=(Chip&&) noexcept;

  // Hardware reset: registers and RAM cells to their reset values, cycle counter to 0. The end
  // of an active interrupt and PB3's fall are told to their observers at cycle 0. Under a CPU
  // board (Cpu51Board) the reset is at the board's instant(), where its clock counts on
  // (docs/cpu.md, "The board"): reset(board.instant()).
  void reset();
  // The same reset in a platform whose clock counts on (a Cpu51Board's instant(), docs/cpu.md):
  // the new time line starts at `cycle`, where the reset's edges are told. A cycle past
  // kLastCycle, or under a CPU board another than its instant, is std::invalid_argument, the chip
  // unchanged.
  void reset(std::uint64_t cycle);

  // --- the bus (front door) ---
  std::uint8_t read(std::uint32_t addr);
  void write(std::uint32_t addr, std::uint8_t value);
  // Block transfers, what the drivers' CopyToVpc3 & co. do (docs/timing.md, "Block transfers"):
  // byte i at addr + i, each an ordinary bus access in order, exactly as that many read() /
  // write() calls would be (time, values, log, observers); a stretch of plain RAM that no event
  // interrupts moves at once.
  void write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes);
  void read_block(std::uint32_t addr, std::span<std::uint8_t> out);
  void fill(std::uint32_t addr, std::uint8_t value, std::size_t len);
  // Reads a + i, then b + i, for each i, and stops after the first pair that differs (the
  // drivers' Vpc3MemCmp); true when all len pairs are equal.
  bool equal(std::uint32_t a, std::uint32_t b, std::size_t len);
  // Of the next `len` accesses to addr, addr + 1, ... (reads, or writes): how many touch only
  // plain RAM (no register, no hooked or reserved cell, no RAM access violation) and end before
  // the next event. They change nothing but that RAM and the cycle, so a CPU model may make them
  // at once (session/cpu.cpp). 0 in the per-cycle engine and while an access is watched.
  [[nodiscard]] std::size_t quiet_ram_run(std::uint32_t addr, std::size_t len, bool write) const;

  // --- the debugger (back door): no time passes, no side effects but the state poked, no log ---
  // peek returns what a bus read would return now (command reads: the result they would give).
  [[nodiscard]] std::uint8_t peek(std::uint32_t addr) const;
  // poke stores into RAM / a RAM cell / the latch behind the read side; false where the read
  // side has no storage (derived values, reserved and unmapped addresses). A byte that would
  // change Mode_Reg1's run state or pulses (below) is std::invalid_argument, nothing stored
  // (poke_problem says why; "" when the poke is taken).
  bool poke(std::uint32_t addr, std::uint8_t value);
  [[nodiscard]] std::string poke_problem(std::uint32_t addr, std::uint8_t value) const;
  // Whole registers by id, including write-only latches (Int_Mask_Reg, WD_Baud_Control_Val).
  // A poked latch is the state it holds: VPC3+ Mode_Reg2.4kB_Mode switches the RAM decode
  // (2 KB / 4 KB) at once, in Offline or not. Bits whose state is the chip's machines',
  // not the latch's, never disagree with them: a poke that would change Mode_Reg1's Start_SPC3,
  // Go_Offline (the run state) or its pulses EOI, User_Leave_Master is std::invalid_argument
  // (poke_reg_problem says why; "" when the poke is taken), nothing stored. "Change" is against
  // what the chip has (Start_SPC3: started; pulses: 0), not the latch, as at the byte door.
  [[nodiscard]] std::uint16_t peek_reg(RegId id) const;
  bool poke_reg(RegId id, std::uint16_t value);
  [[nodiscard]] std::string poke_reg_problem(RegId id, std::uint16_t value) const;

  // --- time ---
  // The chip's time ends at kLastCycle, 2^62 - 1 (about 3 000 years at 48 MHz): a step past it
  // stops there, whatever `cycles` says. UINT64_MAX marks a timer that is off, and a timer armed
  // at the last cycle (now + its period) must not wrap past it.
  static constexpr std::uint64_t kLastCycle = (std::uint64_t{1} << 62) - 1;
  // The cycle `cycles` after `from`, or kLastCycle where that lies beyond it.
  static constexpr std::uint64_t cycle_after(std::uint64_t from, std::uint64_t cycles) {
    return cycles < kLastCycle - from ? from + cycles : kLastCycle;
  }
  void step(std::uint64_t cycles = 1);
  // Steps at most `cycles`, stopping right after the event that makes the interrupt active
  // (true) — where firmware would enter its ISR.
  bool step_until_irq(std::uint64_t cycles);
  // Ends the step_until_irq() in progress after the current event (an observer's way to hand
  // control back to whoever steps the chip); step() runs its whole count regardless. Bus accesses
  // always take their full time.
  void request_stop();
  [[nodiscard]] bool stop_requested() const;
  void clear_stop();
  [[nodiscard]] std::uint64_t cycle() const { return *now_; }
  [[nodiscard]] std::uint32_t clock_hz() const;
  [[nodiscard]] std::uint32_t bus_access_cycles() const;

  // --- pins and state ---
  // X/INT pin level (true = high), after the polarity of Mode_Reg0.INT_Pol: the external
  // processor's interrupt controller. With IrqController::c31 the bus reaches the C31's, and the
  // external one, which nobody unmasks, keeps X/INT inactive.
  [[nodiscard]] bool x_int_pin() const;
  // Whether the interrupt of the controller the bus reaches is active (independent of polarity):
  // the user's processor's interrupt input; on_irq_change reports it.
  [[nodiscard]] bool irq_active() const;
  [[nodiscard]] bool started() const;
  [[nodiscard]] DpState dp_state() const;
  [[nodiscard]] WdState wd_state() const;

  // dpc31 port PB3 (seed 003): with C31_Control.Enable_DX_Out_Port = 1 it goes high in the
  // cycle a Global_Control with Sync (without Unsync) latches DX_Out and low when DX_Out is
  // acknowledged (docs/timing.md). Always low on the other profiles.
  [[nodiscard]] bool pb3_pin() const;
  void on_pb3_change(std::function<void(std::uint64_t, bool)> cb);
  // Called whenever the interrupt becomes active or inactive: (cycle, active).
  void on_irq_change(std::function<void(std::uint64_t, bool)> cb);

  // --- the serial side (RS-485) ---
  // RxD changes to `level` at `cycle` (>= cycle(), non-decreasing); whole frames may be given
  // ahead of time. A cycle before cycle() throws std::invalid_argument and drives nothing: an
  // edge in the chip's past would be a glitch now.
  void drive_rxd(std::uint64_t cycle, bool level);
  // `bytes` as back-to-back UART characters on RxD from `start`, `bit_cycles` per bit: the edges
  // uart_encode gives, with `fault`. `start` >= cycle() and `bit_cycles` from 1 to 2^32 - 1 (the
  // same for hear_telegram): else std::invalid_argument, nothing driven. Characters, not edges,
  // reach the receiver where it takes them whole (event engine, the rate it listens at, the line
  // idle, no fault in the telegram); the chip's state, its timing and the on_rxd observers are the
  // same as with the edges given one by one (docs/engine.md, "Characters on RxD"). Returns the end
  // of the last stop bit.
  std::uint64_t drive_rxd_chars(std::span<const std::uint8_t> bytes, std::uint64_t start,
                                std::uint32_t bit_cycles, UartFault fault = {});
  // The same characters as drive_rxd_chars (no fault), heard as one telegram (the built-in
  // master, the bridge, a segment's stations: docs/engine.md "Telegrams heard whole"): where the
  // receiver is idle at their rate and the MAC between telegrams (event engine, not in
  // Baud_Search), the chip has no event inside the telegram but where it shows something (a
  // count, the frame's verdict at its last stop sample); its state, counters, timing, pins and
  // observers are those of drive_rxd_chars at every cycle (fewer on_state_change calls), and a
  // snapshot is the same. Returns the end of the last stop bit.
  std::uint64_t hear_telegram(std::span<const std::uint8_t> bytes, std::uint64_t start,
                              std::uint32_t bit_cycles);
  // The same for a telegram decoded once for many chips (HeardFrame::make, not empty): each chip
  // keeps a reference and runs neither the assembler nor the decoder over it again.
  std::uint64_t hear_telegram(const std::shared_ptr<const HeardFrame>& frame, std::uint64_t start,
                              std::uint32_t bit_cycles);
  // A run of telegrams heard whole taken at once, the chip standing at the first one's start: its
  // state and counters then are those hear_telegram of each at its start (the chip stepped from
  // one to the next) leaves once the last one's verdict is taken. False, and nothing taken, where
  // the chip is not as the run assumes: an observer, an event or an answer pending, its receiver
  // not where the line's telegram before the run left it (the caller then hears them one by one).
  bool hear_run(const HeardRun& run);
  // Observers are lists: each on_* call adds one; an empty function removes all of that kind.
  // TxD edges, reported when time reaches them: each edge is an event of the chip.
  void on_txd(std::function<void(std::uint64_t, bool)> cb);
  // TxD edges for a receiver of the caller's own (a master, the bridge): handed over in order and
  // in batches, none before its cycle, at the chip's next event, at take_txd(), at load_state
  // (the old state's) and at the end of every answer. They are no events: a run nobody else watches
  // is not stepped bit by bit (docs/engine.md, "Characters on TxD").
  void on_txd_edges(std::function<void(std::span<const std::pair<std::uint64_t, bool>>)> cb);
  // The same line for a receiver that takes characters (the built-in master, the bridge): handed
  // over as on_txd_edges hands its edges, but a character whose edges are all on the line comes
  // whole (TxdRun::bytes), the rest as edges. While only such observers (or none) watch TxD, the
  // chip keeps its answer as characters and makes no edges for it (docs/engine.md, "Characters
  // on TxD"); an on_txd or on_txd_edges observer makes it edges again.
  // Returns the observer's id for remove_txd_chars (0 for an empty function).
  ObserverId on_txd_chars(std::function<void(const TxdRun&)> cb);
  // Removes that one on_txd_chars observer, the others stay: a receiver that goes before the
  // chip (a master destroyed) takes its own away. An unknown id removes nothing.
  void remove_txd_chars(ObserverId id);
  // Hands the TxD edges up to cycle() to the on_txd_edges and on_txd_chars observers.
  void take_txd();
  // While on, the chip's next falling TxD edge (a start bit) is an event after which the step
  // stops as after request_stop(). Off clears a wake-up that fired but was not taken.
  void wake_on_txd(bool on);
  // RxD edges as they are driven (may lie ahead of cycle()).
  void on_rxd(std::function<void(std::uint64_t, bool)> cb);
  // After every event the chip processes and every bus access: internal state may have changed.
  // The promise is a call at every cycle where the state may have changed; how many calls there
  // are is an engine detail, not contract (the engine fuses events, and a telegram heard whole
  // has fewer than its edges: docs/engine.md, docs/decisions.md). Compare what the state shows,
  // and at which cycles it changes, not the calls.
  void on_state_change(std::function<void(std::uint64_t)> cb);
  // Every error-free frame the chip receives and every answer it sends.
  void on_telegram(std::function<void(const Telegram&)> cb);
  // Every answer the chip sends, as on_telegram reports it (when the chip arms it, with its
  // start and end on the line), without the frames it hears: a segment learns its stations'
  // answers so, at no cost per frame heard.
  void on_answer(std::function<void(const Telegram&)> cb);
  // Every CPU bus access, with its cycle.
  void on_bus_access(std::function<void(std::uint64_t, const BusAccess&)> cb);
  // The chip's cycle after every call that may have changed it (the bus, step, step_until_irq,
  // reset, load_state), even where it stayed: a segment keeps its line's front and the chips
  // stepped through a kept Chip& without looking at each (docs/segment.md). One watcher: a
  // second replaces the first, an empty function removes it.
  void on_cycle(std::function<void(std::uint64_t)> cb);
  [[nodiscard]] bool txd_pin() const;
  [[nodiscard]] const FdlCounters& fdl_counters() const;
  [[nodiscard]] std::uint8_t station_address() const;
  [[nodiscard]] std::uint32_t bit_cycles() const;  // at the current (or searched) baud rate
  // The chip's log: every line passes a LogLimiter per level first (at most LogLimiter::kBurst
  // lines per level in LogLimiter::kWindow cycles). Repeats are folded as the sink sees them: a
  // line equal to the one the sink was given last is counted, and the count comes right after
  // the line it counts, before any line of another level. The sink gets every level, or with
  // `shown` those from it up: the chip formats no line below (a debug line it does not show ends
  // no fold). Replacing the sink (an empty one at the end of a run) first gives the old one what
  // its limiters still owe.
  void set_log_sink(LogSink sink);
  void set_log_sink(LogSink sink, LogLevel shown);

  [[nodiscard]] const ProfileDesc& profile() const;
  // The VPC3+ variant the chip was made as (nullopt on the other profiles).
  [[nodiscard]] std::optional<Vpc3Variant> vpc3_variant() const;
  // The interrupt controller the bus reaches (ChipOptions::irq_controller).
  [[nodiscard]] IrqController irq_controller() const;
  [[nodiscard]] BusMode bus_mode() const;

  // Address of a register's read side (or write side if it has none) in this profile; -1 if the
  // profile lacks it.
  [[nodiscard]] std::int32_t addr_of(RegId id) const;

  // DPC31 (docs/dpc31.md, "The queues"): where the user's next request goes, read from the queue
  // cells without an access: the entry's address (code, then parameter) and the InstQ_Wr value
  // that hands it to the chip. A queue of length 0 gives nullopt, as do the other profiles.
  struct RequestSlot {
    std::uint32_t entry;
    std::uint8_t next_wr;
  };
  [[nodiscard]] std::optional<RequestSlot> next_request_slot() const;

  // Whether the SSA buffer takes a Set_Slave_Add (SSA_Buffer_Free_Cmd was read since the last).
  [[nodiscard]] bool ssa_buffer_free() const;

  // --- snapshots (docs/snapshots.md) ---
  // The whole chip state: registers, RAM, every block's state, timers, the serial receiver and
  // transmitter, RxD edges already driven ahead of time, the cycle counter. Observers and the log
  // sink are not state: they stay attached across load_state.
  [[nodiscard]] std::vector<std::uint8_t> save_state() const;
  // Only a snapshot of a chip with the same profile, bus mode and clock_hz is accepted, and
  // under a CPU board (Cpu51Board) only one of the board's instant, where its last run ended.
  // throws dpc31::SnapshotError; on error the chip is unchanged. The TxD edges up to the old
  // cycle go to the on_txd_edges and on_txd_chars observers first, as take_txd() hands them
  // over; on_irq_change and on_pb3_change see the loaded interrupt and PB3 at the loaded cycle
  // where they differ. A wake_on_txd and a request_stop stay as they were (not state). Refused
  // from inside one of the chip's observers or its log sink while the chip calls it (the access
  // or step in progress runs on the state it would replace): std::logic_error, chip unchanged.
  void load_state(std::span<const std::uint8_t> bytes);
  // temp file + rename; throws SnapshotError (message names the path)
  void save_state_file(const std::string& path) const;
  // throws SnapshotError "PATH: message"
  void load_state_file(const std::string& path);

  // --- observables ---
  [[nodiscard]] ChipProbe probe() const;
  // The next cycle at which something may happen inside the chip without a bus access or a new
  // RxD edge: a timer, the serial receiver or transmitter (the per-cycle engine: the next clock).
  [[nodiscard]] std::uint64_t next_deadline() const;
  // next_deadline() without the verdict of a telegram heard whole (hear_telegram) where it shows
  // nothing outside the chip: a frame for another station, a token, an answer, a broken frame, a
  // start without TSYN, counted only, while no on_telegram or on_state_change observer watches and
  // no answer is on TxD (docs/segment.md, "Verdicts that show nothing"), and without a
  // User_Timer_Clock tick while its IRR bit is set. The chip takes such a verdict or tick inside
  // its next step, at its own cycle: whoever steps it needs no stop there.
  [[nodiscard]] std::uint64_t line_deadline() const;
  // Whether a line may give this chip a telegram heard whole at `bit_cycles` per bit later, at
  // its next step, instead of at the telegram's start: until line_deadline() (an event may change
  // it) and while no observer is added, every such telegram that is not a request with data to
  // this chip's address or a broadcast, and whose frame ends at its last character, would be taken
  // whole and show nothing (no on_telegram, on_state_change or on_rxd observer, no answer on TxD,
  // not in Baud_Search, the receiver idle at that rate between telegrams). A segment's telegram
  // log (docs/segment.md).
  [[nodiscard]] bool may_hear_later(std::uint32_t bit_cycles) const;
  // The cycle the running watchdog (Baud_Control or DP_Control) expires; UINT64_MAX: none.
  [[nodiscard]] std::uint64_t watchdog_due() const;
  // The cycle the EOI inactive time ends (X/INT may become active again from then on); at or
  // before cycle() when none runs.
  [[nodiscard]] std::uint64_t eoi_inactive_until() const;

 private:
  friend struct ChipAccess;
  void moved() const {
    if (on_cycle_) on_cycle_(cycle());
  }
  std::unique_ptr<ChipCore> core_;
  // The core's cycle counter: cycle() is read at every bus access and by every round of a
  // segment, and inline it costs no call. Set wherever core_ is.
  const std::uint64_t* now_;
  std::function<void(std::uint64_t)> on_cycle_;
  // The instant of the CPU board that drives the bus (its last run's end), or none.
  const std::uint64_t* board_instant_ = nullptr;
  friend struct LineAccess;
  friend struct BoardAccess;
};

// Internal: a CPU board's hold on its chip (session/cpu51_board.cpp): load_state takes only a
// snapshot of the board's instant, where the CPU's time stands.
struct BoardAccess {
  static void hold(Chip& c, const std::uint64_t* instant) { c.board_instant_ = instant; }
};

// Internal: a segment's way onto its chips' RxD (session/segment.cpp), not the user's (use the
// checked calls of Chip): the serial calls without their checks. The line drives each chip at the
// line's time, and a chip whose firmware's last bus access ran past the line's round stands a few
// clocks ahead of it: an edge before the chip's cycle() counts at cycle(), characters from such a
// start are given edge by edge, each at its own cycle or at cycle() where that is later.
struct LineAccess {
  static void drive_rxd(Chip& c, std::uint64_t cycle, bool level);
  static std::uint64_t drive_rxd_chars(Chip& c, std::span<const std::uint8_t> bytes,
                                       std::uint64_t start, std::uint32_t bit_cycles,
                                       UartFault fault);
  static std::uint64_t hear_telegram(Chip& c, const std::shared_ptr<const HeardFrame>& frame,
                                     std::uint64_t start, std::uint32_t bit_cycles);
};

}  // namespace dpc31
