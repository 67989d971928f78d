// Scenarios: the runner, which plays a parsed Scenario on one chip and prints the state walk
// (docs/scenario-format.md). The parser is scenario_parse.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cpu51_module.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/hex.hpp"
#include "firmware_host.hpp"
#include "scenario.hpp"
#include "scenario_bus.hpp"
#include "scenario_dpv1.hpp"
#include "scenario_expect.hpp"
#include "scenario_lex.hpp"
#include "scenario_send.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

namespace {

using scenario_expect::port_text;
using scenario_lex::bytes_text;
using scenario_send::answer_text;

// The master's call for each request step that takes no data.
using PlainRequest = Exchange (DpMaster::*)();
constexpr std::pair<StepKind, PlainRequest> kPlainRequests[] = {
    {StepKind::diag, &DpMaster::slave_diag},
    {StepKind::fdl_status, &DpMaster::fdl_status},
    {StepKind::get_cfg, &DpMaster::get_cfg},
    {StepKind::read_inputs, &DpMaster::read_inputs},
    {StepKind::read_outputs, &DpMaster::read_outputs}};

PlainRequest plain_request(StepKind k) {
  return std::find_if(std::begin(kPlainRequests), std::end(kPlainRequests),
                      [k](const auto& r) { return r.first == k; })
      ->second;
}

// The built-in user side serves MSAC_C1 to the scenario's master only.
ResponderConfig user_config(const Scenario& s) {
  ResponderConfig c = s.user;
  c.dpv1.c1_master = s.master.address;
  return c;
}

class Runner {
 public:
  Runner(const Scenario& s, const LineSink& walk, const LineSink& errors,
         const ScenarioHooks& hooks = {})
      : s_(s), walk_(walk), errors_(errors), hooks_(hooks), chip_(s.chip), user_(user_config(s)) {}
  Runner(const Runner&) = delete;
  Runner& operator=(const Runner&) = delete;

