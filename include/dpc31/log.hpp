// Diagnostics of the chip model: every access the model does not fully honour (reserved,
// unmapped, unmodelled, ignored) is reported by name, never dropped silently.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace dpc31 {

enum class LogLevel : std::uint8_t { debug, info, warn, error };

struct LogRecord {
  std::uint64_t cycle;
  LogLevel level;
  std::string text;
};

using LogSink = std::function<void(const LogRecord&)>;

std::string_view level_name(LogLevel l);

// The default sink: warnings and errors to stderr as "[cycle N] warn: text".
LogSink stderr_sink(LogLevel min_level = LogLevel::warn);

}  // namespace dpc31
