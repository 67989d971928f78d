/* RTL models (lib/cosim/rtl_model/dpc31_rtl_model.h) whose table is wrong in one way each, as a
 * hand-written entry point for another simulator may be: `dpc31 cosim --rtl-model` refuses each
 * with one line naming what is wrong, exit 2, and never calls a NULL entry
 * (tests/bad_input_test.cpp, BadInput.RtlModelTablesAreCheckedBeforeUse), one per macro
 * (tests/CMakeLists.txt):
 *   GET_NULL      dpc31_rtl_model_get() returns NULL
 *   OLD_ABI       interface version 3
 *   OUTPUTS_30    30 outputs, not DPC31_RTL_OUTPUTS
 *   NULL_STEP     step is NULL
 *   NO_PROFILE    profile is NULL
 *   BAD_PROFILE   profile "dpc32"
 *   SPC3          built for profile spc3 (run on dpc31: refused)
 *   CREATE_NULL   create() returns NULL
 * and two that load (BadInput.RtlModelWithoutTracingOrMutantOfAnotherProfile):
 *   NO_TRACE      every output 0 (diverges at cycle 0), trace_to returns 0
 *   MUTANT_SEL    as NO_TRACE, with the mutant_sel input */
#include "dpc31_rtl_model.h"

#define EXPORT __attribute__((visibility("default")))

static void* create(int motorola, unsigned asic_type, unsigned mutant_sel) {
  (void)motorola;
  (void)asic_type;
  (void)mutant_sel;
#if defined(CREATE_NULL)
  return 0;
#else
  static int instance;
  return &instance;
#endif
}
static void destroy(void* m) { (void)m; }
#if !defined(NULL_STEP)
static void step(void* m, const struct dpc31_rtl_inputs* in) {
  (void)m;
  (void)in;
}
#endif
static void read_outputs(const void* m, uint32_t out[DPC31_RTL_OUTPUTS]) {
  (void)m;
  for (int i = 0; i < DPC31_RTL_OUTPUTS; ++i) out[i] = 0;
}
static int trace_to(void* m, const char* path) {
  (void)m;
  (void)path;
  return 0;
}

static const struct dpc31_rtl_model model = {
#if defined(OLD_ABI)
    .abi = 3,
#else
    .abi = DPC31_RTL_MODEL_ABI,
#endif
#if defined(OUTPUTS_30)
    .outputs = 30,
#else
    .outputs = DPC31_RTL_OUTPUTS,
#endif
#if defined(MUTANT_SEL)
    .has_mutant_sel = 1,
#endif
    .top = "table",
#if defined(BAD_PROFILE)
    .profile = "dpc32",
#elif defined(SPC3)
    .profile = "spc3",
#elif !defined(NO_PROFILE)
    .profile = "dpc31",
#endif
    .create = create,
    .destroy = destroy,
#if defined(NULL_STEP)
    .step = 0,
#else
    .step = step,
#endif
    .read_outputs = read_outputs,
    .trace_to = trace_to};

EXPORT const struct dpc31_rtl_model* dpc31_rtl_model_get(void);
const struct dpc31_rtl_model* dpc31_rtl_model_get(void) {
#if defined(GET_NULL)
  (void)model;
  return 0;
#else
  return &model;
#endif
}
