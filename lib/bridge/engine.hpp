// The chip side of `dpc31 bridge` (docs/bridge.md): one chip with an example firmware on its host
// CPU, fed with the bytes a DP master program writes and giving back the bytes the chip sends.
// No operating system here: the pty, the wall clock and the pacing are the caller's
// (tools/cli/bridge.cpp, with pacing.hpp), so tests can drive it cycle-exactly.
//
// With several slaves (Setup::slaves, --slave) the line is a Segment (session/segment.hpp): the
// client is the segment's sender "master", every station a chip with its user side.
//
// Client bytes are split into telegrams by their SD and LE (fdl::Assembler); each telegram goes on
// RxD as 11-bit characters at the bridge's baud rate after TSYN (33 bit times) of bus idle,
// measured from the end of the last telegram on the bus (request or answer). A request that wants
// an answer holds the bus until the chip's answer is complete or a slot time has passed, as a
// master would. TxD is decoded by a UART receiver like DpMaster's; every character becomes one
// output byte.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cpu51_module.hpp"
#include "dp_master.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/hex.hpp"
#include "firmware.h"
#include "firmware_host.hpp"
#include "segment.hpp"
#include "station.hpp"

namespace dpc31::bridge {

// More client bytes than this waiting for the bus are dropped: the client writes faster than
// the line can carry them (a master never does: it waits for each answer).
inline constexpr std::size_t kMaxQueuedBytes = 64 * 1024;
// Consecutive bytes that cannot be a telegram go on the bus as one run of at most this many
// (one log line each), not one byte at a time.
inline constexpr std::size_t kMaxGarbageRun = 256;

// How much the log says (docs/bridge.md, "The log"). events: state changes and faults (the
// chip's messages, DP and watchdog states, a port's new value, the bridge's notes, broken or late
// telegrams); telegrams: also every telegram both ways and every port write.
enum class LogDetail : std::uint8_t { events, telegrams };

struct Setup {
  ChipOptions chip;
  LogDetail log_detail = LogDetail::events;
  std::uint32_t baud = 19200;  // one of kBaudRates
  std::uint8_t address = 5;    // the station address the firmware gives the chip
  const dpc31_firmware* firmware = nullptr;
  // Instead of `firmware`: an image on an 80C32 beside the chip (--cpu 80c32, docs/cpu.md).
  std::optional<Cpu51Config> cpu;
  Cpu51Image cpu_image;
  std::uint32_t slot_bits = 100;  // how long a request waits for the first answer character
  // Not empty: these stations on one segment instead of the one chip above (`chip`, `address`,
  // `firmware` and `cpu` then unused); stations_problem() must find nothing (else the Engine
  // throws std::invalid_argument with its line).
  std::vector<SlaveSpec> slaves;
};

// The names the log and the capture give the line's parties besides the stations (docs/bridge.md).
inline constexpr std::string_view kMasterName = "master";  // the client: what it sent
inline constexpr std::string_view kBridgeName = "bridge";  // the bridge's own NOTE and LOG lines

// A station on the bridge's line: a chip with its user side, named in the log and the capture
// ("slave5"). One without --slave, the --slave list with it.
struct Station {
  std::string name;
  std::uint8_t address = 0;
};

// One telegram on the line, as the bridge put it on RxD (the master's) or decoded it from TxD (a
// station's answer): its first start bit, the end of its last stop bit, who sent it, its bytes.
struct LineTelegram {
  std::uint64_t start = 0;
  std::uint64_t end = 0;
  std::string_view sender;  // kMasterName or a station's name
  std::span<const std::uint8_t> bytes;
};
using LineSink = std::function<void(const LineTelegram&)>;

// One log line: its cycle, a tag ("RxD", "TxD", "PORT", "STATE", "CHIP", "NOTE"), the station it
// is about (kMasterName for RxD, kBridgeName for NOTE and LOG, else a station's name) and text.
// Lines come in cycle order (those of one cycle in the order they arose): the engine holds each
// line until no line with a smaller cycle can come any more (a request goes on RxD up to TSYN
// ahead; an answer's line is known at its end but stamped with its start).
using LogSink = std::function<void(std::uint64_t cycle, std::string_view tag,
                                   std::string_view station, const std::string&)>;

// The bridge's log bound at the telegrams level (docs/bridge.md, "The log"): a line at 12 Mbaud
// carries up to about 80 000 telegrams a second; the events level has LogLimiter::kBurst.
inline constexpr std::uint32_t kTelegramBurst = 200'000;

// "FDL_Status 2->5 FC 49", "DL 5->2 SAP 60->62 DU 02 05 00 FF 0D 04", "broken (bad_fcs)".
std::string telegram_summary(std::span<const std::uint8_t> bytes);
// "10 05 02 49 50 16".
using dpc31::hex_bytes;

class Engine {
 public:
  // Builds the chip (or the segment) and runs each firmware's main() (which starts its chip).
  Engine(const Setup& setup, LogSink log);
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // Bytes the client wrote. Each complete telegram (and each run of bytes that cannot start one,
  // up to kMaxGarbageRun bytes a run) queues for the bus; an incomplete telegram waits for more
  // bytes or flush_partial(). Beyond kMaxQueuedBytes waiting, bytes are dropped, and reported in
  // one line per second of chip time at most ("N bytes dropped in the last ... ms").
  void feed(std::span<const std::uint8_t> bytes);
  // The client paused: an incomplete telegram goes on the bus as it is (the chip counts it).
  void flush_partial();
  [[nodiscard]] bool partial() const { return !partial_.empty(); }
  // A request is queued, still on the line, or not yet answered (nor timed out).
  [[nodiscard]] bool busy() const;

