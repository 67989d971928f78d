// The chip's FDL MAC: the RxD receiver framing characters into telegrams (TSYN before a
// request, errors counted by class), baud-rate search, and the TxD transmitter that sends our
// answer MinTSDR bit times after the request's last stop bit.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "dp_sm.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/fifo.hpp"
#include "dpc31/uart.hpp"
#include "regfile.hpp"
#include "signals.hpp"
#include "timer.hpp"
#include "watchdog.hpp"

namespace dpc31 {

// Baud_Search listens at each rate for max(kBaudSearchBits bit times, kBaudSearchFloorUs) before
// trying the next lower one (modelled, docs/timing.md "Baud_Search"): the floor in time lets a
// master that repeats FDL_Status every 10 ms be heard at every rate within one round.
inline constexpr std::uint32_t kBaudSearchBits = 4096;
inline constexpr std::uint32_t kBaudSearchFloorUs = 20'000;
inline constexpr std::uint32_t kMinTsdrBits = 11;

// Per-cycle engine: counts whole bit times of `t` clocks, one tick per clock.
struct BitTimer {
  bool on = false;
  std::uint32_t sub = 0;   // clocks into the current bit time
  std::uint32_t bits = 0;  // whole bit times counted
  std::uint32_t target = 0;
  void start(std::uint32_t n) { *this = BitTimer{true, 0, 0, n}; }
  // One clock; true on the clock that completes `target` bit times (the timer then stops).
  bool tick(std::uint32_t t) {
    if (!on || ++sub < t) return false;
    sub = 0;
    if (++bits < target) return false;
    on = false;
    return true;
  }
};

// Per-cycle engine: the transmitter shifting our answer out bit by bit.
struct TxShifter {
  // wait_end: the rest of the request's stop bit; tsdr: MinTSDR bit times; shifting: on the line.
  enum class Phase : std::uint8_t { idle, wait_end, tsdr, shifting };
  Phase phase = Phase::idle;
  std::vector<std::uint8_t> bytes;
  std::uint32_t tsdr_bits = 0;
  BitTimer timer;
  std::size_t index = 0;  // character on the line
  std::uint32_t bit = 0;  // bit of that character
  std::uint32_t sub = 0;  // clocks into that bit
};

// A telegram heard whole (Mac::hear_telegram, docs/segment.md "Telegram level"): its characters
// are not in the receiver. The MAC acts at the stop sample of the first character on_char would
// show (`effect_at`), sets the receiver as the characters leave it at the last one's, and turns
// the telegram back into characters (Mac::materialize) when anything else reaches the receiver
// first: an edge, a reconfigure, Go_Offline, a snapshot.
struct HeardTelegram {
  // frame: TSYN before it, a frame starts; no_sync: a start without TSYN, counted, the rest
  // skipped; skipped: without TSYN while the MAC skips already (nothing to show).
  enum class Kind : std::uint8_t { frame, no_sync, skipped };
  bool active = false;
  Kind kind = Kind::skipped;
  // The characters and the assembler's run over them up to its verdict (Kind::frame: the first
  // effect), shared by every chip that hears the telegram.
  std::shared_ptr<const HeardFrame> tel;
  std::uint64_t start = 0;
  std::uint32_t t = 0;
  std::uint64_t driven_at = 0;       // the chip's cycle when it was driven
  std::uint64_t effect_at = kNever;  // kNever: shown already, or nothing to show
  [[nodiscard]] std::uint64_t stop_sample(std::size_t i) const {
    return start + (i * kUartCharBits + kUartCharBits - 1) * std::uint64_t{t} + t / 2;
  }
  [[nodiscard]] std::uint64_t due() const {
    return effect_at != kNever ? effect_at : stop_sample(tel->bytes.size() - 1);
  }
};

// Our answer as characters (docs/engine.md "Characters on TxD"): while nobody watches TxD edges
// (no on_txd, no on_txd_edges observer) the transmitter keeps the answer as its bytes, back to
// back from `start` at `t` clocks per bit, and makes edges only for whoever needs them
// (Mac::tx_to_edges, a snapshot, a character only partly on the line when TxD is taken).
struct TxChars {
  std::vector<std::uint8_t> bytes;  // empty: no answer, or it is in State::tx_edges
  std::uint64_t start = 0;
  std::uint32_t t = 0;
  std::uint64_t taken = 0;  // TxD is taken up to this cycle: its edges at or before it
  [[nodiscard]] bool active() const { return !bytes.empty(); }
  [[nodiscard]] std::uint64_t frame_cycles() const { return std::uint64_t{kUartCharBits} * t; }
  [[nodiscard]] std::uint64_t char_start(std::size_t i) const { return start + i * frame_cycles(); }
  // The character whose frame holds cycle `c` (>= start); bytes.size() past the last.
  [[nodiscard]] std::size_t char_at(std::uint64_t c) const {
    return static_cast<std::size_t>(
        std::min<std::uint64_t>((c - start) / frame_cycles(), bytes.size()));
  }
  [[nodiscard]] bool level(std::uint64_t c) const {  // TxD at cycle c
    if (c < start) return true;
    const std::size_t i = char_at(c);
    if (i == bytes.size()) return true;
    return uart_bit(bytes[i], static_cast<std::uint32_t>((c - char_start(i)) / t));
  }
  // The edges of character i at or before `to` and after `from`, written to out (at most 11).
  std::size_t edges(std::size_t i, std::uint64_t from, std::uint64_t to,
                    std::pair<std::uint64_t, bool>* out) const;
  // All edges, as uart_encode gives them (a snapshot, Mac::tx_to_edges).
  void encode(std::vector<std::pair<std::uint64_t, bool>>& out) const;
};

class Mac {
 public:
  struct State {
    UartRx rx;
    fdl::Assembler frame;
    std::vector<UartChar> chars;  // scratch for UartRx::advance
    bool in_frame = false;
    bool skipping = false;  // after a telegram, an error or an unsynchronised start: wait for TSYN
    std::uint64_t frame_timeout = kNever;
    std::uint8_t search_code = 0;
    std::uint64_t search_deadline = kNever;
    // Transmitter: TxD edges still to come, and the end of our answer's last stop bit.
    std::vector<std::pair<std::uint64_t, bool>> tx_edges;
    std::size_t tx_next = 0;
    std::uint64_t tx_end = kNever;
    bool txd = true;
    TxChars tx_chars;  // or the answer as characters (then tx_edges is empty)
    // Per-cycle engine (docs/engine.md): its own receiver and counters; never the deadlines above.
    UartSampler sampler;
    BitTimer gap;     // idle inside a telegram, from the end of a character (TSYN ends it)
    BitTimer search;  // the Baud_Search window at the current rate, in clocks
    TxShifter shifter;
    // RxD edges driven for later cycles. Kept here, not in the receiver, so they survive a
    // receiver (re)configure (Baud_Search switching the rate, Start).
    Fifo<std::pair<std::uint64_t, bool>> rxd_pending;
    bool rxd_level = true;  // the RxD line (per-cycle engine)
    // Event engine: a telegram heard whole; a snapshot writes it as its characters (materialize).
    HeardTelegram heard;
    // Go_Offline or a RAM access violation while a request was in progress (docs/timing.md,
    // "Go_Offline"): Offline when the request being received (`request`) or the answer armed or
    // on the line (`answer`) ends.
    enum class OfflinePending : std::uint8_t { none, request, answer };
    OfflinePending offline_pending = OfflinePending::none;

