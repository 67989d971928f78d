// dpc31 cosim's stimulus traces: the header of a shrunk trace (the run it names, refused where an
// option says otherwise) and the trace file read like the emulator's own text files.
#include "cosim_trace.hpp"

#include <fmt/core.h>

#include <filesystem>
#include <string_view>
#include <vector>

#include "chip_choice.hpp"
#include "rtl_library.hpp"
#include "textfile.hpp"
#include "whole_number.hpp"

namespace dpc31::cli {

namespace {

// The same files, by their real paths, in the same order (a path may name a file that is gone).
bool same_files(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  const auto real = [](const std::string& f) {
    std::error_code ec;
    return std::filesystem::weakly_canonical(std::filesystem::absolute(f, ec), ec);
  };
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(),
                    [&](const std::string& x, const std::string& y) { return real(x) == real(y); });
}

std::string joined(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : " ") + s;
  return out;
}

// The one line for what only profile `want` has (a variant, a built-in mutant: `key` `value`)
// beside a run on another: at the header line to edit, with what else would do
// (docs/golden-model.md). `line` is the header line of `key` (0: the option --key gave it),
// `profile_line` that of `# profile` (0: none).
std::string not_for_profile(const std::string& path, const CosimOptions& o, int profile_line,
                            const char* key, const std::string& value, int line, Profile want) {
  const std::string_view p = profile_name(want);
  if (line == 0) {
    return fmt::format(
        "{}:{}: recorded on profile {}, and --{} {} is for profile {}: edit this line or drop --{}",
        path, profile_line, o.profile_name, key, value, p, key);
  }
  if (profile_line != 0) {
    return fmt::format(
        "{}:{}: {} {} is for profile {}, not the profile {} of line {}: edit one of the two lines",
        path, line, key, value, p, o.profile_name, profile_line);
  }
  return fmt::format(
      "{}:{}: {} {} is for profile {}, not {} {}: give --profile {} or edit this line", path, line,
      key, value, p, o.profile_given ? "--profile" : "the default profile", o.profile_name, p);
}

