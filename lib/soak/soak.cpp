#include "soak.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>

#include "dp_master.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/names.hpp"
#include "firmware_host.hpp"
#include "numbers.hpp"
#include "outfile.hpp"
#include "path_option.hpp"
#include "responder.hpp"
#include "scenario.hpp"
#include "vocabulary.hpp"

namespace dpc31::soak {

namespace {

constexpr std::uint32_t kRetries = 1;            // a request without an answer is sent once more
constexpr std::uint64_t kTries = kStartupTries;  // start-up and restart give up after this many
constexpr std::uint8_t kSlave = 5;
constexpr std::uint8_t kMaster = 2;
const std::vector<std::uint8_t> kInputs = {0x11, 0x22, 0x33, 0x44};

constexpr std::array<Fault, kFaultKinds> kAll = {Fault::noise,  Fault::noise_sync, Fault::glitch,
                                                 Fault::parity, Fault::stop,       Fault::cable,
                                                 Fault::restart};

// TWD on the 10 ms base: at least 20 ms and 4000 bit times (about ten Data_Exchange cycles), so
// the watchdog never expires while the master is talking.
std::uint32_t twd_ms(std::uint32_t baud) {
  const std::uint64_t need = std::max<std::uint64_t>(20, (4000ull * 1000 + baud - 1) / baud);
  return static_cast<std::uint32_t>(std::min<std::uint64_t>((need + 9) / 10, 255) * 10);
}

class Soak {
 public:
  explicit Soak(const Options& o)
      : o_(o), rc_(responder_config(o)), chip_(chip_options(o)), user_(rc_), rng_(o.seed) {
    chip_.set_log_sink(
        [this](const LogRecord& r) {
          if (log_.size() < kKeptLog) {
            log_.push_back(log_line(r));
          } else {
            ++log_left_out_;
          }
        },
        LogLevel::warn);
    DirectBus bus(chip_);
    MasterConfig mc;
    mc.address = kMaster;
    mc.baud = o.baud;
    SlaveConfig slave = rc_.slave;
    if (!o.firmware) {
      user_.set_inputs(kInputs);
      user_.init(bus);
      master_ = std::make_unique<DpMaster>(chip_, mc, slave);
      master_->set_firmware([this](BusPort& b) { user_.isr(b); });
    } else {
      fw_ = std::make_unique<FirmwareHost>(find_firmware(*o.firmware));
      const dpc31_firmware& f = fw_->firmware();
      slave.ident = f.ident;
      slave.cfg.assign(f.cfg, f.cfg + f.cfg_len);
      slave.in_len = f.in_len;
      slave.out_len = f.out_len;
      slave.user_prm.assign(f.user_prm, f.user_prm + f.user_prm_len);
      fw_->init(bus, kSlave);
      master_ = std::make_unique<DpMaster>(chip_, mc, slave);
      master_->set_firmware(fw_->program());
    }
    out_len_ = slave.out_len;
    t_ = master_->bit_cycles();
    twd_ = std::uint64_t{twd_ms(o.baud)} * chip_.clock_hz() / 1000;
  }

