// Register description tables: the compiled form of regs/dpc31_regs.json.
// The tables themselves are generated (build/generated/reg_tables.cpp) by tools/reggen; this header
// only declares their shape. Nothing here is written by hand per register.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

// RegId is declared opaque here so the generator can use these types before the ids exist;
// the generated "dpc31/reg_ids.hpp" completes it with one enumerator per register name.

namespace dpc31 {

enum class RegId : std::uint16_t;

enum class Profile : std::uint8_t { spc3, vpc3plus, dpc31 };
inline constexpr Profile kAllProfiles[] = {Profile::spc3, Profile::vpc3plus, Profile::dpc31};

enum class BusMode : std::uint8_t { intel, motorola };

// Where a register's value lives.
enum class Kind : std::uint8_t {
  latch,     // flip-flops inside the chip (IRR, IMR, Mode_Reg0, ...)
  cell,      // a RAM cell with a fixed meaning (organisational parameters)
  derived,   // read side computed by the owning block (Int_Reg, Status_Reg, *_Buffer_SM, commands)
  port,      // write side acting on another register (Int_Ack_Reg -> Int_Req_Reg, Mode_Reg1_S/_R)
  reserved,  // a documented gap: reads 00h, writes ignored; every access logged by name
};

// Per-bit access policy, SystemRDL/UVM vocabulary where it exists.
enum class Access : std::uint8_t {
  RO,     // read only (writes have no effect)
  RW,     // read/write storage
  W1C,    // write 1 clears the bit of the target (Int_Ack_Reg, Mode_Reg1_R)
  W1S,    // write 1 sets the bit of the target (Mode_Reg1_S)
  CMD,    // command-on-read: reading performs an action, the value is its result
  WO,     // write only storage (read side of the address is another register)
  IGN,    // documented as "no effect when written" (IAR bits of New_Prm/New_Cfg); logged
  RSVD,   // reserved: reads 0, not writable; a write that would change it is logged
  UNIMP,  // exists on the chip, behaviour not modelled (DXB); stored, logged on every access
};

enum class Block : std::uint8_t { irq, mode, status, buffers, dp_sm, watchdog, fdl, ram, requests };

struct FieldDesc {
  std::string_view name;
  std::uint8_t lsb;
  std::uint8_t width;
  Access access;
  bool pulse;  // self-clearing: the chip clears the bit again (EOI, User_Leave_Master)
  std::string_view desc;
};

struct RegDesc {
  RegId id;
  std::string_view name;
  Kind kind;
  Block block;
  std::uint8_t width;  // 8 or 16 bits
  bool has_reset;      // false for command reads (reading them has side effects)
  std::uint16_t reset;
  std::int32_t read_addr;   // physical byte address of the lowest byte, -1 = none
  std::int32_t write_addr;  // -1 = none
  RegId target;             // storage register acted on (ports); == id otherwise
  // Per-bit policy masks, derived from the fields (bit set = policy applies to that bit).
  std::uint16_t ro, rw, w1c, w1s, cmd, wo, ign, rsvd, unimp, pulse;
  // Byte placement of 16-bit values: byte index (0 = bits 7..0, 1 = bits 15..8) found at
  // addr + 0 and addr + 1, for each bus mode. For 8-bit registers {0, 0}.
  std::uint8_t intel[2];
  std::uint8_t motorola[2];
  bool documented;  // true: fact from the manuals; false: our modelled choice (see note)
  std::string_view source;
  std::string_view note;
  std::string_view desc;
  std::span<const FieldDesc> fields;
  bool reserved = false;  // kind cell only: a RAM cell the manuals mark reserved (accesses logged)
  // The name this profile's own manual gives the register, where it differs (the DPC31's
  // User_New_Dout_Cmd for Next_Dout_Buffer_Cmd); the C header and find_reg know it too.
  std::string_view alias{};
  // The byte lanes (bit 0: bits 7..0, bit 1: bits 15..8; the address of each lane follows from
  // the bus mode's placement) whose CPU accesses are plain storage by the description: a latch
  // whose lane has no W1C, W1S, CMD, IGN or pulse bit and a register without UNIMP bits, or a RAM
  // cell the manuals do not mark reserved. Reserved bits may be in a plain lane: a write that
  // leaves them as they are is a straight store, one that would change them takes the reference
  // path, which logs it (docs/decisions.md). The chip adds what the description does not know:
  // a lane is stored straight only if no block installed a hook on the register (emu/bus.cpp).
  std::uint8_t plain = 0;

