#include "dp_master.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <stdexcept>

#include "dpc31/dp.hpp"
#include "dpc31/pdu.hpp"
#include "segment.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

namespace {
// A slave answers no earlier than 11 bit times after its request's end (EN 50170: TSDR >= 11).
constexpr std::uint32_t kShortestTsdrBits = 11;
}  // namespace

std::uint64_t send_on_rxd(Chip& chip, std::span<const std::uint8_t> bytes, std::uint64_t start,
                          std::uint32_t bit_cycles, UartFault fault) {
  if (fault.kind != UartFault::Kind::none)
    return chip.drive_rxd_chars(bytes, start, bit_cycles, fault);
  return chip.hear_telegram(bytes, start, bit_cycles);
}

bool wants_answer(const fdl::Frame& f) {
  const fdl::Function fn = fdl::request_function(f.fc);
  return f.da != fdl::kBroadcast &&
         (fn == fdl::Function::SRD_low || fn == fdl::Function::SRD_high ||
          fn == fdl::Function::FDL_Status);
}

void AnswerCollector::reset() {
  frame_.reset();
  bytes_.clear();
  started_ = false;
  bad_ = false;
  start_ = 0;
  end_ = 0;
}

void AnswerCollector::push(const UartChar& c) {
  if (!started_) start_ = c.start;
  started_ = true;
  end_ = c.end;
  if (bytes_.size() <= fdl::kMaxFrameLength) bytes_.push_back(c.data);
  if (!c.ok()) bad_ = true;
  if (bad_ || frame_.push(c.data) == fdl::Assembler::Status::error) bad_ = true;
}

void AnswerCollector::push_block(std::span<const std::uint8_t> bytes, std::uint64_t start,
                                 std::uint32_t bit_cycles) {
  if (bytes.empty()) return;
  if (!started_) start_ = start;
  started_ = true;
  end_ = start + bytes.size() * kUartCharBits * std::uint64_t{bit_cycles};
  const std::size_t room =
      fdl::kMaxFrameLength + 1 - std::min(bytes_.size(), fdl::kMaxFrameLength + 1);
  bytes_.insert(bytes_.end(), bytes.begin(),
                bytes.begin() + static_cast<std::ptrdiff_t>(std::min(room, bytes.size())));
  if (bad_) return;
  // A byte after the verdict is pushed as push() would: oversize after complete.
  const std::size_t n = frame_.push_block(bytes);
  if (n < bytes.size()) frame_.push(bytes[n]);
  bad_ = frame_.status() == fdl::Assembler::Status::error;
}

bool AnswerCollector::decodes(fdl::Decoded& d) const {
  if (bad_ || frame_.status() != fdl::Assembler::Status::complete) return false;
  fdl::decode(frame_.bytes(), d);
  return d.error == fdl::Error::none;
}

std::optional<fdl::Frame> AnswerCollector::frame() const {
  fdl::Decoded d;
  if (!decodes(d)) return std::nullopt;
  return std::move(d.frame);
}

void AnswerCollector::frame(std::optional<fdl::Frame>& out) {
  if (!decodes(decoded_)) {
    out.reset();
  } else if (out) {
    // The frame of the last call goes back to decoded_: its DU's buffer serves the next decode.
    std::swap(*out, decoded_.frame);
  } else {
    out = std::move(decoded_.frame);
  }
}

DpMaster::DpMaster(Chip& chip, MasterConfig m, SlaveConfig s)
    : chip_(&chip),
      cfg_(m),
      slave_(std::move(s)),
      t_(dpc31::bit_cycles(chip.clock_hz(), m.baud)),
      target_(slave_.address),
      rx_(t_, chip.cycle()),
      bus_free_(chip.cycle()) {
  // TxD in batches of characters, taken when the master looks (take_txd): no event per bit, and
  // no edges where nobody else watches them.
  txd_observer_ = chip_->on_txd_chars([this](const TxdRun& r) { rx_.take(r); });
  slaves_.push_back({slave_, target_, fcb_, fcv_started_});
}

DpMaster::~DpMaster() {
  if (chip_) chip_->remove_txd_chars(txd_observer_);
}

DpMaster::DpMaster(Segment& seg, std::size_t station, MasterConfig m,
                   std::vector<SlaveConfig> slaves)
    : seg_(&seg),
      station_(station),
      cfg_(m),
      slave_(checked_slaves(slaves, m.address)),
      t_(seg.bit_cycles()),
      target_(slave_.address),
      rx_(t_, seg.cycle()),
      bus_free_(seg.cycle()) {
  if (dpc31::bit_cycles(seg.clock_hz(), m.baud) != t_) {
    throw std::invalid_argument("DpMaster: the master's baud rate is not the segment's");
  }
  for (SlaveConfig& s : slaves) {
    const std::uint8_t a = s.address;
    slaves_.push_back({std::move(s), a, true, false});
  }
  // The line as this station hears it: what the others drive.
  scheduler = [this](std::uint64_t cycle) {
    seg_->run_until(cycle, wake_on_txd_ ? std::optional<std::size_t>(station_) : std::nullopt);
  };
}

