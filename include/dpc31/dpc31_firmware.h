/*
 * dpc31_firmware.h -- a firmware as a run-time plug-in (docs/bring-up.md): the descriptor a
 * shared library exports, the board hooks the firmware calls, and a C host that runs one.
 *
 * Usable from C99 and C++. A plug-in is a shared library that defines one dpc31_firmware and
 * exports it with DPC31_FIRMWARE_EXPORT; `dpc31 run` (scenario header `firmware ./libmine.so`)
 * and `dpc31 bridge --firmware ./libmine.so` load it with dlopen, look up the symbol
 * DPC31_FIRMWARE_SYMBOL, and check abi_version and the required fields before anything runs
 * (one line and exit 2 if a check fails).
 *
 * The firmware reaches the chip through the C HAL (dpc31_hal.h: Vpc3Read & co.,
 * dpc31_port_write) and the board hooks below. Those functions belong to the host process (the
 * dpc31 program, or libdpc31emu.so that a C host links): a plug-in links no library of ours and
 * leaves them undefined (CMake: dpc31emu::firmware; pkg-config: --cflags only).
 *
 * How the host runs it, on the host CPU of docs/bring-up.md section 4: init() once, as main()'s
 * set-up; then main_step() over and over (main()'s loop) while no interrupt is being served; the
 * ISR whenever X/INT is active and the board's interrupt input is enabled, preempting the main
 * loop between two of its bus accesses. Every bus access costs its 4 clocks; a main_step() pass
 * takes at least 1 us of chip time (the rest of the microsecond: the loop's own instructions).
 */
#ifndef DPC31_FIRMWARE_H_
#define DPC31_FIRMWARE_H_

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The version of this descriptor layout; a host refuses a plug-in built against another one. */
#define DPC31_FIRMWARE_ABI_VERSION 1u
/* The one symbol a plug-in exports: a const pointer to its descriptor. */
#define DPC31_FIRMWARE_SYMBOL "dpc31_firmware_descriptor"

/* What the board tells the firmware at init: which chip it is wired to and the station address
 * from its address switch. */
typedef struct dpc31_board {
  int profile;  /* DPC31_PROFILE_SPC3, _VPC3PLUS or _DPC31 (dpc31_regs.h) */
  int motorola; /* 1: Motorola byte order on the bus */
  uint8_t station_address;
} dpc31_board;

typedef struct dpc31_firmware {
  uint32_t abi_version;     /* DPC31_FIRMWARE_ABI_VERSION (required) */
  const char* name;         /* "DO4" (required, not empty) */
  const char* gsd;          /* its GSD file, relative to the plug-in's directory; NULL: none */
  const char* const* ports; /* the module's output port names by number, NULL-terminated;
                               NULL: none (dpc31_port_write) */
  /* main()'s set-up: configure and start the chip, then return (required). */
  void (*init)(const dpc31_board* board);
  /* The X/INT interrupt service routine; NULL: the firmware polls. */
  void (*isr)(void);
  /* One pass of main()'s loop; NULL: the CPU sleeps until the next interrupt. At least one of
   * isr and main_step is required. */
  void (*main_step)(void);
  /* Hardware inputs of the module (counter pulses, events): 0 done, -1 unknown name, -2 value
   * out of range. NULL: the module has none. It runs with no chip selected: it notes the input
   * for the ISR or main loop (a chip access from it is a firmware fault). */
  int (*hw_input)(const char* name, uint32_t value);
  const char* const* hw_inputs; /* their names, NULL-terminated (NULL: none) */
  /* The GSD defaults a master is configured with: Ident_Number, the module's Cfg bytes
   * (required: cfg_len >= 1), input/output lengths, and the user parameter bytes from Set_Prm
   * byte 7 on (Spec_User_Prm_Byte first). */
  uint16_t ident;
  const uint8_t* cfg;
  uint8_t cfg_len;
  uint8_t in_len;
  uint8_t out_len;
  const uint8_t* user_prm;
  uint8_t user_prm_len;
} dpc31_firmware;

#if defined(__GNUC__) || defined(__clang__)
#define DPC31_FIRMWARE_VISIBLE __attribute__((visibility("default")))
#else
#define DPC31_FIRMWARE_VISIBLE
#endif

/* The exported symbol (declared here so that the definition has C linkage in C++ too). */
extern DPC31_FIRMWARE_VISIBLE const dpc31_firmware* const dpc31_firmware_descriptor;

/* In exactly one source file of the plug-in, at file scope:
 *     static const dpc31_firmware kMine = {DPC31_FIRMWARE_ABI_VERSION, "MINE", ...};
 *     DPC31_FIRMWARE_EXPORT(kMine);                                                        */
#define DPC31_FIRMWARE_EXPORT(descriptor) \
  const dpc31_firmware* const dpc31_firmware_descriptor = &(descriptor)

/* --- the board hooks: what the drivers' platform macros do besides the chip --- */

/* The chip's reset line (VPC3_RESET / VPC3_CLEAR_RESET), 1 asserted. The emulated chip starts in
 * its reset state, so a pulse before the firmware starts the chip (DP state Offline) changes
 * nothing; one after the start stops the run with an error (docs/decisions.md). */
void dpc31_board_reset(int asserted);
/* The CPU's interrupt input from X/INT (ENABLE_VPC3_INT / DISABLE_VPC3_INT): 0 masks it. Enabled
 * when the firmware starts. */
void dpc31_board_int_enable(int enabled);
/* Vpc3Wait_1ms: 1 ms of chip time passes (clock / 1000 clocks) with no bus access; an enabled
 * interrupt is served meanwhile, in init too. */
void dpc31_board_wait_1ms(void);

/* --- a C host: load a plug-in and run it on a chip --- */

/* Loads a plug-in (dlopen) and checks its descriptor. NULL on failure, with one line (the
 * reason) in err. The library stays loaded until the process ends. */
const dpc31_firmware* dpc31_firmware_load(const char* path, char* err, size_t err_size);

/* A module: a chip (profile "spc3", "vpc3plus" or "dpc31", Intel or Motorola bus) with the
 * firmware on its host CPU at a station address of 0..125. Create runs init(); NULL for an
 * unknown profile, a descriptor that fails its checks or an address above 125. Every module is an
 * instance of its own: a plug-in that keeps its state in globals runs in a private copy of its
 * library per module, loaded afresh for it (its constructors run, its globals start as the file
 * gives them) and unloaded with it (docs/firmware.md, "Instances": a C++ plug-in's template or
 * inline statics are shared by every copy). NULL also when that copy cannot be loaded (no file
 * descriptor left, for one). */
typedef struct dpc31_module dpc31_module;
dpc31_module* dpc31_module_create(const char* profile, int motorola, const dpc31_firmware* fw,
                                  uint8_t station_address);
void dpc31_module_destroy(dpc31_module* module);
/* Runs the chip and the firmware for `cycles` clocks. 0 ok; -1 the firmware stopped the run
 * (dpc31_module_error says why; the module cannot run on). */
int dpc31_module_run(dpc31_module* module, uint64_t cycles);
const char* dpc31_module_error(const dpc31_module* module);
uint64_t dpc31_module_cycle(const dpc31_module* module);
/* Debugger access to the chip: no time passes, no side effects. */
uint8_t dpc31_module_peek(const dpc31_module* module, uint16_t addr);
/* A port's last written value (0 before the first write); -1 for an unknown name. */
int64_t dpc31_module_port(const dpc31_module* module, const char* name);

#ifdef __cplusplus
}
#endif

#endif /* DPC31_FIRMWARE_H_ */
