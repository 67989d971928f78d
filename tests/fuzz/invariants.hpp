// Invariants of the chip model, checked from outside after every event and every bus access
// (Chip::on_state_change) while a fuzz target or a test drives the chip (docs/robustness.md):
//
//   xint     the interrupt activity, the X/INT pin and the last on_irq_change report equal the
//            documented function of IR = Int_Req_Reg & ~Int_Mask_Reg and the EOI inactive time,
//            which the checker times itself from the EOI writes it sees (docs/timing.md)
//   buffers  Dout_Buffer_SM and Din_Buffer_SM name each buffer at most once, D and U always one;
//            the two diag buffers are never both the user's nor both being sent; the ASIC only
//            swaps the pointer cells of the Dout (with C), Din, Diag and Aux/Prm/Cfg/Read_Cfg/SSA
//            groups: their values stay the same multiset until the user writes one of them
//   answer   every telegram the chip sends answers a frame the checker decoded itself on RxD
//            (its own receiver, its own FCS check): no answer to a frame with a parity error,
//            a bad FCS or a bad end delimiter, nor without any request
//   dp       the DP state moves only along documented transitions: Wait_Prm -> Wait_Cfg at a
//            User_Prm_Data_Okay read, Wait_Cfg -> Data_Exchange at a User_Cfg_Data_Okay read,
//            Data_Exchange -> Wait_Cfg at an accepted Chk_Cfg, anything -> Wait_Prm; entering
//            or leaving Data_Exchange latches Go_Leave_Data_Exchange (except when going Offline)
//
// The checker only reads the chip through its public interface (peek, peek_reg, pins, observers),
// so a fault inside the model shows up as a difference.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include "block_event.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/uart.hpp"

namespace dpc31::fuzz {

class InvariantChecker {
 public:
  // On a violation: called with a readable message. The default prints it and aborts (so
  // libFuzzer records the input); tests collect the messages instead.
  using Report = std::function<void(const std::string&)>;

  explicit InvariantChecker(Report report = {});
  InvariantChecker(const InvariantChecker&) = delete;
  InvariantChecker& operator=(const InvariantChecker&) = delete;

  // Starts watching `chip` (adds observers; the chip must outlive the checker's use). The EOI
  // inactive time in force at attach (a snapshot may be inside one) is taken from the chip once.
  // `line_idle`: RxD is known to have been idle for at least TSYN before now (a fresh chip, a
  // master that waited), so a telegram that starts right away is judged; otherwise answers to a
  // request that may have begun before attach are not.
  void attach(Chip& chip, bool line_idle = false);
  // All checks at the chip's current cycle (the state observer calls it after every event).
  void check();

  // The observers' entry points, public so tests can feed the checker a mutated history.
  void on_rxd(std::uint64_t cycle, bool level);
  void on_answer(const Telegram& t);
  void on_block(const BlockEvent& e);

  [[nodiscard]] std::uint64_t checks() const { return checks_; }
  [[nodiscard]] std::uint64_t answers_checked() const { return answers_; }
  // Answers whose request may have begun before attach (the checker saw only part of it).
  [[nodiscard]] std::uint64_t answers_unjudged() const { return unjudged_; }
  [[nodiscard]] std::uint64_t violations() const { return violations_; }

 private:
  void fail(const std::string& what);
  void check_xint();
  void check_buffers();
  void check_dp();
  void sync_rx();  // the checker's receiver up to the chip's current cycle
  [[nodiscard]] std::vector<std::uint8_t> group_values(int g) const;

  Report report_;
  Chip* chip_ = nullptr;
  std::uint64_t checks_ = 0;
  std::uint64_t answers_ = 0;
  std::uint64_t unjudged_ = 0;
  std::uint64_t violations_ = 0;

  // xint
  std::uint64_t eoi_until_ = 0;  // no activity before this cycle
  bool reported_ = false;        // last on_irq_change level
  std::uint32_t mode1_s_ = 0;    // Mode_Reg1_S: EOI writes

  // buffers: pointer-cell groups, their last multiset, and whether the user wrote one
  std::vector<std::vector<std::uint32_t>> groups_;
  std::vector<std::vector<std::uint8_t>> group_base_;
  std::vector<bool> group_written_;

  // dp
  DpState dp_ = DpState::Wait_Prm;
  bool started_ = false;
  bool prm_ok_read_ = false, cfg_ok_read_ = false, cfg_accepted_ = false;
  bool new_din_read_ = false;
  bool cfg_ok_given_ = false;  // a Cfg OK since the last Set_Prm / Chk_Cfg / Wait_Prm
  std::int32_t prm_ok_addr_ = -1, cfg_ok_addr_ = -1, new_din_addr_ = -1;

  // answer: the checker's own receiver at the chip's bit rate
  struct RxChar {
    std::uint8_t data;
    bool parity_ok;
    std::uint64_t end;
    std::uint64_t idle_bits;
    std::uint64_t seq;    // characters decoded since attach, 0 = the first
    std::uint32_t epoch;  // receiver (re)configurations: a telegram never spans two
  };
  UartRx rx_;
  std::uint32_t rx_t_ = 0;
  std::uint32_t epoch_ = 0;
  std::uint64_t seq_ = 0;
  std::uint64_t attached_at_ = 0;
  bool line_idle_ = false;
  std::deque<std::pair<std::uint64_t, bool>> edges_;  // driven, not yet fed
  std::deque<RxChar> chars_;                          // the latest ones (a frame's worth)
  std::vector<UartChar> scratch_;
};

// A valid FDL request frame as a slave may answer it (SD1, SD2, SD3 with FCS and ED), checked
// here independently of emu/fdl.cpp.
bool valid_request_frame(const std::uint8_t* b, std::size_t n);

}  // namespace dpc31::fuzz
