// The strict JSON reader and the RegDesc bit helpers of the loader (regjson_text.hpp).
#include "regjson_text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <set>
#include <vector>

#include "regjson.hpp"

namespace dpc31::regjson::detail {

using Json = nlohmann::json;

// Each policy's mask in a RegDesc, in the order of Access (RO .. UNIMP).
constexpr std::array<std::uint16_t RegDesc::*, 9> kAccessMasks = {
    &RegDesc::ro, &RegDesc::rw,  &RegDesc::w1c,  &RegDesc::w1s,  &RegDesc::cmd,
    &RegDesc::wo, &RegDesc::ign, &RegDesc::rsvd, &RegDesc::unimp};
static_assert(kAccessMasks.size() == static_cast<std::size_t>(Access::UNIMP) + 1,
              "a mask for every access policy");

std::uint16_t& access_mask(RegDesc& r, Access a) {
  return r.*kAccessMasks.at(static_cast<std::size_t>(a));
}

bool is_identifier(std::string_view s, bool leading_digit_ok) {
  if (s.empty()) return false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    const bool ok = std::isalnum(c) != 0 || c == '_';
    if (!ok || (i == 0 && !leading_digit_ok && std::isdigit(c) != 0)) return false;
  }
  return true;
}

Json parse_text(std::string_view text, const std::string& file) {
  // Duplicate keys are legal JSON but almost always a mistake here: reject them.
  std::vector<std::set<std::string>> open_objects;
  std::string duplicate;
  auto cb = [&](int /*depth*/, Json::parse_event_t ev, Json& parsed) {
    switch (ev) {
      case Json::parse_event_t::object_start:
        open_objects.emplace_back();
        break;
      case Json::parse_event_t::object_end:
        if (!open_objects.empty()) open_objects.pop_back();
        break;
      case Json::parse_event_t::key:
        if (!open_objects.empty() &&
            !open_objects.back().insert(parsed.get<std::string>()).second && duplicate.empty()) {
          duplicate = parsed.get<std::string>();
        }
        break;
      default:
        break;
    }
    return true;
  };
  Json root;
  try {
    root = Json::parse(text.begin(), text.end(), cb);
  } catch (const Json::parse_error& e) {
    std::string what = e.what();
    if (const auto p = what.find("] "); what.rfind("[json.exception.", 0) == 0 && p != what.npos) {
      what.erase(0, p + 2);
    }
    std::replace(what.begin(), what.end(), '\n', ' ');
    throw Error(fmt::format("{}: JSON parse error at byte {}: {}", file, e.byte, what));
  }
  if (!duplicate.empty()) {
    throw Error(fmt::format("{}: duplicate key '{}' in one JSON object", file, duplicate));
  }
  return root;
}

std::uint8_t plain_lanes(const RegDesc& r) {
  const std::uint8_t all = r.width == 16 ? 0b11 : 0b01;
  if (r.kind == Kind::cell) return r.reserved ? 0 : all;
  if (r.kind != Kind::latch || r.unimp != 0) return 0;
  const auto acting = static_cast<std::uint16_t>(r.w1c | r.w1s | r.cmd | r.ign | r.pulse);
  std::uint8_t lanes = 0;
  for (unsigned b = 0; b < static_cast<unsigned>(r.bytes()); ++b) {
    if ((acting & (0xFFu << (8 * b))) == 0) lanes = static_cast<std::uint8_t>(lanes | 1u << b);
  }
  return lanes;
}

}  // namespace dpc31::regjson::detail
