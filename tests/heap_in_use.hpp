// What the heap holds now, for the tests that a long run's memory stays flat: malloc's count.
// ASan's allocator is not malloc's, so under ASan the count says nothing (kHeapCounted).
#pragma once

#include <malloc.h>

#include <cstddef>

namespace dpc31::test {

inline std::size_t heap_in_use() {
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
}

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kHeapCounted = false;
#else
inline constexpr bool kHeapCounted = true;
#endif

}  // namespace dpc31::test