  ScenarioOutcome run() {
    if (walk_) {
      walk_(fmt::format("scenario {}: profile {}{}{}, bus {}, master {} -> slave {} at {} baud",
                        s_.file, profile_name(s_.chip.profile),
                        s_.chip.variant
                            ? fmt::format(", variant {}", vpc3_variant_name(*s_.chip.variant))
                            : std::string(),
                        s_.chip.irq_controller == IrqController::c31
                            ? std::string(", the C31's interrupt controller")
                            : std::string(),
                        s_.chip.bus == BusMode::intel ? "intel" : "motorola", s_.master.address,
                        s_.user.slave.address, s_.master.baud));
    }
    chip_.set_log_sink([this](const LogRecord& r) { note(r.cycle, "chip: " + r.text); },
                       LogLevel::info);
    if (hooks_.observer != nullptr) hooks_.observer->run_begins(chip_);
    if (hooks_.at_start) hooks_.at_start(chip_);
    user_.set_inputs(s_.inputs);
    DirectBus bus(chip_);
    if (s_.cpu && !start_cpu()) return out_;
    // The chip tells of every cycle where its state may have changed (bus accesses, its events):
    // each change is noted at its own cycle, whoever made it (docs/scenario-format.md). A run
    // nobody reads the walk of and without a state's `at`/`after` needs none (an observer takes
    // the chip's plain bus path away: `dpc31 bench`).
    dp_ = chip_.dp_state();
    wd_ = chip_.wd_state();
    started_ = chip_started();
    dp_since_ = wd_since_ = chip_.cycle();
    if (walk_ || hooks_.observer != nullptr || states_timed()) {
      chip_.on_state_change([this](std::uint64_t cycle) { check_states(cycle); });
    }
    if (s_.cpu) {
    } else if (!s_.firmware.empty()) {
      fw_ = std::make_unique<FirmwareHost>(*s_.firmware_desc);
      fw_->on_port = [this](std::uint64_t cycle, unsigned port, std::uint32_t value) {
        port_since_[fw_->port_name(port)] = cycle;
        note(cycle, fmt::format("{}: {} = {} at {}", fw_->firmware().name, fw_->port_name(port),
                                port_text(value), time_text(cycle)));
      };
      fw_->init(bus, s_.user.slave.address);
    } else {
      user_.init(bus);
    }
    master_ = std::make_unique<DpMaster>(chip_, s_.master, s_.user.slave);
    // The parser refused DPV1 steps on another chip: only a VPC3+ has a DPV1 master.
    if (s_.chip.profile == Profile::vpc3plus) {
      dpv1_ = std::make_unique<Dpv1Master>(chip_, *master_, s_.dpv1);
      dpv1_->rules().retries = s_.retries;
      // Each poll reported as it comes, then forgotten, as `exchange N` does, and the walk's lines
      // written as their folds are decided: a long DPV1 time-out keeps the history and the walk
      // flat. Nothing noted later is older than the chip's cycle, so what is sorted now stays so.
      // An observer is told every event held so far, and that none older will come (a trace writes
      // what precedes them; its checkpoint waits for step_ends).
      dpv1_->polled = [this] {
        report_history();
        forget_reported();
        if (events_.size() >= kDrainAt) {
          report_outputs();
          drain(false);
          if (hooks_.observer != nullptr) hooks_.observer->events_told(chip_.cycle());
        }
      };
    }
    master_->on_locked = [this](std::uint8_t, std::uint8_t by) { locked_by_ = by; };
    master_->on_late = [this](std::uint64_t end, bool after_slot) {
      note(end, fmt::format("master: {}", late_answer_text(after_slot)));
    };
    if (hooks_.observer != nullptr) {
      master_->on_send = [this](std::uint64_t start, std::span<const std::uint8_t> bytes,
                                UartFault fault) {
        hooks_.observer->telegram_sent(start, bytes, fault);
      };
    }
    if (m51_) {
      // The 80C32 board moves time itself (DpMaster::scheduler): it brings CPU and chip to the
      // cycle, or stops early when a step of the chip asked to.
      master_->scheduler = [this](std::uint64_t cycle) {
        while (chip_.cycle() < cycle && !chip_.stop_requested()) m51_->run_until(cycle);
      };
    } else if (fw_) {
      master_->set_firmware(fw_->program());
    } else {
      master_->set_firmware([this](BusPort& b) { user_.isr(b); });
    }
    chip_.on_irq_change([this](std::uint64_t cycle, bool active) {
      if (active) {
        ++irq_count_;
        if (irq_rises_.size() < scenario_expect::kIrqRisesShown ||
            std::find(irq_asked_.begin(), irq_asked_.end(), cycle) != irq_asked_.end())
          irq_rises_.emplace_back(cycle, chip_.peek_reg(RegId::Int_Reg));
      }
    });
    chip_.on_pb3_change([this](std::uint64_t cycle, bool high) {
      pb3_rises_ += high ? 1 : 0;
      note(cycle, fmt::format("PB3 {}", high ? "high (DX_Out of a Sync)" : "low"),
           Event::Kind::pin);
    });
    outputs_.assign(s_.user.slave.out_len, 0);
    // A host user side has started the chip in its init (the line at its Start_SPC3); a `cpu`
    // firmware starts it later, and that start is a line of its own (check_states).
    note(started_ ? dp_since_ : chip_.cycle(),
         started_ ? states_text("started") : states_text("not started") + not_started_why(),
         Event::Kind::started);
    walk_begun_ = true;
    flush();
    for (const ScenarioStep& st : s_.steps) {
      if (st.kind == StepKind::expect) {
        check(st);
        continue;
      }
      // A fault and the action it damages count as one action for "+N" and irr_bit.
      const bool modifier = is_fault(st.kind);
      if (modifier || (is_action(st.kind) && !fault_ && !bad_fcs_)) {
        base_counters_ = chip_.fdl_counters();
        interrupts().clear();  // what the ISR saw before this action is not its
        irr_isr_ = 0;
        base_pb3_ = pb3_rises_;
        base_cycle_ = chip_.cycle();
        irq_rises_.clear();  // `expect irq` looks at the last action only
        irq_count_ = 0;
        ask_irq_cycles(static_cast<std::size_t>(&st - s_.steps.data()));
      }
      note(chip_.cycle(), fmt::format("line {}: {}", st.line, st.text), Event::Kind::step, &st);
      if (walk_) walk_now(events_.back());
      if (hooks_.at_step) hooks_.at_step(st);
      // Requests counted, not history().size(): a long exchange step forgets history as it goes.
      const std::uint64_t sent = master_->counters().requests;
      act(st);
      if (master_->counters().requests != sent) settle();
      report_history();
      report_outputs();
      fold_interrupts();
      flush();
      forget_reported();
    }
    // A late answer to the last request ends on the line before the run does: a trace that
    // ended inside it could not replay (the chip's `tx` line past its `end`).
    master_->hear_out_late_answer();
    report_history();
    fold_interrupts();
    if (hooks_.observer != nullptr) hooks_.observer->run_ends(chip_);
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
    if (m51_) {
      for (const Cpu51Module::PortWrite& w : m51_->port_writes()) {
        out_.port_writes.push_back({w.cycle, m51_->port_name(w.port), w.value});
      }
      for (std::string& l : port_lines_.flush())
        limited_note(chip_.cycle(), false, l, "80C32 port writes");
      for (std::string& l : serial_lines_.flush())
        limited_note(chip_.cycle(), false, l, "serial port");
    }
    // What the chip's log still owes (a repeat count, lines left out) comes before the end line.
    chip_.set_log_sink({});
    note(chip_.cycle(),
         fmt::format("end: dp_state {}, wd_state {}; expects passed {}, failed {}",
                     dp_state_name(out_.dp), wd_state_name(out_.wd), out_.passed, out_.failed),
         Event::Kind::end);
    drain(true);
    chip_.on_state_change({});
    chip_.on_irq_change({});
    chip_.on_pb3_change({});
    return out_;
  }

