// Golden traces: the replay (a Trace on a fresh chip, every expectation checked). The format:
// docs/trace-format.md.
#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "dpc31/fdl.hpp"
#include "dpc31/hex.hpp"
#include "trace.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

// ---------------------------------------------------------------------------------------------
// Replay

namespace {

struct Mismatch {
  int line;
  std::string message;
};

// A Trace in memory as a TraceSource: its lines copied as they are taken.
class MemoryCursor final : public TraceCursor {
 public:
  MemoryCursor(const std::vector<TraceLine>& lines, std::optional<TraceKind> only)
      : lines_(lines), only_(only) {}
  const TraceLine* peek() override {
    while (i_ < lines_.size() && only_ && lines_[i_].kind != *only_) ++i_;
    return i_ < lines_.size() ? &lines_[i_] : nullptr;
  }
  TraceLine take() override {
    const TraceLine* l = peek();
    ++i_;
    return *l;
  }

 private:
  const std::vector<TraceLine>& lines_;
  std::optional<TraceKind> only_;
  std::size_t i_ = 0;
};

class MemorySource final : public TraceSource {
 public:
  explicit MemorySource(const Trace& t) : t_(t) {}
  [[nodiscard]] const Trace& header() const override { return t_; }
  [[nodiscard]] std::unique_ptr<TraceCursor> cursor(std::optional<TraceKind> only) const override {
    return std::make_unique<MemoryCursor>(t_.lines, only);
  }

 private:
  const Trace& t_;
};

class Replayer {
 public:
  explicit Replayer(const TraceSource& s)
      : t_(s.header()),
        chip_(t_.chip),
        lines_(s.cursor(std::nullopt)),
        tx_expected_(s.cursor(TraceKind::tx)) {
    irq_.expected = s.cursor(TraceKind::xint);
    if (t_.check_pb3) pb3_.expected = s.cursor(TraceKind::pb3);
    // Each event the chip makes ends the step in progress, to be checked before time goes on.
    chip_.on_irq_change([this](std::uint64_t cycle, bool active) {
      irq_.seen.emplace_back(cycle, active);
      chip_.request_stop();
    });
    if (t_.check_pb3) {
      chip_.on_pb3_change([this](std::uint64_t cycle, bool high) {
        pb3_.seen.emplace_back(cycle, high);
        chip_.request_stop();
      });
    }
    chip_.on_telegram([this](const Telegram& tg) {
      if (tg.from_chip) {
        tx_.push_back(tg);
        chip_.request_stop();
      }
    });
    t_bit_ = bit_cycles(chip_.clock_hz(), t_.baud);
    access_ = chip_.bus_access_cycles();
    chip_.set_log_sink({});  // the replay reports its checks, not the model's remarks
  }

  ReplayOutcome run() {
    ReplayOutcome o;
    o.pb3_checked = t_.check_pb3;
    try {
      while (lines_->peek() != nullptr) {
        const TraceLine l = lines_->take();
        check_due(o, l.cycle, &l);
        act(l, lines_->peek(), o);
      }
      o.ok = true;
    } catch (const Mismatch& m) {
      o.failure = fmt::format("{}:{}: {}", t_.file, m.line, m.message);
    }
    o.final_cycle = chip_.cycle();
    return o;
  }

 private:
  [[noreturn]] static void mismatch(int line, std::string msg) {
    throw Mismatch{line, std::move(msg)};
  }

  // Steps to cycle `c`, checking each event of the chip as it comes with the check that follows
  // the step (`horizon`, `next`: check_due's): a wrong trace fails at its first mismatch, not
  // after the rest of its time (an 'end' near 2^62 ran for hours before it said so).
  void step_to(const TraceLine& l, std::uint64_t c, ReplayOutcome& o, std::uint64_t horizon,
               const TraceLine* next) {
    if (chip_.cycle() > c) {
      // The parser rules this out; kept as a guard against a model that moves time by itself.
      mismatch(l.line,
               fmt::format("expected the chip at cycle {}, got cycle {}", c, chip_.cycle()));
    }
    const std::uint64_t to = std::min(c, Chip::kLastCycle);  // where the chip's time ends
    while (chip_.cycle() < to) {
      chip_.clear_stop();                        // one an access requested, too
      chip_.step_until_irq(to - chip_.cycle());  // step() does not end at a request
      if (!irq_.seen.empty() || !pb3_.seen.empty() || !tx_.empty()) check_due(o, horizon, next);
    }
  }

