#include "segment.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <deque>
#include <iterator>
#include <stdexcept>

#include "segment_station.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

namespace {

// `slot` holds `value` for a scope (left by an exception from a firmware too).
class Scoped {
 public:
  Scoped(std::optional<std::uint64_t>& slot, std::uint64_t value) : slot_(slot), old_(slot) {
    slot_ = value;
  }
  ~Scoped() { slot_ = old_; }
  Scoped(const Scoped&) = delete;
  Scoped& operator=(const Scoped&) = delete;

 private:
  std::optional<std::uint64_t>& slot_;
  std::optional<std::uint64_t> old_;
};

bool before(std::uint64_t c, const Heard& h) { return c < h.at; }

// The start bit of the last character (or the edge) a sender heard.
std::uint64_t last_heard(const std::vector<Heard>& h, std::uint64_t frame) {
  return h.back().whole ? h.back().at + (h.back().count - 1) * frame : h.back().at;
}

// Its runs as one entry per character: what lands between two characters of a run (out of cycle
// order, rare) is inserted between them as before. In place, from the back: the vector keeps its
// memory.
void one_by_one(std::vector<Heard>& h, std::uint64_t frame) {
  std::size_t n = 0;
  for (const Heard& e : h) n += e.whole ? e.count : 1;
  std::size_t j = n;
  std::size_t i = h.size();
  if (n == i) return;
  h.resize(n);
  while (i > 0) {
    const Heard e = h[--i];
    if (!e.whole) {
      h[--j] = e;
      continue;
    }
    for (std::size_t c = e.count; c > 0; --c)
      h[--j] = Heard{e.at + (c - 1) * frame, true, false, 1, e.first + c - 1};
  }
}

}  // namespace

// The chips' baud search finds only the PROFIBUS rates: on another, nobody would ever answer.
static std::uint32_t profibus_rate(std::uint32_t baud) {
  if (const std::string e = not_a_profibus_rate(baud); !e.empty()) throw std::invalid_argument(e);
  return baud;
}

Segment::Segment(std::uint32_t baud, std::uint32_t clock_hz)
    : clock_hz_(clock_hz != 0 ? clock_hz : Chip().clock_hz()),
      t_(dpc31::bit_cycles(clock_hz_, profibus_rate(baud))),
      line_rx_(t_, 0) {}

Segment::~Segment() = default;

void Segment::use_reference_line(bool on) {
  if (on != reference_ && std::any_of(stations_.begin(), stations_.end(),
                                      [](const auto& s) { return s->chip != nullptr; })) {
    throw std::logic_error("segment: use_reference_line before the first chip");
  }
  reference_ = on;
}

// A name is a waveform scope, part of a trace's file name and in every capture comment: its
// bound holds at every door (docs/capture.md), not only where a scenario or Python checks it;
// checked before anything of the station is made.
void Segment::check_name(const std::string& name) const {
  if (name.size() > kMaxStationName) {
    throw std::invalid_argument(fmt::format(
        "segment: {}", station_name_refused(name, fmt::format("station {}", stations_.size()))));
  }
}

std::size_t Segment::add_chip(std::string name, ChipOptions opt) {
  check_name(name);
  auto s = std::make_unique<Station>();
  s->name = std::move(name);
  s->chip = std::make_unique<Chip>(opt);
  if (s->chip->clock_hz() != clock_hz_) {
    throw std::invalid_argument(fmt::format("segment: station {} runs at {} Hz, the line at {} Hz",
                                            s->name, s->chip->clock_hz(), clock_hz_));
  }
  // A station joins the line at the line's time, after the telegrams logged so far.
  if (now_ > 0) s->chip->step(now_);
  s->taken = log_.end();
  log_.add_chip(stations_.size());
  Station* raw = s.get();
  if (reference_) {
    // Every TxD edge an event of the chip (Chip::on_txd): next_deadline() then bounds the next
    // one, which the rounds of the reference line rely on.
    s->chip->on_txd([this, raw](std::uint64_t cycle, bool level) {
      if (raw->txd.empty()) drove_.push_back(raw->index);
      raw->txd.emplace_back(cycle, level);
    });
  } else {
    // The answer stays characters in the chip (no edge events): the line relays the edges of
    // the answer armed, and checks what the chip drives against them.
    s->chip->on_txd_chars([this, raw](const TxdRun& run) { check_txd(*raw, run); });
  }
  s->chip->on_answer([this, raw](const Telegram& t) {
    raw->out.arm(t, raw->chip->bit_cycles());
    if (reference_) return;
    raw->answer = true;
    // In station order (relay_armed's ties).
    const auto at = std::lower_bound(armed_.begin(), armed_.end(), raw->index);
    if (at == armed_.end() || *at != raw->index) armed_.insert(at, raw->index);
  });
  add_station(std::move(s));
  raw->known = raw->chip->cycle();
  front_ = std::max(front_, raw->known);
  raw->chip->on_cycle([this, raw](std::uint64_t cycle) { cycle_moved(*raw, cycle); });
  look_at(*raw);
  return raw->index;
}

