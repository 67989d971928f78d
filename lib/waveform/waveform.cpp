#include "waveform.hpp"

#include <fmt/format.h>
#include <fnmatch.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "dpc31/reg_ids.hpp"
#include "dpc31/regdesc.hpp"
#include "gtkw.hpp"
#include "gtkwave/fstapi.h"
#include "outfile.hpp"
#include "pvs.hpp"
#include "vcd_body.hpp"
#include "vocabulary.hpp"
#include "wavediff.hpp"  // vcd_id: one VCD identifier code for every writer

namespace dpc31::wave {

namespace {

enum Sig : std::uint16_t {
  kRxd,
  kTxd,
  kXInt,
  kBusRd,
  kBusWr,
  kBusAddr,
  kBusData,
  kDpState,
  kWdState,
  kBaud,
  kIrr,
  kDoutSm,
  kDinSm,
  kDiagSm,
  kPb3,      // after the others, so the older signals keep their VCD identifiers
  kService,  // likewise
  kC31Int0,  // likewise
  kCount
};

// Constant-initialised: other translation units may call signal_list() during their static
// initialisation (bench/ registers one benchmark per signal count).
constexpr std::array<SignalDef, kCount> kSignals = {{{"pins.rxd", 1},
                                                     {"pins.txd", 1},
                                                     {"pins.x_int", 1},
                                                     {"bus.rd", 1},
                                                     {"bus.wr", 1},
                                                     {"bus.addr", 13},
                                                     {"bus.data", 8},
                                                     {"state.dp_state", 2},
                                                     {"state.wd_state", 2},
                                                     {"state.baud_code", 4},
                                                     {"blocks.irr", 16},
                                                     {"blocks.dout_sm", 8},
                                                     {"blocks.din_sm", 8},
                                                     {"blocks.diag_sm", 4},
                                                     {"pins.pb3", 1},
                                                     {"state.service", 8},
                                                     {"pins.c31_int0", 1}}};

static_assert(std::all_of(kSignals.begin(), kSignals.end(),
                          [](const SignalDef& d) { return d.width <= 16; }),
              "Event::value holds 16 bits");

// 16 bytes: a traced run records one per change of every signal.
struct Event {
  std::uint64_t cycle;
  std::uint32_t seq;  // the order of recording, for changes in the same cycle
  std::uint16_t value;
  std::uint16_t var;  // the recording's variable (Recorder::Impl::vars)
};

// state.service: the DP service of a request the chip received, by the slave's SAP (the DSAP,
// 0..63); without one 80h Data_Exchange (SRD), 81h FDL_Status, 82h another FDL service; -1 for
// what is no request (an answer, the token, SC).
int request_service(const std::vector<std::uint8_t>& b) {
  const std::size_t pos = !b.empty() && b[0] == 0x68 ? 4 : 1;
  if (b.empty() || (b[0] != 0x10 && b[0] != 0x68 && b[0] != 0xA2) || b.size() < pos + 4) return -1;
  const std::uint8_t fc = b[pos + 2];
  if ((fc & 0x40) == 0) return -1;
  if ((b[pos] & 0x80) != 0 && b[0] != 0x10) return b[pos + 3] & 0x3F;
  const unsigned code = fc & 0x0Fu;
  return code == 0xC || code == 0xD ? 0x80 : code == 0x9 ? 0x81 : 0x82;
}

bool before(const Event& a, const Event& b) {
  return a.cycle != b.cycle ? a.cycle < b.cycle : a.seq < b.seq;
}

// Changes in (cycle, seq) order. Each source reports in time order except the bus strobe's fall
// one cycle ahead, so a change moves back past at most a few others.
struct Stream {
  std::vector<Event> events;
  void push(const Event& e) {
    events.push_back(e);
    for (auto i = events.end() - 1; i != events.begin() && before(*i, *(i - 1)); --i) {
      std::iter_swap(i, i - 1);
    }
  }
  // The first `n` were written.
  void drop(std::size_t n) {
    events.erase(events.begin(), events.begin() + static_cast<std::ptrdiff_t>(n));
  }
};

std::string bits(std::uint32_t v, int width) {
  std::string s;
  for (int b = width - 1; b >= 0; --b) s += ((v >> b) & 1) != 0 ? '1' : '0';
  return s;
}

// The line of a segment: its level and who drives it.
enum LineSig : std::uint8_t { kLineLevel, kLineDriver, kLineCount };
constexpr std::array<SignalDef, kLineCount> kLineSignals = {
    {{"line.level", 1}, {"line.driver", 8}}};

// A variable of the file: its name below the top scope, its width, and what it shows.
struct Var {
  std::string name;
  int width = 1;
  std::size_t source = 0;  // Recorder::Impl::sources: the line first, then the chips
  std::uint8_t sig = 0;    // Sig of a chip, LineSig of the line
};

bool glob(const std::string& pattern, const std::string& name) {
  return fnmatch(pattern.c_str(), name.c_str(), 0) == 0;
}

// Whether a chip has the signal: PB3 is a DPC31 port; the C31's INT0 is driven by the chip only
// when the bus reaches the C31's interrupt controller (docs/dpc31.md, "Two interrupt
// controllers"), X/INT then stays inactive.
bool chip_has(const Chip& chip, std::size_t sig) {
  if (sig == kPb3) return chip.profile().id == Profile::dpc31;
  if (sig == kC31Int0) return chip.irq_controller() == IrqController::c31;
  return true;
}

// The time unit 10^exp s as $timescale writes it: "1ps", "10ns", "100us".
std::string unit_text(int exp) {
  static constexpr const char* kUnit[] = {"s", "ms", "us", "ns", "ps", "fs"};
  const int e = -exp;
  return fmt::format("{}{}", e % 3 == 0 ? 1 : e % 3 == 1 ? 100 : 10, kUnit[(e + 2) / 3]);
}

// A clock in MHz, exact: "48", "14.7456" (a truncated 14 would be another clock's cycle times).
std::string mhz_text(std::uint32_t hz) {
  std::string s = fmt::format("{}.{:06}", hz / 1'000'000, hz % 1'000'000);
  s.erase(s.find_last_not_of('0') + 1);
  if (s.back() == '.') s.pop_back();
  return s;
}

}  // namespace

const std::vector<SignalDef>& signal_list() {
  static const std::vector<SignalDef> list(kSignals.begin(), kSignals.end());
  return list;
}

// Changes are written as the run goes: every change before the horizon (the chips' current
// cycle; in a segment also the line's, Segment::line_final) is final (sources report at or after
// it; RxD and the line ahead of it), so the streams hold only what is ahead and what came since
// the last drain, and memory stays bounded however long the run.
struct Recorder::Impl {
  // A drain runs after this many new changes: the buffer stays within about 64 KiB, small enough
  // to be reused from the heap (larger, it came and went as fresh pages on every run).
  static constexpr std::size_t kDrainEvery = 4096;
  static constexpr std::uint32_t kNoVar = UINT32_MAX;

