// The MCS-51 core as an 80C32 (Intel MCS-51 User's Manual): 256 bytes of internal RAM, the 8032's
// SFRs, timers 0, 1 and 2, the serial port, the two-level interrupt system, idle and power-down.
// Time is counted in machine cycles of 12 oscillator periods (the classic core, docs/cpu.md).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

namespace mcs51 {

// SFR addresses (Intel MCS-51 User's Manual, table "Special Function Registers", 8052 column).
namespace sfr {
inline constexpr std::uint8_t P0 = 0x80, SP = 0x81, DPL = 0x82, DPH = 0x83, PCON = 0x87,
                              TCON = 0x88, TMOD = 0x89, TL0 = 0x8A, TL1 = 0x8B, TH0 = 0x8C,
                              TH1 = 0x8D, P1 = 0x90, SCON = 0x98, SBUF = 0x99, P2 = 0xA0, IE = 0xA8,
                              P3 = 0xB0, IP = 0xB8, T2CON = 0xC8, RCAP2L = 0xCA, RCAP2H = 0xCB,
                              TL2 = 0xCC, TH2 = 0xCD, PSW = 0xD0, ACC = 0xE0, B = 0xF0;
}

inline constexpr unsigned clocks_per_cycle = 12;  // oscillator periods per machine cycle

// The external data memory (MOVX). `clock` is the oscillator clock, counted from reset, at which
// RD or WR rises (the instant the access is complete on the bus, docs/cpu.md "MOVX timing").
class XdataBus {
 public:
  virtual ~XdataBus() = default;
  virtual std::uint8_t read(std::uint16_t addr, std::uint64_t clock) = 0;
  virtual void write(std::uint16_t addr, std::uint8_t value, std::uint64_t clock) = 0;
};

// Oscillator clocks from the start of a MOVX's first machine cycle to the rising edge of RD or
// WR: the strobe spans S1P1..S3P2 of the second machine cycle (docs/cpu.md).
inline constexpr unsigned movx_strobe_end = 18;

// MOVX A,@DPTR / A,@Ri / @DPTR,A / @Ri,A: E0h, E2h, E3h, F0h, F2h, F3h.
constexpr bool is_movx(std::uint8_t op) { return (op & 0xEC) == 0xE0 && (op & 0x03) != 0x01; }

// Interrupt sources in their polling order within one priority level (vector 3 + 8 * index).
enum class Source : std::uint8_t { ie0, tf0, ie1, tf1, serial, timer2 };

// What one call of Cpu::step did.
enum class StepKind : std::uint8_t { instruction, interrupt, idle, power_down };

struct StepResult {
  StepKind kind;
  unsigned cycles;  // machine cycles taken
};

class Cpu {
 public:
  Cpu();

  // The hardware reset: PC 0, SP 07h, the ports FFh, every other SFR 00h; RAM is kept; idle and
  // power-down end, an interrupt due or in service is forgotten. The clock counts on: the first
  // instruction starts at machine cycle `from` (a board's RESET at its instant), or where the
  // CPU stands if that is later.
  void reset(std::uint64_t from = 0);
  // Program memory (64 KB, external on the 80C32: EA tied low).
  void load_code(std::uint16_t addr, std::span<const std::uint8_t> bytes);
  std::uint8_t code(std::uint16_t addr) const { return code_[addr]; }
  // MOVX goes to `bus`; null: a plain 64 KB XDATA memory inside the model.
  void set_xdata(XdataBus* bus) { bus_ = bus; }
  std::uint8_t xram(std::uint16_t addr) const { return xram_[addr]; }

  // One instruction, one interrupt call (LCALL to the vector: 2 cycles), or in idle / power-down
  // one machine cycle.
  StepResult step();
  // Steps until at least `cycles` more machine cycles have passed; returns the cycles run.
  std::uint64_t run(std::uint64_t cycles);
  // Steps while the next step ends by machine cycle `end` (a step that would end later is left
  // to the caller); an XDATA access may lower the end for the steps after it (set_run_end).
  // Returns the cycles run.
  std::uint64_t run_within(std::uint64_t end);
  void set_run_end(std::uint64_t end) { run_end_ = end; }
  std::uint64_t cycles() const { return cycles_; }
  std::uint64_t clocks() const { return cycles_ * clocks_per_cycle; }

