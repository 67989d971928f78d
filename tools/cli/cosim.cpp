// dpc31 cosim: the C++ blocks against the Verilated RTL, cycle by cycle, over seeded random
// stimulus (or a replayed trace). Exit 0 no divergence, 1 divergence, 2 bad input.
#include "cosim.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "chip_choice.hpp"
#include "lockstep.hpp"
#include "outfile.hpp"
#include "rtl_library.hpp"
#include "scenario.hpp"
#include "session.hpp"
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

// The variant the run's chip has: the VPC3+'s is its ASIC type, VPC3+C where none was given
// (docs/golden-model.md); the other profiles have none.
std::optional<Vpc3Variant> variant_run(const cosim::DutOptions& d) {
  if (d.profile != Profile::vpc3plus) return std::nullopt;
  return static_cast<Vpc3Variant>(d.asic_type());
}

// Its name (b, c, s; "" for none), as --variant and a trace's `# variant` give it.
std::string variant_run_name(const cosim::DutOptions& d) {
  const std::optional<Vpc3Variant> v = variant_run(d);
  return v ? std::string(vpc3_variant_name(*v)) : "";
}

// The summary's `variant`: the ASIC type as a number (12 for C), null for none.
nlohmann::json variant_json(const cosim::DutOptions& d) {
  const std::optional<Vpc3Variant> v = variant_run(d);
  return v ? nlohmann::json(static_cast<int>(*v)) : nlohmann::json();
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
  const std::string recorded = rtl.empty() ? "--rtl-model " + rtl_model : "--rtl " + joined(rtl);
  if ((!o.rtl_sources.empty() || !o.rtl_model.empty()) &&
      !(same_files(o.rtl_sources, rtl) && same_files({o.rtl_model}, {rtl_model}))) {
    error = fmt::format(
        "{}:{}: recorded with {}, not {}", path, rtl_line, recorded,
        o.rtl_sources.empty() ? "--rtl-model " + o.rtl_model : "--rtl " + joined(o.rtl_sources));
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

// True if `dir` is a directory or can be made one: the nearest part of it that exists is a
// directory.
bool can_be_directory(const std::filesystem::path& dir, std::string& why) {
  std::error_code ec;
  for (std::filesystem::path p = dir; !p.empty(); p = p.parent_path()) {
    const auto st = std::filesystem::status(p, ec);
    if (std::filesystem::exists(st)) {
      if (std::filesystem::is_directory(st)) return true;
      why = p == dir ? "not a directory" : fmt::format("{} is not a directory", p.string());
      return false;
    }
    if (p == p.parent_path()) break;
  }
  return true;  // a relative path below the working directory
}

// The files a waveform window (--vcd, --dump) writes into its directory.
const char* const kWindowFiles[] = {"emu.vcd", "rtl.vcd", "rtl_internal.fst"};

// "" if each of the window's files in `dir` can be written (opened, then discarded), else the
// one-line reason: checked before the seeds run, not found after them.
std::string window_unwritable(const std::string& dir) {
  for (const char* name : kWindowFiles) {
    outfile::OutFile out;
    if (!out.open((std::filesystem::path(dir) / name).string())) return out.error();
  }
  return "";
}

// The shrinker's budgets: a seed's stimulus is thousands of cycles, a session's millions, and
// each run replays it up to the divergence (a session stops shrinking sooner; what it has is
// still a trace that fails).
constexpr int kSeedShrinkRuns = 3000;
constexpr int kSessionShrinkRuns = 50;

// What a divergence of `s` leaves: its stimulus shrunk (in at most `max_runs` lockstep runs) into
// --out as `name` (the header names the run's model and `origin`, a seed or a session) and the
// waveform window in --vcd; `entry` gets their paths, a file not written goes to `output_failed`.
void write_divergence(const CosimOptions& o, const cosim::Stimulus& s, const cosim::RunResult& r,
                      const cosim::DutOptions& dut, const std::string& name,
                      const std::string& origin, int max_runs, nlohmann::json& entry,
                      const std::function<void(const std::string&)>& output_failed) {
  using namespace dpc31::cosim;
  entry["signals"] = r.signals;
  const Stimulus small = shrink(s, dut, o.mutant, max_runs);
  const std::string dir = o.out_dir.empty() ? "." : o.out_dir;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);  // checked up front; a failure shows below
  // A replay shrinks its trace again under a name of its own: a seed run's trace, which the
  // replayed one may be or come from, is never written over, nor the replayed trace itself.
  const std::string trace = (std::filesystem::path(dir) / name).string();
  const bool replayed = !o.replay.empty() && std::filesystem::equivalent(trace, o.replay, ec);
  std::string error;
  const auto events = [](const Stimulus& x) { return x.event_count(); };
  Stimulus before = s;
  before.resize(static_cast<std::uint64_t>(r.divergence) + 1);
  const std::string variant = variant_run_name(dut);  // the VPC3+'s default C named too
  const std::string header = fmt::format(
      "profile {}\nbus {}\nvariant {}\n{}\nmutant {}\n{}shrunk from {} to {} stimulus "
      "events ({} cycles)",
      o.profile_name, o.bus == BusMode::intel ? "intel" : "motorola",
      variant.empty() ? "-" : variant, origin, o.mutant.empty() ? "-" : o.mutant, rtl_header(o),
      events(before), events(small), small.size());
  if (replayed) {
    if (!o.quiet) {
      fmt::print(stderr,
                 "  shrunk to {} stimulus events: not written over {}, the trace "
                 "replayed\n",
                 events(small), trace);
    }
  } else if (outfile::write_file(trace, write_trace(small, header), error)) {
    entry["trace"] = trace;
    if (!o.quiet) {
      // The shrinker keeps any stimulus that still fails: idled, it may fail sooner, and its
      // replay reports that cycle.
      const std::int64_t own = run_lockstep(small, dut, o.mutant).divergence;
      fmt::print(stderr, "  shrunk to {} stimulus events{}: {}\n", events(small),
                 own == r.divergence
                     ? ""
                     : fmt::format(", which diverge at cycle {} (replay it there)", own),
                 trace);
    }
  } else {
    output_failed(error);
  }
  if (!o.vcd_dir.empty()) {
    // Drawn over the run that failed, not the shrunk stimulus cut at the divergence: the
    // --window cycles after it too, idle where the stimulus has ended.
    const auto d = static_cast<std::uint64_t>(r.divergence);
    const std::uint64_t from = d > o.window ? d - o.window : 0;
    Stimulus around = s;
    around.resize(d + o.window + 1);
    // Joined as paths: `--vcd win/` names win/emu.vcd, not win//emu.vcd.
    const auto in_vcd = [&](const char* name) {
      return (std::filesystem::path(o.vcd_dir) / name).string();
    };
    if (write_window(around, dut, o.mutant, from, around.size(), o.vcd_dir, error)) {
      entry["vcd"] = {in_vcd("emu.vcd"), in_vcd("rtl.vcd")};
    } else {
      output_failed(error);
    }
    const cosim::RtlFst fst =
        write_rtl_fst(around, dut, o.mutant, in_vcd("rtl_internal.fst"), error);
    if (fst == cosim::RtlFst::written) {
      entry["fst"] = in_vcd("rtl_internal.fst");
    } else if (fst == cosim::RtlFst::failed) {
      output_failed(error);
    } else if (!o.quiet) {
      fmt::print(stderr, "  {}\n", error);
    }
  }
}

// --dump: the whole run of `s`, both sides, for wavediff or GTKWave.
void write_dump(const CosimOptions& o, const cosim::Stimulus& s, const cosim::DutOptions& dut,
                const std::function<void(const std::string&)>& output_failed) {
  std::string error;
  if (!write_window(s, dut, o.mutant, 0, s.size(), o.dump_dir, error)) output_failed(error);
  const cosim::RtlFst fst = write_rtl_fst(
      s, dut, o.mutant, (std::filesystem::path(o.dump_dir) / "rtl_internal.fst").string(), error);
  if (fst == cosim::RtlFst::failed) {
    output_failed(error);
  } else if (fst == cosim::RtlFst::not_traced && !o.quiet) {
    fmt::print(stderr, "{}\n", error);
  }
}

// The waveform windows' files, checked before the run (false: the line printed, exit 2).
bool windows_ready(const CosimOptions& o) {
  // One that cannot be written was found only after the run. --dump always writes its directory,
  // made now; --vcd's is made at a divergence, its files are checked now if it is there: first,
  // so that a refusal leaves no --dump directory behind.
  for (const auto& [opt, dir, make] :
       {std::tuple{"--vcd", o.vcd_dir, false}, std::tuple{"--dump", o.dump_dir, true}}) {
    if (dir.empty()) continue;
    std::error_code ec;
    if (make) std::filesystem::create_directories(dir, ec);
    if (ec) {
      fmt::print(stderr, "dpc31 cosim: {} {}: cannot create the directory: {}\n", opt, dir,
                 ec.message());
      return false;
    }
    if (!std::filesystem::is_directory(dir, ec)) continue;
    if (const std::string why = window_unwritable(dir); !why.empty()) {
      fmt::print(stderr, "{}\n", why);
      return false;
    }
  }
  return true;
}

// Text for an XML attribute value: the markup characters as entities, tab, line feed and
// carriage return as character references (an attribute's newline would read as a space), and
// the other C0 controls, which XML 1.0 cannot carry at all, as U+FFFD. A session's case is named
// by its scenario's file name, which may hold any of them.
std::string xml_attribute(std::string_view text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      case '\t':
        out += "&#9;";
        break;
      case '\n':
        out += "&#10;";
        break;
      case '\r':
        out += "&#13;";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
          out += "\xEF\xBF\xBD";
        } else {
          out += c;
        }
    }
  }
  return out;
}

