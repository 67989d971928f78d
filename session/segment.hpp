// A bus segment (docs/segment.md): one RS-485 line that every station hangs on. A station is a
// chip (its own profile, variant, address and user side) or a sender without a chip (a built-in
// master, a scripted station of a fault). Every character on the line reaches every other
// station at the same cycle; each chip's TxD drives the line. Two stations driving at once is a
// collision, reported with both names and the cycle; the first driver keeps the line.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "cpu.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/uart.hpp"
#include "telegram_log.hpp"
#include "txd_receiver.hpp"

namespace dpc31 {

// One telegram on the line: who drove it, its first start bit, the end of its last stop bit and
// its characters' data (a broken character as its data bits read), and the verdict of its first
// broken character as the line's receiver read it (its index and the first error sampled: start
// bit, parity, stop bit, as a chip counts them; kind none: every character good). A chip
// discards such a telegram (docs/timing.md "Telegrams"), so the bus check and the capture do.
// `collided`: its first character went on from a burst of its sender that drove into another's
// telegram (a Collision's second driver): the rest of a telegram the collision cut, no telegram
// of its own to the bus check and the capture.
struct LineTelegram {
  std::size_t from = 0;
  std::uint64_t start = 0;
  std::uint64_t end = 0;
  std::vector<std::uint8_t> bytes;
  UartFault fault;
  bool collided = false;
};

struct Collision {
  std::uint64_t cycle = 0;  // the second driver's first edge while the first drove
  std::size_t first = 0;    // the station that had the line
  std::size_t second = 0;   // the station that drove into it (not heard by the others)
  // The second driver's telegram may be an answer: a chip's (a slave sends nothing else), a
  // sender's unless its bytes are a request or a token (a master's are).
  bool answer = true;
};

class Segment {
 public:
  // All stations share one time base (the chips' clock, 48 MHz unless given) and one bit rate.
  Segment(std::uint32_t baud, std::uint32_t clock_hz = 0);
  ~Segment();
  Segment(const Segment&) = delete;
  Segment& operator=(const Segment&) = delete;

  // A chip station; its clock must be the segment's. Returns its index. A name longer than
  // kMaxStationName (64 bytes) is std::invalid_argument, for a sender too.
  std::size_t add_chip(std::string name, ChipOptions opt);
  // A station without a chip (a master, a scripted station): it drives the line with send().
  std::size_t add_sender(std::string name);
  // Takes the last station added off the line again, a chip that has never driven it: a door
  // whose user side fails to set up after add_chip (a firmware's init) refuses the station and
  // leaves the segment as it was (its size, its names, the next station's index, the line's
  // time). std::logic_error for another station or one that drove the line.
  void remove_last_chip();
  // The user side of chip station `i`, run on its own host CPU whenever its X/INT is active
  // (or with a main loop).
  void set_firmware(std::size_t i, Cpu::Isr isr);
  void set_firmware(std::size_t i, Cpu::Program program);

  [[nodiscard]] std::size_t size() const { return stations_.size(); }
  [[nodiscard]] const std::string& name(std::size_t i) const;
  [[nodiscard]] bool is_chip(std::size_t i) const;
  // The chip of station i at the line's time: a station the line left alone (no event of its own,
  // its firmware asleep) may stand earlier, and is brought to cycle() first (docs/segment.md); one
  // whose firmware waits for its next access (up to kCpuSlack short) stays where that starts.
  // It also takes the telegrams the line logged for it (docs/segment.md, "The telegram log"): a
  // Chip& kept past a run of the line shows them, and counts observers added through it, only
  // after chip(i) (or align()) again.
  [[nodiscard]] Chip& chip(std::size_t i);
  [[nodiscard]] const Chip& chip(std::size_t i) const;
  [[nodiscard]] std::uint32_t bit_cycles() const { return t_; }
  [[nodiscard]] std::uint32_t clock_hz() const { return clock_hz_; }
  // The line's time: every chip the line needed has run to here (or will, before anything else
  // happens on the line: a chip's user side may have run it ahead with bus accesses, its init for
  // one); chip(i) brings the others here when looked at.
  [[nodiscard]] std::uint64_t cycle() const;
  // Every chip to cycle() and through the telegram log, also those the line left alone: for
  // whoever holds a station's Chip& (a trace recorder, an observer reading chip.cycle()) and
  // looks at it between runs.
  void align();

