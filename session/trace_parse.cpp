// Golden traces: the parser (trace text -> Trace). The format: docs/trace-format.md.
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <filesystem>
#include <limits>
#include <system_error>

#include "dpc31/fdl.hpp"
#include "outfile.hpp"
#include "scenario_lex.hpp"
#include "textfile.hpp"
#include "trace.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

namespace {

constexpr std::uint64_t kMaxCycle = std::uint64_t{1} << 62;
constexpr std::uint32_t kMaxClock = 200'000'000;

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
  const bool digits = !s.empty() && p == s.data() + s.size();
  if (digits && (ec == std::errc::result_out_of_range || v > kMaxCycle)) {
    // The bound of a cycle (2^62); the other numbers have smaller ones, checked where they are
    // used.
    fail(fmt::format("{} '{}' out of range", what, shown(s)));
  }
  if (!digits || ec != std::errc()) {
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

  // Parses line `no`: true if it is an event, then in `l`.
  bool line(int no, std::string_view raw, TraceLine& l) {
    const std::string_view text = raw.substr(0, raw.find('#'));
    const std::vector<std::string_view> w = words(text);
    if (no == 1) {
      if (w.size() != 2 || w[0] != "dpc31-trace") {
        fail(fmt::format("not a dpc31 trace (the first line must be '{}')", kTraceMagic));
      }
      if (w[1] != "1") fail(fmt::format("trace format version '{}': only 1 is known", shown(w[1])));
      return false;
    }
    if (w.empty()) return false;
    if (ended_) fail(fmt::format("'{}' after the 'end' line", shown(w[0])));
    if (header(w)) {
      if (body_) fail(fmt::format("header line '{}' after the first event", shown(w[0])));
      return false;
    }
    if (!body_) {
      for (const auto& [name, seen] : {std::pair{"profile", have_profile_},
                                       {"bus", have_bus_},
                                       {"clock", have_clock_},
                                       {"baud", have_baud_}}) {
        if (!seen) fail(fmt::format("the header has no '{}' line", name));
      }
      body_ = true;
    }
    l = TraceLine{};
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
    return true;
  }

  // An event line of a trace whose lines were all parsed before (a cursor reads them again): the
  // header is t_'s, the order and timing were checked then.
  void event(int no, std::string_view raw, TraceLine& l) {
    l = TraceLine{};
    l.line = no;
    body(words(raw.substr(0, raw.find('#'))), l);
  }

  // After the last line: why the trace is not whole ("" if it is).
  [[nodiscard]] std::string unfinished() const {
    if (ended_) return "";
    return body_ ? "truncated trace: no 'end' line" : "no events and no 'end' line";
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
    } else if (k == "irq-controller") {
      once(have_irq_controller_);
      arity(w, 2, "irq-controller external|c31");
      if (!parse_irq_controller(w[1], t_.chip.irq_controller))
        fail(fmt::format("unknown irq-controller '{}' (external, c31)", shown(w[1])));
      // Any value, external too: no other profile has a choice (docs/decisions.md).
      if (t_.chip.profile != Profile::dpc31 || !have_profile_) {
        fail(fmt::format(
            "'irq-controller {}' follows 'profile dpc31': only the DPC31 has a C31 core", w[1]));
      }
    } else if (k == "check") {
      once(have_check_);
      arity(w, 2, "check pb3");
      if (w[1] != "pb3") fail(fmt::format("unknown check '{}' (pb3)", shown(w[1])));
      if (t_.chip.profile != Profile::dpc31 || !have_profile_) {
        fail("'check pb3' follows 'profile dpc31': only the DPC31 has the DX_Out port PB3");
      }
      t_.check_pb3 = true;
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
      if (const std::string why = trace_baud_problem(b); !why.empty()) fail(why);
      t_.baud = static_cast<std::uint32_t>(b);
    } else {
      return false;
    }
    // At the later of the two lines, the one that makes the pair unusable.
    if ((k == "clock" || k == "baud") && have_clock_ && have_baud_) {
      if (const std::string why = trace_baud_problem(t_.baud, clock()); !why.empty()) fail(why);
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
      case TraceKind::pb3:
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
      case TraceKind::reset:
        break;
    }
    if (start < now_) {
      fail(fmt::format("starts at cycle {}, before cycle {} where the previous line left the chip",
                       start, now_));
    }
    now_ = l.cycle;
  }

