// The block-level ports of docs/golden-model.md, and the Dut interface the lockstep harness
// drives: one adapter for the C++ blocks, one per Verilated model, and any user RTL with the same
// ports.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/regdesc.hpp"

namespace dpc31 {
struct BlockEvent;
}

namespace dpc31::cosim {

class RtlLibrary;

struct Inputs {
  bool rst = false;
  bool ev_dx = false;
  bool bus_rd = false;
  bool bus_wr = false;
  std::uint16_t bus_addr = 0;
  std::uint8_t bus_wdata = 0;
  std::uint16_t ev_irq = 0;
  bool ev_leave_master = false;
  bool ev_wd_expired = false;
  bool ev_prm_fault = false;
  bool ev_gc = false;
  std::uint8_t gc_cmd = 0;
  bool ev_dout = false;
  bool ev_failsafe = false;
  bool ev_din = false;
  bool ev_diag_begin = false;
  bool ev_diag_end = false;
  bool stat_diag = false;
  bool ev_prm = false;
  bool ev_cfg = false;
  bool ev_ssa = false;
  bool ev_dis = false;
  std::uint8_t dis_bits = 0;
  bool ev_mac_stop = false;
  bool ev_mac_start = false;
  // vpc3plus, DPV1 (docs/golden-model.md, "The SAP-buffer header machine")
  bool ev_ext_prm = false;
  bool ev_sap_sent = false;
  bool ev_sap_ind = false;
  bool ev_sap_srd = false;
  std::uint16_t sap_entry = 0;  // ev_sap_ind / ev_sap_srd: the SAP-list entry's RAM address
  std::uint8_t sap_len = 0;     // ev_sap_ind: the request's data length

  [[nodiscard]] bool idle() const;
  [[nodiscard]] std::string describe() const;  // "wr 0008<-02 ev_gc(08)"; empty when idle
  bool operator==(const Inputs&) const = default;
};

// The stimulus vocabulary (lib/cosim/stimulus.cpp, one table): one token of a trace line into
// `in` (the bus accesses read their operand from `rest`); "" or the one-line reason it is none
// ("unknown stimulus 'x'", or a known event whose operand is not as Inputs::describe writes it).
std::string parse_input_token(const std::string& tok, std::istringstream& rest, Inputs& in);
// "" or why `in` has an input the chip of profile `p` does not have ("'ev_mac_start' is an input
// of profile dpc31 only, not of spc3").
std::string input_not_on(const Inputs& in, Profile p);
// A block event of a chip session (emu/block_event.hpp) into the inputs of its cycle.
void apply_block_event(Inputs& in, const BlockEvent& e);

// Every compared output, in a fixed order (names are the Verilog port names).
struct Outputs {
  static constexpr std::size_t kCount = 31;
  std::array<std::uint32_t, kCount> v{};
  static const std::array<std::string_view, kCount>& names();
  static const std::array<int, kCount>& widths();
  // Index of bus_rdata, compared only in cycles with a read of a compared address.
  static constexpr std::size_t kRdata = kCount - 1;
};

class Dut {
 public:
  virtual ~Dut() = default;
  // One clock: apply the inputs of this cycle, then the outputs show the state after it.
  virtual void step(const Inputs& in) = 0;
  [[nodiscard]] virtual Outputs outputs() const = 0;
  [[nodiscard]] virtual std::string name() const = 0;
  // Whether a read of this RAM address is compared besides the registers and mirrored cells
  // (compared_read): the C++ side names the cells of the SAP-buffer header machine.
  [[nodiscard]] virtual bool compares_ram(std::uint16_t /*addr*/) const { return false; }
  // Internal waveform of the whole model from now on (Verilated models built with tracing:
  // FST). False where the model has none.
  virtual bool trace_to(const std::string& /*path*/) { return false; }
  // The model has stopped itself ($stop, $fatal or a failed assertion of an RTL): a divergence.
  [[nodiscard]] virtual bool stopped() const { return false; }
};

struct DutOptions {
  Profile profile = Profile::dpc31;
  BusMode bus = BusMode::intel;
  std::optional<Vpc3Variant> variant = std::nullopt;  // vpc3plus only (ChipOptions::variant)
  // A model loaded at run time (rtl_library.hpp) in place of the built-in ones.
  std::shared_ptr<const RtlLibrary> rtl = nullptr;
  // The C++ blocks' engine (docs/engine.md): event (the default) lets idle cycles pass in one
  // step until something is due; per_cycle evaluates every clock, the reference it is checked
  // against (tests: CosimEngines.*).
  Engine engine = Engine::event;
  // Status_Reg bits 15..12: the RTL's static input asic_type.
  [[nodiscard]] std::uint8_t asic_type() const {
    return variant ? static_cast<std::uint8_t>(*variant) : profile_desc(profile).release;
  }
};

std::unique_ptr<Dut> make_cpp_dut(const DutOptions& o);
// The Verilated model of rtl/dpc31_blocks.v for the profile, or one of its mutants (by macro
// name without the MUTANT_ prefix, "" = none). nullptr if that variant was not built. With
// o.rtl, that model, its mutant_sel input set from the mutant's name (or number).
std::unique_ptr<Dut> make_rtl_dut(const DutOptions& o, std::string_view mutant = "");
std::vector<std::string> rtl_mutants();
// The profile of the built-in model that carries the mutant (vpc3plus: the SAP-buffer header
// machine's, dpc31: the others); nullopt for no such mutant.
std::optional<Profile> rtl_mutant_profile(std::string_view mutant);

// Whether a read of this address is compared (registers and mirrored cells of the block).
bool compared_read(const ProfileDesc& p, std::uint16_t addr);

}  // namespace dpc31::cosim
