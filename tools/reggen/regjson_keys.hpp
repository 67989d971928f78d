// The schema of regs/dpc31_regs.json as the loader checks it (regjson.cpp): the keys each kind
// of object may carry; any other key is refused with one line naming it.
#pragma once

#include <string_view>

namespace dpc31::regjson {

constexpr std::string_view kTopKeys[] = {"format",   "title",     "clock_hz",
                                         "profiles", "fieldsets", "registers"};
constexpr std::string_view kProfileKeys[] = {"name",
                                             "title",
                                             "macro",
                                             "address_bits",
                                             "ram_begin",
                                             "ram_size",
                                             "ram_size_large",
                                             "cells_base",
                                             "user_base",
                                             "segment_shift",
                                             "segment_shift_large",
                                             "violation_from",
                                             "violation_subtract",
                                             "release",
                                             "bus_access_cycles",
                                             "note",
                                             "regions",
                                             "layouts"};
constexpr std::string_view kLayoutKeys[] = {"name", "size", "source", "desc", "bytes"};
constexpr std::string_view kLayoutByteKeys[] = {"offset", "name", "desc", "bits", "values"};
constexpr std::string_view kLayoutValueKeys[] = {"name", "mask", "value", "desc"};
constexpr std::string_view kRegionKeys[] = {"name", "begin", "end", "ram", "reserved", "desc"};
constexpr std::string_view kFieldKeys[] = {"bits", "name", "access", "pulse", "desc"};
constexpr std::string_view kRegisterKeys[] = {
    "name",     "kind",  "target",   "block",    "width",  "reset",    "read",
    "write",    "cell",  "reserved", "fieldset", "access", "override", "fields",
    "profiles", "bytes", "origin",   "source",   "note",   "desc",     "alias"};

}  // namespace dpc31::regjson