const SlaveConfig& DpMaster::checked_slaves(const std::vector<SlaveConfig>& slaves,
                                            std::uint8_t master) {
  if (slaves.empty()) throw std::invalid_argument("DpMaster: a master needs at least one slave");
  for (auto it = slaves.begin(); it != slaves.end(); ++it) {
    if (it->address == master)
      throw std::invalid_argument("DpMaster: " + master_at_station(master));
    if (std::any_of(slaves.begin(), it,
                    [&it](const SlaveConfig& s) { return s.address == it->address; })) {
      throw std::invalid_argument(
          fmt::format("DpMaster: slave {} is listed twice (a slave has one FCB)", it->address));
    }
  }
  return slaves.front();
}

std::uint64_t DpMaster::now() const { return seg_ ? seg_->cycle() : chip_->cycle(); }

std::uint64_t DpMaster::put_on_line(std::span<const std::uint8_t> bytes, std::uint64_t start,
                                    UartFault fault) {
  return seg_ ? seg_->send(station_, bytes, start, fault)
              : send_on_rxd(*chip_, bytes, start, t_, fault);
}

void DpMaster::select(std::size_t i) {
  SlaveState& s = slaves_.at(i);
  // The selected slave's state lives in slave_ & co. (its entry is read only here): moved in and
  // out, not copied (a DP cycle selects every slave).
  if (i == current_) return;
  slaves_[current_] = {std::move(slave_), target_, fcb_, fcv_started_};
  slave_ = std::move(s.config);
  target_ = s.target;
  fcb_ = s.fcb;
  fcv_started_ = s.fcv_started;
  current_ = i;
}

bool DpMaster::startup_all(int tries) {
  bool all = true;
  for (std::size_t i = 0; i < slaves_.size(); ++i) {
    select(i);
    all = startup(tries) && all;
  }
  select(0);
  return all;
}

void DpMaster::check_outputs(const std::vector<std::vector<std::uint8_t>>& outputs) const {
  if (outputs.size() > slaves_.size()) {
    throw std::invalid_argument(fmt::format("{} outputs for {} slave{}: at most one per slave",
                                            outputs.size(), slaves_.size(),
                                            slaves_.size() == 1 ? "" : "s"));
  }
}

std::vector<Exchange> DpMaster::dp_cycle(const std::vector<std::vector<std::uint8_t>>& outputs) {
  std::vector<Exchange> out;
  dp_cycle(outputs, out);
  return out;
}

void DpMaster::dp_cycle(const std::vector<std::vector<std::uint8_t>>& outputs,
                        std::vector<Exchange>& out) {
  std::size_t i = 0;
  try {
    check_outputs(outputs);
    out.resize(slaves_.size());
    for (; i < slaves_.size(); ++i) {
      select(i);
      data_exchange(outputs_of(outputs, i), {}, out[i]);
    }
  } catch (...) {
    out.resize(i);  // the exchanges made before the one that threw, none of an earlier cycle
    throw;
  }
  select(0);
}

std::span<const std::uint8_t> DpMaster::outputs_of(
    const std::vector<std::vector<std::uint8_t>>& outputs, std::size_t i) const {
  // A span, not `i < size ? outputs[i] : std::vector(out_len)`: that would copy outputs[i].
  static constexpr std::array<std::uint8_t, 256> kZeros{};
  if (i < outputs.size()) return outputs[i];
  return std::span(kZeros).first(slave_.out_len);
}

void DpMaster::begin_startup(int tries) {
  Startup s;
  s.tries = tries;
  startups_.assign(slaves_.size(), s);
}

bool DpMaster::starting_up() const {
  return std::any_of(startups_.begin(), startups_.end(), [](const Startup& s) {
    return s.phase != Startup::Phase::ready && s.phase != Startup::Phase::failed;
  });
}

bool DpMaster::started_up() const {
  return !startups_.empty() &&
         std::all_of(startups_.begin(), startups_.end(),
                     [](const Startup& s) { return s.phase == Startup::Phase::ready; });
}

Exchange DpMaster::pass_token(std::uint8_t next) {
  const Exchange ex = transact(fdl::token(next, cfg_.address));
  passed_held_ = holding_ && next != cfg_.address;
  holding_ = next == cfg_.address;
  if (holding_) {  // the only master: it receives its own token at the end of the SD4
    trr_ = token_at_ != 0 ? ex.request_end - token_at_ : 0;
    token_at_ = ex.request_end;
  }
  return ex;
}

void DpMaster::keep_token() {
  // Its arrival and TRR stay those of the token it held, as the bus check keeps them.
  if (passed_held_) holding_ = true;
  passed_held_ = false;
}

