/*
 * cnt2.h -- CNT2: a module with 2 counter and 2 PWM channels, each with message bits (MSG) and
 * the LOGMSG hold with a shadow register (seed 001: Eaton XI/ON XNE-2CNT-2PWM, "Storage of
 * messages"). Portable C99 firmware over the dps driver layer.
 *
 * Outputs from the master (6 bytes, Cfg 0x25):
 *   bytes 0, 1 counter channel 1, 2: bit 0 CNT_EN (count pulses), bit 1 CNT_RESET (counter held
 *     at 0), bit 7 CNTx_LOGMSG
 *   bytes 2, 3 PWM channel 1: control (bit 0 PWM_EN, bit 7 PWM1_LOGMSG), duty cycle in % (0..100)
 *   bytes 4, 5 PWM channel 2, the same
 * Inputs to the master (8 bytes, Cfg 0x17):
 *   bytes 0..5, 3 per counter channel: counter high byte, counter low byte, status
 *   bytes 6, 7 status of PWM channel 1, 2
 *   status: bits 3..0 MSG, bit 7 LOGMSG_ACK (1 = the MSG bits shown are held)
 * Counter MSG bits: 0 MSG_OVERFLOW (counter passed FFFFh), 1 MSG_REF (reference input edge),
 *                   2 MSG_SHORT (output short circuit), 3 MSG_SUPPLY (supply fault).
 * PWM MSG bits:     0 MSG_DUTY (duty cycle above 100 %, 100 % driven), 1 MSG_SHORT,
 *                   2 MSG_SUPPLY, 3 MSG_OPEN_LOAD (no load on the output).
 *
 * Storage of messages, the same for each of the four channels: while its LOGMSG = 0 new messages
 * are ORed into MSG. Its change 0 -> 1 holds MSG; messages arriving meanwhile go to the shadow
 * register (REG_CNTx_LOGMSG / REG_PWMx_LOGMSG, all 0 at the start). Its change 1 -> 0 copies the
 * shadow into MSG and clears the shadow. So a master that sets LOGMSG, waits for LOGMSG_ACK,
 * evaluates MSG and clears LOGMSG loses no message.
 */
#ifndef DPC31_FIRMWARE_CNT2_H
#define DPC31_FIRMWARE_CNT2_H

#include <stdint.h>

#include "../firmware.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CNT2_IDENT 0x0C02u
/* Ports: 1 while a channel holds its MSG bits (from the hold instant's cycle); the PWM outputs'
 * driven duty cycle in % (0 = off). */
#define CNT2_PORT_HOLD1 0u
#define CNT2_PORT_HOLD2 1u
#define CNT2_PORT_PWM_HOLD1 2u
#define CNT2_PORT_PWM_HOLD2 3u
#define CNT2_PORT_PWM1 4u
#define CNT2_PORT_PWM2 5u

enum {
  CNT2_MSG_OVERFLOW = 0x01,
  CNT2_MSG_REF = 0x02,
  CNT2_MSG_SHORT = 0x04,
  CNT2_MSG_SUPPLY = 0x08
};
enum {
  CNT2_PWM_MSG_DUTY = 0x01,
  CNT2_PWM_MSG_SHORT = 0x02,
  CNT2_PWM_MSG_SUPPLY = 0x04,
  CNT2_PWM_MSG_OPEN_LOAD = 0x08
};

/* The firmware as hosts find it (firmware.h). */
extern const dpc31_firmware cnt2_firmware;
extern const dpc31_builtin cnt2_builtin;

/* The message storage of one channel. */
typedef struct cnt2_msgs {
  uint8_t hw_events; /* hardware event latch, read and cleared by the firmware */
  uint8_t msg;       /* MSG bits as reported */
  uint8_t shadow;    /* REG_CNTx_LOGMSG / REG_PWMx_LOGMSG */
  uint8_t hold;      /* CNTx_LOGMSG / PWMx_LOGMSG seen as 1 */
} cnt2_msgs;

typedef struct cnt2_channel {
  uint16_t counter; /* hardware counter */
  uint8_t enabled;  /* hardware gate (CNT_EN and not CNT_RESET) */
  cnt2_msgs m;
} cnt2_channel;

typedef struct cnt2_pwm {
  uint8_t duty;      /* duty cycle driven, % (0 while PWM_EN is 0 or the outputs are safe) */
  uint8_t requested; /* duty cycle byte of the master's last transfer */
  cnt2_msgs m;
} cnt2_pwm;

/* One CNT2 (dps.h, "One instance"): the driver first (its callbacks find the module around it;
 * the 80C32's driver is a static of its own), then the module's channels. */
typedef struct cnt2 {
#ifndef __SDCC
  dps drv;
#endif
  cnt2_channel c[2];
  cnt2_pwm p[2];
} cnt2;

void cnt2_init(DPS_P_(cnt2) const dps_board* board);
void cnt2_isr(DPS_P(cnt2));
const cnt2_channel* cnt2_get_channel(DPS_P_(cnt2) int channel); /* 0 or 1 */
const cnt2_pwm* cnt2_get_pwm(DPS_P_(cnt2) int channel);         /* 0 or 1 */
/* The module's hardware (hosts only): "count1"/"count2" N pulses, "event1"/"event2" counter MSG
 * bits (1..15), "pwm_event1"/"pwm_event2" PWM MSG bits (1..15). */
int cnt2_hw_input(cnt2* self, const char* name, uint32_t value);

#ifdef __cplusplus
}
#endif

#endif /* DPC31_FIRMWARE_CNT2_H */
