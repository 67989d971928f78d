// GTKWave save files for the waveforms of runs (docs/waveforms.md, "GTKWave"): the signals
// grouped by block, the state machines and buffer states as text through the translate filter
// files of lib/waveform/gtkwave/ (installed as share/dpc31emu/gtkwave/), named markers at the DP
// and watchdog state changes.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace dpc31::wave {

struct SaveFile {
  std::string dump;                  // the waveform the save file opens
  std::vector<std::string> signals;  // the names written, below `top`, in declaration order
  std::vector<int> widths;
  bool flat = false;        // the logic-analyser form: the leaves directly under "dpc31"
  std::uint64_t start = 0;  // the first time, in the file's units: the window's (--from)
  std::uint64_t end = 0;    // the last time (start and end give the view GTKWave opens on)
  // Named markers (GTKWave has 26, A to Z): time in the file's units and the name.
  std::vector<std::pair<std::uint64_t, std::string>> markers;
  std::string filter_dir;     // "" = no translate filters (values as numbers)
  std::string top = "dpc31";  // the top scope ("segment" for a segment's waveform)
  int timescale_exp = -12;    // the file's unit, 10^exp seconds
};

// Where the translate filters are: share/dpc31emu/gtkwave beside the program (installed, or the
// copy in the build tree); "" if it has none.
std::string filter_dir();

// The save file's text (GTKWave 3.3's format).
std::string save_file_text(const SaveFile& f);

}  // namespace dpc31::wave
