// The names the session layer and the tools print and read, in one place: DP and watchdog
// states, the FDL counters, DP services and FDL responses of a telegram, UART faults. The walk
// of a scenario, the trace files, the bridge's log and the serve protocol all use these.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "dpc31/chip.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/uart.hpp"

namespace dpc31 {

std::string_view dp_state_name(DpState s);
std::string_view wd_state_name(WdState s);

// The FdlCounters fields by name, in declaration order (expect counter, JSON summaries).
std::span<const CounterField> fdl_counter_fields();
// The counters that are not 0, "name:N,name:N", or "-" (a trace's `state ... fdl=`).
std::string counters_text(const FdlCounters& c);

// The DP service a request asks for ("Set_Prm", "Data_Exchange", "SAP 12", ...).
std::string service_name(const fdl::Frame& request);
// An FDL request function: "SRD_high", "SDN_low", "FDL_Status", ...
std::string_view function_name(fdl::Function f);
// An FDL response code: "OK", "DL", "RS", ...
std::string_view response_name(fdl::Response r);
// A UART fault as the walk tells it ("parity error") and as trace files write it ("parity").
std::string_view fault_name(UartFault::Kind k);
std::string_view fault_kind_name(UartFault::Kind k);
// The kind named by fault_kind_name ("parity", "start", "stop"); false for any other name.
bool parse_fault_kind(std::string_view name, UartFault::Kind& kind);

}  // namespace dpc31
