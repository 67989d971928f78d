/* Firmware plug-ins a host must refuse at load (tests/bad_input_test.cpp, FirmwarePlugins), one
 * per defect, selected by a macro (tests/CMakeLists.txt):
 *   BAD_ABI      the descriptor's abi_version is not DPC31_FIRMWARE_ABI_VERSION
 *   NO_INIT      a required field (init) is NULL
 *   BAD_PORT     a port name that is not a word ("out puts")
 *   TWICE_INPUT  a hardware input named twice
 *   NO_EXPORT    no DPC31_FIRMWARE_EXPORT: the well-known symbol is missing
 *   NL_NAME      a name with a newline, which would forge a line of the walk (s33 audit)
 *   UNDEFINED    it calls a function no host provides: dlopen (RTLD_NOW) fails
 *   SPIN         it loads, and its init spins in while(1) without a bus access (the hang guard)
 *   MARK         a valid plug-in whose loading alone (a constructor) creates the file named by
 *                DPC31_PLUGIN_MARK: shows whether a command ran its code
 * (tests/code_security_test.cpp); and two that load and then misuse the HAL, a firmware fault
 * (tests/bad_input_test.cpp, FirmwareFaults):
 *   HAL_INIT     its init calls CopyToVpc3 with a NULL buffer
 *   HAL_ISR      its init raises an interrupt; its ISR calls CopyFromVpc3 with a NULL buffer;
 *                its hardware input "kick" reads the chip, which no host selects for it
 *   HAL_SWAP     its init calls CopyToVpc3 with the two pointers swapped: a host address as the
 *                chip pointer, a chip address (0x40) as the local buffer
 * and one that crashes (a store through a NULL pointer in init), which the host cannot catch: the
 * fatal-signal handler names it and removes the temporaries (tests/bad_input_serve_test.cpp):
 *   CRASH
 *   CRASH_INPUT  its hardware input "crash" stores through a NULL pointer (a crash after the walk
 *                has printed lines)
 * and one whose ISR hangs, so that the guard stops it inside a scenario's step (FirmwarePlugins):
 *   SPIN_ISR     its init raises an interrupt as HAL_ISR's does; its ISR spins in while(1)
 * and one whose hardware input "spin" hangs, which the guard stops inside a scenario's `hw` step as
 * in its ISR, and whose input "wait" calls a board hook that needs the chip (FirmwarePlugins):
 *   SPIN_INPUT   its hw_input spins in while(1) for "spin", calls dpc31_board_wait_1ms for "wait",
 *                releases the reset line (dpc31_board_reset(0)) for "release"
 * and one that shows whether a module starts with fresh globals (tests/cpu_test.cpp):
 *   GLOBALS      its init counts its runs in a global and writes the count to its port "boots" */
#include "dpc31/dpc31_firmware.h"
#include "dpc31/dpc31_hal.h"

#ifdef MARK
#include <stdio.h>
#include <stdlib.h>

__attribute__((constructor)) static void mark(void) {
  const char* path = getenv("DPC31_PLUGIN_MARK");
  FILE* f = path != NULL ? fopen(path, "w") : NULL;
  if (f != NULL) fclose(f);
}
#endif

#ifdef UNDEFINED
void no_such_board_function(void);
#endif

#ifdef GLOBALS
static unsigned g_boots;
static const char* const kPorts[] = {"boots", 0};
#define PORTS kPorts
#elif defined(BAD_PORT)
static const char* const kPorts[] = {"outputs", "out puts", 0};
#define PORTS kPorts
#else
#define PORTS 0
#endif

#ifdef CRASH
static volatile unsigned char* volatile g_nowhere; /* NULL, unknown to the compiler */
#endif

