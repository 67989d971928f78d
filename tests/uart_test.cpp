// PROFIBUS UART with exact cycles from docs/timing.md, "Serial line (UART)": T = round(f / baud);
// a character starts at a falling edge s while idle; bit k is sampled at s + k*T + T/2 and reads
// the last edge at or before that cycle; end = s + 11 T; the next start needs a falling edge at
// or after the end. Every expected cycle below is worked out from those rules.
#include "dpc31/uart.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <span>
#include <utility>
#include <vector>

#include "snapshot.hpp"

using namespace dpc31;

namespace {

using Edges = std::vector<std::pair<std::uint64_t, bool>>;
constexpr std::uint64_t kIdle = UartRx::kIdle;

// Feeds every edge, then advances once to `until`.
std::vector<UartChar> receive(const Edges& edges, std::uint32_t t, std::uint64_t until,
                              std::uint64_t configured_at = 0) {
  UartRx rx(t, configured_at);
  for (const auto& [cycle, level] : edges) rx.edge(cycle, level);
  std::vector<UartChar> out;
  rx.advance(until, out);
  return out;
}

UartChar good(std::uint8_t data, std::uint64_t start, std::uint32_t t, std::uint64_t idle) {
  return UartChar{data, true, true, true, start, start + 11 * std::uint64_t{t}, idle};
}

}  // namespace

// ---- bit times and codes ----

TEST(UartBaud, BitCyclesAt48MHz) {
  constexpr std::uint32_t kExpected[10] = {4, 8, 16, 32, 96, 256, 512, 1056, 2500, 5000};
  for (int i = 0; i < 10; ++i) {
    SCOPED_TRACE(kBaudRates[i]);
    EXPECT_EQ(bit_cycles(48'000'000, kBaudRates[i]), kExpected[i]);
  }
}