std::string junit(const std::string& profile, const nlohmann::json& results) {
  std::string cases;
  int failures = 0;
  for (const auto& r : results) {
    // A seed's case, or a session's (named by its scenario).
    // The whole name escaped: a merged summary's profile is a string as any other.
    const std::string name =
        xml_attribute(r.contains("seed")
                          ? fmt::format("{}.seed{}", profile, r["seed"].get<std::uint64_t>())
                          : fmt::format("{}.session.{}", profile, r["session"].get<std::string>()));
    // A session fails on a divergence and on a scenario expect that did not hold (exit 1 both).
    const bool expects_failed =
        r.contains("scenario_expects_passed") && !r["scenario_expects_passed"].get<bool>();
    if (r["diverged"].get<bool>()) {
      ++failures;
      cases += fmt::format(
          "  <testcase classname=\"cosim\" name=\"{}\"><failure message=\"divergence at cycle "
          "{}\"/></testcase>\n",
          name, r["cycle"].get<std::int64_t>());
    } else if (expects_failed) {
      ++failures;
      cases += fmt::format(
          "  <testcase classname=\"cosim\" name=\"{}\"><failure message=\"an expect of the "
          "scenario failed\"/></testcase>\n",
          name);
    } else {
      cases += fmt::format("  <testcase classname=\"cosim\" name=\"{}\"/>\n", name);
    }
  }
  return fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuite name=\"dpc31-cosim\" tests=\"{}\" "
      "failures=\"{}\">\n{}</testsuite>\n",
      results.size(), failures, cases);
}

