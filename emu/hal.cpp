// The C HAL: a chip handle for C hosts, and the driver-shaped access functions on the bus
// selected for the calling thread (a handle's own bus, or the host CPU's while it runs an ISR).
#include "dpc31/hal.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <span>

#include "dpc31/dpc31_hal.h"
#include "dpc31/dpc31_version.h"
#include "harness.hpp"

struct dpc31_chip {
  explicit dpc31_chip(dpc31::ChipOptions o)
      : chip(o), bus(chip), core(dpc31::harness::core(chip)) {}
  dpc31::Chip chip;
  dpc31::DirectBus bus;
  dpc31::hal::PortSink ports;
  // What Chip::read / Chip::write (and so `bus`) call: core.bus_read / bus_write (chip.cpp). The
  // single-byte accesses call it here, inline: the out-of-line Chip::write is a call, and its
  // register saves, more per access (docs/decisions.md, "HAL accesses inline").
  dpc31::ChipCore& core;
};

namespace dpc31::hal {
namespace {

// The selection (Selection). The emulator's objects are position independent (they also make
// libdpc31emu.so), so the default TLS model would be local-dynamic: a __tls_get_addr call per
// access in the shared library, the thread pointer, an add and a load in an executable.
// initial-exec is one load from the thread pointer (and a GOT load in the shared library); its
// cost, 24 bytes of static TLS when the library is dlopen'ed, glibc reserves room for.
[[gnu::tls_model("initial-exec")]] thread_local BusPort* t_bus = nullptr;
[[gnu::tls_model("initial-exec")]] thread_local const PortSink* t_ports = nullptr;
[[gnu::tls_model("initial-exec")]] thread_local ChipCore* t_core = nullptr;
[[gnu::tls_model("initial-exec")]] thread_local const ErrorSink* t_errors = nullptr;

void default_error(const char* message) {
  std::fprintf(stderr, "dpc31 HAL: %s\n", message);
  std::abort();
}

dpc31_error_fn g_error = default_error;

// The selection's host (a firmware fault) or else the process's handler. Neither may return: a
// handler that returns cannot make the access happen. The message is in a buffer of the thread,
// and no frame between the access function and the handler owns anything to destroy, so a C
// handler may longjmp out (dpc31_hal.h).
[[noreturn, gnu::cold, gnu::noinline, gnu::format(printf, 1, 2)]] void misuse(const char* format,
                                                                              ...) {
  thread_local char message[256];
  va_list args;
  va_start(args, format);
  std::vsnprintf(message, sizeof message, format, args);
  va_end(args);
  if (t_errors != nullptr && *t_errors) (*t_errors)(message);
  g_error(message);
  std::fprintf(stderr,
               "dpc31 HAL: the error handler returned from \"%s\"; it must not (exit, longjmp): "
               "aborting\n",
               message);
  std::abort();
}

// A firmware run by a host cannot select a chip: the hint is for a program that can.
[[noreturn, gnu::cold, gnu::noinline]] void no_chip(const char* fn) {
  misuse("%s called with no chip selected%s", fn, t_errors != nullptr ? "" : " (dpc31_select)");
}

// Inline, the error out of line: every Vpc3Read / Vpc3Write asks.
inline BusPort& bus(const char* fn) {
  BusPort* const b = t_bus;
  if (b == nullptr) [[unlikely]]
    no_chip(fn);
  return *b;
}

// Vpc3Read / Vpc3Write on any other bus, out of line (the fast path stays small).
[[gnu::noinline]] std::uint8_t read_bus(std::uint16_t addr) { return bus("Vpc3Read").read(addr); }
[[gnu::noinline]] void write_bus(std::uint16_t addr, std::uint8_t value) {
  bus("Vpc3Write").write(addr, value);
}

// A block's pointers, checked in one place before any access. A chip "pointer" of the drivers'
// serial mode holds a chip address (0x0000..0xFFFF) in its value; a local buffer is host memory,
// which never lies there (Linux maps nothing below vm.mmap_min_addr, 64 KiB by default). Either
// the other way round is a swapped pair of arguments: the HAL would read or write host memory at
// a chip address, a crash the firmware's call can name (docs/decisions.md).
constexpr std::uintptr_t kChipWindow = 0x10000;

std::uint16_t chip_address(const char* fn, const std::uint8_t* chip, uint16_t len) {
  const auto value = reinterpret_cast<std::uintptr_t>(chip);
  if (len != 0 && value >= kChipWindow) [[unlikely]]
    misuse("%s: chip pointer %#" PRIxPTR
           " is not a chip address (0x0000..0xFFFF): the arguments swapped?",
           fn, value);
  return static_cast<std::uint16_t>(value);
}

void check_local(const char* fn, const void* local, uint16_t len) {
  const auto value = reinterpret_cast<std::uintptr_t>(local);
  if (len == 0 || value >= kChipWindow) [[likely]]
    return;
  if (local == nullptr)
    misuse("%s: local buffer is NULL with length %u", fn, static_cast<unsigned>(len));
  misuse("%s: local buffer %#" PRIxPTR
         " is a chip address (0x0000..0xFFFF), not host memory: the arguments swapped?",
         fn, value);
}

[[noreturn, gnu::cold, gnu::noinline]] void null_handle(const char* fn) {
  misuse("%s called with a NULL chip handle", fn);
}

// The drivers' chip addresses wrap at 16 bits: byte i of a block is at (uint16_t)(addr + i).
// f(address, offset, n) gets the pieces that do not wrap, in order.
template <typename F>
void pieces(uint16_t addr, uint16_t len, F&& f) {
  for (std::size_t i = 0; i < len;) {
    const auto a = static_cast<uint16_t>(addr + i);
    const std::size_t n = std::min<std::size_t>(len - i, 0x10000u - a);
    f(a, i, n);
    i += n;
  }
}

// The block functions: one block transfer of the bus per piece (Chip::write_block & co.).
void copy_to(BusPort& b, uint16_t dst, const uint8_t* src, uint16_t len, const char* fn) {
  check_local(fn, src, len);
  pieces(dst, len, [&](uint16_t a, std::size_t i, std::size_t n) {
    b.write_block(a, std::span<const uint8_t>(src + i, n));
  });
}

void copy_from(BusPort& b, uint8_t* dst, uint16_t src, uint16_t len, const char* fn) {
  check_local(fn, dst, len);
  pieces(src, len, [&](uint16_t a, std::size_t i, std::size_t n) {
    b.read_block(a, std::span<uint8_t>(dst + i, n));
  });
}

void mem_set(BusPort& b, uint16_t addr, uint8_t value, uint16_t len) {
  pieces(addr, len, [&](uint16_t a, std::size_t, std::size_t n) { b.fill(a, value, n); });
}

// Stops at the first difference, as the drivers' version does (its reads are what it costs).
uint8_t mem_cmp(BusPort& b, uint16_t a, uint16_t c, uint16_t len) {
  for (std::size_t i = 0; i < len;) {
    const auto ai = static_cast<uint16_t>(a + i);
    const auto ci = static_cast<uint16_t>(c + i);
    const std::size_t n = std::min<std::size_t>({len - i, 0x10000u - ai, 0x10000u - ci});
    if (!b.equal(ai, ci, n)) return 1;
    i += n;
  }
  return 0;
}

}  // namespace

}  // namespace dpc31::hal