TEST(UartBaud, BitCyclesRoundToNearest) {
  // 12 MHz: 1, 8, 264.03 -> 264, 1250.
  EXPECT_EQ(bit_cycles(12'000'000, 12'000'000), 1u);
  EXPECT_EQ(bit_cycles(12'000'000, 1'500'000), 8u);
  EXPECT_EQ(bit_cycles(12'000'000, 45'450), 264u);
  EXPECT_EQ(bit_cycles(12'000'000, 9'600), 1250u);
  // 10 MHz: 1.67 -> 2 (up), 3.33 -> 3 (down), 6.67 -> 7, 0.83 -> 1.
  EXPECT_EQ(bit_cycles(10'000'000, 6'000'000), 2u);
  EXPECT_EQ(bit_cycles(10'000'000, 3'000'000), 3u);
  EXPECT_EQ(bit_cycles(10'000'000, 1'500'000), 7u);
  EXPECT_EQ(bit_cycles(10'000'000, 12'000'000), 1u);
  // A half rounds up; below a half the rate is unusable (0), as is baud 0.
  EXPECT_EQ(bit_cycles(6'000'000, 12'000'000), 1u);
  EXPECT_EQ(bit_cycles(5'000'000, 12'000'000), 0u);
  EXPECT_EQ(bit_cycles(48'000'000, 0), 0u);
  // No overflow at the top of the range: 4294967295 / 2 = 2147483647.5 -> 2147483648.
  EXPECT_EQ(bit_cycles(0xFFFF'FFFF, 2), 2147483648u);
}

// docs/timing.md, "the lowest clock": from 9 MHz up the ten rates have ten different bit times
// (1, 2, 3, 6, 18, 48, 96, 198, 469, 938 at 9 MHz: 0.75 and 1.5 round up); one clock below,
// 12 and 6 Mbaud share one (0.749... and 1.499... both round to 1), and at any clock from 9 MHz up
// each rate's bit time is above the next faster one's.
TEST(UartBaud, TheTenRatesAreDistinctFromNineMegahertz) {
  constexpr std::uint32_t kAt9MHz[10] = {1, 2, 3, 6, 18, 48, 96, 198, 469, 938};
  for (int i = 0; i < 10; ++i) EXPECT_EQ(bit_cycles(9'000'000, kBaudRates[i]), kAt9MHz[i]);
  EXPECT_EQ(bit_cycles(8'999'999, 12'000'000), bit_cycles(8'999'999, 6'000'000));
  for (const std::uint32_t hz : {9'000'000u, 9'000'001u, 11'999'999u, 17'999'999u, 48'000'000u}) {
    for (int i = 1; i < 10; ++i) {
      EXPECT_GT(bit_cycles(hz, kBaudRates[i]), bit_cycles(hz, kBaudRates[i - 1]))
          << hz << " Hz, " << kBaudRates[i] << " baud";
    }
  }
}

TEST(UartBaud, BaudCodeRoundTrip) {
  for (int i = 0; i < 10; ++i) EXPECT_EQ(baud_code(kBaudRates[i]), i);
  EXPECT_EQ(baud_code(0), -1);
  EXPECT_EQ(baud_code(115'200), -1);
  EXPECT_EQ(baud_code(45'455), -1);
}

TEST(UartBaud, EvenParity) {
  EXPECT_EQ(even_parity(0x00), 0);
  EXPECT_EQ(even_parity(0x01), 1);
  EXPECT_EQ(even_parity(0x03), 0);
  EXPECT_EQ(even_parity(0x10), 1);
  EXPECT_EQ(even_parity(0x7F), 1);
  EXPECT_EQ(even_parity(0xFF), 0);
}

// ---- encoder ----

TEST(UartEncode, Byte0x10AtT4FromCycle100) {
  // Bits at 100 + 4k: start 0 @100, d0..d3 = 0, d4 = 1 @120, d5..d7 = 0 @124, parity 1 @136,
  // stop 1 @140; the line is already high at the stop bit, so no edge at 140 or 144.
  const std::uint8_t b[] = {0x10};
  Edges e;
  uart_encode(b, 100, 4, e);
  EXPECT_EQ(e, (Edges{{100, false}, {120, true}, {124, false}, {136, true}}));
}

TEST(UartEncode, BackToBackAndFinalRise) {
  Edges e;
  const std::uint8_t two[] = {0x10, 0x10};  // the second char starts at 100 + 44 = 144
  uart_encode(two, 100, 4, e);
  EXPECT_EQ(e, (Edges{{100, false},
                      {120, true},
                      {124, false},
                      {136, true},
                      {144, false},
                      {164, true},
                      {168, false},
                      {180, true}}));
  e.clear();
  const std::uint8_t zero[] = {0x00};  // low from start to the stop bit: rise at 0 + 10*4
  uart_encode(zero, 0, 4, e);
  EXPECT_EQ(e, (Edges{{0, false}, {40, true}}));
  e.clear();
  const std::uint8_t ones[] = {0xFF};  // parity 0 at 36, stop rises at 40
  uart_encode(ones, 0, 4, e);
  EXPECT_EQ(e, (Edges{{0, false}, {4, true}, {36, false}, {40, true}}));
}

TEST(UartEncode, EveryByteEdgeForEdgeFromItsBits) {
  // docs/timing.md "Serial line (UART)": start bit 0, d0..d7 LSB first, even parity, stop bit 1,
  // bit k from start + k T. An edge wherever a bit differs from the one before (the idle line
  // before the first start bit is high); each byte back to back after 0x55, at T = 3.
  for (unsigned d = 0; d < 256; ++d) {
    const std::uint8_t b[] = {0x55, static_cast<std::uint8_t>(d)};
    Edges want;
    bool line = true;
    for (std::uint64_t i = 0; i < 2; ++i) {
      unsigned ones = 0;
      for (unsigned k = 0; k < 11; ++k) {
        const bool data_bit = k >= 1 && k <= 8 && ((b[i] >> (k - 1)) & 1u) != 0;
        ones += data_bit ? 1u : 0u;
        const bool bit = k == 0 ? false : k <= 8 ? data_bit : k == 9 ? (ones & 1u) != 0 : true;
        if (bit != line) want.emplace_back(7 + (i * 11 + k) * 3, bit);
        line = bit;
      }
    }
    Edges e;
    uart_encode(b, 7, 3, e);
    EXPECT_EQ(e, want) << "byte " << d;
  }
}

// uart_char_edge_count: a character's edges from its bits alone (docs/timing.md, as above): the
// start bit's fall, then one change wherever a bit differs from the one before, counted by hand;
// and always uart_char_edges's count.
TEST(UartEncode, EdgeCountOfEveryByte) {
  EXPECT_EQ(uart_char_edge_count(0x00), 2u);   // low through parity 0, the stop bit rises
  EXPECT_EQ(uart_char_edge_count(0x80), 2u);   // d7 and parity 1 rise once at bit 8
  EXPECT_EQ(uart_char_edge_count(0xC0), 4u);   // rise at d6, fall at parity 0, rise at stop
  EXPECT_EQ(uart_char_edge_count(0xFF), 4u);   // rise at d0, fall at parity 0, rise at stop
  EXPECT_EQ(uart_char_edge_count(0x55), 10u);  // 0 1 0 1 0 1 0 1 0 (parity 0) 1: every bit
  for (unsigned d = 0; d < 256; ++d) {
    std::pair<std::uint64_t, bool> e[11];
    EXPECT_EQ(uart_char_edge_count(static_cast<std::uint8_t>(d)),
              uart_char_edges(static_cast<std::uint8_t>(d), 0, 4, e))
        << "byte " << d;
  }
}

TEST(UartEncode, Faults) {
  const std::uint8_t b[] = {0x10};
  Edges e;
  uart_encode(b, 100, 4, e, {0, UartFault::Kind::parity});  // parity 0: stays low to the stop
  EXPECT_EQ(e, (Edges{{100, false}, {120, true}, {124, false}, {140, true}}));
  e.clear();
  uart_encode(b, 100, 4, e, {0, UartFault::Kind::start});  // high through bit 0, d0 falls at 104
  EXPECT_EQ(e, (Edges{{104, false}, {120, true}, {124, false}, {136, true}}));
  e.clear();
  uart_encode(b, 100, 4, e, {0, UartFault::Kind::stop});  // stop low at 140, back high at 144
  EXPECT_EQ(
      e, (Edges{{100, false}, {120, true}, {124, false}, {136, true}, {140, false}, {144, true}}));
  e.clear();
  uart_encode(b, 100, 4, e, {1, UartFault::Kind::stop});  // no char 1: no fault
  EXPECT_EQ(e, (Edges{{100, false}, {120, true}, {124, false}, {136, true}}));
  e.clear();
  // A stop bit sent low leaves the line low into the next character: its start bit is no edge
  // (00h twice: low from 100 through the second frame's parity, its stop bit rises at 144 + 40).
  const std::uint8_t zeros[] = {0x00, 0x00};
  uart_encode(zeros, 100, 4, e, {0, UartFault::Kind::stop});
  EXPECT_EQ(e, (Edges{{100, false}, {184, true}}));
}

// ---- receiver ----

TEST(UartRx, Decodes0x10AtT4) {
  // Samples at 102, 106, ..., 142: 0 | 0 0 0 0 1 0 0 0 | 1 | 1 -> 0x10, all ok.
  UartRx rx(4, 0);
  EXPECT_EQ(rx.next_deadline(), kIdle);
  const Edges e{{100, false}, {120, true}, {124, false}, {136, true}};
  rx.edge(100, false);
  EXPECT_EQ(rx.next_deadline(), 142u);  // 100 + 10*4 + 2
  for (std::size_t i = 1; i < e.size(); ++i) rx.edge(e[i].first, e[i].second);
  std::vector<UartChar> out;
  rx.advance(141, out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(rx.next_deadline(), 142u);
  rx.advance(142, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], good(0x10, 100, 4, 25));  // idle since 0: 100 / 4 = 25 bit times
  EXPECT_EQ(out[0].end, 144u);
  EXPECT_EQ(rx.next_deadline(), kIdle);
}

TEST(UartRx, RoundTripEveryRate) {
  std::mt19937 rng(20240611);
  for (std::uint32_t baud : kBaudRates) {
    const std::uint32_t t = bit_cycles(48'000'000, baud);
    SCOPED_TRACE(t);
    std::vector<std::uint8_t> a(17), b(9);
    for (auto& x : a) x = static_cast<std::uint8_t>(rng());
    for (auto& x : b) x = static_cast<std::uint8_t>(rng());
    // Burst a starts 7 bit times + 3 cycles after configure (idle_bits 7); burst b starts
    // exactly 33 bit times after the end of a (idle_bits 33).
    const std::uint64_t t64 = t;
    const std::uint64_t sa = 7 * t64 + 3;
    const std::uint64_t sb = sa + 11 * t64 * a.size() + 33 * t64;
    Edges e;
    uart_encode(a, sa, t, e);
    uart_encode(b, sb, t, e);
    const auto out = receive(e, t, sb + 11 * t64 * b.size());
    ASSERT_EQ(out.size(), a.size() + b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(out[i], good(a[i], sa + 11 * t64 * i, t, i == 0 ? 7 : 0)) << i;
    }
    for (std::size_t i = 0; i < b.size(); ++i) {
      EXPECT_EQ(out[a.size() + i], good(b[i], sb + 11 * t64 * i, t, i == 0 ? 33 : 0)) << i;
    }
  }
}

TEST(UartRx, AdvanceAtAnyTimeGivesTheSameCharacters) {
  // Cycle by cycle, as an engine that delivers the edges of cycle c and then advances to c:
  // each char appears exactly at its stop sample s + 10T + T/2 and next_deadline() names that
  // cycle from s on; outside a char it is kIdle.
  constexpr std::uint32_t t = 4;
  std::mt19937 rng(7);
  std::vector<std::uint8_t> a(6), b(5);
  for (auto& x : a) x = static_cast<std::uint8_t>(rng());
  for (auto& x : b) x = static_cast<std::uint8_t>(rng());
  const std::uint64_t sa = 40, sb = sa + 11 * t * a.size() + 5 * t + 1;
  Edges e;
  uart_encode(a, sa, t, e);
  uart_encode(b, sb, t, e);
  const std::uint64_t last = sb + 11 * t * b.size() + 20;
  std::vector<std::uint64_t> starts;
  for (std::size_t i = 0; i < a.size(); ++i) starts.push_back(sa + 11 * t * i);
  for (std::size_t i = 0; i < b.size(); ++i) starts.push_back(sb + 11 * t * i);

  const auto once = receive(e, t, last);
  ASSERT_EQ(once.size(), starts.size());

  UartRx rx(t, 0);
  std::vector<UartChar> stepped;
  std::size_t next_edge = 0;
  for (std::uint64_t c = 0; c <= last; ++c) {
    while (next_edge < e.size() && e[next_edge].first == c) {
      rx.edge(c, e[next_edge].second);
      ++next_edge;
    }
    const std::size_t before = stepped.size();
    rx.advance(c, stepped);
    std::uint64_t expect_deadline = kIdle;
    for (std::size_t i = 0; i < starts.size(); ++i) {
      const std::uint64_t stop = starts[i] + 10 * t + t / 2;
      if (c == stop) {
        EXPECT_EQ(stepped.size(), before + 1) << c;
      }
      if (starts[i] <= c && c < stop) expect_deadline = stop;
    }
    if (stepped.size() == before + 1) {
      EXPECT_EQ(stepped.back().start + 10 * t + t / 2, c);
    }
    EXPECT_EQ(rx.next_deadline(), expect_deadline) << c;
  }
  EXPECT_EQ(stepped, once);

  // All edges fed ahead, then advance() at scattered times (some repeated, some going back).
  UartRx ahead(t, 0);
  for (const auto& [cycle, level] : e) ahead.edge(cycle, level);
  EXPECT_EQ(ahead.next_deadline(), sa + 10 * t + t / 2);
  std::vector<UartChar> scattered;
  for (std::uint64_t c : {std::uint64_t{0}, std::uint64_t{85}, std::uint64_t{86}, std::uint64_t{86},
                          std::uint64_t{50}, std::uint64_t{200}, sb, last}) {
    ahead.advance(c, scattered);
  }
  EXPECT_EQ(scattered, once);
  EXPECT_EQ(ahead.next_deadline(), kIdle);
}

TEST(UartRx, SamplePointsAt45450Baud) {
  // T = 1056, T/2 = 528; start at 1000: samples at 1528, 2584, 3640, 4696, 5752, 6808, 7864,
  // 8920, 9976, 11032, stop 12088; end 1000 + 11616 = 12616.
  constexpr std::uint32_t t = 1056;
  ASSERT_EQ(bit_cycles(48'000'000, 45'450), t);
  // An edge exactly at a sample point is seen by it: d0 = 1 (rise at 2584), d1 = 1 (fall one
  // cycle after its sample at 3640), d2 = 0, d3.. = 1 (rise at 5752), parity 1, stop 1.
  // Data 1101'1111 LSB first = 0xFB, 7 ones + parity 1: even.
  const Edges at{{1000, false}, {2584, true}, {3641, false}, {5752, true}};
  auto out = receive(at, t, 12088);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], good(0xFB, 1000, t, 0));  // idle 1000 cycles < one bit time
  EXPECT_EQ(out[0].end, 12616u);
  // Each edge one cycle later: d0 = 0, d1 = 1, d2 = 0, d3 = 0, d4.. = 1 -> 1111'0010 = 0xF2,
  // 5 ones + parity 1: even.
  const Edges late{{1000, false}, {2585, true}, {3641, false}, {5753, true}};
  out = receive(late, t, 12088);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], good(0xF2, 1000, t, 0));
  // The stop sample is at 12088: nothing at 12087; a fall at 12088 is a framing error, a fall
  // at 12089 is not.
  EXPECT_TRUE(receive(at, t, 12087).empty());
  Edges e = at;
  e.emplace_back(12088, false);
  out = receive(e, t, 12088);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_FALSE(out[0].stop_ok);
  e.back().first = 12089;
  out = receive(e, t, 12089);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_TRUE(out[0].ok());
}

TEST(UartRx, IdleBitsCountWholeBitsAndSaturate) {
  // Configured at 10, T = 8: a fall at 10 + 8*5 + 7 = 57 -> 5 whole bit times.
  auto out = receive({{57, false}, {57 + 80, true}}, 8, 57 + 84, 10);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].idle_bits, 5u);
  EXPECT_EQ(out[0].data, 0x00);
  EXPECT_TRUE(out[0].ok());
  // 2^32 + 5 bit times of idle saturates; the receiver holds no edge history meanwhile.
  const std::uint64_t s = 4 * ((std::uint64_t{1} << 32) + 5);
  out = receive({{s, false}, {s + 40, true}}, 4, s + 42);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].idle_bits, 0xFFFF'FFFFu);
  EXPECT_EQ(out[0].start, s);
}

TEST(UartRx, ConfigureRestartsAndZeroDisables) {
  UartRx rx(4, 0);
  rx.edge(100, false);  // a char in progress is dropped by configure
  rx.configure(8, 110);
  EXPECT_EQ(rx.next_deadline(), kIdle);
  EXPECT_TRUE(rx.level());  // assumed idle since 110
  rx.edge(126, false);      // 16 cycles after configure: 2 bit times
  EXPECT_EQ(rx.next_deadline(), 126u + 80 + 4);
  rx.edge(126 + 80, true);
  std::vector<UartChar> out;
  rx.advance(1000, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], good(0x00, 126, 8, 2));

  rx.configure(0, 2000);  // T = 0: never starts a character
  rx.edge(2100, false);
  rx.edge(2200, true);
  EXPECT_EQ(rx.next_deadline(), kIdle);
  rx.advance(100000, out);
  EXPECT_EQ(out.size(), 1u);
}

// ---- faults ----

namespace {
// T = 4: 0x01 at 100, 0x10 at 144 with `fault`, then 0x22 at 268. The receiver reads 0x01 (25
// idle bits before it), `second`, then 0x22 after `idle` idle bits.
void expect_burst_with_fault(UartFault::Kind fault, const UartChar& second, std::uint32_t idle) {
  const std::uint8_t burst[] = {0x01, 0x10};
  const std::uint8_t next[] = {0x22};
  Edges e;
  uart_encode(burst, 100, 4, e, {1, fault});
  uart_encode(next, 268, 4, e);
  EXPECT_EQ(receive(e, 4, 1000),
            (std::vector<UartChar>{good(0x01, 100, 4, 25), second, good(0x22, 268, 4, idle)}));
}
}  // namespace

TEST(UartFault, ParityOnTheChosenCharOnly) {
  // T = 8 from 80: chars at 80, 168, 256, 344; idle 80 / 8 = 10 before the first.
  const std::uint8_t b[] = {0x11, 0x22, 0x33, 0x44};
  for (int bad = 0; bad < 4; ++bad) {
    SCOPED_TRACE(bad);
    Edges e;
    uart_encode(b, 80, 8, e, {bad, UartFault::Kind::parity});
    const auto out = receive(e, 8, 1000);
    ASSERT_EQ(out.size(), 4u);
    for (int i = 0; i < 4; ++i) {
      UartChar want = good(b[i], 80 + 88 * static_cast<std::uint64_t>(i), 8, i == 0 ? 10 : 0);
      want.parity_ok = i != bad;
      EXPECT_EQ(out[i], want) << i;
    }
  }
}

TEST(UartFault, MissingStartBitShiftsTheFrame) {
  // T = 4: 0x01 at 100, 0x10 at 144 with its start bit high, then 0x22 at 268.
  // Char 1 has no falling edge at 144; the first one is d0 at 148, so the receiver starts there
  // (idle_bits (148 - 144) / 4 = 1) and reads bits 1..10 of the sent char plus the idle line:
  // d = 0 0 0 1 0 0 0 1 (d1..d7, parity) = 0x88, parity sample = stop (1): 3 ones, odd.
  // Stop sample 148 + 42 = 190 is idle (1). End 192; 0x22 at 268: (268 - 192) / 4 = 19 idle bits.
  expect_burst_with_fault(UartFault::Kind::start, {0x88, true, false, true, 148, 192, 1}, 19);
}

TEST(UartFault, StopBitZeroIsAFramingError) {
  // T = 4: 0x01 at 100, 0x10 at 144 with stop low at 184..188, then 0x22 at 268 (idle
  // (268 - 188) / 4 = 20).
  expect_burst_with_fault(UartFault::Kind::stop, {0x10, true, true, false, 144, 188, 0}, 20);
}

TEST(UartFault, BreakThenNormalCharAfterTheLineRecovers) {
  // T = 4: low from 100 for 30 bit times (rise at 220), 0x10 from 232. The break reads as 0x00
  // with parity 0 (ok) and stop 0; at its end (144) the line is still low, which is no start.
  // 0x10 at 232: high since the rise at 220 -> (232 - 220) / 4 = 3 idle bits.
  Edges e{{100, false}, {220, true}};
  const std::uint8_t b[] = {0x10};
  uart_encode(b, 232, 4, e);
  const auto out = receive(e, 4, 1000);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0], (UartChar{0x00, true, true, false, 100, 144, 25}));
  EXPECT_EQ(out[1], good(0x10, 232, 4, 3));
}

TEST(UartFault, BreakSwallowsTheNextStartEdge) {
  // T = 4: 0x10 at 100 with stop 0 (fall at 140), 0xFF back to back at 144: its start bit keeps
  // the line low, so there is no falling edge at 144. Edges after 140: rise 148 (d0), fall 180
  // (parity 0), rise 184 (stop). The fall at 180 starts a char: start 182 = 0, 186.. = 1 ->
  // 0xFF, parity sample 218 = 1 (odd), stop 222 = 1. High since 148: (180 - 148) / 4 = 8.
  const std::uint8_t b[] = {0x10, 0xFF};
  Edges e;
  uart_encode(b, 100, 4, e, {0, UartFault::Kind::stop});
  EXPECT_EQ(e, (Edges{{100, false},
                      {120, true},
                      {124, false},
                      {136, true},
                      {140, false},
                      {148, true},
                      {180, false},
                      {184, true}}));
  const auto out = receive(e, 4, 1000);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0], (UartChar{0x10, true, true, false, 100, 144, 25}));
  EXPECT_EQ(out[1], (UartChar{0xFF, true, false, true, 180, 224, 8}));
}

