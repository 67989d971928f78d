/* fstapi with its compressors as one translation unit (as Verilator's verilated_fst_c.cpp does),
 * so that weakening the symbols it defines (weaken_defined.cmake) leaves no weak references
 * between its parts. Third-party code from Debian's verilator package; compiled without -W. */
/* Its unchecked writes are counted (util/outfile/fst_hooks.h). */
#define DPC31_FST_HOOK_CALLS
#include "fst_hooks.h"
#define FST_CONFIG_INCLUDE "fst_config.h"
#include "gtkwave/fastlz.c"
#include "gtkwave/fstapi.c"
#include "gtkwave/lz4.c"
