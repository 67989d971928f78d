// The chip's snapshot (docs/snapshots.md, format version 7): every block's state, written and
// read in one place so that the format is one list. Each list is a template run with a Writer
// (save) or a Reader (load), so save and load cannot drift apart; a static_assert on each
// block's State makes a new member fail the build until it is listed here.
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>
#include <type_traits>

#include "block_access.hpp"
#include "core.hpp"
#include "snapshot.hpp"

namespace dpc31 {

namespace {

using A = BlockAccess;

template <typename Ar, typename S>
void irq_fields(Ar& ar, S& s) {
  static_assert(snap::member_count<InterruptController::State>() == 5, "a new member: add it here");
  static_assert(snap::member_count<Timer>() == 2, "a new member: add it here and in TIMR");
  ar(s.eoi.at);
  ar(s.eoi.left);
  ar(s.event_cycle);
  ar(s.event_mask);
}

template <typename Ar, typename S>
void ring_fields(Ar& ar, S& s) {
  static_assert(snap::member_count<BufferRing>() == 4, "a new member: add it here");
  ar.bounded(s.d, std::uint8_t{3});
  ar.bounded(s.n, std::uint8_t{3});
  ar.bounded(s.u, std::uint8_t{3});
  ar.bounded(s.f, std::uint8_t{3});
}

template <typename Ar, typename S>
void buffer_fields(Ar& ar, S& s) {
  static_assert(snap::member_count<BufferUnit::State>() == 10, "a new member: add it here");
  static_assert(snap::member_count<DiagPair>() == 2, "a new member: add it here");
  ring_fields(ar, s.dout);
  ring_fields(ar, s.din);
  ar.bounded(s.diag.buf[0], DiagState::Asic_Send_Mode);
  ar.bounded(s.diag.buf[1], DiagState::Asic_Send_Mode);
  ar(s.n_cleared);
  ar(s.u_cleared);
  ar(s.diag_flag);
  ar(s.n_cl);
  ar(s.d_fresh);
  ar(s.c_swap_pending);
  ar(s.in_clear);
}

// D and U always hold a buffer, exactly one of N and F is Nil, no buffer is held twice: the
// pointer cells are indexed by these numbers.
bool valid_ring(const BufferRing& b) {
  const bool n_nil = b.n == 0;
  const bool f_nil = b.f == 0;
  const std::uint8_t third = n_nil ? b.f : b.n;
  return b.d != 0 && b.u != 0 && n_nil != f_nil && b.d != b.u && third != b.d && third != b.u;
}

// The two diag buffers as BufferUnit moves them: never Nil, never both in one state (one with the
// user and one with the ASIC, or one waiting while the other is sent).
bool valid_diag(const DiagPair& d) {
  const DiagState x = d.buf[0], y = d.buf[1];
  return x != DiagState::Nil && y != DiagState::Nil && x != y;
}

template <typename Ar, typename S>
void handshake_fields(Ar& ar, S& s) {
  static_assert(snap::member_count<Handshake>() == 2, "a new member: add it here");
  ar(s.pending);
  ar(s.newer_arrived);
}

template <typename Ar, typename S>
void dp_fields(Ar& ar, S& s) {
  static_assert(snap::member_count<DpStateMachine::State>() == 30, "a new member: add it here");
  ar.bounded(s.state, DpState::Data_Exchange);
  handshake_fields(ar, s.prm);
  handshake_fields(ar, s.cfg);
  ar(s.ssa_free);
  ar(s.prm_fault);
  ar(s.cfg_fault);
  ar(s.not_supported);
  ar(s.station);
  ar(s.no_add_change);
  ar(s.master_add);
  ar(s.group_ident);
  ar(s.min_tsdr);
  ar(s.prm_wd_on);
  ar(s.prm_wd_fact1);
  ar(s.prm_wd_fact2);
  ar(s.prm_wd_1ms);
  ar(s.failsafe);
  ar(s.dx_deferred);
  ar(s.diag_requester);
  ar(s.sync_mode);
  ar(s.freeze_mode);
  ar(s.user_wd_armed);
  ar(s.user_wd);
  ar(s.fcb_valid);
  ar(s.last_fcb);
  ar(s.last_master);
  ar.byte_vector(s.last_response, fdl::kMaxFrameLength);
  ar(s.ext_prm);  // version 4
}

// Edges queued on a line are in time order; those before `next` are taken (at or before `now`),
// the rest are still to come. Out of order, a line would run back in time (Chip::drive_rxd's
// contract: non-decreasing cycles).
template <typename Edges>
bool edge_queue_valid(const Edges& edges, std::size_t next, std::uint64_t now) {
  std::uint64_t last = 0;
  std::size_t i = 0;
  for (const auto& e : edges) {
    if (e.first < last || (i < next) != (e.first <= now)) return false;
    last = e.first;
    ++i;
  }
  return true;
}

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

// `chars` is scratch (cleared before every use), not state; rxd_pending and rxd_level are in
// the CORE section (format version 2).
template <typename Ar, typename S>
void mac_fields(Ar& ar, S& s, std::uint64_t now) {
  // `heard` is not written: Chip::save_state turns it into characters first (Mac::materialize).
  // `tx_chars` is written as the edges it stands for (below): the format does not change.
  static_assert(snap::member_count<Mac::State>() == 21, "a new member: add it here");
  ar.block(s.rx);
  ar.block(s.frame);
  ar(s.in_frame);
  ar(s.skipping);
  // The byte of the retired `discarding` (a character after TSYN opens a telegram whatever the one
  // before was, docs/timing.md "Telegrams"): written 0, read and ignored, the format unchanged.
  bool discarding = false;
  ar(discarding);
  ar(s.frame_timeout);
  ar.bounded(s.search_code, static_cast<std::uint8_t>(std::size(kBaudRates) - 1));
  ar(s.search_deadline);
  const auto edge = [](auto& a, auto& e) {
    a(e.first);
    a(e.second);
  };
  if constexpr (requires { ar.fail(""); }) {
    ar.sequence(s.tx_edges, kMaxTxEdges, edge);  // a loaded answer is edges (Mac::tx_to_edges)
    ar.size(s.tx_next, s.tx_edges.size());
    if (!edge_queue_valid(s.tx_edges, s.tx_next, now))
      ar.fail("TxD edges out of time order, or taken and to come on the wrong side of now");
    ar(s.tx_end);
    ar(s.txd);
  } else if (s.tx_chars.active()) {
    // The answer kept as characters, written as its edges with those up to now taken.
    std::vector<std::pair<std::uint64_t, bool>> edges;
    s.tx_chars.encode(edges);
    const auto next = static_cast<std::size_t>(
        std::partition_point(edges.begin(), edges.end(),
                             [&](const auto& e) { return e.first <= now; }) -
        edges.begin());
    ar.sequence(edges, kMaxTxEdges, edge);
    ar.size(next, edges.size());
    ar(s.tx_end);
    ar(s.tx_chars.level(now));
  } else {
    // The TxD edges up to now as taken: a snapshot does not depend on when the MAC takes them
    // (at its next event, or when a master looks: Chip::on_txd_edges).
    ar.sequence(s.tx_edges, kMaxTxEdges, edge);
    const auto [next, txd] = s.txd_at(now);
    ar.size(next, s.tx_edges.size());
    ar(s.tx_end);
    ar(txd);
  }
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
  ar.bounded(s.offline_pending, Mac::State::OfflinePending::answer);  // version 5
}

template <typename Ar, typename S>
void counter_fields(Ar& ar, S& s) {
  static_assert(snap::member_count<FdlCounters>() == kFdlCounterFields.size(),
                "a new member: add it to kFdlCounterFields");
  for (const CounterField& f : kFdlCounterFields) ar(s.*(f.member));
}

// A FoldedLog: the occurrences counted, then the addresses logged one line each (the first one
// with the first occurrence: none exactly when nothing was counted).
template <typename Ar, typename L>
void folded_log_fields(Ar& ar, L& l) {
  static_assert(snap::member_count<FoldedLog>() == 2, "a new member: add it here");
  ar(l.count);
  ar.sequence(l.logged, FoldedLog::kAddressLines, [](auto& a, auto& x) { a(x); });
  if constexpr (requires { ar.fail(""); }) {
    if (l.logged.empty() != (l.count == 0) || l.logged.size() > l.count)
      ar.fail(fmt::format("a folded log of {} occurrences with {} addresses logged", l.count,
                          l.logged.size()));
  }
}

// Everything that influences future behaviour. Not here: the configuration (profile, bus,
// clock rate: the header), the tables derived from the profile (decode maps, hooks), the log sink
// and the observers, quiet_until (a cache, 0 = recompute) and stop (a request of whoever steps the
// chip).
template <typename Ar, typename C>
void core_fields(Ar& ar, C& c) {
  auto& regs = A::state(c.regs);
  auto& irq = A::state(c.irq);
  auto& dp = A::state(c.dp);
  auto& wd = A::state(c.watchdog);
  auto& mode = A::state(c.mode);
  auto& mac = A::state(c.mac);
  static_assert(snap::member_count<RegisterFile::State>() == 4, "a new member: add it here");
  static_assert(snap::member_count<Watchdog::State>() == 5, "a new member: add it here");
  static_assert(snap::member_count<ModeRegisters::State>() == 1, "a new member: add it here");
  ar.section("CORE");
  ar.bounded(c.clock.now, Chip::kLastCycle);  // past it a step would wrap (Chip::cycle_after)
  ar(dp.started);
  ar(regs.ram_access_violation);
  ar(regs.large_ram);
  ar.bounded(wd.baud_code, static_cast<std::uint8_t>(std::size(kBaudRates) - 1));
  ar(c.written_bits);
  ar(dp.diag_in_flight);
  ar(irq.line);
  ar(irq.pb3);
  // Each engine keeps its timers its own way: a snapshot loads into a chip of the same engine.
  Engine engine = c.clock.engine;
  ar.bounded(engine, Engine::per_cycle);
  if constexpr (requires { ar.fail(""); }) {
    if (engine != c.clock.engine)
      ar.fail("the snapshot is of the other engine (event / per_cycle)");
  }
  const auto edge = [](auto& a, auto& e) {
    a(e.first);
    a(e.second);
  };
  if constexpr (requires { ar.fail(""); }) {
    ar.sequence(mac.rxd_pending, snap::kMaxFileSize, edge);
    if (!edge_queue_valid(mac.rxd_pending, 0, c.clock.now))
      ar.fail("RxD edges driven ahead out of time order, or at or before the snapshot's cycle");
    mac.heard.active = false;
  } else {
    // The edges still to come: those up to now are heard already, whenever the queue drops them.
    Fifo<std::pair<std::uint64_t, bool>> ahead;
    for (const auto& e : mac.rxd_pending) {
      if (e.first > c.clock.now) ahead.emplace_back(e);
    }
    ar.sequence(ahead, snap::kMaxFileSize, edge);
  }
  ar(mac.rxd_level);
  ar.section("LTCH");
  ar.array(regs.latch);
  if constexpr (requires { ar.fail(""); }) {
    // A latch holds no more bits than its register has: an 8-bit MinTSDR_Val of 0xFFFF would
    // delay every answer by 65 535 bit times. A RegId the profile lacks has no flip-flops.
    for (std::size_t i = 0; i < regs.latch.size(); ++i) {
      const RegDesc* r = c.regs.reg(static_cast<RegId>(i));
      if (r == nullptr && regs.latch[i] != 0)
        ar.fail(
            fmt::format("latch {} is {:04X}h on a chip without that register", i, regs.latch[i]));
      if (r != nullptr && (regs.latch[i] & ~r->mask()) != 0)
        ar.fail(fmt::format("latch {} is {:04X}h: more than its {} bits", r->name, regs.latch[i],
                            r->width));
    }
  }
  ar.section("MEM ");
  ar.fixed_bytes(regs.mem);
  ar.section("IRQC");
  irq_fields(ar, irq);
  if constexpr (requires { ar.fail(""); }) {
    // X/INT as last shown is what IR and the EOI time make it: a chip tells on_irq_change only
    // where the two differ, so a stale one would hide the next activation, or report a change
    // that never was.
    if (irq.line != c.irq.active())
      ar.fail(fmt::format("X/INT shown {} where IRR, IMR and the EOI time make it {}",
                          irq.line ? "active" : "inactive",
                          c.irq.active() ? "active" : "inactive"));
    // PB3 is the DPC31's, high from a DX_Out until the user acknowledges it.
    if (irq.pb3 && (c.prof().id != Profile::dpc31 ||
                    (regs.latch[static_cast<std::size_t>(RegId::Int_Req_Reg)] & irq::DX_Out) == 0))
      ar.fail("PB3 high without a DX_Out pending on a DPC31");
  }
  ar.section("BUFS");
  buffer_fields(ar, A::state(c.buffers));
  if constexpr (requires { ar.fail(""); }) {
    const auto& b = A::state(c.buffers);
    if (!valid_ring(b.dout) || !valid_ring(b.din)) ar.fail("Dout or Din ring is not buffers 1..3");
    if (!valid_diag(b.diag)) ar.fail("the diag buffers are both in one state, or one is Nil");
  }
  ar.section("DPSM");
  dp_fields(ar, dp);
  if constexpr (requires { ar.fail(""); }) {
    // An FCB repetition sends these bytes again as they are (DpStateMachine::service): only a
    // telegram the chip could have sent.
    if (!dp.last_response.empty() && fdl::decode(dp.last_response).error != fdl::Error::none)
      ar.fail("the answer kept for a repetition is not a valid telegram");
  }
  // The order of format version 2: both timers' deadlines first, their per-cycle counts last.
  ar.section("TIMR");
  ar(mode.user.at);
  ar.bounded(wd.wd, WdState::DP_Control);
  ar(wd.timer.at);
  ar(wd.dp_wd_on);
  ar(wd.dp_wd_cycles);
  ar(mode.user.left);
  ar(wd.timer.left);
  ar.section("MAC ");
  mac_fields(ar, mac, c.clock.now);
  if constexpr (requires { ar.fail(""); }) {
    mac.chars.clear();
    // Only a telegram in progress has a timeout; a stale one would be due for ever.
    if (!mac.in_frame && mac.frame_timeout != kNever) ar.fail("frame timeout outside a telegram");
    // An Offline waits for a request in progress of a started chip: its telegram, or its answer.
    using Pending = Mac::State::OfflinePending;
    const bool answering = mac.tx_end != kNever || mac.shifter.phase != TxShifter::Phase::idle;
    if ((mac.offline_pending != Pending::none && !dp.started) ||
        (mac.offline_pending == Pending::request && !mac.in_frame) ||
        (mac.offline_pending == Pending::answer && !answering))
      ar.fail("an Offline pending without the request it waits for");
    // The receivers listen at the rate of the search code (Mac::listen): a bit time of 0 would
    // divide by zero, another one hear a rate the chip does not know.
    const std::uint32_t t = bit_cycles(c.clock.hz, kBaudRates[mac.search_code]);
    if (mac.rx.bit_time() != t || mac.sampler.bit_time() != t)
      ar.fail(fmt::format("a receiver's bit time is not {} clocks, the one of its baud rate", t));
  }
  ar.section("CNTR");
  counter_fields(ar, c.counters);
  // Format version 3: the DPC31's request interface (its DPS_User_Watchdog).
  auto& rq = A::state(c.requests);
  static_assert(snap::member_count<RequestInterface::State>() == 3, "a new member: add it here");
  ar.section("RQIF");
  ar(rq.wd.at);
  ar(rq.wd.left);
  ar(rq.wd_left);
  ar(rq.wd_locked);
  if constexpr (requires { ar.fail(""); }) {
    // Only the DPC31 has the interface: elsewhere it stays as reset left it (its timer would
    // reach for the DPC31's cells).
    const RequestInterface::State rq_reset{};  // RequestInterface::reset
    if (c.prof().id != Profile::dpc31 &&
        (rq.wd.at != rq_reset.wd.at || rq.wd.left != rq_reset.wd.left ||
         rq.wd_left != rq_reset.wd_left || rq.wd_locked != rq_reset.wd_locked))
      ar.fail("the request interface is not idle on a chip without one (DPC31 only)");
  }
  // Format version 4: the VPC3+'s SAP list (DPV1, docs/dpv1.md).
  auto& sl = A::state(c.sap_list);
  static_assert(snap::member_count<SapList::State>() == 4, "a new member: add it here");
  ar.section("SAPL");
  ar(sl.enabled);
  ar(sl.sending);
  ar(sl.entry);
  ar(sl.response);
  if constexpr (requires { ar.fail(""); }) {
    const std::uint32_t end = 1u << c.prof().address_bits;
    if (sl.entry >= end || sl.response >= end) ar.fail("SAP list address beyond the address bus");
    const SapList::State sl_reset{};  // SapList::reset
    if (c.prof().id != Profile::vpc3plus &&
        (sl.enabled != sl_reset.enabled || sl.sending != sl_reset.sending ||
         sl.entry != sl_reset.entry || sl.response != sl_reset.response))
      ar.fail("the SAP list is not off on a chip without one (VPC3+ only)");
  }
  // Format version 6: what the log has said already, so that a restored chip does not say it
  // again where the original run would not.
  ar.section("LOGS");
  for (auto& [cell, logged] : A::over_long(c.dp)) {
    ar(logged);
    if constexpr (requires { ar.fail(""); }) {
      if (logged != 0 && logged <= fdl::kMaxDpData)
        ar.fail(fmt::format("{} logged as over-long at {}, within the {} bytes of a DP data unit",
                            kRegIdNames[static_cast<std::size_t>(cell)], logged, fdl::kMaxDpData));
    }
  }
  // Format version 7: the SPC3's wait for New_Din_Buffer_Cmd, as the log has seen it.
  auto& din_wait = A::din_wait(c.dp);
  static_assert(snap::member_count<std::remove_cvref_t<decltype(din_wait)>>() == 2,
                "a new member: add it here");
  ar(din_wait.since);
  ar(din_wait.said);
  if constexpr (requires { ar.fail(""); }) {
    if (c.dp.waits_for_din() && din_wait.since > c.clock.now)
      ar.fail(
          fmt::format("the wait for New_Din_Buffer_Cmd begins at cycle {}, after the snapshot's {}",
                      din_wait.since, c.clock.now));
  }
  folded_log_fields(ar, c.unmapped);
  folded_log_fields(ar, c.beyond_bus);
  folded_log_fields(ar, A::over_registers(c.regs));
}

snap::Header header_of(const ChipCore& c) {
  return {c.prof().id, c.regs.bus(), c.clock.hz, snap::register_map_fingerprint()};
}

}  // namespace

std::vector<std::uint8_t> Chip::save_state() const {
  core_->mac.materialize();  // a telegram heard whole is written as its characters
  snap::Writer w;
  core_fields(w, *core_);
  return snap::seal(header_of(*core_), w.bytes());
}

void Chip::load_state(std::span<const std::uint8_t> bytes) {
  ChipCore& c = *core_;
  // The blocks below the observer are in the middle of an event or access on the old core.
  if (c.signals.calling_out()) {
    throw std::logic_error(
        "load_state from inside the chip's observer or log sink: the chip is in the middle of an "
        "event or access (load it after the call that runs the chip has returned)");
  }
  const std::span<const std::uint8_t> payload = snap::open(bytes, header_of(c));
  // Decode into a fresh core (its tables built from the same profile); *core_ is untouched until
  // everything has been read and checked.
  auto fresh = std::make_unique<ChipCore>(ChipOptions{c.prof().id, c.regs.bus(), c.clock.hz,
                                                      c.clock.engine, c.variant, c.irq.served()});
  fresh->signals.sink = nullptr;
  snap::Reader r(payload);
  core_fields(r, *fresh);
  r.finish();
  // A CPU board's time goes on from its instant (docs/cpu.md, "The board"): a chip at another
  // cycle would take the CPU's accesses at cycles the firmware never saw.
  if (board_instant_ != nullptr && fresh->clock.now != *board_instant_) {
    throw SnapshotError(
        fmt::format("snapshot of cycle {} under a CPU board at cycle {}: the CPU's state is not "
                    "the chip's: it would run on against another chip",
                    fresh->clock.now, *board_instant_));
  }
  // The old state's TxD edges up to its cycle reach the batch observers, as at take_txd(): the
  // snapshot has them as taken.
  c.mac.tx_catch_up();
  // Commit: nothing below throws. The log sink, the observers and the wake-up and stop request
  // belong to whoever attached or asked for them, not to the state.
  fresh->signals.take_attachments(c.signals);
  fresh->mac.keep_wake(c.mac);
  fresh->stop = c.stop;
  const bool line = c.irq.line(), pb3 = c.irq.pb3();
  core_ = std::move(fresh);
  now_ = &core_->clock.now;
  // The loaded X/INT and PB3 from the loaded cycle on: their observers see the edges there.
  core_->irq.tell_since(line, pb3);
  moved();
}

void Chip::save_state_file(const std::string& path) const {
  snap::write_file_atomic(path, save_state());
}

void Chip::load_state_file(const std::string& path) {
  const std::vector<std::uint8_t> bytes = snap::read_file(path);
  try {
    load_state(bytes);
  } catch (const SnapshotError& e) {
    throw SnapshotError(path + ": " + e.what());
  }
}

}  // namespace dpc31
