// Scenario files: parser and runner. The format and every command: docs/scenario-format.md.
#include "scenario.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <utility>

#include "core.hpp"  // the watchdog deadline, so `silence` stops at each state change
#include "dp_sm.hpp"
#include "fdl.hpp"
#include "firmware_host.hpp"
#include "textfile.hpp"

namespace dpc31 {

std::string ScenarioError::text() const {
  if (line <= 0) return fmt::format("{}: {}", file, message);
  return fmt::format("{}:{}: {}", file, line, message);
}

std::string_view dp_state_name(DpState s) {
  switch (s) {
    case DpState::Wait_Prm:
      return "Wait_Prm";
    case DpState::Wait_Cfg:
      return "Wait_Cfg";
    case DpState::Data_Exchange:
      return "Data_Exchange";
  }
  return "?";
}

std::string_view wd_state_name(WdState s) {
  switch (s) {
    case WdState::Baud_Search:
      return "Baud_Search";
    case WdState::Baud_Control:
      return "Baud_Control";
    case WdState::DP_Control:
      return "DP_Control";
  }
  return "?";
}

std::span<const CounterField> fdl_counter_fields() {
  static constexpr CounterField kFields[] = {
      {"parity", &FdlCounters::parity},
      {"start_bit", &FdlCounters::start_bit},
      {"stop_bit", &FdlCounters::stop_bit},
      {"bad_sd", &FdlCounters::bad_sd},
      {"le_mismatch", &FdlCounters::le_mismatch},
      {"bad_le", &FdlCounters::bad_le},
      {"bad_fcs", &FdlCounters::bad_fcs},
      {"wrong_ed", &FdlCounters::wrong_ed},
      {"truncated", &FdlCounters::truncated},
      {"oversize", &FdlCounters::oversize},
      {"bad_sap", &FdlCounters::bad_sap},
      {"no_sync", &FdlCounters::no_sync},
      {"foreign_address", &FdlCounters::foreign_address},
      {"unknown_sap", &FdlCounters::unknown_sap},
      {"unsupported_function", &FdlCounters::unsupported_function},
      {"not_allowed", &FdlCounters::not_allowed},
      {"no_resource", &FdlCounters::no_resource},
      {"offline", &FdlCounters::offline},
      {"repeated", &FdlCounters::repeated},
      {"requests", &FdlCounters::requests},
  };
  return kFields;
}

namespace {

// Simulated time one `silence` may take: bounds the run time of a typo like `silence 10000s`.
constexpr std::uint64_t kMaxSeconds = 3600;
constexpr std::uint64_t kMaxExchanges = 1'000'000;
constexpr std::uint64_t kMaxTries = 100'000;
constexpr std::size_t kMaxFileBytes = 16u << 20;
constexpr std::size_t kMaxDu = 244;

// Global_Control command bits (DP standard).
constexpr std::pair<std::string_view, std::uint8_t> kGcNames[] = {
    {"sync", 0x20},     {"unsync", 0x10}, {"freeze", 0x08},
    {"unfreeze", 0x04}, {"clear", 0x02},  {"operate", 0x00},
};

constexpr std::string_view kAnswerKinds[] = {"none", "sc", "data", "ok", "ue",
                                             "rr",   "rs", "dl",   "nr", "dh"};

std::string hex(std::span<const std::uint8_t> bytes, std::size_t max = 32) {
  std::string s;
  for (std::size_t i = 0; i < bytes.size() && i < max; ++i) {
    if (i != 0) s += ' ';
    s += fmt::format("{:02X}", bytes[i]);
  }
  if (bytes.size() > max) s += fmt::format(" ... ({} bytes)", bytes.size());
  return s;
}

bool parse_u64(std::string_view s, std::uint64_t& v) {
  int base = 10;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    base = 16;
    s.remove_prefix(2);
  }
  if (s.empty()) return false;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  return ec == std::errc() && p == s.data() + s.size();
}

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  for (;;) {
    const std::size_t k = s.find(sep);
    out.push_back(s.substr(0, k));
    if (k == std::string_view::npos) return out;
    s.remove_prefix(k + 1);
  }
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

struct ParseFail {
  int line = 0;  // 0: the line being parsed
  std::string message;
};

bool is_action(StepKind k) {
  return k != StepKind::expect && k != StepKind::corrupt && k != StepKind::bad_fcs &&
         k != StepKind::inputs && k != StepKind::hw;
}

// Index of `name` in a NULL-terminated list of names, -1 if absent.
int name_index(const char* const* names, std::string_view name) {
  for (int i = 0; names != nullptr && names[i] != nullptr; ++i) {
    if (name == names[i]) return i;
  }
  return -1;
}

std::string name_list(const char* const* names) {
  std::string all;
  for (int i = 0; names != nullptr && names[i] != nullptr; ++i) {
    all += (i == 0 ? "" : ", ") + std::string(names[i]);
  }
  return all.empty() ? "none" : all;
}

// Actions whose first telegram a fault can be injected into.
bool sends_request(StepKind k) {
  return is_action(k) && k != StepKind::silence && k != StepKind::foreign_master;
}

class Parser {
 public:
  explicit Parser(Scenario& s) : s_(s) {}

  void line(int no, std::string_view raw) {
    const std::string_view text = trim(raw.substr(0, raw.find('#')));
    if (text.empty()) return;
    words_.clear();
    pos_.clear();
    opts_.clear();
    std::string_view rest = text;
    while (!rest.empty()) {
      std::size_t k = 0;
      while (k < rest.size() && !is_space(rest[k])) ++k;
      words_.push_back(rest.substr(0, k));
      rest = trim(rest.substr(k));
    }
    cmd_ = words_[0];
    for (std::size_t i = 1; i < words_.size(); ++i) {
      const std::size_t eq = words_[i].find('=');
      if (eq == std::string_view::npos) {
        pos_.push_back(words_[i]);
      } else {
        const std::string_view key = words_[i].substr(0, eq);
        if (key.empty()) fail(fmt::format("option without a name: '{}'", shown(words_[i])));
        for (const auto& o : opts_) {
          if (o.first == key) fail(fmt::format("option '{}' given twice", shown(key)));
        }
        opts_.emplace_back(key, words_[i].substr(eq + 1));
      }
    }
    step_ = ScenarioStep{};
    step_.line = no;
    step_.text = std::string(text);
    if (header()) {
      headers_ = true;
      if (body_) {
        fail(
            fmt::format("'{}' is a header command: headers come before actions and expects", cmd_));
      }
      return;
    }
    if (!body_) view_ = s_.user.slave;
    body_ = true;
    body();
    s_.steps.push_back(std::move(step_));
  }

  // Checks that need the whole file: a fault must be followed by an action that sends.
  void finish() {
    if (s_.steps.empty()) {
      fail_at(-1,
              headers_ ? "only header commands: nothing to run" : "no commands: nothing to run");
    }
    const ScenarioStep* fault = nullptr;
    for (const ScenarioStep& st : s_.steps) {
      if (st.kind == StepKind::corrupt || st.kind == StepKind::bad_fcs) {
        if (fault != nullptr) {
          fail_at(st.line,
                  fmt::format("a second fault before the request of line {}", fault->line));
        }
        fault = &st;
        continue;
      }
      if (fault == nullptr || !is_action(st.kind)) continue;
      if (!sends_request(st.kind)) {
        fail_at(fault->line, fmt::format("the next action ('{}', line {}) sends no request to "
                                         "damage",
                                         st.text.substr(0, st.text.find(' ')), st.line));
      }
      fault = nullptr;
    }
    if (fault != nullptr) fail_at(fault->line, "no request follows to damage");
  }

 private:
  [[noreturn]] static void fail(std::string msg) { throw ParseFail{0, std::move(msg)}; }
  [[noreturn]] static void fail_at(int line, std::string msg) {
    throw ParseFail{line, std::move(msg)};
  }

