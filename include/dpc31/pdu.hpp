// The DP and DPV1 data units, each declared once (EN 50170 / IEC 61158-6 type 3, the VPC3+C
// manual's Figure 7-1 for Set_Prm with DPV1; the Profichip driver's dp_if.h for the DPV1 function
// numbers and error codes): a struct with named fields, `parse` (nullopt on a data unit that is
// not one of these: wrong function number or length) and `build`. The chip (Set_Prm's checks),
// the built-in master, traces and the dissector's tests use these; nobody indexes the bytes.
// Pure: no chip state, no timing. The data unit excludes the SAP bytes (fdl::Frame::du).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "dpv1.hpp"

namespace dpc31::pdu {

using Bytes = std::vector<std::uint8_t>;
using View = std::span<const std::uint8_t>;

// --- DP ---

// Global_Control (SAP 58): Control_Command, then Group_Select. The Control_Command bits (DPC31 HW
// description p.32, seed 003); bits 7, 6 and 0 are reserved.
namespace control_command {
inline constexpr std::uint8_t Sync = 0x20, Unsync = 0x10, Freeze = 0x08, Unfreeze = 0x04,
                              Clear_Data = 0x02, Reserved = 0xC1;
}  // namespace control_command

// Set_Prm (SAP 61): seven standard bytes, then (DPV0) the Spec_User_Prm_Byte and User_Prm_Data,
// or (DPV1_Enable in byte 7) DPV1_Status_1..3 and the User_Prm_Data from byte 10.
struct SetPrm {
  // Station_Status (byte 0).
  static constexpr std::uint8_t Lock_Req = 0x80, Unlock_Req = 0x40, Sync_Req = 0x20,
                                Freeze_Req = 0x10, WD_On = 0x08, Station_Status_Reserved = 0x07;
  static constexpr std::size_t kStandard = 7;

  std::uint8_t station_status = 0;
  std::uint8_t wd_fact1 = 1;
  std::uint8_t wd_fact2 = 1;
  std::uint8_t min_tsdr = 0;
  std::uint16_t ident = 0;
  std::uint8_t group_ident = 0;
  // From byte 7 on as sent: the Spec_User_Prm_Byte or DPV1_Status_1..3, then User_Prm_Data.
  Bytes user_prm;

  [[nodiscard]] bool dpv1() const {
    return !user_prm.empty() && (user_prm[0] & dpv1::status1::DPV1_Enable) != 0;
  }
  // DPV1_Status_1..3 (0 where the telegram has no such byte).
  [[nodiscard]] std::uint8_t status(unsigned k) const {
    return k >= 1 && k <= 3 && user_prm.size() >= k ? user_prm[k - 1] : 0;
  }
  // The User_Prm_Data after the DPV1_Status bytes (DPV1) or after the Spec_User_Prm_Byte.
  [[nodiscard]] View user_data() const;

  static std::optional<SetPrm> parse(View du);  // nullopt: fewer than 7 bytes
  [[nodiscard]] Bytes build() const;
  friend bool operator==(const SetPrm&, const SetPrm&) = default;
};

// Slave_Diag (SAP 60) answer: the six standard bytes and the extended diagnosis blocks.
struct SlaveDiag {
  // Station_Status_1..3 bits (chip-facts §8).
  static constexpr std::uint8_t St1_Station_Non_Existent = 0x01, St1_Station_Not_Ready = 0x02,
                                St1_Cfg_Fault = 0x04, St1_Ext_Diag = 0x08, St1_Not_Supported = 0x10,
                                St1_Invalid_Slave_Response = 0x20, St1_Prm_Fault = 0x40,
                                St1_Master_Lock = 0x80;
  static constexpr std::uint8_t St2_Prm_Req = 0x01, St2_Stat_Diag = 0x02, St2_Always_1 = 0x04,
                                St2_WD_On = 0x08, St2_Freeze_Mode = 0x10, St2_Sync_Mode = 0x20,
                                St2_Deactivated = 0x80;
  static constexpr std::uint8_t St3_Ext_Diag_Overflow = 0x80;
  static constexpr std::size_t kStandard = 6;

