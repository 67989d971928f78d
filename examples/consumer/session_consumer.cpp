// A C++ program on the installed session layer: the built-in DP master brings the example
// firmware DO4 to Data_Exchange and writes its outputs. Exit 0 only if every expect held.
#include <cstdio>
#include <string>

#include "dpc31/session/scenario.hpp"

int main() {
  static constexpr const char* kScenario =
      "profile dpc31\n"
      "baud 1500000\n"
      "firmware DO4\n"
      "slave address=5\n"
      "startup\n"
      "expect dp_state Data_Exchange\n"
      "exchange outputs=05,01\n"
      "expect port outputs 0x5\n";
  dpc31::Scenario scenario;
  dpc31::ScenarioError err;
  if (!dpc31::parse_scenario(kScenario, "consumer.scn", scenario, err)) {
    std::fprintf(stderr, "%s:%d: %s\n", err.file.c_str(), err.line, err.message.c_str());
    return 2;
  }
  const auto print = [](const std::string& line) { std::puts(line.c_str()); };
  const dpc31::ScenarioOutcome outcome = dpc31::run_scenario(scenario, {}, print);
  std::printf("session consumer: %u expects held, %u failed, cycle %llu\n", outcome.passed,
              outcome.failed, static_cast<unsigned long long>(outcome.final_cycle));
  return outcome.ok() && outcome.passed == 2 ? 0 : 1;
}