  // A bus address within the profile's address bus: the chip would drop the upper bits, and the
  // line would act on another address (as every door refuses it: docs/decisions.md).
  std::uint32_t address(std::string_view s) {
    const std::uint32_t a = hexnum(s, 4, "address");
    const ValueRange bus{"address", 0, (1u << profile_desc(t_.chip.profile).address_bits) - 1};
    if (a > bus.max) fail(out_of_range(bus, fmt::format("0x{}", s)));
    return a;
  }

  void body(const std::vector<std::string_view>& w, TraceLine& l) {
    const std::string_view k = w[0];
    if (k == "wr") {
      arity(w, 4, "wr CYCLE ADDR DATA");
      l.kind = TraceKind::wr;
      l.cycle = dec(w[1], "cycle");
      l.addr = address(w[2]);
      l.data = hexbyte(w[3], "data");
    } else if (k == "rd") {
      arity(w, 5, "rd CYCLE ADDR = DATA");
      if (w[3] != "=") fail("expected 'rd CYCLE ADDR = DATA'");
      l.kind = TraceKind::rd;
      l.cycle = dec(w[1], "cycle");
      l.addr = address(w[2]);
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
          if (!parse_fault_kind(kind, l.fault.kind)) {
            fail(fmt::format("bad fault '{}' (parity, start or stop, then :CHAR)", shown(v)));
          }
          if (colon == std::string_view::npos) fail("fault= needs the character: KIND:CHAR");
          // Bounded before it is an int (4294967296 was character 0): a telegram's length.
          const std::uint64_t ch = dec(v.substr(colon + 1), "fault character");
          if (ch >= fdl::kMaxFrameLength) {
            fail(fmt::format("fault in character {}: a telegram has at most {} characters", ch,
                             fdl::kMaxFrameLength));
          }
          l.fault.char_index = static_cast<int>(ch);
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
    } else if (k == "xint" || k == "pb3") {
      arity(w, 3, k == "xint" ? "xint CYCLE 0|1" : "pb3 CYCLE 0|1");
      // Without the header's `check pb3` the replay would not look at PB3 besides this line.
      if (k == "pb3" && !t_.check_pb3) fail("a 'pb3' line needs the header line 'check pb3'");
      l.kind = k == "xint" ? TraceKind::xint : TraceKind::pb3;
      l.cycle = dec(w[1], "cycle");
      if (w[2] != "0" && w[2] != "1") fail(fmt::format("bad level '{}' (0 or 1)", shown(w[2])));
      l.level = w[2] == "1";
    } else if (k == "reset") {
      arity(w, 2, "reset CYCLE");
      l.kind = TraceKind::reset;
      l.cycle = dec(w[1], "cycle");
      // Chip::reset refuses a cycle past the chip's time; here it is the line's bad input.
      if (l.cycle > Chip::kLastCycle)
        fail(fmt::format("reset cycle {} is past the chip's last cycle {}", l.cycle,
                         Chip::kLastCycle));
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
          fmt::format("unknown line '{}' (rx, rxd, wr, rd, xint, pb3, tx, state, end; header: "
                      "profile, variant, irq-controller, check, bus, clock, baud)",
                      shown(k)));
    }
  }

  Trace& t_;
  bool have_profile_ = false;
  bool have_variant_ = false;
  bool have_irq_controller_ = false;
  bool have_check_ = false;
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

std::string trace_baud_problem(std::uint64_t baud, std::uint32_t clock_hz) {
  if (baud == 0 || baud > 12'000'000)
    return fmt::format("baud {} out of range (1..12000000)", baud);
  if (clock_hz != 0 && bit_cycles(clock_hz, static_cast<std::uint32_t>(baud)) == 0)
    return fmt::format("baud {} is unusable at clock {}", baud, clock_hz);
  return "";
}

bool parse_trace(std::string_view text, const std::string& file, Trace& out, TraceError& err) {
  Trace t;
  t.file = file;
  text = scenario_lex::without_bom(text);
  if (text.empty()) {
    err = TraceError{file, 0, "empty file, not a trace"};
    return false;
  }
  TraceParser p(t);
  int no = 0;
  try {
    std::string_view rest = text;
    TraceLine l;
    while (!rest.empty()) {
      const std::size_t nl = rest.find('\n');
      const std::string_view line = rest.substr(0, nl);
      rest = nl == std::string_view::npos ? std::string_view{} : rest.substr(nl + 1);
      ++no;
      if (line.find('\0') != std::string_view::npos) fail(not_text(0));
      if (p.line(no, line, l)) t.lines.push_back(std::move(l));
    }
  } catch (const Fail& f) {
    err = TraceError{file, no, f.message};
    return false;
  }
  if (std::string why = p.unfinished(); !why.empty()) {
    err = TraceError{file, no, std::move(why)};
    return false;
  }
  out = std::move(t);
  return true;
}