  // One chip (its scope "" on its own, the station's in a segment), or the line (no chip).
  struct Source {
    Chip* chip = nullptr;
    std::string scope;
    Stream ahead;   // RxD edges, driven (and reported) ahead of time; the line's changes
    Stream others;  // the rest, reported when time reaches them
    std::array<std::uint32_t, kCount> var{};  // the variable of each signal, kNoVar if not taken
    std::array<std::uint32_t, kCount> sampled{};
  };

  Options opt;
  std::string top = "dpc31";
  std::uint32_t clock_hz = 48'000'000;
  std::vector<std::unique_ptr<Source>> sources;
  std::vector<Var> vars;
  std::function<std::uint64_t()> horizon;  // the line's (a segment); the chips' always count
  std::size_t buffered = 0;
  std::size_t next_drain = kDrainEvery;
  std::uint32_t seq = 0;
  std::uint64_t drained_to = 0;  // every change before this cycle has been taken
  std::string error;             // the first failure, reported by finish()
  outfile::OutFile out;          // opened by the first attach, so that a bad path is found early
  outfile::OutFile gtkw;         // the save file (Options::gtkw), likewise
  outfile::OutFile pvs;          // the PulseView session setup (Options::pvs), likewise
  std::vector<std::pair<std::uint64_t, std::string>> markers;  // its named markers (26 at most)

  // The line (attach_line): station -> driver code, the bit time, the character on the line.
  Source* line = nullptr;
  std::vector<std::uint8_t> driver_codes;
  std::uint64_t char_cycles = 0;
  std::uint64_t char_end = 0;            // end of the last stop bit of the character
  std::optional<std::uint64_t> release;  // driver back to none here, unless continued
  std::uint32_t driver = kNoDriver;

  // What has been written: the values in force, and the window's start once dumped.
  std::vector<std::uint32_t> cur;
  bool opened = false;
  std::uint64_t last_t = 0;
  // The changes of one time are gathered and written when time moves on: one value per variable
  // and time, the last, as a viewer shows only that (irr changes twice in the cycle the
  // watchdog expires).
  std::uint64_t step_cycle = 0;
  std::uint64_t step_t = 0;
  std::vector<std::uint32_t> step_vars;  // the variables changed at step_t, in order
  std::vector<std::uint32_t> next;       // each variable's value at step_t
  std::vector<bool> in_step;
  std::vector<std::string> id;
  std::unique_ptr<VcdBody> body;
  void* fst = nullptr;
  std::vector<fstHandle> handle;

