// Internal: the two reader factories behind open_wave().
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "wave_reader.hpp"

namespace dpc31::wavediff {

// What a file's declarations may make a reader hold (docs/wavediff.md, "Limits"): a small file
// must not expand into gigabytes of names or values. The open scopes are one prefix string
// ("top.dut.") built as they open and cut back as they close, so a variable's full name costs
// its own length once, not a join of every scope.
class Declarations {
 public:
  static constexpr std::size_t kMaxDepth = 256;                      // open scopes
  static constexpr std::size_t kMaxName = 16u << 10;                 // one full name, bytes
  static constexpr std::uint64_t kMaxNames = 32u << 20;              // all full names, bytes
  static constexpr std::uint64_t kMaxBits = std::uint64_t{1} << 26;  // all value slots, bits

  explicit Declarations(const std::string& path) : path_(path) {}
  void open_scope(std::string_view name, std::uint64_t line);
  // False if no scope is open.
  bool close_scope();
  [[nodiscard]] std::size_t depth() const { return ends_.size(); }
  // The full name of `ref` in the open scopes; `line` for the message.
  std::string name(std::string_view ref, std::uint64_t line);
  // A new value slot of `bits` (64 for a real).
  void slot(std::uint64_t bits, std::uint64_t line);

 private:
  const std::string& path_;
  std::string prefix_;
  std::vector<std::size_t> ends_;  // prefix_ length before each open scope
  std::uint64_t names_ = 0;
  std::uint64_t bits_ = 0;
};

// Each input is opened once (a pipe, `<(cat a.vcd)`, can be read only once): `fd` is the open
// input, owned by the reader from here on. A VCD reader reads on from where `fd` is, after
// `prefix` (what format detection consumed from a pipe). The FST reader opens a seekable file
// by `access` (/proc/self/fd/N of `fd`, or of a memfd holding what a pipe gave); `path` names
// the input in messages.
std::unique_ptr<WaveReader> open_vcd(const std::string& path, int fd, std::string_view prefix);
std::unique_ptr<WaveReader> open_fst(const std::string& path, int fd, const std::string& access);

}  // namespace dpc31::wavediff