    // TxD with the edges up to `now` taken, whether or not an event has taken them yet: the
    // first edge after `now`, and the line's level (the answer as edges).
    [[nodiscard]] std::pair<std::size_t, bool> txd_at(std::uint64_t now) const {
      std::size_t i = tx_next;
      bool level = txd;
      for (; i < tx_edges.size() && tx_edges[i].first <= now; ++i) level = tx_edges[i].second;
      return {i, level};
    }
  };

  Mac(Clock& clock, const RegisterFile& regs, DpStateMachine& dp, Watchdog& watchdog,
      FdlCounters& counters, Signals& sig)
      : clock_(clock), regs_(regs), dp_(dp), watchdog_(watchdog), counters_(counters), sig_(sig) {}
  void reset();  // a hardware reset: listening at 12 Mbaud (for the offline count), line idle

  void start_search();  // Baud_Search from the highest rate down (Start, Baud_Control expiry)
  void stop();          // Go_Offline: no search, no telegram, no answer; TxD idle
  // Go_Offline (or a RAM access violation) on a started chip: true when a request is in
  // progress, then `offline_due` takes the chip Offline at its end; false: Offline now.
  // `cause` names it in the log line.
  bool defer_offline(std::string_view cause);
  std::function<void()> offline_due;  // ModeRegisters::offline (set by its constructor)
  void drive_rxd(std::uint64_t cycle, bool level);
  // Chip::drive_rxd_chars: one good character from `start` (>= now), whole when the receiver can
  // take it so (UartRx::whole_char), else edge by edge; the same state and observers either way.
  void drive_rxd_char(std::uint64_t start, std::uint8_t data, std::uint32_t bit_cycles);
  // Chip::hear_telegram: good back-to-back characters from `start` (>= now) taken as one
  // telegram when the receiver is idle at their rate and the MAC between telegrams (event engine,
  // not in Baud_Search); false, and nothing taken, otherwise.
  bool hear_telegram(const std::shared_ptr<const HeardFrame>& tel, std::uint64_t start,
                     std::uint32_t bit_cycles);
  // Chip::hear_run: a run of telegrams heard whole taken at once; false, and nothing taken,
  // where the chip is not as the run assumes (then it hears them one by one).
  bool hear_run(const HeardRun& run);
  // Whether hear_telegram would take `chars` characters from `start` now.
  [[nodiscard]] bool can_hear(std::size_t chars, std::uint64_t start,
                              std::uint32_t bit_cycles) const;
  // A telegram heard whole as the characters drive_rxd_char would have given the receiver, and
  // what their stop samples up to now did: from here on the MAC is where characters leave it.
  void materialize();
  void watch_txd(std::function<void(std::uint64_t, bool)> cb);  // Chip::on_txd
  // Chip::on_txd_edges: edge observers need the answer as edges.
  void watch_txd_edges(std::function<void(std::span<const std::pair<std::uint64_t, bool>>)> cb);
  // Chip::take_txd: the TxD edges up to now onto the pin, handed to the on_txd_edges observers.
  void tx_catch_up();
  // Chip::wake_on_txd: while on, the next falling TxD edge is an event that fires the wake-up.
  void wake_on_txd(bool on);
  // Whether a TxD wake-up fired since the last call (ChipCore stops the step there).
  [[nodiscard]] bool take_txd_wake() { return std::exchange(woke_, false); }
  // Chip::load_state: the wake-up is whoever steps the chip's, not state: it stays as it was.
  void keep_wake(const Mac& old) {
    wake_ = old.wake_;
    woke_ = old.woke_;
    if (wake_) clock_.note_deadline(deadline());
  }
  [[nodiscard]] bool txd_level() const;  // TxD now, also with edges not yet taken
  [[nodiscard]] std::uint32_t bit_time() const { return s_.rx.bit_time(); }

