/* hal51.c -- the HAL's access functions on the 80C32: MOVX to the chip's window, the block
 * functions loops of them (dpc31/dpc31_hal.h of this folder). With DPC31_HAL_MOVX the byte
 * accesses are that header's macros instead. */
#include "dpc31/dpc31_hal.h"

#define CHIP_ADR(p) ((uint16_t)(uintptr_t)(p))

#ifndef DPC31_HAL_MOVX
uint8_t Vpc3Read(uint16_t wAddress) { return DPC31_XBYTE(wAddress); }

void Vpc3Write(uint16_t wAddress, uint8_t bData) { DPC31_XBYTE(wAddress) = bData; }
#endif

void CopyToVpc3(uint8_t* pToVpc3Memory, uint8_t* pLocalMemory, uint16_t wLength) {
  volatile __xdata uint8_t* dst = &DPC31_XBYTE(CHIP_ADR(pToVpc3Memory));
  while (wLength--) *dst++ = *pLocalMemory++;
}

void CopyFromVpc3(uint8_t* pLocalMemory, uint8_t* pToVpc3Memory, uint16_t wLength) {
  volatile __xdata uint8_t* src = &DPC31_XBYTE(CHIP_ADR(pToVpc3Memory));
  while (wLength--) *pLocalMemory++ = *src++;
}

void Vpc3MemSet(uint16_t wAddress, uint8_t bValue, uint16_t wLength) {
  volatile __xdata uint8_t* dst = &DPC31_XBYTE(wAddress);
  while (wLength--) *dst++ = bValue;
}

uint8_t Vpc3MemCmp(uint8_t* pToVpc3Memory1, uint8_t* pToVpc3Memory2, uint16_t wLength) {
  volatile __xdata uint8_t* a = &DPC31_XBYTE(CHIP_ADR(pToVpc3Memory1));
  volatile __xdata uint8_t* b = &DPC31_XBYTE(CHIP_ADR(pToVpc3Memory2));
  while (wLength--) {
    if (*a++ != *b++) return 1;
  }
  return 0;
}