TokenVisit DpMaster::use_token(std::uint8_t next,
                               const std::vector<std::vector<std::uint8_t>>& outputs) {
  check_outputs(outputs);
  // A token to this master already on the line is taken (as wait_token takes it); without one
  // the master claims the token: no rotation before it; held from TSYN before its first request.
  if (!holding_ && !wait_token(0)) {
    token_at_ = send_time(now(), cfg_.idle_bits) - std::uint64_t{cfg_.idle_bits} * t_;
    trr_ = 0;
    holding_ = true;
  }
  TokenVisit v;
  v.arrived = token_at_;
  v.rotation = trr_;
  const std::uint64_t ttr = cfg_.ttr_bits * t_;
  v.hold = trr_ < ttr ? ttr - trr_ : 0;
  // A message cycle starts with its request's first start bit: after the idle time.
  const auto time_left = [&] {
    return cfg_.ttr_bits == 0 || send_time(now(), cfg_.idle_bits) < v.arrived + v.hold;
  };
  const std::size_t keep = current_;
  const bool startup = starting_up();
  if (startup) {
    // The start-up's requests are the visit's high-priority cycles, in startup_all's order;
    // a slave waiting out its Prm check ends the visit. The GAP update waits for its end.
    for (std::size_t i = 0; i < slaves_.size() && (v.startup.empty() || time_left());) {
      select(i);
      Startup& st = startups_[i];
      if (startup_request(st)) {
        v.startup.push_back(i);
      } else if (st.phase == Startup::Phase::ready || st.phase == Startup::Phase::failed) {
        ++i;
      } else {
        break;  // it waits out its Prm check
      }
    }
  } else {
    for (std::size_t n = 0; n < slaves_.size() && (v.polled.empty() || time_left()); ++n) {
      const std::size_t i = next_slave_;
      select(i);
      Exchange ex;
      data_exchange(outputs_of(outputs, i), {}, ex);
      v.polled.push_back(i);
      next_slave_ = (next_slave_ + 1) % slaves_.size();
    }
  }
  select(keep);
  if (cfg_.gap_factor != 0 && !startup) {
    ++visits_since_gap_;
    if (visits_since_gap_ >= cfg_.gap_factor && time_left()) {
      const auto after = [&](std::uint8_t a) {
        return static_cast<std::uint8_t>(a >= cfg_.hsa ? 0 : a + 1);
      };
      std::uint8_t a = gap_next_.value_or(after(cfg_.address));
      if (a == next || a == cfg_.address) a = after(cfg_.address);  // the GAP begins again
      if (a != next && a != cfg_.address) {  // an empty GAP (next = own address + 1) has none
        v.gap = a;
        v.gap_answered =
            transact(fdl::make_frame(a, cfg_.address,
                                     fdl::make_request_fc(fdl::Function::FDL_Status, false, false)))
                .answer.has_value();
        gap_next_ = after(a);
        visits_since_gap_ = 0;
      }
    }
  }
  pass_token(next);
  return v;
}

bool DpMaster::wait_token(std::uint64_t timeout) {
  const std::uint64_t until = Chip::cycle_after(now(), timeout);
  AnswerCollector heard;
  for (;;) {
    look();
    rx_.due_chars(chars_);  // a token's few characters one by one
    for (const UartChar& c : chars_) {
      if (heard.finished()) heard.reset();
      heard.push(c);
      const std::optional<fdl::Frame> f = heard.frame();
      if (f && f->sd == fdl::SD4 && f->da == cfg_.address) {
        bus_free_ = heard.end();
        if (token_at_ != 0) trr_ = heard.end() - token_at_;
        token_at_ = heard.end();
        holding_ = true;
        return true;
      }
    }
    if (now() >= until) return false;
    wake_on_txd_ = true;
    run_until(std::min(until, std::max(now() + 1, rx_.receiving() ? rx_.next_deadline() : until)));
    wake_on_txd_ = false;
  }
}

std::uint64_t DpMaster::look() {
  if (seg_) {
    seg_->take_line(station_, [this](const TxdRun& r) { rx_.take(r); });
  } else {
    chip_->take_txd();
  }
  chars_.clear();
  const std::uint64_t at = now();
  rx_.advance(at, chars_);
  // Every station counts its idle time from the last character on the line, whoever sent it
  // (a single chip's late answer too); a telegram still arriving is not waited for here, but by
  // next_start after a wait without an answer (docs/timing.md, "The master's wait").
  if (!rx_.receiving()) {
    if (!rx_.due().empty()) {
      line_end_ = rx_.due_start() + rx_.due().size() * std::uint64_t{kUartCharBits} * t_;
    } else if (!chars_.empty()) {
      line_end_ = chars_.back().end;
    }
  }
  return at;
}

