/*
 * dpc31_pdu.h -- the protocol names a C DP / DPV1 driver needs beside dpc31_regs.h (the chip's
 * registers and buffer layouts): the diag buffer's standard part and the user's bits in its byte
 * 0, the Slave_Diag status bits, the DPV1 SAPs, function numbers and error codes, the MSAC_C2
 * Initiate's and Abort's values. C99, plain integer constants (SDCC too); the C++ side has the
 * same values in pdu.hpp, fdl.hpp and dp.hpp (tests/pdu_c_header_test.cpp holds them equal).
 */
#ifndef DPC31_PDU_H
#define DPC31_PDU_H

/* --- The diag buffer as the user fills it (SPC3 p.33: "The first 6 bytes are space holders,
 * except for the three least significant bit positions in the first byte"; the chip writes the
 * standard bytes when it sends, docs/decisions.md "s22-do4"). --- */
#define DPC31_DIAG_EXT_DIAG 0x01u          /* byte 0: sent as Station_Status_1 Ext_Diag */
#define DPC31_DIAG_STAT_DIAG 0x02u         /* byte 0: sent as Station_Status_2 Stat_Diag */
#define DPC31_DIAG_EXT_DIAG_OVERFLOW 0x04u /* byte 0: sent as Station_Status_3 bit 7 */
#define DPC31_DIAG_USER_BITS 0x07u         /* the three together */

/* The standard part's bytes (as sent, and as the chip leaves them in the buffer it sent). */
#define DPC31_DIAG_STATION_STATUS_1 0u
#define DPC31_DIAG_STATION_STATUS_2 1u
#define DPC31_DIAG_STATION_STATUS_3 2u
#define DPC31_DIAG_MASTER_ADD 3u /* FFh: no master has parameterised the slave */
#define DPC31_DIAG_IDENT_HIGH 4u
#define DPC31_DIAG_IDENT_LOW 5u
#define DPC31_DIAG_STANDARD 6u /* Ext_Diag_Data from here */
#define DPC31_DIAG_NO_MASTER 0xFFu

/* Station_Status_1..3 in a Slave_Diag answer (chip-facts.md §6). */
#define DPC31_ST1_STATION_NON_EXISTENT 0x01u
#define DPC31_ST1_STATION_NOT_READY 0x02u
#define DPC31_ST1_CFG_FAULT 0x04u
#define DPC31_ST1_EXT_DIAG 0x08u
#define DPC31_ST1_NOT_SUPPORTED 0x10u
#define DPC31_ST1_INVALID_SLAVE_RESPONSE 0x20u
#define DPC31_ST1_PRM_FAULT 0x40u
#define DPC31_ST1_MASTER_LOCK 0x80u
#define DPC31_ST2_PRM_REQ 0x01u
#define DPC31_ST2_STAT_DIAG 0x02u
#define DPC31_ST2_ALWAYS_1 0x04u
#define DPC31_ST2_WD_ON 0x08u
#define DPC31_ST2_FREEZE_MODE 0x10u
#define DPC31_ST2_SYNC_MODE 0x20u
#define DPC31_ST2_DEACTIVATED 0x80u
#define DPC31_ST3_EXT_DIAG_OVERFLOW 0x80u

/* --- DPV1 (manual-quotes.md, "DPV1"; docs/dpv1.md) --- */

/* The SAPs a firmware puts into the VPC3+'s SAP list. */
#define DPC31_SAP_MSAC_C2_RM 49u /* class-2 resource manager (Initiate) */
#define DPC31_SAP_MSAC_C1_ALARM 50u
#define DPC31_SAP_MSAC_C1 51u /* class-1 Read / Write / Alarm_Ack */

/* The function code of the slave's response telegram that carries the DPV1 answer (the DPV1
 * buffer's Function_Code byte): DL, response data low. */
#define DPC31_DPV1_FC_RESPONSE 0x08u

