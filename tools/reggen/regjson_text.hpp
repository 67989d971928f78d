// The description's text and small per-register helpers of the loader (regjson.cpp): the strict
// JSON reader (a duplicate key is an error) and the bit bookkeeping of a RegDesc.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "dpc31/regdesc.hpp"

namespace dpc31::regjson::detail {

// The JSON of `text`; a syntax error or a duplicate key in one object throws Error naming `file`.
nlohmann::json parse_text(std::string_view text, const std::string& file);
// The policy mask of a register that collects the bits of one access.
std::uint16_t& access_mask(RegDesc& r, Access a);
// Letters, digits and '_' (a leading digit only when allowed).
bool is_identifier(std::string_view s, bool leading_digit_ok);
// RegDesc::plain: the lanes whose accesses are straight stores and loads by the description.
std::uint8_t plain_lanes(const RegDesc& r);

}  // namespace dpc31::regjson::detail
