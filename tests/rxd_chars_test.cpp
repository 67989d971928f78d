// Characters on RxD (Chip::drive_rxd_chars, issue 19 item 1) against the same telegrams as edges
// (uart_encode, then Chip::drive_rxd edge by edge), the path every earlier test and golden trace
// was made with. Two chips of the same profile get the same line: from Start through the baud
// search (telegrams at the master's rate while the chip listens at the others: those characters
// cannot go whole), then, at the rate found, good requests, damaged ones (parity, start bit, stop
// bit: still damaged, counted the same) and line noise. After every telegram the two chips hold
// the same state, every byte of it (save_state), have put out the same TxD edges, and count the
// same FDL errors. Every profile, every PROFIBUS rate.
#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "baud_search.hpp"
#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/fdl.hpp"
#include "responder.hpp"
#include "test_util.hpp"

using namespace dpc31;

namespace {

using Edges = std::vector<std::pair<std::uint64_t, bool>>;

struct Side {
  Chip chip;
  Responder user{ResponderConfig{}};
  Edges txd;
  explicit Side(Profile p) : chip({p, BusMode::intel, 0}) {
    chip.set_log_sink(nullptr);
    DirectBus bus(chip);
    user.init(bus);  // station address 5, buffers, Start (dpc31: MAC_Start)
    chip.on_txd([this](std::uint64_t c, bool l) { txd.emplace_back(c, l); });
  }
};

class RxdChars : public ::testing::TestWithParam<std::tuple<Profile, std::uint32_t>> {};

}  // namespace

TEST_P(RxdChars, TheChipIsLeftAsByItsEdges) {
  const auto [profile, baud] = GetParam();
  Side edges(profile);
  Side chars(profile);
  const std::uint32_t t = bit_cycles(edges.chip.clock_hz(), baud);
  std::uint64_t next = edges.chip.cycle() + 40 * std::uint64_t{t};
  // One telegram on both lines, then both chips run until the slot time after it has passed.
  const auto send = [&](const std::vector<std::uint8_t>& bytes, UartFault fault) {
    Edges e;
    uart_encode(bytes, next, t, e, fault);
    for (const auto& [cycle, level] : e) edges.chip.drive_rxd(cycle, level);
    const std::uint64_t end = chars.chip.drive_rxd_chars(bytes, next, t, fault);
    // Answer (up to 250 characters) after the slot time, and TSYN before the next request.
    const std::uint64_t until = end + (100 + 33) * std::uint64_t{t};
    edges.chip.step(until - edges.chip.cycle());
    chars.chip.step(until - chars.chip.cycle());
    while (edges.chip.txd_pin() == false || chars.chip.txd_pin() == false) {
      edges.chip.step(11 * std::uint64_t{t});
      chars.chip.step(11 * std::uint64_t{t});
    }
    next = edges.chip.cycle() + 33 * std::uint64_t{t};
  };
  const auto check = [&](const char* what) {
    SCOPED_TRACE(what);
    ASSERT_TRUE(testutil::same_state(edges.chip, chars.chip));
    ASSERT_EQ(edges.txd, chars.txd);
    ASSERT_EQ(edges.chip.fdl_counters(), chars.chip.fdl_counters());
  };
  const std::uint8_t slave = 5;
  const std::uint8_t master = 2;
  const std::vector<std::uint8_t> status = fdl::encode(fdl::make_frame(
      slave, master, fdl::make_request_fc(fdl::Function::FDL_Status, false, false)));
  // The baud search: FDL_Status until the chip has found the rate (two rounds at most).
  const std::uint64_t give_up = next + 2 * testutil::kBaudSearchRound + 10'000'000;
  while (chars.chip.wd_state() == WdState::Baud_Search && next < give_up) {
    send(status, {});
    check("baud search");
  }
  ASSERT_NE(chars.chip.wd_state(), WdState::Baud_Search) << "the rate was never found";
  ASSERT_FALSE(edges.txd.empty()) << "FDL_Status was never answered";

  const std::vector<std::uint8_t> diag = fdl::encode(
      fdl::make_frame(slave, master, fdl::make_request_fc(fdl::Function::SRD_high, true, true), {},
                      sap::Slave_Diag, sap::Master));
  const std::vector<std::uint8_t> prm = fdl::encode(
      fdl::make_frame(slave, master, fdl::make_request_fc(fdl::Function::SRD_high, false, true),
                      prm_du(SlaveConfig{}, 0x88), sap::Set_Prm, sap::Master));
  send(diag, {});
  check("Slave_Diag");
  send(prm, {3, UartFault::Kind::parity});
  check("Set_Prm, parity error in character 3");
  send(prm, {5, UartFault::Kind::stop});
  check("Set_Prm, stop bit 0 in character 5");
  send(prm, {1, UartFault::Kind::start});
  check("Set_Prm, no start bit in character 1");
  send({0x00, 0xFF, 0x55, 0x10, 0x68}, {});
  check("line noise");
  send(status, {});
  check("FDL_Status again");
  send(diag, {});
  check("Slave_Diag again");
  const FdlCounters& n = chars.chip.fdl_counters();
  EXPECT_GE(n.parity + n.start_bit + n.stop_bit, 2u) << "the damaged characters were not damaged";
}

