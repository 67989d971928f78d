#include "engine.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "vocabulary.hpp"  // state, service, function and response names

namespace dpc31::bridge {

namespace {

// Port writes and ISR entries are kept this long by FirmwareHost before the bridge drops them.
constexpr std::size_t kHistoryLimit = 4096;

bool wants_answer(std::span<const std::uint8_t> bytes) {
  const fdl::Decoded d = fdl::decode(bytes);
  if (d.error != fdl::Error::none) return false;
  const fdl::Frame& f = d.frame;
  if (f.sd == fdl::SC || f.sd == fdl::SD4 || !fdl::is_request(f.fc)) return false;
  const fdl::Function fn = fdl::request_function(f.fc);
  return f.da != fdl::kBroadcast && fn != fdl::Function::SDN_low && fn != fdl::Function::SDN_high;
}

}  // namespace

std::string telegram_summary(std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) return "empty";
  const fdl::Decoded d = fdl::decode(bytes);
  if (d.error != fdl::Error::none) {
    return fmt::format("broken telegram ({})", fdl::error_name(d.error));
  }
  const fdl::Frame& f = d.frame;
  if (f.sd == fdl::SC) return "SC (short acknowledge)";
  if (f.sd == fdl::SD4) return fmt::format("token {}->{}", f.sa, f.da);
  std::string s;
  if (fdl::is_request(f.fc)) {
    const fdl::Function fn = fdl::request_function(f.fc);
    s = fmt::format("{} {}->{}", service_name(f), f.sa, f.da);
    if (fn != fdl::Function::FDL_Status) s += fmt::format(" {}", function_name(fn));
    if (fdl::fcv(f.fc)) s += fmt::format(" FCB {}", fdl::fcb(f.fc) ? 1 : 0);
  } else {
    s = fmt::format("{} {}->{}", response_name(fdl::response_code(f.fc)), f.sa, f.da);
  }
  if (f.ssap || f.dsap) {
    s += fmt::format(" SAP {}->{}", f.ssap ? fmt::format("{}", fdl::sap_number(*f.ssap)) : "-",
                     f.dsap ? fmt::format("{}", fdl::sap_number(*f.dsap)) : "-");
  }
  if (!f.du.empty()) s += fmt::format(" DU {}", hex_bytes(f.du));
  return s;
}

Engine::Engine(const Setup& setup, LogSink log)
    : setup_(setup),
      log_(std::move(log)),
      // Every telegram is a line at the telegrams level: its bound is the busiest real line's.
      limiter_(setup.log_detail == LogDetail::telegrams ? kTelegramBurst : LogLimiter::kBurst) {
  if (!setup_.slaves.empty()) {
    if (const std::string why = stations_problem(setup_.slaves); !why.empty()) {
      throw std::invalid_argument(why);
    }
    seg_ = std::make_unique<Segment>(setup_.baud);
    master_ = seg_->add_sender(std::string(kMasterName));
    t_ = seg_->bit_cycles();
    stations_.reserve(setup_.slaves.size());
    slaves_.resize(setup_.slaves.size());
    for (std::size_t i = 0; i < setup_.slaves.size(); ++i) {
      const SlaveSpec& s = setup_.slaves[i];
      stations_.push_back({fmt::format("slave{}", s.address), s.address});
      const std::size_t index = seg_->add_chip(stations_.back().name, s.chip);
      Chip& chip = seg_->chip(index);
      add_slave(i, chip, s);
      seg_->set_firmware(index, slaves_[i].user.program);
      watch_answers(i, chip);
    }
    seg_->on_collision = [this](const Collision& c) {
      add_line(c.cycle, "NOTE", kBridgeName,
               fmt::format("collision: {} drove into the telegram of {}", seg_->name(c.second),
                           seg_->name(c.first)));
    };
    rx_ = TxdReceiver(t_, seg_->cycle());
    bus_free_ = seg_->cycle();
    return;
  }
  stations_.push_back({fmt::format("slave{}", setup_.address), setup_.address});
  solo_ = std::make_unique<Chip>(setup_.chip);
  t_ = dpc31::bit_cycles(solo_->clock_hz(), setup_.baud);
  slaves_.resize(1);
  if (setup_.cpu) {  // the 80C32 starts from reset with the chip and runs its own main()
    slaves_[0].chip = solo_.get();
    watch_slave(0);
    m51_ = std::make_unique<Cpu51Module>(*solo_, *setup_.cpu, setup_.cpu_image, setup_.address);
    m51_->on_port = [this](std::uint64_t cycle, unsigned port, std::uint32_t value) {
      port_written(0, cycle, "80C32", m51_->port_name(port), port, value);
    };
    // What the firmware sends on its UART (a debug printf): every character, at both levels (the
    // log's bound holds it, docs/bridge.md "The log").
    m51_->on_serial = [this](std::uint64_t cycle, std::uint8_t data) {
      add_line(cycle, "SBUF", stations_[0].name, Cpu51Module::serial_text(setup_.cpu->c31, data));
    };
  } else {
    add_slave(0, *solo_, SlaveSpec{setup_.address, setup_.chip, setup_.firmware});
  }
  watch_answers(0, *solo_);
  rx_ = TxdReceiver(t_, solo_->cycle());
  // TxD in batches of characters, taken when the bridge looks (collect): no event per bit.
  solo_->on_txd_chars([this](const TxdRun& r) { rx_.take(r); });
  if (!m51_) cpu_ = std::make_unique<Cpu>(*solo_, slaves_[0].user.program);
  bus_free_ = solo_->cycle();
}

