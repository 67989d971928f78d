/* do4.c -- DO4 with the OSP function model (see do4.h). */
#include "do4.h"

#include <string.h>

#include "../firmware.h"
#include "dpc31/dpc31_pdu.h"
#include "dpc31/dpc31_regs.h"

static const uint8_t kCfg[2] = {0x21, 0x10}; /* 2 output bytes, 1 input byte */

/* The instance (dps.h, "One instance"): passed on as ME / ME_, its driver as DRV / DRV_. On the
 * 80C32 the one static instance. */
#define ME DPS_A(self)
#define ME_ DPS_A_(self)
#define DRV DPS_A(&self->drv)
#define DRV_ DPS_A_(&self->drv)
#ifdef __SDCC
static do4 do4_the;
#define self (&do4_the)
#endif

/* The diag block after the 6 standard bytes. DP: `02h, S` (device-related, S bit 0 = OSP). With
 * DPV1 a device-related block holds an alarm or status block (header 05h, Alarm_Type / Status_Type,
 * Slot_Number 0, Specifier, S): the diagnostic alarm (Alarm_Type 01h) while one is outstanding,
 * else the status (Status_Type 81h: status message) with Specifier 1 OSP appears, 2 disappears.
 * Ext_Diag is set while an alarm is outstanding. */
enum { kDiagAlarm = 0x01u, kStatusMessage = 0x81u, kAppears = 0x01u, kDisappears = 0x02u };

static int dpv1_on(DPS_P(do4)) {
  return (dps_dpv1_status(DRV_ 1) & VPC3_Prm_Status_1_DPV1_Enable_Msk) != 0;
}

static void publish_diag(DPS_P(do4)) {
  const uint8_t osp = (uint8_t)(self->s.modul_ok ? 0x00 : 0x01);
  if (!dpv1_on(ME)) {
    const uint8_t diag[2] = {0x02, osp};
    dps_set_diag(DRV_ diag, sizeof diag, 0);
  } else {
    const uint8_t diag[5] = {
        0x05, self->alarm_spec ? (uint8_t)kDiagAlarm : (uint8_t)kStatusMessage, 0x00,
        self->alarm_spec ? self->alarm_spec : (uint8_t)(osp ? kAppears : kDisappears), osp};
    dps_set_diag(DRV_ diag, sizeof diag, self->alarm_spec != 0);
  }
}

/* The terminals are the module's real outputs: the host sees each change with its cycle. */
static void drive(DPS_P_(do4) uint8_t terminals, uint8_t modul_ok) {
  if (terminals != self->s.terminals) {
    self->s.terminals = terminals;
    dpc31_port_write(DO4_PORT_OUTPUTS, terminals);
  }
  if (modul_ok != self->s.modul_ok) {
    self->s.modul_ok = modul_ok;
    dpc31_port_write(DO4_PORT_MODUL_OK, modul_ok);
    /* Entering OSP mode is a diagnostic alarm if the master enabled them (one outstanding). */
    if (!modul_ok && !self->alarm_spec && dpv1_on(ME) &&
        (dps_dpv1_status(DRV_ 2) & VPC3_Prm_Status_2_Enable_Diagnostic_Alarm_Msk) != 0) {
      self->alarm_spec = (uint8_t)(self->alarm_seq << 3 | kAppears);
      self->alarm_seq = (uint8_t)((self->alarm_seq + 1u) & 0x1Fu);
    }
    /* The mode is also a status for the master. */
    publish_diag(ME);
  }
}

/* OSP mode: the output follows OSPMode, no longer the master. */
static void enter_osp(DPS_P(do4)) {
  self->s.osp_valid = 0;
  drive(ME_ self->s.osp_mode == DO4_REPLACE ? self->s.osp_value : self->s.last_valid, 0);
}

/* DPV1 (VPC3+, docs/firmware.md "DO4 with DPV1"): the OSP configuration as the record of slot 0
 * index 1, two bytes as in Set_Prm: OSPMode, replacement value. Function numbers and error codes
 * per IEC 61158-6 type 3 (docs/dpv1.md, "Negative responses"). */
enum { kRead = DPC31_DPV1_READ, kWrite = DPC31_DPV1_WRITE, kAlarmAck = DPC31_DPV1_ALARM_ACK };
enum { kErrorBit = DPC31_DPV1_ERROR_BIT, kErrorDecodeDpv1 = DPC31_DPV1_ERROR_DECODE_DPV1 };
enum {
  kInvalidIndex = DPC31_DPV1_INVALID_INDEX,
  kWriteLengthError = DPC31_DPV1_WRITE_LENGTH_ERROR,
  kInvalidSlot = DPC31_DPV1_INVALID_SLOT,
  kStateConflict = DPC31_DPV1_STATE_CONFLICT,
  kInvalidRange = DPC31_DPV1_INVALID_RANGE,
  kInvalidParameter = DPC31_DPV1_INVALID_PARAMETER,
  kFeatureNotSupported = DPC31_DPV1_FEATURE_NOT_SUPPORTED
};
enum { kOspSlot = 0u, kOspIndex = 1u, kOspRecordLen = 2u };