  // Runs the chip and its firmware to `cycle` (a firmware access may end up to 3 clocks later),
  // putting queued requests on RxD as the bus allows.
  void run_until(std::uint64_t cycle);
  // Runs until no request is queued or on the line and none waits for its answer (answered, or
  // its slot time passed), at most `max_cycles`; stops right after the last answer character
  // (or the request's last stop bit). Returns whether it is no longer busy().
  bool settle(std::uint64_t max_cycles);

  // Every telegram on the line from now on, in the order each is complete (a request when it goes
  // on RxD, an answer at its last stop bit): the capture (--pcap).
  void on_line(LineSink sink) { line_ = std::move(sink); }
  [[nodiscard]] const std::vector<Station>& stations() const { return stations_; }

  // TxD characters decoded since the last call, in order.
  std::vector<std::uint8_t> take_output();
  // The client went away: its incomplete telegram and every queued telegram that has not reached
  // the bus yet are dropped (what is on the line finishes), so that the next client's requests
  // are not stuck behind a flood of its bytes; one line says how much. A run of unanswered
  // requests ends with it (its count is written).
  void client_gone();
  // Reports bytes dropped since the last report, whether or not a second has passed.
  void report_dropped();

  // The first station's chip; station `i`'s (in the order of stations()).
  [[nodiscard]] const Chip& chip(std::size_t i = 0) const { return *slaves_.at(i).chip; }
  [[nodiscard]] std::uint64_t cycle() const { return seg_ ? seg_->cycle() : solo_->cycle(); }
  [[nodiscard]] std::uint32_t bit_cycles() const { return t_; }
  // The 80C32 board (nullptr: the firmware runs on the host CPU).
  [[nodiscard]] Cpu51Module* cpu51() { return m51_.get(); }
  // An event line at the current cycle.
  void note(const std::string& text);
  // Every line held back goes to the sink now: the owner calls it at the end (nothing more will
  // come), before the sink goes away. A run of unanswered requests ends here (its count written).
  void flush_log();

