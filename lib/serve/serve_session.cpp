#include "serve_session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <exception>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "dpc31/fdl.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/hex.hpp"
#include "dpc31/regdesc.hpp"
#include "dpc31/snapshot.hpp"
#include "dpc31/uart.hpp"
#include "vocabulary.hpp"  // state names
#include "whole_number.hpp"

namespace dpc31::serve {

namespace {

using Tokens = std::vector<std::string_view>;

// One failed command: the reply is "ERR <code> <message>".
struct Fail {
  std::string_view code;
  std::string message;
};

Session::Result ok(std::string text = {}) {
  return {text.empty() ? std::string("OK") : "OK " + text, Session::Action::none};
}

Session::Result err(std::string_view code, std::string_view message) {
  return {fmt::format("ERR {} {}", code, message), Session::Action::none};
}

// Replies and async lines are single lines of printable ASCII, whatever a message contains.
std::string one_line(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    out.push_back(c >= 0x20 && c < 0x7F ? ch : ' ');
  }
  return out;
}

// Into `t`, whose storage is kept from line to line.
void split(std::string_view line, Tokens& t) {
  t.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > b) t.push_back(line.substr(b, i - b));
  }
}

// "0x1F" (hex, either case) or "31" (decimal); nothing else. Throws Fail: syntax for malformed
// text, range for a value outside min..max (including anything beyond 64 bits).
std::uint64_t number(std::string_view s, std::uint64_t max, std::string_view what,
                     std::uint64_t min = 0) {
  std::uint64_t v = 0;
  const std::errc ec = numbers::parse_whole(s, v);
  if (ec == std::errc::invalid_argument) {
    throw Fail{"syntax", fmt::format("{} '{}' is not a number (decimal or 0x hex)", what, s)};
  }
  if (ec == std::errc::result_out_of_range || v > max || v < min) {
    throw Fail{"range", range_error_text(what, s, min, max)};
  }
  return v;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Hex bytes, two digits each, in one or more tokens: "10 05 02" or "100502".
void hex_bytes(std::string_view tok, std::vector<std::uint8_t>& out, std::size_t max) {
  if (tok.size() % 2 != 0) {
    throw Fail{"syntax", fmt::format("'{}' is not hex bytes (two digits each)", tok)};
  }
  for (std::size_t i = 0; i < tok.size(); i += 2) {
    const int hi = hex_digit(tok[i]);
    const int lo = hex_digit(tok[i + 1]);
    if (hi < 0 || lo < 0) {
      throw Fail{"syntax", fmt::format("'{}' is not hex bytes (two digits each)", tok)};
    }
    if (out.size() >= max) throw Fail{"range", fmt::format("more than {} bytes", max)};
    out.push_back(static_cast<std::uint8_t>(hi << 4 | lo));
  }
}

// The usage is formatted only when it is needed (a `peek` should not pay for it).
void arity(const Tokens& t, std::size_t min, std::size_t max, std::string_view usage,
           std::string_view args = {}) {
  if (t.size() - 1 < min || t.size() - 1 > max) {
    throw Fail{"syntax", fmt::format("usage: {}{}{}", usage, args.empty() ? "" : " ", args)};
  }
}

// key=value options after the positional arguments.
struct Options {
  std::vector<std::pair<std::string_view, std::string_view>> kv;
  // Splits tokens [from, end) into plain tokens (returned) and key=value options (kept).
  static std::pair<Tokens, Options> parse(const Tokens& t, std::size_t from,
                                          std::initializer_list<std::string_view> keys) {
    Tokens plain;
    Options o;
    for (std::size_t i = from; i < t.size(); ++i) {
      const std::size_t eq = t[i].find('=');
      if (eq == std::string_view::npos) {
        plain.push_back(t[i]);
        continue;
      }
      const std::string_view k = t[i].substr(0, eq);
      if (std::find(keys.begin(), keys.end(), k) == keys.end()) {
        throw Fail{"syntax", fmt::format("unknown option '{}'", k)};
      }
      for (const auto& [have, v] : o.kv) {
        if (have == k) throw Fail{"syntax", fmt::format("option '{}' given twice", k)};
      }
      o.kv.emplace_back(k, t[i].substr(eq + 1));
    }
    return {plain, o};
  }
  [[nodiscard]] std::optional<std::string_view> get(std::string_view k) const {
    for (const auto& [have, v] : kv) {
      if (have == k) return v;
    }
    return std::nullopt;
  }
};

// The rest of the line after the command word (paths may contain blanks).
std::string_view rest_of_line(std::string_view line, std::string_view cmd) {
  std::string_view r = line.substr(line.find(cmd) + cmd.size());
  // The blanks before it separate it from the command; those at its end are NAME's, and
  // StateDir refuses them (docs/protocol.md, "Snapshots").
  while (!r.empty() && (r.front() == ' ' || r.front() == '\t')) r.remove_prefix(1);
  return r;
}

}  // namespace

