/* nested_wait.c -- firmware/mcs51/hooks51.c's dpc31_board_wait_1ms inside itself: timer 1's ISR
 * waits while main()'s wait runs (docs/cpu.md, "The HAL on the 80C32";
 * Cpu51Board.NestedWaitsEndTogether). A write to the chip's RAM at 8040h marks main()'s call and
 * the end of each wait: 0 before main()'s wait, 1 after the ISR's, 2 after main()'s. */
#include <8052.h>
#include <stdint.h>

#include "dpc31/dpc31_firmware.h"

#define MARK (*(volatile __xdata uint8_t*)0x8040)

void timer1_isr(void) __interrupt(3) {
  dpc31_board_wait_1ms();
  MARK = 1;
}

void main(void) {
  TMOD = 0x10; /* timer 1 in mode 1: it overflows 500 machine cycles after TR1 */
  TH1 = (uint8_t)((65536u - 500u) >> 8);
  TL1 = (uint8_t)(65536u - 500u);
  ET1 = 1;
  EA = 1;
  TR1 = 1;
  MARK = 0;
  dpc31_board_wait_1ms();
  MARK = 2;
  for (;;) {
  }
}
