// The register file: the latches behind the register ports, the RAM with its organisational
// cells, and the address decode of the profile (chip-facts §1, regs/dpc31_regs.json). The blocks
// keep their parameters and buffers here as the chip does; the CPU's accesses with their hooks and
// QEMU's write rule are the chip's bus side (emu/bus.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string_view>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/reg_ids.hpp"
#include "dpc31/regdesc.hpp"
#include "folded_log.hpp"
#include "signals.hpp"

namespace dpc31 {

inline constexpr std::uint16_t kNoReg = 0xFFFF;

class RegisterFile {
 public:
  struct State {
    std::array<std::uint16_t, kRegIdCount> latch{};
    std::vector<std::uint8_t> mem;  // 2^address_bits bytes; only RAM regions are used as RAM
    bool large_ram = false;         // VPC3+ 4kB_Mode
    bool ram_access_violation = false;
  };

  RegisterFile(const ProfileDesc& prof, BusMode bus, const Signals& sig);
  void reset();  // zeros, then every reset value of the description

  [[nodiscard]] const ProfileDesc& profile() const { return *prof_; }
  [[nodiscard]] Profile id() const { return prof_->id; }
  [[nodiscard]] BusMode bus() const { return bus_; }
  [[nodiscard]] const RegDesc* reg(RegId id) const {
    const std::uint16_t i = reg_index_[idx(id)];
    return i == kNoReg ? nullptr : &prof_->regs[i];
  }
  static constexpr std::size_t idx(RegId id) { return static_cast<std::size_t>(id); }

  // The latch behind a register (storage of latch, port target and derived-with-storage kinds).
  [[nodiscard]] std::uint16_t latch(RegId id) const { return s_.latch[idx(id)]; }
  std::uint16_t& latch(RegId id) { return s_.latch[idx(id)]; }
  [[nodiscard]] bool mode0(std::uint16_t bit) const { return (latch(RegId::Mode_Reg0) & bit) != 0; }

  // Organisational cells in RAM (8 bit, or 16 bit placed by the bus mode).
  [[nodiscard]] std::uint8_t cell(RegId id) const;
  void set_cell(RegId id, std::uint8_t v);
  void swap_cells(RegId a, RegId b);
  [[nodiscard]] std::uint16_t cell16(const RegDesc& r) const;
  void set_cell16(const RegDesc& r, std::uint16_t v);

  // Raw RAM by decoded address (the bus side and the back door).
  [[nodiscard]] std::uint8_t mem(std::uint32_t a) const { return s_.mem[a]; }
  void set_mem(std::uint32_t a, std::uint8_t v) { s_.mem[a] = v; }
  std::uint8_t* mem_at(std::uint32_t a) { return &s_.mem[a]; }  // block transfers (bus.cpp)

  // The ASIC's own RAM accesses (buffers): the same decode and violation as the bus.
  [[nodiscard]] std::uint32_t segment_shift() const;
  [[nodiscard]] std::uint32_t buffer_addr(RegId ptr_cell) const;
  std::uint8_t ram_read(std::uint32_t addr);
  void ram_write(std::uint32_t addr, std::uint8_t v);
  // A buffer the ASIC uses over the registers (its pointer 00h, the reset value, or any segment
  // below the first RAM cell) keeps its bytes in the RAM behind them, which the CPU does not see
  // there (modelled): each use is logged, through the warnings' limiter.
  void clear_buffer(RegId ptr_cell, std::size_t len);
  // The same for a buffer the ASIC reaches otherwise (the DPC31's queues, the VPC3+'s SAP list
  // and its Ind / Resp buffers): `pointer` names what holds `value`, called only when `base` is
  // over the registers (over_registers), so a caller builds that name only then.
  [[nodiscard]] bool over_registers(std::uint32_t base) const { return base < registers_end_; }
  void note_buffer(std::string_view pointer, std::uint8_t value, std::uint32_t base);
  void note_buffer(RegId ptr_cell, std::uint32_t base, std::size_t len);
  void write_buffer(RegId ptr_cell, std::span<const std::uint8_t> bytes);
  // `len` bytes into `out` (its old contents replaced, its capacity kept).
  void read_buffer(RegId ptr_cell, std::size_t len, std::vector<std::uint8_t>& out);

  // Address decode: the address bus width and the RAM access violation (the access wraps).
  std::uint32_t decode(std::uint32_t addr, bool& violation) const {
    const std::uint32_t a = addr & ((1u << prof_->address_bits) - 1u);
    violation = prof_->violation_from != 0 && a >= prof_->violation_from && !s_.large_ram;
    return violation ? a - prof_->violation_subtract : a;
  }
  // One past the last address that decodes as itself (no violation, inside the address bus).
  [[nodiscard]] std::uint32_t undecoded_end() const {
    return prof_->violation_from != 0 && !s_.large_ram ? prof_->violation_from
                                                       : 1u << prof_->address_bits;
  }
  void note_violation(std::uint32_t addr, std::uint32_t mapped);
  [[nodiscard]] bool ram_access_violation() const { return s_.ram_access_violation; }
  void clear_ram_access_violation() { s_.ram_access_violation = false; }
  // VPC3+ 4kB_Mode: the RAM decode follows Mode_Reg2, written over the bus or poked.
  void follow_mode2(std::uint16_t mode2) {
    s_.large_ram = prof_->ram_size_large != 0 && (mode2 & fields::Mode_Reg2::_4kB_Mode) != 0;
  }
  // A violation takes a started chip offline: wired by the chip to the mode block.
  std::function<void()> on_violation;

  // Decode tables: address -> index into profile().regs or regions (kNoReg: none).
  [[nodiscard]] std::uint16_t read_index(std::uint32_t a) const { return rd_map_[a]; }
  [[nodiscard]] std::uint16_t write_index(std::uint32_t a) const { return wr_map_[a]; }
  [[nodiscard]] std::uint16_t region_index(std::uint32_t a) const { return region_map_[a]; }

 private:
  friend struct BlockAccess;
  const ProfileDesc* prof_;
  BusMode bus_;
  const Signals* sig_;
  std::uint32_t registers_end_ = 0;  // one past the non-RAM regions from address 0 (registers)
  FoldedLog over_registers_;         // buffers used there, by address: a log, not chip state
  State s_;
  std::vector<std::uint16_t> rd_map_;
  std::vector<std::uint16_t> wr_map_;
  std::vector<std::uint16_t> region_map_;
  std::array<std::uint16_t, kRegIdCount> reg_index_{};  // RegId -> index into prof_->regs
};

}  // namespace dpc31
