// A built-in DP master (class 1) that drives the chip from the bus side like a real one: it
// puts its requests on RxD as UART edges and decodes the chip's TxD with its own UART receiver.
// Between telegrams it keeps TSYN idle; it waits a slot time for the first character of an
// answer. While the chip runs, the user side (firmware) is called whenever X/INT goes active.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cpu.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/uart.hpp"
#include "txd_receiver.hpp"

namespace dpc31 {

class Segment;

// The default Cfg: 4 bytes in, 4 bytes out (byte consistency). A named array, not an
// initializer list in SlaveConfig: GCC 12 at -O3 takes the list's backing array for
// uninitialized where SlaveConfig() is inlined (a false -Wmaybe-uninitialized, issue 17).
inline constexpr std::array<std::uint8_t, 2> kDefaultCfg = {0x13, 0x23};

struct SlaveConfig {
  std::uint8_t address = 5;
  std::uint16_t ident = 0x0C31;
  std::vector<std::uint8_t> cfg{kDefaultCfg.begin(), kDefaultCfg.end()};
  std::uint8_t in_len = 4;
  std::uint8_t out_len = 4;
  bool wd_on = true;
  std::uint8_t wd_fact1 = 10;
  std::uint8_t wd_fact2 = 10;
  // Set_Prm byte 7 bit 2 (SPC3 / DPC31), ORed with user_prm byte 0 bit 2: either sets the 1 ms
  // base (false is also "not given", so user_prm's bit decides then).
  bool wd_base_1ms = false;
  std::uint8_t group_ident = 0;
  bool sync_req = false;
  bool freeze_req = false;
  std::uint8_t min_tsdr = 0;           // Set_Prm byte 3, 0 = no change
  std::vector<std::uint8_t> user_prm;  // bytes after the 7 standard ones (byte 7 first)
};

// Set_Prm's Station_Status byte for `s`: Lock_Req, with WD_On / Freeze_Req / Sync_Req as set.
[[nodiscard]] std::uint8_t prm_station_status(const SlaveConfig& s);
// Set_Prm's data unit for `s` with this Station_Status byte: the 7 standard bytes, then the
// User_Prm_Data (at least one byte, WD_Base in bit 2 of the first). DpMaster::set_prm sends it;
// a scenario builds the damaged copy of a request from it.
[[nodiscard]] std::vector<std::uint8_t> prm_du(const SlaveConfig& s, std::uint8_t station_status);

struct MasterConfig {
  std::uint8_t address = 2;
  std::uint32_t baud = 1'500'000;
  std::uint32_t slot_bits = 100;  // TSL: wait for the first character of an answer
  std::uint32_t idle_bits = 33;   // idle before each request (at least TSYN)
  // The token (use_token, docs/segment.md "The token"): TTR, the target rotation time in bit
  // times (0: no limit, every cycle of a visit is done); G, the GAP update factor (0: no GAP
  // update); HSA, the highest station address, where the GAP wraps to 0.
  std::uint64_t ttr_bits = 0;
  std::uint8_t gap_factor = 0;
  std::uint8_t hsa = 126;
};

// What one visit of the token did (DpMaster::use_token).
struct TokenVisit {
  std::uint64_t arrived = 0;        // the token's arrival: the end of its SD4, or the claim
  std::uint64_t rotation = 0;       // TRR: from the arrival before (0: the ring's first visit)
  std::uint64_t hold = 0;           // TTH = TTR - TRR in cycles (0: a late token)
  std::vector<std::size_t> polled;  // the slaves (indices) exchanged with, in order
  // In a start-up (DpMaster::begin_startup): the slave (index) of each start-up request, in order.
  std::vector<std::size_t> startup;
  std::optional<std::uint8_t> gap;  // the address the GAP update asked with FDL_Status
  bool gap_answered = false;
};

struct Exchange {
  fdl::Frame request;
  std::uint64_t request_start = 0;
  std::uint64_t request_end = 0;
  std::optional<fdl::Frame> answer;  // nullopt: no (valid) answer within the slot time
  std::uint64_t answer_start = 0;
  std::uint64_t answer_end = 0;
  // A valid telegram in the answer's place whose DA and SA are not the request's SA and DA (an
  // SC has none): not its answer, so `answer` is nullopt (docs/timing.md, "The master's wait").
  std::optional<fdl::Frame> stray;
  // Where the master's wait ended (docs/timing.md, "The master's wait"): a slot time after the
  // last character on the line when none came or the answer stopped short; the end of a telegram
  // that ended it complete (decoded or not, a bad FCS) or broken by a bad character. 0: no wait
  // (send-data-no-acknowledge).
  std::uint64_t wait_end = 0;
};

// Puts `bytes` on the chip's RxD as back-to-back UART characters from `start`: one telegram
// heard whole where the chip takes it so (Chip::hear_telegram), else whole characters or edges
// (Chip::drive_rxd_chars; a damaged telegram always). The whole request goes on the line ahead
// of time, so firmware running meanwhile cannot delay it.
// Returns the end of the last stop bit.
std::uint64_t send_on_rxd(Chip& chip, std::span<const std::uint8_t> bytes, std::uint64_t start,
                          std::uint32_t bit_cycles, UartFault fault = {});

// One answer as a master's receiver sees it, fed with the characters its UART decodes from TxD:
// the first character starts it, fdl::Assembler tells when it is complete; a bad character or a
// framing error breaks it. Used by DpMaster and by the pty bridge (lib/bridge).
class AnswerCollector {
 public:
  void reset();
  void push(const UartChar& c);
  // push() of good characters `bytes`, back to back from `start` at `bit_cycles` per bit, at once.
  void push_block(std::span<const std::uint8_t> bytes, std::uint64_t start,
                  std::uint32_t bit_cycles);
  [[nodiscard]] bool started() const { return started_; }
  // Complete or broken: no further character belongs to it. (The caller also waits until its
  // receiver is idle: a character may still be in progress.)
  [[nodiscard]] bool finished() const {
    return started_ && (bad_ || frame_.status() != fdl::Assembler::Status::need_more);
  }
  [[nodiscard]] std::uint64_t start() const { return start_; }  // first start bit
  // Characters in the whole answer, 0 until its start delimiter (and LE) tell.
  [[nodiscard]] std::size_t expected_length() const { return frame_.expected_length(); }
  [[nodiscard]] std::uint64_t end() const { return end_; }  // end of the last stop bit
  // The answer, if it is complete and decodes without error.
  [[nodiscard]] std::optional<fdl::Frame> frame() const;
  // The same into `out`, whose data unit's buffer (and the last call's) is reused: a master that
  // decodes every answer allocates none once grown.
  void frame(std::optional<fdl::Frame>& out);
  // Every character's data as received (also of a broken answer), at most kMaxFrameLength + 1.
  [[nodiscard]] const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  // Complete and decodes without error, into `d`.
  bool decodes(fdl::Decoded& d) const;

