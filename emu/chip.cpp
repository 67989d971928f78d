// The public Chip: a thin wrapper over ChipCore. How time advances is in engine.cpp.
#include "dpc31/chip.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <iterator>
#include <stdexcept>
#include <type_traits>

#include "core.hpp"

namespace dpc31 {

Chip::Chip(ChipOptions opt) : core_(std::make_unique<ChipCore>(opt)), now_(&core_->clock.now) {}
Chip::~Chip() = default;
Chip::Chip(Chip&&) noexcept = default;
Chip& Chip::operator=(Chip&&) noexcept = default;

// Under a CPU board the reset is an event at the board's instant, as a load there takes only it.
void Chip::reset() { reset(board_instant_ != nullptr ? *board_instant_ : 0); }
void Chip::reset(std::uint64_t cycle) {
  if (cycle > kLastCycle) {
    throw std::invalid_argument(
        fmt::format("Chip::reset: cycle {} is past the chip's last cycle {}", cycle, kLastCycle));
  }
  if (board_instant_ != nullptr && cycle != *board_instant_) {
    throw std::invalid_argument(fmt::format(
        "Chip::reset: cycle {} under a CPU board at cycle {}: a reset there is at the board's "
        "instant (the CPU's clock counts on)",
        cycle, *board_instant_));
  }
  core_->reset(cycle);
  moved();
}
std::uint8_t Chip::read(std::uint32_t addr) {
  const std::uint8_t v = core_->bus_read(addr);
  moved();
  return v;
}
void Chip::write(std::uint32_t addr, std::uint8_t value) {
  core_->bus_write(addr, value);
  moved();
}
void Chip::write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes) {
  core_->bus_write_block(addr, bytes);
  moved();
}
void Chip::read_block(std::uint32_t addr, std::span<std::uint8_t> out) {
  core_->bus_read_block(addr, out);
  moved();
}
void Chip::fill(std::uint32_t addr, std::uint8_t value, std::size_t len) {
  core_->bus_fill(addr, value, len);
  moved();
}
bool Chip::equal(std::uint32_t a, std::uint32_t b, std::size_t len) {
  const bool same = core_->bus_equal(a, b, len);
  moved();
  return same;
}
std::size_t Chip::quiet_ram_run(std::uint32_t addr, std::size_t len, bool write) const {
  return core_->quiet_ram_run(addr, len, write);
}
std::uint8_t Chip::peek(std::uint32_t addr) const { return core_->peek(addr); }
namespace {

// Why Mode_Reg1 may not take `value` ("" when it may): Start_SPC3 and Go_Offline are the chip's
// run state, EOI and User_Leave_Master pulses. The comparison is with what the chip has (the DP
// part's started state, the last Go_Offline command, pulses 0, reserved bits as the read side
// shows them), not with the latch, so that a latch put wrong can always be put right.
std::string run_state_problem(const ChipCore& c, RegId id, std::uint16_t value) {
  if (id != RegId::Mode_Reg1) return {};
  namespace m1 = fields::Mode_Reg1;
  const auto run_state =
      static_cast<std::uint16_t>(m1::Start_SPC3 | m1::Go_Offline | m1::EOI | m1::User_Leave_Master);
  const auto has = static_cast<std::uint16_t>(
      ((c.dp.started() ? m1::Start_SPC3 : 0u) | (c.regs.latch(id) & m1::Go_Offline)) &
      ~c.regs.reg(id)->rsvd);
  const auto changed = static_cast<std::uint16_t>((has ^ value) & run_state);
  if (changed == 0) return {};
  return fmt::format(
      "bits {:#04x} would change; Start_SPC3 and Go_Offline are the chip's run state ({}), EOI "
      "and User_Leave_Master pulses that never stay set: only a command changes them "
      "(Mode_Reg1_S / Mode_Reg1_R over the bus)",
      changed, c.dp.started() ? "Passive_Idle" : "Offline");
}

}  // namespace

std::string Chip::poke_problem(std::uint32_t addr, std::uint8_t value) const {
  const auto l = core_->poked_latch(addr, value);
  if (!l) return {};
  const std::string why = run_state_problem(*core_, l->id, l->value);
  return why.empty() ? why
                     : fmt::format("poke {:#06x} {:#04x}: {} {:#04x}: {}", addr, value,
                                   core_->regs.reg(l->id)->name, l->value, why);
}

bool Chip::poke(std::uint32_t addr, std::uint8_t value) {
  if (std::string why = poke_problem(addr, value); !why.empty())
    throw std::invalid_argument(std::move(why));
  return core_->poke(addr, value);
}

