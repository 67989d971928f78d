// The FDL MAC of the chip. Rules (docs/timing.md, "Serial line"): a telegram starts with a
// start delimiter after at least TSYN = 33 idle bit times; the line idle for TSYN inside a
// telegram ends it as truncated; a bad character aborts the telegram and the receiver waits for
// TSYN again; a request is acted on at the stop-bit sample of its last character; the answer's
// first start bit goes out MinTSDR bit times after the end of that character's stop bit.
#include <algorithm>

#include "core.hpp"

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

void ChipCore::mac_start_search() {
  mac_listen(0);  // from the highest rate down
  mac.in_frame = false;
  mac.skipping = false;
  mac.frame.reset();
  mac.frame_timeout = kNever;
  arm_search_window();
}

void ChipCore::mac_listen(std::uint8_t code) {
  mac.search_code = code;
  const std::uint32_t t = bit_cycles(clock_hz, kBaudRates[code]);
  mac.rx.configure(t, now);
  mac.sampler.configure(t);
  // Edges driven for later cycles are still to come on the line: the receiver hears them at the
  // new rate (the per-cycle engine reads them off the line clock by clock anyway).
  if (engine == Engine::event) {
    for (const auto& [cycle, level] : rxd_pending) {
      if (cycle > now) mac.rx.edge(cycle, level);
    }
    note_deadline(mac.rx.next_deadline());
  }
}

void ChipCore::mac_search_next() {
  // The windows are fixed (4096 bit times each), whatever is on the line: a character or
  // telegram in progress is dropped with the old rate.
  mac_listen(static_cast<std::uint8_t>((mac.search_code + 1) % std::size(kBaudRates)));
  mac.in_frame = false;
  mac.frame.reset();
  mac.frame_timeout = kNever;
  mac.skipping = false;
  arm_search_window();
}

void ChipCore::mac_truncated() {
  ++counters.truncated;
  log(LogLevel::info, "telegram truncated: the line went idle for TSYN after {} bytes",
      mac.frame.bytes().size());
  mac.in_frame = false;
  mac.frame.reset();
  mac.frame_timeout = kNever;
}

void ChipCore::mac_txd(std::uint64_t cycle, bool level) {
  if (level == mac.txd) return;
  mac.txd = level;
  if (txd_observer) txd_observer(cycle, level);
}

void ChipCore::mac_tx_done() {
  mac.tx_end = kNever;
  mac.tx_edges.clear();
  mac.tx_next = 0;
  mac.shifter = TxShifter{};
  dp_response_sent();
}

bool ChipCore::mac_tx_busy() const {
  return engine == Engine::event ? mac.tx_end != kNever
                                 : mac.shifter.phase != TxShifter::Phase::idle;
}

void ChipCore::mac_stop() {
  stop_search_window();
  mac.frame_timeout = kNever;
  mac.gap.on = false;
  mac.in_frame = false;
  mac.frame.reset();
  mac.tx_edges.clear();
  mac.tx_next = 0;
  mac.tx_end = kNever;
  mac.shifter = TxShifter{};
  diag_in_flight = false;
  mac_txd(now, true);
}

std::uint64_t ChipCore::mac_deadline() const {
  std::uint64_t t =
      std::min({mac.rx.next_deadline(), mac.frame_timeout, mac.search_deadline, mac.tx_end});
  // Single TxD bits are events only for someone watching them; otherwise the answer's edges are
  // taken as the line is looked at (txd_pin) or at the end of the answer.
  if (txd_observer && mac.tx_next < mac.tx_edges.size()) {
    t = std::min(t, mac.tx_edges[mac.tx_next].first);
  }
  return t;
}

void ChipCore::watch_txd(std::function<void(std::uint64_t, bool)> cb) {
  // Edges before now happened unwatched; from now on each one is an event again.
  mac_tx_catch_up();
  txd_observer.add(std::move(cb));
  note_deadline(mac_deadline());
}

void ChipCore::mac_tx_catch_up() {
  while (mac.tx_next < mac.tx_edges.size() && mac.tx_edges[mac.tx_next].first <= now) {
    mac_txd(mac.tx_edges[mac.tx_next].first, mac.tx_edges[mac.tx_next].second);
    ++mac.tx_next;
  }
}

bool ChipCore::txd_level() const {
  bool level = mac.txd;
  for (std::size_t i = mac.tx_next; i < mac.tx_edges.size() && mac.tx_edges[i].first <= now; ++i) {
    level = mac.tx_edges[i].second;
  }
  return level;
}

void ChipCore::mac_process() {
  mac.chars.clear();
  mac.rx.advance(now, mac.chars);
  for (const UartChar& c : mac.chars) mac_char(c);
  if (mac.in_frame && mac.frame_timeout <= now) {
    // A character that started before the gap reached TSYN continues the telegram: its stop
    // sample decides.
    if (mac.rx.busy_from() < mac.frame_timeout) {
      mac.frame_timeout = kNever;
    } else {
      mac_truncated();
    }
  }
  if (mac.search_deadline <= now) mac_search_next();
  mac_tx_catch_up();
  if (mac.tx_end <= now) mac_tx_done();
}