static uint8_t dpv1_error(uint8_t* resp, uint8_t function, uint8_t code) {
  resp[0] = (uint8_t)(function | kErrorBit);
  resp[1] = kErrorDecodeDpv1;
  resp[2] = code;
  resp[3] = 0x00; /* Error_Code_2: no detail */
  return 4;
}

/* Read or Write of a record: slot, index, then (Write) the length and the module's state. */
static uint8_t dpv1_record(DPS_P_(do4) const uint8_t* req, uint8_t len, uint8_t* resp) {
  const uint8_t fn = req[0];
  if (req[1] != kOspSlot) return dpv1_error(resp, fn, kInvalidSlot);
  if (req[2] != kOspIndex) return dpv1_error(resp, fn, kInvalidIndex);
  resp[0] = fn;
  resp[1] = req[1];
  resp[2] = req[2];
  if (fn == kRead) { /* the record's bytes, at most as many as asked for */
    resp[3] = req[3] < kOspRecordLen ? req[3] : (uint8_t)kOspRecordLen;
    resp[4] = self->s.osp_mode;
    resp[5] = self->s.osp_value;
    return (uint8_t)(4u + resp[3]);
  }
  if (req[3] != kOspRecordLen || len != 4u + kOspRecordLen)
    return dpv1_error(resp, fn, kWriteLengthError);
  /* The replacement value is what drives the terminals in OSP mode: not changed under them. */
  if (!self->s.modul_ok) return dpv1_error(resp, fn, kStateConflict);
  if (req[4] > DO4_REPLACE || (req[5] & 0xF0u) != 0) return dpv1_error(resp, fn, kInvalidRange);
  self->s.osp_mode = req[4];
  self->s.osp_value = req[5];
  resp[3] = kOspRecordLen;
  return 4;
}

/* Alarm_Ack (5Ch, Slot_Number, Alarm_Type, Specifier): the outstanding alarm acknowledged, the
 * positive response echoes the request; the diag no longer holds the alarm. A slot the module
 * does not have is B2h as for a record (the slot is checked first there too). */
static uint8_t dpv1_alarm_ack(DPS_P_(do4) const uint8_t* req, uint8_t* resp) {
  if (req[1] != kOspSlot) return dpv1_error(resp, kAlarmAck, kInvalidSlot);
  if (!self->alarm_spec) return dpv1_error(resp, kAlarmAck, kStateConflict);
  if (req[2] != kDiagAlarm || req[3] != self->alarm_spec)
    return dpv1_error(resp, kAlarmAck, kInvalidParameter);
  self->alarm_spec = 0;
  publish_diag(ME);
  memcpy(resp, req, 4);
  return 4;
}

static uint8_t dpv1_request(DPS_CB_P_ uint8_t sap, const uint8_t* req, uint8_t len,
                            uint8_t* resp) DPS_REENTRANT {
  DPS_MODULE_SELF(do4);
  const uint8_t fn = req[0];
  /* Alarm_Ack is MSAC_C1's on SAP 50 or 51 (manual-quotes.md, DPV1). */
  if ((sap == DPS_SAP_ALARM || sap == DPS_SAP_C1) && len == 4u && fn == kAlarmAck)
    return dpv1_alarm_ack(ME_ req, resp);
  /* MSAC_C1 and the MSAC_C2 connection: the same record, the same answers. */
  if ((sap == DPS_SAP_C1 || sap == DPS_SAP_C2) && len >= 4u && (fn == kRead || fn == kWrite))
    return dpv1_record(ME_ req, len, resp);
  return dpv1_error(resp, fn, kFeatureNotSupported);
}

/* DPV1 (VPC3+): after a Set_Prm. A block already shown that the Set_Prm made wrong is handed over
 * again at once, not at the next change of mode: the DP block after one with DPV1_Enable (or the
 * other way round), an alarm it dropped (check_prm; docs/firmware.md: "A new Set_Prm drops an
 * outstanding alarm", "Without DPV1 the block stays 02h, S"). Else nothing: an unchanged block
 * would only raise Diag_Flag, and a first one would change the start-up. */
