// The free helpers of the register description loader (regjson.cpp): the JSON text with
// duplicate keys refused, identifiers, and what a register's description implies.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "dpc31/regdesc.hpp"

namespace dpc31::regjson {

// The description text as JSON; throws Error (regjson.hpp) on a syntax error or a key that
// appears twice in one object, naming `file` and the byte.
nlohmann::json parse_text(std::string_view text, const std::string& file);
// [A-Za-z_][A-Za-z0-9_]*, or also a leading digit.
bool is_identifier(std::string_view s, bool leading_digit_ok);
// The RegDesc mask that holds the bits of policy `a`.
std::uint16_t& access_mask(RegDesc& r, Access a);
// RegDesc::plain: the lanes whose accesses are straight stores and loads by the description.
std::uint8_t plain_lanes(const RegDesc& r);

}  // namespace dpc31::regjson
