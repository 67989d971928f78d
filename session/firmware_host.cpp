#include "firmware_host.hpp"

namespace dpc31 {

FirmwareHost::FirmwareHost(const dpc31_firmware& fw)
    : fw_(fw), sink_([this](std::uint64_t cycle, unsigned port, std::uint32_t value) {
        writes_.push_back(PortWrite{cycle, port, value});
        if (port >= values_.size()) values_.resize(port + 1, 0);
        values_[port] = value;
        if (on_port) on_port(cycle, port, value);
      }) {}

void FirmwareHost::init(BusPort& bus, std::uint8_t station_address) {
  const Chip& c = bus.chip();
  const dps_board board{static_cast<int>(c.profile().id), c.bus_mode() == BusMode::motorola ? 1 : 0,
                        station_address};
  hal::Scope scope(bus, &sink_);
  fw_.init(&board);
}

void FirmwareHost::isr(BusPort& bus) {
  interrupts.emplace_back(bus.cycle(), bus.chip().peek_reg(RegId::Int_Reg));
  hal::Scope scope(bus, &sink_);
  fw_.isr();
}

std::string FirmwareHost::hw_input(const std::string& name, std::uint32_t value) {
  const int r = fw_.hw_input != nullptr ? fw_.hw_input(name.c_str(), value) : -1;
  if (r == -1) return "unknown hardware input '" + name + "' of " + fw_.name;
  if (r == -2) return "value " + std::to_string(value) + " out of range for " + name;
  return {};
}

std::int64_t FirmwareHost::port(const std::string& name) const {
  for (unsigned i = 0; fw_.ports[i] != nullptr; ++i) {
    if (name == fw_.ports[i]) return i < values_.size() ? values_[i] : 0;
  }
  return -1;
}

std::string FirmwareHost::port_name(unsigned port) const {
  for (unsigned i = 0; fw_.ports[i] != nullptr; ++i) {
    if (i == port) return fw_.ports[i];
  }
  return "port" + std::to_string(port);
}

}  // namespace dpc31