  // The chips' observers outlive the recorder (a Chip's observers are removed only all of a
  // kind at once): each holds this flag and does nothing once the recorder is gone.
  std::shared_ptr<bool> live = std::make_shared<bool>(true);

  ~Impl() {
    *live = false;
    if (fst != nullptr) fstWriterClose(fst);  // an unfinished recording: `out` discards it
  }
  // `f` as a chip observer that is a no-op once the recorder is destroyed.
  template <typename F>
  auto while_live(F f) const {
    return [live = live, f = std::move(f)](auto&&... a) {
      if (*live) f(std::forward<decltype(a)>(a)...);
    };
  }

  [[nodiscard]] bool take(const std::string& local, const std::string& full, int width) const {
    if (opt.flat && width != 1) return false;
    bool t = opt.signals.empty();
    for (const std::string& p : opt.signals) t = t || glob(p, local) || glob(p, full);
    return t;
  }
  [[nodiscard]] std::string full_name(const Source& s, const char* name) const {
    return s.scope.empty() ? std::string(name) : s.scope + "." + name;
  }
  // Opens the outputs at the first attach: a bad path is found before the run.
  bool open_outputs(std::string& err) {
    if (opt.timescale_exp > 0 || opt.timescale_exp < -15) {
      err = "timescale must be between 1 fs and 1 s";
      return false;
    }
    if (!out.is_open() && !out.open(opt.path)) {
      err = out.error();
      return false;
    }
    if (!opt.gtkw.empty() && !gtkw.is_open() && !gtkw.open(opt.gtkw)) {
      err = gtkw.error();
      return false;
    }
    if (!opt.pvs.empty()) {
      // PulseView reads VCD (libsigrok's input), and only the logic-analyser form of it.
      if (opt.fst || !opt.flat) {
        err = fmt::format("{}: a PulseView session is for a VCD in the logic-analyser form (flat)",
                          opt.pvs);
        return false;
      }
      if (opt.baud == 0) {
        err = fmt::format("{}: a PulseView session needs the bus's baud rate", opt.pvs);
        return false;
      }
      if (!pvs.is_open() && !pvs.open(opt.pvs)) {
        err = pvs.error();
        return false;
      }
    }
    return true;
  }
  // The channels a PulseView session's UART decoder reads, as the file names them: one chip's
  // RxD and TxD, or a segment's line (the bus as every station hears it: rx only).
  [[nodiscard]] std::pair<std::string, std::string> session_channels() const {
    std::pair<std::string, std::string> rx_tx;
    for (const Var& v : vars) {
      if (v.name == "pins.rxd" || v.name == kLineSignals[kLineLevel].name)
        rx_tx.first = path(v).second;
      if (v.name == "pins.txd") rx_tx.second = path(v).second;
    }
    return rx_tx;
  }
  [[nodiscard]] std::string no_session_channel() const {
    return fmt::format(
        "{}: a PulseView session decodes pins.rxd or pins.txd (a segment's line.level), and "
        "--signals leaves them out of {}",
        opt.pvs, opt.path);
  }
  // A session left without a channel to decode (--signals) is refused as the run starts.
  [[nodiscard]] bool session_has_channels(std::string& err) const {
    const auto [rx, tx] = session_channels();
    if (!pvs.is_open() || !rx.empty() || !tx.empty()) return true;
    err = no_session_channel();
    return false;
  }

  [[nodiscard]] std::uint64_t now() const {
    // A segment's stations join one by one, each running its init first: nothing is final
    // before the line is attached (attach_line) and every station with it.
    if (line != nullptr && !horizon) return 0;
    std::uint64_t h = horizon ? horizon() : UINT64_MAX;
    for (const auto& s : sources) {
      if (s->chip != nullptr) h = std::min(h, s->chip->cycle());
    }
    return h;
  }

  void push(Source& s, std::uint64_t cycle, std::uint8_t sig, std::uint32_t v) {
    const std::uint32_t var = s.var[sig];
    if (var == kNoVar || cycle >= opt.to || !error.empty()) return;
    if (cycle < drained_to) {
      error = fmt::format("{}: a change at cycle {} was reported after cycle {} was written",
                          opt.path, cycle, drained_to);
      return;
    }
    if (seq == UINT32_MAX) {
      error = fmt::format("{}: more than {} changes in one recording", opt.path, seq);
      return;
    }
    const bool ahead = s.chip == nullptr || sig == kRxd;
    (ahead ? s.ahead : s.others)
        .push({cycle, seq++, static_cast<std::uint16_t>(v), static_cast<std::uint16_t>(var)});
    if (++buffered >= next_drain) {
      drain(now());
      next_drain = buffered + kDrainEvery;
    }
  }

