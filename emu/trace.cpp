// Golden traces: recorder, parser and replay. The format: docs/trace-format.md.
#include "trace.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <limits>
#include <span>

#include "dp_services.hpp"
#include "fdl.hpp"
#include "textfile.hpp"

namespace dpc31 {

namespace {

constexpr std::size_t kMaxFileBytes = 64u << 20;
constexpr std::uint64_t kMaxCycle = std::uint64_t{1} << 62;
constexpr std::uint32_t kMaxClock = 200'000'000;

std::string hex_bytes(std::span<const std::uint8_t> b) {
  std::string s;
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (i != 0) s += ' ';
    s += fmt::format("{:02X}", b[i]);
  }
  return s;
}

std::string_view fault_kind_name(UartFault::Kind k) {
  switch (k) {
    case UartFault::Kind::parity:
      return "parity";
    case UartFault::Kind::start:
      return "start";
    case UartFault::Kind::stop:
      return "stop";
    case UartFault::Kind::none:
      break;
  }
  return "none";
}

// The FdlCounters that are not 0, "name:N,name:N", or "-".
std::string counters_text(const FdlCounters& c) {
  std::string s;
  for (const CounterField& f : fdl_counter_fields()) {
    const std::uint32_t v = c.*(f.member);
    if (v == 0) continue;
    if (!s.empty()) s += ',';
    s += fmt::format("{}:{}", f.name, v);
  }
  return s.empty() ? "-" : s;
}

// The chip's state as a `state` line's keys, in the order the recorder writes them.
std::vector<TraceStateKey> chip_state(const Chip& c) {
  return {
      {"dp", std::string(dp_state_name(c.dp_state()))},
      {"wd", std::string(wd_state_name(c.wd_state()))},
      {"status", fmt::format("{:04X}", c.peek_reg(RegId::Status_Reg))},
      {"irr", fmt::format("{:04X}", c.peek_reg(RegId::Int_Req_Reg))},
      {"imr", fmt::format("{:04X}", c.peek_reg(RegId::Int_Mask_Reg))},
      {"station", std::to_string(c.station_address())},
      {"fdl", counters_text(c.fdl_counters())},
  };
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::vector<std::string_view> words(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && is_space(s[i])) ++i;
    std::size_t k = i;
    while (k < s.size() && !is_space(s[k])) ++k;
    if (k > i) out.push_back(s.substr(i, k - i));
    i = k;
  }
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// RxD batches

std::string format_rxd(std::uint64_t fed, const std::vector<std::pair<std::uint64_t, bool>>& edges,
                       std::uint32_t t) {
  const auto raw = [&] {
    std::string s = fmt::format("rxd {}", fed);
    for (const auto& [c, l] : edges) s += fmt::format(" {}:{}", c, l ? 1 : 0);
    return s;
  };
  if (edges.empty() || edges.front().second || t == 0) return raw();
  const std::uint64_t s = edges.front().first;
  const std::uint64_t ch = std::uint64_t{kUartCharBits} * t;
  // The line level at `at`: the last edge at or before it; high before the first.
  const auto level_at = [&](std::uint64_t at) {
    const auto it = std::upper_bound(
        edges.begin(), edges.end(), at,
        [](std::uint64_t v, const std::pair<std::uint64_t, bool>& e) { return v < e.first; });
    return it == edges.begin() ? true : std::prev(it)->second;
  };
  const std::uint64_t n0 = (edges.back().first - s) / ch + 1;
  for (std::uint64_t n = n0; n >= 1 && n + 1 >= n0; --n) {
    std::vector<std::uint8_t> bytes;
    std::vector<UartFault> anomalies;
    for (std::uint64_t i = 0; i < n; ++i) {
      std::uint16_t bits = 0;
      for (std::uint32_t k = 0; k < kUartCharBits; ++k) {
        if (level_at(s + i * ch + std::uint64_t{k} * t + t / 2)) {
          bits = static_cast<std::uint16_t>(bits | (1u << k));
        }
      }
      const auto d = static_cast<std::uint8_t>(bits >> 1);
      bytes.push_back(d);
      const int idx = static_cast<int>(i);
      if ((bits & 1) != 0) anomalies.push_back({idx, UartFault::Kind::start});
      if (((bits >> 9) & 1) != even_parity(d)) anomalies.push_back({idx, UartFault::Kind::parity});
      if (((bits >> 10) & 1) == 0) anomalies.push_back({idx, UartFault::Kind::stop});
    }
    if (anomalies.size() > 1) continue;
    const UartFault fault = anomalies.empty() ? UartFault{} : anomalies.front();
    std::vector<std::pair<std::uint64_t, bool>> enc;
    uart_encode(bytes, s, t, enc, fault);
    if (enc != edges) continue;
    std::string line = fmt::format("rx {} {}", s, hex_bytes(bytes));
    if (fault.kind != UartFault::Kind::none) {
      line += fmt::format(" fault={}:{}", fault_kind_name(fault.kind), fault.char_index);
    }
    if (fed != s) line += fmt::format(" fed={}", fed);
    return line;
  }
  return raw();
}

// ---------------------------------------------------------------------------------------------
// Recorder

TraceRecorder::TraceRecorder(std::uint32_t baud, std::vector<std::string> notes)
    : baud_(baud), notes_(std::move(notes)) {}

void TraceRecorder::attach(Chip& chip) {
  chip_ = &chip;
  if (chip.cycle() != 0) {
    error_ = fmt::format("the recording must start at cycle 0, not {}", chip.cycle());
  }
  header_.emplace_back(kTraceMagic);
  for (const std::string& n : notes_) header_.push_back(n.empty() ? "#" : "# " + n);
  header_.push_back(fmt::format("profile {}", profile_name(chip.profile().id)));
  if (chip.vpc3_variant()) {
    header_.push_back(fmt::format("variant {}", vpc3_variant_name(*chip.vpc3_variant())));
  }
  header_.push_back(
      fmt::format("bus {}", chip.bus_mode() == BusMode::intel ? "intel" : "motorola"));
  header_.push_back(fmt::format("clock {}", chip.clock_hz()));
  header_.push_back(fmt::format("baud {}", baud_));

  chip.on_bus_access([this](std::uint64_t cycle, const BusAccess& e) {
    if (e.write) {
      add(cycle, fmt::format("wr {} {:04X} {:02X}", cycle, e.addr, e.data));
    } else {
      // Emitted when the access completes, just before it acts: peek gives what it returns
      // (a command read's result included). The replay holds the two to account.
      add(cycle, fmt::format("rd {} {:04X} = {:02X}", cycle, e.addr, chip_->peek(e.addr)));
    }
  });
  chip.on_irq_change([this](std::uint64_t cycle, bool active) {
    add(cycle, fmt::format("xint {} {}", cycle, active ? 1 : 0));
  });
  chip.on_telegram([this](const Telegram& t) {
    if (!t.from_chip) return;  // received ones are recorded from RxD, edge by edge
    add(t.start, fmt::format("tx {} {} {}", t.start, t.end, hex_bytes(t.bytes)));
  });
  chip.on_rxd([this](std::uint64_t cycle, bool level) {
    if (finished_) return;
    if (closing_) close_segment();
    const std::uint64_t fed = chip_->cycle();
    if (!rxd_.empty() && fed != rxd_fed_) close_rxd();
    rxd_fed_ = fed;
    rxd_.emplace_back(cycle, level);
  });
}

void TraceRecorder::add(std::uint64_t key, std::string text) {
  if (finished_) {
    if (error_.empty()) error_ = fmt::format("an event at cycle {} after the end", key);
    return;
  }
  if (closing_) close_segment();
  close_rxd();
  seg_.push_back(Entry{key, std::move(text)});
}

void TraceRecorder::close_rxd() {
  if (rxd_.empty()) return;
  const std::uint32_t t = chip_ != nullptr ? bit_cycles(chip_->clock_hz(), baud_) : 0;
  seg_.push_back(Entry{rxd_fed_, format_rxd(rxd_fed_, rxd_, t)});
  rxd_.clear();
}

void TraceRecorder::heading(std::string text) { headings_.push_back(std::move(text)); }

void TraceRecorder::note(std::uint64_t cycle, std::string text) {
  seg_.push_back(Entry{cycle, "# " + std::move(text)});
}

std::string TraceRecorder::state_line() const {
  std::string s = fmt::format("state {}", chip_->cycle());
  for (const TraceStateKey& k : chip_state(*chip_)) s += fmt::format(" {}={}", k.key, k.value);
  return s;
}

void TraceRecorder::close_segment() {
  close_rxd();
  closing_ = false;
  std::stable_sort(seg_.begin(), seg_.end(),
                   [](const Entry& a, const Entry& b) { return a.key < b.key; });
  for (const std::string& h : headings_) body_.push_back("# " + h);
  for (const Entry& e : seg_) {
    const bool comment = e.text.starts_with('#');
    if (e.key < last_key_ && !comment && error_.empty()) {
      error_ = fmt::format("'{}' is out of cycle order (after cycle {})", e.text, last_key_);
    }
    if (!comment) last_key_ = std::max(last_key_, e.key);
    body_.push_back(e.text);
  }
  headings_.clear();
  seg_.clear();
  if (pending_state_) {
    const auto& [cycle, line] = *pending_state_;
    if (cycle < last_key_ && error_.empty()) {
      error_ = fmt::format("'{}' is out of cycle order (after cycle {})", line, last_key_);
    }
    last_key_ = std::max(last_key_, cycle);
    if (line != last_state_) body_.push_back(line);
    last_state_ = line;
    pending_state_.reset();
  }
}

void TraceRecorder::checkpoint() {
  if (chip_ == nullptr || finished_) return;
  close_rxd();
  pending_state_.emplace(chip_->cycle(), state_line());
  close_segment();
}

void TraceRecorder::finish() {
  if (chip_ == nullptr || finished_) return;
  if (closing_) close_segment();
  checkpoint();
  body_.push_back(fmt::format("end {}", chip_->cycle()));
  finished_ = true;
}

std::string TraceRecorder::text() const {
  std::string s;
  for (const std::string& l : header_) s += l + '\n';
  for (const std::string& l : body_) s += l + '\n';
  return s;
}

ScenarioHooks TraceRecorder::scenario_hooks() {
  ScenarioHooks h;
  h.at_start = [this](Chip& c) { attach(c); };
  h.at_end = [this](Chip&) { finish(); };
  return h;
}

LineSink TraceRecorder::scenario_walk(const Scenario& s, LineSink forward) {
  return [this, &s, forward = std::move(forward)](const std::string& line) {
    if (forward) forward(line);
    walk_line(s, line);
  };
}

// The runner prints its walk at the end of every step ("flush"), with the chip standing still:
// the step's own line ("line K: ...") marks a checkpoint, the other lines become notes at their
// cycles. The segment is closed when the next chip event (of the next step) comes in.
void TraceRecorder::walk_line(const Scenario& s, const std::string& line) {
  if (chip_ == nullptr || finished_ || !line.starts_with("[cycle ")) return;
  const std::size_t close = line.find("] ");
  if (close == std::string::npos) return;
  std::uint64_t cycle = 0;
  const std::string_view num = std::string_view(line).substr(7, close - 7);
  const std::size_t first = num.find_first_not_of(' ');
  if (first == std::string_view::npos) return;
  const auto [p, ec] = std::from_chars(num.data() + first, num.data() + num.size(), cycle);
  if (ec != std::errc() || p != num.data() + num.size()) return;
  const std::string text = line.substr(close + 2);

  const auto mark = [&](std::string heading) {
    if (closing_) close_segment();  // the previous step left no event: close it now
    close_rxd();
    headings_.push_back(std::move(heading));
    pending_state_.emplace(chip_->cycle(), state_line());
    closing_ = true;
  };
  if (text.starts_with("line ")) {
    int no = 0;
    const auto [q, e2] = std::from_chars(text.data() + 5, text.data() + text.size(), no);
    if (e2 == std::errc() && q != text.data() + text.size() && *q == ':') {
      const auto it = std::find_if(s.steps.begin(), s.steps.end(),
                                   [&](const ScenarioStep& st) { return st.line == no; });
      if (it != s.steps.end()) {
        mark(text);
        return;
      }
    }
  }
  if (text.starts_with("started:")) {
    mark("firmware init (the built-in user side): registers, buffers, Start_SPC3; " + text);
    return;
  }
  if (text.starts_with("end:")) return;
  seg_.push_back(Entry{cycle, "# " + text});
}

// ---------------------------------------------------------------------------------------------
// Parser

std::string TraceError::text() const {
  if (line <= 0) return fmt::format("{}: {}", file, message);
  return fmt::format("{}:{}: {}", file, line, message);
}

namespace {

struct Fail {
  std::string message;
};

[[noreturn]] void fail(std::string msg) { throw Fail{std::move(msg)}; }

std::uint64_t dec(std::string_view s, std::string_view what) {
  std::uint64_t v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 10);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v > kMaxCycle) {
    fail(fmt::format("bad {} '{}' (a decimal number)", what, shown(s)));
  }
  return v;
}

