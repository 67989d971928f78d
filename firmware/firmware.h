/*
 * firmware.h -- how a host (dpc31 run, dpc31 bridge, tests) finds and drives an example
 * firmware: its entry points, its ports, its hardware inputs, and the slave as its GSD file
 * describes it (what a master is configured with).
 */
#ifndef DPC31_FIRMWARE_H
#define DPC31_FIRMWARE_H

#include <stdint.h>

#include "dps/dps.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dpc31_firmware {
  const char* name;                     /* "DO4" */
  const char* gsd;                      /* the GSD file, relative to firmware/ */
  const char* const* ports;             /* port names by number, NULL-terminated */
  void (*init)(const dps_board* board); /* main(): set up and start the chip */
  void (*isr)(void);                    /* X/INT */
  /* Hardware inputs of the module (counter pulses, events): 0 done, -1 unknown name,
   * -2 value out of range. NULL: the module has none. */
  int (*hw_input)(const char* name, uint32_t value);
  const char* const* hw_inputs; /* their names, NULL-terminated (NULL: none) */
  /* The GSD defaults: Ident_Number, the module's Cfg bytes, input/output lengths, and the
   * user parameter bytes from Set_Prm byte 7 on (Spec_User_Prm_Byte first). */
  uint16_t ident;
  const uint8_t* cfg;
  uint8_t cfg_len;
  uint8_t in_len;
  uint8_t out_len;
  const uint8_t* user_prm;
  uint8_t user_prm_len;
} dpc31_firmware;

/* By name, case-insensitive ("do4", "CNT2"); NULL if there is none. */
const dpc31_firmware* dpc31_find_firmware(const char* name);
/* All of them, NULL-terminated. */
extern const dpc31_firmware* const dpc31_firmwares[];

#ifdef __cplusplus
}
#endif

#endif /* DPC31_FIRMWARE_H */
