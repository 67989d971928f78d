/* hooks51.c -- the board hooks of dpc31/dpc31_firmware.h on the 80C32 board (docs/cpu.md, "The
 * HAL on the 80C32"): what a driver's VPC3_RESET, ENABLE_VPC3_INT and Vpc3Wait_1ms map to. */
#include <8052.h>

#include "dpc31/dpc31_firmware.h"

#ifndef DPC31_CPU_HZ
#define DPC31_CPU_HZ 24000000UL
#endif
/* Timer 0 counts machine cycles (12 oscillator clocks): 1 ms rounded up. */
#define WAIT_1MS_CYCLES ((DPC31_CPU_HZ + 11999UL) / 12000UL)

/* The board ties the chip's RESET to the power-on reset it shares with the 80C32: no pin to
 * drive. The chip starts reset, so the drivers' pulse before Start changes nothing, as on the
 * host (there a pulse after Start stops the run; here it goes unnoticed). */
void dpc31_board_reset(int asserted) { (void)asserted; }

/* X/INT is on INT0. */
void dpc31_board_int_enable(int enabled) { EX0 = enabled ? 1 : 0; }

/* Waits in progress: an ISR's wait may run inside the main loop's. */
static volatile __data uint8_t waits;

/* At least 1 ms: timer 0 in mode 1 (16 bit) runs WAIT_1MS_CYCLES machine cycles, plus the call's
 * own; an enabled interrupt is served meanwhile. Timer 0 is the hook's: the firmware must not
 * use it. A wait inside another (an ISR's) restarts the timer and, when it returns, leaves it
 * running with TF0 set, so the outer wait ends too: it has lasted the inner one's 1 ms. */
void dpc31_board_wait_1ms(void) {
  waits++;
  TR0 = 0;
  TMOD = (uint8_t)((TMOD & 0xF0u) | 0x01u);
  TH0 = (uint8_t)((65536UL - WAIT_1MS_CYCLES) >> 8);
  TL0 = (uint8_t)(65536UL - WAIT_1MS_CYCLES);
  TF0 = 0;
  TR0 = 1;
  while (!TF0) {
  }
  if (--waits == 0) {
    TR0 = 0;
    TF0 = 0;
  }
}