namespace dpc31 {

// Byte by byte: what a bus without block transfers of its own does.
void BusPort::write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes) {
  for (const std::uint8_t v : bytes) write(addr++, v);
}

void BusPort::read_block(std::uint32_t addr, std::span<std::uint8_t> out) {
  for (std::uint8_t& v : out) v = read(addr++);
}

void BusPort::fill(std::uint32_t addr, std::uint8_t value, std::size_t len) {
  for (std::size_t i = 0; i < len; ++i) write(addr + static_cast<std::uint32_t>(i), value);
}

bool BusPort::equal(std::uint32_t a, std::uint32_t b, std::size_t len) {
  for (std::size_t i = 0; i < len; ++i) {
    const std::uint8_t first = read(a + static_cast<std::uint32_t>(i));  // this order on the bus
    if (first != read(b + static_cast<std::uint32_t>(i))) return false;
  }
  return true;
}

}  // namespace dpc31

namespace dpc31::hal {

Selection exchange_selection(Selection s) {
  const Selection prev{t_bus, t_ports, t_core, t_errors};
  t_bus = s.bus;
  t_ports = s.ports;
  t_core = s.core;
  t_errors = s.errors;
  return prev;
}

Scope::Scope(BusPort& b, const PortSink* ports, const ErrorSink* errors)
    : prev_(exchange_selection({&b, ports, nullptr, errors})) {}

Scope::~Scope() { exchange_selection(prev_); }

}  // namespace dpc31::hal

using dpc31::hal::bus;

