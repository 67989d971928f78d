// Streaming readers for waveforms: VCD (IEEE 1364-2005 §18) and FST (fstapi from Debian's
// verilator package). Both give the declared names and a pull interface that advances one time
// step at a time, so two files can be walked in time order together while memory stays bounded
// by the number of signals (docs/wavediff.md, "Streaming").
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace dpc31::wavediff {

// Bad input: the message is one line, "file:line: what" (line 0: the file as a whole).
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// An option's value the comparison cannot take (an output over an input, --merge's extension, an
// option of the mode not run, options that leave nothing to compare, an output that cannot be
// written): the message is bare; the command line's report prefixes `dpc31 wavediff: ` once
// (docs/bad-input.md), Python's does not.
class OptionError : public InputError {
 public:
  using InputError::InputError;
};

[[noreturn]] void fail(const std::string& file, std::uint64_t line, const std::string& what);

// A value holder. Aliases (several names with one VCD id code, or FST aliases) share one slot.
struct Slot {
  std::uint32_t width = 1;
  bool real = false;
  std::string bits;         // width chars of 0 1 x z, most significant (leftmost declared) first
  double value = 0;         // real variables
  std::uint64_t stamp = 0;  // internal: step in which it last changed
};

// One declared name.
struct Var {
  std::string name;  // scopes and reference joined by '.', without a [msb:lsb] range suffix;
                     // a single index stays: "x[3]" (a bit of a split vector, or an array word)
  int msb = -1;      // declared range [msb:lsb], -1 if none
  int lsb = -1;
  std::uint32_t slot = 0;
};

class WaveReader {
 public:
  virtual ~WaveReader() = default;
  WaveReader() = default;
  WaveReader(const WaveReader&) = delete;
  WaveReader& operator=(const WaveReader&) = delete;

  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] const char* format() const { return format_; }
  // The time unit is 10^timescale_pow femtoseconds (0 = 1 fs ... 15 = 1 s, 17 = 100 s).
  [[nodiscard]] int timescale_pow() const { return ts_pow_; }
  [[nodiscard]] const std::vector<Var>& vars() const { return vars_; }
  [[nodiscard]] const std::vector<Slot>& slots() const { return slots_; }

  // True while another time step is waiting; next_time() is its time in file units.
  [[nodiscard]] virtual bool has_next() = 0;
  [[nodiscard]] virtual std::uint64_t next_time() = 0;
  // Applies every change of the next time step (all changes with that timestamp). Returns the
  // slots that were written in it (each once). Throws InputError on malformed input.
  virtual const std::vector<std::uint32_t>& step() = 0;
  // Time of the last step applied, and the line where the step's data ended (VCD; 0 for FST).
  [[nodiscard]] std::uint64_t time() const { return time_; }
  [[nodiscard]] virtual std::uint64_t line() const { return 0; }
  // Changes after this time (file units) are not needed: an FST reader skips the blocks after
  // it. Call before the first has_next().
  virtual void set_limit_end(std::uint64_t /*t*/) {}

  // The equal-bytes fast path (docs/wavediff.md, "Equal stretches"). can_follow: whether this
  // reader can take a step of `leader` as its own when the input bytes agree (both VCD, one
  // timescale, the same identifier codes for the same slots of the same shapes); asked once.
  [[nodiscard]] virtual bool can_follow(const WaveReader& /*leader*/) const { return false; }
  // Only after can_follow(leader). If this reader stands where the leader stood before its last
  // step() (the same next time, the same open section) and the bytes that step consumed come next
  // here too: consumes them, takes the leader's time, next time and line count, and the values
  // of the slots that step changed; true. Otherwise false, and the next step() reads on as if
  // follow had not been called.
  virtual bool follow(const WaveReader& /*leader*/) { return false; }

 protected:
  std::string path_;
  const char* format_ = "vcd";
  int ts_pow_ = 6;  // 1 ns
  std::vector<Var> vars_;
  std::vector<Slot> slots_;
  std::vector<std::uint32_t> changed_;
  std::uint64_t stamp_ = 0;
  std::uint64_t time_ = 0;

  // Once per value change: always inlined into the readers' value parsers.
  [[gnu::always_inline]] void touch(std::uint32_t slot) {
    Slot& s = slots_[slot];
    if (s.stamp != stamp_) {
      s.stamp = stamp_;
      changed_.push_back(slot);
    }
  }
};

// Opens a VCD or FST file (FST recognised by its first byte, anything else is read as VCD) and
// reads its header.
std::unique_ptr<WaveReader> open_wave(const std::string& path);

// VCD timescale text ("1ns", "10 ps", "100s") to a power of ten of femtoseconds; false if bad.
bool parse_timescale(std::string_view text, int& pow);
// "1ns", "10ps", "100s" for a power of ten of femtoseconds.
std::string timescale_text(int pow);

// Splits a declared reference ("data [7:0]", "data[7:0]", "x [3]", "x(3)") into the name used
// for matching (range removed, single index kept without blanks) and the declared range.
void split_reference(std::string_view ref, std::string& name, int& msb, int& lsb);

// Normalises a value character: 0 1 x z (and X Z); the nine-valued letters U W - read as x and
// H L as 1 0 (uppercase only, as GTKWave writes them for VHDL). 0 if not a value.
constexpr char value_char(char c) {
  switch (c) {
    case '0':
    case '1':
    case 'x':
    case 'z':
      return c;
    case 'X':
    case 'U':
    case 'W':
    case '-':
      return 'x';
    case 'Z':
      return 'z';
    case 'H':
      return '1';
    case 'L':
      return '0';
    default:
      return 0;
  }
}

}  // namespace dpc31::wavediff