  // The reference line (on: as before issue 30 item 6): every station stepped in every round and
  // every character and edge given to every chip as it comes. Off (the default): telegram level,
  // docs/segment.md; the two are proven equal by tests/segment_speed_test.cpp. Before the first
  // chip only (the line watches its chips' TxD differently): throws std::logic_error after.
  void use_reference_line(bool on);

  // `bytes` as back-to-back characters from `start` (>= cycle()) driven by station `from`
  // (`fault` damages one character, as uart_encode does; char_index -1 the last one, as
  // place_fault says). Every station runs to `start` first. Returns the end of the last stop
  // bit. `from` must be a sender (add_sender): std::out_of_range for no station,
  // std::invalid_argument for a chip's, for a fault beyond the telegram or for a telegram that
  // would end past the last cycle the line counts (UINT64_MAX is its "never").
  std::uint64_t send(std::size_t from, std::span<const std::uint8_t> bytes, std::uint64_t start,
                     UartFault fault = {});
  // A low pulse from `from` of `low_cycles` at `start` (a glitch, line noise); refused as send(),
  // and a `low_cycles` of 0 (std::invalid_argument, nothing on the line).
  void pulse(std::size_t from, std::uint64_t start, std::uint64_t low_cycles);

  // Runs every station to `cycle`. With `wake_for`, returns as soon as a start bit from another
  // station than that one is on the line (cycle() is then where the line stands).
  void run_until(std::uint64_t cycle, std::optional<std::size_t> wake_for = std::nullopt);
  // run_until for a sender whose telegram starts at `start`: no firmware runs past it (a hard
  // end, docs/segment.md "A firmware across a round's end"), so every chip can be given it there.
  void run_to_send(std::uint64_t start, std::optional<std::size_t> wake_for = std::nullopt);

  // What station `listener` hears of the line (everything but its own driving) up to cycle(),
  // handed to `take` in order as runs of TxD: good characters whole from their start bits (a
  // character whose start bit is on the line comes whole), the rest as edges up to the line's
  // time (docs/segment.md). A sender's receiver (a master: TxdReceiver::take) uses it.
  void take_line(std::size_t listener, const std::function<void(const TxdRun&)>& take);
  // Whether the line brought `listener` nothing since it last took it (take_line).
  [[nodiscard]] bool heard_nothing(std::size_t listener) const;

  // The last telegram the line relayed whole to the senders (a chip's answer at its first start
  // bit, a sender's good telegram): its first start bit and its characters back to back, known to
  // its end from that start bit on, before the line's time reaches them (docs/segment.md).
  [[nodiscard]] std::uint64_t whole_start() const { return whole_start_; }
  [[nodiscard]] std::span<const std::uint8_t> whole_bytes() const { return whole_; }

  [[nodiscard]] const std::vector<Collision>& collisions() const { return collisions_; }
  // Every telegram on the line, in order of its start, as soon as its end is known (at the latest
  // one character time after its last stop bit, or at flush()).
  std::function<void(const LineTelegram&)> on_telegram;
  // Told of every collision as it is found.
  std::function<void(const Collision&)> on_collision;
  // Every edge on the line as its holder drives it (the station, the cycle, the level), in cycle
  // order: a sender's when it sends (ahead of time), a chip's when it is relayed. Waveforms use it.
  std::function<void(std::size_t, std::uint64_t, bool)> on_line;
  // Every edge on the line before this cycle has been handed to on_line.
  [[nodiscard]] std::uint64_t line_final() const { return line_final_; }
  // Hands on_telegram what is still open (the end of a run).
  void flush();
  // Hands on_telegram the open telegram if it ended by the line's time and no character starts at
  // its end (every edge up to the line's time is relayed): what a round after this cycle would
  // close first, told now (a scenario's step that ends while a collision keeps the line busy).
  void close_ended();

