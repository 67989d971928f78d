#include "firmware_host.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <span>

#include "firmware.h"
#include "scenario_lex.hpp"

namespace dpc31 {

class FirmwareHost::Entered {
 public:
  Entered(FirmwareHost& h, BusPort& bus)
      : h_(h),
        hal_(bus, &h.sink_, &h.errors_),
        bus_(std::exchange(h.bus_, &bus)),
        hooks_(board::exchange(&h)) {}
  ~Entered() {
    board::exchange(hooks_);
    h_.bus_ = bus_;
  }
  Entered(const Entered&) = delete;
  Entered& operator=(const Entered&) = delete;

 private:
  FirmwareHost& h_;
  hal::Scope hal_;
  BusPort* bus_;
  board::Hooks* hooks_;
};

// init runs on the caller's stack and bus, not on the host CPU (cpu.hpp), so this bus gives it
// what the host CPU gives the ISR and the main loop: each access is progress for the hang guard
// (a loop polling the chip runs on), and a wait serves an enabled interrupt as Cpu::idle does.
class FirmwareHost::InitBus final : public BusPort {
 public:
  InitBus(FirmwareHost& h, BusPort& bus) : h_(h), bus_(bus) {}
  std::uint8_t read(std::uint32_t addr) override {
    access();
    return bus_.read(addr);
  }
  void write(std::uint32_t addr, std::uint8_t value) override {
    access();
    bus_.write(addr, value);
  }
  void write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes) override {
    access();
    bus_.write_block(addr, bytes);
  }
  void read_block(std::uint32_t addr, std::span<std::uint8_t> out) override {
    access();
    bus_.read_block(addr, out);
  }
  void fill(std::uint32_t addr, std::uint8_t value, std::size_t len) override {
    access();
    bus_.fill(addr, value, len);
  }
  bool equal(std::uint32_t a, std::uint32_t b, std::size_t len) override {
    access();
    return bus_.equal(a, b, len);
  }
  void idle(std::uint64_t cycles) override {
    access();
    const std::uint64_t end = Chip::cycle_after(cycle(), cycles);
    while (cycle() < end) {
      const bool serves = !in_isr_ && h_.fw_.isr != nullptr && h_.int_enabled_;
      if (serves && chip().irq_active()) {
        serve();  // X/INT is level-triggered: the ISR runs until it is gone or masked
        continue;
      }
      // With no bus access, X/INT changes only at an event of the chip.
      const std::uint64_t to =
          serves ? std::min(std::max(chip().next_deadline(), cycle() + 1), end) : end;
      bus_.idle(to - cycle());
    }
  }
  [[nodiscard]] const Chip& chip() const override { return bus_.chip(); }

 private:
  void access() {
    board::progress();
    ++accesses_;
  }
  // As Cpu::serve: an ISR without a bus access costs one access time, so time advances.
  void serve() {
    in_isr_ = true;
    const std::uint64_t before = accesses_;
    h_.isr(*this);
    if (accesses_ == before) bus_.idle(Cpu::kNoAccessCycles);
    in_isr_ = false;
  }

  FirmwareHost& h_;
  BusPort& bus_;
  std::uint64_t accesses_ = 0;
  bool in_isr_ = false;  // the ISR's own waits do not enter it again
};

namespace {

// A call into the firmware on the caller's stack (init, a hardware input): firmware code runs for
// the hang guard until it returns or throws (the host CPU counts its own hand-overs).
class FirmwareCode {
 public:
  FirmwareCode() { board::firmware_entered(); }
  ~FirmwareCode() { board::firmware_left(); }
  FirmwareCode(const FirmwareCode&) = delete;
  FirmwareCode& operator=(const FirmwareCode&) = delete;
};

// A built-in's instance: zeroed, aligned for any type.
std::unique_ptr<std::max_align_t[]> new_instance(const dpc31_builtin* b) {
  if (b == nullptr) return nullptr;
  const std::size_t n =
      (b->instance_size + sizeof(std::max_align_t) - 1) / sizeof(std::max_align_t);
  return std::make_unique<std::max_align_t[]>(n);  // value-initialised: all zero
}

}  // namespace

FirmwareHost::FirmwareHost(const dpc31_firmware& fw)
    : fw_(fw),
      name_(fmt::format("firmware {}", fw.name)),
      builtin_(dpc31_builtin_of(&fw)),
      self_(new_instance(builtin_)),
      run_(builtin_ != nullptr ? nullptr : plugin_copy(fw)),
      sink_([this](std::uint64_t cycle, unsigned port, std::uint32_t value) {
        writes_.push_back(PortWrite{cycle, port, value});
        if (port >= values_.size()) values_.resize(port + 1, 0);
        values_[port] = value;
        if (on_port) on_port(cycle, port, value);
      }),
      // Thrown through the firmware's C frames as the reset line's error is: the plug-in's unwind
      // tables (gcc's and clang's default) carry it to the host (docs/decisions.md).
      errors_([this](const char* message) {
        throw FirmwareError(fmt::format("{}: {}", name_, message));
      }),
      input_errors_([this](const char* message) {
        throw FirmwareError(fmt::format(
            "{}: {} (hw_input runs with no chip selected: it notes the input for the ISR or the "
            "main loop)",
            name_, message));
      }) {}

