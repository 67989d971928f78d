#pragma once

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/dp.hpp"
#include "spec.hpp"

namespace testutil {

// Collects the chip's log so tests can assert what was reported.
struct LogCapture {
  std::vector<dpc31::LogRecord> records;
  void attach(dpc31::Chip& c) {
    c.set_log_sink([this](const dpc31::LogRecord& r) { records.push_back(r); });
  }
  [[nodiscard]] std::size_t count_containing(const std::string& s) const {
    std::size_t n = 0;
    for (const auto& r : records) n += r.text.find(s) != std::string::npos ? 1 : 0;
    return n;
  }
  void clear() { records.clear(); }
};

// Two chip log lines a test can repeat through the bus: an info line, a read of RAM the user must
// not touch (the profile's last reserved RAM region), and a debug line, a write of 1 to a bit
// Int_Ack_Reg ignores (emu/bus.cpp; docs/timing.md "acknowledge exceptions"), Intel mode: the
// register's low byte at the lower address. 0 where the profile has none.
struct RepeatableLogLines {
  std::uint32_t info_read = 0;
  std::uint32_t debug_write = 0;
  std::uint8_t debug_value = 0;
  explicit RepeatableLogLines(const dpc31::ProfileDesc& p) {
    for (const dpc31::RegionDesc& g : p.regions)
      if (g.ram && g.reserved) info_read = g.begin;
    const dpc31::RegDesc* ack = dpc31::find_reg(p, dpc31::RegId::Int_Ack_Reg);
    if (ack == nullptr || ack->ign == 0) return;
    const int bit = std::countr_zero(ack->ign);
    debug_write = static_cast<std::uint32_t>(ack->write_addr + bit / 8);
    debug_value = static_cast<std::uint8_t>(1u << (bit % 8));
  }
};

inline std::string pname(dpc31::Profile p) { return std::string(dpc31::profile_desc(p).name); }

// Test names of a (profile, baud rate) parameter: "spc3_1500000".
inline std::string profile_rate_name(
    const ::testing::TestParamInfo<std::tuple<dpc31::Profile, std::uint32_t>>& i) {
  return pname(std::get<0>(i.param)) + "_" + std::to_string(std::get<1>(i.param));
}

// Two chips in the same state (save_state), or the first byte where their snapshots differ.
inline ::testing::AssertionResult same_state(const dpc31::Chip& a, const dpc31::Chip& b) {
  const std::vector<std::uint8_t> x = a.save_state();
  const std::vector<std::uint8_t> y = b.save_state();
  if (x == y) return ::testing::AssertionSuccess();
  std::size_t i = 0;
  while (i < x.size() && i < y.size() && x[i] == y[i]) ++i;
  return ::testing::AssertionFailure() << "snapshots differ from byte " << i << " of " << x.size()
                                       << " / " << y.size() << " at cycle " << a.cycle();
}

struct ChipParam {
  dpc31::Profile profile;
  dpc31::BusMode bus;
};

inline std::string param_name(const ::testing::TestParamInfo<ChipParam>& i) {
  return pname(i.param.profile) + (i.param.bus == dpc31::BusMode::intel ? "_intel" : "_motorola");
}

inline std::vector<ChipParam> all_chip_params() {
  std::vector<ChipParam> v;
  for (dpc31::Profile p : dpc31::kAllProfiles) {
    v.push_back({p, dpc31::BusMode::intel});
    v.push_back({p, dpc31::BusMode::motorola});
  }
  return v;
}

// A fresh chip of the test's profile and bus mode, its log captured.
class ChipTest : public ::testing::TestWithParam<ChipParam> {
 protected:
  dpc31::Chip make(std::uint32_t clock_hz = 0) {
    dpc31::Chip c({GetParam().profile, GetParam().bus, clock_hz});
    log_.attach(c);
    return c;
  }
  LogCapture log_;
};

// Front-door access of a whole register through the bus, with the manuals' byte order.
inline std::uint16_t bus_read16(dpc31::Chip& c, int addr, int width) {
  if (width == 8) return c.read(static_cast<std::uint32_t>(addr));
  std::uint16_t v = 0;
  for (int off = 0; off < 2; ++off) {
    v = static_cast<std::uint16_t>(v | c.read(static_cast<std::uint32_t>(addr + off))
                                           << (8 * spec::byte_index_at(c.bus_mode(), off)));
  }
  return v;
}

inline void bus_write16(dpc31::Chip& c, int addr, int width, std::uint16_t v) {
  if (width == 8) {
    c.write(static_cast<std::uint32_t>(addr), static_cast<std::uint8_t>(v));
    return;
  }
  for (int off = 0; off < 2; ++off) {
    c.write(static_cast<std::uint32_t>(addr + off),
            static_cast<std::uint8_t>(v >> (8 * spec::byte_index_at(c.bus_mode(), off))));
  }
}

// The user's start, stop and Leave_Master as the profile takes them: Mode_Reg1_S bits 0, 2, 3 on
// the SPC3 and the VPC3+, a request through the Instruction_Queue on the DPC31 (p.22, Table
// 5.1-3: MAC_Start, MAC_Stop, User_Leave_Master), whose Mode_Reg1 has no such bits. The queue is
// the one the chip has (a Responder sets one up); without one, a ring of 4 entries at 1F00h is
// set up first. Returns the cycle the command acted: the completion of its last write.
inline std::uint64_t user_command(dpc31::Chip& c, std::uint8_t mode_reg1_bit,
                                  std::uint8_t request) {
  using dpc31::RegId;
  auto cell = [&](RegId id) { return static_cast<std::uint32_t>(c.addr_of(id)); };
  if (c.profile().id != dpc31::Profile::dpc31) {
    c.write(cell(RegId::Mode_Reg1_S), mode_reg1_bit);
    return c.cycle();
  }
  if (c.peek(cell(RegId::InstQ_Len)) == 0) {
    c.write(cell(RegId::InstQ_Base), 0xF8);
    c.write(cell(RegId::InstQ_Len), 4);
  }
  const dpc31::Chip::RequestSlot slot = *c.next_request_slot();
  c.write(slot.entry, request);
  c.write(slot.entry + 1, 0x00);
  c.write(cell(RegId::InstQ_Wr), slot.next_wr);
  return c.cycle();
}
inline std::uint64_t user_start(dpc31::Chip& c) {
  return user_command(c, 0x01, dpc31::request::MAC_Start);  // Start_SPC3
}
inline std::uint64_t user_go_offline(dpc31::Chip& c) {
  return user_command(c, 0x04, dpc31::request::MAC_Stop);  // Go_Offline
}
inline std::uint64_t user_leave_master(dpc31::Chip& c) {
  return user_command(c, 0x08, dpc31::request::User_Leave_Master);
}

}  // namespace testutil
