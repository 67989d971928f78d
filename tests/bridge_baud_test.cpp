// dpc31 bridge and the chip's baud search (issue 31 item 5): a master that repeats FDL_Status
// every 10 ms, as pyprofibus does, finds the slave at every one of the ten rates within the time
// docs/bridge.md and docs/timing.md ("Baud_Search") state. The master runs on the engine in free
// pacing (docs/bridge.md, "Pacing"): each exchange takes chip time only (the request, the slot
// time), then 10 ms of wall time pass, so its period is 10 ms + 166 bit times of chip time.
//
// Expected values from the documented rule only (tests/baud_search.hpp): the window of the
// master's rate opens at Start + the windows of the faster rates and again one round later; a
// request is heard when its first start bit is at least TSYN (33 bit times) after the opening and
// its last stop-bit sample (start + 65.5 bit times) at or before the window's end; the answer
// starts MinTSDR = 11 bit times after the request's end. The request cycles are the bridge's
// (its RxD lines), Start the chip's ("request MAC_Start", the dpc31 profile's Start).
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "../lib/bridge/engine.hpp"
#include "baud_search.hpp"
#include "dpc31/fdl.hpp"

namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::uint64_t kTenMs = 480'000;  // 10 ms at 48 MHz
const Bytes kFdlStatus = dpc31::fdl::encode(dpc31::fdl::make_frame(5, 2, 0x49));

struct Line {
  std::uint64_t cycle;
  std::string tag;
  std::string text;
};

// Where the master starts: with the chip (its first request right after the firmware's Start),
// or at the worst phase (its first request's last stop sample half a bit time after the window
// of its rate closed, so the whole rest of the round passes before it is heard).
enum class Phase : std::uint8_t { start_up, worst };

class BridgeBaudSearch : public ::testing::TestWithParam<std::tuple<std::uint32_t, Phase>> {
 protected:
  void SetUp() override {
    dpc31::bridge::Setup s;
    s.firmware = dpc31_find_firmware("DO4");
    s.baud = std::get<0>(GetParam());
    s.log_detail = dpc31::bridge::LogDetail::telegrams;
    engine_ = std::make_unique<dpc31::bridge::Engine>(
        s, [this](std::uint64_t cycle, std::string_view tag, std::string_view /*station*/,
                  const std::string& text) {
          lines_.push_back({cycle, std::string(tag), text});
        });
  }

  // The 10 ms master: FDL_Status until answered, at most `budget` cycles of chip time.
  void poll(std::uint64_t budget) {
    const std::uint64_t from = engine_->cycle();
    while (engine_->cycle() - from < budget) {
      engine_->feed(kFdlStatus);
      ASSERT_TRUE(engine_->settle(48'000'000));
      if (!engine_->take_output().empty()) return;
      engine_->run_until(engine_->cycle() + kTenMs);
    }
  }

  [[nodiscard]] std::vector<std::uint64_t> cycles_of(const std::string& tag) const {
    std::vector<std::uint64_t> out;
    for (const Line& l : lines_) {
      if (l.tag == tag) out.push_back(l.cycle);
    }
    return out;
  }
  [[nodiscard]] std::uint64_t start_cycle() const {
    for (const Line& l : lines_) {
      if (l.tag == "CHIP" && l.text == "request MAC_Start") return l.cycle;
    }
    ADD_FAILURE() << "no MAC_Start in the log";
    return 0;
  }

  std::unique_ptr<dpc31::bridge::Engine> engine_;
  std::vector<Line> lines_;
};

TEST_P(BridgeBaudSearch, TenMsMasterIsAnsweredWithinTheDocumentedTime) {
  const auto [baud, phase] = GetParam();
  const std::uint64_t t = testutil::bit_time_48mhz(baud);
  ASSERT_EQ(engine_->bit_cycles(), t);
  engine_->run_until(engine_->cycle() + 1);  // the log up to now: Start
  const std::uint64_t s = start_cycle();
  const std::uint64_t w = testutil::baud_search_window(baud);
  const std::uint64_t opens = s + testutil::baud_search_opens(baud);
  const std::uint64_t round = testutil::kBaudSearchRound;
  if (phase == Phase::worst) {
    // The first request starts 65 bit times before the window closes: its last stop sample
    // (65.5 bit times in) falls after the end.
    engine_->run_until(opens + w - 65 * t);
    ASSERT_EQ(engine_->cycle(), opens + w - 65 * t);
  }
  poll(2 * round);
  engine_->flush_log();

  const std::vector<std::uint64_t> rx = cycles_of("RxD");
  const std::vector<std::uint64_t> tx = cycles_of("TxD");
  ASSERT_EQ(tx.size(), 1u) << "answered once, the last request";
  ASSERT_FALSE(rx.empty());
  // The master's period, start to start: the request and the slot time, then 10 ms (longer than
  // TSYN: the next request goes out at once).
  const std::uint64_t period = kTenMs + (66 + 100) * t;
  for (std::size_t k = 1; k < rx.size(); ++k) ASSERT_EQ(rx[k] - rx[k - 1], period) << k;
  // The request the rule says is heard: the first that lies whole in a window of the rate.
  std::size_t heard = rx.size();
  for (std::size_t k = 0; k < rx.size() && heard == rx.size(); ++k) {
    for (std::uint64_t o = opens; o <= rx[k]; o += round) {
      if (rx[k] >= o + 33 * t && rx[k] + 65 * t + t / 2 <= o + w) heard = k;
    }
  }
  ASSERT_EQ(heard, rx.size() - 1) << "the requests after the heard one were not sent";
  EXPECT_EQ(tx[0], rx[heard] + (66 + 11) * t);
  EXPECT_EQ(engine_->chip().wd_state(), dpc31::WdState::Baud_Control);

  // The documented bounds (docs/timing.md, "Baud_Search"): from the master's first request at
  // most R - W + P + 176 bit times, under 0.9 s; from Start, the faster rates' windows + P + 110.
  const std::uint64_t found = tx[0] - rx[0];
  RecordProperty("found_cycles", std::to_string(found));
  EXPECT_LE(found, round - w + period + 176 * t);
  EXPECT_LT(found, 43'200'000u) << "0.9 s";
  if (phase == Phase::start_up) {
    EXPECT_LE(tx[0] - s, testutil::baud_search_opens(baud) + period + 110 * t);
  } else {
    EXPECT_GT(found, round - w) << "the worst phase waits for the next round";
  }
}

INSTANTIATE_TEST_SUITE_P(AllRates, BridgeBaudSearch,
                         ::testing::Combine(::testing::ValuesIn(dpc31::kBaudRates),
                                            ::testing::Values(Phase::start_up, Phase::worst)),
                         [](const auto& i) {
                           return std::to_string(std::get<0>(i.param)) +
                                  (std::get<1>(i.param) == Phase::start_up ? "_from_start_up"
                                                                           : "_worst_phase");
                         });

}  // namespace
