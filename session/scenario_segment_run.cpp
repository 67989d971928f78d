// Segment scenarios: the runner (scenario_segment.hpp). Every station is a chip with its user side
// on its own host CPU, every master a DpMaster on the segment; the bus check sees every telegram.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/pdu.hpp"
#include "firmware_host.hpp"
#include "responder.hpp"
#include "scenario_expect.hpp"
#include "scenario_lex.hpp"
#include "scenario_segment.hpp"
#include "segment.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

namespace {

// `cycles` in bit times of `t` clocks, as the checks that take bit times are written: `11`, or
// `11 3/32` where it is no whole number of them.
std::string bit_times(std::uint64_t cycles, std::uint64_t t) {
  const std::uint64_t rest = cycles % t;
  return rest == 0 ? fmt::format("{}", cycles / t) : fmt::format("{} {}/{}", cycles / t, rest, t);
}

class SegmentRun {
 public:
  SegmentRun(const SegmentScenario& s, const LineSink& walk, const LineSink& errors,
             SegmentObserver* observer)
      : s_(s),
        walk_(walk),
        errors_(errors),
        observer_(observer != nullptr ? observer : &quiet_),
        seg_(s.baud),
        check_(BusTiming{seg_.bit_cycles(), 11, s.slot_bits, 33,
                         s.masters.size() > 1 ? s.ttr_bits : 0, masters()},
               [this](const LogRecord& r) {
                 states_through(r.cycle);  // a check's line in cycle order (token_lost)
                 print(r.cycle, r.text);
               }) {
    check_.on_answer = [this](std::uint64_t delay) { answered(delay); };
  }

  int run() {
    build();
    for (const SegmentStep& st : s_.steps) {
      const std::string text = fmt::format("line {}: {}", st.line, st.text);
      say(seg_.cycle(), text);
      observer_->step_begins(st, text);
      act(st);
      settle();
      observer_->step_ends(st);
    }
    // The run ends on a quiet line: an answer a chip is still sending is finished first, so that
    // every output holds it whole (a station's trace ends after its last `tx`).
    quiet();
    settle();
    seg_.flush();
    states_in_order();
    check_.flush();
    seg_.align();  // the observers' chips at the line's time (docs/segment.md)
    // What the chips' logs still owe (a fold's `last line repeated` note): before the last line.
    for (const auto& st : stations_) seg_.chip(st->index).set_log_sink({});
    observer_->run_ends(seg_, passed_, failed_);
    say(seg_.cycle(), fmt::format("{} expects passed, {} failed", passed_, failed_));
    return failed_ == 0 ? 0 : 1;
  }

 private:
  struct Station {
    std::size_t index = 0;
    std::unique_ptr<Responder> responder;
    FirmwareHost* firmware = nullptr;  // in hosts_
    DpState dp = DpState::Wait_Prm;
    WdState wd = WdState::Baud_Search;
    std::optional<std::uint64_t> left_dp_control;  // the cycle DP_Control last ended
    std::uint64_t request_end = 0;    // the end of the last request to it the chip took
    std::uint64_t entered = 0;        // the cycle its DP state last changed
    std::uint64_t entered_after = 0;  // ... and the end of the request before it
  };

  std::vector<std::uint8_t> masters() const {
    std::vector<std::uint8_t> out;
    for (const SegmentMaster& m : s_.masters) out.push_back(m.address);
    return out;
  }

