#include "lockstep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <system_error>

#include "child.hpp"
#include "dpc31/dpv1.hpp"
#include "dpc31/reg_ids.hpp"
#include "fst_hooks.h"
#include "outfile.hpp"
#include "rtl_library.hpp"
#include "textfile.hpp"
#include "whole_number.hpp"

namespace dpc31::cosim {

namespace {

constexpr std::size_t kRecent = 32;

std::string hex(std::uint32_t v, int width) {
  return width == 1 ? fmt::format("{}", v) : fmt::format("0x{:0{}x}", v, (width + 3) / 4);
}

}  // namespace

Lockstep::Lockstep(std::unique_ptr<Dut> emu, std::unique_ptr<Dut> rtl, const ProfileDesc& profile)
    : emu_(std::move(emu)), rtl_(std::move(rtl)), profile_(profile) {}

bool Lockstep::step(const Inputs& in) {
  emu_->step(in);
  rtl_->step(in);
  if (!in.idle()) {
    recent_.emplace_back(cycle_, in);
    if (recent_.size() > kRecent) recent_.pop_front();
  }
  const Outputs a = emu_->outputs();
  const Outputs b = rtl_->outputs();
  const bool read_compared =
      in.bus_rd && !in.rst &&
      (compared_read(profile_, in.bus_addr) || emu_->compares_ram(in.bus_addr));
  const bool stopped = rtl_->stopped();
  // Nearly every cycle agrees: one comparison of the arrays, the report only on a difference.
  if (!stopped && std::equal(a.v.begin(), a.v.begin() + Outputs::kRdata, b.v.begin()) &&
      (!read_compared || a.v[Outputs::kRdata] == b.v[Outputs::kRdata])) {
    ++cycle_;
    return true;
  }
  std::vector<std::string> lines;
  std::vector<std::string> names;
  if (stopped) {
    lines.push_back(fmt::format(
        "  {} stopped itself ($stop, $fatal or a failed assertion; its message is on standard "
        "error)",
        rtl_->name()));
    names.emplace_back("$stop");
  }
  for (std::size_t i = 0; i < Outputs::kCount; ++i) {
    if (i == Outputs::kRdata && !read_compared) continue;
    if (a.v[i] == b.v[i]) continue;
    const std::string_view n = Outputs::names()[i];
    const int w = Outputs::widths()[i];
    lines.push_back(fmt::format("  {} {}={} / {} {}={}", emu_->name(), n, hex(a.v[i], w),
                                rtl_->name(), n, hex(b.v[i], w)));
    names.emplace_back(n);
  }
  const std::uint64_t c = cycle_++;
  if (lines.empty()) return true;
  if (divergences_++ == 0) {
    first_ = c;
    signals_ = names;
  }
  errors_.push_back(
      fmt::format("divergence at cycle {} ({}):", c, in.idle() ? "no stimulus" : in.describe()));
  errors_.insert(errors_.end(), lines.begin(), lines.end());
  errors_.push_back(fmt::format("  last {} stimulus events:", recent_.size()));
  for (const auto& [cy, ev] : recent_)
    errors_.push_back(fmt::format("    cycle {:>8}: {}", cy, ev.describe()));
  return false;
}

// --- stimulus ---

namespace {
const Inputs kIdle{};
bool before(const Stimulus::Event& e, std::uint64_t c) { return e.first < c; }
}  // namespace

const Inputs& Stimulus::operator[](std::uint64_t c) const {
  const auto it = std::lower_bound(events_.begin(), events_.end(), c, before);
  return it != events_.end() && it->first == c ? it->second : kIdle;
}

void Stimulus::set(std::uint64_t c, const Inputs& in) {
  cycles_ = std::max(cycles_, c + 1);
  if (!events_.empty() && events_.back().first < c) {  // the common case: built in order
    if (!in.idle()) events_.emplace_back(c, in);
    return;
  }
  const auto it = std::lower_bound(events_.begin(), events_.end(), c, before);
  if (it != events_.end() && it->first == c) {
    if (in.idle()) {
      events_.erase(it);
    } else {
      it->second = in;
    }
  } else if (!in.idle()) {
    events_.insert(it, {c, in});
  }
}

void Stimulus::resize(std::uint64_t cycles) {
  cycles_ = cycles;
  events_.erase(std::lower_bound(events_.begin(), events_.end(), cycles, before), events_.end());
}

void Stimulus::clear(std::uint64_t from, std::uint64_t to) {
  const auto a = std::lower_bound(events_.begin(), events_.end(), from, before);
  events_.erase(a, std::lower_bound(a, events_.end(), to, before));
}

std::uint64_t Stimulus::next_event(std::uint64_t c) const {
  const auto it = std::lower_bound(events_.begin(), events_.end(), c, before);
  return it == events_.end() ? cycles_ : it->first;
}

Stimulus::Iterator::Iterator(const Stimulus& s, std::uint64_t c)
    : s_(&s),
      c_(c),
      k_(static_cast<std::size_t>(std::lower_bound(s.events_.begin(), s.events_.end(), c, before) -
                                  s.events_.begin())) {}

const Inputs& Stimulus::Iterator::operator*() const {
  return k_ < s_->events_.size() && s_->events_[k_].first == c_ ? s_->events_[k_].second : kIdle;
}

Stimulus::Iterator& Stimulus::Iterator::operator++() {
  if (k_ < s_->events_.size() && s_->events_[k_].first == c_) ++k_;
  ++c_;
  return *this;
}

RunResult run_lockstep(const Stimulus& s, const DutOptions& o, std::string_view mutant) {
  RunResult r;
  std::unique_ptr<Dut> rtl = make_rtl_dut(o, mutant);
  if (!rtl) {
    r.report.push_back(fmt::format("no RTL model built for mutant '{}'", mutant));
    r.divergence = 0;
    return r;
  }
  Lockstep ls(make_cpp_dut(o), std::move(rtl), profile_desc(o.profile));
  for (const Inputs& in : s) {
    if (!ls.step(in)) {
      r.divergence = static_cast<std::int64_t>(ls.first_divergence());
      r.report = ls.errors();
      r.signals = ls.diverged_signals();
      return r;
    }
  }
  return r;
}

// --- constrained random stimulus ---

namespace {

struct Gen {
  std::mt19937_64 rng;
  const ProfileDesc& p;
  bool chance(double prob) { return std::uniform_real_distribution<double>(0.0, 1.0)(rng) < prob; }
  std::uint32_t pick(std::uint32_t n) { return static_cast<std::uint32_t>(rng() % n); }
  std::uint8_t byte() { return static_cast<std::uint8_t>(rng()); }
  std::uint16_t addr(RegId id, int byte_offset = 0) {
    const RegDesc* r = find_reg(p, id);
    const std::int32_t a = r->read_addr >= 0 ? r->read_addr : r->write_addr;
    return static_cast<std::uint16_t>(a + byte_offset);
  }
  std::uint16_t waddr(RegId id, int byte_offset = 0) {
    const RegDesc* r = find_reg(p, id);
    return static_cast<std::uint16_t>((r->write_addr >= 0 ? r->write_addr : r->read_addr) +
                                      byte_offset);
  }
};

// Every address whose read the harness compares (the registers, command reads included, and the
// mirrored cells; compared_read), once per profile: the reads that kReads does not weight.
const std::vector<std::uint16_t>& compared_reads(const ProfileDesc& p) {
  static const std::array<std::vector<std::uint16_t>, std::size(kAllProfiles)> tables = [] {
    std::array<std::vector<std::uint16_t>, std::size(kAllProfiles)> t;
    for (const Profile q : kAllProfiles) {
      for (std::uint32_t a = 0; a <= 0xFFFF; ++a)
        if (compared_read(profile_desc(q), static_cast<std::uint16_t>(a)))
          t[static_cast<std::size_t>(q)].push_back(static_cast<std::uint16_t>(a));
    }
    return t;
  }();
  return tables[static_cast<std::size_t>(p.id)];
}

// RAM outside the registers and cells that a bus write may hit, [first, end): the user area, on
// the vpc3plus past the stimulus's SAP list and buffers (080h-27Fh) and below the 2 KB end (a
// RAM access violation is an event input, not a bus write's effect here).
struct RamRange {
  std::uint16_t first, end;
};
RamRange user_ram(Profile p) {
  switch (p) {
    case Profile::spc3:
      return {0x040, 0x600};
    case Profile::vpc3plus:
      return {0x300, 0x800};
    default:
      return {0x8A0, 0x2000};  // dpc31: the user buffer area
  }
}

void random_access(Gen& g, Inputs& in) {
  static constexpr RegId kReads[] = {RegId::Int_Req_Reg,         RegId::Int_Reg,
                                     RegId::Status_Reg,          RegId::Mode_Reg0,
                                     RegId::Din_Buffer_SM,       RegId::New_Din_Buffer_Cmd,
                                     RegId::Dout_Buffer_SM,      RegId::Next_Dout_Buffer_Cmd,
                                     RegId::Diag_Buffer_SM,      RegId::New_Diag_Buffer_Cmd,
                                     RegId::User_Prm_Data_Okay,  RegId::User_Prm_Data_Not_Okay,
                                     RegId::User_Cfg_Data_Okay,  RegId::User_Cfg_Data_Not_Okay,
                                     RegId::SSA_Buffer_Free_Cmd, RegId::R_Dout_Buf_Ptr1,
                                     RegId::R_Cfg_Buf_Ptr,       RegId::R_GC_Command};
  const std::uint32_t kind = g.pick(100);
  if (kind >= 32 && kind < 40) {  // any compared read: the read-backs and cells kReads lacks
    const std::vector<std::uint16_t>& all = compared_reads(g.p);
    in.bus_rd = true;
    in.bus_addr = all[g.pick(static_cast<std::uint32_t>(all.size()))];
    return;
  }
  if (kind < 32) {
    const RegId id = kReads[g.pick(std::size(kReads))];
    const RegDesc* r = find_reg(g.p, id);
    in.bus_rd = true;
    in.bus_addr = g.addr(id, r->width == 16 ? static_cast<int>(g.pick(2)) : 0);
    return;
  }
  in.bus_wr = true;
  in.bus_wdata = g.byte();
  const int lane = static_cast<int>(g.pick(2));
  if (kind < 55) {  // EOI, the most frequent write of an ISR
    in.bus_addr = g.waddr(RegId::Mode_Reg1_S);
    in.bus_wdata = fields::Mode_Reg1_S::EOI;
  } else if (kind < 65) {  // acknowledges
    in.bus_addr = g.waddr(RegId::Int_Ack_Reg, lane);
  } else if (kind < 72) {  // masks, biased to unmasking
    in.bus_addr = g.waddr(RegId::Int_Mask_Reg, lane);
    in.bus_wdata = g.chance(0.6) ? static_cast<std::uint8_t>(in.bus_wdata & g.byte() & g.byte())
                                 : in.bus_wdata;
  } else if (kind < 76) {
    in.bus_addr = g.waddr(RegId::Int_Req_Reg, lane);
    in.bus_wdata = static_cast<std::uint8_t>(in.bus_wdata & g.byte());
  } else if (kind < 82) {  // Mode_Reg1 set: Start (twice as often), the others, Start with EOI
    // or Go_Offline, and any value (several actions in one write)
    namespace m1 = fields::Mode_Reg1_S;
    static constexpr std::uint8_t kSet[] = {
        m1::Start_SPC3,           m1::Start_SPC3,
        m1::User_Leave_Master,    m1::Go_Offline,
        m1::En_Change_Cfg_Buffer, m1::Res_User_WD,
        m1::Start_SPC3 | m1::EOI, m1::Start_SPC3 | m1::Go_Offline};
    in.bus_addr = g.waddr(RegId::Mode_Reg1_S);
    const std::uint32_t k = g.pick(std::size(kSet) + 1);
    if (k < std::size(kSet)) in.bus_wdata = kSet[k];
  } else if (kind < 85) {
    in.bus_addr = g.waddr(RegId::Mode_Reg1_R);
  } else if (kind < 90) {
    in.bus_addr = g.waddr(RegId::Mode_Reg0, lane);
  } else if (kind < 93) {
    const RegId opt = g.p.id == Profile::dpc31      ? RegId::Param_Reg
                      : g.p.id == Profile::vpc3plus ? RegId::Mode_Reg2
                                                    : RegId::Mode_Reg0;
    in.bus_addr = g.waddr(opt);
    in.bus_wdata = static_cast<std::uint8_t>(in.bus_wdata & 0x03);
  } else if (kind < 97) {  // the mirrored pointer cells
    static constexpr RegId kCells[] = {RegId::R_Dout_Buf_Ptr1,    RegId::R_Dout_Buf_Ptr2,
                                       RegId::R_Dout_Buf_Ptr3,    RegId::R_Cfg_Buf_Ptr,
                                       RegId::R_Read_Cfg_Buf_Ptr, RegId::R_GC_Command};
    in.bus_addr = g.waddr(kCells[g.pick(std::size(kCells))]);
  } else {  // other RAM: a write that must change no register (an address decode that aliases)
    const RamRange r = user_ram(g.p.id);
    in.bus_addr = static_cast<std::uint16_t>(r.first + g.pick(r.end - r.first));
  }
}

void random_event(Gen& g, Inputs& in) {
  static constexpr std::uint8_t kGc[] = {0x20, 0x10, 0x08, 0x04, 0x02, 0x22, 0x30,
                                         0x0C, 0x00, 0x01, 0x40, 0x80, 0x28};
  // The dpc31's requests MAC_Stop and MAC_Start come in as two more events.
  switch (g.pick(g.p.id == Profile::dpc31 ? 19 : 17)) {
    case 0:
      in.ev_irq = static_cast<std::uint16_t>(1u << g.pick(16));
      break;
    case 1:
      in.ev_leave_master = true;
      break;
    case 2:
      in.ev_gc = true;
      in.gc_cmd = g.chance(0.9) ? kGc[g.pick(std::size(kGc))] : g.byte();
      break;
    case 3:
    case 4:
      in.ev_dout = true;
      break;
    case 5:
      in.ev_failsafe = true;
      break;
    case 6:
    case 7:
      in.ev_din = true;
      break;
    case 8:
      in.ev_diag_begin = true;
      break;
    case 9:
      in.ev_diag_end = true;
      in.stat_diag = g.chance(0.3);
      break;
    case 10:
      in.ev_prm = true;
      break;
    case 11:
      in.ev_cfg = true;
      break;
    case 12:
      in.ev_prm_fault = true;
      break;
    case 14:
      in.ev_dx = true;
      break;
    case 13:
      in.ev_dis = true;
      in.dis_bits = static_cast<std::uint8_t>(g.pick(4));
      break;
    case 16:
      in.ev_wd_expired = true;
      break;
    case 17:
      in.ev_mac_stop = true;
      break;
    case 18:
      in.ev_mac_start = true;
      break;
    default:
      in.ev_ssa = true;
      break;
  }
}

}  // namespace

// --- DPV1 on the vpc3plus: a SAP list, its buffers and the header machine's events ---

namespace {

// A SAP list as a firmware lays it out while Offline (docs/dpv1.md): up to four entries (SAP 51
// and 49 as the Profichip driver's MSAC_C1 and resource manager, then others), each with one or
// two indication buffers and a response buffer that may be its first indication buffer.
struct SapLayout {
  static constexpr std::uint8_t kListSegment = 0x10;  // 080h, in the user area
  static constexpr std::uint8_t kFirstBuffer = 0x20;  // 100h on: 32 bytes (4 segments) each
  static constexpr std::uint32_t kMaxData = 28;       // 32 less the header
  std::vector<std::uint16_t> entries;                 // RAM addresses
  std::vector<std::uint8_t> saps;
  std::vector<std::uint16_t> headers;  // every buffer's header (RAM address)
  std::vector<Inputs> setup;           // the writes that lay it out, in order
};

Inputs ram_write(std::uint16_t addr, std::uint8_t v) {
  Inputs in;
  in.bus_wr = true;
  in.bus_addr = addr;
  in.bus_wdata = v;
  return in;
}

SapLayout sap_layout(Gen& g) {
  namespace e = dpv1::entry;
  namespace h = dpv1::header;
  constexpr std::uint32_t kShift = 3;  // 2 KB mode: the stimulus never sets 4kB_Mode
  SapLayout l;
  l.setup.push_back(ram_write(g.addr(RegId::R_FDL_SAP_List_Ptr), SapLayout::kListSegment));
  const std::uint32_t n = 1 + g.pick(4);
  std::uint8_t next = SapLayout::kFirstBuffer;
  auto buffer = [&] {
    const std::uint8_t seg = next;
    next = static_cast<std::uint8_t>(next + 4);
    const auto hdr = static_cast<std::uint16_t>(seg << kShift);
    l.headers.push_back(hdr);
    l.setup.push_back(ram_write(static_cast<std::uint16_t>(hdr + h::Control), 0x00));
    // Max_Length up to the 28 bytes the 32-byte buffer holds, now and then less.
    const auto max = static_cast<std::uint8_t>(g.chance(0.7) ? SapLayout::kMaxData
                                                             : g.pick(SapLayout::kMaxData + 1));
    l.setup.push_back(ram_write(static_cast<std::uint16_t>(hdr + h::Max_Length), max));
    return seg;
  };
  for (std::uint32_t i = 0; i < n; ++i) {
    const auto entry =
        static_cast<std::uint16_t>((SapLayout::kListSegment << kShift) + i * e::kBytes);
    const std::uint8_t sap = i == 0 ? 51 : i == 1 ? 49 : static_cast<std::uint8_t>(g.pick(49));
    const std::uint8_t ind0 = buffer();
    const std::uint32_t two = g.pick(3);  // a second buffer, none (00h), or the same one
    const std::uint8_t ind1 = two == 0 ? buffer() : two == 1 ? 0 : ind0;
    const std::uint8_t resp = g.chance(0.5) ? ind0 : buffer();
    const std::uint8_t bytes[e::kBytes] = {sap,  e::kAll, e::kAll, dpv1::service::All,
                                           ind0, ind1,    resp};
    for (std::uint32_t k = 0; k < e::kBytes; ++k)
      l.setup.push_back(ram_write(static_cast<std::uint16_t>(entry + k), bytes[k]));
    l.entries.push_back(entry);
    l.saps.push_back(sap);
  }
  l.setup.push_back(
      ram_write(static_cast<std::uint16_t>((SapLayout::kListSegment << kShift) + n * e::kBytes),
                e::kEndOfList));
  return l;
}

// One DPV1 action: what the SAP list hands the header machine (the verdicts of the C++ chip: a
// request or poll for an entry, the response's end, a Set_Ext_Prm), or the firmware's side
// (reads of the headers and Response_Sent, IND cleared, a response with USER + RESP, a buffer
// freed, Response_Sent cleared).
void dpv1_action(Gen& g, const SapLayout& l, Inputs& in) {
  namespace h = dpv1::header;
  const std::uint32_t k = g.pick(static_cast<std::uint32_t>(l.entries.size()));
  const std::uint16_t hdr = l.headers[g.pick(static_cast<std::uint32_t>(l.headers.size()))];
  const std::uint32_t what = g.pick(100);
  if (what < 18) {  // a request with data; an SRD is answered in the same cycle
    in.ev_sap_ind = true;
    in.sap_entry = l.entries[k];
    in.sap_len = static_cast<std::uint8_t>(1 + g.pick(32));
    in.ev_sap_srd = g.chance(0.6);
  } else if (what < 30) {  // a poll
    in.ev_sap_srd = true;
    in.sap_entry = l.entries[k];
  } else if (what < 38) {
    in.ev_sap_sent = true;
  } else if (what < 40) {
    in.ev_ext_prm = true;
  } else if (what < 62) {  // the firmware reads a Control byte or an entry's byte 0
    in.bus_rd = true;
    in.bus_addr = g.chance(0.7) ? hdr : l.entries[k];
  } else if (what < 90) {  // the firmware writes a Control byte
    static constexpr std::uint8_t kControl[] = {
        h::USER, h::USER | h::RESP, 0x00, h::USER | h::RESP, h::USER | h::IND, h::RESP, h::INUSE};
    in.bus_wr = true;
    in.bus_addr = hdr;
    in.bus_wdata = g.chance(0.9) ? kControl[g.pick(std::size(kControl))] : g.byte();
  } else if (what < 97) {  // Response_Sent cleared (the SAP number written back)
    in.bus_wr = true;
    in.bus_addr = l.entries[k];
    in.bus_wdata = l.saps[k];
  } else {  // a new Max_Length, within the buffer (the chip writes up to Max_Length bytes)
    in.bus_wr = true;
    in.bus_addr = static_cast<std::uint16_t>(hdr + h::Max_Length);
    in.bus_wdata = static_cast<std::uint8_t>(g.pick(SapLayout::kMaxData + 1));
  }
}

}  // namespace

Stimulus random_stimulus(const RandomConfig& c) {
  Gen g{std::mt19937_64(c.seed * 0x9E3779B97F4A7C15ull + static_cast<unsigned>(c.profile)),
        profile_desc(c.profile)};
  Stimulus s(c.cycles);
  // vpc3plus: a SAP list laid out at the start and again after every reset.
  const bool dpv1 = c.profile == Profile::vpc3plus;
  SapLayout sap;
  std::size_t setup = 0;  // the next write of sap.setup
  if (dpv1) sap = sap_layout(g);
  // Bursts of activity and quiet stretches, so timers (EOI, user timer) run out too.
  double activity = 0.3;
  // The user timer needs P = 48 000 started cycles (docs/golden-model.md), and resets, Go_Offline
  // and MAC_Stop come far more often. So a stimulus that can hold one gets, in half the seeds,
  // one stretch of kQuiet cycles that begins with a reset and has none of the three: a start
  // early in it is followed by User_Timer_Clock. Drawn apart from `g`: shorter stimuli, the
  // default runs', stay as they were.
  constexpr std::uint64_t kQuiet = 56'000;
  std::uint64_t quiet_from = c.cycles;  // none
  if (c.cycles >= kQuiet) {
    std::mt19937_64 q(c.seed * 0xC2B2AE3D27D4EB4Full + static_cast<unsigned>(c.profile));
    if (q() % 2 == 0) quiet_from = q() % (c.cycles - kQuiet + 1);
  }
  const std::uint16_t mode_reg1_s = g.waddr(RegId::Mode_Reg1_S);
  for (std::uint64_t i = 0; i < c.cycles; ++i) {
    if (i % 256 == 0)
      activity = g.chance(0.25) ? 0.01 : 0.1 + 0.5 * std::uniform_real_distribution<>(0, 1)(g.rng);
    const bool quiet = i >= quiet_from && i - quiet_from < kQuiet;
    Inputs in;
    if (i == quiet_from || (setup >= sap.setup.size() && !quiet && g.chance(0.00005))) {
      in.rst = true;
      setup = 0;
    } else if (setup < sap.setup.size()) {
      in = sap.setup[setup++];
    } else if (g.chance(activity)) {
      if (dpv1 && g.chance(0.3)) {
        dpv1_action(g, sap, in);
      } else {
        const std::uint32_t what = g.pick(10);
        if (what < 5) random_access(g, in);
        if (what >= 4) random_event(g, in);  // 4: an event and an access in the same cycle
        if (what == 9) random_event(g, in);  // two events in one cycle
      }
      if (quiet) {
        in.ev_mac_stop = false;
        if (in.bus_wr && in.bus_addr == mode_reg1_s)
          in.bus_wdata = static_cast<std::uint8_t>(in.bus_wdata & ~fields::Mode_Reg1_S::Go_Offline);
      }
    }
    s.set(i, in);
  }
  return s;
}

// --- shrinking ---

namespace {

// The inputs of one cycle as the tokens of its trace line ("rd 000e", "ev_dout"), each whole.
std::vector<std::string> input_tokens(const Inputs& in) {
  const std::string line = in.describe();
  std::vector<std::string> out;
  std::istringstream is(line);
  for (std::string tok;;) {
    is >> std::ws;
    const auto from = static_cast<std::size_t>(is.tellg());
    if (!(is >> tok)) break;
    Inputs scratch;
    parse_input_token(tok, is, scratch);  // reads the operand of "rd" / "wr" too
    const auto to = is.tellg();
    out.push_back(
        line.substr(from, to < 0 ? std::string::npos : static_cast<std::size_t>(to) - from));
  }
  return out;
}

// The inputs of the tokens but the k-th.
Inputs without_token(const std::vector<std::string>& tokens, std::size_t k) {
  Inputs in;
  for (std::size_t i = 0; i < tokens.size(); ++i) {
    if (i == k) continue;
    std::istringstream is(tokens[i]);
    std::string tok;
    is >> tok;
    parse_input_token(tok, is, in);
  }
  return in;
}

}  // namespace

Stimulus shrink(const Stimulus& s, const DutOptions& o, std::string_view mutant, int max_runs,
                int* runs_taken) {
  int own = 0;
  int& runs = runs_taken != nullptr ? *runs_taken : own;
  runs = 1;
  RunResult r = run_lockstep(s, o, mutant);
  if (r.divergence < 0) return s;
  Stimulus best = s;
  best.resize(static_cast<std::uint64_t>(r.divergence) + 1);
  auto fails = [&](const Stimulus& t) {
    ++runs;
    const RunResult x = run_lockstep(t, o, mutant);
    return x.divergence >= 0 ? x.divergence : -1;
  };
  // Delta debugging over the non-idle cycles: try to make chunks of them idle.
  for (std::uint64_t chunk = best.size() / 2; chunk >= 1 && runs < max_runs; chunk /= 2) {
    bool progress = true;
    while (progress && runs < max_runs) {
      progress = false;
      for (std::uint64_t start = 0; start < best.size() && runs < max_runs; start += chunk) {
        // Chunks without inputs change nothing: go straight to the next one that has some. None
        // left ends the pass; a chunk without inputs that "still fails" is no progress.
        const std::uint64_t next = best.next_event(start);
        if (next >= best.size()) break;
        start = next / chunk * chunk;
        Stimulus t = best;
        t.clear(start, std::min(best.size(), start + chunk));
        const std::int64_t d = fails(t);
        if (d >= 0) {
          t.resize(static_cast<std::uint64_t>(d) + 1);
          best = std::move(t);
          progress = true;
        }
      }
    }
    if (chunk == 1) break;
  }
  // Then the inputs of each cycle left one by one: a read or an event beside the input that
  // fails goes too.
  const std::vector<Stimulus::Event> kept = best.events();
  for (const auto& [c, in] : kept) {
    if (c >= best.size()) break;  // cut off: it fails sooner without an input dropped before
    std::vector<std::string> tokens = input_tokens(in);
    for (std::size_t k = 0; tokens.size() > 1 && k < tokens.size() && runs < max_runs;) {
      Stimulus t = best;
      t.set(c, without_token(tokens, k));
      if (const std::int64_t d = fails(t); d >= 0) {
        t.resize(static_cast<std::uint64_t>(d) + 1);
        best = std::move(t);
        tokens.erase(tokens.begin() + static_cast<std::ptrdiff_t>(k));
      } else {
        ++k;
      }
    }
  }
  return best;
}

// --- trace files ---

std::string write_trace(const Stimulus& s, const std::string& header) {
  std::string out = "# dpc31 cosim stimulus trace\n";
  std::istringstream h(header);
  for (std::string line; std::getline(h, line);) out += "# " + line + "\n";
  for (const auto& [cycle, in] : s.events()) out += fmt::format("{} {}\n", cycle, in.describe());
  out += fmt::format("end {}\n", s.size());
  return out;
}

bool parse_trace(const std::string& text, const std::string& file, Stimulus& out,
                 std::string& error, std::optional<Profile> profile) {
  constexpr std::uint64_t kMaxCycles = 100'000'000;
  out = Stimulus{};
  std::istringstream is(text);
  std::string line;
  int n = 0;
  bool ended = false;
  std::uint64_t last = 0;
  auto fail = [&](const std::string& m) {
    error = fmt::format("{}:{}: {}", file, n, m);
    return false;
  };
  while (std::getline(is, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    if (ended) return fail("text after 'end'");
    std::istringstream ls(line);
    std::string first;
    ls >> first;
    if (first == "end") {
      std::string count;
      ls >> count;
      std::uint64_t total = 0;
      const std::errc ec = numbers::parse_whole(count, total);
      // The bound of the cycle lines and of --cycles (the run time, not memory: the stimulus
      // keeps only the lines given); a count beyond 64 bits is beyond it too.
      if (ec == std::errc::result_out_of_range || (ec == std::errc{} && total > kMaxCycles))
        return fail(fmt::format("'end' beyond {} cycles", kMaxCycles));
      if (ec != std::errc{} || total < last)
        return fail("'end' needs the cycle count, at least the last cycle + 1");
      // One count, as the golden trace's 'end CYCLE' and the header's one value per line.
      if (std::string more; ls >> more)
        return fail(fmt::format("'end' takes one cycle count, not also '{}'", shown(more)));
      out.resize(total);
      ended = true;
      continue;
    }
    // Read as every door reads a whole number: no sign ("-1", "+5"), a number beyond 64 bits is
    // beyond the bound.
    std::uint64_t cycle = 0;
    const std::errc cycle_ec = numbers::parse_whole(first, cycle);
    // The other ".trace" of the project: a chip's golden trace (docs/trace-format.md).
    if (n == 1 && first == "dpc31-trace") {
      return fail(
          "a golden trace of `dpc31 run --record` (replay it with `dpc31 replay`), not a "
          "stimulus trace of `dpc31 cosim`");
    }
    if (cycle_ec == std::errc::invalid_argument)
      return fail(fmt::format("'{}' is not a cycle number", shown(first)));
    if (cycle_ec == std::errc{} && cycle < last && !(cycle == 0 && out.empty()))
      return fail("cycles must increase");
    if (cycle_ec == std::errc::result_out_of_range || cycle > kMaxCycles)
      return fail(fmt::format("cycle beyond {}", kMaxCycles));
    Inputs in;
    std::string tok;
    while (ls >> tok) {
      if (const std::string why = parse_input_token(tok, ls, in); !why.empty()) return fail(why);
    }
    if (in.idle()) return fail("a stimulus line without stimulus");
    if (profile) {
      if (const std::string why = input_not_on(in, *profile); !why.empty()) return fail(why);
    }
    out.set(cycle, in);
    last = cycle + 1;
  }
  if (!ended) return fail("missing 'end <cycles>' (truncated trace?)");
  return true;
}

RtlFst write_rtl_fst(const Stimulus& s, const DutOptions& o, std::string_view mutant,
                     std::uint64_t from, const std::string& path, std::string& error) {
  outfile::OutFile out;
  if (!out.open(path)) {
    error = out.error();
    return RtlFst::failed;
  }
  // Verilator's tracer opens the file by name (fstapi unlinks it first): a regular file of ours.
  const std::string name = out.library_path();
  if (name.empty()) {
    error = out.error();
    return RtlFst::failed;
  }
  // The model traces in a child process: the tracer of a model built elsewhere (--rtl,
  // --rtl-model) carries its own fstapi, whose writes nobody checks, and it dies of SIGBUS when
  // a file of it cannot grow (a full file system, `ulimit -f`). Here that is one line and exit
  // 2, after the summary, with the temporaries removed by this process.
  enum : int { kTraced = 0, kNoTracing = 3, kWritesFailed = 4 };
  const child::Result r = child::call([&] {
    std::unique_ptr<Dut> rtl = make_rtl_dut(o, mutant);
    const unsigned long failed = dpc31_fst_failed_writes();
    if (!rtl) return int{kNoTracing};
    // The cycles before the window untraced: the FST's first clock edge is the window's first
    // cycle, as in emu.vcd, so that wavediff lines the files up edge by edge.
    Stimulus::Iterator in = s.begin();
    for (std::uint64_t c = 0; c < std::min(from, s.size()); ++c, ++in) rtl->step(*in);
    if (!rtl->trace_to(name)) return int{kNoTracing};
    for (std::uint64_t c = std::min(from, s.size()); c < s.size(); ++c, ++in) rtl->step(*in);
    rtl.reset();  // closes the trace
    return dpc31_fst_failed_writes() == failed ? int{kTraced} : int{kWritesFailed};
  });
  if (r.exit_code == kNoTracing) {
    error = o.rtl ? fmt::format(
                        "{}: not written: the RTL model {} did not trace (its trace_to "
                        "returned 0)",
                        path, o.rtl->path())
                  : fmt::format(
                        "{}: not written: the built-in mutants' RTL model is built "
                        "without tracing",
                        path);
    return RtlFst::not_traced;
  }
  if (r.exit_code != kTraced && r.exit_code != kWritesFailed) {
    error = fmt::format(
        "{}: cannot write: the RTL model's FST tracer ended its process ({}): is the file "
        "system full?",
        path, r.exit_code == -1 ? "a signal" : fmt::format("exit {}", r.exit_code));
    return RtlFst::failed;
  }
  if (!out.commit_fst(r.exit_code == kWritesFailed)) {
    error = out.error();
    return RtlFst::failed;
  }
  return RtlFst::written;
}

// --- waveform window ---

namespace {

// Both sides use Verilator's convention: the clock falls at time 2c and rises at 2c + 1, where
// the outputs of cycle c change; one time unit is half a clock.
void vcd_header(std::FILE* f, const std::string& side) {
  fmt::print(f, "$date dpc31 cosim $end\n$version dpc31emu cosim ({}) $end\n$timescale 1ns $end\n",
             side);
  fmt::print(f, "$scope module blocks $end\n$var wire 1 c clk $end\n");
  for (std::size_t i = 0; i < Outputs::kCount; ++i) {
    fmt::print(f, "$var wire {} o{} {} $end\n", Outputs::widths()[i], i, Outputs::names()[i]);
  }
  fmt::print(f, "$upscope $end\n$enddefinitions $end\n");
}

void vcd_value(std::FILE* f, std::size_t i, std::uint32_t v) {
  const int w = Outputs::widths()[i];
  if (w == 1) {
    fmt::print(f, "{}o{}\n", v & 1, i);
    return;
  }
  std::string bits;
  for (int b = w - 1; b >= 0; --b) bits += ((v >> b) & 1) != 0 ? '1' : '0';
  fmt::print(f, "b{} o{}\n", bits, i);
}

}  // namespace

bool write_window(const Stimulus& s, const DutOptions& o, std::string_view mutant,
                  std::uint64_t from, std::uint64_t to, const std::string& dir,
                  std::string& error) {
  std::unique_ptr<Dut> sides[2] = {make_cpp_dut(o), make_rtl_dut(o, mutant)};
  if (!sides[1]) {
    error = "no RTL model for that mutant";
    return false;
  }
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const char* names[2] = {"emu", "rtl"};
  outfile::OutFile out[2];
  std::FILE* f[2] = {nullptr, nullptr};
  for (int k = 0; k < 2; ++k) {
    // Joined as paths, so that its messages name win/emu.vcd for `win/`.
    if (!out[k].open((std::filesystem::path(dir) / fmt::format("{}.vcd", names[k])).string())) {
      error = out[k].error();
      return false;
    }
    f[k] = out[k].stream();
  }
  try {
    for (int k = 0; k < 2; ++k) vcd_header(f[k], names[k]);
    Outputs last[2];
    Stimulus::Iterator in = s.begin();
    for (std::uint64_t c = 0; c < std::min<std::uint64_t>(to, s.size()); ++c, ++in) {
      for (int k = 0; k < 2; ++k) {
        sides[k]->step(*in);
        if (c < from) continue;
        const Outputs now = sides[k]->outputs();
        fmt::print(f[k], "#{}\n0c\n#{}\n1c\n", 2 * c, 2 * c + 1);
        for (std::size_t i = 0; i < Outputs::kCount; ++i) {
          if (c == from || now.v[i] != last[k].v[i]) vcd_value(f[k], i, now.v[i]);
        }
        last[k] = now;
      }
    }
  } catch (const std::system_error& e) {
    // fmt::print throws where a write fails (a full disk, ulimit -f): the file whose stream
    // failed, as OutFile names one; the temporaries go with `out`.
    const int k = std::ferror(f[0]) != 0 ? 0 : 1;
    error = fmt::format("{}: cannot write: {}", out[k].path(), e.code().message());
    return false;
  }
  for (auto& o_k : out) {
    if (!o_k.commit()) {
      error = o_k.error();
      return false;
    }
  }
  return true;
}

}  // namespace dpc31::cosim