  Result run() {
    // The wall time is the whole run's, the start-up's baud search (0.6 s of chip time at
    // 9600 baud) included: from after it, a short run reported a real-time factor of 3000.
    const auto wall0 = std::chrono::steady_clock::now();
    if (!master_->startup(static_cast<int>(kTries))) {
      const std::vector<Exchange>& h = master_->history();
      const bool answered =
          std::any_of(h.begin(), h.end(), [](const Exchange& e) { return e.answer.has_value(); });
      throw std::runtime_error(fmt::format(
          "the first start-up did not reach Data_Exchange: after {} tries the slave is in {}{}",
          kTries, dp_state_name(chip_.dp_state()),
          answered ? "" : "; no request was answered, not even FDL_Status"));
    }
    // The baud search counts the garbage it hears at wrong rates: the baseline is after it.
    const FdlCounters chip0 = chip_.fdl_counters();
    const MasterCounters master0 = master_->counters();
    const std::uint32_t prm0 = user_.prm_accepted;
    const std::uint32_t cfg0 = user_.cfg_accepted;
    const std::uint32_t rej0 = user_.cfg_rejected;
    collect();
    Result r;
    r.first_cycle = chip_.cycle();
    r.clock_hz = chip_.clock_hz();
    r.twd_ms = twd_ms(o_.baud);
    r.rss_start_kib = resident_kib();

    bool unaccounted_pending = !o_.unaccounted.empty();
    std::array<Fault, kFaultKinds> round = kAll;
    std::size_t next_in_round = kFaultKinds;
    std::uint64_t next_fault = chip_.cycle() + o_.fault_period;
    while (chip_.cycle() < o_.cycles) {
      if (chip_.cycle() < next_fault) {
        exchange();
        continue;
      }
      if (unaccounted_pending) {  // this slot's fault, deliberately not counted in injected_
        unaccounted_pending = false;
        inject(parse_fault(o_.unaccounted));
        next_fault = chip_.cycle() + o_.fault_period;
        continue;
      }
      if (next_in_round == kFaultKinds) {  // every kind once per round, in a random order
        std::shuffle(round.begin(), round.end(), rng_);
        next_in_round = 0;
      }
      const Fault f = round[next_in_round++];
      ++injected_[static_cast<std::size_t>(f)];
      inject(f);
      next_fault = chip_.cycle() + o_.fault_period;
    }
    // A last exchange, so that the slave lost to a fault just before the end is recovered and
    // counted as such.
    exchange();

    r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    r.rss_end_kib = resident_kib();
    r.cycles = chip_.cycle();
    r.exchanges = exchanges_;
    r.injected = injected_;
    const auto n = [this](Fault f) { return injected_[static_cast<std::size_t>(f)]; };
    const std::uint64_t damaged = n(Fault::parity) + n(Fault::stop);
    const MasterCounters& m = master_->counters();
    // The chip: each counter grew by exactly what was injected of its class, nothing else.
    const FdlCounters& c = chip_.fdl_counters();
    for (const CounterField& f : fdl_counter_fields()) {
      std::uint64_t expected = 0;
      const std::string_view name = f.name;
      if (name == "parity") expected = n(Fault::parity);
      if (name == "stop_bit") expected = n(Fault::stop);
      if (name == "start_bit") expected = n(Fault::glitch);
      if (name == "bad_sd") expected = n(Fault::noise);
      if (name == "no_sync") expected = n(Fault::noise_sync);
      if (name == "not_allowed") expected = n(Fault::cable);  // the first Data_Exchange: RS
      if (name == "requests") expected = (m.requests - master0.requests) - damaged;
      r.rows.push_back({"chip." + std::string(name), expected, c.*f.member - chip0.*f.member});
    }
    r.rows.push_back({"master.no_answer", damaged, m.no_answer - master0.no_answer});
    r.rows.push_back({"master.bad_answer", 0, m.bad_answer - master0.bad_answer});
    r.rows.push_back({"master.noise", n(Fault::noise) + n(Fault::noise_sync) + n(Fault::glitch),
                      m.noise - master0.noise});
    r.rows.push_back({"master.recoveries", n(Fault::cable), recoveries_});
    if (fw_) return r;  // the rest is the built-in responder's bookkeeping and data
    r.rows.push_back({"firmware.wd_timeouts", n(Fault::cable), wd_timeouts_});
    r.rows.push_back(
        {"firmware.prm_accepted", n(Fault::cable) + n(Fault::restart), user_.prm_accepted - prm0});
    r.rows.push_back(
        {"firmware.cfg_accepted", n(Fault::cable) + n(Fault::restart), user_.cfg_accepted - cfg0});
    r.rows.push_back({"firmware.cfg_rejected", 0, user_.cfg_rejected - rej0});
    r.rows.push_back({"data.wrong_inputs", 0, wrong_inputs_});
    r.rows.push_back({"data.wrong_outputs", 0, wrong_outputs_});
    return r;
  }

