#include "run.hpp"

#include <fmt/core.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <system_error>

// The scenario runner lives with the emulator (emu/ is not on this target's include path).
#include "../../emu/scenario.hpp"

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
bool write_json(const std::string& path, const nlohmann::json& j) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) return false;
    f << j.dump(2) << '\n';
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

}  // namespace

int run_scenario_command(const RunOptions& opt, std::FILE* out, std::FILE* err) {
  LineSink walk;
  if (!opt.quiet) walk = [out](const std::string& line) { fmt::print(out, "{}\n", line); };
  const LineSink errors = [err](const std::string& line) { fmt::print(err, "{}\n", line); };
  Scenario s;
  ScenarioOutcome o;
  const int rc = run_scenario_file(opt.scenario, walk, errors, &s, &o);
  if (rc == 2) return rc;
  if (!opt.json.empty() && !write_json(opt.json, summary(s, o))) {
    fmt::print(err, "dpc31 run: cannot write the JSON summary to {}\n", opt.json);
    return 2;
  }
  return rc;
}

}  // namespace dpc31::cli
