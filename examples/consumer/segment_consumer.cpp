// A C++ program on the installed segment outputs (dpc31emu::segment_outputs): a segment of two
// slaves (DO4 on an SPC3, CNT2 on a VPC3+) brought to Data_Exchange by the built-in master,
// its waveform (VCD) and the pcapng of its line written to the two paths given. Exit 0 only if
// every expect held and both files were written.
#include <cstdio>
#include <string>

#include "dpc31/segment_outputs/segment_outputs.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: segment_consumer VCD PCAPNG\n");
    return 2;
  }
  static constexpr const char* kScenario =
      "segment baud=1500000\n"
      "station 5 name=spc3 profile=spc3 firmware=DO4\n"
      "station 6 name=vpc3plus profile=vpc3plus firmware=CNT2\n"
      "master 2 slaves=5,6\n"
      "startup\n"
      "cycle 2\n"
      "expect state 5 Data_Exchange\n"
      "expect state 6 Data_Exchange\n";
  dpc31::SegmentScenario scenario;
  dpc31::ScenarioError err;
  if (!dpc31::parse_segment_scenario(kScenario, "segment.scn", scenario, err)) {
    std::fprintf(stderr, "%s\n", err.text().c_str());
    return 2;
  }
  dpc31::SegmentOutputOptions opt;
  dpc31::wave::Options vcd;
  vcd.path = argv[1];
  opt.waves.push_back(vcd);
  opt.pcap = argv[2];
  dpc31::SegmentScenarioOutputs out(scenario, opt);
  std::string error;
  if (!out.open(error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 2;
  }
  const auto print = [](const std::string& line) { std::puts(line.c_str()); };
  const int code = dpc31::run_segment_scenario(scenario, print, print, &out);
  if (!out.ended() || !out.write(error)) {
    std::fprintf(stderr, "segment consumer: %s\n", error.c_str());
    return 1;
  }
  std::printf("segment consumer: exit %d, scopes %s and %s\n", code, out.scopes().at(0).c_str(),
              out.scopes().at(1).c_str());
  return code;
}
