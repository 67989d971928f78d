/*
 * firmware.h -- the example firmwares built into the emulator (DO4, CNT2), for hosts that pick
 * one by name. Each is described by the plug-in descriptor of dpc31/dpc31_firmware.h and is
 * also built as a plug-in of its own (build/lib/libdpc31_fw_do4.so, ..._cnt2.so; plugin.c).
 *
 * A built-in firmware keeps its state in an instance (dps.h, "One instance"), so a host runs it
 * on any number of stations at once: dpc31_builtin gives the instance's size and the entry
 * points that take it. The descriptor's own entry points drive one static instance: what the
 * plug-in build of the same sources runs (a host loads a private copy of a plug-in per station,
 * docs/firmware.md).
 */
#ifndef DPC31_FIRMWARE_H
#define DPC31_FIRMWARE_H

#include "dpc31/dpc31_firmware.h"
#include "dps/dps.h"

#ifdef __cplusplus
extern "C" {
#endif

/* By name, case-insensitive ("do4", "CNT2"); NULL if there is none (a NULL name too). */
const dpc31_firmware* dpc31_find_firmware(const char* name);
/* All of them, NULL-terminated. */
extern const dpc31_firmware* const dpc31_firmwares[];

/* The values one hardware input takes, min..max (a host checks a scenario's `hw` line against
 * them when it parses it). */
typedef struct dpc31_hw_range {
  uint32_t min;
  uint32_t max;
} dpc31_hw_range;

/* A built-in firmware on instances: `instance_size` zeroed bytes per station, aligned for any
 * type, passed to every entry point. */
typedef struct dpc31_builtin {
  const dpc31_firmware* descriptor; /* name, GSD file, ports, hardware inputs, GSD defaults */
  size_t instance_size;
  void (*init)(void* self, const dpc31_board* board);
  void (*isr)(void* self);
  int (*hw_input)(void* self, const char* name, uint32_t value); /* NULL: none */
  const dpc31_hw_range* hw_ranges; /* one per descriptor->hw_inputs, in their order (NULL: none) */
} dpc31_builtin;

/* The built-in firmware of a descriptor; NULL: not one of them (a plug-in). */
const dpc31_builtin* dpc31_builtin_of(const dpc31_firmware* fw);

/* The board as the dps driver layer takes it. (Host builds only: SDCC returns no struct; an
 * 80C32 firmware fills its dps_board itself, firmware/mcs51/.) */
#ifndef __SDCC
static inline dps_board dpc31_dps_board(const dpc31_board* board) {
  dps_board b;
  b.profile = board->profile;
  b.motorola = board->motorola;
  b.station_address = board->station_address;
  return b;
}

/* The entry points of built-in firmware `fw` (its instance type `fw`, its fw_init and fw_isr):
 * fw_start_in / fw_isr_in on an instance, fw_start_single / fw_isr_single on the one static
 * instance of the descriptor. */
#define DPC31_BUILTIN_ENTRIES(fw)                                                                 \
  static void fw##_start_in(void* inst, const dpc31_board* board) {                               \
    const dps_board b = dpc31_dps_board(board);                                                   \
    fw##_init((fw*)inst, &b);                                                                     \
  }                                                                                               \
  static void fw##_isr_in(void* inst) { fw##_isr((fw*)inst); }                                    \
  static fw fw##_single;                                                                          \
  static void fw##_start_single(const dpc31_board* board) { fw##_start_in(&fw##_single, board); } \
  static void fw##_isr_single(void) { fw##_isr(&fw##_single); }
#endif

#ifdef __cplusplus
}
#endif

#endif /* DPC31_FIRMWARE_H */
