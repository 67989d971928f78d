#include "waveform.hpp"

#include <fmt/format.h>
#include <fnmatch.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <string_view>

#include "dpc31/reg_ids.hpp"
#include "gtkw.hpp"
#include "gtkwave/fstapi.h"
#include "outfile.hpp"
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
                                                     {"state.service", 8}}};

static_assert(std::all_of(kSignals.begin(), kSignals.end(),
                          [](const SignalDef& d) { return d.width <= 16; }),
              "Event::value holds 16 bits");

// 16 bytes: a traced run records one per change of every signal.
struct Event {
  std::uint64_t cycle;
  std::uint32_t seq;  // the order of recording, for changes in the same cycle
  std::uint16_t value;
  std::uint8_t sig;
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

// The two streams (RxD, driven ahead of time, and everything else) merged in (cycle, seq) order.
class Merged {
 public:
  Merged(const std::vector<Event>& a, const std::vector<Event>& b) : a_(a), b_(b) {}
  [[nodiscard]] const Event* peek() const {
    if (i_ < a_.size() && (j_ == b_.size() || before(a_[i_], b_[j_]))) return &a_[i_];
    return j_ < b_.size() ? &b_[j_] : nullptr;
  }
  void pop() {
    if (i_ < a_.size() && (j_ == b_.size() || before(a_[i_], b_[j_]))) {
      ++i_;
    } else {
      ++j_;
    }
  }
  [[nodiscard]] std::size_t taken_a() const { return i_; }
  [[nodiscard]] std::size_t taken_b() const { return j_; }

 private:
  const std::vector<Event>& a_;
  const std::vector<Event>& b_;
  std::size_t i_ = 0;
  std::size_t j_ = 0;
};

std::string bits(std::uint32_t v, int width) {
  std::string s;
  for (int b = width - 1; b >= 0; --b) s += ((v >> b) & 1) != 0 ? '1' : '0';
  return s;
}

// The VCD body, formatted by hand into a 16 KiB buffer: a traced run writes a line per change, and
// a formatted print per line (fmt into stdio) was a fifth of its cost (docs/performance.md, i).
class VcdBody {
 public:
  explicit VcdBody(std::FILE* f) : f_(f) {}
  VcdBody(const VcdBody&) = delete;
  VcdBody& operator=(const VcdBody&) = delete;
  ~VcdBody() { flush(); }
  // Times only grow, and a VCD of a run writes one for nearly every change: the digits above the
  // last eight are kept from the previous time, the last eight converted two at a time.
  void time(std::uint64_t t) {
    room(32);
    *p_++ = '#';
    const std::uint64_t high = t / 100'000'000;
    const auto low = static_cast<std::uint32_t>(t % 100'000'000);
    if (high == 0) {
      int n = 1;
      for (std::uint32_t v = low; v >= 10; v /= 10) ++n;
      p_ = digits(low, n, p_);
    } else {
      if (high != high_) {
        high_ = high;
        high_len_ = static_cast<std::size_t>(
            std::to_chars(high_digits_.data(), high_digits_.data() + high_digits_.size(), high)
                .ptr -
            high_digits_.data());
      }
      p_ = digits(low, 8, std::copy_n(high_digits_.data(), high_len_, p_));
    }
    *p_++ = '\n';
  }
  // `id` is the signal's identifier code; `width` 1 writes the scalar form.
  void value(std::string_view id, int width, std::uint32_t v) {
    room(id.size() + 20);
    if (width == 1) {
      *p_++ = (v & 1) != 0 ? '1' : '0';
    } else {
      *p_++ = 'b';
      for (int b = width - 1; b >= 0; --b) *p_++ = ((v >> b) & 1) != 0 ? '1' : '0';
      *p_++ = ' ';
    }
    p_ = std::copy(id.begin(), id.end(), p_);
    *p_++ = '\n';
  }
  void flush() {
    std::fwrite(buf_.get(), 1, static_cast<std::size_t>(p_ - buf_.get()), f_);
    p_ = buf_.get();
  }