std::uint16_t Chip::peek_reg(RegId id) const { return core_->reg_value(id); }

std::string Chip::poke_reg_problem(RegId id, std::uint16_t value) const {
  const std::string why = run_state_problem(*core_, id, value);
  return why.empty()
             ? why
             : fmt::format("poke_reg {} {:#04x}: {}", core_->regs.reg(id)->name, value, why);
}

bool Chip::poke_reg(RegId id, std::uint16_t value) {
  ChipCore& c = *core_;
  const RegDesc* r = c.regs.reg(id);
  if (r == nullptr) return false;
  if (r->kind == Kind::cell) {
    c.regs.set_cell16(*r, value);
    return true;
  }
  if (r->kind != Kind::latch) return false;
  if (std::string why = poke_reg_problem(id, value); !why.empty())
    throw std::invalid_argument(std::move(why));
  c.poke_latch(id, value);
  return true;
}

void Chip::step(std::uint64_t cycles) {
  core_->advance(cycles);
  moved();
}
bool Chip::step_until_irq(std::uint64_t cycles) {
  if (core_->stop) return false;
  const bool irq = core_->advance(cycles, ChipCore::Stop::on_irq_or_request);
  moved();
  return irq;
}
void Chip::request_stop() { core_->stop = true; }
bool Chip::stop_requested() const { return core_->stop; }
void Chip::clear_stop() { core_->stop = false; }

namespace {

// The public serial calls' refusals (chip.hpp): a time in the chip's past, a bit of no time.
void check_line(const char* call, const char* what, std::uint64_t at, std::uint64_t now) {
  if (at < now) {
    throw std::invalid_argument(
        fmt::format("{}: {} {} is before the chip's cycle {}", call, what, at, now));
  }
}
void check_chars(const char* call, std::uint64_t start, std::uint32_t bit_cycles,
                 std::uint64_t now) {
  check_line(call, "start", start, now);
  if (bit_cycles == 0) {
    throw std::invalid_argument(fmt::format("{}: bit_cycles 0: a bit lasts 1 clock or more", call));
  }
}

}  // namespace

