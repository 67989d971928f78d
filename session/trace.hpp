// Golden traces: a line-based, diff-friendly record of one chip session with cycle stamps — the
// telegrams the chip received (RxD) and sent (TxD), every CPU bus access (writes, and reads with
// the value the firmware got), every X/INT edge (and the DPC31's PB3 edges), and the chip's state
// at checkpoints — and the replay that plays it back on a fresh chip with neither master nor
// firmware: the recorded RxD telegrams and bus accesses are performed at their cycles, everything
// else is an expectation and checked exactly. The format is specified in docs/trace-format.md;
// `dpc31 run --record` and `dpc31 replay` are the front ends.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/uart.hpp"
#include "scenario.hpp"

namespace dpc31 {

// The first line of every trace file.
inline constexpr std::string_view kTraceMagic = "dpc31-trace 1";

// --- recording ---

// A telegram as its sender put it on RxD.
struct RxdTelegram {
  std::uint64_t start = 0;  // first start bit
  std::vector<std::uint8_t> bytes;
  UartFault fault;
};

// Records a session on one chip. attach() it at cycle 0, before anything touches the chip; the
// recorder must outlive the chip's observers (it stays registered until the chip is gone).
// Entries are collected per segment — the stretch between two checkpoints — and each segment is
// written in cycle order, headed by its comments and followed by a `state` line. The lines go
// out as they are decided (write_to), or are kept for text(): the header at attach(), a segment
// when it closes, and during a long scenario step the lines that no later event can precede
// (events_told), so a long run holds only what is still open.
class TraceRecorder final : public ScenarioObserver {
 public:
  // `baud`: the rate of the telegrams on RxD (the master's); `notes`: comment lines for the top
  // of the file (without the leading '#').
  TraceRecorder(std::uint32_t baud, std::vector<std::string> notes = {});
  TraceRecorder(const TraceRecorder&) = delete;
  TraceRecorder& operator=(const TraceRecorder&) = delete;

  // The trace's bytes, line by line as they are decided, go to `out` instead of text(). Call
  // before attach(). A trace whose error() is not empty at the end is no trace: its reader
  // discards what it was given (`dpc31 run --record` writes a temporary file it then removes).
  void write_to(std::function<void(std::string_view)> out) { out_ = std::move(out); }
  void attach(Chip& chip);
  // The chip is a station of a segment (docs/segment.md, "Outputs"): its RxD is the line, handed
  // over edge by edge at their cycles when another chip drives it. Every telegram it hears
  // (characters back to back, T = `bit_cycles`) is one batch, and the recorder reads its
  // characters itself: the batch is an `rx` line when uart_encode of them gives exactly its
  // edges. Call before attach().
  void hear_line(std::uint32_t bit_cycles) { line_t_ = bit_cycles; }
  // A comment heading the current segment (e.g. the scenario line being executed).
  void heading(std::string text);
  // A comment placed among the current segment's events at `cycle`.
  void note(std::uint64_t cycle, std::string text);
  // A comment on the telegram heard from `start` (hear_line): right after its `rx` line.
  void note_heard(std::uint64_t start, std::string text);
  // The line's telegram from `start` is reported (a segment's on_telegram, in order of start):
  // no note comes for it or an earlier one, so the lines before the next `rx` line go out.
  void heard(std::uint64_t start);
  // Closes the current segment: its events in cycle order, then a `state` line at the chip's
  // current cycle (left out when nothing changed since the previous one).
  void checkpoint();
  // The last checkpoint and the `end` line. Nothing may be recorded afterwards.
  void finish();

  // The trace once finish()ed, without write_to (what went out so far before then).
  [[nodiscard]] const std::string& text() const { return kept_; }
  // Empty, or why the recording is not a valid trace (then text() must not be used).
  [[nodiscard]] const std::string& error() const { return error_; }