// The end of a run: the JSON summary, the JUnit of its `results`, then the first output that
// failed. Exit 0 clean, 1 a divergence, 2 an output not written.
int finish(const CosimOptions& o, const nlohmann::json& summary, const nlohmann::json& results,
           outfile::OutFile& junit_out, const std::string& failed_output) {
  fmt::print("{}\n", summary.dump(2));
  if (!o.junit.empty() &&
      !(junit_out.write(junit(o.profile_name, results)) && junit_out.commit())) {
    fmt::print(stderr, "{}\n", junit_out.error());
    return 2;
  }
  if (!failed_output.empty()) {
    fmt::print(stderr, "{}\n", failed_output);
    return 2;
  }
  const bool diverged = std::any_of(results.begin(), results.end(), [](const nlohmann::json& r) {
    return r["diverged"].get<bool>();
  });
  return diverged ? 1 : 0;
}

// "" or why the built-in --mutant NAME does not run on the run's profile: the built-in mutants
// live in a model of one profile (the SAP header machine's: vpc3plus).
std::string mutant_not_on_profile(const CosimOptions& o) {
  const auto p = cosim::rtl_mutant_profile(o.mutant);
  if (!p || *p == o.profile) return "";
  return fmt::format("mutant '{}' is built for profile {}, not {} (--profile {})", o.mutant,
                     profile_name(*p), o.profile_name, profile_name(*p));
}

// Whether the run's RTL side can be made (the built-in model of its profile, or --mutant's); else
// false with the line printed (exit 2): a mutant of another profile, or no such mutant.
bool rtl_dut_ready(const CosimOptions& o, const cosim::DutOptions& dut) {
  if (cosim::make_rtl_dut(dut, o.mutant)) return true;
  if (const std::string why = mutant_not_on_profile(o); !why.empty()) {
    fmt::print(stderr, "dpc31 cosim: {}\n", why);
  } else {
    fmt::print(stderr, "dpc31 cosim: no RTL model for profile {} mutant '{}' (no such mutant)\n",
               o.profile_name, o.mutant);
  }
  return false;
}

// The model the run uses in place of the built-in ones: --rtl (built into the cache, or taken
// from it) or --rtl-model. False with the line already printed (exit 2).
// `id` names the model in the JSON summary the same on every machine: the cache key for --rtl,
// the file name for --rtl-model, "" for the built-in models.
bool load_rtl(const CosimOptions& o, cosim::DutOptions& dut, std::string& id) {
  using namespace dpc31::cosim;
  const auto fail = [](const std::string& why) {
    fmt::print(stderr, "dpc31 cosim: {}\n", why);
    return false;
  };
  if (o.rtl_sources.empty() && o.rtl_host_code) return fail("--rtl-host-code is for --rtl");
  if (o.rtl_sources.empty() && o.rtl_model.empty()) {
    if (!o.top.empty() || !o.defines.empty())
      return fail(fmt::format("--{} is for --rtl", o.top.empty() ? "define" : "top"));
    return true;
  }
  if (!o.rtl_sources.empty() && !o.rtl_model.empty())
    return fail("--rtl and --rtl-model: one model at a time");
  std::string path = o.rtl_model;
  std::string error;
  // The note that a build starts (minutes) only on a terminal, as the progress bar: in a log,
  // stderr is the report alone.
  std::FILE* progress = o.quiet || isatty(STDERR_FILENO) == 0 ? nullptr : stderr;
  if (!o.rtl_sources.empty() &&
      !build_rtl_model({o.rtl_sources, o.top, o.defines, o.profile, o.rtl_host_code}, path, error,
                       progress)) {
    return fail(error);
  }
  if (o.rtl_sources.empty() && (!o.top.empty() || !o.defines.empty()))
    return fail("--top and --define are for --rtl (a --rtl-model is built already)");
  dut.rtl = RtlLibrary::load(path, error);
  if (!dut.rtl) return fail(error);
  // Its PROFILE is fixed when it is built: on another profile every seed would "diverge".
  if (dut.rtl->profile() != o.profile) {
    return fail(fmt::format(
        "{}: the model is built for profile {}, not {}: run it with --profile {} (a session: a "
        "scenario of that profile), or build it with PROFILE {}",
        path, profile_name(dut.rtl->profile()), o.profile_name, profile_name(dut.rtl->profile()),
        o.profile_name));
  }
  const std::filesystem::path p(path);
  id = (o.rtl_model.empty() ? p.parent_path().filename() : p.filename()).string();
  if (!o.mutant.empty()) {
    if (!mutant_sel(o.mutant))
      return fail(fmt::format(
          "--mutant {}: with --rtl, a mutant of rtl/dpc31_blocks.v by name or a number 1..15 "
          "for the mutant_sel input",
          o.mutant));
    if (!dut.rtl->has_mutant_sel())
      return fail(
          fmt::format("--mutant {}: module {} has no mutant_sel input (rtl/dpc31_blocks.v "
                      "has it with --define MUTANTS)",
                      o.mutant, dut.rtl->top()));
    // A mutant of rtl/dpc31_blocks.v by name runs where the built-in one does.
    if (const std::string why = mutant_not_on_profile(o); !why.empty()) return fail(why);
  }
  if (!make_rtl_dut(dut, o.mutant))
    return fail(path + ": its create() returned NULL: no model to run (out of memory?)");
  return true;
}

