/* cnt2_main.c -- CNT2 on an 80C32 board (docs/cpu.md, "CNT2 on the 80C32"): the board of DO4
 * (do4_main.c): the chip (SPC3, Intel mode) in XDATA, X/INT on INT0 (level-triggered), the
 * station address from the address switch on port 1, the module's outputs (hold and PWM ports)
 * on the XDATA latch. main() is the driver's set-up, then the CPU idles until the next interrupt.
 */
#include <8052.h>

#include "cnt2/cnt2.h"
#include "dpc31/dpc31_regs.h"

#ifndef DPC31_BOARD_PROFILE
#define DPC31_BOARD_PROFILE DPC31_PROFILE_SPC3
#endif

void int0_isr(void) __interrupt(0) { cnt2_isr(); }

void main(void) {
  dps_board board;
  board.profile = DPC31_BOARD_PROFILE;
  board.motorola = 0;
  board.station_address = P1; /* the address switch */
  IT0 = 0;                    /* INT0 level-triggered */
  cnt2_init(&board);
  EX0 = 1;
  EA = 1;
  for (;;) PCON |= 0x01; /* idle until X/INT */
}
