// The C++ side of the C HAL (include/dpc31/dpc31_hal.h): which bus the driver-shaped access
// functions (Vpc3Read & co.) and dpc31_port_write reach on the calling thread.
#pragma once

#include <cstdint>
#include <functional>

#include "dpc31/bus_port.hpp"

namespace dpc31::hal {

// While alive, Vpc3Read & co. on this thread access `bus`, port writes go to `ports` and a
// misuse of the HAL goes to `errors` (nullptr: the process's error handler); the previous
// selection comes back afterwards (scopes nest).
class Scope {
 public:
  Scope(BusPort& bus, const PortSink* ports, const ErrorSink* errors = nullptr);
  ~Scope();
  Scope(const Scope&) = delete;
  Scope& operator=(const Scope&) = delete;

 private:
  Selection prev_;
};

}  // namespace dpc31::hal