// What a random run's JSON summary says about the run besides its results: a merge of shards
// checks that these are the same in every shard (docs/regression.md).
const char* const kRunKeys[] = {"profile",         "bus",       "variant", "mutant", "rtl",
                                "cycles_per_seed", "keep_going"};

// "" if the run keys of a shard's summary have the types a run writes, else what is wrong with
// the first that has not ("FIELD: VALUE is not …"): equal in every shard is not enough.
std::string run_key_mistyped(const nlohmann::json& j) {
  for (const char* k : kRunKeys) {
    const nlohmann::json& v = j[k];
    const std::string_view key = k;
    const char* want = nullptr;
    if (key == "variant") {
      if (!v.is_null() && !v.is_number_unsigned()) want = "null or a variant number";
    } else if (key == "cycles_per_seed") {
      if (!v.is_number_unsigned()) want = "a number of cycles";
    } else if (key == "keep_going") {
      if (!v.is_boolean()) want = "true or false";
    } else if (!v.is_string()) {
      want = "a string";
    }
    if (want != nullptr) return fmt::format("{}: {} is not {}", k, shown(v.dump()), want);
  }
  return "";
}

// A shard's summary nests 3 levels (the object, results, a result): deeper input is refused
// while it is parsed, before it is built (a 400 KB file of '[' crashed the merge, a 40 KB one
// printed 800 MB; docs/security.md).
constexpr int kMaxSummaryDepth = 16;
struct TooDeep {};

// The text as JSON, discarded if it is not JSON; `too_deep` if it nests beyond kMaxSummaryDepth.
nlohmann::json parse_summary(const std::string& text, bool& too_deep) {
  too_deep = false;
  try {
    return nlohmann::json::parse(
        text,
        [](int depth, nlohmann::json::parse_event_t /*event*/, nlohmann::json& /*value*/) {
          if (depth >= kMaxSummaryDepth) throw TooDeep{};  // depth counts from 0
          return true;
        },
        false);
  } catch (const TooDeep&) {
    too_deep = true;
    return nlohmann::json(nlohmann::json::value_t::discarded);
  }
}

// Why a shard's summary does not add up ("" if it does): its seeds are not its part of the run's
// range, run in order from the first, all of them unless it stopped at its one divergence
// (without --keep-going), or its counts are not those of its results.
std::string shard_mismatch(const nlohmann::json& j) {
  const nlohmann::json& of = j["shard"]["of"];
  if (!of.is_object() || !of.value("from", nlohmann::json()).is_number_unsigned() ||
      !of.value("to", nlohmann::json()).is_number_unsigned())
    return "a shard without the seed range of its run";
  const auto index = j["shard"]["index"].get<std::uint64_t>();
  const auto count = j["shard"]["count"].get<std::uint64_t>();
  const auto from = of["from"].get<std::uint64_t>();
  const auto to = of["to"].get<std::uint64_t>();
  // The bounds of --seeds and --shard keep the arithmetic below within 64 bits.
  if (to < from || to - from > 100'000'000 || count == 0 || count > 0xFFFF'FFFF || index == 0 ||
      index > count)
    return fmt::format("shard {}/{} of seeds from {} to {} is no shard of a run", index, count,
                       from, to);
  const std::uint64_t lo = from + (to - from) * (index - 1) / count;
  const std::uint64_t hi = from + (to - from) * index / count;
  if (j["seeds"]["from"] != lo || j["seeds"]["to"] != hi)
    return fmt::format("seeds from {} to {}, but shard {}/{} of seeds from {} to {} has {} to {}",
                       j["seeds"]["from"].dump(), j["seeds"]["to"].dump(), index, count, from, to,
                       lo, hi);
  const nlohmann::json& results = j["results"];
  std::uint64_t diverged = 0;
  for (std::size_t k = 0; k < results.size(); ++k) {
    const auto seed = results[k]["seed"].get<std::uint64_t>();
    if (seed != lo + k)
      return fmt::format("result {} is seed {}, not {}: not its seeds from {} to {} in order",
                         k + 1, seed, lo + k, lo, hi);
    if (results[k]["diverged"].get<bool>()) ++diverged;
  }
  const bool stopped =
      j["keep_going"] != true && diverged == 1 && results.back()["diverged"].get<bool>();
  if (results.size() != hi - lo && !stopped)
    return fmt::format("{} results for its {} seeds from {} to {}", results.size(), hi - lo, lo,
                       hi);
  if (j["keep_going"] != true && diverged > 1)
    return fmt::format("{} divergent results without keep_going", diverged);
  if (j.value("divergent_seeds", nlohmann::json()) != diverged ||
      j["seeds"].value("run", nlohmann::json()) != results.size())
    return fmt::format("divergent_seeds {} and seeds run {}, but {} results of which {} diverged",
                       j.value("divergent_seeds", nlohmann::json()).dump(),
                       j["seeds"].value("run", nlohmann::json()).dump(), results.size(), diverged);
  return "";
}