  fdl::Assembler frame_;
  fdl::Decoded decoded_;  // frame(out)'s decode, holding the buffer of the frame it replaced
  std::vector<std::uint8_t> bytes_;
  bool started_ = false;
  bool bad_ = false;
  std::uint64_t start_ = 0;
  std::uint64_t end_ = 0;
};

// What the walks say of a telegram taken for a late answer (DpMaster::on_late).
[[nodiscard]] std::string_view late_answer_text(bool after_slot);

// The request is SRD or FDL_Status to one station: the master waits for an answer.
[[nodiscard]] bool wants_answer(const fdl::Frame& request);

// What the master saw of its own requests (DpMaster::counters).
struct MasterCounters {
  std::uint64_t requests = 0;   // telegrams sent by transact / transact_raw
  std::uint64_t answered = 0;   // a complete, valid answer came back
  std::uint64_t no_answer = 0;  // an answer was due, nothing started within the slot time
  // An answer started but was broken (character or frame error), or was not addressed as the
  // request's answer (Exchange::stray).
  std::uint64_t bad_answer = 0;
  std::uint64_t noise = 0;  // noise bursts and glitches put on the line (line_noise, glitch)
  // Telegrams taken for late answers, no answer to any request (docs/timing.md, "The master's
  // wait"): one heard after a wait ended without an answer, before the next request went out,
  // or one whose first start bit came before a request's end + 11 bit times (the shortest TSDR).
  std::uint64_t late = 0;
};

// Requests of a start-up by default: enough FDL_Status for the chip's baud search from Start at
// every rate (605 at 3 and 6 Mbaud, where the 199-bit-time period of unanswered requests meets
// the 20 ms windows; docs/timing.md, "Baud_Search").
inline constexpr int kStartupTries = 1000;

class DpMaster {
 public:
  using Firmware = Cpu::Isr;  // the ISR, run (on the host CPU) while X/INT is active

