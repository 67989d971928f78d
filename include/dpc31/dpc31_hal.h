/*
 * dpc31_hal.h -- the C HAL: host-built firmware against the emulated SPC3 / VPC3+ / DPC31.
 *
 * Usable from C99 and C++. Two layers:
 *
 *  1. A chip handle (dpc31_create ... dpc31_destroy) with byte access, block copy, memset and
 *     memcmp on chip RAM, the clock and the interrupt line.
 *  2. The six access functions of the public SPC3/VPC3+ drivers, with their names and
 *     signatures (Vpc3Read, Vpc3Write, CopyToVpc3, CopyFromVpc3, Vpc3MemSet, Vpc3MemCmp). They
 *     act on the chip selected for the calling thread (dpc31_select), so a driver ports by
 *     deleting its own versions of exactly these six (docs/bring-up.md).
 *
 * Every access costs the modelled bus cycles (4 chip clocks, docs/timing.md) and takes effect at
 * the end of the access. Chip addresses are plain 16-bit byte offsets, as in the drivers'
 * VPC3_SERIAL_MODE. The header uses only standard types: the drivers' own platform.h #defines
 * uint16_t (uint16_t), VPC3_UNSIGNED8_PTR and MEM_UNSIGNED8_PTR (uint8_t *), and the six
 * prototypes below are what those expand to, so both declarations agree. A chip pointer
 * (VPC3_UNSIGNED8_PTR) carries the chip address, 0x0000..0xFFFF, in its value.
 */
#ifndef DPC31_HAL_H
#define DPC31_HAL_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dpc31_chip dpc31_chip;

/* --- the chip handle --- */

/* profile: "spc3", "vpc3plus" or "dpc31"; motorola: 0 = Intel byte order (XINT low active
 * by default), 1 = Motorola. Returns NULL for an unknown profile. */
dpc31_chip* dpc31_create(const char* profile, int motorola);
/* The same with the VPC3+ variant: "b", "c" or "s" (Status_Reg bits 15..12 read Bh, Ch, Eh,
 * the ASIC type the Profichip drivers check); NULL = "c". Returns NULL for an unknown profile
 * or variant, or a variant with a profile other than "vpc3plus". */
dpc31_chip* dpc31_create_variant(const char* profile, const char* variant, int motorola);
/* Frees the chip; NULL does nothing (as free). It deselects the chip on the calling thread only:
 * a thread that selected it must deselect it (dpc31_select(NULL)) before it is destroyed, or its
 * next Vpc3Read & co. use freed memory, unnoticed. A handle destroyed twice, or used after its
 * destroy, is freed memory too: neither can be detected. */
void dpc31_destroy(dpc31_chip* chip);

/* A NULL handle to any of the functions below (and dpc31_set_*_callback) is a programming error:
 * the error handler gets "FN called with a NULL chip handle" (dpc31_set_error_handler). */

uint8_t dpc31_read(dpc31_chip* chip, uint16_t addr);
void dpc31_write(dpc31_chip* chip, uint16_t addr, uint8_t value);
void dpc31_copy_to(dpc31_chip* chip, uint16_t dst, const uint8_t* src, uint16_t len);
void dpc31_copy_from(dpc31_chip* chip, uint8_t* dst, uint16_t src, uint16_t len);
void dpc31_memset(dpc31_chip* chip, uint16_t addr, uint8_t value, uint16_t len);
/* 0 when the two blocks of chip memory are equal, 1 when not (Vpc3MemCmp's convention). */
uint8_t dpc31_memcmp(dpc31_chip* chip, uint16_t a, uint16_t b, uint16_t len);

/* Debugger access: no time passes, no side effects. */
uint8_t dpc31_peek(const dpc31_chip* chip, uint16_t addr);

/* --- time and the interrupt line --- */
void dpc31_run(dpc31_chip* chip, uint64_t cycles);
/* Runs at most max_cycles; stops right after the interrupt line changed (returns 1) or when
 * max_cycles have passed (returns 0). */
int dpc31_run_until_irq_change(dpc31_chip* chip, uint64_t max_cycles);
uint64_t dpc31_cycle(const dpc31_chip* chip);
uint32_t dpc31_clock_hz(const dpc31_chip* chip);
/* The interrupt is active (independent of the X/INT polarity in Mode_Reg0). */
int dpc31_irq_active(const dpc31_chip* chip);
/* Called on every change of the interrupt line, with the cycle of the change. */
typedef void (*dpc31_irq_fn)(void* user, uint64_t cycle, int active);
void dpc31_set_irq_callback(dpc31_chip* chip, dpc31_irq_fn fn, void* user);
/* dpc31 port PB3 (C31_Control.Enable_DX_Out_Port: DX_Out of a Global_Control with Sync and
 * without Unsync), 1 high;
 * the callback gets (user, cycle, level) on every change. */
int dpc31_pb3(const dpc31_chip* chip);
void dpc31_set_pb3_callback(dpc31_chip* chip, dpc31_irq_fn fn, void* user);

/* --- the driver-shaped access functions --- */

/* The chip Vpc3Read & co. act on for the calling thread (NULL: none). Each thread has its own
 * selection; see dpc31_destroy for a chip selected on another thread. */
void dpc31_select(dpc31_chip* chip);

uint8_t Vpc3Read(uint16_t wAddress);
void Vpc3Write(uint16_t wAddress, uint8_t bData);
void CopyToVpc3(uint8_t* pToVpc3Memory, uint8_t* pLocalMemory, uint16_t wLength);
void CopyFromVpc3(uint8_t* pLocalMemory, uint8_t* pToVpc3Memory, uint16_t wLength);
void Vpc3MemSet(uint16_t wAddress, uint8_t bValue, uint16_t wLength);
uint8_t Vpc3MemCmp(uint8_t* pToVpc3Memory1, uint8_t* pToVpc3Memory2, uint16_t wLength);

/* --- board support: what the module does besides the chip --- */

/* The module's own outputs (digital outputs, LEDs): firmware writes a port; the host sees the
 * value with the cycle of the write (the end of the firmware's last bus access). */
void dpc31_port_write(unsigned port, uint32_t value);
typedef void (*dpc31_port_fn)(void* user, uint64_t cycle, unsigned port, uint32_t value);
void dpc31_set_port_callback(dpc31_chip* chip, dpc31_port_fn fn, void* user);

/* Calling Vpc3Read & co. (or dpc31_port_write) with no chip selected, or a block function with a
 * non-zero length and a NULL local buffer, a local buffer at a chip address (below 0x10000: the
 * two pointers swapped) or a chip pointer beyond 0xFFFF, is a programming error: the handler
 * gets a message; the default prints it to stderr and aborts. The handler must not return (the access cannot be
 * made): exit or longjmp out of it; one that returns gets a line on stderr saying so and the
 * process aborts. A longjmp out of it leaks nothing (the message is in a buffer of the calling
 * thread, valid until its next error). NULL restores the default. A firmware run by a host of the
 * emulator (the dpc31 program, the Python module, dpc31_module_*) is a firmware fault instead: the
 * host reports the message as its error (docs/bring-up.md). */
typedef void (*dpc31_error_fn)(const char* message);
void dpc31_set_error_handler(dpc31_error_fn fn);

#ifdef __cplusplus
}
#endif

#endif /* DPC31_HAL_H */