// The JSON summary of a random run, and of a merge of shards, which must equal it.
nlohmann::json summary_json(nlohmann::json run, const nlohmann::json& shard, std::uint64_t from,
                            std::uint64_t to, std::uint64_t cycles, double secs,
                            nlohmann::json results) {
  std::uint64_t diverged = 0;
  for (const auto& r : results) diverged += r["diverged"].get<bool>() ? 1 : 0;
  run["shard"] = shard;
  run["seeds"] = {{"from", from}, {"to", to}, {"run", results.size()}};
  run["cycles"] = cycles;
  run["seconds"] = secs;
  run["lockstep_cycles_per_second"] = secs > 0 ? static_cast<double>(cycles) / secs : 0.0;
  run["divergent_seeds"] = diverged;
  run["results"] = std::move(results);
  return run;
}

}  // namespace

namespace {

// The scenario names the chip it runs on: a --profile, --bus or --variant that says otherwise
// would be dropped without a word. "" or why not.
std::string session_chip_mismatch(const CosimOptions& o, const dpc31::cosim::DutOptions& d) {
  const auto bus_name = [](BusMode b) { return b == BusMode::intel ? "intel" : "motorola"; };
  const std::string_view profile = profile_desc(d.profile).name;
  const std::string variant = variant_run_name(d);
  if (o.profile_given && o.profile != d.profile) {
    return fmt::format("{}: the scenario runs profile {}, not --profile {}", o.session, profile,
                       o.profile_name);
  }
  if (o.bus_given && o.bus != d.bus) {
    return fmt::format("{}: the scenario runs bus {}, not --bus {}", o.session, bus_name(d.bus),
                       bus_name(o.bus));
  }
  if (!o.variant_name.empty() && o.variant_name != variant) {
    return fmt::format("{}: the scenario runs profile {}{}, not --variant {}", o.session, profile,
                       variant.empty() ? " (no variant)" : " variant " + variant, o.variant_name);
  }
  return {};
}

int run_session_mode(const CosimOptions& given, outfile::OutFile& junit_out) {
  using namespace dpc31::cosim;
  Session s;
  std::string error;
  const auto t0 = std::chrono::steady_clock::now();
  if (!record_session(given.session, s, error)) {
    fmt::print(stderr, "{}\n", error);
    return 2;
  }
  if (const std::string why = session_chip_mismatch(given, s.options); !why.empty()) {
    fmt::print(stderr, "dpc31 cosim: {}\n", why);
    return 2;
  }
  // The scenario's chip is the run's: the RTL is built for its profile, and a trace's header
  // names it.
  CosimOptions o = given;
  o.profile = s.options.profile;
  o.profile_name = profile_desc(s.options.profile).name;
  o.bus = s.options.bus;
  std::string rtl_id;
  if (!load_rtl(o, s.options, rtl_id) || !rtl_dut_ready(o, s.options) || !windows_ready(o))
    return 2;
  // A chip that did not do what its scenario says: its lines, as `dpc31 run` prints them, and
  // exit 1 whatever the lockstep finds.
  for (const std::string& line : s.scenario_failures) fmt::print(stderr, "{}\n", line);
  const RunResult r = run_session(s, o.mutant);  // s.options carries a --rtl model
  if (!o.quiet) {
    for (const std::string& line : r.report) fmt::print(stderr, "{}\n", line);
  }
  std::string failed_output;
  const auto output_failed = [&failed_output](const std::string& why) {
    if (failed_output.empty()) failed_output = why;
  };
  const std::string stem = std::filesystem::path(o.session).stem().string();
  nlohmann::json entry = {{"session", stem},
                          {"diverged", r.divergence >= 0},
                          {"cycle", r.divergence},
                          {"scenario_expects_passed", s.scenario_failures.empty()}};
  const Stimulus stimulus = session_stimulus(s);
  if (r.divergence >= 0 && static_cast<std::uint64_t>(r.divergence) < s.cycles) {
    write_divergence(o, stimulus, r, s.options,
                     fmt::format("cosim-{}-session-{}.trace", o.profile_name, stem),
                     "session " + std::filesystem::absolute(o.session).string(), kSessionShrinkRuns,
                     entry, output_failed);
  } else if (r.divergence >= 0 && !o.quiet) {
    // Only the live chip saw the other end: a trace replays the blocks, not the chip.
    fmt::print(stderr, "  no trace or waveform window: a replay has no live chip to differ from\n");
  }
  if (!o.dump_dir.empty()) write_dump(o, stimulus, s.options, output_failed);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json summary = {{"session", o.session},
                            {"profile", o.profile_name},
                            {"bus", s.options.bus == BusMode::intel ? "intel" : "motorola"},
                            {"variant", variant_json(s.options)},
                            {"mutant", o.mutant},
                            {"rtl", rtl_id},
                            {"cycles", s.cycles},
                            {"block_events", s.events.size()},
                            {"scenario_expects_passed", s.scenario_failures.empty()},
                            {"diverged", r.divergence >= 0},
                            {"cycle", r.divergence},
                            {"signals", r.signals},
                            {"seconds", secs}};
  for (const char* k : {"trace", "vcd", "fst"}) {
    if (entry.contains(k)) summary[k] = entry[k];
  }
  const int rc = finish(o, summary, nlohmann::json::array({entry}), junit_out, failed_output);
  return rc == 0 && !s.scenario_failures.empty() ? 1 : rc;
}

}  // namespace

