// The public Chip: a thin wrapper over ChipCore. How time advances is in engine.cpp.
#include "dpc31/chip.hpp"

#include <algorithm>
#include <type_traits>

#include "core.hpp"
#include "snapshot.hpp"

namespace dpc31 {

Chip::Chip(ChipOptions opt) : core_(std::make_unique<ChipCore>(opt)) {}
Chip::~Chip() = default;
Chip::Chip(Chip&&) noexcept = default;
Chip& Chip::operator=(Chip&&) noexcept = default;

void Chip::reset() { core_->reset(); }
std::uint8_t Chip::read(std::uint32_t addr) { return core_->bus_read(addr); }
void Chip::write(std::uint32_t addr, std::uint8_t value) { core_->bus_write(addr, value); }
std::uint8_t Chip::peek(std::uint32_t addr) const { return core_->peek(addr); }
bool Chip::poke(std::uint32_t addr, std::uint8_t value) { return core_->poke(addr, value); }
std::uint16_t Chip::peek_reg(RegId id) const { return core_->reg_value(id); }

bool Chip::poke_reg(RegId id, std::uint16_t value) {
  ChipCore& c = *core_;
  const RegDesc* r = c.reg(id);
  if (r == nullptr) return false;
  if (r->kind == Kind::cell) {
    c.set_cell16(*r, value);
    return true;
  }
  if (r->kind != Kind::latch) return false;
  c.latch[ChipCore::idx(id)] = static_cast<std::uint16_t>(value & r->mask());
  c.update_irq_line();
  return true;
}

void Chip::step(std::uint64_t cycles) { core_->advance(cycles); }
bool Chip::step_until_irq(std::uint64_t cycles) {
  if (core_->stop) return false;
  return core_->advance(cycles, ChipCore::Stop::on_irq_or_request);
}
void Chip::request_stop() { core_->stop = true; }
bool Chip::stop_requested() const { return core_->stop; }
void Chip::clear_stop() { core_->stop = false; }

void Chip::drive_rxd(std::uint64_t cycle, bool level) { core_->drive_rxd(cycle, level); }
void Chip::on_rxd(std::function<void(std::uint64_t, bool)> cb) {
  core_->rxd_observer.add(std::move(cb));
}
void Chip::on_state_change(std::function<void(std::uint64_t)> cb) {
  core_->state_observer.add(std::move(cb));
}
void Chip::on_txd(std::function<void(std::uint64_t, bool)> cb) { core_->watch_txd(std::move(cb)); }
void Chip::on_bus_access(std::function<void(std::uint64_t, const BusAccess&)> cb) {
  core_->bus_observer.add(std::move(cb));
}
void Chip::on_telegram(std::function<void(const Telegram&)> cb) {
  core_->telegram_observer.add(std::move(cb));
}
ChipProbe Chip::probe() const {
  const ChipCore& c = *core_;
  return {c.dp.state,          c.timers.wd,
          c.baud_code,         c.latch[ChipCore::idx(RegId::Int_Req_Reg)],
          c.buffers.dout.sm(), c.buffers.din.sm(),
          c.buffers.diag.sm()};
}
std::uint64_t Chip::next_deadline() const { return core_->next_event(); }
std::uint64_t Chip::watchdog_due() const { return core_->watchdog_due(); }
std::uint64_t Chip::eoi_inactive_until() const { return core_->due(core_->irq.eoi); }

bool Chip::txd_pin() const { return core_->txd_level(); }
const FdlCounters& Chip::fdl_counters() const { return core_->counters; }
std::uint8_t Chip::station_address() const { return core_->dp.station; }
std::uint32_t Chip::bit_cycles() const { return core_->mac.rx.bit_time(); }
std::uint64_t Chip::cycle() const { return core_->now; }
std::uint32_t Chip::clock_hz() const { return core_->clock_hz; }
std::uint32_t Chip::bus_access_cycles() const { return core_->prof->bus_access_cycles; }

bool Chip::x_int_pin() const {
  // INT_Pol = 0: low-active (the default), 1: high-active.
  return core_->mode0(fields::Mode_Reg0::INT_Pol) ? core_->irq_active() : !core_->irq_active();
}
bool Chip::irq_active() const { return core_->irq_active(); }
bool Chip::pb3_pin() const { return core_->pb3; }
void Chip::on_pb3_change(std::function<void(std::uint64_t, bool)> cb) {
  core_->pb3_observer.add(std::move(cb));
}
bool Chip::started() const { return core_->started; }
DpState Chip::dp_state() const { return core_->dp.state; }
WdState Chip::wd_state() const { return core_->timers.wd; }

void Chip::on_irq_change(std::function<void(std::uint64_t, bool)> cb) {
  core_->irq_observer.add(std::move(cb));
}
void Chip::set_log_sink(LogSink sink) { core_->sink = std::move(sink); }
const ProfileDesc& Chip::profile() const { return *core_->prof; }
BusMode Chip::bus_mode() const { return core_->bus; }
std::optional<Vpc3Variant> Chip::vpc3_variant() const { return core_->variant; }

bool parse_vpc3_variant(std::string_view s, Vpc3Variant& out) {
  for (Vpc3Variant v : kAllVpc3Variants) {
    if (s == vpc3_variant_name(v)) {
      out = v;
      return true;
    }
  }
  return false;
}

std::string_view vpc3_variant_name(Vpc3Variant v) {
  switch (v) {
    case Vpc3Variant::b:
      return "b";
    case Vpc3Variant::c:
      return "c";
    case Vpc3Variant::s:
      return "s";
  }
  return "?";
}

std::int32_t Chip::addr_of(RegId id) const {
  const RegDesc* r = core_->reg(id);
  if (r == nullptr) return -1;
  return r->read_addr >= 0 ? r->read_addr : r->write_addr;
}

bool Chip::ssa_buffer_free() const { return core_->dp.ssa_free; }

// ---- snapshots (docs/snapshots.md) ----

namespace {

// A guard for the one platform the size is known on: a new member of ChipCore changes its size
// (less the arrays that grow with the register description), or lands in padding, which the
// snapshot tests' many save points in live sessions catch. Then: state goes into core_fields,
// configuration into the header, attachments into move_attachments.
#if defined(__x86_64__) && defined(__GLIBCXX__)
constexpr std::size_t round8(std::size_t n) { return (n + 7) / 8 * 8; }
static_assert(sizeof(ChipCore) - 2 * round8(sizeof(ChipCore::latch)) - sizeof(HookTable) == 1304,
              "a new member of ChipCore: see the comment above");
#endif

// Everything that influences future behaviour. Not here: the configuration (prof, bus,
// clock_hz: the header), the tables derived from the profile (rd_map, wr_map, region_map,
// reg_index, hooks), the log sink and the observers, quiet_until (a cache, 0 = recompute) and stop
// (a request of whoever steps the chip).
template <typename Ar, typename C>
void core_fields(Ar& ar, C& c) {
  ar.section("CORE");
  ar(c.now);
  ar(c.started);
  ar(c.ram_access_violation);
  ar(c.large_ram);
  ar.bounded(c.baud_code, static_cast<std::uint8_t>(std::size(kBaudRates) - 1));
  ar(c.written_bits);
  ar(c.diag_in_flight);
  ar(c.irq_line);
  ar(c.pb3);
  // Each engine keeps its timers its own way: a snapshot loads into a chip of the same engine.
  Engine engine = c.engine;
  ar.bounded(engine, Engine::per_cycle);
  if constexpr (requires { ar.fail(""); }) {
    if (engine != c.engine) ar.fail("the snapshot is of the other engine (event / per_cycle)");
  }
  ar.sequence(c.rxd_pending, snap::kMaxFileSize, [](auto& a, auto& e) {
    a(e.first);
    a(e.second);
  });
  ar(c.rxd_level);
  ar.section("LTCH");
  ar.array(c.latch);
  ar.section("MEM ");
  ar.fixed_bytes(c.mem);
  ar.block(c.irq);
  ar.block(c.buffers);
  ar.block(c.dp);
  ar.block(c.timers);
  ar.block(c.mac);
  ar.block(c.counters);
}

snap::Header header_of(const ChipCore& c) {
  return {c.prof->id, c.bus, c.clock_hz, snap::register_map_fingerprint()};
}

// The log sink and the observers belong to whoever attached them, not to the state.
void move_attachments(ChipCore& from, ChipCore& to) noexcept {
  to.sink = std::move(from.sink);
  to.irq_observer = std::move(from.irq_observer);
  to.pb3_observer = std::move(from.pb3_observer);
  to.txd_observer = std::move(from.txd_observer);
  to.rxd_observer = std::move(from.rxd_observer);
  to.telegram_observer = std::move(from.telegram_observer);
  to.block_observer = std::move(from.block_observer);
  to.bus_observer = std::move(from.bus_observer);
  to.state_observer = std::move(from.state_observer);
}

}  // namespace

std::vector<std::uint8_t> Chip::save_state() const {
  snap::Writer w;
  core_fields(w, *core_);
  return snap::seal(header_of(*core_), w.bytes());
}

void Chip::load_state(std::span<const std::uint8_t> bytes) {
  ChipCore& c = *core_;
  const std::span<const std::uint8_t> payload = snap::open(bytes, header_of(c));
  // Decode into a fresh core (its tables built from the same profile); *core_ is untouched until
  // everything has been read and checked.
  auto fresh =
      std::make_unique<ChipCore>(ChipOptions{c.prof->id, c.bus, c.clock_hz, c.engine, c.variant});
  fresh->sink = nullptr;
  snap::Reader r(payload);
  core_fields(r, *fresh);
  r.finish();
  // Commit: nothing below throws.
  static_assert(std::is_nothrow_move_assignable_v<ChipCore>);
  move_attachments(c, *fresh);
  c = std::move(*fresh);
}

void Chip::save_state_file(const std::string& path) const {
  snap::write_file_atomic(path, save_state());
}

void Chip::load_state_file(const std::string& path) {
  const std::vector<std::uint8_t> bytes = snap::read_file(path);
  try {
    load_state(bytes);
  } catch (const SnapshotError& e) {
    throw SnapshotError(path + ": " + e.what());
  }
}

}  // namespace dpc31
