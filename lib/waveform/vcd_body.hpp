// The body of a VCD (waveform.cpp): times and value changes formatted by hand into a buffer.
#pragma once

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string_view>

namespace dpc31::wave {

// The VCD body, formatted by hand into a 16 KiB buffer: a traced run writes a line per change, and
// a formatted print per line (fmt into stdio) was a fifth of its cost (docs/performance.md, i).
class VcdBody {
 public:
  explicit VcdBody(std::FILE* f) : f_(f) {}
  VcdBody(const VcdBody&) = delete;
  VcdBody& operator=(const VcdBody&) = delete;
  ~VcdBody() { flush(); }
  // Times only grow, and a VCD of a run writes one for nearly every change: the digits above the
  // last eight are kept from the previous time, the last eight converted two at a time.
  void time(std::uint64_t t) {
    room(32);
    *p_++ = '#';
    const std::uint64_t high = t / 100'000'000;
    const auto low = static_cast<std::uint32_t>(t % 100'000'000);
    if (high == 0) {
      int n = 1;
      for (std::uint32_t v = low; v >= 10; v /= 10) ++n;
      p_ = digits(low, n, p_);
    } else {
      if (high != high_) {
        high_ = high;
        high_len_ = static_cast<std::size_t>(
            std::to_chars(high_digits_.data(), high_digits_.data() + high_digits_.size(), high)
                .ptr -
            high_digits_.data());
      }
      p_ = digits(low, 8, std::copy_n(high_digits_.data(), high_len_, p_));
    }
    *p_++ = '\n';
  }
  // `id` is the signal's identifier code; `width` 1 writes the scalar form.
  void value(std::string_view id, int width, std::uint32_t v) {
    room(id.size() + 20);
    if (width == 1) {
      *p_++ = (v & 1) != 0 ? '1' : '0';
    } else {
      *p_++ = 'b';
      for (int b = width - 1; b >= 0; --b) *p_++ = ((v >> b) & 1) != 0 ? '1' : '0';
      *p_++ = ' ';
    }
    p_ = std::copy(id.begin(), id.end(), p_);
    *p_++ = '\n';
  }
  void flush() {
    std::fwrite(buf_.get(), 1, static_cast<std::size_t>(p_ - buf_.get()), f_);
    p_ = buf_.get();
  }

 private:
  // The last `n` decimal digits of `v` (with leading zeros) at `p`; returns the end.
  static char* digits(std::uint32_t v, int n, char* p) {
    static constexpr char kPairs[] =
        "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
        "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
        "8081828384858687888990919293949596979899";
    char* const end = p + n;
    for (; n >= 2; n -= 2, v /= 100) {
      std::memcpy(p + n - 2, &kPairs[2 * (v % 100)], 2);
    }
    if (n == 1) *p = static_cast<char>('0' + v % 10);
    return end;
  }
  char* end() { return buf_.get() + kSize; }
  void room(std::size_t n) {
    if (static_cast<std::size_t>(end() - p_) < n) flush();
  }
  std::FILE* f_;
  std::uint64_t high_ = 0;
  std::array<char, 20> high_digits_{};
  std::size_t high_len_ = 0;
  static constexpr std::size_t kSize = 16 * 1024;
  std::unique_ptr<char[]> buf_ = std::make_unique_for_overwrite<char[]>(kSize);
  char* p_ = buf_.get();
};

}  // namespace dpc31::wave
