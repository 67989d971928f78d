// Lockstep in the style of lowRISC Ibex's Cosim: the harness pushes what the models cannot
// predict (the stimulus of a cycle), steps both, and collects mismatches as readable paired
// lines. The first divergence stops the comparison unless told to continue.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dut.hpp"

namespace dpc31::cosim {

class Lockstep {
 public:
  Lockstep(std::unique_ptr<Dut> emu, std::unique_ptr<Dut> rtl, const ProfileDesc& profile);

  // One cycle on both sides. False when an output differs; errors() then holds the report.
  bool step(const Inputs& in);
  [[nodiscard]] const std::vector<std::string>& errors() const { return errors_; }
  void clear_errors() { errors_.clear(); }
  [[nodiscard]] std::uint64_t cycle() const { return cycle_; }  // cycles stepped so far
  [[nodiscard]] std::uint64_t divergences() const { return divergences_; }
  [[nodiscard]] std::uint64_t first_divergence() const { return first_; }
  // Names of the outputs that differed at the first divergence.
  [[nodiscard]] const std::vector<std::string>& diverged_signals() const { return signals_; }
  // The last 32 non-idle stimulus cycles, oldest first.
  [[nodiscard]] const std::deque<std::pair<std::uint64_t, Inputs>>& recent() const {
    return recent_;
  }

  Dut& emu() { return *emu_; }
  Dut& rtl() { return *rtl_; }

 private:
  std::unique_ptr<Dut> emu_;
  std::unique_ptr<Dut> rtl_;
  const ProfileDesc& profile_;
  std::uint64_t cycle_ = 0;
  std::uint64_t divergences_ = 0;
  std::uint64_t first_ = 0;
  std::vector<std::string> errors_;
  std::vector<std::string> signals_;
  std::deque<std::pair<std::uint64_t, Inputs>> recent_;
};

// A stimulus: the inputs of every cycle from a reset on, kept sparse (only the non-idle cycles
// are stored), so memory follows the events and never the cycle count a trace file names.
class Stimulus {
 public:
  using Event = std::pair<std::uint64_t, Inputs>;  // cycle, inputs (never idle)

  Stimulus() = default;
  explicit Stimulus(std::uint64_t cycles) : cycles_(cycles) {}

  [[nodiscard]] std::uint64_t size() const { return cycles_; }  // cycles, idle ones included
  [[nodiscard]] bool empty() const { return cycles_ == 0; }
  [[nodiscard]] std::size_t event_count() const { return events_.size(); }
  [[nodiscard]] const std::vector<Event>& events() const { return events_; }
  // The inputs of cycle c (idle when nothing happens then).
  [[nodiscard]] const Inputs& operator[](std::uint64_t c) const;
  // Sets the inputs of cycle c (idle removes it); the stimulus grows to cover c.
  void set(std::uint64_t c, const Inputs& in);
  // Keeps the first `cycles` cycles (or grows with idle ones).
  void resize(std::uint64_t cycles);
  // Makes cycles [from, to) idle.
  void clear(std::uint64_t from, std::uint64_t to);
  // The first cycle >= c with inputs (size() when none).
  [[nodiscard]] std::uint64_t next_event(std::uint64_t c) const;
  bool operator==(const Stimulus&) const = default;

  // Every cycle in order, idle ones included: `for (const Inputs& in : s)`.
  class Iterator {
   public:
    Iterator(const Stimulus& s, std::uint64_t c);
    const Inputs& operator*() const;
    Iterator& operator++();
    bool operator!=(const Iterator& o) const { return c_ != o.c_; }

   private:
    const Stimulus* s_;
    std::uint64_t c_;
    std::size_t k_;  // the first event at or after c_
  };
  [[nodiscard]] Iterator begin() const { return {*this, 0}; }
  [[nodiscard]] Iterator end() const { return {*this, cycles_}; }

 private:
  std::uint64_t cycles_ = 0;
  std::vector<Event> events_;  // ascending cycle, each < cycles_
};

struct RandomConfig {
  Profile profile = Profile::dpc31;
  std::uint64_t seed = 1;
  std::uint64_t cycles = 20'000;
};
// Constrained random, reproducible from the seed: reads of every compared address (command reads,
// read-backs, mirrored cells), writes (masks, acknowledges, EOI, any Mode_Reg1_S value, the mode
// and option registers, mirrored cells, other RAM), every event input, Global_Control commands,
// resets, and same-cycle collisions of events with accesses.
Stimulus random_stimulus(const RandomConfig& c);

// Runs a whole stimulus; returns the cycle of the first divergence or -1.
struct RunResult {
  std::int64_t divergence = -1;
  std::vector<std::string> report;   // paired lines and the recent stimulus
  std::vector<std::string> signals;  // outputs that differed
};
using DutFactory = std::unique_ptr<Dut> (*)(const DutOptions&, std::string_view);
RunResult run_lockstep(const Stimulus& s, const DutOptions& o, std::string_view mutant = "");

// Shrinks a failing stimulus to a short one that still diverges (cycles made idle, the tail cut,
// then the inputs of each cycle left one by one).
// `runs_taken`, if given, receives the number of lockstep runs it took (at most max_runs).
Stimulus shrink(const Stimulus& s, const DutOptions& o, std::string_view mutant,
                int max_runs = 3000, int* runs_taken = nullptr);

// Trace files: one line per non-idle cycle, "<cycle> <describe()>", '#' comments; the last cycle
// is given by a line "end <cycle>". Parse errors: "file:line: message". With `profile`, an input
// that profile's chip does not have is one too (input_not_on).
std::string write_trace(const Stimulus& s, const std::string& header);
bool parse_trace(const std::string& text, const std::string& file, Stimulus& out,
                 std::string& error, std::optional<Profile> profile = std::nullopt);

// The RTL's internal waveform (FST, Verilator tracing) of a stimulus from cycle `from` on (a
// window's first cycle, as its emu.vcd and rtl.vcd; 0: the whole run): written, not traced (the
// built-in mutants' model is built without tracing, a --rtl-model's trace_to returned 0: a note,
// the run's outcome stands) or failed (the file cannot be written); `error` says why.
enum class RtlFst { written, not_traced, failed };
RtlFst write_rtl_fst(const Stimulus& s, const DutOptions& o, std::string_view mutant,
                     std::uint64_t from, const std::string& path, std::string& error);

// VCD of both sides' outputs (and the inputs) for cycles [from, to): the waveform window around
// a divergence. Files written to a temporary name and renamed.
bool write_window(const Stimulus& s, const DutOptions& o, std::string_view mutant,
                  std::uint64_t from, std::uint64_t to, const std::string& dir, std::string& error);

}  // namespace dpc31::cosim
