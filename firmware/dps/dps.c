/* dps.c -- the DP-slave driver layer (see dps.h). */
#include "dps.h"

#include <string.h>

#include "dpc31/dpc31_pdu.h"
#include "dpc31/dpc31_regs.h"

/* The drivers' serial-mode types, as their platform.h defines them (the HAL uses the plain
 * types): a chip address, and a chip "pointer" that carries the address in its value. */
typedef uint16_t VPC3_ADR;
#ifndef CHIP_PTR /* the target's HAL header may define its own (firmware/mcs51/) */
#define CHIP_PTR(a) ((uint8_t*)(uintptr_t)(a))
#endif

/* The addresses this driver uses, per chip. A driver for one chip would use the macros
 * directly; the examples run on all three, so they pick a table at init. */
struct dps_regmap {
  VPC3_ADR int_req, int_reg, int_ack, status, int_mask, mode0, mode1_s, mode1_r, mode2;
  VPC3_ADR din_sm, new_din, dout_sm, next_dout, diag_sm, new_diag, wd_baud, min_tsdr;
  VPC3_ADR prm_ok, prm_not_ok, cfg_ok, cfg_not_ok, ssa_free;
  VPC3_ADR ts_adr, user_wd, len_dout, dout_ptr[3], len_din, din_ptr[3], dout_ptr_c;
  VPC3_ADR len_diag[2], diag_ptr[2], len_cntrl[2], aux_sel, aux_ptr[2];
  VPC3_ADR len_ssa, ssa_ptr, len_prm, prm_ptr, len_cfg, cfg_ptr, len_read_cfg, read_cfg_ptr;
  VPC3_ADR real_no_add_change, ident_lo, ident_hi, gc_command;
  VPC3_ADR user_base, segment_shift;
};
typedef struct dps_regmap regmap;