  // The chip's log, kept for the report (set_log_sink hands over what its limiters still owe).
  void take_log(Result& r) {
    chip_.set_log_sink({});
    r.log = std::move(log_);
    r.log_left_out = log_left_out_;
  }

 private:
  static ChipOptions chip_options(const Options& o) {
    ChipOptions co;
    if (!parse_profile(o.profile, co.profile)) {
      throw std::invalid_argument("unknown profile '" + o.profile + "'");
    }
    if (const std::string why = cli::apply_chip_choice(o.chip, co); !why.empty()) {
      throw std::invalid_argument(why);
    }
    return co;
  }

  // Not inlined: GCC 12 warns maybe-uninitialized about SlaveConfig's vector initialiser when it
  // is (a false positive).
  [[gnu::noinline]] static ResponderConfig responder_config(const Options& o) {
    // Checked here, the first to use it: twd_ms() divides by it.
    if (const std::string e = not_a_profibus_rate(o.baud); !e.empty()) {
      throw std::invalid_argument(e);
    }
    ResponderConfig rc;
    rc.slave.address = kSlave;
    rc.slave.wd_on = true;
    rc.slave.wd_fact1 = static_cast<std::uint8_t>(twd_ms(o.baud) / 10);
    rc.slave.wd_fact2 = 1;
    // The user watchdog is armed at init (511 Data_Exchange): a firmware that arms it feeds it.
    rc.user_watchdog = true;
    return rc;
  }

  static Fault parse_fault(const std::string& s) {
    for (Fault f : kAll) {
      if (s == fault_name(f)) return f;
    }
    throw std::invalid_argument("unknown fault '" + s + "'");
  }

  std::uint32_t below(std::uint32_t n) {
    return static_cast<std::uint32_t>(std::uniform_int_distribution<std::uint32_t>(0, n - 1)(rng_));
  }
  std::vector<std::uint8_t> random_bytes(std::size_t n) {
    std::vector<std::uint8_t> b(n);
    for (std::uint8_t& x : b) x = static_cast<std::uint8_t>(below(256));
    return b;
  }

  // One Data_Exchange with new outputs (a running number), repeated once without an answer.
  void exchange(UartFault fault = {}) {
    ++sent_count_;
    // The running number, big-endian, in the module's output bytes (the last ones).
    std::vector<std::uint8_t> out(out_len_);
    for (std::size_t i = 0; i < out.size(); ++i) {
      const std::size_t shift = 8 * (out.size() - 1 - i);
      out[i] = shift < 64 ? static_cast<std::uint8_t>(sent_count_ >> shift) : 0;
    }
    // Matched against what the built-in user fetched (collect); a firmware keeps no record of
    // its fetches, so with one nothing is kept (it grew by an exchange each: issue 29).
    if (!fw_) pending_.push_back(out);
    const Exchange ex = master_->retry(master_->data_exchange(out, fault), kRetries);
    const bool data = ex.answer && !ex.answer->du.empty();
    if (data) {
      ++exchanges_;
      if (!fw_ && ex.answer->du != kInputs) ++wrong_inputs_;
    }
    if (ex.answer_end != 0) {
      // Until the master could send again: the firmware has handled what this exchange raised.
      const std::uint64_t free = ex.answer_end + std::uint64_t{33} * t_;
      if (free > chip_.cycle()) master_->idle(free - chip_.cycle());
    }
    collect();
    if (!data) {  // RS (the slave left Data_Exchange) or nothing at all: start over
      ++recoveries_;
      master_->restart(kTries, kRetries);
      collect();
    }
  }