  // A line of the walk. The bus check's own lines (print) fold a violation repeated back to back;
  // any other line ends such a run, its note right after it (docs/segment.md, "Bus checks").
  void say(std::uint64_t cycle, const std::string& text) {
    states_in_order();
    check_.end_repeats();
    print(cycle, text);
  }
  void print(std::uint64_t cycle, const std::string& text) {
    if (walk_) walk_(fmt::format("[cycle {:>10}] {}", cycle, text));
  }
  // The chips' state changes, held until the next other line: in one round of the line each chip
  // runs on its own, so two chips' changes come in station order, not in cycle order.
  void states_in_order() { states_through(UINT64_MAX); }
  // Those up to `cycle`; the rest stay held. A bus check's line found late (token_lost, at the
  // step's end: stamped TTO after the line fell idle) comes after those before it only.
  void states_through(std::uint64_t cycle) {
    if (telling_states_) return;  // a check's note among them (end_repeats): they are in order
    telling_states_ = true;
    std::stable_sort(states_.begin(), states_.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    const auto end = std::find_if(states_.begin(), states_.end(),
                                  [cycle](const auto& s) { return s.first > cycle; });
    for (auto it = states_.begin(); it != end; ++it) {
      check_.end_repeats();
      print(it->first, it->second);
    }
    states_.erase(states_.begin(), end);
    telling_states_ = false;
  }

  void build() {
    for (const SegmentStation& def : s_.stations) {
      auto st = std::make_unique<Station>();
      st->index = seg_.add_chip(def.name, def.chip);
      observer_->station_added(seg_, st->index);
      Chip& chip = seg_.chip(st->index);
      // The chip's own log (info and up, folded by the chip) as the single chip's walk has it,
      // named by station as its other lines: held with the state changes, in cycle order.
      chip.set_log_sink(
          [this, name = def.name](const LogRecord& r) {
            states_.emplace_back(r.cycle, fmt::format("{}: chip: {}", name, r.text));
          },
          LogLevel::info);
      DirectBus bus(chip);
      // The words of the single chip's trace heading (scenario_run.cpp's user_side_name).
      std::string who = "the built-in user side";
      if (def.firmware.empty()) {
        ResponderConfig rc;
        rc.slave = def.slave;
        rc.user_watchdog = def.user_watchdog;
        rc.user_wd_value = def.user_wd_value;
        st->responder = std::make_unique<Responder>(rc);
        st->responder->init(bus);
        Responder* r = st->responder.get();
        // Nothing reads what the responder records: it is forgotten at once (memory stays flat).
        seg_.set_firmware(st->index, [r](BusPort& b) {
          r->isr(b);
          r->keep_last_output();
          r->interrupts.clear();
        });
      } else {
        const dpc31_firmware& fw = find_firmware(def.firmware);
        who = fmt::format("the host firmware {}", fw.name);
        hosts_.push_back(std::make_unique<FirmwareHost>(fw));
        st->firmware = hosts_.back().get();
        st->firmware->name_station(def.slave.address);
        // Its port writes as the single chip's walk shows them, named by station, held with the
        // state changes: a chip runs ahead of the others in a round (states_in_order).
        const FirmwareHost* host = st->firmware;
        st->firmware->on_port = [this, host, name = def.name, &chip](
                                    std::uint64_t cycle, unsigned port, std::uint32_t value) {
          states_.emplace_back(
              cycle, fmt::format("{}: {}: {} = {} at {:.3f} us", name, host->firmware().name,
                                 host->port_name(port), scenario_expect::port_text(value),
                                 static_cast<double>(cycle) * 1e6 / chip.clock_hz()));
        };
        st->firmware->init(bus, def.slave.address);
        seg_.set_firmware(st->index, st->firmware->program());
      }
      Station* raw = st.get();
      const std::string name = def.name;
      chip.on_state_change([this, raw, name, &chip](std::uint64_t cycle) {
        const DpState dp = chip.dp_state();
        const WdState wd = chip.wd_state();
        if (dp == raw->dp && wd == raw->wd) return;
        if (raw->wd == WdState::DP_Control && wd != WdState::DP_Control)
          raw->left_dp_control = cycle;
        if (dp != raw->dp) {
          raw->entered = cycle;
          raw->entered_after = raw->request_end;
        }
        raw->dp = dp;
        raw->wd = wd;
        states_.emplace_back(
            cycle, fmt::format("{}: {} / {}", name, dp_state_name(dp), wd_state_name(wd)));
      });
      const std::uint8_t address = def.slave.address;
      chip.on_telegram([this, raw, address](const Telegram& t) {
        if (t.from_chip) {
          if (t.end >= tx_until_) {
            tx_from_ = t.start;
            tx_until_ = t.end;
          }
          return;
        }
        // A request to this station, taken at its last stop sample: before anything it causes.
        const fdl::Decoded d = fdl::decode(t.bytes);
        if (d.error == fdl::Error::none && d.frame.sd != fdl::SD4 && d.frame.da == address &&
            fdl::is_request(d.frame.fc)) {
          raw->request_end = t.end;
        }
      });
      observer_->user_side_started(st->index, who);
      stations_.push_back(std::move(st));
    }
    for (const std::string& name : s_.senders) senders_[name] = seg_.add_sender(name);
    for (const SegmentMaster& m : s_.masters) {
      // Slave i of the DpMaster is m.slaves[i]: the walk and `expect visit` name a visit's
      // slaves by these positions.
      std::vector<SlaveConfig> slaves;
      for (const std::uint8_t a : m.slaves) {
        const auto def =
            std::find_if(s_.stations.begin(), s_.stations.end(),
                         [a](const SegmentStation& d) { return d.slave.address == a; });
        if (def == s_.stations.end()) {
          throw std::invalid_argument(fmt::format("master {}: no station {}", m.address, a));
        }
        slaves.push_back(def->slave);
      }
      const std::size_t station = seg_.add_sender(master_station_name(m.address));
      MasterConfig mc{m.address, s_.baud, s_.slot_bits};
      mc.ttr_bits = m.ttr_bits;
      mc.gap_factor = m.gap_factor;
      mc.hsa = m.hsa;
      masters_.push_back(std::make_unique<DpMaster>(seg_, station, mc, slaves));
      masters_.back()->on_locked = [this, a = m.address](std::uint8_t slave, std::uint8_t by) {
        say(seg_.cycle(), fmt::format("master {}: station {} is locked by master {} (its "
                                      "Slave_Diag's Master_Add): not parameterised, its start-up "
                                      "ends",
                                      a, slave, by));
      };
      // Held with the state changes: the master may take the late telegram before the segment
      // tells of it.
      masters_.back()->on_late = [this, a = m.address](std::uint64_t end, bool after_slot) {
        states_.emplace_back(end, fmt::format("master {}: {}", a, late_answer_text(after_slot)));
      };
      visits_.emplace_back();
    }
    observer_->stations_added(seg_);
    seg_.on_telegram = [this](const LineTelegram& t) {
      states_in_order();
      check_.telegram(t, seg_.name(t.from));
      telegram(t);
      observer_->telegram(t);
    };
    seg_.on_collision = [this](const Collision& c) {
      states_in_order();
      check_.collision(c, seg_.name(c.first), seg_.name(c.second));
    };
  }

  // The last request to each station from its locking master (expect watchdog_expired).
  void telegram(const LineTelegram& t) {
    const fdl::Decoded d = fdl::decode(t.bytes);
    say(t.start, fmt::format("{}: {}", seg_.name(t.from), scenario_lex::bytes_text(t.bytes)));
    if (d.error != fdl::Error::none || d.frame.sd == fdl::SD4) return;
    const fdl::Frame& f = d.frame;
    if (!fdl::is_request(f.fc)) {
      // A Slave_Diag answer shows whom the station is locked to (Master_Add, FFh none).
      if (f.ssap == sap::Slave_Diag && f.du.size() >= pdu::SlaveDiag::kStandard)
        locked_to_[f.sa] = f.du[3];
      return;
    }
    // "The 'DP_Control' state serves response time monitoring of the DP master (Master_Add)"
    // (SPC3 p.25): only its requests restart the timer, another master's (a class-2 master's
    // MSAC_C2) do not. Checked before the request is served, as the chip does.
    const auto lock = locked_to_.find(f.da);
    if (lock != locked_to_.end() && lock->second == f.sa) last_request_[f.da] = t.end;
    if (f.dsap != sap::Set_Prm || f.du.empty()) return;
    // A Set_Prm locks a station no other master holds (Lock_Req) and unlocks it (Unlock_Req);
    // while another master holds it, it is ignored (DPC31 p.28).
    std::uint8_t& holder = locked_to_.try_emplace(f.da, pdu::SlaveDiag::kNoMaster).first->second;
    if (holder != pdu::SlaveDiag::kNoMaster && holder != f.sa) return;
    if ((f.du[0] & pdu::SetPrm::Unlock_Req) != 0)
      holder = pdu::SlaveDiag::kNoMaster;
    else if ((f.du[0] & pdu::SetPrm::Lock_Req) != 0)
      holder = f.sa;
  }

  // An answer as the bus check pairs it with its request (BusCheck::on_answer): its delay for
  // `expect tsdr`, so that both call the same telegrams answers (docs/segment.md "Bus checks").
  void answered(std::uint64_t delay) {
    delays_.count += 1;
    delays_.min = std::min(delays_.min, delay);
    delays_.max = std::max(delays_.max, delay);
  }

  // The line to the end of the telegram on it (the last one relayed whole, or an answer a chip
  // still sends): a master returns at the last stop sample of the answer or token it took,
  // inside its stop bit, and the next step begins on a quiet line (a `send after=33bits` then
  // keeps TSYN).
  void quiet() {
    const std::uint64_t end = std::max(tx_until_, whole_end());
    if (end > seg_.cycle()) seg_.run_until(end);
  }
  // The end of the last stop bit of the telegram last relayed whole (0: none yet).
  std::uint64_t whole_end() const {
    const std::size_t n = seg_.whole_bytes().size();
    return n == 0 ? 0 : seg_.whole_start() + n * kUartCharBits * seg_.bit_cycles();
  }

  // Moves no time (an expect is checked at the step's cycle, `run T` lasts T). A telegram that
  // ended by now is over at the step's end unless one goes on at once (a character back to back
  // would join it): the segment would tell of it only a character time later, after the next
  // step's lines; told now, the walk prints it before them and the checks see it
  // (docs/decisions.md, the twenty-third session).
  void settle() {
    const std::uint64_t now = seg_.cycle();
    const bool whole_on = seg_.whole_start() <= now && now < whole_end();
    const bool answer_on = tx_from_ <= now && now < tx_until_;
    if (!whole_on && !answer_on) {
      seg_.flush();
    } else {
      seg_.close_ended();  // one that ended while another station drives on (a collision)
    }
    seg_.align();  // a station's trace checkpoints its chip at the line's time
    check_.idle_until(seg_.cycle());
    states_in_order();
  }

  // Each master in turn from the one that holds the token, the token passed on after it (with
  // several masters): `work(m, next)` does master m's part and returns whether it passed the
  // token to `next` itself.
  template <typename Work>
  void rotation(Work work) {
    const std::size_t n = masters_.size();
    const bool ring = n > 1;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t m = (holder_ + k) % n;
      if (ring && k > 0) masters_[m]->wait_token(token_wait());
      const std::uint8_t next = masters_[(m + 1) % n]->address();
      if (!work(m, next) && ring) masters_[m]->pass_token(next);
    }
    if (ring) masters_[holder_]->wait_token(token_wait());
  }
  std::uint64_t token_wait() const { return std::uint64_t{s_.slot_bits} * 300 * seg_.bit_cycles(); }

