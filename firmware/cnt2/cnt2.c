/* cnt2.c -- CNT2 with MSG storage through a shadow register (see cnt2.h). */
#include "cnt2.h"

#include <string.h>

#include "../firmware.h"

enum { CNT_EN = 0x01, CNT_RESET = 0x02, PWM_EN = 0x01, LOGMSG = 0x80, LOGMSG_ACK = 0x80 };
enum { DUTY_MAX = 100 };

static cnt2_channel C[2];
static cnt2_pwm P[2];

/* Messages the hardware latched since the last look go to MSG, or to the shadow while MSG is
 * held. One read-and-clear of the latch, so nothing can slip in between. */
static void collect(cnt2_msgs* m) {
  const uint8_t ev = m->hw_events;
  m->hw_events = 0;
  if (m->hold) {
    m->shadow |= ev;
  } else {
    m->msg |= ev;
  }
}

/* The control bit CNTx_LOGMSG / PWMx_LOGMSG of one channel, with its hold port. */
static void logmsg(cnt2_msgs* m, uint8_t ctl, unsigned port) {
  const uint8_t hold = (uint8_t)((ctl & LOGMSG) != 0);
  if (hold == m->hold) return;
  collect(m);  /* what came before this instant belongs to the old side */
  if (!hold) { /* 1 -> 0: the shadow's messages become the MSG bits */
    m->msg = m->shadow;
    m->shadow = 0;
  }
  m->hold = hold;
  dpc31_port_write(port, hold);
}

static uint8_t status(cnt2_msgs* m) {
  collect(m);
  return (uint8_t)(m->msg | (m->hold ? LOGMSG_ACK : 0));
}

static void drive_pwm(int c, uint8_t duty) {
  if (duty == P[c].duty) return;
  P[c].duty = duty;
  dpc31_port_write(c == 0 ? CNT2_PORT_PWM1 : CNT2_PORT_PWM2, duty);
}

static int check_prm(const uint8_t* prm, uint8_t len) DPS_REENTRANT {
  (void)prm;
  return len == 0;
}

/* The safe state of the outputs: the counters stop, the PWM outputs go off; the MSG bits, held
 * or not, stay. */
static void safe_state(void) {
  C[0].enabled = C[1].enabled = 0;
  drive_pwm(0, 0);
  drive_pwm(1, 0);
}

static void outputs(const uint8_t* out, int cleared) DPS_REENTRANT {
  int c;
  if (cleared) { /* Clear_Data, a fail-safe exchange, Leave_Master: the ASIC cleared the outputs, */
    safe_state(); /* the master did not write LOGMSG 0: a hold stays until it does */
    return;
  }
  for (c = 0; c < 2; ++c) {
    cnt2_channel* ch = &C[c];
    const uint8_t ctl = out[c];
    ch->enabled = (uint8_t)((ctl & CNT_EN) != 0 && (ctl & CNT_RESET) == 0);
    if (ctl & CNT_RESET) ch->counter = 0;
    logmsg(&ch->m, ctl, c == 0 ? CNT2_PORT_HOLD1 : CNT2_PORT_HOLD2);
  }
  for (c = 0; c < 2; ++c) {
    cnt2_pwm* pw = &P[c];
    const uint8_t ctl = out[2 + 2 * c];
    const uint8_t duty = out[3 + 2 * c];
    /* The control bit first: a range message of this same transfer comes after its hold. */
    logmsg(&pw->m, ctl, c == 0 ? CNT2_PORT_PWM_HOLD1 : CNT2_PORT_PWM_HOLD2);
    /* One message when the value leaves the range, not one per transfer that repeats it. */
    if (duty > DUTY_MAX && pw->requested <= DUTY_MAX) pw->m.hw_events |= CNT2_PWM_MSG_DUTY;
    pw->requested = duty;
    drive_pwm(c, (ctl & PWM_EN) ? (uint8_t)(duty > DUTY_MAX ? DUTY_MAX : duty) : 0);
  }
}

static void inputs(uint8_t* in) {
  int c;
  for (c = 0; c < 2; ++c) {
    cnt2_channel* ch = &C[c];
    in[3 * c] = (uint8_t)(ch->counter >> 8);
    in[3 * c + 1] = (uint8_t)ch->counter;
    in[3 * c + 2] = status(&ch->m);
    in[6 + c] = status(&P[c].m);
  }
}

/* Communication lost: the outputs go to the safe state; messages are kept. */
static void comm_lost(int why) {
  (void)why;
  safe_state();
}

static const uint8_t kCfg[2] = {0x25, 0x17};
static const dps_module kModule = {"CNT2",    CNT2_IDENT, kCfg,   sizeof kCfg, 8, 6, 7 + 1,
                                   check_prm, outputs,    inputs, comm_lost,   0, 0};

void cnt2_init(const dps_board* board) {
  memset(C, 0, sizeof C); /* the shadows start as all MSG = 0 */
  memset(P, 0, sizeof P);
  dps_init(board, &kModule);
}

void cnt2_isr(void) { dps_isr(); }

const cnt2_channel* cnt2_get_channel(int channel) { return &C[channel & 1]; }
const cnt2_pwm* cnt2_get_pwm(int channel) { return &P[channel & 1]; }

/* The module's hardware inputs as a host feeds them, and the plug-in descriptor, are the host's
 * (firmware.h); an 80C32 build has its own main() and no such inputs wired (docs/cpu.md, "CNT2 on
 * the 80C32"). */
#ifndef __SDCC

static int channel_of(const char* name, const char* stem) {
  const size_t n = strlen(stem);
  if (strncmp(name, stem, n) != 0 || (name[n] != '1' && name[n] != '2') || name[n + 1] != 0)
    return -1;
  return name[n] - '1';
}

int cnt2_hw_input(const char* name, uint32_t value) {
  cnt2_msgs* m;
  int c = channel_of(name, "count");
  if (c >= 0) {
    cnt2_channel* ch = &C[c];
    if (ch->enabled) {
      const uint32_t sum = ch->counter + value;
      if (sum > 0xFFFFu) ch->m.hw_events |= CNT2_MSG_OVERFLOW;
      ch->counter = (uint16_t)sum;
    }
    return 0;
  }
  if ((c = channel_of(name, "event")) >= 0) {
    m = &C[c].m;
  } else if ((c = channel_of(name, "pwm_event")) >= 0) {
    m = &P[c].m;
  } else {
    return -1;
  }
  if (value == 0 || value > 0x0Fu) return -2;
  m->hw_events |= (uint8_t)value;
  return 0;
}

static const char* const kPorts[] = {"hold1", "hold2", "pwm_hold1", "pwm_hold2", "pwm1", "pwm2", 0};
static const char* const kHwInputs[] = {"count1",     "count2",     "event1", "event2",
                                        "pwm_event1", "pwm_event2", 0};
static const uint8_t kPrm[] = {0x00}; /* Spec_User_Prm_Byte */
static void start(const dpc31_board* board) {
  const dps_board b = dpc31_dps_board(board);
  cnt2_init(&b);
}

const dpc31_firmware cnt2_firmware = {DPC31_FIRMWARE_ABI_VERSION,
                                      "CNT2",
                                      "cnt2/CNT2_0C02.gsd",
                                      kPorts,
                                      start,
                                      cnt2_isr,
                                      0,
                                      cnt2_hw_input,
                                      kHwInputs,
                                      CNT2_IDENT,
                                      kCfg,
                                      sizeof kCfg,
                                      8,
                                      6,
                                      kPrm,
                                      sizeof kPrm};
#endif