  DpMaster(Chip& chip, MasterConfig m, SlaveConfig s);
  // Takes its TxD observer off the chip, which may run on (another master on it, a new one).
  ~DpMaster();
  // The chip's observer holds `this`.
  DpMaster(const DpMaster&) = delete;
  DpMaster& operator=(const DpMaster&) = delete;
  // A master on a segment (docs/segment.md): station `station` of `seg` (a sender), polling
  // `slaves` (at least one), each with its own FCB state; the first is selected. The stations'
  // firmware is the segment's, not the master's.
  DpMaster(Segment& seg, std::size_t station, MasterConfig m, std::vector<SlaveConfig> slaves);
  // The slaves such a master at `master` may poll: at least one, no address twice (each keeps one
  // FCB state, which a second entry would break), none at the master's own address (a master is
  // a station too: "master 5 at the address of station 5"); else std::invalid_argument. Returns
  // the first.
  static const SlaveConfig& checked_slaves(const std::vector<SlaveConfig>& slaves,
                                           std::uint8_t master);

  void set_firmware(Firmware isr) { cpu_ = std::make_unique<Cpu>(*chip_, std::move(isr)); }
  // A firmware with a main loop and the board's interrupt input (FirmwareHost::program).
  void set_firmware(Cpu::Program program) {
    cpu_ = std::make_unique<Cpu>(*chip_, std::move(program));
  }