// ---- glitches ----

TEST(UartGlitch, ShortLowPulseIsABadStartBit) {
  // T = 16, T/2 = 8. Fall at 200, rise at 207 (7 cycles, before the start sample at 208): the
  // receiver commits to the frame: start reads 1, data 0xFF, parity 1 (9 ones: odd), stop 1.
  // Reported at the stop sample 200 + 168 = 368; end 376; idle 200 / 16 = 12.
  UartRx rx(16, 0);
  rx.edge(200, false);
  rx.edge(207, true);
  EXPECT_EQ(rx.next_deadline(), 368u);
  std::vector<UartChar> out;
  rx.advance(367, out);
  EXPECT_TRUE(out.empty());
  rx.advance(368, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (UartChar{0xFF, false, false, true, 200, 376, 12}));
  // A real char may start right at the end of the glitch frame: high since 376, idle 0.
  Edges e;
  const std::uint8_t b[] = {0x10};
  uart_encode(b, 376, 16, e);
  for (const auto& [c, l] : e) rx.edge(c, l);
  rx.advance(2000, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1], good(0x10, 376, 16, 0));
}

TEST(UartGlitch, PulseEndingOnTheStartSample) {
  // The start sample reads the level of the edge at its own cycle: rise at 208 -> bad start;
  // rise at 209 -> good start, the rest high (0xFF, parity 1: odd).
  auto out = receive({{200, false}, {208, true}}, 16, 1000);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (UartChar{0xFF, false, false, true, 200, 376, 12}));
  out = receive({{200, false}, {209, true}}, 16, 1000);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (UartChar{0xFF, true, false, true, 200, 376, 12}));
}

