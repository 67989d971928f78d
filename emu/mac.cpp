// The FDL MAC of the chip. Rules (docs/timing.md, "Serial line"): a telegram starts with a
// start delimiter after at least TSYN = 33 idle bit times; the line idle for TSYN inside a
// telegram ends it as truncated; a bad character aborts the telegram and the receiver waits for
// TSYN again; a request is acted on at the stop-bit sample of its last character; the answer's
// first start bit goes out MinTSDR bit times after the end of that character's stop bit.
#include "mac.hpp"

#include <algorithm>
#include <array>
#include <tuple>

namespace dpc31 {

namespace {

void count(FdlCounters& n, fdl::Error e) {
  switch (e) {
    case fdl::Error::none:
      break;
    case fdl::Error::bad_sd:
      ++n.bad_sd;
      break;
    case fdl::Error::truncated:
      ++n.truncated;
      break;
    case fdl::Error::le_mismatch:
      ++n.le_mismatch;
      break;
    case fdl::Error::bad_le:
      ++n.bad_le;
      break;
    case fdl::Error::bad_fcs:
      ++n.bad_fcs;
      break;
    case fdl::Error::wrong_ed:
      ++n.wrong_ed;
      break;
    case fdl::Error::oversize:
      ++n.oversize;
      break;
    case fdl::Error::bad_sap:
      ++n.bad_sap;
      break;
  }
}

}  // namespace

void count_frame_error(FdlCounters& n, const fdl::Assembler& frame, fdl::Error decoded) {
  if (frame.status() != fdl::Assembler::Status::error) {
    count(n, decoded);
    return;
  }
  const auto bytes = frame.bytes();
  const bool too_long =
      frame.error() == fdl::Error::bad_le && bytes.size() >= 2 && bytes[1] > fdl::kMaxLe;
  count(n, too_long ? fdl::Error::oversize : frame.error());
}

void Mac::start_search() {
  listen(0);  // from the highest rate down
  s_.in_frame = false;
  s_.skipping = false;
  s_.frame.reset();
  s_.frame_timeout = kNever;
  arm_search_window();
  request_ended();  // a Baud_Control expiry drops a telegram in progress
}

void Mac::listen(std::uint8_t code) {
  materialize();  // a telegram heard whole is re-heard at the new rate as its edges would be
  s_.search_code = code;
  const std::uint32_t t = bit_cycles(clock_.hz, kBaudRates[code]);
  s_.rx.configure(t, clock_.now);
  s_.sampler.configure(t);
  // Edges driven for later cycles are still to come on the line: the receiver hears them at the
  // new rate (the per-cycle engine reads them off the line clock by clock anyway).
  if (clock_.engine == Engine::event) {
    for (const auto& [cycle, level] : s_.rxd_pending) {
      if (cycle > clock_.now) s_.rx.edge(cycle, level);
    }
    clock_.note_deadline(s_.rx.next_deadline());
  }
}

void Mac::search_next() {
  // A window has its fixed length whatever is on the line: garbage heard at a wrong rate neither
  // restarts nor extends it (a master at another rate would hold the search forever), and a
  // character or telegram in progress is dropped with the old rate.
  listen(static_cast<std::uint8_t>((s_.search_code + 1) % std::size(kBaudRates)));
  s_.in_frame = false;
  s_.frame.reset();
  s_.frame_timeout = kNever;
  s_.skipping = false;
  arm_search_window();
  request_ended();
}

void Mac::truncated() {
  ++counters_.truncated;
  sig_.log(LogLevel::info, "telegram truncated: the line went idle for TSYN after {} bytes",
           s_.frame.bytes().size());
  s_.in_frame = false;
  s_.frame.reset();
  s_.frame_timeout = kNever;
  request_ended();
}

bool Mac::set_txd(std::uint64_t cycle, bool level) {
  if (level == s_.txd) return false;
  s_.txd = level;
  if (sig_.txd) sig_.txd(cycle, level);
  if (wake_ && !level) {
    wake_ = false;
    woke_ = true;
  }
  return true;
}

void Mac::txd_edge(std::uint64_t cycle, bool level) {
  if (!set_txd(cycle, level) || !edge_batches()) return;
  const std::pair<std::uint64_t, bool> e{cycle, level};
  hand_txd_edges(std::span(&e, 1));
}

void Mac::hand_txd_edges(std::span<const std::pair<std::uint64_t, bool>> e) {
  if (sig_.txd_edges) sig_.txd_edges(e);
  if (sig_.txd_chars) sig_.txd_chars(TxdRun{{}, 0, 0, e});
}

void Mac::tx_done() {
  s_.tx_end = kNever;
  s_.tx_edges.clear();
  s_.tx_next = 0;
  s_.tx_chars.bytes.clear();
  s_.shifter = TxShifter{};
  dp_.response_sent();
  if (s_.offline_pending == State::OfflinePending::answer) {
    s_.offline_pending = State::OfflinePending::none;
    offline_due();
  }
}

void Mac::request_ended() {
  if (s_.offline_pending != State::OfflinePending::request) return;
  if (tx_busy()) {
    s_.offline_pending = State::OfflinePending::answer;
    return;
  }
  s_.offline_pending = State::OfflinePending::none;
  offline_due();
}

bool Mac::defer_offline(std::string_view cause) {
  if (s_.offline_pending != State::OfflinePending::none) return true;
  materialize();  // a telegram heard whole: is it in progress now?
  // An answer armed or on the line is the current request's; a telegram being received after
  // TSYN (from its first character's stop sample on) is one.
  if (tx_busy()) {
    s_.offline_pending = State::OfflinePending::answer;
  } else if (s_.in_frame || serving_) {
    s_.offline_pending = State::OfflinePending::request;
  } else {
    return false;
  }
  sig_.log(LogLevel::info, "{}: Offline after the current request", cause);
  sig_.emit(BlockEvent::Kind::offline_deferred);
  return true;
}

bool Mac::tx_busy() const {
  return clock_.engine == Engine::event ? s_.tx_end != kNever
                                        : s_.shifter.phase != TxShifter::Phase::idle;
}

void Mac::stop() {
  materialize();  // the receiver goes on taking characters; only the MAC's framing stops
  tx_catch_up();  // what went out before the stop reaches the edge observers
  stop_search_window();
  s_.frame_timeout = kNever;
  s_.gap.on = false;
  s_.in_frame = false;
  s_.frame.reset();
  s_.tx_edges.clear();
  s_.tx_next = 0;
  s_.tx_chars.bytes.clear();
  s_.tx_end = kNever;
  s_.shifter = TxShifter{};
  s_.offline_pending = State::OfflinePending::none;
  txd_edge(clock_.now, true);
}

std::uint64_t Mac::deadline() const {
  const std::uint64_t t = deadline_but_heard();
  return s_.heard.active ? std::min(t, s_.heard.due()) : t;
}

std::uint64_t Mac::line_deadline() const {
  const std::uint64_t t = deadline_but_heard();
  return s_.heard.active && !heard_quiet() ? std::min(t, s_.heard.due()) : t;
}

// take_heard's paths, decided ahead from what they read (on_frame's state of the DP state machine
// and the watchdog: only an event changes it, and each event is before the due cycle or in the
// deadline the line sees). Observers of telegrams and of the state would be called at the due
// cycle; an answer on TxD is handed to its observers at every event.
bool Mac::heard_quiet() const {
  const HeardTelegram& h = s_.heard;
  if (sig_.telegram || sig_.state || s_.tx_end != kNever) return false;
  if (h.kind != HeardTelegram::Kind::frame) return true;  // no_sync counted; the receiver set
  const std::uint64_t last = h.stop_sample(h.tel->bytes.size() - 1);
  const fdl::Assembler::Status st = h.tel->frame.status();
  if (h.effect_at != last || st == fdl::Assembler::Status::need_more) return false;  // characters
  if (st == fdl::Assembler::Status::error || h.tel->decoded.error != fdl::Error::none) return true;
  const fdl::Frame& f = h.tel->decoded.frame;
  if (!dp_.started()) return true;  // counted offline
  const bool carries_data = f.sd == fdl::SD1 || f.sd == fdl::SD2 || f.sd == fdl::SD3;
  if (!carries_data) return true;                               // a token, a short ack
  if (watchdog_.state() == WdState::Baud_Search) return false;  // the rate found
  if (!fdl::is_request(f.fc)) return true;                      // an answer
  return f.da != dp_.station() && f.da != fdl::kBroadcast;      // foreign_address counted
}

bool Mac::hears_later(std::uint32_t t) const {
  // heard_quiet's conditions that do not depend on the frame; the frame's are the line's
  // (TelegramLog::concerns: a request with data to this address or a broadcast is served).
  if (clock_.engine != Engine::event || sig_.telegram || sig_.state || sig_.rxd ||
      s_.tx_end != kNever || watchdog_.state() == WdState::Baud_Search ||
      s_.search_deadline != kNever || s_.in_frame || s_.frame_timeout != kNever ||
      (!s_.rxd_pending.empty() && (s_.rxd_pending.end() - 1)->first > clock_.now)) {
    return false;
  }
  // can_hear from the next telegram on: the receiver idle at `t`, or so once the telegram it
  // heard whole is taken (after_chars at the same rate), quietly.
  const HeardTelegram& h = s_.heard;
  if (h.active) return h.t == t && s_.rx.bit_time() == t && heard_quiet();
  return s_.rx.bit_time() == t && t >= 2 && s_.rx.level() && !s_.rx.receiving() &&
         s_.rx.next_deadline() == UartRx::kIdle;
}

std::uint64_t Mac::deadline_but_heard() const {
  std::uint64_t t =
      std::min({s_.rx.next_deadline(), s_.frame_timeout, s_.search_deadline, s_.tx_end});
  // Single TxD bits are events only for someone watching them one by one, and the next start
  // bit for a wake-up; otherwise the answer's edges are taken as the line is looked at
  // (txd_pin, take_txd) or at the next event, at the latest the end of the answer.
  const std::size_t next = s_.tx_next;
  if (next < s_.tx_edges.size()) {
    if (sig_.txd) {
      t = std::min(t, s_.tx_edges[next].first);
    } else if (wake_) {
      // The edges alternate: the next falling one is this edge or the one after.
      const std::size_t fall = s_.tx_edges[next].second ? next + 1 : next;
      if (fall < s_.tx_edges.size()) t = std::min(t, s_.tx_edges[fall].first);
    }
  } else if (const TxChars& a = s_.tx_chars; wake_ && a.active()) {
    // Every start bit is a falling edge: the next one after what is taken.
    const std::size_t i = a.taken < a.start ? 0 : a.char_at(a.taken) + 1;
    if (i < a.bytes.size()) t = std::min(t, a.char_start(i));
  }
  return t;
}

void Mac::wake_on_txd(bool on) {
  wake_ = on;
  woke_ = false;
  if (on) clock_.note_deadline(deadline());
}

void Mac::watch_txd(std::function<void(std::uint64_t, bool)> cb) {
  // Edges before now happened unwatched; from now on each one is an event again.
  tx_catch_up();
  tx_to_edges();
  sig_.txd.add(std::move(cb));
  clock_.note_deadline(deadline());
}

void Mac::watch_txd_edges(std::function<void(std::span<const std::pair<std::uint64_t, bool>>)> cb) {
  // The new observer gets the edges not taken yet, as it would from an answer made of edges.
  tx_to_edges();
  sig_.txd_edges.add(std::move(cb));
}

std::size_t TxChars::edges(std::size_t i, std::uint64_t from, std::uint64_t to,
                           std::pair<std::uint64_t, bool>* out) const {
  std::array<std::pair<std::uint64_t, bool>, kUartCharBits> all{};
  // A good character follows a stop bit or the idle line.
  const std::size_t n = uart_char_edges(bytes[i], char_start(i), t, all.data());
  std::size_t m = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (all[k].first > from && all[k].first <= to) out[m++] = all[k];
  }
  return m;
}

