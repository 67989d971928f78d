// What the bridge engine's tests record: the log's lines and the line's telegrams
// (Engine::on_line), for the one-slave fixture (bridge_test.cpp) and the segment's
// (bridge_segment_test.cpp).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "../lib/bridge/engine.hpp"

namespace testutil {

using Bytes = std::vector<std::uint8_t>;

struct LogLine {
  std::uint64_t cycle;
  std::string tag;
  std::string text;
  std::string station;
};

struct Sent {
  std::uint64_t start, end;
  std::string sender;
  Bytes bytes;
};

class EngineRecord {
 public:
  // A new engine with `s`; what came before is forgotten.
  void make(const dpc31::bridge::Setup& s) {
    engine_.reset();
    lines_.clear();
    line_.clear();
    engine_ = std::make_unique<dpc31::bridge::Engine>(
        s, [this](std::uint64_t cycle, std::string_view tag, std::string_view station,
                  const std::string& text) {
          lines_.push_back({cycle, std::string(tag), text, std::string(station)});
        });
    engine_->on_line([this](const dpc31::bridge::LineTelegram& t) {
      line_.push_back(
          {t.start, t.end, std::string(t.sender), Bytes(t.bytes.begin(), t.bytes.end())});
    });
  }

  // The client writes `req`; the answer once the line has settled (within 1 s of chip time).
  Bytes exchange(const Bytes& req) {
    engine_->feed(req);
    EXPECT_TRUE(engine_->settle(48'000'000));
    return engine_->take_output();
  }

  [[nodiscard]] std::vector<LogLine> tagged(const std::string& tag) const {
    std::vector<LogLine> out;
    for (const LogLine& l : lines_) {
      if (l.tag == tag) out.push_back(l);
    }
    return out;
  }

 protected:
  std::unique_ptr<dpc31::bridge::Engine> engine_;
  std::vector<LogLine> lines_;
  std::vector<Sent> line_;  // the line as the capture sees it (Engine::on_line)
};

}  // namespace testutil
