/*
 * dpc31_hal.h for the 80C32 (SDCC): the HAL's access functions as a real 8051 driver has them.
 * The chip sits in XDATA at DPC31_XDATA_BASE (the board's chip select, 4 KB window; Intel mode
 * on the 80C32's multiplexed bus); every access is one MOVX through an __xdata pointer, and the
 * block functions loop over them (hal51.c). The firmware's module outputs (dpc31_port_write) go
 * to an output latch in XDATA at DPC31_PORT_LATCH + port, outside the chip's window. This header
 * stands ahead of include/dpc31/dpc31_hal.h on the target's include path (firmware/CMakeLists.txt);
 * the firmware sources are the host's, unchanged. docs/cpu.md, "The HAL on the 80C32".
 *
 * Vpc3Read and Vpc3Write are real functions (hal51.c), with the host's prototypes, so a driver's
 * own declarations of the six compile next to them (docs/bring-up.md). A firmware that declares
 * neither of the two may define DPC31_HAL_MOVX (DO4 and CNT2 do): then they are macros, the MOVX
 * in place: a read at a constant address 4 machine cycles instead of 36, a write 5 instead of 44
 * (docs/cpu.md).
 */
#ifndef DPC31_HAL_H
#define DPC31_HAL_H

#include <stdint.h>

#ifndef DPC31_XDATA_BASE
#define DPC31_XDATA_BASE 0x8000u
#endif
#ifndef DPC31_PORT_LATCH
#define DPC31_PORT_LATCH 0x4000u
#endif

#define DPC31_XBYTE(a) (*(volatile __xdata uint8_t*)(uint16_t)(DPC31_XDATA_BASE + (uint16_t)(a)))

#ifdef DPC31_HAL_MOVX
#define Vpc3Read(wAddress) DPC31_XBYTE(wAddress)
#define Vpc3Write(wAddress, bData) (DPC31_XBYTE(wAddress) = (bData))
#else
uint8_t Vpc3Read(uint16_t wAddress);
void Vpc3Write(uint16_t wAddress, uint8_t bData);
#endif
#define dpc31_port_write(port, value) \
  (*(volatile __xdata uint8_t*)(uint16_t)(DPC31_PORT_LATCH + (port)) = (uint8_t)(value))

/* The drivers' chip "pointer": the chip address as an XDATA pointer's value. */
#define CHIP_PTR(a) ((uint8_t*)(__xdata uint8_t*)(uint16_t)(a))

/* A chip "pointer" carries the chip address in its low 16 bits (the 8051 generic pointer). */
void CopyToVpc3(uint8_t* pToVpc3Memory, uint8_t* pLocalMemory, uint16_t wLength);
void CopyFromVpc3(uint8_t* pLocalMemory, uint8_t* pToVpc3Memory, uint16_t wLength);
void Vpc3MemSet(uint16_t wAddress, uint8_t bValue, uint16_t wLength);
uint8_t Vpc3MemCmp(uint8_t* pToVpc3Memory1, uint8_t* pToVpc3Memory2, uint16_t wLength);

#endif /* DPC31_HAL_H */