int run_cosim(const CosimOptions& given) {
  using namespace dpc31::cosim;
  CosimOptions o = given;
  std::vector<outfile::Named> inputs = {
      {"--replay", o.replay}, {"--session", o.session}, {"--rtl-model", o.rtl_model}};
  for (const std::string& v : o.rtl_sources) inputs.push_back({"--rtl", v});
  // What the scenario reads (a plug-in, a `cpu` image): a scenario that does not load is said
  // by the session's recording, with its line; a pipe is read once, by the recording.
  if (Scenario sc; std::filesystem::is_regular_file(o.session)) {
    if (ScenarioError ignored; load_scenario(o.session, sc, ignored)) {
      for (outfile::Named& n : scenario_inputs(sc)) inputs.push_back(std::move(n));
    }
  }
  if (const std::string same = outfile::distinct(inputs, {{"--junit", o.junit}}); !same.empty()) {
    fmt::print(stderr, "dpc31 cosim: {}\n", same);
    return 2;
  }
  // The summary's "to" is one past the last seed (base + seeds), a 64-bit number like every
  // seed: a range that wrapped to 0 ran seeds of another run and summed to a summary merge
  // refuses. So the last seed a run can have is 2^64 - 2, and the message says that, not that
  // the seeds themselves overflow (seed 2^64 - 1 alone would fit, its "to" would not).
  if (o.replay.empty() && o.seeds > std::numeric_limits<std::uint64_t>::max() - o.seed_base) {
    fmt::print(stderr,
               "dpc31 cosim: --seed-base {} with --seeds {}: the summary's \"to\" (one past the "
               "last seed) would pass {}, the last 64-bit number: the last seed a run can have "
               "is {}\n",
               o.seed_base, o.seeds, std::numeric_limits<std::uint64_t>::max(),
               std::numeric_limits<std::uint64_t>::max() - 1);
    return 2;
  }
  // Opened before the seeds run: a bad path is one line up front, not after minutes.
  outfile::OutFile junit_out;
  if (!o.junit.empty() && !junit_out.open(o.junit)) {
    fmt::print(stderr, "{}\n", junit_out.error());
    return 2;
  }
  // The directories are made only when something goes into them, but checked now.
  for (const auto& [opt, dir] : {std::pair{"--out", o.out_dir}, std::pair{"--vcd", o.vcd_dir},
                                 std::pair{"--dump", o.dump_dir}}) {
    if (std::string why; !dir.empty() && !can_be_directory(dir, why)) {
      fmt::print(stderr, "dpc31 cosim: {} {}: {}\n", opt, dir, why);
      return 2;
    }
  }
  if (!o.session.empty()) return run_session_mode(o, junit_out);
  // A replayed trace first: its header names the model to build.
  std::vector<std::pair<std::uint64_t, Stimulus>> runs;
  if (!o.replay.empty()) {
    Stimulus s;
    std::uint64_t seed = 0;
    std::string error;
    if (!read_stimulus(o.replay, s, o, seed, error)) {
      fmt::print(stderr, "{}\n", error);
      return 2;
    }
    // The RTL the header names is an input as --rtl is: --junit must not replace it.
    std::vector<outfile::Named> named;
    for (const std::string& v : o.rtl_sources) named.push_back({"the trace's rtl", v});
    if (!o.rtl_model.empty()) named.push_back({"the trace's rtl-model", o.rtl_model});
    if (const std::string same = outfile::distinct(named, {{"--junit", o.junit}}); !same.empty()) {
      fmt::print(stderr, "dpc31 cosim: {}\n", same);
      return 2;
    }
    ChipOptions chip{o.profile};
    if (const std::string why = apply_variant(o.variant_name, chip); !why.empty()) {
      fmt::print(stderr, "dpc31 cosim: {}\n", why);
      return 2;
    }
    o.variant = chip.variant;
    runs.emplace_back(seed, std::move(s));
  }
  DutOptions dut{o.profile, o.bus, o.variant};
  std::string rtl_id;
  if (!load_rtl(o, dut, rtl_id)) return 2;
  if (!rtl_dut_ready(o, dut) || !windows_ready(o)) return 2;
  // A model that does not trace (the built-in mutants', a --rtl-model whose trace_to returns 0)
  // writes no rtl_internal.fst: a note. Any other output that fails in the run is exit 2, after
  // the summary and the JUnit, which record the seeds that ran; the first failure is the one line.
  std::string failed_output;
  const auto output_failed = [&failed_output](const std::string& error) {
    if (failed_output.empty()) failed_output = error;
  };
  // Seeds of this shard: a contiguous part of [seed_base, seed_base + seeds).
  const std::uint64_t lo = o.seed_base + o.seeds * (o.shard - 1) / o.shards;
  const std::uint64_t hi = o.seed_base + o.seeds * o.shard / o.shards;
  const bool tty = isatty(STDOUT_FILENO) != 0 && !o.quiet;
  nlohmann::json results = nlohmann::json::array();
  std::uint64_t diverged = 0;
  std::uint64_t cycles = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint64_t total = runs.empty() ? hi - lo : 1;
  for (std::uint64_t i = 0; i < total; ++i) {
    const std::uint64_t seed = runs.empty() ? lo + i : runs[0].first;
    const Stimulus s = runs.empty() ? random_stimulus({o.profile, seed, o.cycles}) : runs[0].second;
    const RunResult r = run_lockstep(s, dut, o.mutant);
    cycles += r.divergence >= 0 ? static_cast<std::uint64_t>(r.divergence) + 1 : s.size();
    nlohmann::json entry = {
        {"seed", seed}, {"diverged", r.divergence >= 0}, {"cycle", r.divergence}};
    if (r.divergence >= 0) {
      ++diverged;
      if (!o.quiet) {
        fmt::print(stderr, "{}seed {}: ", tty ? "\n" : "", seed);
        for (const std::string& line : r.report) fmt::print(stderr, "{}\n", line);
      }
      write_divergence(o, s, r, dut,
                       fmt::format("cosim-{}-seed{}{}.trace", o.profile_name, seed,
                                   o.replay.empty() ? "" : "-replay"),
                       fmt::format("seed {}", seed), kSeedShrinkRuns, entry, output_failed);
    }
    results.push_back(entry);
    if (tty) {
      const std::size_t width = 40;
      const std::size_t done = (i + 1) * width / total;
      fmt::print("\r[{}{}] {}/{} seeds, {} divergent", std::string(done, '#'),
                 std::string(width - done, '.'), i + 1, total, diverged);
      std::fflush(stdout);
    }
    if (diverged > 0 && !o.keep_going) break;
  }
  if (tty) fmt::print("\n");
  if (!o.dump_dir.empty()) {
    // The whole run of the first stimulus.
    write_dump(o, runs.empty() ? random_stimulus({o.profile, lo, o.cycles}) : runs[0].second, dut,
               output_failed);
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json run = {{"profile", o.profile_name},
                        {"bus", o.bus == BusMode::motorola ? "motorola" : "intel"},
                        {"variant", variant_json(dut)},
                        {"mutant", o.mutant},
                        {"rtl", rtl_id}};
  nlohmann::json summary;
  if (!runs.empty()) {
    // A replay is one trace, not a range of seeds: the summary names it and its length.
    run["replay"] = o.replay;
    run["trace_cycles"] = runs[0].second.size();
    run["cycles"] = cycles;
    run["seconds"] = secs;
    run["divergent_seeds"] = diverged;
    run["results"] = results;
    summary = std::move(run);
  } else {
    run["cycles_per_seed"] = o.cycles;
    run["keep_going"] = o.keep_going;
    const nlohmann::json shard = {{"index", o.shard},
                                  {"count", o.shards},
                                  {"of", {{"from", o.seed_base}, {"to", o.seed_base + o.seeds}}}};
    summary = summary_json(run, shard, lo, hi, cycles, secs, results);
  }
  return finish(o, summary, results, junit_out, failed_output);
}

int run_cosim_merge(const MergeOptions& o) {
  const auto fail = [](const std::string& why) {
    fmt::print(stderr, "dpc31 cosim merge: {}\n", why);
    return 2;
  };
  std::vector<outfile::Named> inputs;
  for (const std::string& f : o.inputs) inputs.push_back({"the summary", f});
  if (const std::string same = outfile::distinct(inputs, {{"--junit", o.junit}}); !same.empty()) {
    return fail(same);
  }
  outfile::OutFile junit_out;
  if (!o.junit.empty() && !junit_out.open(o.junit)) return fail(junit_out.error());
  struct Part {
    std::string file;
    nlohmann::json j;
  };
  std::vector<Part> parts;
  for (const std::string& f : o.inputs) {
    std::string text;
    std::string why;
    if (!read_text_file(f, 256u << 20, "JSON summary", text, why)) return fail(f + ": " + why);
    bool too_deep = false;
    nlohmann::json j = parse_summary(text, too_deep);
    if (too_deep) {
      return fail(
          fmt::format("{}: nested deeper than {} levels: not the JSON summary of a "
                      "`dpc31 cosim --shard` run",
                      f, kMaxSummaryDepth));
    }
    // What a shard of a random run writes: these keys with these types (a session summary, a
    // cut-off file or another JSON document is refused here, not half-merged).
    const bool shaped = j.is_object() && j.contains("shard") && j["shard"].is_object() &&
                        j["shard"].value("index", nlohmann::json()).is_number_unsigned() &&
                        j["shard"].value("count", nlohmann::json()).is_number_unsigned() &&
                        j["shard"].contains("of") && j.contains("seeds") &&
                        j["seeds"].value("from", nlohmann::json()).is_number_unsigned() &&
                        j["seeds"].value("to", nlohmann::json()).is_number_unsigned() &&
                        j.value("cycles", nlohmann::json()).is_number_unsigned() &&
                        j.value("seconds", nlohmann::json()).is_number() && j.contains("results") &&
                        j["results"].is_array() &&
                        std::all_of(std::begin(kRunKeys), std::end(kRunKeys),
                                    [&j](const char* k) { return j.contains(k); });
    if (!shaped) {
      return fail(fmt::format("{}: not the JSON summary of a `dpc31 cosim --shard` run{}", f,
                              j.is_discarded() ? " (not JSON, or cut off)" : ""));
    }
    for (const auto& r : j["results"]) {
      if (!r.is_object() || !r.value("seed", nlohmann::json()).is_number_unsigned() ||
          !r.value("diverged", nlohmann::json()).is_boolean() ||
          !r.value("cycle", nlohmann::json()).is_number_integer())
        return fail(fmt::format("{}: a result without seed, diverged and cycle", f));
    }
    if (const std::string why = run_key_mistyped(j); !why.empty())
      return fail(fmt::format("{}: {}", f, why));
    parts.push_back({f, std::move(j)});
  }
  if (parts.empty()) return fail("no summaries to merge");
  std::sort(parts.begin(), parts.end(), [](const Part& a, const Part& b) {
    return a.j["shard"]["index"].get<std::uint64_t>() < b.j["shard"]["index"].get<std::uint64_t>();
  });
  const nlohmann::json& first = parts.front().j;
  const std::uint64_t count = first["shard"]["count"].get<std::uint64_t>();
  nlohmann::json results = nlohmann::json::array();
  std::uint64_t cycles = 0;
  double secs = 0;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const nlohmann::json& j = parts[i].j;
    const std::string& f = parts[i].file;
    for (const char* k : kRunKeys) {
      if (j[k] != first[k])
        return fail(fmt::format("{}: {} is {}, in {} it is {}: not shards of one run", f, k,
                                j[k].dump(), parts.front().file, first[k].dump()));
    }
    if (j["shard"]["count"] != first["shard"]["count"] || j["shard"]["of"] != first["shard"]["of"])
      return fail(fmt::format("{}: shard {}/{} of seeds {}, {} is {}/{} of {}: not one run", f,
                              j["shard"]["index"].dump(), j["shard"]["count"].dump(),
                              j["shard"]["of"].dump(), parts.front().file,
                              first["shard"]["index"].dump(), count, first["shard"]["of"].dump()));
    const std::uint64_t index = j["shard"]["index"].get<std::uint64_t>();
    if (index != i + 1) {
      return fail(index < i + 1 ? fmt::format("{}: shard {}/{} given twice", f, index, count)
                                : fmt::format("shard {}/{} missing", i + 1, count));
    }
    if (const std::string why = shard_mismatch(j); !why.empty())
      return fail(fmt::format("{}: {}: not the complete set of one run", f, why));
    for (const auto& r : j["results"]) results.push_back(r);
    cycles += j["cycles"].get<std::uint64_t>();
    secs += j["seconds"].get<double>();
  }
  if (parts.size() != count)
    return fail(fmt::format("shard {}/{} missing", parts.size() + 1, count));
  nlohmann::json run = nlohmann::json::object();
  for (const char* k : kRunKeys) run[k] = first[k];
  const nlohmann::json& of = first["shard"]["of"];
  const nlohmann::json shard = {{"index", 1}, {"count", 1}, {"of", of}};
  const nlohmann::json summary =
      summary_json(run, shard, parts.front().j["seeds"]["from"].get<std::uint64_t>(),
                   parts.back().j["seeds"]["to"].get<std::uint64_t>(), cycles, secs, results);
  fmt::print("{}\n", summary.dump(2));
  if (!o.junit.empty() &&
      !(junit_out.write(junit(first["profile"].get<std::string>(), summary["results"])) &&
        junit_out.commit())) {
    fmt::print(stderr, "{}\n", junit_out.error());
    return 2;
  }
  return summary["divergent_seeds"].get<std::uint64_t>() == 0 ? 0 : 1;
}

}  // namespace dpc31::cli
