#include "dpc31/log.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cstdio>

#include "dpc31/names.hpp"
#include "folded_log.hpp"

namespace dpc31 {

constexpr std::array<std::string_view, 4> kLogLevelNames = {"debug", "info", "warn", "error"};
static_assert(kLogLevelNames.size() == static_cast<std::size_t>(LogLevel::error) + 1,
              "a new value: name it here");

std::string_view level_name(LogLevel l) { return name_of(l, kLogLevelNames); }

std::string log_line(const LogRecord& r) {
  return fmt::format("[cycle {}] {}: {}", r.cycle, level_name(r.level), r.text);
}

LogSink stderr_sink(LogLevel min_level) {
  return [min_level](const LogRecord& r) {
    if (r.level < min_level) return;
    fmt::print(stderr, "{}\n", log_line(r));
  };
}

void LogLimiter::pass(std::vector<std::string>& out, std::string line) {
  if (in_window_ < burst_) {
    ++in_window_;
    out.push_back(std::move(line));
  } else {
    ++left_out_;
    ++left_out_total_;
  }
}

std::vector<std::string> LogLimiter::add(std::uint64_t cycle, std::string_view text) {
  std::vector<std::string> out;
  if (cycle >= window_start_ + window_) {
    if (left_out_ != 0)
      out.push_back(
          fmt::format("{} log lines left out in the {} cycles before (at most {} a window)",
                      left_out_, window_, burst_));
    window_start_ = cycle - (cycle - window_start_) % window_;
    in_window_ = 0;
    left_out_ = 0;
  }
  if (!last_.empty() && text == last_) {
    if (repeats_ == 0) first_repeat_ = cycle;
    last_repeat_ = cycle;
    ++repeats_;
    // 10, 100, 1000, ...: a run that never ends still says how long it is.
    std::uint64_t p = 10;
    while (p < repeats_) p *= 10;
    if (p == repeats_) {
      pass(out, fmt::format("last line repeated {} times so far", repeats_));
      repeats_reported_ = repeats_;
    }
    return out;
  }
  if (repeats_ > repeats_reported_) pass(out, repeated());
  repeats_ = 0;
  repeats_reported_ = 0;
  last_.assign(text);
  pass(out, std::string(text));
  return out;
}

// Written when the next line comes (or at the end), so it names the repeats' own cycles.
std::string LogLimiter::repeated() const {
  if (repeats_ == 1) return fmt::format("last line repeated 1 times, at cycle {}", first_repeat_);
  return fmt::format("last line repeated {} times, cycles {} to {}", repeats_, first_repeat_,
                     last_repeat_);
}

std::vector<std::string> LogLimiter::end_repeats() {
  std::vector<std::string> out;
  if (repeats_ > repeats_reported_) pass(out, repeated());
  repeats_ = repeats_reported_ = 0;
  last_.clear();
  return out;
}

std::vector<std::string> LogLimiter::flush() {
  std::vector<std::string> out;
  if (repeats_ > repeats_reported_) out.push_back(repeated());
  if (left_out_ != 0)
    out.push_back(
        fmt::format("{} log lines left out (at most {} in {} cycles)", left_out_, burst_, window_));
  repeats_ = repeats_reported_ = 0;
  left_out_ = 0;
  last_.clear();
  return out;
}

// Unmapped accesses and those beyond the address bus, buffers over the registers: a driver's
// polling loop is millions of them.
FoldedLog::Line FoldedLog::note(std::uint32_t a) {
  ++count;
  if (count == 1) {
    logged.push_back(a);
    return Line::first;
  }
  if (logged.size() < kAddressLines && std::find(logged.begin(), logged.end(), a) == logged.end()) {
    logged.push_back(a);
    return Line::address;
  }
  std::uint64_t p = 10;
  while (p < count) p *= 10;
  return p == count ? Line::count : Line::none;
}

}  // namespace dpc31
