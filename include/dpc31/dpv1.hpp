// The VPC3+'s DPV1 interface in its RAM (VPC3+C User Manual Rev 1.03 chapter 7, pp. 54-56; the
// VPC3+S Rev 1.04 pp. 60-63): the SAP list whose segment is in R_FDL_SAP_List_Ptr (17h), its
// 7-byte entries, and the 4-byte header of each indication / response buffer. The firmware lays
// them out in the user area while Offline; the chip reads them at every request (docs/dpv1.md).
// The bits below are the manual's figures 7-3 and 7-4; what the manual leaves open is marked
// modelled (docs/decisions.md).
#pragma once

#include <cstdint>

namespace dpc31::dpv1 {

// Figure 7-3: one SAP-list entry. Byte 0 = FFh ends the list.
namespace entry {
inline constexpr std::uint32_t kBytes = 7;
inline constexpr std::uint8_t kEndOfList = 0xFF;
// Byte offsets.
inline constexpr std::uint32_t Sap = 0;                // Response_Sent, SAP_Number
inline constexpr std::uint32_t Request_SA = 1;         // 7Fh: any source address
inline constexpr std::uint32_t Request_SSAP = 2;       // 7Fh: any source SAP
inline constexpr std::uint32_t Service_Supported = 3;  // 00h: all FDL services
inline constexpr std::uint32_t Ind_Buf_Ptr0 = 4;       // segment; 00h: SAP not activated (modelled)
inline constexpr std::uint32_t Ind_Buf_Ptr1 = 5;       // segment; 00h or = Ind_Buf_Ptr0: one buffer
inline constexpr std::uint32_t Resp_Buf_Ptr = 6;       // segment; 00h: no response buffer
// Byte 0 bits.
inline constexpr std::uint8_t Response_Sent = 0x80;  // set by the chip, cleared by the user
inline constexpr std::uint8_t SAP_Number = 0x3F;
// Request_SA / Request_SSAP: the value that lets every station / SAP in ("default value 7FH").
inline constexpr std::uint8_t kAll = 0x7F;
}  // namespace entry

// Service_Supported codes (the FDL Access_SAP service types, as the Profichip driver codes them;
// modelled: the manual names only 00h).
namespace service {
inline constexpr std::uint8_t All = 0x00;
inline constexpr std::uint8_t SDN_L = 0x01;
inline constexpr std::uint8_t SDN_H = 0x02;
inline constexpr std::uint8_t SDN_LH = 0x03;
inline constexpr std::uint8_t SDN_SRD_LH = 0x04;
inline constexpr std::uint8_t SRD_L = 0x09;
inline constexpr std::uint8_t SRD_H = 0x0A;
inline constexpr std::uint8_t SRD_LH = 0x0B;
}  // namespace service

// Figure 7-4: the header of an indication or response buffer; the data follow it.
namespace header {
inline constexpr std::uint32_t kBytes = 4;
inline constexpr std::uint32_t Control = 0;
inline constexpr std::uint32_t Max_Length = 1;     // length of the data block
inline constexpr std::uint32_t Length = 2;         // length of the data in it
inline constexpr std::uint32_t Function_Code = 3;  // indication: the request's FC; response: ours
// Control bits.
inline constexpr std::uint8_t USER = 0x80;   // buffer assigned to user
inline constexpr std::uint8_t IND = 0x40;    // indication data included in buffer
inline constexpr std::uint8_t RESP = 0x20;   // response data included in buffer
inline constexpr std::uint8_t INUSE = 0x10;  // buffer assigned to VPC3+
}  // namespace header

// Set_Prm bytes 7-9 with DPV1 (VPC3+C p.53, Figure 7-1).
namespace status1 {
inline constexpr std::uint8_t DPV1_Enable = 0x80;
inline constexpr std::uint8_t Fail_Safe = 0x40;
inline constexpr std::uint8_t Publisher_Enable = 0x20;
inline constexpr std::uint8_t Reserved = 0x18;
inline constexpr std::uint8_t WD_Base = 0x04;
inline constexpr std::uint8_t Dis_Stop_Control = 0x02;
inline constexpr std::uint8_t Dis_Start_Control = 0x01;
}  // namespace status1
namespace status2 {
inline constexpr std::uint8_t Enable_Pull_Plug_Alarm = 0x80;
inline constexpr std::uint8_t Enable_Process_Alarm = 0x40;
inline constexpr std::uint8_t Enable_Diagnostic_Alarm = 0x20;
inline constexpr std::uint8_t Enable_Manufacturer_Specific_Alarm = 0x10;
inline constexpr std::uint8_t Enable_Status_Alarm = 0x08;
inline constexpr std::uint8_t Enable_Update_Alarm = 0x04;
inline constexpr std::uint8_t Reserved = 0x02;
inline constexpr std::uint8_t Chk_Cfg_Mode = 0x01;
}  // namespace status2
namespace status3 {
inline constexpr std::uint8_t PrmCmd = 0x80;
inline constexpr std::uint8_t Reserved = 0x60;
inline constexpr std::uint8_t IsoM_Req = 0x10;
inline constexpr std::uint8_t Prm_Structure = 0x08;
inline constexpr std::uint8_t Alarm_Mode = 0x07;
}  // namespace status3
// The Set_Prm byte offsets of DPV1_Status_1..3; User_Prm_Data start at kUserPrm.
inline constexpr std::uint32_t kStatus1 = 7;
inline constexpr std::uint32_t kStatus2 = 8;
inline constexpr std::uint32_t kStatus3 = 9;
inline constexpr std::uint32_t kUserPrm = 10;

}  // namespace dpc31::dpv1