TEST(UartGlitch, SwallowsACharStartingInsideItsFrame) {
  // Glitch 200..207, then 0x00 sent from 240 (inside the frame that ends at 376): fall 240,
  // rise 400. Samples 208 = 1, 224 = 1, 240 = 0 (edge at 240), 256..368 = 0: start 1, data
  // 0x01, parity 0 (odd), stop 0. At 376 the line is low; the rise at 400 starts nothing.
  Edges e{{200, false}, {207, true}};
  const std::uint8_t b[] = {0x00};
  uart_encode(b, 240, 16, e);
  EXPECT_EQ(e, (Edges{{200, false}, {207, true}, {240, false}, {400, true}}));
  const auto out = receive(e, 16, 10000);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (UartChar{0x01, false, false, false, 200, 376, 12}));
}

// ---- whole characters (issue 19 item 1) ----

namespace {

std::vector<std::uint8_t> rx_state(const UartRx& rx) {
  snap::Writer w;
  rx.save_state(w);
  return w.bytes();
}

void feed(UartRx& rx, const Edges& edges) {
  for (const auto& [cycle, level] : edges) rx.edge(cycle, level);
}

}  // namespace

// UartRx::whole_char against the same character's edges (uart_encode) fed one by one, on two
// receivers given the same random line: good characters back to back, after gaps, starting
// inside the previous frame, at another bit time; damaged ones (parity, start, stop: as edges on
// both, and the next character after a stop fault finds the line low); glitches; advance() at
// random cycles in between. After every step both receivers hold the same state, every member
// (their snapshot bytes), and give the same characters. The whole path must have been taken often.
TEST(UartRx, AWholeCharacterLeavesTheStateItsEdgesLeave) {
  std::mt19937 rng(19);
  for (const std::uint32_t t : {2u, 3u, 4u, 8u, 16u, 32u, 96u, 256u, 512u, 1056u, 2500u, 5000u}) {
    SCOPED_TRACE(t);
    UartRx a(t, 0);
    UartRx b(t, 0);
    std::uint64_t cursor = 100;  // no edge of the next step before this
    std::uint64_t advanced = 0;  // the last advance()
    int whole = 0;
    std::vector<UartChar> out_a;
    std::vector<UartChar> out_b;
    for (int step = 0; step < 400; ++step) {
      SCOPED_TRACE(step);
      const std::uint64_t tt = t;
      // Where the next thing starts: back to back, after a gap, or inside the last frame's
      // stop bit (cursor is the last frame's end minus T at most).
      switch (rng() % 4) {
        case 0:
          break;
        case 1:
          cursor += rng() % (40 * tt);
          break;
        case 2:
          cursor += tt * (rng() % 3);
          break;
        default:
          cursor += rng() % tt;
          break;
      }
      if (rng() % 3 == 0 && cursor > advanced + 1) {
        const std::uint64_t at = advanced + rng() % (cursor - advanced);
        a.advance(at, out_a);
        b.advance(at, out_b);
        advanced = at;
      }
      const auto data = static_cast<std::uint8_t>(rng());
      Edges edges;
      const unsigned kind = rng() % 10;
      if (kind < 6) {  // a good character: whole on b where it can be
        uart_encode(std::vector<std::uint8_t>{data}, cursor, t, edges);
        feed(a, edges);
        if (b.whole_char(cursor, data, t)) {
          ++whole;
        } else {
          feed(b, edges);
        }
      } else if (kind == 6) {  // a good character at another bit time: never whole
        const std::uint32_t other = t + 1 + rng() % 3;
        uart_encode(std::vector<std::uint8_t>{data}, cursor, other, edges);
        feed(a, edges);
        EXPECT_FALSE(b.whole_char(cursor, data, other));
        feed(b, edges);
      } else if (kind < 9) {  // a damaged character
        const UartFault f{0, kind == 7
                                 ? UartFault::Kind::parity
                                 : (rng() % 2 ? UartFault::Kind::start : UartFault::Kind::stop)};
        uart_encode(std::vector<std::uint8_t>{data}, cursor, t, edges, f);
        feed(a, edges);
        feed(b, edges);
      } else {  // a glitch
        const std::uint64_t low = 1 + rng() % (2 * tt);
        edges = {{cursor, false}, {cursor + low, true}};
        feed(a, edges);
        feed(b, edges);
      }
      cursor = std::max(cursor + 10 * tt, edges.empty() ? cursor : edges.back().first);
      ASSERT_EQ(rx_state(a), rx_state(b));
      ASSERT_EQ(out_a, out_b);
    }
    a.advance(cursor + 20 * t, out_a);
    b.advance(cursor + 20 * t, out_b);
    EXPECT_EQ(out_a, out_b);
    EXPECT_EQ(rx_state(a), rx_state(b));
    EXPECT_GE(whole, 60) << "the whole path was rarely taken";  // 86-99 of 400 steps
  }
}