std::size_t Segment::add_sender(std::string name) {
  check_name(name);
  auto s = std::make_unique<Station>();
  s->name = std::move(name);
  add_station(std::move(s));
  senders_.push_back(stations_.size() - 1);
  return stations_.size() - 1;
}

void Segment::remove_last_chip() {
  if (stations_.empty() || !stations_.back()->chip) {
    throw std::logic_error("segment: remove_last_chip without a chip added last");
  }
  Station& s = *stations_.back();
  // What it drove is on the line, in the other stations and in the collisions: it stays.
  if (!s.out.bytes.empty() || !s.txd.empty() || owner_ == s.index) {
    throw std::logic_error("segment: station " + s.name + " drove the line: it stays on it");
  }
  set_next(s.index, UINT64_MAX);  // its leaf is free again, as add_station finds a new one
  next_.pop_back();
  everyone_.pop_back();
  std::erase(busy_, s.index);
  std::erase(moved_, s.index);
  log_.remove_chip(s.index, s.address);
  stations_.pop_back();
  front_stale_ = true;  // its init may have run it ahead of the line's time (cycle())
}

void Segment::set_firmware(std::size_t i, Cpu::Isr isr) {
  station(i).cpu = std::make_unique<Cpu>(chip(i), std::move(isr));
  look_at(*stations_[i]);
}

void Segment::set_firmware(std::size_t i, Cpu::Program program) {
  station(i).cpu = std::make_unique<Cpu>(chip(i), std::move(program));
  look_at(*stations_[i]);
}

void Segment::look_at(Station& s) {
  const bool busy = s.cpu && s.cpu->busy();
  // A verdict that shows nothing outside the chip is no event of the line's (docs/segment.md,
  // "Verdicts that show nothing"): the chip takes it inside its next step. A running firmware is
  // stepped in every round anyway, to the same ends as on the reference line.
  std::uint64_t next = reference_ || busy ? s.chip->next_deadline() : s.chip->line_deadline();
  next = std::min(next, s.out.next_edge());
  set_next(s.index, next);
  s.looked = s.chip->cycle();
  // Past its answer's end the chip has handed over all of it (its end is an event).
  if (s.broken.empty() && s.looked > s.out.end && s.out.behind()) {
    s.broken = fmt::format("stopped driving TxD before cycle {}", s.out.first_unconfirmed());
  }
  if (!s.broken.empty()) {
    throw std::logic_error(fmt::format("segment: {} {}, not the answer its chip armed (cut short?)",
                                       s.name, s.broken));
  }
  if (busy != s.busy) {
    s.busy = busy;
    const auto at = std::lower_bound(busy_.begin(), busy_.end(), s.index);
    if (busy) {
      busy_.insert(at, s.index);
    } else {
      busy_.erase(at);
    }
  }
  // Until its next event (or a new observer: chip(i) has it looked at again) the telegrams heard
  // whole that concern neither every chip nor its address may wait in the log.
  const bool eager = reference_ || busy || !s.chip->may_hear_later(t_);
  if (eager != s.eager) {
    s.eager = eager;
    log_.set_eager(s.index, eager);
  }
  const int address = s.chip->station_address();
  if (address != s.address) {
    log_.set_address(s.index, s.address, address);
    s.address = address;
  }
}

void Segment::set_next(std::size_t i, std::uint64_t next) {
  if (next_[i] == next) return;  // the tree holds it already (most looks change nothing)
  next_[i] = next;
  // The leaf and its ancestors up to the first whose minimum stays.
  std::size_t k = leaves_ + i;
  next_tree_[k] = next;
  for (k /= 2; k >= 1; k /= 2) {
    const std::uint64_t m = std::min(next_tree_[2 * k], next_tree_[2 * k + 1]);
    if (next_tree_[k] == m) break;
    next_tree_[k] = m;
  }
}

void Segment::add_station(std::unique_ptr<Station> s) {
  s->index = stations_.size();
  stations_.push_back(std::move(s));
  next_.push_back(UINT64_MAX);
  everyone_.push_back(stations_.size() - 1);
  if (stations_.size() > leaves_) {
    leaves_ = std::bit_ceil(stations_.size());
    next_tree_.assign(2 * leaves_, UINT64_MAX);
    std::copy(next_.begin(), next_.end(),
              next_tree_.begin() + static_cast<std::ptrdiff_t>(leaves_));
    for (std::size_t k = leaves_ - 1; k >= 1; --k)
      next_tree_[k] = std::min(next_tree_[2 * k], next_tree_[2 * k + 1]);
  }
}

