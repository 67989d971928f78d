/* echo.c -- ECHO, a DP slave on the DPC31's own C31 core (docs/dpc31.md, "The C31", "ECHO on the
 * C31"): it starts the DPC31, accepts Set_Prm and Chk_Cfg, and in Data_Exchange hands the outputs
 * of each telegram back as the inputs of the next one.
 *
 * The C31's XDATA is the chip's own address space ("the interface is identical in both cases",
 * DPC31 p.12), so every register and cell is one MOVX through an __xdata pointer, Intel byte
 * order. Its INT0 is the C31's interrupt controller, level-triggered. A minimal driver written for
 * this chip, not firmware/dps: dps.c is 11.2 KB of code for the 80C32 (three chips, DPV1), the
 * code area holds at most 5.9 KB (docs/decisions.md).
 *
 * Memory plan (docs/dpc31.md): the buffers one 32-byte segment each from the user area's first
 * segment (08A0h) to 0A9Fh; the code (the scenario's code=, 1000h) above them; no XDATA variables
 * (small model: the echo, the locals and the stack are in the C31's internal RAM). */
#include <8052.h>
#include <stdint.h>

#include "dpc31/dpc31_regs.h"

#define CELL(a) (*(volatile __xdata uint8_t*)(uint16_t)(a))
#define SEGMENT(seg) ((volatile __xdata uint8_t*)(uint16_t)((uint16_t)(seg) << DPC31_SEGMENT_SHIFT))
#define HI(mask) ((uint8_t)((mask) >> 8))

#define ECHO_IDENT 0x0C31u
#define ECHO_LEN 2u    /* output bytes, echoed as as many input bytes */
#define ECHO_CFG 0x31u /* one identifier: input and output (bits 5:4 = 11), 2 bytes (3:0 = 1) */
/* The 7 standard bytes and byte 13, "permanently reserved for the DPC31" (p.26): no user
 * parameters, so a longer Set_Prm is not this slave's. */
#define ECHO_PRM_MAX 8u
#define STD_DIAG 6u
#define RESULT_CONFLICT 0x01u /* User_Prm/Cfg_Data_(Not_)Okay: 01 conflict, check again */
#define MAC_START 0x10u       /* request code, Table 5.1-3 */

/* The buffer segments, from the user area's first (45h). */
enum {
  SEG_DOUT = DPC31_USER_BASE >> DPC31_SEGMENT_SHIFT, /* Dout 1..3: 45h..47h */
  SEG_DIN = SEG_DOUT + 3,                            /* Din 1..3: 48h..4Ah */
  SEG_DOUT_C = SEG_DIN + 3,                          /* the clear buffer C: 4Bh */
  SEG_DIAG = SEG_DOUT_C + 1,                         /* Diag 1, 2: 4Ch, 4Dh */
  SEG_AUX = SEG_DIAG + 2,                            /* Aux 1, 2: 4Eh, 4Fh */
  SEG_PRM = SEG_AUX + 2,                             /* 50h */
  SEG_CFG = SEG_PRM + 1,                             /* 51h */
  SEG_READ_CFG = SEG_CFG + 1,                        /* 52h */
  SEG_INSTQ = SEG_READ_CFG + 1,                      /* 53h: Instruction_Queue, 2 entries */
  SEG_INDQ = SEG_INSTQ + 1                           /* 54h: Indication_Queue, 2 entries */
};
#define AUX_LEN 32u /* Set_Prm and Chk_Cfg up to a segment; the checks below say what is taken */

/* Interrupts served: all three in Int_Reg's high byte. */
#define SERVED                                                               \
  (DPC31_Int_Req_Reg_New_Prm_Data_Msk | DPC31_Int_Req_Reg_New_Cfg_Data_Msk | \
   DPC31_Int_Req_Reg_DX_Out_Msk)

static uint8_t echo[ECHO_LEN]; /* the outputs last fetched: the next inputs */

