// Scenario files: the parser (text -> Scenario). The format and every command:
// docs/scenario-format.md; the runner is scenario_run.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <map>
#include <utility>

#include "dpc31/dpv1.hpp"
#include "dpc31/fdl.hpp"
#include "firmware.h"
#include "firmware_host.hpp"
#include "scenario.hpp"
#include "scenario_bus.hpp"
#include "scenario_dpv1.hpp"
#include "scenario_expect.hpp"
#include "scenario_lex.hpp"
#include "scenario_send.hpp"
#include "textfile.hpp"

namespace dpc31 {

std::string ScenarioError::text() const {
  // One line whatever the file's name holds (a newline, an ESC).
  if (line <= 0) return shown_line(fmt::format("{}: {}", file, message));
  return shown_line(fmt::format("{}:{}: {}", file, line, message));
}

namespace {

using namespace scenario_lex;  // NOLINT: the parser's own lexical helpers

constexpr std::uint64_t kMaxExchanges = 1'000'000;

constexpr std::string_view kAnswerKinds[] = {"none", "sc", "data", "ok", "ue",
                                             "rr",   "rs", "dl",   "nr", "dh"};

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// Actions whose first telegram a fault can be injected into.
bool sends_request(StepKind k) {
  return is_action(k) && k != StepKind::silence && k != StepKind::foreign_master &&
         k != StepKind::write && k != StepKind::read && k != StepKind::send &&
         k != StepKind::request && k != StepKind::dpv1 && k != StepKind::reset;
}

class Parser {
 public:
  Parser(Scenario& s, const dpc31_firmware* bound) : s_(s), bound_(bound) {}

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
    if (first_line_ == 0) {
      first_line_ = no;
      first_cmd_ = std::string(cmd_);
    }
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
      // Given twice, a header's second line would silently replace the first (a `record` is one
      // record each, checked for its slot and index).
      if (cmd_ != "record") {
        const auto [first, fresh] = header_lines_.try_emplace(std::string(cmd_), no);
        if (!fresh) fail(fmt::format("'{}' given twice: first at line {}", cmd_, first->second));
      }
      return;
    }
    if (!body_) {
      profile_options_checked();
      view_ = s_.user.slave;
      view_wd_base_10ms_ = wd_base_line_ != 0 && wd_base_10ms_;
    }
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
      if (is_fault(st.kind)) {
        if (fault != nullptr) {
          fail_at(st.line,
                  fmt::format("a second fault before the request of line {}", fault->line));
        }
        fault = &st;
        continue;
      }
      if (fault == nullptr || !is_action(st.kind)) continue;
      if (!sends_request(st.kind)) {
        // A DPV1 service sends a request and polls, but is not one a fault damages
        // (docs/scenario-format.md, "DPV1").
        const std::string_view why = st.kind == StepKind::dpv1
                                         ? "is a DPV1 service: a fault line cannot damage it"
                                         : "sends no request to damage";
        fail_at(fault->line, fmt::format("the next action ('{}', line {}) {}",
                                         st.text.substr(0, st.text.find(' ')), st.line, why));
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

  std::uint32_t clock() const {
    return s_.chip.clock_hz != 0 ? s_.chip.clock_hz : chip_timing().clock_hz;
  }

  // No silent options (docs/decisions.md, "No silent options"): once the headers are complete, an
  // option the chosen profile has nothing for is refused at its line.
  void profile_options_checked() const {
    const Profile p = s_.chip.profile;
    if (substitute_line_ != 0 && p != Profile::dpc31) {
      fail_at(substitute_line_, substitute_is_for_dpc31("user substitute="));
    }
    if (dx_out_port_line_ != 0 && p != Profile::dpc31) {
      fail_at(dx_out_port_line_, dx_out_port_is_for_dpc31("user dx_out_port="));
    }
    if (user_wd_value_line_ != 0 && p == Profile::dpc31 && !s_.user.user_watchdog) {
      fail_at(user_wd_value_line_, user_wd_value_needs_user_wd("user user_wd_value="));
    }
    if (wd_base_line_ != 0) {
      wd_base_checked(s_.user.slave, wd_base_line_);
      wd_base_agrees(s_.user.slave, wd_base_10ms_, wd_base_line_);
    }
    // The built-in user side's DPV1 part answers only what the chip hands it: without
    // DPV1_Enable the SAP list stays off (every request RS), without a record there is none.
    if (const std::string why = records_need_dpv1("record", s_.user.slave.user_prm);
        record_line_ != 0 && !why.empty()) {
      fail_at(record_line_, why);
    }
    if (work_line_ != 0 && (firmware_seen_ || s_.cpu)) {
      fail_at(work_line_, scenario_dpv1::user_side_only("dpv1 work="));
    }
    if (work_line_ != 0 && record_line_ == 0) {
      fail_at(work_line_,
              "dpv1 work= is the built-in user side's DPV1 time and needs a record: without one "
              "it serves no DPV1");
    }
    if (s_.cpu) {  // `bus` and `irq-controller` may come after `cpu`
      if (const std::string why = s_.cpu->chip_problem(s_.chip); !why.empty())
        fail_at(cpu_line_, why);
    }
    const std::uint8_t slave = s_.user.slave.address;
    if (slave == s_.master.address) {
      // The later of the two lines that set them (one may be the other's default).
      fail_at(std::max(master_address_line_, slave_address_line_), master_and_slave_at(slave));
    }
    if (const std::string why = inputs_length_problem(s_.inputs.size(), s_.user.slave.in_len);
        inputs_line_ != 0 && !why.empty()) {
      fail_at(inputs_line_, "user inputs=: " + why);
    }
    if (const std::string why =
            substitute_length_problem(s_.user.substitute.size(), s_.user.slave.out_len);
        substitute_line_ != 0 && !why.empty()) {
      fail_at(substitute_line_, "user substitute=: " + why);
    }
    // The built-in user side's buffers must fit this profile's RAM (the lengths are `slave`'s,
    // the DPV1 part's room the records').
    if (const std::string why = responder_layout_problem(profile_desc(p), s_.user);
        !firmware_seen_ && !s_.cpu && !why.empty()) {
      fail_at(slave_line_ != 0 ? slave_line_ : record_line_, "slave " + why);
    }
  }
  // The VPC3+ takes WD_Base from Set_Prm's DPV1_Status_1 only with DPV1_Enable; without it
  // Mode_Reg0.WD_Base decides (VPC3+C p.53, docs/dpv1.md).
  void wd_base_checked(const SlaveConfig& sl, int line) const {
    if (s_.chip.profile != Profile::vpc3plus) return;
    if (!sl.user_prm.empty() && (sl.user_prm[0] & dpv1::status1::DPV1_Enable) != 0) return;
    fail_at(line, wd_base_needs_dpv1("wd_base="));
  }

  // wd_base=10ms and user_prm byte 0 bit 2 (1 ms) both give Set_Prm byte 7 bit 2: the master
  // would send the 1 ms base, so the contradiction is refused (No silent options).
  void wd_base_agrees(const SlaveConfig& sl, bool wd_base_10ms, int line) const {
    if (!wd_base_10ms || sl.user_prm.empty() || (sl.user_prm[0] & dpv1::status1::WD_Base) == 0)
      return;
    fail_at(line, wd_base_contradicts_user_prm());
  }

  // Cycles, or a time with a unit; rounded up like every minimum time (docs/timing.md).
  std::uint64_t duration(std::string_view s) const {
    return scenario_lex::duration(s, clock(), bit_cycles(clock(), s_.master.baud));
  }

  // Options of `slave` that also apply to `set_prm` (what Set_Prm carries).
  bool prm_option(SlaveConfig& sl, std::string_view k, std::string_view v) const {
    if (k == "ident") {
      sl.ident = static_cast<std::uint16_t>(number(v, kIdent));
    } else if (k == "wd") {
      const std::vector<std::string_view> f = split(v, ',');
      if (f.size() != 2) fail(fmt::format("wd='{}': two factors, as in wd=10,10", shown(v)));
      sl.wd_fact1 = static_cast<std::uint8_t>(number(f[0], kWdFactor1));
      sl.wd_fact2 = static_cast<std::uint8_t>(number(f[1], kWdFactor2));
    } else if (k == "wd_on") {
      sl.wd_on = flag(v, "wd_on");
    } else if (k == "wd_base") {
      if (v != "1ms" && v != "10ms") fail(fmt::format("wd_base '{}': 1ms or 10ms", shown(v)));
      sl.wd_base_1ms = v == "1ms";
      wd_base_10ms_ = !sl.wd_base_1ms;
      wd_base_line_ = step_.line;
    } else if (k == "group") {
      sl.group_ident = static_cast<std::uint8_t>(number(v, kGroupIdent));
    } else if (k == "sync") {
      sl.sync_req = flag(v, "sync");
    } else if (k == "freeze") {
      sl.freeze_req = flag(v, "freeze");
    } else if (k == "min_tsdr") {
      sl.min_tsdr = static_cast<std::uint8_t>(number(v, kMinTsdr));
    } else if (k == "user_prm") {
      // The master always sends byte 7 (DpMaster's prm_du): "none" would be a byte 7 of 00.
      if (v == "-") {
        fail(
            "user_prm=-: the master always sends byte 7 (user_prm=00 is that byte as 00); a "
            "Set_Prm of 7 bytes is 'set_prm bytes=BYTES'");
      }
      sl.user_prm = bytes(v, "user_prm", kMaxDu - 7);
    } else {
      return false;
    }
    return true;
  }

  [[nodiscard]] std::string beside_scenario(const std::string& path) const {
    return beside_file(s_.file, path);
  }
  // `cpu 80c32 clock=HZ firmware FILE.ihx [base=A] [latch=A] [ports=N1,N2...]`, or `cpu c31
  // clock=HZ firmware FILE.ihx [code=A]` on the dpc31 (the C31 serves its own interrupt
  // controller): only checked here; the image is read when the run starts (cpu51_module.hpp).
  void cpu_header() {
    positional(3, 3, "80c32 firmware FILE.ihx");
    const std::string_view core = cpu_core(pos_[0]);
    const bool c31 = core == "c31";
    if (core.empty() || pos_[1] != "firmware") {
      fail(
          fmt::format("{}the form is 'cpu 80c32 [clock=HZ] firmware FILE [base=A] [latch=A] "
                      "[ports=N1,N2...]' or 'cpu c31 [clock=HZ] firmware FILE [code=A]'",
                      core.empty() ? fmt::format("unknown CPU '{}' (80c32, c31): ", shown(pos_[0]))
                                   : std::string()));
    }
    // Line-ordered as `irq-controller`: the default profile is no `profile` line.
    if (c31 && (profile_line_ == 0 || s_.chip.profile != Profile::dpc31))
      fail("'cpu c31' needs 'profile dpc31' before it: only the DPC31 has a C31 core");
    if (firmware_seen_ || user_seen_ || slave_seen_ || !s_.user.dpv1.records.empty())
      fail("'cpu' comes before 'slave', without 'firmware', 'user' and 'record'");
    cpu_line_ = step_.line;
    Cpu51Config c{.hex = beside_scenario(std::string(pos_[2])), .c31 = c31};
    for (const auto& [k, v] : opts_) {
      if (k == "clock") {
        c.hz = static_cast<std::uint32_t>(number(v, kCpuClock));
      } else if (c31 && k == "code") {
        c.code = static_cast<std::uint16_t>(number(v, kC31Code));
      } else if (c31) {
        fail(fmt::format("'cpu c31' takes clock= and code= ('{}=' is the 80C32 board's)", k));
      } else if (k == "base" || k == "latch") {  // the latch an address in the same range
        (k == "base" ? c.base : c.latch) =
            static_cast<std::uint16_t>(number(v, k, kBoardBase.min, kBoardBase.max));
      } else if (k == "ports") {
        for (std::string_view n : split(v, ',')) c.ports.emplace_back(n);
        if (const std::string why = c.ports_problem(); !why.empty()) fail("ports=: " + why);
      } else {
        unknown_option(k);
      }
    }
    if (const std::string why = c31 ? "" : c.latch_problem(); !why.empty()) fail(why);
    if (c31) s_.chip.irq_controller = IrqController::c31;
    s_.cpu = std::move(c);
    s_.cpu_line = step_.line;
    for (const std::string& n : s_.cpu->latch_ports()) ports_.insert(ports_.end() - 1, n.c_str());
  }

  bool header() {
    if (cmd_ == "profile") {
      positional(1, 1, "one of spc3, vpc3plus, dpc31");
      no_options();
      if (!parse_profile(pos_[0], s_.chip.profile)) {
        fail(fmt::format("unknown profile '{}' (spc3, vpc3plus, dpc31)", shown(pos_[0])));
      }
      profile_line_ = step_.line;
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
    } else if (cmd_ == "irq-controller") {
      positional(1, 1, "external or c31");
      no_options();
      irq_controller_line_ = step_.line;
      if (!parse_irq_controller(pos_[0], s_.chip.irq_controller)) {
        fail(fmt::format("unknown irq-controller '{}' (external, c31)", shown(pos_[0])));
      }
      // After `profile dpc31` only (docs/scenario-format.md), as `variant` after its profile:
      // the default profile is no `profile` line.
      if (profile_line_ == 0 || s_.chip.profile != Profile::dpc31) {
        fail("'irq-controller' needs 'profile dpc31' before it: only the DPC31 has a C31 core");
      }
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
      s_.master.baud = profibus_baud(pos_[0]);
    } else if (cmd_ == "master") {
      positional(0, 0, "options only");
      for (const auto& [k, v] : opts_) {
        if (k == "address") {
          s_.master.address = static_cast<std::uint8_t>(number(v, kMasterAddress));
          master_address_line_ = step_.line;
        } else if (k == "slot") {
          s_.master.slot_bits = static_cast<std::uint32_t>(number(v, kSlotBits));
        } else if (k == "idle") {
          s_.master.idle_bits = static_cast<std::uint32_t>(number(v, kIdleBits));
        } else if (k == "retries") {
          s_.retries = static_cast<std::uint32_t>(number(v, kRetries));
        } else {
          unknown_option(k);
        }
      }
    } else if (cmd_ == "firmware") {
      positional(1, 1, "a firmware name or plug-in path");
      no_options();
      if (slave_seen_) fail("'firmware' comes before 'slave': it sets the slave's GSD defaults");
      if (user_seen_ || !s_.user.dpv1.records.empty())
        fail("'firmware' excludes 'user' and 'record' (the built-in user side's)");
      if (s_.cpu) fail("'firmware' and 'cpu' exclude each other");
      firmware_seen_ = true;
      s_.firmware_line = step_.line;
      std::string spec(pos_[0]);
      if (is_plugin_path(spec)) {
        spec = beside_scenario(spec);
        // Never loaded while parsing: bind_plugin() loads it before the run, once the whole file
        // has parsed (and the command has checked everything else), then parses again with it.
        s_.firmware = spec;
        fw_ = bound_;
      } else {
        try {
          fw_ = &find_firmware(spec);
        } catch (const FirmwareError& e) {
          fail(e.what());
        }
        s_.firmware = fw_->name;
      }
      s_.firmware_desc = fw_;
      if (fw_ != nullptr) {
        for (auto n = fw_->ports; n && *n; ++n) ports_.insert(ports_.end() - 1, *n);
      }
      if (fw_ != nullptr) s_.user.slave = with_gsd_defaults(*fw_, s_.user.slave);
    } else if (cmd_ == "cpu") {
      cpu_header();
    } else if (cmd_ == "slave") {
      positional(0, 0, "options only");
      slave_seen_ = true;
      slave_line_ = step_.line;
      SlaveConfig& sl = s_.user.slave;
      for (const auto& [k, v] : opts_) {
        if (prm_option(sl, k, v)) continue;
        if (k == "address") {
          sl.address = static_cast<std::uint8_t>(number(v, kSlaveAddress));
          slave_address_line_ = step_.line;
        } else if (k == "cfg") {
          sl.cfg = bytes(v, "cfg");
          if (sl.cfg.empty()) fail("cfg: at least one byte");
        } else if (k == "in") {
          sl.in_len = static_cast<std::uint8_t>(number(v, kInLen));
        } else if (k == "out") {
          sl.out_len = static_cast<std::uint8_t>(number(v, kOutLen));
        } else {
          unknown_option(k);
        }
      }
    } else if (cmd_ == "user") {
      positional(0, 0, "options only");
      if (firmware_seen_ || s_.cpu) fail(refused_beside_firmware("user"));
      user_seen_ = true;
      ResponderConfig& u = s_.user;
      for (const auto& [k, v] : opts_) {
        if (k == "inputs") {
          s_.inputs = bytes(v, "inputs");
          inputs_line_ = step_.line;
        } else if (k == "sync_supported") {
          u.sync_supported = flag(v, k);
        } else if (k == "freeze_supported") {
          u.freeze_supported = flag(v, k);
        } else if (k == "spec_clear") {
          u.spec_clear_mode = flag(v, k);
        } else if (k == "user_wd") {
          u.user_watchdog = flag(v, k);
        } else if (k == "user_wd_value") {
          user_wd_value_line_ = step_.line;
          u.user_wd_value = static_cast<std::uint16_t>(number(v, kUserWdValue));
        } else if (k == "wd_baud_control") {
          u.wd_baud_control = static_cast<std::uint8_t>(number(v, kWdBaudControl));
        } else if (k == "substitute") {
          substitute_line_ = step_.line;
          u.substitute = bytes(v, k);
        } else if (k == "dx_out_port") {
          dx_out_port_line_ = step_.line;
          u.dx_out_port = flag(v, k);
        } else {
          unknown_option(k);
        }
      }
    } else if (!scenario_dpv1::parse_header(cmd_, pos_, opts_, s_)) {
      return false;
    } else if (cmd_ == "record" && record_line_ == 0) {
      record_line_ = step_.line;
    } else if (cmd_ == "dpv1") {
      for (const auto& o : opts_) {
        if (o.first == "work") work_line_ = step_.line;
      }
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
      step_.count = number(v, kTries);
    }
  }

  void body() {
    if (cmd_ == "startup" || cmd_ == "restart") {
      step_.kind = cmd_ == "startup" ? StepKind::startup : StepKind::restart;
      tries(kStartupTries);
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
      for (const auto& [k, v] : opts_) {
        if (k == "groups") {
          step_.value2 = static_cast<std::uint32_t>(number(v, "groups", 0, 255));
        } else if (k == "data") {
          step_.bytes = bytes(v, "data");
          step_.has_bytes = true;
        } else if (!from_option(k, v)) {
          unknown_option(k);
        }
      }
      if (step_.has_bytes) {
        positional(0, 0, "no command with data= (the data unit as it is)");
        if (option("groups")) fail("gc: data= is the whole data unit; groups= goes into it");
      } else {
        positional(1, 1, "a command (sync, unsync, freeze, unfreeze, clear, operate, or a number)");
        step_.value = gc_command(pos_[0]);
        step_.bytes = {static_cast<std::uint8_t>(step_.value),
                       static_cast<std::uint8_t>(step_.value2)};
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
        if (k == "bytes") {
          step_.bytes = bytes(v, "bytes");
          step_.has_bytes = true;
        } else if (!from_option(k, v) && !prm_option(*step_.slave, k, v)) {
          unknown_option(k);
        }
      }
      if (step_.has_bytes && opts_.size() > (step_.from ? 2u : 1u)) {
        fail("set_prm: bytes= is the whole data unit; no other parameter options with it");
      }
      // wd_base= on this line, else the one the master's view of the slave carries.
      const bool here = wd_base_line_ == step_.line;
      const bool wd_base_10ms = here ? wd_base_10ms_ : view_wd_base_10ms_;
      if (here) wd_base_checked(*step_.slave, step_.line);
      wd_base_agrees(*step_.slave, wd_base_10ms, step_.line);
      if (!step_.from && !step_.has_bytes) {
        view_ = step_.slave;
        view_wd_base_10ms_ = wd_base_10ms;
      }
    } else if (cmd_ == "chk_cfg") {
      step_.kind = StepKind::chk_cfg;
      positional(0, 0, "options only");
      step_.slave = view_;
      for (const auto& [k, v] : opts_) {
        if (from_option(k, v)) continue;
        if (k != "cfg") unknown_option(k);
        step_.slave->cfg = bytes(v, "cfg");
        if (step_.slave->cfg.empty()) fail("cfg: at least one byte");
      }
      if (!step_.from) view_ = step_.slave;
    } else if (cmd_ == "send") {
      scenario_send::parse(pos_, opts_, step_);
    } else if (cmd_ == "set_slave_address") {
      step_.kind = StepKind::set_slave_address;
      positional(1, 1, "the new address");
      step_.value = static_cast<std::uint32_t>(number(pos_[0], kNewAddress));
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
    } else if (cmd_ == "reset") {
      // The RESET a CPU board shares with the chip (docs/cpu.md, "The board's reset"); a host's
      // firmware or the built-in user side would not start the chip again after it.
      if (!s_.cpu)
        fail("'reset' is the RESET of a CPU board (header 'cpu'), CPU and chip together");
      simple(StepKind::reset);
    } else if (cmd_ == "hw") {
      step_.kind = StepKind::hw;
      positional(2, 2, "a hardware input and a value");
      no_options();
      if (s_.cpu) {
        fail(
            fmt::format("'hw': the {} board wires no hardware inputs to its firmware (docs/cpu.md, "
                        "CNT2 on the 80C32, \"Limits\")",
                        s_.cpu->c31 ? "C31" : "80C32"));
      }
      if (!firmware_seen_) fail("'hw' needs a firmware (header 'firmware NAME')");
      if (fw_ != nullptr && name_index(fw_->hw_inputs, pos_[0]) < 0) {
        fail(fmt::format("unknown hardware input '{}' of {} ({})", shown(pos_[0]), fw_->name,
                         name_list(fw_->hw_inputs)));
      }
      step_.name = std::string(pos_[0]);
      // A built-in firmware's range is known now; a plug-in's hw_input says at the run.
      const std::optional<ValueRange> range =
          fw_ != nullptr ? builtin_hw_range(*fw_, pos_[0]) : std::nullopt;
      step_.value = static_cast<std::uint32_t>(
          number(pos_[1], range.value_or(ValueRange{"hw value", 0, 0xFFFF'FFFF})));
    } else if (cmd_ == "inputs") {
      if (firmware_seen_ || s_.cpu)
        fail("'inputs' feeds the built-in user side; a firmware makes its own");
      step_.kind = StepKind::inputs;
      positional(1, 1, "a byte list");
      no_options();
      step_.bytes = bytes(pos_[0], "inputs");
      if (const std::string why = inputs_length_problem(step_.bytes.size(), s_.user.slave.in_len);
          !why.empty()) {
        fail("inputs: " + why);
      }
    } else if (cmd_ == "corrupt") {
      step_.kind = StepKind::corrupt;
      positional(1, 1, "parity, start or stop");
      if (!parse_fault_kind(pos_[0], step_.fault.kind)) {
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
    } else if (scenario_bus::parse_action(cmd_, pos_, opts_, s_.chip.profile, step_, last_read_)) {
    } else if (scenario_dpv1::parse_action(cmd_, pos_, opts_, s_, step_)) {
    } else if (cmd_ == "segment") {
      // A segment's file has its own loader (scenario_segment.hpp), which `dpc31 run` takes for
      // a file whose first line is `segment`: after another line it is misplaced.
      if (first_line_ != step_.line) {
        fail(
            fmt::format("'segment' must be the first line of a segment scenario "
                        "(docs/scenario-format.md, \"Segments\"); '{}' (line {}) is a single "
                        "chip's, which a segment scenario has not",
                        shown(first_cmd_), first_line_));
      }
      fail(
          "'segment' begins a segment scenario (docs/scenario-format.md, \"Segments\"): load it "
          "with SegmentScenario (load_segment_scenario; dpc31.SegmentScenario in Python) or run "
          "it with `dpc31 run`");
    } else {
      fail(fmt::format("unknown command '{}'", shown(cmd_)));
    }
  }

  // from=SA: another master sends the request (docs/scenario-format.md, "Telegrams as given").
  bool from_option(std::string_view k, std::string_view v) {
    if (k != "from") return false;
    step_.from = static_cast<std::uint8_t>(number(v, "from", 0, 126));
    if (*step_.from == s_.master.address) {
      fail(fmt::format("from={} is our own master: leave from= out", *step_.from));
    }
    return true;
  }
  [[nodiscard]] bool option(std::string_view key) const {
    return std::any_of(opts_.begin(), opts_.end(), [&](const auto& o) { return o.first == key; });
  }

  void expect() {
    if (pos_.empty()) fail("'expect' needs what to check and the expected value");
    const std::string_view what = pos_[0];
    if (pos_.size() >= 3 && (pos_[pos_.size() - 2] == "at" || pos_[pos_.size() - 2] == "after")) {
      if (what != "dp_state" && what != "wd_state" && what != "dpv1" && what != "irq" &&
          what != "port") {
        fail(fmt::format(
            "'{}' is for dp_state, wd_state, dpv1, irq and port: the cycle a state was entered, a "
            "response ended, X/INT went active or a port was written",
            pos_[pos_.size() - 2]));
      }
      step_.when =
          pos_[pos_.size() - 2] == "at" ? ScenarioStep::When::at : ScenarioStep::When::after;
      step_.when_cycle = number(pos_.back(), "cycle", 0, kMaxSeconds * clock() * 1000);
      pos_.resize(pos_.size() - 2);
    }
    // The form (with its cycle for dp_state, wd_state and port) and the first word too many.
    auto args = [&](std::size_t n, std::string_view form) {
      if (pos_.size() == n + 1) return;
      const bool timed = what == "dp_state" || what == "wd_state" || what == "port";
      const std::string usage =
          fmt::format("expected 'expect {} {}{}'", what, form, timed ? " [at CYCLE|after N]" : "");
      if (pos_.size() < n + 1) fail(usage);
      fail(fmt::format("{}; unexpected '{}'", usage, shown(pos_[n + 1])));
    };
    if (what == "dp_state") {
      args(1, "Wait_Prm|Wait_Cfg|Data_Exchange");
      step_.expect = ExpectKind::dp_state;
      step_.value =
          state_value(pos_[1], {dp_state_name(DpState::Wait_Prm), dp_state_name(DpState::Wait_Cfg),
                                dp_state_name(DpState::Data_Exchange)});
    } else if (what == "wd_state") {
      args(1, "Baud_Search|Baud_Control|DP_Control");
      step_.expect = ExpectKind::wd_state;
      step_.value = state_value(
          pos_[1], {wd_state_name(WdState::Baud_Search), wd_state_name(WdState::Baud_Control),
                    wd_state_name(WdState::DP_Control)});
    } else if (what == "port") {
      args(2, "NAME VALUE");
      if (!firmware_seen_ && !s_.cpu) fail("'expect port' needs a firmware ('firmware' or 'cpu')");
      if ((fw_ != nullptr || s_.cpu) && name_index(ports_.data(), pos_[1]) < 0) {
        fail(fmt::format("unknown port '{}' of {} ({})", shown(pos_[1]),
                         fw_ ? fw_->name : "the 80C32 board", name_list(ports_.data())));
      }
      step_.expect = ExpectKind::port;
      step_.name = std::string(pos_[1]);
      // An 80C32 board's port is a byte of its latch; a host firmware's port value is 32 bits.
      step_.value =
          static_cast<std::uint32_t>(number(pos_[2], "port value", 0, s_.cpu ? 0xFF : 0xFFFF'FFFF));
    } else if (what == "outputs" || what == "inputs") {
      args(1, "BYTES");
      if (what == "outputs" && (firmware_seen_ || s_.cpu)) {
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
      if (firmware_seen_ || s_.cpu) {
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
      step_.value2 = scenario_expect::irq_bit(s_.chip.profile, pos_[1]);
      step_.value = flag(pos_[2], "irr_bit") ? 1 : 0;
    } else if (what == "answer") {
      args(1, "none|sc|data|ok|ue|rr|rs|dl|nr|dh");
      step_.expect = ExpectKind::answer;
      if (std::find(std::begin(kAnswerKinds), std::end(kAnswerKinds), pos_[1]) ==
          std::end(kAnswerKinds)) {
        if (pos_[1].find_first_not_of("0123456789abcdefABCDEFxX,") != std::string_view::npos) {
          fail(
              fmt::format("unknown answer kind '{}' (none, sc, data, ok, ue, rr, rs, dl, nr, dh, "
                          "or the answer's bytes)",
                          shown(pos_[1])));
        }
        step_.bytes = bytes(pos_[1], "answer", fdl::kMaxFrameLength);  // the whole telegram
        step_.has_bytes = true;
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
      if (s_.chip.profile != Profile::dpc31) fail("'expect pb3' needs profile dpc31");
      step_.expect = ExpectKind::pb3;
      step_.value = flag(pos_[1], "pb3") ? 1 : 0;
    } else if (what == "baud") {
      args(1, "N");
      step_.expect = ExpectKind::baud;
      step_.value = static_cast<std::uint32_t>(number(pos_[1], "baud", 1, 12'000'000));
    } else if (what == "dpv1") {
      scenario_dpv1::parse_expect(pos_, s_, step_);
    } else if (what == "irq") {
      scenario_expect::parse_irq(pos_, s_.chip.profile, step_);
    } else if (!scenario_bus::parse_expect(pos_, s_.chip.profile, last_read_, step_)) {
      fail(fmt::format(
          "unknown check '{}' (dp_state, wd_state, outputs, cleared, inputs, counter, "
          "irr_bit, irq, answer, station, diag_byte, baud, port, pb3, reg, ram, read, dpv1)",
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

  Scenario& s_;
  ScenarioStep step_;
  std::optional<SlaveConfig> view_;  // the master's view of the slave after the steps so far
  bool headers_ = false;
  std::string first_cmd_;  // the file's first command and its line (a misplaced `segment`)
  int first_line_ = 0;
  const dpc31_firmware* bound_;         // the plug-in bind_plugin() loaded, or nullptr
  const dpc31_firmware* fw_ = nullptr;  // the firmware's descriptor, once known
  bool firmware_seen_ = false;
  std::vector<const char*> ports_{nullptr};  // the firmware's port names, NULL-terminated
  bool slave_seen_ = false;
  bool user_seen_ = false;
  // The lines of options only some profiles act on (profile_options_checked); 0: not given.
  int profile_line_ = 0;  // the last `profile`
  int irq_controller_line_ = 0;
  int cpu_line_ = 0;
  int substitute_line_ = 0;
  int dx_out_port_line_ = 0;
  int user_wd_value_line_ = 0;
  int record_line_ = 0;  // the first `record`
  int work_line_ = 0;    // `dpv1 work=`
  mutable int wd_base_line_ = 0;
  mutable bool wd_base_10ms_ = false;  // that line's wd_base= was 10ms
  bool view_wd_base_10ms_ = false;     // view_ has wd_base=10ms given (by the slave or a set_prm)
  // The lines of the stations' addresses and of the user's inputs (0: the default).
  int master_address_line_ = 0;
  int slave_address_line_ = 0;
  int slave_line_ = 0;  // the last `slave` (its lengths place the user side's buffers)
  int inputs_line_ = 0;
  std::map<std::string, int, std::less<>> header_lines_;  // each header command's line
  bool body_ = false;                  // an action or expect has been seen: no more headers
  scenario_bus::ReadShape last_read_;  // what `expect read` compares
  std::vector<std::string_view> words_;
  std::string_view cmd_;
  std::vector<std::string_view> pos_;
  std::vector<std::pair<std::string_view, std::string_view>> opts_;
};

}  // namespace

bool parse_scenario(std::string_view text, const std::string& file, const dpc31_firmware* plugin,
                    Scenario& out, ScenarioError& err) {
  Scenario s;
  s.file = file;
  Parser p(s, plugin);
  int no = 0;
  text = without_bom(text);
  try {
    for (std::string_view line : split(text, '\n')) p.line(++no, line);
    p.finish();
  } catch (const ParseFail& f) {
    err = ScenarioError{file, f.line == 0 ? no : std::max(f.line, 0), f.message};
    return false;
  }
  if (s.firmware_desc == nullptr && !s.firmware.empty()) s.text = std::string(text);
  out = std::move(s);
  return true;
}

bool parse_scenario(std::string_view text, const std::string& file, Scenario& out,
                    ScenarioError& err) {
  return parse_scenario(text, file, nullptr, out, err);
}

}  // namespace dpc31