// UartRx::edges (the master's and the bridge's receiver on TxD, Chip::on_txd_edges) against the
// same edges fed one by one: a random line of good characters (back to back, after gaps, inside
// the previous frame's stop bit, at another bit time), damaged ones and glitches, handed over in
// batches that end at random cycles (`upto`: the chip's events and the master's looks), with
// advance() at some of them. After every batch both receivers hold the same state, every member,
// and have given the same characters; the whole path must have been taken often.
TEST(UartRx, EdgesInBatchesLeaveTheStateTheEdgesOneByOneLeave) {
  std::mt19937 rng(23);
  for (const std::uint32_t t : {2u, 3u, 4u, 8u, 16u, 32u, 96u, 256u, 512u, 1056u, 2500u, 5000u}) {
    SCOPED_TRACE(t);
    const std::uint64_t tt = t;
    Edges line;
    std::uint64_t cursor = 100;
    for (int step = 0; step < 400; ++step) {
      cursor += rng() % 3 == 0 ? rng() % (40 * tt) : (rng() % 2 ? 0 : rng() % tt);
      const auto data = static_cast<std::uint8_t>(rng());
      Edges e;
      const unsigned kind = rng() % 10;
      if (kind < 6) {
        uart_encode(std::vector<std::uint8_t>{data}, cursor, t, e);
      } else if (kind == 6) {
        uart_encode(std::vector<std::uint8_t>{data}, cursor, t + 1 + rng() % 3, e);
      } else if (kind < 9) {
        const UartFault f{0, kind == 7
                                 ? UartFault::Kind::parity
                                 : (rng() % 2 ? UartFault::Kind::start : UartFault::Kind::stop)};
        uart_encode(std::vector<std::uint8_t>{data}, cursor, t, e, f);
      } else {
        e = {{cursor, false}, {cursor + 1 + rng() % (2 * tt), true}};
      }
      // A line has one level at a time: a fault's first edge may repeat the level the line has.
      for (const auto& x : e) {
        if (line.empty() ? !x.second : line.back().second != x.second) line.push_back(x);
      }
      cursor = std::max(cursor + 10 * tt, e.empty() ? cursor : e.back().first);
    }
    UartRx a(t, 0);
    UartRx b(t, 0);
    std::vector<UartChar> out_a;
    std::vector<UartChar> out_b;
    std::size_t next = 0;
    std::size_t whole = 0;
    std::uint64_t upto = 0;
    while (next < line.size()) {
      SCOPED_TRACE(upto);
      const unsigned span_kind = rng() % 3;
      upto += 1 + rng() % (span_kind == 0 ? 3 * tt : (span_kind == 1 ? 40 * tt : 400 * tt));
      std::size_t end = next;
      while (end < line.size() && line[end].first <= upto) ++end;
      for (std::size_t i = next; i < end; ++i) a.edge(line[i].first, line[i].second);
      whole += b.edges(std::span(line).subspan(next, end - next));
      next = end;
      if (rng() % 2 == 0) {
        a.advance(upto, out_a);
        b.advance(upto, out_b);
      }
      ASSERT_EQ(rx_state(a), rx_state(b));
      ASSERT_EQ(out_a, out_b);
      ASSERT_EQ(a.receiving(), b.receiving());
      ASSERT_EQ(a.next_deadline(), b.next_deadline());
    }
    a.advance(upto + 20 * tt, out_a);
    b.advance(upto + 20 * tt, out_b);
    EXPECT_EQ(out_a, out_b);
    EXPECT_EQ(rx_state(a), rx_state(b));
    EXPECT_GE(whole, 60u) << "the whole path was rarely taken";
  }
}

