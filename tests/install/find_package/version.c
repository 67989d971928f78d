/* The version macros and dpc31emu_version() from C (dpc31/dpc31_version.h); #if on the minor. */
#include <stdio.h>

#include "dpc31/dpc31_version.h"

#if DPC31EMU_VERSION_MAJOR == 0 && DPC31EMU_VERSION_MINOR < 1
#error "0.x: this consumer was written against 0.1"
#endif

int main(void) {
  printf("%d.%d.%d %s %s\n", DPC31EMU_VERSION_MAJOR, DPC31EMU_VERSION_MINOR, DPC31EMU_VERSION_PATCH,
         DPC31EMU_VERSION_STRING, dpc31emu_version());
  return 0;
}