// Who drove an answer, and until when (a late one too, for next_start): each chip tells of its
// own when it arms it.
void Engine::watch_answers(std::size_t i, Chip& chip) {
  chip.on_telegram([this, i](const Telegram& t) {
    if (t.from_chip) sent_.push_back({t.start, t.end, i});
  });
}

// The log's view of station `i`: its chip's messages and state changes.
void Engine::watch_slave(std::size_t i) {
  Slave& s = slaves_[i];
  s.chip->set_log_sink(
      [this, i](const LogRecord& r) { add_line(r.cycle, "CHIP", stations_[i].name, r.text); },
      LogLevel::info);
  s.dp = s.chip->dp_state();
  s.wd = s.chip->wd_state();
  s.chip->on_state_change([this, i](std::uint64_t cycle) { check_states(i, cycle); });
}

void Engine::add_slave(std::size_t i, Chip& chip, const SlaveSpec& spec) {
  Slave& s = slaves_[i];
  s.chip = &chip;
  watch_slave(i);
  s.user = make_user_side(chip, spec, seg_ != nullptr);
  if (FirmwareHost* fw = s.user.firmware.get()) {
    fw->on_port = [this, i, fw](std::uint64_t cycle, unsigned port, std::uint32_t value) {
      port_written(i, cycle, fw->firmware().name, fw->port_name(port), port, value);
    };
  }
}

// At the events level a port write is logged when it changes the port's value.
void Engine::port_written(std::size_t i, std::uint64_t cycle, const std::string& module,
                          const std::string& port, unsigned index, std::uint32_t value) {
  Slave& s = slaves_[i];
  if (index >= s.port.size()) {
    s.port.resize(index + 1, 0);
    s.port_logged.resize(index + 1, false);
  }
  if (setup_.log_detail == LogDetail::events && s.port_logged[index] && s.port[index] == value)
    return;
  s.port[index] = value;
  s.port_logged[index] = true;
  add_line(cycle, "PORT", stations_[i].name, fmt::format("{} {} = 0x{:02X}", module, port, value));
}

Engine::~Engine() {
  // The host CPUs stop before their user sides and chips go away.
  cpu_.reset();
  seg_.reset();
  if (solo_) {
    solo_->on_txd_chars({});
    solo_->on_state_change({});
    solo_->set_log_sink({});
  }
}

void Engine::add_line(std::uint64_t cycle, std::string_view tag, std::string_view who,
                      std::string text) {
  if (log_) held_.push_back({cycle, tag, who, std::move(text)});
}

void Engine::log_telegram(std::uint64_t cycle, std::string_view tag, std::string_view who,
                          std::span<const std::uint8_t> bytes, std::string_view how) {
  const bool broken = fdl::decode(bytes).error != fdl::Error::none;
  if (setup_.log_detail == LogDetail::events && !broken && how.empty()) return;
  std::string s = fmt::format("{}  | {}", hex_bytes(bytes), telegram_summary(bytes));
  if (!how.empty()) s += fmt::format(" ({})", how);
  add_line(cycle, tag, who, std::move(s));
}

std::uint64_t Engine::log_horizon() const {
  // A station behind the segment's front may still log below it.
  std::uint64_t h = rx_.busy_from();
  for (const Slave& s : slaves_) h = std::min(h, s.chip->cycle());
  if (answer_.started()) h = std::min(h, answer_.start());
  if (stray_.started()) h = std::min(h, stray_.start());
  if (in_flight_ && !answer_.started()) h = std::min(h, slot_end_);
  return h;
}

