// The C++ blocks as a Dut: a ChipCore stepped at every cycle with stimulus (idle cycles in one
// advance with the event engine), the bus access applied in its completion cycle, the events
// through the same actions the protocol engine uses.
#include "cpp_dut.hpp"

#include <fmt/format.h>

#include <array>
#include <iterator>
#include <vector>

#include "block_access.hpp"
#include "core.hpp"
#include "dpc31/dpv1.hpp"
#include "dpc31/reg_ids.hpp"
#include "dut.hpp"

namespace dpc31::cosim {

namespace {

// At most one entry per SAP 0-51 (docs/dpv1.md).
constexpr std::uint32_t kMaxSapEntries = 52;

constexpr std::array<std::string_view, Outputs::kCount> kNames = {
    "x_int",         "irr",         "imr",         "mode_reg0", "mode_reg1",    "started",
    "dp_state",      "prm_pending", "cfg_pending", "ssa_free",  "prm_fault",    "cfg_fault",
    "not_supported", "sync_mode",   "freeze_mode", "diag_flag", "dout_sm",      "din_sm",
    "diag_sm",       "u_cleared",   "n_cleared",   "n_cl",      "d_fresh",      "dout_ptr1",
    "dout_ptr2",     "dout_ptr3",   "dout_ptr_c",  "cfg_ptr",   "read_cfg_ptr", "gc_command",
    "bus_rdata"};
constexpr std::array<int, Outputs::kCount> kWidths = {
    1, 16, 16, 16, 8, 1, 2, 1, 1, 1, 1, 1, 1, 1, 1, 1, 8, 8, 4, 1, 1, 1, 1, 8, 8, 8, 8, 8, 8, 8, 8};

class CppDut final : public Dut {
 public:
  explicit CppDut(const DutOptions& o)
      : core_(ChipOptions{o.profile, o.bus, 0, o.engine, o.variant}),
        lazy_(o.engine == Engine::event) {
    core_.signals.sink = nullptr;
    // The request interface (DPC31 Instruction_Queue) is not one of the blocks: what its requests
    // do to them comes in as events (ev_mac_stop, ev_mac_start, ev_leave_master, ev_irq), so a
    // replayed InstQ_Wr write must not execute the queue a second time.
    core_.hooks[RegisterFile::idx(RegId::InstQ_Wr)].post_write = nullptr;
    core_.reset();
  }

  // An idle cycle is only counted (with the event engine): the blocks catch up in one advance at
  // the next stimulus, or when the outputs are asked for and an internal event (a timer) fell
  // due in between; until then the outputs of the last evaluation still hold.
  void step(const Inputs& in) override {
    if (in.rst) {
      core_.reset();  // the cycle count restarts with the hardware
      rdata_ = 0;
      idle_ = 0;
      fresh_ = false;
      return;
    }
    if (lazy_ && in.idle()) {
      ++idle_;
      return;
    }
    core_.advance(idle_ + 1);
    idle_ = 0;
    fresh_ = false;
    DpStateMachine& dp = core_.dp;
    BufferUnit& buffers = core_.buffers;
    if (in.ev_dx)
      core_.regs.latch(RegId::Mode_Reg1) &=
          static_cast<std::uint16_t>(~fields::Mode_Reg1::Res_User_WD);
    if (in.ev_irq != 0) core_.irq.raise(in.ev_irq);
    if (in.ev_leave_master) dp.leave_master();
    if (in.ev_wd_expired) {
      core_.irq.raise(irq::WD_DP_Control_Timeout);
      dp.dp_control_expired();
    }
    if (in.ev_prm_fault) dp.prm_fault();
    if (in.ev_gc) dp.apply_global_control(in.gc_cmd);
    if (in.ev_dout) buffers.outputs_received(BlockAccess::state(dp).sync_mode);
    if (in.ev_failsafe) buffers.failsafe_clear();
    if (in.ev_din) buffers.inputs_due(BlockAccess::state(dp).freeze_mode);
    if (in.ev_diag_begin) buffers.diag_send_begin();
    if (in.ev_diag_end) buffers.diag_send_end(in.stat_diag);
    if (in.ev_dis) {
      std::uint16_t& m0 = core_.regs.latch(RegId::Mode_Reg0);
      constexpr std::uint16_t kDis =
          fields::Mode_Reg0::Dis_Start_Control | fields::Mode_Reg0::Dis_Stop_Control;
      m0 = static_cast<std::uint16_t>((m0 & ~kDis) | (in.dis_bits & kDis));
    }
    if (in.ev_prm) dp.prm_accepted();
    if (in.ev_ext_prm) dp.ext_prm_accepted();
    if (in.ev_cfg) dp.cfg_accepted();
    if (in.ev_ssa) dp.ssa_accepted();
    // The SAP list's verdicts (the entry, the request's length) come in; the header machine runs.
    if (in.ev_sap_sent) core_.sap_list.response_sent();
    if (in.ev_sap_ind) {
      fdl::Frame req;
      req.du.assign(in.sap_len, 0);  // the data are not compared, their length is
      core_.sap_list.indicate(in.sap_entry, req);
    }
    if (in.ev_sap_srd) core_.sap_list.answer(in.sap_entry);
    if (in.ev_mac_stop) core_.mode.offline();  // as MAC_Stop (requests.cpp): at once
    if (in.ev_mac_start) core_.mode.start();
    if (in.bus_rd) rdata_ = core_.read_now(in.bus_addr);
    if (in.bus_wr) core_.write_now(in.bus_addr, in.bus_wdata);
    core_.irq.update_line();
  }