void Chip::drive_rxd(std::uint64_t cycle, bool level) {
  check_line("drive_rxd", "cycle", cycle, this->cycle());
  LineAccess::drive_rxd(*this, cycle, level);
}
std::uint64_t Chip::drive_rxd_chars(std::span<const std::uint8_t> bytes, std::uint64_t start,
                                    std::uint32_t bit_cycles, UartFault fault) {
  check_chars("drive_rxd_chars", start, bit_cycles, cycle());
  return LineAccess::drive_rxd_chars(*this, bytes, start, bit_cycles, fault);
}
std::uint64_t Chip::hear_telegram(std::span<const std::uint8_t> bytes, std::uint64_t start,
                                  std::uint32_t bit_cycles) {
  check_chars("hear_telegram", start, bit_cycles, cycle());
  // Asked before the frame is made (an allocation and a decode) that the MAC then asks again.
  if (!core_->mac.can_hear(bytes.size(), start, bit_cycles)) {
    return LineAccess::drive_rxd_chars(*this, bytes, start, bit_cycles, {});
  }
  return LineAccess::hear_telegram(*this, HeardFrame::make(bytes), start, bit_cycles);
}
std::uint64_t Chip::hear_telegram(const std::shared_ptr<const HeardFrame>& frame,
                                  std::uint64_t start, std::uint32_t bit_cycles) {
  check_chars("hear_telegram", start, bit_cycles, cycle());
  return LineAccess::hear_telegram(*this, frame, start, bit_cycles);
}
void LineAccess::drive_rxd(Chip& c, std::uint64_t cycle, bool level) {
  c.core_->mac.drive_rxd(cycle, level);
}
std::uint64_t LineAccess::drive_rxd_chars(Chip& c, std::span<const std::uint8_t> bytes,
                                          std::uint64_t start, std::uint32_t bit_cycles,
                                          UartFault fault) {
  const std::uint64_t frame = std::uint64_t{kUartCharBits} * bit_cycles;
  Mac& mac = c.core_->mac;
  if (fault.kind != UartFault::Kind::none) {
    // A damaged character changes the framing of the ones after it: edges for all of them.
    std::vector<std::pair<std::uint64_t, bool>> edges;
    uart_encode(bytes, start, bit_cycles, edges, fault);
    for (const auto& [cycle, level] : edges) mac.drive_rxd(cycle, level);
  } else {
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      mac.drive_rxd_char(start + i * frame, bytes[i], bit_cycles);
    }
  }
  return start + bytes.size() * frame;
}
std::uint64_t LineAccess::hear_telegram(Chip& c, const std::shared_ptr<const HeardFrame>& frame,
                                        std::uint64_t start, std::uint32_t bit_cycles) {
  if (!c.core_->mac.hear_telegram(frame, start, bit_cycles)) {
    return drive_rxd_chars(c, frame->bytes, start, bit_cycles, {});
  }
  return start + frame->bytes.size() * std::uint64_t{kUartCharBits} * bit_cycles;
}
bool Chip::hear_run(const HeardRun& run) {
  // No event of the chip's own inside the run that shows something (it would come between two of
  // its verdicts; a quiet one changes nothing they count).
  const std::uint64_t end = run.last_start + std::uint64_t{kUartCharBits} * run.bit_cycles;
  return core_->line_event() > end && core_->mac.hear_run(run);
}
std::shared_ptr<const HeardFrame> HeardFrame::make(std::span<const std::uint8_t> bytes) {
  auto h = std::make_shared<HeardFrame>();
  h->fill(bytes);
  return h;
}
void HeardFrame::fill(std::span<const std::uint8_t> chars) {
  bytes.assign(chars.begin(), chars.end());
  verdict = 0;
  frame.reset();
  decoded.clear();            // as a new frame's until decoded
  if (chars.empty()) return;  // nobody hears it whole (Mac::can_hear)
  // The byte of the assembler's verdict, or the last one.
  verdict = frame.push_block(chars) - 1;
  if (frame.status() == fdl::Assembler::Status::complete) fdl::decode(frame.bytes(), decoded);
}
std::shared_ptr<const HeardFrame> HeardFramePool::make(std::span<const std::uint8_t> bytes) {
  for (std::size_t k = 0; k < frames_.size(); ++k) {
    const std::size_t i = (next_ + k) % frames_.size();
    if (frames_[i].use_count() == 1) {
      frames_[i]->fill(bytes);
      next_ = (i + 1) % frames_.size();
      return frames_[i];
    }
  }
  // All held: a new one, the youngest, just before the oldest.
  const auto at = frames_.insert(frames_.begin() + static_cast<std::ptrdiff_t>(next_),
                                 std::make_shared<HeardFrame>());
  (*at)->fill(bytes);
  next_ = (next_ + 1) % frames_.size();
  return *at;
}
void Chip::on_rxd(std::function<void(std::uint64_t, bool)> cb) {
  core_->signals.rxd.add(std::move(cb));
}
void Chip::on_state_change(std::function<void(std::uint64_t)> cb) {
  core_->signals.state.add(std::move(cb));
}
void Chip::on_txd(std::function<void(std::uint64_t, bool)> cb) {
  core_->mac.watch_txd(std::move(cb));
}
void Chip::on_txd_edges(std::function<void(std::span<const std::pair<std::uint64_t, bool>>)> cb) {
  core_->mac.watch_txd_edges(std::move(cb));
}
ObserverId Chip::on_txd_chars(std::function<void(const TxdRun&)> cb) {
  return core_->signals.txd_chars.add(std::move(cb));
}
void Chip::remove_txd_chars(ObserverId id) { core_->signals.txd_chars.remove(id); }
void Chip::take_txd() { core_->mac.tx_catch_up(); }
void Chip::wake_on_txd(bool on) { core_->mac.wake_on_txd(on); }
void Chip::on_bus_access(std::function<void(std::uint64_t, const BusAccess&)> cb) {
  core_->signals.bus.add(std::move(cb));
}
void Chip::on_telegram(std::function<void(const Telegram&)> cb) {
  core_->signals.telegram.add(std::move(cb));
}
void Chip::on_answer(std::function<void(const Telegram&)> cb) {
  core_->signals.answer.add(std::move(cb));
}
void Chip::on_cycle(std::function<void(std::uint64_t)> cb) { on_cycle_ = std::move(cb); }
ChipProbe Chip::probe() const {
  const ChipCore& c = *core_;
  return {c.dp.state(),
          c.watchdog.state(),
          c.watchdog.baud_code(),
          c.regs.latch(RegId::Int_Req_Reg),
          c.buffers.dout_ring_sm(),
          c.buffers.din_sm(),
          c.buffers.diag_sm()};
}
std::uint64_t Chip::next_deadline() const { return core_->next_event(); }
std::uint64_t Chip::line_deadline() const { return core_->line_event(); }
bool Chip::may_hear_later(std::uint32_t bit_cycles) const {
  return core_->mac.hears_later(bit_cycles);
}
std::uint64_t Chip::watchdog_due() const { return core_->watchdog.due(); }
std::uint64_t Chip::eoi_inactive_until() const { return core_->irq.inactive_until(); }

