// A minimal user side (the firmware's part) written against the register interface only, as a
// driver would be: the init sequence, and an ISR that accepts Prm, checks Cfg against Read_Cfg,
// fetches outputs on DX_Out, hands over new inputs, acknowledges and EOIs. Scenarios use it until
// real example firmware takes its place.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cpu.hpp"
#include "dp_master.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/reg_ids.hpp"
#include "responder_dpv1.hpp"

namespace dpc31 {

struct ResponderConfig {
  SlaveConfig slave;
  bool sync_supported = true;
  bool freeze_supported = true;
  bool spec_clear_mode = true;
  // The user watchdog, reset on every DX_Out: Res_User_WD on the SPC3 and VPC3+; on the DPC31 the
  // DPS_User_Watchdog through the Instruction_Queue (Enable at the start, Reset on every DX_Out).
  bool user_watchdog = false;
  std::uint16_t user_wd_value = 0x01FF;
  std::uint8_t wd_baud_control = 0x10;   // x 10 ms
  std::vector<std::uint8_t> substitute;  // dpc31 clear buffer C contents
  bool dx_out_port = false;              // dpc31 C31_Control.Enable_DX_Out_Port (PB3)
  Dpv1UserConfig dpv1;                   // vpc3plus: records to serve over DPV1 (none: off)
};

// Why an option of the built-in user side is refused, in the words of every door that takes one
// (the single chip's `user` step, a segment's `station`, Python's Segment.add_station, the
// bridge's --slave), `option` spelled as that door spells it (docs/decisions.md, "No silent
// options"). Beside a firmware, which sets up its own user side:
[[nodiscard]] std::string refused_beside_firmware(std::string_view option);
// `user_wd_value` on the dpc31 without `user_wd`: acts on nothing there.
[[nodiscard]] std::string user_wd_value_needs_user_wd(std::string_view option);
// Inputs of `given` bytes for a slave of `in_len` input bytes: "" when they fit (none, or exactly
// in_len), else why not, in the words of every door that sets them (the single chip's `user
// inputs=` and `inputs`, Responder::set_inputs, Python's Responder.inputs).
[[nodiscard]] std::string inputs_length_problem(std::size_t given, std::size_t in_len);
// The same for the dpc31 clear buffer C's substitute values and the slave's out_len (the single
// chip's `user substitute=`, the Responder's constructor, Python's run_responder(substitute=)).
[[nodiscard]] std::string substitute_length_problem(std::size_t given, std::size_t out_len);

// Where the built-in user side puts its buffers (Responder::init): segment after segment from
// the start of the user area, in the order init() writes the pointer cells.
struct ResponderLayout {
  bool large = false;  // VPC3+ 4kB_Mode: its 16-byte segments and 4 KB of RAM
  std::uint32_t seg_shift = 3;
  std::array<std::uint32_t, kRegIdCount> segment{};  // by pointer cell (R_*_Buf_Ptr*, queues)
  std::uint32_t dpv1 = 0;                            // the DPV1 part's first segment
  std::uint32_t end = 0;                             // one past the last byte of the last buffer
  std::uint32_t ram_end = 0;  // one past the last byte of the RAM (in that mode)
};
[[nodiscard]] ResponderLayout responder_layout(const ProfileDesc& p, const ResponderConfig& cfg);
// "" when the layout fits the profile's RAM, else why not, in the words of every door that sets
// the slave's lengths (a scenario's `slave`, Python's run_responder and Segment.add_station,
// Responder::init itself): a buffer past the RAM is a RAM access violation on every access.
[[nodiscard]] std::string responder_layout_problem(const ProfileDesc& p,
                                                   const ResponderConfig& cfg);

class Responder {
 public:
  // dpv1_ is built in the initialiser list: an emplace() in the body makes GCC 12's
  // -Wmaybe-uninitialized fire (falsely) in the ASan build. Substitute values of another length
  // than the slave's out_len are std::invalid_argument (substitute_length_problem): the user would
  // get them padded with the C buffer's stale bytes, or cut.
  explicit Responder(ResponderConfig cfg)
      : cfg_(checked(std::move(cfg))),
        dpv1_(cfg_.dpv1.records.empty() ? std::nullopt
                                        : std::optional<Dpv1User>(std::in_place, cfg_.dpv1)) {}

