#include "synthetic_vcd.hpp"

#include <array>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <memory>

namespace dpc31::wavediff {
namespace {

constexpr int kBits = 32;   // s0..s31, 1 bit
constexpr int kBuses = 32;  // v0..v31, 16 bits
constexpr std::size_t kChunk = std::size_t{1} << 20;

static_assert(1 + kBits + kBuses <= 94, "one-character identifier codes");

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

bool put(std::FILE* f, const std::string& s, const std::string& path, std::string& error) {
  if (std::fwrite(s.data(), 1, s.size(), f) == s.size()) return true;
  error = path + ": write failed (disk full?)";
  return false;
}

}  // namespace

std::uint64_t synthetic_steps_for_megabytes(std::uint64_t megabytes) {
  return megabytes * 1'000'000 / 104;  // 104 bytes a step on average (measured)
}

bool write_synthetic_vcd_pair(const std::string& path_a, const std::string& path_b,
                              const SyntheticVcd& spec, std::string& error) {
  File fa(std::fopen(path_a.c_str(), "wb"));
  File fb(std::fopen(path_b.c_str(), "wb"));
  if (!fa || !fb) {
    error = (fa ? path_b : path_a) + ": cannot create";
    return false;
  }
  // Identifier codes, one printable character from '!': clk, the 1-bit signals, the buses.
  std::array<std::string, 1 + kBits + kBuses> ids;
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = std::string(1, static_cast<char>('!' + i));
  std::string s = "$date synthetic $end\n$timescale 1ps $end\n$scope module top $end\n";
  s += "$var wire 1 " + ids[0] + " clk $end\n";
  for (int i = 0; i < kBits; ++i) {
    s += "$var wire 1 " + ids[1 + i] + " s" + std::to_string(i) + " $end\n";
  }
  for (int i = 0; i < kBuses; ++i) {
    s += "$var wire 16 " + ids[1 + kBits + i] + " v" + std::to_string(i) + " [15:0] $end\n";
  }
  s += "$upscope $end\n$enddefinitions $end\n";

  auto next_diff = spec.diff_steps.begin();
  std::vector<std::size_t> flips;  // offsets in `s` of the characters B has flipped
  std::uint32_t x = 12345;         // linear congruential generator: the same file every time
  char num[24];
  for (std::uint64_t t = 0; t < spec.steps; ++t) {
    s += '#';
    s.append(num, std::to_chars(num, num + sizeof num, t * 10).ptr);
    s += '\n';
    s += (t & 1) == 0 ? '1' : '0';
    s += ids[0];
    s += '\n';
    for (int k = 0; k < 4; ++k) {
      x = x * 1103515245u + 12345u;
      s += static_cast<char>('0' + ((x >> 20) & 1));
      s += ids[1 + (x >> 8) % kBits];
      s += '\n';
      x = x * 1103515245u + 12345u;
      const std::uint32_t v = x >> 16;
      s += 'b';
      for (int b = 15; b >= 0; --b) s += static_cast<char>('0' + ((v >> b) & 1));
      if (k == 3 && next_diff != spec.diff_steps.end() && *next_diff == t) {
        flips.push_back(s.size() - 1);
        ++next_diff;
      }
      s += ' ';
      s += ids[1 + kBits + (x >> 8) % kBuses];
      s += '\n';
    }
    if (s.size() >= kChunk || t + 1 == spec.steps) {
      if (!put(fa.get(), s, path_a, error)) return false;
      for (const std::size_t i : flips) s[i] ^= 1;  // '0' <-> '1'
      if (!put(fb.get(), s, path_b, error)) return false;
      flips.clear();
      s.clear();
    }
  }
  if (spec.steps == 0 && (!put(fa.get(), s, path_a, error) || !put(fb.get(), s, path_b, error))) {
    return false;
  }
  if (std::fflush(fa.get()) != 0 || std::fflush(fb.get()) != 0) {
    error = "flush failed (disk full?)";
    return false;
  }
  return true;
}

}  // namespace dpc31::wavediff
