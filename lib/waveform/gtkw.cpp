#include "gtkw.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <map>

#include "gtkw_view.hpp"

namespace dpc31::wave {

namespace {

// GTKWave's trace flags (analyzer.h): hex 0x2, binary 0x8, right-justified 0x20, blank 0x200,
// translated by a filter file 0x2000, group begin 0x800000, group end 0x1000000.
constexpr const char* kBin = "@28";
constexpr const char* kHex = "@22";
constexpr const char* kHexTranslated = "@2022";
constexpr const char* kGroupBegin = "@800200";
constexpr const char* kGroupEnd = "@1000200";

// The translate filter of each signal that has one (lib/waveform/gtkwave/).
const std::map<std::string, std::string>& filters() {
  static const std::map<std::string, std::string> f = {
      {"state.dp_state", "dp_state.txt"},   {"state.wd_state", "wd_state.txt"},
      {"state.baud_code", "baud_code.txt"}, {"state.service", "service.txt"},
      {"blocks.dout_sm", "buffer_sm.txt"},  {"blocks.din_sm", "buffer_sm.txt"},
      {"blocks.diag_sm", "diag_sm.txt"}};
  return f;
}

std::string absolute(const std::string& p) {
  std::error_code ec;
  const auto a = std::filesystem::absolute(p, ec);
  return ec ? p : a.string();
}

}  // namespace

std::string filter_dir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const auto d = (exe.parent_path() / DPC31_BIN_TO_DATA / "gtkwave").lexically_normal();
  return std::filesystem::is_regular_file(d / "dp_state.txt", ec) ? d.string() : std::string();
}

std::string save_file_text(const SaveFile& f) {
  std::string s = fmt::format(
      "[*] dpc31emu: the run's signals by block, states by name (docs/waveforms.md)\n"
      "[dumpfile] \"{}\"\n",
      absolute(f.dump));
  std::vector<std::uint64_t> at;
  for (const auto& m : f.markers) at.push_back(m.first);
  s += gtkw::view_lines(f.start, f.end, f.timescale_exp + 15, at);
  for (std::size_t i = 0; i < f.markers.size() && i < 26; ++i) {
    s += fmt::format("[markername] {}{}\n", static_cast<char>('A' + i), f.markers[i].second);
  }
  s += "[sst_expanded] 1\n";
  std::map<std::string, int> filter_index;
  std::string group;
  for (std::size_t i = 0; i < f.signals.size(); ++i) {
    const std::string& name = f.signals[i];
    const std::string block = name.substr(0, name.find('.'));
    if (block != group) {
      if (!group.empty()) s += fmt::format("{}\n-{}\n", kGroupEnd, group);
      s += fmt::format("{}\n-{}\n", kGroupBegin, block);
      group = block;
    }
    const std::string leaf = f.flat ? name.substr(name.find('.') + 1) : name;
    const int w = f.widths[i];
    const std::string full =
        w == 1 ? fmt::format("{}.{}", f.top, leaf) : fmt::format("{}.{}[{}:0]", f.top, leaf, w - 1);
    // A station's signal in a segment's waveform has the filter of the chip's signal.
    auto filter = filters().find(name);
    if (filter == filters().end()) filter = filters().find(name.substr(name.find('.') + 1));
    if (filter != filters().end() && !f.filter_dir.empty()) {
      auto [it, added] =
          filter_index.emplace(filter->second, static_cast<int>(filter_index.size()) + 1);
      s += fmt::format("{}\n^{} {}/{}\n{}\n", kHexTranslated, it->second, f.filter_dir,
                       filter->second, full);
    } else {
      s += fmt::format("{}\n{}\n", w == 1 ? kBin : kHex, full);
    }
  }
  if (!group.empty()) s += fmt::format("{}\n-{}\n", kGroupEnd, group);
  return s;
}

}  // namespace dpc31::wave
