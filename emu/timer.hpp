// The engine's timer (docs/engine.md, docs/timing.md "Order within one cycle"). A block asks
// "wake me `cycles` clocks from now" (ChipCore::arm), whether the time has come (reached) or is
// still running (running), and when it fires (due); it never asks which engine runs. The engine
// keeps each timer its own way: the event engine as the absolute cycle it fires (`at`, a
// deadline it jumps to), the per-cycle engine as the clocks still to count (`left`, counted down
// once per clock, never derived from `at`), so the two engines agreeing (tests: Engine.*) checks
// the deadline arithmetic. Only emu/engine.cpp reads or writes the members.
#pragma once

#include <cstdint>
#include <limits>

namespace dpc31 {

inline constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();

struct Timer {
  std::uint64_t at = kNever;    // event engine: the cycle it fires (kNever: off)
  std::uint64_t left = kNever;  // per-cycle engine: clocks still to count (kNever: off, 0: reached)
  // A timer that has already run out (the EOI inactive time after reset).
  static constexpr Timer elapsed() { return Timer{0, 0}; }
};

}  // namespace dpc31