static void dpv1_prm(DPS_CB_P) DPS_REENTRANT {
  DPS_MODULE_SELF(do4);
  const uint8_t head = dps_given_diag(DRV_ 0); /* 02h DP, 05h DPV1; 0: none shown yet */
  if (head != 0 && (head != (dpv1_on(ME) ? 0x05u : 0x02u) ||
                    (head == 0x05u && dps_given_diag(DRV_ 1) == kDiagAlarm && !self->alarm_spec)))
    publish_diag(ME);
}

static int check_prm(DPS_CB_P_ const uint8_t* prm, uint8_t len) DPS_REENTRANT {
  DPS_MODULE_SELF(do4);
  if (len != 3 || prm[0] > DO4_REPLACE || (prm[1] & 0xF0u) != 0) return 0;
  self->s.osp_mode = prm[0];
  self->s.osp_value = prm[1];
  self->s.refresh_ms = prm[2];
  self->alarm_spec = 0; /* a new parameterisation: no alarm outstanding */
  self->s.ms_since_refresh = 0;
  dps_timer_enable(DRV_ self->s.refresh_ms != 0);
  if (!self->s.osp_valid) enter_osp(ME); /* the new replacement value applies at once */
  return 1;
}

static void outputs(DPS_CB_P_ const uint8_t* out, int cleared) DPS_REENTRANT {
  DPS_MODULE_SELF(do4);
  self->s.ms_since_refresh = 0;
  if (cleared) { /* Clear_Data or a fail-safe telegram: communication interrupted */
    ++self->s.osp_events;
    enter_osp(ME);
    return;
  }
  if (out[1] & 0x01u) { /* a set OSPValid transferred: normal operation */
    self->s.osp_valid = 1;
    self->s.last_valid = out[0] & 0x0Fu;
    drive(ME_ self->s.last_valid, 1);
  } else { /* the master requests OSP (initial start, restart) */
    enter_osp(ME);
  }
}

static void inputs(DPS_CB_P_ uint8_t* in) {
  DPS_MODULE_SELF(do4);
  in[0] = (uint8_t)(self->s.terminals << 4 | self->s.modul_ok);
}

static void comm_lost(DPS_CB_P_ int why) {
  DPS_MODULE_SELF(do4);
  (void)why;
  ++self->s.osp_events;
  enter_osp(ME);
}

/* A few bus cycles without refresh (EMC): OSPValid is reset in the module only. */
static void tick(DPS_CB_P) {
  DPS_MODULE_SELF(do4);
  if (self->s.ms_since_refresh < 255u) ++self->s.ms_since_refresh;
  if (self->s.osp_valid && self->s.ms_since_refresh >= self->s.refresh_ms) {
    ++self->s.osp_events;
    enter_osp(ME);
  }
}

static const dps_module kModule = {"DO4",     DO4_IDENT, kCfg,         sizeof kCfg, 1,
                                   2,         7 + 1 + 3, check_prm,    outputs,     inputs,
                                   comm_lost, tick,      dpv1_request, dpv1_prm};

void do4_init(DPS_P_(do4) const dps_board* board) {
  memset(&self->s, 0,
         sizeof self->s); /* power on: outputs off, OSP until the master sets OSPValid */
  self->alarm_spec = 0;
  self->alarm_seq = 0;
  dps_init(DRV_ board, &kModule);
}

void do4_isr(DPS_P(do4)) { dps_isr(DRV); }

const do4_state* do4_get_state(DPS_P(do4)) { return &self->s; }

/* The plug-in descriptor is the host's (firmware.h); an 80C32 build has its own main(). */
#ifndef __SDCC

DPC31_BUILTIN_ENTRIES(do4)

static const char* const kPorts[] = {"outputs", "modul_ok", 0};
/* Spec_User_Prm_Byte 00; OSPMode 0 (retain); replacement value 0; refresh monitor 100 ms: a
 * few Data_Exchange cycles even at 9.6 kbaud, where one cycle takes about 30 ms. */
static const uint8_t kPrm[] = {0x00, DO4_RETAIN_LAST, 0x00, 0x64};
const dpc31_firmware do4_firmware = {DPC31_FIRMWARE_ABI_VERSION,
                                     "DO4",
                                     "do4/DO4_0D04.gsd",
                                     kPorts,
                                     do4_start_single,
                                     do4_isr_single,
                                     0,
                                     0,
                                     0,
                                     DO4_IDENT,
                                     kCfg,
                                     sizeof kCfg,
                                     1,
                                     2,
                                     kPrm,
                                     sizeof kPrm};
const dpc31_builtin do4_builtin = {&do4_firmware, sizeof(do4), do4_start_in, do4_isr_in, 0, 0};
#endif