  [[nodiscard]] Outputs outputs() const override {
    if (idle_ != 0 && core_.clock.now + idle_ >= core_.next_event()) {
      core_.advance(idle_);
      core_.irq.update_line();
      idle_ = 0;
      fresh_ = false;
    }
    if (!fresh_) {
      outputs_ = block_outputs(core_, rdata_);
      fresh_ = true;
    }
    return outputs_;
  }

  [[nodiscard]] std::string name() const override { return "EMU"; }

  // The cells the SAP-buffer header machine writes: byte 0 of each entry of the list at
  // R_FDL_SAP_List_Ptr (Response_Sent) and the Control byte of each buffer an entry names.
  [[nodiscard]] bool compares_ram(std::uint16_t addr) const override {
    namespace e = dpv1::entry;
    const RegisterFile& regs = core_.regs;
    if (regs.id() != Profile::vpc3plus || regs.cell(RegId::R_FDL_SAP_List_Ptr) == 0) return false;
    const std::uint32_t shift = regs.segment_shift();
    std::uint32_t a = std::uint32_t{regs.cell(RegId::R_FDL_SAP_List_Ptr)} << shift;
    for (std::uint32_t i = 0; i < kMaxSapEntries; ++i, a += e::kBytes) {
      const std::uint8_t b0 = core_.peek(a + e::Sap);
      if (b0 == e::kEndOfList) return false;
      if (addr == a + e::Sap) return true;
      for (const std::uint32_t k : {e::Ind_Buf_Ptr0, e::Ind_Buf_Ptr1, e::Resp_Buf_Ptr}) {
        const std::uint8_t seg = core_.peek(a + k);
        if (seg != 0 && addr == (std::uint32_t{seg} << shift) + dpv1::header::Control) return true;
      }
    }
    return false;
  }