// Per-cycle engine: the MAC's clock (docs/engine.md, step 4): the receiver looks at RxD, the
// TSYN gap, the Baud_Search window and the transmitter count bit times.
void ChipCore::mac_clock() {
  const std::uint32_t t = mac.rx.bit_time();
  UartChar ch;
  const UartSampler::Clock r = mac.sampler.clock(rxd_level, now, ch);
  if (r.ready) mac_char(ch);
  // Idle inside a telegram counts from the end of a stop bit; a start bit ends the gap, but one
  // on the very clock TSYN is reached comes too late (the gap is 33 bit times).
  if (mac.gap.tick(t) && mac.in_frame) mac_truncated();
  if (r.ended && mac.in_frame) mac.gap.start(kTsynBits);
  if (r.started) mac.gap.on = false;
  if (mac.search.tick(t)) mac_search_next();
  TxShifter& tx = mac.shifter;
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
        mac_txd(now, uart_bit(tx.bytes[0], 0));
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
        mac_txd(now, uart_bit(tx.bytes[tx.index], tx.bit));
      } else {
        mac_txd(now, true);
        mac_tx_done();
      }
      break;
  }
}

void ChipCore::mac_char(const UartChar& c) {
  const bool start_ok = c.start_ok || mode0(fields::Mode_Reg0::Dis_Start_Control);
  const bool stop_ok = c.stop_ok || mode0(fields::Mode_Reg0::Dis_Stop_Control);
  if (!c.parity_ok || !start_ok || !stop_ok) {
    // One count per broken telegram: characters misframed after the first error are its tail.
    // Of one character's errors the first sampled counts: start bit, parity, stop bit.
    const bool fresh = !mac.discarding && (mac.in_frame || c.idle_bits >= kTsynBits);
    if (fresh) {
      if (!start_ok) {
        ++counters.start_bit;
      } else if (!c.parity_ok) {
        ++counters.parity;
      } else {
        ++counters.stop_bit;
      }
    }
    mac.discarding = true;
    mac.in_frame = false;
    mac.frame.reset();
    mac.frame_timeout = kNever;
    mac.skipping = true;
    return;
  }
  const std::uint64_t tsyn = std::uint64_t{kTsynBits};
  if (mac.in_frame && c.idle_bits >= tsyn) {
    ++counters.truncated;  // a new telegram began before the old one was complete
    mac.in_frame = false;
    mac.frame.reset();
  }
  if (!mac.in_frame) {
    if (c.idle_bits < tsyn) {
      if (!mac.skipping) ++counters.no_sync;
      mac.skipping = true;
      return;
    }
    mac.skipping = false;
    mac.discarding = false;
    mac.in_frame = true;
    mac.frame.reset();
  }
  const fdl::Assembler::Status st = mac.frame.push(c.data);
  mac.frame_timeout = c.end + tsyn * mac.rx.bit_time();
  if (st == fdl::Assembler::Status::need_more) return;
  mac.in_frame = false;
  mac.frame_timeout = kNever;
  if (st == fdl::Assembler::Status::error) {
    // The rest of the broken telegram is its tail, not an unsynchronised one: wait for TSYN.
    mac.discarding = true;
    mac.skipping = true;
    // An LE beyond the longest telegram is an oversize frame, not a malformed one.
    const auto bytes = mac.frame.bytes();
    const bool too_long =
        mac.frame.error() == fdl::Error::bad_le && bytes.size() >= 2 && bytes[1] > fdl::kMaxLe;
    count(counters, too_long ? fdl::Error::oversize : mac.frame.error());
    return;
  }
  const fdl::Decoded d = fdl::decode(mac.frame.bytes());
  if (d.error != fdl::Error::none) {
    count(counters, d.error);
    return;
  }
  const std::uint64_t frame_chars = mac.frame.bytes().size();
  if (telegram_observer) {
    const std::uint64_t t = std::uint64_t{kUartCharBits} * mac.rx.bit_time();
    telegram_observer(Telegram{false,
                               {mac.frame.bytes().begin(), mac.frame.bytes().end()},
                               c.end - frame_chars * t,
                               c.end});
  }
  mac_frame(d.frame, c);
}

void ChipCore::mac_frame(const fdl::Frame& f, const UartChar& last) {
  if (!started) {
    ++counters.offline;
    return;
  }
  const bool carries_data = f.sd == fdl::SD1 || f.sd == fdl::SD2 || f.sd == fdl::SD3;
  if (timers.wd == WdState::Baud_Search && carries_data) {
    stop_search_window();
    baud_found(mac.search_code);
  }
  if (!carries_data || !fdl::is_request(f.fc)) return;  // tokens, acknowledges, answers
  if (f.da != dp.station && f.da != fdl::kBroadcast) {
    ++counters.foreign_address;
    return;
  }
  if (f.da == dp.station) watchdog_retrigger(f.sa);
  const std::optional<fdl::Frame> answer = dp_service(f);
  if (answer) mac_send(*answer, last.end);
}