void TxChars::encode(std::vector<std::pair<std::uint64_t, bool>>& out) const {
  uart_encode(bytes, start, t, out);
}

void Mac::tx_to_edges() {
  TxChars& a = s_.tx_chars;
  if (!a.active()) return;
  s_.tx_edges.clear();
  a.encode(s_.tx_edges);
  // What was taken as characters is taken as edges; TxD (s_.txd) is the level it left.
  s_.tx_next = static_cast<std::size_t>(
      std::partition_point(s_.tx_edges.begin(), s_.tx_edges.end(),
                           [&](const auto& e) { return e.first <= a.taken; }) -
      s_.tx_edges.begin());
  a.bytes.clear();
}

void Mac::tx_catch_up_chars() {
  TxChars& a = s_.tx_chars;
  const std::uint64_t from = a.taken;
  const std::uint64_t now = clock_.now;
  if (now <= from || now < a.start) return;
  a.taken = now;
  s_.txd = a.level(now);
  // The first character whose start bit (a falling edge) lies after `from`, and the one whose
  // frame holds `now`.
  const std::size_t first = from < a.start ? 0 : a.char_at(from) + 1;
  const std::size_t last = a.char_at(now);
  if (wake_ && first <= last && first < a.bytes.size()) {
    wake_ = false;
    woke_ = true;
  }
  if (!sig_.txd_chars) return;
  std::array<std::pair<std::uint64_t, bool>, kUartCharBits> e{};
  const auto hand_edges = [&](std::size_t i) {
    const std::size_t n = a.edges(i, from, now, e.data());
    if (n > 0) sig_.txd_chars(TxdRun{{}, 0, 0, std::span(e.data(), n)});
  };
  // The rest of a character partly taken before, ...
  if (first > 0 && first - 1 < a.bytes.size()) hand_edges(first - 1);
  // ... the characters whose edges (up to the rise into the stop bit) are all on the line ...
  const std::uint64_t last_edge = std::uint64_t{kUartCharBits - 1} * a.t;
  std::size_t whole = first;
  if (now >= a.start + last_edge) {
    whole = std::max(
        first, std::min<std::size_t>(
                   a.bytes.size(),
                   static_cast<std::size_t>((now - a.start - last_edge) / a.frame_cycles()) + 1));
  }
  if (whole > first) {
    sig_.txd_chars(
        TxdRun{std::span(a.bytes).subspan(first, whole - first), a.char_start(first), a.t, {}});
  }
  // ... and the edges so far of the one on the line now.
  if (whole < a.bytes.size() && a.char_start(whole) <= now) hand_edges(whole);
}