static void fill(uint8_t seg, uint8_t n) {
  volatile __xdata uint8_t* p = SEGMENT(seg);
  while (n--) *p++ = 0x00;
}

/* The echo into the Din buffer the user owns (Din_Buffer_SM U), then U -> N (User_New_Din_Cmd):
 * the chip sends it with the next Data_Exchange answer. */
static void hand_over(void) {
  const uint8_t u = (uint8_t)(CELL(DPC31_Din_Buffer_SM) >> 4) & (DPC31_Din_Buffer_SM_U_Msk >> 4);
  volatile __xdata uint8_t* in;
  uint8_t k;
  if (u == 0) return;
  in = SEGMENT(CELL(DPC31_R_Din_Buf_Ptr1 - 1u + u));
  for (k = 0; k < ECHO_LEN; ++k) in[k] = echo[k];
  (void)CELL(DPC31_User_New_Din_Cmd);
}

/* New_Prm_Data: the ASIC checked ident, lock and length >= 7 (p.26); the user's part is that
 * there are no user parameters. A Set_Prm arriving during the check makes the verdict read
 * return a conflict: check the new one. */
static void set_prm(void) {
  uint8_t ok;
  do {
    ok = CELL(DPC31_R_Len_Prm_Data) <= ECHO_PRM_MAX;
  } while ((CELL(ok ? DPC31_User_Prm_Data_Okay : DPC31_User_Prm_Data_Not_Okay) &
            DPC31_User_Prm_Data_Okay_Result_Msk) == RESULT_CONFLICT);
}

/* New_Cfg_Data: the master's configuration must be ECHO_CFG; with it accepted the echo goes into
 * the input buffer at once, so the first Data_Exchange answers with defined inputs. */
static void chk_cfg(void) {
  uint8_t ok, result;
  do {
    ok = CELL(DPC31_R_Len_Cfg_Data) == 1u && *SEGMENT(CELL(DPC31_R_Cfg_Buf_Ptr)) == ECHO_CFG;
    result = CELL(ok ? DPC31_User_Cfg_Data_Okay : DPC31_User_Cfg_Data_Not_Okay) &
             DPC31_User_Cfg_Data_Okay_Result_Msk;
  } while (result == RESULT_CONFLICT);
  if (ok && result == 0u) hand_over();
}

/* DX_Out: acknowledged before the fetch, so that outputs arriving after it raise a new call; the
 * buffer N -> U (User_New_Dout_Cmd), its bytes are the echo. U_Buffer_Cleared: the chip cleared
 * them (Leave_Master, a DP watchdog expiry), or a Clear_Data handed the user the clear buffer C by
 * exchanging the pointer cells of C and U; then the old U is the new C and must hold the
 * substitute values, zeros, before the next clear (seed 003). */
static void dx_out(void) {
  uint8_t r, k;
  volatile __xdata uint8_t* out;
  CELL(DPC31_Int_Ack_Reg_HI_INTEL) = HI(DPC31_Int_Req_Reg_DX_Out_Msk);
  r = CELL(DPC31_User_New_Dout_Cmd);
  if ((r & DPC31_User_New_Dout_Cmd_State_U_Buffer_Msk) == 0) return;
  out = SEGMENT(CELL(DPC31_R_Dout_Buf_Ptr1 - 1u + (r & DPC31_User_New_Dout_Cmd_Ind_U_Buffer_Msk)));
  for (k = 0; k < ECHO_LEN; ++k) echo[k] = out[k];
  if (r & DPC31_User_New_Dout_Cmd_U_Buffer_Cleared_Msk)
    fill(CELL(DPC31_R_Dout_Buf_Ptr_C), ECHO_LEN);
  hand_over();
}

