#include "dpc31/log.hpp"

#include <fmt/core.h>

#include <cstdio>

#include "dpc31/names.hpp"

namespace dpc31 {

constexpr std::array<std::string_view, 4> kLogLevelNames = {"debug", "info", "warn", "error"};
static_assert(kLogLevelNames.size() == static_cast<std::size_t>(LogLevel::error) + 1,
              "a new value: name it here");

std::string_view level_name(LogLevel l) { return name_of(l, kLogLevelNames); }

LogSink stderr_sink(LogLevel min_level) {
  return [min_level](const LogRecord& r) {
    if (r.level < min_level) return;
    fmt::print(stderr, "[cycle {}] {}: {}\n", r.cycle, level_name(r.level), r.text);
  };
}

}  // namespace dpc31