  // An extended diagnosis block: its header's bits 7..6 say which (00 device-related with the
  // DPV1 alarm / status blocks inside, 01 identifier-related, 10 channel-related).
  enum class Kind : std::uint8_t { device = 0, identifier = 1, channel = 2, reserved = 3 };
  struct Block {
    Kind kind = Kind::device;
    Bytes bytes;  // the whole block, header included
    friend bool operator==(const Block&, const Block&) = default;
  };

  std::uint8_t station_status_1 = 0;
  std::uint8_t station_status_2 = St2_Always_1;
  std::uint8_t station_status_3 = 0;
  static constexpr std::uint8_t kNoMaster = 0xFF;  // Master_Add: no master parameterised it
  std::uint8_t master_add = kNoMaster;
  std::uint16_t ident = 0;
  std::vector<Block> blocks;

  static std::optional<SlaveDiag> parse(View du);  // nullopt: short, or a block runs past the end
  [[nodiscard]] Bytes build() const;
  friend bool operator==(const SlaveDiag&, const SlaveDiag&) = default;
};

// A DPV1 alarm or status block inside a device-related block (DPV1): header (length incl.
// itself), Alarm_Type / Status_Type (bit 7: 0 alarm, 1 status), Slot_Number, Specifier, then
// the diagnosis data.
struct Dpv1DiagBlock {
  static constexpr std::uint8_t kStatusFlag = 0x80;
  static constexpr std::size_t kHeader = 4;
  bool status = false;    // a status block (Status_Type), else an alarm (Alarm_Type)
  std::uint8_t type = 0;  // Alarm_Type 1 diagnosis, 2 process, 3 pull, 4 plug, 5 status, 6 update
  std::uint8_t slot = 0;
  // Specifier: alarm sequence number (bits 7..3), Add_Ack (bit 2), specifier (bits 1..0:
  // 1 appears, 2 disappears, 3 disappears other errors remain).
  std::uint8_t specifier = 0;
  Bytes data;

  [[nodiscard]] std::uint8_t seq_nr() const { return specifier >> 3; }
  static std::optional<Dpv1DiagBlock> parse(const SlaveDiag::Block& b);
  [[nodiscard]] SlaveDiag::Block build() const;
  friend bool operator==(const Dpv1DiagBlock&, const Dpv1DiagBlock&) = default;
};

// Chk_Cfg (SAP 62) / Get_Cfg: identifier bytes (general format) with what they declare.
struct Cfg {
  struct Module {
    Bytes bytes;                // the identifier byte(s) as sent
    std::uint16_t inputs = 0;   // bytes
    std::uint16_t outputs = 0;  // bytes
  };
  std::vector<Module> modules;

