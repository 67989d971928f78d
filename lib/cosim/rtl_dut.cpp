// The Verilated models of rtl/dpc31_blocks.v as Duts: one class per profile, and one (dpc31) with
// every mutant behind its mutant_sel input, listed in the generated rtl_models.inc (rtl/).
#include <verilated.h>
#include <verilated_fst_c.h>

#include <memory>

#include "dut.hpp"
#include "rtl_models_includes.inc"

namespace dpc31::cosim {

namespace {

template <class V>
class RtlDut final : public Dut {
 public:
  RtlDut(const DutOptions& o, int mutant_sel) : top_(std::make_unique<V>(&ctx_)) {
    // Only the mutants' model has the input; it stays constant for the whole run.
    if constexpr (requires(V & v) { v.mutant_sel; }) top_->mutant_sel = mutant_sel;
    top_->motorola = o.bus == BusMode::motorola ? 1 : 0;
    top_->asic_type = o.asic_type();
    top_->clk = 0;
    top_->rst = 1;  // power-on: registers to their reset values before cycle 0
    clock();
    top_->rst = 0;
  }
  ~RtlDut() override {
    top_->final();
    if (fst_) fst_->close();
  }

  bool trace_to(const std::string& path) override {
    if constexpr (requires(V & v, VerilatedFstC * t) { v.trace(t, 99); }) {
      ctx_.traceEverOn(true);
      fst_ = std::make_unique<VerilatedFstC>();
      top_->trace(fst_.get(), 99);
      fst_->open(path.c_str());
      return fst_->isOpen();
    } else {
      return false;
    }
  }

  void step(const Inputs& in) override {
    top_->rst = in.rst;
    top_->bus_rd = in.bus_rd;
    top_->bus_wr = in.bus_wr;
    top_->bus_addr = in.bus_addr;
    top_->bus_wdata = in.bus_wdata;
    top_->ev_irq = in.ev_irq;
    top_->ev_leave_master = in.ev_leave_master;
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
    clock();
  }

  [[nodiscard]] Outputs outputs() const override {
    const V& t = *top_;
    Outputs o;
    o.v = {t.x_int,         t.irr,         t.imr,         t.mode_reg0, t.mode_reg1,    t.started,
           t.dp_state,      t.prm_pending, t.cfg_pending, t.ssa_free,  t.prm_fault,    t.cfg_fault,
           t.not_supported, t.sync_mode,   t.freeze_mode, t.diag_flag, t.dout_sm,      t.din_sm,
           t.diag_sm,       t.u_cleared,   t.n_cleared,   t.n_cl,      t.d_fresh,      t.dout_ptr1,
           t.dout_ptr2,     t.dout_ptr3,   t.dout_ptr_c,  t.cfg_ptr,   t.read_cfg_ptr, t.gc_command,
           t.bus_rdata};
    return o;
  }

  [[nodiscard]] std::string name() const override { return "RTL"; }

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

struct Model {
  const char* mutant;
  int profile;     // -1: any
  int mutant_sel;  // the model's mutant_sel input (0: none)
  std::unique_ptr<Dut> (*make)(const DutOptions&, int mutant_sel);
};

template <class V>
std::unique_ptr<Dut> make(const DutOptions& o, int mutant_sel) {
  return std::make_unique<RtlDut<V>>(o, mutant_sel);
}

#define DPC31_RTL_MODEL(cls, mutant, profile, mutant_sel) {mutant, profile, mutant_sel, &make<cls>},
constexpr Model kModels[] = {
#include "rtl_models.inc"
};
#undef DPC31_RTL_MODEL

}  // namespace

std::unique_ptr<Dut> make_rtl_dut(const DutOptions& o, std::string_view mutant) {
  for (const Model& m : kModels) {
    if (mutant == m.mutant && (m.profile < 0 || m.profile == static_cast<int>(o.profile)))
      return m.make(o, m.mutant_sel);
  }
  return nullptr;
}

std::vector<std::string> rtl_mutants() {
  std::vector<std::string> out;
  for (const Model& m : kModels) {
    if (*m.mutant != '\0') out.emplace_back(m.mutant);
  }
  return out;
}

}  // namespace dpc31::cosim
