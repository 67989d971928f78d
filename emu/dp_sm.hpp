// DP slave state machine (chip-facts §5.4, §6): Wait_Prm -> Wait_Cfg -> Data_Exchange, the
// services the ASIC answers by itself (Set_Prm, Chk_Cfg, Slave_Diag, Get_Cfg, Rd_Inp, Rd_Outp,
// Set_Slave_Add, Data_Exchange, FDL_Status) and the user's Prm / Cfg / SSA handshakes, whose
// OK / Not_OK reads answer 00 finished, 01 conflict, 11 not allowed.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "buffers.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/pdu.hpp"
#include "irq.hpp"
#include "reg_hooks.hpp"
#include "regfile.hpp"
#include "sap_list.hpp"
#include "signals.hpp"
#include "watchdog.hpp"

namespace dpc31 {

inline constexpr std::uint8_t kHandshakeFinished = 0x00;
inline constexpr std::uint8_t kHandshakeConflict = 0x01;
inline constexpr std::uint8_t kHandshakeNotAllowed = 0x03;

// One pending telegram awaiting the user's verdict (Set_Prm or Chk_Cfg).
struct Handshake {
  bool pending = false;        // a telegram is waiting for OK / Not_OK
  bool newer_arrived = false;  // another one came while the user was checking

  void arrived() {
    if (pending) newer_arrived = true;
    pending = true;
  }
  // The result of an OK / Not_OK read; `done` tells whether the handshake completed.
  std::uint8_t answer(bool& done) {
    done = false;
    if (!pending) return kHandshakeNotAllowed;
    if (newer_arrived) {
      newer_arrived = false;  // the user re-validates the newer buffer
      return kHandshakeConflict;
    }
    pending = false;
    done = true;
    return kHandshakeFinished;
  }
  [[nodiscard]] std::uint8_t preview() const {
    if (!pending) return kHandshakeNotAllowed;
    return newer_arrived ? kHandshakeConflict : kHandshakeFinished;
  }
};

class DpStateMachine {
 public:
  struct State {
    bool started = false;  // Start_SPC3: Offline -> Passive_Idle (Status_Reg.Offline_Passive_Idle)
    DpState state = DpState::Wait_Prm;
    Handshake prm;
    Handshake cfg;
    bool ssa_free = true;        // SAP55 enabled (SSA buffer free)
    bool prm_fault = false;      // diag St1 Prm_Fault
    bool cfg_fault = false;      // diag St1 Cfg_Fault
    bool not_supported = false;  // diag St1 Not_Supported (reserved Global_Control bits, ...)
    std::uint8_t station = 0;    // own address: R_TS_Adr at Start, changed by Set_Slave_Add
    bool no_add_change = false;  // Real_No_Add_Change adopted from Set_Slave_Add
    std::uint8_t master_add = pdu::SlaveDiag::kNoMaster;  // the master that locked us
    std::uint8_t group_ident = 0;
    // The last Set_Prm's byte 3 when it is newer than the user's MinTSDR_Val; 0 = MinTSDR_Val.
    std::uint8_t min_tsdr = 0;
    // The watchdog parameters of the Set_Prm the user is checking: DP_Control starts with them at
    // User_Prm_Data_Okay, not when the telegram arrives.
    bool prm_wd_on = false;
    std::uint8_t prm_wd_fact1 = 0;
    std::uint8_t prm_wd_fact2 = 0;
    bool prm_wd_1ms = false;
    bool failsafe = false;  // dpc31: Set_Prm byte 13 Failsafe (fail-safe Data_Exchange accepted)
    // Cfg OK given, Data_Exchange waits: on an SPC3 with a Din buffer for the user's next
    // New_Din_Buffer_Cmd, on a VPC3+ for the pending Set_Ext_Prm's verdict.
    bool dx_deferred = false;
    std::uint8_t diag_requester = 0xFF;  // the master whose Slave_Diag answer is being sent
    bool sync_mode = false;
    bool freeze_mode = false;
    // User watchdog: armed by Res_User_WD, counts Data_Exchange telegrams down.
    bool user_wd_armed = false;
    std::uint16_t user_wd = 0;
    // FCB/FCV: a repeated request (same master, FCV = 1, same FCB) gets the previous answer again.
    bool fcb_valid = false;
    bool last_fcb = false;
    std::uint8_t last_master = 0xFF;
    std::vector<std::uint8_t> last_response;
    bool diag_in_flight = false;  // a Slave_Diag answer is being sent
    bool ext_prm = false;         // VPC3+: the Prm verdict pending is a Set_Ext_Prm's
  };
  enum class Verdict : std::uint8_t { ok, not_ok };

