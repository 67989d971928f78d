// The headers' version and the loaded library's (dpc31/dpc31_version.h), beside the C++20 chip
// API, in a project that sets no C++ standard of its own.
#include <cstdio>

#include "dpc31/chip.hpp"
#include "dpc31/dpc31_version.h"

int main() {
  dpc31::Chip chip({dpc31::Profile::spc3, dpc31::BusMode::intel});
  chip.step(1);
  std::printf("%d.%d.%d %s %s\n", DPC31EMU_VERSION_MAJOR, DPC31EMU_VERSION_MINOR,
              DPC31EMU_VERSION_PATCH, DPC31EMU_VERSION_STRING, dpc31emu_version());
}
