// The Verilated models of rtl/dpc31_blocks.v built into the harness as Duts: one class per
// profile, and one (dpc31) with every mutant behind its mutant_sel input, listed in the generated
// rtl_models.inc (rtl/). Models loaded at run time: rtl_library.cpp.
#include <memory>

#include "dut.hpp"
#include "rtl_library.hpp"
#include "rtl_models_includes.inc"
#include "verilated_blocks.hpp"

namespace dpc31::cosim {

dpc31_rtl_inputs rtl_inputs(const Inputs& in) {
  dpc31_rtl_inputs r{};
  r.rst = in.rst;
  r.ev_dx = in.ev_dx;
  r.bus_rd = in.bus_rd;
  r.bus_wr = in.bus_wr;
  r.bus_addr = in.bus_addr;
  r.bus_wdata = in.bus_wdata;
  r.ev_irq = in.ev_irq;
  r.ev_leave_master = in.ev_leave_master;
  r.ev_wd_expired = in.ev_wd_expired;
  r.ev_prm_fault = in.ev_prm_fault;
  r.ev_gc = in.ev_gc;
  r.gc_cmd = in.gc_cmd;
  r.ev_dout = in.ev_dout;
  r.ev_failsafe = in.ev_failsafe;
  r.ev_din = in.ev_din;
  r.ev_diag_begin = in.ev_diag_begin;
  r.ev_diag_end = in.ev_diag_end;
  r.stat_diag = in.stat_diag;
  r.ev_prm = in.ev_prm;
  r.ev_cfg = in.ev_cfg;
  r.ev_ssa = in.ev_ssa;
  r.ev_dis = in.ev_dis;
  r.dis_bits = in.dis_bits;
  r.ev_mac_stop = in.ev_mac_stop;
  r.ev_mac_start = in.ev_mac_start;
  r.ev_ext_prm = in.ev_ext_prm;
  r.ev_sap_sent = in.ev_sap_sent;
  r.ev_sap_ind = in.ev_sap_ind;
  r.ev_sap_srd = in.ev_sap_srd;
  r.sap_entry = in.sap_entry;
  r.sap_len = in.sap_len;
  return r;
}

namespace {

static_assert(Outputs::kCount == DPC31_RTL_OUTPUTS);

template <class V>
class RtlDut final : public Dut {
 public:
  RtlDut(const DutOptions& o, int mutant_sel)
      : blocks_(o.bus == BusMode::motorola, o.asic_type(), static_cast<unsigned>(mutant_sel)) {}

  bool trace_to(const std::string& path) override { return blocks_.trace_to(path.c_str()); }
  void step(const Inputs& in) override { blocks_.step(rtl_inputs(in)); }
  [[nodiscard]] Outputs outputs() const override {
    Outputs o;
    blocks_.read_outputs(o.v.data());
    return o;
  }
  [[nodiscard]] std::string name() const override { return "RTL"; }
  [[nodiscard]] bool stopped() const override { return blocks_.stopped(); }

 private:
  VerilatedBlocks<V> blocks_;
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
  if (o.rtl) return o.rtl->make_dut(o, mutant_sel(mutant).value_or(0));
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

std::optional<Profile> rtl_mutant_profile(std::string_view mutant) {
  for (const Model& m : kModels) {
    if (*m.mutant != '\0' && mutant == m.mutant) return static_cast<Profile>(m.profile);
  }
  return std::nullopt;
}

std::optional<unsigned> mutant_sel(std::string_view mutant) {
  if (mutant.empty()) return 0u;
  for (const Model& m : kModels) {
    if (mutant == m.mutant) return static_cast<unsigned>(m.mutant_sel);
  }
  // A number for a design of your own with other mutants (mutant_sel is 4 bits).
  unsigned n = 0;
  for (const char c : mutant) {
    if (c < '0' || c > '9' || n > 15) return std::nullopt;
    n = n * 10 + static_cast<unsigned>(c - '0');
  }
  return n >= 1 && n <= 15 ? std::optional<unsigned>(n) : std::nullopt;
}

}  // namespace dpc31::cosim
