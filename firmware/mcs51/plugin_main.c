/* plugin_main.c -- a firmware shaped as a plug-in (dpc31/dpc31_firmware.h: its descriptor, built
 * unchanged) on the 80C32 board, as the host runs it (docs/cpu.md, "The HAL on the 80C32"): the
 * chip in XDATA, X/INT on INT0 (level-triggered) with the interrupt input enabled when the
 * firmware starts, the station address from the address switch on port 1. main() calls the
 * descriptor's init, then its main_step in a loop, or idles until the next interrupt without one;
 * INT0 calls its isr, at any instruction: the HAL's functions (hal51.c) are not reentrant, so isr
 * and init/main_step must not both call them. The board hooks are hooks51.c's. */
#include <8052.h>

#include "dpc31/dpc31_firmware.h"
#include "dpc31/dpc31_regs.h"

#ifndef DPC31_BOARD_PROFILE
#define DPC31_BOARD_PROFILE DPC31_PROFILE_VPC3PLUS
#endif

/* A polling firmware has no ISR: X/INT is its main loop's, and INT0, level-triggered, would call
 * again at once, so it is masked. */
void int0_isr(void) __interrupt(0) {
  if (dpc31_firmware_descriptor->isr != 0) {
    dpc31_firmware_descriptor->isr();
  } else {
    EX0 = 0;
  }
}

void main(void) {
  dpc31_board board;
  const dpc31_firmware* fw = dpc31_firmware_descriptor;
  board.profile = DPC31_BOARD_PROFILE;
  board.motorola = 0;
  board.station_address = P1; /* the address switch */
  IT0 = 0;                    /* INT0 level-triggered */
  EX0 = 1;                    /* the interrupt input is enabled when the firmware starts */
  EA = 1;
  fw->init(&board);
  for (;;) {
    if (fw->main_step != 0) {
      fw->main_step();
    } else {
      PCON |= 0x01; /* idle until X/INT */
    }
  }
}