  // nullopt: a special-format identifier runs past the end.
  static std::optional<Cfg> parse(View du);
  [[nodiscard]] Bytes build() const;
  [[nodiscard]] std::uint16_t input_bytes() const;
  [[nodiscard]] std::uint16_t output_bytes() const;
};

// --- DPV1 (MSAC_C1 on SAP 50 / 51, MSAC_C2 on SAP 49 and the connection's SAP) ---

enum class Function : std::uint8_t {
  Idle = 0x48,
  Data_Transport = 0x51,
  Resource_Manager = 0x56,  // the RM's immediate response (SAP 49)
  Initiate = 0x57,
  Abort = 0x58,
  Alarm_Ack = 0x5C,
  Read = 0x5E,
  Write = 0x5F,
};
inline constexpr std::uint8_t kErrorBit = 0x80;  // a negative response's function number
// Error_Decode 80h: DPV1; Error_Code_1 = class (bits 7..4) | code (bits 3..0).
inline constexpr std::uint8_t Error_Decode_DPV1 = 0x80;
namespace error {
inline constexpr std::uint8_t Invalid_Index = 0xB0;
inline constexpr std::uint8_t Write_Length_Error = 0xB1;
inline constexpr std::uint8_t Invalid_Slot = 0xB2;
inline constexpr std::uint8_t Type_Conflict = 0xB3;
inline constexpr std::uint8_t Invalid_Area = 0xB4;
inline constexpr std::uint8_t State_Conflict = 0xB5;
inline constexpr std::uint8_t Access_Denied = 0xB6;
inline constexpr std::uint8_t Invalid_Range = 0xB7;
inline constexpr std::uint8_t Invalid_Parameter = 0xB8;
inline constexpr std::uint8_t Invalid_Type = 0xB9;
inline constexpr std::uint8_t Read_Constrain_Conflict = 0xC0;
inline constexpr std::uint8_t Write_Constrain_Conflict = 0xC1;
inline constexpr std::uint8_t Feature_Not_Supported = 0xA9;  // application: not supported
inline constexpr std::uint8_t Resource_Busy = 0xC2;
inline constexpr std::uint8_t Resource_Unavailable = 0xC3;
}  // namespace error

// The function number of a DPV1 data unit, if it has one (its first byte without kErrorBit).
[[nodiscard]] std::optional<Function> function_of(View du);
[[nodiscard]] bool is_negative(View du);

// Read request (4 bytes) and positive response (4 + data); Write request (4 + data) and
// positive response (4); Data_Transport request and response (4 + data). `length` is the
// request's Length byte (Read: the bytes wanted; Write / Data_Transport: data.size()).
struct Record {
  Function function = Function::Read;
  std::uint8_t slot = 0;
  std::uint8_t index = 0;
  std::uint8_t length = 0;
  Bytes data;  // none in a Read request and a Write response