 private:
  // The last `n` decimal digits of `v` (with leading zeros) at `p`; returns the end.
  static char* digits(std::uint32_t v, int n, char* p) {
    static constexpr char kPairs[] =
        "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
        "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
        "8081828384858687888990919293949596979899";
    char* const end = p + n;
    for (; n >= 2; n -= 2, v /= 100) {
      std::memcpy(p + n - 2, &kPairs[2 * (v % 100)], 2);
    }
    if (n == 1) *p = static_cast<char>('0' + v % 10);
    return end;
  }
  char* end() { return buf_.get() + kSize; }
  void room(std::size_t n) {
    if (static_cast<std::size_t>(end() - p_) < n) flush();
  }
  std::FILE* f_;
  std::uint64_t high_ = 0;
  std::array<char, 20> high_digits_{};
  std::size_t high_len_ = 0;
  static constexpr std::size_t kSize = 16 * 1024;
  std::unique_ptr<char[]> buf_ = std::make_unique_for_overwrite<char[]>(kSize);
  char* p_ = buf_.get();
};

}  // namespace

const std::vector<SignalDef>& signal_list() {
  static const std::vector<SignalDef> list(kSignals.begin(), kSignals.end());
  return list;
}

// Changes are written as the run goes: every change before the chip's current cycle is final
// (sources report at or after it; RxD ahead of it), so the streams hold only what is ahead and
// what came since the last drain, and memory stays bounded however long the run.
struct Recorder::Impl {
  // A drain runs after this many new changes: the buffer stays within about 64 KiB, small enough
  // to be reused from the heap (larger, it came and went as fresh pages on every run).
  static constexpr std::size_t kDrainEvery = 4096;

  Options opt;
  Chip* chip = nullptr;
  std::uint32_t clock_hz = 48'000'000;
  std::vector<bool> selected = std::vector<bool>(kCount, false);
  std::vector<std::size_t> order;  // declaration order of the selected signals
  Stream rxd;                      // RxD edges, driven (and reported) ahead of time
  Stream others;                   // the rest, reported when time reaches them
  std::size_t next_drain = kDrainEvery;
  std::vector<std::uint32_t> sampled = std::vector<std::uint32_t>(kCount, 0xFFFFFFFF);
  std::uint32_t seq = 0;
  std::uint64_t drained_to = 0;  // every change before this cycle has been taken
  std::string error;             // the first failure, reported by finish()
  outfile::OutFile out;          // opened by attach(), so that a bad path is found before the run
  outfile::OutFile gtkw;         // the save file (Options::gtkw), likewise
  std::vector<std::pair<std::uint64_t, std::string>> markers;  // its named markers (26 at most)

  // What has been written: the values in force, and the window's start once dumped.
  std::array<std::uint32_t, kCount> cur{};
  bool opened = false;
  std::uint64_t last_cycle = 0;
  std::uint64_t last_t = 0;
  std::array<std::string, kCount> id;
  std::unique_ptr<VcdBody> body;
  void* fst = nullptr;
  std::array<fstHandle, kCount> handle{};

  ~Impl() {
    if (fst != nullptr) fstWriterClose(fst);  // an unfinished recording: `out` discards it
  }