  // --- several slaves (a segment; one slave is the special case of the other constructor) ---
  [[nodiscard]] std::size_t slave_count() const { return slaves_.size(); }
  // The slave the services address from now on (its SlaveConfig, target and FCB state).
  void select(std::size_t i);
  [[nodiscard]] std::size_t selected() const { return current_; }
  // startup() of every slave in turn; false if one did not reach Data_Exchange.
  bool startup_all(int tries = kStartupTries);
  // One DP cycle: Data_Exchange with every slave in order, `outputs[i]` to slave i (its out_len
  // bytes of zeros where none are given); more outputs than slaves: std::invalid_argument.
  std::vector<Exchange> dp_cycle(const std::vector<std::vector<std::uint8_t>>& outputs = {});
  // The same into `out` (one Exchange per slave), whose exchanges' buffers are reused: a long
  // run (the bench) that keeps one vector and clears the history every cycle (clear_history:
  // the history's copies reuse its spares) allocates nothing for its exchanges once grown. On
  // an exception `out` holds the exchanges made before it, none of an earlier cycle.
  void dp_cycle(const std::vector<std::vector<std::uint8_t>>& outputs, std::vector<Exchange>& out);
  // Passes the token (SD4) to `next` (its own address: keeps it); nothing is waited for.
  Exchange pass_token(std::uint8_t next);
  // The addressee of the last pass_token showed no activity within TSL (a slave, an absent
  // address): the token it held stays with it (EN 50170), so use_token goes on with that token's
  // arrival and TRR. Nothing when it held none before the pass.
  void keep_token();
  // Listens until an SD4 to this master arrives (true: the token is ours, token_rotation() is the
  // time since the last one) or `timeout` cycles of line time pass.
  bool wait_token(std::uint64_t timeout);
  // TRR: the real rotation time measured at the last token received (0 before the second).
  [[nodiscard]] std::uint64_t token_rotation() const { return trr_; }
  // One visit of the token (docs/segment.md, "The token"), once this master holds it (after
  // wait_token; a token to it already on the line is taken as wait_token takes it; else now,
  // claiming it: the ring starts here, TRR 0): Data_Exchange with its slaves
  // in turn, from where the last visit stopped, each a high-priority message cycle that starts
  // only while the rotation time since the token before is under TTR (the first cycle of a visit
  // always: a late token allows that one only); every G visits, while time remains, one address
  // of the GAP (this address + 1 up to `next` - 1, wrapping after HSA) asked with FDL_Status;
  // then the token to `next`. `outputs[i]` go to slave i (zeros where none are given; more
  // outputs than slaves: std::invalid_argument).
  TokenVisit use_token(std::uint8_t next,
                       const std::vector<std::vector<std::uint8_t>>& outputs = {});
  // The start-up under the token's rules (docs/segment.md, "The start-up under TTR"): from now on
  // the visits of use_token spend their high-priority cycles on startup_all's requests, in its
  // order (slave by slave, request by request, each a message cycle by the same rule as a DP
  // cycle), until every slave reached Data_Exchange or used `tries`; a slave waiting out its Prm
  // check ends a visit. Such a visit has no GAP poll and does not count towards G. Then the
  // visits are DP cycles again.
  void begin_startup(int tries = kStartupTries);
  [[nodiscard]] bool starting_up() const;
  // Every slave's start-up (begin_startup) reached Data_Exchange.
  [[nodiscard]] bool started_up() const;
  [[nodiscard]] std::uint8_t address() const { return cfg_.address; }
  // Sends one request after the idle time and waits for its answer. `fault` corrupts one
  // character on the wire (parity, start or stop bit; char_index -1 the last one, the ED:
  // place_fault, vocabulary.hpp). A frame fdl::encode refuses, or a fault beyond the telegram,
  // is std::invalid_argument, nothing sent; so is every service's data unit over the 244 bytes
  // of DP (fdl::kMaxDpData), before its FCB changes.
  Exchange transact(fdl::Frame req, UartFault fault = {});
  // Sends raw bytes as they are (malformed frames) and waits a slot time for an answer.
  Exchange transact_raw(const std::vector<std::uint8_t>& bytes, UartFault fault = {});
  // Lets time pass with a silent bus (cable pulled), running the firmware on interrupts.
  void idle(std::uint64_t cycles);
  // After a wait without an answer, runs on to where a next request of ours could start, as
  // sending one would: a late answer still on the line is heard out (counted, on_late told) and
  // the idle time counted from its end. On one chip nothing otherwise; on a segment it runs on
  // to the idle time after the line's last telegram (next_start watches the line there). The end
  // of a session: what a request's asked station still sends belongs to it.
  void hear_out_late_answer() { next_start(cfg_.idle_bits); }
  // Sends `ex.request` again, unchanged (same FCB), while it wants an answer and has none, at
  // most `retries` times.
  Exchange retry(Exchange ex, std::uint32_t retries);
  // Noise on the line: `bytes` as UART characters after `idle_bits` of bus idle (fewer than TSYN:
  // a telegram the chip must not accept). Nothing is waited for but the last stop bit.
  void line_noise(std::span<const std::uint8_t> bytes, std::uint32_t idle_bits);
  // A low pulse of `low_cycles` after a TSYN of bus idle; the chip's receiver samples one
  // character from it (11 bit times). The next request waits out that character and the pulse,
  // whichever ends later (a pulse longer than a character holds the line low, as a segment's
  // does). A `low_cycles` of 0 is std::invalid_argument, nothing on the line.
  void glitch(std::uint32_t low_cycles);

