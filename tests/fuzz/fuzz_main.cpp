// libFuzzer's entry point for one target, chosen at compile time (DPC31_FUZZ_ENTRY).
#include "fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return dpc31::fuzz::DPC31_FUZZ_ENTRY(data, size);
}
