// The C entry point (dpc31_rtl_model.h) over one Verilated model, compiled once per model by
// dpc31emu_verilate_model() (packaging/dpc31emu_rtl.cmake) with DPC31_RTL_CLASS (the Verilated
// class) and DPC31_RTL_HEADER (its header), DPC31_RTL_TOP (the module name), DPC31_RTL_PROFILE
// (the PROFILE it is verilated for).
#include "verilated_blocks.hpp"
#include DPC31_RTL_HEADER

namespace {

using Blocks = dpc31::cosim::VerilatedBlocks<DPC31_RTL_CLASS>;

void* create(int motorola, unsigned asic_type, unsigned mutant_sel) {
  try {
    return new Blocks(motorola != 0, asic_type, mutant_sel);
  } catch (...) {  // nothing may cross the C boundary
    return nullptr;
  }
}
void destroy(void* m) { delete static_cast<Blocks*>(m); }
void step(void* m, const dpc31_rtl_inputs* in) { static_cast<Blocks*>(m)->step(*in); }
void read_outputs(const void* m, std::uint32_t* out) {
  static_cast<const Blocks*>(m)->read_outputs(out);
}
int trace_to(void* m, const char* path) { return static_cast<Blocks*>(m)->trace_to(path) ? 1 : 0; }
int stopped(const void* m) { return static_cast<const Blocks*>(m)->stopped() ? 1 : 0; }

constexpr dpc31_rtl_model kModel = {DPC31_RTL_MODEL_ABI,
                                    DPC31_RTL_OUTPUTS,
                                    Blocks::kHasMutantSel ? 1 : 0,
                                    DPC31_RTL_TOP,
                                    DPC31_RTL_PROFILE,
                                    create,
                                    destroy,
                                    step,
                                    read_outputs,
                                    trace_to,
                                    stopped};

}  // namespace

extern "C" __attribute__((visibility("default"))) const dpc31_rtl_model* dpc31_rtl_model_get() {
  return &kModel;
}