  // The DP services, FCB handled per EN 50170 (FCV = 1 from the second SRD on).
  Exchange fdl_status();
  Exchange slave_diag();
  Exchange set_prm(std::uint8_t station_status_extra = 0);
  // Set_Prm with this Station_Status byte as it is (Lock_Req / Unlock_Req as given).
  Exchange set_prm_status(std::uint8_t station_status);
  Exchange chk_cfg();
  Exchange get_cfg();
  Exchange data_exchange(const std::vector<std::uint8_t>& outputs, UartFault fault = {});
  Exchange global_control(std::uint8_t command, std::uint8_t groups = 0);
  Exchange read_inputs();
  Exchange read_outputs();
  Exchange set_slave_address(std::uint8_t new_address, bool no_add_change);
  // Set_Ext_Prm (SAP 53, VPC3+ DPV1) with these data.
  Exchange set_ext_prm(std::vector<std::uint8_t> du);
  // An SRD from our SAP `ssap` to the slave's SAP `dsap` (DPV1: MSAC_C1 on 51, MSAC_C2 on 49 and
  // the connection's SAP), FCB as for every SRD: a request with data, or a poll without.
  Exchange acyclic(std::uint8_t dsap, std::uint8_t ssap, std::vector<std::uint8_t> du);
  // Any service of this master with this data unit as it is (FCB as for every SRD; `srd` false:
  // SDN to the broadcast address): a Set_Prm or Global_Control of any length.
  Exchange service(std::uint8_t dsap, std::vector<std::uint8_t> du, bool srd = true);

  // The standard start-up: FDL_Status until answered, Slave_Diag, Set_Prm, Chk_Cfg, Slave_Diag
  // until the slave is ready. An unanswered Set_Prm is followed by Slave_Diag, not Chk_Cfg; after
  // an unanswered Set_Prm or Chk_Cfg a Slave_Diag that is not ready starts Set_Prm and Chk_Cfg
  // again. Returns false if it did not reach Data_Exchange within `tries`, or
  // at once when a Slave_Diag names another master in Master_Add (on_locked).
  // A slave still checking our accepted Set_Prm (Prm_Req, Master_Add ours, no fault) is polled
  // every 1 ms for up to kPrmCheckMs before it is parameterised again.
  bool startup(int tries = kStartupTries);
  static constexpr std::uint64_t kPrmCheckMs = 10;
  // A master restart: FDL_Status until answered, Slave_Diag, Set_Prm, Chk_Cfg, then Slave_Diag
  // until ready. Unlike startup it parameterises even a slave that reports itself ready. Every
  // request without an answer is repeated up to `retries` times.
  bool restart(std::uint64_t tries, std::uint32_t retries);
  // Parses the six standard diag bytes: ready = no Station_Not_Ready, no Prm_Req, no faults.
  static bool diag_ready(const fdl::Frame& diag_answer);

