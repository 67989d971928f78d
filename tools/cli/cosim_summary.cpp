// The JSON summary and the JUnit XML of `dpc31 cosim` and `dpc31 cosim merge`.
#include "cosim_summary.hpp"

#include <fmt/core.h>

#include <string_view>
#include <utility>

namespace dpc31::cli {

namespace {

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

}  // namespace

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

}  // namespace dpc31::cli