  // A line the chip drives (X/INT, PB3): its expected edges (`xint` / `pb3` lines, read from a
  // cursor of their own), and the edges the chip made that no expectation has matched yet.
  struct Pin {
    TraceKind kind;  // of its trace lines
    std::string_view keyword;
    std::string_view edge;  // "X/INT edge"
    std::unique_ptr<TraceCursor> expected;
    std::deque<std::pair<std::uint64_t, bool>> seen;
  };

  // The first expectation of `c` not yet met, once it has been played (a line up to the one
  // played last): the expectations not yet due are those, in order.
  [[nodiscard]] const TraceLine* pending(TraceCursor* c) const {
    const TraceLine* e = c != nullptr ? c->peek() : nullptr;
    return e != nullptr && e->line <= played_ ? e : nullptr;
  }

  static std::string edge_text(const Pin& p, std::uint64_t c, bool level) {
    return fmt::format("{} {} at cycle {}", p.keyword, level ? 1 : 0, c);
  }
  static std::string tx_text(std::uint64_t s, std::uint64_t e,
                             std::span<const std::uint8_t> bytes) {
    return fmt::format("tx {}..{} {}", s, e, hex_bytes(bytes));
  }

  // What the trace says instead of an event of the chip that no expectation matches.
  static std::string nothing_expected(std::uint64_t horizon, const TraceLine* next,
                                      std::string_view what) {
    if (next == nullptr || next->kind == TraceKind::end) return fmt::format("no more {}s", what);
    return fmt::format("no other {} up to cycle {}", what, horizon - 1);
  }

  // Compares the edges of `p` due by now with its expectations, in order (check_due).
  void check_edges(Pin& p, std::uint32_t& count, std::uint64_t now, std::uint64_t horizon,
                   const TraceLine* next, int next_line) {
    for (;;) {
      const TraceLine* e = pending(p.expected.get());
      if (e != nullptr && e->cycle <= now) {
        if (p.seen.empty()) {
          mismatch(e->line, fmt::format("expected {}, got no {} by cycle {}",
                                        edge_text(p, e->cycle, e->level), p.edge, now));
        }
        const auto [c, lv] = p.seen.front();
        if (c != e->cycle || lv != e->level) {
          mismatch(e->line, fmt::format("expected {}, got {}", edge_text(p, e->cycle, e->level),
                                        edge_text(p, c, lv)));
        }
        p.seen.pop_front();
        p.expected->take();
        ++count;
        continue;
      }
      if (!p.seen.empty() && p.seen.front().first <= now && p.seen.front().first < horizon &&
          (e == nullptr || p.seen.front().first < e->cycle)) {
        if (e == nullptr && next != nullptr && next->kind == p.kind) e = next;
        const std::string got = edge_text(p, p.seen.front().first, p.seen.front().second);
        if (e != nullptr) {
          mismatch(e->line,
                   fmt::format("expected {}, got {}", edge_text(p, e->cycle, e->level), got));
        }
        mismatch(next_line,
                 fmt::format("expected {}, got {}", nothing_expected(horizon, next, p.edge), got));
      }
      return;
    }
  }

  // Compares the expectations due by now with what the chip did, in order. Every expectation
  // before `horizon` has been read (`next` is the line about to be played, nullptr after the
  // end): an event the chip made before it is unexpected if no expectation matches it.
  void check_due(ReplayOutcome& o, std::uint64_t horizon, const TraceLine* next) {
    const std::uint64_t now = chip_.cycle();
    const int next_line = next != nullptr ? next->line : played_;  // after the last: the last
    check_edges(irq_, o.irq_edges, now, horizon, next, next_line);
    check_edges(pb3_, o.pb3_edges, now, horizon, next, next_line);
    for (;;) {
      const TraceLine* e = pending(tx_expected_.get());
      if (e != nullptr && e->start <= now) {
        if (tx_.empty()) {
          mismatch(e->line, fmt::format("expected {}, got no telegram from the chip by cycle {}",
                                        tx_text(e->start, e->end, e->bytes), now));
        }
        const Telegram& g = tx_.front();
        if (g.start != e->start || g.end != e->end || g.bytes != e->bytes) {
          mismatch(e->line, fmt::format("expected {}, got {}", tx_text(e->start, e->end, e->bytes),
                                        tx_text(g.start, g.end, g.bytes)));
        }
        tx_.pop_front();
        tx_expected_->take();
        ++o.telegrams_out;
        continue;
      }
      if (!tx_.empty() && tx_.front().start <= now && tx_.front().start < horizon &&
          (e == nullptr || tx_.front().start < e->start)) {
        if (e == nullptr && next != nullptr && next->kind == TraceKind::tx) e = next;
        const Telegram& g = tx_.front();
        const std::string got = tx_text(g.start, g.end, g.bytes);
        if (e != nullptr) {
          mismatch(e->line,
                   fmt::format("expected {}, got {}", tx_text(e->start, e->end, e->bytes), got));
        }
        mismatch(next_line, fmt::format("expected {}, got {}",
                                        nothing_expected(horizon, next, "telegram"), got));
      }
      break;
    }
  }