std::string_view late_answer_text(bool after_slot) {
  return after_slot ? "a late answer on the line (after the slot time): no answer"
                    : "a late answer inside a request or its shortest TSDR: no answer";
}

void DpMaster::late_answer(std::uint64_t end, bool after_slot) {
  ++counters_.late;
  if (on_late) on_late(end, after_slot);
}

// To `cycle`, or less when the chip's TxD wakes the master up (wake_on_txd_).
void DpMaster::run_until(std::uint64_t cycle) {
  cycle = std::min(cycle, Chip::kLastCycle);  // the chips' time ends there: so does a wait
  // A falling edge may be a start bit: look at the line again (the wait is event-driven).
  if (seg_) {
    scheduler(cycle);
    end_wait();
    return;
  }
  if (wake_on_txd_) chip_->wake_on_txd(true);
  if (scheduler) {
    scheduler(cycle);
  } else if (cpu_) {
    cpu_->run_until(cycle);
  } else {
    while (chip_->cycle() < cycle && !chip_->stop_requested()) {
      chip_->step_until_irq(cycle - chip_->cycle());
    }
  }
  if (wake_on_txd_) chip_->wake_on_txd(false);
  chip_->clear_stop();
  end_wait();
}

// A `waited` that throws ends the caller's wait there: no wake on TxD may outlive it (a later
// idle() would stop at every TxD edge).
void DpMaster::end_wait() {
  if (!waited) return;
  wake_on_txd_ = false;
  waited();
}

void DpMaster::idle(std::uint64_t cycles) { run_until(Chip::cycle_after(now(), cycles)); }

Exchange DpMaster::retry(Exchange ex, std::uint32_t retries) {
  for (std::uint32_t i = 0; i < retries && !ex.answer && wants_answer(ex.request); ++i) {
    ex = transact(std::move(ex.request));
  }
  return ex;
}

std::uint64_t DpMaster::send_time(std::uint64_t at, std::uint32_t idle_bits) const {
  return std::max(at, std::max(bus_free_, line_end_) + std::uint64_t{idle_bits} * t_);
}

std::uint64_t DpMaster::next_start(std::uint32_t idle_bits) {
  std::uint64_t start = send_time(look(), idle_bits);
  // On one chip only the chip answers, and only the master: nothing to watch but its late answer.
  if (!watch_late_ && !seg_) return start;
  // A master drives no busy line (RS-485 half duplex, EN 50170 TSYN): a telegram on it when the
  // master decides, or one whose first start bit comes before the master's (another station's
  // answer to a scripted station's request, a sender's telegram), moves the start to the idle
  // time after that telegram's end, so no station after it misses TSYN. After a wait without an
  // answer (watch_late_) it is the asked station's late answer, no answer to any request; else
  // it is another station's, and no late answer of ours.
  const bool asked = watch_late_;
  watch_late_ = false;
  bool heard = late_heard_;
  late_heard_ = false;
  for (;;) {
    heard = heard || rx_.receiving() || !chars_.empty() || !rx_.due().empty();
    if (rx_.receiving()) {
      run_until(std::max(rx_.next_deadline(), now() + 1));
    } else {
      start = send_time(now(), idle_bits);
      if (now() >= start || wait_to_send(start)) break;
    }
    look();
  }
  if (heard && asked) late_answer(line_end_, true);
  return start;
}

bool DpMaster::wait_to_send(std::uint64_t start) {
  wake_on_txd_ = true;  // a start bit wakes the master up
  if (seg_) {
    seg_->run_to_send(start, station_);
    end_wait();
  } else {
    run_until(start);
  }
  wake_on_txd_ = false;
  return seg_ && now() >= start && seg_->heard_nothing(station_);
}

void DpMaster::line_noise(std::span<const std::uint8_t> bytes, std::uint32_t idle_bits) {
  const std::uint64_t start = next_start(idle_bits);
  if (on_send) on_send(start, bytes, {});
  bus_free_ = put_on_line(bytes, start, {});
  ++counters_.noise;
  run_until(bus_free_);
}

void DpMaster::glitch(std::uint32_t low_cycles) {
  // Its rising edge at its falling edge's cycle is no pulse (the chip counted a start bit error).
  if (low_cycles == 0)
    throw std::invalid_argument("glitch: low_cycles 0: a pulse lasts 1 clock or more");
  const std::uint64_t start = next_start(cfg_.idle_bits);
  if (seg_) {
    seg_->pulse(station_, start, low_cycles);
  } else {
    chip_->drive_rxd(start, false);
    chip_->drive_rxd(start + low_cycles, true);
  }
  // Free once the line has risen and the character the receiver samples from it has ended: a
  // request before the rise would go out on a line held low.
  bus_free_ = start + std::max<std::uint64_t>(low_cycles, std::uint64_t{kUartCharBits} * t_);
  ++counters_.noise;
  run_until(bus_free_);
}