// ---------------------------------------------------------------------------------------------
// A trace file, read line by line

namespace {

// A line's text before its comment: a telegram's `rx` or `tx` line has less than 1 KiB, an
// `rxd` line with every edge of a 255-character telegram less than 64 KiB.
constexpr std::size_t kMaxTextBytes = 1u << 20;
// A whole line, comment and all: a scenario's comment (its file has at most 16 MiB) heads the
// trace the recorder writes of it.
constexpr std::uint64_t kMaxLineBytes = std::uint64_t{64} << 20;
// A pipe is read once: its trace is copied to a scratch file first, at most this much.
constexpr std::uint64_t kMaxPipeBytes = std::uint64_t{1} << 30;

// Refuses (throws Fail) a line that TextLines read but the parser must not see.
void refuse_unparsable(const TextLines::Line& l) {
  if (l.nul) fail(not_text(0));
  if (l.too_long) {
    fail(fmt::format("a line of more than {} bytes: not a trace line", kMaxLineBytes));
  }
  if (l.long_text) {
    fail(fmt::format("more than {} bytes before the comment: not a trace line", kMaxTextBytes));
  }
}

// The keyword of a line of `kind`.
std::string_view keyword(TraceKind kind) {
  constexpr std::array<std::string_view, 10> kWords = {"rx",  "rxd", "wr",    "rd",    "xint",
                                                       "pb3", "tx",  "state", "reset", "end"};
  return kWords.at(static_cast<std::size_t>(kind));
}

// The first word of a line's text (before its comment).
std::string_view first_word(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size() && is_space(text[i])) ++i;
  std::size_t k = i;
  while (k < text.size() && !is_space(text[k])) ++k;
  return text.substr(i, k - i);
}

// The event lines of a checked trace file, read again from its first event line.
class FileCursor final : public TraceCursor {
 public:
  FileCursor(int fd, const Trace& header, std::uint64_t offset, int line,
             std::optional<TraceKind> only)
      : reader_(fd, offset, kMaxTextBytes, kMaxLineBytes, '#', false),
        header_(header),
        parser_(header_),
        no_(line - 1),
        only_(only ? keyword(*only) : std::string_view{}) {}

  const TraceLine* peek() override {
    if (!have_ && !done_) advance();
    return have_ ? &line_ : nullptr;
  }
  TraceLine take() override {
    peek();
    have_ = false;
    return std::move(line_);
  }

 private:
  // The file was checked whole before: what no longer parses, or ends early, was changed since.
  [[noreturn]] void changed(int line, std::string_view why) const {
    throw TraceError{header_.file, line,
                     fmt::format("the file changed while it was replayed: {}", why)};
  }

  void advance() {
    TextLines::Line t;
    while (reader_.next(t)) {
      ++no_;
      try {
        refuse_unparsable(t);
        const std::string_view w = first_word(t.text);
        if (w.empty() || (!only_.empty() && w != only_)) continue;
        parser_.event(no_, t.text, line_);
      } catch (const Fail& f) {
        changed(no_, f.message);
      }
      have_ = true;
      done_ = line_.kind == TraceKind::end;
      return;
    }
    if (reader_.failed()) throw TraceError{header_.file, 0, "cannot read the file"};
    done_ = true;
    if (only_.empty()) changed(no_, "no 'end' line");
  }

  TextLines reader_;
  Trace header_;
  TraceParser parser_;
  int no_;
  std::string_view only_;  // the keyword of the lines it reads ("": all)
  TraceLine line_;
  bool have_ = false;  // line_ is the next line
  bool done_ = false;  // past the 'end' line or the file's end
};

}  // namespace

TraceFile::~TraceFile() {
  if (fd_ >= 0) ::close(fd_);
}

bool TraceFile::open(const std::string& path, TraceError& err) {
  err = TraceError{path, 0, {}};
  if (fd_ >= 0) ::close(fd_);
  body_line_ = 0;
  bool pipe = false;
  fd_ = open_text_file(path, "trace", err.message, pipe);
  if (fd_ < 0 || (pipe && !copy_pipe(err.message))) return false;
  header_ = Trace{};
  header_.file = path;
  return check(err);
}