// The run a shrunk trace's header names (`# profile NAME`, `# bus NAME`, `# variant NAME` or `-`,
// `# mutant NAME` or `-`, and for your RTL `# rtl PATH` per source, `# top NAME`, `# define D`
// per define or `# rtl-model PATH`, written below): taken into `o`, unless --profile, --bus,
// --variant, --mutant, --rtl, --rtl-model, --top or --define given says otherwise (refused: the
// trace would replay clean on another model; docs/golden-model.md). A trace without them keeps `o`.
// Each names one thing: given twice, it names none, and a `# top` or `# define` belongs to the
// `# rtl` sources. Every refusal is at the header line to edit.
bool take_trace_header(const std::string& path, const std::string& text, CosimOptions& o,
                       std::uint64_t& seed, std::string& error) {
  static constexpr std::string_view kOnce[] = {"profile", "bus", "variant",  "mutant",
                                               "seed",    "top", "rtl-model"};
  std::istringstream is(text);
  int n = 0;
  std::vector<std::string> rtl;
  std::string rtl_model;
  std::string top;
  std::vector<std::string> defines;
  std::map<std::string, int> first_line;  // of each key the header has
  for (std::string line; std::getline(is, line) && line.starts_with('#');) {
    ++n;
    std::istringstream ls(line.substr(1));
    std::string key;
    std::string rest;  // a path may hold spaces: the rest of the line
    ls >> key;
    std::getline(ls >> std::ws, rest);
    const bool whole_rest = key == "rtl" || key == "rtl-model" || key == "define";
    std::istringstream vs(rest);
    std::string value;
    std::string more;
    if (whole_rest ? rest.empty() : !(vs >> value)) continue;  // a comment
    const bool once = std::find(std::begin(kOnce), std::end(kOnce), key) != std::end(kOnce);
    if (!whole_rest && vs >> more) {
      // `# profile dpc31 spc3` names no one model: refused, not read as a comment and dropped.
      if (!once) continue;
      error = fmt::format("{}:{}: '# {}' takes one value, not '{}': a header line names one thing",
                          path, n, key, shown(rest));
      return false;
    }
    const auto [first, is_first] = first_line.try_emplace(key, n);
    if (!is_first && once) {
      error =
          fmt::format("{}:{}: '# {}' given twice, first at line {}", path, n, key, first->second);
      return false;
    }
    if (key == "rtl" || key == "rtl-model") {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(rest, ec)) {
        error =
            fmt::format("{}:{}: recorded with --{} {}: no such file", path, n, key, shown(rest));
        return false;
      }
      (key == "rtl" ? rtl.emplace_back() : rtl_model) = rest;
    } else if (key == "define") {
      defines.push_back(rest);
    } else if (key == "profile") {
      Profile p{};
      if (!parse_profile(value, p)) {
        error = fmt::format("{}:{}: '{}' is not a chip profile", path, n, shown(value));
        return false;
      }
      if (o.profile_given && p != o.profile) {
        error = fmt::format("{}:{}: recorded on profile {}, not --profile {}", path, n, value,
                            o.profile_name);
        return false;
      }
      o.profile = p;
      o.profile_name = value;
    } else if (key == "bus") {
      if (value != "intel" && value != "motorola") {
        error =
            fmt::format("{}:{}: '{}' is not a bus mode (intel, motorola)", path, n, shown(value));
        return false;
      }
      const BusMode b = value == "intel" ? BusMode::intel : BusMode::motorola;
      if (o.bus_given && b != o.bus) {
        error = fmt::format("{}:{}: recorded on bus {}, not --bus {}", path, n, value,
                            o.bus == BusMode::intel ? "intel" : "motorola");
        return false;
      }
      o.bus = b;
    } else if (key == "variant") {
      const std::string variant = value == "-" ? "" : value;
      if (Vpc3Variant v{}; !variant.empty() && !parse_vpc3_variant(variant, v)) {
        error = fmt::format("{}:{}: '{}' is not a variant (b, c, s; - for none)", path, n,
                            shown(value));
        return false;
      }
      if (!o.variant_name.empty() && variant != o.variant_name) {
        error = fmt::format("{}:{}: recorded with variant {}, not --variant {}", path, n, value,
                            o.variant_name);
        return false;
      }
      o.variant_name = variant;
    } else if (key == "mutant") {
      const std::string mutant = value == "-" ? "" : value;
      if (o.mutant_given && mutant != o.mutant) {
        error = fmt::format("{}:{}: recorded with mutant {}, not --mutant {}", path, n, value,
                            o.mutant.empty() ? "''" : o.mutant);
        return false;
      }
      // Checked here, where the line is known (the model is loaded later): a name of ours or,
      // with your RTL, a mutant_sel number.
      if (!mutant.empty() && !cosim::mutant_sel(mutant)) {
        error = fmt::format("{}:{}: '{}' is not a mutant", path, n, shown(value));
        return false;
      }
      o.mutant = mutant;
    } else if (key == "top") {
      top = value;
    } else if (key == "seed") {
      if (numbers::parse_whole(value, seed) != std::errc{}) {
        error = fmt::format("{}:{}: '{}' is not a seed", path, n, shown(value));
        return false;
      }
    }
  }
  const auto at = [&first_line](const char* key) {
    const auto it = first_line.find(key);
    return it == first_line.end() ? 0 : it->second;
  };
  if (!rtl.empty() && !rtl_model.empty()) {
    error = fmt::format("{}:{}: '# rtl-model' beside the '# rtl' of line {}: one model at a time",
                        path, at("rtl-model"), at("rtl"));
    return false;
  }
  for (const char* key : {"top", "define"}) {
    if (rtl.empty() && at(key) != 0) {
      error = rtl_model.empty()
                  ? fmt::format(
                        "{}:{}: '# {}' without '# rtl': it belongs to the RTL sources "
                        "the trace was run on (add them, or delete this line)",
                        path, at(key), key)
                  : fmt::format(
                        "{}:{}: '# {}' beside the '# rtl-model' of line {}: a built "
                        "model takes no top or define (delete this line)",
                        path, at(key), key, at("rtl-model"));
      return false;
    }
  }
  // What only one profile has, beside another: refused at the header line, not later as if an
  // option had said it (the hint to give --profile was then refused in turn).
  const int profile_line = at("profile");
  if (!o.variant_name.empty() && o.profile != Profile::vpc3plus &&
      (at("variant") != 0 || profile_line != 0)) {
    error = not_for_profile(path, o, profile_line, "variant", o.variant_name, at("variant"),
                            Profile::vpc3plus);
    return false;
  }
  const bool any_rtl =
      !rtl.empty() || !rtl_model.empty() || !o.rtl_sources.empty() || !o.rtl_model.empty();
  if (!any_rtl && !o.mutant.empty() && at("mutant") != 0 && !cosim::rtl_mutant_profile(o.mutant)) {
    error = fmt::format(
        "{}:{}: mutant {} is a mutant_sel number, for a run on your RTL: give --rtl or "
        "--rtl-model, or edit this line",
        path, at("mutant"), o.mutant);
    return false;
  }
  if (const auto p = cosim::rtl_mutant_profile(o.mutant);
      !any_rtl && p && *p != o.profile && (at("mutant") != 0 || profile_line != 0)) {
    error = not_for_profile(path, o, profile_line, "mutant", o.mutant, at("mutant"), *p);
    return false;
  }
  if (rtl.empty() && rtl_model.empty()) return true;
  const int rtl_line = rtl.empty() ? at("rtl-model") : at("rtl");
  // Your RTL: the run's model, as it was built (sources, top, defines) or loaded.
  const std::string recorded =
      rtl.empty() ? "--rtl-model " + rtl_model : fmt::format("--rtl {}", joined(rtl));
  if ((!o.rtl_sources.empty() || !o.rtl_model.empty()) &&
      !(same_files(o.rtl_sources, rtl) && same_files({o.rtl_model}, {rtl_model}))) {
    error = fmt::format("{}:{}: recorded with {}, not {}", path, rtl_line, recorded,
                        o.rtl_sources.empty() ? "--rtl-model " + o.rtl_model
                                              : fmt::format("--rtl {}", joined(o.rtl_sources)));
    return false;
  }
  if (!rtl.empty() && !o.top.empty() && o.top != top) {
    error = fmt::format("{}:{}: recorded with --top {}, not --top {}", path,
                        at("top") != 0 ? at("top") : rtl_line, top.empty() ? "''" : top, o.top);
    return false;
  }
  if (!rtl.empty() && !o.defines.empty() && o.defines != defines) {
    error = fmt::format("{}:{}: recorded with {}, not --define {}", path,
                        at("define") != 0 ? at("define") : rtl_line,
                        defines.empty() ? "no --define" : "--define " + joined(defines),
                        joined(o.defines));
    return false;
  }
  o.rtl_sources = rtl;
  o.rtl_model = rtl_model;
  if (!rtl.empty()) {
    o.top = top;
    o.defines = defines;
  }
  return true;
}

}  // namespace