  void act(const SegmentStep& st) {
    using K = SegmentStep::Kind;
    switch (st.kind) {
      case K::startup:
        startup();
        quiet();
        break;
      case K::cycle:
        for (std::uint64_t n = 0; n < st.count; ++n) {
          rotation([this, &st](std::size_t m, std::uint8_t next) {
            if (s_.masters[m].obeys_token) {
              visit(m, next);
              return true;
            }
            DpMaster& dm = *masters_[m];
            for (std::size_t i = 0; i < dm.slave_count(); ++i) {
              dm.select(i);
              if (st.skip && dm.slave().address == *st.skip) continue;
              dm.data_exchange(std::vector<std::uint8_t>(dm.slave().out_len));
            }
            dm.select(0);
            return false;
          });
          forget();
        }
        quiet();
        break;
      case K::run:
        seg_.run_until(seg_.cycle() + st.time);
        break;
      case K::send:
        seg_.send(senders_.at(st.name), st.bytes, seg_.cycle() + st.time);
        seg_.run_until(seg_.cycle() + st.bytes.size() * 11 * seg_.bit_cycles());
        break;
      case K::pass_token: {
        // A master among the scenario's takes the token (the next rotation starts there); another
        // address shows no activity, and the passer keeps it (EN 50170: nobody took it).
        holder_ = master_index(st.address).value();  // the parser refuses another
        masters_[holder_]->pass_token(st.station);
        if (const auto to = master_index(st.station); !to) {
          masters_[holder_]->keep_token();
        } else if (*to != holder_) {
          masters_[*to]->wait_token(token_wait());
          holder_ = *to;
        }
        quiet();
        break;
      }
      default:
        check(st);
    }
    forget();
  }

