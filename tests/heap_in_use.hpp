// What the heap holds now, for the tests that a long run's memory stays flat: malloc's count,
// signed, so that a run that gave memory back grows by a negative number.
// ASan's allocator is not malloc's, so under ASan the count says nothing (kHeapCounted).
#pragma once

#include <malloc.h>

#include <cstdint>

namespace dpc31::test {

inline std::int64_t heap_in_use() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<std::int64_t>(m.uordblks + m.hblkhd);
}

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kHeapCounted = false;
#else
inline constexpr bool kHeapCounted = true;
#endif

}  // namespace dpc31::test