  // For scenario runs: hooks with the recorder as the run's observer. It attaches at the start
  // and finishes at the end; each step and each checked expect heads a segment closed by the
  // chip's state at its end (step_ends), the walk's other events become notes at their cycles.
  // The recorder must outlive the run.
  ScenarioHooks scenario_hooks();
  void run_begins(Chip& chip) override;
  void user_side_started(std::uint64_t cycle, std::string_view who, std::string_view text) override;
  // The init's heading without the walk's line (docs/trace-format.md): `firmware init (WHO): …`
  // once the chip is started, `user side: WHO` while it is not. A segment's station takes it alone.
  [[nodiscard]] std::string user_side_heading(std::string_view who) const;
  void step_begins(std::uint64_t cycle, const ScenarioStep& st, std::string_view text) override;
  void expect_checked(std::uint64_t cycle, const ScenarioStep& st, bool ok,
                      std::string_view text) override;
  void walk_note(std::uint64_t cycle, std::string_view text) override;
  // A `reset` line: the replay resets its chip there.
  void board_reset(std::uint64_t cycle) override;
  // Writes the segment's heading and its lines before `cycle` (and before an RxD batch still
  // open): no later event is older.
  void events_told(std::uint64_t cycle) override;
  // The chip's state now is the checkpoint of the segment headed last; it closes at the next
  // chip event (the step's walk notes, told before, are in it).
  void step_ends(std::uint64_t cycle) override;
  // What the sender puts on RxD next (DpMaster::on_send): the batch of edges it hands over is
  // written as an `rx` line from it when uart_encode of it gives exactly those edges.
  void telegram_sent(std::uint64_t start, std::span<const std::uint8_t> bytes,
                     UartFault fault) override;
  void run_ends(Chip& chip) override;

 private:
  struct Entry {
    std::uint64_t key;  // cycle the line is ordered by
    std::string text;
    // A walk note: after the chip's lines of its cycle, as when the runner told the notes only at
    // the step's end.
    bool walk = false;
  };
  void add(std::uint64_t key, std::string text);
  void close_rxd();
  void close_segment();
  // The headings, then the segment's entries before `upto` in cycle order (the rest stay).
  void write_entries(std::uint64_t upto);
  // A line of the trace: to out_ (or kept_); a station's (hear_line) waits in held_ while a note
  // may still come after an `rx` line before it.
  void put(std::string_view line);
  void emit(std::string line);
  void release_held(bool all);
  [[nodiscard]] std::string state_line() const;
  // A heading for the segment of the step (or expect) now told; step_ends() gives its checkpoint.
  void mark(std::string heading);

  Chip* chip_ = nullptr;
  std::uint32_t baud_;
  std::vector<std::string> notes_;
  std::function<void(std::string_view)> out_;
  std::string kept_;
  std::deque<std::string> held_;
  std::optional<std::uint64_t> heard_;  // heard(): the start of the last telegram reported
  // The segment being collected.
  std::vector<std::string> headings_;
  std::vector<Entry> seg_;
  bool closing_ = false;  // a checkpoint is due before the next chip event
  // RxD edges handed to the chip in one go (one telegram).
  std::uint64_t rxd_fed_ = 0;
  std::vector<std::pair<std::uint64_t, bool>> rxd_;
  std::optional<RxdTelegram> sent_;  // what the sender said the next batch is
  std::uint32_t line_t_ = 0;         // hear_line(): the line's bit time
  std::uint64_t line_char_end_ = 0;  // end of the stop bit of the last character heard
  std::uint64_t last_key_ = 0;
  // The state at the segment's checkpoint (cycle, line), taken when it was due.
  std::optional<std::pair<std::uint64_t, std::string>> pending_state_;
  std::string last_state_;
  bool finished_ = false;
  std::string error_;
};

// Formats a batch of RxD edges handed to the chip at `fed` as an `rx` line — when the sender
// said what it is (`sent`: characters at bit time `t` from the first start bit, with at most one
// damaged character) and uart_encode of that reproduces the edges exactly — or else as an `rxd`
// line with the raw edges.
std::string format_rxd(std::uint64_t fed, const std::vector<std::pair<std::uint64_t, bool>>& edges,
                       std::uint32_t t, const RxdTelegram* sent);

// The batch's clean characters back to back from its first edge at bit time `t`, when
// uart_encode of them gives exactly `edges` (TraceRecorder::hear_line).
std::optional<RxdTelegram> read_chars(const std::vector<std::pair<std::uint64_t, bool>>& edges,
                                      std::uint32_t t);

// --- the trace file ---

struct TraceError {
  std::string file;
  int line = 0;  // 0: the file as a whole
  std::string message;
  [[nodiscard]] std::string text() const;  // "FILE:LINE: message" (or "FILE: message")
};

enum class TraceKind : std::uint8_t { rx, rxd, wr, rd, xint, pb3, tx, state, reset, end };

struct TraceStateKey {
  std::string key;    // dp, wd, status, irr, imr, station, fdl
  std::string value;  // as written (normalised for hex and counter lists)
};

// The chip's state as a `state` line's keys, in the order the recorder writes them; the replay
// compares the chip's against the recorded ones.
std::vector<TraceStateKey> trace_state(const Chip& c);

struct TraceLine {
  int line = 0;
  TraceKind kind = TraceKind::end;
  std::uint64_t cycle = 0;  // ordering cycle: rx/rxd the feed cycle, tx its start
  std::uint64_t start = 0;  // rx: first start bit; tx: first start bit
  std::uint64_t end = 0;    // tx: end of the last stop bit
  std::uint32_t addr = 0;   // wr / rd
  std::uint8_t data = 0;    // wr data, rd expected value
  bool level = false;       // xint: 1 = active; pb3: 1 = high
  std::vector<std::uint8_t> bytes;
  UartFault fault;
  std::vector<std::pair<std::uint64_t, bool>> edges;  // rxd
  std::vector<TraceStateKey> state;
};

struct Trace {
  std::string file;
  ChipOptions chip;
  std::uint32_t baud = 0;
  // The header's `check pb3`: the DPC31's PB3 edges are expectations (`pb3` lines), every other
  // edge a mismatch. Without it (traces older than the line) PB3 is not looked at.
  bool check_pb3 = false;
  std::vector<TraceLine> lines;
};

// Why `baud` cannot be a trace's `baud` line ("" if it can): out of 1..12000000, or (with a
// `clock_hz`) no whole bit time at that clock. The parser and the recorder say it alike.
std::string trace_baud_problem(std::uint64_t baud, std::uint32_t clock_hz = 0);

bool parse_trace(std::string_view text, const std::string& file, Trace& out, TraceError& err);

// The event lines of a trace in order, one at a time: all of them, or those of one kind.
class TraceCursor {
 public:
  virtual ~TraceCursor() = default;
  // The next line, nullptr after the last; valid until take().
  virtual const TraceLine* peek() = 0;
  // The next line; the cursor moves past it.
  virtual TraceLine take() = 0;
};

// What a replay reads: a trace's header (a Trace's fields but its lines) and cursors over its
// event lines, as many as it needs at once.
class TraceSource {
 public:
  virtual ~TraceSource() = default;
  [[nodiscard]] virtual const Trace& header() const = 0;
  [[nodiscard]] virtual std::unique_ptr<TraceCursor> cursor(
      std::optional<TraceKind> only) const = 0;
};

// A trace file, checked whole in one reading line by line, then read again by its cursors: a
// trace of any length in bounded memory (a piece of the file and a line per reader; a line
// whose text before its comment is over 1 MiB, or over 64 MiB in all, is refused at its line).
// A pipe, which can be read only once, is copied to a scratch file in TMPDIR first (unlinked at
// once), at most 1 GiB. A cursor that finds the file changed since (a line that no longer
// parses, no 'end' line) throws a TraceError.
class TraceFile final : public TraceSource {
 public:
  TraceFile() = default;
  ~TraceFile() override;
  TraceFile(const TraceFile&) = delete;
  TraceFile& operator=(const TraceFile&) = delete;