 private:
  // outputs() catches up with counted idle cycles: the chip's time is the Dut's, not a value.
  mutable ChipCore core_;
  std::uint8_t rdata_ = 0;
  const bool lazy_;
  mutable std::uint64_t idle_ = 0;  // idle cycles counted, not yet applied
  mutable Outputs outputs_;         // the outputs after the last evaluation
  mutable bool fresh_ = false;      // outputs_ is current
};

}  // namespace

const std::array<std::string_view, Outputs::kCount>& Outputs::names() { return kNames; }
const std::array<int, Outputs::kCount>& Outputs::widths() { return kWidths; }

// Asked twice per lockstep cycle: one OR over every member, without a branch per member (the
// member-wise comparison with Inputs{} was a tenth of the lockstep's instructions).
bool Inputs::idle() const {
  static_assert(sizeof(Inputs) == 36, "a new member of Inputs: add it here");
  const unsigned strobes = rst | ev_dx | bus_rd | bus_wr | ev_leave_master | ev_wd_expired |
                           ev_prm_fault | ev_gc | ev_dout | ev_failsafe | ev_din | ev_diag_begin |
                           ev_diag_end | stat_diag | ev_prm | ev_cfg | ev_ssa | ev_dis |
                           ev_mac_stop | ev_mac_start | ev_ext_prm | ev_sap_sent | ev_sap_ind |
                           ev_sap_srd;
  const unsigned values = bus_addr | bus_wdata | ev_irq | gc_cmd | dis_bits | sap_entry | sap_len;
  return (strobes | values) == 0;
}

Outputs block_outputs(const ChipCore& c, std::uint8_t rdata) {
  auto latch = [&](RegId id) { return std::uint32_t{c.regs.latch(id)}; };
  auto cell = [&](RegId id) -> std::uint32_t {
    return c.regs.reg(id) != nullptr ? c.regs.cell(id) : 0;
  };
  const bool int_pol = (latch(RegId::Mode_Reg0) & fields::Mode_Reg0::INT_Pol) != 0;
  const bool active = c.irq.active();
  const BufferUnit::State& b = BlockAccess::state(c.buffers);
  const DpStateMachine::State& dp = BlockAccess::state(c.dp);
  Outputs o;
  o.v = {int_pol ? active : !active,
         latch(RegId::Int_Req_Reg),
         latch(RegId::Int_Mask_Reg),
         latch(RegId::Mode_Reg0),
         latch(RegId::Mode_Reg1),
         dp.started,
         static_cast<std::uint32_t>(dp.state),
         dp.prm.pending,
         dp.cfg.pending,
         dp.ssa_free,
         dp.prm_fault,
         dp.cfg_fault,
         dp.not_supported,
         dp.sync_mode,
         dp.freeze_mode,
         b.diag_flag,
         b.dout.sm(),
         b.din.sm(),
         b.diag.sm(),
         b.u_cleared,
         b.n_cleared,
         b.n_cl,
         b.d_fresh,
         cell(RegId::R_Dout_Buf_Ptr1),
         cell(RegId::R_Dout_Buf_Ptr2),
         cell(RegId::R_Dout_Buf_Ptr3),
         cell(RegId::R_Dout_Buf_Ptr_C),
         cell(RegId::R_Cfg_Buf_Ptr),
         cell(RegId::R_Read_Cfg_Buf_Ptr),
         cell(RegId::R_GC_Command),
         rdata};
  return o;
}

std::unique_ptr<Dut> make_cpp_dut(const DutOptions& o) { return std::make_unique<CppDut>(o); }

namespace {

// The compared addresses of a profile, one bit per address of the 16-bit bus.
std::vector<bool> compared_addresses(const ProfileDesc& p) {
  std::vector<bool> set(0x10000, false);
  static constexpr RegId kCells[] = {RegId::R_Dout_Buf_Ptr1, RegId::R_Dout_Buf_Ptr2,
                                     RegId::R_Dout_Buf_Ptr3, RegId::R_Dout_Buf_Ptr_C,
                                     RegId::R_Cfg_Buf_Ptr,   RegId::R_Read_Cfg_Buf_Ptr,
                                     RegId::R_GC_Command};
  for (RegId id : kCells) {
    const RegDesc* r = find_reg(p, id);
    if (r != nullptr && r->read_addr >= 0) set[static_cast<std::size_t>(r->read_addr)] = true;
  }
  for (const RegDesc& r : p.regs) {
    // C31_Control (the DX_Out port option) is not one of the blocks.
    if (r.kind == Kind::cell || r.read_addr < 0 || r.id == RegId::C31_Control) continue;
    for (int k = 0; k < r.bytes(); ++k) set[static_cast<std::size_t>(r.read_addr + k)] = true;
  }
  return set;
}

}  // namespace

// Asked at every read of the lockstep: a table per profile, made once.
bool compared_read(const ProfileDesc& p, std::uint16_t addr) {
  static const std::array<std::vector<bool>, std::size(kAllProfiles)> tables = [] {
    std::array<std::vector<bool>, std::size(kAllProfiles)> t;
    for (const Profile q : kAllProfiles)
      t[static_cast<std::size_t>(q)] = compared_addresses(profile_desc(q));
    return t;
  }();
  return tables[static_cast<std::size_t>(p.id)][addr];
}

}  // namespace dpc31::cosim
