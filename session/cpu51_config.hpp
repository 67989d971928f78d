// What a board with an 80C32 beside the chip is (the scenario header `cpu 80c32`, `dpc31 bridge
// --cpu`): its clock, the firmware image and where the chip and the module's output latch sit in
// XDATA (docs/cpu.md, "DO4 on the 80C32"). Plain data: users of scenario.hpp need no MCS-51 core
// (its checks are in cpu51_module.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "dpc31/chip.hpp"

namespace dpc31 {

// The chip's window in XDATA: [base, base + kCpu51Window).
inline constexpr std::uint32_t kCpu51Window = 0x1000;

struct Cpu51Config {
  std::uint32_t hz = 24'000'000;
  std::string hex{};  // the Intel HEX file (a scenario's relative path already resolved)
  std::uint16_t base = 0x8000;
  std::uint16_t latch = 0x4000;
  std::vector<std::string> ports{};  // latch bytes by name, from `latch` on; none: default_ports()
  // `cpu c31`: the DPC31's internal C31 instead (docs/dpc31.md, "The C31"): its XDATA is the
  // chip's own space, its code the chip's RAM from `code` up to 1FFFh; no board RAM, no latch.
  bool c31 = false;
  std::uint16_t code = 0x1000;
  // DO4's latch bytes, `outputs` and `modul_ok` (docs/cpu.md, "DO4 on the 80C32": the shipped
  // firmware writes 4000h + port): the latch of a board whose `ports` names none, at every door.
  static const std::vector<std::string>& default_ports();
  // The latch bytes by name from `latch` on: `ports`, default_ports() when it names none, none on
  // the C31 (it has no latch). What every door names, checks and records.
  [[nodiscard]] const std::vector<std::string>& latch_ports() const;
  // "" or "the chip's window covers the output latch at 0x4000": a byte of latch_ports() inside
  // the window would go into the chip. The one check of the scenario header, the bridge and serve.
  [[nodiscard]] std::string latch_problem() const;
  // "" or why `ports` cannot name the latch bytes: a name empty, not a word
  // ([A-Za-z_][A-Za-z0-9_]*: `serve`'s protocol lines and `latch` replies carry it between blanks),
  // or given twice
  // (`expect port` would see only the first). The one check of every door.
  [[nodiscard]] std::string ports_problem() const;
  // "" or why the chip `chip` makes cannot be on this board: the 80C32 drives the chip's Intel
  // mode and takes X/INT on INT0, which the C31's interrupt controller leaves inactive; the C31
  // serves that controller (docs/cpu.md).
  [[nodiscard]] std::string chip_problem(const ChipOptions& chip) const;
};

// "" or why `names` cannot name ports (what = "port") or a module's inputs ("input"): one empty,
// not a word, or named twice, in the words of Cpu51Config::ports_problem, which uses it, as does
// a plug-in's descriptor at load (firmware_plugin.cpp).
// The core a scenario's `cpu` line or `--cpu` names, in any case (`80C32`, as the docs and the walk
// spell the part; `--firmware DO4` is case-insensitive too): "80c32", "c31", or "" for another.
[[nodiscard]] std::string_view cpu_core(std::string_view word);

[[nodiscard]] std::string names_problem(const std::vector<std::string>& names,
                                        std::string_view what);

}  // namespace dpc31