/* Function numbers: a data unit's first byte. */
#define DPC31_DPV1_IDLE 0x48u
#define DPC31_DPV1_DATA_TRANSPORT 0x51u
#define DPC31_DPV1_RESOURCE_MANAGER 0x56u /* the RM's immediate response (SAP 49) */
#define DPC31_DPV1_INITIATE 0x57u
#define DPC31_DPV1_ABORT 0x58u
#define DPC31_DPV1_ALARM_ACK 0x5Cu
#define DPC31_DPV1_READ 0x5Eu
#define DPC31_DPV1_WRITE 0x5Fu

/* A negative response (4 bytes): function number | DPC31_DPV1_ERROR_BIT, Error_Decode,
 * Error_Code_1 (class in bits 7..4, code in bits 3..0), Error_Code_2. */
#define DPC31_DPV1_ERROR_BIT 0x80u
#define DPC31_DPV1_ERROR_DECODE_DPV1 0x80u
#define DPC31_DPV1_INVALID_INDEX 0xB0u
#define DPC31_DPV1_WRITE_LENGTH_ERROR 0xB1u
#define DPC31_DPV1_INVALID_SLOT 0xB2u
#define DPC31_DPV1_TYPE_CONFLICT 0xB3u
#define DPC31_DPV1_INVALID_AREA 0xB4u
#define DPC31_DPV1_STATE_CONFLICT 0xB5u
#define DPC31_DPV1_ACCESS_DENIED 0xB6u
#define DPC31_DPV1_INVALID_RANGE 0xB7u
#define DPC31_DPV1_INVALID_PARAMETER 0xB8u
#define DPC31_DPV1_INVALID_TYPE 0xB9u
#define DPC31_DPV1_READ_CONSTRAIN_CONFLICT 0xC0u
#define DPC31_DPV1_WRITE_CONSTRAIN_CONFLICT 0xC1u
#define DPC31_DPV1_RESOURCE_BUSY 0xC2u
#define DPC31_DPV1_RESOURCE_UNAVAILABLE 0xC3u
#define DPC31_DPV1_FEATURE_NOT_SUPPORTED 0xA9u /* application: feature not supported */

/* MSAC_C2's Initiate (docs/dpv1.md "The Initiate"): the request's bytes through D_Len (57h, 3
 * reserved, Send_Timeout, Features_Supported_1 and _2, Profile_Features_Supported,
 * Profile_Ident_Number, S_Type, S_Len, D_Type, D_Len), its response's (57h, Max_Len_Data_Unit,
 * then the same from Features_Supported on), a Type 0 address (API and SCL, Len 2) and the least
 * request with two of them (the Profichip driver's MSAC_C2_MIN_CR_PDU_SIZE). */
#define DPC31_MSAC_C2_INITIATE_REQ_FIXED 16u
#define DPC31_MSAC_C2_INITIATE_RES_FIXED 12u
#define DPC31_MSAC_C2_ADDR_TYPE_API_SCL 0x00u
#define DPC31_MSAC_C2_ADDR_LEN_API_SCL 2u
#define DPC31_MSAC_C2_INITIATE_MIN 20u
#define DPC31_MSAC_C2_FEATURES_1_RW 0x01u /* Features_Supported_1: Read and Write supported */
/* The Send_Timeout (10 ms units) the Profichip driver keeps a connection on at least (its
 * MSAC_C2_TIMEOUT_12MBAUD .. _1_5MBAUD), and the one its refusals run on. */
#define DPC31_MSAC_C2_TIMEOUT_MIN 100u

/* MSAC_C2's Abort (4 bytes): 58h, Subnet, Instance (bits 5..4) | Reason_Code (bits 3..0),
 * Additional_Detail; the ones the Profichip driver sends for an Initiate it refuses. */
#define DPC31_MSAC_C2_INSTANCE_MSAC_C2 0x10u
#define DPC31_MSAC_C2_ABT_FE 0x02u /* invalid request PDU received */
#define DPC31_MSAC_C2_ABT_IA 0x07u /* invalid additional address information */

#endif /* DPC31_PDU_H */