void Mac::tx_catch_up() {
  if (s_.tx_chars.active()) {
    tx_catch_up_chars();
    return;
  }
  const std::size_t from = s_.tx_next;
  if (sig_.txd || wake_) {
    while (s_.tx_next < s_.tx_edges.size() && s_.tx_edges[s_.tx_next].first <= clock_.now) {
      set_txd(s_.tx_edges[s_.tx_next].first, s_.tx_edges[s_.tx_next].second);
      ++s_.tx_next;
    }
  } else {
    std::tie(s_.tx_next, s_.txd) = s_.txd_at(clock_.now);  // nobody to tell edge by edge
  }
  if (s_.tx_next > from && edge_batches()) {
    hand_txd_edges(std::span(s_.tx_edges).subspan(from, s_.tx_next - from));
  }
}

bool Mac::txd_level() const {
  return s_.tx_chars.active() ? s_.tx_chars.level(clock_.now) : s_.txd_at(clock_.now).second;
}

void Mac::process() {
  if (s_.heard.active && s_.heard.due() <= clock_.now) take_heard();
  s_.chars.clear();
  s_.rx.advance(clock_.now, s_.chars);
  for (const UartChar& c : s_.chars) on_char(c);
  if (s_.in_frame && s_.frame_timeout <= clock_.now) {
    // A character that started before the gap reached TSYN continues the telegram: its stop
    // sample decides.
    if (s_.rx.busy_from() < s_.frame_timeout) {
      s_.frame_timeout = kNever;
    } else {
      truncated();
    }
  }
  if (s_.search_deadline <= clock_.now) search_next();
  tx_catch_up();
  if (s_.tx_end <= clock_.now) tx_done();
}

