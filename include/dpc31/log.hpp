// Diagnostics of the chip model: every access the model does not fully honour (reserved,
// unmapped, unmodelled, ignored) is reported by name, never dropped silently.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace dpc31 {

enum class LogLevel : std::uint8_t { debug, info, warn, error };

struct LogRecord {
  std::uint64_t cycle;
  LogLevel level;
  std::string text;
};

using LogSink = std::function<void(const LogRecord&)>;

std::string_view level_name(LogLevel l);

// "[cycle N] warn: text", the default sink's line (without its newline).
std::string log_line(const LogRecord& r);

// The default sink: warnings and errors to stderr as log_line has them.
LogSink stderr_sink(LogLevel min_level = LogLevel::warn);

// A log that never floods (docs/decisions.md, "Logs that never flood"). Every log of ours (the
// chip's, the bridge's) passes its lines through one: a line equal to the one before it is
// counted instead of written, and the count is written when it reaches 10, 100, 1000, ... and
// when another line comes (with the cycles of the first and the last repeat); and no more than
// `burst` lines are written in one window of `window` cycles: the rest are counted and one line
// says how many were left out when the next window opens (or at flush). Time is the chip's
// cycle, so what a log keeps does not depend on the machine's speed.
class LogLimiter {
 public:
  static constexpr std::uint32_t kBurst = 1000;
  static constexpr std::uint64_t kWindow = 48'000'000;  // 1 s at the default 48 MHz

  explicit LogLimiter(std::uint32_t burst = kBurst, std::uint64_t window = kWindow)
      : burst_(burst), window_(window) {}

  // The lines to write for one more line `text` at `cycle`, in order: what is owed about the
  // lines before it, then `text` itself unless it repeats the one before or is over the bound.
  [[nodiscard]] std::vector<std::string> add(std::uint64_t cycle, std::string_view text);
  // What is still owed at the end of a log (a repeat count, a count of lines left out).
  [[nodiscard]] std::vector<std::string> flush();
  // Another line of the same log comes between: the repeats owed are told now (their note right
  // after them) and the next line, even one equal to the last, is no repeat.
  [[nodiscard]] std::vector<std::string> end_repeats();

  [[nodiscard]] std::uint64_t left_out() const { return left_out_total_; }

 private:
  void pass(std::vector<std::string>& out, std::string line);
  [[nodiscard]] std::string repeated() const;  // "last line repeated N times" and their cycles

  std::uint32_t burst_;
  std::uint64_t window_;
  std::uint64_t window_start_ = 0;
  std::uint32_t in_window_ = 0;
  std::uint64_t left_out_ = 0;  // in the current window, not yet reported
  std::uint64_t left_out_total_ = 0;
  std::string last_;
  std::uint64_t repeats_ = 0;           // of last_, since it was written
  std::uint64_t repeats_reported_ = 0;  // of those, already said in a "so far" line
  std::uint64_t first_repeat_ = 0;      // the cycles of the first and the last repeat
  std::uint64_t last_repeat_ = 0;
};

}  // namespace dpc31
