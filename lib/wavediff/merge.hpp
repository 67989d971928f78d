// The merged waveform of a comparison (--diff-vcd, --merge): A's and B's compared signals under
// the scopes a and b, and for each a 1-bit diff signal (1 = the values differ), written while the
// comparison walks both files, as VCD (diff_vcd.cpp) or FST (merge.cpp). docs/wavediff.md.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine.hpp"
#include "outfile.hpp"

namespace dpc31::wavediff::detail {

// Where a merged waveform goes: its declarations (in order; the n-th var() is variable n), then
// time steps with the values that change.
class WaveSink {
 public:
  enum class Kind { wire, integer, real };
  virtual ~WaveSink() = default;
  WaveSink() = default;
  WaveSink(const WaveSink&) = delete;
  WaveSink& operator=(const WaveSink&) = delete;
  virtual void scope(const std::string& name) = 0;
  virtual void upscope() = 0;
  virtual void var(Kind kind, std::uint32_t width, const std::string& leaf) = 0;
  virtual void end_header() = 0;
  virtual void time(std::uint64_t t) = 0;
  // Bits MSB first; a shorter value is extended with 0 on the left.
  virtual void bits(std::size_t var, std::string_view bits) = 0;
  virtual void real(std::size_t var, double v) = 0;
  virtual void end_point() = 0;
  // Renames the file into place; without it the destructor discards it. Throws InputError.
  virtual void commit() = 0;
};

// `pow`: the time unit, a power of ten of femtoseconds.
std::unique_ptr<WaveSink> vcd_sink(const std::string& path, int pow);  // diff_vcd.cpp
std::unique_ptr<WaveSink> fst_sink(const std::string& path, int pow);  // merge.cpp

class MergedWave {
 public:
  MergedWave(std::unique_ptr<WaveSink> sink, Engine& e);
  void point(Engine& e, const Point& pt, bool full);
  // The file, then the save file if any (both were opened before the walk).
  void commit();
  // --merge's GTKWave save file, opened before the walk, written after it (it opens GTKWave on
  // the merged file's first..last time) and committed after the waveform.
  outfile::OutFile save_file;
  // The times of the first and the last point written (0 before any).
  [[nodiscard]] std::uint64_t first_time() const { return first_; }
  [[nodiscard]] std::uint64_t last_time() const { return last_; }

 private:
  std::unique_ptr<WaveSink> sink_;
  bool written_ = false;
  std::uint64_t first_ = 0;
  std::uint64_t last_ = 0;
  std::vector<std::size_t> var_;  // pair * 3 + side -> the sink's variable
  std::size_t cycle_var_ = 0;
  std::vector<signed char> flag_;
};

}  // namespace dpc31::wavediff::detail
