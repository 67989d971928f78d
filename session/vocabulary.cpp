// The names of vocabulary.hpp.
#include "vocabulary.hpp"

#include <fmt/format.h>

#include "dpc31/dp.hpp"
#include "dpc31/names.hpp"

namespace dpc31 {

constexpr std::array<std::string_view, 3> kDpStateNames = {"Wait_Prm", "Wait_Cfg", "Data_Exchange"};
static_assert(kDpStateNames.size() == static_cast<std::size_t>(DpState::Data_Exchange) + 1,
              "a new value: name it here");

std::string_view dp_state_name(DpState s) { return name_of(s, kDpStateNames); }

constexpr std::array<std::string_view, 3> kWdStateNames = {"Baud_Search", "Baud_Control",
                                                           "DP_Control"};
static_assert(kWdStateNames.size() == static_cast<std::size_t>(WdState::DP_Control) + 1,
              "a new value: name it here");

std::string_view wd_state_name(WdState s) { return name_of(s, kWdStateNames); }

std::span<const CounterField> fdl_counter_fields() {
  static constexpr CounterField kFields[] = {
      {"parity", &FdlCounters::parity},
      {"start_bit", &FdlCounters::start_bit},
      {"stop_bit", &FdlCounters::stop_bit},
      {"bad_sd", &FdlCounters::bad_sd},
      {"le_mismatch", &FdlCounters::le_mismatch},
      {"bad_le", &FdlCounters::bad_le},
      {"bad_fcs", &FdlCounters::bad_fcs},
      {"wrong_ed", &FdlCounters::wrong_ed},
      {"truncated", &FdlCounters::truncated},
      {"oversize", &FdlCounters::oversize},
      {"bad_sap", &FdlCounters::bad_sap},
      {"no_sync", &FdlCounters::no_sync},
      {"foreign_address", &FdlCounters::foreign_address},
      {"unknown_sap", &FdlCounters::unknown_sap},
      {"unsupported_function", &FdlCounters::unsupported_function},
      {"not_allowed", &FdlCounters::not_allowed},
      {"no_resource", &FdlCounters::no_resource},
      {"offline", &FdlCounters::offline},
      {"repeated", &FdlCounters::repeated},
      {"requests", &FdlCounters::requests},
  };
  return kFields;
}

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

std::string service_name(const fdl::Frame& f) {
  const fdl::Function fn = fdl::request_function(f.fc);
  if (fn == fdl::Function::FDL_Status) return "FDL_Status";
  if (!f.dsap) {
    return fn == fdl::Function::SRD_high || fn == fdl::Function::SRD_low ? "Data_Exchange"
                                                                         : "no SAP";
  }
  switch (fdl::sap_number(*f.dsap)) {
    case sap::Set_Slave_Add:
      return "Set_Slave_Add";
    case sap::Rd_Inp:
      return "Rd_Inp";
    case sap::Rd_Outp:
      return "Rd_Outp";
    case sap::Global_Control:
      return "Global_Control";
    case sap::Get_Cfg:
      return "Get_Cfg";
    case sap::Slave_Diag:
      return "Slave_Diag";
    case sap::Set_Prm:
      return "Set_Prm";
    case sap::Chk_Cfg:
      return "Chk_Cfg";
    default:
      return fmt::format("SAP {}", fdl::sap_number(*f.dsap));
  }
}

std::string_view response_name(fdl::Response r) {
  switch (r) {
    case fdl::Response::OK:
      return "OK";
    case fdl::Response::UE:
      return "UE";
    case fdl::Response::RR:
      return "RR";
    case fdl::Response::RS:
      return "RS";
    case fdl::Response::DL:
      return "DL";
    case fdl::Response::NR:
      return "NR";
    case fdl::Response::DH:
      return "DH";
    case fdl::Response::RDL:
      return "RDL";
    case fdl::Response::RDH:
      return "RDH";
  }
  return "FC?";
}

std::string_view fault_name(UartFault::Kind k) {
  switch (k) {
    case UartFault::Kind::parity:
      return "parity error";
    case UartFault::Kind::start:
      return "no start bit";
    case UartFault::Kind::stop:
      return "stop bit 0";
    case UartFault::Kind::none:
      break;
  }
  return "no fault";
}

std::string_view fault_kind_name(UartFault::Kind k) {
  switch (k) {
    case UartFault::Kind::parity:
      return "parity";
    case UartFault::Kind::start:
      return "start";
    case UartFault::Kind::stop:
      return "stop";
    case UartFault::Kind::none:
      break;
  }
  return "none";
}

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

}  // namespace dpc31
