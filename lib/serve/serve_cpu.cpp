#include "serve_cpu.hpp"

#include <fmt/format.h>

#include <utility>

namespace dpc31::serve {

BoardCpu::BoardCpu(Chip& chip, CpuSetup setup, std::function<void(std::string)> port_line)
    : chip_(chip), s_(std::move(setup)), line_(std::move(port_line)) {
  module_ = std::make_unique<Cpu51Module>(chip_, s_.cfg, s_.image, s_.address);
  module_->on_port = [this](std::uint64_t cycle, unsigned port, std::uint32_t value) {
    bounded(port_lines_, cycle,
            fmt::format("{} {} {:#04x}", cycle, module_->port_name(port), value), "port");
  };
  module_->on_serial = [this](std::uint64_t cycle, std::uint8_t data) {
    bounded(serial_lines_, cycle, fmt::format("{} {:#04x}", cycle, data), "serial");
  };
  chip_.on_irq_change([this](std::uint64_t, bool active) {
    if (!active || !watch_irq_) return;
    irq_seen_ = true;
    chip_.request_stop();  // the board ends the CPU's step in progress, then returns
  });
}

void BoardCpu::run_until(std::uint64_t cycle) {
  while (chip_.cycle() < cycle) {
    module_->run_until(cycle);
    chip_.clear_stop();
    if (watch_irq_ && irq_seen_) break;
  }
  // Nothing reads the module's history here: the `! port` lines have told it; what their bound
  // left out is told before the reply.
  module_->clear_history();
  for (const std::string& l : port_lines_.flush())
    line_(fmt::format("! port_log {} {}", chip_.cycle(), l));
  for (const std::string& l : serial_lines_.flush())
    line_(fmt::format("! serial_log {} {}", chip_.cycle(), l));
}

// "! KIND TEXT" through `limit`, and what it left out as "! KIND_log CYCLE ...".
void BoardCpu::bounded(LogLimiter& limit, std::uint64_t cycle, const std::string& text,
                       std::string_view kind) {
  for (const std::string& l : limit.add(cycle, text))
    line_(l == text ? fmt::format("! {} {}", kind, l)
                    : fmt::format("! {}_log {} {}", kind, cycle, l));
}

bool BoardCpu::run_until_irq(std::uint64_t cycle) {
  watch_irq_ = true;
  irq_seen_ = false;
  run_until(cycle);
  watch_irq_ = false;
  return irq_seen_;
}

std::string BoardCpu::registers() const {
  const mcs51::Cpu& c = module_->board().cpu();
  std::string regs;
  for (unsigned n = 0; n < 8; ++n) regs += fmt::format(" r{}={:#04x}", n, c.reg(n));
  return fmt::format(
      "core={} hz={} pc={:#06x} a={:#04x} b={:#04x} psw={:#04x} sp={:#04x} dptr={:#06x}{} "
      "ie={:#04x} ip={:#04x} in_service={} idle={} machine_cycles={}",
      s_.cfg.c31 ? "c31" : "80c32", s_.cfg.hz, c.pc(), c.a(), c.b(), c.psw(), c.sp(), c.dptr(),
      regs, c.sfr_latch(mcs51::sfr::IE), c.sfr_latch(mcs51::sfr::IP), c.in_service(),
      c.idle() ? 1 : 0, c.cycles());
}

std::string BoardCpu::port(unsigned n) const {
  const mcs51::Cpu& c = module_->board().cpu();
  return fmt::format("latch={:#04x} pins={:#04x}", c.port_latch(n), c.port_pins(n));
}

std::string BoardCpu::latch() const {
  std::string out;
  for (const std::string& name : s_.cfg.latch_ports()) {
    out += fmt::format("{}{}={:#04x}", out.empty() ? "" : " ", name, module_->port(name));
  }
  return out;
}

std::string BoardCpu::describe() const {
  return s_.cfg.c31
             ? fmt::format("cpu=c31 cpu_hz={} code={:#06x}", s_.cfg.hz, s_.cfg.code)
             : fmt::format("cpu=80c32 cpu_hz={} board_address={:#06x}", s_.cfg.hz, s_.cfg.base);
}

void BoardCpu::poked(std::uint32_t addr, std::uint8_t value) {
  module_->board().poked(static_cast<std::uint16_t>(addr), value);
}

}  // namespace dpc31::serve