  void positional(std::size_t min, std::size_t max, std::string_view what) const {
    if (pos_.size() < min) {
      fail(fmt::format("'{}' needs {}", cmd_, what));
    }
    if (pos_.size() > max) {
      fail(fmt::format("'{}' takes {}; unexpected '{}'", cmd_, max == 0 ? "no arguments" : what,
                       shown(pos_[max])));
    }
  }
  void no_options() const {
    if (!opts_.empty())
      fail(fmt::format("unknown option '{}' for {}", shown(opts_[0].first), cmd_));
  }
  [[noreturn]] void unknown_option(std::string_view key) const {
    fail(fmt::format("unknown option '{}' for {}", shown(key), cmd_));
  }

  static std::uint64_t number(std::string_view s, std::string_view what, std::uint64_t min,
                              std::uint64_t max) {
    std::uint64_t v = 0;
    if (!parse_u64(s, v)) fail(fmt::format("bad number '{}' for {}", shown(s), what));
    if (v < min || v > max) {
      fail(fmt::format("{} {} out of range ({}..{})", what, shown(s), min, max));
    }
    return v;
  }
  static bool flag(std::string_view s, std::string_view what) {
    if (s == "0") return false;
    if (s == "1") return true;
    fail(fmt::format("bad value '{}' for {}: 0 or 1", shown(s), what));
  }
  // Hex bytes "13,23" ("0x13" also accepted); "-" is the empty list.
  static std::vector<std::uint8_t> bytes(std::string_view s, std::string_view what,
                                         std::size_t max = kMaxDu) {
    std::vector<std::uint8_t> out;
    if (s == "-") return out;
    if (s.empty()) fail(fmt::format("empty byte list for {} (write '-' for none)", what));
    for (std::string_view b : split(s, ',')) {
      std::string_view d = b;
      if (d.size() > 2 && d[0] == '0' && (d[1] == 'x' || d[1] == 'X')) d.remove_prefix(2);
      unsigned v = 0;
      const auto [p, ec] = std::from_chars(d.data(), d.data() + d.size(), v, 16);
      if (d.empty() || d.size() > 2 || ec != std::errc() || p != d.data() + d.size()) {
        fail(fmt::format("bad byte '{}' in {} (hex bytes separated by commas)", shown(b), what));
      }
      out.push_back(static_cast<std::uint8_t>(v));
    }
    if (out.size() > max) fail(fmt::format("{}: {} bytes, at most {}", what, out.size(), max));
    return out;
  }

  std::uint32_t clock() const {
    return s_.chip.clock_hz != 0 ? s_.chip.clock_hz : chip_timing().clock_hz;
  }