// Per-cycle engine: the MAC's clock (docs/engine.md, step 4): the receiver looks at RxD, the
// TSYN gap and the transmitter count bit times, the Baud_Search window clocks.
void Mac::clock() {
  while (!s_.rxd_pending.empty() && s_.rxd_pending.front().first <= clock_.now) {
    s_.rxd_level = s_.rxd_pending.front().second;
    s_.rxd_pending.pop_front();
  }
  const std::uint32_t t = s_.rx.bit_time();
  UartChar ch;
  const UartSampler::Clock r = s_.sampler.clock(s_.rxd_level, clock_.now, ch);
  if (r.ready) on_char(ch);
  // Idle inside a telegram counts from the end of a stop bit; a start bit ends the gap, but one
  // on the very clock TSYN is reached comes too late (the gap is 33 bit times).
  if (s_.gap.tick(t) && s_.in_frame) truncated();
  if (r.ended && s_.in_frame) s_.gap.start(kTsynBits);
  if (r.started) s_.gap.on = false;
  if (s_.search.tick(1)) search_next();
  TxShifter& tx = s_.shifter;
  switch (tx.phase) {
    case TxShifter::Phase::idle:
      break;
    case TxShifter::Phase::wait_end:
      if (r.ended) {
        tx.phase = TxShifter::Phase::tsdr;
        tx.timer.start(tx.tsdr_bits);
      }
      break;
    case TxShifter::Phase::tsdr:
      if (tx.timer.tick(t)) {
        tx.phase = TxShifter::Phase::shifting;
        tx.index = 0;
        tx.bit = 0;
        tx.sub = 0;
        txd_edge(clock_.now, uart_bit(tx.bytes[0], 0));
      }
      break;
    case TxShifter::Phase::shifting:
      if (++tx.sub < t) break;
      tx.sub = 0;
      if (++tx.bit == kUartCharBits) {
        tx.bit = 0;
        ++tx.index;
      }
      if (tx.index < tx.bytes.size()) {
        txd_edge(clock_.now, uart_bit(tx.bytes[tx.index], tx.bit));
      } else {
        txd_edge(clock_.now, true);
        tx_done();
      }
      break;
  }
}