std::uint32_t hexnum(std::string_view s, std::size_t max_digits, std::string_view what) {
  std::uint32_t v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 16);
  if (s.empty() || s.size() > max_digits || ec != std::errc() || p != s.data() + s.size()) {
    fail(fmt::format("bad {} '{}' (up to {} hex digits)", what, shown(s), max_digits));
  }
  return v;
}

std::uint8_t hexbyte(std::string_view s, std::string_view what) {
  return static_cast<std::uint8_t>(hexnum(s, 2, what));
}

void arity(const std::vector<std::string_view>& w, std::size_t n, std::string_view form) {
  if (w.size() != n) fail(fmt::format("expected '{}'", form));
}

// Canonical form of a `state` value (hex upper case, counters in declaration order).
std::string state_value(std::string_view key, std::string_view v) {
  if (key == "dp") {
    for (DpState s : {DpState::Wait_Prm, DpState::Wait_Cfg, DpState::Data_Exchange}) {
      if (v == dp_state_name(s)) return std::string(v);
    }
    fail(fmt::format("unknown dp state '{}' (Wait_Prm, Wait_Cfg, Data_Exchange)", shown(v)));
  }
  if (key == "wd") {
    for (WdState s : {WdState::Baud_Search, WdState::Baud_Control, WdState::DP_Control}) {
      if (v == wd_state_name(s)) return std::string(v);
    }
    fail(fmt::format("unknown wd state '{}' (Baud_Search, Baud_Control, DP_Control)", shown(v)));
  }
  if (key == "status" || key == "irr" || key == "imr") {
    return fmt::format("{:04X}", hexnum(v, 4, key));
  }
  if (key == "station") {
    const std::uint64_t n = dec(v, "station");
    if (n > 127) fail(fmt::format("station {} out of range (0..127)", n));
    return std::to_string(n);
  }
  if (key == "fdl") {
    FdlCounters c;
    if (v != "-") {
      std::string_view rest = v;
      while (!rest.empty()) {
        const std::size_t comma = rest.find(',');
        const std::string_view item = rest.substr(0, comma);
        rest = comma == std::string_view::npos ? std::string_view{} : rest.substr(comma + 1);
        const std::size_t colon = item.find(':');
        if (colon == std::string_view::npos) {
          fail(fmt::format("bad counter '{}' in fdl= (name:N, separated by commas)", shown(item)));
        }
        const auto fields = fdl_counter_fields();
        const auto f = std::find_if(fields.begin(), fields.end(), [&](const CounterField& cf) {
          return cf.name == item.substr(0, colon);
        });
        if (f == fields.end()) {
          fail(fmt::format("unknown counter '{}' in fdl=", shown(item.substr(0, colon))));
        }
        const std::uint64_t n = dec(item.substr(colon + 1), "counter value");
        if (n == 0 || n > 0xFFFF'FFFF || c.*(f->member) != 0) {
          fail(fmt::format("bad counter '{}' in fdl= (each counter once, 1..4294967295)",
                           shown(item)));
        }
        c.*(f->member) = static_cast<std::uint32_t>(n);
      }
    }
    return counters_text(c);
  }
  fail(fmt::format("unknown state key '{}' (dp, wd, status, irr, imr, station, fdl)", shown(key)));
}