 private:
  struct Event {
    // pin: a pin's edge, which an observer takes from the chip itself (a trace's `pb3` line).
    enum class Kind : std::uint8_t { note, pin, started, step, passed, failed, end };
    std::uint64_t cycle;
    std::string text;
    Kind kind = Kind::note;
    const ScenarioStep* step = nullptr;  // step / passed / failed
    bool walked = false;                 // printed already (walk_now); the observer is told later
    bool told = false;                   // to the observer (the walk may still hold it)
  };

  // A step's line is printed when the step begins, before the firmware runs in it: when that
  // firmware hangs (the guard ends the process) or faults, the walk shows the step it was in.
  // The observer is told in flush(), in cycle order with the step's other events.
  void walk_now(Event& e) {
    walk_(fmt::format("[cycle {:>10}] {}", e.cycle, e.text));
    e.walked = true;
  }

  void note(std::uint64_t cycle, std::string text, Event::Kind kind = Event::Kind::note,
            const ScenarioStep* step = nullptr) {
    // --quiet without an observer: nobody reads them.
    if (walk_ || hooks_.observer != nullptr) {
      events_.push_back(Event{cycle, std::move(text), kind, step});
    }
  }

  // A port write's (or a sent character's) own line, or what the limiter says of those it left
  // out, after `what`.
  void limited_note(std::uint64_t cycle, bool own, std::string& line, std::string_view what) {
    note(cycle, own ? std::move(line) : fmt::format("{}: {}", what, line));
  }

  void tell(ScenarioObserver& o, const Event& e) {
    switch (e.kind) {
      case Event::Kind::note:
        o.walk_note(e.cycle, e.text);
        break;
      case Event::Kind::started:
        o.user_side_started(e.cycle, user_side_name(), e.text);
        break;
      case Event::Kind::step:
        o.step_begins(e.cycle, *e.step, e.text);
        break;
      case Event::Kind::passed:
      case Event::Kind::failed:
        o.expect_checked(e.cycle, *e.step, e.kind == Event::Kind::passed, e.text);
        break;
      case Event::Kind::pin:
      case Event::Kind::end:
        break;
    }
  }

  // Events are collected during an action and printed in cycle order: a transaction's line is
  // only known once its answer is in, after the state changes it caused. The walk folds what
  // repeats (an observer is told every event, then that the step, expect or init has ended).
  void flush() {
    drain(true);
    if (hooks_.observer != nullptr) hooks_.observer->step_ends(chip_.cycle());
  }

  // Writes the events whose lines are decided and forgets them. At the step's end (`all`) that is
  // every event; during a long action (a DPV1 service's polls) the ones whose fold the events
  // still to come cannot change. fold_at decides which group folds; its repeats are counted one
  // by one as they come (`fold_`), whether they are all here (the step's end) or still coming (a
  // long action): one rule, so the walk is the one the whole step would give, the memory flat.
  void drain(bool all) {
    std::stable_sort(events_.begin(), events_.end(),
                     [](const Event& a, const Event& b) { return a.cycle < b.cycle; });
    const std::size_t n = events_.size();
    // The observer is told every event now, whatever the walk still holds for its folds.
    if (hooks_.observer != nullptr) {
      for (Event& e : events_) {
        if (!std::exchange(e.told, true)) tell(*hooks_.observer, e);
      }
    }
    std::size_t i = walk_ ? 0 : n;  // the first event not written
    while (i < n) {
      if (fold_) {
        const std::size_t k = fold_->group.size();
        const std::size_t have = std::min(k, n - i);
        bool same = true;
        for (std::size_t x = 0; x < have && same; ++x)
          same = events_[i + x].text == fold_->group[x];
        if (same && have == k) {
          if (fold_->repeats++ == 0) fold_->first_cycle = events_[i].cycle;
          fold_->last_cycle = events_[i + k - 1].cycle;
          i += k;
          continue;
        }
        if (same && !all) break;  // the next repeat still coming
        end_fold();
        continue;
      }
      // Where the fold of the line is decided: the line, or the first occurrence of the group
      // that folds, is written; the group's repeats, those here and those still to come, are
      // counted above, by the one running fold.
      const Fold f = fold_at(i, n);
      if (!all && !f.settled && !f.periodic) break;
      const std::size_t lines = f.repeats == 0 ? 1 : f.lines;
      for (std::size_t x = 0; x < lines; ++x) write(events_[i + x]);
      if (f.repeats != 0) {
        fold_ = Folding{};
        for (std::size_t x = 0; x < lines; ++x) fold_->group.push_back(events_[i + x].text);
      }
      i += lines;
    }
    events_.erase(events_.begin(), events_.begin() + static_cast<std::ptrdiff_t>(i));
    if (all && fold_) end_fold();
  }

