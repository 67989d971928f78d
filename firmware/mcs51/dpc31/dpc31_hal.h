/*
 * dpc31_hal.h for the 80C32 (SDCC): the HAL's access functions as a real 8051 driver has them.
 * The chip sits in XDATA at DPC31_XDATA_BASE (the board's chip select, 4 KB window; Intel mode
 * on the 80C32's multiplexed bus), so Vpc3Read / Vpc3Write are single MOVX accesses through an
 * __xdata pointer, and the block functions loop over them (hal51.c). The firmware's module
 * outputs (dpc31_port_write) go to an output latch in XDATA at DPC31_PORT_LATCH + port, outside
 * the chip's window. This header stands ahead of include/dpc31/dpc31_hal.h on the target's
 * include path (firmware/CMakeLists.txt); the firmware sources are the host's, unchanged.
 * docs/cpu.md, "DO4 on the 80C32".
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

#define Vpc3Read(wAddress) DPC31_XBYTE(wAddress)
#define Vpc3Write(wAddress, bData) (DPC31_XBYTE(wAddress) = (bData))
#define dpc31_port_write(port, value) \
  (*(volatile __xdata uint8_t*)(uint16_t)(DPC31_PORT_LATCH + (port)) = (uint8_t)(value))

/* The drivers' chip "pointer": the chip address as an XDATA pointer's value. */
#define CHIP_PTR(a) ((uint8_t*)(__xdata uint8_t*)(uint16_t)(a))

/* A chip "pointer" carries the chip address in its low 16 bits, as on the host. */
void CopyToVpc3(uint8_t* pToVpc3Memory, uint8_t* pLocalMemory, uint16_t wLength);
void CopyFromVpc3(uint8_t* pLocalMemory, uint8_t* pToVpc3Memory, uint16_t wLength);
void Vpc3MemSet(uint16_t wAddress, uint8_t bValue, uint16_t wLength);
uint8_t Vpc3MemCmp(uint8_t* pToVpc3Memory1, uint8_t* pToVpc3Memory2, uint16_t wLength);

#endif /* DPC31_HAL_H */