void Mac::on_char(const UartChar& c) {
  const bool start_ok = c.start_ok || regs_.mode0(fields::Mode_Reg0::Dis_Start_Control);
  const bool stop_ok = c.stop_ok || regs_.mode0(fields::Mode_Reg0::Dis_Stop_Control);
  if (!c.parity_ok || !start_ok || !stop_ok) {
    // One count per broken telegram: characters misframed after the first error are its tail.
    // A character after TSYN opens a telegram whatever the one before was (docs/timing.md
    // "Telegrams"). Of one character's errors the first sampled counts: start bit, parity, stop
    // bit.
    if (s_.in_frame || c.idle_bits >= kTsynBits) {
      if (!start_ok) {
        ++counters_.start_bit;
      } else if (!c.parity_ok) {
        ++counters_.parity;
      } else {
        ++counters_.stop_bit;
      }
    }
    s_.in_frame = false;
    s_.frame.reset();
    s_.frame_timeout = kNever;
    s_.skipping = true;
    request_ended();
    return;
  }
  const std::uint64_t tsyn = std::uint64_t{kTsynBits};
  if (s_.in_frame && c.idle_bits >= tsyn) {
    ++counters_.truncated;  // a new telegram began before the old one was complete
    s_.in_frame = false;
    s_.frame.reset();
    request_ended();
  }
  if (!s_.in_frame) {
    if (c.idle_bits < tsyn) {
      if (!s_.skipping) ++counters_.no_sync;
      s_.skipping = true;
      return;
    }
    s_.skipping = false;
    s_.in_frame = true;
    s_.frame.reset();
  }
  const fdl::Assembler::Status st = s_.frame.push(c.data);
  s_.frame_timeout = c.end + tsyn * s_.rx.bit_time();
  if (st == fdl::Assembler::Status::need_more) return;
  frame_ended(st, c);
  request_ended();
}

void Mac::frame_ended(fdl::Assembler::Status st, const UartChar& c, const fdl::Decoded* decoded) {
  s_.in_frame = false;
  s_.frame_timeout = kNever;
  if (st == fdl::Assembler::Status::error) {
    // The rest of the broken telegram is its tail, not an unsynchronised one: wait for TSYN.
    s_.skipping = true;
    count_frame_error(counters_, s_.frame, fdl::Error::none);
    return;
  }
  fdl::Decoded own;
  if (decoded == nullptr) own = fdl::decode(s_.frame.bytes());
  const fdl::Decoded& d = decoded != nullptr ? *decoded : own;
  if (d.error != fdl::Error::none) {
    count_frame_error(counters_, s_.frame, d.error);
    return;
  }
  const std::uint64_t frame_chars = s_.frame.bytes().size();
  if (sig_.telegram) {
    const std::uint64_t t = std::uint64_t{kUartCharBits} * s_.rx.bit_time();
    sig_.telegram(Telegram{
        false, {s_.frame.bytes().begin(), s_.frame.bytes().end()}, c.end - frame_chars * t, c.end});
  }
  on_frame(d.frame, c);
}

