/* cnt2.c -- CNT2 with MSG storage through a shadow register (see cnt2.h). */
#include "cnt2.h"

#include <string.h>

#include "../firmware.h"

enum { CNT_EN = 0x01, CNT_RESET = 0x02, PWM_EN = 0x01, LOGMSG = 0x80, LOGMSG_ACK = 0x80 };
enum { DUTY_MAX = 100 };

/* The instance (dps.h, "One instance"): passed on as ME / ME_, its driver as DRV / DRV_. On the
 * 80C32 the one static instance. */
#define ME DPS_A(self)
#define ME_ DPS_A_(self)
#define DRV DPS_A(&self->drv)
#define DRV_ DPS_A_(&self->drv)
#ifdef __SDCC
static cnt2 cnt2_the;
#define self (&cnt2_the)
#endif

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

static void drive_pwm(DPS_P_(cnt2) int c, uint8_t duty) {
  if (duty == self->p[c].duty) return;
  self->p[c].duty = duty;
  dpc31_port_write(c == 0 ? CNT2_PORT_PWM1 : CNT2_PORT_PWM2, duty);
}

static int check_prm(DPS_CB_P_ const uint8_t* prm, uint8_t len) DPS_REENTRANT {
#ifndef __SDCC
  (void)drv;
#endif
  (void)prm;
  return len == 0;
}

/* The safe state of the outputs: the counters stop, the PWM outputs go off; the MSG bits, held
 * or not, stay. */
static void safe_state(DPS_P(cnt2)) {
  self->c[0].enabled = self->c[1].enabled = 0;
  drive_pwm(ME_ 0, 0);
  drive_pwm(ME_ 1, 0);
}

static void outputs(DPS_CB_P_ const uint8_t* out, int cleared) DPS_REENTRANT {
  DPS_MODULE_SELF(cnt2);
  int c;
  if (cleared) { /* Clear_Data, a fail-safe exchange, Leave_Master: the ASIC cleared the outputs, */
    safe_state(ME); /* the master did not write LOGMSG 0: a hold stays until it does */
    return;
  }
  for (c = 0; c < 2; ++c) {
    cnt2_channel* ch = &self->c[c];
    const uint8_t ctl = out[c];
    ch->enabled = (uint8_t)((ctl & CNT_EN) != 0 && (ctl & CNT_RESET) == 0);
    if (ctl & CNT_RESET) ch->counter = 0;
    logmsg(&ch->m, ctl, c == 0 ? CNT2_PORT_HOLD1 : CNT2_PORT_HOLD2);
  }
  for (c = 0; c < 2; ++c) {
    cnt2_pwm* pw = &self->p[c];
    const uint8_t ctl = out[2 + 2 * c];
    const uint8_t duty = out[3 + 2 * c];
    /* The control bit first: a range message of this same transfer comes after its hold. */
    logmsg(&pw->m, ctl, c == 0 ? CNT2_PORT_PWM_HOLD1 : CNT2_PORT_PWM_HOLD2);
    /* One message when the value leaves the range, not one per transfer that repeats it. */
    if (duty > DUTY_MAX && pw->requested <= DUTY_MAX) pw->m.hw_events |= CNT2_PWM_MSG_DUTY;
    pw->requested = duty;
    drive_pwm(ME_ c, (ctl & PWM_EN) ? (uint8_t)(duty > DUTY_MAX ? DUTY_MAX : duty) : 0);
  }
}

static void inputs(DPS_CB_P_ uint8_t* in) {
  DPS_MODULE_SELF(cnt2);
  int c;
  for (c = 0; c < 2; ++c) {
    cnt2_channel* ch = &self->c[c];
    in[3 * c] = (uint8_t)(ch->counter >> 8);
    in[3 * c + 1] = (uint8_t)ch->counter;
    in[3 * c + 2] = status(&ch->m);
    in[6 + c] = status(&self->p[c].m);
  }
}

/* Communication lost: the outputs go to the safe state; messages are kept. */
static void comm_lost(DPS_CB_P_ int why) {
  DPS_MODULE_SELF(cnt2);
  (void)why;
  safe_state(ME);
}