  void inject(Fault f) {
    switch (f) {
      case Fault::noise: {
        std::vector<std::uint8_t> b = random_bytes(1 + below(8));
        while (b[0] == fdl::SD1 || b[0] == fdl::SD2 || b[0] == fdl::SD3 || b[0] == fdl::SD4 ||
               b[0] == fdl::SC) {
          b[0] = static_cast<std::uint8_t>(below(256));
        }
        master_->line_noise(b, 33 + below(64));
        break;
      }
      case Fault::noise_sync: {
        // A token between two other stations, then noise right after it (less than TSYN).
        std::vector<std::uint8_t> b = {fdl::SD4, 9, 3};
        const std::vector<std::uint8_t> tail = random_bytes(1 + below(8));
        b.insert(b.end(), tail.begin(), tail.end());
        master_->line_noise(b, 33 + below(64));
        break;
      }
      case Fault::glitch:
        master_->glitch(1 + below(std::max<std::uint32_t>(1, t_ / 2 - 1)));
        break;
      case Fault::parity:
      case Fault::stop: {
        UartFault u;
        u.kind = f == Fault::parity ? UartFault::Kind::parity : UartFault::Kind::stop;
        // SD2: 9 characters and the outputs; without outputs an SD1 of 6.
        u.char_index = static_cast<int>(below(out_len_ == 0 ? 6 : 9 + out_len_));
        exchange(u);
        return;
      }
      case Fault::cable:
        master_->idle(twd_ + twd_ / 4);
        break;
      case Fault::restart:
        master_->idle(twd_ / 4);
        master_->restart(kTries, kRetries);
        break;
    }
    collect();
  }

  // Reads and forgets what the firmware and the master recorded, so memory stays flat.
  void collect() {
    if (fw_) {
      fw_->clear_history();
      master_->clear_history();
      return;
    }
    for (const auto& [cycle, ir] : user_.interrupts) {
      if ((ir & irq::WD_DP_Control_Timeout) != 0) ++wd_timeouts_;
    }
    user_.interrupts.clear();
    // Every fetched output must be one the master sent, in order (cleared ones are zeros).
    for (const Responder::Output& o : user_.outputs) {
      if (o.cleared) continue;
      while (!pending_.empty() && pending_.front() != o.data) pending_.pop_front();
      if (pending_.empty()) {
        ++wrong_outputs_;
      } else {
        pending_.pop_front();
      }
    }
    user_.outputs.clear();
    if (pending_.size() > 2) pending_.erase(pending_.begin(), pending_.end() - 2);
    master_->clear_history();
  }

