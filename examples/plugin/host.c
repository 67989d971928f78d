/* host.c -- a C host for a firmware plug-in, on the installed package only: load the plug-in,
 * put it on an emulated VPC3+ (its init runs), let 150 ms of chip time pass without a master,
 * and report what the firmware did. Usage: example_host ./libexample.so */
#include <stdio.h>

#include "dpc31/dpc31_firmware.h"
#include "dpc31/dpc31_regs.h"

int main(int argc, char** argv) {
  char err[512];
  const dpc31_firmware* fw;
  dpc31_module* m;
  uint64_t start;
  uint8_t status;
  if (argc != 2) {
    fprintf(stderr, "usage: %s PLUGIN.so\n", argv[0]);
    return 2;
  }
  fw = dpc31_firmware_load(argv[1], err, sizeof err);
  if (fw == NULL) {
    fprintf(stderr, "example_host: %s\n", err);
    return 2;
  }
  m = dpc31_module_create("vpc3plus", 0, fw, 5);
  start = m != NULL ? dpc31_module_cycle(m) : 0; /* init has run */
  if (m == NULL || dpc31_module_run(m, 150u * 48000u) != 0) {
    fprintf(stderr, "example_host: %s\n", m != NULL ? dpc31_module_error(m) : "no module");
    return 1;
  }
  status = dpc31_module_peek(m, VPC3_Status_Reg_LO_INTEL);
  /* Status_Reg bit 0: Offline/Passive_Idle (1: started); bits 5..4: the DP state, 0 Wait_Prm. */
  printf("%s on vpc3plus: %llu ms after init, started %u, DP state %u, led %lld\n", fw->name,
         (unsigned long long)((dpc31_module_cycle(m) - start) / 48000u), (unsigned)(status & 1u),
         (unsigned)((status >> 4) & 3u), (long long)dpc31_module_port(m, "led"));
  dpc31_module_destroy(m);
  return 0;
}