  // False with `err` if `path` cannot be read or is not a trace: the error parse_trace gives its
  // text, and those of a file (a cut last line: docs/trace-format.md).
  bool open(const std::string& path, TraceError& err);
  [[nodiscard]] const Trace& header() const override { return header_; }
  [[nodiscard]] std::unique_ptr<TraceCursor> cursor(std::optional<TraceKind> only) const override;

 private:
  bool copy_pipe(std::string& error);
  bool check(TraceError& err);

  int fd_ = -1;
  Trace header_;
  std::uint64_t body_offset_ = 0;  // where the first event line begins
  int body_line_ = 0;              // its number
};

// The whole trace in memory (TraceFile's reading; its lines, however many).
bool load_trace(const std::string& path, Trace& out, TraceError& err);

// --- replay ---

struct ReplayOutcome {
  bool ok = false;
  std::string failure;  // "FILE:LINE: expected X, got Y" (the first mismatch)
  std::uint64_t final_cycle = 0;
  std::uint32_t reads = 0;
  std::uint32_t writes = 0;
  std::uint32_t telegrams_in = 0;
  std::uint32_t telegrams_out = 0;
  std::uint32_t irq_edges = 0;
  bool pb3_checked = false;  // the trace's `check pb3`
  std::uint32_t pb3_edges = 0;
  std::uint32_t states = 0;
};

ReplayOutcome replay_trace(const Trace& t);
// The lines as it goes, each from a cursor of `s`: the replay holds the lines it plays and the
// next expectation of each kind, not the trace (a TraceFile's cursor may throw a TraceError).
ReplayOutcome replay_trace(const TraceSource& s);

// Check, then replay, the file (TraceFile). Exit code: 0 every expectation held, 1 one did not
// (`message` is the first mismatch), 2 bad input (`message` is one "FILE:LINE: message" line,
// nothing run; or the file changed while it was replayed).
int replay_trace_file(const std::string& path, std::string& message,
                      ReplayOutcome* outcome = nullptr);

}  // namespace dpc31
