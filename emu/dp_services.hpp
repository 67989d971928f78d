// The snapshot of the FDL counters (include/dpc31/fdl_counters.hpp).
#pragma once

#include <cstdint>

#include "dpc31/fdl_counters.hpp"
#include "snapshot.hpp"

namespace dpc31 {

// In mac.cpp, where they are counted.
void save_state(snap::Writer& w, const FdlCounters& s);
void load_state(snap::Reader& r, FdlCounters& s);

}  // namespace dpc31
