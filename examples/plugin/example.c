/* example.c -- the example module as a dpc31emu firmware plug-in: one output byte that drives
 * its terminals (port "outputs"), one input byte that reports them inverted, and a heartbeat LED
 * (port "led") that the main loop toggles every 100 ms. The DP side is dp_slave.c. */
#include "dp_slave.h"
#include "platform.h"

#define EXAMPLE_IDENT 0x0E01u
enum { PORT_OUTPUTS = 0, PORT_LED = 1 };

static const uint8_t kCfg[] = {0x20, 0x10}; /* 1 output byte, 1 input byte */
static const uint8_t kUserPrm[] = {0x00};   /* Spec_User_Prm_Byte */

static uint8_t exchange(uint8_t outputs) {
  BOARD_OUTPUT(PORT_OUTPUTS, outputs);
  return (uint8_t)~outputs;
}

static const dp_app kApp = {EXAMPLE_IDENT, kCfg, sizeof kCfg, 7u + sizeof kUserPrm, exchange};

static void init(const dpc31_board* board) { dp_init(board->station_address, &kApp); }

#ifdef DP_POLLING
/* main()'s loop: look at the chip, nothing else. */
static void main_step(void) { dp_poll(); }
#define EXAMPLE_NAME "EXAMPLE-POLLING"
#define EXAMPLE_ISR 0
#else
static uint8_t g_led;
/* main()'s loop: the heartbeat; the DP side runs in the ISR, which preempts it. */
static void main_step(void) {
  int ms;
  for (ms = 0; ms < 100; ++ms) Vpc3Wait_1ms();
  g_led ^= 1u;
  BOARD_OUTPUT(PORT_LED, g_led);
}
#define EXAMPLE_NAME "EXAMPLE"
#define EXAMPLE_ISR dp_isr
#endif

static const char* const kPorts[] = {"outputs", "led", 0};

static const dpc31_firmware kExample = {.abi_version = DPC31_FIRMWARE_ABI_VERSION,
                                        .name = EXAMPLE_NAME,
                                        .ports = kPorts,
                                        .init = init,
                                        .isr = EXAMPLE_ISR,
                                        .main_step = main_step,
                                        .ident = EXAMPLE_IDENT,
                                        .cfg = kCfg,
                                        .cfg_len = sizeof kCfg,
                                        .in_len = 1,
                                        .out_len = 1,
                                        .user_prm = kUserPrm,
                                        .user_prm_len = sizeof kUserPrm};
DPC31_FIRMWARE_EXPORT(kExample);