  // State signals: recorded when they change.
  void sample(Source& s, std::uint64_t cycle) {
    const ChipProbe c = s.chip->probe();
    const std::uint32_t now[] = {static_cast<std::uint32_t>(c.dp_state),
                                 static_cast<std::uint32_t>(c.wd_state),
                                 c.baud_code,
                                 c.irr,
                                 c.dout_buffer_sm,
                                 c.din_buffer_sm,
                                 c.diag_buffer_sm,
                                 s.chip->x_int_pin() ? 1u : 0u,
                                 s.chip->pb3_pin() ? 1u : 0u,
                                 s.chip->irq_active() ? 0u : 1u};  // INT0 is low-active
    const Sig sigs[] = {kDpState, kWdState, kBaud, kIrr, kDoutSm,
                        kDinSm,   kDiagSm,  kXInt, kPb3, kC31Int0};
    for (std::size_t i = 0; i < std::size(sigs); ++i) {
      if (s.sampled[sigs[i]] == now[i]) continue;
      s.sampled[sigs[i]] = now[i];
      push(s, cycle, sigs[i], now[i]);
    }
  }

  // The line: every edge of its holder (Segment::on_line). The driver is the holder from the
  // start bit of its first character to the end of the stop bit of its last one back to back.
  void line_edge(std::size_t from, std::uint64_t cycle, bool level) {
    settle_line(cycle);
    if (!level && cycle >= char_end) {
      const std::uint32_t code = from < driver_codes.size() ? driver_codes[from] : kNoDriver;
      if (code != driver) push(*line, cycle, kLineDriver, code);
      driver = code;
      char_end = cycle + char_cycles;
      release = char_end;
    }
    push(*line, cycle, kLineLevel, level ? 1 : 0);
  }
  // The driver is released at the end of its last character once nothing continued it before
  // `upto` (every edge before it has been reported).
  void settle_line(std::uint64_t upto) {
    if (line == nullptr || !release || *release >= upto) return;
    const std::uint64_t at = *release;
    release.reset();
    driver = kNoDriver;
    push(*line, at, kLineDriver, kNoDriver);
  }

  // cycle -> time units, rounded to the nearest unit: floor((cycle x 10^-exp + f / 2) / f),
  // computed from the absolute cycle so the rounding never accumulates. With g = gcd(10^-exp, f)
  // that is floor((cycle x num + floor(f / 2 / g)) / den), in 64 bits while it fits.
  std::uint64_t num = 1;
  std::uint64_t den = 1;
  std::uint64_t half = 0;
  // False if a unit is longer than a clock cycle: changes of neighbouring cycles would share a
  // time, a one-cycle strobe would vanish and sigrok would decode a 12 Mbaud line as noise.
  bool set_units(std::uint32_t f, std::string& err) {
    std::uint64_t scale = 1;
    for (int e = opt.timescale_exp; e < 0; ++e) scale *= 10;
    if (scale < f) {
      int finest = 0;
      for (std::uint64_t s = 1; s < f; s *= 10) --finest;
      err = fmt::format(
          "{}: timescale {} is longer than a clock cycle ({:.1f} ns at {} MHz): use {} or finer",
          opt.path, unit_text(opt.timescale_exp), 1e9 / f, mhz_text(f), unit_text(finest));
      return false;
    }
    const std::uint64_t g = std::gcd(scale, std::uint64_t{f});
    num = scale / g;
    den = f / g;
    half = f / 2 / g;
    return true;
  }
  // A time past 2^64 units is refused (the first failure): VCD and FST times are 64 bits.
  std::uint64_t units(std::uint64_t cycle) {
    if (cycle <= (UINT64_MAX - half) / num) return (cycle * num + half) / den;
    __extension__ using u128 = unsigned __int128;
    const u128 t = (static_cast<u128>(cycle) * num + half) / den;
    if (t <= UINT64_MAX) return static_cast<std::uint64_t>(t);
    if (error.empty()) {
      error = fmt::format("{}: cycle {} is past the last time a waveform in units of {} can hold",
                          opt.path, cycle, unit_text(opt.timescale_exp));
    }
    return UINT64_MAX;
  }