  const Options& o_;
  const ResponderConfig rc_;
  Chip chip_;
  Responder user_;
  std::unique_ptr<FirmwareHost> fw_;  // instead of user_ with --firmware
  std::size_t out_len_ = 0;
  std::unique_ptr<DpMaster> master_;
  std::mt19937_64 rng_;
  std::uint32_t t_ = 0;
  std::uint64_t twd_ = 0;
  std::array<std::uint64_t, kFaultKinds> injected_{};
  std::uint64_t sent_count_ = 0;
  std::deque<std::vector<std::uint8_t>> pending_;  // outputs sent, not yet seen fetched
  std::uint64_t exchanges_ = 0;
  std::uint64_t recoveries_ = 0;
  std::uint64_t wd_timeouts_ = 0;
  std::uint64_t wrong_inputs_ = 0;
  std::uint64_t wrong_outputs_ = 0;
  std::vector<std::string> log_;
  std::uint64_t log_left_out_ = 0;
};

}  // namespace

constexpr std::array<std::string_view, 7> kFaultNames = {"noise", "noise_sync", "glitch", "parity",
                                                         "stop",  "cable",      "restart"};
static_assert(kFaultNames.size() == kFaultKinds, "a new fault kind: name it here");

const char* fault_name(Fault f) { return name_of(f, kFaultNames).data(); }

bool Result::ok() const {
  return std::all_of(rows.begin(), rows.end(), [](const Row& r) { return r.ok(); });
}

std::uint64_t resident_kib() {
  std::ifstream in("/proc/self/status");
  std::string key;
  while (in >> key) {
    if (key == "VmRSS:") {
      std::uint64_t kib = 0;
      in >> kib;
      return kib;
    }
    in.ignore(1 << 16, '\n');
  }
  return 0;
}

Result run(const Options& o) {
  Soak soak(o);
  Result r = soak.run();
  soak.take_log(r);
  return r;
}

CLI::App* add_subcommand(CLI::App& app, Options& o) {
  auto* s = app.add_subcommand(
      "soak", "a long Data_Exchange run with injected faults; every error counter must match");
  // Counts of cycles may be written 1e9; a fraction of a cycle is refused, never cut off.
  const auto cycles = [s](const char* name, std::uint64_t& v, const char* what) {
    s->add_option(name, v, fmt::format("{} (default {})", what, v))
        ->transform(numbers::count(1, 1'000'000'000'000'000));
  };
  cycles("--cycles", o.cycles, "run until the chip's cycle counter reaches this");
  s->add_option("--profile", o.profile, "chip profile")
      ->capture_default_str()
      ->check(CLI::IsMember({"spc3", "vpc3plus", "dpc31"}));
  cli::add_chip_options(s, o.chip);
  // Checked on the text, before CLI11 converts it: it would take "" as 0, and "010" as octal.
  s->add_option("--baud", o.baud, "bus baud rate: " + profibus_rates())
      ->capture_default_str()
      ->transform(CLI::Validator(
          [](std::string& text) {
            std::uint32_t baud = 0;
            std::string why = not_a_profibus_rate(text, baud);
            if (why.empty()) text = std::to_string(baud);
            return why;
          },
          "RATE"));
  cycles("--fault-period", o.fault_period,
         "cycles of undisturbed Data_Exchange between two injected faults");
  s->add_option("--seed", o.seed, "seed of the fault order and the noise bytes")
      ->capture_default_str()
      ->transform(numbers::whole(0));
  s->add_option("--json", o.json, "write the result as JSON to this file")
      ->transform(outfile::named(outfile::Use::write));
  s->add_option("--firmware", o.firmware,
                "the slave's firmware instead of the built-in responder: a built-in name or a "
                "plug-in ./libmine.so (only the chip's and the master's counters are checked)");
  std::vector<std::string> kinds;
  for (Fault f : kAll) kinds.emplace_back(fault_name(f));
  s->add_option("--unaccounted-fault", o.unaccounted,
                "inject one extra fault of this kind without accounting for it (the check must "
                "then fail; for testing the check)")
      ->check(CLI::IsMember(kinds));
  return s;
}

int run_cli(const Options& o, std::FILE* out, std::FILE* err) {
  // The JSON report appears whole or not at all, and a bad path fails before the run
  // (docs/bad-input.md). Never over the plug-in it runs (docs/security.md).
  if (const std::string same = outfile::distinct(
          {{"--firmware", o.firmware && is_plugin_path(*o.firmware) ? *o.firmware : std::string()}},
          {{"--json", o.json.value_or("")}});
      !same.empty()) {
    fmt::print(err, "dpc31 soak: {}\n", same);
    return 2;
  }
  outfile::OutFile json_out;
  if (o.json && !json_out.open(*o.json)) {
    fmt::print(err, "dpc31 soak: {}\n", json_out.error());
    return 2;
  }
  Result r;
  try {
    // A firmware stuck in a loop without a bus access cannot be stopped from this thread.
    if (o.firmware)
      board::guard_hangs("dpc31 soak", find_firmware(*o.firmware, hex_at_command("soak")).name);
    r = run(o);
  } catch (const std::exception& e) {
    fmt::print(err, "dpc31 soak: {}\n", e.what());
    return 2;
  }
  // The chip as run, defaults named: a report or JSON alone tells which chip it was.
  const std::string variant =
      o.profile != "vpc3plus" ? "" : (o.chip.variant.empty() ? "c" : o.chip.variant);
  // On the spc3 and vpc3plus too: their one controller is the external processor's (X/INT).
  const std::string irq_controller =
      o.chip.irq_controller.empty() ? "external" : o.chip.irq_controller;
  fmt::print(
      out, "dpc31 soak: profile {}{}{}, {} baud, TWD {} ms, a fault every {} cycles, seed {}{}{}\n",
      o.profile, variant.empty() ? "" : " variant " + variant,
      irq_controller == "c31" ? ", irq-controller c31" : "", o.baud, r.twd_ms, o.fault_period,
      o.seed, o.firmware ? ", firmware " + *o.firmware : "",
      o.unaccounted.empty() ? "" : ", one unaccounted " + o.unaccounted + " fault");
  const double hz = r.clock_hz;
  // Fixed-point, with the digits a short run needs to show more than 0.00 (never 1e+03).
  const int wall_digits = r.wall_s >= 0.1 ? 2 : r.wall_s >= 0.001 ? 4 : 6;
  fmt::print(out,
             "cycles {} ({:.3f} s of chip time), {} after the start-up; wall {:.{}f} s ({:.1f}x "
             "real time)\n",
             r.cycles, static_cast<double>(r.cycles) / hz, r.cycles - r.first_cycle, r.wall_s,
             wall_digits, static_cast<double>(r.cycles) / hz / std::max(r.wall_s, 1e-9));
  fmt::print(out, "Data_Exchange answered with data: {}\n", r.exchanges);
  fmt::print(out, "VmRSS: {} KiB after the start-up, {} KiB at the end\n", r.rss_start_kib,
             r.rss_end_kib);
  std::string inj;
  for (Fault f : kAll) {
    inj += fmt::format("{}{} {}", inj.empty() ? "" : ", ", fault_name(f),
                       r.injected[static_cast<std::size_t>(f)]);
  }
  fmt::print(out, "injected: {}\n\n{:<24} {:>12} {:>12}\n", inj, "counter", "expected", "actual");
  std::size_t bad = 0;
  for (const Row& row : r.rows) {
    fmt::print(out, "{:<24} {:>12} {:>12}{}\n", row.name, row.expected, row.actual,
               row.ok() ? "" : "  MISMATCH");
    bad += row.ok() ? 0 : 1;
  }
  if (bad == 0) {
    fmt::print(out, "\nresult: every counter accounts exactly for the injected faults\n");
  } else {
    fmt::print(out, "\nresult: {} counter(s) do not match the injected faults\n", bad);
  }
  if (o.json) {
    nlohmann::json j;
    j["profile"] = o.profile;
    if (!variant.empty()) j["variant"] = variant;
    j["irq_controller"] = irq_controller;
    j["baud"] = o.baud;
    j["seed"] = o.seed;
    if (o.firmware) j["firmware"] = *o.firmware;
    if (!o.unaccounted.empty()) j["unaccounted_fault"] = o.unaccounted;
    j["fault_period"] = o.fault_period;
    j["twd_ms"] = r.twd_ms;
    j["cycles"] = r.cycles;
    j["first_cycle"] = r.first_cycle;
    j["wall_s"] = r.wall_s;
    j["rss_start_kib"] = r.rss_start_kib;
    j["rss_end_kib"] = r.rss_end_kib;
    j["exchanges"] = r.exchanges;
    for (Fault f : kAll) j["injected"][fault_name(f)] = r.injected[static_cast<std::size_t>(f)];
    for (const Row& row : r.rows) {
      j["counters"].push_back(
          {{"name", row.name}, {"expected", row.expected}, {"actual", row.actual}});
    }
    j["ok"] = r.ok();
    if (!json_out.write(j.dump(2) + '\n') || !json_out.commit()) {
      fmt::print(err, "dpc31 soak: {}\n", json_out.error());
      return 2;
    }
  }
  // The chip's log after every output is written: a run that ends in exit 2 says one line.
  for (const std::string& l : r.log) fmt::print(err, "{}\n", l);
  if (r.log_left_out != 0) {
    fmt::print(err, "... and {} more lines of the chip's log\n", r.log_left_out);
  }
  return bad == 0 ? 0 : 1;
}

}  // namespace dpc31::soak
