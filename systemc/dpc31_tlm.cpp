// The SystemC TLM-2.0 model of the chip (docs/systemc.md).
//
// Time: the chip's cycle c is at time_of(c) on the SystemC time line. The chip never runs ahead of
// what the rest of the platform could still change but the rxd port (an access takes the chip to
// its end at once; an rxd change meanwhile lands at the chip's cycle) and a reset or load_state
// by another process (it undoes what an initiator running ahead did: warned, went_back): its own
// thread steps it only up to the current time, from event to event (Chip::next_deadline); a bus
// access may take it ahead of the current time (an initiator running ahead with a quantum keeper)
// only while no event of the chip falls before the access ends and no other process waits for a
// cycle before the access starts; otherwise the initiator is synchronised first. The pins' changes
// are applied at their times.
#include "dpc31_tlm.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "board.hpp"

namespace dpc31::systemc {

KeepSelection::KeepSelection()
    : hal_(hal::exchange_selection({})), hooks_(board::exchange(nullptr)) {}

KeepSelection::~KeepSelection() {
  board::exchange(hooks_);
  hal::exchange_selection(hal_);
}

namespace {

enum Pin { kXInt, kIrq, kPb3, kTxd };
constexpr std::uint64_t kNone = std::numeric_limits<std::uint64_t>::max();
__extension__ using u128 = unsigned __int128;

}  // namespace

Dpc31Tlm::Dpc31Tlm(const sc_core::sc_module_name& name, const ChipOptions& options)
    : sc_core::sc_module(name),
      bus("bus"),
      x_int("x_int"),
      irq("irq"),
      pb3("pb3"),
      txd("txd"),
      rxd("rxd"),
      chip_(options),
      ticks_per_second_(static_cast<std::uint64_t>(
          std::llround(1.0 / sc_core::sc_get_time_resolution().to_seconds()))),
      x_int_level_(chip_.x_int_pin()) {
  // Coarser, two cycles share a time: accesses are no longer back to back, events move.
  if (ticks_per_second_ < chip_.clock_hz()) {
    throw std::invalid_argument(
        "Dpc31Tlm: the time resolution " + sc_core::sc_get_time_resolution().to_string() +
        " is coarser than one clock of the chip at " + std::to_string(chip_.clock_hz()) +
        " Hz: set sc_set_time_resolution to one clock or finer");
  }
  bus.register_b_transport(this, &Dpc31Tlm::b_transport);
  bus.register_transport_dbg(this, &Dpc31Tlm::transport_dbg);
  bus.register_get_direct_mem_ptr(this, &Dpc31Tlm::get_direct_mem_ptr);
  x_int.initialize(x_int_level_);
  irq.initialize(chip_.irq_active());
  pb3.initialize(chip_.pb3_pin());
  txd.initialize(chip_.txd_pin());
  chip_.on_irq_change([this](std::uint64_t cycle, bool active) {
    follow_x_int(cycle);
    schedule(cycle, kIrq, active);
  });
  // After every bus access, step, reset and load_state: a Mode_Reg0.INT_Pol written or reset
  // flips X/INT without a change of the interrupt (no on_irq_change); a reset or a load may take
  // the chip back.
  chip_.on_cycle([this](std::uint64_t cycle) {
    if (cycle < seen_) went_back(cycle);
    seen_ = cycle;
    follow_x_int(cycle);
  });
  chip_.on_pb3_change([this](std::uint64_t cycle, bool high) { schedule(cycle, kPb3, high); });
  chip_.on_txd([this](std::uint64_t cycle, bool level) { schedule(cycle, kTxd, level); });
  SC_THREAD(run);
  SC_THREAD(watch_rxd);
  SC_METHOD(apply_edges);
  sensitive << edge_due_;
  dont_initialize();
}

sc_core::sc_time Dpc31Tlm::time_of(std::uint64_t cycle) const {
  if (cycle > last_cycle()) {
    throw std::out_of_range("Dpc31Tlm::time_of: cycle " + std::to_string(cycle) +
                            " is beyond SystemC's time line (its last cycle is " +
                            std::to_string(last_cycle()) + ")");
  }
  const u128 f = chip_.clock_hz();
  return sc_core::sc_time::from_value(
      static_cast<std::uint64_t>((u128{cycle} * ticks_per_second_ + f - 1) / f));
}

std::uint64_t Dpc31Tlm::cycle_at(const sc_core::sc_time& t) const {
  return static_cast<std::uint64_t>(u128{t.value()} * chip_.clock_hz() / ticks_per_second_);
}

std::uint64_t Dpc31Tlm::last_cycle() const {
  return std::min(Chip::kLastCycle, cycle_at(sc_core::sc_max_time()));
}

void Dpc31Tlm::schedule(std::uint64_t cycle, int pin, bool level) {
  const sc_core::sc_time at = time_of(cycle);
  edges_.push_back({at, pin, level});
  const sc_core::sc_time now = sc_core::sc_time_stamp();
  edge_due_.notify(at > now ? at - now : sc_core::SC_ZERO_TIME);
}

void Dpc31Tlm::went_back(std::uint64_t cycle) {
  const sc_core::sc_time now = sc_core::sc_time_stamp();
  if (seen_ > cycle_at(now)) {
    SC_REPORT_WARNING(
        "/dpc31/Dpc31Tlm/reset",
        ("a reset or load_state at " + now.to_string() + " took back the chip's cycles up to " +
         std::to_string(seen_) + " (" + time_of(seen_).to_string() +
         "), which an initiator running ahead had reached: its accesses there are undone, their "
         "pin changes not shown; synchronise the initiators before a reset")
            .c_str());
  }
  // The pin changes after now are of the time line the chip left: the pins show the chip's.
  std::erase_if(edges_, [&](const Edge& e) { return e.at > now; });
  const auto last = [&](int pin, bool shown) {
    for (auto e = edges_.rbegin(); e != edges_.rend(); ++e) {
      if (e->pin == pin) return e->level;
    }
    return shown;
  };
  x_int_level_ = last(kXInt, x_int.read());
  if (last(kIrq, irq.read()) != chip_.irq_active()) schedule(cycle, kIrq, chip_.irq_active());
  if (last(kPb3, pb3.read()) != chip_.pb3_pin()) schedule(cycle, kPb3, chip_.pb3_pin());
  if (last(kTxd, txd.read()) != chip_.txd_pin()) schedule(cycle, kTxd, chip_.txd_pin());
}

void Dpc31Tlm::follow_x_int(std::uint64_t cycle) {
  if (chip_.x_int_pin() == x_int_level_) return;
  x_int_level_ = !x_int_level_;
  schedule(cycle, kXInt, x_int_level_);
}

void Dpc31Tlm::apply_edges() {
  const sc_core::sc_time now = sc_core::sc_time_stamp();
  bool irq_level = irq.read();
  const bool irq_was = irq_level;
  while (!edges_.empty() && edges_.front().at <= now) {
    const Edge e = edges_.front();
    edges_.pop_front();
    switch (e.pin) {
      case kXInt:
        x_int.write(e.level);
        break;
      case kIrq:
        irq.write(e.level);
        irq_level = e.level;
        break;
      case kPb3:
        pb3.write(e.level);
        break;
      default:
        txd.write(e.level);
        break;
    }
  }
  // A rise of the signal (the last write of a time wins), at the next delta: its waiters wake
  // after the update, and the signal reads true.
  if (irq_level && !irq_was) irq_rise_.notify(sc_core::SC_ZERO_TIME);
  if (!edges_.empty()) edge_due_.notify(edges_.front().at - now);
}

void Dpc31Tlm::step_to(std::uint64_t cycle) {
  if (chip_.cycle() < cycle) chip_.step(cycle - chip_.cycle());
  if (chip_.stop_requested()) stopped_.notify();
}

void Dpc31Tlm::run() {
  for (;;) {
    step_to(cycle_at(sc_core::sc_time_stamp()));
    const std::uint64_t next = chip_.next_deadline();
    if (next == kNone || std::max(next, chip_.cycle() + 1) > last_cycle()) {
      wait(changed_);
      continue;
    }
    // An event at or before the chip's cycle is behind it already (an access took it there).
    const sc_core::sc_time at = time_of(std::max(next, chip_.cycle() + 1));
    wait(at - sc_core::sc_time_stamp(), changed_);
  }
}

void Dpc31Tlm::watch_rxd() {
  if (rxd.size() == 0) return;
  // A signal declared without a value starts low: the chip's line follows it (a falling edge that
  // never comes would be lost without a word), and the user is told once.
  if (!rxd->read()) {
    chip_.drive_rxd(chip_.cycle(), false);
    SC_REPORT_WARNING("/dpc31/Dpc31Tlm/rxd",
                      "rxd is low at time 0: the chip's RxD is held low until it rises (a PROFIBUS "
                      "line idles high: initialise the signal to true)");
  }
  for (;;) {
    wait(rxd->value_changed_event());
    const sc_core::sc_time now = sc_core::sc_time_stamp();
    std::uint64_t at = cycle_at(now);
    if (time_of(at) < now) ++at;
    chip_.drive_rxd(std::max(at, chip_.cycle()), rxd->read());
    changed_.notify(sc_core::SC_ZERO_TIME);
  }
}

void Dpc31Tlm::run_until(std::uint64_t cycle) {
  cycle = std::min(cycle, last_cycle());  // where the time line ends, so does a wait
  horizon_ = cycle;
  scheduler_moved_.notify();
  changed_.notify(sc_core::SC_ZERO_TIME);  // the caller may have driven RxD
  for (;;) {
    step_to(std::min(cycle, cycle_at(sc_core::sc_time_stamp())));
    if (chip_.cycle() >= cycle || chip_.stop_requested()) break;
    wait(time_of(cycle) - sc_core::sc_time_stamp(), stopped_);
  }
  // The caller acts now, before an access that waited for it (it runs until its next wait).
  horizon_ = kNone;
  scheduler_moved_.notify();
}

void Dpc31Tlm::b_transport(tlm::tlm_generic_payload& tr, sc_core::sc_time& delay) {
  const std::uint64_t addr = tr.get_address();
  const unsigned len = tr.get_data_length();
  const unsigned width = tr.get_streaming_width() == 0 ? len : tr.get_streaming_width();
  const std::uint64_t span = std::min(len, width);
  tr.set_dmi_allowed(false);
  if (!tr.is_read() && !tr.is_write()) {
    tr.set_response_status(tlm::TLM_COMMAND_ERROR_RESPONSE);
    return;
  }
  // Compared without adding to `addr`: near 2^64 the sum would wrap round to a small address.
  if (const std::uint64_t limit = std::uint64_t{1} << chip_.profile().address_bits;
      addr >= limit || span > limit - addr) {
    tr.set_response_status(tlm::TLM_ADDRESS_ERROR_RESPONSE);
    return;
  }
  const unsigned char* be = tr.get_byte_enable_ptr();
  const unsigned be_len = tr.get_byte_enable_length();
  const auto enabled = [&](unsigned i) {
    return be == nullptr || be_len == 0 || be[i % be_len] == TLM_BYTE_ENABLED;
  };
  unsigned n = 0;
  for (unsigned i = 0; i < len; ++i) n += enabled(i) ? 1 : 0;

  // The access starts at the first clock at or after the initiator's local time.
  const sc_core::sc_time local = sc_core::sc_time_stamp() + delay;
  std::uint64_t start = cycle_at(local);
  if (time_of(start) < local) ++start;
  start = std::max(start, chip_.cycle());
  const std::uint64_t end = start + std::uint64_t{n} * chip_.bus_access_cycles();
  if (end > chip_.next_deadline() || start >= horizon_ || chip_.stop_requested()) {
    // Something else happens first: an event of the chip (a telegram, a timer, the end of the
    // EOI time: X/INT may change), or a process waiting for a cycle up to the access. Run the
    // platform up to the initiator's time, and let a waiting process act first.
    ++syncs_;
    {
      const KeepSelection keep;  // the other initiators run their firmware meanwhile
      wait(delay);
      delay = sc_core::SC_ZERO_TIME;
      step_to(cycle_at(sc_core::sc_time_stamp()));
      // A stop lets the process in run_until act first; with none there, nobody would clear it.
      while (chip_.cycle() >= horizon_ || (chip_.stop_requested() && horizon_ != kNone))
        wait(scheduler_moved_);
    }
    step_to(start);
  } else {
    step_to(start);
  }
  unsigned char* data = tr.get_data_ptr();
  for (unsigned i = 0; i < len; ++i) {
    if (!enabled(i)) continue;
    const auto a = static_cast<std::uint32_t>(addr + i % width);
    if (tr.is_read()) {
      data[i] = chip_.read(a);
    } else {
      chip_.write(a, data[i]);  // X/INT followed at its completion (on_cycle)
    }
    ++accesses_;
  }
  delay = time_of(chip_.cycle()) - sc_core::sc_time_stamp();
  changed_.notify(sc_core::SC_ZERO_TIME);
  tr.set_response_status(tlm::TLM_OK_RESPONSE);
}

unsigned int Dpc31Tlm::transport_dbg(tlm::tlm_generic_payload& tr) {
  // TLM_IGNORE_COMMAND is neither a read nor a write: nothing is transferred.
  if (!tr.is_read() && !tr.is_write()) {
    tr.set_response_status(tlm::TLM_COMMAND_ERROR_RESPONSE);
    return 0;
  }
  const std::uint64_t addr = tr.get_address();
  const unsigned len = tr.get_data_length();
  unsigned char* data = tr.get_data_ptr();
  const std::uint64_t limit = std::uint64_t{1} << chip_.profile().address_bits;
  unsigned done = 0;
  for (; done < len && addr + done < limit; ++done) {
    const auto a = static_cast<std::uint32_t>(addr + done);
    if (tr.is_read()) {
      data[done] = chip_.peek(a);
    } else if (!chip_.poke_problem(a, data[done]).empty() || !chip_.poke(a, data[done])) {
      break;  // no storage behind the read side, or Mode_Reg1's run state: the bytes before it
              // are written
    } else {
      follow_x_int(chip_.cycle());  // a poked INT_Pol moves the pin too
    }
  }
  tr.set_response_status(tlm::TLM_OK_RESPONSE);
  return done;
}

bool Dpc31Tlm::get_direct_mem_ptr(tlm::tlm_generic_payload& tr, tlm::tlm_dmi& dmi) {
  // No direct access anywhere: registers act on access, RAM cells may be hooked (InstQ_Wr), and
  // every access takes bus time. The whole address range is refused at once.
  dmi.set_start_address(0);
  dmi.set_end_address((std::uint64_t{1} << chip_.profile().address_bits) - 1);
  dmi.set_granted_access(tlm::tlm_dmi::DMI_ACCESS_NONE);
  tr.set_dmi_allowed(false);
  return false;
}

}  // namespace dpc31::systemc
