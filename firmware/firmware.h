/*
 * firmware.h -- the example firmwares built into the emulator (DO4, CNT2), for hosts that pick
 * one by name. Each is described by the plug-in descriptor of dpc31/dpc31_firmware.h and is
 * also built as a plug-in of its own (build/lib/libdpc31_fw_do4.so, ..._cnt2.so; plugin.c).
 */
#ifndef DPC31_FIRMWARE_H
#define DPC31_FIRMWARE_H

#include "dpc31/dpc31_firmware.h"
#include "dps/dps.h"

#ifdef __cplusplus
extern "C" {
#endif

/* By name, case-insensitive ("do4", "CNT2"); NULL if there is none. */
const dpc31_firmware* dpc31_find_firmware(const char* name);
/* All of them, NULL-terminated. */
extern const dpc31_firmware* const dpc31_firmwares[];

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
#endif

#ifdef __cplusplus
}
#endif

#endif /* DPC31_FIRMWARE_H */