  // Pins driven from outside (true = high). The pin is the port latch AND this input.
  void set_port_input(unsigned port, std::uint8_t value);
  void set_int0(bool high) { set_pin(3, 2, high); }
  // INT0 changes to `high` from machine cycle `at` on (>= cycles(), within the next step): a
  // board that knows the pin's future sets it at the cycle whose S5P2 sample first sees it.
  void schedule_int0(std::uint64_t at, bool high);
  // The machine cycles the next step() takes, and whether it is a MOVX (whose access may itself
  // change a pin).
  unsigned next_step_cycles() const;
  bool next_is_movx() const;
  void set_int1(bool high) { set_pin(3, 3, high); }
  // A character arrives on RXD: its start bit begins now (modes 1-3; `bit8` is the stop bit in
  // mode 1, the ninth data bit in modes 2 and 3).
  void serial_receive(std::uint8_t data, bool bit8);
  // A character's transmission ends (TI set): data, TB8 (modes 2, 3), the machine cycle.
  std::function<void(std::uint8_t, bool, std::uint64_t)> on_serial_tx;

  // Programmer's model.
  std::uint16_t pc() const { return pc_; }
  void set_pc(std::uint16_t pc) { pc_ = pc; }
  std::uint8_t a() const { return sfr_[sfr::ACC - 0x80]; }
  std::uint8_t b() const { return sfr_[sfr::B - 0x80]; }
  std::uint8_t psw() const { return sfr_[sfr::PSW - 0x80]; }
  std::uint8_t sp() const { return sfr_[sfr::SP - 0x80]; }
  std::uint16_t dptr() const;
  std::uint8_t reg(unsigned n) const { return iram_[bank() + (n & 7)]; }
  std::uint8_t iram(std::uint8_t addr) const { return iram_[addr]; }
  void set_iram(std::uint8_t addr, std::uint8_t v) { iram_[addr] = v; }
  // The SFR latch as stored (ports: the latch, SBUF: the receive buffer).
  std::uint8_t sfr_latch(std::uint8_t addr) const { return sfr_[addr - 0x80]; }
  // Port n (0..3, P0 at 80h, P1 at 90h, ...): its latch, and its pins (the latch AND what the
  // outside drives).
  std::uint8_t port_latch(unsigned n) const {
    return sfr_latch(static_cast<std::uint8_t>(sfr::P0 + 0x10 * (n & 3)));
  }
  std::uint8_t port_pins(unsigned n) const {
    return static_cast<std::uint8_t>(port_latch(n) & port_in_[n & 3]);
  }
  bool idle() const { return (sfr_latch(sfr::PCON) & 1) != 0; }
  bool powered_down() const { return (sfr_latch(sfr::PCON) & 2) != 0; }
  // An interrupt call is the next step (the last instruction's poll chose a source).
  bool interrupt_due() const { return next_irq_ >= 0; }
  // The source whose call is the next step (valid while interrupt_due()): its vector is
  // 3 + 8 * index (`dpc31 bridge --trace-cpu` names it).
  Source due_source() const { return static_cast<Source>(next_irq_); }
  // Interrupt levels in service: bit 0 low priority, bit 1 high priority.
  std::uint8_t in_service() const { return in_service_; }

 private:
  unsigned bank() const { return psw() & 0x18; }
  std::uint8_t& r(unsigned n) { return iram_[bank() + (n & 7)]; }
  std::uint8_t& acc() { return sfr_[sfr::ACC - 0x80]; }
  std::uint8_t& sf(std::uint8_t addr) { return sfr_[addr - 0x80]; }
  std::uint8_t fetch() { return code_[pc_++]; }
  std::uint16_t fetch16();

  std::uint8_t read_direct(std::uint8_t addr, bool rmw = false);
  void write_direct(std::uint8_t addr, std::uint8_t v);
  bool read_bit(std::uint8_t bit, bool rmw = false);
  void write_bit(std::uint8_t bit, bool v);
  std::uint8_t read_sfr(std::uint8_t addr, bool rmw);
  void write_sfr(std::uint8_t addr, std::uint8_t v);
  void push(std::uint8_t v);
  std::uint8_t pop();
  static bool core_sfr(std::uint8_t addr);
  void set_cy(bool c);
  bool cy() const { return (psw() & 0x80) != 0; }
  void add(std::uint8_t v, bool carry_in);
  void subb(std::uint8_t v);
  void jump_rel(bool taken);
  void cjne(std::uint8_t x, std::uint8_t y);
  std::uint8_t movx_read(std::uint16_t addr);
  void movx_write(std::uint16_t addr, std::uint8_t v);
  static const std::array<std::uint8_t, 256> cycle_table;
  // The instructions (cpu.cpp): one function per opcode, `op_fn<Op>`, each the instruction set's
  // code with the opcode a constant, so that the compiler folds the decoding away; `dispatch_`
  // the table of them by opcode.
  void execute(std::uint8_t op);
  void execute_low(std::uint8_t op);
  void execute_high(std::uint8_t op);
  using OpFn = void (*)(Cpu&);
  template <unsigned Op>
  static void op_fn(Cpu& cpu);
  template <std::size_t... Op>
  static constexpr std::array<OpFn, 256> make_dispatch(std::index_sequence<Op...>);
  static const std::array<OpFn, 256> dispatch_;
  StepResult advance();
  StepResult slow_step();
  // P is the parity of A after every instruction.
  void set_parity() { sf(sfr::PSW) = static_cast<std::uint8_t>((psw() & 0xFE) | parity_[a()]); }
  static const std::array<std::uint8_t, 256> parity_;
  void poll_after(std::uint8_t sampled);