  void push(std::uint64_t cycle, Sig s, std::uint32_t v) {
    if (!selected[s] || cycle >= opt.to || !error.empty()) return;
    if (cycle < drained_to) {
      error = fmt::format("{}: a change at cycle {} was reported after cycle {} was written",
                          opt.path, cycle, drained_to);
      return;
    }
    if (seq == UINT32_MAX) {
      error = fmt::format("{}: more than {} changes in one recording", opt.path, seq);
      return;
    }
    (s == kRxd ? rxd : others)
        .push({cycle, seq++, static_cast<std::uint16_t>(v), static_cast<std::uint8_t>(s)});
    if (rxd.events.size() + others.events.size() >= next_drain) {
      drain(chip->cycle());
      next_drain = rxd.events.size() + others.events.size() + kDrainEvery;
    }
  }
  // State signals: recorded when they change.
  void sample(std::uint64_t cycle) {
    const ChipProbe c = chip->probe();
    const std::uint32_t now[] = {static_cast<std::uint32_t>(c.dp_state),
                                 static_cast<std::uint32_t>(c.wd_state),
                                 c.baud_code,
                                 c.irr,
                                 c.dout_buffer_sm,
                                 c.din_buffer_sm,
                                 c.diag_buffer_sm,
                                 chip->x_int_pin() ? 1u : 0u,
                                 chip->pb3_pin() ? 1u : 0u};
    const Sig sigs[] = {kDpState, kWdState, kBaud, kIrr, kDoutSm, kDinSm, kDiagSm, kXInt, kPb3};
    for (std::size_t i = 0; i < std::size(sigs); ++i) {
      if (sampled[sigs[i]] == now[i]) continue;
      sampled[sigs[i]] = now[i];
      push(cycle, sigs[i], now[i]);
    }
  }
  // cycle -> time units, rounded to the nearest unit: floor((cycle x 10^-exp + f / 2) / f),
  // computed from the absolute cycle so the rounding never accumulates. With g = gcd(10^-exp, f)
  // that is floor((cycle x num + floor(f / 2 / g)) / den), in 64 bits while it fits.
  std::uint64_t num = 1;
  std::uint64_t den = 1;
  std::uint64_t half = 0;
  void set_units(std::uint32_t f) {
    std::uint64_t scale = 1;
    for (int e = opt.timescale_exp; e < 0; ++e) scale *= 10;
    const std::uint64_t g = std::gcd(scale, std::uint64_t{f});
    num = scale / g;
    den = f / g;
    half = f / 2 / g;
  }
  [[nodiscard]] std::uint64_t units(std::uint64_t cycle) const {
    if (cycle <= (UINT64_MAX - half) / num) return (cycle * num + half) / den;
    __extension__ using u128 = unsigned __int128;
    return static_cast<std::uint64_t>((static_cast<u128>(cycle) * num + half) / den);
  }

  // Takes every change before `upto` out of the streams: up to the window's first cycle they set
  // the values it opens with (so a pin set at that cycle is dumped once, with its value then);
  // after it they are written.
  void drain(std::uint64_t upto) {
    Merged events(rxd.events, others.events);
    for (; events.peek() != nullptr && events.peek()->cycle < upto; events.pop()) {
      const Event& e = *events.peek();
      if (!opened && e.cycle > opt.from) open();
      if (!opened) {
        cur[e.sig] = e.value;
      } else {
        write(e);
      }
    }
    rxd.drop(events.taken_a());
    others.drop(events.taken_b());
    drained_to = std::max(drained_to, upto);
  }

  // The header and the values in force at the window's start.
  void open() {
    opened = true;
    last_cycle = opt.from;
    last_t = units(opt.from);
    if (opt.fst) {
      open_fst();
    } else {
      open_vcd();
    }
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
    fstWriterSetScope(fst, FST_ST_VCD_MODULE, "dpc31", nullptr);
    std::string scope;
    for (std::size_t i : order) {
      std::string name = kSignals[i].name;
      const auto dot = name.find('.');
      const std::string sc = opt.flat ? "" : name.substr(0, dot);
      if (!opt.flat && sc != scope) {
        if (!scope.empty()) fstWriterSetUpscope(fst);
        fstWriterSetScope(fst, FST_ST_VCD_MODULE, sc.c_str(), nullptr);
        scope = sc;
      }
      const std::string leaf = name.substr(dot + 1);
      handle[i] =
          fstWriterCreateVar(fst, FST_VT_VCD_WIRE, FST_VD_IMPLICIT,
                             static_cast<std::uint32_t>(kSignals[i].width), leaf.c_str(), 0);
    }
    if (!scope.empty()) fstWriterSetUpscope(fst);
    fstWriterSetUpscope(fst);
    fstWriterEmitTimeChange(fst, last_t);
    for (std::size_t i : order)
      fstWriterEmitValueChange(fst, handle[i], bits(cur[i], kSignals[i].width).c_str());
  }