  // The index of the master of `address` in masters_ (none: no master there).
  std::optional<std::size_t> master_index(std::uint8_t address) const {
    const auto m = std::find_if(masters_.begin(), masters_.end(),
                                [address](const auto& dm) { return dm->address() == address; });
    if (m == masters_.end()) return std::nullopt;
    return static_cast<std::size_t>(m - masters_.begin());
  }

  // Nothing here reads the masters' histories nor what a firmware wrote to its ports or took as
  // interrupts: a long run keeps memory flat (as the bridge does, docs/decisions.md).
  void forget() {
    for (auto& m : masters_) m->clear_history();
    for (auto& st : stations_) {
      if (st->firmware) st->firmware->clear_history();
    }
  }

  // Each master's start-up of its slaves. One that obeys the token spreads it over its visits
  // (DpMaster::begin_startup), the rotations going on until every such start-up is over; another
  // does its whole start-up in its first visit, as before.
  void startup() {
    bool first = true;
    for (std::size_t m = 0; m < masters_.size(); ++m) {
      if (s_.masters[m].obeys_token) masters_[m]->begin_startup();
    }
    do {
      rotation([this, first](std::size_t m, std::uint8_t next) {
        if (s_.masters[m].obeys_token) {
          visit(m, next);
          return true;
        }
        if (first) masters_[m]->startup_all();
        return false;
      });
      first = false;
    } while (std::any_of(masters_.begin(), masters_.end(),
                         [](const auto& m) { return m->starting_up(); }));
  }