bool Chip::txd_pin() const { return core_->mac.txd_level(); }
const FdlCounters& Chip::fdl_counters() const { return core_->counters; }
std::uint8_t Chip::station_address() const { return core_->dp.station(); }
std::uint32_t Chip::bit_cycles() const { return core_->mac.bit_time(); }
std::uint32_t Chip::clock_hz() const { return core_->clock.hz; }
std::uint32_t Chip::bus_access_cycles() const { return core_->prof().bus_access_cycles; }

bool Chip::x_int_pin() const {
  // INT_Pol = 0: low-active (the default), 1: high-active.
  const bool active = core_->irq.x_int_active();
  return core_->regs.mode0(fields::Mode_Reg0::INT_Pol) ? active : !active;
}
bool Chip::irq_active() const { return core_->irq.active(); }
bool Chip::pb3_pin() const { return core_->irq.pb3(); }
void Chip::on_pb3_change(std::function<void(std::uint64_t, bool)> cb) {
  core_->signals.pb3.add(std::move(cb));
}
bool Chip::started() const { return core_->dp.started(); }
DpState Chip::dp_state() const { return core_->dp.state(); }
WdState Chip::wd_state() const { return core_->watchdog.state(); }

void Chip::on_irq_change(std::function<void(std::uint64_t, bool)> cb) {
  core_->signals.irq.add(std::move(cb));
}
void Chip::set_log_sink(LogSink sink) { set_log_sink(std::move(sink), LogLevel::debug); }
void Chip::set_log_sink(LogSink sink, LogLevel shown) {
  core_->signals.flush_log();  // what the old sink is still owed (a repeat count, lines left out)
  core_->signals.sink = std::move(sink);
  core_->signals.shown = shown;
}
const ProfileDesc& Chip::profile() const { return core_->prof(); }
BusMode Chip::bus_mode() const { return core_->regs.bus(); }
std::optional<Vpc3Variant> Chip::vpc3_variant() const { return core_->variant; }
IrqController Chip::irq_controller() const { return core_->irq.served(); }

bool parse_vpc3_variant(std::string_view s, Vpc3Variant& out) {
  for (Vpc3Variant v : kAllVpc3Variants) {
    if (s == vpc3_variant_name(v)) {
      out = v;
      return true;
    }
  }
  return false;
}

namespace {
// The names of kAllVpc3Variants, in its order.
constexpr std::array<std::string_view, 3> kVpc3VariantNames = {"b", "c", "s"};
static_assert(std::size(kAllVpc3Variants) == kVpc3VariantNames.size(), "name every variant");
}  // namespace

std::string_view vpc3_variant_name(Vpc3Variant v) {
  for (std::size_t i = 0; i < kVpc3VariantNames.size(); ++i) {
    if (kAllVpc3Variants[i] == v) return kVpc3VariantNames[i];
  }
  return "?";
}

std::optional<Chip::RequestSlot> Chip::next_request_slot() const {
  if (profile().id != Profile::dpc31) return std::nullopt;
  auto cell = [this](RegId id) { return peek(static_cast<std::uint32_t>(addr_of(id))); };
  const std::uint8_t len = cell(RegId::InstQ_Len);
  if (len == 0) return std::nullopt;
  const std::uint8_t wr = cell(RegId::InstQ_Wr);
  return RequestSlot{
      (static_cast<std::uint32_t>(cell(RegId::InstQ_Base)) << profile().segment_shift) +
          wr * request::kEntryBytes,
      static_cast<std::uint8_t>((wr + 1) % len)};
}

bool parse_irq_controller(std::string_view s, IrqController& out) {
  for (IrqController c : {IrqController::external, IrqController::c31}) {
    if (s == irq_controller_name(c)) {
      out = c;
      return true;
    }
  }
  return false;
}

std::string_view irq_controller_name(IrqController c) {
  return c == IrqController::c31 ? "c31" : "external";
}

std::int32_t Chip::addr_of(RegId id) const {
  const RegDesc* r = core_->regs.reg(id);
  if (r == nullptr) return -1;
  return r->read_addr >= 0 ? r->read_addr : r->write_addr;
}

bool Chip::ssa_buffer_free() const { return core_->dp.ssa_free(); }

}  // namespace dpc31