class TraceParser {
 public:
  explicit TraceParser(Trace& t) : t_(t) {}

  void line(int no, std::string_view raw) {
    const std::string_view text = raw.substr(0, raw.find('#'));
    const std::vector<std::string_view> w = words(text);
    if (no == 1) {
      if (w.size() != 2 || w[0] != "dpc31-trace") {
        fail(fmt::format("not a dpc31 trace (the first line must be '{}')", kTraceMagic));
      }
      if (w[1] != "1") fail(fmt::format("trace format version '{}': only 1 is known", shown(w[1])));
      return;
    }
    if (w.empty()) return;
    if (ended_) fail(fmt::format("'{}' after the 'end' line", shown(w[0])));
    if (header(w)) {
      if (body_) fail(fmt::format("header line '{}' after the first event", shown(w[0])));
      return;
    }
    if (!body_) {
      for (const auto& [name, seen] : {std::pair{"profile", have_profile_},
                                       {"bus", have_bus_},
                                       {"clock", have_clock_},
                                       {"baud", have_baud_}}) {
        if (!seen) fail(fmt::format("the header has no '{}' line", name));
      }
      if (bit_cycles(clock(), t_.baud) == 0) {
        fail(fmt::format("baud {} is unusable at clock {}", t_.baud, clock()));
      }
      body_ = true;
    }
    TraceLine l;
    l.line = no;
    body(w, l);
    if (l.cycle < order_) {
      fail(
          fmt::format("cycle {} comes before cycle {} of an earlier line: lines must be in "
                      "cycle order",
                      l.cycle, order_));
    }
    order_ = l.cycle;
    timing(l);
    t_.lines.push_back(std::move(l));
  }