// The leaves at or before `bound`, in station order: a walk that descends only into subtrees
// whose minimum is due, O(log N) for each chip due, without recursion (a subtree is not entered
// to find it has nothing due).
void Segment::due_by(std::uint64_t bound) {
  due_.clear();
  if (next_tree_.empty() || next_tree_[1] > bound) return;
  std::size_t k = 1;
  for (;;) {
    // A due subtree's first due leaf: where the left child has nothing due, the right one has.
    while (k < leaves_) {
      k *= 2;
      if (next_tree_[k] > bound) ++k;
    }
    due_.push_back(k - leaves_);
    // Up to the nearest left child whose right sibling is due, and into that sibling.
    for (;; k /= 2) {
      if (k == 1) return;
      if (k % 2 == 0 && next_tree_[k + 1] <= bound) break;
    }
    ++k;
  }
}

Segment::Station& Segment::station(std::size_t i) const {
  if (i >= stations_.size()) {
    throw std::out_of_range(fmt::format("station {}: the segment has {} station{}", i,
                                        stations_.size(), stations_.size() == 1 ? "" : "s"));
  }
  return *stations_[i];
}

const std::string& Segment::name(std::size_t i) const { return station(i).name; }
bool Segment::is_chip(std::size_t i) const { return station(i).chip != nullptr; }

Chip& Segment::chip(std::size_t i) {
  Station& s = station(i);
  if (!s.chip) throw std::invalid_argument("segment: station " + s.name + " has no chip");
  // Left alone by the line, it has no event the line sees before now_ and its firmware sleeps:
  // stepping it here changes nothing but its cycle and what the verdicts it takes on the way
  // (Chip::line_deadline) count, as they would have by now on the reference line.
  if (s.chip->cycle() < now_ || s.taken < log_.end()) {
    const Scoped at(hard_end_, now_);  // its firmware does not run past the line's time
    step_station(s, now_);
  }
  // Whoever asks for it may arm something without time passing (an observer of TxD edges): the
  // rounds look at it again.
  s.looked = UINT64_MAX;
  mark(s);
  return *s.chip;
}

const Chip& Segment::chip(std::size_t i) const {
  // Bringing a station to the line's time changes nothing a user of the segment sees but its
  // cycle (chip() above): a const look may do it.
  return const_cast<Segment*>(this)->chip(i);
}

std::uint64_t Segment::cycle() const {
  if (front_stale_) {
    // A chip went back (a reset, an earlier snapshot): the front is the latest of the others.
    front_ = 0;
    for (const auto& s : stations_) {
      if (s->chip) front_ = std::max(front_, s->chip->cycle());
    }
    front_stale_ = false;
  }
  return std::max(now_, front_);
}

// Every change of a chip's cycle passes here (Chip::on_cycle), the segment's own steps and a
// user's through a kept Chip& alike: the line's front without a look at every chip, and the chips
// catch_up must look at again.
void Segment::cycle_moved(Station& s, std::uint64_t cycle) {
  if (cycle < s.known) front_stale_ = true;
  s.known = cycle;
  front_ = std::max(front_, cycle);
  mark(s);
}

void Segment::mark(Station& s) {
  if (s.moved) return;
  s.moved = true;
  moved_.push_back(s.index);
}

void Segment::catch_up() {
  const std::uint64_t front = cycle();
  const Scoped at(hard_end_, front);
  // The chips moved or handed out since the last catch_up (the others stand where the rounds
  // looked at them last); stepping them below marks them again.
  catching_.swap(moved_);
  moved_.clear();
  for (const std::size_t i : catching_) stations_[i]->moved = false;
  std::sort(catching_.begin(), catching_.end());
  if (reference_) {
    catching_ = everyone_;
  } else if (front > now_) {
    // Those with an event by `front` or a running firmware step there too; one without either
    // only passes time, as a chip the rounds leave alone does (step_station).
    due_by(front);
    stepped_.clear();
    std::set_union(catching_.begin(), catching_.end(), due_.begin(), due_.end(),
                   std::back_inserter(stepped_));
    catching_.clear();
    std::set_union(stepped_.begin(), stepped_.end(), busy_.begin(), busy_.end(),
                   std::back_inserter(catching_));
  }
  for (const std::size_t i : catching_) {
    Station& s = *stations_[i];
    if (!s.chip) continue;
    if (front > now_) step_station(s, front);
    // A user side arms something only with a bus access (time passes) or through chip(i).
    if (s.chip->cycle() != s.looked) look_at(s);
  }
  now_ = front;
}

// A chip the line left alone hears what the line brings standing at its cycle, as on the
// reference line (its on_rxd observers see the cycle it is fed at: a trace's `fed=`); it has no
// event before, so that costs one look at its deadlines.
void Segment::align() {
  catch_up();
  const Scoped at(hard_end_, now_);  // no firmware runs past the line's time
  for (const auto& s : stations_) step_station(*s, now_);
}

