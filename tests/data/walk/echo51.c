/* echo51.c: an SPC3 echo slave on an 80C32 board (chip at XDATA 8000h, X/INT on INT0,
 * station address on P1, outputs echoed to inputs, and a copy of output byte 0 on the latch
 * at 4000h). Written from docs/cpu.md and include/dpc31/dpc31_regs.h. */
#include <8052.h>
#include <stdint.h>

#include "dpc31/dpc31_regs.h"

#define BASE 0x8000u
#define CELL(a) (*(volatile __xdata uint8_t*)(uint16_t)(BASE + (a)))
#define SEGP(seg) \
  ((volatile __xdata uint8_t*)(uint16_t)(BASE + ((uint16_t)(seg) << SPC3_SEGMENT_SHIFT)))
#define LATCH(p) (*(volatile __xdata uint8_t*)(uint16_t)(0x4000u + (p)))
#define HI(m) ((uint8_t)((m) >> 8))
#define LEN 2u
#define IDENT 0x0E51u

enum {
  SEG_DOUT = SPC3_USER_BASE >> SPC3_SEGMENT_SHIFT,
  SEG_DIN = SEG_DOUT + 3,
  SEG_DIAG = SEG_DIN + 3,
  SEG_AUX = SEG_DIAG + 2,
  SEG_CFG = SEG_AUX + 8,
  SEG_RCFG = SEG_CFG + 4,
  SEG_PRM = SEG_RCFG + 1
};

#define SERVED                                                             \
  (SPC3_Int_Req_Reg_New_Prm_Data_Msk | SPC3_Int_Req_Reg_New_Cfg_Data_Msk | \
   SPC3_Int_Req_Reg_DX_Out_Msk)

static uint8_t echo[LEN];
volatile uint16_t dx_count;

static void hand_over(void) {
  uint8_t u = (CELL(SPC3_Din_Buffer_SM) >> 4) & 3u, k;
  volatile __xdata uint8_t* in;
  if (u == 0) return;
  in = SEGP(CELL(SPC3_R_Din_Buf_Ptr1 - 1u + u));
  for (k = 0; k < LEN; ++k) in[k] = echo[k];
  (void)CELL(SPC3_New_Din_Buffer_Cmd);
}

void isr(void) __interrupt(0) {
  uint8_t ir = CELL(SPC3_Int_Reg_HI_INTEL), r, k;
  volatile __xdata uint8_t* out;
  if (ir & HI(SPC3_Int_Req_Reg_New_Prm_Data_Msk)) {
    while ((CELL(SPC3_User_Prm_Data_Okay) & 3u) == 1u) {
    }
  }
  if (ir & HI(SPC3_Int_Req_Reg_New_Cfg_Data_Msk)) {
    do r = CELL(SPC3_User_Cfg_Data_Okay) & 3u;
    while (r == 1u);
    if (r == 0) hand_over();
  }
  if (ir & HI(SPC3_Int_Req_Reg_DX_Out_Msk)) {
    CELL(SPC3_Int_Ack_Reg_HI_INTEL) = HI(SPC3_Int_Req_Reg_DX_Out_Msk);
    r = CELL(SPC3_Next_Dout_Buffer_Cmd);
    if (r & SPC3_Next_Dout_Buffer_Cmd_State_U_Buffer_Msk) {
      out = SEGP(CELL(SPC3_R_Dout_Buf_Ptr1 - 1u + (r & 3u)));
      for (k = 0; k < LEN; ++k) echo[k] = out[k];
      LATCH(0) = echo[0];
      ++dx_count;
      hand_over();
    }
  }
  CELL(SPC3_Mode_Reg1_S) = SPC3_Mode_Reg1_S_EOI_Msk;
}

void main(void) {
  uint8_t k;
  CELL(SPC3_Int_Mask_Reg_LO_INTEL) = (uint8_t)~SERVED;
  CELL(SPC3_Int_Mask_Reg_HI_INTEL) = HI(~SERVED);
  CELL(SPC3_Mode_Reg0_HI_INTEL) = HI(SPC3_Mode_Reg0_DP_Mode_Msk);
  CELL(SPC3_WD_Baud_Control_Val) = 0x10;
  CELL(SPC3_MinTSDR_Val) = 11;
  CELL(SPC3_R_TS_Adr) = P1;
  CELL(SPC3_R_Real_No_Add_Change) = 0xFF;
  CELL(SPC3_R_Ident_Low) = (uint8_t)IDENT;
  CELL(SPC3_R_Ident_High) = (uint8_t)(IDENT >> 8);
  CELL(SPC3_R_Len_Dout_Buf) = LEN;
  CELL(SPC3_R_Len_Din_Buf) = LEN;
  for (k = 0; k < 3; ++k) {
    CELL(SPC3_R_Dout_Buf_Ptr1 + k) = SEG_DOUT + k;
    CELL(SPC3_R_Din_Buf_Ptr1 + k) = SEG_DIN + k;
  }
  for (k = 0; k < 2; ++k) {
    CELL(SPC3_R_Len_Diag_Buf1 + k) = 6;
    CELL(SPC3_R_Diag_Buf_Ptr1 + k) = SEG_DIAG + k;
    *SEGP(SEG_DIAG + k) = 0;
    CELL(SPC3_R_Len_Cntrl_Buf1 + k) = 32;
    CELL(SPC3_R_Aux_Buf_Ptr1 + k) = SEG_AUX + 4 * k;
  }
  CELL(SPC3_R_Aux_Buf_Sel) = 0;
  CELL(SPC3_R_Cfg_Buf_Ptr) = SEG_CFG;
  CELL(SPC3_R_Read_Cfg_Buf_Ptr) = SEG_RCFG;
  CELL(SPC3_R_Prm_Buf_Ptr) = SEG_PRM;
  CELL(SPC3_R_Len_Read_Cfg_Data) = 1;
  *SEGP(SEG_RCFG) = 0x31;
  IT0 = 0;
  EX0 = 1;
  EA = 1;
  CELL(SPC3_Mode_Reg1_S) = SPC3_Mode_Reg1_S_Start_SPC3_Msk;
  for (;;) PCON |= IDL;
}