  void write(const Event& e) {
    if (!e.walked) walk_(fmt::format("[cycle {:>10}] {}", e.cycle, e.text));
  }
  void end_fold() {
    const std::size_t k = fold_->group.size();
    walk_(fmt::format("[cycle {:>10}] {} repeated (x{}, last at cycle {})", fold_->first_cycle,
                      k == 1 ? std::string("the line above") : fmt::format("the {} lines above", k),
                      fold_->repeats, fold_->last_cycle));
    fold_.reset();
  }

  // A run of a group of up to kFoldLines lines that comes again and again (a start-up that
  // cannot succeed: Set_Prm, Chk_Cfg, Slave_Diag and the chip's remarks, a thousand times; an
  // exchange that changes nothing) is its first occurrence and one line with the count and the
  // cycles of the repeats. At each line the group that folds the most lines is taken, if it
  // comes at least three times.
  static constexpr std::size_t kFoldLines = 8;
  // The events a long action holds before it writes those decided (many times kFoldLines).
  static constexpr std::size_t kDrainAt = 256;
  struct Fold {
    std::size_t lines = 0;    // in the group that starts at this line
    std::size_t repeats = 0;  // how often it comes again right after its first occurrence
    // Of the first `n` events: no group size's run reaches the n-th (the later events cannot
    // change the fold), or only those of multiples of `lines` do, which never fold more than
    // `lines` (a longer run only adds repeats).
    bool settled = true;
    bool periodic = false;
  };
  [[nodiscard]] Fold fold_at(std::size_t i, std::size_t n) const {
    const auto same = [&](std::size_t a, std::size_t b, std::size_t k) {
      for (std::size_t x = 0; x < k; ++x) {
        if (events_[a + x].text != events_[b + x].text) return false;
      }
      return true;
    };
    Fold best;
    std::vector<std::size_t> open;  // the group sizes whose run reaches the n-th event
    for (std::size_t k = 1; k <= kFoldLines; ++k) {
      if (i + 2 * k > n) {
        open.push_back(k);
        continue;
      }
      std::size_t r = 0;
      while (i + (r + 2) * k <= n && same(i, i + (r + 1) * k, k)) ++r;
      if (i + (r + 2) * k > n) open.push_back(k);
      if (r >= 2 && r * k > best.repeats * best.lines) best = {k, r};
    }
    best.settled = open.empty();
    best.periodic = best.repeats != 0 && std::all_of(open.begin(), open.end(), [&](std::size_t k) {
                      return k % best.lines == 0;
                    });
    return best;
  }
  // A group being folded: its repeats counted as they come.
  struct Folding {
    std::vector<std::string> group;
    std::size_t repeats = 0;
    std::uint64_t first_cycle = 0;  // of the first repeat
    std::uint64_t last_cycle = 0;   // of the last line of the last repeat
  };
  std::optional<Folding> fold_;

  void fail(int line, const std::string& msg) {
    const std::string text = fmt::format("{}:{}: {}", s_.file, line, msg);
    out_.failures.push_back(text);
    if (errors_) errors_(text);
  }

  std::uint32_t chip_baud() const {
    const unsigned code = field_of(chip_.peek_reg(RegId::Status_Reg), fields::Status_Reg::Baudrate);
    return code < std::size(kBaudRates) ? kBaudRates[code] : 0;
  }

  [[nodiscard]] bool states_timed() const {
    return std::any_of(s_.steps.begin(), s_.steps.end(), [](const ScenarioStep& st) {
      return st.kind == StepKind::expect && st.when != ScenarioStep::When::any &&
             (st.expect == ExpectKind::dp_state || st.expect == ExpectKind::wd_state);
    });
  }
  [[nodiscard]] bool chip_started() const {
    return field_of(chip_.peek_reg(RegId::Status_Reg), fields::Status_Reg::Offline_Passive_Idle) !=
           0;
  }
  [[nodiscard]] std::string states_text(std::string_view what) const {
    return fmt::format("{}: dp_state {}, wd_state {}", what, dp_state_name(dp_),
                       wd_state_name(wd_));
  }
  // What drives the chip, as the trace's heading names it (docs/trace-format.md).
  [[nodiscard]] std::string user_side_name() const {
    if (s_.cpu) {
      return fmt::format("the {} firmware {}", s_.cpu->c31 ? "C31" : "80C32",
                         std::filesystem::path(s_.cpu->hex).filename().string());
    }
    return s_.firmware_desc != nullptr ? fmt::format("the host firmware {}", s_.firmware_desc->name)
                                       : "the built-in user side";
  }
  [[nodiscard]] std::string not_started_why() const {
    const char* start = chip_.profile().id == Profile::dpc31 ? "MAC_Start" : "Start_SPC3";
    return s_.cpu ? fmt::format(", the chip Offline until the firmware's {}", start)
                  : fmt::format(", the chip Offline (the user side gave no {})", start);
  }