#ifndef NO_INIT
static void init(const dpc31_board* board) {
  (void)board;
#ifdef GLOBALS
  dpc31_port_write(0, ++g_boots);
#endif
#ifdef UNDEFINED
  no_such_board_function();
#endif
#ifdef SPIN
  while (1) {
  }
#endif
#ifdef HAL_INIT
  CopyToVpc3((uint8_t*)0x100, 0, 4);
#endif
#ifdef HAL_SWAP
  CopyToVpc3((uint8_t*)(uintptr_t)0x12345678u, (uint8_t*)0x40, 4);
#endif
#ifdef CRASH
  *g_nowhere = 1;
#endif
#if defined(HAL_ISR) || defined(SPIN_ISR)
  /* Int_Mask_Reg all open, Int_Req_Reg's MAC_Reset set (both bytes: either bus mode). */
  Vpc3Write(0x004, 0x00);
  Vpc3Write(0x005, 0x00);
  Vpc3Write(0x000, 0x01);
  Vpc3Write(0x001, 0x01);
#endif
}
#endif

#ifdef HAL_ISR
static void isr(void) { CopyFromVpc3(0, (uint8_t*)0x40, 2); }
static int kick(const char* name, uint32_t value) {
  (void)name;
  (void)value;
  return Vpc3Read(0);
}
static const char* const kInputs[] = {"kick", 0};
#define ISR isr
#define HW_INPUT kick
#define HW_INPUTS kInputs
#elif defined(TWICE_INPUT)
static int kick(const char* name, uint32_t value) {
  (void)name;
  (void)value;
  return 0;
}
static const char* const kInputs[] = {"kick", "event", "kick", 0};
#define HW_INPUT kick
#define HW_INPUTS kInputs
#elif defined(SPIN_ISR)
static void isr(void) {
  while (1) {
  }
}
#define ISR isr
#elif defined(SPIN_INPUT)
static int spin(const char* name, uint32_t value) {
  (void)value;
  if (name[0] == 'w') {
    dpc31_board_wait_1ms();
    return 0;
  }
  if (name[0] == 'r') { /* a released reset line needs no chip */
    dpc31_board_reset(0);
    return 0;
  }
  while (1) {
  }
}
static const char* const kInputs[] = {"spin", "wait", "release", 0};
#define HW_INPUT spin
#define HW_INPUTS kInputs
#elif defined(CRASH_INPUT)
static volatile unsigned char* volatile g_nowhere_later; /* NULL, unknown to the compiler */
static int crash(const char* name, uint32_t value) {
  (void)name;
  (void)value;
  *g_nowhere_later = 1;
  return 0;
}
static const char* const kInputs[] = {"crash", 0};
#define HW_INPUT crash
#define HW_INPUTS kInputs
#endif
#if !defined(HAL_ISR) && !defined(TWICE_INPUT) && !defined(SPIN_INPUT) && !defined(CRASH_INPUT)
#define HW_INPUT 0
#define HW_INPUTS 0
#endif
#ifndef ISR
#define ISR 0
#endif

static void step(void) { (void)Vpc3Read(0); }

static const uint8_t kCfg[] = {0x10};

#ifdef BAD_ABI
#define ABI (DPC31_FIRMWARE_ABI_VERSION + 1u)
#else
#define ABI DPC31_FIRMWARE_ABI_VERSION
#endif
#ifdef NO_INIT
#define INIT 0
#else
#define INIT init
#endif

#ifdef NL_NAME
#define NAME "BAD\n[cycle 1] line 9: expect dp_state Data_Exchange: ok"
#else
#define NAME "BAD"
#endif

static const dpc31_firmware kBad = {ABI,       NAME,   0,    PORTS,       INIT, ISR, step, HW_INPUT,
                                    HW_INPUTS, 0x0001, kCfg, sizeof kCfg, 1,    0,   0,    0};

#ifdef NO_EXPORT
/* A firmware without its export: the descriptor is referenced so that it is not unused. */
const dpc31_firmware* bad_plugin_descriptor(void);
const dpc31_firmware* bad_plugin_descriptor(void) { return &kBad; }
#else
DPC31_FIRMWARE_EXPORT(kBad);
#endif