  // One visit of the token to master m (DpMaster::use_token: TTR, the GAP update), then the token
  // to `next` (its own address when it is alone: it passes the token to itself). The walk tells
  // what it did.
  void visit(std::size_t m, std::uint8_t next) {
    DpMaster& dm = *masters_[m];
    const TokenVisit v = dm.use_token(next);
    const std::uint64_t t = seg_.bit_cycles();
    std::string polled;
    for (const std::size_t i : v.polled) {
      polled += fmt::format("{}{}", polled.empty() ? "" : ",", s_.masters[m].slaves[i]);
    }
    std::string startup;
    for (const std::size_t i : v.startup) {
      startup += fmt::format("{}{}", startup.empty() ? "" : ",", s_.masters[m].slaves[i]);
    }
    if (!startup.empty()) polled = fmt::format("none, start-up requests to {}", startup);
    say(v.arrived, fmt::format("master {}: the token: TRR {} bit times, TTH {}, polled {}{}",
                               dm.address(), v.rotation / t, v.hold / t, polled,
                               v.gap ? fmt::format(", GAP address {} asked ({})", *v.gap,
                                                   v.gap_answered ? "answered" : "no answer")
                                     : std::string()));
    visits_[m] = v;
  }

  // `expect visit`: the fields given, against master `st.address`'s last visit.
  [[nodiscard]] bool visit_matches(const SegmentStep& st, std::string& got) const {
    std::size_t m = 0;
    while (s_.masters[m].address != st.address) ++m;
    if (!visits_[m]) {
      got = "no visit yet";
      return false;
    }
    const TokenVisit& v = *visits_[m];
    const std::uint64_t t = seg_.bit_cycles();
    std::vector<std::uint8_t> polled;
    for (const std::size_t i : v.polled) polled.push_back(s_.masters[m].slaves[i]);
    std::vector<std::uint8_t> startup;
    for (const std::size_t i : v.startup) startup.push_back(s_.masters[m].slaves[i]);
    const SegmentStep::Visit& want = st.visit;
    got = fmt::format("polled {}{}, rotation {} bit times, hold {} bit times, gap {}{}",
                      polled.empty() ? "none" : fmt::format("{}", fmt::join(polled, ",")),
                      startup.empty() ? "" : fmt::format(", start-up {}", fmt::join(startup, ",")),
                      bit_times(v.rotation, t), bit_times(v.hold, t),
                      v.gap ? std::to_string(*v.gap) : "none",
                      v.gap ? (v.gap_answered ? " (answered)" : " (no answer)") : "");
    return (!want.polled || *want.polled == polled) &&
           (!want.startup || *want.startup == startup) &&
           (!want.rotation_bits || *want.rotation_bits * t == v.rotation) &&
           (!want.hold_bits || *want.hold_bits * t == v.hold) &&
           (!want.gap || *want.gap == v.gap) &&
           (!want.gap_answered || (v.gap && *want.gap_answered == v.gap_answered));
  }