fdl::Frame DpMaster::request(std::optional<std::uint8_t> dsap, std::vector<std::uint8_t> du,
                             bool srd) {
  fdl::Frame f;
  f.du = std::move(du);
  make_request(f, dsap, srd);
  return f;
}

void DpMaster::make_request(fdl::Frame& f, std::optional<std::uint8_t> dsap, bool srd) {
  // Before the FCB toggles: a request refused leaves the master as it was.
  if (f.du.size() > fdl::kMaxDpData) {
    throw std::invalid_argument(
        fmt::format("a request with {} data bytes: a DP telegram carries at most {}", f.du.size(),
                    fdl::kMaxDpData));
  }
  std::uint8_t fc = fdl::make_request_fc(fdl::Function::SDN_high, false, false);
  if (srd) {
    fcb_ = !fcb_;
    fc = fdl::make_request_fc(fdl::Function::SRD_high, fcb_, fcv_started_);
  }
  const std::optional<std::uint8_t> ssap =
      dsap ? std::optional<std::uint8_t>(sap::Master) : std::nullopt;
  // The data unit's buffer moves through make_frame and back: its capacity stays f's.
  f = fdl::make_frame(target_, cfg_.address, fc, std::move(f.du), dsap, ssap);
}

namespace {

// SDN and the token (SD4) want no answer.
bool sdn(const fdl::Frame& f) {
  const fdl::Function fn = fdl::request_function(f.fc);
  return f.sd == fdl::SD4 || fn == fdl::Function::SDN_high || fn == fdl::Function::SDN_low;
}

}  // namespace

Exchange DpMaster::transact(fdl::Frame req, UartFault fault) {
  Exchange ex;
  ex.request = std::move(req);
  transact(fault, ex);
  return ex;
}

void DpMaster::transact(UartFault fault, Exchange& ex) {
  const fdl::Frame& req = ex.request;
  // decode(encode(req)) == req whenever encode gives bytes: the request needs no decoding.
  if (!fdl::encode(req, tx_)) throw std::invalid_argument(fdl::encode_refusal(req));
  send(tx_, fault, sdn(req), ex, &req);
}

Exchange DpMaster::transact_raw(const std::vector<std::uint8_t>& bytes, UartFault fault) {
  const fdl::Decoded d = fdl::decode(bytes);
  Exchange ex;
  const bool decodes = d.error == fdl::Error::none;
  send(bytes, fault, decodes && sdn(d.frame), ex, decodes ? &d.frame : nullptr);
  return ex;
}

void DpMaster::send(std::span<const std::uint8_t> bytes, UartFault fault, bool no_answer,
                    Exchange& ex, const fdl::Frame* req) {
  place_fault(fault, bytes.size());
  // What the line carried before (another master's traffic, for instance) is no answer to us.
  ex.request_start = next_start(cfg_.idle_bits);
  if (on_send) on_send(ex.request_start, bytes, fault);
  ex.request_end = put_on_line(bytes, ex.request_start, fault);
  // On a segment the wait for an answer runs the line itself: a stop at the request's end would
  // only cost a round (docs/segment.md, "Masters on it"). One chip's scheduler is asked for it.
  if (no_answer || !seg_) run_until(ex.request_end);
  ++counters_.requests;
  if (no_answer) {
    bus_free_ = ex.request_end;  // send-data-no-acknowledge: nothing to wait for
    // ex may hold an earlier exchange (dp_cycle's filling form): none of its answer stays.
    ex.answer.reset();
    ex.answer_start = 0;
    ex.answer_end = 0;
    ex.stray.reset();
    ex.wait_end = 0;
  } else {
    wait_answer(ex, req);
    if (ex.answer) {
      ++counters_.answered;
    } else if (ex.answer_end == 0) {
      ++counters_.no_answer;
    } else {
      ++counters_.bad_answer;
    }
  }
  if (spare_.empty()) {
    history_.push_back(ex);
  } else {
    spare_.back() = ex;
    history_.push_back(std::move(spare_.back()));
    spare_.pop_back();
  }
}

