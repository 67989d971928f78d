#include "responder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "dpc31/dp.hpp"

namespace dpc31 {

namespace {

namespace m0 = fields::Mode_Reg0;
namespace m1 = fields::Mode_Reg1_S;
constexpr std::uint8_t kHandshakeConflict = 0x01;  // the OK / Not_OK reads' 01: a newer one came
constexpr std::uint16_t kHandledByReads = irq::New_Prm_Data | irq::New_Cfg_Data;
constexpr std::uint8_t kQueueLen = 4;  // dpc31: entries of each queue (one always empty)
constexpr std::uint16_t kDpv1Events = irq::FDL_Ind | irq::Poll_End_Ind | irq::User_Timer_Clock;
constexpr std::uint8_t kDiagLen = 6;  // the standard diag, no user part
// Aux buffers (Set_Prm, Chk_Cfg and the Read_Cfg copy in them, Set_Slave_Address) take the
// longest of the three.
std::uint32_t aux_len(const SlaveConfig& s) {
  return std::max<std::uint32_t>({8u + static_cast<std::uint32_t>(s.user_prm.size()),
                                  static_cast<std::uint32_t>(s.cfg.size()), 4u});
}

// "" when `given` bytes fill the slave's `key`= bytes (none, or exactly `len`), else why not.
std::string length_problem(std::size_t given, std::size_t len, std::string_view key,
                           std::string_view what) {
  if (given == 0 || given == len) return {};
  return fmt::format("{} bytes for a slave with {}={}: {} are exactly {}= bytes, or none", given,
                     key, len, what, key);
}

}  // namespace

std::string refused_beside_firmware(std::string_view option) {
  return fmt::format("'{}' configures the built-in user side; a firmware configures itself",
                     option);
}

std::string inputs_length_problem(std::size_t given, std::size_t in_len) {
  return length_problem(given, in_len, "in", "inputs");
}

std::string substitute_length_problem(std::size_t given, std::size_t out_len) {
  return length_problem(given, out_len, "out", "substitute values");
}

ResponderConfig Responder::checked(ResponderConfig cfg) {
  if (const std::string why = substitute_length_problem(cfg.substitute.size(), cfg.slave.out_len);
      !why.empty()) {
    throw std::invalid_argument("substitute: " + why);
  }
  return cfg;
}

void Responder::set_inputs(std::vector<std::uint8_t> in) {
  if (const std::string why = inputs_length_problem(in.size(), cfg_.slave.in_len); !why.empty()) {
    throw std::invalid_argument("inputs: " + why);
  }
  inputs_ = std::move(in);
}

std::string user_wd_value_needs_user_wd(std::string_view option) {
  // The responder sends DPS_User_Wd requests only with user_wd=1; on the SPC3 and VPC3+ the value
  // acts always (its Start carries Res_User_WD).
  return fmt::format(
      "{} needs user_wd=1 on profile dpc31: the DPS_User_Watchdog loads R_User_WD_Value only "
      "through its requests",
      option);
}

namespace {

// The layout in one RAM mode (the VPC3+'s 4kB_Mode: `large`).
ResponderLayout layout_in(const ProfileDesc& p, const ResponderConfig& cfg, bool large) {
  const SlaveConfig& s = cfg.slave;
  ResponderLayout l;
  l.large = large;
  l.seg_shift = l.large ? p.segment_shift_large : p.segment_shift;
  l.ram_end = p.ram_begin + (l.large ? p.ram_size_large : p.ram_size);
  const std::uint32_t seg = 1u << l.seg_shift;
  std::uint32_t next = (p.user_base + seg - 1) / seg;
  const auto alloc = [&](RegId ptr_cell, std::uint32_t len) {
    l.segment[static_cast<std::size_t>(ptr_cell)] = next;
    next += std::max<std::uint32_t>(1, (len + seg - 1) / seg);
  };
  for (RegId r : {RegId::R_Dout_Buf_Ptr1, RegId::R_Dout_Buf_Ptr2, RegId::R_Dout_Buf_Ptr3})
    alloc(r, s.out_len);
  for (RegId r : {RegId::R_Din_Buf_Ptr1, RegId::R_Din_Buf_Ptr2, RegId::R_Din_Buf_Ptr3})
    alloc(r, s.in_len);
  if (p.id == Profile::dpc31) alloc(RegId::R_Dout_Buf_Ptr_C, s.out_len);
  alloc(RegId::R_Diag_Buf_Ptr1, kDiagLen);
  alloc(RegId::R_Diag_Buf_Ptr2, kDiagLen);
  for (RegId r : {RegId::R_Aux_Buf_Ptr1, RegId::R_Aux_Buf_Ptr2, RegId::R_Prm_Buf_Ptr,
                  RegId::R_Cfg_Buf_Ptr, RegId::R_Read_Cfg_Buf_Ptr, RegId::R_SSA_Buf_Ptr}) {
    alloc(r, aux_len(s));
  }
  if (p.id == Profile::dpc31) {
    alloc(RegId::InstQ_Base, kQueueLen * request::kEntryBytes);
    alloc(RegId::IndQ_Base, kQueueLen * request::kEntryBytes);
  }
  l.dpv1 = next;
  if (!cfg.dpv1.records.empty()) next += Dpv1User::segments(l.seg_shift);
  l.end = next << l.seg_shift;
  return l;
}

// A pointer cell holds segments 0..255: past them is no buffer either (never below the RAM's
// end on our profiles, but the check is the cell's).
std::uint32_t layout_limit(const ResponderLayout& l) {
  return std::min(l.ram_end, 256u << l.seg_shift);
}

}  // namespace

// The smaller RAM mode while the layout fits it: 4kB_Mode (VPC3+) only for one that does not.
ResponderLayout responder_layout(const ProfileDesc& p, const ResponderConfig& cfg) {
  const ResponderLayout small = layout_in(p, cfg, false);
  if (small.end <= layout_limit(small) || p.ram_size_large == 0) return small;
  return layout_in(p, cfg, true);
}

std::string responder_layout_problem(const ProfileDesc& p, const ResponderConfig& cfg) {
  const ResponderLayout l = responder_layout(p, cfg);
  const std::uint32_t limit = layout_limit(l);
  if (l.end <= limit) return {};
  // Every length the layout takes: the aux buffers are as long as the longer of cfg and
  // user_prm (+ 8), the DPV1 part is there with records.
  const SlaveConfig& s = cfg.slave;
  const auto bytes = [](std::size_t n) { return fmt::format("{} byte{}", n, n == 1 ? "" : "s"); };
  return fmt::format(
      "in={} out={} cfg of {} user_prm of {}{}: the built-in user side's buffers would end at "
      "{:#05x}, past the {} bytes of RAM of profile {}{} (its user area {:#05x}..{:#05x})",
      s.in_len, s.out_len, bytes(s.cfg.size()), bytes(s.user_prm.size()),
      cfg.dpv1.records.empty() ? "" : " and the DPV1 records' buffers", l.end - 1,
      l.ram_end - p.ram_begin, p.name, l.large ? " in 4kB_Mode" : "", p.user_base, limit - 1);
}

const RegDesc& Responder::reg(const Chip& c, RegId id) const {
  const ProfileDesc& p = c.profile();
  if (regs_of_ != &p) {
    regs_.fill(nullptr);
    regs_of_ = &p;
  }
  const RegDesc*& r = regs_[static_cast<std::size_t>(id)];
  if (r == nullptr) r = find_reg(p, id);
  return *r;
}

std::uint32_t Responder::waddr(const Chip& c, RegId id) const {
  const RegDesc& r = reg(c, id);
  return static_cast<std::uint32_t>(r.write_addr >= 0 ? r.write_addr : r.read_addr);
}

std::uint32_t Responder::raddr(const Chip& c, RegId id) const {
  return static_cast<std::uint32_t>(reg(c, id).read_addr);
}

// 16-bit registers go over the 8-bit bus low byte first; the address of each byte depends on
// the bus mode (Intel: low byte at the lower address).
void Responder::write16(BusPort& c, RegId id, std::uint16_t v) const {
  const std::uint32_t a = waddr(c.chip(), id);
  const std::uint32_t lo = c.chip().bus_mode() == BusMode::intel ? a : a + 1;
  const std::uint32_t hi = c.chip().bus_mode() == BusMode::intel ? a + 1 : a;
  c.write(lo, static_cast<std::uint8_t>(v));
  c.write(hi, static_cast<std::uint8_t>(v >> 8));
}

std::uint16_t Responder::read16(BusPort& c, RegId id) const {
  const std::uint32_t a = raddr(c.chip(), id);
  const std::uint32_t lo = c.chip().bus_mode() == BusMode::intel ? a : a + 1;
  const std::uint32_t hi = c.chip().bus_mode() == BusMode::intel ? a + 1 : a;
  const std::uint8_t l = c.read(lo);
  return static_cast<std::uint16_t>(c.read(hi) << 8 | l);
}

std::uint32_t Responder::buffer(BusPort& c, RegId ptr_cell) const {
  return static_cast<std::uint32_t>(c.read(cell_addr(c.chip(), ptr_cell))) << seg_shift_;
}

void Responder::init(BusPort& c) {
  const ProfileDesc& p = c.chip().profile();
  const SlaveConfig& s = cfg_.slave;
  if (const std::string why = responder_layout_problem(p, cfg_); !why.empty())
    throw std::invalid_argument(why);
  const ResponderLayout layout = responder_layout(p, cfg_);
  // Only defined bits: a write to reserved bits would be reported by the chip.
  const auto defined = [&](RegId id) {
    const RegDesc* r = find_reg(p, id);
    return static_cast<std::uint16_t>(~(r->rsvd | r->ign));
  };
  write16(c, RegId::Int_Req_Reg, 0x0000);
  write16(c, RegId::Int_Ack_Reg,
          static_cast<std::uint16_t>(defined(RegId::Int_Ack_Reg) & ~kHandledByReads));
  c.write(waddr(c.chip(), RegId::Mode_Reg1_R),
          static_cast<std::uint8_t>(defined(RegId::Mode_Reg1_R)));
  std::uint16_t mode0 = m0::DP_Mode;  // EOI inactive time 1 us; user timer 1 ms
  if (cfg_.sync_supported) mode0 |= m0::Sync_Supported;
  if (cfg_.freeze_supported) mode0 |= m0::Freeze_Supported;
  if (cfg_.spec_clear_mode) mode0 |= m0::Spec_Clear_Mode;
  write16(c, RegId::Mode_Reg0, mode0);
  // VPC3+ Mode_Reg2: large buffers need the 4 KB mode (this write leaves GC_Int_Mode 0). An
  // input-only slave raises DX_Out only with DX_Int_Mode = 1 ("0 - DX Interrupt only generated, if
  // DOUT length not 0", Profichip DpCfg.h), and the user watchdog is served on DX_Out: the user
  // side sets it then, as an input-only slave's firmware does.
  if (p.id == Profile::vpc3plus) {
    const auto reset = static_cast<std::uint16_t>(find_reg(p, RegId::Mode_Reg2)->reset);
    std::uint16_t mode2 = layout.large ? fields::Mode_Reg2::_4kB_Mode : reset;
    if (cfg_.user_watchdog && s.out_len == 0) mode2 |= fields::Mode_Reg2::DX_Int_Mode;
    if (mode2 != reset)
      c.write(waddr(c.chip(), RegId::Mode_Reg2), static_cast<std::uint8_t>(mode2));
  }
  seg_shift_ = layout.seg_shift;
  const std::uint16_t enabled = irq::MAC_Reset | irq::Go_Leave_Data_Exchange |
                                irq::Baudrate_Detect | irq::WD_DP_Control_Timeout |
                                irq::New_GC_Command | irq::New_SSA_Data | irq::New_Cfg_Data |
                                irq::New_Prm_Data | irq::Diag_Buffer_Changed | irq::DX_Out |
                                (dpv1_ ? irq::FDL_Ind | irq::Poll_End_Ind : 0);
  mask_ = static_cast<std::uint16_t>(~enabled);
  write16(c, RegId::Int_Mask_Reg, mask_);
  c.write(waddr(c.chip(), RegId::WD_Baud_Control_Val), cfg_.wd_baud_control);
  c.write(waddr(c.chip(), RegId::MinTSDR_Val), 0x0B);
  write16(c, RegId::R_User_WD_Value, cfg_.user_wd_value);
  c.write(cell_addr(c.chip(), RegId::R_Ident_Low), static_cast<std::uint8_t>(s.ident));
  c.write(cell_addr(c.chip(), RegId::R_Ident_High), static_cast<std::uint8_t>(s.ident >> 8));
  c.write(cell_addr(c.chip(), RegId::R_TS_Adr), s.address);
  c.write(cell_addr(c.chip(), RegId::R_Real_No_Add_Change), 0x00);

  // Buffers where responder_layout puts them, the cells in the order of its allocation.
  const auto place = [&](RegId ptr_cell) {
    c.write(cell_addr(c.chip(), ptr_cell),
            static_cast<std::uint8_t>(layout.segment[static_cast<std::size_t>(ptr_cell)]));
  };
  c.write(cell_addr(c.chip(), RegId::R_Len_Dout_Buf), s.out_len);
  c.write(cell_addr(c.chip(), RegId::R_Len_Din_Buf), s.in_len);
  for (RegId r : {RegId::R_Dout_Buf_Ptr1, RegId::R_Dout_Buf_Ptr2, RegId::R_Dout_Buf_Ptr3,
                  RegId::R_Din_Buf_Ptr1, RegId::R_Din_Buf_Ptr2, RegId::R_Din_Buf_Ptr3})
    place(r);
  if (p.id == Profile::dpc31) place(RegId::R_Dout_Buf_Ptr_C);
  c.write(cell_addr(c.chip(), RegId::R_Len_Diag_Buf1), kDiagLen);
  c.write(cell_addr(c.chip(), RegId::R_Len_Diag_Buf2), kDiagLen);
  place(RegId::R_Diag_Buf_Ptr1);
  place(RegId::R_Diag_Buf_Ptr2);
  c.write(cell_addr(c.chip(), RegId::R_Len_Cntrl_Buf1), static_cast<std::uint8_t>(aux_len(s)));
  c.write(cell_addr(c.chip(), RegId::R_Len_Cntrl_Buf2), static_cast<std::uint8_t>(aux_len(s)));
  c.write(cell_addr(c.chip(), RegId::R_Aux_Buf_Sel), 0x00);
  for (RegId r : {RegId::R_Aux_Buf_Ptr1, RegId::R_Aux_Buf_Ptr2, RegId::R_Prm_Buf_Ptr,
                  RegId::R_Cfg_Buf_Ptr, RegId::R_Read_Cfg_Buf_Ptr, RegId::R_SSA_Buf_Ptr}) {
    place(r);
  }
  c.write(cell_addr(c.chip(), RegId::R_Len_Read_Cfg_Data), static_cast<std::uint8_t>(s.cfg.size()));
  c.write_block(buffer(c, RegId::R_Read_Cfg_Buf_Ptr), s.cfg);
  if (p.id == Profile::dpc31) {
    refill_substitute(c, false);  // C holds 00h from the reset unless substitute values are given
    place(RegId::InstQ_Base);
    place(RegId::IndQ_Base);
    c.write(cell_addr(c.chip(), RegId::InstQ_Len), kQueueLen);
    c.write(cell_addr(c.chip(), RegId::IndQ_Len), kQueueLen);
  }
  if (p.id == Profile::dpc31 && cfg_.dx_out_port)
    c.write(waddr(c.chip(), RegId::C31_Control), fields::C31_Control::Enable_DX_Out_Port);
  if (dpv1_) dpv1_->init(c, layout.dpv1, seg_shift_);
  give_inputs(c);
  if (p.id != Profile::dpc31) {
    c.write(waddr(c.chip(), RegId::Mode_Reg1_S),
            static_cast<std::uint8_t>(m1::Start_SPC3 | m1::Res_User_WD));
    return;
  }
  // The DPC31 starts its MAC through the Instruction_Queue (DPC31 p.22, Table 5.1-3): the entry
  // MAC_Start, then InstQ_Wr past it; with the user watchdog, DPS_User_Wd Enable in the same
  // write (p.31: it loads R_User_WD_Value and counts down every 10 ms).
  instq_wr_ = 0;
  if (cfg_.user_watchdog) {
    request(c, {{request::MAC_Start, 0x00}, {request::DPS_User_Wd, request::Wd_Enable}});
  } else {
    request(c, {{request::MAC_Start, 0x00}});
  }
}

void Responder::request(BusPort& c,
                        std::initializer_list<std::pair<std::uint8_t, std::uint8_t>> entries) {
  const std::uint32_t instq = buffer(c, RegId::InstQ_Base);
  for (const auto& [code, parameter] : entries) {
    c.write(instq + instq_wr_ * request::kEntryBytes, code);
    c.write(instq + instq_wr_ * request::kEntryBytes + 1, parameter);
    instq_wr_ = static_cast<std::uint8_t>((instq_wr_ + 1) % kQueueLen);
  }
  c.write(cell_addr(c.chip(), RegId::InstQ_Wr), instq_wr_);
}

// dpc31: after a cleared fetch the old U may be the new clear buffer C; prepare the substitute
// values. Without any they are 00h: C holds them from the RAM's reset until the first C fetch,
// which leaves the old outputs there, so only that is zeroed (`c_fetched`).
void Responder::refill_substitute(BusPort& c, bool c_fetched) {
  const std::uint32_t base = buffer(c, RegId::R_Dout_Buf_Ptr_C);  // read always: traces show it
  if (!cfg_.substitute.empty()) {
    c.write_block(base, cfg_.substitute);
  } else if (c_fetched) {
    const std::vector<std::uint8_t> zeros(cfg_.slave.out_len, 0x00);
    c.write_block(base, zeros);
  }
}

void Responder::give_inputs(BusPort& c, bool always) {
  if (inputs_.empty() && !always) return;
  const std::uint8_t u =
      static_cast<std::uint8_t>((c.read(raddr(c.chip(), RegId::Din_Buffer_SM)) >> 4) & 3);
  static constexpr RegId kPtr[] = {RegId::R_Din_Buf_Ptr1, RegId::R_Din_Buf_Ptr2,
                                   RegId::R_Din_Buf_Ptr3};
  c.write_block(buffer(c, kPtr[u - 1]), inputs_);
  c.read(raddr(c.chip(), RegId::New_Din_Buffer_Cmd));
}

void Responder::keep_last_output() {
  if (outputs.size() < 2) return;
  spare_ = std::move(outputs[outputs.size() - 2].data);
  outputs.erase(outputs.begin(), outputs.end() - 1);
}

void Responder::isr(BusPort& c) {
  const std::uint16_t ir = read16(c, RegId::Int_Reg);
  interrupts.emplace_back(c.cycle(), ir);
  if ((ir & irq::New_Prm_Data) != 0) {
    while (c.read(raddr(c.chip(), RegId::User_Prm_Data_Okay)) == kHandshakeConflict) {
    }
    ++prm_accepted;
  }
  if ((ir & irq::New_Cfg_Data) != 0) {
    for (;;) {
      const std::uint32_t cfg = buffer(c, RegId::R_Cfg_Buf_Ptr);
      const std::uint8_t len = c.read(cell_addr(c.chip(), RegId::R_Len_Cfg_Data));
      bool same = len == cfg_.slave.cfg.size();
      for (std::uint32_t i = 0; same && i < len; ++i) same = c.read(cfg + i) == cfg_.slave.cfg[i];
      const RegId verdict = same ? RegId::User_Cfg_Data_Okay : RegId::User_Cfg_Data_Not_Okay;
      if (c.read(raddr(c.chip(), verdict)) != kHandshakeConflict) {
        ++(same ? cfg_accepted : cfg_rejected);
        // The SPC3 enters Data_Exchange with the first New_Din_Buffer_Cmd after Cfg OK (SPC3
        // p.31, docs/decisions.md): fresh inputs for the first answer.
        if (same && c.chip().profile().id == Profile::spc3) give_inputs(c, true);
        break;
      }
    }
  }
  if ((ir & irq::DX_Out) != 0) {
    const std::uint8_t r = c.read(raddr(c.chip(), RegId::Next_Dout_Buffer_Cmd));
    if ((r & fields::Next_Dout_Buffer_Cmd::State_U_Buffer) != 0) {
      static constexpr RegId kPtr[] = {RegId::R_Dout_Buf_Ptr1, RegId::R_Dout_Buf_Ptr2,
                                       RegId::R_Dout_Buf_Ptr3};
      const auto u =
          static_cast<std::uint8_t>(field_of(r, fields::Next_Dout_Buffer_Cmd::Ind_U_Buffer));
      const std::uint32_t base = buffer(c, kPtr[u - 1]);
      Output& o = outputs.emplace_back(Output{
          c.cycle(), std::move(spare_), (r & fields::Next_Dout_Buffer_Cmd::U_Buffer_Cleared) != 0});
      o.data.resize(cfg_.slave.out_len);
      c.read_block(base, o.data);
      // The C fetch exchanges the pointer cells, so U keeps its number; N -> U never does.
      if (o.cleared && c.chip().profile().id == Profile::dpc31) refill_substitute(c, u == last_u_);
      last_u_ = u;
    }
    give_inputs(c);
    if (cfg_.user_watchdog) {
      if (c.chip().profile().id == Profile::dpc31) {
        request(c, {{request::DPS_User_Wd, request::Wd_Reset}});
      } else {
        c.write(waddr(c.chip(), RegId::Mode_Reg1_S), m1::Res_User_WD);
      }
    }
  }
  // MSAC_C1 belongs to the class-1 master's Data_Exchange: a new parameterisation (as DO4's
  // driver does) and leaving Data_Exchange stop it, entering it starts it (docs/dpv1.md).
  if (dpv1_ && (ir & irq::New_Prm_Data) != 0) dpv1_->data_exchange(c, false);
  if (dpv1_ && (ir & irq::Go_Leave_Data_Exchange) != 0) {
    const auto dp =
        static_cast<DpState>(field_of(read16(c, RegId::Status_Reg), fields::Status_Reg::DP_State));
    dpv1_->data_exchange(c, dp == DpState::Data_Exchange);
  }
  if (dpv1_ && (ir & kDpv1Events) != 0) {
    // Acknowledged before the buffers are looked at: an indication stored meanwhile raises the
    // event again instead of being lost.
    write16(c, RegId::Int_Ack_Reg, static_cast<std::uint16_t>(ir & kDpv1Events));
    dpv1_->serve(c, ir);
    const std::uint16_t mask = dpv1_->timer_wanted()
                                   ? static_cast<std::uint16_t>(mask_ & ~irq::User_Timer_Clock)
                                   : static_cast<std::uint16_t>(mask_ | irq::User_Timer_Clock);
    if (mask != mask_) write16(c, RegId::Int_Mask_Reg, mask_ = mask);
  }
  const auto ack = static_cast<std::uint16_t>(ir & ~kHandledByReads & ~kDpv1Events);
  if (ack != 0) write16(c, RegId::Int_Ack_Reg, ack);
  c.write(waddr(c.chip(), RegId::Mode_Reg1_S), m1::EOI);
}

}  // namespace dpc31
