/*
 * vpc3.h -- the example driver's view of the VPC3+: register addresses in serial mode (Intel
 * byte order: the low byte of a 16-bit register at the lower address), the bits it uses, and the
 * six access functions as the driver declares them (platform.h supplies the types).
 */
#ifndef EXAMPLE_VPC3_H
#define EXAMPLE_VPC3_H

#include "platform.h"

/* Registers (read side / write side where they share an address). */
#define REG_INT_REQ 0x00u    /* 16 bit, read/write */
#define REG_INT_REG 0x02u    /* 16 bit, read: Int_Req AND NOT Int_Mask */
#define REG_INT_ACK 0x02u    /* 16 bit, write */
#define REG_STATUS 0x04u     /* 16 bit, read */
#define REG_INT_MASK 0x04u   /* 16 bit, write */
#define REG_MODE0 0x06u      /* 16 bit, write */
#define REG_DIN_SM 0x08u     /* read */
#define REG_MODE1_SET 0x08u  /* write */
#define REG_NEW_DIN 0x09u    /* read */
#define REG_WD_BAUD 0x0Au    /* write */
#define REG_NEXT_DOUT 0x0Bu  /* read */
#define REG_MIN_TSDR 0x0Bu   /* write */
#define REG_PRM_OK 0x0Eu     /* read */
#define REG_PRM_NOT_OK 0x0Fu /* read */
#define REG_CFG_OK 0x10u     /* read */
#define REG_CFG_NOT_OK 0x11u /* read */
/* The parameter cells. */
#define CELL_TS_ADR 0x16u
#define CELL_USER_WD 0x18u /* 16 bit */
#define CELL_LEN_DOUT 0x1Au
#define CELL_DOUT_PTR 0x1Bu /* three */
#define CELL_LEN_DIN 0x1Eu
#define CELL_DIN_PTR 0x1Fu   /* three */
#define CELL_LEN_DIAG 0x24u  /* two */
#define CELL_DIAG_PTR 0x26u  /* two */
#define CELL_LEN_CNTRL 0x28u /* two */
#define CELL_AUX_SEL 0x2Au
#define CELL_AUX_PTR 0x2Bu /* two */
#define CELL_SSA_PTR 0x2Eu
#define CELL_LEN_PRM 0x2Fu
#define CELL_PRM_PTR 0x30u
#define CELL_LEN_CFG 0x31u
#define CELL_CFG_PTR 0x32u
#define CELL_LEN_READ_CFG 0x33u
#define CELL_READ_CFG_PTR 0x34u
#define CELL_NO_ADD_CHANGE 0x39u
#define CELL_IDENT_LOW 0x3Au
#define CELL_IDENT_HIGH 0x3Bu
/* The user area, in 8-byte segments from here. */
#define USER_BASE 0x40u
#define SEGMENT_SHIFT 3u

/* Interrupt requests. */
#define EV_NEW_PRM 0x0800u
#define EV_NEW_CFG 0x0400u
#define EV_DX_OUT 0x2000u
#define EV_ALL 0xFFFFu
/* Mode_Reg0: DP mode. Mode_Reg1 (set): start, EOI, retrigger the user watchdog. */
#define MODE0_DP 0x0100u
#define MODE1_START 0x01u
#define MODE1_EOI 0x02u
#define MODE1_RES_USER_WD 0x20u
/* The verdict reads' answer when a newer telegram is already waiting. */
#define VERDICT_CONFLICT 0x01u
/* Next_Dout_Buffer_Cmd: the user got a new buffer (bits 1:0 name it). */
#define DOUT_STATE_U 0x04u
/* Status_Reg bits 15..12: the ASIC; C = VPC3+C. Bits 5..4: the DP state. */
#define STATUS_ASIC(s) (((s) >> 12) & 0x0Fu)
#define ASIC_VPC3_C 0x0Cu

/* The six access functions, as the driver declares them. */
uint8_t Vpc3Read(VPC3_ADR wAddress);
void Vpc3Write(VPC3_ADR wAddress, uint8_t bData);
void CopyToVpc3(VPC3_UNSIGNED8_PTR pToVpc3Memory, MEM_UNSIGNED8_PTR pLocalMemory, uint16_t wLength);
void CopyFromVpc3(MEM_UNSIGNED8_PTR pLocalMemory, VPC3_UNSIGNED8_PTR pToVpc3Memory,
                  uint16_t wLength);
void Vpc3MemSet(VPC3_ADR wAddress, uint8_t bValue, uint16_t wLength);
uint8_t Vpc3MemCmp(VPC3_UNSIGNED8_PTR pToVpc3Memory1, VPC3_UNSIGNED8_PTR pToVpc3Memory2,
                   uint16_t wLength);

#endif /* EXAMPLE_VPC3_H */