  // The chip's observer: at each cycle where its state may have changed. Start_SPC3 (MAC_Start)
  // puts both states at that cycle, Go_Offline and a RAM access violation at that cycle or at the
  // end of the current request (docs/timing.md, "Mode and state changes").
  void check_states(std::uint64_t cycle) {
    const DpState dp = chip_.dp_state();
    const WdState wd = chip_.wd_state();
    // A start or stop leaves (or finds) both states at their reset values: only then, or with a
    // change, is Status read (the call comes at every bus access).
    const bool reset = dp == DpState::Wait_Prm && wd == WdState::Baud_Search;
    if (dp == dp_ && wd == wd_ && !reset) return;
    if (const bool on = chip_started(); on != started_) {
      started_ = on;
      dp_ = dp;
      wd_ = wd;
      dp_since_ = wd_since_ = cycle;
      // Before the walk's first line the host user side's start is that line.
      if (walk_begun_) note(cycle, states_text(on ? "started" : "offline"));
      return;
    }
    if (dp != dp_) {
      note(cycle, fmt::format("dp_state {} -> {}", dp_state_name(dp_), dp_state_name(dp)));
      dp_ = dp;
      dp_since_ = cycle;
    }
    if (wd != wd_) {
      std::string found;
      if (wd_ == WdState::Baud_Search) found = fmt::format(" ({} baud)", chip_baud());
      note(cycle, fmt::format("wd_state {} -> {}{}", wd_state_name(wd_), wd_state_name(wd), found));
      wd_ = wd;
      wd_since_ = cycle;
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
      case StepKind::gc:  // st.bytes: the data unit (Control_Command, Group_Select, or data=)
        if (st.from)
          return scenario_send::from_other_master(st, fdl::kBroadcast, sap::Global_Control,
                                                  st.bytes);
        return fdl::make_frame(fdl::kBroadcast, a,
                               fdl::make_request_fc(fdl::Function::SDN_high, false, false),
                               st.bytes, sap::Global_Control, sap::Master);
      case StepKind::diag:
        return srd(sap::Slave_Diag, {});
      case StepKind::get_cfg:
        return srd(sap::Get_Cfg, {});
      case StepKind::read_inputs:
        return srd(sap::Rd_Inp, {});
      case StepKind::read_outputs:
        return srd(sap::Rd_Outp, {});
      case StepKind::set_prm:
      case StepKind::chk_cfg: {
        const bool prm = st.kind == StepKind::set_prm;
        const SlaveConfig& own = st.from ? *st.slave : sl;  // another master's parameters
        std::vector<std::uint8_t> du = !prm           ? own.cfg
                                       : st.has_bytes ? st.bytes
                                                      : prm_du(own, prm_station_status(own));
        const std::uint8_t dsap = prm ? sap::Set_Prm : sap::Chk_Cfg;
        if (st.from) return scenario_send::from_other_master(st, t, dsap, std::move(du));
        return srd(dsap, std::move(du));
      }
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
      if (const std::string why = place_fault(fl, bytes.size(), "corrupt char"); !why.empty()) {
        fail(fault_line_, why + ", sent undamaged");
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
                        prm_du(master_->slave(), prm_station_status(master_->slave())),
                        sap::Set_Prm, sap::Master)));
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