  std::uint32_t bit_cycles() const { return t_; }
  // TSL in clocks: the wait after a request's last stop bit for its answer's first start bit.
  std::uint64_t slot_cycles() const { return std::uint64_t{cfg_.slot_bits} * t_; }
  const SlaveConfig& slave() const { return slave_; }
  SlaveConfig& slave() { return slave_; }
  std::uint8_t target() const { return target_; }
  void set_target(std::uint8_t a) { target_ = a; }
  const std::vector<Exchange>& history() const { return history_; }
  // Forgets history() (the counters stay): a long run (dpc31 soak) calls it so memory does not
  // grow with time. The exchanges forgotten lend their memory to the next ones (spare_).
  void clear_history() {
    std::swap(history_, spare_);
    history_.clear();
  }
  // Forgets all of history() but its last exchange: the scenario runner calls it once a step is
  // reported, so that the memory of `dpc31 run` does not grow with the run.
  void keep_last_exchange() {
    if (history_.size() > 1) history_.erase(history_.begin(), history_.end() - 1);
  }
  // Forgets history()[first, last): a DPV1 service folds its polls (Dpv1Master::polled).
  void forget_exchanges(std::size_t first, std::size_t last) {
    last = std::min(last, history_.size());
    if (first < last) {
      history_.erase(history_.begin() + static_cast<std::ptrdiff_t>(first),
                     history_.begin() + static_cast<std::ptrdiff_t>(last));
    }
  }
  [[nodiscard]] const MasterCounters& counters() const { return counters_; }
  // Who moves time while the master waits. Empty: the master steps its chip itself (and runs
  // its firmware's CPU). Set: a scheduler of the caller's does (the SystemC model,
  // docs/systemc.md): it returns once the chip has reached `cycle`, or earlier when a step of the
  // chip stopped (Chip::request_stop, wake_on_txd).
  std::function<void(std::uint64_t cycle)> scheduler;
  // Called after each wait, the chip's stop cleared: it may throw to end the master's call there
  // (Python: an observer's exception ends the call at once). Empty: the master goes on.
  std::function<void()> waited;
  // A telegram taken for a late answer (counters().late, docs/timing.md "The master's wait"):
  // the end of its last stop bit and where it came (`after_slot`: on the line after a wait that
  // ended without an answer; else inside a request or its shortest TSDR). `dpc31 run`'s walks
  // tell it.
  std::function<void(std::uint64_t end, bool after_slot)> on_late;
  // A start-up found `slave` locked by master `by` (its Slave_Diag's Master_Add): the master
  // leaves it alone, as a DP master does, and that slave's start-up ends without Data_Exchange.
  std::function<void(std::uint8_t slave, std::uint8_t by)> on_locked;
  // The slaves the last start-up of each found locked (slave -> the master its Slave_Diag's
  // Master_Add names): the doors without on_locked (Python's startup() returns a bare bool) read
  // why a start-up failed here. A later start-up's Slave_Diag without a lock takes the slave off.
  [[nodiscard]] const std::map<std::uint8_t, std::uint8_t>& locks() const { return locks_; }
  // Told of every telegram just before it goes on RxD (requests, line noise): its first start
  // bit, its bytes and the fault it carries. A trace recorder writes the batch from it.
  std::function<void(std::uint64_t start, std::span<const std::uint8_t> bytes, UartFault fault)>
      on_send;

  // At most one output per slave (dp_cycle, use_token; a caller's own loop over the slaves):
  // std::invalid_argument naming both counts.
  void check_outputs(const std::vector<std::vector<std::uint8_t>>& outputs) const;

 private:
  fdl::Frame request(std::optional<std::uint8_t> dsap, std::vector<std::uint8_t> du,
                     bool srd = true);
  // Makes `f`, its data unit given, the selected slave's request (its buffers kept).
  void make_request(fdl::Frame& f, std::optional<std::uint8_t> dsap, bool srd = true);
  // Slave i's outputs of a DP cycle (dp_cycle, use_token): outputs[i], or the selected slave's
  // out_len zeros where none are given.
  [[nodiscard]] std::span<const std::uint8_t> outputs_of(
      const std::vector<std::vector<std::uint8_t>>& outputs, std::size_t i) const;
  // data_exchange and transact into `ex` (its buffers reused): dp_cycle's filling form.
  void data_exchange(std::span<const std::uint8_t> outputs, UartFault fault, Exchange& ex);
  void transact(UartFault fault, Exchange& ex);  // ex.request sent
  void run_until(std::uint64_t cycle);
  void end_wait();  // after a wait: the Python door's `waited`
  // transact / transact_raw: `bytes` on the line, then the answer awaited unless `no_answer`,
  // into `ex`, whose request is the exchange's (and the history's) request.
  // `req`: the request as it decodes (nullptr: it does not), whose answer is mirrored.
  void send(std::span<const std::uint8_t> bytes, UartFault fault, bool no_answer, Exchange& ex,
            const fdl::Frame* req);
  void wait_answer(Exchange& ex, const fdl::Frame* req);  // its answer, if any, into `ex`
  [[nodiscard]] std::size_t length_known(std::uint64_t first) const;
  // The characters on TxD whose stop sample is due by now: chars_, then rx_.due().
  std::uint64_t look();  // the line up to now(), which it returns
  // The first start bit a telegram of ours may have at `at` or later: `idle_bits` after the end
  // of the last telegram on the line, ours or another station's (as far as look() heard it).
  [[nodiscard]] std::uint64_t send_time(std::uint64_t at, std::uint32_t idle_bits) const;
  // send_time from now, the line watched up to it (on a segment always, on one chip after a wait
  // without an answer, watch_late_): a telegram heard there moves it to `idle_bits` after that
  // telegram's end (after such a wait: a late answer, counted and told).
  std::uint64_t next_start(std::uint32_t idle_bits);
  // Runs the line up to our first start bit at `start`, woken by another station's start bit;
  // on a segment no firmware runs past `start` (Segment::run_to_send), and true: it got there
  // and nobody else drove meanwhile (nothing new for look()).
  bool wait_to_send(std::uint64_t start);
  void late_answer(std::uint64_t end, bool after_slot);  // counted, and on_late told
  [[nodiscard]] std::uint64_t now() const;
  std::uint64_t put_on_line(std::span<const std::uint8_t> bytes, std::uint64_t start,
                            UartFault fault);