  void finish(int last) {
    if (!ended_) {
      throw std::pair<int, std::string>(
          last, body_ ? "truncated trace: no 'end' line" : "no events and no 'end' line");
    }
  }

 private:
  [[nodiscard]] std::uint32_t clock() const {
    return t_.chip.clock_hz != 0 ? t_.chip.clock_hz : chip_timing().clock_hz;
  }

  bool header(const std::vector<std::string_view>& w) {
    const std::string_view k = w[0];
    const auto once = [&](bool& seen) {
      if (seen) fail(fmt::format("'{}' given twice", k));
      seen = true;
    };
    if (k == "profile") {
      once(have_profile_);
      arity(w, 2, "profile spc3|vpc3plus|dpc31");
      if (!parse_profile(w[1], t_.chip.profile)) {
        fail(fmt::format("unknown profile '{}' (spc3, vpc3plus, dpc31)", shown(w[1])));
      }
    } else if (k == "variant") {
      once(have_variant_);
      arity(w, 2, "variant b|c|s");
      if (t_.chip.profile != Profile::vpc3plus || !have_profile_) {
        fail("'variant' follows 'profile vpc3plus': only the VPC3+ has variants");
      }
      Vpc3Variant v{};
      if (!parse_vpc3_variant(w[1], v))
        fail(fmt::format("unknown variant '{}' (b, c, s)", shown(w[1])));
      t_.chip.variant = v;
    } else if (k == "bus") {
      once(have_bus_);
      arity(w, 2, "bus intel|motorola");
      if (w[1] != "intel" && w[1] != "motorola") {
        fail(fmt::format("unknown bus '{}' (intel, motorola)", shown(w[1])));
      }
      t_.chip.bus = w[1] == "intel" ? BusMode::intel : BusMode::motorola;
    } else if (k == "clock") {
      once(have_clock_);
      arity(w, 2, "clock HZ");
      const std::uint64_t hz = dec(w[1], "clock");
      if (hz == 0 || hz > kMaxClock)
        fail(fmt::format("clock {} out of range (1..{})", hz, kMaxClock));
      t_.chip.clock_hz = static_cast<std::uint32_t>(hz);
    } else if (k == "baud") {
      once(have_baud_);
      arity(w, 2, "baud N");
      const std::uint64_t b = dec(w[1], "baud");
      if (b == 0 || b > 12'000'000) fail(fmt::format("baud {} out of range (1..12000000)", b));
      t_.baud = static_cast<std::uint32_t>(b);
    } else {
      return false;
    }
    return true;
  }

