/* registry.c -- the example firmwares, for hosts that pick one by name. */
#include <ctype.h>

#include "cnt2/cnt2.h"
#include "do4/do4.h"
#include "firmware.h"

const dpc31_firmware* const dpc31_firmwares[] = {&do4_firmware, &cnt2_firmware, 0};
static const dpc31_builtin* const kBuiltins[] = {&do4_builtin, &cnt2_builtin, 0};

static int same_name(const char* a, const char* b) {
  for (; *a && *b; ++a, ++b) {
    if (tolower((unsigned char)*a) != tolower((unsigned char)*b)) return 0;
  }
  return *a == *b;
}

const dpc31_firmware* dpc31_find_firmware(const char* name) {
  int i;
  if (name == 0) return 0; /* no name names none (an audit's NULL crashed same_name) */
  for (i = 0; dpc31_firmwares[i] != 0; ++i) {
    if (same_name(dpc31_firmwares[i]->name, name)) return dpc31_firmwares[i];
  }
  return 0;
}

const dpc31_builtin* dpc31_builtin_of(const dpc31_firmware* fw) {
  int i;
  for (i = 0; kBuiltins[i] != 0; ++i) {
    if (kBuiltins[i]->descriptor == fw) return kBuiltins[i];
  }
  return 0;
}