void Mac::on_frame(const fdl::Frame& f, const UartChar& last) {
  // A telegram that ends while the chip waits to go Offline after its answer is not a request.
  if (!dp_.started() || s_.offline_pending == State::OfflinePending::answer) {
    ++counters_.offline;
    return;
  }
  const bool carries_data = f.sd == fdl::SD1 || f.sd == fdl::SD2 || f.sd == fdl::SD3;
  if (watchdog_.state() == WdState::Baud_Search && carries_data) {
    stop_search_window();
    watchdog_.baud_found(s_.search_code);
  }
  if (!carries_data || !fdl::is_request(f.fc)) return;  // tokens, acknowledges, answers
  if (f.da != dp_.station() && f.da != fdl::kBroadcast) {
    ++counters_.foreign_address;
    return;
  }
  if (f.da == dp_.station() && tx_busy()) {
    // Half duplex, one request at a time: the answer to the one before still waits for its TSDR
    // or is on the line, so this one is not acted on (docs/timing.md, "Telegrams").
    sig_.log(LogLevel::warn,
             "a request from station {} ended while the answer to the one before was still due "
             "(armed or on the line): not acted on, not answered (half duplex)",
             f.sa);
    return;
  }
  if (f.da == dp_.station()) watchdog_.retrigger(f.sa, dp_.master_add());
  serving_ = true;
  if (dp_.service(f)) send(dp_.answer(), last.end);
  serving_ = false;
}

void Mac::send(std::span<const std::uint8_t> answer, std::uint64_t request_end) {
  if (tx_busy()) return;  // half duplex: still sending the previous answer
  // Into the buffer of the answer before (idle, so empty): no allocation per answer.
  std::vector<std::uint8_t> bytes = std::move(s_.tx_chars.bytes);
  bytes.assign(answer.begin(), answer.end());
  const std::uint32_t t = s_.rx.bit_time();
  // The newest of Set_Prm byte 3 (not 0), a MinTSDR_Val write and MAC_New_TRDY (dp_sm.hpp).
  const std::uint32_t tsdr = std::max<std::uint32_t>(
      kMinTsdrBits, dp_.min_tsdr() != 0 ? dp_.min_tsdr() : regs_.latch(RegId::MinTSDR_Val));
  const std::uint64_t start = request_end + std::uint64_t{tsdr} * t;
  const std::uint64_t end = start + bytes.size() * std::uint64_t{kUartCharBits} * t;
  if (sig_.telegram || sig_.answer) {
    // The observers see it by const reference: the bytes are lent to it, not copied.
    Telegram armed{true, std::move(bytes), start, end};
    sig_.telegram(armed);
    sig_.answer(armed);
    bytes = std::move(armed.bytes);
  }
  if (clock_.engine == Engine::per_cycle) {
    // Counted from the end of the request's stop bit, as the receiver sees it.
    s_.shifter.phase = TxShifter::Phase::wait_end;
    s_.shifter.bytes = std::move(bytes);
    s_.shifter.tsdr_bits = tsdr;
    return;
  }
  s_.tx_edges.clear();
  s_.tx_next = 0;
  if (sig_.txd || sig_.txd_edges) {
    uart_encode(bytes, start, t, s_.tx_edges);
    s_.tx_chars.bytes = std::move(bytes);
    s_.tx_chars.bytes.clear();  // the answer is its edges; the buffer kept for the next one
  } else {                      // nobody watches the edges: the answer stays characters (TxChars)
    s_.tx_chars.bytes = std::move(bytes);
    s_.tx_chars.start = start;
    s_.tx_chars.t = t;
    s_.tx_chars.taken = clock_.now;
  }
  s_.tx_end = end;
}

void Mac::reset() {
  tx_catch_up();  // as stop(): what went out before reaches the edge observers
  s_ = State{};
  listen(0);  // listening at 12 Mbaud, for the offline count
}

void Mac::arm_search_window() {
  // 4096 bit times, at least 20 ms: 20 ms ... 427 ms at 48 MHz (at most 4096 x 447 392 clocks
  // at 9.6 kbaud with the fastest clock a uint32_t holds, so the count fits the BitTimer).
  const std::uint64_t window = std::max(std::uint64_t{kBaudSearchBits} * s_.rx.bit_time(),
                                        clock_.cycles_for_us(kBaudSearchFloorUs));
  if (clock_.engine == Engine::event) {
    s_.search_deadline = clock_.now + window;
    clock_.note_deadline(s_.search_deadline);
  } else {
    s_.search.start(static_cast<std::uint32_t>(window));
  }
}

