/*
 * platform.h -- the board under the example driver, ported to the emulator.
 *
 * A serial-mode SPC3/VPC3+ driver keeps everything board-specific here: the address types, the
 * six chip access functions (on the real board SPI transfers in the board's own source file) and
 * the board hooks (reset line, the CPU's interrupt input, a 1 ms delay). The port to dpc31emu
 * changes only this file: the six functions come from the HAL (that source file is left out of
 * the build) and the hooks become the HAL's board hooks. Nothing in the driver itself changes.
 */
#ifndef EXAMPLE_PLATFORM_H
#define EXAMPLE_PLATFORM_H

#include <stdint.h>

/* The driver's address types in serial mode: a chip address, and a chip "pointer" that carries
 * the address in its value. */
#define VPC3_SERIAL_MODE 1
#define VPC3_ADR uint16_t
#define VPC3_UNSIGNED8_PTR uint8_t*
#define MEM_UNSIGNED8_PTR uint8_t*

/* The six access functions (Vpc3Read & co.) and the board hooks: from the emulator. */
#include "dpc31/dpc31_firmware.h"
#include "dpc31/dpc31_hal.h"

/* A chip address as a chip pointer. The 80C32's HAL header (firmware/mcs51, docs/cpu.md) has its
 * own, through an __xdata pointer: SDCC warns when an integer becomes a generic pointer. */
#ifdef CHIP_PTR
#define VPC3_PTR(adr) CHIP_PTR(adr)
#else
#define VPC3_PTR(adr) ((VPC3_UNSIGNED8_PTR)(uintptr_t)(adr))
#endif

#define VPC3_RESET() dpc31_board_reset(1)
#define VPC3_CLEAR_RESET() dpc31_board_reset(0)
#define ENABLE_VPC3_INT() dpc31_board_int_enable(1)
#define DISABLE_VPC3_INT() dpc31_board_int_enable(0)
#define Vpc3Wait_1ms() dpc31_board_wait_1ms()

/* The module's LEDs and output terminals (dpc31_port_write on the emulator). */
#define BOARD_OUTPUT(port, value) dpc31_port_write((port), (value))

#endif /* EXAMPLE_PLATFORM_H */
