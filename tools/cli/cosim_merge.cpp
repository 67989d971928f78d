// dpc31 cosim merge: the JSON summaries of the shards of one random run (`dpc31 cosim --shard`)
// checked and merged into the summary of the whole run (docs/regression.md). Exit 0 no
// divergence, 1 divergence, 2 bad input.
#include <fmt/core.h>

#include <algorithm>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "cosim.hpp"
#include "cosim_summary.hpp"
#include "outfile.hpp"
#include "textfile.hpp"

namespace dpc31::cli {

namespace {

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

// A summary's seed range in words: its "to" is one past the last seed, said so (an empty
// shard's range has no last seed). Every message of merge says a range this way.
std::string seeds_text(std::string_view from, std::string_view to) {
  return fmt::format("seeds from {} up to {} (exclusive)", from, to);
}
std::string seeds_text(std::uint64_t from, std::uint64_t to) {
  return seeds_text(std::to_string(from), std::to_string(to));
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
    return fmt::format("shard {}/{} of {} is no shard of a run", index, count,
                       seeds_text(from, to));
  const std::uint64_t lo = from + (to - from) * (index - 1) / count;
  const std::uint64_t hi = from + (to - from) * index / count;
  if (j["seeds"]["from"] != lo || j["seeds"]["to"] != hi)
    return fmt::format("{}, but shard {}/{} of {} has {}",
                       seeds_text(j["seeds"]["from"].dump(), j["seeds"]["to"].dump()), index, count,
                       seeds_text(from, to), seeds_text(lo, hi));
  const nlohmann::json& results = j["results"];
  std::uint64_t diverged = 0;
  for (std::size_t k = 0; k < results.size(); ++k) {
    const auto seed = results[k]["seed"].get<std::uint64_t>();
    if (seed != lo + k)
      return fmt::format("result {} is seed {}, not {}: not its {} in order", k + 1, seed, lo + k,
                         seeds_text(lo, hi));
    if (results[k]["diverged"].get<bool>()) ++diverged;
  }
  const bool stopped =
      j["keep_going"] != true && diverged == 1 && results.back()["diverged"].get<bool>();
  if (results.size() != hi - lo && !stopped)
    return fmt::format("{} results for its {} {}", results.size(), hi - lo, seeds_text(lo, hi));
  if (j["keep_going"] != true && diverged > 1)
    return fmt::format("{} divergent results without keep_going", diverged);
  if (j.value("divergent_seeds", nlohmann::json()) != diverged ||
      j["seeds"].value("run", nlohmann::json()) != results.size())
    return fmt::format("divergent_seeds {} and seeds run {}, but {} results of which {} diverged",
                       j.value("divergent_seeds", nlohmann::json()).dump(),
                       j["seeds"].value("run", nlohmann::json()).dump(), results.size(), diverged);
  return "";
}

}  // namespace

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
    return fail(junit_out.error());
  }
  return summary["divergent_seeds"].get<std::uint64_t>() == 0 ? 0 : 1;
}

}  // namespace dpc31::cli
