// The DPC31's request interface: the Instruction_Queue, the Indication_Queue and the
// DPS_User_Watchdog (DPC31 HW description p.22, §5.1.3, p.31; docs/dpc31.md). The queues are
// rings of 2-byte entries (code, parameter) in RAM; one entry always stays empty, so equal
// pointers mean an empty queue.
#include "requests.hpp"

namespace dpc31 {

namespace {

constexpr std::uint64_t kUserWdPeriodUs = 10'000;  // "decremented every 10 msec" (p.31)

struct Ring {
  std::uint32_t base;
  std::uint8_t len;
  std::uint8_t wr;
  std::uint8_t rd;
  [[nodiscard]] bool valid() const { return len != 0 && wr < len && rd < len; }
  [[nodiscard]] std::uint32_t entry(std::uint8_t i) const {
    return base + i * request::kEntryBytes;
  }
  [[nodiscard]] std::uint8_t next(std::uint8_t i) const {
    return static_cast<std::uint8_t>((i + 1u) % len);
  }
};

Ring ring(const RegisterFile& regs, RegId base, RegId len, RegId wr, RegId rd) {
  return {regs.buffer_addr(base), regs.cell(len), regs.cell(wr), regs.cell(rd)};
}

}  // namespace

void RequestInterface::install_hooks(HookTable& h) {
  bind_hooks(h, RegId::InstQ_Wr, *this).post_write = [](void* b, std::uint16_t, std::uint16_t,
                                                        std::uint16_t) {
    self<RequestInterface>(b).instq_written();
  };
}

void RequestInterface::instq_written() {
  Ring q = ring(regs_, RegId::InstQ_Base, RegId::InstQ_Len, RegId::InstQ_Wr, RegId::InstQ_Rd);
  if (!q.valid()) {
    sig_.log(LogLevel::warn,
             "InstQ_Wr {} written with InstQ_Rd {} and InstQ_Len {}: a pointer outside the "
             "queue, no request executed",
             q.wr, q.rd, q.len);
    return;
  }
  if (q.rd != q.wr) regs_.note_buffer(RegId::InstQ_Base, q.base, q.len * request::kEntryBytes);
  while (q.rd != q.wr) {
    const std::uint8_t code = regs_.ram_read(q.entry(q.rd));
    const std::uint8_t param = regs_.ram_read(q.entry(q.rd) + 1);
    q.rd = q.next(q.rd);
    regs_.set_cell(RegId::InstQ_Rd, q.rd);
    execute(code, param);
  }
}

void RequestInterface::execute(std::uint8_t code, std::uint8_t param) {
  switch (code) {
    case request::MAC_Start:  // "MAC enters Pas_Idle"; the SSA state machine starts over
      sig_.log(LogLevel::info, "request MAC_Start");
      sig_.emit(BlockEvent::Kind::mac_start);
      mode_.start();
      return;
    case request::MAC_Stop:  // "MAC enters Offline", confirmed in the Indication_Queue
      sig_.log(LogLevel::info, "request MAC_Stop");
      sig_.emit(BlockEvent::Kind::mac_stop);
      mode_.offline();  // at once: the DPC31 has no "after the current request" (decisions.md)
      indicate(request::MAC_Stop, request::Stop_Confirmed);
      return;
    case request::MAC_New_TRDY:  // "Transfer of TRDY": the parameter is the new MinTSDR
      sig_.log(LogLevel::info, "request MAC_New_TRDY: MinTSDR {} bit times", param);
      regs_.latch(RegId::MinTSDR_Val) = param;
      dp_.user_min_tsdr_set();
      return;
    case request::User_Leave_Master:
      sig_.log(LogLevel::info, "request User_Leave_Master");
      sig_.emit(BlockEvent::Kind::leave_master);
      dp_.leave_master();
      return;
    case request::DPS_User_Wd:
      user_wd(param);
      return;
    default:
      sig_.log(LogLevel::warn, "unknown request code {:02X}h (parameter {:02X}h): skipped", code,
               param);
  }
}

// "With 'DPS_USER WD, Enable' request, the DPS_User WD is automatically set to its initial value
// and started" (p.31). Reset reloads it and lifts the lock of an expiry; Disable stops it.
void RequestInterface::user_wd(std::uint8_t param) {
  const std::uint16_t value = regs_.cell16(*regs_.reg(RegId::R_User_WD_Value));
  switch (param) {
    case request::Wd_Reset:
      // A firmware retriggers it after every exchange: debug, not info.
      sig_.log(LogLevel::debug, "request DPS_User_Wd Reset: {}", value);
      s_.wd_left = value;
      s_.wd_locked = false;
      return;
    case request::Wd_Enable:
      if (s_.wd_locked) {
        sig_.log(LogLevel::warn, "request DPS_User_Wd Enable after an expiry: locked until Reset");
        return;
      }
      sig_.log(LogLevel::info, "request DPS_User_Wd Enable: {} x 10 ms", value);
      s_.wd_left = value;
      clock_.arm(s_.wd, clock_.cycles_for_us(kUserWdPeriodUs));
      return;
    case request::Wd_Disable:
      sig_.log(LogLevel::info, "request DPS_User_Wd Disable");
      clock_.arm(s_.wd, kNever);
      return;
    default:
      sig_.log(LogLevel::warn, "request DPS_User_Wd with unknown parameter {:02X}h: skipped",
               param);
  }
}

// "If the timer reaches the value '0000h', DPS ... executes 'Leave_Master', locks the DPS_User
// WD, and enters the event 'DPS_User_WD Expired' in the Indication_Queue" (p.31).
void RequestInterface::wd_tick() {
  if (s_.wd_left > 0) --s_.wd_left;
  if (s_.wd_left != 0) {
    clock_.arm(s_.wd, clock_.cycles_for_us(kUserWdPeriodUs));
    return;
  }
  clock_.arm(s_.wd, kNever);
  s_.wd_locked = true;
  sig_.log(LogLevel::info, "DPS_User_WD expired: Leave_Master");
  sig_.emit(BlockEvent::Kind::leave_master);
  dp_.leave_master();
  indicate(request::DPS_User_Wd, request::Wd_Expired);
}

// A full queue or one the user has not set up loses the indication (logged): the chip cannot
// wait for the user.
void RequestInterface::indicate(std::uint8_t code, std::uint8_t event) {
  Ring q = ring(regs_, RegId::IndQ_Base, RegId::IndQ_Len, RegId::IndQ_Wr, RegId::IndQ_Rd);
  if (!q.valid()) {
    sig_.log(LogLevel::warn,
             "indication {:02X}h/{:02X}h lost: IndQ_Wr {} / IndQ_Rd {} outside IndQ_Len {}", code,
             event, q.wr, q.rd, q.len);
    return;
  }
  if (q.next(q.wr) == q.rd) {
    sig_.log(LogLevel::warn, "indication {:02X}h/{:02X}h lost: the Indication_Queue is full", code,
             event);
    return;
  }
  regs_.note_buffer(RegId::IndQ_Base, q.base, q.len * request::kEntryBytes);
  regs_.ram_write(q.entry(q.wr), code);
  regs_.ram_write(q.entry(q.wr) + 1, event);
  regs_.set_cell(RegId::IndQ_Wr, q.next(q.wr));
  sig_.emit(BlockEvent::Kind::irq, irq::Indication);
  irq_.raise(irq::Indication);
}

}  // namespace dpc31