void DpMaster::wait_answer(Exchange& ex, const fdl::Frame* req) {
  const std::uint64_t slot = slot_cycles();
  // The slot time is the wait for an answer's first start bit: one later is no answer.
  const std::uint64_t last_start = ex.request_end + slot;
  answer_.reset();
  // What began before the request's end + the shortest TSDR (11 bit times, EN 50170) is no answer
  // to it (a late answer to the request before, another station's telegram): a character that
  // starts then, and each one back to back after it (less than a bit time of idle: the same
  // telegram), is passed over.
  const std::uint64_t first_answer = ex.request_end + std::uint64_t{kShortestTsdrBits} * t_;
  std::uint64_t passed_end = 0;
  const auto passed = [&](std::uint64_t start) {
    return !answer_.started() &&
           (start < first_answer || (passed_end != 0 && start < passed_end + t_));
  };
  bool late = false;  // a first start bit past the slot time came
  // The character starting at `start` belongs to the answer (else it is passed over, or late).
  const auto ours = [&](std::uint64_t start) {
    if (passed(start)) {
      passed_end = start + std::uint64_t{kUartCharBits} * t_;
      return false;
    }
    late = late || (!answer_.started() && start > last_start);
    return !late;
  };
  for (;;) {
    // Nothing below moves time before run_until: the cycle looked at is now() (a segment's
    // cycle() looks at every chip).
    const std::uint64_t at = look();
    for (const UartChar& c : chars_) {
      if (ours(c.start)) answer_.push(c);
    }
    std::span<const std::uint8_t> block = rx_.due();
    std::uint64_t block_start = rx_.due_start();
    while (!block.empty() && !ours(block_start)) {
      block = block.subspan(1);
      block_start += std::uint64_t{kUartCharBits} * t_;
    }
    answer_.push_block(block, block_start, t_);
    if (answer_.finished() && !rx_.receiving()) {
      bus_free_ = ex.wait_end = answer_.end();
      break;
    }
    if (at >= Chip::kLastCycle) {  // the chips' time has ended: no character comes any more
      bus_free_ = ex.wait_end = at;
      break;
    }
    // The one rule of the wait: a slot time after the last character on the line (the
    // request's, then each of the answer's) for the next start bit. Past it the exchange is over
    // (no answer, or a broken one) and the line is free from where the master found that: the
    // next request follows TSYN later (docs/timing.md: unanswered requests every 66 + 100 + 33
    // bit times). That is the wait's end itself unless a firmware's instruction (an 80C32's)
    // carried the run past it (docs/decisions.md, "The master's per-exchange cost"). A start bit
    // found only then, past the slot time, is no answer either.
    const std::uint64_t wait_end = (answer_.started() ? answer_.end() : ex.request_end) + slot;
    const bool late_start = !answer_.started() && rx_.receiving() && !passed(rx_.busy_from()) &&
                            rx_.busy_from() > last_start;
    if (late || late_start || (!rx_.receiving() && at >= wait_end)) {
      // The wait ended at wait_end; a late start bit is found only at or past it. Without an
      // answer started the asked station may still answer: next_start watches for it.
      bus_free_ = at;
      ex.wait_end = wait_end;
      watch_late_ = !answer_.started();
      late_heard_ = late || late_start;
      break;
    }
    // Event-driven: sleep until a start bit (TxD falls) or the wait ends; once the length is
    // known, until the stop sample of the answer's last character (sent back to back). Between
    // two characters of the answer, until the stop sample of one back to back: a start bit inside
    // a telegram wakes nobody on a segment (the line is its sender's, docs/segment.md).
    const bool receiving = rx_.receiving();
    std::size_t len = answer_.expected_length();
    std::uint64_t next = wait_end;
    if (receiving || answer_.started()) {
      const std::uint64_t first = answer_.started() ? answer_.start() : rx_.busy_from();
      if (len == 0) len = length_known(first);
      const auto stop_sample = [&](std::uint64_t start, std::size_t chars) {
        return start + (chars * kUartCharBits - 1) * std::uint64_t{t_} + t_ / 2;
      };
      if (receiving) {
        next = len != 0 ? stop_sample(first, len) : rx_.next_deadline();
      } else {
        // Between characters the slot time runs: an answer that stops ends the wait at its end.
        next = std::min(wait_end, len != 0 && stop_sample(first, len) > at
                                      ? stop_sample(first, len)
                                      : stop_sample(answer_.end(), 1));
      }
    }
    wake_on_txd_ = len == 0 || !receiving;
    run_until(std::max(next, at + 1));
  }
  wake_on_txd_ = false;
  if (passed_end != 0) late_answer(passed_end, false);  // one to the request before
  // No answer within the slot time: 0, 0 and none. An earlier answer in ex (dp_cycle's filling
  // form) lends its data unit's buffer to this one.
  ex.answer_start = answer_.start();
  ex.answer_end = answer_.end();
  answer_.frame(ex.answer);
  ex.stray.reset();
  // An answer mirrors its request's addresses (EN 50170: DA the requester, SA the responder)
  // and is a response (FC bit 6 clear; a token is none); another telegram in its place is not
  // its answer (an SC carries no addresses).
  if (ex.answer && req != nullptr && ex.answer->sd != fdl::SC &&
      (ex.answer->sd == fdl::SD4 || fdl::is_request(ex.answer->fc) || ex.answer->da != req->sa ||
       ex.answer->sa != req->da)) {
    ex.stray = std::move(ex.answer);
    ex.answer.reset();
  }
}

