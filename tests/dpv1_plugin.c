/* dpv1_plugin.c -- a firmware plug-in for the bridge tests of tools/dp_master.py's MSAC_C1: the
 * example plug-in's DP-slave driver (examples/plugin/dp_slave.c: one output and one input byte,
 * interrupt-driven) and, in its main loop, the DPV1 side by polling: one SAP-list entry, SAP 51
 * (MSAC_C1), with one buffer for indication and response (docs/dpv1.md, VPC3+C chapter 7), and
 * one 4-byte record at slot 0, index 1 that Read returns and Write replaces. Other records:
 * Invalid_Index (80 B0 00); a Write of another length: Write_Length_Error (80 B1 00). Built in
 * C99 on the HAL's six access functions only, as the example is. */
#include <string.h>

#include "dp_slave.h"
#include "platform.h"
#include "vpc3.h"

#define DPV1_IDENT 0x0E01u
#define CELL_SAP_LIST_PTR 0x17u /* R_FDL_SAP_List_Ptr */
#define MODE1_GO_OFFLINE 0x04u
#define LIST 0x0500u   /* the SAP list: one entry and FFh */
#define BUFFER 0x0600u /* its buffer: 4-byte header, 244 data bytes */
#define MAX_LEN 244u
/* Figure 7-4: Control, Max_Length, Length, Function_Code; Control bits. */
#define H_CONTROL 0u
#define H_MAX_LEN 1u
#define H_LENGTH 2u
#define H_FC 3u
#define USER 0x80u
#define IND 0x40u
#define RESP 0x20u
#define RESPONSE_SENT 0x80u
#define SAP_MSAC_C1 51u
#define FN_READ 0x5Eu
#define FN_WRITE 0x5Fu

enum { PORT_OUTPUTS = 0 };
static const uint8_t kCfg[] = {0x20, 0x10};
static const uint8_t kUserPrm[] = {0x80, 0x00, 0x00}; /* DPV1_Enable */
static uint8_t g_record[4] = {0x11, 0x22, 0x33, 0x44};

static uint8_t exchange(uint8_t outputs) {
  BOARD_OUTPUT(PORT_OUTPUTS, outputs);
  return (uint8_t)~outputs;
}

static const dp_app kApp = {DPV1_IDENT, kCfg, sizeof kCfg, 7u + sizeof kUserPrm, exchange};

/* The SAP list is set up while Offline (VPC3+C p.54): Go_Offline, the entry (SAP 51, any
 * station and SAP, all services, the one buffer as indication and response buffer), Start. */
static void init(const dpc31_board* board) {
  const uint8_t entry[7] = {SAP_MSAC_C1, 0x7F, 0x7F, 0x00, BUFFER >> 3, 0x00, BUFFER >> 3};
  dp_init(board->station_address, &kApp);
  Vpc3Write(REG_MODE1_SET, MODE1_GO_OFFLINE);
  CopyToVpc3(VPC3_PTR(LIST), (MEM_UNSIGNED8_PTR)entry, sizeof entry);
  Vpc3Write(LIST + sizeof entry, 0xFF);
  Vpc3Write(BUFFER + H_CONTROL, 0x00);
  Vpc3Write(BUFFER + H_MAX_LEN, MAX_LEN);
  Vpc3Write(CELL_SAP_LIST_PTR, LIST >> 3);
  Vpc3Write(REG_MODE1_SET, MODE1_START);
}

/* The response to the request in `req` (`n` bytes) into `res`; its length. */
static uint8_t answer(const uint8_t* req, uint8_t n, uint8_t* res) {
  const int ours = n >= 4 && req[1] == 0 && req[2] == 1;
  memcpy(res, req, 4);
  if (!ours || (req[0] != FN_READ && req[0] != FN_WRITE)) {
    res[0] = (uint8_t)(req[0] | 0x80);
    res[1] = 0x80;
    res[2] = 0xB0; /* Invalid_Index */
    res[3] = 0x00;
    return 4;
  }
  if (req[0] == FN_READ) {
    res[3] = req[3] < sizeof g_record ? req[3] : (uint8_t)sizeof g_record;
    memcpy(res + 4, g_record, res[3]);
    return (uint8_t)(4 + res[3]);
  }
  if (req[3] != sizeof g_record || n != 4 + sizeof g_record) {
    res[0] = (uint8_t)(FN_WRITE | 0x80);
    res[1] = 0x80;
    res[2] = 0xB1; /* Write_Length_Error */
    res[3] = 0x00;
    return 4;
  }
  memcpy(g_record, req + 4, sizeof g_record);
  return 4;
}

/* main()'s loop: a request in the buffer (IND) is taken and answered (RESP); a response sent is
 * acknowledged (Response_Sent cleared). FDL_Ind and Poll_End_Ind stay masked: polled here. */
static void main_step(void) {
  uint8_t req[MAX_LEN], res[MAX_LEN], n, m;
  const uint8_t sap = Vpc3Read(LIST);
  if (sap & RESPONSE_SENT) Vpc3Write(LIST, (uint8_t)(sap & ~RESPONSE_SENT));
  if ((Vpc3Read(BUFFER + H_CONTROL) & IND) == 0) return;
  Vpc3Write(BUFFER + H_CONTROL, USER);
  n = Vpc3Read(BUFFER + H_LENGTH);
  if (n > MAX_LEN) n = MAX_LEN;
  CopyFromVpc3((MEM_UNSIGNED8_PTR)req, VPC3_PTR(BUFFER + 4), n);
  m = answer(req, n, res);
  CopyToVpc3(VPC3_PTR(BUFFER + 4), (MEM_UNSIGNED8_PTR)res, m);
  Vpc3Write(BUFFER + H_LENGTH, m);
  Vpc3Write(BUFFER + H_FC, 0x08); /* DL */
  Vpc3Write(BUFFER + H_CONTROL, USER | RESP);
}

static const char* const kPorts[] = {"outputs", 0};

static const dpc31_firmware kDpv1 = {.abi_version = DPC31_FIRMWARE_ABI_VERSION,
                                     .name = "DPV1-TEST",
                                     .ports = kPorts,
                                     .init = init,
                                     .isr = dp_isr,
                                     .main_step = main_step,
                                     .ident = DPV1_IDENT,
                                     .cfg = kCfg,
                                     .cfg_len = sizeof kCfg,
                                     .in_len = 1,
                                     .out_len = 1,
                                     .user_prm = kUserPrm,
                                     .user_prm_len = sizeof kUserPrm};
DPC31_FIRMWARE_EXPORT(kDpv1);