// UartRx::take (the master's and the bridge's receiver on TxD, Chip::on_txd_chars) against the
// same line fed edge by edge: telegrams of back-to-back good characters after random gaps (at the
// receiver's bit time, sometimes at another, where take falls back to edges), sometimes after a
// glitch, each handed over as the MAC hands them: runs of whole characters split at random
// characters, and a character cut at a random cycle as its edges before and after the cut. After
// every run both receivers hold the same state and have given the same characters.
TEST(UartRx, RunsOfCharactersLeaveTheStateTheirEdgesLeave) {
  std::mt19937 rng(31);
  for (const std::uint32_t t : {2u, 3u, 4u, 8u, 32u, 256u, 1056u, 5000u}) {
    SCOPED_TRACE(t);
    const std::uint64_t tt = t;
    UartRx a(t, 0);
    UartRx b(t, 0);
    std::vector<UartChar> out_a;
    std::vector<UartChar> out_b;
    std::uint64_t cursor = 100;
    const auto both = [&](const TxdRun& r) {
      Edges e(r.edges.begin(), r.edges.end());
      uart_encode(r.bytes, r.start, r.bit_cycles, e);
      for (const auto& [c, l] : e) a.edge(c, l);
      b.take(r);
      ASSERT_EQ(rx_state(a), rx_state(b));
      ASSERT_EQ(a.receiving(), b.receiving());
      ASSERT_EQ(a.next_deadline(), b.next_deadline());
    };
    for (int telegram = 0; telegram < 60; ++telegram) {
      cursor += rng() % 3 == 0 ? rng() % 3 : 1 + rng() % (50 * tt);
      if (rng() % 8 == 0) {  // a glitch the next telegram may start inside
        const Edges g{{cursor, false}, {cursor + 1 + rng() % (2 * tt), true}};
        ASSERT_NO_FATAL_FAILURE(both(TxdRun{{}, 0, 0, g}));
        cursor += rng() % (12 * tt);
      }
      const std::uint32_t bt = rng() % 6 == 0 ? t + 1 : t;
      std::vector<std::uint8_t> bytes(1 + rng() % 40);
      for (auto& x : bytes) x = static_cast<std::uint8_t>(rng());
      const std::uint64_t frame = std::uint64_t{kUartCharBits} * bt;
      std::size_t i = 0;
      while (i < bytes.size()) {
        const std::size_t n = 1 + rng() % (bytes.size() - i);
        const std::uint64_t at = cursor + i * frame;
        if (rng() % 4 == 0) {  // the first character of this piece cut at a random cycle
          Edges e;
          uart_encode(std::span(bytes).subspan(i, 1), at, bt, e);
          const std::size_t k = rng() % (e.size() + 1);
          if (k > 0) {
            ASSERT_NO_FATAL_FAILURE(both(TxdRun{{}, 0, 0, std::span(e).first(k)}));
          }
          if (k < e.size()) {
            ASSERT_NO_FATAL_FAILURE(both(TxdRun{{}, 0, 0, std::span(e).subspan(k)}));
          }
          ++i;
          continue;
        }
        ASSERT_NO_FATAL_FAILURE(both(TxdRun{std::span(bytes).subspan(i, n), at, bt, {}}));
        i += n;
        if (rng() % 2 == 0) {
          const std::uint64_t now = cursor + i * frame - rng() % frame;
          a.advance(now, out_a);
          b.advance(now, out_b);
          ASSERT_EQ(out_a, out_b);
        }
      }
      cursor += bytes.size() * frame;
    }
    a.advance(cursor + 20 * tt, out_a);
    b.advance(cursor + 20 * tt, out_b);
    EXPECT_EQ(out_a, out_b);
    EXPECT_EQ(rx_state(a), rx_state(b));
    EXPECT_GE(out_a.size(), 600u);
  }
}