void Mac::stop_search_window() {
  s_.search_deadline = kNever;
  s_.search.on = false;
}

void Mac::drive_rxd(std::uint64_t cycle, bool level) {
  materialize();
  const std::uint64_t at = std::max(cycle, clock_.now);
  clock_.quiet_until = 0;
  if (clock_.engine == Engine::event) {
    // The receiver samples edges as they are given; the queue only serves a later reconfigure.
    while (!s_.rxd_pending.empty() && s_.rxd_pending.front().first <= clock_.now)
      s_.rxd_pending.pop_front();
    s_.rx.edge(at, level);
    if (at > clock_.now) s_.rxd_pending.emplace_back(at, level);
  } else if (at > clock_.now) {
    s_.rxd_pending.emplace_back(at, level);
  } else {
    // This clock is already evaluated: the edge counts for it, its samples are taken.
    s_.rxd_level = level;
    if (s_.sampler.late_edge(level, clock_.now)) s_.gap.on = false;
  }
  sig_.rxd(at, level);
}

void Mac::drive_rxd_char(std::uint64_t start, std::uint8_t data, std::uint32_t bit_cycles) {
  materialize();
  // The character's edges, as uart_encode gives them after a high line.
  std::array<std::pair<std::uint64_t, bool>, kUartCharBits> edges{};
  const std::size_t n = uart_char_edges(data, start, bit_cycles, edges.data());
  // The per-cycle engine is the reference: it always takes edges.
  if (clock_.engine != Engine::event || start < clock_.now ||
      !s_.rx.whole_char(start, data, bit_cycles)) {
    for (std::size_t i = 0; i < n; ++i) drive_rxd(edges[i].first, edges[i].second);
    return;
  }
  // Taken whole: the rest of drive_rxd for each edge (a reconfigure hears the pending ones again).
  clock_.quiet_until = 0;
  drop_heard_rxd(clock_.now);
  for (std::size_t i = 0; i < n; ++i) {
    if (edges[i].first > clock_.now) s_.rxd_pending.emplace_back(edges[i]);
    sig_.rxd(edges[i].first, edges[i].second);
  }
}

void Mac::drop_heard_rxd(std::uint64_t at) {
  while (!s_.rxd_pending.empty() && s_.rxd_pending.front().first <= at) s_.rxd_pending.pop_front();
}

bool Mac::can_hear(std::size_t chars, std::uint64_t start, std::uint32_t bit_cycles) const {
  // Between telegrams: nothing of the receiver's still to report, no frame open or timing out,
  // no search window that would switch the rate inside it, no edge driven ahead.
  return clock_.engine == Engine::event && !s_.heard.active && chars > 0 && start >= clock_.now &&
         s_.rx.idle_for(start, bit_cycles) && !s_.in_frame && s_.frame_timeout == kNever &&
         s_.search_deadline == kNever &&
         (s_.rxd_pending.empty() || (s_.rxd_pending.end() - 1)->first <= clock_.now);
}

bool Mac::hear_telegram(const std::shared_ptr<const HeardFrame>& tel, std::uint64_t start,
                        std::uint32_t bit_cycles) {
  if (!can_hear(tel->bytes.size(), start, bit_cycles)) return false;
  const std::vector<std::uint8_t>& bytes = tel->bytes;
  HeardTelegram& h = s_.heard;
  h.tel = tel;
  h.start = start;
  h.t = bit_cycles;
  h.driven_at = clock_.now;
  // on_char's first decision (docs/timing.md "Serial line"): TSYN before the first character.
  if (s_.rx.idle_bits_at(start) >= kTsynBits) {
    // A frame starts; nothing shows before the assembler's verdict (complete or an error).
    h.kind = HeardTelegram::Kind::frame;
    h.effect_at = h.stop_sample(tel->verdict);
  } else if (!s_.skipping) {
    h.kind = HeardTelegram::Kind::no_sync;  // counted at the first stop sample, the rest skipped
    h.effect_at = h.stop_sample(0);
  } else {
    h.kind = HeardTelegram::Kind::skipped;
    h.effect_at = kNever;
  }
  h.active = true;
  if (sig_.rxd) {
    std::array<std::pair<std::uint64_t, bool>, kUartCharBits> edges{};
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      const std::uint64_t at = start + i * std::uint64_t{kUartCharBits} * bit_cycles;
      const std::size_t n = uart_char_edges(bytes[i], at, bit_cycles, edges.data());
      for (std::size_t k = 0; k < n; ++k) sig_.rxd(edges[k].first, edges[k].second);
    }
  }
  clock_.quiet_until = 0;
  return true;
}