// A telegram a segment relayed whole is known to its end at its first start bit: its length from
// its first characters, where all of it is known (0: not known yet, the characters tell).
std::size_t DpMaster::length_known(std::uint64_t first) const {
  if (!seg_ || seg_->whole_start() != first) return 0;
  const std::span<const std::uint8_t> bytes = seg_->whole_bytes();
  fdl::Assembler a;
  for (const std::uint8_t b : bytes) {
    if (a.push(b) != fdl::Assembler::Status::need_more || a.expected_length() != 0) break;
  }
  return a.expected_length() <= bytes.size() ? a.expected_length() : 0;
}

Exchange DpMaster::fdl_status() {
  const Exchange ex = transact(fdl::make_frame(
      target_, cfg_.address, fdl::make_request_fc(fdl::Function::FDL_Status, false, false)));
  if (ex.answer) {
    fcb_ = false;  // the first SRD after FDL_Status carries FCV = 1, FCB = 1
    fcv_started_ = true;
  }
  return ex;
}

Exchange DpMaster::slave_diag() { return transact(request(sap::Slave_Diag, {})); }

Exchange DpMaster::set_ext_prm(std::vector<std::uint8_t> du) {
  return transact(request(sap::Set_Ext_Prm, std::move(du)));
}

Exchange DpMaster::acyclic(std::uint8_t dsap, std::uint8_t ssap, std::vector<std::uint8_t> du) {
  fdl::Frame f = request(dsap, std::move(du));
  f.ssap = ssap;
  return transact(f);
}

std::uint8_t prm_station_status(const SlaveConfig& s) {
  using P = pdu::SetPrm;
  std::uint8_t status = P::Lock_Req;
  if (s.wd_on) status |= P::WD_On;
  if (s.freeze_req) status |= P::Freeze_Req;
  if (s.sync_req) status |= P::Sync_Req;
  return status;
}

// Spec_User_Prm_Byte (byte 7) is always sent, 0 when the slave has no user parameters; WD_Base
// is its bit 2 (DPV1_Status_1 includes it).
std::vector<std::uint8_t> prm_du(const SlaveConfig& s, std::uint8_t station_status) {
  pdu::SetPrm p;
  p.station_status = station_status;
  p.wd_fact1 = s.wd_fact1;
  p.wd_fact2 = s.wd_fact2;
  p.min_tsdr = s.min_tsdr;
  p.ident = s.ident;
  p.group_ident = s.group_ident;
  p.user_prm.resize(std::max<std::size_t>(s.user_prm.size(), 1), 0);
  std::copy(s.user_prm.begin(), s.user_prm.end(), p.user_prm.begin());
  if (s.wd_base_1ms) p.user_prm[0] |= dpv1::status1::WD_Base;
  return p.build();
}

Exchange DpMaster::set_prm(std::uint8_t station_status_extra) {
  return set_prm_status(
      static_cast<std::uint8_t>(prm_station_status(slave_) | station_status_extra));
}

Exchange DpMaster::set_prm_status(std::uint8_t status) {
  return transact(request(sap::Set_Prm, prm_du(slave_, status)));
}

Exchange DpMaster::chk_cfg() { return transact(request(sap::Chk_Cfg, slave_.cfg)); }
Exchange DpMaster::get_cfg() { return transact(request(sap::Get_Cfg, {})); }
Exchange DpMaster::data_exchange(const std::vector<std::uint8_t>& outputs, UartFault fault) {
  Exchange ex;
  data_exchange(outputs, fault, ex);
  return ex;
}

void DpMaster::data_exchange(std::span<const std::uint8_t> outputs, UartFault fault, Exchange& ex) {
  ex.request.du.assign(outputs.begin(), outputs.end());
  const bool fcb = fcb_;
  make_request(ex.request, std::nullopt);
  try {
    transact(fault, ex);
  } catch (const std::invalid_argument&) {
    fcb_ = fcb;  // refused before it went out (a fault beyond the telegram): the FCB as it was
    throw;
  }
}
Exchange DpMaster::read_inputs() { return transact(request(sap::Rd_Inp, {})); }
Exchange DpMaster::read_outputs() { return transact(request(sap::Rd_Outp, {})); }

Exchange DpMaster::global_control(std::uint8_t command, std::uint8_t groups) {
  const std::uint8_t keep = target_;
  target_ = fdl::kBroadcast;
  const Exchange ex = transact(request(sap::Global_Control, {command, groups}, false));
  target_ = keep;
  return ex;
}

Exchange DpMaster::service(std::uint8_t dsap, std::vector<std::uint8_t> du, bool srd) {
  const std::uint8_t keep = target_;
  if (!srd) target_ = fdl::kBroadcast;
  const Exchange ex = transact(request(dsap, std::move(du), srd));
  target_ = keep;
  return ex;
}