  // The chip's cycle after the actions so far: the replay never goes back in time, and the
  // expectations must all be due by the end.
  void timing(const TraceLine& l) {
    const std::uint32_t access = profile_desc(t_.chip.profile).bus_access_cycles;
    std::uint64_t start = l.cycle;
    switch (l.kind) {
      case TraceKind::wr:
      case TraceKind::rd:
        if (l.cycle < access) {
          fail(fmt::format("a bus access cannot complete before cycle {}", access));
        }
        start = l.cycle - access;
        break;
      case TraceKind::xint:
        last_expect_ = std::max(last_expect_, l.cycle);
        return;
      case TraceKind::tx:
        last_expect_ = std::max(last_expect_, l.end);
        return;
      case TraceKind::end:
        if (l.cycle < last_expect_) {
          fail(fmt::format("end at cycle {} before an expected event at cycle {}", l.cycle,
                           last_expect_));
        }
        break;
      case TraceKind::rx:
      case TraceKind::rxd:
      case TraceKind::state:
        break;
    }
    if (start < now_) {
      fail(fmt::format("starts at cycle {}, before cycle {} where the previous line left the chip",
                       start, now_));
    }
    now_ = l.cycle;
  }

  void body(const std::vector<std::string_view>& w, TraceLine& l) {
    const std::string_view k = w[0];
    const std::uint32_t addr_digits = 4;
    if (k == "wr") {
      arity(w, 4, "wr CYCLE ADDR DATA");
      l.kind = TraceKind::wr;
      l.cycle = dec(w[1], "cycle");
      l.addr = hexnum(w[2], addr_digits, "address");
      l.data = hexbyte(w[3], "data");
    } else if (k == "rd") {
      arity(w, 5, "rd CYCLE ADDR = DATA");
      if (w[3] != "=") fail("expected 'rd CYCLE ADDR = DATA'");
      l.kind = TraceKind::rd;
      l.cycle = dec(w[1], "cycle");
      l.addr = hexnum(w[2], addr_digits, "address");
      l.data = hexbyte(w[4], "data");
    } else if (k == "rx") {
      if (w.size() < 3) fail("expected 'rx START BYTES... [fault=KIND:CHAR] [fed=CYCLE]'");
      l.kind = TraceKind::rx;
      l.start = dec(w[1], "start cycle");
      l.cycle = l.start;
      bool fed = false;
      for (std::size_t i = 2; i < w.size(); ++i) {
        const std::size_t eq = w[i].find('=');
        if (eq == std::string_view::npos) {
          if (fed || l.fault.kind != UartFault::Kind::none) {
            fail(fmt::format("byte '{}' after the options", shown(w[i])));
          }
          l.bytes.push_back(hexbyte(w[i], "byte"));
          continue;
        }
        const std::string_view key = w[i].substr(0, eq);
        const std::string_view v = w[i].substr(eq + 1);
        if (key == "fed" && !fed) {
          fed = true;
          l.cycle = dec(v, "fed cycle");
        } else if (key == "fault" && l.fault.kind == UartFault::Kind::none) {
          const std::size_t colon = v.find(':');
          const std::string_view kind = v.substr(0, colon);
          if (kind == "parity") {
            l.fault.kind = UartFault::Kind::parity;
          } else if (kind == "start") {
            l.fault.kind = UartFault::Kind::start;
          } else if (kind == "stop") {
            l.fault.kind = UartFault::Kind::stop;
          } else {
            fail(fmt::format("bad fault '{}' (parity, start or stop, then :CHAR)", shown(v)));
          }
          if (colon == std::string_view::npos) fail("fault= needs the character: KIND:CHAR");
          l.fault.char_index = static_cast<int>(dec(v.substr(colon + 1), "fault character"));
        } else {
          fail(fmt::format("unknown or repeated option '{}' (fault=, fed=)", shown(key)));
        }
      }
      if (l.bytes.empty()) fail("'rx' needs at least one byte");
      if (l.bytes.size() > fdl::kMaxFrameLength) {
        fail(fmt::format("{} bytes: a telegram has at most {}", l.bytes.size(),
                         fdl::kMaxFrameLength));
      }
      if (l.fault.kind != UartFault::Kind::none &&
          static_cast<std::size_t>(l.fault.char_index) >= l.bytes.size()) {
        fail(fmt::format("fault in character {} of {}", l.fault.char_index, l.bytes.size()));
      }
      if (l.cycle > l.start) fail("fed= after the first start bit");
    } else if (k == "rxd") {
      if (w.size() < 3) fail("expected 'rxd FED CYCLE:LEVEL...'");
      l.kind = TraceKind::rxd;
      l.cycle = dec(w[1], "fed cycle");
      std::uint64_t prev = l.cycle;
      for (std::size_t i = 2; i < w.size(); ++i) {
        const std::size_t colon = w[i].find(':');
        const std::string_view lv = colon == std::string_view::npos ? "" : w[i].substr(colon + 1);
        if (lv != "0" && lv != "1")
          fail(fmt::format("bad edge '{}' (CYCLE:0 or CYCLE:1)", shown(w[i])));
        const std::uint64_t c = dec(w[i].substr(0, colon), "edge cycle");
        if (c < prev) fail(fmt::format("edge at cycle {} before cycle {}", c, prev));
        prev = c;
        l.edges.emplace_back(c, lv == "1");
      }
    } else if (k == "xint") {
      arity(w, 3, "xint CYCLE 0|1");
      l.kind = TraceKind::xint;
      l.cycle = dec(w[1], "cycle");
      if (w[2] != "0" && w[2] != "1") fail(fmt::format("bad level '{}' (0 or 1)", shown(w[2])));
      l.level = w[2] == "1";
    } else if (k == "tx") {
      if (w.size() < 4) fail("expected 'tx START END BYTES...'");
      l.kind = TraceKind::tx;
      l.start = dec(w[1], "start cycle");
      l.end = dec(w[2], "end cycle");
      l.cycle = l.start;
      if (l.end <= l.start) fail("the end of a telegram must come after its start");
      for (std::size_t i = 3; i < w.size(); ++i) l.bytes.push_back(hexbyte(w[i], "byte"));
    } else if (k == "state") {
      if (w.size() < 3) fail("expected 'state CYCLE KEY=VALUE...'");
      l.kind = TraceKind::state;
      l.cycle = dec(w[1], "cycle");
      for (std::size_t i = 2; i < w.size(); ++i) {
        const std::size_t eq = w[i].find('=');
        if (eq == std::string_view::npos || eq == 0) {
          fail(fmt::format("bad state item '{}' (KEY=VALUE)", shown(w[i])));
        }
        const std::string_view key = w[i].substr(0, eq);
        for (const TraceStateKey& s : l.state) {
          if (s.key == key) fail(fmt::format("state key '{}' given twice", shown(key)));
        }
        l.state.push_back({std::string(key), state_value(key, w[i].substr(eq + 1))});
      }
    } else if (k == "end") {
      arity(w, 2, "end CYCLE");
      l.kind = TraceKind::end;
      l.cycle = dec(w[1], "cycle");
      ended_ = true;
    } else {
      fail(
          fmt::format("unknown line '{}' (rx, rxd, wr, rd, xint, tx, state, end; header: profile, "
                      "variant, bus, clock, baud)",
                      shown(k)));
    }
  }