  // One slave's start-up as a sequence of message cycles (startup(), begin_startup): where it
  // stands and how many of its `tries` it has used.
  struct Startup {
    enum class Phase : std::uint8_t { fdl_status, diag, prm, cfg, ready, failed };
    Phase phase = Phase::fdl_status;
    int tries = kStartupTries;
    int n = 0;
    std::uint64_t check_until = 0;  // our accepted Set_Prm's start + kPrmCheckMs; 0: none yet
    std::uint64_t wait_until = 0;   // a slave checking our Set_Prm is asked again from here
    bool unconfirmed = false;       // our last Set_Prm or Chk_Cfg went unanswered
  };
  // The selected slave's next start-up request; false when none went out (it is over, or it
  // waits until wait_until).
  bool startup_request(Startup& s);

  struct SlaveState {
    SlaveConfig config;
    std::uint8_t target = 0;
    bool fcb = true;
    bool fcv_started = false;
  };

  Chip* chip_ = nullptr;         // the one chip (single-slave master)
  ObserverId txd_observer_ = 0;  // on chip_
  Segment* seg_ = nullptr;       // or the segment and this master's station on it
  std::size_t station_ = 0;
  std::vector<SlaveState> slaves_;  // the others' state while one is selected
  std::size_t current_ = 0;
  std::uint64_t token_at_ = 0;  // when the token last came
  std::uint64_t trr_ = 0;
  bool holding_ = false;        // the token is ours (received or claimed, not passed on)
  bool passed_held_ = false;    // the last pass_token passed a token held (keep_token)
  std::size_t next_slave_ = 0;  // where the next visit's cycles begin
  std::uint64_t visits_since_gap_ = 0;
  std::optional<std::uint8_t> gap_next_;        // the GAP address asked next (none: the first)
  std::vector<Startup> startups_;               // each slave's start-up under the token
  std::map<std::uint8_t, std::uint8_t> locks_;  // locks(): slave -> the master that holds it
  MasterConfig cfg_;
  SlaveConfig slave_;
  std::uint32_t t_;
  std::uint8_t target_;
  TxdReceiver rx_;
  AnswerCollector answer_;
  std::vector<UartChar> chars_;
  bool fcb_ = true;  // toggled before every SRD with FCV
  bool fcv_started_ = false;
  bool wake_on_txd_ = false;    // waiting for an answer whose length is not known yet
  std::uint64_t bus_free_ = 0;  // where our own last exchange left the line free
  std::uint64_t line_end_ = 0;  // end of the last character another station drove (look())
  // The last wait ended without an answer: the asked station may still answer late, so the
  // line is watched up to the next request's start (next_start).
  bool watch_late_ = false;
  bool late_heard_ = false;  // that wait ended at a late start bit: the watch counts it
  std::unique_ptr<Cpu> cpu_;
  std::vector<Exchange> history_;
  // The exchanges clear_history() forgot last: history() takes each new exchange as a copy into
  // one of them, whose frames' data units keep their capacity (no allocation once grown).
  std::vector<Exchange> spare_;
  MasterCounters counters_;
  std::vector<std::uint8_t> tx_;  // transact's request as sent (one buffer for every request)
};

}  // namespace dpc31