bool Mac::hear_run(const HeardRun& r) {
  // Every verdict of the run shows nothing (heard_quiet: no observer, no answer on TxD, not the
  // rate found by Baud_Search), and the receiver is where the line's telegram before the run left
  // it: the run's first TSYN is the line's.
  if (sig_.telegram || sig_.state || sig_.rxd || s_.tx_end != kNever ||
      (dp_.started() && watchdog_.state() == WdState::Baud_Search) ||
      !can_hear(1, r.first_start, r.bit_cycles) ||
      s_.rx.idle_bits_at(r.first_start) != r.first_idle) {
    return false;
  }
  // take_heard of each: the first one's no_sync depends on the chip's framing before it.
  if (r.first_idle < kTsynBits && !s_.skipping) ++counters_.no_sync;
  const FdlCounters& add = dp_.started() ? r.started : r.offline;
  for (const CounterField& f : kFdlCounterFields) counters_.*f.member += add.*f.member;
  s_.skipping = r.skipping;
  if (r.synced != nullptr) s_.frame = r.synced->frame;
  s_.rx.after_chars(r.last_start, r.last_byte, r.last_idle);
  drop_heard_rxd(clock_.now);
  clock_.quiet_until = 0;
  return true;
}

void Mac::take_heard() {
  HeardTelegram& h = s_.heard;
  const std::uint64_t last = h.stop_sample(h.tel->bytes.size() - 1);
  if (h.kind == HeardTelegram::Kind::no_sync && h.effect_at != kNever) {
    ++counters_.no_sync;  // on_char of the first character
    s_.skipping = true;
    h.effect_at = kNever;
    if (clock_.now < last) return;
  }
  if (h.kind == HeardTelegram::Kind::frame &&
      (h.effect_at < last || h.tel->frame.status() == fdl::Assembler::Status::need_more)) {
    // The frame ends before the telegram does, or runs into a frame timeout: character by
    // character.
    materialize();
    return;
  }
  // The last stop sample: the receiver as the characters leave it, drive_rxd_char's queue.
  const std::uint64_t frame_cycles = std::uint64_t{kUartCharBits} * h.t;
  const std::uint64_t last_start = h.start + (h.tel->bytes.size() - 1) * frame_cycles;
  const std::uint64_t idle = h.tel->bytes.size() == 1 ? s_.rx.idle_bits_at(h.start) : 0;
  s_.rx.after_chars(last_start, h.tel->bytes.back(), idle);
  drop_heard_rxd(h.driven_at);
  h.active = false;
  if (h.kind != HeardTelegram::Kind::frame) return;
  // on_char of each character: a frame after TSYN, complete or broken at the last one.
  s_.skipping = false;
  s_.frame = h.tel->frame;
  frame_ended(
      s_.frame.status(),
      UartChar{h.tel->bytes.back(), true, true, true, last_start, last_start + frame_cycles, idle},
      &h.tel->decoded);
  request_ended();
}

void Mac::materialize() {
  HeardTelegram& h = s_.heard;
  if (!h.active) return;
  h.active = false;
  // What drive_rxd_char did when the telegram was driven ...
  drop_heard_rxd(h.driven_at);
  std::array<std::pair<std::uint64_t, bool>, kUartCharBits> edges{};
  for (std::size_t i = 0; i < h.tel->bytes.size(); ++i) {
    const std::uint64_t at = h.start + i * std::uint64_t{kUartCharBits} * h.t;
    const std::size_t n = uart_char_edges(h.tel->bytes[i], at, h.t, edges.data());
    s_.rx.whole_char(at, h.tel->bytes[i], h.t);
    for (std::size_t k = 0; k < n; ++k) {
      if (edges[k].first > h.driven_at) s_.rxd_pending.emplace_back(edges[k]);
    }
  }
  // ... and what the stop samples up to now did (nothing shown before the first effect; an
  // effect shown already is not shown twice: a no_sync leaves `skipping` set).
  std::vector<UartChar> chars;
  s_.rx.advance(clock_.now, chars);
  for (const UartChar& c : chars) on_char(c);
  clock_.quiet_until = 0;
}

}  // namespace dpc31
