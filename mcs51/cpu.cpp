// The MCS-51 instruction set (Intel MCS-51 User's Manual, "Instruction Set": operations, flags and
// the machine cycles of each opcode). Peripherals and interrupts are in peripherals.cpp.
#include "mcs51/cpu.hpp"

#include <algorithm>
#include <bit>

namespace mcs51 {

namespace {
constexpr std::uint8_t cy_bit = 0x80, ac_bit = 0x40, ov_bit = 0x04;
bool is_port(std::uint8_t addr) { return (addr & 0x8F) == 0x80; }
}  // namespace

// The SFRs of the core itself: no peripheral reads or changes them, so their accesses need no
// sync() of the deferred peripheral cycles.
bool Cpu::core_sfr(std::uint8_t addr) {
  switch (addr) {
    case sfr::ACC:
    case sfr::B:
    case sfr::PSW:
    case sfr::SP:
    case sfr::DPL:
    case sfr::DPH:
      return true;
    default:
      return false;
  }
}

// Machine cycles per opcode, one string per high nibble (Intel MCS-51 User's Manual, instruction
// set summary; A5h, reserved, runs as a one-cycle no-op).
const std::array<std::uint8_t, 256> Cpu::cycle_table = [] {
  constexpr const char* rows[16] = {
      "1221111111111111", "2221111111111111", "2221111111111111", "2221111111111111",
      "2212111111111111", "2212111111111111", "2212111111111111", "2222121111111111",
      "2222422222222222", "2222111111111111", "2212412222222222", "2211222222222222",
      "2211111111111111", "2211121122222222", "2222111111111111", "2222111111111111"};
  std::array<std::uint8_t, 256> t{};
  for (unsigned op = 0; op < 256; ++op)
    t[op] = static_cast<std::uint8_t>(rows[op >> 4][op & 15] - '0');
  return t;
}();

const std::array<std::uint8_t, 256> Cpu::parity_ = [] {
  std::array<std::uint8_t, 256> t{};
  for (unsigned v = 0; v < 256; ++v) t[v] = static_cast<std::uint8_t>(std::popcount(v) & 1);
  return t;
}();

Cpu::Cpu() { reset(); }

void Cpu::reset(std::uint64_t from) {
  cycles_ = std::max(cycles_, from);  // the clock counts on; the peripherals' lag_ is dropped below
  insn_start_ = cycles_;
  sfr_.fill(0);
  sf(sfr::SP) = 0x07;
  sf(sfr::P0) = sf(sfr::P1) = sf(sfr::P2) = sf(sfr::P3) = 0xFF;
  pc_ = 0;
  in_service_ = 0;
  raised_ = 0;
  block_ = false;
  next_irq_ = -1;
  last_req_ = 0;
  int0_change_.pending = false;
  last_pins_ = 0x3F;
  pins_dirty_ = true;
  t1_half_ = tx_div_ = rx_div_ = 0;
  tx_bits_ = -2;
  rx_ticks_ = -1;
  lag_ = 0;
  irq_dirty_ = true;
  unplan();
}

void Cpu::load_code(std::uint16_t addr, std::span<const std::uint8_t> bytes) {
  for (std::uint8_t b : bytes) code_[addr++] = b;
}

std::uint16_t Cpu::dptr() const {
  return static_cast<std::uint16_t>(sfr_latch(sfr::DPH) << 8 | sfr_latch(sfr::DPL));
}

std::uint16_t Cpu::fetch16() {
  std::uint16_t hi = fetch();
  return static_cast<std::uint16_t>(hi << 8 | fetch());
}

// Ports read their pins, except in read-modify-write instructions, which read the latch.
std::uint8_t Cpu::read_sfr(std::uint8_t addr, bool rmw) {
  if (!core_sfr(addr)) sync();
  if (is_port(addr) && !rmw) return sf(addr) & port_in_[(addr >> 4) & 3];
  return sf(addr);
}

void Cpu::write_sfr(std::uint8_t addr, std::uint8_t v) {
  if (!core_sfr(addr)) {  // a peripheral's set-up, a flag or a pin may change: plan again
    sync();
    irq_dirty_ = stale_ = true;
  }
  switch (addr) {
    case sfr::SBUF:  // the transmit register; SBUF reads give the receive buffer
      tx_data_ = v;
      tx_bit8_ = (sf(sfr::SCON) & 0x08) != 0;
      tx_bits_ = -1;
      return;
    case sfr::IE:
    case sfr::IP:  // a write to IE or IP holds off the next interrupt call by one instruction
      block_ = true;
      break;
    default:
      pins_dirty_ = pins_dirty_ || is_port(addr);
      break;
  }
  sf(addr) = v;
}

std::uint8_t Cpu::read_direct(std::uint8_t addr, bool rmw) {
  return addr < 0x80 ? iram_[addr] : read_sfr(addr, rmw);
}

void Cpu::write_direct(std::uint8_t addr, std::uint8_t v) {
  if (addr < 0x80)
    iram_[addr] = v;
  else
    write_sfr(addr, v);
}

bool Cpu::read_bit(std::uint8_t bit, bool rmw) {
  std::uint8_t addr = bit < 0x80 ? static_cast<std::uint8_t>(0x20 + (bit >> 3)) : bit & 0xF8;
  return ((read_direct(addr, rmw) >> (bit & 7)) & 1) != 0;
}

void Cpu::write_bit(std::uint8_t bit, bool v) {
  std::uint8_t addr = bit < 0x80 ? static_cast<std::uint8_t>(0x20 + (bit >> 3)) : bit & 0xF8;
  std::uint8_t mask = static_cast<std::uint8_t>(1u << (bit & 7));
  std::uint8_t old = read_direct(addr, true);
  write_direct(addr, static_cast<std::uint8_t>(v ? old | mask : old & ~mask));
}

void Cpu::push(std::uint8_t v) { iram_[++sf(sfr::SP)] = v; }
std::uint8_t Cpu::pop() { return iram_[sf(sfr::SP)--]; }

void Cpu::set_cy(bool c) {
  sf(sfr::PSW) = static_cast<std::uint8_t>(c ? psw() | cy_bit : psw() & ~cy_bit);
}

void Cpu::add(std::uint8_t v, bool carry_in) {
  unsigned a = acc(), c = carry_in ? 1 : 0;
  unsigned sum = a + v + c;
  bool ac = ((a & 0x0F) + (v & 0x0F) + c) > 0x0F;
  bool c6 = ((a & 0x7F) + (v & 0x7F) + c) > 0x7F;
  bool c7 = sum > 0xFF;
  std::uint8_t p = psw() & static_cast<std::uint8_t>(~(cy_bit | ac_bit | ov_bit));
  sf(sfr::PSW) = static_cast<std::uint8_t>(p | (c7 ? cy_bit : 0) | (ac ? ac_bit : 0) |
                                           (c6 != c7 ? ov_bit : 0));
  acc() = static_cast<std::uint8_t>(sum);
}

void Cpu::subb(std::uint8_t v) {
  unsigned a = acc(), c = cy() ? 1 : 0;
  unsigned diff = a - v - c;
  bool borrow = a < v + c;
  bool ac = (a & 0x0F) < (v & 0x0F) + c;
  bool ov = ((a ^ v) & (a ^ diff) & 0x80) != 0;
  std::uint8_t p = psw() & static_cast<std::uint8_t>(~(cy_bit | ac_bit | ov_bit));
  sf(sfr::PSW) =
      static_cast<std::uint8_t>(p | (borrow ? cy_bit : 0) | (ac ? ac_bit : 0) | (ov ? ov_bit : 0));
  acc() = static_cast<std::uint8_t>(diff);
}

void Cpu::jump_rel(bool taken) {
  auto rel = static_cast<std::int8_t>(fetch());
  if (taken) pc_ = static_cast<std::uint16_t>(pc_ + rel);
}

void Cpu::cjne(std::uint8_t x, std::uint8_t y) {
  set_cy(x < y);
  jump_rel(x != y);
}

std::uint8_t Cpu::movx_read(std::uint16_t addr) {
  if (bus_ == nullptr) return xram_[addr];
  return bus_->read(addr, insn_start_ * clocks_per_cycle + movx_strobe_end);
}

void Cpu::movx_write(std::uint16_t addr, std::uint8_t v) {
  if (bus_ == nullptr)
    xram_[addr] = v;
  else
    bus_->write(addr, v, insn_start_ * clocks_per_cycle + movx_strobe_end);
}

[[gnu::always_inline]] inline void Cpu::execute(std::uint8_t op) {
  if (op < 0x80)
    execute_low(op);
  else
    execute_high(op);
}

// Opcodes 00h..7Fh.
[[gnu::always_inline]] inline void Cpu::execute_low(std::uint8_t op) {
  const unsigned col = op & 0x0F;
  if (col == 0x01) {  // AJMP / ACALL addr11
    std::uint8_t lo = fetch();
    if (op & 0x10) {
      push(static_cast<std::uint8_t>(pc_));
      push(static_cast<std::uint8_t>(pc_ >> 8));
    }
    pc_ = static_cast<std::uint16_t>((pc_ & 0xF800) | ((op >> 5) << 8) | lo);
    return;
  }
  if (col >= 4) {
    const unsigned row = op >> 4;
    // The operand of columns 4..F: #data / A, direct, @Ri, Rn.
    auto source = [&]() -> std::uint8_t {
      if (col == 4) return fetch();
      if (col == 5) return read_direct(fetch());
      if (col < 8) return iram_[r(col & 1)];
      return r(col & 7);
    };
    switch (row) {
      case 0x0:  // INC
      case 0x1:  // DEC
      {
        const int d = row == 0 ? 1 : -1;
        if (col == 4)
          acc() = static_cast<std::uint8_t>(acc() + d);
        else if (col == 5) {
          std::uint8_t addr = fetch();
          write_direct(addr, static_cast<std::uint8_t>(read_direct(addr, true) + d));
        } else if (col < 8)
          iram_[r(col & 1)] = static_cast<std::uint8_t>(iram_[r(col & 1)] + d);
        else
          r(col & 7) = static_cast<std::uint8_t>(r(col & 7) + d);
        return;
      }
      case 0x2:
        add(source(), false);
        return;
      case 0x3:
        add(source(), cy());
        return;
      case 0x4:
        acc() |= source();
        return;
      case 0x5:
        acc() &= source();
        return;
      case 0x6:
        acc() ^= source();
        return;
      case 0x7:  // MOV operand,#data
        if (col == 4) {
          acc() = fetch();
          return;
        }
        if (col == 5) {
          std::uint8_t addr = fetch();
          write_direct(addr, fetch());
          return;
        }
        if (col < 8)
          iram_[r(col & 1)] = fetch();
        else
          r(col & 7) = fetch();
        return;
      default:
        break;
    }
  }
  switch (op) {
    case 0x00:
      return;  // NOP
    case 0x02:
      pc_ = fetch16();
      return;     // LJMP
    case 0x12: {  // LCALL
      std::uint16_t target = fetch16();
      push(static_cast<std::uint8_t>(pc_));
      push(static_cast<std::uint8_t>(pc_ >> 8));
      pc_ = target;
      return;
    }
    case 0x22:    // RET
    case 0x32: {  // RETI: also ends the highest level in service and holds off the next call
      std::uint16_t hi = pop();
      pc_ = static_cast<std::uint16_t>(hi << 8 | pop());
      if (op == 0x32) {
        in_service_ = (in_service_ & 2) ? (in_service_ & 1) : 0;
        block_ = irq_dirty_ = true;
      }
      return;
    }
    case 0x03:
      acc() = std::rotr(acc(), 1);
      return;  // RR A
    case 0x23:
      acc() = std::rotl(acc(), 1);
      return;     // RL A
    case 0x13: {  // RRC A
      bool c = acc() & 1;
      acc() = static_cast<std::uint8_t>((acc() >> 1) | (cy() ? 0x80 : 0));
      set_cy(c);
      return;
    }
    case 0x33: {  // RLC A
      bool c = acc() & 0x80;
      acc() = static_cast<std::uint8_t>((acc() << 1) | (cy() ? 1 : 0));
      set_cy(c);
      return;
    }
    case 0x10: {  // JBC bit,rel
      std::uint8_t bit = fetch();
      bool set = read_bit(bit, true);
      if (set) write_bit(bit, false);
      jump_rel(set);
      return;
    }
    case 0x20:
      jump_rel(read_bit(fetch()));
      return;  // JB
    case 0x30:
      jump_rel(!read_bit(fetch()));
      return;  // JNB
    case 0x40:
      jump_rel(cy());
      return;  // JC
    case 0x50:
      jump_rel(!cy());
      return;  // JNC
    case 0x60:
      jump_rel(acc() == 0);
      return;  // JZ
    case 0x70:
      jump_rel(acc() != 0);
      return;  // JNZ
    case 0x42:
    case 0x52:
    case 0x62: {  // ORL / ANL / XRL direct,A
      std::uint8_t addr = fetch();
      std::uint8_t v = read_direct(addr, true);
      v = op == 0x42 ? v | acc() : op == 0x52 ? v & acc() : v ^ acc();
      write_direct(addr, v);
      return;
    }
    case 0x43:
    case 0x53:
    case 0x63: {  // ORL / ANL / XRL direct,#data
      std::uint8_t addr = fetch();
      std::uint8_t d = fetch();
      std::uint8_t v = read_direct(addr, true);
      v = op == 0x43 ? v | d : op == 0x53 ? v & d : v ^ d;
      write_direct(addr, v);
      return;
    }
    case 0x72: {  // ORL C,bit
      bool bit = read_bit(fetch());
      set_cy(cy() || bit);
      return;
    }
    case 0x73:
      pc_ = static_cast<std::uint16_t>(acc() + dptr());
      return;  // JMP @A+DPTR
    default:
      return;  // every opcode of 00h..7Fh is handled above
  }
}

// Opcodes 80h..FFh.
[[gnu::always_inline]] inline void Cpu::execute_high(std::uint8_t op) {
  const unsigned col = op & 0x0F;
  if (col == 0x01) {  // AJMP / ACALL
    execute_low(op);
    return;
  }
  if (col >= 5 || op == 0xB4) {
    // Rn / @Ri / direct operand of columns 5..F.
    auto ref = [&]() -> std::uint8_t& { return col < 8 ? iram_[r(col & 1)] : r(col & 7); };
    switch (op >> 4) {
      case 0x8:  // MOV direct,src
        if (col == 5) {
          std::uint8_t src = fetch();
          std::uint8_t dst = fetch();
          write_direct(dst, read_direct(src));
        } else {
          std::uint8_t dst = fetch();
          write_direct(dst, ref());
        }
        return;
      case 0x9:
        subb(col == 5 ? read_direct(fetch()) : ref());
        return;                // SUBB
      case 0xA:                // MOV dst,direct
        if (col == 5) return;  // A5h: reserved, executed as a one-cycle no-op (docs/cpu.md)
        ref() = read_direct(fetch());
        return;
      case 0xB: {  // CJNE
        if (col == 4) {
          std::uint8_t d = fetch();
          cjne(acc(), d);
        } else if (col == 5) {
          std::uint8_t d = read_direct(fetch());
          cjne(acc(), d);
        } else {
          std::uint8_t d = fetch();
          cjne(ref(), d);
        }
        return;
      }
      case 0xC: {  // XCH A,operand
        if (col == 5) {
          std::uint8_t addr = fetch();
          std::uint8_t v = read_direct(addr, true);
          write_direct(addr, acc());
          acc() = v;
        } else {
          std::uint8_t& m = ref();
          std::swap(m, acc());
        }
        return;
      }
      case 0xD:  // DJNZ / XCHD
        if (col == 6 || col == 7) {
          std::uint8_t& m = ref();
          std::uint8_t lo = m & 0x0F;
          m = static_cast<std::uint8_t>((m & 0xF0) | (acc() & 0x0F));
          acc() = static_cast<std::uint8_t>((acc() & 0xF0) | lo);
          return;
        }
        if (col == 5) {
          std::uint8_t addr = fetch();
          std::uint8_t v = static_cast<std::uint8_t>(read_direct(addr, true) - 1);
          write_direct(addr, v);
          jump_rel(v != 0);
        } else {
          std::uint8_t& m = ref();
          --m;
          jump_rel(m != 0);
        }
        return;
      case 0xE:
        acc() = col == 5 ? read_direct(fetch()) : ref();
        return;  // MOV A,src
      case 0xF:  // MOV dst,A
        if (col == 5)
          write_direct(fetch(), acc());
        else
          ref() = acc();
        return;
      default:
        break;
    }
  }
  switch (op) {
    case 0x80:
      jump_rel(true);
      return;     // SJMP
    case 0x82:    // ANL C,bit
    case 0xB0:    // ANL C,/bit
    case 0xA0: {  // ORL C,/bit
      bool bit = read_bit(fetch()) != (op != 0x82);
      set_cy(op == 0xA0 ? cy() || bit : cy() && bit);
      return;
    }
    case 0x83:
      acc() = code_[static_cast<std::uint16_t>(acc() + pc_)];
      return;  // MOVC @A+PC
    case 0x93:
      acc() = code_[static_cast<std::uint16_t>(acc() + dptr())];
      return;     // @A+DPTR
    case 0x84: {  // DIV AB
      std::uint8_t p = psw() & static_cast<std::uint8_t>(~(cy_bit | ov_bit));
      if (b() == 0) {
        p |= ov_bit;  // A and B are undefined by the manual; the model keeps them
      } else {
        std::uint8_t q = acc() / b(), rem = acc() % b();
        acc() = q;
        sf(sfr::B) = rem;
      }
      sf(sfr::PSW) = p;
      return;
    }
    case 0xA4: {  // MUL AB
      unsigned prod = unsigned{acc()} * b();
      acc() = static_cast<std::uint8_t>(prod);
      sf(sfr::B) = static_cast<std::uint8_t>(prod >> 8);
      std::uint8_t p = psw() & static_cast<std::uint8_t>(~(cy_bit | ov_bit));
      sf(sfr::PSW) = static_cast<std::uint8_t>(p | (prod > 0xFF ? ov_bit : 0));
      return;
    }
    case 0x90: {  // MOV DPTR,#data16
      sf(sfr::DPH) = fetch();
      sf(sfr::DPL) = fetch();
      return;
    }
    case 0x92:
      write_bit(fetch(), cy());
      return;  // MOV bit,C
    case 0xA2:
      set_cy(read_bit(fetch()));
      return;     // MOV C,bit
    case 0xA3: {  // INC DPTR
      auto d = static_cast<std::uint16_t>(dptr() + 1);
      sf(sfr::DPH) = static_cast<std::uint8_t>(d >> 8);
      sf(sfr::DPL) = static_cast<std::uint8_t>(d);
      return;
    }
    case 0xB2: {  // CPL bit
      std::uint8_t bit = fetch();
      write_bit(bit, !read_bit(bit, true));
      return;
    }
    case 0xB3:
      set_cy(!cy());
      return;     // CPL C
    case 0xC0: {  // PUSH direct
      std::uint8_t v = read_direct(fetch());
      push(v);
      return;
    }
    case 0xD0: {  // POP direct
      std::uint8_t addr = fetch();
      std::uint8_t v = pop();
      write_direct(addr, v);
      return;
    }
    case 0xC2:
      write_bit(fetch(), false);
      return;  // CLR bit
    case 0xC3:
      set_cy(false);
      return;  // CLR C
    case 0xD2:
      write_bit(fetch(), true);
      return;  // SETB bit
    case 0xD3:
      set_cy(true);
      return;  // SETB C
    case 0xC4:
      acc() = std::rotl(acc(), 4);
      return;     // SWAP A
    case 0xD4: {  // DA A
      unsigned t = acc();
      bool c = cy();
      if ((t & 0x0F) > 9 || (psw() & ac_bit)) t += 0x06;
      if (t > 0xFF) c = true;
      if (((t >> 4) & 0x0F) > 9 || c) t += 0x60;
      if (t > 0xFF) c = true;
      acc() = static_cast<std::uint8_t>(t);
      set_cy(c);
      return;
    }
    case 0xE0:
      acc() = movx_read(dptr());
      return;  // MOVX A,@DPTR
    case 0xF0:
      movx_write(dptr(), acc());
      return;  // MOVX @DPTR,A
    case 0xE2:
    case 0xE3:  // MOVX A,@Ri: P2 drives the high address byte
      acc() = movx_read(static_cast<std::uint16_t>(sf(sfr::P2) << 8 | r(op & 1)));
      return;
    case 0xF2:
    case 0xF3:
      movx_write(static_cast<std::uint16_t>(sf(sfr::P2) << 8 | r(op & 1)), acc());
      return;
    case 0xE4:
      acc() = 0;
      return;  // CLR A
    case 0xF4:
      acc() = static_cast<std::uint8_t>(~acc());
      return;  // CPL A
    case 0x94:
      subb(fetch());
      return;  // SUBB A,#data
    default:
      return;  // every opcode of 80h..FFh is handled above
  }
}

template <unsigned Op>
void Cpu::op_fn(Cpu& cpu) {
  cpu.execute(static_cast<std::uint8_t>(Op));
}

template <std::size_t... Op>
constexpr std::array<Cpu::OpFn, 256> Cpu::make_dispatch(std::index_sequence<Op...>) {
  return {&Cpu::op_fn<Op>...};
}

const std::array<Cpu::OpFn, 256> Cpu::dispatch_ = make_dispatch(std::make_index_sequence<256>{});

// One instruction on the quiet path, here beside the instructions so that it inlines them; the
// rest goes to slow_step (peripherals.cpp).
[[gnu::always_inline]] inline StepResult Cpu::advance() {
  const std::uint8_t op = code_[pc_];
  const unsigned n = cycle_table[op];
  if (cycles_ + n > horizon_) return slow_step();
  // Quiet: no peripheral can raise a new request within the instruction, so its cycles are only
  // counted; an SFR access of the instruction syncs them first (all of them, or all but a MOVX's
  // second, as slow_step orders them).
  ++pc_;
  if (!is_movx(op)) {
    cycles_ += n;
    lag_ += n;
    dispatch_[op](*this);
  } else {
    insn_start_ = cycles_;
    ++cycles_;
    ++lag_;
    dispatch_[op](*this);
    if (stale_) {  // the access changed a pin: its last cycle samples it
      sync();
      tick(1);
    } else {
      ++cycles_;
      ++lag_;
    }
  }
  set_parity();
  if (irq_dirty_) poll_after(last_req_);
  if (stale_ || irq_dirty_) replan();
  return {StepKind::instruction, n};
}

StepResult Cpu::step() {
  const StepResult r = advance();
  sync();
  return r;
}

std::uint64_t Cpu::run(std::uint64_t cycles) {
  std::uint64_t done = 0;
  while (done < cycles) done += advance().cycles;
  sync();
  return done;
}

unsigned Cpu::next_step_cycles() const {
  if (powered_down() || idle()) return 1;
  if (next_irq_ >= 0) return 2;
  return cycle_table[code_[pc_]];
}

std::uint64_t Cpu::run_within(std::uint64_t end) {
  run_end_ = end;
  const std::uint64_t from = cycles_;
  for (;;) {
    if (cycles_ < idle_until_) {  // quiet idle cycles (replan): counted at once
      const std::uint64_t to = std::min(idle_until_, run_end_);
      if (to <= cycles_) break;
      lag_ += to - cycles_;
      cycles_ = to;
      continue;
    }
    if (cycles_ + next_step_cycles() > run_end_) break;
    advance();
  }
  sync();
  return cycles_ - from;
}

}  // namespace mcs51