void Engine::release_log(std::uint64_t upto) {
  if (held_.empty()) return;
  std::stable_sort(held_.begin(), held_.end(),
                   [](const HeldLine& a, const HeldLine& b) { return a.cycle < b.cycle; });
  std::size_t n = 0;
  for (; n < held_.size() && held_[n].cycle <= upto; ++n) {
    const HeldLine& l = held_[n];
    const std::string key = fmt::format("{} {} {}", l.tag, l.who, l.text);
    for (const std::string& s : limiter_.add(l.cycle, key)) {
      if (s == key) {
        log_(l.cycle, l.tag, l.who, l.text);
      } else {
        log_(l.cycle, "LOG", kBridgeName, s);  // a repeat count, or how many lines were left out
      }
    }
  }
  held_.erase(held_.begin(), held_.begin() + static_cast<std::ptrdiff_t>(n));
}

void Engine::end_unanswered_run(std::string_view how) {
  if (unanswered_ == 0) return;
  add_line(cycle(), "NOTE", kBridgeName,
           fmt::format("{} request{} without an answer, then {}", unanswered_,
                       unanswered_ == 1 ? "" : "s", how));
  unanswered_ = 0;
}

void Engine::flush_log() {
  // A run of unanswered requests the events level said it counts is closed by the end too.
  end_unanswered_run("the bridge stopped");
  release_log(UINT64_MAX);
  for (const std::string& s : limiter_.flush()) log_(cycle(), "LOG", kBridgeName, s);
}

void Engine::note(const std::string& text) {
  add_line(cycle(), "NOTE", kBridgeName, text);
  release_log(log_horizon());
}

void Engine::check_states(std::size_t i, std::uint64_t cycle) {
  Slave& st = slaves_[i];
  const DpState dp = st.chip->dp_state();
  const WdState wd = st.chip->wd_state();
  if (dp == st.dp && wd == st.wd) return;
  std::string s;
  if (dp != st.dp) {
    s = fmt::format("dp_state {} -> {}", dp_state_name(st.dp), dp_state_name(dp));
  }
  if (wd != st.wd) {
    if (!s.empty()) s += ", ";
    s += fmt::format("wd_state {} -> {}", wd_state_name(st.wd), wd_state_name(wd));
  }
  add_line(cycle, "STATE", stations_[i].name, std::move(s));
  st.dp = dp;
  st.wd = wd;
}

void Engine::feed(std::span<const std::uint8_t> bytes) {
  for (const std::uint8_t b : bytes) {
    partial_.push_back(b);
    const fdl::Assembler::Status st = in_.push(b);
    if (st == fdl::Assembler::Status::need_more) continue;
    // Complete, or bytes that cannot be a telegram: they go on the bus as they came (the chip
    // counts the error) and the next byte may start a telegram again.
    std::vector<std::uint8_t> group;
    group.swap(partial_);
    in_.reset();
    queue_group(std::move(group), st == fdl::Assembler::Status::error);
  }
}

void Engine::flush_partial() {
  if (partial_.empty()) return;
  std::vector<std::uint8_t> group;
  group.swap(partial_);
  in_.reset();
  queue_group(std::move(group), true);
}

void Engine::client_gone() {
  end_unanswered_run("the client went away");
  if (!partial_.empty()) {
    note(fmt::format("dropped an incomplete telegram: {}",
                     hex_bytes(std::span(partial_).first(
                         std::min<std::size_t>(partial_.size(), kMaxGarbageRun)))));
  }
  partial_.clear();
  in_.reset();
  report_dropped();
  if (!queue_.empty()) {
    note(
        fmt::format("the client's {} queued telegrams ({} bytes) dropped: they had not reached "
                    "the bus",
                    queue_.size(), queued_bytes_));
  }
  queue_.clear();
  queued_bytes_ = 0;
}

void Engine::drop(std::size_t bytes) {
  if (dropped_ == 0) dropped_since_ = cycle();
  dropped_ += bytes;
  if (cycle() - last_drop_report_ >= chip().clock_hz()) report_dropped();
}

void Engine::report_dropped() {
  if (dropped_ == 0) return;
  // The time since the first of them, rounded up and at least 1 ms, so that the line is true
  // (rounded down, a drop reported in its own cycle was "in the last 0 ms").
  const std::uint64_t hz = chip().clock_hz();
  const std::uint64_t ms =
      std::max<std::uint64_t>(1, ((cycle() - dropped_since_) * 1000 + hz - 1) / hz);
  note(
      fmt::format("{} byte{} dropped in the last {} ms: the client writes faster than the bus "
                  "carries",
                  dropped_, dropped_ == 1 ? "" : "s", ms));
  dropped_ = 0;
  last_drop_report_ = cycle();
}