  // Takes every change before `upto` out of the streams, merged in (cycle, seq) order: up to the
  // window's first cycle they set the values it opens with (so a pin set at that cycle is dumped
  // once, with its value then); after it they are written.
  void drain(std::uint64_t upto) {
    settle_line(upto);
    std::vector<Stream*> streams;
    for (const auto& s : sources) {
      streams.push_back(&s->ahead);
      streams.push_back(&s->others);
    }
    std::vector<std::size_t> taken(streams.size(), 0);
    for (;;) {
      const Event* e = nullptr;
      std::size_t from = 0;
      for (std::size_t k = 0; k < streams.size(); ++k) {
        const std::vector<Event>& ev = streams[k]->events;
        if (taken[k] < ev.size() && ev[taken[k]].cycle < upto &&
            (e == nullptr || before(ev[taken[k]], *e))) {
          e = &ev[taken[k]];
          from = k;
        }
      }
      if (e == nullptr) break;
      if (!opened && e->cycle > opt.from) open();
      if (!opened) {
        cur[e->var] = e->value;
      } else {
        write(*e);
      }
      ++taken[from];
    }
    for (std::size_t k = 0; k < streams.size(); ++k) {
      streams[k]->drop(taken[k]);
      buffered -= taken[k];
    }
    drained_to = std::max(drained_to, upto);
  }

  // The header and the values in force at the window's start.
  void open() {
    opened = true;
    step_cycle = opt.from;
    last_t = step_t = units(opt.from);
    if (opt.fst) {
      open_fst();
    } else {
      open_vcd();
    }
  }

  // The scopes of a variable below the top (none in the logic-analyser form) and its leaf.
  [[nodiscard]] std::pair<std::vector<std::string>, std::string> path(const Var& v) const {
    std::vector<std::string> scopes;
    std::size_t at = 0;
    for (std::size_t dot = v.name.find('.'); dot != std::string::npos; dot = v.name.find('.', at)) {
      scopes.push_back(v.name.substr(at, dot - at));
      at = dot + 1;
    }
    std::string leaf = v.name.substr(at);
    if (!opt.flat) return {scopes, leaf};
    // One scope: a station's pins as station5_spc3_rxd, the line's level as `line`.
    if (v.name == kLineSignals[kLineLevel].name) return {{}, "line"};
    return {{}, scopes.size() > 1 ? scopes.front() + "_" + leaf : leaf};
  }

  // Every variable in order, the scopes opened and closed around them as their names say.
  template <typename Scope, typename Up, typename Decl>
  void declare(Scope scope, Up up, Decl decl) const {
    std::vector<std::string> open_scopes;
    for (std::size_t i = 0; i < vars.size(); ++i) {
      const auto [scopes, leaf] = path(vars[i]);
      std::size_t same = 0;
      while (same < open_scopes.size() && same < scopes.size() && open_scopes[same] == scopes[same])
        ++same;
      for (; open_scopes.size() > same; open_scopes.pop_back()) up();
      for (; open_scopes.size() < scopes.size(); open_scopes.push_back(scopes[open_scopes.size()]))
        scope(scopes[open_scopes.size()]);
      decl(i, leaf);
    }
    for (; !open_scopes.empty(); open_scopes.pop_back()) up();
  }

  void open_fst() {
    // fstapi opens the file by name (it unlinks it first): it writes a regular file of ours.
    const std::string name = out.library_path();
    fst = name.empty() ? nullptr : fstWriterCreate(name.c_str(), 1);
    if (fst == nullptr) {
      if (error.empty())
        error = name.empty() ? out.error() : fmt::format("{}: cannot write", opt.path);
      return;
    }
    fstWriterSetTimescale(fst, opt.timescale_exp);
    fstWriterSetVersion(fst, "dpc31emu");
    fstWriterSetScope(fst, FST_ST_VCD_MODULE, top.c_str(), nullptr);
    declare(
        [&](const std::string& s) {
          fstWriterSetScope(fst, FST_ST_VCD_MODULE, s.c_str(), nullptr);
        },
        [&] { fstWriterSetUpscope(fst); },
        [&](std::size_t i, const std::string& leaf) {
          handle[i] =
              fstWriterCreateVar(fst, FST_VT_VCD_WIRE, FST_VD_IMPLICIT,
                                 static_cast<std::uint32_t>(vars[i].width), leaf.c_str(), 0);
        });
    fstWriterSetUpscope(fst);
    fstWriterEmitTimeChange(fst, last_t);
    for (std::size_t i = 0; i < vars.size(); ++i)
      fstWriterEmitValueChange(fst, handle[i], bits(cur[i], vars[i].width).c_str());
  }

