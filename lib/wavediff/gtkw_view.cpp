#include "gtkw_view.hpp"

#include <fmt/format.h>

#include <cmath>

namespace dpc31::gtkw {

std::string view_lines(std::uint64_t first, std::uint64_t last, int pow,
                       const std::vector<std::uint64_t>& markers) {
  // GTKWave 3.3 counts a file's times in the unit's prefix, the file's time times the unit's 1,
  // 10 or 100 (a 10ns file's #1 is its 10 ns), and reads the save file's times in those: 128 bits,
  // as #2^64 - 1 at 100 ps is past 64.
  __extension__ using u128 = unsigned __int128;
  const u128 scale = pow % 3 == 0 ? 1 : pow % 3 == 1 ? 10 : 100;
  std::string s = fmt::format("[timestart] {}\n", first * scale);
  // GTKWave 3.3 shows 2^-zoom of its time units per 200 pixels of its wave pane (measured: 2.79 x
  // 2^-zoom in its default 1000-pixel window, whose pane is 558 pixels): from [timestart],
  // -log2(span / 2) opens on the whole file, every marker in view, in any pane of 400 pixels or
  // more (a window from a late --from is far from time 0).
  const u128 span = last > first ? (last - first) * scale : 0;
  const double zoom = span > 2 ? -std::log2(static_cast<double>(span) / 2.0) : 0.0;
  s += fmt::format("*{:.6f} -1", zoom);
  for (std::size_t i = 0; i < 26; ++i) {
    s += i < markers.size() ? fmt::format(" {}", markers[i] * scale) : std::string(" -1");
  }
  s += '\n';
  return s;
}

}  // namespace dpc31::gtkw