  void open_vcd() {
    std::FILE* f = out.stream();
    static constexpr const char* kUnit[] = {"s", "ms", "us", "ns", "ps", "fs"};
    const int e = -opt.timescale_exp;
    fmt::print(f,
               "$date dpc31emu $end\n$version dpc31emu {} MHz clock $end\n$timescale {}{} $end\n",
               clock_hz / 1'000'000,
               e % 3 == 0   ? 1
               : e % 3 == 1 ? 100
                            : 10,
               kUnit[(e + 2) / 3]);
    fmt::print(f, "$scope module dpc31 $end\n");
    std::string scope;
    for (std::size_t i = 0; i < kCount; ++i) id[i] = wavediff::vcd_id(i);
    for (std::size_t i : order) {
      const std::string name = kSignals[i].name;
      const auto dot = name.find('.');
      const std::string sc = name.substr(0, dot);
      if (!opt.flat && sc != scope) {
        if (!scope.empty()) fmt::print(f, "$upscope $end\n");
        fmt::print(f, "$scope module {} $end\n", sc);
        scope = sc;
      }
      fmt::print(f, "$var wire {} {} {} $end\n", kSignals[i].width, id[i], name.substr(dot + 1));
    }
    if (!opt.flat && !scope.empty()) fmt::print(f, "$upscope $end\n");
    fmt::print(f, "$upscope $end\n$enddefinitions $end\n#{}\n$dumpvars\n", last_t);
    body = std::make_unique<VcdBody>(f);
    for (std::size_t i : order) body->value(id[i], kSignals[i].width, cur[i]);
    body->flush();
    std::fputs("$end\n", f);
  }

  void write(const Event& e) {
    if (cur[e.sig] == e.value) return;
    cur[e.sig] = e.value;
    if ((e.sig == kDpState || e.sig == kWdState) && markers.size() < 26) {
      markers.emplace_back(units(e.cycle),
                           e.sig == kDpState
                               ? fmt::format("dp_state={}", dp_state_name(DpState(e.value)))
                               : fmt::format("wd_state={}", wd_state_name(WdState(e.value))));
    }
    if (opt.fst) {
      if (fst == nullptr) return;
      fstWriterEmitTimeChange(fst, units(e.cycle));
      fstWriterEmitValueChange(fst, handle[e.sig], bits(e.value, kSignals[e.sig].width).c_str());
      return;
    }
    if (e.cycle != last_cycle) {
      last_cycle = e.cycle;
      const std::uint64_t t = units(e.cycle);
      if (t != last_t) body->time(t);
      last_t = t;
    }
    body->value(id[e.sig], kSignals[e.sig].width, e.value);
  }
};

Recorder::Recorder(const Options& o) : impl_(std::make_unique<Impl>()) { impl_->opt = o; }
Recorder::~Recorder() = default;

