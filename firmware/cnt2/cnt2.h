/*
 * cnt2.h -- CNT2: a 2-channel counter module with message bits (MSG) and the LOGMSG hold with a
 * shadow register (seed 001: Eaton XI/ON XNE-2CNT-2PWM, "Storage of messages"). Portable C99
 * firmware over the dps driver layer.
 *
 * Outputs from the master (2 bytes, Cfg 0x21), byte c for channel c+1:
 *   bit 0 CNT_EN (count pulses), bit 1 CNT_RESET (counter held at 0), bit 7 CNTx_LOGMSG
 * Inputs to the master (6 bytes, Cfg 0x15), 3 bytes per channel:
 *   counter high byte, counter low byte, status: bits 3..0 MSG, bit 7 LOGMSG_ACK (1 = the MSG
 *   bits shown are held)
 * MSG bits: 0 MSG_OVERFLOW (counter passed FFFFh), 1 MSG_REF (reference input edge),
 *           2 MSG_SHORT (output short circuit), 3 MSG_SUPPLY (supply fault).
 *
 * Storage of messages: while CNTx_LOGMSG = 0 new messages are ORed into MSG. Its change 0 -> 1
 * holds MSG; messages arriving meanwhile go to the shadow register (all 0 at the start). Its
 * change 1 -> 0 copies the shadow into MSG and clears the shadow. So a master that sets LOGMSG,
 * waits for LOGMSG_ACK, evaluates MSG and clears LOGMSG loses no message.
 */
#ifndef DPC31_FIRMWARE_CNT2_H
#define DPC31_FIRMWARE_CNT2_H

#include <stdint.h>

#include "../firmware.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CNT2_IDENT 0x0C02u
#define CNT2_PORT_HOLD1 0u /* 1 while channel 1 holds its MSG bits (the hold instant's cycle) */
#define CNT2_PORT_HOLD2 1u

enum {
  CNT2_MSG_OVERFLOW = 0x01,
  CNT2_MSG_REF = 0x02,
  CNT2_MSG_SHORT = 0x04,
  CNT2_MSG_SUPPLY = 0x08
};

/* The firmware as hosts find it (firmware.h). */
extern const dpc31_firmware cnt2_firmware;

void cnt2_init(const dps_board* board);
void cnt2_isr(void);
/* The module's hardware: "count1"/"count2" N pulses, "event1"/"event2" MSG bits (1..15). */
int cnt2_hw_input(const char* name, uint32_t value);

typedef struct cnt2_channel {
  uint16_t counter;  /* hardware counter */
  uint8_t enabled;   /* hardware gate (CNT_EN and not CNT_RESET) */
  uint8_t hw_events; /* hardware event latch, read and cleared by the firmware */
  uint8_t msg;       /* MSG bits as reported */
  uint8_t shadow;    /* REG_CNTx_LOGMSG */
  uint8_t hold;      /* CNTx_LOGMSG seen as 1 */
} cnt2_channel;
const cnt2_channel* cnt2_get_channel(int channel); /* 0 or 1 */

#ifdef __cplusplus
}
#endif

#endif /* DPC31_FIRMWARE_CNT2_H */
