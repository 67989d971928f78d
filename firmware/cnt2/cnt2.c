/* cnt2.c -- CNT2 with MSG storage through a shadow register (see cnt2.h). */
#include "cnt2.h"

#include <string.h>

#include "../firmware.h"

enum { CNT_EN = 0x01, CNT_RESET = 0x02, CNT_LOGMSG = 0x80, LOGMSG_ACK = 0x80 };

static cnt2_channel C[2];

/* Messages the hardware latched since the last look go to MSG, or to the shadow while MSG is
 * held. One read-and-clear of the latch, so nothing can slip in between. */
static void collect(cnt2_channel* ch) {
  const uint8_t ev = ch->hw_events;
  ch->hw_events = 0;
  if (ch->hold) {
    ch->shadow |= ev;
  } else {
    ch->msg |= ev;
  }
}

static int check_prm(const uint8_t* prm, uint8_t len) {
  (void)prm;
  return len == 0;
}

/* The safe state of the outputs: the counters stop; the MSG bits, held or not, stay. */
static void stop_counters(void) { C[0].enabled = C[1].enabled = 0; }

static void outputs(const uint8_t* out, int cleared) {
  int c;
  if (cleared) { /* Clear_Data, a fail-safe exchange, Leave_Master: the ASIC cleared the outputs, */
    stop_counters(); /* the master did not write LOGMSG 0: a hold stays until it does */
    return;
  }
  for (c = 0; c < 2; ++c) {
    cnt2_channel* ch = &C[c];
    const uint8_t ctl = out[c];
    const uint8_t hold = (uint8_t)((ctl & CNT_LOGMSG) != 0);
    ch->enabled = (uint8_t)((ctl & CNT_EN) != 0 && (ctl & CNT_RESET) == 0);
    if (ctl & CNT_RESET) ch->counter = 0;
    if (hold == ch->hold) continue;
    collect(ch); /* what came before this instant belongs to the old side */
    if (!hold) { /* 1 -> 0: the shadow's messages become the MSG bits */
      ch->msg = ch->shadow;
      ch->shadow = 0;
    }
    ch->hold = hold;
    dpc31_port_write(c == 0 ? CNT2_PORT_HOLD1 : CNT2_PORT_HOLD2, hold);
  }
}

static void inputs(uint8_t* in) {
  int c;
  for (c = 0; c < 2; ++c) {
    cnt2_channel* ch = &C[c];
    collect(ch);
    in[3 * c] = (uint8_t)(ch->counter >> 8);
    in[3 * c + 1] = (uint8_t)ch->counter;
    in[3 * c + 2] = (uint8_t)(ch->msg | (ch->hold ? LOGMSG_ACK : 0));
  }
}

/* Communication lost: the counters stop (outputs to the safe state); messages are kept. */
static void comm_lost(int why) {
  (void)why;
  stop_counters();
}

static const uint8_t kCfg[2] = {0x21, 0x15};
static const dps_module kModule = {"CNT2", CNT2_IDENT, kCfg,    sizeof kCfg, 6,         2,
                                   7 + 1,  check_prm,  outputs, inputs,      comm_lost, 0};

void cnt2_init(const dps_board* board) {
  memset(C, 0, sizeof C); /* the shadow starts as all MSG = 0 */
  dps_init(board, &kModule);
}

void cnt2_isr(void) { dps_isr(); }

static int channel_of(const char* name, const char* stem) {
  const size_t n = strlen(stem);
  if (strncmp(name, stem, n) != 0 || (name[n] != '1' && name[n] != '2') || name[n + 1] != 0)
    return -1;
  return name[n] - '1';
}

int cnt2_hw_input(const char* name, uint32_t value) {
  int c = channel_of(name, "count");
  if (c >= 0) {
    cnt2_channel* ch = &C[c];
    if (ch->enabled) {
      const uint32_t sum = ch->counter + value;
      if (sum > 0xFFFFu) ch->hw_events |= CNT2_MSG_OVERFLOW;
      ch->counter = (uint16_t)sum;
    }
    return 0;
  }
  c = channel_of(name, "event");
  if (c < 0) return -1;
  if (value == 0 || value > 0x0Fu) return -2;
  C[c].hw_events |= (uint8_t)value;
  return 0;
}

const cnt2_channel* cnt2_get_channel(int channel) { return &C[channel & 1]; }

static const char* const kPorts[] = {"hold1", "hold2", 0};
static const char* const kHwInputs[] = {"count1", "count2", "event1", "event2", 0};
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
                                      6,
                                      2,
                                      kPrm,
                                      sizeof kPrm};