  Trace& t_;
  bool have_profile_ = false;
  bool have_variant_ = false;
  bool have_bus_ = false;
  bool have_clock_ = false;
  bool have_baud_ = false;
  bool body_ = false;
  bool ended_ = false;
  std::uint64_t order_ = 0;
  std::uint64_t now_ = 0;
  std::uint64_t last_expect_ = 0;
};

}  // namespace

bool parse_trace(std::string_view text, const std::string& file, Trace& out, TraceError& err) {
  Trace t;
  t.file = file;
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
  if (text.empty()) {
    err = TraceError{file, 0, "empty file, not a trace"};
    return false;
  }
  TraceParser p(t);
  int no = 0;
  try {
    std::string_view rest = text;
    while (!rest.empty()) {
      const std::size_t nl = rest.find('\n');
      const std::string_view line = rest.substr(0, nl);
      rest = nl == std::string_view::npos ? std::string_view{} : rest.substr(nl + 1);
      ++no;
      if (line.find('\0') != std::string_view::npos) fail("a NUL byte: not a text file");
      p.line(no, line);
    }
    p.finish(no);
  } catch (const Fail& f) {
    err = TraceError{file, no, f.message};
    return false;
  } catch (const std::pair<int, std::string>& f) {
    err = TraceError{file, f.first, f.second};
    return false;
  }
  out = std::move(t);
  return true;
}