  [[nodiscard]] constexpr int bytes() const { return width / 8; }
  [[nodiscard]] constexpr std::uint16_t mask() const {
    return width == 16 ? std::uint16_t{0xFFFF} : std::uint16_t{0x00FF};
  }
  [[nodiscard]] constexpr const std::uint8_t* placement(BusMode m) const {
    return m == BusMode::intel ? intel : motorola;
  }
};

// A contiguous memory region of a profile.
struct RegionDesc {
  std::string_view
      name;             // "register area", "internal work cells", "organisational parameters", ...
  std::uint32_t begin;  // first address
  std::uint32_t end;    // one past the last address
  bool ram;             // backed by RAM (peek/poke/walk) or not
  bool reserved;        // accesses logged (the user must not touch)
  std::string_view desc;
};

// A structure the firmware lays out in RAM and the chip reads there (the VPC3+'s SAP-list entry
// and the header of its DPV1 buffers): no fixed address, so its C macros are byte offsets, bit
// masks and codes.
struct LayoutValue {
  std::string_view name;
  std::uint8_t value;
  bool mask;  // a bit mask (macro suffix _Msk), else a code the byte may hold
  std::string_view desc;
};
struct LayoutByte {
  std::string_view name;
  std::uint8_t offset;
  std::string_view desc;
  std::span<const LayoutValue> values;
};
struct LayoutDesc {
  std::string_view name;  // macro infix: P_<name>_<byte>
  std::uint8_t size;      // bytes of the structure
  std::string_view source;
  std::string_view desc;
  std::span<const LayoutByte> bytes;
};

struct ProfileDesc {
  Profile id;
  std::string_view name;   // "spc3"
  std::string_view title;  // "Siemens SPC3"
  std::string_view macro;  // C macro prefix "SPC3"
  std::uint8_t address_bits;
  std::uint32_t ram_begin;       // first RAM address
  std::uint32_t ram_size;        // bytes of RAM (normal mode)
  std::uint32_t ram_size_large;  // bytes of RAM with VPC3+ 4kB_Mode (0 = no such mode)
  std::uint32_t cells_base;      // physical address of organisational cell 16h
  std::uint32_t user_base;       // first byte of the user buffer area
  std::uint8_t segment_shift;    // buffer pointer -> physical address shift
  std::uint8_t segment_shift_large;
  std::uint32_t violation_from;  // first address that is a RAM access violation (0 = none)
  std::uint32_t violation_subtract;
  std::uint8_t release;            // Status_Reg bits 15..12
  std::uint8_t bus_access_cycles;  // clocks one bus access takes (docs/timing.md)
  std::string_view note;
  std::span<const RegDesc> regs;
  std::span<const RegionDesc> regions;
  std::span<const LayoutDesc> layouts{};
};

// Clock and timing constants from the description (docs/timing.md).
struct ChipTiming {
  std::uint32_t clock_hz;
};

const ProfileDesc& profile_desc(Profile p);
const ChipTiming& chip_timing();
const RegDesc* find_reg(const ProfileDesc& p, RegId id);
const RegDesc* find_reg(const ProfileDesc& p, std::string_view name);
bool parse_profile(std::string_view s, Profile& out);
std::string_view access_name(Access a);
std::string_view kind_name(Kind k);
std::string_view block_name(Block b);
// Counterparts of the *_name functions (exact spelling as in regs/dpc31_regs.json) and the
// one-line meaning of each kind / access policy (legend of docs/registers.md). Defined with the
// *_name functions and find_reg in tools/reggen/regdesc.cpp (library dpc31_regfmt).
std::string_view profile_name(Profile p);  // "spc3", "vpc3plus", "dpc31"
bool parse_kind(std::string_view s, Kind& out);
bool parse_access(std::string_view s, Access& out);
bool parse_block(std::string_view s, Block& out);
std::string_view kind_desc(Kind k);
std::string_view access_desc(Access a);

}  // namespace dpc31