namespace {
// A handle the caller passed: NULL is a misuse (the error handler's message), not a crash.
template <typename C>
C& handle(C* chip, const char* fn) {
  if (chip == nullptr) [[unlikely]]
    dpc31::hal::null_handle(fn);
  return *chip;
}
// A pin's C callback as the chip's observer: fn(user, cycle, 1 when active / high).
std::function<void(std::uint64_t, bool)> pin_observer(dpc31_irq_fn fn, void* user) {
  return [fn, user](std::uint64_t cycle, bool level) { fn(user, cycle, level ? 1 : 0); };
}
}  // namespace

extern "C" {

dpc31_chip* dpc31_create(const char* profile, int motorola) {
  return dpc31_create_variant(profile, nullptr, motorola);
}

dpc31_chip* dpc31_create_variant(const char* profile, const char* variant, int motorola) {
  dpc31::ChipOptions o;
  if (profile == nullptr || !dpc31::parse_profile(profile, o.profile)) return nullptr;
  if (variant != nullptr) {
    dpc31::Vpc3Variant v{};
    if (o.profile != dpc31::Profile::vpc3plus || !dpc31::parse_vpc3_variant(variant, v))
      return nullptr;
    o.variant = v;
  }
  o.bus = motorola != 0 ? dpc31::BusMode::motorola : dpc31::BusMode::intel;
  return new dpc31_chip(o);
}

void dpc31_destroy(dpc31_chip* chip) {
  if (chip == nullptr) return;  // as free(NULL): the clean-up path of a failed create
  if (dpc31::hal::t_bus == &chip->bus) dpc31_select(nullptr);
  delete chip;
}

// flatten: the core's plain path inline here too (GCC inlines it into Chip::write, not always
// into these).
[[gnu::flatten]] uint8_t dpc31_read(dpc31_chip* chip, uint16_t addr) {
  return handle(chip, "dpc31_read").core.bus_read(addr);
}
[[gnu::flatten]] void dpc31_write(dpc31_chip* chip, uint16_t addr, uint8_t value) {
  handle(chip, "dpc31_write").core.bus_write(addr, value);
}

void dpc31_copy_to(dpc31_chip* chip, uint16_t dst, const uint8_t* src, uint16_t len) {
  dpc31::hal::copy_to(handle(chip, "dpc31_copy_to").bus, dst, src, len, "dpc31_copy_to");
}

void dpc31_copy_from(dpc31_chip* chip, uint8_t* dst, uint16_t src, uint16_t len) {
  dpc31::hal::copy_from(handle(chip, "dpc31_copy_from").bus, dst, src, len, "dpc31_copy_from");
}

void dpc31_memset(dpc31_chip* chip, uint16_t addr, uint8_t value, uint16_t len) {
  dpc31::hal::mem_set(handle(chip, "dpc31_memset").bus, addr, value, len);
}

uint8_t dpc31_memcmp(dpc31_chip* chip, uint16_t a, uint16_t b, uint16_t len) {
  return dpc31::hal::mem_cmp(handle(chip, "dpc31_memcmp").bus, a, b, len);
}

uint8_t dpc31_peek(const dpc31_chip* chip, uint16_t addr) {
  return handle(chip, "dpc31_peek").chip.peek(addr);
}

void dpc31_run(dpc31_chip* chip, uint64_t cycles) { handle(chip, "dpc31_run").chip.step(cycles); }

int dpc31_run_until_irq_change(dpc31_chip* chip, uint64_t max_cycles) {
  dpc31::Chip& c = handle(chip, "dpc31_run_until_irq_change").chip;
  const bool was = c.irq_active();
  const uint64_t end = dpc31::Chip::cycle_after(c.cycle(), max_cycles);
  if (!was) return c.step_until_irq(max_cycles) ? 1 : 0;
  // Active: with no bus access the line can only fall at an event (the EOI inactive time, a
  // reset); go from event to event.
  while (c.cycle() < end) {
    const uint64_t next = std::max(c.next_deadline(), c.cycle() + 1);
    c.step(std::min(next, end) - c.cycle());
    if (c.irq_active() != was) return 1;
  }
  return 0;
}

uint64_t dpc31_cycle(const dpc31_chip* chip) { return handle(chip, "dpc31_cycle").chip.cycle(); }
uint32_t dpc31_clock_hz(const dpc31_chip* chip) {
  return handle(chip, "dpc31_clock_hz").chip.clock_hz();
}
int dpc31_irq_active(const dpc31_chip* chip) {
  return handle(chip, "dpc31_irq_active").chip.irq_active() ? 1 : 0;
}

void dpc31_set_irq_callback(dpc31_chip* chip, dpc31_irq_fn fn, void* user) {
  dpc31_chip& h = handle(chip, "dpc31_set_irq_callback");
  h.chip.on_irq_change({});
  if (fn != nullptr) h.chip.on_irq_change(pin_observer(fn, user));
}

int dpc31_pb3(const dpc31_chip* chip) { return handle(chip, "dpc31_pb3").chip.pb3_pin() ? 1 : 0; }

void dpc31_set_pb3_callback(dpc31_chip* chip, dpc31_irq_fn fn, void* user) {
  dpc31_chip& h = handle(chip, "dpc31_set_pb3_callback");
  h.chip.on_pb3_change({});
  if (fn != nullptr) h.chip.on_pb3_change(pin_observer(fn, user));
}

void dpc31_select(dpc31_chip* chip) {
  dpc31::hal::exchange_selection(chip != nullptr
                                     ? dpc31::hal::Selection{&chip->bus, &chip->ports, &chip->core}
                                     : dpc31::hal::Selection{});
}

// A chip of dpc31_select: its core inline (what its DirectBus reaches); any other bus (the host
// CPU's, a hal::Scope's) through the bus.
[[gnu::flatten]] uint8_t Vpc3Read(uint16_t wAddress) {
  if (dpc31::ChipCore* const c = dpc31::hal::t_core; c != nullptr) [[likely]]
    return c->bus_read(wAddress);
  return dpc31::hal::read_bus(wAddress);
}

[[gnu::flatten]] void Vpc3Write(uint16_t wAddress, uint8_t bData) {
  if (dpc31::ChipCore* const c = dpc31::hal::t_core; c != nullptr) [[likely]] {
    c->bus_write(wAddress, bData);
    return;
  }
  dpc31::hal::write_bus(wAddress, bData);
}

void CopyToVpc3(uint8_t* pToVpc3Memory, uint8_t* pLocalMemory, uint16_t wLength) {
  const char* const fn = "CopyToVpc3";
  const uint16_t dst = dpc31::hal::chip_address(fn, pToVpc3Memory, wLength);
  dpc31::hal::copy_to(bus(fn), dst, pLocalMemory, wLength, fn);
}

void CopyFromVpc3(uint8_t* pLocalMemory, uint8_t* pToVpc3Memory, uint16_t wLength) {
  const char* const fn = "CopyFromVpc3";
  const uint16_t src = dpc31::hal::chip_address(fn, pToVpc3Memory, wLength);
  dpc31::hal::copy_from(bus(fn), pLocalMemory, src, wLength, fn);
}

void Vpc3MemSet(uint16_t wAddress, uint8_t bValue, uint16_t wLength) {
  dpc31::hal::mem_set(bus("Vpc3MemSet"), wAddress, bValue, wLength);
}

uint8_t Vpc3MemCmp(uint8_t* pToVpc3Memory1, uint8_t* pToVpc3Memory2, uint16_t wLength) {
  const char* const fn = "Vpc3MemCmp";
  const uint16_t a = dpc31::hal::chip_address(fn, pToVpc3Memory1, wLength);
  const uint16_t b = dpc31::hal::chip_address(fn, pToVpc3Memory2, wLength);
  return dpc31::hal::mem_cmp(bus(fn), a, b, wLength);
}

void dpc31_port_write(unsigned port, uint32_t value) {
  dpc31::BusPort& b = bus("dpc31_port_write");
  const dpc31::hal::PortSink* const ports = dpc31::hal::t_ports;
  if (ports != nullptr && *ports) {
    (*ports)(b.cycle(), port, value);
  }
}

void dpc31_set_port_callback(dpc31_chip* chip, dpc31_port_fn fn, void* user) {
  dpc31_chip& h = handle(chip, "dpc31_set_port_callback");
  h.ports = nullptr;
  if (fn != nullptr) {
    h.ports = [fn, user](std::uint64_t cycle, unsigned port, std::uint32_t value) {
      fn(user, cycle, port, value);
    };
  }
}

void dpc31_set_error_handler(dpc31_error_fn fn) {
  dpc31::hal::g_error = fn != nullptr ? fn : dpc31::hal::default_error;
}

// The header's version as compiled into this library (dpc31_version.h).
const char* dpc31emu_version(void) { return DPC31EMU_VERSION_STRING; }

}  // extern "C"