  void act(const ScenarioStep& st) {
    switch (st.kind) {
      case StepKind::startup: {
        damage(st);
        locked_by_.reset();
        const bool ok = master_->startup(static_cast<int>(st.count));
        note(chip_.cycle(),
             ok           ? std::string("startup: slave ready for Data_Exchange")
             : locked_by_ ? fmt::format("startup: slave locked by master {} (its Slave_Diag's "
                                        "Master_Add): not parameterised",
                                        *locked_by_)
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
          report_outputs();
          fold_interrupts();
          forget_reported();
        }
        break;
      }
      case StepKind::gc:
        if (!damage(st)) break;
        if (st.from) {
          master_->transact(predict(st, {}));
        } else {
          master_->service(sap::Global_Control, st.bytes, false);
        }
        break;
      case StepKind::diag:
      case StepKind::fdl_status:
      case StepKind::get_cfg:
      case StepKind::read_inputs:
      case StepKind::read_outputs:
        damage(st);
        with_retries((*master_.*plain_request(st.kind))());
        break;
      case StepKind::set_prm:
      case StepKind::chk_cfg:
        if (!st.from && !st.has_bytes) master_->slave() = *st.slave;
        damage(st);
        if (st.from) {  // another master: the frame as predicted, FCV = 0
          with_retries(master_->transact(predict(st, {})));
        } else if (st.has_bytes) {
          with_retries(master_->service(sap::Set_Prm, st.bytes));
        } else {
          with_retries(st.kind == StepKind::set_prm ? master_->set_prm() : master_->chk_cfg());
        }
        break;
      case StepKind::send:  // the bytes as given, kept for the walk
        master_->transact_raw(raw_[master_->history().size()] =
                                  scenario_send::telegram(st, master_->target()));
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
        master_->idle(st.cycles);
        break;
      case StepKind::write:
      case StepKind::read:
      case StepKind::request: {
        std::string done = scenario_bus::act(chip_, st, last_read_);  // the accesses take time
        if (done.empty()) {  // the walk says it too: an empty line said nothing
          done = "request: the Instruction_Queue is not set up (InstQ_Len 0)";
          fail(st.line, done);
        }
        note(chip_.cycle(), std::move(done));
        break;
      }
      case StepKind::dpv1: {
        dpv1_last_ = scenario_dpv1::act(*dpv1_, st);
        // At the outcome's cycle, the one `expect dpv1 ... at / after` checks (docs/dpv1.md).
        note(dpv1_last_->end, fmt::format("{}: {}", st.name, answer_summary(*dpv1_last_)));
        break;
      }
      case StepKind::reset:  // at the board's instant, the chip's cycle (the scheduler's end)
        if (hooks_.observer != nullptr) hooks_.observer->board_reset(chip_.cycle());
        m51_->board().reset();
        check_states(chip_.cycle());  // the chip stopped: the walk says so at the reset's cycle
        note(chip_.cycle(),
             fmt::format("reset: the {} and the chip start again", s_.cpu->c31 ? "C31" : "80C32"));
        break;
      case StepKind::inputs:
        user_.set_inputs(st.bytes);
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
    if (const auto raw = raw_.find(i); raw != raw_.end()) {  // `send`: the bytes as given
      const fdl::Decoded d = fdl::decode(raw->second);
      std::string s = fmt::format("send {}", hex_bytes(raw->second, " ", fdl::kMaxFrameLength));
      if (d.error != fdl::Error::none) {
        s += fmt::format(" [{}]", fdl::error_name(d.error));
      } else if (!wants_answer(d.frame)) {
        return s;
      }
      return s + " => " + outcome(master_->history()[i]);
    }
    const fdl::Frame& req = request_of(i);
    std::string s = fmt::format("{} -> {} {}", req.sa, req.da, service_name(req));
    if (!req.du.empty()) s += fmt::format(" {}", hex_bytes(req.du, " ", 32));
    const auto it = notes_.find(i);
    if (it != notes_.end()) s += " [" + it->second + "]";
    if (wants_answer(req)) s += fmt::format(" => {}", outcome(master_->history()[i]));
    return s;
  }

  // The answer, or the telegram that came in its place addressed otherwise (Exchange::stray).
  static std::string outcome(const Exchange& ex) {
    if (!ex.stray) return answer_text(ex.answer);
    return fmt::format("not its answer ({} from {} to {})", answer_text(ex.stray), ex.stray->sa,
                       ex.stray->da);
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
    if (req.sa != s_.master.address || notes_.count(i) != 0 || raw_.count(i) != 0) return;
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

  // The 80C32 board: its image read now, when the run starts (a bad file is one line and a
  // failure, nothing run); the CPU starts from reset at cycle 0 with the chip.
  bool start_cpu() {
    std::string err;
    if (!load_cpu51_image(*s_.cpu, image_, err)) {
      out_.failures.push_back(err);
      if (errors_) errors_(err);
      return false;
    }
    m51_ = std::make_unique<Cpu51Module>(chip_, *s_.cpu, image_, s_.user.slave.address);
    m51_->on_port = [this](std::uint64_t cycle, unsigned port, std::uint32_t value) {
      // The MOVX (one byte) has been fetched: it is the byte before the PC.
      const auto at = static_cast<std::uint16_t>(m51_->board().cpu().pc() - 1);
      port_since_[m51_->port_name(port)] = cycle;
      const std::string line =
          fmt::format("80C32 at {}: {} = {} at {}", code_name(image_, at), m51_->port_name(port),
                      port_text(value), time_text(cycle));
      for (std::string& l : port_lines_.add(cycle, line))
        limited_note(cycle, l == line, l, "80C32 port writes");
    };
    // What the firmware sends on its UART (a debug printf), bounded as the port writes.
    m51_->on_serial = [this](std::uint64_t cycle, std::uint8_t data) {
      const std::string line =
          fmt::format("{} at {}", Cpu51Module::serial_text(s_.cpu->c31, data), time_text(cycle));
      for (std::string& l : serial_lines_.add(cycle, line))
        limited_note(cycle, l == line, l, "serial port");
    };
    const std::string symbols = symbols_text(image_);
    if (s_.cpu->c31) {
      note(0, fmt::format("C31 at {} Hz: {} ({} bytes{}), its code area from {:04X}h", s_.cpu->hz,
                          s_.cpu->hex, image_.size, symbols, s_.cpu->code));
    } else {
      note(0, fmt::format("80C32 at {} Hz: {} ({} bytes{}), the chip at XDATA {:04X}h", s_.cpu->hz,
                          s_.cpu->hex, image_.size, symbols, s_.cpu->base));
    }
    return true;
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
    keep_last(raw_);
    master_->keep_last_exchange();
    reported_ = 1;
  }

  // Reported fetches are forgotten but the last (the expects read it): memory stays flat.
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
    user_.keep_last_output();
    outputs_seen_ = user_.outputs.size();
  }

  // The ISR entries the user side recorded (cycle, IR) and not yet folded.
  std::vector<std::pair<std::uint64_t, std::uint16_t>>& interrupts() {
    return m51_ ? m51_->interrupts : fw_ ? fw_->interrupts : user_.interrupts;
  }

  // What the ISR saw since the last action began goes into irr_isr_; the user side's record of
  // it is then forgotten: memory stays flat.
  void fold_interrupts() {
    auto& irqs = interrupts();
    for (const auto& [cycle, ir] : irqs) irr_isr_ |= ir;
    irqs.clear();
  }

  // Port values in hex and, for the bit patterns of digital outputs, binary.

  std::string time_text(std::uint64_t cycle) const {
    return fmt::format("{:.3f} us", static_cast<double>(cycle) * 1e6 / chip_.clock_hz());
  }

  // --- checks ---

  void check(const ScenarioStep& st) {
    // The firmware acknowledges what it handles, so the register alone rarely shows an event:
    // what its ISR saw during the last action counts as well.
    fold_interrupts();
    const auto irr_seen = static_cast<std::uint16_t>(chip_.peek_reg(RegId::Int_Req_Reg) | irr_isr_);
    const scenario_expect::Seen seen{
        .chip = chip_,
        .outputs = user_.outputs,
        .last_inputs = last_inputs_,
        .last_diag = last_diag_,
        .base_counters = base_counters_,
        .irr = irr_seen,
        .last_answer = master_->history().empty() ? std::nullopt : master_->history().back().answer,
        .baud = chip_baud(),
        // DX_Out is acknowledged by the ISR at once, so a rise during the last action counts.
        .pb3 = chip_.pb3_pin() || pb3_rises_ > base_pb3_,
        .port =
            [this](const std::string& name) {
              return static_cast<std::uint32_t>(m51_ ? m51_->port(name) : fw_->port(name));
            },
        .irq_rises = irq_rises_,
        .irq_count = irq_count_,
        .base_cycle = base_cycle_};
    scenario_bus::Check c = scenario_expect::is_bus(st.expect)
                                ? scenario_bus::check(chip_, st, last_read_)
                            : st.expect == ExpectKind::dpv1 ? scenario_dpv1::check(st, dpv1_last_)
                                                            : scenario_expect::check(st, seen);
    const std::string& what = c.what;
    const std::string& want = c.want;
    std::string& got = c.got;
    if (st.when != ScenarioStep::When::any && st.expect != ExpectKind::irq && got == want) {
      const std::uint64_t since = st.expect == ExpectKind::dpv1       ? dpv1_last_->end
                                  : st.expect == ExpectKind::dp_state ? dp_since_
                                  : st.expect == ExpectKind::port     ? port_since_[st.name]
                                                                      : wd_since_;
      scenario_bus::when(st, since, base_cycle_, c.want, got);
    }
    if (got == want) {
      ++out_.passed;
      note(chip_.cycle(), fmt::format("line {}: {}: ok", st.line, st.text), Event::Kind::passed,
           &st);
    } else {
      ++out_.failed;
      note(chip_.cycle(), fmt::format("line {}: {}: FAILED, got {}", st.line, st.text, got),
           Event::Kind::failed, &st);
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
  Cpu51Image image_;
  std::unique_ptr<Cpu51Module> m51_;  // instead of both on `cpu 80c32`
  // The walk's lines of the 80C32's port writes, bounded as the chip's log: a firmware writing its
  // latch in a loop is no flood (--json's port_writes has every write).
  LogLimiter port_lines_;
  LogLimiter serial_lines_;
  std::unique_ptr<DpMaster> master_;
  std::optional<std::uint8_t> locked_by_;  // the master a `startup` found holding the slave
  std::unique_ptr<Dpv1Master> dpv1_;
  std::optional<Dpv1Answer> dpv1_last_;  // what `expect dpv1` compares
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
  std::map<std::size_t, std::vector<std::uint8_t>> raw_;      // history index -> `send`'s bytes
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
  std::uint16_t irr_isr_ = 0;  // Int_Reg at the ISR entries of the last action
  std::size_t pb3_rises_ = 0;  // PB3 rising edges so far (dpc31 DX_Out port)
  std::size_t base_pb3_ = 0;
  std::uint64_t base_cycle_ = 0;  // when the last action began (`after N`)
  // X/INT activations since then: how many, and those `expect irq` may name (the first
  // kIrqRisesShown, and those at the cycles the expects after the action ask for: irq_asked_), so
  // that a long action keeps a few, not one per activation.
  std::vector<scenario_expect::IrqRise> irq_rises_;
  std::size_t irq_count_ = 0;
  std::vector<std::uint64_t> irq_asked_;
  std::uint64_t dp_since_ = 0;  // when dp_ / wd_ were entered, as the walk shows it
  std::uint64_t wd_since_ = 0;
  bool started_ = false;     // the chip's Status bit 0 (Passive_Idle) as the walk last saw it
  bool walk_begun_ = false;  // the walk's first line is out
  // The cycle of each firmware port's last write (`expect port NAME V at|after N`); 0 before it.
  std::map<std::string, std::uint64_t> port_since_;
  scenario_bus::LastRead last_read_;  // what `expect read` compares

  // The cycles the `expect irq NAME at|after` steps name that judge the action beginning at step
  // `i` (base_cycle_ set): every one up to the step that begins the next (a fault step, or an
  // action but the one a fault step at `i` damages), past `inputs` and `hw` steps and expects.
  void ask_irq_cycles(std::size_t i) {
    irq_asked_.clear();
    const std::vector<ScenarioStep>& steps = s_.steps;
    bool damaged_action_to_come = is_fault(steps[i].kind);
    for (++i; i < steps.size(); ++i) {
      const ScenarioStep& e = steps[i];
      if (is_fault(e.kind)) break;
      if (is_action(e.kind)) {
        if (!std::exchange(damaged_action_to_come, false)) break;
        continue;
      }
      if (e.kind != StepKind::expect || e.expect != ExpectKind::irq || e.name == "count") continue;
      irq_asked_.push_back(e.when == ScenarioStep::When::after ? base_cycle_ + e.when_cycle
                                                               : e.when_cycle);
    }
  }
};

}  // namespace

ScenarioOutcome run_scenario(const Scenario& s, const LineSink& walk, const LineSink& errors,
                             const ScenarioHooks& hooks) {
  if (plugin_pending(s)) {
    Scenario bound = s;
    ScenarioError err;
    if (!bind_plugin(bound, err)) throw FirmwareError(err.text());
    return run_scenario(bound, walk, errors, hooks);
  }
  Runner r(s, walk, errors, hooks);
  return r.run();
}

bool check_cpu_image(const Scenario& s, std::string& error) {
  Cpu51Image image;
  if (!s.cpu || load_cpu51_image(*s.cpu, image, error)) return true;
  // The file run is the scenario, as for a plug-in: its line first, then the image's own words.
  error = fmt::format("{}:{}: {}", s.file, s.cpu_line, error);
  return false;
}

int run_scenario_file(const std::string& path, const LineSink& walk, const LineSink& errors,
                      Scenario* scenario, ScenarioOutcome* outcome) {
  Scenario s;
  ScenarioError err;
  if (!load_scenario(path, s, err)) {
    if (errors) errors(err.text());
    return 2;
  }
  if (!bind_plugin(s, err)) {
    if (errors) errors(err.text());
    return 2;
  }
  if (std::string why; !check_cpu_image(s, why)) {  // parsed whole first; then the image
    if (errors) errors(why);
    return 2;
  }
  const ScenarioOutcome o = run_scenario(s, walk, errors);
  const int rc = o.ok() ? 0 : 1;
  if (scenario != nullptr) *scenario = std::move(s);
  if (outcome != nullptr) *outcome = o;
  return rc;
}

}  // namespace dpc31