bool is_command(std::string_view word) {
  if (word.empty()) return false;
  for (std::size_t b = 0; b < kCommandNames.size();) {
    std::size_t e = kCommandNames.find(' ', b);
    if (e == std::string_view::npos) e = kCommandNames.size();
    if (kCommandNames.substr(b, e - b) == word) return true;
    b = e + 1;
  }
  return false;
}

void Session::prune_injected() {
  while (!injected_.empty() && injected_.front().first <= chip_.cycle()) {
    injected_bytes_ -= injected_.front().second;
    injected_.pop_front();
  }
}

void Session::clear_injected() {
  std::deque<std::pair<std::uint64_t, std::size_t>>().swap(injected_);
  injected_bytes_ = 0;
  rx_free_ = 0;
}

std::size_t Session::inject_queue_bytes() {
  prune_injected();
  return injected_bytes_;
}

std::size_t Session::inject_queue_telegrams() {
  prune_injected();
  return injected_.size();
}

Session::Session(ChipOptions opt, std::function<void(const AsyncLine&)> sink)
    : chip_(opt), emit_(std::move(sink)) {
  chip_.on_irq_change([this](std::uint64_t cycle, bool active) {
    emit(AsyncLine::Kind::irq, fmt::format("! irq {} {}", cycle, active ? 1 : 0));
  });
  // The DPC31's DX_Out port (seed 003): the level a client sees in `status` changes here.
  chip_.on_pb3_change([this](std::uint64_t cycle, bool high) {
    emit(AsyncLine::Kind::pb3, fmt::format("! pb3 {} {}", cycle, high ? 1 : 0));
  });
  chip_.on_telegram([this](const Telegram& t) {
    emit(AsyncLine::Kind::telegram,
         fmt::format("! telegram {} {} {} {}", t.start, t.end, t.from_chip ? "tx" : "rx",
                     dpc31::hex_bytes(t.bytes, "")));
  });
  chip_.set_log_sink({});  // no client asked for the log yet (show_log)
}

void Session::follow_log(ClientState& client, std::optional<LogLevel> level) {
  if (client.log_level) --log_clients_[static_cast<std::size_t>(*client.log_level)];
  if (level) ++log_clients_[static_cast<std::size_t>(*level)];
  show_log();  // what the old sink is owed goes to the clients as they asked for it
  client.log_level = level;
}

void Session::leave(ClientState& client) { follow_log(client, std::nullopt); }

void Session::show_log() {
  std::optional<LogLevel> lowest;
  for (std::size_t l = log_clients_.size(); l-- > 0;)
    if (log_clients_[l] != 0) lowest = static_cast<LogLevel>(l);
  if (lowest == log_shown_) return;
  log_shown_ = lowest;
  if (!lowest) {
    chip_.set_log_sink({});
    return;
  }
  chip_.set_log_sink(
      [this](const LogRecord& r) {
        emit(AsyncLine::Kind::log,
             fmt::format("! log {} {} {}", r.cycle, level_name(r.level), one_line(r.text)),
             r.level);
      },
      *lowest);
}

void Session::attach_cpu(CpuSetup setup) {
  cpu_ = std::make_unique<BoardCpu>(chip_, std::move(setup), [this](std::string line) {
    emit(AsyncLine::Kind::port, std::move(line));
  });
}

void Session::emit(AsyncLine::Kind kind, std::string text, LogLevel level) {
  if (emit_) emit_(AsyncLine{kind, level, std::move(text)});
}

std::uint32_t Session::default_bit_cycles() const {
  // While the chip searches (and before Start) it listens at 12 Mbaud first.
  if (chip_.wd_state() == WdState::Baud_Search) return bit_cycles(chip_.clock_hz(), kBaudRates[0]);
  return chip_.bit_cycles();
}

std::uint32_t Session::address_limit() const { return 1u << chip_.profile().address_bits; }