  // Registers, buffers, Start_SPC3 (dpc31: the queues, MAC_Start). Buffers that would not fit
  // the RAM (responder_layout_problem) are std::invalid_argument, before any write.
  void init(BusPort& bus);
  void isr(BusPort& bus);

  struct Output {
    std::uint64_t cycle;
    std::vector<std::uint8_t> data;
    bool cleared;
  };
  // The inputs handed to the chip on every DX_Out: none (empty, the chip keeps what it has) or
  // exactly the slave's in_len bytes. Another length is std::invalid_argument
  // (inputs_length_problem), the inputs as they were: the chip would get them cut or padded
  // with the buffer's stale bytes.
  void set_inputs(std::vector<std::uint8_t> in);
  [[nodiscard]] const std::vector<std::uint8_t>& inputs() const { return inputs_; }
  // Every fetch of new outputs since the owner last called keep_last_output().
  std::vector<Output> outputs;
  std::vector<std::pair<std::uint64_t, std::uint16_t>> interrupts;  // cycle, IR at ISR entry
  std::uint32_t prm_accepted = 0;
  std::uint32_t cfg_accepted = 0;
  std::uint32_t cfg_rejected = 0;
  // Forgets every fetch but the last (`expect outputs` and `cleared` read it): a driver that runs
  // long calls it once it has read `outputs`, so memory stays flat. The forgotten fetch's buffer
  // takes the next one: trimmed after every ISR, a fetch allocates nothing.
  void keep_last_output();
  // The DPV1 part (records, Alarm_Acks taken), when the configuration has records.
  [[nodiscard]] const std::optional<Dpv1User>& dpv1() const { return dpv1_; }

 private:
  // The register's description, looked up once per id: the ISR reads the same few registers on
  // every interrupt (a segment's slaves hundreds of times per DP cycle).
  const RegDesc& reg(const Chip& c, RegId id) const;
  std::uint32_t waddr(const Chip& c, RegId id) const;
  std::uint32_t raddr(const Chip& c, RegId id) const;
  std::uint32_t cell_addr(const Chip& c, RegId id) const { return raddr(c, id); }
  void write16(BusPort& c, RegId id, std::uint16_t v) const;
  std::uint16_t read16(BusPort& c, RegId id) const;
  std::uint32_t buffer(BusPort& c, RegId ptr_cell) const;
  // Hands U over (New_Din_Buffer_Cmd) with `inputs`; without inputs only if `always`.
  void give_inputs(BusPort& c, bool always = false);
  void refill_substitute(BusPort& c, bool c_fetched);
  static ResponderConfig checked(ResponderConfig cfg);
  // dpc31: puts requests (code, parameter) into the Instruction_Queue and moves InstQ_Wr past
  // them with one write: the MAC executes them in that write's completion cycle.
  void request(BusPort& c, std::initializer_list<std::pair<std::uint8_t, std::uint8_t>> entries);

  ResponderConfig cfg_;
  std::vector<std::uint8_t> inputs_;
  std::optional<Dpv1User> dpv1_;
  std::uint16_t mask_ = 0xFFFF;  // Int_Mask_Reg as written
  std::uint32_t seg_shift_ = 3;
  std::vector<std::uint8_t> spare_;  // a forgotten fetch's data buffer, for the next fetch
  std::uint8_t instq_wr_ = 0;        // dpc31: the next free Instruction_Queue entry
  std::uint8_t last_u_ = 0;          // the U buffer of the last fetch (0: none yet)
  mutable const ProfileDesc* regs_of_ = nullptr;  // the profile regs_ was filled from
  mutable std::array<const RegDesc*, kRegIdCount> regs_{};
};

}  // namespace dpc31
