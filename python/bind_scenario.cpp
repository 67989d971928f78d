// dpc31.Scenario in Python (docs/python.md): a scenario file parsed and run as `dpc31 run` does,
// every expect and step with its cycle (session/scenario.hpp).
#include <fmt/format.h>
#include <pybind11/operators.h>

#include <memory>
#include <thread>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "bind_session.hpp"
#include "firmware_host.hpp"
#include "scenario.hpp"
#include "scenario_lex.hpp"

namespace dpc31::py_bind {

namespace {

// What a scenario run reports beyond ScenarioOutcome: every expect and step with its cycle.
struct ExpectResult {
  int line;
  std::string text;
  bool ok;
  U64 cycle;
};
struct StepRecord {
  int line;
  std::string text;
  U64 cycle;
};
struct ScenarioResult {
  ScenarioOutcome outcome;
  std::vector<std::string> walk;
  std::vector<ExpectResult> expects;
  std::vector<StepRecord> steps;
};

class Recorder final : public ScenarioObserver {
 public:
  explicit Recorder(ScenarioResult& r) : r_(r) {}
  void step_begins(U64 cycle, const ScenarioStep& st, std::string_view) override {
    r_.steps.push_back({st.line, st.text, cycle});
  }
  void expect_checked(U64 cycle, const ScenarioStep& st, bool ok, std::string_view) override {
    r_.expects.push_back({st.line, st.text, ok, cycle});
  }

 private:
  ScenarioResult& r_;
};

[[noreturn]] void raise_scenario(const ScenarioError& e) {
  raise(errors().scenario, e.text(),
        {{"file", py::str(e.file)}, {"line", py::int_(e.line)}, {"reason", py::str(e.message)}});
}

}  // namespace

void bind_scenarios(py::module_& m) {
  py::enum_<StepKind>(m, "StepKind")
      .value("startup", StepKind::startup)
      .value("restart", StepKind::restart)
      .value("exchange", StepKind::exchange)
      .value("gc", StepKind::gc)
      .value("diag", StepKind::diag)
      .value("fdl_status", StepKind::fdl_status)
      .value("set_prm", StepKind::set_prm)
      .value("chk_cfg", StepKind::chk_cfg)
      .value("get_cfg", StepKind::get_cfg)
      .value("read_inputs", StepKind::read_inputs)
      .value("read_outputs", StepKind::read_outputs)
      .value("set_slave_address", StepKind::set_slave_address)
      .value("foreign_master", StepKind::foreign_master)
      .value("silence", StepKind::silence)
      .value("inputs", StepKind::inputs)
      .value("hw", StepKind::hw)
      .value("corrupt", StepKind::corrupt)
      .value("bad_fcs", StepKind::bad_fcs)
      .value("expect", StepKind::expect)
      .value("write", StepKind::write)
      .value("read", StepKind::read)
      .value("send", StepKind::send)
      .value("request", StepKind::request)
      .value("dpv1", StepKind::dpv1)
      .value("reset", StepKind::reset);
  py::class_<ScenarioStep>(m, "Step", "One line of a scenario file.")
      .def_readonly("line", &ScenarioStep::line)
      .def_readonly("text", &ScenarioStep::text)
      .def_readonly("kind", &ScenarioStep::kind);
  py::class_<ExpectResult>(m, "ExpectResult",
                           "One expect of a run: its line, text, verdict, cycle.")
      .def_readonly("line", &ExpectResult::line)
      .def_readonly("text", &ExpectResult::text)
      .def_readonly("ok", &ExpectResult::ok)
      .def_readonly("cycle", &ExpectResult::cycle);
  py::class_<StepRecord>(m, "StepRecord", "One step of a run and the cycle it began at.")
      .def_readonly("line", &StepRecord::line)
      .def_readonly("text", &StepRecord::text)
      .def_readonly("cycle", &StepRecord::cycle);
  py::class_<ScenarioResult>(m, "ScenarioResult", "What a scenario run gave (dpc31 run's walk).")
      .def_property_readonly("ok", [](const ScenarioResult& r) { return r.outcome.ok(); })
      .def_property_readonly("final_cycle",
                             [](const ScenarioResult& r) { return r.outcome.final_cycle; })
      .def_property_readonly("dp_state", [](const ScenarioResult& r) { return r.outcome.dp; })
      .def_property_readonly("wd_state", [](const ScenarioResult& r) { return r.outcome.wd; })
      .def_property_readonly("passed", [](const ScenarioResult& r) { return r.outcome.passed; })
      .def_property_readonly("failed", [](const ScenarioResult& r) { return r.outcome.failed; })
      .def_property_readonly("failures", [](const ScenarioResult& r) { return r.outcome.failures; })
      .def_property_readonly(
          "counters", [](const ScenarioResult& r) { return counters_dict(r.outcome.counters); })
      .def_readonly("walk", &ScenarioResult::walk)
      .def_readonly("expects", &ScenarioResult::expects)
      .def_readonly("steps", &ScenarioResult::steps);
  py::class_<Scenario>(m, "Scenario", "A parsed scenario file (docs/scenario-format.md).")
      .def_static(
          "load",
          [](const py::object& path) {
            Scenario s;
            ScenarioError err;
            if (!load_scenario(read_path_arg(fspath_arg(path, "path"), "path"), s, err))
              raise_scenario(err);
            return s;
          },
          py::arg("path"))
      .def_static(
          "parse",
          [](std::string_view text, const std::string& file) {
            Scenario s;
            ScenarioError err;
            if (!parse_scenario(text, path_arg(file, "file"), s, err)) raise_scenario(err);
            return s;
          },
          py::arg("text"), py::arg("file") = "<string>")
      .def_readonly("file", &Scenario::file)
      .def_property_readonly(
          "profile", [](const Scenario& s) { return std::string(profile_name(s.chip.profile)); })
      .def_readonly("firmware", &Scenario::firmware)
      .def_readonly("steps", &Scenario::steps)
      .def_property_readonly("expects",
                             [](const Scenario& s) {
                               std::vector<ScenarioStep> e;
                               for (const ScenarioStep& st : s.steps) {
                                 if (st.kind == StepKind::expect) e.push_back(st);
                               }
                               return e;
                             })
      .def("run", [](const Scenario& s) {
        ScenarioResult r;
        Recorder rec(r);
        ScenarioHooks hooks;
        hooks.observer = &rec;
        // A firmware's fault names its place as `dpc31 run`'s line does: the `firmware` line
        // (its load, its init), then the step it runs in ("x.scn:10: dpv1_read").
        FirmwarePlace place(s.file, s.firmware_line);
        Scenario bound = s;
        if (ScenarioError err; !bind_plugin(bound, err)) {
          // The plug-in's load fails at the `firmware` line; a step naming a port or an input the
          // plug-in has not is the scenario's error, as `dpc31 run` reports it.
          if (err.line != s.firmware_line) raise_scenario(err);
          raise_firmware(place, err.message);
        }
        // A bad 80C32 image is an InputError before anything runs (docs/cpu.md), as in `run`.
        if (std::string why; !check_cpu_image(bound, why)) raise(errors().input, why);
        hooks.at_step = [&place](const ScenarioStep& st) { place.enter(st.line, st.text); };
        try {
          py::gil_scoped_release nogil;
          r.outcome = run_scenario(
              bound, [&](const std::string& l) { r.walk.push_back(l); }, LineSink{}, hooks);
        } catch (const FirmwareError& e) {
          raise_firmware(place, e.what());
        }
        return r;
      });
}

}  // namespace dpc31::py_bind