bool Segment::others_drive(const Station& s, std::uint64_t from, std::uint64_t to) const {
  if (hard_end_ && *hard_end_ >= from && *hard_end_ <= to) return true;
  if (!reference_) {
    // The same facts: only the armed answers with edges after the line's time drive from `from`.
    return std::any_of(armed_.begin(), armed_.end(), [&](std::size_t i) {
      return i != s.index && stations_[i]->out.drives(from, to);
    });
  }
  return std::any_of(stations_.begin(), stations_.end(), [&](const auto& o) {
    return o.get() != &s && o->chip && o->out.drives(from, to);
  });
}

// The host CPU never splits a bus access: one started before `to` may end up to kCpuSlack clocks
// past it. Its accesses must be those of the chip alone wherever the round ends (docs/segment.md,
// "A firmware across a round's end"), so, in this order:
// - nobody else drives the line from `to` to `to` + kCpuSlack (no other chip's armed answer, no
//   sender's telegram starting there, no hard end of a run): the CPU runs to `to` as on one chip,
//   the chip ends up to kCpuSlack past it (cycle() shows that, and run_until brings the line
//   there before it returns), and whatever drives later reaches it ahead of time;
// - else, its CPU runs to kCpuSlack short of `to` (an asleep one: the chip to `to` or to X/INT
//   going active), and when its own TxD stays quiet up to `to` the chip waits where its next
//   access (or its ISR) starts, in a later round (no edge of its own is missing from this one, and
//   what the line brings meanwhile reaches it ahead of time);
// - else (it drives too: a collision) the chip alone runs the rest, and the firmware's next access
//   starts at `to`, up to kCpuSlack clocks late.
void Segment::step_station(Station& s, std::uint64_t to) {
  if (!s.chip) return;
  take_log(s, to);
  if (s.chip->cycle() >= to) return;
  if (!reference_ && !s.busy && next_[s.index] > to && s.looked == s.chip->cycle()) {
    s.chip->step(to - s.chip->cycle());  // nothing happens in it before `to`: only time passes
    return;
  }
  if (s.cpu) {
    // An asleep CPU starts no access before X/INT: the chip runs on to `to` or until then.
    const auto asleep_to_end = [&] {
      while (!s.cpu->busy() && s.chip->cycle() < to) {
        s.chip->step_until_irq(to - s.chip->cycle());
        s.chip->clear_stop();
      }
    };
    asleep_to_end();
    if (s.chip->cycle() >= to) return;
    if (!others_drive(s, to, to + kCpuSlack)) {
      s.cpu->run_until(to);
      s.chip->clear_stop();
    } else if (to > kCpuSlack) {
      s.cpu->run_until(to - kCpuSlack);
      s.chip->clear_stop();
      asleep_to_end();
      if (s.chip->cycle() < to && !s.out.drives(s.chip->cycle() + 1, to)) return;
    }
  }
  if (s.chip->cycle() < to) s.chip->step(to - s.chip->cycle());
}

// Each entry at its start as send() gave it (nothing happens in the chip meanwhile but the verdicts
// before: they change nothing the rounds know of it), or folded (docs/segment.md, "The fold").
void Segment::take_log(Station& s, std::uint64_t to) {
  if (s.taken == log_.end()) return;
  const bool current = s.looked == s.chip->cycle();
  while (s.taken < log_.end() && log_.at(s.taken).start <= to) {
    const TelegramLog::Entry& e = log_.at(s.taken++);
    if (e.from == s.index) continue;  // its own answer
    if (s.chip->cycle() < e.start) s.chip->step(e.start - s.chip->cycle());
    LineAccess::hear_telegram(*s.chip, e.frame, e.start, t_);
    while (!s.own.empty() && s.own.front() < s.taken) s.own.pop_front();
    std::uint64_t until = log_.folds_until(s.taken, to);
    if (!s.own.empty()) until = std::min(until, s.own.front());
    if (until < s.taken + 3) continue;  // a fold of two entries at least
    const TelegramLog::Entry& first = log_.at(s.taken);
    if (s.chip->cycle() < first.start) s.chip->step(first.start - s.chip->cycle());
    if (s.chip->hear_run(log_.run(s.taken, until - 1, t_))) s.taken = until - 1;
  }
  if (current) s.looked = s.chip->cycle();
}