  // A host CPU may end a firmware access this many clocks after the cycle it was asked to reach:
  // past a round's end only where nobody else drives within them (docs/segment.md, "A firmware
  // across a round's end").
  static constexpr std::uint64_t kCpuSlack = 3;

 private:
  struct Station;
  using Edges = std::vector<std::pair<std::uint64_t, bool>>;
  void step_station(Station& s, std::uint64_t to);
  // The telegrams of the log station s has not taken and that start by `to`, each at its start
  // (stepped there: they came after its last look, before its next event, and heard whole); the
  // entries after one it heard, up to its own next answer and the last by `to` (its verdict may
  // be due after `to`), in one update (Chip::hear_run).
  void take_log(Station& s, std::uint64_t to);
  // A telegram heard whole from `from` at `start`: to the chips it concerns at once (stepped to
  // `start`, looked at again), into the log for the others.
  void hear_whole(std::size_t from, const std::shared_ptr<const HeardFrame>& heard,
                  std::uint64_t start);
  // Whether another station drives the line anywhere in [from, to] (another chip's armed answer)
  // or a firmware may not run past a cycle there (hard_end_).
  [[nodiscard]] bool others_drive(const Station& s, std::uint64_t from, std::uint64_t to) const;
  // One round of run_until: every station that needs it to the earliest next event (<= cycle).
  void round(std::uint64_t cycle);
  // What the rounds know of a chip: its next event and whether its firmware runs.
  void look_at(Station& s);
  void set_next(std::size_t i, std::uint64_t next);
  void add_station(std::unique_ptr<Station> s);
  void check_name(const std::string& name) const;
  // due_: the chips whose next event is at or before `bound`, in station order.
  void due_by(std::uint64_t bound);
  // Station i's answer, armed and now starting on the line at `cycle`, to every other chip whole;
  // the rest of its edges to the senders and the line's decoder at once.
  // False where it goes edge by edge (the reference line, another rate, no answer armed there).
  bool relay_answer(std::size_t i, std::uint64_t cycle);
  // Telegram level: the armed answers' edges up to now_ to the line (a chip's TxD edges are no
  // events of it: the line takes them from the answer it armed, docs/segment.md); `before`: the
  // line's time before this round.
  void relay_armed(std::uint64_t before);
  // A run of station s's TxD (Chip::on_txd_chars) checked against the answer its chip armed.
  void check_txd(Station& s, const TxdRun& run);
  // Every chip to cycle(): what its user side did directly on its bus moved it alone.
  void catch_up();
  // Chip::on_cycle of station s; a station for catch_up to look at again.
  void cycle_moved(Station& s, std::uint64_t cycle);
  void mark(Station& s);
  // An edge station `i` drove (in order, up to its cycle): the line's owner's are heard by all.
  void relay(std::size_t i, std::uint64_t cycle, bool level);
  void hear(std::size_t from, std::uint64_t cycle, bool level);
  // The character decoder of the line (for on_telegram), fed with what the owner drove.
  void decode(std::size_t from, std::uint64_t cycle, bool level);
  // The same for a good telegram from `start` whose edges are `edges`: its characters whole.
  // `edges` are needed only by on_line (empty without one).
  void decode_chars(std::size_t from, std::span<const std::uint8_t> bytes, std::uint64_t start,
                    std::span<const std::pair<std::uint64_t, bool>> edges);
  // What the senders but `from` hear: edges (in cycle order, anywhere) and good characters whole
  // from `start` (after everything they heard so far, or placed in order).
  // Throws unless `from` is a sender whose `cycles` from `start` end before UINT64_MAX.
  void check_send(std::size_t from, std::uint64_t start, std::uint64_t cycles) const;
  // Station i; std::out_of_range naming it and how many there are.
  [[nodiscard]] Station& station(std::size_t i) const;
  void senders_hear(std::size_t from, std::span<const std::pair<std::uint64_t, bool>> edges);
  void senders_hear(std::size_t from, std::span<const std::uint8_t> bytes, std::uint64_t start);
  // The line's decoder up to min(upto, known) (the line is known up to `known`: the line's time,
  // or before a round's end where nobody drives before it).
  void close_telegrams(std::uint64_t upto, std::uint64_t known);
  // Characters of the line back to back from `start`, at its bit time: the open telegram's, or
  // the first of a new one.
  // `bad`: the first error of a one-character `data` (none: good).
  void line_chars(std::span<const std::uint8_t> data, std::uint64_t start,
                  UartFault::Kind bad = UartFault::Kind::none);
  // `answer`: Collision::answer (false: a sender's request or token).
  void collide(std::size_t first, std::size_t second, std::uint64_t cycle, bool answer = true);