bool Recorder::attach(Chip& chip, std::string& error) {
  Impl& m = *impl_;
  if (m.opt.timescale_exp > 0 || m.opt.timescale_exp < -15) {
    error = "timescale must be between 1 fs and 1 s";
    return false;
  }
  for (std::size_t i = 0; i < kCount; ++i) {
    bool take = m.opt.signals.empty();
    for (const std::string& p : m.opt.signals)
      take = take || fnmatch(p.c_str(), kSignals[i].name, 0) == 0;
    if (m.opt.flat && kSignals[i].width != 1) take = false;
    if (i == kPb3 && chip.profile().id != Profile::dpc31) take = false;  // a DPC31 port
    m.selected[i] = take;
  }
  for (const std::string& p : m.opt.signals) {
    const bool any = std::any_of(kSignals.begin(), kSignals.end(), [&](const SignalDef& d) {
      return fnmatch(p.c_str(), d.name, 0) == 0;
    });
    if (!any) {
      error = fmt::format("no signal matches '{}' (see docs/waveforms.md)", p);
      return false;
    }
  }
  if (!m.out.open(m.opt.path)) {
    error = m.out.error();
    return false;
  }
  if (!m.opt.gtkw.empty() && !m.gtkw.open(m.opt.gtkw)) {
    error = m.gtkw.error();
    return false;
  }
  m.chip = &chip;
  m.clock_hz = chip.clock_hz();
  m.set_units(m.clock_hz);
  // Declared scope by scope: PB3 (the newest signal, last in the list) beside the other pins.
  for (std::size_t i = 0; i < kCount; ++i) {
    if (i != kPb3 && i != kService && m.selected[i]) m.order.push_back(i);
    if (i == kXInt && m.selected[kPb3]) m.order.push_back(kPb3);
    if (i == kBaud && m.selected[kService]) m.order.push_back(kService);
  }
  Impl* im = &m;
  m.push(chip.cycle(), kRxd, 1);
  m.push(chip.cycle(), kTxd, chip.txd_pin() ? 1 : 0);
  m.push(chip.cycle(), kBusRd, 0);
  m.push(chip.cycle(), kBusWr, 0);
  m.push(chip.cycle(), kService, 0xFF);  // no request yet
  m.sample(chip.cycle());
  chip.on_rxd([im](std::uint64_t c, bool l) { im->push(c, kRxd, l ? 1 : 0); });
  chip.on_txd([im](std::uint64_t c, bool l) { im->push(c, kTxd, l ? 1 : 0); });
  chip.on_irq_change([im](std::uint64_t c, bool) { im->sample(c); });
  chip.on_state_change([im](std::uint64_t c) { im->sample(c); });
  if (m.selected[kService]) {
    // Reported when the request is acted on (the stop sample of its last character).
    chip.on_telegram([im](const Telegram& t) {
      const int code = t.from_chip ? -1 : request_service(t.bytes);
      if (code >= 0) im->push(im->chip->cycle(), kService, static_cast<std::uint32_t>(code));
    });
  }
  chip.on_bus_access([im](std::uint64_t c, const BusAccess& e) {
    const Sig strobe = e.write ? kBusWr : kBusRd;
    im->push(c, kBusAddr, e.addr);
    if (e.write) im->push(c, kBusData, e.data);
    im->push(c, strobe, 1);  // the strobe is high for the access's completion cycle
    im->push(c + 1, strobe, 0);
  });
  return true;
}

bool Recorder::finish(std::uint64_t end_cycle, std::string& error) {
  Impl& m = *impl_;
  if (!m.out.is_open()) {
    error = fmt::format("{}: not attached to a chip", m.opt.path);
    return false;
  }
  const std::uint64_t to = std::min(m.opt.to, end_cycle + 1);
  if (m.error.empty()) m.drain(to);
  if (m.error.empty() && !m.opened) {
    m.drain(m.opt.from);  // a window that opens after the run's end: the values in force then
    m.open();
  }
  if (m.error.empty()) {
    if (m.opt.fst) {
      fstWriterEmitTimeChange(m.fst, m.units(to));
      fstWriterClose(m.fst);
      m.fst = nullptr;
    } else {
      if (m.units(to) != m.last_t) m.body->time(m.units(to));
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
    SaveFile f{m.opt.path, {}, {}, m.opt.flat, m.units(to), m.markers, filter_dir()};
    for (std::size_t i : m.order) {
      f.signals.emplace_back(kSignals[i].name);
      f.widths.push_back(kSignals[i].width);
    }
    if (!(m.gtkw.write(save_file_text(f)) && m.gtkw.commit())) {
      error = m.gtkw.error();
      return false;
    }
  }
  return true;
}

}  // namespace dpc31::wave
