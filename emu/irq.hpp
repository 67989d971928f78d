// Interrupt controller (chip-facts §2): IRR latched independent of IMR, IR = IRR & ~IMR,
// X/INT = OR of IR unless inside the inactive time that follows an EOI.
#pragma once

#include <cstdint>
#include <limits>

#include "snapshot.hpp"
#include "timer.hpp"

namespace dpc31 {

struct IrqController {
  // The EOI inactive time: X/INT may not become active while it runs.
  Timer eoi = Timer::elapsed();
  // Events latched in the current cycle survive an acknowledge in that same cycle.
  std::uint64_t event_cycle = std::numeric_limits<std::uint64_t>::max();
  std::uint16_t event_mask = 0;

  void reset() { *this = IrqController{}; }
  void note_events(std::uint16_t bits, std::uint64_t now) {
    if (event_cycle != now) {
      event_cycle = now;
      event_mask = 0;
    }
    event_mask |= bits;
  }
  [[nodiscard]] std::uint16_t events_at(std::uint64_t now) const {
    return event_cycle == now ? event_mask : std::uint16_t{0};
  }
};

void save_state(snap::Writer& w, const IrqController& s);
void load_state(snap::Reader& r, IrqController& s);

}  // namespace dpc31
