// Shared set-up of the conformance tests: a chip, the minimal user side (Responder) and the
// built-in master on RxD/TxD, with the bit time T = round(48 MHz / baud) of docs/timing.md.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/reg_ids.hpp"
#include "responder.hpp"
#include "test_util.hpp"

namespace conformance {

using Bytes = std::vector<std::uint8_t>;

// The telegram bits the tests send, typed here once from the standard and the manual (the oracle,
// not the emulator's own constants): Set_Prm's Station_Status (EN 50170) and Global_Control's
// Control_Command (DPC31 HW description p.32, seed 003).
inline constexpr std::uint8_t kLock_Req = 0x80, kUnlock_Req = 0x40, kWD_On = 0x08;
inline constexpr std::uint8_t kGC_Sync = 0x20, kGC_Unsync = 0x10, kGC_Freeze = 0x08,
                              kGC_Unfreeze = 0x04, kGC_Clear_Data = 0x02;

inline std::uint32_t T_of(std::uint32_t baud) {
  return static_cast<std::uint32_t>((48'000'000u + baud / 2) / baud);
}

// A DP slave on the wire: the chip, the user side and a class-1 master (address 2).
struct Bench {
  dpc31::Chip chip;
  dpc31::Responder user;
  dpc31::DpMaster master;

  explicit Bench(dpc31::Profile p, std::uint32_t baud = 1'500'000, dpc31::ResponderConfig rc = {},
                 dpc31::BusMode bus = dpc31::BusMode::intel, std::uint8_t master_address = 2)
      : chip({p, bus, 0}),
        user(rc),
        master(init(chip, user, rc.slave.in_len),
               dpc31::MasterConfig{master_address, baud, 100, 33}, user_slave(rc)) {
    master.set_firmware([this](dpc31::BusPort& c) { user.isr(c); });
  }
  static dpc31::SlaveConfig user_slave(const dpc31::ResponderConfig& rc) { return rc.slave; }
  // The inputs A1, A2, ... of the slave's length (A1..A4 by default).
  static dpc31::Chip& init(dpc31::Chip& c, dpc31::Responder& u, std::size_t in_len) {
    c.set_log_sink(nullptr);
    std::vector<std::uint8_t> in(in_len);
    for (std::size_t i = 0; i < in_len; ++i) in[i] = static_cast<std::uint8_t>(0xA1 + i);
    u.set_inputs(std::move(in));
    dpc31::DirectBus bus(c);
    u.init(bus);
    return c;
  }
  [[nodiscard]] std::uint32_t T() const { return master.bit_cycles(); }
  // The cycle a request is acted on: the stop-bit sample of its last character (timing.md).
  [[nodiscard]] std::uint64_t acted(const dpc31::Exchange& ex) const {
    return ex.request_end - T() + T() / 2;
  }
};

inline Bytes wire(const std::optional<dpc31::fdl::Frame>& f) {
  return f ? dpc31::fdl::encode(*f) : Bytes{};
}

}  // namespace conformance

namespace conformance {

// A user side that only acknowledges and EOIs (Int_Ack_Reg, Mode_Reg1_S.EOI), recording the
// Int_Reg it saw: the buffers are left for the test to drive over the bus.
struct AckOnly {
  std::vector<std::pair<std::uint64_t, std::uint16_t>> seen;  // cycle, Int_Reg at ISR entry
  void isr(dpc31::BusPort& c) {
    const dpc31::Chip& chip = c.chip();
    const auto ir_addr = static_cast<std::uint32_t>(chip.addr_of(dpc31::RegId::Int_Reg));
    const auto ack_addr = static_cast<std::uint32_t>(chip.addr_of(dpc31::RegId::Int_Ack_Reg));
    const std::uint16_t ir = testutil_read16(c, ir_addr);
    seen.emplace_back(c.cycle(), ir);
    // New_Prm_Data / New_Cfg_Data clear only through their OK reads (SPC3 p.22).
    const auto ack =
        static_cast<std::uint16_t>(ir & ~(dpc31::irq::New_Prm_Data | dpc31::irq::New_Cfg_Data));
    if (ack != 0) {
      c.write(ack_addr, static_cast<std::uint8_t>(ack));
      c.write(ack_addr + 1, static_cast<std::uint8_t>(ack >> 8));
    }
    c.write(static_cast<std::uint32_t>(chip.addr_of(dpc31::RegId::Mode_Reg1_S)), 0x02);  // EOI
  }
  // Intel byte order (the benches here use the Intel bus).
  static std::uint16_t testutil_read16(dpc31::BusPort& c, std::uint32_t a) {
    const std::uint8_t lo = c.read(a);
    return static_cast<std::uint16_t>(lo | c.read(a + 1) << 8);
  }
};

// The bus address of a register of the bench's chip.
inline std::uint32_t addr(const dpc31::Chip& c, dpc31::RegId id) {
  return static_cast<std::uint32_t>(c.addr_of(id));
}

// The RAM address a buffer pointer cell names (segment << shift), read over the bus.
inline std::uint32_t buffer_base(dpc31::Chip& c, dpc31::RegId ptr_cell) {
  return static_cast<std::uint32_t>(c.read(addr(c, ptr_cell))) << c.profile().segment_shift;
}

// `n` bytes from RAM over the bus.
inline Bytes read_ram(dpc31::Chip& c, std::uint32_t base, std::size_t n) {
  Bytes out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(c.read(base + static_cast<std::uint32_t>(i)));
  return out;
}

inline dpc31::RegId dout_ptr(unsigned buffer) {
  static constexpr dpc31::RegId kPtr[] = {
      dpc31::RegId::R_Dout_Buf_Ptr1, dpc31::RegId::R_Dout_Buf_Ptr2, dpc31::RegId::R_Dout_Buf_Ptr3};
  return kPtr[buffer - 1];
}

}  // namespace conformance
