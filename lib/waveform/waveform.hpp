// Waveforms of a chip run: VCD (IEEE 1364-2005 §18) or FST (fstapi from Debian's verilator
// package) of the pins, the bus, the state machines and the block registers, under stable
// hierarchical names (docs/waveforms.md). Only the signals and the window asked for are written.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "dpc31/chip.hpp"

namespace dpc31::wave {

struct Options {
  std::string path;
  bool fst = false;
  std::vector<std::string> signals;  // glob patterns on the names below ("" = all)
  std::uint64_t from = 0;            // first cycle written
  std::uint64_t to = UINT64_MAX;     // one past the last cycle written
  int timescale_exp = -12;           // 10^exp seconds per unit: -12 1 ps, -8 10 ns, ...
  bool flat = false;                 // one scope, 1-bit signals only (for sigrok's VCD input)
  std::string gtkw;                  // also a GTKWave save file for it here (gtkw.hpp)
  std::string pvs;                   // also a PulseView session setup here (pvs.hpp): flat VCD
  std::uint32_t baud = 0;            // the bus's rate, for that setup's UART decoder
};

// The documented signal list: name (below the top scope "dpc31") and width.
struct SignalDef {
  const char* name;
  int width;
};
const std::vector<SignalDef>& signal_list();

// line.driver of a segment's waveform: the PROFIBUS address of the station that drives the line,
// or one of these.
inline constexpr std::uint8_t kNoDriver = 0xFF;              // the line is idle
inline constexpr std::uint8_t kDriverWithoutAddress = 0xFE;  // a scripted sender

// Watches a chip (or the chips of a segment) from now on and writes the waveform as the run goes:
// changes wait in a small buffer until the chip's time has passed them (RxD edges are known ahead
// of time), so memory stays bounded however long the run. finish() writes the rest and puts the
// file in place.
class Recorder {
 public:
  explicit Recorder(const Options& o);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Opens the files now (else the first attach does): a bad path is found before the run. False
  // with a one-line error.
  bool open(std::string& error);
  // False (with a one-line error) if a signal pattern matches no signal of a chip: what attach()
  // checks first, for a caller that finds bad input before the run (with open()).
  bool check_signals(std::string& error) const;
  // False (with a one-line error) if a signal pattern matches nothing or the options are bad.
  bool attach(Chip& chip, std::string& error);
  // A segment (docs/segment.md, docs/waveforms.md "Segments"): under the top scope "segment",
  // the line (line.level, line.driver) and each chip's signals under its station's scope.
  // attach_station() each chip station as it joins (before it runs), then attach_line() once
  // every station is on the line: `driver_codes` has each station's code in line.driver (in the
  // segment's order, senders too), `line_final` the cycle before which every edge of the line
  // has been reported (Segment::line_final). Then every edge the line's holder drives through
  // line_edge (Segment::on_line). False with a one-line error as attach().
  bool attach_station(Chip& chip, const std::string& scope, std::string& error);
  // The last station attached leaves again before the line is attached (its chip left the
  // segment before it ran: Segment::remove_last_chip): its scope, its variables and its changes
  // go, the first station's with the line's.
  void detach_station();
  bool attach_line(std::vector<std::uint8_t> driver_codes, std::uint32_t bit_cycles,
                   std::function<std::uint64_t()> line_final, std::string& error);
  void line_edge(std::size_t station, std::uint64_t cycle, bool level);
  // Writes everything up to `end_cycle` (temporary file, then rename). False with a reason.
  bool finish(std::uint64_t end_cycle, std::string& error);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dpc31::wave
