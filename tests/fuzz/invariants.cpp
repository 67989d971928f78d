#include "invariants.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "harness.hpp"
#include "scenario.hpp"

namespace dpc31::fuzz {

namespace {

constexpr std::uint16_t kGo_Leave_Data_Exchange = 1u << 1;
constexpr std::uint8_t kEOI = 0x02;                // Mode_Reg1 bit 1
constexpr std::uint16_t kINT_Pol = 1u << 4;        // Mode_Reg0
constexpr std::uint16_t kEOI_Time_Base = 1u << 9;  // Mode_Reg0
constexpr std::size_t kKeepChars = 300;            // more than the longest frame (255)
// Gap (whole idle bit times) that certainly ends a telegram: TSYN is 33; one bit of slack for
// where the chip's receiver counts idle from (its configure cycle may lie half a bit earlier).
constexpr std::uint64_t kGapEnds = 34;

std::uint8_t sum(const std::uint8_t* b, std::size_t n) {
  unsigned s = 0;
  for (std::size_t i = 0; i < n; ++i) s += b[i];
  return static_cast<std::uint8_t>(s);
}

// The swap groups of pointer cells (the ASIC exchanges cells only within a group).
const std::vector<std::vector<RegId>>& swap_groups() {
  static const std::vector<std::vector<RegId>> g = {
      {RegId::R_Dout_Buf_Ptr1, RegId::R_Dout_Buf_Ptr2, RegId::R_Dout_Buf_Ptr3,
       RegId::R_Dout_Buf_Ptr_C},
      {RegId::R_Din_Buf_Ptr1, RegId::R_Din_Buf_Ptr2, RegId::R_Din_Buf_Ptr3},
      {RegId::R_Diag_Buf_Ptr1, RegId::R_Diag_Buf_Ptr2},
      {RegId::R_Aux_Buf_Ptr1, RegId::R_Aux_Buf_Ptr2, RegId::R_Prm_Buf_Ptr, RegId::R_Cfg_Buf_Ptr,
       RegId::R_Read_Cfg_Buf_Ptr, RegId::R_SSA_Buf_Ptr},
  };
  return g;
}

// A ring's state byte: F 7:6 (unless `no_f`), U 5:4, N 3:2, D 1:0.
std::string ring_problem(std::uint16_t sm, bool no_f) {
  const unsigned d = sm & 3, n = (sm >> 2) & 3, u = (sm >> 4) & 3, f = (sm >> 6) & 3;
  if (d == 0) return "D is Nil";
  if (u == 0) return "U is Nil";
  unsigned seen = 0;
  for (unsigned b : {d, n, u, no_f ? 0u : f}) {
    if (b == 0) continue;
    if ((seen & (1u << b)) != 0) return fmt::format("buffer {} named twice", b);
    seen |= 1u << b;
  }
  return {};
}

}  // namespace

bool valid_request_frame(const std::uint8_t* b, std::size_t n) {
  if (n == 0) return false;
  std::size_t fc_at = 3;
  std::size_t body = 0, len = 0;  // FCS covers b[body .. body+len)
  switch (b[0]) {
    case 0x10:  // SD1: SD DA SA FC FCS ED
      if (n != 6) return false;
      body = 1;
      len = 3;
      break;
    case 0xA2:  // SD3: SD DA SA FC DU(8) FCS ED
      if (n != 14) return false;
      body = 1;
      len = 11;
      break;
    case 0x68: {  // SD2: SD LE LEr SD DA SA FC DU FCS ED
      if (n < 9 || b[3] != 0x68 || b[1] != b[2]) return false;
      const std::size_t le = b[1];
      if (le < 4 || le > 249 || n != le + 6) return false;
      body = 4;
      len = le;
      fc_at = 6;
      break;
    }
    default:
      return false;
  }
  if (b[n - 1] != 0x16 || b[n - 2] != sum(b + body, len)) return false;
  return (b[fc_at] & 0x40) != 0;  // a request (a slave answers nothing else)
}

InvariantChecker::InvariantChecker(Report report) : report_(std::move(report)) {}

void InvariantChecker::fail(const std::string& what) {
  ++violations_;
  const std::string msg = fmt::format("invariant violated at cycle {}: {}",
                                      chip_ != nullptr ? chip_->cycle() : 0, what);
  if (report_) {
    report_(msg);
    return;
  }
  std::fprintf(stderr, "%s\n", msg.c_str());
  std::abort();
}

void InvariantChecker::attach(Chip& chip, bool line_idle) {
  chip_ = &chip;
  line_idle_ = line_idle;
  mode1_s_ = static_cast<std::uint32_t>(chip.addr_of(RegId::Mode_Reg1_S));
  prm_ok_addr_ = chip.addr_of(RegId::User_Prm_Data_Okay);
  cfg_ok_addr_ = chip.addr_of(RegId::User_Cfg_Data_Okay);
  new_din_addr_ = chip.addr_of(RegId::New_Din_Buffer_Cmd);
  // The one piece of internal state read: an EOI inactive time already running at attach.
  eoi_until_ = chip.eoi_inactive_until();
  reported_ = chip.irq_active();
  dp_ = chip.dp_state();
  started_ = chip.started();
  groups_.clear();
  group_base_.clear();
  for (const auto& g : swap_groups()) {
    std::vector<std::uint32_t> addrs;
    for (RegId id : g) {
      const std::int32_t a = chip.addr_of(id);
      if (a >= 0) addrs.push_back(static_cast<std::uint32_t>(a));
    }
    groups_.push_back(std::move(addrs));
  }
  for (std::size_t g = 0; g < groups_.size(); ++g) group_base_.push_back(group_values(int(g)));
  group_written_.assign(groups_.size(), false);
  rx_t_ = chip.bit_cycles();
  rx_.configure(rx_t_, chip.cycle());
  attached_at_ = chip.cycle();
  chip.on_irq_change([this](std::uint64_t, bool active) { reported_ = active; });
  chip.on_rxd([this](std::uint64_t c, bool l) { on_rxd(c, l); });
  chip.on_telegram([this](const Telegram& t) {
    if (t.from_chip) on_answer(t);
  });
  harness::on_block_event(chip, [this](std::uint64_t, const BlockEvent& e) { on_block(e); });
  chip.on_state_change([this](std::uint64_t) { check(); });
}

std::vector<std::uint8_t> InvariantChecker::group_values(int g) const {
  std::vector<std::uint8_t> v;
  for (std::uint32_t a : groups_[static_cast<std::size_t>(g)]) v.push_back(chip_->peek(a));
  std::sort(v.begin(), v.end());
  return v;
}

void InvariantChecker::on_block(const BlockEvent& e) {
  using K = BlockEvent::Kind;
  const std::uint32_t mask = (1u << chip_->profile().address_bits) - 1;
  const std::uint32_t a = e.value & mask;
  if (e.kind == K::write) {
    if (a == mode1_s_ && (e.data & kEOI) != 0) {
      // The inactive time of docs/timing.md: ceil(1 us or 1 ms x f), from the write's completion.
      const std::uint64_t us = (chip_->peek_reg(RegId::Mode_Reg0) & kEOI_Time_Base) != 0 ? 1000 : 1;
      eoi_until_ = chip_->cycle() + (us * chip_->clock_hz() + 999'999) / 1'000'000;
    }
    for (std::size_t g = 0; g < groups_.size(); ++g) {
      for (std::uint32_t c : groups_[g]) {
        if (c == a) group_written_[g] = true;
      }
    }
  } else if (e.kind == K::read) {
    if (static_cast<std::int32_t>(a) == prm_ok_addr_) prm_ok_read_ = true;
    if (static_cast<std::int32_t>(a) == cfg_ok_addr_) cfg_ok_read_ = cfg_ok_given_ = true;
    if (static_cast<std::int32_t>(a) == new_din_addr_) new_din_read_ = true;
  } else if (e.kind == K::cfg || e.kind == K::prm) {
    cfg_accepted_ = e.kind == K::cfg;
    cfg_ok_given_ = false;  // a new telegram needs its verdict again
  }
}

void InvariantChecker::check() {
  if (chip_ == nullptr) return;
  ++checks_;
  sync_rx();
  check_xint();
  check_buffers();
  check_dp();
  prm_ok_read_ = cfg_ok_read_ = cfg_accepted_ = new_din_read_ = false;
}

void InvariantChecker::check_xint() {
  const std::uint16_t irr = chip_->peek_reg(RegId::Int_Req_Reg);
  const std::uint16_t imr = chip_->peek_reg(RegId::Int_Mask_Reg);
  const std::uint16_t ir = static_cast<std::uint16_t>(irr & ~imr);
  const bool want = ir != 0 && chip_->cycle() >= eoi_until_;
  const bool high_active = (chip_->peek_reg(RegId::Mode_Reg0) & kINT_Pol) != 0;
  const bool pin_want = high_active ? want : !want;
  if (chip_->irq_active() != want || chip_->x_int_pin() != pin_want || reported_ != want) {
    fail(fmt::format(
        "X/INT: IRR={:04X} IMR={:04X} IR={:04X}, EOI inactive until {}: expected {} (pin {}), "
        "chip says active={} pin={} last reported={}",
        irr, imr, ir, eoi_until_, want ? "active" : "inactive", pin_want ? 1 : 0,
        chip_->irq_active(), chip_->x_int_pin() ? 1 : 0, reported_));
  }
}

void InvariantChecker::check_buffers() {
  const bool dpc31 = chip_->profile().id == Profile::dpc31;
  // dpc31: Dout_Buffer_SM bit 7 is N_Cl and F is not shown (docs/decisions.md).
  const std::uint16_t dout = chip_->peek_reg(RegId::Dout_Buffer_SM);
  std::string p =
      ring_problem(dpc31 ? (dout & (fields::Dout_Buffer_SM::D | fields::Dout_Buffer_SM::N |
                                    fields::Dout_Buffer_SM::U))
                         : dout,
                   dpc31);
  if (!p.empty()) fail(fmt::format("Dout_Buffer_SM {:02X}: {}", dout, p));
  const std::uint16_t din = chip_->peek_reg(RegId::Din_Buffer_SM);
  p = ring_problem(din, false);
  if (!p.empty()) fail(fmt::format("Din_Buffer_SM {:02X}: {}", din, p));
  const std::uint16_t diag = chip_->peek_reg(RegId::Diag_Buffer_SM);
  const unsigned d1 = diag & 3, d2 = (diag >> 2) & 3;
  if (d1 == d2 && (d1 == 1 || d1 == 3)) {
    fail(fmt::format("Diag_Buffer_SM {:02X}: both diag buffers {}", diag,
                     d1 == 1 ? "with the user" : "being sent"));
  }
  for (std::size_t g = 0; g < groups_.size(); ++g) {
    std::vector<std::uint8_t> now = group_values(static_cast<int>(g));
    if (!group_written_[g] && now != group_base_[g]) {
      fail(
          fmt::format("pointer cells of group {} changed from {:02X} to {:02X} without a user "
                      "write (the ASIC may only swap them)",
                      g, fmt::join(group_base_[g], " "), fmt::join(now, " ")));
    }
    group_base_[g] = std::move(now);
    group_written_[g] = false;
  }
}

void InvariantChecker::check_dp() {
  const DpState now = chip_->dp_state();
  const bool started = chip_->started();
  const DpState was = dp_;
  const bool was_started = started_;
  dp_ = now;
  started_ = started;
  if (now == was) return;
  bool ok = false;
  const char* why = "";
  if (now == DpState::Wait_Prm) cfg_ok_given_ = false;
  if (now == DpState::Wait_Prm) {
    ok = true;  // Leave_Master, Go_Offline, Not_OK, watchdogs: from anywhere
  } else if (was == DpState::Wait_Prm && now == DpState::Wait_Cfg) {
    ok = prm_ok_read_;
    why = "without a User_Prm_Data_Okay read";
  } else if (was == DpState::Wait_Cfg && now == DpState::Data_Exchange) {
    // SPC3 with a Din buffer: at the first New_Din_Buffer_Cmd after Cfg OK (docs/decisions.md).
    ok = cfg_ok_read_ || (chip_->profile().id == Profile::spc3 && new_din_read_ && cfg_ok_given_);
    why = "without a User_Cfg_Data_Okay read (SPC3: or a New_Din_Buffer_Cmd after one)";
  } else if (was == DpState::Data_Exchange && now == DpState::Wait_Cfg) {
    ok = cfg_accepted_;
    why = "without an accepted Chk_Cfg";
  } else {
    why = "is not a documented transition";
  }
  if (!ok) fail(fmt::format("DP state {} -> {} {}", dp_state_name(was), dp_state_name(now), why));
  const bool leaves_offline = was_started && !started;
  if ((was == DpState::Data_Exchange || now == DpState::Data_Exchange) && !leaves_offline &&
      (chip_->peek_reg(RegId::Int_Req_Reg) & kGo_Leave_Data_Exchange) == 0) {
    fail(fmt::format("DP state {} -> {} without Go_Leave_Data_Exchange in Int_Req_Reg",
                     dp_state_name(was), dp_state_name(now)));
  }
}

void InvariantChecker::on_rxd(std::uint64_t cycle, bool level) {
  edges_.emplace_back(cycle, level);
}

void InvariantChecker::sync_rx() {
  const std::uint64_t now = chip_->cycle();
  while (!edges_.empty() && edges_.front().first <= now) {
    rx_.edge(edges_.front().first, edges_.front().second);
    edges_.pop_front();
  }
  scratch_.clear();
  rx_.advance(now, scratch_);
  for (const UartChar& c : scratch_) {
    chars_.push_back({c.data, c.parity_ok, c.end, c.idle_bits, seq_++, epoch_});
    if (chars_.size() > kKeepChars) chars_.pop_front();
  }
  // Follow the chip's rate (Baud_Search windows, Start): a reconfigure drops what is in progress,
  // as the chip's receiver does at the same cycle.
  const std::uint32_t t = chip_->bit_cycles();
  if (t != rx_t_) {
    rx_t_ = t;
    rx_.configure(t, now);
    ++epoch_;
  }
}

void InvariantChecker::on_answer(const Telegram& t) {
  if (chip_ == nullptr) return;
  sync_rx();
  // The characters that ended before the answer starts; the request must be the last of them.
  std::size_t j = chars_.size();
  while (j > 0 && chars_[j - 1].end > t.start) --j;
  // Nothing seen yet, or a chain back to the first character since attach without the line
  // provably idle before it: the request may have begun before the checker was watching.
  const std::uint64_t frame_time = (255ull * kUartCharBits + 100) * chip_->bit_cycles();
  if (j == 0) {
    if (!line_idle_ && t.start < attached_at_ + frame_time) {
      ++unjudged_;
      return;
    }
    ++answers_;
    fail(fmt::format("the chip sent {:02X} at {} with no request received before it",
                     fmt::join(t.bytes, " "), t.start));
    return;
  }
  ++answers_;
  std::vector<std::uint8_t> bytes;
  bool parity = true;
  // Candidate requests: chars i..j-1 without a telegram-ending gap inside, all parity-good,
  // forming a valid frame. One is enough (the checker does not pin down TSYN to the bit).
  std::size_t i = j;
  while (i-- > 0 && j - i <= 255) {
    if (!chars_[i].parity_ok) parity = false;
    if (parity) {
      bytes.clear();
      for (std::size_t k = i; k < j; ++k) bytes.push_back(chars_[k].data);
      if (valid_request_frame(bytes.data(), bytes.size())) return;
    }
    if (chars_[i].idle_bits >= kGapEnds) break;  // chars before i belong to an earlier telegram
    if (i > 0 && chars_[i - 1].epoch != chars_[i].epoch) break;
    if (chars_[i].seq == 0 && !line_idle_) {  // the first since attach, maybe mid-telegram
      --answers_;
      ++unjudged_;
      return;
    }
  }
  std::string seen;
  for (std::size_t k = j >= 16 ? j - 16 : 0; k < j; ++k) {
    seen += fmt::format(" {:02X}{}{}", chars_[k].data, chars_[k].parity_ok ? "" : "(parity!)",
                        chars_[k].idle_bits >= kGapEnds ? "(after gap)" : "");
  }
  fail(
      fmt::format("the chip answered {:02X} at {}, but the characters before it do not end in a "
                  "valid request frame (parity, FCS, ED, length):{}",
                  fmt::join(t.bytes, " "), t.start, seen));
}

}  // namespace dpc31::fuzz
