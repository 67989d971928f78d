// The example firmware (firmware/) on the host CPU against the built-in master, and the GSD
// files as a configuration tool reads them: shared by tests/firmware_test.cpp and the
// conformance suite (tests/conformance/).
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cnt2/cnt2.h"
#include "do4/do4.h"
#include "dp_master.hpp"
#include "firmware.h"
#include "firmware_host.hpp"

namespace firmware_bench {

using namespace dpc31;

inline SlaveConfig gsd_slave(const dpc31_firmware& fw, std::uint8_t address) {
  SlaveConfig s;
  s.address = address;
  return with_gsd_defaults(fw, s);
}

// A built-in firmware's instance on a host, as its type (firmware.h), and its driver's counters.
inline do4* do4_of(const FirmwareHost& h) { return static_cast<do4*>(h.instance()); }
inline cnt2* cnt2_of(const FirmwareHost& h) { return static_cast<cnt2*>(h.instance()); }
inline const dps_stats* stats_of(const FirmwareHost& h) {
  return dps_get_stats(static_cast<dps*>(h.instance()));  // the driver comes first (dps.h)
}

// One chip, one firmware on its host CPU, the built-in master.
struct Bench {
  Bench(Profile p, const dpc31_firmware& fw, SlaveConfig slave, std::uint32_t baud)
      : Bench(ChipOptions{p, BusMode::intel}, fw, std::move(slave), baud) {}
  Bench(const ChipOptions& o, const dpc31_firmware& fw, SlaveConfig slave, std::uint32_t baud)
      : chip(o), host(fw), master(chip, MasterConfig{2, baud, 100, 33}, slave) {
    chip.on_irq_change([this](std::uint64_t cycle, bool active) {
      if (active) activations.push_back(cycle);
    });
    chip.on_bus_access([this](std::uint64_t, const BusAccess& a) {
      if (in_init_) init_accesses.push_back(a);
    });
    DirectBus bus(chip);
    host.init(bus, slave.address);
    in_init_ = false;
    master.set_firmware([this](BusPort& b) { host.isr(b); });
  }
  std::optional<FirmwareHost::PortWrite> last_write(unsigned port) const {
    const auto& w = host.port_writes();
    for (auto it = w.rbegin(); it != w.rend(); ++it) {
      if (it->port == port) return *it;
    }
    return std::nullopt;
  }
  // The request was acted on at the stop sample of its last character: end - T + floor(T/2).
  std::uint64_t acted(const Exchange& ex) const {
    return ex.request_end - master.bit_cycles() + master.bit_cycles() / 2;
  }
  Chip chip;
  FirmwareHost host;
  DpMaster master;
  std::vector<std::uint64_t> activations;  // X/INT going active: the ISR starts there
  std::vector<BusAccess> init_accesses;    // the firmware's init (it starts the chip)

 private:
  bool in_init_ = true;
};

// The GSD keys of the ten baud rates and the rates.
inline constexpr std::pair<const char*, std::uint32_t> kGsdRates[] = {
    {"9.6_supp", 9600},     {"19.2_supp", 19200},  {"45.45_supp", 45450},  {"93.75_supp", 93750},
    {"187.5_supp", 187500}, {"500_supp", 500000},  {"1.5M_supp", 1500000}, {"3M_supp", 3000000},
    {"6M_supp", 6000000},   {"12M_supp", 12000000}};

struct Gsd {
  std::map<std::string, std::string> keys;
  std::vector<std::uint8_t> module_cfg;
  std::vector<std::uint8_t> prm_const;
  struct Param {
    int offset;  // into the user parameter bytes (Ext_User_Prm_Data_Ref)
    int def, min, max;
  };
  std::map<int, Param> params;  // by ExtUserPrmData number
};

inline std::vector<std::uint8_t> hex_list(const std::string& s) {
  std::vector<std::uint8_t> v;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    v.push_back(static_cast<std::uint8_t>(std::stoul(item, nullptr, 0)));
  return v;
}

inline std::string trim(std::string s) {
  const auto b = s.find_first_not_of(" \t\r");
  const auto e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

// The subset of the GSD grammar these files use; anything else fails the test.
inline Gsd load_gsd(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  Gsd g;
  std::string line;
  int param = -1;
  while (std::getline(in, line)) {
    line = trim(line.substr(0, line.find(';')));
    if (line.empty() || line == "#Profibus_DP" || line == "EndModule" || line == "EndPrmText")
      continue;
    if (line == "EndExtUserPrmData") {
      param = -1;
      continue;
    }
    if (param >= 0 && line.rfind("Unsigned8 ", 0) == 0) {
      int def = 0, lo = 0, hi = 0;
      EXPECT_EQ(std::sscanf(line.c_str(), "Unsigned8 %d %d-%d", &def, &lo, &hi), 3) << line;
      g.params[param].def = def;
      g.params[param].min = lo;
      g.params[param].max = hi;
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;  // Text(k) lines of a PrmText block have '=' too
    const std::string key = trim(line.substr(0, eq));
    const std::string value = trim(line.substr(eq + 1));
    if (key == "Module") {
      g.module_cfg = hex_list(value.substr(value.rfind('"') + 1));
    } else if (key == "ExtUserPrmData") {
      param = std::stoi(value);
    } else if (key == "Ext_User_Prm_Data_Const(0)") {
      g.prm_const = hex_list(value);
    } else if (key.rfind("Ext_User_Prm_Data_Ref(", 0) == 0) {
      g.params[std::stoi(value)].offset = std::stoi(key.substr(22));
    } else {
      g.keys[key] = value;
    }
  }
  return g;
}

// The slave as a configuration tool sets the master up from the GSD file: its Ident_Number,
// the module's Cfg bytes and the user parameters at their defaults (Ext_User_Prm_Data_Const
// with every Ext_User_Prm_Data_Ref at its default value).
inline SlaveConfig gsd_configured_slave(const dpc31_firmware& fw, const Gsd& g,
                                        std::uint8_t address) {
  SlaveConfig s = gsd_slave(fw, address);
  s.ident = static_cast<std::uint16_t>(std::stoul(g.keys.at("Ident_Number"), nullptr, 0));
  s.cfg = g.module_cfg;
  s.user_prm = g.prm_const;
  for (const auto& [n, p] : g.params)
    s.user_prm.at(static_cast<std::size_t>(p.offset)) = static_cast<std::uint8_t>(p.def);
  return s;
}

}  // namespace firmware_bench