  // A Read / Write / Data_Transport PDU: with data when `with_data` (Read response, Write and
  // Data_Transport request and response), Length = data bytes; else exactly 4 bytes.
  static std::optional<Record> parse(View du, Function f, bool with_data);
  [[nodiscard]] Bytes build() const;
  friend bool operator==(const Record&, const Record&) = default;
};
[[nodiscard]] Record read_request(std::uint8_t slot, std::uint8_t index, std::uint8_t length);
[[nodiscard]] Record write_request(std::uint8_t slot, std::uint8_t index, Bytes data);

// Alarm_Ack request and positive response: 5Ch, Slot_Number, Alarm_Type, Specifier (4 bytes).
struct AlarmAck {
  std::uint8_t slot = 0;
  std::uint8_t alarm_type = 0;
  std::uint8_t specifier = 0;
  static std::optional<AlarmAck> parse(View du);
  [[nodiscard]] Bytes build() const;
  friend bool operator==(const AlarmAck&, const AlarmAck&) = default;
};

// A negative response: function number | 80h, Error_Decode, Error_Code_1, Error_Code_2.
struct ErrorResponse {
  Function function = Function::Read;
  std::uint8_t error_decode = Error_Decode_DPV1;
  std::uint8_t error_code_1 = 0;
  std::uint8_t error_code_2 = 0;
  static std::optional<ErrorResponse> parse(View du);
  [[nodiscard]] Bytes build() const;
  friend bool operator==(const ErrorResponse&, const ErrorResponse&) = default;
};

// MSAC_C2 Initiate request: 57h, 3 reserved, Send_Timeout, Features_Supported,
// Profile_Features_Supported, Profile_Ident_Number, then Add_Addr_Param (S_Type, S_Len, D_Type,
// D_Len, S_Addr, D_Addr). The response: 57h, Max_Len_Data_Unit, Features_Supported,
// Profile_Features_Supported, Profile_Ident_Number, Add_Addr_Param. Features_Supported is two
// bytes on the wire, Features_Supported_1 first (the high byte of the field here): its bit 0 is
// "Read and Write supported" (the Profichip driver's C2_FEATURES_SUPPORTED_1 01h, _2 00h).
inline constexpr std::uint16_t Features_DPV1_RW = 0x0100;
// Add_Addr_Param's Type 0: the address is API and SCL, one byte each (Len 2); the Profichip
// driver aborts an Initiate whose Type 0 address has another Len, or that is shorter than
// 20 bytes (MSAC_C2_MIN_CR_PDU_SIZE).
inline constexpr std::uint8_t Addr_Type_API_SCL = 0;
// The request's and the response's bytes through D_Len, and the request's least length with
// Type 0 addresses.
inline constexpr std::size_t kAddrLenAPISCL = 2, kInitiateReqFixed = 16, kInitiateResFixed = 12,
                             kInitiateReqMin = 20;
// The Send_Timeout (10 ms) the Profichip driver keeps a connection on at least (its
// MSAC_C2_TIMEOUT_12MBAUD .. _1_5MBAUD), and the one its refusals run on.
inline constexpr std::uint16_t kMsacC2TimeoutMin = 100;
struct Initiate {
  bool response = false;
  std::uint16_t send_timeout = 0;      // request only, 10 ms units
  std::uint8_t max_len_data_unit = 0;  // response only
  std::uint16_t features_supported = 0;
  std::uint16_t profile_features_supported = 0;
  std::uint16_t profile_ident_number = 0;
  std::uint8_t s_type = 0;
  std::uint8_t d_type = 0;
  Bytes s_addr;
  Bytes d_addr;
  static std::optional<Initiate> parse(View du, bool response);
  [[nodiscard]] Bytes build() const;
  friend bool operator==(const Initiate&, const Initiate&) = default;
};
// The class-2 master's Initiate request: Read/Write (Features_DPV1_RW), no profile, S_Addr and
// D_Addr of Type 0: API 0, SCL 0 each (20 bytes).
[[nodiscard]] Initiate initiate_request(std::uint16_t send_timeout);

// MSAC_C2 Abort: 58h, Subnet, Instance (bits 5..4) | Reason_Code (bits 3..0), Additional_Detail.
struct Abort {
  std::uint8_t subnet = 0;
  std::uint8_t instance = 0;     // 0 FDL, 1 MSAC_C2, 2 user
  std::uint8_t reason_code = 0;  // e.g. 3 TO: the connection timed out
  std::uint8_t additional_detail = 0;
  static std::optional<Abort> parse(View du);
  [[nodiscard]] Bytes build() const;
  friend bool operator==(const Abort&, const Abort&) = default;
};
// Instance and Reason_Code values (the Profichip driver's MSAC_C2_INSTANCE_*, MSAC_C2_ABT_*).
inline constexpr std::uint8_t Abort_Instance_MSAC_C2 = 1;
inline constexpr std::uint8_t Abort_FE = 0x02;  // invalid request PDU received
inline constexpr std::uint8_t Abort_IA = 0x07;  // invalid additional address information
// The slave's checks of an Initiate request before its user sees it (the Profichip driver's
// MSAC_C2_RealizeIndRecv): a Type 0 address whose Len is not 2 is Abort FE, a request shorter
// than 20 bytes or than 16 + S_Len + D_Len is Abort IA (MSAC_C2 instance, Subnet 0); nullopt:
// accepted (bytes past the addresses are ignored).
[[nodiscard]] std::optional<Abort> initiate_abort(View req);

// MSAC_C2 Idle: 48h and one reserved byte. The RM's immediate response on SAP 49: 56h, the
// connection's SAP, Send_Timeout (high, low).
struct Idle {
  static std::optional<Idle> parse(View du);
  [[nodiscard]] Bytes build() const;
  friend bool operator==(const Idle&, const Idle&) = default;
};
struct ResourceManager {
  std::uint8_t sap = 0;
  std::uint16_t send_timeout = 0;
  static std::optional<ResourceManager> parse(View du);
  [[nodiscard]] Bytes build() const;
  friend bool operator==(const ResourceManager&, const ResourceManager&) = default;
};

}  // namespace dpc31::pdu
