#include "station.hpp"

#include <fmt/format.h>

#include <utility>

#include "dpc31/bus_port.hpp"

namespace dpc31::bridge {

std::string_view UserSide::name() const {
  return firmware ? std::string_view(firmware->firmware().name) : kResponderName;
}

UserSide make_user_side(Chip& chip, const SlaveSpec& s, bool on_segment) {
  UserSide u;
  DirectBus bus(chip);
  if (s.firmware != nullptr) {
    u.firmware = std::make_unique<FirmwareHost>(*s.firmware);
    if (on_segment) u.firmware->name_station(s.address);
    u.firmware->init(bus, s.address);
    u.program = u.firmware->program();
    return u;
  }
  ResponderConfig rc;
  rc.slave.address = s.address;
  rc.user_watchdog = s.user_watchdog;
  rc.user_wd_value = s.user_wd_value;
  u.responder = std::make_unique<Responder>(rc);
  u.responder->init(bus);
  Responder* r = u.responder.get();
  // The loop-back: the outputs of the last DX_Out are the inputs handed over at the next. What
  // the responder records is taken here, so a bridge running for days does not grow.
  u.program.isr = [r](BusPort& b) {
    r->isr(b);
    if (!r->outputs.empty()) r->set_inputs(std::move(r->outputs.back().data));
    r->outputs.clear();
    r->interrupts.clear();
  };
  return u;
}

std::string stations_problem(std::span<const SlaveSpec> slaves) {
  for (std::size_t i = 0; i < slaves.size(); ++i) {
    for (std::size_t k = 0; k < i; ++k) {
      if (slaves[k].address == slaves[i].address) {
        return fmt::format(
            "--slave {}: a second station at address {} (two stations at one address both "
            "answer: a collision on every request)",
            slaves[i].address, slaves[i].address);
      }
    }
  }
  return {};
}

}  // namespace dpc31::bridge
