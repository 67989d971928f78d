// DP layer constants of the telegrams (EN 50170 / IEC 61158 type 3): the service access points
// (SAPs) of the DP services, as a master addresses them and the slave answers from them; and the
// DPC31's request and indication codes.
#pragma once

#include <cstdint>

namespace dpc31 {

// DP service access points (DSAP at the slave) and the master's SSAP.
namespace sap {
inline constexpr std::uint8_t Set_Slave_Add = 55;
inline constexpr std::uint8_t Rd_Inp = 56;
inline constexpr std::uint8_t Rd_Outp = 57;
inline constexpr std::uint8_t Global_Control = 58;
inline constexpr std::uint8_t Get_Cfg = 59;
inline constexpr std::uint8_t Slave_Diag = 60;
inline constexpr std::uint8_t Set_Prm = 61;
inline constexpr std::uint8_t Chk_Cfg = 62;
inline constexpr std::uint8_t Master = 62;
// DPV1 (VPC3+C p.53 "Set_(Ext_)Prm (SAP 53 / SAP 61)"; the MSAC services of IEC 61158-6-3): the
// SAPs a firmware puts into the VPC3+'s SAP list (0-51), and Set_Ext_Prm, which the chip serves.
inline constexpr std::uint8_t MSAC_C2_RM = 49;  // class-2 resource manager (Initiate)
inline constexpr std::uint8_t MSAC_C1_Alarm = 50;
inline constexpr std::uint8_t MSAC_C1 = 51;  // class-1 Read / Write / Alarm_Ack
inline constexpr std::uint8_t Set_Ext_Prm = 53;
inline constexpr std::uint8_t kSapListLast = 51;  // SAP_Number: 0 - 51 (VPC3+C p.55)
}  // namespace sap

// The DPC31's request interface (DPC31 HW description p.22, Table 5.1-3, p.31; docs/dpc31.md):
// request codes and the DPS_User_Wd parameters, written by the user into the Instruction_Queue.
namespace request {
inline constexpr std::uint8_t MAC_Start = 0x10;
inline constexpr std::uint8_t MAC_Stop = 0x11;
inline constexpr std::uint8_t MAC_New_TRDY = 0x12;
inline constexpr std::uint8_t User_Leave_Master = 0x15;
inline constexpr std::uint8_t DPS_User_Wd = 0x20;
inline constexpr std::uint8_t Wd_Reset = 0x00;
inline constexpr std::uint8_t Wd_Enable = 0x01;
inline constexpr std::uint8_t Wd_Disable = 0x02;
// Indications: the code of the request they answer, and the event (modelled, docs/dpc31.md).
inline constexpr std::uint8_t Stop_Confirmed = 0x00;  // MAC_Stop executed: the MAC is Offline
inline constexpr std::uint8_t Wd_Expired = 0x03;      // DPS_User_WD Expired
inline constexpr std::uint32_t kEntryBytes = 2;       // code, parameter
}  // namespace request

}  // namespace dpc31
