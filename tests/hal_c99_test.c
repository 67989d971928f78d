/* The C HAL from strict C99: every function once, with the cycle costs of docs/timing.md
 * (4 clocks per byte access). Exit 0 when all hold; each failure prints its line.
 *
 * Compiled with a public SPC3/VPC3+ driver's headers: the example driver's platform.h
 * (examples/plugin/) #defines the address types (serial mode), and its vpc3.h declares the six
 * access functions with them. Both must compile next to the HAL's prototypes (the declarations
 * agree). */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "dpc31/dpc31_hal.h"
#include "dpc31/dpc31_regs.h"
#include "platform.h"
#include "vpc3.h"

/* A chip address as the serial mode's chip pointer. */
#define CHIP_PTR(a) VPC3_PTR(a)

static int failures;
#define CHECK(cond)                                              \
  do {                                                           \
    if (!(cond)) {                                               \
      fprintf(stderr, "%s:%d: %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                \
    }                                                            \
  } while (0)

static uint64_t edges[4];
static int edge_levels[4];
static int n_edges;
static void on_irq(void* user, uint64_t cycle, int active) {
  (void)user;
  if (n_edges < 4) {
    edges[n_edges] = cycle;
    edge_levels[n_edges] = active;
  }
  ++n_edges;
}

int main(void) {
  static uint8_t pattern[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  uint8_t back[8];
  const VPC3_ADR a = SPC3_USER_BASE;
  dpc31_chip* chip = dpc31_create("spc3", 0);
  CHECK(dpc31_create("spc4", 0) == NULL);
  CHECK(chip != NULL);
  if (chip == NULL) return 1;
  dpc31_select(chip);
  CHECK(dpc31_clock_hz(chip) == 48000000u);
  CHECK(dpc31_cycle(chip) == 0);
  Vpc3Write(a, 0x5A);
  CHECK(dpc31_cycle(chip) == 4);
  CHECK(Vpc3Read(a) == 0x5A && dpc31_cycle(chip) == 8);
  CopyToVpc3(CHIP_PTR(a + 16), pattern, 8);
  CHECK(dpc31_cycle(chip) == 8 + 32);
  CopyFromVpc3(back, CHIP_PTR(a + 16), 8);
  CHECK(memcmp(back, pattern, 8) == 0 && dpc31_cycle(chip) == 40 + 32);
  Vpc3MemSet((VPC3_ADR)(a + 32), 0x11, 4);
  CHECK(dpc31_cycle(chip) == 72 + 16);
  CHECK(dpc31_peek(chip, (VPC3_ADR)(a + 35)) == 0x11 && dpc31_cycle(chip) == 88);
  /* equal blocks: 2 reads per byte; a difference in the first byte: 2 reads */
  CHECK(Vpc3MemCmp(CHIP_PTR(a + 16), CHIP_PTR(a + 16), 3) == 0);
  CHECK(dpc31_cycle(chip) == 88 + 24);
  CHECK(Vpc3MemCmp(CHIP_PTR(a + 16), CHIP_PTR(a + 32), 8) == 1);
  CHECK(dpc31_cycle(chip) == 112 + 8);
  /* the handle functions are the same accesses */
  dpc31_write(chip, a, 0xA5);
  CHECK(dpc31_read(chip, a) == 0xA5 && dpc31_cycle(chip) == 128);
  dpc31_memset(chip, (VPC3_ADR)(a + 40), 0x22, 2);
  dpc31_copy_from(chip, back, (VPC3_ADR)(a + 40), 2);
  CHECK(back[0] == 0x22 && back[1] == 0x22 && dpc31_cycle(chip) == 128 + 16);
  dpc31_copy_to(chip, (VPC3_ADR)(a + 40), pattern, 2);
  CHECK(dpc31_memcmp(chip, (VPC3_ADR)(a + 16), (VPC3_ADR)(a + 40), 2) == 0);
  CHECK(dpc31_cycle(chip) == 144 + 8 + 16);

  /* The interrupt line: DX_Out unmasked, raised by a write to Int_Req_Reg (high byte, Intel),
   * then EOI: inactive for 1 us = 48 clocks, active again (docs/timing.md). */
  dpc31_set_irq_callback(chip, on_irq, NULL);
  Vpc3Write(SPC3_Int_Mask_Reg_LO_INTEL, 0xFF);
  Vpc3Write(SPC3_Int_Mask_Reg_HI_INTEL, 0xDF); /* cycle 176 */
  CHECK(dpc31_irq_active(chip) == 0);
  CHECK(dpc31_run_until_irq_change(chip, 100) == 0 && dpc31_cycle(chip) == 276);
  Vpc3Write(SPC3_Int_Req_Reg_HI_INTEL, 0x20); /* active at 280 */
  CHECK(dpc31_irq_active(chip) == 1);
  Vpc3Write(SPC3_Mode_Reg1_S, 0x02); /* EOI: inactive at 284 */
  CHECK(dpc31_irq_active(chip) == 0);
  CHECK(dpc31_run_until_irq_change(chip, 1000) == 1 && dpc31_cycle(chip) == 284 + 48);
  CHECK(n_edges == 3 && edges[0] == 280 && edge_levels[0] == 1 && edges[1] == 284 &&
        edge_levels[1] == 0 && edges[2] == 332 && edge_levels[2] == 1);
  dpc31_run(chip, 1000);
  CHECK(dpc31_cycle(chip) == 1332);
  dpc31_destroy(chip);
  if (failures == 0) printf("hal_c99_test: all checks hold\n");
  return failures == 0 ? 0 : 1;
}