void Engine::queue_group(std::vector<std::uint8_t> bytes, bool garbage) {
  if (queued_bytes_ + bytes.size() > kMaxQueuedBytes) {
    drop(bytes.size());
    return;
  }
  queued_bytes_ += bytes.size();
  if (garbage && !queue_.empty() && queue_.back().garbage &&
      queue_.back().bytes.size() + bytes.size() <= kMaxGarbageRun) {
    queue_.back().bytes.insert(queue_.back().bytes.end(), bytes.begin(), bytes.end());
    return;
  }
  Request r;
  r.wants_answer = !garbage && wants_answer(bytes);
  r.garbage = garbage;
  r.bytes = std::move(bytes);
  queue_.push_back(std::move(r));
}

// Queued requests go on RxD after TSYN of bus idle (all edges of one at once), up to the first
// that waits for an answer, and none that would start more than TSYN from now: the rest waits
// in the queue (bounded, and dropped with its client), not as RxD edges driven minutes ahead.
// (A request behind one that wants no answer starts when the chip reaches that one's end.)
// On a segment a request starts only when the line has reached its start (Segment::send runs
// every station there first).
void Engine::start_next() {
  while (!in_flight_ && !queue_.empty()) {
    const std::uint64_t start = next_start();
    if (start > cycle() + lead()) break;
    Request r = std::move(queue_.front());
    queue_.pop_front();
    queued_bytes_ -= r.bytes.size();
    log_telegram(start, "RxD", kMasterName, r.bytes, "");
    request_end_ = put_on_line(r.bytes, start);
    if (line_) line_({start, request_end_, kMasterName, r.bytes});
    if (r.wants_answer) {
      in_flight_ = true;
      slot_end_ = request_end_ + std::uint64_t{setup_.slot_bits} * t_;
      answer_.reset();
    } else {
      bus_free_ = request_end_;  // nothing to wait for: the next request follows after TSYN
    }
  }
}

// TSYN counts from the end of whatever a chip drives, an answer nobody waits for any more (a late
// one) included: it is on the line until its end, which the chip knew when it armed it. A master
// hears the line busy before its own start and waits.
std::uint64_t Engine::next_start() {
  for (;;) {
    const std::uint64_t start = std::max(cycle(), bus_free_ + std::uint64_t{kTsynBits} * t_);
    const auto driving = std::find_if(sent_.begin(), sent_.end(), [&](const Sent& a) {
      return a.start <= start && a.end > bus_free_;
    });
    if (driving == sent_.end()) return start;
    bus_free_ = driving->end;
  }
}

std::uint64_t Engine::put_on_line(std::span<const std::uint8_t> bytes, std::uint64_t start) {
  return seg_ ? seg_->send(master_, bytes, start) : send_on_rxd(*solo_, bytes, start, t_);
}

std::string_view Engine::sender_of(std::uint64_t start) const {
  if (!seg_) return stations_.front().name;
  // The chip whose answer covers the character (every character the client hears is a chip's);
  // of two that overlap the one that began first, which the segment lets keep the line; the
  // bytes of the second after the first's end are its own. None covers it: the latest begun.
  const Sent* who = nullptr;
  for (const Sent& a : sent_) {
    if (a.start > start) continue;
    const bool covers = start < a.end;
    const bool who_covers = who != nullptr && start < who->end;
    if (who == nullptr || (covers && (!who_covers || a.start < who->start)) ||
        (!covers && !who_covers && a.start > who->start)) {
      who = &a;
    }
  }
  return stations_[who != nullptr ? who->station : 0].name;
}

void Engine::finish_answer(AnswerCollector& a, std::string_view how) {
  const std::string_view who = sender_of(a.start());
  // An answer over by this one's start covers no later character (bus_free_ is past its end).
  std::erase_if(sent_, [&](const Sent& s) { return s.end <= a.start(); });
  log_telegram(a.start(), "TxD", who, a.bytes(), how);
  if (line_) line_({a.start(), a.end(), who, a.bytes()});
  bus_free_ = std::max(bus_free_, a.end());
  a.reset();
}

