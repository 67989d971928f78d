#include "segment_outputs.hpp"

#include <fmt/core.h>

#include <utility>

#include "bus_check.hpp"
#include "dp_master.hpp"
#include "dpc31/fdl.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

SegmentOutputs::SegmentOutputs(SegmentOutputOptions opt) : opt_(std::move(opt)) {
  for (const wave::Options& w : opt_.waves) waves_.push_back(std::make_unique<wave::Recorder>(w));
}

SegmentOutputs::~SegmentOutputs() { *live_ = false; }

bool SegmentOutputs::open(std::string& error) {
  for (auto& w : waves_) {
    if (!w->open(error)) return false;
  }
  if (!opt_.pcap.empty() && !pcap_.open(opt_.pcap)) {
    error = pcap_.error();
    return false;
  }
  return true;
}

bool SegmentOutputs::add_station(Segment& seg, std::size_t index, const std::string& scope,
                                 std::string& error) {
  // One scope a chip: two would be one module in a VCD, one set of wires in an LA-VCD.
  for (const auto& [taken, name] : scoped_) {
    if (taken == scope) {
      error = second_station_in_scope(seg.name(index), name, scope);
      return false;
    }
  }
  seg_ = &seg;
  for (std::size_t i = 0; i < waves_.size(); ++i) {
    if (waves_[i]->attach_station(seg.chip(index), scope, error)) continue;
    // Refused by one: out of those before it too, so that the station may leave whole.
    while (i > 0) waves_[--i]->detach_station();
    return false;
  }
  scoped_.emplace_back(scope, seg.name(index));
  return true;
}

void SegmentOutputs::remove_station() {
  for (auto& w : waves_) w->detach_station();
  scoped_.pop_back();
}

bool SegmentOutputs::attach_line(Segment& seg, std::vector<std::uint8_t> driver_codes,
                                 std::string& error) {
  seg_ = &seg;
  for (auto& w : waves_) {
    if (!w->attach_line(
            driver_codes, seg.bit_cycles(), [&seg] { return seg.line_final(); }, error))
      return false;
  }
  if (!waves_.empty()) {
    // The segment may run on after this is gone (dpc31.Segment's close()): then a no-op.
    seg.on_line = [this, live = live_](std::size_t from, std::uint64_t cycle, bool level) {
      if (!*live) return;
      for (auto& w : waves_) w->line_edge(from, cycle, level);
    };
  }
  return true;
}

void SegmentOutputs::telegram(const LineTelegram& t) {
  if (pcap_.is_open()) capture(t);
}

void SegmentOutputs::end(const Segment& seg) {
  seg_ = &seg;
  if (held_) add(*held_);
  held_.reset();
  end_cycle_ = seg.cycle();
}

bool SegmentOutputs::write(std::string& error) {
  for (auto& w : waves_) {
    if (!w->finish(end_cycle_, error)) return false;
  }
  if (pcap_.is_open() && !pcap_.close()) {
    error = pcap_.error();
    return false;
  }
  return true;
}

// The line's telegrams (docs/capture.md, "A segment's line"): each with its sender; a request that
// wants an answer is held until the next telegram says who answered it (a frame that decodes,
// from another station: what is left of a collision answers nothing, even where its bytes read
// as a frame; a telegram the bus check calls unsolicited answers nothing either).
void SegmentOutputs::capture(const LineTelegram& t) {
  const fdl::Decoded d = fdl::decode(t.bytes);
  const bool chars_ok = t.fault.kind == UartFault::Kind::none;
  const bool ok = chars_ok && d.error == fdl::Error::none && d.frame.sd != fdl::SD4;
  const bool request = ok && fdl::is_request(d.frame.fc);
  Held h{t, fmt::format("cycles {}-{}, {}", t.start, t.end, seg_->name(t.from)), d.frame.sa,
         d.frame.da};
  // A broken character: the bus check's words, and the packet flagged (docs/capture.md).
  if (!chars_ok)
    h.comment += fmt::format(", character {}: {}", t.fault.char_index, fault_name(t.fault.kind));
  if (held_) {
    const BusTiming timing{seg_->bit_cycles(), 11, opt_.slot_bits, 33, 0, {}};
    if (ok && !request && !t.collided && t.from != held_->t.from &&
        answers_request(timing, t.start - held_->t.end, ok,
                        mirrors(d.frame, held_->sa, held_->da))) {
      held_->comment += fmt::format(", answered by {}", seg_->name(t.from));
      h.comment += fmt::format(", answer to {}", seg_->name(held_->t.from));
    }
    add(*held_);
    held_.reset();
  }
  if (request && wants_answer(d.frame)) {
    held_ = std::move(h);
  } else {
    add(h);
  }
}

void SegmentOutputs::add(const Held& h) {
  const std::optional<std::uint64_t> ns = capture::cycles_to_ns(h.t.start, seg_->clock_hz());
  if (!ns) return;  // 584 years of line time
  pcap_.add(capture::Packet{
      *ns, seg_->is_chip(h.t.from) ? capture::Direction::outbound : capture::Direction::inbound,
      h.t.bytes, h.comment, h.t.fault.kind != UartFault::Kind::none});
}

SegmentScenarioOutputs::SegmentScenarioOutputs(const SegmentScenario& s, SegmentOutputOptions opt)
    : s_(s), out_(std::move(opt)), place_(s.file, 0) {
  out_.pair_within(s.slot_bits);
  for (const SegmentStation& st : s.stations)
    scopes_.push_back(station_scope(st.slave.address, st.name));
}

void SegmentScenarioOutputs::step_begins(const SegmentStep& st, std::string_view /*text*/) {
  place_.enter(st.line, st.text);
}

void SegmentScenarioOutputs::station_added(Segment& seg, std::size_t index) {
  std::string error;
  if (!out_.add_station(seg, index, scopes_[index], error)) throw SegmentOutputError(error);
}

// Each station's code in line.driver: a chip's and a master's address, FEh a sender.
void SegmentScenarioOutputs::stations_added(Segment& seg) {
  std::vector<std::uint8_t> codes;
  for (const SegmentStation& st : s_.stations) codes.push_back(st.slave.address);
  codes.resize(codes.size() + s_.senders.size(), wave::kDriverWithoutAddress);
  for (const SegmentMaster& m : s_.masters) codes.push_back(m.address);
  std::string error;
  if (!out_.attach_line(seg, std::move(codes), error)) throw SegmentOutputError(error);
}

void SegmentScenarioOutputs::run_ends(Segment& seg, std::uint32_t, std::uint32_t) {
  out_.end(seg);
  ended_ = true;
}

bool SegmentScenarioOutputs::write(std::string& error) {
  if (!ended_) {
    error = fmt::format("{}: the run did not end: nothing written", s_.file);
    return false;
  }
  return out_.write(error);
}

}  // namespace dpc31