  // Lazy peripherals (docs/cpu.md, "Speed"): while nothing the peripherals do can raise a new
  // request or be seen outside, their machine cycles are only counted (`lag_`) and applied in one
  // go by sync() before anything reads or writes their SFRs, a pin changes, or a step returns.
  void sync();
  void replan();
  void unplan();  // something outside changed: plan again before the next step
  [[nodiscard]] bool serial_quiet() const;

  // Peripherals (peripherals.cpp).
  void set_pin(unsigned port, unsigned bit, bool high);
  bool pin(unsigned port, unsigned bit) const;
  std::uint8_t requests() const;
  int choose(std::uint8_t requested) const;
  void call_interrupt(int source);
  void tick(unsigned cycles);
  bool timers01_bulk(unsigned cycles, std::uint8_t fall, std::uint8_t pins);
  void timer1_clocks_serial(unsigned overflows);
  void timers01(std::uint8_t fall, std::uint8_t pins);
  void timer2(std::uint8_t fall);
  void serial(unsigned tx_ticks, unsigned rx_ticks);
  void serial_mode0();
  void raise(std::uint8_t addr, std::uint8_t mask, int source);

  std::vector<std::uint8_t> code_ = std::vector<std::uint8_t>(0x10000, 0);
  std::vector<std::uint8_t> xram_ = std::vector<std::uint8_t>(0x10000, 0);
  XdataBus* bus_ = nullptr;
  std::array<std::uint8_t, 256> iram_{};
  std::array<std::uint8_t, 128> sfr_{};
  std::array<std::uint8_t, 4> port_in_{0xFF, 0xFF, 0xFF, 0xFF};
  std::uint16_t pc_ = 0;
  std::uint64_t cycles_ = 0;
  std::uint64_t insn_start_ = 0;  // machine cycle at which the instruction in progress began

  // Interrupts: levels in service, the requests sampled before the last cycle, IE/IP/RETI block.
  std::uint8_t in_service_ = 0;
  std::uint8_t raised_ = 0;  // requests raised by hardware in the cycles ticked so far
  bool block_ = false;
  int next_irq_ = -1;  // the source whose call follows the instruction just ended, -1 none
  // The poll's inputs (flags, IE, IP, levels in service) changed since the last poll; the
  // requests of that poll. While clean, the poll's answer is the last one: none.
  bool irq_dirty_ = true;
  std::uint8_t last_req_ = 0;
  // Deferred peripheral cycles, and the machine cycle up to which instructions may defer them:
  // the peripherals' next possible new request, or `cycles_` when every cycle must be ticked.
  std::uint64_t lag_ = 0;
  std::uint64_t horizon_ = 0;
  bool stale_ = true;             // the peripherals' set-up changed: replan() before the next step
  std::uint64_t idle_until_ = 0;  // in idle: the machine cycle up to which idle cycles are counted
  std::uint64_t run_end_ = 0;     // run_within's end

  // Pin samples of the previous machine cycle (edge detection): INT0, INT1, T0, T1, T2, T2EX.
  std::uint8_t last_pins_ = 0x3F;
  bool pins_dirty_ = true;  // a port write or a change from outside: sample the pins again
  struct PinChange {
    std::uint64_t at;
    bool high;
    bool pending;
  } int0_change_{0, true, false};

  // Serial port: the divide-by-16 counters (rx_div_: mode 0's bit count), the transmitter and
  // receiver in progress.
  std::uint8_t t1_half_ = 0;  // SMOD = 0 halves timer 1's overflow rate
  std::uint8_t tx_div_ = 0, rx_div_ = 0;
  int tx_bits_ = -2;  // -2 idle, -1 waiting for the next bit boundary, then the bit in progress
  std::uint8_t tx_data_ = 0;
  bool tx_bit8_ = false;
  int rx_ticks_ = -1;  // 16x ticks left until the receiver's last sample, -1 idle
  std::uint8_t rx_data_ = 0;
  bool rx_bit8_ = false;
};

}  // namespace mcs51
