/* input_only_plugin.c -- a firmware plug-in with inputs only (one byte, a counter of its
 * Data_Exchanges; no outputs): the master's Data_Exchange request carries no data unit, an SD1 of
 * 6 characters (soak's fault placement, tests/soak_test.cpp). On the shipped dps driver.
 * With FORGETS_DIN it makes the mistake of docs/bring-up.md, section 7
 * (tests/scenario_walk_test.cpp): its own ISR, entered before the driver's, gives the Cfg verdict
 * on New_Cfg_Data (User_Cfg_Data_Okay) and nothing else; that read clears the event, so the
 * driver's Cfg handler, which would hand the inputs over with New_Din_Buffer_Cmd, never runs.
 * It starts only on the emulator its headers are from (dpc31emu_version(), docs/install.md
 * "Versions"): the program that loads it exports that function too (firmware/plugin_host.list). */
#include <string.h>

#ifdef FORGETS_DIN
#include "dpc31/dpc31_regs.h"
#endif
#include "dpc31/dpc31_version.h"
#include "firmware.h"

#define INPUT_ONLY_IDENT 0x0E10u

typedef struct input_only {
  dps drv; /* first: the driver's callbacks get it (DPS_MODULE_SELF) */
  uint8_t count;
} input_only;

static const uint8_t kCfg[] = {0x10}; /* 1 input byte */

static int check_prm(DPS_CB_P_ const uint8_t* prm, uint8_t len) DPS_REENTRANT {
  (void)drv;
  (void)prm;
  return len == 0;
}

static void outputs(DPS_CB_P_ const uint8_t* out, int cleared) DPS_REENTRANT {
  (void)drv;
  (void)out;
  (void)cleared;
}

static void inputs(DPS_CB_P_ uint8_t* in) {
  DPS_MODULE_SELF(input_only);
  in[0] = ++self->count;
}

static void comm_lost(DPS_CB_P_ int why) {
  (void)drv;
  (void)why;
}

static const dps_module kModule = {"INPUT-ONLY", INPUT_ONLY_IDENT, kCfg,   sizeof kCfg, 1, 0, 7 + 1,
                                   check_prm,    outputs,          inputs, comm_lost,   0, 0, 0};

static input_only g_the;
#ifdef FORGETS_DIN
static int g_motorola;
#endif

static void start(const dpc31_board* board) {
  const dps_board b = dpc31_dps_board(board);
  if (strcmp(dpc31emu_version(), DPC31EMU_VERSION_STRING) != 0) return; /* silent: no slave */
  memset(&g_the, 0, sizeof g_the);
#ifdef FORGETS_DIN
  g_motorola = board->motorola;
#endif
  dps_init(&g_the.drv, &b, &kModule);
}

static void isr(void) {
#ifdef FORGETS_DIN /* the SPC3's registers: the mistake is the SPC3's alone */
  const uint8_t high = Vpc3Read(g_motorola ? SPC3_Int_Reg_HI_MOTOROLA : SPC3_Int_Reg_HI_INTEL);
  if ((high & (SPC3_Int_Reg_New_Cfg_Data_Msk >> 8)) != 0) (void)Vpc3Read(SPC3_User_Cfg_Data_Okay);
#endif
  dps_isr(&g_the.drv);
}

static const uint8_t kPrm[] = {0x00}; /* Spec_User_Prm_Byte */
static const dpc31_firmware kInputOnly = {
    DPC31_FIRMWARE_ABI_VERSION, "INPUT-ONLY", 0,           0, start, isr,  0,          0, 0,
    INPUT_ONLY_IDENT,           kCfg,         sizeof kCfg, 1, 0,     kPrm, sizeof kPrm};
DPC31_FIRMWARE_EXPORT(kInputOnly);