bool load_trace(const std::string& path, Trace& out, TraceError& err) {
  err = TraceError{path, 0, {}};
  std::string text;
  if (!read_text_file(path, kMaxFileBytes, "trace", text, err.message)) return false;
  if ((err.line = cut_off_line(text, err.message)) != 0) return false;
  return parse_trace(text, path, out, err);
}

// ---------------------------------------------------------------------------------------------
// Replay

namespace {

struct Mismatch {
  int line;
  std::string message;
};

class Replayer {
 public:
  explicit Replayer(const Trace& t) : t_(t), chip_(t.chip) {
    chip_.on_irq_change(
        [this](std::uint64_t cycle, bool active) { irq_.emplace_back(cycle, active); });
    chip_.on_telegram([this](const Telegram& tg) {
      if (tg.from_chip) tx_.push_back(tg);
    });
    t_bit_ = bit_cycles(chip_.clock_hz(), t.baud);
    access_ = chip_.bus_access_cycles();
    chip_.set_log_sink({});  // the replay reports its checks, not the model's remarks
    end_line_ = t.lines.empty() ? 0 : t.lines.back().line;
  }

  ReplayOutcome run() {
    ReplayOutcome o;
    try {
      for (const TraceLine& l : t_.lines) {
        check_due(o, l.cycle, &l);
        act(l, o);
      }
      o.ok = true;
    } catch (const Mismatch& m) {
      o.failure = fmt::format("{}:{}: {}", t_.file, m.line, m.message);
    }
    o.final_cycle = chip_.cycle();
    return o;
  }

 private:
  [[noreturn]] static void mismatch(int line, std::string msg) {
    throw Mismatch{line, std::move(msg)};
  }

  void step_to(const TraceLine& l, std::uint64_t c) {
    if (chip_.cycle() > c) {
      // The parser rules this out; kept as a guard against a model that moves time by itself.
      mismatch(l.line,
               fmt::format("expected the chip at cycle {}, got cycle {}", c, chip_.cycle()));
    }
    chip_.step(c - chip_.cycle());
  }

  static std::string xint_text(std::uint64_t c, bool level) {
    return fmt::format("xint {} at cycle {}", level ? 1 : 0, c);
  }
  static std::string tx_text(std::uint64_t s, std::uint64_t e,
                             std::span<const std::uint8_t> bytes) {
    return fmt::format("tx {}..{} {}", s, e, hex_bytes(bytes));
  }

  // What the trace says instead of an event of the chip that no expectation matches.
  static std::string nothing_expected(std::uint64_t horizon, const TraceLine* next,
                                      std::string_view what) {
    if (next == nullptr || next->kind == TraceKind::end) return fmt::format("no more {}s", what);
    return fmt::format("no other {} up to cycle {}", what, horizon - 1);
  }

  // Compares the expectations due by now with what the chip did, in order. Every expectation
  // before `horizon` has been read (`next` is the line about to be played, nullptr after the
  // end): an event the chip made before it is unexpected if no expectation matches it.
  void check_due(ReplayOutcome& o, std::uint64_t horizon, const TraceLine* next) {
    const std::uint64_t now = chip_.cycle();
    const int next_line = next != nullptr ? next->line : end_line_;
    for (;;) {
      const TraceLine* e = pend_irq_.empty() ? nullptr : pend_irq_.front();
      if (e != nullptr && e->cycle <= now) {
        if (irq_.empty()) {
          mismatch(e->line, fmt::format("expected {}, got no X/INT edge by cycle {}",
                                        xint_text(e->cycle, e->level), now));
        }
        const auto [c, lv] = irq_.front();
        if (c != e->cycle || lv != e->level) {
          mismatch(e->line, fmt::format("expected {}, got {}", xint_text(e->cycle, e->level),
                                        xint_text(c, lv)));
        }
        irq_.pop_front();
        pend_irq_.pop_front();
        ++o.irq_edges;
        continue;
      }
      if (!irq_.empty() && irq_.front().first <= now && irq_.front().first < horizon &&
          (e == nullptr || irq_.front().first < e->cycle)) {
        if (e == nullptr && next != nullptr && next->kind == TraceKind::xint) e = next;
        const std::string got = xint_text(irq_.front().first, irq_.front().second);
        if (e != nullptr) {
          mismatch(e->line, fmt::format("expected {}, got {}", xint_text(e->cycle, e->level), got));
        }
        mismatch(next_line, fmt::format("expected {}, got {}",
                                        nothing_expected(horizon, next, "X/INT edge"), got));
      }
      break;
    }
    for (;;) {
      const TraceLine* e = pend_tx_.empty() ? nullptr : pend_tx_.front();
      if (e != nullptr && e->start <= now) {
        if (tx_.empty()) {
          mismatch(e->line, fmt::format("expected {}, got no telegram from the chip by cycle {}",
                                        tx_text(e->start, e->end, e->bytes), now));
        }
        const Telegram& g = tx_.front();
        if (g.start != e->start || g.end != e->end || g.bytes != e->bytes) {
          mismatch(e->line, fmt::format("expected {}, got {}", tx_text(e->start, e->end, e->bytes),
                                        tx_text(g.start, g.end, g.bytes)));
        }
        tx_.pop_front();
        pend_tx_.pop_front();
        ++o.telegrams_out;
        continue;
      }
      if (!tx_.empty() && tx_.front().start <= now && tx_.front().start < horizon &&
          (e == nullptr || tx_.front().start < e->start)) {
        if (e == nullptr && next != nullptr && next->kind == TraceKind::tx) e = next;
        const Telegram& g = tx_.front();
        const std::string got = tx_text(g.start, g.end, g.bytes);
        if (e != nullptr) {
          mismatch(e->line,
                   fmt::format("expected {}, got {}", tx_text(e->start, e->end, e->bytes), got));
        }
        mismatch(next_line, fmt::format("expected {}, got {}",
                                        nothing_expected(horizon, next, "telegram"), got));
      }
      break;
    }
  }

