// Scenario files: the shared lexical helpers (scenario_lex.hpp).
#include "scenario_lex.hpp"

#include <fmt/format.h>

#include <charconv>
#include <filesystem>
#include <utility>

#include "dpc31/hex.hpp"
#include "dpc31/pdu.hpp"
#include "dpc31/uart.hpp"
#include "textfile.hpp"
#include "whole_number.hpp"

namespace dpc31::scenario_lex {

void fail(std::string msg) { throw ParseFail{0, std::move(msg)}; }

bool parse_u64(std::string_view s, std::uint64_t& v) {
  return numbers::parse_whole(s, v) == std::errc{};
}

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  for (;;) {
    const std::size_t k = s.find(sep);
    out.push_back(s.substr(0, k));
    if (k == std::string_view::npos) return out;
    s.remove_prefix(k + 1);
  }
}

std::uint64_t number(std::string_view s, std::string_view what, std::uint64_t min,
                     std::uint64_t max) {
  std::uint64_t v = 0;
  if (!parse_u64(s, v)) fail(fmt::format("bad number '{}' for {}", shown(s), what));
  if (v < min || v > max) {
    fail(out_of_range(ValueRange{what, min, max}, shown(s)));
  }
  return v;
}

std::string_view without_bom(std::string_view text) {
  return text.starts_with("\xEF\xBB\xBF") ? text.substr(3) : text;
}

std::uint32_t profibus_baud(std::string_view s) {
  const std::uint64_t b = number(s, "baud", 1, 12'000'000);
  if (const std::string e = not_a_profibus_rate(b); !e.empty()) fail(e);
  return static_cast<std::uint32_t>(b);
}

bool flag(std::string_view s, std::string_view what) {
  if (s == "0") return false;
  if (s == "1") return true;
  fail(fmt::format("bad value '{}' for {}: 0 or 1", shown(s), what));
}

std::uint64_t duration(std::string_view s, std::uint64_t f, std::uint64_t t) {
  std::uint64_t v = 0;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    return number(s, "time", 0, kMaxSeconds * f);
  }
  std::size_t k = 0;
  while (k < s.size() && s[k] >= '0' && s[k] <= '9') ++k;
  const std::string_view unit = s.substr(k);
  if (k == 0 || !parse_u64(s.substr(0, k), v)) {
    fail(fmt::format("bad time '{}' (cycles, or a number with us, ms, s or bits)", shown(s)));
  }
  const auto check = [&](std::uint64_t max) {
    if (v > max) fail(fmt::format("time '{}' too long (at most {} s)", shown(s), kMaxSeconds));
  };
  if (unit.empty() || unit == "cycles") {
    check(kMaxSeconds * f);
    return v;
  }
  if (unit == "us") {
    check(kMaxSeconds * 1'000'000);
    return (v * f + 999'999) / 1'000'000;
  }
  if (unit == "ms") {
    check(kMaxSeconds * 1'000);
    return (v * f + 999) / 1'000;
  }
  if (unit == "s") {
    check(kMaxSeconds);
    return v * f;
  }
  if (unit == "bits") {
    check(kMaxSeconds * f / t);
    return v * t;
  }
  if (unit.size() > 1 && (unit[0] == '.' || unit[0] == ',') && unit[1] >= '0' && unit[1] <= '9') {
    fail(fmt::format("time '{}': a time is a whole number of its unit: write it in a smaller unit",
                     shown(s)));
  }
  fail(fmt::format("bad time unit '{}' in '{}' (us, ms, s, bits, or none for cycles)", shown(unit),
                   shown(s)));
}

void spaced_bytes(std::string_view command, std::string_view second) {
  fail(fmt::format("{}: the bytes are separated by commas (10,05,...); unexpected '{}'", command,
                   shown(second)));
}

std::vector<std::uint8_t> bytes(std::string_view s, std::string_view what, std::size_t max) {
  std::vector<std::uint8_t> out;
  if (s == "-") return out;
  if (s.empty()) fail(fmt::format("empty byte list for {} (write '-' for none)", what));
  for (std::string_view b : split(s, ',')) {
    std::string_view d = b;
    if (d.size() > 2 && d[0] == '0' && (d[1] == 'x' || d[1] == 'X')) d.remove_prefix(2);
    unsigned v = 0;
    const auto [p, ec] = std::from_chars(d.data(), d.data() + d.size(), v, 16);
    if (d.empty() || d.size() > 2 || ec != std::errc() || p != d.data() + d.size()) {
      fail(fmt::format("bad byte '{}' in {} (hex bytes separated by commas)", shown(b), what));
    }
    out.push_back(static_cast<std::uint8_t>(v));
    if (out.size() > max) fail(fmt::format("{}: more than {} bytes", what, max));
  }
  return out;
}

std::string beside_file(const std::string& scenario_file, const std::string& path) {
  if (path.empty() || path.front() == '/') return path;
  std::error_code ec;
  const std::filesystem::path real = std::filesystem::canonical(scenario_file, ec);
  const std::filesystem::path dir =
      (ec ? std::filesystem::path(scenario_file) : real).parent_path();
  return (dir / path).lexically_normal().string();
}

std::string bytes_text(std::span<const std::uint8_t> b) {
  return b.empty() ? "-" : hex_bytes(b, " ", 4096);
}

// Global_Control command bits by their scenario names.
constexpr std::pair<std::string_view, std::uint8_t> kGcNames[] = {
    {"sync", pdu::control_command::Sync},        {"unsync", pdu::control_command::Unsync},
    {"freeze", pdu::control_command::Freeze},    {"unfreeze", pdu::control_command::Unfreeze},
    {"clear", pdu::control_command::Clear_Data}, {"operate", 0x00},
};

std::uint32_t gc_command(std::string_view s) {
  if (!s.empty() && s[0] >= '0' && s[0] <= '9') {
    return static_cast<std::uint32_t>(number(s, "gc command", 0, 255));
  }
  std::uint32_t c = 0;
  for (std::string_view n : split(s, ',')) {
    bool found = false;
    for (const auto& [name, bits] : kGcNames) {
      if (n == name) {
        c |= bits;
        found = true;
      }
    }
    if (!found) {
      fail(
          fmt::format("unknown gc command '{}' (sync, unsync, freeze, unfreeze, clear, "
                      "operate, or a number)",
                      shown(n)));
    }
  }
  return c;
}

int name_index(const char* const* names, std::string_view name) {
  for (int i = 0; names != nullptr && names[i] != nullptr; ++i) {
    if (name == names[i]) return i;
  }
  return -1;
}

std::string name_list(const char* const* names) {
  std::string all;
  for (int i = 0; names != nullptr && names[i] != nullptr; ++i) {
    all += (i == 0 ? "" : ", ") + std::string(names[i]);
  }
  return all.empty() ? "none" : all;
}

}  // namespace dpc31::scenario_lex