void Engine::collect() {
  chars_.clear();
  if (seg_) {
    seg_->take_line(master_, [this](const TxdRun& r) { rx_.take(r); });
  } else {
    solo_->take_txd();
  }
  rx_.advance(cycle(), chars_);
  for (const UartChar& c : chars_) {
    out_.push_back(c.data);
    // Before the request's end the line carries nothing of ours: such characters are late.
    if (in_flight_ && c.start >= request_end_ && !stray_.started()) {
      answer_.push(c);
    } else {
      stray_.push(c);
    }
  }
  // The whole characters after those: all of the answer, or (one before its time, or a stray
  // one before them) all late, as the rule above takes them one by one.
  const std::span<const std::uint8_t> due = rx_.due();
  out_.insert(out_.end(), due.begin(), due.end());
  const bool answer = in_flight_ && rx_.due_start() >= request_end_ && !stray_.started();
  (answer ? answer_ : stray_).push_block(due, rx_.due_start(), t_);
  if (stray_.finished() && !rx_.receiving()) finish_answer(stray_, "late");
  if (!in_flight_) return;
  if (answer_.finished() && !rx_.receiving()) {
    // Closes every run of unanswered requests, also a run of one: the events level said at its
    // start that it counts until an answer.
    if (unanswered_ != 0) {
      add_line(answer_.start(), "NOTE", kBridgeName,
               fmt::format("answered again, after {} request{} without an answer", unanswered_,
                           unanswered_ == 1 ? "" : "s"));
    }
    unanswered_ = 0;
    finish_answer(answer_, "");
    in_flight_ = false;
  } else if (!answer_.started() && !rx_.receiving() && cycle() >= slot_end_) {
    // At the events level a run of them (a master looking for a slave during its baud search,
    // or for one that is not there) is one line at its start and one at its end.
    if (setup_.log_detail == LogDetail::telegrams) {
      add_line(slot_end_, "NOTE", kBridgeName, "no answer within the slot time");
    } else if (unanswered_ == 0) {
      add_line(slot_end_, "NOTE", kBridgeName,
               "no answer within the slot time (the next ones are counted until an answer)");
    }
    ++unanswered_;
    bus_free_ = std::max(bus_free_, slot_end_);
    in_flight_ = false;
  }
}

// Where to look at the line next: as DpMaster does, bit by bit while an answer is awaited until
// a character starts, then at the receiver's samples; the end of a request that waits for none.
std::uint64_t Engine::next_wake(std::uint64_t limit) const {
  const std::uint64_t now = cycle();
  std::uint64_t next = limit;
  if (rx_.receiving()) {
    next = std::min(next, rx_.next_deadline());
  } else if (in_flight_ || stray_.started()) {
    next =
        std::min(next, in_flight_ && !answer_.started() ? std::min(slot_end_, now + t_) : now + t_);
  }
  if (!in_flight_ && now < request_end_) next = std::min(next, request_end_);
  // A queued request starts once its start is lead() ahead (start_next()).
  if (!in_flight_ && !queue_.empty()) {
    next = std::min(next, bus_free_ + std::uint64_t{kTsynBits} * t_ - lead());
  }
  return std::clamp(next, now + 1, std::max(limit, now + 1));
}

void Engine::step_to(std::uint64_t to) {
  if (m51_) {
    m51_->run_until(to);
    solo_->clear_stop();
    if (m51_->port_writes().size() > kHistoryLimit || m51_->interrupts.size() > kHistoryLimit) {
      m51_->clear_history();
    }
  } else {
    if (seg_) {
      seg_->run_until(to);
    } else {
      cpu_->run_until(to);
    }
    for (Slave& s : slaves_) {
      FirmwareHost* fw = s.user.firmware.get();
      if (fw &&
          (fw->port_writes().size() > kHistoryLimit || fw->interrupts.size() > kHistoryLimit)) {
        fw->clear_history();
      }
    }
  }
  collect();
}

void Engine::run_until(std::uint64_t to) {
  while (cycle() < to) {
    start_next();
    step_to(next_wake(to));
  }
  start_next();
  if (dropped_ != 0 && cycle() - last_drop_report_ >= chip().clock_hz()) report_dropped();
  release_log(log_horizon());
}

bool Engine::settle(std::uint64_t max_cycles) {
  const std::uint64_t limit = cycle() + max_cycles;
  start_next();
  while (busy() && cycle() < limit) {
    step_to(next_wake(limit));
    start_next();
  }
  release_log(log_horizon());
  return !busy();
}

bool Engine::busy() const { return in_flight_ || !queue_.empty() || cycle() < request_end_; }

std::vector<std::uint8_t> Engine::take_output() {
  std::vector<std::uint8_t> out;
  out.swap(out_);
  return out;
}

}  // namespace dpc31::bridge
