#include "dpc31/log.hpp"

#include <fmt/core.h>

#include <cstdio>

namespace dpc31 {

std::string_view level_name(LogLevel l) {
  switch (l) {
    case LogLevel::debug:
      return "debug";
    case LogLevel::info:
      return "info";
    case LogLevel::warn:
      return "warn";
    case LogLevel::error:
      return "error";
  }
  return "?";
}

LogSink stderr_sink(LogLevel min_level) {
  return [min_level](const LogRecord& r) {
    if (r.level < min_level) return;
    fmt::print(stderr, "[cycle {}] {}: {}\n", r.cycle, level_name(r.level), r.text);
  };
}

}  // namespace dpc31
