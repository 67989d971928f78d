// What a `dpc31 cosim` run and `dpc31 cosim merge` both write: the JSON summary of a random run
// and the JUnit of its results (cosim_summary.cpp).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

namespace dpc31::cli {

// What a random run's JSON summary says about the run besides its results: a merge of shards
// checks that these are the same in every shard (docs/regression.md).
const char* const kRunKeys[] = {"profile",         "bus",       "variant", "mutant", "rtl",
                                "cycles_per_seed", "keep_going"};

// The JUnit XML of a run's results: one test case a seed or a session, a failure a
// divergence or a scenario expect that did not hold.
std::string junit(const std::string& profile, const nlohmann::json& results);

// The JSON summary of a random run, and of a merge of shards, which must equal it.
nlohmann::json summary_json(nlohmann::json run, const nlohmann::json& shard, std::uint64_t from,
                            std::uint64_t to, std::uint64_t cycles, double secs,
                            nlohmann::json results);

}  // namespace dpc31::cli
