/* dp_slave.c -- the example's DP-slave driver (dp_slave.h). Written for this example; it reaches
 * the chip only through the six access functions and the board macros of platform.h. */
#include "dp_slave.h"

#include "vpc3.h"

#define OUT_LEN 1u
#define IN_LEN 1u
#define AUX_LEN 16u /* Set_Prm and Chk_Cfg telegrams up to this length */

static const dp_app* g_app;
static volatile uint8_t g_fatal; /* why the driver stopped (a debugger looks here) */

static void write16(VPC3_ADR a, uint16_t v) {
  Vpc3Write(a, (uint8_t)v);
  Vpc3Write((VPC3_ADR)(a + 1u), (uint8_t)(v >> 8));
}

static uint16_t read16(VPC3_ADR a) {
  const uint8_t lo = Vpc3Read(a);
  return (uint16_t)(Vpc3Read((VPC3_ADR)(a + 1u)) << 8 | lo);
}

/* A buffer pointer cell holds a segment number. */
static VPC3_ADR buffer(VPC3_ADR cell) { return (VPC3_ADR)(Vpc3Read(cell) << SEGMENT_SHIFT); }

/* Nothing sensible can go on: stop here with interrupts off. The board's watchdog would reset
 * the CPU; the emulator stops the run (its hang guard). */
static void fatal_error(uint8_t why) {
  DISABLE_VPC3_INT();
  g_fatal = why;
  while (1) {
  }
}

static void set_inputs(uint8_t value) {
  const uint8_t u = (uint8_t)((Vpc3Read(REG_DIN_SM) >> 4) & 3u); /* the buffer the user owns */
  if (u == 0) return;
  CopyToVpc3(VPC3_PTR(buffer((VPC3_ADR)(CELL_DIN_PTR + u - 1u))), &value, IN_LEN);
  (void)Vpc3Read(REG_NEW_DIN);
}

static void new_prm(void) {
  uint8_t result;
  do { /* a newer Set_Prm during the check: check that one */
    const int ok = Vpc3Read(CELL_LEN_PRM) == g_app->prm_len;
    result = Vpc3Read(ok ? REG_PRM_OK : REG_PRM_NOT_OK);
  } while (result == VERDICT_CONFLICT);
}

static void new_cfg(void) {
  uint8_t result;
  do {
    const uint8_t len = Vpc3Read(CELL_LEN_CFG);
    int ok = len == g_app->cfg_len;
    if (ok) { /* two bus reads in a fixed order (C leaves the order of arguments open) */
      const VPC3_ADR cfg = buffer(CELL_CFG_PTR);
      const VPC3_ADR read_cfg = buffer(CELL_READ_CFG_PTR);
      ok = Vpc3MemCmp(VPC3_PTR(cfg), VPC3_PTR(read_cfg), len) == 0;
    }
    result = Vpc3Read(ok ? REG_CFG_OK : REG_CFG_NOT_OK);
  } while (result == VERDICT_CONFLICT);
}

static void dx_out(void) {
  const uint8_t r = Vpc3Read(REG_NEXT_DOUT);
  if ((r & DOUT_STATE_U) != 0 && (r & 3u) != 0) {
    uint8_t out;
    CopyFromVpc3(&out, VPC3_PTR(buffer((VPC3_ADR)(CELL_DOUT_PTR + (r & 3u) - 1u))), OUT_LEN);
    set_inputs(g_app->exchange(out));
  }
  Vpc3Write(REG_MODE1_SET, MODE1_RES_USER_WD);
}

/* The events of `req`, then their acknowledge (New_Prm/Cfg_Data go with the verdict reads). */
static void serve(uint16_t req) {
  if (req & EV_NEW_PRM) new_prm();
  if (req & EV_NEW_CFG) new_cfg();
  if (req & EV_DX_OUT) dx_out();
  req &= (uint16_t) ~(EV_NEW_PRM | EV_NEW_CFG);
  if (req != 0) write16(REG_INT_ACK, req);
}

void dp_poll(void) {
  const uint16_t req = read16(REG_INT_REQ);
  if (req != 0) serve(req);
}

