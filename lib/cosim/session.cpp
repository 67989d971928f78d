#include "session.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "board.hpp"
#include "cpp_dut.hpp"
#include "firmware_host.hpp"
#include "harness.hpp"
#include "scenario.hpp"
#include "vocabulary.hpp"

namespace dpc31::cosim {

namespace {

// The inputs of one cycle act in a fixed order (docs/golden-model.md): ev_leave_master and
// ev_wd_expired among the protocol events, then ev_mac_stop, then ev_mac_start. The rank of each of
// them, -1 for the events whose order within a cycle does not change the result.
int request_rank(BlockEvent::Kind k) {
  switch (k) {
    case BlockEvent::Kind::leave_master:
    case BlockEvent::Kind::wd_expired:  // both end in leave_master: their order does not matter
      return 0;
    case BlockEvent::Kind::mac_stop:
      return 1;
    case BlockEvent::Kind::mac_start:
      return 2;
    default:
      return -1;
  }
}

}  // namespace

void begin_recording(Chip& chip, Session& out) {
  harness::on_block_event(
      chip, [&out, rank = -1](std::uint64_t cycle, const BlockEvent& e) mutable {
        if (e.kind == BlockEvent::Kind::offline_deferred) {
          // The golden model has no MAC: it would go Offline at the access, not at the end.
          if (out.unreplayable.empty()) {
            out.unreplayable = fmt::format(
                "cycle {}: Go_Offline or a RAM access violation during a request (the chip goes "
                "Offline at the request's end; the golden model has no MAC and cannot wait for it)",
                cycle);
          }
          return;
        }
        const std::uint64_t index = cycle - 1;  // the C++ Dut reaches cycle i + 1 in step i
        if (out.events.empty() || out.events.back().first != index) {
          out.events.emplace_back(index, Inputs{});
          rank = -1;
        }
        const int r = request_rank(e.kind);
        if (r >= 0 && r < rank && out.unreplayable.empty()) {
          out.unreplayable = fmt::format(
              "cycle {}: requests of one InstQ_Wr write in an order the block events cannot replay "
              "(they act as User_Leave_Master, MAC_Stop, MAC_Start)",
              cycle);
        }
        rank = std::max(rank, r);
        apply_block_event(out.events.back().second, e);
      });
}

void end_recording(Chip& chip, Session& out) {
  out.cycles = chip.cycle();
  out.chip_final = block_outputs(harness::core(chip), 0);
  harness::on_block_event(chip, nullptr);
}

bool record_session(const std::string& scenario_path, Session& out, std::string& error) {
  Scenario sc;
  ScenarioError err;
  if (!load_scenario(scenario_path, sc, err)) {
    error = err.text();
    return false;
  }
  if (!bind_plugin(sc, err)) {  // the plug-in it names, loaded only now that it has parsed
    error = err.text();
    return false;
  }
  if (!check_cpu_image(sc, error)) return false;  // a bad 80C32 image: its line, as in `run`
  // The block events replay one time line from the chip's power-on: a RESET inside it is none.
  for (const ScenarioStep& st : sc.steps) {
    if (st.kind != StepKind::reset) continue;
    error = fmt::format(
        "{}:{}: 'reset' (the CPU board's RESET) cannot be replayed in lockstep: "
        "the block events start at the one reset of the session",
        scenario_path, st.line);
    return false;
  }
  out = Session{};
  out.options = {sc.chip.profile, sc.chip.bus, sc.chip.variant};
  ScenarioHooks hooks;
  hooks.at_start = [&out](Chip& chip) { begin_recording(chip, out); };
  hooks.at_end = [&out](Chip& chip) { end_recording(chip, out); };
  // A firmware's fault or hang is at the scenario's `firmware` line in its init, then at the step
  // it runs in, as in `dpc31 run` (docs/bring-up.md, section 4); a firmware stuck without a bus
  // access cannot be stopped from this thread: the guard ends the process with one line.
  FirmwarePlace where(scenario_path, sc.firmware_line);
  hooks.at_step = [&where](const ScenarioStep& st) { where.enter(st.line, st.text); };
  if (sc.firmware_desc != nullptr) board::guard_hangs("dpc31 cosim", sc.firmware_desc->name);
  const board::HangPlace place(where.text());
  ScenarioOutcome o;
  try {
    o = run_scenario(sc, nullptr, nullptr, hooks);
  } catch (const FirmwareError& e) {
    error = "dpc31 cosim: " + where.message(e.what());
    return false;
  }
  out.scenario_failures = o.failures;
  if (!out.unreplayable.empty()) {
    error = scenario_path + ": " + out.unreplayable;
    return false;
  }
  return true;
}

Stimulus session_stimulus(const Session& s) {
  Stimulus out(s.cycles);
  for (const auto& [cycle, in] : s.events) out.set(cycle, in);
  return out;
}

RunResult run_session(const Session& s, std::string_view mutant) {
  RunResult r;
  std::unique_ptr<Dut> rtl = make_rtl_dut(s.options, mutant);
  if (!rtl) {
    r.divergence = 0;
    r.report.push_back(fmt::format("no RTL model for mutant '{}'", mutant));
    return r;
  }
  Lockstep ls(make_cpp_dut(s.options), std::move(rtl), profile_desc(s.options.profile));
  std::size_t next = 0;
  const Inputs idle;
  for (std::uint64_t i = 0; i < s.cycles; ++i) {
    const bool event = next < s.events.size() && s.events[next].first == i;
    if (!ls.step(event ? s.events[next].second : idle)) {
      r.divergence = static_cast<std::int64_t>(ls.first_divergence());
      r.report = ls.errors();
      r.signals = ls.diverged_signals();
      return r;
    }
    if (event) ++next;
  }
  // The replayed blocks against the live chip. The Cfg pointer cells are left out: the chip's
  // own Aux-buffer exchanges move them, which is not a block event.
  const Outputs replay = ls.emu().outputs();
  for (std::size_t i = 0; i + 1 < Outputs::kCount; ++i) {
    const std::string_view n = Outputs::names()[i];
    if (n == "cfg_ptr" || n == "read_cfg_ptr" || replay.v[i] == s.chip_final.v[i]) continue;
    if (r.divergence < 0) {
      r.divergence = static_cast<std::int64_t>(s.cycles);
      r.report.push_back(fmt::format(
          "the replayed blocks differ from the live chip at the end (cycle {}):", s.cycles));
    }
    r.report.push_back(
        fmt::format("  CHIP {}={:#x} / EMU {}={:#x}", n, s.chip_final.v[i], n, replay.v[i]));
    r.signals.emplace_back(n);
  }
  return r;
}

}  // namespace dpc31::cosim
