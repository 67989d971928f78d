/* hal51.c -- the HAL's block functions on the 80C32: loops of MOVX to the chip's window
 * (dpc31/dpc31_hal.h of this folder). */
#include "dpc31/dpc31_hal.h"

#define CHIP_ADR(p) ((uint16_t)(uintptr_t)(p))

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
