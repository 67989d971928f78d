// The answer a chip armed, as the segment keeps it (session/segment_station.hpp, ArmedAnswer):
// its TxD edges are made only where something takes them one by one. Until then every question
// the line asks of it (its next edge, whether it drives within a window, whether TxD drove its
// next characters or edges) must have the answer its edges give once made; the edges themselves
// are uart_encode's, checked bit by bit against docs/timing.md's frame by
// UartEncode.EveryByteEdgeForEdgeFromItsBits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "segment_station.hpp"

namespace dpc31 {
namespace {

using Edge = std::pair<std::uint64_t, bool>;

// A Data_Exchange answer (SD2, 8 bytes of inputs) with data bytes whose only fall is their start
// bit (0x00 with even parity 0, 0xFF's parity 0 falls) and one with a fall in every other bit.
Telegram answer() {
  return Telegram{true,
                  {0x68, 0x0B, 0x0B, 0x68, 0x02, 0x05, 0x08, 0x00, 0xFF, 0x55, 0xAA, 0x00, 0x01,
                   0x80, 0x7E, 0x00, 0x16},
                  1000,
                  0};
}
constexpr std::uint32_t kT = 32;  // 1.5 Mbaud at 48 MHz

struct Pair {
  Pair() {
    const Telegram tel = answer();
    lazy.arm(tel, kT);
    made.arm(tel, kT);
    made.make();
  }
  ArmedAnswer lazy;
  ArmedAnswer made;
};

TEST(SegmentAnswer, ItsEdgesAreUartEncodesAndItsLastIsTheRiseIntoTheLastStopBit) {
  Pair p;
  std::vector<Edge> expected;
  uart_encode(p.made.bytes, 1000, kT, expected);
  EXPECT_EQ(p.made.edges, expected);
  EXPECT_EQ(p.lazy.last, expected.back().first);
  EXPECT_TRUE(expected.back().second);
  EXPECT_EQ(p.lazy.next_edge(), 1000u);  // its first start bit
}

TEST(SegmentAnswer, DrivesInEveryWindowAsItsEdgesSay) {
  Pair p;
  const std::uint64_t end = p.made.last + 2 * kT;
  for (const std::uint64_t width : {0u, 1u, 3u, kT - 1, kT, 11 * kT}) {
    for (std::uint64_t from = 990; from <= end; ++from) {
      ASSERT_EQ(p.lazy.drives(from, from + width), p.made.drives(from, from + width))
          << "window [" << from << ", " << from + width << "]";
    }
  }
  EXPECT_FALSE(p.lazy.made);  // asked without making its edges
}

TEST(SegmentAnswer, TxdSeenInCharactersAndEdgesAsItsEdgesSay) {
  Pair p;
  const std::uint64_t frame = 11 * kT;
  const auto chars = [&](std::size_t from, std::size_t n) {
    const std::span<const std::uint8_t> data(p.made.bytes.data() + from, n);
    const bool a = p.lazy.see(data, 1000 + from * frame, kT);
    EXPECT_EQ(a, p.made.see(data, 1000 + from * frame, kT)) << "characters from " << from;
    return a;
  };
  const auto edges_of = [&](std::size_t k) {
    std::vector<Edge> e;
    uart_encode(std::span(p.made.bytes).subspan(k, 1), 1000 + k * frame, kT, e);
    return e;
  };
  const auto edge = [&](Edge e) {
    const bool a = p.lazy.see(e);
    EXPECT_EQ(a, p.made.see(e)) << "edge at " << e.first;
    return a;
  };
  // The line relayed it whole: TxD is behind until it drove all of it.
  p.lazy.next = ArmedAnswer::kWhole;
  p.made.next = p.made.edges.size();
  EXPECT_TRUE(p.lazy.behind());
  EXPECT_TRUE(chars(0, 3));
  EXPECT_FALSE(chars(4, 2));  // a character skipped
  const std::vector<Edge> c3 = edges_of(3);
  EXPECT_TRUE(edge(c3[0]));
  EXPECT_TRUE(edge(c3[1]));
  // Made halfway through a character (an observer takes its edges): on from the same place.
  ArmedAnswer half = p.lazy;
  half.make();
  EXPECT_EQ(half.confirmed, p.made.confirmed);
  EXPECT_EQ(half.next, p.made.next);
  EXPECT_EQ(p.lazy.first_unconfirmed(), c3[2].first);
  EXPECT_EQ(p.lazy.first_unconfirmed(), p.made.first_unconfirmed());
  EXPECT_FALSE(chars(3, 1));                            // the character half seen, again whole
  EXPECT_FALSE(chars(4, 1));                            // the next one before the rest of it
  EXPECT_FALSE(edge({c3[2].first + 1, c3[2].second}));  // a cycle late
  EXPECT_FALSE(edge({c3[2].first, !c3[2].second}));     // the wrong level
  for (std::size_t j = 2; j < c3.size(); ++j) EXPECT_TRUE(edge(c3[j]));
  EXPECT_TRUE(chars(4, 6));
  EXPECT_EQ(p.lazy.first_unconfirmed(), 1000 + 10 * frame);
  EXPECT_TRUE(p.lazy.behind());
  // Made between characters.
  ArmedAnswer between = p.lazy;
  between.make();
  EXPECT_EQ(between.confirmed, p.made.confirmed);
  EXPECT_EQ(between.next, p.made.next);
  for (const Edge& e : edges_of(10)) EXPECT_TRUE(edge(e));
  EXPECT_TRUE(chars(11, p.made.bytes.size() - 11));
  EXPECT_FALSE(p.lazy.behind());
  EXPECT_FALSE(p.made.behind());
  EXPECT_FALSE(edge({p.made.last + kT, false}));  // nothing after its end
}

TEST(SegmentAnswer, WithdrawnItHasNothingToRelayOrToSee) {
  Pair p;
  p.lazy.withdraw();
  p.made.withdraw();
  EXPECT_TRUE(p.lazy.all_relayed());
  EXPECT_EQ(p.lazy.next_edge(), UINT64_MAX);
  EXPECT_EQ(p.made.next_edge(), UINT64_MAX);
  EXPECT_FALSE(p.lazy.behind());
  EXPECT_FALSE(p.made.behind());
}

}  // namespace
}  // namespace dpc31