INSTANTIATE_TEST_SUITE_P(ProfilesAndRates, RxdChars,
                         ::testing::Combine(::testing::Values(Profile::spc3, Profile::vpc3plus,
                                                              Profile::dpc31),
                                            ::testing::ValuesIn(kBaudRates)),
                         testutil::profile_rate_name);

// The serial calls refuse what a user's line cannot do (include/dpc31/chip.hpp, "the serial
// side"): an edge or a start before the chip's cycle() (it would be a glitch now, in the chip's
// past) and a bit of 0 clocks, each with std::invalid_argument naming the call, nothing driven:
// the chip's state, every byte of it, as before, and no on_rxd edge. The range's edges are taken.
TEST(ChipRxdRefusals, ATimeInTheChipsPastOrABitOfNoClocksIsRefusedAndDrivesNothing) {
  Chip chip;
  chip.set_log_sink(nullptr);
  chip.step(1000);
  Edges seen;
  chip.on_rxd([&](std::uint64_t c, bool l) { seen.emplace_back(c, l); });
  const std::vector<std::uint8_t> before = chip.save_state();
  const std::vector<std::uint8_t> status = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
  const auto message = [&](auto call) {
    try {
      call();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message([&] { chip.drive_rxd(999, false); }),
            "drive_rxd: cycle 999 is before the chip's cycle 1000");
  EXPECT_EQ(message([&] { chip.drive_rxd_chars(status, 999, 4); }),
            "drive_rxd_chars: start 999 is before the chip's cycle 1000");
  EXPECT_EQ(message([&] {
              chip.drive_rxd_chars(status, 999, 4, {2, UartFault::Kind::parity});
            }),
            "drive_rxd_chars: start 999 is before the chip's cycle 1000");
  EXPECT_EQ(message([&] { chip.drive_rxd_chars(status, 1000, 0); }),
            "drive_rxd_chars: bit_cycles 0: a bit lasts 1 clock or more");
  EXPECT_EQ(message([&] { chip.hear_telegram(status, 0, 4); }),
            "hear_telegram: start 0 is before the chip's cycle 1000");
  EXPECT_EQ(message([&] { chip.hear_telegram(status, 2000, 0); }),
            "hear_telegram: bit_cycles 0: a bit lasts 1 clock or more");
  EXPECT_EQ(message([&] { chip.hear_telegram(HeardFrame::make(status), 999, 4); }),
            "hear_telegram: start 999 is before the chip's cycle 1000");
  EXPECT_EQ(message([&] { chip.hear_telegram(HeardFrame::make(status), 2000, 0); }),
            "hear_telegram: bit_cycles 0: a bit lasts 1 clock or more");
  EXPECT_EQ(chip.save_state(), before);
  EXPECT_TRUE(seen.empty());
  // The edges of the range are taken: a cycle or a start at cycle(), 1 clock per bit. The
  // character 00h (chip-facts.md, "UART char: 11 bits = start, 8 data (LSB first), even parity,
  // 1 stop") is low from its start bit through its parity bit and rises for the stop bit, bit
  // 10; its last stop bit ends 11 clocks after the start.
  chip.drive_rxd(1000, true);
  EXPECT_EQ(chip.drive_rxd_chars(std::vector<std::uint8_t>{0x00}, 1000, 1), 1011u);
  EXPECT_EQ(seen, (Edges{{1000, true}, {1000, false}, {1010, true}}));
}