  // Plays line `l`; `after` is the line after it (nullptr after the end), whose check of the
  // expectations due follows the steps of `l`.
  void act(const TraceLine& l, const TraceLine* after, ReplayOutcome& o) {
    constexpr std::uint64_t kForever = std::numeric_limits<std::uint64_t>::max();
    const std::uint64_t horizon = after != nullptr ? after->cycle : kForever;
    played_ = l.line;
    switch (l.kind) {
      case TraceKind::rx: {
        step_to(l, l.cycle, o, horizon, after);
        chip_.drive_rxd_chars(l.bytes, l.start, t_bit_, l.fault);
        ++o.telegrams_in;
        break;
      }
      case TraceKind::rxd:
        step_to(l, l.cycle, o, horizon, after);
        for (const auto& [c, lv] : l.edges) chip_.drive_rxd(c, lv);
        ++o.telegrams_in;
        break;
      case TraceKind::reset:  // the board's RESET: the chip's new time line starts there
        step_to(l, l.cycle, o, horizon, after);
        chip_.reset(l.cycle);
        break;
      case TraceKind::wr:
        step_to(l, l.cycle - access_, o, horizon, after);
        chip_.write(l.addr, l.data);
        ++o.writes;
        break;
      case TraceKind::rd: {
        step_to(l, l.cycle - access_, o, horizon, after);
        const std::uint8_t v = chip_.read(l.addr);
        if (v != l.data) {
          mismatch(l.line, fmt::format("expected rd {:04X} = {:02X} at cycle {}, got {:02X}",
                                       l.addr, l.data, l.cycle, v));
        }
        ++o.reads;
        break;
      }
      case TraceKind::xint:
      case TraceKind::pb3:
      case TraceKind::tx:
        return;  // pending now, checked when time has passed it
      case TraceKind::state: {
        step_to(l, l.cycle, o, l.cycle + 1, &l);
        check_due(o, l.cycle + 1, &l);  // a state line follows the expectations of its cycle
        const std::vector<TraceStateKey> now = trace_state(chip_);
        for (const TraceStateKey& want : l.state) {
          const auto it = std::find_if(now.begin(), now.end(),
                                       [&](const TraceStateKey& k) { return k.key == want.key; });
          if (it->value != want.value) {
            mismatch(l.line, fmt::format("expected {}={} at cycle {}, got {}={}", want.key,
                                         want.value, l.cycle, it->key, it->value));
          }
        }
        ++o.states;
        return;
      }
      case TraceKind::end:
        step_to(l, l.cycle, o, kForever, nullptr);
        check_due(o, kForever, nullptr);
        if (pending(irq_.expected.get()) != nullptr || pending(pb3_.expected.get()) != nullptr ||
            pending(tx_expected_.get()) != nullptr) {
          // The parser keeps expectations before the end; a guard all the same.
          mismatch(l.line, "expected every expectation due by the end");
        }
        return;
    }
  }

  const Trace& t_;
  Chip chip_;
  std::unique_ptr<TraceCursor> lines_;        // every line, played in order
  std::unique_ptr<TraceCursor> tx_expected_;  // the `tx` lines
  int played_ = 0;                            // the line played last
  std::uint32_t t_bit_ = 0;
  std::uint32_t access_ = 4;
  Pin irq_{TraceKind::xint, "xint", "X/INT edge", {}, {}};
  Pin pb3_{
      TraceKind::pb3, "pb3", "PB3 edge", {}, {}};  // looked at with the header's `check pb3` only
  std::deque<Telegram> tx_;                        // observed, not yet matched
};

}  // namespace

ReplayOutcome replay_trace(const TraceSource& s) {
  Replayer r(s);
  return r.run();
}

ReplayOutcome replay_trace(const Trace& t) { return replay_trace(MemorySource(t)); }

int replay_trace_file(const std::string& path, std::string& message, ReplayOutcome* outcome) {
  TraceFile file;
  TraceError err;
  if (!file.open(path, err)) {
    message = err.text();
    return 2;
  }
  try {
    const ReplayOutcome o = replay_trace(file);
    if (outcome != nullptr) *outcome = o;
    message = o.failure;
    return o.ok ? 0 : 1;
  } catch (const TraceError& changed) {
    message = changed.text();
    return 2;
  }
}

}  // namespace dpc31
