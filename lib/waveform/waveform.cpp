#include "waveform.hpp"

#include <fmt/format.h>
#include <fnmatch.h>

#include <algorithm>
#include <array>
#include <cstdio>

#include "dpc31/reg_ids.hpp"
#include "gtkwave/fstapi.h"
#include "outfile.hpp"
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
  kPb3,  // last, so the older signals keep their VCD identifiers
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
                                                     {"pins.pb3", 1}}};

struct Event {
  std::uint64_t cycle;
  std::uint64_t seq;  // keeps the order of changes within one cycle
  std::uint16_t sig;
  std::uint32_t value;
};

std::string bits(std::uint32_t v, int width) {
  std::string s;
  for (int b = width - 1; b >= 0; --b) s += ((v >> b) & 1) != 0 ? '1' : '0';
  return s;
}

}  // namespace

const std::vector<SignalDef>& signal_list() {
  static const std::vector<SignalDef> list(kSignals.begin(), kSignals.end());
  return list;
}

struct Recorder::Impl {
  Options opt;
  Chip* chip = nullptr;
  std::uint32_t clock_hz = 48'000'000;
  std::vector<bool> selected = std::vector<bool>(kCount, false);
  std::vector<Event> events;
  std::vector<std::uint32_t> sampled = std::vector<std::uint32_t>(kCount, 0xFFFFFFFF);
  std::uint64_t seq = 0;
  outfile::OutFile out;  // opened by attach(), so that a bad path is found before the run