static const uint8_t kCfg[2] = {0x25, 0x17};
static const dps_module kModule = {"CNT2",    CNT2_IDENT, kCfg,   sizeof kCfg, 8, 6, 7 + 1,
                                   check_prm, outputs,    inputs, comm_lost,   0, 0, 0};

void cnt2_init(DPS_P_(cnt2) const dps_board* board) {
  memset(self->c, 0, sizeof self->c); /* the shadows start as all MSG = 0 */
  memset(self->p, 0, sizeof self->p);
  dps_init(DRV_ board, &kModule);
}

void cnt2_isr(DPS_P(cnt2)) { dps_isr(DRV); }

const cnt2_channel* cnt2_get_channel(DPS_P_(cnt2) int channel) { return &self->c[channel & 1]; }
const cnt2_pwm* cnt2_get_pwm(DPS_P_(cnt2) int channel) { return &self->p[channel & 1]; }

/* The module's hardware inputs as a host feeds them, and the plug-in descriptor, are the host's
 * (firmware.h); an 80C32 build has its own main() and no such inputs wired (docs/cpu.md, "CNT2 on
 * the 80C32"). */
#ifndef __SDCC

enum { MSG_ALL = 0x0F }; /* the four MSG bits */

static int channel_of(const char* name, const char* stem) {
  const size_t n = strlen(stem);
  if (strncmp(name, stem, n) != 0 || (name[n] != '1' && name[n] != '2') || name[n + 1] != 0)
    return -1;
  return name[n] - '1';
}

int cnt2_hw_input(cnt2* self, const char* name, uint32_t value) {
  cnt2_msgs* m;
  int c = channel_of(name, "count");
  if (c >= 0) {
    cnt2_channel* ch = &self->c[c];
    if (ch->enabled) {
      const uint32_t sum = ch->counter + value;
      if (sum > 0xFFFFu) ch->m.hw_events |= CNT2_MSG_OVERFLOW;
      ch->counter = (uint16_t)sum;
    }
    return 0;
  }
  if ((c = channel_of(name, "event")) >= 0) {
    m = &self->c[c].m;
  } else if ((c = channel_of(name, "pwm_event")) >= 0) {
    m = &self->p[c].m;
  } else {
    return -1;
  }
  if (value == 0 || value > MSG_ALL) return -2;
  m->hw_events |= (uint8_t)value;
  return 0;
}

static const char* const kPorts[] = {"hold1", "hold2", "pwm_hold1", "pwm_hold2", "pwm1", "pwm2", 0};
static const char* const kHwInputs[] = {"count1",     "count2",     "event1", "event2",
                                        "pwm_event1", "pwm_event2", 0};
/* A count is any number of pulses; a message event latches MSG bits, at least one of the four. */
static const dpc31_hw_range kHwRanges[] = {{0, 0xFFFFFFFFu}, {0, 0xFFFFFFFFu}, {1, MSG_ALL},
                                           {1, MSG_ALL},     {1, MSG_ALL},     {1, MSG_ALL}};
static const uint8_t kPrm[] = {0x00}; /* Spec_User_Prm_Byte */
DPC31_BUILTIN_ENTRIES(cnt2)
static int cnt2_hw_input_in(void* inst, const char* name, uint32_t value) {
  return cnt2_hw_input((cnt2*)inst, name, value);
}
static int cnt2_hw_input_single(const char* name, uint32_t value) {
  return cnt2_hw_input(&cnt2_single, name, value);
}

const dpc31_firmware cnt2_firmware = {DPC31_FIRMWARE_ABI_VERSION,
                                      "CNT2",
                                      "cnt2/CNT2_0C02.gsd",
                                      kPorts,
                                      cnt2_start_single,
                                      cnt2_isr_single,
                                      0,
                                      cnt2_hw_input_single,
                                      kHwInputs,
                                      CNT2_IDENT,
                                      kCfg,
                                      sizeof kCfg,
                                      8,
                                      6,
                                      kPrm,
                                      sizeof kPrm};
const dpc31_builtin cnt2_builtin = {&cnt2_firmware, sizeof(cnt2),     cnt2_start_in,
                                    cnt2_isr_in,    cnt2_hw_input_in, kHwRanges};
#endif