void Segment::hear_whole(std::size_t from, const std::shared_ptr<const HeardFrame>& heard,
                         std::uint64_t start) {
  const std::vector<std::size_t>& now = log_.hear_now(*heard);
  for (const std::size_t k : now) {
    if (k == from) continue;
    Station& s = *stations_[k];
    step_station(s, start);
    LineAccess::hear_telegram(*s.chip, heard, start, t_);
    look_at(s);
  }
  // Every chip heard it at once (or sent it, with nothing left to take): no entry.
  const Station& sender = *stations_[from];
  const bool sender_in = sender.chip && std::binary_search(now.begin(), now.end(), from);
  if (now.size() + (sender.chip && !sender_in ? 1 : 0) == log_.chips() &&
      (!sender.chip || sender.taken == log_.end())) {
    log_.line_taken();
    return;
  }
  if (sender.chip) stations_[from]->own.push_back(log_.end());
  log_.append(heard, start, from, t_);
  for (const std::size_t k : now) {
    if (k != from) stations_[k]->taken = log_.end();
  }
  // The log is trimmed past its bound: the chips that lag by more than half of it take their
  // entries now (a chip takes every entry once, now or at its next step), and the entries every
  // chip took are forgotten. A chip polled within the bound is not brought up early.
  const std::uint64_t bound = 64 + 4 * stations_.size();
  if (log_.end() - log_.first() > bound) {
    std::uint64_t taken = log_.end();
    for (const auto& s : stations_) {
      if (!s->chip) continue;
      if (log_.end() - s->taken > bound / 2) take_log(*s, UINT64_MAX);
      taken = std::min(taken, s->taken);
    }
    log_.forget(taken);
  }
}

void Segment::collide(std::size_t first, std::size_t second, std::uint64_t cycle, bool answer) {
  // One collision per burst of the second driver: each of its falling edges holds the burst open
  // one character time, as the line's holder's do.
  Station& s = *stations_[second];
  const bool fresh = s.colliding_until == 0 || cycle > s.colliding_until;
  s.colliding_until = std::max(s.colliding_until, cycle + std::uint64_t{kUartCharBits} * t_);
  if (!fresh) return;
  collisions_.push_back({cycle, first, second, answer});
  if (on_collision) on_collision(collisions_.back());
}

// The line is held by whoever drove the first start bit while it was free, for one character
// time from each of its falling edges (a start bit or a data bit: at most ten bit times too
// long, shorter than any legal gap). Another driver meanwhile collides and is not heard.
void Segment::relay(std::size_t i, std::uint64_t cycle, bool level) {
  const bool free = !owner_ || cycle >= owned_until_;
  if (!free && *owner_ != i) {
    if (!level) collide(*owner_, i, cycle);
    return;
  }
  if (free && level) return;  // the end of a burst nobody else hears
  if (!level) {
    if (free && wake_for_ && *wake_for_ != i) woken_ = true;
    owner_ = i;
    owned_until_ = std::max(owned_until_, cycle + std::uint64_t{kUartCharBits} * t_);
    if (free && relay_answer(i, cycle)) return;
  }
  hear(i, cycle, level);
}

void Segment::hear(std::size_t from, std::uint64_t cycle, bool level) {
  log_.line_taken();
  for (const std::size_t k : everyone_) {
    Station& s = *stations_[k];
    if (k == from || !s.chip) continue;
    if (cycle < s.chip->cycle()) {
      throw std::logic_error(fmt::format(
          "segment: the edge of {} at cycle {} reached {} at cycle {} (line order broken)",
          stations_[from]->name, cycle, s.name, s.chip->cycle()));
    }
    step_station(s, cycle);
    LineAccess::drive_rxd(*s.chip, cycle, level);
    look_at(s);
  }
  const std::pair<std::uint64_t, bool> edge{cycle, level};
  senders_hear(from, std::span(&edge, 1));
  decode(from, cycle, level);
}

void Segment::senders_hear(std::size_t from,
                           std::span<const std::pair<std::uint64_t, bool>> edges) {
  const std::uint64_t frame = std::uint64_t{kUartCharBits} * t_;
  for (const std::size_t k : senders_) {
    if (k == from) continue;
    std::vector<Heard>& h = stations_[k]->heard;
    for (const auto& [at, level] : edges) {
      if (!h.empty() && last_heard(h, frame) > at) one_by_one(h, frame);
      h.insert(std::upper_bound(h.begin(), h.end(), at, before), Heard{at, false, level, 0, 0});
    }
  }
}

void Segment::senders_hear(std::size_t from, std::span<const std::uint8_t> bytes,
                           std::uint64_t start) {
  const std::uint64_t frame = std::uint64_t{kUartCharBits} * t_;
  whole_start_ = start;
  whole_.assign(bytes.begin(), bytes.end());
  if (bytes.empty()) return;
  for (const std::size_t k : senders_) {
    if (k == from) continue;
    std::vector<Heard>& h = stations_[k]->heard;
    std::vector<std::uint8_t>& b = stations_[k]->heard_bytes;
    const std::size_t first = b.size();
    b.insert(b.end(), bytes.begin(), bytes.end());
    if (h.empty() || last_heard(h, frame) <= start) {
      // After everything it heard so far (the common case): one run, appended.
      h.push_back(Heard{start, true, false, bytes.size(), first});
      continue;
    }
    one_by_one(h, frame);
    auto at = std::upper_bound(h.begin(), h.end(), start, before);
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      at = std::upper_bound(at, h.end(), start + i * frame, before);
      at = std::next(h.insert(at, Heard{start + i * frame, true, false, 1, first + i}));
    }
  }
}