  void push(std::uint64_t cycle, Sig s, std::uint32_t v) {
    if (!selected[s] || cycle >= opt.to) return;
    events.push_back({cycle, seq++, s, v});
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
  // cycle -> time units, rounded to the nearest unit (computed from the absolute cycle, so the
  // rounding never accumulates).
  [[nodiscard]] std::uint64_t units(std::uint64_t cycle) const {
    __extension__ using u128 = unsigned __int128;
    u128 scale = 1;
    for (int e = opt.timescale_exp; e < 0; ++e) scale *= 10;
    return static_cast<std::uint64_t>((static_cast<u128>(cycle) * scale + clock_hz / 2) / clock_hz);
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
  m.chip = &chip;
  m.clock_hz = chip.clock_hz();
  Impl* im = &m;
  m.push(chip.cycle(), kRxd, 1);
  m.push(chip.cycle(), kTxd, chip.txd_pin() ? 1 : 0);
  m.push(chip.cycle(), kBusRd, 0);
  m.push(chip.cycle(), kBusWr, 0);
  m.sample(chip.cycle());
  chip.on_rxd([im](std::uint64_t c, bool l) { im->push(c, kRxd, l ? 1 : 0); });
  chip.on_txd([im](std::uint64_t c, bool l) { im->push(c, kTxd, l ? 1 : 0); });
  chip.on_irq_change([im](std::uint64_t c, bool) { im->sample(c); });
  chip.on_state_change([im](std::uint64_t c) { im->sample(c); });
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
  std::stable_sort(m.events.begin(), m.events.end(), [](const Event& a, const Event& b) {
    return a.cycle != b.cycle ? a.cycle < b.cycle : a.seq < b.seq;
  });
  const std::uint64_t to = std::min(m.opt.to, end_cycle + 1);
  if (!m.out.is_open()) {
    error = fmt::format("{}: not attached to a chip", m.opt.path);
    return false;
  }
  std::vector<std::uint32_t> cur(kCount, 0);
  // Declared scope by scope: PB3 (the newest signal, last in the list) beside the other pins.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < kCount; ++i) {
    if (i != kPb3 && m.selected[i]) order.push_back(i);
    if (i == kXInt && m.selected[kPb3]) order.push_back(kPb3);
  }
  // The values in force when the window opens, then the changes inside it.
  std::size_t k = 0;
  for (; k < m.events.size() && m.events[k].cycle < m.opt.from; ++k) {
    cur[m.events[k].sig] = m.events[k].value;
  }
  if (m.opt.fst) {
    // fstapi opens the file by name (it unlinks it first): it writes a regular file of ours.
    const std::string name = m.out.library_path();
    void* ctx = name.empty() ? nullptr : fstWriterCreate(name.c_str(), 1);
    if (ctx == nullptr) {
      error = name.empty() ? m.out.error() : fmt::format("{}: cannot write", m.opt.path);
      m.out.discard();
      return false;
    }
    fstWriterSetTimescale(ctx, m.opt.timescale_exp);
    fstWriterSetVersion(ctx, "dpc31emu");
    fstWriterSetScope(ctx, FST_ST_VCD_MODULE, "dpc31", nullptr);
    std::vector<fstHandle> h(kCount, 0);
    std::string scope;
    for (std::size_t i : order) {
      std::string name = kSignals[i].name;
      const auto dot = name.find('.');
      const std::string sc = m.opt.flat ? "" : name.substr(0, dot);
      if (!m.opt.flat && sc != scope) {
        if (!scope.empty()) fstWriterSetUpscope(ctx);
        fstWriterSetScope(ctx, FST_ST_VCD_MODULE, sc.c_str(), nullptr);
        scope = sc;
      }
      const std::string leaf = name.substr(dot + 1);
      h[i] = fstWriterCreateVar(ctx, FST_VT_VCD_WIRE, FST_VD_IMPLICIT,
                                static_cast<std::uint32_t>(kSignals[i].width), leaf.c_str(), 0);
    }
    if (!scope.empty()) fstWriterSetUpscope(ctx);
    fstWriterSetUpscope(ctx);
    fstWriterEmitTimeChange(ctx, m.units(m.opt.from));
    for (std::size_t i : order)
      fstWriterEmitValueChange(ctx, h[i], bits(cur[i], kSignals[i].width).c_str());
    for (; k < m.events.size() && m.events[k].cycle < to; ++k) {
      const Event& e = m.events[k];
      if (cur[e.sig] == e.value) continue;
      cur[e.sig] = e.value;
      fstWriterEmitTimeChange(ctx, m.units(e.cycle));
      fstWriterEmitValueChange(ctx, h[e.sig], bits(e.value, kSignals[e.sig].width).c_str());
    }
    fstWriterEmitTimeChange(ctx, m.units(to));
    fstWriterClose(ctx);
  } else {
    std::FILE* f = m.out.stream();
    static constexpr const char* kUnit[] = {"s", "ms", "us", "ns", "ps", "fs"};
    const int e = -m.opt.timescale_exp;
    fmt::print(f,
               "$date dpc31emu $end\n$version dpc31emu {} MHz clock $end\n$timescale {}{} $end\n",
               m.clock_hz / 1'000'000,
               e % 3 == 0   ? 1
               : e % 3 == 1 ? 100
                            : 10,
               kUnit[(e + 2) / 3]);
    fmt::print(f, "$scope module dpc31 $end\n");
    std::string scope;
    for (std::size_t i : order) {
      const std::string name = kSignals[i].name;
      const auto dot = name.find('.');
      const std::string sc = name.substr(0, dot);
      if (!m.opt.flat && sc != scope) {
        if (!scope.empty()) fmt::print(f, "$upscope $end\n");
        fmt::print(f, "$scope module {} $end\n", sc);
        scope = sc;
      }
      fmt::print(f, "$var wire {} {} {} $end\n", kSignals[i].width, wavediff::vcd_id(i),
                 name.substr(dot + 1));
    }
    if (!m.opt.flat && !scope.empty()) fmt::print(f, "$upscope $end\n");
    fmt::print(f, "$upscope $end\n$enddefinitions $end\n#{}\n$dumpvars\n", m.units(m.opt.from));
    auto value = [&](std::size_t i, std::uint32_t v) {
      if (kSignals[i].width == 1) {
        fmt::print(f, "{}{}\n", v & 1, wavediff::vcd_id(i));
      } else {
        fmt::print(f, "b{} {}\n", bits(v, kSignals[i].width), wavediff::vcd_id(i));
      }
    };
    for (std::size_t i : order) value(i, cur[i]);
    fmt::print(f, "$end\n");
    std::uint64_t last_t = m.units(m.opt.from);
    for (; k < m.events.size() && m.events[k].cycle < to; ++k) {
      const Event& ev = m.events[k];
      if (cur[ev.sig] == ev.value) continue;
      cur[ev.sig] = ev.value;
      const std::uint64_t t = m.units(ev.cycle);
      if (t != last_t) fmt::print(f, "#{}\n", t);
      last_t = t;
      value(ev.sig, ev.value);
    }
    if (m.units(to) != last_t) fmt::print(f, "#{}\n", m.units(to));
  }
  if (!(m.opt.fst ? m.out.commit_fst() : m.out.commit())) {
    error = m.out.error();
    return false;
  }
  return true;
}

}  // namespace dpc31::wave
