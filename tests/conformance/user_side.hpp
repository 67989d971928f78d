// What the user has, for the conformance tests: the register addresses of the profile, bus
// reads of Status_Reg and Int_Req_Reg, the DP SAP numbers (chip-facts §8), and a bench whose
// user side is the test itself (no ISR runs: the test reads and writes the chip at the cycles
// it chooses).
#pragma once

#include <cstdint>
#include <vector>

#include "conformance.hpp"
#include "dpc31/dp.hpp"

namespace conformance {

// DP SAPs at the slave (chip-facts §8, EN 50170); the master's SSAP is 62.
namespace dsap = dpc31::sap;

// Address of a register's read side (or its write side if it has none).
inline std::uint32_t rd(const dpc31::Chip& c, dpc31::RegId id) {
  const dpc31::RegDesc* r = dpc31::find_reg(c.profile(), id);
  return static_cast<std::uint32_t>(r->read_addr >= 0 ? r->read_addr : r->write_addr);
}
inline std::uint32_t wr(const dpc31::Chip& c, dpc31::RegId id) {
  const dpc31::RegDesc* r = dpc31::find_reg(c.profile(), id);
  return static_cast<std::uint32_t>(r->write_addr >= 0 ? r->write_addr : r->read_addr);
}

// Status_Reg, Int_Req_Reg, Int_Reg through the bus (two 4-clock reads).
inline std::uint16_t status(dpc31::Chip& c) {
  return testutil::bus_read16(c, static_cast<int>(rd(c, dpc31::RegId::Status_Reg)), 16);
}
inline std::uint16_t irr(dpc31::Chip& c) {
  return testutil::bus_read16(c, static_cast<int>(rd(c, dpc31::RegId::Int_Req_Reg)), 16);
}
// Status_Reg bits 5:4 (DP_State) and 7:6 (WD_State), chip-facts §3.
inline int dp_bits(std::uint16_t s) { return (s >> 4) & 3; }
inline int wd_bits(std::uint16_t s) { return (s >> 6) & 3; }
inline constexpr int kWaitPrm = 0, kWaitCfg = 1, kDataEx = 2;
inline constexpr int kBaudSearch = 0, kBaudControl = 1, kDpControl = 2;

// A chip set up by the minimal driver (Responder::init: buffers, Start_SPC3) and the master,
// with no ISR: every interrupt stays for the test to see and handle.
struct Bare {
  dpc31::Chip chip;
  dpc31::Responder user;
  dpc31::DpMaster master;

  explicit Bare(dpc31::Profile p, std::uint32_t baud = 12'000'000, dpc31::ResponderConfig rc = {})
      : chip({p, dpc31::BusMode::intel, 0}),
        user(rc),
        master(Bench::init(chip, user, rc.slave.in_len), dpc31::MasterConfig{2, baud, 100, 33},
               rc.slave) {}
  [[nodiscard]] std::uint32_t T() const { return master.bit_cycles(); }
  [[nodiscard]] std::uint64_t acted(const dpc31::Exchange& ex) const {
    return ex.request_end - T() + T() / 2;
  }
  // A DP request with SAPs, FCV = 0 (never a repeat), as any master would send it.
  dpc31::Exchange sap_request(std::uint8_t dsap_, Bytes du, std::uint8_t from = 2) {
    return master.transact(dpc31::fdl::make_frame(
        master.target(), from,
        dpc31::fdl::make_request_fc(dpc31::fdl::Function::SRD_high, false, false), std::move(du),
        dsap_, dsap::Master));
  }
};

// The start-up with the test as the user: FDL_Status, Set_Prm, Prm OK (0Eh), Chk_Cfg, Cfg OK
// (10h), then the first inputs: `inputs` (if any) into U (Din_Buffer_SM bits 5:4) and
// New_Din_Buffer_Cmd (09h), with which the SPC3 enters Data_Exchange (SPC3 p.31).
inline void start_by_hand(Bare& b, const Bytes& inputs = {}) {
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  ASSERT_EQ(b.chip.read(0x0E), 0x00);
  b.master.chk_cfg();
  ASSERT_EQ(b.chip.read(0x10), 0x00);
  static constexpr dpc31::RegId kPtr[] = {
      dpc31::RegId::R_Din_Buf_Ptr1, dpc31::RegId::R_Din_Buf_Ptr2, dpc31::RegId::R_Din_Buf_Ptr3};
  const unsigned u = (b.chip.read(0x08) >> 4) & 3u;
  const std::uint32_t base = buffer_base(b.chip, kPtr[u - 1]);
  for (std::size_t k = 0; k < inputs.size(); ++k)
    b.chip.write(base + static_cast<std::uint32_t>(k), inputs[k]);
  b.chip.read(0x09);
}

// The minimal driver's ISR (Responder::isr) logs each entry with the cycle after its two Int_Reg
// reads: X/INT went active, and the ISR started, 2 x 4 clocks earlier (docs/timing.md).
inline constexpr std::uint64_t kIrRead = 8;

// Whether the ISR started at `cycle` and saw all of `bits` in Int_Reg.
inline bool isr_saw(const dpc31::Responder& u, std::uint64_t cycle, std::uint16_t bits) {
  for (const auto& [at, ir] : u.interrupts) {
    if (at == cycle + kIrRead && (ir & bits) == bits) return true;
  }
  return false;
}

// The first ISR start after `after`, or 0.
inline std::uint64_t first_isr_after(const dpc31::Responder& u, std::uint64_t after) {
  for (const auto& [at, ir] : u.interrupts) {
    if (at - kIrRead > after) return at - kIrRead;
  }
  return 0;
}

// FC of a short answer (SD1) or of a data answer: what the response code says (chip-facts §8).
inline constexpr std::uint8_t kFcOk = 0x00, kFcRR = 0x02, kFcRS = 0x03, kFcDL = 0x08, kFcDH = 0x0A;

}  // namespace conformance