// The header lines that name your RTL (none for the built-in models), as take_trace_header reads
// them: the real paths, so the trace replays from any directory.
std::string rtl_header(const CosimOptions& o) {
  const auto real = [](const std::string& f) {
    std::error_code ec;
    const std::filesystem::path p = std::filesystem::canonical(f, ec);
    return ec ? std::filesystem::absolute(f, ec).string() : p.string();
  };
  std::string out;
  for (const std::string& f : o.rtl_sources) out += fmt::format("rtl {}\n", real(f));
  if (!o.rtl_sources.empty()) out += fmt::format("top {}\n", o.top);
  for (const std::string& d : o.defines) out += fmt::format("define {}\n", d);
  if (!o.rtl_model.empty()) out += fmt::format("rtl-model {}\n", real(o.rtl_model));
  return out;
}

// A stimulus trace file (lockstep.hpp), read like the emulator's own text files: missing,
// a directory, empty or cut off is one line "FILE: reason" / "FILE:LINE: reason"; its header
// sets the profile, bus, variant, mutant and RTL in `o`, and `seed` (0 where it names none).
bool read_stimulus(const std::string& path, cosim::Stimulus& s, CosimOptions& o,
                   std::uint64_t& seed, std::string& error) {
  constexpr std::size_t kMaxBytes = 256u << 20;  // 100 M cycles of stimulus fit easily
  std::string text;
  std::string why;
  if (!read_text_file(path, kMaxBytes, "stimulus trace", text, why)) {
    error = fmt::format("{}: {}", path, why);
    return false;
  }
  // A UTF-8 BOM before the first line is skipped, as in a golden trace and a scenario.
  if (text.starts_with("\xEF\xBB\xBF")) text.erase(0, 3);
  if (text.empty()) {
    error = fmt::format("{}: empty file, not a stimulus trace", path);
    return false;
  }
  if (const int line = cut_off_line(text, why); line != 0) {
    error = fmt::format("{}:{}: {}", path, line, why);
    return false;
  }
  // The header first: it names the profile, whose inputs the lines may use.
  return take_trace_header(path, text, o, seed, error) &&
         cosim::parse_trace(text, path, s, error, o.profile);
}

}  // namespace dpc31::cli
