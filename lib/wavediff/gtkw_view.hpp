// The view a GTKWave 3.3 save file opens on, shared by the save files of runs
// (lib/waveform/gtkw.cpp, docs/waveforms.md "GTKWave") and of wavediff --merge (merge.cpp,
// docs/wavediff.md "One file for a comparison").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace dpc31::gtkw {

// The "[timestart] ..." line and the zoom line (the zoom, the primary marker -1, then the named
// markers A..Z, -1 for none; at most 26 of `markers` are written) that open GTKWave on a file's
// FIRST..LAST with every marker in view. Times are the file's, in units of 10^pow fs.
std::string view_lines(std::uint64_t first, std::uint64_t last, int pow,
                       const std::vector<std::uint64_t>& markers);

}  // namespace dpc31::gtkw
