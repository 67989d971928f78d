/* The C entry point of an RTL model built for the lockstep harness (docs/golden-model.md,
 * "Putting your own RTL under the harness"): a shared object made by dpc31emu_verilate_model()
 * or by `dpc31 cosim --rtl` exports dpc31_rtl_model_get(), which `dpc31 cosim` finds with dlsym.
 * Plain C, so the harness and the model need not share a C++ ABI or a Verilator runtime. */
#ifndef DPC31_RTL_MODEL_H
#define DPC31_RTL_MODEL_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Raised whenever a struct below changes; the harness refuses any other value. */
#define DPC31_RTL_MODEL_ABI 5
/* Outputs in the order of docs/golden-model.md "Outputs compared on every cycle", bus_rdata last.
 */
#define DPC31_RTL_OUTPUTS 31

/* The inputs of one cycle (the ports of the same names). */
struct dpc31_rtl_inputs {
  uint8_t rst, ev_dx, bus_rd, bus_wr;
  uint16_t bus_addr;
  uint8_t bus_wdata;
  uint16_t ev_irq;
  uint8_t ev_leave_master, ev_wd_expired, ev_prm_fault, ev_gc, gc_cmd, ev_dout, ev_failsafe, ev_din,
      ev_diag_begin, ev_diag_end, stat_diag, ev_prm, ev_cfg, ev_ssa, ev_dis, dis_bits, ev_mac_stop,
      ev_mac_start;
  /* vpc3plus, DPV1: the SAP-buffer header machine (ABI 3) */
  uint8_t ev_ext_prm, ev_sap_sent, ev_sap_ind, ev_sap_srd;
  uint16_t sap_entry;
  uint8_t sap_len;
};

struct dpc31_rtl_model {
  uint32_t abi;       /* DPC31_RTL_MODEL_ABI */
  uint32_t outputs;   /* DPC31_RTL_OUTPUTS */
  int has_mutant_sel; /* the model has the input mutant_sel[3:0] */
  const char* top;    /* the Verilog top module */
  /* The profile the model is built for (-GPROFILE=): "spc3", "vpc3plus" or "dpc31" (ABI 4); the
   * harness refuses a run of another profile. */
  const char* profile;
  /* A model after its power-on reset (one clock with rst = 1); NULL when out of memory. The
   * static inputs stay as given for the whole run. */
  void* (*create)(int motorola, unsigned asic_type, unsigned mutant_sel);
  void (*destroy)(void* model);
  /* One clock: the inputs of this cycle, then the edge. */
  void (*step)(void* model, const struct dpc31_rtl_inputs* in);
  void (*read_outputs)(const void* model, uint32_t out[DPC31_RTL_OUTPUTS]);
  /* FST of every internal signal from now on; 0 if the file cannot be opened. */
  int (*trace_to)(void* model, const char* path);
  /* 1 once the RTL has stopped itself ($stop, $fatal, a failed assertion), else 0 (ABI 5); the
   * harness reports it as a divergence in that cycle. NULL: a model that never stops itself. */
  int (*stopped)(const void* model);
};

const struct dpc31_rtl_model* dpc31_rtl_model_get(void);

#ifdef __cplusplus
}
#endif

#endif