  DpStateMachine(RegisterFile& regs, InterruptController& irq, BufferUnit& buffers,
                 Watchdog& watchdog, SapList& sap_list, FdlCounters& counters, const Signals& sig)
      : regs_(regs),
        irq_(irq),
        buffers_(buffers),
        watchdog_(watchdog),
        sap_list_(sap_list),
        counters_(counters),
        sig_(sig) {}
  // Binds the hooks of the registers this block owns (reg_hooks.hpp); New_Din_Buffer_Cmd is
  // among them: the handover of the inputs is the state machine's step, through its buffers.
  void install_hooks(HookTable& h);
  // Also the MAC reset (Go_Offline): Offline, as after reset.
  void reset() {
    s_ = State{};
    sap_list_.reset();
  }
  // Start_SPC3: the state machine from the top, at the station address of R_TS_Adr.
  void start();
  [[nodiscard]] bool started() const { return s_.started; }

  // An error-free request for us (or broadcast) arrived now: act; true: send answer().
  bool service(const fdl::Frame& req);
  // The encoded answer of the last request service() answered (the FCB repetition's too).
  [[nodiscard]] const std::vector<std::uint8_t>& answer() const { return s_.last_response; }
  void response_sent();  // our answer's last stop bit is out
  // Leave_Master: back to Wait_Prm, unlocked (User_Leave_Master, a fault, a watchdog expiry).
  void leave_master();
  // The DP watchdog expired in DP_Control: Leave_Master; the DPC31 also resets its SSA state
  // machine (DPC31 p.26).
  void dp_control_expired();
  // The block-level actions of the services (docs/golden-model.md), also for the harness.
  void prm_accepted();      // New_Prm_Data
  void ext_prm_accepted();  // vpc3plus: New_Ext_Prm_Data (Set_Ext_Prm, emu/dpv1.cpp)
  void prm_fault();         // a Set_Prm that failed the ASIC's checks
  void cfg_accepted();      // New_Cfg_Data
  void ssa_accepted();      // New_SSA_Data
  void apply_global_control(std::uint8_t command);

  // The user's side (the command reads of User_Prm/Cfg_Data_(Not_)Okay, SSA_Buffer_Free_Cmd,
  // New_Din_Buffer_Cmd).
  std::uint16_t prm_verdict(Verdict v);
  std::uint16_t cfg_verdict(Verdict v);
  [[nodiscard]] std::uint16_t prm_preview() const { return s_.prm.preview(); }
  [[nodiscard]] std::uint16_t cfg_preview() const { return s_.cfg.preview(); }
  void ssa_buffer_free() { s_.ssa_free = true; }  // SAP55 accepts Set_Slave_Add again
  void din_handed_over();
  // The wait for New_Din_Buffer_Cmd the log warns of, and the time it allows the firmware.
  [[nodiscard]] bool waits_for_din() const {
    return s_.dx_deferred && !s_.prm.pending && s_.state == DpState::Wait_Cfg;
  }
  static constexpr std::uint64_t kDinWaitMs = 10;