  // The engines: whatever is due now (event engine), or one clock (per-cycle engine).
  void process();
  void clock();
  [[nodiscard]] std::uint64_t deadline() const;  // event engine: the MAC's next deadline
  // deadline() without the due cycle of a telegram heard whole that shows nothing outside the
  // chip there (heard_quiet): Chip::line_deadline, docs/segment.md "Verdicts that show nothing".
  [[nodiscard]] std::uint64_t line_deadline() const;
  // Chip::may_hear_later: every telegram heard whole at `t` clocks per bit from the next one on
  // whose frame is not served here would show nothing (heard_quiet) and be taken whole, until
  // the next deadline (an event may change it) or a new observer.
  [[nodiscard]] bool hears_later(std::uint32_t t) const;

 private:
  friend struct BlockAccess;
  void listen(std::uint8_t code);  // receive at kBaudRates[code] from now on
  void arm_search_window();
  void stop_search_window();
  void search_next();
  void truncated();
  bool set_txd(std::uint64_t cycle, bool level);   // false: TxD had that level already
  void txd_edge(std::uint64_t cycle, bool level);  // one edge, to every kind of observer
  void tx_to_edges();  // the answer kept as characters becomes its edges (someone watches them)
  void tx_catch_up_chars();  // tx_catch_up of an answer kept as characters
  void hand_txd_edges(std::span<const std::pair<std::uint64_t, bool>> e);  // to the batch observers
  [[nodiscard]] bool edge_batches() const { return sig_.txd_edges || sig_.txd_chars; }
  void tx_done();
  // A telegram of the request the Offline waits for ended (whole, broken or dropped): Offline
  // now, or at the end of the answer it armed.
  void request_ended();
  [[nodiscard]] bool tx_busy() const;
  void on_char(const UartChar& c);
  // on_char's end of a frame: the assembler's verdict after its last character `last`.
  // `decoded`: fdl::decode of the complete frame, known already (a telegram heard whole).
  void frame_ended(fdl::Assembler::Status st, const UartChar& last,
                   const fdl::Decoded* decoded = nullptr);
  void take_heard();  // the heard telegram's effect or its end is due
  // Whether take_heard at the heard telegram's due cycle changes nothing but counters and the
  // receiver's and the framing's state: no telegram, answer, interrupt, state or log line.
  [[nodiscard]] bool heard_quiet() const;
  [[nodiscard]] std::uint64_t deadline_but_heard() const;
  void drop_heard_rxd(std::uint64_t at);  // the queue as drive_rxd_char left it at cycle `at`
  void on_frame(const fdl::Frame& f, const UartChar& last);
  void send(std::span<const std::uint8_t> answer, std::uint64_t request_end);

  Clock& clock_;
  const RegisterFile& regs_;
  DpStateMachine& dp_;
  Watchdog& watchdog_;
  FdlCounters& counters_;
  Signals& sig_;  // not const: Chip::on_txd adds its observer through the MAC (watch_txd)
  State s_;
  // Not state (a snapshot leaves them): the wake-up a master asked for, and whether it fired.
  bool wake_ = false;
  bool woke_ = false;
  // Inside on_frame's service and send: the chip's own buffer access is part of the request, so
  // a RAM access violation there waits for its end (never set between two cycles).
  bool serving_ = false;
};

}  // namespace dpc31
