#include "cpu.hpp"

namespace dpc31 {

namespace {
struct Stopped {};  // unwinds an ISR that is still waiting when the CPU goes away
}  // namespace

Cpu::Cpu(Chip& chip, Isr isr) : chip_(chip), isr_(std::move(isr)), thread_([this] { body(); }) {}

Cpu::~Cpu() {
  stop_ = true;
  turn_.store(kFirmware);
  turn_.notify_one();
  thread_.join();
}

void Cpu::body() {
  for (;;) {
    turn_.wait(kBusSide);
    if (stop_) return;
    try {
      isr_(*this);
    } catch (const Stopped&) {
      return;
    }
    in_isr_ = false;
    turn_.store(kBusSide);
    turn_.notify_one();
  }
}

void Cpu::hand_to_firmware() {
  turn_.store(kFirmware);
  turn_.notify_one();
  turn_.wait(kFirmware);
}

void Cpu::hand_to_bus_side() {
  turn_.store(kBusSide);
  turn_.notify_one();
  turn_.wait(kBusSide);
  if (stop_) throw Stopped{};
}

void Cpu::gate() {
  // A stop request (an observer of the bus side, e.g. the master seeing an answer start) takes
  // the baton back before the next access, as reaching the limit does.
  while (chip_.cycle() >= limit_ || chip_.stop_requested()) hand_to_bus_side();
}

std::uint8_t Cpu::read(std::uint32_t addr) {
  gate();
  return chip_.read(addr);
}

void Cpu::write(std::uint32_t addr, std::uint8_t value) {
  gate();
  chip_.write(addr, value);
}

void Cpu::run_until(std::uint64_t cycle) {
  while (chip_.cycle() < cycle && !chip_.stop_requested()) {
    limit_ = cycle;
    if (in_isr_) {
      hand_to_firmware();  // an ISR in progress continues with its next access
      continue;
    }
    if (chip_.irq_active()) {
      in_isr_ = true;  // X/INT is level-triggered: the firmware enters its ISR
      hand_to_firmware();
      continue;
    }
    chip_.step_until_irq(cycle - chip_.cycle());
  }
}

}  // namespace dpc31