  [[nodiscard]] DpState state() const { return s_.state; }
  [[nodiscard]] std::uint8_t station() const { return s_.station; }
  [[nodiscard]] std::uint8_t master_add() const { return s_.master_add; }
  [[nodiscard]] std::uint8_t min_tsdr() const { return s_.min_tsdr; }
  // The user set MinTSDR_Val (a write, MAC_New_TRDY): the newest value, it wins over the last
  // Set_Prm's until the next Set_Prm with byte 3 not 0 (docs/timing.md).
  void user_min_tsdr_set() { s_.min_tsdr = 0; }
  [[nodiscard]] bool ssa_free() const { return s_.ssa_free; }

 private:
  friend struct BlockAccess;
  std::optional<fdl::Frame> set_prm(const fdl::Frame& req);
  std::optional<fdl::Frame> chk_cfg(const fdl::Frame& req);
  std::optional<fdl::Frame> slave_diag(const fdl::Frame& req);
  std::optional<fdl::Frame> read_io(const fdl::Frame& req);
  std::optional<fdl::Frame> set_slave_add(const fdl::Frame& req);
  std::optional<fdl::Frame> set_ext_prm(const fdl::Frame& req);
  [[nodiscard]] const char* dpv1_prm_fault(const pdu::SetPrm& prm) const;
  // Locked by a master other than `sa` (the Master_Add its diag shows), which every service of
  // the parameterisation from `sa` leaves alone (DPC31 p.28).
  [[nodiscard]] bool locked_by_another(std::uint8_t sa) const {
    return s_.master_add != pdu::SlaveDiag::kNoMaster && s_.master_add != sa;
  }
  fdl::Frame sap_list_answer(const fdl::Frame& req, const SapListAnswer& a);
  std::optional<fdl::Frame> data_exchange(const fdl::Frame& req);
  void note_din_wait(const fdl::Frame& req, const char* answered);
  void global_control(const fdl::Frame& req);
  template <typename Accepted>
  std::uint16_t verdict(Handshake& h, std::uint16_t event, bool& fault, Verdict v,
                        Accepted accepted);
  void enter_data_exchange();
  bool dx_out_wanted(std::span<const std::uint8_t> outputs);
  bool user_watchdog_tick();
  bool receive_via_aux(std::uint16_t sel, RegId target_ptr, RegId len_cell,
                       std::span<const std::uint8_t> du);
  [[nodiscard]] fdl::Frame sap_answer(const fdl::Frame& req, fdl::Response code,
                                      std::vector<std::uint8_t> du) const;
  [[nodiscard]] fdl::Frame short_answer(const fdl::Frame& req, fdl::Response code) const;
  // The bytes an answer takes from a buffer whose length cell is `len_cell`: the cell's value, at
  // most the 244 of a DP data unit (docs/timing.md, "Length cells").
  std::size_t answer_length(RegId len_cell);

  RegisterFile& regs_;
  InterruptController& irq_;
  BufferUnit& buffers_;
  Watchdog& watchdog_;
  SapList& sap_list_;
  FdlCounters& counters_;
  const Signals& sig_;
  State s_;
  // The RAM's bytes for an answer's data unit (read_buffer): their memory goes out with the
  // answer and comes back once it is encoded (service).
  std::vector<std::uint8_t> du_;
  // The over-long value each answering length cell was last logged with (0: none): one line per
  // cell and value. The log's memory, not the chip's state (a snapshot carries it: LOGS).
  std::array<std::pair<RegId, std::uint8_t>, 5> over_long_ = {{{RegId::R_Len_Din_Buf, 0},
                                                               {RegId::R_Len_Dout_Buf, 0},
                                                               {RegId::R_Len_Read_Cfg_Data, 0},
                                                               {RegId::R_Len_Diag_Buf1, 0},
                                                               {RegId::R_Len_Diag_Buf2, 0}}};
  // An SPC3 waiting for the user's New_Din_Buffer_Cmd after its Cfg OK: when the wait began (the
  // OK read) and whether the log has said that the firmware never made the read; said once per
  // chip. The log's memory, not the chip's state (a snapshot carries it: LOGS).
  struct DinWaitLog {
    std::uint64_t since = 0;
    bool said = false;
  };
  DinWaitLog din_wait_;
};

}  // namespace dpc31