Exchange DpMaster::set_slave_address(std::uint8_t new_address, bool no_add_change) {
  return transact(request(
      sap::Set_Slave_Add,
      {new_address, static_cast<std::uint8_t>(slave_.ident >> 8),
       static_cast<std::uint8_t>(slave_.ident), static_cast<std::uint8_t>(no_add_change ? 1 : 0)}));
}

bool DpMaster::diag_ready(const fdl::Frame& f) {
  using D = pdu::SlaveDiag;
  const std::optional<D> d = D::parse(f.du);
  constexpr std::uint8_t kNotReadyOrFault =
      D::St1_Station_Not_Ready | D::St1_Cfg_Fault | D::St1_Not_Supported | D::St1_Prm_Fault;
  return d && (d->station_status_1 & kNotReadyOrFault) == 0 &&
         (d->station_status_2 & D::St2_Prm_Req) == 0;
}

bool DpMaster::startup(int tries) {
  Startup s;
  s.tries = tries;
  while (startup_request(s)) {
    if (s.wait_until > now()) idle(s.wait_until - now());
  }
  return s.phase == Startup::Phase::ready;
}

bool DpMaster::startup_request(Startup& s) {
  using P = Startup::Phase;
  if (s.phase == P::ready || s.phase == P::failed) return false;
  if (s.n >= s.tries) {
    s.phase = P::failed;
    return false;
  }
  const std::uint64_t ms = (seg_ ? seg_->clock_hz() : chip_->clock_hz()) / 1000;
  switch (s.phase) {
    case P::fdl_status:
      if (fdl_status().answer) {
        s.phase = P::diag;
      } else {
        ++s.n;
      }
      return true;
    case P::prm: {
      const Exchange prm = set_prm();
      s.check_until =
          prm.answer && prm.answer->sd == fdl::SC ? prm.request_start + kPrmCheckMs * ms : 0;
      s.unconfirmed = !prm.answer;
      // Unanswered, the slave's state is unknown: the start-up goes on at Slave_Diag, not with a
      // Chk_Cfg to a slave that may not hold our parameters (docs/decisions.md, the
      // thirty-fourth session).
      s.phase = prm.answer ? P::cfg : P::diag;
      if (!prm.answer) ++s.n;
      return true;
    }
    case P::cfg:
      s.unconfirmed = !chk_cfg().answer;
      ++s.n;
      s.phase = P::diag;
      return true;
    default:
      break;
  }
  if (now() < s.wait_until) return false;
  const Exchange diag = slave_diag();
  if (!diag.answer) {
    ++s.n;
    return true;
  }
  using D = pdu::SlaveDiag;
  const std::optional<D> d = D::parse(diag.answer->du);
  const bool locked = d && d->master_add != D::kNoMaster && d->master_add != cfg_.address;
  if (!locked) locks_.erase(slave_.address);
  if (locked) {
    // Master_Lock: another master parameterised the slave and holds it (chip-facts.md, Slave_Diag
    // byte 3); it is not ours to parameterise (docs/decisions.md, the twenty-eighth session).
    locks_[slave_.address] = d->master_add;
    if (on_locked) on_locked(slave_.address, d->master_add);
    s.phase = P::failed;
    return true;
  }
  if (diag_ready(*diag.answer)) {
    s.phase = P::ready;
    return true;
  }
  const std::vector<std::uint8_t>& du = diag.answer->du;
  const bool fault = !du.empty() && (du[0] & (D::St1_Cfg_Fault | D::St1_Prm_Fault)) != 0;
  if ((du.size() >= 2 && (du[1] & D::St2_Prm_Req) != 0) || fault) {
    // The slave holds our parameters (Master_Add is ours, no fault) and its user is still
    // checking them: a new Set_Prm would only restart the check (Prm_Conflict). Poll every
    // 1 ms for up to kPrmCheckMs after our Set_Prm before parameterising again
    // (docs/decisions.md, "The built-in master waits for a slave's Prm check").
    if (!fault && du.size() >= 4 && du[3] == cfg_.address && now() < s.check_until) {
      s.wait_until = now() + ms;
      ++s.n;
      return true;
    }
    // Prm_Req (or a fault): parameterise and configure.
    s.phase = P::prm;
    return true;
  }
  // Not ready, and our last Set_Prm or Chk_Cfg went unanswered: parameterise and configure again.
  if (s.unconfirmed) {
    s.phase = P::prm;
    return true;
  }
  ++s.n;
  return true;
}

bool DpMaster::restart(std::uint64_t tries, std::uint32_t retries) {
  std::uint64_t n = 0;
  for (; n < tries; ++n) {
    if (retry(fdl_status(), retries).answer) break;
  }
  if (n == tries) return false;
  retry(slave_diag(), retries);
  retry(set_prm(), retries);
  retry(chk_cfg(), retries);
  for (; n < tries; ++n) {
    const Exchange d = retry(slave_diag(), retries);
    if (d.answer && diag_ready(*d.answer)) return true;
  }
  return false;
}

}  // namespace dpc31
