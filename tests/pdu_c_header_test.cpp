// dpc31_pdu.h, the C names of a DP / DPV1 driver, hold the C++ side's values (pdu.hpp, fdl.hpp,
// dp.hpp): checked at compile time; the program only reports that it was built.
#include <cstdio>

#include "dpc31/dp.hpp"
#include "dpc31/dpc31_pdu.h"
#include "dpc31/fdl.hpp"
#include "dpc31/pdu.hpp"

namespace {

using dpc31::pdu::SlaveDiag;
namespace error = dpc31::pdu::error;
using F = dpc31::pdu::Function;

constexpr unsigned u(F f) { return static_cast<unsigned>(f); }

// SPC3 p.33: the user's bits are "the three least significant bit positions in the first byte";
// which is which: docs/decisions.md, "s22-do4" (Ext_Diag, Stat_Diag, Ext_Diag_Overflow).
static_assert(DPC31_DIAG_EXT_DIAG == 0x01 && DPC31_DIAG_STAT_DIAG == 0x02 &&
              DPC31_DIAG_EXT_DIAG_OVERFLOW == 0x04);
static_assert(DPC31_DIAG_USER_BITS ==
              (DPC31_DIAG_EXT_DIAG | DPC31_DIAG_STAT_DIAG | DPC31_DIAG_EXT_DIAG_OVERFLOW));
static_assert(DPC31_DIAG_STANDARD == SlaveDiag::kStandard);
static_assert(DPC31_DIAG_STATION_STATUS_1 == 0 && DPC31_DIAG_STATION_STATUS_2 == 1 &&
              DPC31_DIAG_STATION_STATUS_3 == 2 && DPC31_DIAG_MASTER_ADD == 3 &&
              DPC31_DIAG_IDENT_HIGH == 4 && DPC31_DIAG_IDENT_LOW == 5);
static_assert(DPC31_DIAG_NO_MASTER == SlaveDiag{}.master_add);

static_assert(DPC31_ST1_STATION_NON_EXISTENT == SlaveDiag::St1_Station_Non_Existent);
static_assert(DPC31_ST1_STATION_NOT_READY == SlaveDiag::St1_Station_Not_Ready);
static_assert(DPC31_ST1_CFG_FAULT == SlaveDiag::St1_Cfg_Fault);
static_assert(DPC31_ST1_EXT_DIAG == SlaveDiag::St1_Ext_Diag);
static_assert(DPC31_ST1_NOT_SUPPORTED == SlaveDiag::St1_Not_Supported);
static_assert(DPC31_ST1_INVALID_SLAVE_RESPONSE == SlaveDiag::St1_Invalid_Slave_Response);
static_assert(DPC31_ST1_PRM_FAULT == SlaveDiag::St1_Prm_Fault);
static_assert(DPC31_ST1_MASTER_LOCK == SlaveDiag::St1_Master_Lock);
static_assert(DPC31_ST2_PRM_REQ == SlaveDiag::St2_Prm_Req);
static_assert(DPC31_ST2_STAT_DIAG == SlaveDiag::St2_Stat_Diag);
static_assert(DPC31_ST2_ALWAYS_1 == SlaveDiag::St2_Always_1);
static_assert(DPC31_ST2_WD_ON == SlaveDiag::St2_WD_On);
static_assert(DPC31_ST2_FREEZE_MODE == SlaveDiag::St2_Freeze_Mode);
static_assert(DPC31_ST2_SYNC_MODE == SlaveDiag::St2_Sync_Mode);
static_assert(DPC31_ST2_DEACTIVATED == SlaveDiag::St2_Deactivated);
static_assert(DPC31_ST3_EXT_DIAG_OVERFLOW == SlaveDiag::St3_Ext_Diag_Overflow);

static_assert(DPC31_SAP_MSAC_C2_RM == dpc31::sap::MSAC_C2_RM);
static_assert(DPC31_SAP_MSAC_C1_ALARM == dpc31::sap::MSAC_C1_Alarm);
static_assert(DPC31_SAP_MSAC_C1 == dpc31::sap::MSAC_C1);
static_assert(DPC31_DPV1_FC_RESPONSE == static_cast<unsigned>(dpc31::fdl::Response::DL));

static_assert(DPC31_DPV1_IDLE == u(F::Idle));
static_assert(DPC31_DPV1_DATA_TRANSPORT == u(F::Data_Transport));
static_assert(DPC31_DPV1_RESOURCE_MANAGER == u(F::Resource_Manager));
static_assert(DPC31_DPV1_INITIATE == u(F::Initiate));
static_assert(DPC31_DPV1_ABORT == u(F::Abort));
static_assert(DPC31_DPV1_ALARM_ACK == u(F::Alarm_Ack));
static_assert(DPC31_DPV1_READ == u(F::Read));
static_assert(DPC31_DPV1_WRITE == u(F::Write));

static_assert(DPC31_DPV1_ERROR_BIT == dpc31::pdu::kErrorBit);
static_assert(DPC31_DPV1_ERROR_DECODE_DPV1 == dpc31::pdu::Error_Decode_DPV1);
static_assert(DPC31_DPV1_INVALID_INDEX == error::Invalid_Index);
static_assert(DPC31_DPV1_WRITE_LENGTH_ERROR == error::Write_Length_Error);
static_assert(DPC31_DPV1_INVALID_SLOT == error::Invalid_Slot);
static_assert(DPC31_DPV1_TYPE_CONFLICT == error::Type_Conflict);
static_assert(DPC31_DPV1_INVALID_AREA == error::Invalid_Area);
static_assert(DPC31_DPV1_STATE_CONFLICT == error::State_Conflict);
static_assert(DPC31_DPV1_ACCESS_DENIED == error::Access_Denied);
static_assert(DPC31_DPV1_INVALID_RANGE == error::Invalid_Range);
static_assert(DPC31_DPV1_INVALID_PARAMETER == error::Invalid_Parameter);
static_assert(DPC31_DPV1_INVALID_TYPE == error::Invalid_Type);
static_assert(DPC31_DPV1_READ_CONSTRAIN_CONFLICT == error::Read_Constrain_Conflict);
static_assert(DPC31_DPV1_WRITE_CONSTRAIN_CONFLICT == error::Write_Constrain_Conflict);
static_assert(DPC31_DPV1_RESOURCE_BUSY == error::Resource_Busy);
static_assert(DPC31_DPV1_RESOURCE_UNAVAILABLE == error::Resource_Unavailable);
static_assert(DPC31_DPV1_FEATURE_NOT_SUPPORTED == error::Feature_Not_Supported);

static_assert(DPC31_MSAC_C2_INITIATE_REQ_FIXED == dpc31::pdu::kInitiateReqFixed);
static_assert(DPC31_MSAC_C2_INITIATE_RES_FIXED == dpc31::pdu::kInitiateResFixed);
static_assert(DPC31_MSAC_C2_ADDR_TYPE_API_SCL == dpc31::pdu::Addr_Type_API_SCL);
static_assert(DPC31_MSAC_C2_ADDR_LEN_API_SCL == dpc31::pdu::kAddrLenAPISCL);
static_assert(DPC31_MSAC_C2_INITIATE_MIN == dpc31::pdu::kInitiateReqMin);
static_assert(DPC31_MSAC_C2_TIMEOUT_MIN == dpc31::pdu::kMsacC2TimeoutMin);
// Features_Supported_1 is the high byte of pdu::Initiate's field.
static_assert(DPC31_MSAC_C2_FEATURES_1_RW << 8 == dpc31::pdu::Features_DPV1_RW);
// The Abort's third byte as the C name gives it: Instance in bits 5..4.
static_assert(DPC31_MSAC_C2_INSTANCE_MSAC_C2 == dpc31::pdu::Abort_Instance_MSAC_C2 << 4);
static_assert(DPC31_MSAC_C2_ABT_FE == dpc31::pdu::Abort_FE);
static_assert(DPC31_MSAC_C2_ABT_IA == dpc31::pdu::Abort_IA);

}  // namespace

int main() {
  std::puts("dpc31_pdu.h agrees with pdu.hpp, fdl.hpp and dp.hpp");
  return 0;
}