  // Cycles, or a time with a unit; rounded up like every minimum time (docs/timing.md).
  std::uint64_t duration(std::string_view s) const {
    std::uint64_t v = 0;
    const std::uint64_t f = clock();
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
      v = number(s, "time", 0, kMaxSeconds * f);
      return v;
    }
    std::size_t k = 0;
    while (k < s.size() && s[k] >= '0' && s[k] <= '9') ++k;
    const std::string_view unit = s.substr(k);
    if (k == 0 || !parse_u64(s.substr(0, k), v)) {
      fail(fmt::format("bad time '{}' (cycles, or a number with us, ms, s or bits)", shown(s)));
    }
    const auto check = [&](std::uint64_t max) {
      if (v > max) fail(fmt::format("time '{}' too long (at most {} s)", shown(s), kMaxSeconds));
    };
    if (unit.empty() || unit == "cycles") {
      check(kMaxSeconds * f);
      return v;
    }
    if (unit == "us") {
      check(kMaxSeconds * 1'000'000);
      return (v * f + 999'999) / 1'000'000;
    }
    if (unit == "ms") {
      check(kMaxSeconds * 1'000);
      return (v * f + 999) / 1'000;
    }
    if (unit == "s") {
      check(kMaxSeconds);
      return v * f;
    }
    if (unit == "bits") {
      const std::uint64_t t = bit_cycles(clock(), s_.master.baud);
      check(kMaxSeconds * f / t);
      return v * t;
    }
    fail(fmt::format("bad time unit '{}' in '{}' (us, ms, s, bits, or none for cycles)",
                     shown(unit), shown(s)));
  }

  // Options of `slave` that also apply to `set_prm` (what Set_Prm carries).
  bool prm_option(SlaveConfig& sl, std::string_view k, std::string_view v) const {
    if (k == "ident") {
      sl.ident = static_cast<std::uint16_t>(number(v, "ident", 0, 0xFFFF));
    } else if (k == "wd") {
      const std::vector<std::string_view> f = split(v, ',');
      if (f.size() != 2) fail(fmt::format("wd='{}': two factors, as in wd=10,10", shown(v)));
      sl.wd_fact1 = static_cast<std::uint8_t>(number(f[0], "wd factor 1", 1, 255));
      sl.wd_fact2 = static_cast<std::uint8_t>(number(f[1], "wd factor 2", 1, 255));
    } else if (k == "wd_on") {
      sl.wd_on = flag(v, "wd_on");
    } else if (k == "wd_base") {
      if (v != "1ms" && v != "10ms") fail(fmt::format("wd_base '{}': 1ms or 10ms", shown(v)));
      sl.wd_base_1ms = v == "1ms";
    } else if (k == "group") {
      sl.group_ident = static_cast<std::uint8_t>(number(v, "group", 0, 255));
    } else if (k == "sync") {
      sl.sync_req = flag(v, "sync");
    } else if (k == "freeze") {
      sl.freeze_req = flag(v, "freeze");
    } else if (k == "min_tsdr") {
      sl.min_tsdr = static_cast<std::uint8_t>(number(v, "min_tsdr", 0, 255));
    } else if (k == "user_prm") {
      sl.user_prm = bytes(v, "user_prm", kMaxDu - 7);
    } else {
      return false;
    }
    return true;
  }

  bool header() {
    if (cmd_ == "profile") {
      positional(1, 1, "one of spc3, vpc3plus, dpc31");
      no_options();
      if (!parse_profile(pos_[0], s_.chip.profile)) {
        fail(fmt::format("unknown profile '{}' (spc3, vpc3plus, dpc31)", shown(pos_[0])));
      }
      if (s_.chip.variant && s_.chip.profile != Profile::vpc3plus) {
        fail("a 'variant' was given: only profile vpc3plus has variants");
      }
    } else if (cmd_ == "variant") {
      positional(1, 1, "one of b, c, s");
      no_options();
      Vpc3Variant v{};
      if (!parse_vpc3_variant(pos_[0], v)) {
        fail(fmt::format("unknown variant '{}' (b, c, s)", shown(pos_[0])));
      }
      if (s_.chip.profile != Profile::vpc3plus) {
        fail("'variant' needs 'profile vpc3plus' before it: only the VPC3+ has variants");
      }
      s_.chip.variant = v;
    } else if (cmd_ == "bus") {
      positional(1, 1, "intel or motorola");
      no_options();
      if (pos_[0] != "intel" && pos_[0] != "motorola") {
        fail(fmt::format("unknown bus '{}' (intel, motorola)", shown(pos_[0])));
      }
      s_.chip.bus = pos_[0] == "intel" ? BusMode::intel : BusMode::motorola;
    } else if (cmd_ == "baud") {
      positional(1, 1, "a baud rate");
      no_options();
      const std::uint64_t b = number(pos_[0], "baud", 1, 12'000'000);
      if (baud_code(static_cast<std::uint32_t>(b)) < 0) {
        fail(
            fmt::format("baud {} is not a PROFIBUS rate (9600, 19200, 45450, 93750, 187500, "
                        "500000, 1500000, 3000000, 6000000, 12000000)",
                        b));
      }
      s_.master.baud = static_cast<std::uint32_t>(b);
    } else if (cmd_ == "master") {
      positional(0, 0, "options only");
      for (const auto& [k, v] : opts_) {
        if (k == "address") {
          s_.master.address = static_cast<std::uint8_t>(number(v, "master address", 0, 126));
        } else if (k == "slot") {
          s_.master.slot_bits = static_cast<std::uint32_t>(number(v, "slot", 1, 65535));
        } else if (k == "idle") {
          s_.master.idle_bits = static_cast<std::uint32_t>(number(v, "idle", 1, 65535));
        } else if (k == "retries") {
          s_.retries = static_cast<std::uint32_t>(number(v, "retries", 0, 8));
        } else {
          unknown_option(k);
        }
      }
    } else if (cmd_ == "firmware") {
      positional(1, 1, "a firmware name");
      no_options();
      if (slave_seen_) fail("'firmware' comes before 'slave': it sets the slave's GSD defaults");
      if (user_seen_) fail("'firmware' and 'user' exclude each other");
      const std::string name(pos_[0]);
      fw_ = dpc31_find_firmware(name.c_str());
      if (fw_ == nullptr) {
        std::string all;
        for (int i = 0; dpc31_firmwares[i] != nullptr; ++i) {
          all += (i == 0 ? "" : ", ") + std::string(dpc31_firmwares[i]->name);
        }
        fail(fmt::format("unknown firmware '{}' ({})", shown(pos_[0]), all));
      }
      s_.firmware = fw_->name;
      SlaveConfig& sl = s_.user.slave;
      sl.ident = fw_->ident;
      sl.cfg.assign(fw_->cfg, fw_->cfg + fw_->cfg_len);
      sl.in_len = fw_->in_len;
      sl.out_len = fw_->out_len;
      sl.user_prm.assign(fw_->user_prm, fw_->user_prm + fw_->user_prm_len);
    } else if (cmd_ == "slave") {
      positional(0, 0, "options only");
      slave_seen_ = true;
      SlaveConfig& sl = s_.user.slave;
      for (const auto& [k, v] : opts_) {
        if (prm_option(sl, k, v)) continue;
        if (k == "address") {
          sl.address = static_cast<std::uint8_t>(number(v, "slave address", 0, 125));
        } else if (k == "cfg") {
          sl.cfg = bytes(v, "cfg");
          if (sl.cfg.empty()) fail("cfg: at least one byte");
        } else if (k == "in") {
          sl.in_len = static_cast<std::uint8_t>(number(v, "in", 0, kMaxDu));
        } else if (k == "out") {
          sl.out_len = static_cast<std::uint8_t>(number(v, "out", 0, kMaxDu));
        } else {
          unknown_option(k);
        }
      }
    } else if (cmd_ == "user") {
      positional(0, 0, "options only");
      if (fw_ != nullptr)
        fail("'user' configures the built-in user side; a firmware configures itself");
      user_seen_ = true;
      ResponderConfig& u = s_.user;
      for (const auto& [k, v] : opts_) {
        if (k == "inputs") {
          s_.inputs = bytes(v, "inputs");
        } else if (k == "sync_supported") {
          u.sync_supported = flag(v, k);
        } else if (k == "freeze_supported") {
          u.freeze_supported = flag(v, k);
        } else if (k == "spec_clear") {
          u.spec_clear_mode = flag(v, k);
        } else if (k == "user_wd") {
          u.user_watchdog = flag(v, k);
        } else if (k == "user_wd_value") {
          u.user_wd_value = static_cast<std::uint16_t>(number(v, k, 0, 0xFFFF));
        } else if (k == "wd_baud_control") {
          u.wd_baud_control = static_cast<std::uint8_t>(number(v, k, 0, 255));
        } else if (k == "substitute") {
          u.substitute = bytes(v, k);
        } else if (k == "dx_out_port") {
          u.dx_out_port = flag(v, k);
        } else {
          unknown_option(k);
        }
      }
    } else {
      return false;
    }
    return true;
  }

  void simple(StepKind k) {
    positional(0, 0, "no arguments");
    no_options();
    step_.kind = k;
  }

  void tries(std::uint64_t dflt) {
    positional(0, 0, "options only");
    step_.count = dflt;
    for (const auto& [k, v] : opts_) {
      if (k != "tries") unknown_option(k);
      step_.count = number(v, "tries", 1, kMaxTries);
    }
  }

  void body() {
    if (cmd_ == "startup" || cmd_ == "restart") {
      step_.kind = cmd_ == "startup" ? StepKind::startup : StepKind::restart;
      tries(200);
    } else if (cmd_ == "exchange") {
      step_.kind = StepKind::exchange;
      positional(0, 1, "one count");
      if (!pos_.empty()) step_.count = number(pos_[0], "exchange count", 1, kMaxExchanges);
      for (const auto& [k, v] : opts_) {
        if (k != "outputs") unknown_option(k);
        step_.bytes = bytes(v, "outputs");
        step_.has_bytes = true;
      }
    } else if (cmd_ == "gc") {
      step_.kind = StepKind::gc;
      positional(1, 1, "a command (sync, unsync, freeze, unfreeze, clear, operate, or a number)");
      step_.value = gc_command(pos_[0]);
      for (const auto& [k, v] : opts_) {
        if (k != "groups") unknown_option(k);
        step_.value2 = static_cast<std::uint32_t>(number(v, "groups", 0, 255));
      }
    } else if (cmd_ == "diag") {
      simple(StepKind::diag);
    } else if (cmd_ == "fdl_status") {
      simple(StepKind::fdl_status);
    } else if (cmd_ == "get_cfg") {
      simple(StepKind::get_cfg);
    } else if (cmd_ == "read_inputs") {
      simple(StepKind::read_inputs);
    } else if (cmd_ == "read_outputs") {
      simple(StepKind::read_outputs);
    } else if (cmd_ == "set_prm") {
      step_.kind = StepKind::set_prm;
      positional(0, 0, "options only");
      step_.slave = view_;
      for (const auto& [k, v] : opts_) {
        if (!prm_option(*step_.slave, k, v)) unknown_option(k);
      }
      view_ = step_.slave;
    } else if (cmd_ == "chk_cfg") {
      step_.kind = StepKind::chk_cfg;
      positional(0, 0, "options only");
      step_.slave = view_;
      for (const auto& [k, v] : opts_) {
        if (k != "cfg") unknown_option(k);
        step_.slave->cfg = bytes(v, "cfg");
        if (step_.slave->cfg.empty()) fail("cfg: at least one byte");
      }
      view_ = step_.slave;
    } else if (cmd_ == "set_slave_address") {
      step_.kind = StepKind::set_slave_address;
      positional(1, 1, "the new address");
      step_.value = static_cast<std::uint32_t>(number(pos_[0], "new address", 0, 126));
      for (const auto& [k, v] : opts_) {
        if (k != "no_change") unknown_option(k);
        step_.value2 = flag(v, "no_change") ? 1 : 0;
      }
    } else if (cmd_ == "foreign_master") {
      step_.kind = StepKind::foreign_master;
      positional(0, 0, "address=N");
      bool have = false;
      for (const auto& [k, v] : opts_) {
        if (k != "address") unknown_option(k);
        step_.value = static_cast<std::uint32_t>(number(v, "foreign master address", 0, 126));
        have = true;
      }
      if (!have) fail("foreign_master needs address=N");
      if (step_.value == s_.master.address) {
        fail(fmt::format("foreign_master address={} is our own master's address", step_.value));
      }
    } else if (cmd_ == "silence") {
      step_.kind = StepKind::silence;
      positional(1, 1, "one time (e.g. 200ms)");
      no_options();
      step_.cycles = duration(pos_[0]);
    } else if (cmd_ == "hw") {
      step_.kind = StepKind::hw;
      positional(2, 2, "a hardware input and a value");
      no_options();
      if (fw_ == nullptr) fail("'hw' needs a firmware (header 'firmware NAME')");
      if (name_index(fw_->hw_inputs, pos_[0]) < 0) {
        fail(fmt::format("unknown hardware input '{}' of {} ({})", shown(pos_[0]), fw_->name,
                         name_list(fw_->hw_inputs)));
      }
      step_.name = std::string(pos_[0]);
      step_.value = static_cast<std::uint32_t>(number(pos_[1], "hw value", 0, 0xFFFF'FFFF));
    } else if (cmd_ == "inputs") {
      if (fw_ != nullptr) fail("'inputs' feeds the built-in user side; a firmware makes its own");
      step_.kind = StepKind::inputs;
      positional(1, 1, "a byte list");
      no_options();
      step_.bytes = bytes(pos_[0], "inputs");
    } else if (cmd_ == "corrupt") {
      step_.kind = StepKind::corrupt;
      positional(1, 1, "parity, start or stop");
      if (pos_[0] == "parity") {
        step_.fault.kind = UartFault::Kind::parity;
      } else if (pos_[0] == "start") {
        step_.fault.kind = UartFault::Kind::start;
      } else if (pos_[0] == "stop") {
        step_.fault.kind = UartFault::Kind::stop;
      } else {
        fail(fmt::format("unknown fault '{}' (parity, start, stop)", shown(pos_[0])));
      }
      step_.fault.char_index = -1;
      for (const auto& [k, v] : opts_) {
        if (k != "char") unknown_option(k);
        step_.fault.char_index =
            v == "last" ? -1 : static_cast<int>(number(v, "char", 0, fdl::kMaxFrameLength - 1));
      }
    } else if (cmd_ == "bad_fcs") {
      simple(StepKind::bad_fcs);
    } else if (cmd_ == "expect") {
      step_.kind = StepKind::expect;
      no_options();
      expect();
    } else {
      fail(fmt::format("unknown command '{}'", shown(cmd_)));
    }
  }

  std::uint32_t gc_command(std::string_view s) const {
    if (!s.empty() && s[0] >= '0' && s[0] <= '9') {
      return static_cast<std::uint32_t>(number(s, "gc command", 0, 255));
    }
    std::uint32_t c = 0;
    for (std::string_view n : split(s, ',')) {
      bool found = false;
      for (const auto& [name, bits] : kGcNames) {
        if (n == name) {
          c |= bits;
          found = true;
        }
      }
      if (!found) {
        fail(
            fmt::format("unknown gc command '{}' (sync, unsync, freeze, unfreeze, clear, "
                        "operate, or a number)",
                        shown(n)));
      }
    }
    return c;
  }

  void expect() {
    if (pos_.empty()) fail("'expect' needs what to check and the expected value");
    const std::string_view what = pos_[0];
    auto args = [&](std::size_t n, std::string_view form) {
      if (pos_.size() != n + 1) fail(fmt::format("expected 'expect {} {}'", what, form));
    };
    if (what == "dp_state") {
      args(1, "Wait_Prm|Wait_Cfg|Data_Exchange");
      step_.expect = ExpectKind::dp_state;
      step_.value = state_value(pos_[1], {"Wait_Prm", "Wait_Cfg", "Data_Exchange"});
    } else if (what == "wd_state") {
      args(1, "Baud_Search|Baud_Control|DP_Control");
      step_.expect = ExpectKind::wd_state;
      step_.value = state_value(pos_[1], {"Baud_Search", "Baud_Control", "DP_Control"});
    } else if (what == "port") {
      args(2, "NAME VALUE");
      if (fw_ == nullptr) fail("'expect port' needs a firmware (header 'firmware NAME')");
      if (name_index(fw_->ports, pos_[1]) < 0) {
        fail(fmt::format("unknown port '{}' of {} ({})", shown(pos_[1]), fw_->name,
                         name_list(fw_->ports)));
      }
      step_.expect = ExpectKind::port;
      step_.name = std::string(pos_[1]);
      step_.value = static_cast<std::uint32_t>(number(pos_[2], "port value", 0, 0xFFFF'FFFF));
    } else if (what == "outputs" || what == "inputs") {
      args(1, "BYTES");
      if (what == "outputs" && fw_ != nullptr) {
        fail("'expect outputs' checks the built-in user side; with a firmware check its ports");
      }
      step_.expect = what == "outputs" ? ExpectKind::outputs : ExpectKind::inputs;
      if (what == "outputs" && pos_[1] == "none") {
        step_.value = 1;  // nothing fetched yet
      } else {
        step_.bytes = bytes(pos_[1], what);
      }
    } else if (what == "cleared") {
      args(1, "0|1");
      if (fw_ != nullptr) {
        fail("'expect cleared' checks the built-in user side; with a firmware check its ports");
      }
      step_.expect = ExpectKind::cleared;
      step_.value = flag(pos_[1], "cleared") ? 1 : 0;
    } else if (what == "counter") {
      args(2, "NAME N (or +N: increase during the last action)");
      step_.expect = ExpectKind::counter;
      step_.name = std::string(pos_[1]);
      const auto fields = fdl_counter_fields();
      if (std::none_of(fields.begin(), fields.end(),
                       [&](const CounterField& f) { return f.name == pos_[1]; })) {
        fail(
            fmt::format("unknown counter '{}' (the FdlCounters fields: parity, stop_bit, bad_fcs, "
                        "not_allowed, requests, ...)",
                        shown(pos_[1])));
      }
      std::string_view n = pos_[2];
      if (!n.empty() && n[0] == '+') {
        step_.value2 = 1;
        n.remove_prefix(1);
      }
      step_.value = static_cast<std::uint32_t>(number(n, "counter value", 0, 0xFFFF'FFFF));
    } else if (what == "irr_bit") {
      args(2, "NAME 0|1");
      step_.expect = ExpectKind::irr_bit;
      step_.name = std::string(pos_[1]);
      step_.value2 = irq_bit(pos_[1]);
      step_.value = flag(pos_[2], "irr_bit") ? 1 : 0;
    } else if (what == "answer") {
      args(1, "none|sc|data|ok|ue|rr|rs|dl|nr|dh");
      step_.expect = ExpectKind::answer;
      if (std::find(std::begin(kAnswerKinds), std::end(kAnswerKinds), pos_[1]) ==
          std::end(kAnswerKinds)) {
        fail(fmt::format("unknown answer kind '{}' (none, sc, data, ok, ue, rr, rs, dl, nr, dh)",
                         shown(pos_[1])));
      }
      step_.name = std::string(pos_[1]);
    } else if (what == "station") {
      args(1, "N");
      step_.expect = ExpectKind::station;
      step_.value = static_cast<std::uint32_t>(number(pos_[1], "station", 0, 127));
    } else if (what == "diag_byte") {
      args(2, "K VALUE");
      step_.expect = ExpectKind::diag_byte;
      step_.value2 = static_cast<std::uint32_t>(number(pos_[1], "diag byte index", 0, kMaxDu - 1));
      step_.value = static_cast<std::uint32_t>(number(pos_[2], "diag byte value", 0, 255));
    } else if (what == "pb3") {
      args(1, "0|1");
      step_.expect = ExpectKind::pb3;
      step_.value = flag(pos_[1], "pb3") ? 1 : 0;
    } else if (what == "baud") {
      args(1, "N");
      step_.expect = ExpectKind::baud;
      step_.value = static_cast<std::uint32_t>(number(pos_[1], "baud", 1, 12'000'000));
    } else {
      fail(
          fmt::format("unknown check '{}' (dp_state, wd_state, outputs, cleared, inputs, counter, "
                      "irr_bit, answer, station, diag_byte, baud, port, pb3)",
                      shown(what)));
    }
  }

  static std::uint32_t state_value(std::string_view s, std::initializer_list<std::string_view> n) {
    std::uint32_t i = 0;
    for (std::string_view name : n) {
      if (s == name) return i;
      ++i;
    }
    std::string all;
    for (std::string_view name : n) all += (all.empty() ? "" : ", ") + std::string(name);
    fail(fmt::format("unknown state '{}' ({})", shown(s), all));
  }

  // Interrupt names are the Int_Req_Reg fields of the chosen profile.
  std::uint32_t irq_bit(std::string_view name) const {
    const RegDesc* r = find_reg(profile_desc(s_.chip.profile), RegId::Int_Req_Reg);
    for (const FieldDesc& f : r->fields) {
      if (f.name == name && f.width == 1 && f.access != Access::RSVD) return f.lsb;
    }
    fail(
        fmt::format("'{}' is not an interrupt of {} (Int_Req_Reg: DX_Out, New_Prm_Data, "
                    "WD_DP_Control_Timeout, ...)",
                    shown(name), profile_desc(s_.chip.profile).name));
  }

  Scenario& s_;
  ScenarioStep step_;
  std::optional<SlaveConfig> view_;  // the master's view of the slave after the steps so far
  bool headers_ = false;
  const dpc31_firmware* fw_ = nullptr;
  bool slave_seen_ = false;
  bool user_seen_ = false;
  bool body_ = false;  // an action or expect has been seen: no more headers
  std::vector<std::string_view> words_;
  std::string_view cmd_;
  std::vector<std::string_view> pos_;
  std::vector<std::pair<std::string_view, std::string_view>> opts_;
};

// --- the runner ---

std::string bytes_text(std::span<const std::uint8_t> b) { return b.empty() ? "-" : hex(b, 244); }

std::string service_name(const fdl::Frame& f) {
  if (fdl::request_function(f.fc) == fdl::Function::FDL_Status) return "FDL_Status";
  if (!f.dsap) return "Data_Exchange";
  switch (fdl::sap_number(*f.dsap)) {
    case sap::Set_Slave_Add:
      return "Set_Slave_Add";
    case sap::Rd_Inp:
      return "Rd_Inp";
    case sap::Rd_Outp:
      return "Rd_Outp";
    case sap::Global_Control:
      return "Global_Control";
    case sap::Get_Cfg:
      return "Get_Cfg";
    case sap::Slave_Diag:
      return "Slave_Diag";
    case sap::Set_Prm:
      return "Set_Prm";
    case sap::Chk_Cfg:
      return "Chk_Cfg";
    default:
      return fmt::format("SAP{}", fdl::sap_number(*f.dsap));
  }
}

std::string_view response_name(std::uint8_t fc) {
  switch (fdl::response_code(fc)) {
    case fdl::Response::OK:
      return "OK";
    case fdl::Response::UE:
      return "UE";
    case fdl::Response::RR:
      return "RR";
    case fdl::Response::RS:
      return "RS";
    case fdl::Response::DL:
      return "DL";
    case fdl::Response::NR:
      return "NR";
    case fdl::Response::DH:
      return "DH";
    case fdl::Response::RDL:
      return "RDL";
    case fdl::Response::RDH:
      return "RDH";
  }
  return "FC?";
}

std::string answer_text(const std::optional<fdl::Frame>& a) {
  if (!a) return "no answer";
  if (a->sd == fdl::SC) return "SC";
  std::string s(response_name(a->fc));
  if (!a->du.empty()) s += " " + hex(a->du);
  return s;
}

// The kinds of `expect answer`, lower case.
std::string answer_kind(const std::optional<fdl::Frame>& a) {
  if (!a) return "none";
  if (a->sd == fdl::SC) return "sc";
  std::string s(response_name(a->fc));
  std::transform(s.begin(), s.end(), s.begin(), [](char c) { return static_cast<char>(c | 0x20); });
  if (!a->du.empty()) s += fmt::format(" with {} data bytes", a->du.size());
  return s;
}

bool answer_is(const std::optional<fdl::Frame>& a, std::string_view kind) {
  if (kind == "none" || !a) return kind == "none" && !a;
  if (kind == "sc" || a->sd == fdl::SC) return kind == "sc" && a->sd == fdl::SC;
  if (kind == "data") return !a->du.empty();
  return answer_kind(a).starts_with(kind) &&
         (answer_kind(a).size() == kind.size() || answer_kind(a)[kind.size()] == ' ');
}

// Set_Prm's data unit as DpMaster::set_prm builds it: the damaged copy of a request must be the
// telegram the master then repeats.
std::vector<std::uint8_t> prm_du(const SlaveConfig& s) {
  std::uint8_t status = 0x80;  // Lock_Req
  if (s.wd_on) status |= 0x08;
  if (s.freeze_req) status |= 0x10;
  if (s.sync_req) status |= 0x20;
  std::vector<std::uint8_t> du = {status,
                                  s.wd_fact1,
                                  s.wd_fact2,
                                  s.min_tsdr,
                                  static_cast<std::uint8_t>(s.ident >> 8),
                                  static_cast<std::uint8_t>(s.ident),
                                  s.group_ident};
  std::vector<std::uint8_t> user = s.user_prm;
  if (user.empty()) user.push_back(0);
  if (s.wd_base_1ms) user[0] |= 0x04;
  du.insert(du.end(), user.begin(), user.end());
  return du;
}

std::string_view fault_name(UartFault::Kind k) {
  switch (k) {
    case UartFault::Kind::parity:
      return "parity error";
    case UartFault::Kind::start:
      return "no start bit";
    case UartFault::Kind::stop:
      return "stop bit 0";
    case UartFault::Kind::none:
      break;
  }
  return "no fault";
}

class Runner {
 public:
  Runner(const Scenario& s, const LineSink& walk, const LineSink& errors,
         const ScenarioHooks& hooks = {})
      : s_(s), walk_(walk), errors_(errors), hooks_(hooks), chip_(s.chip), user_(s.user) {}
  Runner(const Runner&) = delete;
  Runner& operator=(const Runner&) = delete;

  ScenarioOutcome run() {
    if (walk_) {
      walk_(fmt::format("scenario {}: profile {}{}, bus {}, master {} -> slave {} at {} baud",
                        s_.file, profile_name(s_.chip.profile),
                        s_.chip.variant
                            ? fmt::format(", variant {}", vpc3_variant_name(*s_.chip.variant))
                            : std::string(),
                        s_.chip.bus == BusMode::intel ? "intel" : "motorola", s_.master.address,
                        s_.user.slave.address, s_.master.baud));
    }
    chip_.set_log_sink([this](const LogRecord& r) {
      if (r.level >= LogLevel::info) note(r.cycle, "chip: " + r.text);
    });
    if (hooks_.at_start) hooks_.at_start(chip_);
    user_.inputs = s_.inputs;
    DirectBus bus(chip_);
    if (!s_.firmware.empty()) {
      fw_ = std::make_unique<FirmwareHost>(*dpc31_find_firmware(s_.firmware.c_str()));
      fw_->on_port = [this](std::uint64_t cycle, unsigned port, std::uint32_t value) {
        note(cycle, fmt::format("{}: {} = {} at {}", fw_->firmware().name, fw_->port_name(port),
                                port_text(value), time_text(cycle)));
      };
      fw_->init(bus, s_.user.slave.address);
    } else {
      user_.init(bus);
    }
    master_ = std::make_unique<DpMaster>(chip_, s_.master, s_.user.slave);
    // State changes are looked for wherever they can happen: after the firmware's ISR (its
    // Prm/Cfg verdicts), at every telegram, at every X/INT edge, after every transaction.
    master_->set_firmware([this](BusPort& b) {
      if (fw_) {
        fw_->isr(b);
      } else {
        user_.isr(b);
      }
      check_states();
    });
    chip_.on_telegram([this](const Telegram&) { check_states(); });
    chip_.on_irq_change([this](std::uint64_t, bool) { check_states(); });
    chip_.on_pb3_change([this](std::uint64_t cycle, bool high) {
      pb3_rises_ += high ? 1 : 0;
      note(cycle, fmt::format("PB3 {}", high ? "high (DX_Out of a Sync)" : "low"));
    });
    dp_ = chip_.dp_state();
    wd_ = chip_.wd_state();
    outputs_.assign(s_.user.slave.out_len, 0);
    note(chip_.cycle(),
         fmt::format("started: dp_state {}, wd_state {}", dp_state_name(dp_), wd_state_name(wd_)));
    flush();
    for (const ScenarioStep& st : s_.steps) {
      if (st.kind == StepKind::expect) {
        check(st);
        continue;
      }
      // A fault and the action it damages count as one action for "+N" and irr_bit.
      const bool modifier = st.kind == StepKind::corrupt || st.kind == StepKind::bad_fcs;
      if (modifier || (is_action(st.kind) && !fault_ && !bad_fcs_)) {
        base_counters_ = chip_.fdl_counters();
        base_irq_ = interrupts().size();
        base_pb3_ = pb3_rises_;
      }
      note(chip_.cycle(), fmt::format("line {}: {}", st.line, st.text));
      // Requests counted, not history().size(): a long exchange step forgets history as it goes.
      const std::uint64_t sent = master_->counters().requests;
      act(st);
      if (master_->counters().requests != sent) settle();
      check_states();
      report_history();
      report_outputs();
      flush();
      forget_reported();
    }
    if (hooks_.at_end) hooks_.at_end(chip_);
    out_.final_cycle = chip_.cycle();
    out_.dp = chip_.dp_state();
    out_.wd = chip_.wd_state();
    out_.counters = chip_.fdl_counters();
    if (fw_) {
      for (const FirmwareHost::PortWrite& w : fw_->port_writes()) {
        out_.port_writes.push_back({w.cycle, fw_->port_name(w.port), w.value});
      }
    }
    note(chip_.cycle(),
         fmt::format("end: dp_state {}, wd_state {}; expects passed {}, failed {}",
                     dp_state_name(out_.dp), wd_state_name(out_.wd), out_.passed, out_.failed));
    flush();
    chip_.set_log_sink({});
    chip_.on_telegram({});
    chip_.on_irq_change({});
    chip_.on_pb3_change({});
    return out_;
  }

 private:
  struct Event {
    std::uint64_t cycle;
    std::string text;
  };

  void note(std::uint64_t cycle, std::string text) {
    if (walk_) events_.push_back(Event{cycle, std::move(text)});  // --quiet: nobody reads them
  }

  // Events are collected during an action and printed in cycle order: a transaction's line is
  // only known once its answer is in, after the state changes it caused.
  void flush() {
    std::stable_sort(events_.begin(), events_.end(),
                     [](const Event& a, const Event& b) { return a.cycle < b.cycle; });
    if (walk_) {
      for (const Event& e : events_) walk_(fmt::format("[cycle {:>10}] {}", e.cycle, e.text));
    }
    events_.clear();
  }

  void fail(int line, const std::string& msg) {
    const std::string text = fmt::format("{}:{}: {}", s_.file, line, msg);
    out_.failures.push_back(text);
    if (errors_) errors_(text);
  }

  std::uint32_t chip_baud() const {
    const unsigned code = (chip_.peek_reg(RegId::Status_Reg) >> 8) & 0xF;
    return code < std::size(kBaudRates) ? kBaudRates[code] : 0;
  }

  void check_states() {
    const DpState dp = chip_.dp_state();
    const WdState wd = chip_.wd_state();
    if (dp != dp_) {
      note(chip_.cycle(), fmt::format("dp_state {} -> {}", dp_state_name(dp_), dp_state_name(dp)));
      dp_ = dp;
    }
    if (wd != wd_) {
      std::string found;
      if (wd_ == WdState::Baud_Search) found = fmt::format(" ({} baud)", chip_baud());
      note(chip_.cycle(),
           fmt::format("wd_state {} -> {}{}", wd_state_name(wd_), wd_state_name(wd), found));
      wd_ = wd;
    }
  }

  // --- requests ---

  fdl::Frame predict(const ScenarioStep& st, const std::vector<std::uint8_t>& outputs) const {
    const std::uint8_t a = s_.master.address;
    const std::uint8_t t = master_->target();
    const auto srd = [&](std::optional<std::uint8_t> dsap, std::vector<std::uint8_t> du) {
      const std::optional<std::uint8_t> ssap =
          dsap ? std::optional<std::uint8_t>(sap::Master) : std::nullopt;
      return fdl::make_frame(t, a, fdl::make_request_fc(fdl::Function::SRD_high, !fcb_, fcv_),
                             std::move(du), dsap, ssap);
    };
    const SlaveConfig& sl = master_->slave();
    switch (st.kind) {
      case StepKind::exchange:
        return srd(std::nullopt, outputs);
      case StepKind::gc:
        return fdl::make_frame(
            fdl::kBroadcast, a, fdl::make_request_fc(fdl::Function::SDN_high, false, false),
            {static_cast<std::uint8_t>(st.value), static_cast<std::uint8_t>(st.value2)},
            sap::Global_Control, sap::Master);
      case StepKind::diag:
        return srd(sap::Slave_Diag, {});
      case StepKind::get_cfg:
        return srd(sap::Get_Cfg, {});
      case StepKind::read_inputs:
        return srd(sap::Rd_Inp, {});
      case StepKind::read_outputs:
        return srd(sap::Rd_Outp, {});
      case StepKind::set_prm:
        return srd(sap::Set_Prm, prm_du(sl));
      case StepKind::chk_cfg:
        return srd(sap::Chk_Cfg, sl.cfg);
      case StepKind::set_slave_address:
        return srd(sap::Set_Slave_Add,
                   {static_cast<std::uint8_t>(st.value), static_cast<std::uint8_t>(sl.ident >> 8),
                    static_cast<std::uint8_t>(sl.ident), static_cast<std::uint8_t>(st.value2)});
      default:
        return fdl::make_frame(t, a, fdl::make_request_fc(fdl::Function::FDL_Status, false, false));
    }
  }

  // Sends the damaged copy of the action's first request, if a fault is pending. The chip
  // discards it, so the master gets no answer and repeats the request: the action proper.
  // Global_Control expects no answer: the damaged telegram is all there is (false).
  bool damage(const ScenarioStep& st, const std::vector<std::uint8_t>& outputs = {}) {
    if (!fault_ && !bad_fcs_) return true;
    const fdl::Frame f = predict(st, outputs);
    std::vector<std::uint8_t> bytes = fdl::encode(f);
    const std::size_t index = master_->history().size();
    if (bad_fcs_) {
      bad_fcs_ = false;
      bytes[bytes.size() - 2] = static_cast<std::uint8_t>(bytes[bytes.size() - 2] + 1);
      master_->transact_raw(bytes);
      notes_[index] = "bad FCS";
    } else {
      UartFault fl = *fault_;
      fault_.reset();
      if (fl.char_index < 0) fl.char_index = static_cast<int>(bytes.size()) - 1;
      if (static_cast<std::size_t>(fl.char_index) >= bytes.size()) {
        fail(fault_line_, fmt::format("corrupt char={}: the request has only {} characters, sent "
                                      "undamaged",
                                      fl.char_index, bytes.size()));
        return true;
      }
      master_->transact(f, fl);
      notes_[index] = fmt::format("{} in char {}", fault_name(fl.kind), fl.char_index);
    }
    sent_[index] = f;
    if (st.kind == StepKind::gc) return false;
    repeat_ = std::make_pair(index + 1, f);
    repeat_line_ = fault_line_;
    return true;
  }

  // A request without an answer is sent again, unchanged (same FCB), up to `retries` times.
  Exchange with_retries(Exchange ex) { return master_->retry(std::move(ex), s_.retries); }

  void foreign_master(std::uint8_t a) {
    const std::uint8_t t = master_->target();
    const Exchange fs = with_retries(master_->transact(
        fdl::make_frame(t, a, fdl::make_request_fc(fdl::Function::FDL_Status, false, false))));
    if (!fs.answer) return;
    // Its first SRD after FDL_Status: FCB = 1, FCV = 1; Lock_Req as any class-1 master sends.
    with_retries(master_->transact(
        fdl::make_frame(t, a, fdl::make_request_fc(fdl::Function::SRD_high, true, true),
                        prm_du(master_->slave()), sap::Set_Prm, sap::Master)));
  }

  // Runs on to the earliest start of the master's next request (TSYN after the last telegram,
  // as DpMaster times it), so the firmware has answered what the action raised and checks see
  // a settled slave. The master's timing is unchanged: it could not have sent earlier.
  void settle() {
    const Exchange& ex = master_->history().back();
    std::uint64_t free = chip_.cycle();
    if (ex.answer_end != 0) {
      free = ex.answer_end;
    } else if (!wants_answer(request_of(master_->history().size() - 1))) {
      free = ex.request_end;
    }
    const std::uint64_t next = free + std::uint64_t{s_.master.idle_bits} * master_->bit_cycles();
    if (next > chip_.cycle()) master_->idle(next - chip_.cycle());
  }

  void silence(std::uint64_t cycles) {
    // Stop at each watchdog deadline so a state change without an interrupt (Baud_Control ->
    // Baud_Search) is reported at its own cycle.
    const std::uint64_t end = chip_.cycle() + cycles;
    while (chip_.cycle() < end) {
      std::uint64_t next = std::min(end, chip_.watchdog_due());
      if (next <= chip_.cycle()) next = end;
      master_->idle(next - chip_.cycle());
      check_states();
    }
  }

  void act(const ScenarioStep& st) {
    switch (st.kind) {
      case StepKind::startup: {
        damage(st);
        const bool ok = master_->startup(static_cast<int>(st.count));
        note(chip_.cycle(), ok ? std::string("startup: slave ready for Data_Exchange")
                               : fmt::format("startup: slave not ready after {} tries", st.count));
        break;
      }
      case StepKind::restart: {
        damage(st);
        const bool ok = master_->restart(st.count, s_.retries);
        note(chip_.cycle(), ok ? std::string("restart: slave ready for Data_Exchange")
                               : fmt::format("restart: slave not ready after {} tries", st.count));
        break;
      }
      case StepKind::exchange: {
        if (st.has_bytes) outputs_ = st.bytes;
        damage(st, outputs_);
        for (std::uint64_t i = 0; i < st.count; ++i) {
          with_retries(master_->data_exchange(outputs_));
          report_history();  // as it goes: `exchange 1000000` keeps memory flat
          forget_reported();
        }
        break;
      }
      case StepKind::gc:
        if (damage(st)) {
          master_->global_control(static_cast<std::uint8_t>(st.value),
                                  static_cast<std::uint8_t>(st.value2));
        }
        break;
      case StepKind::diag:
        damage(st);
        with_retries(master_->slave_diag());
        break;
      case StepKind::fdl_status:
        damage(st);
        with_retries(master_->fdl_status());
        break;
      case StepKind::get_cfg:
        damage(st);
        with_retries(master_->get_cfg());
        break;
      case StepKind::read_inputs:
        damage(st);
        with_retries(master_->read_inputs());
        break;
      case StepKind::read_outputs:
        damage(st);
        with_retries(master_->read_outputs());
        break;
      case StepKind::set_prm:
        master_->slave() = *st.slave;
        damage(st);
        with_retries(master_->set_prm());
        break;
      case StepKind::chk_cfg:
        master_->slave() = *st.slave;
        damage(st);
        with_retries(master_->chk_cfg());
        break;
      case StepKind::set_slave_address: {
        damage(st);
        const Exchange ex = with_retries(
            master_->set_slave_address(static_cast<std::uint8_t>(st.value), st.value2 != 0));
        if (ex.answer && ex.answer->sd == fdl::SC) {
          master_->set_target(static_cast<std::uint8_t>(st.value));
          note(chip_.cycle(), fmt::format("master: slave now addressed as {}", st.value));
        }
        break;
      }
      case StepKind::foreign_master:
        foreign_master(static_cast<std::uint8_t>(st.value));
        break;
      case StepKind::silence:
        silence(st.cycles);
        break;
      case StepKind::inputs:
        user_.inputs = st.bytes;
        break;
      case StepKind::hw:
        if (const std::string err = fw_->hw_input(st.name, st.value); !err.empty()) {
          fail(st.line, err);
        }
        break;
      case StepKind::corrupt:
        fault_ = st.fault;
        fault_line_ = st.line;
        break;
      case StepKind::bad_fcs:
        bad_fcs_ = true;
        fault_line_ = st.line;
        break;
      case StepKind::expect:
        break;
    }
  }

  // --- the walk ---

  const fdl::Frame& request_of(std::size_t i) const {
    const auto it = sent_.find(i);
    return it != sent_.end() ? it->second : master_->history()[i].request;
  }

  std::string describe(std::size_t i) const {
    const fdl::Frame& req = request_of(i);
    std::string s = fmt::format("{} -> {} {}", req.sa, req.da, service_name(req));
    if (!req.du.empty()) s += " " + hex(req.du);
    const auto it = notes_.find(i);
    if (it != notes_.end()) s += " [" + it->second + "]";
    if (wants_answer(req)) s += " => " + answer_text(master_->history()[i].answer);
    return s;
  }

  // What the expects need from each transaction, and the master's FCB for predict().
  void track(std::size_t i) {
    const Exchange& ex = master_->history()[i];
    const fdl::Frame& req = request_of(i);
    if (repeat_ && repeat_->first == i) {
      if (!(req == repeat_->second)) {
        fail(repeat_line_, "internal: the master's repeat differs from the damaged request");
      }
      repeat_.reset();
    }
    if (req.sa != s_.master.address || notes_.count(i) != 0) return;
    const fdl::Function fn = fdl::request_function(req.fc);
    if (fn == fdl::Function::SRD_high && req.da != fdl::kBroadcast) {
      fcb_ = fdl::fcb(req.fc);
      fcv_ = fdl::fcv(req.fc);
    } else if (fn == fdl::Function::FDL_Status && ex.answer) {
      fcb_ = false;  // DpMaster: the first SRD after FDL_Status has FCB = 1, FCV = 1
      fcv_ = true;
    }
    if (!ex.answer) return;
    const fdl::Frame& a = *ex.answer;
    const bool data = a.sd != fdl::SC && (fdl::response_code(a.fc) == fdl::Response::DL ||
                                          fdl::response_code(a.fc) == fdl::Response::DH);
    const bool dx = !req.dsap && fn == fdl::Function::SRD_high;
    if ((dx && (data || a.sd == fdl::SC)) ||
        (req.dsap && fdl::sap_number(*req.dsap) == sap::Rd_Inp && data)) {
      last_inputs_ = a.sd == fdl::SC ? std::vector<std::uint8_t>{} : a.du;
    }
    if (req.dsap && fdl::sap_number(*req.dsap) == sap::Slave_Diag && data) last_diag_ = a.du;
  }

  void report_history() {
    const std::vector<Exchange>& h = master_->history();
    while (reported_ < h.size()) {
      const std::size_t i = reported_;
      track(i);
      // A run of the same unanswered request (baud search, retries) is one line.
      std::size_t j = i;
      while (j + 1 < h.size() && !h[i].answer && !h[j + 1].answer && notes_.count(i) == 0 &&
             notes_.count(j + 1) == 0 && request_of(j + 1) == request_of(i)) {
        track(++j);
      }
      std::string line = describe(i);
      if (j > i) line += fmt::format(" (x{}, last at cycle {})", j - i + 1, h[j].request_start);
      note(h[i].request_start, std::move(line));
      reported_ = j + 1;
    }
  }

  // Once a step is reported, the master's history is not needed but for its last exchange (the
  // `answer` expect reads it; a damaged request's note may name it): memory stays flat over a
  // long run. Not while a repeat of a damaged request is still to come (it names a later index).
  void forget_reported() {
    const std::size_t n = master_->history().size();
    if (n < 2 || reported_ != n || repeat_) return;
    const auto keep_last = [n](auto& by_index) {
      const auto it = by_index.find(n - 1);
      if (it == by_index.end()) {
        by_index.clear();
        return;
      }
      auto v = std::move(it->second);
      by_index.clear();
      by_index.emplace(0, std::move(v));
    };
    keep_last(notes_);
    keep_last(sent_);
    master_->keep_last_exchange();
    reported_ = 1;
  }

  void report_outputs() {
    for (; outputs_seen_ < user_.outputs.size(); ++outputs_seen_) {
      const Responder::Output& o = user_.outputs[outputs_seen_];
      if (shown_output_ && shown_output_->first == o.data && shown_output_->second == o.cleared) {
        continue;  // only changes: every Data_Exchange hands over outputs
      }
      note(o.cycle,
           fmt::format("user: outputs {}{}", bytes_text(o.data), o.cleared ? " (cleared)" : ""));
      shown_output_ = std::make_pair(o.data, o.cleared);
    }
  }

  const std::vector<std::pair<std::uint64_t, std::uint16_t>>& interrupts() const {
    return fw_ ? fw_->interrupts : user_.interrupts;
  }

  // Port values in hex and, for the bit patterns of digital outputs, binary.
  static std::string port_text(std::uint32_t v) {
    return v <= 0xF ? fmt::format("0x{:X} ({:04b})", v, v) : fmt::format("0x{:X}", v);
  }

  std::string time_text(std::uint64_t cycle) const {
    return fmt::format("{:.3f} us", static_cast<double>(cycle) * 1e6 / chip_.clock_hz());
  }

  // --- checks ---

  void check(const ScenarioStep& st) {
    std::string what;
    std::string want;
    std::string got;
    const std::vector<Responder::Output>& outs = user_.outputs;
    switch (st.expect) {
      case ExpectKind::dp_state:
        what = "dp_state";
        want = dp_state_name(static_cast<DpState>(st.value));
        got = dp_state_name(chip_.dp_state());
        break;
      case ExpectKind::wd_state:
        what = "wd_state";
        want = wd_state_name(static_cast<WdState>(st.value));
        got = wd_state_name(chip_.wd_state());
        break;
      case ExpectKind::outputs:
        what = "outputs";
        want = st.value != 0 ? "none" : bytes_text(st.bytes);
        got = outs.empty() ? "none" : bytes_text(outs.back().data);
        break;
      case ExpectKind::cleared:
        what = "cleared";
        want = std::to_string(st.value);
        got = outs.empty() ? "no outputs fetched" : outs.back().cleared ? "1" : "0";
        break;
      case ExpectKind::inputs:
        what = "inputs";
        want = bytes_text(st.bytes);
        got = last_inputs_ ? bytes_text(*last_inputs_) : "no inputs received";
        break;
      case ExpectKind::counter: {
        what = "counter " + st.name;
        const auto fields = fdl_counter_fields();
        const auto f = std::find_if(fields.begin(), fields.end(),
                                    [&](const CounterField& c) { return c.name == st.name; });
        const std::uint32_t now = chip_.fdl_counters().*(f->member);
        if (st.value2 != 0) {
          want = fmt::format("+{}", st.value);
          got = fmt::format("+{}", now - base_counters_.*(f->member));
          if (got != want) got += fmt::format(" (now {})", now);
        } else {
          want = std::to_string(st.value);
          got = std::to_string(now);
        }
        break;
      }
      case ExpectKind::irr_bit: {
        what = "irr_bit " + st.name;
        // The firmware acknowledges what it handles, so the register alone rarely shows an
        // event: what its ISR saw during the last action counts as well.
        std::uint16_t seen = chip_.peek_reg(RegId::Int_Req_Reg);
        for (std::size_t i = base_irq_; i < interrupts().size(); ++i) {
          seen |= interrupts()[i].second;
        }
        want = std::to_string(st.value);
        got = ((seen >> st.value2) & 1) != 0 ? "1" : "0";
        break;
      }
      case ExpectKind::answer: {
        what = "answer";
        const std::optional<fdl::Frame> last =
            master_->history().empty() ? std::nullopt : master_->history().back().answer;
        want = st.name;
        got = answer_is(last, st.name) ? st.name : answer_kind(last);
        break;
      }
      case ExpectKind::station:
        what = "station";
        want = std::to_string(st.value);
        got = std::to_string(chip_.station_address());
        break;
      case ExpectKind::diag_byte:
        what = fmt::format("diag_byte {}", st.value2);
        want = fmt::format("0x{:02X}", st.value);
        got = !last_diag_                       ? std::string("no diagnosis received")
              : st.value2 >= last_diag_->size() ? fmt::format("{} bytes", last_diag_->size())
                                                : fmt::format("0x{:02X}", (*last_diag_)[st.value2]);
        break;
      case ExpectKind::baud:
        what = "baud";
        want = std::to_string(st.value);
        got = std::to_string(chip_baud());
        break;
      case ExpectKind::pb3:
        // DX_Out is acknowledged by the ISR at once, so a rise during the last action counts.
        what = "pb3";
        want = std::to_string(st.value);
        got = chip_.pb3_pin() || pb3_rises_ > base_pb3_ ? "1" : "0";
        break;
      case ExpectKind::port:
        what = "port " + st.name;
        want = port_text(st.value);
        got = port_text(static_cast<std::uint32_t>(fw_->port(st.name)));
        break;
    }
    if (got == want) {
      ++out_.passed;
      note(chip_.cycle(), fmt::format("line {}: {}: ok", st.line, st.text));
    } else {
      ++out_.failed;
      note(chip_.cycle(), fmt::format("line {}: {}: FAILED, got {}", st.line, st.text, got));
      fail(st.line, fmt::format("expected {} {}, got {}", what, want, got));
    }
    flush();
  }

  const Scenario& s_;
  const LineSink& walk_;
  const LineSink& errors_;
  const ScenarioHooks& hooks_;
  Chip chip_;
  Responder user_;
  std::unique_ptr<FirmwareHost> fw_;  // instead of user_ when the scenario names a firmware
  std::unique_ptr<DpMaster> master_;
  ScenarioOutcome out_;
  std::vector<Event> events_;
  DpState dp_ = DpState::Wait_Prm;
  WdState wd_ = WdState::Baud_Search;
  std::vector<std::uint8_t> outputs_;  // what `exchange` sends when no outputs= is given
  // Faults waiting for the next request, and what was sent in their place.
  std::optional<UartFault> fault_;
  bool bad_fcs_ = false;
  int fault_line_ = 0;
  std::map<std::size_t, std::string> notes_;                  // history index -> the damage done
  std::map<std::size_t, fdl::Frame> sent_;                    // history index -> the frame damaged
  std::optional<std::pair<std::size_t, fdl::Frame>> repeat_;  // the master's repeat, checked
  int repeat_line_ = 0;
  // The master's FCB state as DpMaster keeps it (private there), for predict().
  bool fcb_ = true;
  bool fcv_ = false;
  // Walk and expects bookkeeping.
  std::size_t reported_ = 0;
  std::size_t outputs_seen_ = 0;
  std::optional<std::pair<std::vector<std::uint8_t>, bool>> shown_output_;
  std::optional<std::vector<std::uint8_t>> last_inputs_;
  std::optional<std::vector<std::uint8_t>> last_diag_;
  FdlCounters base_counters_;
  std::size_t base_irq_ = 0;
  std::size_t pb3_rises_ = 0;  // PB3 rising edges so far (dpc31 DX_Out port)
  std::size_t base_pb3_ = 0;
};

}  // namespace

bool parse_scenario(std::string_view text, const std::string& file, Scenario& out,
                    ScenarioError& err) {
  Scenario s;
  s.file = file;
  Parser p(s);
  int no = 0;
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);  // a UTF-8 BOM from an editor
  try {
    for (std::string_view line : split(text, '\n')) p.line(++no, line);
    p.finish();
  } catch (const ParseFail& f) {
    err = ScenarioError{file, f.line == 0 ? no : std::max(f.line, 0), f.message};
    return false;
  }
  out = std::move(s);
  return true;
}

bool load_scenario(const std::string& path, Scenario& out, ScenarioError& err) {
  err = ScenarioError{path, 0, {}};
  std::string text;
  if (!read_text_file(path, kMaxFileBytes, "scenario", text, err.message)) return false;
  if ((err.line = cut_off_line(text, err.message)) != 0) return false;
  return parse_scenario(text, path, out, err);
}

ScenarioOutcome run_scenario(const Scenario& s, const LineSink& walk, const LineSink& errors,
                             const ScenarioHooks& hooks) {
  Runner r(s, walk, errors, hooks);
  return r.run();
}

int run_scenario_file(const std::string& path, const LineSink& walk, const LineSink& errors,
                      Scenario* scenario, ScenarioOutcome* outcome) {
  Scenario s;
  ScenarioError err;
  if (!load_scenario(path, s, err)) {
    if (errors) errors(err.text());
    return 2;
  }
  const ScenarioOutcome o = run_scenario(s, walk, errors);
  const int rc = o.ok() ? 0 : 1;
  if (scenario != nullptr) *scenario = std::move(s);
  if (outcome != nullptr) *outcome = o;
  return rc;
}

}  // namespace dpc31
