#include "run.hpp"

#include <fmt/core.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <system_error>
#include <vector>

// The scenario runner lives with the emulator (emu/ is not on this target's include path).
#include "../../emu/scenario.hpp"
#include "../../emu/trace.hpp"

namespace dpc31::cli {

namespace {

nlohmann::json summary(const Scenario& s, const ScenarioOutcome& o) {
  nlohmann::json counters = nlohmann::json::object();
  for (const CounterField& f : fdl_counter_fields()) {
    counters[std::string(f.name)] = o.counters.*(f.member);
  }
  return {
      {"scenario", s.file},
      {"profile", std::string(profile_name(s.chip.profile))},
      {"bus", s.chip.bus == BusMode::intel ? "intel" : "motorola"},
      {"baud", s.master.baud},
      {"final_cycle", o.final_cycle},
      {"dp_state", std::string(dp_state_name(o.dp))},
      {"wd_state", std::string(wd_state_name(o.wd))},
      {"counters", counters},
      {"expects", {{"passed", o.passed}, {"failed", o.failed}}},
      {"failures", o.failures},
      {"ok", o.ok()},
  };
}

// Written next to the target and renamed over it: a reader never sees half a file.
bool write_file(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) return false;
    f << text;
    f.close();
    if (!f) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      return false;
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) std::filesystem::remove(tmp, ec);
  return !ec;
}

bool write_json(const std::string& path, const nlohmann::json& j) {
  return write_file(path, j.dump(2) + '\n');
}

// The comment block at the top of a scenario file (its description, and for golden traces what
// was checked by hand): it heads the recorded trace.
std::vector<std::string> leading_comments(const std::string& path) {
  std::vector<std::string> out;
  std::ifstream f(path, std::ios::binary);
  std::string line;
  bool first = true;
  while (std::getline(f, line)) {
    if (first && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);
    first = false;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!line.starts_with('#')) break;
    line.erase(0, line.starts_with("# ") ? 2 : 1);
    out.push_back(line);
  }
  return out;
}

// `run --record`: the same run, with a trace recorder on the chip and on the walk.
int run_recorded(const RunOptions& opt, const LineSink& walk, const LineSink& errors, Scenario& s,
                 ScenarioOutcome& o, std::FILE* err) {
  ScenarioError perr;
  if (!load_scenario(opt.scenario, s, perr)) {
    errors(perr.text());
    return 2;
  }
  std::vector<std::string> notes = leading_comments(opt.scenario);
  if (!notes.empty()) notes.emplace_back();
  notes.push_back(
      fmt::format("recorded by `dpc31 run --record` from {} (docs/trace-format.md)", s.file));
  TraceRecorder rec(s.master.baud, std::move(notes));
  o = run_scenario(s, rec.scenario_walk(s, walk), errors, rec.scenario_hooks());
  const int rc = o.ok() ? 0 : 1;
  if (!rec.error().empty()) {
    fmt::print(err, "dpc31 run: cannot record {}: {}\n", opt.scenario, rec.error());
    return 2;
  }
  if (!write_file(opt.record, rec.text())) {
    fmt::print(err, "dpc31 run: cannot write the trace to {}\n", opt.record);
    return 2;
  }
  return rc;
}

}  // namespace

int run_scenario_command(const RunOptions& opt, std::FILE* out, std::FILE* err) {
  LineSink walk;
  if (!opt.quiet) walk = [out](const std::string& line) { fmt::print(out, "{}\n", line); };
  const LineSink errors = [err](const std::string& line) { fmt::print(err, "{}\n", line); };
  Scenario s;
  ScenarioOutcome o;
  const int rc = opt.record.empty() ? run_scenario_file(opt.scenario, walk, errors, &s, &o)
                                    : run_recorded(opt, walk, errors, s, o, err);
  if (rc == 2) return rc;
  if (!opt.json.empty() && !write_json(opt.json, summary(s, o))) {
    fmt::print(err, "dpc31 run: cannot write the JSON summary to {}\n", opt.json);
    return 2;
  }
  return rc;
}

}  // namespace dpc31::cli
