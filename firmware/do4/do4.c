/* do4.c -- DO4 with the OSP function model (see do4.h). */
#include "do4.h"

#include <string.h>

#include "../firmware.h"

static const uint8_t kCfg[2] = {0x21, 0x10}; /* 2 output bytes, 1 input byte */
static do4_state S;

/* The terminals are the module's real outputs: the host sees each change with its cycle. */
static void drive(uint8_t terminals, uint8_t modul_ok) {
  if (terminals != S.terminals) {
    S.terminals = terminals;
    dpc31_port_write(DO4_PORT_OUTPUTS, terminals);
  }
  if (modul_ok != S.modul_ok) {
    S.modul_ok = modul_ok;
    dpc31_port_write(DO4_PORT_MODUL_OK, modul_ok);
    /* The mode is also a status for the master: device-related diag byte, bit 0 = OSP. */
    {
      const uint8_t diag[2] = {0x02, (uint8_t)(modul_ok ? 0x00 : 0x01)};
      dps_set_diag(diag, sizeof diag, 0);
    }
  }
}

/* OSP mode: the output follows OSPMode, no longer the master. */
static void enter_osp(void) {
  S.osp_valid = 0;
  drive(S.osp_mode == DO4_REPLACE ? S.osp_value : S.last_valid, 0);
}

static int check_prm(const uint8_t* prm, uint8_t len) DPS_REENTRANT {
  if (len != 3 || prm[0] > DO4_REPLACE || (prm[1] & 0xF0u) != 0) return 0;
  S.osp_mode = prm[0];
  S.osp_value = prm[1];
  S.refresh_ms = prm[2];
  S.ms_since_refresh = 0;
  dps_timer_enable(S.refresh_ms != 0);
  if (!S.osp_valid) enter_osp(); /* the new replacement value applies at once */
  return 1;
}

static void outputs(const uint8_t* out, int cleared) DPS_REENTRANT {
  S.ms_since_refresh = 0;
  if (cleared) { /* Clear_Data or a fail-safe telegram: communication interrupted */
    ++S.osp_events;
    enter_osp();
    return;
  }
  if (out[1] & 0x01u) { /* a set OSPValid transferred: normal operation */
    S.osp_valid = 1;
    S.last_valid = out[0] & 0x0Fu;
    drive(S.last_valid, 1);
  } else { /* the master requests OSP (initial start, restart) */
    enter_osp();
  }
}

static void inputs(uint8_t* in) { in[0] = (uint8_t)(S.terminals << 4 | S.modul_ok); }

static void comm_lost(int why) {
  (void)why;
  ++S.osp_events;
  enter_osp();
}

/* A few bus cycles without refresh (EMC): OSPValid is reset in the module only. */
static void tick(void) {
  if (S.ms_since_refresh < 255u) ++S.ms_since_refresh;
  if (S.osp_valid && S.ms_since_refresh >= S.refresh_ms) {
    ++S.osp_events;
    enter_osp();
  }
}

static const dps_module kModule = {"DO4",     DO4_IDENT, kCfg,    sizeof kCfg, 1,         2,
                                   7 + 1 + 3, check_prm, outputs, inputs,      comm_lost, tick};

void do4_init(const dps_board* board) {
  memset(&S, 0, sizeof S); /* power on: outputs off, OSP until the master sets OSPValid */
  dps_init(board, &kModule);
}

void do4_isr(void) { dps_isr(); }

const do4_state* do4_get_state(void) { return &S; }

/* The plug-in descriptor is the host's (firmware.h); an 80C32 build has its own main(). */
#ifndef __SDCC

static void start(const dpc31_board* board) {
  const dps_board b = dpc31_dps_board(board);
  do4_init(&b);
}

static const char* const kPorts[] = {"outputs", "modul_ok", 0};
/* Spec_User_Prm_Byte 00; OSPMode 0 (retain); replacement value 0; refresh monitor 100 ms: a
 * few Data_Exchange cycles even at 9.6 kbaud, where one cycle takes about 30 ms. */
static const uint8_t kPrm[] = {0x00, DO4_RETAIN_LAST, 0x00, 0x64};
const dpc31_firmware do4_firmware = {DPC31_FIRMWARE_ABI_VERSION,
                                     "DO4",
                                     "do4/DO4_0D04.gsd",
                                     kPorts,
                                     start,
                                     do4_isr,
                                     0,
                                     0,
                                     0,
                                     DO4_IDENT,
                                     kCfg,
                                     sizeof kCfg,
                                     1,
                                     2,
                                     kPrm,
                                     sizeof kPrm};
#endif
