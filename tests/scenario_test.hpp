// What the scenario tests share (scenario_test.cpp, scenario_timing_test.cpp,
// scenario_cpu51_test.cpp, scenario_long_run_test.cpp): the lines a run says, a scenario text run
// or parsed as "t.scn", a scenario file in a temporary directory.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

// emu/ is not on the tests' include path.
#include "scenario.hpp"
#include "test_files.hpp"

namespace scenario_test {

struct Lines {
  std::vector<std::string> lines;
  dpc31::LineSink sink() {
    return [this](const std::string& l) { lines.push_back(l); };
  }
  [[nodiscard]] bool has(const std::string& s) const {
    for (const std::string& l : lines) {
      if (l.find(s) != std::string::npos) return true;
    }
    return false;
  }
};

// `text` as "t.scn" parsed (a parse error fails the test) and run, its failures into `errors`.
inline dpc31::ScenarioOutcome run_text(const std::string& text, Lines& errors) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  EXPECT_TRUE(dpc31::parse_scenario(text, "t.scn", s, err)) << err.text();
  return dpc31::run_scenario(s, {}, errors.sink());
}

// The first parse error of `text` as "FILE:LINE: message"; "" if it parses.
inline std::string parse_error(const std::string& text) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  if (dpc31::parse_scenario(text, "t.scn", s, err)) return "";
  return err.text();
}

// A scenario file in a fresh private temporary directory (testutil::TempDir: TMPDIR, mkdtemp
// checked, removed with everything in it).
class TempFile {
 public:
  explicit TempFile(const std::string& text) : path_(dir_.write("s.scn", text)) {}
  [[nodiscard]] std::string path() const { return path_; }
  [[nodiscard]] std::filesystem::path dir() const { return dir_.path(); }

 private:
  testutil::TempDir dir_;
  std::string path_;
};

}  // namespace scenario_test
