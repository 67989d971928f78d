// What the blocks tell the world: the log and the observers of the chip's pins and events
// (dpc31::Chip::on_*). Every block gets the one Signals of its chip; none of them is state (a
// snapshot leaves them with whoever attached them).
#pragma once

#include <fmt/format.h>

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include "block_event.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/log.hpp"
#include "timer.hpp"

namespace dpc31 {

// Counts a call out of the chip to its user (an observer, the log sink) while it runs, also
// when it throws.
struct Calling {
  explicit Calling(std::uint32_t& n) : n_(n) { ++n_; }
  ~Calling() { --n_; }
  Calling(const Calling&) = delete;
  Calling& operator=(const Calling&) = delete;

 private:
  std::uint32_t& n_;
};

// Several parties watch the chip (the scenario runner, waveform and capture writers, the
// built-in master): each observer is a list. Adding an empty function clears the list.
// Each has an id (from 1), so that one party can take its own away (remove) and leave the rest.
template <typename... A>
struct Observers {
  std::vector<std::function<void(A...)>> fns;
  std::vector<ObserverId> ids;  // fns[i]'s
  ObserverId last = 0;
  // Calls in progress: the chip is inside one of them (Signals::calling_out).
  mutable std::uint32_t calling = 0;
  explicit operator bool() const { return !fns.empty(); }
  void operator()(A... a) const {
    if (fns.empty()) return;  // most lists (the state's, after every event) have none
    const Calling in(calling);
    for (const auto& f : fns) f(a...);
  }
  // The new observer's id; 0 for an empty function.
  ObserverId add(std::function<void(A...)> f) {
    if (!f) {
      fns.clear();
      ids.clear();
      return 0;
    }
    fns.push_back(std::move(f));
    ids.push_back(++last);
    return last;
  }
  void remove(ObserverId id) {
    for (std::size_t i = 0; i < ids.size(); ++i) {
      if (ids[i] == id) {
        fns.erase(fns.begin() + static_cast<std::ptrdiff_t>(i));
        ids.erase(ids.begin() + static_cast<std::ptrdiff_t>(i));
        return;
      }
    }
  }
};

struct Signals {
  explicit Signals(const Clock& c) : clock(&c), sink(stderr_sink()) {}

  const Clock* clock;
  LogSink sink;
  // The sink shows no line below this level: warn for the default stderr sink, so that the
  // debug and info lines it drops are not formatted (an EOI logs one per interrupt); for a sink
  // of the user's what Chip::set_log_sink was given (debug: every level).
  LogLevel shown = LogLevel::warn;
  Observers<std::uint64_t, bool> irq;  // X/INT activity
  Observers<std::uint64_t, bool> pb3;  // dpc31 port PB3
  Observers<std::uint64_t, bool> txd;  // one by one, each edge an event (Chip::on_txd)
  // In batches, when the MAC catches up (Chip::on_txd_edges).
  Observers<std::span<const std::pair<std::uint64_t, bool>>> txd_edges;
  // In batches as characters where it can, else edges (Chip::on_txd_chars).
  Observers<const TxdRun&> txd_chars;
  Observers<std::uint64_t, bool> rxd;  // edges as they are driven (possibly ahead of time)
  Observers<const Telegram&> telegram;
  Observers<const Telegram&> answer;  // the chip's own answers only, when armed
  Observers<std::uint64_t, const BlockEvent&> block;
  Observers<std::uint64_t, const BusAccess&> bus;
  Observers<std::uint64_t> state;              // after every event and every bus access
  mutable std::array<LogLimiter, 4> limiters;  // per LogLevel; they go with the sink
  // Of the log's last line: whose repeats are owed.
  mutable std::size_t last_level = 0;
  mutable std::uint32_t sinking = 0;  // calls of the sink in progress

  // Whether the chip is inside a call to one of its observers or its sink: its blocks are in the
  // middle of an event or access (Chip::load_state refuses to replace them there).
  [[nodiscard]] bool calling_out() const {
    return sinking + irq.calling + pb3.calling + txd.calling + txd_edges.calling +
               txd_chars.calling + rxd.calling + telegram.calling + answer.calling + block.calling +
               bus.calling + state.calling !=
           0;
  }

  // Reports a protocol-side action on the blocks (call sites only, never inside the actions).
  void emit(BlockEvent::Kind k, std::uint16_t value = 0, std::uint8_t data = 0) const {
    if (block) block(clock->now, BlockEvent{k, value, data});
  }
  // Through the level's limiter (folded, bounded: dpc31::LogLimiter); one per level, so that a
  // flood of remarks never crowds out a warning. The repeats are the log's as its sink shows it
  // (syslogd's "last message repeated"): a line of another level ends those of the line before,
  // whose count comes first (s33 audit, s34-left). A level the sink does not show is not even
  // formatted, so a firmware's per-interrupt debug lines end no fold where nobody sees them.
  template <typename... Args>
  void log(LogLevel level, fmt::format_string<Args...> f, Args&&... args) const {
    if (!sink || level < shown) return;
    const Calling in(sinking);
    const auto l = static_cast<std::size_t>(level);
    if (l != last_level) {
      for (std::string& t : limiters[last_level].end_repeats())
        sink(LogRecord{clock->now, static_cast<LogLevel>(last_level), std::move(t)});
      last_level = l;
    }
    for (std::string& t : limiters[l].add(clock->now, fmt::format(f, std::forward<Args>(args)...)))
      sink(LogRecord{clock->now, level, std::move(t)});
  }
  // What the limiters still owe goes to the sink (before it is replaced, at the end of a run).
  void flush_log() const {
    const Calling in(sinking);
    for (std::size_t l = 0; l < limiters.size(); ++l)
      for (std::string& t : limiters[l].flush())
        if (sink) sink(LogRecord{clock->now, static_cast<LogLevel>(l), std::move(t)});
  }
  // Everything attached moves to another chip's Signals (a snapshot load); the clock stays.
  void take_attachments(Signals& from) noexcept {
    sink = std::move(from.sink);
    shown = from.shown;
    limiters = std::move(from.limiters);
    last_level = from.last_level;
    irq = std::move(from.irq);
    pb3 = std::move(from.pb3);
    txd = std::move(from.txd);
    txd_edges = std::move(from.txd_edges);
    txd_chars = std::move(from.txd_chars);
    rxd = std::move(from.rxd);
    telegram = std::move(from.telegram);
    answer = std::move(from.answer);
    block = std::move(from.block);
    bus = std::move(from.bus);
    state = std::move(from.state);
  }
};

}  // namespace dpc31