void dp_isr(void) {
  serve(read16(REG_INT_REG));
  Vpc3Write(REG_MODE1_SET, MODE1_EOI);
}

void dp_init(uint8_t station_address, const dp_app* app) {
  unsigned seg = USER_BASE >> SEGMENT_SHIFT;
  unsigned k;
  g_app = app;
  DISABLE_VPC3_INT();
  VPC3_RESET();
  Vpc3Wait_1ms();
  VPC3_CLEAR_RESET();
  Vpc3Wait_1ms();
  if (STATUS_ASIC(read16(REG_STATUS)) != ASIC_VPC3_C) fatal_error(1);

  write16(REG_INT_REQ, 0x0000);
  write16(REG_INT_ACK, (uint16_t)(EV_ALL & ~(EV_NEW_PRM | EV_NEW_CFG)));
  write16(REG_MODE0, MODE0_DP);
#ifdef DP_POLLING
  write16(REG_INT_MASK, EV_ALL); /* every interrupt masked: the main loop polls */
#else
  write16(REG_INT_MASK, (uint16_t) ~(EV_NEW_PRM | EV_NEW_CFG | EV_DX_OUT));
#endif
  Vpc3Write(REG_WD_BAUD, 0x10);  /* baud search watchdog: 16 x 10 ms */
  Vpc3Write(REG_MIN_TSDR, 0x0B); /* 11 bit times */
  write16(CELL_USER_WD, 0x01FF);
  Vpc3Write(CELL_IDENT_LOW, (uint8_t)app->ident);
  Vpc3Write(CELL_IDENT_HIGH, (uint8_t)(app->ident >> 8));
  Vpc3Write(CELL_TS_ADR, station_address);
  Vpc3Write(CELL_NO_ADD_CHANGE, 0xFF); /* no Set_Slave_Add */

  /* Buffers, one after the other from the user area: 3 Dout, 3 Din, 2 diag, 2 aux, Prm, Cfg,
   * Read_Cfg, SSA; AUX_LEN bytes (2 segments) where a telegram goes. */
  Vpc3Write(CELL_LEN_DOUT, OUT_LEN);
  Vpc3Write(CELL_LEN_DIN, IN_LEN);
  for (k = 0; k < 3; ++k) Vpc3Write((VPC3_ADR)(CELL_DOUT_PTR + k), (uint8_t)seg++);
  for (k = 0; k < 3; ++k) Vpc3Write((VPC3_ADR)(CELL_DIN_PTR + k), (uint8_t)seg++);
  for (k = 0; k < 2; ++k) {
    Vpc3Write((VPC3_ADR)(CELL_LEN_DIAG + k), 6);
    Vpc3Write((VPC3_ADR)(CELL_DIAG_PTR + k), (uint8_t)seg);
    seg += 2;
    Vpc3Write((VPC3_ADR)(CELL_LEN_CNTRL + k), AUX_LEN);
    Vpc3Write((VPC3_ADR)(CELL_AUX_PTR + k), (uint8_t)seg);
    seg += 2;
  }
  Vpc3Write(CELL_AUX_SEL, 0x00);
  Vpc3Write(CELL_PRM_PTR, (uint8_t)seg);
  seg += 2;
  Vpc3Write(CELL_CFG_PTR, (uint8_t)seg);
  seg += 2;
  Vpc3Write(CELL_READ_CFG_PTR, (uint8_t)seg);
  seg += 2;
  Vpc3Write(CELL_SSA_PTR, (uint8_t)seg);
  seg += 2;
  Vpc3MemSet(USER_BASE, 0x00, (uint16_t)((seg << SEGMENT_SHIFT) - USER_BASE));
  Vpc3Write(CELL_LEN_READ_CFG, app->cfg_len);
  CopyToVpc3(VPC3_PTR(buffer(CELL_READ_CFG_PTR)), (MEM_UNSIGNED8_PTR)app->cfg, app->cfg_len);
  set_inputs(0x00);

  Vpc3Write(REG_MODE1_SET, MODE1_START | MODE1_RES_USER_WD);
#ifndef DP_POLLING
  ENABLE_VPC3_INT();
#endif
}
