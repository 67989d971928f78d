#include "cpu.hpp"

namespace dpc31 {

namespace {
struct Stopped {};  // unwinds an ISR that is still waiting when the CPU goes away
}  // namespace

Cpu::Cpu(Chip& chip, Isr isr) : chip_(chip), isr_(std::move(isr)), thread_([this] { body(); }) {}

Cpu::~Cpu() {
  {
    std::unique_lock lk(m_);
    stop_ = true;
    firmware_turn_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void Cpu::body() {
  std::unique_lock lk(m_);
  for (;;) {
    cv_.wait(lk, [this] { return firmware_turn_; });
    if (stop_) return;
    lk.unlock();
    try {
      isr_(*this);
    } catch (const Stopped&) {
      return;
    }
    lk.lock();
    in_isr_ = false;
    firmware_turn_ = false;
    cv_.notify_all();
  }
}

void Cpu::hand_to_firmware() {
  std::unique_lock lk(m_);
  firmware_turn_ = true;
  cv_.notify_all();
  cv_.wait(lk, [this] { return !firmware_turn_; });
}

void Cpu::hand_to_bus_side() {
  std::unique_lock lk(m_);
  firmware_turn_ = false;
  cv_.notify_all();
  cv_.wait(lk, [this] { return firmware_turn_; });
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