void Segment::decode(std::size_t from, std::uint64_t cycle, bool level) {
  if (!level && (claims_.empty() || claims_.back().second != from))
    claims_.emplace_back(cycle, from);
  line_rx_.edge(cycle, level);
  if (on_line) on_line(from, cycle, level);
}

// A good telegram of station `from`: the line's decoder keeps its characters whole until they are
// due (TxdReceiver::take), the waveform's observer gets its edges.
void Segment::decode_chars(std::size_t from, std::span<const std::uint8_t> bytes,
                           std::uint64_t start,
                           std::span<const std::pair<std::uint64_t, bool>> edges) {
  if (claims_.empty() || claims_.back().second != from) claims_.emplace_back(start, from);
  line_rx_.take(TxdRun{bytes, start, t_, {}});
  if (on_line) {
    for (const auto& [at, level] : edges) on_line(from, at, level);
  }
}

// Characters whose stop sample is by `upto` join the open telegram (the driver of its first
// character is its sender); it closes when the line stayed idle past its end (a character back
// to back would have started at its end).
void Segment::close_telegrams(std::uint64_t upto, std::uint64_t known) {
  const std::uint64_t to = std::min(upto, known);
  // A decoder that receives nothing and holds no character due by `to` (most rounds: the line is
  // idle) has nothing to hand over: advance() would only empty due().
  if (line_rx_.receiving() || line_rx_.next_deadline() <= to) {
    chars_.clear();
    line_rx_.advance(to, chars_);
    for (const UartChar& c : chars_) {
      // The first error sampled, as Mac::on_char counts it.
      const UartFault::Kind bad = !c.start_ok    ? UartFault::Kind::start
                                  : !c.parity_ok ? UartFault::Kind::parity
                                  : !c.stop_ok   ? UartFault::Kind::stop
                                                 : UartFault::Kind::none;
      line_chars(std::span(&c.data, 1), c.start, bad);
    }
    // The whole characters after those, back to back: one block.
    if (!line_rx_.due().empty()) line_chars(line_rx_.due(), line_rx_.due_start());
  }
  if (open_now_ &&
      (upto == UINT64_MAX || (upto > open_.end && line_rx_.busy_from() != open_.end))) {
    if (on_telegram) on_telegram(open_);
    open_now_ = false;
  }
}

void Segment::line_chars(std::span<const std::uint8_t> data, std::uint64_t start,
                         UartFault::Kind bad) {
  if (open_now_ && start > open_.end) {
    if (on_telegram) on_telegram(open_);
    open_now_ = false;
  }
  if (!open_now_) {
    std::size_t from = 0;
    for (const auto& [at, who] : claims_) {
      if (at <= start) from = who;
    }
    while (claims_.size() > 1 && claims_[1].first <= start) claims_.erase(claims_.begin());
    open_now_ = true;
    open_.from = from;
    open_.start = start;
    open_.bytes.clear();  // its memory kept: no allocation per telegram
    open_.fault = {};
    // A burst's falling edges come at most a character time apart (Segment::collide).
    open_.collided = start <= stations_[from]->colliding_until;
  }
  if (bad != UartFault::Kind::none && open_.fault.kind == UartFault::Kind::none)
    open_.fault = {static_cast<int>(open_.bytes.size()), bad};
  open_.bytes.insert(open_.bytes.end(), data.begin(), data.end());
  open_.end = start + data.size() * std::uint64_t{kUartCharBits} * t_;
}

void Segment::flush() { close_telegrams(UINT64_MAX, now_); }

void Segment::close_ended() {
  if (open_now_) close_telegrams(now_ + 1, now_);
}

void Segment::check_send(std::size_t from, std::uint64_t start, std::uint64_t cycles) const {
  if (const Station& s = station(from); s.chip) {
    throw std::invalid_argument(fmt::format(
        "station {} ({}) is a chip: its chip drives the line, send from a sender (add_sender)",
        from, s.name));
  }
  if (cycles > Chip::kLastCycle || start > Chip::kLastCycle - cycles) {
    throw std::invalid_argument(
        fmt::format("start {}: {} cycles from there end past the last cycle ({})", start, cycles,
                    Chip::kLastCycle));
  }
}