void c31_isr(void) __interrupt(0) {
  const uint8_t ir = CELL(DPC31_Int_Reg_HI_INTEL);
  /* "the user must follow the sequence Set_Param and then Check_Config acknowledgement" (p.28) */
  if (ir & HI(DPC31_Int_Req_Reg_New_Prm_Data_Msk)) set_prm();
  if (ir & HI(DPC31_Int_Req_Reg_New_Cfg_Data_Msk)) chk_cfg();
  if (ir & HI(DPC31_Int_Req_Reg_DX_Out_Msk)) dx_out();
  CELL(DPC31_Mode_Reg1_S) = DPC31_Mode_Reg1_S_EOI_Msk;
}

static void init(void) {
  uint8_t k;
  CELL(DPC31_Int_Mask_Reg_LO_INTEL) = (uint8_t)~SERVED;
  CELL(DPC31_Int_Mask_Reg_HI_INTEL) = HI(~SERVED);
  CELL(DPC31_Mode_Reg0_HI_INTEL) = HI(DPC31_Mode_Reg0_DP_Mode_Msk); /* EOI after 1 us */
  CELL(DPC31_WD_Baud_Control_Val) = 0x10;                           /* Baud_Control 16 x 10 ms */
  CELL(DPC31_MinTSDR_Val) = 11;                                     /* bit times */
  CELL(DPC31_R_TS_Adr) = P1;                                        /* the address switch */
  CELL(DPC31_R_Real_No_Add_Change) = 0xFF; /* the switch's address; SAP55 off (SSA_Buf_Ptr 00h) */
  CELL(DPC31_R_Ident_Low) = (uint8_t)ECHO_IDENT;
  CELL(DPC31_R_Ident_High) = (uint8_t)(ECHO_IDENT >> 8);
  CELL(DPC31_R_Len_Dout_Buf) = ECHO_LEN;
  CELL(DPC31_R_Len_Din_Buf) = ECHO_LEN;
  for (k = 0; k < 3; ++k) {
    CELL(DPC31_R_Dout_Buf_Ptr1 + k) = SEG_DOUT + k;
    CELL(DPC31_R_Din_Buf_Ptr1 + k) = SEG_DIN + k;
  }
  CELL(DPC31_R_Dout_Buf_Ptr_C) = SEG_DOUT_C;
  fill(SEG_DOUT_C, ECHO_LEN); /* the substitute values of a clear: zeros */
  for (k = 0; k < 2; ++k) {
    CELL(DPC31_R_Len_Diag_Buf1 + k) = STD_DIAG; /* the six standard bytes, no user diag */
    CELL(DPC31_R_Diag_Buf_Ptr1 + k) = SEG_DIAG + k;
    fill(SEG_DIAG + k, 1); /* byte 0: no Ext_Diag, no Stat_Diag */
    CELL(DPC31_R_Len_Cntrl_Buf1 + k) = AUX_LEN;
    CELL(DPC31_R_Aux_Buf_Ptr1 + k) = SEG_AUX + k;
  }
  CELL(DPC31_R_Prm_Buf_Ptr) = SEG_PRM;
  CELL(DPC31_R_Cfg_Buf_Ptr) = SEG_CFG;
  CELL(DPC31_R_Read_Cfg_Buf_Ptr) = SEG_READ_CFG;
  CELL(DPC31_R_Len_Read_Cfg_Data) = 1;
  *SEGMENT(SEG_READ_CFG) = ECHO_CFG; /* Get_Cfg's answer */
  CELL(DPC31_IndQ_Base) = SEG_INDQ;
  CELL(DPC31_IndQ_Len) = 2;
  CELL(DPC31_InstQ_Base) = SEG_INSTQ;
  CELL(DPC31_InstQ_Len) = 2;
  /* MAC_Start (p.22): the entry, then InstQ_Wr past it; the MAC takes it in that write. */
  SEGMENT(SEG_INSTQ)[0] = MAC_START;
  SEGMENT(SEG_INSTQ)[1] = 0x00;
  CELL(DPC31_InstQ_Wr) = 1;
}

void main(void) {
  init();
  IT0 = 0; /* INT0 level-triggered: the controller's output stays active until EOI */
  EX0 = 1;
  EA = 1;
  for (;;) PCON |= IDL; /* idle until the next interrupt */
}