void FirmwareHost::name_station(std::uint8_t address) {
  name_ = fmt::format("station {}: firmware {}", address, fw_.name);
}

void FirmwareHost::init(BusPort& bus, std::uint8_t station_address) {
  const Chip& c = bus.chip();
  const dpc31_board board{static_cast<int>(c.profile().id),
                          c.bus_mode() == BusMode::motorola ? 1 : 0, station_address};
  InitBus init_bus(*this, bus);
  Entered e(*this, init_bus);
  const FirmwareCode running;
  if (builtin_ != nullptr) {
    builtin_->init(self_.get(), &board);
  } else {
    run_->init(&board);
  }
}

void FirmwareHost::isr(BusPort& bus) {
  interrupts.emplace_back(bus.cycle(), bus.chip().peek_reg(RegId::Int_Reg));
  Entered e(*this, bus);
  if (builtin_ != nullptr) {
    builtin_->isr(self_.get());
  } else {
    run_->isr();
  }
}

void FirmwareHost::main_step(BusPort& bus) {
  Entered e(*this, bus);
  run_->main_step();  // a built-in has none (program)
}

Cpu::Program FirmwareHost::program(const Cpu::Isr& after) {
  Cpu::Program p;
  // The plug-in copy stays loaded while the host CPU may still unwind the firmware's frames (its
  // destructor), whichever of the two goes first.
  if (fw_.isr != nullptr) {
    p.isr = [this, after, copy = run_](BusPort& b) {
      isr(b);
      if (after) after(b);
    };
  }
  if (builtin_ == nullptr && run_->main_step != nullptr) {
    p.main_step = [this, after, copy = run_](BusPort& b) {
      main_step(b);
      if (after) after(b);
    };
  }
  p.interrupts_enabled = &int_enabled_;
  return p;
}

std::optional<ValueRange> builtin_hw_range(const dpc31_firmware& fw, std::string_view name) {
  const dpc31_builtin* b = dpc31_builtin_of(&fw);
  const int i = scenario_lex::name_index(fw.hw_inputs, name);
  if (b == nullptr || b->hw_ranges == nullptr || i < 0) return std::nullopt;
  return ValueRange{fw.hw_inputs[i], b->hw_ranges[i].min, b->hw_ranges[i].max};
}

std::string FirmwareHost::hw_input(const std::string& name, std::uint32_t value) {
  // A hardware input is the module's own pin, not a chip access: no bus is selected, and a HAL
  // call or a board hook that needs the chip (reset_line, wait_1ms) from it is the firmware's
  // fault (FirmwareError), as from init or the ISR. Its hooks are this host's, so that the hang
  // guard names this station when it spins.
  struct Input {
    FirmwareHost& h;
    hal::Selection prev;
    BusPort* bus = std::exchange(h.bus_, nullptr);
    board::Hooks* hooks = board::exchange(&h);
    ~Input() {
      board::exchange(hooks);
      h.bus_ = bus;
      hal::exchange_selection(prev);
    }
  } const input{*this, hal::exchange_selection({nullptr, nullptr, nullptr, &input_errors_})};
  const FirmwareCode running;
  int r = -1;
  if (builtin_ != nullptr) {
    if (builtin_->hw_input != nullptr) r = builtin_->hw_input(self_.get(), name.c_str(), value);
  } else if (run_->hw_input != nullptr) {
    r = run_->hw_input(name.c_str(), value);
  }
  if (r == -1) return "unknown hardware input '" + name + "' of " + fw_.name;
  if (r == -2) {
    if (const auto range = builtin_hw_range(fw_, name)) {
      return out_of_range(*range, std::to_string(value));
    }
    return "value " + std::to_string(value) + " out of range for " + name;
  }
  return {};
}

std::int64_t FirmwareHost::port(const std::string& name) const {
  for (unsigned i = 0; fw_.ports != nullptr && fw_.ports[i] != nullptr; ++i) {
    if (name == fw_.ports[i]) return i < values_.size() ? values_[i] : 0;
  }
  return -1;
}

std::string FirmwareHost::port_name(unsigned port) const {
  for (unsigned i = 0; fw_.ports != nullptr && fw_.ports[i] != nullptr; ++i) {
    if (i == port) return fw_.ports[i];
  }
  return "port" + std::to_string(port);
}

// The chip starts in its reset state: a pulse before the firmware started it has nothing to do.
// A reset of a running chip would restart its clock under the bus side: not modelled.
void FirmwareHost::reset_line(bool asserted) {
  if (!asserted) return;  // a release needs no chip: hw_input may release the line
  if (bus_ == nullptr) input_errors_("dpc31_board_reset called with no chip selected");
  if (bus_->chip().started()) {
    throw FirmwareError(fmt::format(
        "{}: reset line asserted at cycle {} after the chip was started (a reset during "
        "operation is not modelled)",
        name_, bus_->cycle()));
  }
}

void FirmwareHost::int_enable(bool enabled) { int_enabled_ = enabled; }

void FirmwareHost::wait_1ms() {
  if (bus_ == nullptr) input_errors_("dpc31_board_wait_1ms called with no chip selected");
  bus_->idle(bus_->chip().clock_hz() / 1000);
}

}  // namespace dpc31