  void check(const SegmentStep& st) {
    using K = SegmentStep::Kind;
    std::string got;
    bool ok = false;
    switch (st.kind) {
      case K::expect_state: {
        const Station& sta = *stations_[st.station_index];
        const Chip& c = seg_.chip(sta.index);
        ok = c.dp_state() == st.dp && (!st.wd || c.wd_state() == *st.wd);
        got = fmt::format("{} / {}", dp_state_name(c.dp_state()), wd_state_name(c.wd_state()));
        if (st.after_request) {
          const std::uint64_t after = sta.entered - sta.entered_after;
          ok = ok && sta.entered_after != 0 && after == *st.after_request;
          got += fmt::format(", entered at cycle {}, {} cycles after the end of the request at {}",
                             sta.entered, after, sta.entered_after);
        }
        break;
      }
      case K::expect_tsdr: {
        // Every answer's delay is the one expected: the least and the greatest are.
        const std::uint64_t want = st.count * seg_.bit_cycles();
        ok = delays_.count != 0 && delays_.min == want && delays_.max == want;
        got = fmt::format("{} answers, delays {}..{} bit times", delays_.count,
                          bit_times(delays_.count != 0 ? delays_.min : 0, seg_.bit_cycles()),
                          bit_times(delays_.max, seg_.bit_cycles()));
        break;
      }
      case K::expect_expired: {
        // docs/timing.md: restarted at the acted-on cycle of the last request (end - T + T/2),
        // expiry at that restart + TWD.
        const std::uint64_t t = seg_.bit_cycles();
        const auto it = last_request_.find(st.station);
        const std::uint64_t want = it == last_request_.end() ? 0 : it->second - t + t / 2 + st.time;
        const std::optional<std::uint64_t> left = stations_[st.station_index]->left_dp_control;
        ok = it != last_request_.end() && left == want;
        got = left ? fmt::format("left DP_Control at cycle {}, expected {}", *left, want)
                   : fmt::format("never left DP_Control, expected it at cycle {}", want);
        break;
      }
      case K::expect_violation:
        ok = check_.count(st.violation) == st.count;
        got = std::to_string(check_.count(st.violation));
        break;
      case K::expect_collisions:
        ok = seg_.collisions().size() == st.count;
        got = std::to_string(seg_.collisions().size());
        break;
      case K::expect_visit:
        ok = visit_matches(st, got);
        break;
      case K::expect_port: {
        const std::int64_t v = stations_[st.station_index]->firmware->port(st.name);
        ok = v == static_cast<std::int64_t>(st.count);
        got = scenario_expect::port_text(static_cast<std::uint32_t>(v));
        break;
      }
      default:
        break;
    }
    if (ok) {
      ++passed_;
      say(seg_.cycle(), "ok");
      return;
    }
    ++failed_;
    // "expected X, got Y" (docs/scenario-format.md): X the check's words after `expect`.
    std::string_view want = st.text;
    want.remove_prefix(want.find("expect") + 6);
    want = want.substr(0, want.find_last_not_of(" \t\r") + 1);
    want.remove_prefix(want.find_first_not_of(" \t"));
    const std::string e = fmt::format("{}:{}: expected {}, got {}", s_.file, st.line, want, got);
    say(seg_.cycle(), "FAILED: " + e);
    if (errors_) errors_(e);
  }

  const SegmentScenario& s_;
  const LineSink& walk_;
  const LineSink& errors_;
  SegmentObserver quiet_;
  SegmentObserver* observer_;
  // The host firmwares outlive the segment: its CPUs unwind a main loop suspended inside one.
  std::vector<std::unique_ptr<FirmwareHost>> hosts_;
  Segment seg_;
  BusCheck check_;
  std::vector<std::unique_ptr<Station>> stations_;
  std::map<std::string, std::size_t> senders_;
  std::vector<std::unique_ptr<DpMaster>> masters_;
  std::size_t holder_ = 0;  // the master that holds the token: a rotation starts there
  std::vector<std::optional<TokenVisit>> visits_;       // each master's last visit of the token
  std::map<std::uint8_t, std::uint64_t> last_request_;  // from the station's locking master
  // Each station's locking master as the line shows it: its Set_Prm's lock bits, its Slave_Diag
  // answers' Master_Add.
  std::map<std::uint8_t, std::uint8_t> locked_to_;
  // The first start bit and the end of the last answer a chip decided to send.
  std::uint64_t tx_from_ = 0;
  std::uint64_t tx_until_ = 0;
  std::vector<std::pair<std::uint64_t, std::string>> states_;  // states_in_order's lines
  bool telling_states_ = false;
  // The answers' delays after their requests so far (expect tsdr): how many, the least and the
  // greatest (kept as these three, not one by one: a long run's memory stays flat).
  struct {
    std::uint64_t count = 0;
    std::uint64_t min = UINT64_MAX;
    std::uint64_t max = 0;
  } delays_;
  std::uint32_t passed_ = 0;
  std::uint32_t failed_ = 0;
};

}  // namespace

int run_segment_scenario(const SegmentScenario& s, const LineSink& walk, const LineSink& errors,
                         SegmentObserver* observer) {
  if (!s.plugins_bound && !segment_plugins(s).empty()) {
    SegmentScenario bound = s;
    ScenarioError err;
    if (!bind_segment_plugins(bound, err)) {
      if (errors) errors(err.text());
      return 2;
    }
    return run_segment_scenario(bound, walk, errors, observer);
  }
  SegmentRun r(s, walk, errors, observer);
  return r.run();
}

}  // namespace dpc31