  void act(const TraceLine& l, ReplayOutcome& o) {
    switch (l.kind) {
      case TraceKind::rx: {
        step_to(l, l.cycle);
        std::vector<std::pair<std::uint64_t, bool>> edges;
        uart_encode(l.bytes, l.start, t_bit_, edges, l.fault);
        for (const auto& [c, lv] : edges) chip_.drive_rxd(c, lv);
        ++o.telegrams_in;
        break;
      }
      case TraceKind::rxd:
        step_to(l, l.cycle);
        for (const auto& [c, lv] : l.edges) chip_.drive_rxd(c, lv);
        ++o.telegrams_in;
        break;
      case TraceKind::wr:
        step_to(l, l.cycle - access_);
        chip_.write(l.addr, l.data);
        ++o.writes;
        break;
      case TraceKind::rd: {
        step_to(l, l.cycle - access_);
        const std::uint8_t v = chip_.read(l.addr);
        if (v != l.data) {
          mismatch(l.line, fmt::format("expected rd {:04X} = {:02X} at cycle {}, got {:02X}",
                                       l.addr, l.data, l.cycle, v));
        }
        ++o.reads;
        break;
      }
      case TraceKind::xint:
        pend_irq_.push_back(&l);
        return;  // checked when time has passed it
      case TraceKind::tx:
        pend_tx_.push_back(&l);
        return;
      case TraceKind::state: {
        step_to(l, l.cycle);
        check_due(o, l.cycle + 1, &l);  // a state line follows the expectations of its cycle
        const std::vector<TraceStateKey> now = chip_state(chip_);
        for (const TraceStateKey& want : l.state) {
          const auto it = std::find_if(now.begin(), now.end(),
                                       [&](const TraceStateKey& k) { return k.key == want.key; });
          if (it->value != want.value) {
            mismatch(l.line, fmt::format("expected {}={} at cycle {}, got {}={}", want.key,
                                         want.value, l.cycle, it->key, it->value));
          }
        }
        ++o.states;
        return;
      }
      case TraceKind::end:
        step_to(l, l.cycle);
        check_due(o, std::numeric_limits<std::uint64_t>::max(), nullptr);
        if (!pend_irq_.empty() || !pend_tx_.empty()) {
          // The parser keeps expectations before the end; a guard all the same.
          mismatch(l.line, "expected every expectation due by the end");
        }
        return;
    }
  }

  const Trace& t_;
  Chip chip_;
  std::uint32_t t_bit_ = 0;
  std::uint32_t access_ = 4;
  int end_line_ = 0;
  std::deque<std::pair<std::uint64_t, bool>> irq_;  // observed, not yet matched
  std::deque<Telegram> tx_;
  std::deque<const TraceLine*> pend_irq_;  // expected, not yet due
  std::deque<const TraceLine*> pend_tx_;
};

}  // namespace

ReplayOutcome replay_trace(const Trace& t) {
  Replayer r(t);
  return r.run();
}

int replay_trace_file(const std::string& path, std::string& message, ReplayOutcome* outcome) {
  Trace t;
  TraceError err;
  if (!load_trace(path, t, err)) {
    message = err.text();
    return 2;
  }
  const ReplayOutcome o = replay_trace(t);
  if (outcome != nullptr) *outcome = o;
  message = o.failure;
  return o.ok ? 0 : 1;
}

}  // namespace dpc31
