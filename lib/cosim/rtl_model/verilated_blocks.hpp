// Any Verilated model with the ports of docs/golden-model.md, driven one cycle at a time: the
// harness's built-in models (lib/cosim/rtl_dut.cpp) and the models built from a user's RTL
// (rtl_model_entry.cpp, through the C entry point of dpc31_rtl_model.h) share this class.
#pragma once

#include <verilated.h>
#include <verilated_fst_c.h>

#include <cstdint>
#include <memory>

#include "dpc31_rtl_model.h"

namespace dpc31::cosim {

template <class V>
class VerilatedBlocks {
 public:
  static constexpr bool kHasMutantSel = requires(V & v) { v.mutant_sel; };

  VerilatedBlocks(bool motorola, unsigned asic_type, unsigned mutant_sel)
      : top_(std::make_unique<V>(&ctx_)) {
    // A $stop, $fatal or failed assertion of the RTL ends its run with a report, not the whole
    // process with abort(): Verilator then only prints its message and sets gotError.
    ctx_.fatalOnError(false);
    // Only a model with mutants has the input; it stays constant for the whole run.
    if constexpr (kHasMutantSel) top_->mutant_sel = static_cast<std::uint8_t>(mutant_sel);
    top_->motorola = motorola ? 1 : 0;
    top_->asic_type = static_cast<std::uint8_t>(asic_type);
    top_->clk = 0;
    top_->rst = 1;  // power-on: registers to their reset values before cycle 0
    clock();
    top_->rst = 0;
  }
  ~VerilatedBlocks() {
    top_->final();
    if (fst_) fst_->close();
  }
  VerilatedBlocks(const VerilatedBlocks&) = delete;
  VerilatedBlocks& operator=(const VerilatedBlocks&) = delete;

  // False for models Verilated without FST tracing (the mutants' built-in model).
  bool trace_to(const char* path) {
    if constexpr (requires(V & v, VerilatedFstC * t) { v.trace(t, 99); }) {
      ctx_.traceEverOn(true);
      fst_ = std::make_unique<VerilatedFstC>();
      top_->trace(fst_.get(), 99);
      fst_->open(path);
      return fst_->isOpen();
    } else {
      return false;
    }
  }

  // The RTL has stopped itself ($stop, $fatal, a failed assertion).
  [[nodiscard]] bool stopped() const { return ctx_.gotError(); }

  void step(const dpc31_rtl_inputs& in) {
    top_->rst = in.rst;
    top_->bus_rd = in.bus_rd;
    top_->bus_wr = in.bus_wr;
    top_->bus_addr = in.bus_addr;
    top_->bus_wdata = in.bus_wdata;
    top_->ev_irq = in.ev_irq;
    top_->ev_leave_master = in.ev_leave_master;
    top_->ev_wd_expired = in.ev_wd_expired;
    top_->ev_gc = in.ev_gc;
    top_->gc_cmd = in.gc_cmd;
    top_->ev_dout = in.ev_dout;
    top_->ev_failsafe = in.ev_failsafe;
    top_->ev_din = in.ev_din;
    top_->ev_diag_begin = in.ev_diag_begin;
    top_->ev_diag_end = in.ev_diag_end;
    top_->stat_diag = in.stat_diag;
    top_->ev_prm = in.ev_prm;
    top_->ev_cfg = in.ev_cfg;
    top_->ev_ssa = in.ev_ssa;
    top_->ev_prm_fault = in.ev_prm_fault;
    top_->ev_dx = in.ev_dx;
    top_->ev_dis = in.ev_dis;
    top_->dis_bits = in.dis_bits;
    top_->ev_mac_stop = in.ev_mac_stop;
    top_->ev_mac_start = in.ev_mac_start;
    top_->ev_ext_prm = in.ev_ext_prm;
    top_->ev_sap_sent = in.ev_sap_sent;
    top_->ev_sap_ind = in.ev_sap_ind;
    top_->ev_sap_srd = in.ev_sap_srd;
    top_->sap_entry = in.sap_entry;
    top_->sap_len = in.sap_len;
    clock();
  }

  void read_outputs(std::uint32_t* out) const {
    const V& t = *top_;
    const std::uint32_t v[DPC31_RTL_OUTPUTS] = {
        t.x_int,         t.irr,         t.imr,         t.mode_reg0, t.mode_reg1,    t.started,
        t.dp_state,      t.prm_pending, t.cfg_pending, t.ssa_free,  t.prm_fault,    t.cfg_fault,
        t.not_supported, t.sync_mode,   t.freeze_mode, t.diag_flag, t.dout_sm,      t.din_sm,
        t.diag_sm,       t.u_cleared,   t.n_cleared,   t.n_cl,      t.d_fresh,      t.dout_ptr1,
        t.dout_ptr2,     t.dout_ptr3,   t.dout_ptr_c,  t.cfg_ptr,   t.read_cfg_ptr, t.gc_command,
        t.bus_rdata};
    for (int i = 0; i < DPC31_RTL_OUTPUTS; ++i) out[i] = v[i];
  }

 private:
  void clock() {
    top_->clk = 0;
    top_->eval();
    if (fst_) fst_->dump(2 * cycle_);
    top_->clk = 1;
    top_->eval();
    if (fst_) fst_->dump(2 * cycle_ + 1);
    ++cycle_;
  }

  VerilatedContext ctx_;
  std::unique_ptr<V> top_;
  std::unique_ptr<VerilatedFstC> fst_;
  std::uint64_t cycle_ = 0;
};

}  // namespace dpc31::cosim
