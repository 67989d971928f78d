/*
 * dps.h -- the DP-slave driver layer shared by the example modules (DO4, CNT2).
 *
 * Portable C99, written as for silicon: the chip is reached only through the six access
 * functions of the public SPC3/VPC3+ drivers (Vpc3Read, Vpc3Write, CopyToVpc3, CopyFromVpc3,
 * Vpc3MemSet, Vpc3MemCmp) and the addresses of the generated register header. It owns the
 * chip: the init sequence, the ISR for every interrupt source, the Prm/Cfg handshakes with
 * their conflict loops, Dout/Din buffer switching, diag updates, Set_Slave_Add and the user
 * watchdog; on the DPC31 through its request interface (DPS_User_Wd, the
 * Indication_Queue; docs/dpc31.md).
 * A module plugs in with a dps_module: its ident, Cfg and lengths, and callbacks.
 */
#ifndef DPC31_FIRMWARE_DPS_H
#define DPC31_FIRMWARE_DPS_H

#include <stdint.h>

#include "dpc31/dpc31_hal.h"

#ifdef __cplusplus
extern "C" {
#endif

/* SDCC calls a function through a pointer with more than one argument only if it is reentrant
 * (its arguments on the stack); the module callbacks with two arguments are declared so. Other
 * compilers: nothing. */
#ifdef __SDCC
#define DPS_REENTRANT __reentrant
#else
#define DPS_REENTRANT
#endif

/* One instance: everything the driver keeps between calls lives in a `dps` (and a module's state
 * in its own struct around it), so a host runs any number of stations at once, the same firmware
 * or different ones. Every function takes its instance first, declared with DPS_P(type) (the only
 * parameter) or DPS_P_(type) (more follow) and passed on with DPS_A(x) / DPS_A_(x). An 80C32
 * board runs one firmware: there the instance is a static and no argument travels (SDCC), so the
 * target's code stays what it was with globals, direct XDATA accesses. */
#ifdef __SDCC
#define DPS_P(type) void
#define DPS_P_(type)
#define DPS_A(x)
#define DPS_A_(x)
#else
#define DPS_P(type) type* self
#define DPS_P_(type) type *self,
#define DPS_A(x) x
#define DPS_A_(x) x,
#endif
/* A module's callbacks get the driver's instance (`drv`): the module's own state is the struct
 * around it, `drv` its first member, and DPS_MODULE_SELF(type) names it `self`. On the 80C32 the
 * module's static is `self` (a macro of its file) and the callbacks take no instance. */
#ifdef __SDCC
#define DPS_CB_P void
#define DPS_CB_P_
#define DPS_MODULE_SELF(type)
#else
#define DPS_CB_P dps* drv
#define DPS_CB_P_ dps *drv,
#define DPS_MODULE_SELF(type) type* const self = (type*)drv
#endif

typedef struct dps dps;

/* What the board tells the firmware: which chip it is wired to and the station address from
 * its address switch. */
typedef struct dps_board {
  int profile;  /* enum dpc31_profile */
  int motorola; /* 1: Motorola byte order on the bus */
  uint8_t station_address;
} dps_board;

/* Why communication with the master was lost (dps_module.comm_lost). */
enum dps_comm_loss {
  DPS_LOSS_WATCHDOG = 1,       /* WD_DP_Control_Timeout */
  DPS_LOSS_LEFT_DATA_EXCH = 2, /* Go_Leave_Data_Exchange, the DP state is no longer DX */
  DPS_LOSS_OFFLINE = 3         /* MAC_Reset: the chip went Offline */
};

#define DPS_MAX_IO 32u   /* input and output bytes of the example modules */
#define DPS_MAX_PRM 32u  /* Set_Prm bytes, the 7 standard ones included */
#define DPS_MAX_DIAG 16u /* user diag bytes after the 6 standard ones */
/* DPV1 (VPC3+): the longest MSAC_C1 data unit a module takes or answers, the 4 bytes of function
 * number, slot, index and length included (GSD C1_Max_Data_Len = DPS_DPV1_MAX_PDU - 4). */
#define DPS_DPV1_MAX_PDU 20u
#define DPS_SAP_C1 51u    /* MSAC_C1 Read / Write, and Alarm_Ack */
#define DPS_SAP_ALARM 50u /* MSAC_C1 Alarm_Ack (the extra alarm SAP) */
#define DPS_SAP_C2_RM 49u /* MSAC_C2 resource manager: Initiate (the driver answers it) */
#define DPS_SAP_C2 40u    /* the one MSAC_C2 connection, open from Initiate to Abort / time-out */

typedef struct dps_module {
  const char* name;
  uint16_t ident;
  const uint8_t* cfg; /* the Chk_Cfg bytes the module accepts (also its Read_Cfg) */
  uint8_t cfg_len;
  uint8_t in_len;
  uint8_t out_len;
  uint8_t prm_len; /* total Set_Prm length, 7 standard bytes + Spec_User_Prm_Byte + module bytes */
  /* Module parameters (Set_Prm bytes 8..): 1 = accept (and take them), 0 = User_Prm_Data_Not_Okay.
   */
  int (*check_prm)(DPS_CB_P_ const uint8_t* prm, uint8_t len) DPS_REENTRANT;
  /* New outputs from the master (DX_Out); cleared = 1 when the ASIC cleared them (Clear_Data,
   * fail-safe telegram). */
  void (*outputs)(DPS_CB_P_ const uint8_t* out, int cleared) DPS_REENTRANT;
  /* The inputs to hand over next. */
  void (*inputs)(DPS_CB_P_ uint8_t* in);
  void (*comm_lost)(DPS_CB_P_ int why);
  /* User_Timer_Clock (1 ms) while the module asked for it (dps_timer_enable); may be NULL. */
  void (*tick)(DPS_CB_P);
  /* DPV1 on the VPC3+ (NULL: the module speaks DP only). A request that came on SAP `sap`
   * (DPS_SAP_C1 or DPS_SAP_ALARM; DPS_SAP_C2 a Read, Write or Data_Transport on the open MSAC_C2
   * connection: the driver itself serves Initiate, Idle, Abort and the time-out): the module writes
   * its response data unit (at most DPS_DPV1_MAX_PDU bytes) into resp and returns its length.
   * Called from the 1 ms task after the indication: the master's polls get SC until then. */
  uint8_t (*dpv1_request)(DPS_CB_P_ uint8_t sap, const uint8_t* req, uint8_t len,
                          uint8_t* resp) DPS_REENTRANT;
  /* DPV1 on the VPC3+: after each Set_Prm (its verdict given; dps_dpv1_status gives the status
   * bytes of the one taken last) the module brings up to date what depends on it, e.g. its diag.
   * May be NULL. */
  void (*dpv1_prm)(DPS_CB_P) DPS_REENTRANT;
} dps_module;

/* Bookkeeping for hosts and tests. */
typedef struct dps_stats {
  uint32_t prm_ok, prm_rejected, cfg_ok, cfg_rejected, prm_conflicts, cfg_conflicts;
  uint32_t dx_out, cleared, gc_commands, ssa, diag_updates, baud_detects, wd_timeouts;
  uint32_t leave_dx, mac_resets, ticks, interrupts;
  uint32_t user_wd_expiries;                   /* dpc31: DPS_User_WD Expired indications */
  uint32_t dpv1_requests, dpv1_responses_sent; /* FDL_Ind taken, Poll_End_Ind */
  uint32_t c2_opened, c2_aborted, c2_timeouts; /* MSAC_C2 connections */
  uint8_t last_gc;                             /* R_GC_Command at the last New_GC_Command */
  uint8_t station_address;
} dps_stats;

/* The driver's state, one per station (the fields are the driver's; a host reads the counters
 * with dps_get_stats). */
#define DPS_DPV1_SAPS 4u /* MSAC_C1, its alarm SAP, the MSAC_C2 connection and resource manager */
struct dps_regmap;
struct dps {
  const struct dps_regmap* map; /* the chip's addresses (dps.c) */
  const dps_module* mod;
  int motorola;
  dps_stats stats;
  uint16_t mask;
  uint8_t diag[DPS_MAX_DIAG];
  uint8_t diag_len;
  uint8_t diag_ext;
  int diag_pending;
  int dpc31;            /* the chip takes requests, not Mode_Reg1 commands */
  uint16_t instq, indq; /* dpc31: the queues' first entries */
  uint8_t instq_wr, indq_rd;
  int timer_module; /* the module asked for User_Timer_Clock */
  int sap_list;     /* set up at init: a VPC3+ and a module with dpv1_request */
  uint16_t sap_entry[DPS_DPV1_SAPS], dpv1_buf[DPS_DPV1_SAPS];
  uint8_t dpv1_status[3];
  uint8_t dpv1_req[DPS_DPV1_SAPS][DPS_DPV1_MAX_PDU];
  uint8_t dpv1_len[DPS_DPV1_SAPS];
  uint8_t dpv1_pending; /* bit k: the request of SAP k waits for the 1 ms task */
  /* MSAC_C2: bit 0 the connection is open, bit 1 the resource manager's response waits for its
   * poll (dps.c, kC2Open, kRmWaits); not 0: the 1 ms tick runs. */
  int c2_busy;
  /* Not 0: the C1 SAPs wait for the master's address, open to any station in Data_Exchange or
   * closed outside it (dps.c, kC1Any, kC1Closed). (With the Send_Timeout in its 16 bits the
   * instance keeps its size: the 80C32 traces count the cycles of its clearing.) */
  int c1_waiting;
  /* The connection's Send_Timeout (Initiate: 10 ms units); without a connection, how long the
   * resource manager's response waits for its poll. */
  uint16_t c2_timeout;
  uint32_t c2_quiet_ms; /* 1 ms ticks since its last request taken or response sent */
};

/* main(): configure the chip for this module and start it (Start_SPC3; DPC31: MAC_Start). */
void dps_init(DPS_P_(dps) const dps_board* board, const dps_module* module);
/* The X/INT interrupt service routine. */
void dps_isr(DPS_P(dps));

/* Hand the module's current inputs (module->inputs) to the chip now. */
void dps_update_inputs(DPS_P(dps));
/* Publish user diag bytes (device-related block) after the 6 standard bytes; ext_diag sets
 * Ext_Diag in byte 0. Queued until a diag buffer is free (Diag_Buffer_Changed). */
void dps_set_diag(DPS_P_(dps) const uint8_t* bytes, uint8_t len, int ext_diag);
/* Byte k of the user diag bytes given last (dps_set_diag); 0 beyond them, and before any. */
uint8_t dps_given_diag(DPS_P_(dps) uint8_t k) DPS_REENTRANT;
/* User_Timer_Clock interrupts on (1) or off (0). */
void dps_timer_enable(DPS_P_(dps) int on);
/* DPV1_Status_1..3 (k = 1..3) of the Set_Prm taken last; all 0 when it had no DPV1_Enable. */
uint8_t dps_dpv1_status(DPS_P_(dps) uint8_t k);

/* The instance's counters. */
const dps_stats* dps_get_stats(DPS_P(dps));

#ifdef __cplusplus
}
#endif

#endif /* DPC31_FIRMWARE_DPS_H */