// A batch may end inside a character (Chip::on_txd_edges hands over what is on the line when
// somebody looks). 0xFE has no edge after its line bit 2, so its first two edges already read as
// a good character and are taken whole; a later batch then brings an edge inside the frame (a low
// line bit 6), and the receiver must read what a receiver fed edge by edge reads.
TEST(UartRx, AnEdgeInsideACharacterTakenWholeReadsAsItsEdgesWould) {
  constexpr std::uint32_t t = 8;
  constexpr std::uint64_t s = 80;
  const Edges first{{s, false}, {s + 2 * t, true}};  // 0xFE: start, bit 0 low, then high
  const Edges later{{s + 6 * t, false}, {s + 7 * t, true}};
  UartRx a(t, 0);
  UartRx b(t, 0);
  for (const auto& [c, l] : first) a.edge(c, l);
  for (const auto& [c, l] : later) a.edge(c, l);
  EXPECT_EQ(b.edges(first), 1u);
  b.edges(later);
  std::vector<UartChar> out_a;
  std::vector<UartChar> out_b;
  a.advance(s + 20 * t, out_a);
  b.advance(s + 20 * t, out_b);
  ASSERT_EQ(out_a.size(), 1u);
  EXPECT_EQ(out_a[0].data, 0xDE);  // data bit 5 (line bit 6) low
  EXPECT_FALSE(out_a[0].parity_ok);
  EXPECT_EQ(out_a, out_b);
  EXPECT_EQ(rx_state(a), rx_state(b));
}

// A glitch anywhere inside a good character's high tail (0xFE: high from line bit 2 through the
// stop bit), in the same batch, on a bit boundary or off one: the receiver reads what a receiver
// fed edge by edge reads.
TEST(UartRx, AGlitchInsideAGoodCharacterReadsAsItsEdgesWould) {
  constexpr std::uint32_t t = 8;
  constexpr std::uint64_t s = 80;
  for (std::uint64_t d = 2 * t + 1; d + 1 < 11 * t; ++d) {
    SCOPED_TRACE(d);
    const Edges e{{s, false}, {s + 2 * t, true}, {s + d, false}, {s + d + 1, true}};
    UartRx a(t, 0);
    UartRx b(t, 0);
    for (const auto& [c, l] : e) a.edge(c, l);
    b.edges(e);
    std::vector<UartChar> out_a;
    std::vector<UartChar> out_b;
    a.advance(s + 30 * t, out_a);
    b.advance(s + 30 * t, out_b);
    ASSERT_EQ(out_a, out_b);
    ASSERT_EQ(rx_state(a), rx_state(b));
  }
}