Session::Result Session::execute(std::string_view line, ClientState& client) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  for (std::size_t i = 0; i < line.size(); ++i) {
    const auto c = static_cast<unsigned char>(line[i]);
    if ((c < 0x20 && c != '\t') || c >= 0x7F) {
      return err("syntax",
                 fmt::format("byte {:#04x} at column {} is not printable ASCII", c, i + 1));
    }
  }
  split(line, tokens_);
  const Tokens& t = tokens_;
  if (t.empty()) return err("syntax", "empty command");
  const std::string_view cmd = t[0];
  const std::uint64_t amax = address_limit() - 1;

  try {
    if (cmd == "help") {
      arity(t, 0, 0, "help");
      return ok(std::string(kCommandNames));
    }
    if (cmd == "info") {
      arity(t, 0, 0, "info");
      const ProfileDesc& p = chip_.profile();
      return ok(fmt::format(
          "protocol={} profile={}{}{} bus={} clock_hz={} bus_access_cycles={} address_bits={}{}",
          kProtocolVersion, p.name,
          chip_.vpc3_variant()
              ? fmt::format(" variant={}", vpc3_variant_name(*chip_.vpc3_variant()))
              : std::string(),
          chip_.irq_controller() == IrqController::c31 ? " irq_controller=c31" : "",
          chip_.bus_mode() == BusMode::intel ? "intel" : "motorola", chip_.clock_hz(),
          chip_.bus_access_cycles(), p.address_bits,
          cpu_ ? fmt::format(" {}", cpu_->describe()) : std::string()));
    }
    if (cmd == "ping") {
      arity(t, 0, 0, "ping");
      return ok("pong");
    }
    if (cmd == "cycle") {
      arity(t, 0, 0, "cycle");
      return ok(fmt::format("{}", chip_.cycle()));
    }
    if (cmd == "status") {
      arity(t, 0, 0, "status");
      std::string baud = "search";
      if (chip_.wd_state() != WdState::Baud_Search) {
        const unsigned code =
            field_of(chip_.peek_reg(RegId::Status_Reg), fields::Status_Reg::Baudrate);
        baud = code < std::size(kBaudRates) ? fmt::format("{}", kBaudRates[code]) : "?";
      }
      return ok(fmt::format(
          "cycle={} started={} dp={} wd={} baud={} xint={} irq={} station={} txd={} pb3={}",
          chip_.cycle(), chip_.started() ? 1 : 0, dp_state_name(chip_.dp_state()),
          wd_state_name(chip_.wd_state()), baud, chip_.x_int_pin() ? 1 : 0,
          chip_.irq_active() ? 1 : 0, chip_.station_address(), chip_.txd_pin() ? 1 : 0,
          chip_.pb3_pin() ? 1 : 0));
    }
    if (cpu_ && (cmd == "read" || cmd == "write" || cmd == "readblock" || cmd == "writeblock")) {
      // The CPU is the bus master (docs/decisions.md): a client's access would take bus cycles
      // from under it. peek/poke are the debugger's and take none.
      return err("cpu", fmt::format("{}: the CPU is the chip's bus master (--cpu); peek and poke "
                                    "look without a bus cycle",
                                    cmd));
    }
    if (cpu_ && cmd == "load") {
      return err("cpu",
                 "load: the CPU's state is not the chip's: it would run on against another "
                 "chip (`reset` starts the board again)");
    }
    if (cmd == "cpu" || cmd == "cpu_port" || cmd == "latch") {
      if (cmd == "cpu_port") {
        arity(t, 1, 1, cmd, "N");
      } else {
        arity(t, 0, 0, cmd);
      }
      if (!cpu_) return err("no_cpu", fmt::format("{}: the server runs no CPU (--cpu)", cmd));
      if (cmd == "cpu") return ok(cpu_->registers());
      if (cmd == "cpu_port") return ok(cpu_->port(static_cast<unsigned>(number(t[1], 3, "port"))));
      const std::string latch = cpu_->latch();
      if (latch.empty()) return err("no_cpu", "latch: the C31 has no output latch");
      return ok(latch);
    }
    if (cmd == "read" || cmd == "peek") {
      arity(t, 1, 1, cmd, "ADDR");
      const auto a = static_cast<std::uint32_t>(number(t[1], amax, "address"));
      const std::uint8_t v = cmd == "read" ? chip_.read(a) : chip_.peek(a);
      return ok(fmt::format("{:#04x}", v));
    }
    if (cmd == "write" || cmd == "poke") {
      arity(t, 2, 2, cmd, "ADDR VALUE");
      const auto a = static_cast<std::uint32_t>(number(t[1], amax, "address"));
      const auto v = static_cast<std::uint8_t>(number(t[2], 0xFF, "value"));
      if (cmd == "write") {
        chip_.write(a, v);
      } else if (std::string why = chip_.poke_problem(a, v); !why.empty()) {
        return err("run_state", std::move(why));
      } else if (!chip_.poke(a, v)) {
        return err("no_storage", fmt::format("nothing to poke at {:#06x}", a));
      } else if (cpu_) {
        cpu_->poked(a, v);
      }
      return ok();
    }
    if (cmd == "readblock" || cmd == "peekblock") {
      arity(t, 2, 2, cmd, "ADDR LEN");
      const auto a = static_cast<std::uint32_t>(number(t[1], amax, "address"));
      const auto n = static_cast<std::uint32_t>(number(t[2], kMaxBlock, "length", 1));
      if (std::uint64_t{a} + n > amax + 1) {
        throw Fail{"range", fmt::format("block {:#06x}+{} ends beyond the address space", a, n)};
      }
      std::vector<std::uint8_t> bytes(n);
      for (std::uint32_t i = 0; i < n; ++i) {
        bytes[i] = cmd == "readblock" ? chip_.read(a + i) : chip_.peek(a + i);
      }
      return ok(dpc31::hex_bytes(bytes, ""));
    }
    if (cmd == "writeblock" || cmd == "pokeblock") {
      if (t.size() < 3) throw Fail{"syntax", fmt::format("usage: {} ADDR HEX...", cmd)};
      const auto a = static_cast<std::uint32_t>(number(t[1], amax, "address"));
      std::vector<std::uint8_t> bytes;
      for (std::size_t i = 2; i < t.size(); ++i) hex_bytes(t[i], bytes, kMaxBlock);
      if (std::uint64_t{a} + bytes.size() > amax + 1) {
        throw Fail{"range",
                   fmt::format("block {:#06x}+{} ends beyond the address space", a, bytes.size())};
      }
      for (std::uint32_t i = 0; i < bytes.size(); ++i) {
        if (cmd == "writeblock") {
          chip_.write(a + i, bytes[i]);
        } else if (std::string why = chip_.poke_problem(a + i, bytes[i]); !why.empty()) {
          return err("run_state", fmt::format("{} ({} bytes before it poked)", why, i));
        } else if (!chip_.poke(a + i, bytes[i])) {
          return err(
              "no_storage",
              fmt::format("nothing to poke at {:#06x} ({} bytes before it poked)", a + i, i));
        } else if (cpu_) {
          cpu_->poked(a + i, bytes[i]);
        }
      }
      return ok();
    }
    if (cmd == "addr" || cmd == "peek_reg" || cmd == "poke_reg") {
      if (cmd == "poke_reg") {
        arity(t, 2, 2, "poke_reg NAME VALUE");
      } else {
        arity(t, 1, 1, cmd, "NAME");
      }
      const RegDesc* r = find_reg(chip_.profile(), t[1]);
      if (r == nullptr) {
        // Another profile's register is no typo: it has no address here (Chip.addr_of: None).
        if (cmd == "addr" && any_profile_has(t[1])) {
          return err("no_address",
                     fmt::format("no register '{}' in profile {}: another profile's register", t[1],
                                 chip_.profile().name));
        }
        return err("unknown_register",
                   fmt::format("no register '{}' in profile {}", t[1], chip_.profile().name));
      }
      if (cmd == "addr") {
        const std::int32_t a = chip_.addr_of(r->id);
        if (a < 0) {  // neither read nor written at an address (the SPC3's Mode_Reg1)
          return err("no_address",
                     fmt::format("{} has no address in profile {}", r->name, chip_.profile().name));
        }
        return ok(fmt::format("{:#06x}", a));
      }
      if (cmd == "peek_reg") return ok(fmt::format("{:#06x}", chip_.peek_reg(r->id)));
      const auto v = static_cast<std::uint16_t>(number(t[2], r->mask(), "value"));
      if (std::string why = chip_.poke_reg_problem(r->id, v); !why.empty())
        return err("run_state", std::move(why));
      if (!chip_.poke_reg(r->id, v)) {
        return err("no_storage", fmt::format("{} has no storage to poke", r->name));
      }
      return ok();  // a changed interrupt: poke_reg told on_irq_change (`! irq`) already
    }
    if (cmd == "step" || cmd == "run_until_irq") {
      arity(t, 1, 1, cmd, cmd == "step" ? "N" : "MAX");
      const std::uint64_t n = number(t[1], cpu_ ? kMaxStepCpu : kMaxStep, "cycles");
      if (n > std::numeric_limits<std::uint64_t>::max() - chip_.cycle()) {
        throw Fail{"range", "the cycle counter would overflow"};
      }
      // With a CPU it runs with the chip, and its step in progress ends: the chip may stop up
      // to one step of the CPU beyond (the reply says where).
      if (cmd == "step") {
        if (cpu_) {
          cpu_->run_until(chip_.cycle() + n);
        } else {
          chip_.step(n);
        }
        return ok(fmt::format("{}", chip_.cycle()));
      }
      // Level-triggered like firmware: an interrupt that is already active stops at once.
      const bool hit = chip_.irq_active() ||
                       (cpu_ ? cpu_->run_until_irq(chip_.cycle() + n) : chip_.step_until_irq(n));
      return ok(fmt::format("{} {}", hit ? "irq" : "timeout", chip_.cycle()));
    }
    if (cmd == "reset") {
      arity(t, 0, 0, "reset");
      // The board's RESET under a CPU, CPU and chip together at the chip's cycle; an interrupt
      // it ends reaches the clients through on_irq_change.
      if (cpu_) {
        cpu_->reset();
      } else {
        chip_.reset();
      }
      clear_injected();
      return ok(fmt::format("{}", chip_.cycle()));
    }
    if (cmd == "inject" || cmd == "inject_fdl") {
      std::vector<std::uint8_t> bytes;
      UartFault fault;
      Options o;
      if (cmd == "inject") {
        auto [plain, opts] = Options::parse(t, 1, {"baud", "idle", "fault"});
        o = opts;
        if (plain.empty())
          throw Fail{"syntax",
                     "usage: inject HEX... [baud=B] [idle=BITS] "
                     "[fault=parity|start|stop:INDEX]"};
        for (const std::string_view tok : plain) hex_bytes(tok, bytes, kMaxInject);
        if (const auto f = o.get("fault")) {
          const std::size_t colon = f->find(':');
          const std::string_view kind = f->substr(0, colon);
          if (colon == std::string_view::npos) {
            throw Fail{"syntax", "fault=KIND:INDEX, KIND parity, start or stop"};
          }
          if (!parse_fault_kind(kind, fault.kind)) {
            throw Fail{"syntax", fmt::format("unknown fault '{}' (parity, start, stop)", kind)};
          }
          fault.char_index =
              static_cast<int>(number(f->substr(colon + 1), bytes.size() - 1, "fault index"));
        }
      } else {
        auto [plain, opts] = Options::parse(t, 1, {"baud", "idle", "dsap", "ssap", "data"});
        o = opts;
        if (plain.size() != 3) {
          throw Fail{"syntax",
                     "usage: inject_fdl DA SA FC [dsap=N] [ssap=N] [data=HEX] [baud=B] "
                     "[idle=BITS]"};
        }
        const auto da = static_cast<std::uint8_t>(number(plain[0], fdl::kAddressMask, "DA"));
        const auto sa = static_cast<std::uint8_t>(number(plain[1], fdl::kAddressMask, "SA"));
        const auto fc = static_cast<std::uint8_t>(number(plain[2], 0xFF, "FC"));
        std::optional<std::uint8_t> dsap;
        std::optional<std::uint8_t> ssap;
        if (const auto v = o.get("dsap"))
          dsap = static_cast<std::uint8_t>(number(*v, 0x7F, "dsap"));
        if (const auto v = o.get("ssap"))
          ssap = static_cast<std::uint8_t>(number(*v, 0x7F, "ssap"));
        std::vector<std::uint8_t> du;
        if (const auto v = o.get("data")) hex_bytes(*v, du, fdl::kMaxLe);
        const fdl::Frame frame = fdl::make_frame(da, sa, fc, std::move(du), dsap, ssap);
        if (!fdl::encode(frame, bytes)) throw Fail{"range", fdl::encode_refusal(frame)};
      }
      std::uint32_t t_bit = default_bit_cycles();
      if (const auto b = o.get("baud")) {
        // A bit time of at least one clock: a faster rate would be sent at the clock's.
        t_bit = bit_cycles(chip_.clock_hz(),
                           static_cast<std::uint32_t>(number(*b, chip_.clock_hz(), "baud", 1)));
      }
      std::uint32_t idle = 33;  // TSYN
      if (const auto v = o.get("idle")) {
        idle = static_cast<std::uint32_t>(number(*v, kMaxIdleBits, "idle"));
      }
      prune_injected();
      if (injected_.size() >= kMaxInjectQueue ||
          injected_bytes_ + bytes.size() > kMaxInjectQueueBytes) {
        return err(
            "queue_full",
            fmt::format("{} telegrams of {} bytes are not yet on the line (at most {} "
                        "telegrams, {} bytes): step past their END first",
                        injected_.size(), injected_bytes_, kMaxInjectQueue, kMaxInjectQueueBytes));
      }
      const std::uint64_t start = std::max(chip_.cycle(), rx_free_) + std::uint64_t{idle} * t_bit;
      rx_free_ = chip_.drive_rxd_chars(bytes, start, t_bit, fault);
      injected_.emplace_back(rx_free_, bytes.size());
      injected_bytes_ += bytes.size();
      return ok(fmt::format("{} {}", start, rx_free_));
    }
    if (cmd == "counters") {
      arity(t, 0, 0, "counters");
      const FdlCounters& c = chip_.fdl_counters();
      return ok(fmt::format(
          "requests={} parity={} start_bit={} stop_bit={} bad_sd={} le_mismatch={} bad_le={} "
          "bad_fcs={} wrong_ed={} truncated={} oversize={} bad_sap={} no_sync={} "
          "foreign_address={} unknown_sap={} unsupported_function={} not_allowed={} "
          "no_resource={} offline={} repeated={}",
          c.requests, c.parity, c.start_bit, c.stop_bit, c.bad_sd, c.le_mismatch, c.bad_le,
          c.bad_fcs, c.wrong_ed, c.truncated, c.oversize, c.bad_sap, c.no_sync, c.foreign_address,
          c.unknown_sap, c.unsupported_function, c.not_allowed, c.no_resource, c.offline,
          c.repeated));
    }
    if (cmd == "log") {
      arity(t, 1, 1, "log off|debug|info|warn|error");
      static constexpr std::array kLevels = {LogLevel::debug, LogLevel::info, LogLevel::warn,
                                             LogLevel::error};
      if (t[1] == "off") {
        follow_log(client, std::nullopt);
        return ok();
      }
      for (const LogLevel l : kLevels) {
        if (t[1] == level_name(l)) {
          follow_log(client, l);
          return ok();
        }
      }
      throw Fail{"syntax", "usage: log off|debug|info|warn|error"};
    }
    if (cmd == "save" || cmd == "load") {
      // The name is the rest of the line (it may contain blanks), relative to --state-dir.
      const std::string_view name = rest_of_line(line, cmd);
      if (name.empty()) throw Fail{"syntax", fmt::format("usage: {} NAME", cmd)};
      StateDir::Error e;
      if (cmd == "save") {
        if (!state_dir_.write(name, chip_.save_state(), e)) {
          return err(e.kind == StateDir::Error::Kind::denied ? "denied" : "snapshot",
                     one_line(e.message));
        }
        return ok(fmt::format("{}", chip_.cycle()));
      }
      std::vector<std::uint8_t> bytes;
      if (!state_dir_.read(name, kMaxSnapshotFileBytes, bytes, e)) {
        return err(e.kind == StateDir::Error::Kind::denied ? "denied" : "snapshot",
                   one_line(e.message));
      }
      try {
        chip_.load_state(bytes);
      } catch (const SnapshotError& x) {
        return err("snapshot", one_line(fmt::format("{}: {}", name, x.what())));
      }
      clear_injected();
      return ok(fmt::format("{}", chip_.cycle()));
    }
    if (cmd == "auth") {
      // The server takes a connection's first line `auth SECRET` before anything reaches here.
      return err("syntax", "auth is accepted only as the first line of a connection");
    }
    if (cmd == "quit") {
      arity(t, 0, 0, "quit");
      return {"OK bye", Action::quit};
    }
    if (cmd == "shutdown") {
      arity(t, 0, 0, "shutdown");
      return {"OK shutdown", Action::shutdown};
    }
  } catch (const Fail& f) {
    return err(f.code, f.message);
  } catch (const std::exception& e) {
    // The model refusing something it should not: report it, keep serving.
    return err("internal", one_line(e.what()));
  }
  return err("unknown_command", fmt::format("'{}' (try help)", one_line(cmd)));
}

}  // namespace dpc31::serve