  void open_vcd() {
    std::FILE* f = out.stream();
    fmt::print(f, "$date dpc31emu $end\n$version dpc31emu {} MHz clock $end\n$timescale {} $end\n",
               mhz_text(clock_hz), unit_text(opt.timescale_exp));
    fmt::print(f, "$scope module {} $end\n", top);
    // One chip: a signal's identifier is its place in the list, whatever was selected (files of
    // older runs keep theirs); a segment numbers its variables.
    for (std::size_t i = 0; i < vars.size(); ++i)
      id[i] = wavediff::vcd_id(line == nullptr ? vars[i].sig : i);
    declare([&](const std::string& s) { fmt::print(f, "$scope module {} $end\n", s); },
            [&] { fmt::print(f, "$upscope $end\n"); },
            [&](std::size_t i, const std::string& leaf) {
              fmt::print(f, "$var wire {} {} {} $end\n", vars[i].width, id[i], leaf);
            });
    fmt::print(f, "$upscope $end\n$enddefinitions $end\n#{}\n$dumpvars\n", last_t);
    body = std::make_unique<VcdBody>(f);
    for (std::size_t i = 0; i < vars.size(); ++i) body->value(id[i], vars[i].width, cur[i]);
    body->flush();
    std::fputs("$end\n", f);
  }

  void write(const Event& e) {
    if (e.cycle != step_cycle) {
      step_cycle = e.cycle;
      const std::uint64_t t = units(e.cycle);
      if (t != step_t) write_step();
      step_t = t;
    }
    if (!in_step[e.var]) {
      in_step[e.var] = true;
      step_vars.push_back(e.var);
    }
    next[e.var] = e.value;
  }

  // The values of step_t that differ from those written before it.
  void write_step() {
    for (const std::uint32_t i : step_vars) {
      in_step[i] = false;
      if (next[i] == cur[i]) continue;
      cur[i] = next[i];
      const Var& v = vars[i];
      const Source& s = *sources[v.source];
      if (s.chip != nullptr && (v.sig == kDpState || v.sig == kWdState) && markers.size() < 26) {
        const std::string m = v.sig == kDpState
                                  ? fmt::format("dp_state={}", dp_state_name(DpState(cur[i])))
                                  : fmt::format("wd_state={}", wd_state_name(WdState(cur[i])));
        markers.emplace_back(step_t, s.scope.empty() ? m : s.scope + " " + m);
      }
      if (opt.fst) {
        if (fst == nullptr) continue;
        if (step_t != last_t) fstWriterEmitTimeChange(fst, step_t);
        fstWriterEmitValueChange(fst, handle[i], bits(cur[i], v.width).c_str());
      } else {
        if (step_t != last_t) body->time(step_t);
        body->value(id[i], v.width, cur[i]);
      }
      last_t = step_t;
    }
    step_vars.clear();
  }

  void add_var(Source& s, std::uint8_t sig, const SignalDef& d) {
    s.var[sig] = static_cast<std::uint32_t>(vars.size());
    vars.push_back({full_name(s, d.name), d.width, sources.size() - 1, sig});
    cur.push_back(0);
    next.push_back(0);
    in_step.push_back(false);
    id.emplace_back();
    handle.push_back(0);
  }

