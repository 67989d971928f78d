// Counters of what the chip's receiver threw away or refused, by class, and of the requests it
// served (Chip::fdl_counters). Each is counted where the telegram is judged: the MAC
// (emu/mac.cpp) and the DP services (emu/dp_sm.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "dpc31/fdl.hpp"

namespace dpc31 {

struct FdlCounters {
  std::uint32_t parity = 0;       // character with a parity error
  std::uint32_t start_bit = 0;    // start bit not 0 (checked unless Dis_Start_Control)
  std::uint32_t stop_bit = 0;     // stop bit not 1 (checked unless Dis_Stop_Control)
  std::uint32_t bad_sd = 0;       // unknown start delimiter / bad repeated SD2
  std::uint32_t le_mismatch = 0;  // LE != LEr
  std::uint32_t bad_le = 0;       // LE out of range
  std::uint32_t bad_fcs = 0;
  std::uint32_t wrong_ed = 0;
  std::uint32_t truncated = 0;             // the line went idle (TSYN) inside a frame
  std::uint32_t oversize = 0;              // more characters than SD / LE announce
  std::uint32_t bad_sap = 0;               // unsupported address extension
  std::uint32_t no_sync = 0;               // a telegram not preceded by TSYN idle (an answer too)
  std::uint32_t foreign_address = 0;       // well-formed, for another station
  std::uint32_t unknown_sap = 0;           // DSAP the DP slave does not serve (answered RS)
  std::uint32_t unsupported_function = 0;  // FC function the slave does not serve
  std::uint32_t not_allowed = 0;           // service refused in this state / from this master
  std::uint32_t no_resource = 0;           // answered RR (buffer too small, SSA busy)
  std::uint32_t offline = 0;               // a frame arrived while the chip was Offline
  std::uint32_t repeated = 0;              // FCB repeat: the previous answer sent again
  std::uint32_t requests = 0;              // error-free requests to us (or broadcast) processed
  bool operator==(const FdlCounters&) const = default;
};

// The counters by name, in declaration order (the snapshot's order, `expect counter`, JSON).
struct CounterField {
  std::string_view name;
  std::uint32_t FdlCounters::*member;
};
inline constexpr std::array<CounterField, 20> kFdlCounterFields = {{
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
}};

// What a MAC counts at a broken frame's verdict (emu/mac.cpp): the assembler's error by class (an
// LE beyond the longest telegram as oversize), else `decoded` (fdl::decode's error) when not none.
void count_frame_error(FdlCounters& n, const fdl::Assembler& frame, fdl::Error decoded);

}  // namespace dpc31
