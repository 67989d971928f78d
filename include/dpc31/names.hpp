// The names of an enum's values as one table next to the enum's owner: name_of(value, table),
// where the enumerators are numbered 0..N-1 in the table's order; "?" for any other value. The
// owner checks the table's length against its last enumerator with a static_assert.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>

namespace dpc31 {

template <typename E, std::size_t N>
constexpr std::string_view name_of(E value, const std::array<std::string_view, N>& names) {
  const auto i = static_cast<std::size_t>(value);
  return i < N ? names[i] : std::string_view("?");
}

}  // namespace dpc31