  std::uint32_t clock_hz_;
  std::uint32_t t_;
  bool reference_ = false;
  std::uint64_t now_ = 0;
  // The latest cycle a chip was told at (Chip::on_cycle); stale after a chip went back. The
  // stations moved or handed out (chip(i)) since the last catch_up, and catch_up's own list.
  mutable std::uint64_t front_ = 0;
  mutable bool front_stale_ = false;
  std::vector<std::size_t> moved_;
  std::vector<std::size_t> catching_;
  std::uint64_t line_final_ = 0;
  std::vector<std::unique_ptr<Station>> stations_;
  std::vector<std::size_t> everyone_;  // every station's index
  std::vector<std::size_t> senders_;   // the stations without a chip
  std::vector<Collision> collisions_;
  // The line: who drives it until when (a falling edge holds it one character time).
  std::optional<std::size_t> owner_;
  std::uint64_t owned_until_ = 0;
  bool woken_ = false;
  std::optional<std::size_t> wake_for_;
  // No firmware runs past this cycle: a sender drives from it, or the line's time is brought there.
  std::optional<std::uint64_t> hard_end_;
  // The telegram being decoded from the line: a good telegram taken whole (decode_chars) stays a
  // run of characters until its stop samples are due.
  TxdReceiver line_rx_;
  std::vector<UartChar> chars_;
  // The telegram being decoded, while open_now_ (kept to reuse its memory).
  LineTelegram open_;
  bool open_now_ = false;
  std::vector<std::pair<std::uint64_t, std::size_t>> claims_;  // (first edge, driver) in order
  // A round's TxD edges of every chip (run_until), kept to reuse its memory.
  struct Driven {
    std::uint64_t cycle;
    std::size_t station;
    bool level;
  };
  std::vector<Driven> round_;
  // The last telegram relayed whole to the senders (whole_start()).
  std::uint64_t whole_start_ = UINT64_MAX;
  std::vector<std::uint8_t> whole_;
  // take_line's runs, kept to reuse their memory.
  std::vector<std::uint8_t> take_bytes_;
  Edges take_edges_;
  // Telegram level: each station's next event as the rounds last looked (UINT64_MAX: a sender),
  // and the same as a tree of minima (next_tree_[1] the earliest, the leaves from leaves_ on, a
  // node the smaller of its two children) so that a round finds its end and the chips due by it
  // without looking at the others; the chips whose firmware runs, in station order; a round's
  // chips due and chips to step (kept to reuse their memory); the stations
  // with TxD edges not yet relayed (docs/segment.md).
  std::vector<std::uint64_t> next_;
  std::vector<std::uint64_t> next_tree_;
  std::size_t leaves_ = 0;
  std::vector<std::size_t> busy_;
  // The telegram log (docs/segment.md) and who hears a telegram at once.
  TelegramLog log_;
  HeardFramePool frames_;  // the telegrams heard whole, their memory used again
  std::vector<std::size_t> due_;
  std::vector<std::size_t> stepped_;
  std::vector<std::size_t> drove_;
  // Telegram level: the stations whose armed answer has edges after the line's time (a handful;
  // those a firmware's access may run into: others_drive).
  std::vector<std::size_t> armed_;
  // The start bits of the answer relayed whole that find the line free again (wake_for).
  std::vector<std::uint64_t> wakes_;
  std::size_t wake_next_ = 0;
  std::size_t wake_from_ = 0;
};

}  // namespace dpc31
