// What a segment writes of itself (docs/segment.md, "Outputs"): the waveforms (VCD, FST, the
// logic-analyser form) with the line at the top and a scope per chip station, and one pcapng of
// the line, every telegram with its sender and who answered a request. `dpc31 run` of a segment
// scenario, dpc31.Segment and dpc31.SegmentScenario in Python write them through this one class.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pcapng.hpp"
#include "scenario_segment.hpp"
#include "segment.hpp"
#include "vocabulary.hpp"
#include "waveform.hpp"

namespace dpc31 {

struct SegmentOutputOptions {
  std::vector<wave::Options> waves;  // each a VCD or an FST (wave::Options)
  std::string pcap;                  // the line as pcapng ("" none)
  // TSL in bit times: the pcapng pairs a request and its answer as the bus check does with it
  // (an answer after TSL, or after TSL + TSYN from the asked station, stands alone).
  std::uint32_t slot_bits = 100;
};

// An output that cannot be made, found when a station joins (its scope, the signals asked).
struct SegmentOutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Not copied nor moved (the segment's on_line holds it; the pcapng writer is neither).
class SegmentOutputs {
 public:
  explicit SegmentOutputs(SegmentOutputOptions opt);
  // The observers it put on the segment and its chips stay there and do nothing from now on.
  ~SegmentOutputs();
  SegmentOutputs(const SegmentOutputs&) = delete;
  SegmentOutputs& operator=(const SegmentOutputs&) = delete;

  // Opens every file (temporaries next to the targets): a bad path is found before the run. False
  // with a line.
  bool open(std::string& error);
  // The line's TSL from now on (SegmentOutputOptions::slot_bits), as its masters join.
  void pair_within(std::uint32_t slot_bits) { opt_.slot_bits = slot_bits; }
  // Chip station `index` of `seg` joins, before its user side's init: its scope in every
  // waveform. False with a line (a scope an earlier station has: second_station_in_scope).
  bool add_station(Segment& seg, std::size_t index, const std::string& scope, std::string& error);
  // The station added last leaves again before it ran (Segment::remove_last_chip): as before it
  // was added.
  void remove_station();
  // Every station is on the line: `driver_codes` each one's code in line.driver, in the segment's
  // order (wave::Recorder::attach_line); the line's edges go to the waveforms from now on
  // (Segment::on_line). False with a line.
  bool attach_line(Segment& seg, std::vector<std::uint8_t> driver_codes, std::string& error);
  // A telegram of the line (Segment::on_telegram).
  void telegram(const LineTelegram& t);
  // After the line's flush: nothing more comes; the files are written up to seg.cycle().
  void end(const Segment& seg);
  // Writes every file (temporaries renamed over the targets). False with a line; nothing is
  // written unless this is called (a run that did not complete leaves every target alone).
  bool write(std::string& error);

 private:
  struct Held {
    LineTelegram t;
    std::string comment;
    std::uint8_t sa = 0;  // the request's, for the answer's mirror
    std::uint8_t da = 0;
  };
  void capture(const LineTelegram& t);
  void add(const Held& h);

  SegmentOutputOptions opt_;
  const Segment* seg_ = nullptr;
  std::vector<std::unique_ptr<wave::Recorder>> waves_;
  capture::PcapngWriter pcap_{capture::WriterOptions{"dpc31emu", "segment", true}};
  std::optional<Held> held_;
  std::vector<std::pair<std::string, std::string>> scoped_;  // each station's scope, its name
  std::uint64_t end_cycle_ = 0;
  std::shared_ptr<bool> live_ = std::make_shared<bool>(true);  // false once destroyed
};

// The outputs of a segment scenario's run (run_segment_scenario's observer): a scope per station
// of the scenario (station_scope), the line's driver codes from its stations, senders and
// masters. station_added() and stations_added() throw SegmentOutputError.
class SegmentScenarioOutputs : public SegmentObserver {
 public:
  SegmentScenarioOutputs(const SegmentScenario& s, SegmentOutputOptions opt);

  [[nodiscard]] const std::vector<std::string>& scopes() const { return scopes_; }
  [[nodiscard]] bool open(std::string& error) { return out_.open(error); }
  // The run ended (run_ends): write() may put the files in place.
  [[nodiscard]] bool ended() const { return ended_; }
  // Writes every file of a run that ended; false with a line.
  bool write(std::string& error);

  // Where the stations' firmware runs now, for its hang and fault lines: the scenario while the
  // stations start (line 0), then the step (`dpc31 run`'s and Python's).
  [[nodiscard]] const FirmwarePlace& firmware_place() const { return place_; }

  void station_added(Segment& seg, std::size_t index) override;
  void stations_added(Segment& seg) override;
  void step_begins(const SegmentStep& st, std::string_view text) override;
  void telegram(const LineTelegram& t) override { out_.telegram(t); }
  void run_ends(Segment& seg, std::uint32_t passed, std::uint32_t failed) override;

 private:
  const SegmentScenario& s_;
  std::vector<std::string> scopes_;
  SegmentOutputs out_;
  bool ended_ = false;
  FirmwarePlace place_;
};

}  // namespace dpc31
