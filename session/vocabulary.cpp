// The names of vocabulary.hpp.
#include "vocabulary.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "dpc31/dp.hpp"
#include "dpc31/dpv1.hpp"
#include "dpc31/names.hpp"
#include "textfile.hpp"
#include "whole_number.hpp"

namespace dpc31 {

constexpr std::array<std::string_view, 3> kDpStateNames = {"Wait_Prm", "Wait_Cfg", "Data_Exchange"};
static_assert(kDpStateNames.size() == static_cast<std::size_t>(DpState::Data_Exchange) + 1,
              "a new value: name it here");

std::string addresses_too_long(std::size_t s_len, std::size_t d_len) {
  if (s_len + d_len <= kAddrMax) return {};
  return fmt::format(
      "s_addr and d_addr: {} bytes together, more than {}: the Initiate ({} bytes) would not fit "
      "the resource manager's {}-byte buffer",
      s_len + d_len, kAddrMax, pdu::kInitiateReqFixed + s_len + d_len, Dpv1User::kRmMax);
}

std::string_view dp_state_name(DpState s) { return name_of(s, kDpStateNames); }

constexpr std::array<std::string_view, 3> kWdStateNames = {"Baud_Search", "Baud_Control",
                                                           "DP_Control"};
static_assert(kWdStateNames.size() == static_cast<std::size_t>(WdState::DP_Control) + 1,
              "a new value: name it here");

std::string_view wd_state_name(WdState s) { return name_of(s, kWdStateNames); }

std::span<const CounterField> fdl_counter_fields() { return kFdlCounterFields; }

std::string counters_text(const FdlCounters& c) {
  std::string s;
  for (const CounterField& f : fdl_counter_fields()) {
    const std::uint32_t v = c.*(f.member);
    if (v == 0) continue;
    if (!s.empty()) s += ',';
    s += fmt::format("{}:{}", f.name, v);
  }
  return s.empty() ? "-" : s;
}

// The SAPs with a DP or DPV1 service, 49 to 62, in order (include/dpc31/dp.hpp): the names every
// decoder gives them (tests/decoder_sap_names.py); 52 and 54 have none.
constexpr std::array<std::string_view, 14> kSapNames = {
    "MSAC_C2_Initiate",  // 49: the class-2 resource manager
    "MSAC_C1_Alarm",     // 50
    "MSAC_C1",           // 51
    "",                  // 52
    "Set_Ext_Prm",       // 53
    "",                  // 54
    "Set_Slave_Add",     // 55
    "Rd_Inp",
    "Rd_Outp",
    "Global_Control",
    "Get_Cfg",
    "Slave_Diag",
    "Set_Prm",
    "Chk_Cfg",  // 62
};
static_assert(sap::MSAC_C2_RM + kSapNames.size() == sap::Chk_Cfg + 1u &&
                  kSapNames[sap::MSAC_C1_Alarm - sap::MSAC_C2_RM] == "MSAC_C1_Alarm" &&
                  kSapNames[sap::Set_Ext_Prm - sap::MSAC_C2_RM] == "Set_Ext_Prm" &&
                  kSapNames[sap::Set_Slave_Add - sap::MSAC_C2_RM] == "Set_Slave_Add",
              "the named SAPs are 49..62");

std::string service_name(const fdl::Frame& f) {
  const fdl::Function fn = fdl::request_function(f.fc);
  if (fn == fdl::Function::FDL_Status) return "FDL_Status";
  if (!f.dsap) {
    return fn == fdl::Function::SRD_high || fn == fdl::Function::SRD_low ? "Data_Exchange"
                                                                         : "no SAP";
  }
  const std::uint8_t sap = fdl::sap_number(*f.dsap);
  if (sap < sap::MSAC_C2_RM || sap > sap::Chk_Cfg || kSapNames[sap - sap::MSAC_C2_RM].empty()) {
    return fmt::format("SAP {}", sap);
  }
  return std::string(kSapNames[sap - sap::MSAC_C2_RM]);
}

FirmwarePlace::FirmwarePlace(std::string file, int line)
    : file_(std::move(file)),
      line_(line),
      text_(line == 0 ? file_ : fmt::format("{}:{}", file_, line)) {}

void FirmwarePlace::enter(int line, std::string_view step_text) {
  line_ = line;
  step_ = step_text.substr(0, step_text.find(' '));  // the step's keyword
  text_ = fmt::format("{}:{}: {}", file_, line_, step_);
}

std::string FirmwarePlace::message(std::string_view what) const {
  return text_.empty() ? std::string(what) : fmt::format("{}: {}", text_, what);
}

// Indexed by the 4-bit code (EN 50170): the request function codes and the response codes.
constexpr std::array<std::string_view, 16> kFunctionNames = {
    "", "",           "", "SDA_low", "SDN_low", "SDA_high", "SDN_high", "DDB",
    "", "FDL_Status", "", "",        "SRD_low", "SRD_high", "Ident",    "LSAP_Status"};
constexpr std::array<std::string_view, 16> kResponseNames = {
    "OK", "UE", "RR", "RS", "", "", "", "", "DL", "NR", "DH", "", "RDL", "RDH", "", ""};

// The name of a 4-bit code, or `other` for a code without one.
template <typename E>
std::string_view code_name(E code, const std::array<std::string_view, 16>& names,
                           std::string_view other) {
  const auto i = static_cast<std::size_t>(code);
  return i < names.size() && !names[i].empty() ? names[i] : other;
}

std::string_view function_name(fdl::Function f) {
  return code_name(f, kFunctionNames, "function?");
}

std::string_view response_name(fdl::Response r) { return code_name(r, kResponseNames, "FC?"); }

// By UartFault::Kind: none, parity, start, stop.
constexpr std::array<std::string_view, 4> kFaultNames = {"no fault", "parity error", "no start bit",
                                                         "stop bit 0"};
constexpr std::array<std::string_view, 4> kFaultKindNames = {"none", "parity", "start", "stop"};
static_assert(kFaultNames.size() == static_cast<std::size_t>(UartFault::Kind::stop) + 1,
              "a new value: name it here");

std::string_view fault_name(UartFault::Kind k) { return name_of(k, kFaultNames); }

std::string_view fault_kind_name(UartFault::Kind k) { return name_of(k, kFaultKindNames); }

bool parse_fault_kind(std::string_view name, UartFault::Kind& kind) {
  for (const UartFault::Kind k :
       {UartFault::Kind::parity, UartFault::Kind::start, UartFault::Kind::stop}) {
    if (name == fault_kind_name(k)) {
      kind = k;
      return true;
    }
  }
  return false;
}

std::string range_text(std::uint64_t min, std::uint64_t max, std::string_view value) {
  if (!value.starts_with("0x") && !value.starts_with("0X"))
    return fmt::format("({}..{})", min, max);
  const std::size_t digits = fmt::format("{:X}", max).size();
  return fmt::format("(0x{:0{}X}..0x{:0{}X})", min, digits, max, digits);
}

std::string out_of_range(const ValueRange& r, std::string_view value) {
  return fmt::format("{} {} out of range {}", r.what, value, range_text(r.min, r.max, value));
}

bool any_profile_has(std::string_view register_name) {
  return std::any_of(std::begin(kAllProfiles), std::end(kAllProfiles), [&](Profile p) {
    return find_reg(profile_desc(p), register_name) != nullptr;
  });
}

std::string profibus_rates() {
  std::string rates;
  for (auto it = std::rbegin(kBaudRates); it != std::rend(kBaudRates); ++it) {
    rates += fmt::format("{}{}", rates.empty() ? "" : ", ", *it);
  }
  return rates;
}

std::string range_error_text(std::string_view what, std::string_view value, std::uint64_t min,
                             std::uint64_t max) {
  return fmt::format("{} {} is out of range {}", what, value, range_text(min, max, value));
}

std::string not_a_profibus_rate(std::uint64_t baud) {
  if (baud <= UINT32_MAX && baud_code(static_cast<std::uint32_t>(baud)) >= 0) return {};
  return fmt::format("baud {} is not a PROFIBUS rate ({})", baud, profibus_rates());
}

std::string not_a_profibus_rate(std::string_view text, std::uint32_t& baud) {
  std::uint64_t v = 0;
  if (numbers::parse_whole(text, v) == std::errc{} && not_a_profibus_rate(v).empty()) {
    baud = static_cast<std::uint32_t>(v);
    return {};
  }
  return fmt::format("'{}' is not a PROFIBUS rate ({})", shown(text), profibus_rates());
}

std::string place_fault(UartFault& f, std::size_t chars, std::string_view what) {
  if (f.kind == UartFault::Kind::none) return {};
  if (chars == 0) return fmt::format("{}: an empty telegram has no character to damage", what);
  if (f.char_index < 0) f.char_index = static_cast<int>(chars - 1);
  if (static_cast<std::size_t>(f.char_index) < chars) return {};
  return fmt::format("{}={}: the telegram has only {} characters", what, f.char_index, chars);
}

void place_fault(UartFault& f, std::size_t chars) {
  if (std::string why = place_fault(f, chars, "fault_char"); !why.empty())
    throw std::invalid_argument(std::move(why));
}

std::string hsa_refused(std::uint8_t hsa, std::uint8_t gap_factor, std::uint8_t address) {
  if (gap_factor == 0) return "hsa= without gap=: the HSA bounds the GAP the master polls";
  if (hsa < address) return fmt::format("hsa={} below the master's address {}", hsa, address);
  return {};
}

std::string master_station_name(std::uint8_t address) { return fmt::format("master {}", address); }

std::string second_station_named(std::string_view name) {
  return fmt::format("a second station named '{}'", name);
}

std::string station_scope(std::uint8_t address, std::string_view name) {
  std::string s = fmt::format("station{}", address);
  if (name == fmt::format("station {}", address)) return s;
  s += '_';
  for (const char c : name) s += std::isalnum(static_cast<unsigned char>(c)) != 0 ? c : '_';
  return s;
}

std::string second_station_in_scope(std::string_view name, std::string_view first,
                                    std::string_view scope) {
  return fmt::format("{} in the waveform scope of '{}' ({})", second_station_named(name), first,
                     scope);
}

std::string master_at_station(std::uint8_t address) {
  return fmt::format("master {} at the address of station {}", address, address);
}

std::string station_at_master(std::uint8_t address) {
  return fmt::format("station {} at the address of master {}", address, address);
}

std::string master_and_slave_at(std::uint8_t address) {
  return fmt::format("the master and the slave both have address {}: each station needs its own",
                     address);
}

std::string station_name_refused(std::string_view name, std::string_view whose) {
  if (name.empty()) return fmt::format("empty name for {}", whose);
  if (name.size() > kMaxStationName) {
    return fmt::format("a name of {} bytes for {}: at most {}", name.size(), whose,
                       kMaxStationName);
  }
  if (std::string c = control_character_in(name); !c.empty())
    return fmt::format("the name for {} has a control character, {}", whose, c);
  return {};
}

std::string control_character_in(std::string_view name) {
  for (std::size_t i = 0; i < name.size(); ++i) {
    const auto b = static_cast<unsigned char>(name[i]);
    if (b < 0x20 || b == 0x7F) return fmt::format("byte {:02X}h at offset {}", b, i);
  }
  return {};
}

std::string substitute_is_for_dpc31(std::string_view option) {
  return fmt::format("{} is for profile dpc31: only the DPC31 has the clear buffer C", option);
}

std::string dx_out_port_is_for_dpc31(std::string_view option) {
  return fmt::format("{} is for profile dpc31: only the DPC31 has C31_Control.Enable_DX_Out_Port",
                     option);
}

std::string wd_base_needs_dpv1(std::string_view option) {
  return fmt::format(
      "{} on profile vpc3plus needs DPV1_Enable (user_prm byte 0 bit 7): without DPV1 the VPC3+ "
      "takes WD_Base from Mode_Reg0, not from Set_Prm",
      option);
}

std::string wd_base_contradicts_user_prm() {
  return "wd_base=10ms contradicts user_prm byte 0 bit 2 (WD_Base: the 1 ms base): both are "
         "Set_Prm byte 7 bit 2; give one of them";
}

std::string records_need_dpv1(std::string_view option, const std::vector<std::uint8_t>& user_prm) {
  if (!user_prm.empty() && (user_prm[0] & dpv1::status1::DPV1_Enable) != 0) return {};
  return fmt::format(
      "{} needs DPV1_Enable (slave user_prm= byte 0 bit 7): without it the VPC3+ keeps the SAP "
      "list off and answers every DPV1 request RS",
      option);
}

}  // namespace dpc31
