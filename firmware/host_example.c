/* host_example.c -- a C host that drives a firmware by hand over the HAL, without the host CPU:
 * a chip, the driver's init, and its ISR while the interrupt is active. Built as
 * dpc31_host_example and run by CTest. (A plug-in's host: examples/plugin/host.c.) */
#include <stdio.h>

#include "do4/do4.h" /* or your driver's header */
#include "dpc31/dpc31_hal.h"
#include "dpc31/dpc31_regs.h"

int main(void) {
  dps_board board = {DPC31_PROFILE_DPC31, 0, 5}; /* chip, bus mode, station address */
  static do4 fw;                                 /* the firmware's instance: all its state */
  dpc31_chip* chip = dpc31_create("dpc31", 0);
  int i;
  dpc31_select(chip);
  do4_init(&fw, &board); /* your driver's init: registers, buffers, Start */
  for (i = 0; i < 1000; ++i) {
    if (dpc31_irq_active(chip)) {
      do4_isr(&fw);
    } else {
      dpc31_run_until_irq_change(chip, 48000);
    }
  }
  printf("cycle %llu: %u interrupts served, DP state %u\n", (unsigned long long)dpc31_cycle(chip),
         (unsigned)dps_get_stats(&fw.drv)->interrupts,
         (unsigned)((dpc31_peek(chip, DPC31_Status_Reg) >> 4) & 3u));
  dpc31_destroy(chip);
  return 0;
}
