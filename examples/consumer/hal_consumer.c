/* A C program on the installed HAL, as firmware sees the chip: the drivers' access functions on
 * the user RAM, each costing the modelled bus time. Exit 0 only if every check held. */
#include <stdio.h>

#include "dpc31/dpc31_hal.h"
#include "dpc31/dpc31_regs.h"

/* A chip address where the drivers' block copies take a pointer (their VPC3_UNSIGNED8_PTR). */
#define CHIP_PTR(a) ((uint8_t*)(uintptr_t)(a))

int main(void) {
  uint8_t out[4] = {0x11, 0x22, 0x33, 0x44};
  uint8_t in[4] = {0};
  uint64_t start;
  uint64_t took;
  int ok;
  dpc31_chip* chip = dpc31_create("dpc31", 0);
  if (!chip) {
    return 1;
  }
  dpc31_select(chip);
  start = dpc31_cycle(chip);
  CopyToVpc3(CHIP_PTR(DPC31_USER_BASE), out, sizeof out);
  Vpc3Write(DPC31_USER_BASE + 4u, 0x55);
  CopyFromVpc3(in, CHIP_PTR(DPC31_USER_BASE), sizeof in);
  took = dpc31_cycle(chip) - start;
  /* 4 + 1 + 4 byte accesses of 4 chip clocks each (docs/timing.md). */
  ok = in[0] == 0x11 && in[3] == 0x44 && Vpc3Read(DPC31_USER_BASE + 4u) == 0x55 && took == 36;
  printf("hal consumer: %s, %llu cycles\n", ok ? "ok" : "FAILED", (unsigned long long)took);
  dpc31_select(NULL);
  dpc31_destroy(chip);
  return ok ? 0 : 1;
}