bool TraceFile::copy_pipe(std::string& error) {
  // Unlinked at once, the copy lives as long as its descriptor.
  const std::string dir = outfile::make_temp_dir("dpc31-replay-", error);
  if (dir.empty()) {
    error = "cannot copy the pipe: " + error;
    return false;
  }
  const std::string name = dir + "/pipe.trace";
  const int copy = ::open(name.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  int e = errno;
  ::unlink(name.c_str());
  ::rmdir(dir.c_str());
  std::vector<char> piece(64 * 1024);
  std::uint64_t total = 0;
  bool copied = copy >= 0;
  while (copied) {
    const ssize_t n = ::read(fd_, piece.data(), piece.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n < 0) error = "cannot read the file";
      break;
    }
    total += static_cast<std::uint64_t>(n);
    if (total > kMaxPipeBytes) {
      error = fmt::format(
          "too large for a trace from a pipe (more than {} bytes): replay it from a file",
          kMaxPipeBytes);
      break;
    }
    for (ssize_t done = 0; copied && done < n;) {
      const ssize_t w = ::write(copy, piece.data() + done, static_cast<std::size_t>(n - done));
      if (w < 0 && errno == EINTR) continue;
      copied = w > 0;
      if (!copied) e = w < 0 ? errno : ENOSPC;
      done += std::max<ssize_t>(w, 0);
    }
  }
  ::close(fd_);
  fd_ = copy;
  if (!copied) {
    error = fmt::format("cannot copy the pipe to a scratch file in {}: {}",
                        std::filesystem::path(dir).parent_path().string(),
                        std::error_code(e, std::generic_category()).message());
  }
  return error.empty();
}

bool TraceFile::check(TraceError& err) {
  TextLines reader(fd_, 0, kMaxTextBytes, kMaxLineBytes, '#', true);
  TraceParser p(header_);
  TextLines::Line t;
  TraceLine l;
  int no = 0;
  bool binary = false;              // a control byte other than tab, CR, LF: no text file
  bool ended = true;                // the last line read ends with its newline
  bool decided = false;             // the error found is the file's whatever follows
  std::optional<TraceError> first;  // the first line that does not parse
  while (reader.next(t)) {
    if (no == std::numeric_limits<int>::max()) {
      err.message = fmt::format("more than {} lines: not a trace", no);
      return false;
    }
    ++no;
    binary |= t.control;
    ended = t.ended;
    if (!first) {
      try {
        refuse_unparsable(t);
        if (p.line(no, no == 1 ? scenario_lex::without_bom(t.text) : t.text, l) &&
            body_line_ == 0) {
          body_offset_ = t.offset;
          body_line_ = no;
        }
      } catch (const Fail& f) {
        first = TraceError{header_.file, no, f.message};
      }
    }
    // A binary file's first error is its own once a later line begins: a cut end cannot hide it.
    decided = first && binary && t.ended;
    if (decided) break;
  }
  if (reader.failed()) {
    err.message = "cannot read the file";
    return false;
  }
  if (no == 0) {
    err.message = "empty file, not a trace";
    return false;
  }
  // As cut_or_earlier_error (textfile.hpp) has it for a file read whole: a text file cut off is
  // the cut's error; a binary one is its first error before the cut line (the cut line blank),
  // and a binary file without any newline is one line, the first.
  const bool cut = !ended && !decided;
  if (first && (!cut || (binary && (first->line < no || no == 1)))) {
    err = *first;
  } else if (cut && !(binary && no == 1)) {
    err = TraceError{header_.file, no, "truncated: the last line has no end of line"};
  } else if (std::string why = p.unfinished(); !why.empty()) {
    err = TraceError{header_.file, no, std::move(why)};
  } else {
    return true;
  }
  return false;
}

std::unique_ptr<TraceCursor> TraceFile::cursor(std::optional<TraceKind> only) const {
  return std::make_unique<FileCursor>(fd_, header_, body_offset_, body_line_, only);
}

bool load_trace(const std::string& path, Trace& out, TraceError& err) {
  TraceFile file;
  if (!file.open(path, err)) return false;
  Trace t = file.header();
  try {
    for (const auto c = file.cursor(std::nullopt); c->peek() != nullptr;) {
      t.lines.push_back(c->take());
    }
  } catch (const TraceError& e) {
    err = e;
    return false;
  }
  out = std::move(t);
  return true;
}

}  // namespace dpc31