std::uint64_t Segment::send(std::size_t from, std::span<const std::uint8_t> bytes,
                            std::uint64_t start, UartFault fault) {
  place_fault(fault, bytes.size());
  const std::uint64_t cycles = bytes.size() * std::uint64_t{kUartCharBits} * t_;
  check_send(from, start, cycles);
  // No firmware runs past the first start bit, neither while the line is brought there nor while
  // the chips are given the telegram (step_station): each takes it at its exact edges.
  const Scoped at(hard_end_, start);
  run_until(start);
  const std::uint64_t end = start + cycles;
  if (owner_ && *owner_ != from && start < owned_until_) {
    const fdl::Decoded d = fdl::decode(bytes);
    const bool request =
        d.error == fdl::Error::none &&
        (d.frame.sd == fdl::SD4 || (d.frame.sd != fdl::SC && fdl::is_request(d.frame.fc)));
    collide(*owner_, from, start, !request);
    return end;
  }
  owner_ = from;
  owned_until_ = end;
  // Decoded once for every chip that hears it whole; its edges only for whom needs them (a
  // damaged telegram, the reference line, an on_line observer).
  const bool whole = !reference_ && fault.kind == UartFault::Kind::none;
  Edges edges;
  if (!whole || on_line) uart_encode(bytes, start, t_, edges, fault);
  // run_until brought the line's time to the front of the chips (none stands past it).
  for (std::size_t k = 0; start < now_ && k < stations_.size(); ++k) {
    const Station& s = *stations_[k];
    if (k != from && s.chip && start < s.chip->cycle()) {
      throw std::logic_error(fmt::format("segment: {} sends at cycle {}, {} is at cycle {}",
                                         stations_[from]->name, start, s.name, s.chip->cycle()));
    }
  }
  if (whole) {
    hear_whole(from, frames_.make(bytes), start);
  } else {
    log_.line_taken();
    for (std::size_t k = 0; k < stations_.size(); ++k) {
      Station& s = *stations_[k];
      if (k == from || !s.chip) continue;
      step_station(s, start);
      LineAccess::drive_rxd_chars(*s.chip, bytes, start, t_, fault);
      look_at(s);
    }
  }
  if (whole) {
    senders_hear(from, bytes, start);
    decode_chars(from, bytes, start, edges);
  } else {
    senders_hear(from, edges);
    for (const auto& [cycle, level] : edges) decode(from, cycle, level);
  }
  return end;
}

void Segment::pulse(std::size_t from, std::uint64_t start, std::uint64_t low_cycles) {
  // Its rising edge at its falling edge's cycle would be no pulse, and out of the line's order.
  if (low_cycles == 0)
    throw std::invalid_argument("pulse: low_cycles 0: a pulse lasts 1 clock or more");
  check_send(from, start, std::max(low_cycles, std::uint64_t{kUartCharBits} * t_));
  // Its two edges are hard ends, as a telegram's first start bit is (send).
  const Scoped at(hard_end_, start);
  run_until(start);
  if (owner_ && *owner_ != from && start < owned_until_) {
    collide(*owner_, from, start);
    return;
  }
  owner_ = from;
  owned_until_ = start + std::uint64_t{kUartCharBits} * t_;
  hear(from, start, false);
  const Scoped rise(hard_end_, start + low_cycles);
  hear(from, start + low_cycles, true);
}

void Segment::run_to_send(std::uint64_t start, std::optional<std::size_t> wake_for) {
  const Scoped at(hard_end_, start);
  run_until(start, wake_for);
}

void Segment::run_until(std::uint64_t cycle, std::optional<std::size_t> wake_for) {
  cycle = std::min(cycle, Chip::kLastCycle);  // where the chips' time ends
  catch_up();
  wake_for_ = wake_for;
  woken_ = false;
  while (now_ < cycle && !woken_) round(cycle);
  // A firmware that ran past the last round's end (step_station) moved cycle(): the line and the
  // other chips follow it there, where no firmware runs past it, so that the line has one time.
  const std::uint64_t front = this->cycle();
  if (front > now_) {
    const Scoped at(hard_end_, front);
    while (now_ < front) round(front);
  }
  wake_for_.reset();
}