#define DPS_REGMAP(P, MODE2, PTR_C, NEW_DIN, NEXT_DOUT, SSA_FREE)                                 \
  {                                                                                               \
    P##_Int_Req_Reg, P##_Int_Reg, P##_Int_Ack_Reg, P##_Status_Reg, P##_Int_Mask_Reg,              \
        P##_Mode_Reg0, P##_Mode_Reg1_S, P##_Mode_Reg1_R, MODE2, P##_Din_Buffer_SM, NEW_DIN,       \
        P##_Dout_Buffer_SM, NEXT_DOUT, P##_Diag_Buffer_SM, P##_New_Diag_Buffer_Cmd,               \
        P##_WD_Baud_Control_Val, P##_MinTSDR_Val, P##_User_Prm_Data_Okay,                         \
        P##_User_Prm_Data_Not_Okay, P##_User_Cfg_Data_Okay, P##_User_Cfg_Data_Not_Okay, SSA_FREE, \
        P##_R_TS_Adr, P##_R_User_WD_Value, P##_R_Len_Dout_Buf,                                    \
        {P##_R_Dout_Buf_Ptr1, P##_R_Dout_Buf_Ptr2, P##_R_Dout_Buf_Ptr3}, P##_R_Len_Din_Buf,       \
        {P##_R_Din_Buf_Ptr1, P##_R_Din_Buf_Ptr2, P##_R_Din_Buf_Ptr3}, PTR_C,                      \
        {P##_R_Len_Diag_Buf1, P##_R_Len_Diag_Buf2}, {P##_R_Diag_Buf_Ptr1, P##_R_Diag_Buf_Ptr2},   \
        {P##_R_Len_Cntrl_Buf1, P##_R_Len_Cntrl_Buf2}, P##_R_Aux_Buf_Sel,                          \
        {P##_R_Aux_Buf_Ptr1, P##_R_Aux_Buf_Ptr2}, P##_R_Len_SSA_Data, P##_R_SSA_Buf_Ptr,          \
        P##_R_Len_Prm_Data, P##_R_Prm_Buf_Ptr, P##_R_Len_Cfg_Data, P##_R_Cfg_Buf_Ptr,             \
        P##_R_Len_Read_Cfg_Data, P##_R_Read_Cfg_Buf_Ptr, P##_R_Real_No_Add_Change,                \
        P##_R_Ident_Low, P##_R_Ident_High, P##_R_GC_Command, P##_USER_BASE, P##_SEGMENT_SHIFT     \
  }

#define NONE 0xFFFFu
/* The DPC31 under its own manual's names: User_New_Din / User_New_Dout (Table 5.2-8) and
 * User_SSA_OK (p.26) are the commands the SPC3 calls New_Din_Buffer_Cmd, Next_Dout_Buffer_Cmd
 * and SSA_Buffer_Free_Cmd. */
static const regmap kMaps[3] = {
    DPS_REGMAP(SPC3, NONE, NONE, SPC3_New_Din_Buffer_Cmd, SPC3_Next_Dout_Buffer_Cmd,
               SPC3_SSA_Buffer_Free_Cmd),
    DPS_REGMAP(VPC3, VPC3_Mode_Reg2, NONE, VPC3_New_Din_Buffer_Cmd, VPC3_Next_Dout_Buffer_Cmd,
               VPC3_SSA_Buffer_Free_Cmd),
    DPS_REGMAP(DPC31, NONE, DPC31_R_Dout_Buf_Ptr_C, DPC31_User_New_Din_Cmd, DPC31_User_New_Dout_Cmd,
               DPC31_User_SSA_OK_Cmd)};

/* The DPC31 takes its requests through the Instruction_Queue and answers through the
 * Indication_Queue (DPC31 p.22, Table 5.1-3, p.31; docs/dpc31.md): 2-byte entries, code then
 * parameter, in rings of DPS_QUEUE_LEN entries (one always stays empty). */
enum { MAC_Start = 0x10u, DPS_User_Wd = 0x20u };
enum { Wd_Reset = 0x00u, Wd_Enable = 0x01u, Wd_Disable = 0x02u, Wd_Expired = 0x03u };
enum { DPS_QUEUE_LEN = 4u };

/* Int_Req_Reg bits, the same in every profile (Indication: the DPC31's only). */
enum {
  MAC_Reset = 0x0001u,
  Go_Leave_Data_Exchange = 0x0002u,
  Baudrate_Detect = 0x0004u,
  WD_DP_Control_Timeout = 0x0008u,
  User_Timer_Clock = 0x0010u,
  Indication = 0x0020u,
  New_Ext_Prm_Data = 0x0040u,
  New_GC_Command = 0x0100u,
  New_SSA_Data = 0x0200u,
  New_Cfg_Data = 0x0400u,
  New_Prm_Data = 0x0800u,
  Diag_Buffer_Changed = 0x1000u,
  DX_Out = 0x2000u
};
enum { Start_SPC3 = 0x01u, EOI = 0x02u, Res_User_WD = 0x20u };
enum { Prm_Conflict = 0x01u };                             /* handshake read result */
enum { State_U_Buffer = 0x04u, U_Buffer_Cleared = 0x08u }; /* Next_Dout_Buffer_Cmd */
enum { DP_Mode = 0x0100u, Spec_Clear_Mode = 0x2000u };     /* Mode_Reg0 */
enum { Ext_Diag = DPC31_DIAG_EXT_DIAG };                   /* diag byte 0 */
enum {
  kDiagMasterAdd = DPC31_DIAG_MASTER_ADD,
  kNoMaster = DPC31_DIAG_NO_MASTER
}; /* diag byte 3: Master_Add */
enum { kStdPrm = 7u, kStdDiag = DPC31_DIAG_STANDARD };

/* The instance every function works on (dps.h, "One instance"): passed on as ME / ME_. On the
 * 80C32 the one static instance, reached by its address. */
#define ME DPS_A(self)
#define ME_ DPS_A_(self)
#ifdef __SDCC
static dps dps_the;
#define self (&dps_the)
#endif

/* DPV1 on the VPC3+ (docs/dpv1.md, docs/firmware.md): a SAP list of four entries, MSAC_C1 (SAP
 * 51) and its alarm SAP (50), the one MSAC_C2 connection (40, Ind_Buf_Ptr[0] 00h while closed:
 * the chip answers RS there) and the MSAC_C2 resource manager (49), each with one buffer that is
 * indication and response buffer at once, as the Profichip driver has it for its MSAC_C1 SAPs.
 * The ISR takes a request on FDL_Ind; the 1 ms task answers it (the master's polls get SC
 * meanwhile); Poll_End_Ind frees the buffer. MSAC_C1 is the locking master's: SAPs 51 and 50
 * open when the chip enters Data_Exchange and take only its address (Request_SA) once the diag
 * buffer names it, any station until then (dpv1_isr). */
/* The connection before the resource manager: an Abort and a new Initiate taken in the same tick
 * close first, then open. */
enum { kDpv1Saps = DPS_DPV1_SAPS, kC1Saps = 2u, kConn = 2u, kRm = 3u };
enum { kFcResponse = DPC31_DPV1_FC_RESPONSE /* DL: response data low */ };
/* MSAC_C2 (IEC 61158-6 type 3; docs/dpv1.md "The master's side"): function numbers, the
 * Initiate request's fixed part (57h, 3 reserved, Send_Timeout, Features_Supported_1 and _2,
 * Profile_Features_Supported, Profile_Ident_Number, S_Type, S_Len, D_Type, D_Len) and its
 * response's (57h, Max_Len_Data_Unit, then the same from Features_Supported on). A Type 0
 * address is API and SCL (2 bytes): the least request is 20 bytes. The Abort the Profichip
 * driver sends for a request it refuses: Instance MSAC_C2 (10h) | FE (invalid request) or IA
 * (invalid address information). */
enum { kIdle = DPC31_DPV1_IDLE, kRmResponse = DPC31_DPV1_RESOURCE_MANAGER };
enum { kInitiate = DPC31_DPV1_INITIATE, kAbort = DPC31_DPV1_ABORT };
enum { kInitiateReq = DPC31_MSAC_C2_INITIATE_REQ_FIXED };
enum { kInitiateRes = DPC31_MSAC_C2_INITIATE_RES_FIXED };
enum { kNegative = DPC31_DPV1_ERROR_BIT, kDecodeDpv1 = DPC31_DPV1_ERROR_DECODE_DPV1 };
enum { kAddrApiScl = DPC31_MSAC_C2_ADDR_LEN_API_SCL, kInitiateReqMin = DPC31_MSAC_C2_INITIATE_MIN };
enum {
  kAddrTypeApiScl = DPC31_MSAC_C2_ADDR_TYPE_API_SCL,
  kSendTimeoutEnd = 6u /* 57h .. low byte */
};
enum { kFeaturesRW = DPC31_MSAC_C2_FEATURES_1_RW };
enum { kAbortFE = DPC31_MSAC_C2_INSTANCE_MSAC_C2 | DPC31_MSAC_C2_ABT_FE };
enum { kAbortIA = DPC31_MSAC_C2_INSTANCE_MSAC_C2 | DPC31_MSAC_C2_ABT_IA };
enum { kInvalidParameter = DPC31_DPV1_INVALID_PARAMETER, kResourceBusy = DPC31_DPV1_RESOURCE_BUSY };
enum { kFeatureNotSupported = DPC31_DPV1_FEATURE_NOT_SUPPORTED };
/* dps.c1_waiting: 0 the C1 SAPs take only the master's address; else they wait for it, open to any
 * station in Data_Exchange (kC1Any) or closed outside it (kC1Closed). */
enum { kC1Any = 1, kC1Closed = 2 };
/* dps.c2_busy; kC2Closing: the connection's buffer holds a refused Initiate's answer, and the
 * connection closes once it is sent. */
enum { kC2Open = 1, kRmWaits = 2, kC2Closing = 4 };
/* How long a resource manager's response that opened nothing waits for its poll (10 ms units): the
 * GSD's C2_Response_Timeout, the time a master waits for it. */
enum { kRmResponseTimeout = 100u };
enum { FDL_Ind = VPC3_Int_Req_Reg_FDL_Ind_Msk, Poll_End_Ind = VPC3_Int_Req_Reg_Poll_End_Ind_Msk };
static const uint8_t kDpv1Sap[kDpv1Saps] = {DPS_SAP_C1, DPS_SAP_ALARM, DPS_SAP_C2, DPS_SAP_C2_RM};

/* 16-bit registers go over the 8-bit bus byte by byte; which address holds the low byte
 * depends on the bus mode (Intel: the lower address). */
static void write16(DPS_P_(dps) VPC3_ADR a, uint16_t v) {
  Vpc3Write(self->motorola ? (VPC3_ADR)(a + 1u) : a, (uint8_t)v);
  Vpc3Write(self->motorola ? a : (VPC3_ADR)(a + 1u), (uint8_t)(v >> 8));
}

static uint16_t read16(DPS_P_(dps) VPC3_ADR a) {
  const uint8_t lo = Vpc3Read(self->motorola ? (VPC3_ADR)(a + 1u) : a);
  return (uint16_t)(Vpc3Read(self->motorola ? a : (VPC3_ADR)(a + 1u)) << 8 | lo);
}

/* A buffer pointer cell holds the segment number. */
static VPC3_ADR buffer(DPS_P_(dps) VPC3_ADR ptr_cell) {
  return (VPC3_ADR)((VPC3_ADR)Vpc3Read(ptr_cell) << self->map->segment_shift);
}

static void set_mask(DPS_P_(dps) uint16_t enabled) {
  self->mask = enabled;
  write16(ME_ self->map->int_mask, (uint16_t)~enabled);
}

/* Buffers, segment by segment from the start of the user area. */
static void allocate_buffers(DPS_P(dps)) {
  const unsigned seg = 1u << self->map->segment_shift;
  unsigned next = (self->map->user_base + seg - 1u) / seg;
  /* A DPV1 Set_Prm carries DPV1_Status_2 and _3 besides the module's bytes. */
  const uint8_t prm_len = (uint8_t)(self->sap_list ? self->mod->prm_len + 2u : self->mod->prm_len);
  const uint8_t aux_len = prm_len > self->mod->cfg_len ? prm_len : self->mod->cfg_len;
  unsigned k;
#define DPS_ALLOC(cell, len)                                                 \
  do {                                                                       \
    Vpc3Write((cell), (uint8_t)next);                                        \
    next += (unsigned)(len) > seg ? ((unsigned)(len) + seg - 1u) / seg : 1u; \
  } while (0)
  Vpc3Write(self->map->len_dout, self->mod->out_len);
  Vpc3Write(self->map->len_din, self->mod->in_len);
  for (k = 0; k < 3; ++k) DPS_ALLOC(self->map->dout_ptr[k], self->mod->out_len);
  for (k = 0; k < 3; ++k) DPS_ALLOC(self->map->din_ptr[k], self->mod->in_len);
  if (self->map->dout_ptr_c != NONE) DPS_ALLOC(self->map->dout_ptr_c, self->mod->out_len);
  for (k = 0; k < 2; ++k) {
    Vpc3Write(self->map->len_diag[k], kStdDiag);
    DPS_ALLOC(self->map->diag_ptr[k], kStdDiag + DPS_MAX_DIAG);
    Vpc3Write(self->map->len_cntrl[k], aux_len);
    DPS_ALLOC(self->map->aux_ptr[k], aux_len);
  }
  Vpc3Write(self->map->aux_sel, 0x00);
  DPS_ALLOC(self->map->prm_ptr, aux_len);
  DPS_ALLOC(self->map->cfg_ptr, aux_len);
  DPS_ALLOC(self->map->read_cfg_ptr, self->mod->cfg_len);
  DPS_ALLOC(self->map->ssa_ptr, aux_len);
  if (self->sap_list) {
    /* While Offline (VPC3+C p.54): the list, FFh after its last entry, the buffer headers. */
    const VPC3_ADR list = (VPC3_ADR)(next << self->map->segment_shift);
    self->c1_waiting = 0;
    DPS_ALLOC(VPC3_R_FDL_SAP_List_Ptr, kDpv1Saps * VPC3_SAP_Entry_SIZE + 1u);
    for (k = 0; k < kDpv1Saps; ++k) {
      const VPC3_ADR e = (VPC3_ADR)(list + k * VPC3_SAP_Entry_SIZE);
      const uint8_t buf = (uint8_t)next;
      /* The connection's SAP stays off until an Initiate opens it. */
      const uint8_t ind0 = k == kConn ? 0x00u : buf;
      self->sap_entry[k] = e;
      self->dpv1_buf[k] = (VPC3_ADR)(next << self->map->segment_shift);
      Vpc3Write(e + VPC3_SAP_Entry_Sap, kDpv1Sap[k]);
      Vpc3Write(e + VPC3_SAP_Entry_Request_SA, VPC3_SAP_Entry_Request_SA_All);
      Vpc3Write(e + VPC3_SAP_Entry_Request_SSAP, VPC3_SAP_Entry_Request_SSAP_All);
      Vpc3Write(e + VPC3_SAP_Entry_Service_Supported, VPC3_SAP_Entry_Service_Supported_All);
      Vpc3Write(e + VPC3_SAP_Entry_Ind_Buf_Ptr0, ind0);
      Vpc3Write(e + VPC3_SAP_Entry_Ind_Buf_Ptr1, buf);
      Vpc3Write(e + VPC3_SAP_Entry_Resp_Buf_Ptr, buf);
      Vpc3Write(self->dpv1_buf[k] + VPC3_DPV1_Buf_Control, 0x00);
      Vpc3Write(self->dpv1_buf[k] + VPC3_DPV1_Buf_Max_Length, DPS_DPV1_MAX_PDU);
      next += (VPC3_DPV1_Buf_SIZE + DPS_DPV1_MAX_PDU + seg - 1u) / seg;
    }
    Vpc3Write((VPC3_ADR)(list + kDpv1Saps * VPC3_SAP_Entry_SIZE), VPC3_SAP_Entry_Sap_End_Of_List);
  }
  if (self->dpc31) {
    DPS_ALLOC(DPC31_InstQ_Base, 2u * DPS_QUEUE_LEN);
    DPS_ALLOC(DPC31_IndQ_Base, 2u * DPS_QUEUE_LEN);
    Vpc3Write(DPC31_InstQ_Len, DPS_QUEUE_LEN);
    Vpc3Write(DPC31_IndQ_Len, DPS_QUEUE_LEN);
  }
#undef DPS_ALLOC
}

/* dpc31: queue requests; the MAC executes them when InstQ_Wr moves past them (one write for
 * several). */
static void queue_request(DPS_P_(dps) uint8_t code, uint8_t param) {
  Vpc3Write((VPC3_ADR)(self->instq + 2u * self->instq_wr), code);
  Vpc3Write((VPC3_ADR)(self->instq + 2u * self->instq_wr + 1u), param);
  self->instq_wr = (uint8_t)((self->instq_wr + 1u) % DPS_QUEUE_LEN);
}
static void send_requests(DPS_P(dps)) { Vpc3Write(DPC31_InstQ_Wr, self->instq_wr); }

/* The user watchdog: the SPC3 and VPC3+ count Data_Exchange telegrams from Res_User_WD on; the
 * DPC31's DPS_User_Watchdog runs on 10 ms from its Enable request, and Reset retriggers it. */
static void user_wd(DPS_P_(dps) uint8_t action) {
  if (!self->dpc31) {
    if (action == Wd_Reset) Vpc3Write(self->map->mode1_s, Res_User_WD);
    return;
  }
  /* Reset first: it lifts the lock an expiry leaves, which Enable alone would not. */
  if (action == Wd_Enable) queue_request(ME_ DPS_User_Wd, Wd_Reset);
  queue_request(ME_ DPS_User_Wd, action);
  send_requests(ME);
}

/* dpc31: read the Indication_Queue up to IndQ_Wr and free the entries. */
static void drain_indications(DPS_P(dps)) {
  const uint8_t wr = Vpc3Read(DPC31_IndQ_Wr);
  while (self->indq_rd != wr && wr < DPS_QUEUE_LEN) {
    const uint8_t code = Vpc3Read((VPC3_ADR)(self->indq + 2u * self->indq_rd));
    const uint8_t event = Vpc3Read((VPC3_ADR)(self->indq + 2u * self->indq_rd + 1u));
    if (code == DPS_User_Wd && event == Wd_Expired) ++self->stats.user_wd_expiries;
    self->indq_rd = (uint8_t)((self->indq_rd + 1u) % DPS_QUEUE_LEN);
  }
  Vpc3Write(DPC31_IndQ_Rd, self->indq_rd);
}

/* dpc31: the clear buffer C holds what a Clear hands over as outputs: all zero. */
static void refill_clear_buffer(DPS_P(dps)) {
  if (self->map->dout_ptr_c != NONE)
    Vpc3MemSet(buffer(ME_ self->map->dout_ptr_c), 0x00, self->mod->out_len);
}

void dps_init(DPS_P_(dps) const dps_board* board, const dps_module* module) {
  static const uint16_t kSources = MAC_Reset | Go_Leave_Data_Exchange | Baudrate_Detect |
                                   WD_DP_Control_Timeout | New_GC_Command | New_SSA_Data |
                                   New_Cfg_Data | New_Prm_Data | Diag_Buffer_Changed | DX_Out;
  self->map = &kMaps[board->profile];
  self->mod = module;
  self->dpc31 = board->profile == DPC31_PROFILE_DPC31;
  self->sap_list = board->profile == DPC31_PROFILE_VPC3PLUS && module->dpv1_request != 0;
  self->timer_module = 0;
  self->dpv1_pending = 0;
  self->c2_busy = 0;
  memset(self->dpv1_status, 0, sizeof self->dpv1_status);
  self->instq_wr = 0;
  self->indq_rd = 0;
  self->motorola = board->motorola;
  memset(&self->stats, 0, sizeof self->stats);
  self->diag_len = 0;
  self->diag_ext = 0;
  self->diag_pending = 0;
  self->stats.station_address = board->station_address;

  write16(ME_ self->map->int_req, 0x0000);
  /* Stale events from before the reset go; New_Prm/Cfg_Data only go with their verdict reads. */
  write16(ME_ self->map->int_ack, (uint16_t)(kSources & ~(New_Prm_Data | New_Cfg_Data)));
  /* DP mode, fail-safe telegrams accepted; no Sync/Freeze (the GSD says so); EOI inactive
   * time 1 us, user timer 1 ms. */
  write16(ME_ self->map->mode0, DP_Mode | Spec_Clear_Mode);
  set_mask(ME_ self->dpc31  ? (uint16_t)(kSources | Indication)
           : self->sap_list ? (uint16_t)(kSources | FDL_Ind | Poll_End_Ind)
                            : kSources);
  Vpc3Write(self->map->wd_baud, 0x10);  /* Baud_Control: 16 x 10 ms */
  Vpc3Write(self->map->min_tsdr, 0x0B); /* 11 bit times */
  write16(ME_ self->map->user_wd, 0x01FF);
  Vpc3Write(self->map->ident_lo, (uint8_t)module->ident);
  Vpc3Write(self->map->ident_hi, (uint8_t)(module->ident >> 8));
  Vpc3Write(self->map->ts_adr, board->station_address);
  Vpc3Write(self->map->real_no_add_change, 0x00); /* Set_Slave_Add allowed */
  allocate_buffers(ME);
  Vpc3Write(self->map->len_read_cfg, module->cfg_len);
  CopyToVpc3(CHIP_PTR(buffer(ME_ self->map->read_cfg_ptr)), (uint8_t*)module->cfg, module->cfg_len);
  refill_clear_buffer(ME);
  dps_update_inputs(ME);
  if (!self->dpc31) {
    Vpc3Write(self->map->mode1_s, Start_SPC3 | Res_User_WD);
    return;
  }
  /* The DPC31 has no Start_SPC3: the MAC starts with a MAC_Start request (Table 5.1-3). Its
   * user watchdog runs while in Data_Exchange (DPS_User_Wd requests). */
  self->instq = buffer(ME_ DPC31_InstQ_Base);
  self->indq = buffer(ME_ DPC31_IndQ_Base);
  queue_request(ME_ MAC_Start, 0x00);
  send_requests(ME);
}

void dps_update_inputs(DPS_P(dps)) {
  uint8_t in[DPS_MAX_IO];
  /* Din_Buffer_SM bits 5:4 name the buffer the user owns (U). */
  const uint8_t u = (uint8_t)((Vpc3Read(self->map->din_sm) >> 4) & 3u);
  if (u == 0 || self->mod->in_len == 0) return;
  self->mod->inputs(ME_ in);
  CopyToVpc3(CHIP_PTR(buffer(ME_ self->map->din_ptr[u - 1u])), in, self->mod->in_len);
  (void)Vpc3Read(self->map->new_din);
}

/* The 1 ms task runs while the module wants it or a DPV1 request waits. */
void dps_timer_enable(DPS_P_(dps) int on) {
  self->timer_module = on;
  set_mask(ME_ on || self->dpv1_pending || self->c2_busy
               ? (uint16_t)(self->mask | User_Timer_Clock)
               : (uint16_t)(self->mask & ~User_Timer_Clock));
}

uint8_t dps_dpv1_status(DPS_P_(dps) uint8_t k) {
  return k >= 1u && k <= 3u ? self->dpv1_status[k - 1u] : 0u;
}

static int in_data_exchange(DPS_P(dps)) {
  return ((read16(ME_ self->map->status) >> 4) & 3u) == 2u;
}

/* Request_SA of both MSAC_C1 SAPs. */
static void c1_request_sa(DPS_P_(dps) uint8_t sa) DPS_REENTRANT {
  uint8_t k;
  for (k = 0; k < kC1Saps; ++k) Vpc3Write(self->sap_entry[k] + VPC3_SAP_Entry_Request_SA, sa);
}

/* The C1 SAPs opened to the locking master once in Data_Exchange. The chip writes Master_Add into
 * byte 3 of the diag buffer it sends (SPC3 p.33; the Profichip driver's VPC3_GetMasterAddress
 * reads it there), and a master checks the slave with Slave_Diag after Chk_Cfg, before its
 * Data_Exchange. The buffer the chip holds is the one it sent last unless the user gave it a new
 * one since (Diag_Flag: not yet fetched); then a later call reads it. */
static void c1_open_to_master(DPS_P(dps)) DPS_REENTRANT {
  const uint16_t status = read16(ME_ self->map->status);
  uint8_t k, master;
  if ((status & VPC3_Status_Reg_Diag_Flag_Msk) != 0 || ((status >> 4) & 3u) != 2u) return;
  /* The chip's buffer is in state 10 or 11 (Diag_Buffer_SM), the user's in 01. */
  k = (Vpc3Read(self->map->diag_sm) & VPC3_Diag_Buffer_SM_Diag_Buf1_State_Msk) >= 2u ? 0u : 1u;
  master = Vpc3Read((VPC3_ADR)(buffer(ME_ self->map->diag_ptr[k]) + kDiagMasterAdd));
  if (master == kNoMaster) return;
  c1_request_sa(ME_ master);
  self->c1_waiting = 0;
}

/* The user's diag buffer is the one in state 01 (User); both may be with the ASIC. */
static void publish_diag(DPS_P(dps)) {
  uint8_t sm;
  int k;
  VPC3_ADR base;
  /* Before the chip gets a buffer it has not sent. */
  if (self->sap_list && self->c1_waiting) c1_open_to_master(ME);
  sm = Vpc3Read(self->map->diag_sm);
  if ((sm & 3u) == 1u) {
    k = 0;
  } else if (((sm >> 2) & 3u) == 1u) {
    k = 1;
  } else {
    self->diag_pending = 1; /* retried on Diag_Buffer_Changed */
    return;
  }
  base = buffer(ME_ self->map->diag_ptr[k]);
  Vpc3Write(base, self->diag_ext ? Ext_Diag : 0x00); /* bytes 1..5 are the ASIC's */
  CopyToVpc3(CHIP_PTR(base + kStdDiag), self->diag, self->diag_len);
  Vpc3Write(self->map->len_diag[k], (uint8_t)(kStdDiag + self->diag_len));
  (void)Vpc3Read(self->map->new_diag);
  self->diag_pending = 0;
  ++self->stats.diag_updates;
}

uint8_t dps_given_diag(DPS_P_(dps) uint8_t k) DPS_REENTRANT {
  return k < self->diag_len ? self->diag[k] : 0u;
}

void dps_set_diag(DPS_P_(dps) const uint8_t* bytes, uint8_t len, int ext_diag) {
  self->diag_len = len > DPS_MAX_DIAG ? (uint8_t)DPS_MAX_DIAG : len;
  memcpy(self->diag, bytes, self->diag_len);
  self->diag_ext = (uint8_t)(ext_diag != 0);
  publish_diag(ME);
}

/* MSAC_C1 stops: both buffers free, no request pending, the C1 SAPs closed until Data_Exchange
 * names the master (another one, maybe). Closed first (our own address: nobody sends to itself,
 * as the Profichip driver locks its SAPs), so freeing the buffers also drops what came before. */
static void c1_close(DPS_P(dps)) {
  uint8_t k;
  c1_request_sa(ME_ self->stats.station_address);
  self->c1_waiting = kC1Closed;
  self->dpv1_pending = (uint8_t)(self->dpv1_pending & ~((1u << kC1Saps) - 1u));
  for (k = 0; k < kC1Saps; ++k) Vpc3Write(self->dpv1_buf[k] + VPC3_DPV1_Buf_Control, 0x00);
}

/* A Set_Prm with DPV1_Enable starts MSAC_C1 afresh, its status bytes kept for the module. The
 * class-1 master's Set_Prm leaves a class-2 master's connection alone (docs/decisions.md). */
static void dpv1_restart(DPS_P_(dps) const uint8_t* status) {
  memcpy(self->dpv1_status, status, sizeof self->dpv1_status);
  c1_close(ME);
}

/* FDL_Ind: take each request whose buffer holds IND (the buffer stays the user's until the
 * response is in it) and have the 1 ms task answer it. */
static void dpv1_take_indications(DPS_P(dps)) {
  uint8_t k;
  for (k = 0; k < kDpv1Saps; ++k) {
    const VPC3_ADR b = self->dpv1_buf[k];
    uint8_t len;
    if ((self->dpv1_pending >> k) & 1u) continue;
    if ((Vpc3Read(b + VPC3_DPV1_Buf_Control) & VPC3_DPV1_Buf_Control_IND_Msk) == 0) continue;
    Vpc3Write(b + VPC3_DPV1_Buf_Control, VPC3_DPV1_Buf_Control_USER_Msk);
    len = Vpc3Read(b + VPC3_DPV1_Buf_Length);
    if (len > DPS_DPV1_MAX_PDU) len = DPS_DPV1_MAX_PDU;
    CopyFromVpc3(self->dpv1_req[k], CHIP_PTR(b + VPC3_DPV1_Buf_SIZE), len);
    self->dpv1_len[k] = len;
    self->dpv1_pending = (uint8_t)(self->dpv1_pending | 1u << k);
    if (k == kConn) self->c2_quiet_ms = 0;
    ++self->stats.dpv1_requests;
  }
  if (self->dpv1_pending && (self->mask & User_Timer_Clock) == 0) {
    /* A tick latched while masked is stale: the answer comes with the next one. */
    write16(ME_ self->map->int_ack, User_Timer_Clock);
    set_mask(ME_(uint16_t)(self->mask | User_Timer_Clock));
  }
}

/* DPV1 events. After a Set_Prm (handle_prm took or refused it) the module brings up to date what
 * depends on it. MSAC_C1 lives in the master's Data_Exchange (docs/dpv1.md): entering it opens the
 * C1 SAPs, to the locking master once the diag buffer names it (c1_open_to_master), to any
 * station until then; DX_Out and FDL_Ind (before its request is taken) narrow them to it; leaving
 * it (Leave_Master, the watchdog) closes them, as the Profichip driver stops MSAC_C1 there. */
static void dpv1_isr(DPS_P_(dps) uint16_t ir) DPS_REENTRANT {
  if ((ir & New_Prm_Data) && self->mod->dpv1_prm != 0) self->mod->dpv1_prm(ME);
  if ((ir & Go_Leave_Data_Exchange) && self->c1_waiting != kC1Closed &&
      (self->dpv1_status[0] & VPC3_Prm_Status_1_DPV1_Enable_Msk) != 0 && !in_data_exchange(ME))
    c1_close(ME);
  if ((ir & (Go_Leave_Data_Exchange | DX_Out | FDL_Ind)) && self->c1_waiting) {
    c1_open_to_master(ME);
    if ((ir & Go_Leave_Data_Exchange) && self->c1_waiting && in_data_exchange(ME)) {
      c1_request_sa(ME_ VPC3_SAP_Entry_Request_SA_All);
      self->c1_waiting = kC1Any;
    }
  }
  if (ir & FDL_Ind) dpv1_take_indications(ME);
}

/* A response into buffer k: the data unit, Length, Function_Code, RESP with USER last. */
static void dpv1_respond(DPS_P_(dps) uint8_t k, const uint8_t* resp, uint8_t n) {
  const VPC3_ADR b = self->dpv1_buf[k];
  if (n > DPS_DPV1_MAX_PDU) n = DPS_DPV1_MAX_PDU;
  CopyToVpc3(CHIP_PTR(b + VPC3_DPV1_Buf_SIZE), (uint8_t*)resp, n);
  Vpc3Write(b + VPC3_DPV1_Buf_Length, n);
  Vpc3Write(b + VPC3_DPV1_Buf_Function_Code, kFcResponse);
  Vpc3Write(b + VPC3_DPV1_Buf_Control,
            VPC3_DPV1_Buf_Control_USER_Msk | VPC3_DPV1_Buf_Control_RESP_Msk);
}

static uint8_t dpv1_negative(uint8_t* resp, uint8_t function, uint8_t code) {
  resp[0] = (uint8_t)(function | kNegative);
  resp[1] = kDecodeDpv1;
  resp[2] = code;
  resp[3] = 0x00;
  return 4;
}

/* A resource manager's response nobody polled for withdrawn: SAP 49's one buffer free, so the
 * chip takes Initiates again instead of answering them RR (docs/firmware.md "MSAC_C2"). */
static void rm_withdraw(DPS_P(dps)) {
  if (self->c2_busy & kRmWaits) Vpc3Write(self->dpv1_buf[kRm] + VPC3_DPV1_Buf_Control, 0x00);
  self->c2_busy = (int)(self->c2_busy & ~kRmWaits);
}

/* The connection closed (Abort, time-out): its SAP off (the chip answers RS there), its buffer
 * free, a request waiting there dropped; so is a resource manager's response still waiting, the
 * one that opened it or a busy answer: its master gave up on it. */
static void c2_close(DPS_P(dps)) {
  Vpc3Write(self->sap_entry[kConn] + VPC3_SAP_Entry_Ind_Buf_Ptr0, 0x00);
  Vpc3Write(self->dpv1_buf[kConn] + VPC3_DPV1_Buf_Control, 0x00);
  self->dpv1_pending = (uint8_t)(self->dpv1_pending & ~(1u << kConn));
  rm_withdraw(ME);
  self->c2_busy = 0;
}

/* Initiate on SAP 49 (another function there: its own number | 80h, feature not supported, as
 * DO4 answers a function it does not serve). Open: Initiate | 80h, Resource_Busy. Else the
 * Initiate response (Max_Len_Data_Unit, its own features: Read/Write, no profile; S and D
 * address swapped) waits in the connection's buffer for the master's first poll there, the
 * connection's SAP is switched on, and the resource manager answers 56h, the connection's SAP,
 * the Send_Timeout (a request too short to hold one: DPC31_MSAC_C2_TIMEOUT_MIN, the driver's
 * own). The Profichip driver's checks before its user sees an Initiate (MSAC_C2_RealizeIndRecv)
 * put its Abort there instead: a Type 0 address whose Len is not 2, Abort FE; shorter than 20
 * bytes or than 16 + both addresses, Abort IA. Then its example user's: a D_Addr whose API is
 * not 0, Abort IA; D_Type not 0 (DO4 is not the connection's end), Initiate | 80h, feature not
 * supported. Either closes the connection once sent. No local beyond the old ones: the 80C32
 * build's XSEG, which its start-up clears, keeps its size (traces/do4_80c32.scn). */
static uint8_t c2_initiate(DPS_P_(dps) const uint8_t* req, uint8_t len, uint8_t* resp) {
  uint8_t res[DPS_DPV1_MAX_PDU];
  uint8_t s_len, d_len;
  if (req[0] != kInitiate) return dpv1_negative(resp, req[0], kFeatureNotSupported);
  if (self->c2_busy & kC2Open) return dpv1_negative(resp, kInitiate, kResourceBusy);
  resp[2] = len < kSendTimeoutEnd ? (uint8_t)(DPC31_MSAC_C2_TIMEOUT_MIN >> 8) : req[4];
  resp[3] = len < kSendTimeoutEnd ? (uint8_t)DPC31_MSAC_C2_TIMEOUT_MIN : req[5];
  s_len = req[13]; /* read before the length is checked: the buffer holds DPS_DPV1_MAX_PDU */
  d_len = req[15];
  res[0] = kAbort;
  res[1] = 0x00; /* Subnet: none */
  res[2] = len < kInitiateReq ? kAbortIA
           : (req[12] == kAddrTypeApiScl && s_len != kAddrApiScl) ||
                   (req[14] == kAddrTypeApiScl && d_len != kAddrApiScl)
               ? kAbortFE
           : len < kInitiateReqMin || (unsigned)len < (unsigned)kInitiateReq + s_len + d_len
               ? kAbortIA
           : d_len != 0u && req[kInitiateReq + s_len] != 0u ? kAbortIA /* D_Addr's API */
                                                            : 0;
  res[3] = 0x00;
  if (res[2] == 0 && req[14] != kAddrTypeApiScl) {
    dpv1_negative(res, kInitiate, kFeatureNotSupported);
  } else if (res[2] == 0) {
    res[0] = kInitiate;
    res[1] = DPS_DPV1_MAX_PDU - 4u;
    res[2] = kFeaturesRW;  /* Features_Supported_1, _2 */
    memset(res + 4, 0, 4); /* Profile_Features_Supported, Profile_Ident_Number: none */
    res[8] = req[14];      /* S_Type, S_Len: the request's D_Type, D_Len */
    res[9] = d_len;
    res[10] = req[12];
    res[11] = s_len;
    memcpy(res + kInitiateRes, req + kInitiateReq + s_len, d_len);
    memcpy(res + kInitiateRes + d_len, req + kInitiateReq, s_len);
  }
  /* res[0]: the Initiate response, or a refusal (the Abort, the negative response: 4 bytes) */
  dpv1_respond(ME_ kConn, res,
               res[0] == kInitiate ? (uint8_t)(kInitiateRes + s_len + d_len) : (uint8_t)4u);
  Vpc3Write(self->sap_entry[kConn] + VPC3_SAP_Entry_Ind_Buf_Ptr0,
            (uint8_t)(self->dpv1_buf[kConn] >> self->map->segment_shift));
  self->c2_busy |= res[0] == kInitiate ? kC2Open : kC2Open | kC2Closing;
  self->c2_timeout = (uint16_t)((uint16_t)resp[2] << 8 | resp[3]);
  self->c2_quiet_ms = 0;
  if (res[0] == kInitiate) ++self->stats.c2_opened;
  resp[0] = kRmResponse;
  resp[1] = DPS_SAP_C2;
  return 4;
}

/* A request on the open connection: Abort closes it (no response), Idle is answered 48h 00h,
 * the rest is the module's. 0: no response. */
static uint8_t c2_request(DPS_P_(dps) const uint8_t* req, uint8_t len, uint8_t* resp) {
  if (req[0] == kAbort) {
    c2_close(ME);
    ++self->stats.c2_aborted;
    return 0;
  }
  if (req[0] == kIdle) {
    resp[0] = kIdle;
    resp[1] = 0x00;
    return 2;
  }
  return self->mod->dpv1_request(ME_ DPS_SAP_C2, req, len, resp);
}

/* The 1 ms task: the requests answered. */
static void dpv1_answer(DPS_P(dps)) {
  uint8_t k;
  for (k = 0; k < kDpv1Saps; ++k) {
    uint8_t resp[DPS_DPV1_MAX_PDU];
    uint8_t n;
    if (((self->dpv1_pending >> k) & 1u) == 0) continue;
    self->dpv1_pending = (uint8_t)(self->dpv1_pending & ~(1u << k));
    if (k == kRm) {
      n = c2_initiate(ME_ self->dpv1_req[k], self->dpv1_len[k], resp);
      /* Its response waits for its poll: with a connection open until it closes, else for
       * C2_Response_Timeout (c2_tick). */
      if ((self->c2_busy & kC2Open) == 0) {
        self->c2_timeout = kRmResponseTimeout;
        self->c2_quiet_ms = 0;
      }
      self->c2_busy |= kRmWaits;
    } else if (k == kConn) {
      n = c2_request(ME_ self->dpv1_req[k], self->dpv1_len[k], resp);
      if (n == 0) continue;
    } else {
      n = self->mod->dpv1_request(ME_ kDpv1Sap[k], self->dpv1_req[k], self->dpv1_len[k], resp);
    }
    dpv1_respond(ME_ k, resp, n);
  }
  if (!self->timer_module && !self->c2_busy)
    set_mask(ME_(uint16_t)(self->mask & ~User_Timer_Clock));
}

/* The connection's time-out, on each 1 ms tick while it is open: closed at the first tick that
 * finds it quiet longer than Send_Timeout, the (10 x Send_Timeout + 1)-th tick after its last
 * request taken or response sent, so never before Send_Timeout has run out (docs/firmware.md).
 * Without a connection the same count withdraws the resource manager's response. */
static void c2_tick(DPS_P(dps)) {
  if (++self->c2_quiet_ms <= (uint32_t)self->c2_timeout * 10u) return;
  if (self->c2_busy & kC2Open) {
    c2_close(ME);
    ++self->stats.c2_timeouts;
  } else {
    rm_withdraw(ME);
  }
  if (!self->timer_module && !self->dpv1_pending)
    set_mask(ME_(uint16_t)(self->mask & ~User_Timer_Clock));
}

/* Poll_End_Ind: a response went out (the chip cleared RESP and USER: the buffer is free again);
 * Response_Sent is the user's to clear. */
static void dpv1_response_sent(DPS_P(dps)) {
  uint8_t k;
  for (k = 0; k < kDpv1Saps; ++k) {
    const uint8_t b0 = Vpc3Read(self->sap_entry[k] + VPC3_SAP_Entry_Sap);
    if ((b0 & VPC3_SAP_Entry_Sap_Response_Sent_Msk) == 0) continue;
    Vpc3Write(self->sap_entry[k] + VPC3_SAP_Entry_Sap,
              (uint8_t)(b0 & ~VPC3_SAP_Entry_Sap_Response_Sent_Msk));
    if (k == kConn) self->c2_quiet_ms = 0;
    if (k == kConn && (self->c2_busy & kC2Closing)) c2_close(ME); /* the refusal went out */
    if (k == kRm) self->c2_busy = (int)(self->c2_busy & ~kRmWaits);
    ++self->stats.dpv1_responses_sent;
  }
  if ((self->mask & User_Timer_Clock) && !self->timer_module && !self->dpv1_pending &&
      !self->c2_busy)
    set_mask(ME_(uint16_t)(self->mask & ~User_Timer_Clock));
}

/* Set_Prm: the ASIC checked ident, lock and reserved bits; the module checks its own bytes.
 * A new Set_Prm arriving during the check makes the verdict read return Prm_Conflict: check
 * the new buffer. */
static void handle_prm(DPS_P(dps)) {
  for (;;) {
    uint8_t prm[DPS_MAX_PRM];
    const uint8_t len = Vpc3Read(self->map->len_prm);
    /* With DPV1_Enable (VPC3+) bytes 7..9 are DPV1_Status_1..3 and the module's bytes start at
     * 10: two bytes longer than with the Spec_User_Prm_Byte. */
    const int dpv1 = self->sap_list && len == self->mod->prm_len + 2u;
    const uint8_t user = (uint8_t)(dpv1 ? kStdPrm + 3u : kStdPrm + 1u);
    int ok = (len == self->mod->prm_len || dpv1) && len <= DPS_MAX_PRM;
    uint8_t result;
    if (ok) {
      CopyFromVpc3(prm, CHIP_PTR(buffer(ME_ self->map->prm_ptr)), len);
      ok = ((prm[VPC3_Prm_Status_1] & VPC3_Prm_Status_1_DPV1_Enable_Msk) != 0) == dpv1 &&
           self->mod->check_prm(ME_ prm + user, (uint8_t)(len - user));
    }
    result = Vpc3Read(ok ? self->map->prm_ok : self->map->prm_not_ok);
    if (result != Prm_Conflict) {
      if (ok) {
        ++self->stats.prm_ok;
        if (dpv1) {
          dpv1_restart(ME_ prm + VPC3_Prm_Status_1);
        } else {
          memset(self->dpv1_status, 0, sizeof self->dpv1_status);
        }
      } else {
        ++self->stats.prm_rejected;
      }
      return;
    }
    ++self->stats.prm_conflicts;
  }
}

/* Chk_Cfg: the master's configuration must equal the module's; same conflict rule. */
static void handle_cfg(DPS_P(dps)) {
  for (;;) {
    const uint8_t len = Vpc3Read(self->map->len_cfg);
    int ok = len == self->mod->cfg_len;
    if (ok) {
      /* One pointer read after the other, not both as arguments: C leaves the order of argument
       * evaluation open, and the bus trace must not depend on the compiler. */
      const VPC3_ADR read_cfg = buffer(ME_ self->map->read_cfg_ptr);
      const VPC3_ADR cfg = buffer(ME_ self->map->cfg_ptr);
      ok = Vpc3MemCmp(CHIP_PTR(cfg), CHIP_PTR(read_cfg), len) == 0;
    }
    const uint8_t result = Vpc3Read(ok ? self->map->cfg_ok : self->map->cfg_not_ok);
    if (result != Prm_Conflict) {
      if (ok) {
        ++self->stats.cfg_ok;
        dps_update_inputs(ME); /* the first Data_Exchange answers with valid inputs */
      } else {
        ++self->stats.cfg_rejected;
      }
      return;
    }
    ++self->stats.cfg_conflicts;
  }
}

static void handle_dx_out(DPS_P(dps)) {
  const uint8_t r = Vpc3Read(self->map->next_dout);
  ++self->stats.dx_out;
  if ((r & State_U_Buffer) != 0 && (r & 3u) != 0) {
    uint8_t out[DPS_MAX_IO];
    const int cleared = (r & U_Buffer_Cleared) != 0;
    CopyFromVpc3(out, CHIP_PTR(buffer(ME_ self->map->dout_ptr[(r & 3u) - 1u])), self->mod->out_len);
    self->mod->outputs(ME_ out, cleared); /* the terminals first: they are what is time-critical */
    if (cleared) {
      ++self->stats.cleared;
      refill_clear_buffer(ME); /* dpc31: the old U is the new C */
    }
  }
  dps_update_inputs(ME);
  user_wd(ME_ Wd_Reset);
}

/* Set_Slave_Add: the new address would go to the board's non-volatile memory. */
static void handle_ssa(DPS_P(dps)) {
  uint8_t ssa[4];
  CopyFromVpc3(ssa, CHIP_PTR(buffer(ME_ self->map->ssa_ptr)), sizeof ssa);
  self->stats.station_address = ssa[0];
  ++self->stats.ssa;
  (void)Vpc3Read(self->map->ssa_free);
}

void dps_isr(DPS_P(dps)) {
  const uint16_t ir = read16(ME_ self->map->int_reg);
  ++self->stats.interrupts;
  if (ir & New_Prm_Data) handle_prm(ME);
  if (ir & New_Cfg_Data) handle_cfg(ME);
  if (ir & DX_Out) handle_dx_out(ME);
  if (ir & WD_DP_Control_Timeout) {
    ++self->stats.wd_timeouts;
    self->mod->comm_lost(ME_ DPS_LOSS_WATCHDOG);
  }
  if (ir & Go_Leave_Data_Exchange) {
    if (in_data_exchange(ME)) {
      user_wd(ME_ Wd_Enable);
    } else {
      ++self->stats.leave_dx;
      user_wd(ME_ Wd_Disable);
      self->mod->comm_lost(ME_ DPS_LOSS_LEFT_DATA_EXCH);
    }
  }
  if (ir & Indication) drain_indications(ME);
  if (ir & MAC_Reset) {
    ++self->stats.mac_resets;
    self->mod->comm_lost(ME_ DPS_LOSS_OFFLINE);
  }
  if (ir & Baudrate_Detect) ++self->stats.baud_detects;
  if (ir & New_GC_Command) {
    self->stats.last_gc = Vpc3Read(self->map->gc_command);
    ++self->stats.gc_commands;
  }
  if (ir & New_SSA_Data) handle_ssa(ME);
  if ((ir & Diag_Buffer_Changed) && self->diag_pending) publish_diag(ME);
  if (self->sap_list && (ir & (New_Prm_Data | Go_Leave_Data_Exchange | DX_Out | FDL_Ind)))
    dpv1_isr(ME_ ir);
  if (self->sap_list && (ir & Poll_End_Ind)) dpv1_response_sent(ME);
  /* The tick first: the one that answers an Initiate does not count for its connection. */
  if ((ir & User_Timer_Clock) && self->c2_busy) c2_tick(ME);
  if ((ir & User_Timer_Clock) && self->dpv1_pending) dpv1_answer(ME);
  if ((ir & User_Timer_Clock) && self->timer_module && self->mod->tick != 0) {
    ++self->stats.ticks;
    self->mod->tick(ME);
  }
  /* New_Prm/Cfg_Data are cleared by the verdict reads; New_Ext_Prm_Data (VPC3+ SAP53) is not
   * enabled, acknowledged like the rest should it ever be latched. */
  if (ir & ~(New_Prm_Data | New_Cfg_Data)) {
    write16(ME_ self->map->int_ack, (uint16_t)(ir & ~(New_Prm_Data | New_Cfg_Data)));
  }
  Vpc3Write(self->map->mode1_s, EOI);
}

const dps_stats* dps_get_stats(DPS_P(dps)) { return &self->stats; }