void ChipCore::mac_send(const fdl::Frame& f, std::uint64_t request_end) {
  if (mac_tx_busy()) return;  // half duplex: still sending the previous answer
  std::vector<std::uint8_t> bytes = fdl::encode(f);
  const std::uint32_t t = mac.rx.bit_time();
  const std::uint32_t tsdr = std::max<std::uint32_t>(
      kMinTsdrBits, dp.min_tsdr != 0 ? dp.min_tsdr : latch[idx(RegId::MinTSDR_Val)]);
  const std::uint64_t start = request_end + std::uint64_t{tsdr} * t;
  const std::uint64_t end = start + bytes.size() * std::uint64_t{kUartCharBits} * t;
  if (telegram_observer) telegram_observer(Telegram{true, bytes, start, end});
  if (engine == Engine::per_cycle) {
    // Counted from the end of the request's stop bit, as the receiver sees it.
    mac.shifter.phase = TxShifter::Phase::wait_end;
    mac.shifter.bytes = std::move(bytes);
    mac.shifter.tsdr_bits = tsdr;
    return;
  }
  mac.tx_edges.clear();
  mac.tx_next = 0;
  uart_encode(bytes, start, t, mac.tx_edges);
  mac.tx_end = end;
}

// ---- snapshot ----

namespace {

// The longest answer on the wire: every character toggling at every bit, plus the final rise.
constexpr std::size_t kMaxTxEdges = fdl::kMaxFrameLength * kUartCharBits + 1;

template <typename Ar, typename T>
void bit_timer(Ar& ar, T& b) {
  static_assert(snap::member_count<BitTimer>() == 4, "a new member: add it here");
  ar(b.on);
  ar(b.sub);
  ar(b.bits);
  ar(b.target);
}

// `chars` is scratch (cleared before every use), not state.
template <typename Ar, typename S>
void members(Ar& ar, S& s) {
  static_assert(snap::member_count<Mac>() == 17, "a new member: add it here");
  ar.block(s.rx);
  ar.block(s.frame);
  ar(s.in_frame);
  ar(s.skipping);
  ar(s.discarding);
  ar(s.frame_timeout);
  ar.bounded(s.search_code, static_cast<std::uint8_t>(std::size(kBaudRates) - 1));
  ar(s.search_deadline);
  ar.sequence(s.tx_edges, kMaxTxEdges, [](auto& a, auto& e) {
    a(e.first);
    a(e.second);
  });
  ar.size(s.tx_next, s.tx_edges.size());
  ar(s.tx_end);
  ar(s.txd);
  ar.block(s.sampler);
  bit_timer(ar, s.gap);
  bit_timer(ar, s.search);
  bit_timer(ar, s.shifter.timer);
  ar.bounded(s.shifter.phase, TxShifter::Phase::shifting);
  ar.byte_vector(s.shifter.bytes, fdl::kMaxFrameLength);
  ar(s.shifter.tsdr_bits);
  ar.size(s.shifter.index, s.shifter.bytes.size());
  ar.bounded(s.shifter.bit, kUartCharBits - 1);
  ar(s.shifter.sub);
}

template <typename Ar, typename S>
void counter_fields(Ar& ar, S& s) {
  static_assert(snap::member_count<FdlCounters>() == 20, "a new member: add it here");
  ar(s.parity);
  ar(s.start_bit);
  ar(s.stop_bit);
  ar(s.bad_sd);
  ar(s.le_mismatch);
  ar(s.bad_le);
  ar(s.bad_fcs);
  ar(s.wrong_ed);
  ar(s.truncated);
  ar(s.oversize);
  ar(s.bad_sap);
  ar(s.no_sync);
  ar(s.foreign_address);
  ar(s.unknown_sap);
  ar(s.unsupported_function);
  ar(s.not_allowed);
  ar(s.no_resource);
  ar(s.offline);
  ar(s.repeated);
  ar(s.requests);
}

}  // namespace

void save_state(snap::Writer& w, const Mac& s) {
  w.section("MAC ");
  members(w, s);
}

void load_state(snap::Reader& r, Mac& s) {
  r.section("MAC ");
  members(r, s);
  s.chars.clear();
  // Only a telegram in progress has a timeout; a stale one would be due for ever.
  if (!s.in_frame && s.frame_timeout != kNever) r.fail("frame timeout outside a telegram");
}

void save_state(snap::Writer& w, const FdlCounters& s) {
  w.section("CNTR");
  counter_fields(w, s);
}

void load_state(snap::Reader& r, FdlCounters& s) {
  r.section("CNTR");
  counter_fields(r, s);
}

}  // namespace dpc31
