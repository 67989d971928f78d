/* board_main.c -- an example firmware on an 80C32 board (docs/cpu.md, "DO4 on the 80C32", "CNT2
 * on the 80C32"): the chip (SPC3, Intel mode) in XDATA, X/INT on INT0 (level-triggered: X/INT
 * stays active until the ISR's EOI), the station address from the address switch on port 1.
 * main() is the driver's set-up, then the CPU idles until the next interrupt. Built once per
 * firmware with DPC31_BOARD_FW = do4 or cnt2 (firmware/CMakeLists.txt): FW_init and FW_isr. */
#include <8052.h>

#include "cnt2/cnt2.h"
#include "do4/do4.h"
#include "dpc31/dpc31_regs.h"

#ifndef DPC31_BOARD_PROFILE
#define DPC31_BOARD_PROFILE DPC31_PROFILE_SPC3
#endif

#define BOARD_CAT2(fw, f) fw##_##f
#define BOARD_CAT(fw, f) BOARD_CAT2(fw, f)

void int0_isr(void) __interrupt(0) { BOARD_CAT(DPC31_BOARD_FW, isr)(); }

void main(void) {
  dps_board board;
  board.profile = DPC31_BOARD_PROFILE;
  board.motorola = 0;
  board.station_address = P1; /* the address switch */
  IT0 = 0;                    /* INT0 level-triggered */
  BOARD_CAT(DPC31_BOARD_FW, init)(&board);
  EX0 = 1;
  EA = 1;
  for (;;) PCON |= 0x01; /* idle until X/INT */
}