  bool attach_chip(Chip& chip, std::string scope, std::string& err);
};

bool Recorder::Impl::attach_chip(Chip& chip, std::string scope, std::string& err) {
  if (!open_outputs(err)) return false;
  if (vars.size() + kCount > UINT16_MAX) {
    err = fmt::format("{}: too many signals for one waveform", opt.path);
    return false;
  }
  clock_hz = chip.clock_hz();
  if (!set_units(clock_hz, err)) return false;
  // The window's start is written as a time even after the run's end: it must fit.
  units(opt.from);
  if (!error.empty()) {
    err = error;
    return false;
  }
  sources.push_back(std::make_unique<Source>());
  Source& s = *sources.back();
  s.chip = &chip;
  s.scope = std::move(scope);
  s.var.fill(kNoVar);
  s.sampled.fill(0xFFFFFFFF);
  // Declared scope by scope: PB3 and the C31's INT0 (newer signals, last in the list) beside
  // the other pins.
  const auto add = [&](std::size_t i) {
    const std::string full = full_name(s, kSignals[i].name);
    if (chip_has(chip, i) && take(kSignals[i].name, full, kSignals[i].width))
      add_var(s, static_cast<std::uint8_t>(i), kSignals[i]);
  };
  for (std::size_t i = 0; i < kCount; ++i) {
    if (i != kPb3 && i != kService && i != kC31Int0) add(i);
    if (i == kXInt) {
      add(kPb3);
      add(kC31Int0);
    }
    if (i == kBaud) add(kService);
  }
  // One chip (a segment's line has its own): a file without a variable helps nobody, and fstapi
  // writes no FST at all for it.
  if (line == nullptr && vars.empty()) {
    err = fmt::format(
        "{}: no 1-bit signal matches --signals: the logic-analyser form has only those", opt.path);
    sources.pop_back();
    return false;
  }
  if (line == nullptr && !session_has_channels(err)) return false;
  Source* src = &s;
  push(s, chip.cycle(), kRxd, 1);
  push(s, chip.cycle(), kTxd, chip.txd_pin() ? 1 : 0);
  push(s, chip.cycle(), kBusRd, 0);
  push(s, chip.cycle(), kBusWr, 0);
  push(s, chip.cycle(), kService, 0xFF);  // no request yet
  sample(s, chip.cycle());
  chip.on_rxd(while_live([this, src](std::uint64_t c, bool l) { push(*src, c, kRxd, l ? 1 : 0); }));
  chip.on_txd(while_live([this, src](std::uint64_t c, bool l) { push(*src, c, kTxd, l ? 1 : 0); }));
  chip.on_irq_change(while_live([this, src](std::uint64_t c, bool) { sample(*src, c); }));
  chip.on_state_change(while_live([this, src](std::uint64_t c) { sample(*src, c); }));
  if (s.var[kService] != kNoVar) {
    // Reported when the request is acted on (the stop sample of its last character).
    chip.on_telegram(while_live([this, src](const Telegram& t) {
      const int code = t.from_chip ? -1 : request_service(t.bytes);
      if (code >= 0) push(*src, src->chip->cycle(), kService, static_cast<std::uint32_t>(code));
    }));
  }
  chip.on_bus_access(while_live([this, src](std::uint64_t c, const BusAccess& e) {
    const Sig strobe = e.write ? kBusWr : kBusRd;
    push(*src, c, kBusAddr, e.addr);
    if (e.write) push(*src, c, kBusData, e.data);
    push(*src, c, strobe, 1);  // the strobe is high for the access's completion cycle
    push(*src, c + 1, strobe, 0);
  }));
  return true;
}

Recorder::Recorder(const Options& o) : impl_(std::make_unique<Impl>()) { impl_->opt = o; }
Recorder::~Recorder() = default;

bool Recorder::open(std::string& error) { return impl_->open_outputs(error); }

bool Recorder::check_signals(std::string& error) const {
  const Impl& m = *impl_;
  for (const std::string& p : m.opt.signals) {
    const bool any = std::any_of(kSignals.begin(), kSignals.end(),
                                 [&](const SignalDef& d) { return glob(p, d.name); });
    if (!any) {
      error = fmt::format("no signal matches '{}' (see docs/waveforms.md)", p);
      return false;
    }
  }
  // A PulseView session needs a line to decode: one chip's RxD or TxD (every chip has both), a
  // segment's line (attach_line checks which of them the run has).
  if (!m.opt.pvs.empty() && !m.take("pins.rxd", "pins.rxd", 1) &&
      !m.take("pins.txd", "pins.txd", 1) && !m.take("line.level", "line.level", 1)) {
    error = m.no_session_channel();
    return false;
  }
  return true;
}

bool Recorder::attach(Chip& chip, std::string& error) {
  if (!check_signals(error)) return false;
  // check_signals() knows no chip: pins.pb3 matches there, and is a DPC31's only.
  for (const std::string& p : impl_->opt.signals) {
    bool any = false;
    for (std::size_t i = 0; i < kCount; ++i)
      any = any || (chip_has(chip, i) && glob(p, kSignals[i].name));
    if (!any) {
      error = fmt::format("no signal of the {} matches '{}' (see docs/waveforms.md)",
                          profile_name(chip.profile().id), p);
      return false;
    }
  }
  return impl_->attach_chip(chip, {}, error);
}

bool Recorder::attach_station(Chip& chip, const std::string& scope, std::string& error) {
  Impl& m = *impl_;
  if (m.line == nullptr) {
    // The first station: the line's variables first, at the top; the stations' scopes follow.
    if (!m.open_outputs(error)) return false;
    m.top = "segment";
    m.sources.push_back(std::make_unique<Impl::Source>());
    Impl::Source& s = *m.sources.back();
    s.var.fill(Impl::kNoVar);
    m.line = &s;
    for (std::uint8_t i = 0; i < kLineCount; ++i) {
      if (m.take(kLineSignals[i].name, kLineSignals[i].name, kLineSignals[i].width))
        m.add_var(s, i, kLineSignals[i]);
    }
    m.push(s, 0, kLineLevel, 1);
    m.push(s, 0, kLineDriver, kNoDriver);
  }
  return m.attach_chip(chip, scope, error);
}

void Recorder::detach_station() {
  Impl& m = *impl_;
  if (m.line == nullptr || m.horizon || m.sources.size() < 2) {
    throw std::logic_error("waveform: detach_station without a station attached before the line");
  }
  // Nothing is drained before the line is attached (now()): its changes are all in its queues.
  m.sources.pop_back();
  if (m.sources.size() == 1) {
    m.sources.pop_back();
    m.line = nullptr;
  }
  const auto first = static_cast<std::size_t>(
      std::find_if(m.vars.begin(), m.vars.end(),
                   [&m](const Var& v) { return v.source >= m.sources.size(); }) -
      m.vars.begin());
  for (auto* v : {&m.cur, &m.next}) v->resize(first);
  m.in_step.resize(first);
  m.id.resize(first);
  m.handle.resize(first);
  m.vars.resize(first);
}

bool Recorder::attach_line(std::vector<std::uint8_t> driver_codes, std::uint32_t bit_cycles,
                           std::function<std::uint64_t()> line_final, std::string& error) {
  Impl& m = *impl_;
  if (m.line == nullptr) {
    error = fmt::format("{}: a segment's line without a station", m.opt.path);
    return false;
  }
  if (!m.session_has_channels(error)) return false;
  m.driver_codes = std::move(driver_codes);
  m.char_cycles = std::uint64_t{kUartCharBits} * bit_cycles;
  m.horizon = std::move(line_final);
  for (const std::string& p : m.opt.signals) {
    const bool any = std::any_of(m.vars.begin(), m.vars.end(), [&](const Var& v) {
      const std::size_t dot = v.name.find('.');
      return glob(p, v.name) ||
             (m.sources[v.source]->chip != nullptr && glob(p, v.name.substr(dot + 1)));
    });
    if (!any) {
      error = fmt::format("no signal matches '{}' (see docs/waveforms.md)", p);
      return false;
    }
  }
  return true;
}

void Recorder::line_edge(std::size_t from, std::uint64_t cycle, bool level) {
  if (impl_->line != nullptr) impl_->line_edge(from, cycle, level);
}

bool Recorder::finish(std::uint64_t end_cycle, std::string& error) {
  Impl& m = *impl_;
  if (!m.out.is_open() || m.sources.empty()) {
    error = fmt::format("{}: not attached to a chip", m.opt.path);
    return false;
  }
  const std::uint64_t to = std::min(m.opt.to, end_cycle + 1);
  if (m.error.empty()) m.drain(to);
  if (m.error.empty() && !m.opened) {
    m.drain(m.opt.from);  // a window that opens after the run's end: the values in force then
    m.open();
  }
  if (m.error.empty()) m.write_step();
  // The window's end; one that opened after the run's end ends where it opened.
  const std::uint64_t end_t = std::max(m.units(to), m.last_t);
  if (m.error.empty()) {
    if (m.opt.fst) {
      fstWriterEmitTimeChange(m.fst, end_t);
      fstWriterClose(m.fst);
      m.fst = nullptr;
    } else {
      if (end_t != m.last_t) m.body->time(end_t);
      m.body.reset();  // flushed
    }
  }
  if (!m.error.empty()) {
    error = m.error;
    m.out.discard();
    return false;
  }
  if (!(m.opt.fst ? m.out.commit_fst() : m.out.commit())) {
    error = m.out.error();
    return false;
  }
  if (m.gtkw.is_open()) {
    SaveFile f{m.opt.path, {}, {}, m.opt.flat, m.units(m.opt.from), end_t, m.markers, filter_dir()};
    f.top = m.top;
    f.timescale_exp = m.opt.timescale_exp;
    for (const Var& v : m.vars) {
      // The logic-analyser form: grouped by the first scope, the leaf as declared.
      f.signals.push_back(m.opt.flat ? v.name.substr(0, v.name.find('.')) + "." + m.path(v).second
                                     : v.name);
      f.widths.push_back(v.width);
    }
    if (!(m.gtkw.write(save_file_text(f)) && m.gtkw.commit())) {
      error = m.gtkw.error();
      return false;
    }
  }
  if (m.pvs.is_open()) {
    const auto [rx, tx] = m.session_channels();
    if (!(m.pvs.write(pulseview_session_text(m.opt.baud, rx, tx)) && m.pvs.commit())) {
      error = m.pvs.error();
      return false;
    }
  }
  return true;
}

}  // namespace dpc31::wave