void Segment::round(std::uint64_t cycle) {
  // No chip's TxD changes before its next deadline: every station may run to the earliest,
  // and what a chip drives there reaches the others at that very cycle.
  std::uint64_t bound = cycle;
  if (reference_) {
    for (const auto& s : stations_) {
      if (s->chip) bound = std::min(bound, s->chip->next_deadline());
    }
  } else if (!next_tree_.empty()) {
    // A chip whose event is at the line's time itself (an answer's first start bit: the round
    // before ended there to relay it) takes it alone first: a round of one cycle for everyone
    // would end where nobody else needs an end.
    if (next_tree_[1] <= now_) {
      due_by(now_);
      for (const std::size_t i : due_) {
        step_station(*stations_[i], now_ + 1);
        look_at(*stations_[i]);
      }
    }
    bound = std::min(bound, next_tree_[1]);  // senders: UINT64_MAX
  }
  // A running firmware makes the chip alone's accesses wherever a round ends (step_station,
  // cases 1 and 2); only in a collision (case 3) does its next access start at a round's end, up
  // to kCpuSlack late (docs/segment.md, "A running firmware sees the same accesses"). So neither
  // the stop samples of the line's characters nor an answer's edges once relayed whole end a round.
  if (wake_for_ && wake_next_ < wakes_.size()) bound = std::min(bound, wakes_[wake_next_]);
  bound = std::max(bound, now_ + 1);
  // Telegram level: nobody drives before `bound` but what the line's decoder holds already (a
  // chip's TxD edges are its events; the senders' telegrams were decoded when sent), so a telegram
  // that ends before it closes now, before the chips step on: on_telegram comes before what they
  // do later (a scenario's log stays in cycle order, also where the master does not stop at its
  // request's end).
  if (!reference_ && open_now_) close_telegrams(bound, bound - 1);
  // Telegram level: a chip without an event by `bound` whose firmware sleeps is left where it
  // is (it is given the line's characters ahead of time, as a master gives them).
  if (reference_) {
    for (const auto& s : stations_) {
      if (!s->chip) continue;
      step_station(*s, bound);
      look_at(*s);
    }
  } else {
    // The chips due by `bound` and those whose firmware runs, in station order.
    due_by(bound);
    const std::vector<std::size_t>* step = &due_;
    if (!busy_.empty()) {
      stepped_.clear();
      std::set_union(due_.begin(), due_.end(), busy_.begin(), busy_.end(),
                     std::back_inserter(stepped_));
      step = &stepped_;
    }
    for (const std::size_t i : *step) {
      step_station(*stations_[i], bound);
      look_at(*stations_[i]);
    }
  }
  const std::uint64_t before = now_;
  now_ = bound;
  // What the chips drove, in the order of its cycles (ties: station order).
  round_.clear();
  if (reference_) {
    std::sort(drove_.begin(), drove_.end());
    for (const std::size_t i : drove_) {
      for (const auto& [at, level] : stations_[i]->txd) round_.push_back({at, i, level});
      stations_[i]->txd.clear();
    }
    drove_.clear();
  } else {
    relay_armed(before);
  }
  // Mostly one edge or none: sorted already, and stable_sort would allocate its buffer.
  const auto earlier = [](const Driven& a, const Driven& b) { return a.cycle < b.cycle; };
  if (!std::is_sorted(round_.begin(), round_.end(), earlier))
    std::stable_sort(round_.begin(), round_.end(), earlier);
  for (const Driven& e : round_) relay(e.station, e.cycle, e.level);
  for (; wake_next_ < wakes_.size() && wakes_[wake_next_] <= now_; ++wake_next_) {
    if (wake_for_ && *wake_for_ != wake_from_) woken_ = true;
  }
  close_telegrams(now_, now_);
  line_final_ = now_;
}

bool Segment::heard_nothing(std::size_t listener) const { return station(listener).heard.empty(); }

// A character whose start bit is on the line is handed whole: the receiver is then as its edges up
// to the line's time would leave it (UartRx::take), and what it reports by then is the same.
void Segment::take_line(std::size_t listener, const std::function<void(const TxdRun&)>& take) {
  Station& s = station(listener);
  const auto end = std::upper_bound(s.heard.begin(), s.heard.end(), now_, before);
  const std::uint64_t frame = std::uint64_t{kUartCharBits} * t_;
  auto h = s.heard.begin();
  bool rest = false;  // a run's characters after the line's time stay for later
  while (h != end && !rest) {
    if (h->whole) {
      // A run of characters back to back, up to the last whose start bit is on the line.
      const std::uint64_t start = h->at;
      take_bytes_.clear();
      for (; h != end && h->whole && h->at == start + take_bytes_.size() * frame; ++h) {
        const std::size_t k = std::min<std::size_t>(h->count, (now_ - h->at) / frame + 1);
        const auto b = s.heard_bytes.begin() + static_cast<std::ptrdiff_t>(h->first);
        take_bytes_.insert(take_bytes_.end(), b, b + static_cast<std::ptrdiff_t>(k));
        if (k < h->count) {
          h->at += k * frame;
          h->first += k;
          h->count -= k;
          rest = true;
          break;
        }
      }
      take(TxdRun{take_bytes_, start, t_, {}});
    } else {
      take_edges_.clear();
      for (; h != end && !h->whole; ++h) take_edges_.emplace_back(h->at, h->level);
      take(TxdRun{{}, 0, t_, take_edges_});
    }
  }
  s.heard.erase(s.heard.begin(), h);
  // The bytes of the runs taken are forgotten (their memory kept).
  std::size_t kept = s.heard_bytes.size();
  for (const Heard& e : s.heard) {
    if (e.whole) kept = std::min(kept, e.first);
  }
  s.heard_bytes.erase(s.heard_bytes.begin(),
                      s.heard_bytes.begin() + static_cast<std::ptrdiff_t>(kept));
  for (Heard& e : s.heard) {
    if (e.whole) e.first -= kept;
  }
}

}  // namespace dpc31