 private:
  struct Request {
    std::vector<std::uint8_t> bytes;
    bool wants_answer = false;
    bool garbage = false;  // bytes that cannot be a telegram (merged with the next such run)
  };
  // Closes a run of unanswered requests that ends otherwise than by an answer: "N requests
  // without an answer, then HOW" (no line when there is none).
  void end_unanswered_run(std::string_view how);
  void queue_group(std::vector<std::uint8_t> bytes, bool garbage);
  void drop(std::size_t bytes);
  void start_next();
  // The first cycle a queued request may start: TSYN after the last telegram on the line.
  std::uint64_t next_start();
  void collect();  // TxD characters up to now: output, answer, end of the exchange
  void finish_answer(AnswerCollector& a, std::string_view how);
  void step_to(std::uint64_t cycle);
  std::uint64_t next_wake(std::uint64_t limit) const;
  // Station `i`'s chip, its user side, and the log's view of it.
  void add_slave(std::size_t i, Chip& chip, const SlaveSpec& spec);
  void watch_slave(std::size_t i);
  void watch_answers(std::size_t i, Chip& chip);
  void check_states(std::size_t i, std::uint64_t cycle);
  void port_written(std::size_t i, std::uint64_t cycle, const std::string& module,
                    const std::string& port, unsigned index, std::uint32_t value);
  // The request on the line: on the one chip's RxD, or sent by the segment's master station.
  std::uint64_t put_on_line(std::span<const std::uint8_t> bytes, std::uint64_t start);
  // How far ahead of the line's time a request may go on the line: TSYN on the one chip (its RxD
  // takes edges ahead), none on a segment (every station hears it at its cycle).
  [[nodiscard]] std::uint64_t lead() const { return seg_ ? 0 : std::uint64_t{kTsynBits} * t_; }
  // Who drove the character whose start bit is at `start`: the chip whose answer covered it (of
  // two, the first, which keeps the line).
  [[nodiscard]] std::string_view sender_of(std::uint64_t start) const;
  void add_line(std::uint64_t cycle, std::string_view tag, std::string_view who, std::string text);
  // A telegram line, at the telegrams level or when it is broken or `how` says what is wrong.
  void log_telegram(std::uint64_t cycle, std::string_view tag, std::string_view who,
                    std::span<const std::uint8_t> bytes, std::string_view how);
  // Hands over the held lines with a cycle up to `upto`.
  void release_log(std::uint64_t upto);
  // No line with a smaller cycle can come: the chip's time, or an earlier start still pending.
  [[nodiscard]] std::uint64_t log_horizon() const;

  // What the engine keeps of one station.
  struct Slave {
    Chip* chip = nullptr;
    UserSide user;  // empty with the 80C32 (m51_)
    DpState dp = DpState::Wait_Prm;
    WdState wd = WdState::Baud_Search;
    std::vector<std::uint32_t> port;  // the last value logged per port (events level)
    std::vector<bool> port_logged;    // whether a value was logged for the port yet
  };

  Setup setup_;
  LogSink log_;
  LineSink line_;
  std::vector<Station> stations_;  // never resized after construction: the log keeps their names
  std::unique_ptr<Chip> solo_;     // the one chip (no --slave)
  std::vector<Slave> slaves_;      // parallel to stations_; outlives seg_'s CPUs that run them
  std::unique_ptr<Segment> seg_;   // or the segment (--slave)
  std::size_t master_ = 0;         // the client's station on seg_
  // The answers the segment's chips armed (their first start bit, the end of their last stop bit,
  // the station), for sender_of and for TSYN after whatever a chip drove.
  struct Sent {
    std::uint64_t start = 0;
    std::uint64_t end = 0;
    std::size_t station = 0;
  };
  std::deque<Sent> sent_;
  std::uint32_t t_;
  std::unique_ptr<Cpu> cpu_;  // the one chip's host CPU
  std::unique_ptr<Cpu51Module> m51_;

  fdl::Assembler in_;                  // the client's bytes, split into telegrams
  std::vector<std::uint8_t> partial_;  // the telegram being assembled
  std::deque<Request> queue_;
  std::size_t queued_bytes_ = 0;
  std::uint64_t dropped_ = 0;           // bytes dropped since the last report
  std::uint64_t dropped_since_ = 0;     // the cycle of the first of them
  std::uint64_t last_drop_report_ = 0;  // the cycle of the last report

  bool in_flight_ = false;  // a request is on the bus and its answer is awaited
  std::uint64_t request_end_ = 0;
  std::uint64_t slot_end_ = 0;
  std::uint64_t unanswered_ = 0;  // requests in a row without an answer within the slot time
  std::uint64_t bus_free_ = 0;    // end of the last telegram on the bus
  TxdReceiver rx_{0, 0};          // the master's receiver on TxD
  std::vector<UartChar> chars_;
  AnswerCollector answer_;  // of the request in flight
  AnswerCollector stray_;   // characters while no request is in flight (a late answer)
  std::vector<std::uint8_t> out_;

  struct HeldLine {
    std::uint64_t cycle;
    std::string_view tag;  // one of the literal tags
    std::string_view who;  // kMasterName, kBridgeName or a name in stations_
    std::string text;
  };
  std::vector<HeldLine> held_;  // in the order they arose
  LogLimiter limiter_;          // the log never floods (docs/bridge.md, "The log")
};

}  // namespace dpc31::bridge
