/*
 * do4.h -- DO4: a 4-channel digital output module with the "OSP" function model (Operator Set
 * Predefined, seed 000: B&R X20DO4331). Portable C99 firmware over the dps driver layer.
 *
 * Outputs from the master (2 bytes, Cfg 0x21):  byte 0 bits 3..0 = DO1..DO4,
 *                                               byte 1 bit 0 = OSPValid (1 normal, 0 request OSP)
 * Inputs to the master (1 byte, Cfg 0x10):      bit 0 = ModulOK (1 normal operation, 0 OSP),
 *                                               bits 7..4 = the output state on the terminals
 * Set_Prm user parameters (bytes 8..10; byte 7 is the chip's Spec_User_Prm_Byte):
 *   byte 8  OSPMode: 0 retain last valid value, 1 replace with static value
 *   byte 9  OSP replacement value, bits 3..0 (bits 7..4 must be 0)
 *   byte 10 refresh monitor in ms (0 = off): no Data_Exchange for this long is a temporary
 *           communication error (OSPValid reset in the module until the next good transfer)
 * docs/firmware.md explains every rule with the seed's wording.
 */
#ifndef DPC31_FIRMWARE_DO4_H
#define DPC31_FIRMWARE_DO4_H

#include <stdint.h>

#include "../firmware.h"

#ifdef __cplusplus
extern "C" {
#endif

#define DO4_IDENT 0x0D04u
#define DO4_PORT_OUTPUTS 0u  /* the four output terminals, bits 3..0 */
#define DO4_PORT_MODUL_OK 1u /* 1 normal operation, 0 OSP */

enum do4_osp_mode { DO4_RETAIN_LAST = 0, DO4_REPLACE = 1 };

/* The firmware as hosts find it (firmware.h). */
extern const dpc31_firmware do4_firmware;
extern const dpc31_builtin do4_builtin;

/* The module as the test bench sees it. */
typedef struct do4_state {
  uint8_t terminals;  /* what the outputs drive now */
  uint8_t modul_ok;   /* 1 normal, 0 OSP */
  uint8_t osp_valid;  /* the module's OSPValid (reset internally by an OSP event) */
  uint8_t last_valid; /* the last value received with OSPValid = 1 */
  uint8_t osp_mode;
  uint8_t osp_value;
  uint8_t refresh_ms;
  uint8_t ms_since_refresh;
  uint32_t osp_events;
} do4_state;

/* One DO4 (dps.h, "One instance"): the driver first (its callbacks find the module around it; the
 * 80C32's driver is a static of its own), then the module. */
typedef struct do4 {
#ifndef __SDCC
  dps drv;
#endif
  do4_state s;
  uint8_t alarm_spec; /* Specifier of the outstanding alarm (Seq_Nr << 3 | appears); 0: none */
  uint8_t alarm_seq;  /* the next alarm's Seq_Nr, 0..31 */
} do4;

void do4_init(DPS_P_(do4) const dps_board* board);
void do4_isr(DPS_P(do4));
const do4_state* do4_get_state(DPS_P(do4));

#ifdef __cplusplus
}
#endif

#endif /* DPC31_FIRMWARE_DO4_H */
