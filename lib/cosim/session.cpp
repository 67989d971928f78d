#include "session.hpp"

#include <fmt/format.h>

#include "cpp_dut.hpp"
#include "harness.hpp"
#include "scenario.hpp"

namespace dpc31::cosim {

namespace {

// Folds one block event into the inputs of its cycle.
void apply(Inputs& in, const BlockEvent& e) {
  using K = BlockEvent::Kind;
  switch (e.kind) {
    case K::dx:
      in.ev_dx = true;
      break;
    case K::irq:
      in.ev_irq = static_cast<std::uint16_t>(in.ev_irq | e.value);
      break;
    case K::leave_master:
      in.ev_leave_master = true;
      break;
    case K::prm_fault:
      in.ev_prm_fault = true;
      break;
    case K::gc:
      in.ev_gc = true;
      in.gc_cmd = static_cast<std::uint8_t>(e.value);
      break;
    case K::dout:
      in.ev_dout = true;
      break;
    case K::failsafe:
      in.ev_failsafe = true;
      break;
    case K::din:
      in.ev_din = true;
      break;
    case K::diag_begin:
      in.ev_diag_begin = true;
      break;
    case K::diag_end:
      in.ev_diag_end = true;
      in.stat_diag = e.value != 0;
      break;
    case K::dis:
      in.ev_dis = true;
      in.dis_bits = static_cast<std::uint8_t>(e.value);
      break;
    case K::prm:
      in.ev_prm = true;
      break;
    case K::cfg:
      in.ev_cfg = true;
      break;
    case K::ssa:
      in.ev_ssa = true;
      break;
    case K::read:
      in.bus_rd = true;
      in.bus_addr = e.value;
      break;
    case K::write:
      in.bus_wr = true;
      in.bus_addr = e.value;
      in.bus_wdata = e.data;
      break;
  }
}

}  // namespace

bool record_session(const std::string& scenario_path, Session& out, std::string& error) {
  Scenario sc;
  ScenarioError err;
  if (!load_scenario(scenario_path, sc, err)) {
    error = err.text();
    return false;
  }
  out = Session{};
  out.options = {sc.chip.profile, sc.chip.bus, sc.chip.variant};
  ScenarioHooks hooks;
  hooks.at_start = [&out](Chip& chip) {
    harness::on_block_event(chip, [&out](std::uint64_t cycle, const BlockEvent& e) {
      const std::uint64_t index = cycle - 1;  // the C++ Dut reaches cycle i + 1 in step i
      if (out.events.empty() || out.events.back().first != index)
        out.events.emplace_back(index, Inputs{});
      apply(out.events.back().second, e);
    });
  };
  hooks.at_end = [&out](Chip& chip) {
    out.cycles = chip.cycle();
    out.chip_final = block_outputs(harness::core(chip), 0);
    harness::on_block_event(chip, nullptr);
  };
  const ScenarioOutcome o = run_scenario(sc, nullptr, nullptr, hooks);
  out.scenario_passed = o.ok();
  return true;
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
