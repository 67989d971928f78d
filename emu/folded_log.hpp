// The chip log's memory of what it has said (docs/decisions.md, "Logs that never flood"): the
// blocks note a cause here and log only the line it gives. Not chip state, but a snapshot carries
// it (docs/snapshots.md, section LOGS), so that a restored chip does not say again what the
// original run would not.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dpc31 {

// A mistake made over and over (an unmapped access in a polling loop, a buffer over the registers
// on every exchange) never floods the log.
struct FoldedLog {
  static constexpr std::size_t kAddressLines = 16;  // the first addresses, one line each
  enum class Line { first, address, count, none };
  // The line one more occurrence at `a` gets: the first names the cause, the first few addresses
  // one each, then a count at 10, 100, 1000, ... occurrences in all.
  Line note(std::uint32_t a);
  std::uint64_t count = 0;
  std::vector<std::uint32_t> logged;  // the first few addresses, one line each
};

}  // namespace dpc31
