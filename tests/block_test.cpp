// The bus's fast paths against their references, by exact comparison (issue 19 items 2 and 3):
// - PlainPath: the event engine stores and loads plain registers and RAM straight
//   (RegDesc::plain, emu/bus.cpp); the per-cycle engine keeps the reference path. The same
//   accesses on both give the same values, cycles, X/INT changes, log and final state.
// - BlockTransfer: Chip::write_block & co., the host CPU's block transfers and the C HAL's
//   CopyToVpc3 & co. against the same accesses made byte by byte (docs/timing.md, "Block
//   transfers"): each access 4 clocks, in order, whatever the block crosses.
#include <gtest/gtest.h>
#include <setjmp.h>

#include <cstdint>
#include <string>
#include <vector>

#include "bytewise_bus.hpp"
#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/dpc31_hal.h"
#include "dpc31/reg_fields.hpp"
#include "heap_in_use.hpp"
#include "responder.hpp"

namespace {

using namespace dpc31;

// A chip and everything a user can see of it without watching the bus (an observer of bus
// accesses or state changes turns the fast paths off): the log and the X/INT changes.
struct Seen {
  explicit Seen(ChipOptions o) : chip(o) {
    chip.set_log_sink([this](const LogRecord& r) {
      log.push_back(std::to_string(r.cycle) + " " + std::to_string(static_cast<int>(r.level)) +
                    " " + r.text);
    });
    chip.on_irq_change([this](std::uint64_t cycle, bool active) {
      irq.push_back(std::to_string(cycle) + (active ? " on" : " off"));
    });
  }
  Chip chip;
  std::vector<std::string> log;
  std::vector<std::string> irq;
};

void expect_same(Seen& a, Seen& b, const std::string& where) {
  ASSERT_EQ(a.chip.cycle(), b.chip.cycle()) << where;
  ASSERT_EQ(a.log, b.log) << where;
  ASSERT_EQ(a.irq, b.irq) << where;
  ASSERT_EQ(a.chip.irq_active(), b.chip.irq_active()) << where;
  const std::uint32_t size = 1u << a.chip.profile().address_bits;
  for (std::uint32_t addr = 0; addr < size; ++addr)
    ASSERT_EQ(a.chip.peek(addr), b.chip.peek(addr)) << where << " at " << addr;
  for (const RegDesc& r : a.chip.profile().regs)
    ASSERT_EQ(a.chip.peek_reg(r.id), b.chip.peek_reg(r.id)) << where << " " << r.name;
}

std::uint32_t addr_of(const Chip& c, RegId id) { return static_cast<std::uint32_t>(c.addr_of(id)); }

struct Lcg {
  std::uint32_t s;
  std::uint32_t next() { return s = s * 1664525u + 1013904223u; }
};

// --- the plain path ---

// Random reads, writes and steps on every profile and bus mode, half of them at a register's
// addresses: the event engine (plain path) and the per-cycle engine (reference) agree on every
// value read, the cycle, the log, every X/INT change and the final registers and RAM.
TEST(PlainPath, EveryAccessAsTheReferenceEngine) {
  for (Profile p : kAllProfiles) {
    for (BusMode m : {BusMode::intel, BusMode::motorola}) {
      Seen fast({p, m, 0, Engine::event});
      Seen ref({p, m, 0, Engine::per_cycle});
      std::vector<std::uint32_t> reg_bytes;
      for (const RegDesc& r : fast.chip.profile().regs) {
        for (int b = 0; b < r.bytes(); ++b) {
          if (r.read_addr >= 0) reg_bytes.push_back(static_cast<std::uint32_t>(r.read_addr + b));
          if (r.write_addr >= 0) reg_bytes.push_back(static_cast<std::uint32_t>(r.write_addr + b));
        }
      }
      const std::uint32_t space = (1u << fast.chip.profile().address_bits) + 16;
      Lcg rng{static_cast<std::uint32_t>(p) * 2 + static_cast<std::uint32_t>(m) + 1};
      for (int i = 0; i < 20000; ++i) {
        const std::uint32_t r = rng.next() >> 8;
        const std::uint32_t addr =
            (r & 1) != 0 ? reg_bytes[(r >> 1) % reg_bytes.size()] : (r >> 1) % space;
        const auto value = static_cast<std::uint8_t>(rng.next() >> 13);
        switch ((rng.next() >> 10) % 10) {
          case 0:
            fast.chip.step(value);
            ref.chip.step(value);
            break;
          case 1:
          case 2:
          case 3:
          case 4:
            fast.chip.write(addr, value);
            ref.chip.write(addr, value);
            break;
          default:
            ASSERT_EQ(fast.chip.read(addr), ref.chip.read(addr))
                << profile_name(p) << " read " << addr << " at step " << i;
        }
        ASSERT_EQ(fast.chip.cycle(), ref.chip.cycle()) << profile_name(p) << " step " << i;
      }
      expect_same(fast, ref,
                  std::string(profile_name(p)) + (m == BusMode::intel ? " intel" : " motorola"));
    }
  }
}

// Int_Mask_Reg is plain (its reserved bits included): unmasking a pending event makes X/INT
// active at the end of the write, masking it again inactive (docs/timing.md, "Interrupt line");
// a write that would change the reserved bits 7..5 is logged and ignored (spc3 p.23), as the
// reference path does.
TEST(PlainPath, MaskWritesMoveXIntAtTheirCycleAndReservedChangesAreLogged) {
  for (Profile p : kAllProfiles) {
    Seen s({p, BusMode::intel, 0, Engine::event});
    const std::uint32_t irr = addr_of(s.chip, RegId::Int_Req_Reg);
    const std::uint32_t imr = addr_of(s.chip, RegId::Int_Mask_Reg);
    s.chip.write(irr, 0x01);  // MAC_Reset, raised by the user for test (SPC3 p.23)
    ASSERT_FALSE(s.chip.irq_active());
    s.chip.write(imr, 0xFE);  // unmask bit 0; the reserved bits 7..5 stay 1
    EXPECT_EQ(s.irq, std::vector<std::string>{"8 on"});
    s.chip.write(imr, 0xFF);
    EXPECT_EQ(s.irq, (std::vector<std::string>{"8 on", "12 off"}));
    EXPECT_TRUE(s.log.empty());
    if (p != Profile::spc3) continue;  // bits 5 and 6 are events on the VPC3+ and the DPC31
    s.chip.write(imr, 0x1F);           // would clear the reserved bits
    ASSERT_EQ(s.log.size(), 1u);
    EXPECT_NE(s.log[0].find("Int_Mask_Reg: write would change reserved bits"), std::string::npos)
        << s.log[0];
    EXPECT_EQ(s.chip.peek_reg(RegId::Int_Mask_Reg) & 0xFF, 0x1Fu);  // reserved bits read 0
  }
}

// --- block transfers on the chip ---

// One block operation on `a` and the same accesses byte by byte on `b`.
struct Pair {
  explicit Pair(ChipOptions o) : a(o), b(o) {}
  void write(std::uint32_t addr, const std::vector<std::uint8_t>& v) {
    a.chip.write_block(addr, v);
    for (std::size_t i = 0; i < v.size(); ++i)
      b.chip.write(addr + static_cast<std::uint32_t>(i), v[i]);
  }
  std::vector<std::uint8_t> read(std::uint32_t addr, std::size_t n) {
    std::vector<std::uint8_t> va(n);
    a.chip.read_block(addr, va);
    std::vector<std::uint8_t> vb(n);
    for (std::size_t i = 0; i < n; ++i) vb[i] = b.chip.read(addr + static_cast<std::uint32_t>(i));
    EXPECT_EQ(va, vb);
    return va;
  }
  void fill(std::uint32_t addr, std::uint8_t v, std::size_t n) {
    a.chip.fill(addr, v, n);
    for (std::size_t i = 0; i < n; ++i) b.chip.write(addr + static_cast<std::uint32_t>(i), v);
  }
  bool equal(std::uint32_t x, std::uint32_t y, std::size_t n) {
    const bool ea = a.chip.equal(x, y, n);
    bool eb = true;
    for (std::size_t i = 0; i < n && eb; ++i) {
      const std::uint8_t first = b.chip.read(x + static_cast<std::uint32_t>(i));
      eb = first == b.chip.read(y + static_cast<std::uint32_t>(i));
    }
    EXPECT_EQ(ea, eb);
    return ea;
  }
  Seen a;
  Seen b;
};

std::vector<std::uint8_t> pattern(std::size_t n, std::uint8_t seed) {
  std::vector<std::uint8_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(seed + 7 * i);
  return v;
}

// Every profile, both engines: blocks in user RAM with an event inside (the end of the EOI
// inactive time, where X/INT becomes active again), blocks over the register area and the
// organisational cells, over the DPC31's hooked cell InstQ_Wr, into the RAM access violation
// (SPC3, VPC3+) and beyond the address bus. Same cycle, values, log, X/INT and state as the bytes
// one by one, and the same snapshot.
TEST(BlockTransfer, SameAsByteByByteOnEveryProfile) {
  for (Profile p : kAllProfiles) {
    for (Engine e : {Engine::event, Engine::per_cycle}) {
      Pair s({p, BusMode::intel, 0, e});
      const std::string where =
          std::string(profile_name(p)) + (e == Engine::event ? " event" : " per-cycle");
      const ProfileDesc& prof = s.a.chip.profile();
      const std::uint32_t user = prof.user_base + 0x40;
      const std::uint32_t end = 1u << prof.address_bits;
      const auto eoi = [&] {
        const std::uint32_t m1s = addr_of(s.a.chip, RegId::Mode_Reg1_S);
        s.a.chip.write(m1s, fields::Mode_Reg1_S::EOI);
        s.b.chip.write(m1s, fields::Mode_Reg1_S::EOI);
      };
      // A pending, unmasked event: X/INT active; EOI makes it inactive for 1 us (48 clocks).
      for (Seen* c : {&s.a, &s.b}) {
        c->chip.write(addr_of(c->chip, RegId::Int_Req_Reg), 0x01);
        c->chip.write(addr_of(c->chip, RegId::Int_Mask_Reg), 0xFE);
      }
      eoi();
      s.write(user, pattern(200, 1));  // X/INT active again inside the block
      expect_same(s.a, s.b, where + " write");
      ASSERT_EQ(s.a.irq.size(), 3u) << where;
      EXPECT_EQ(s.read(user, 200), pattern(200, 1));
      eoi();
      s.fill(user + 200, 0x5A, 100);
      eoi();
      EXPECT_TRUE(s.equal(user, user, 150));
      s.write(user + 300, pattern(50, 1));
      eoi();
      EXPECT_FALSE(s.equal(user, user + 300, 120));  // 50 equal pairs, then the first difference
      EXPECT_FALSE(s.equal(user + 200, user, 10));
      expect_same(s.a, s.b, where + " RAM");
      // The register area and the cells: every register's own access, in order.
      s.read(0, prof.user_base + 8);
      s.write(addr_of(s.a.chip, RegId::Int_Mask_Reg) - 2, pattern(8, 0xE0));
      s.fill(prof.cells_base, 0x00, 16);
      expect_same(s.a, s.b, where + " registers");
      if (p == Profile::dpc31) {
        const std::uint32_t instq = addr_of(s.a.chip, RegId::InstQ_Wr);
        s.write(instq - 4, pattern(9, 0x00));  // InstQ_Wr executes the queue (a cell hook)
        expect_same(s.a, s.b, where + " InstQ_Wr");
      }
      if (prof.violation_from != 0) {  // wraps, logs, takes a started chip offline
        s.write(prof.violation_from - 4, pattern(8, 3));
        s.read(prof.violation_from - 4, 8);
        expect_same(s.a, s.b, where + " violation");
      }
      s.write(end - 4, pattern(8, 9));  // beyond the address bus: upper bits ignored, logged
      s.fill(end - 2, 0x33, 4);
      s.read(end - 4, 8);
      EXPECT_TRUE(s.equal(end - 8, end + (1u << 20) - 8, 4));
      expect_same(s.a, s.b, where + " beyond the bus");
      s.read(0, end);  // the whole address space at once
      EXPECT_EQ(s.a.chip.save_state(), s.b.chip.save_state()) << where;
      EXPECT_FALSE(s.a.log.empty()) << where;  // the out-of-range accesses were logged
    }
  }
}

// --- block transfers of firmware on the host CPU ---

struct Session {
  Session(Profile p, std::uint32_t baud, std::uint8_t len, bool blocks)
      : cfg(config(len)),
        chip({p, BusMode::intel, 0}),
        user(cfg),
        master(chip, {2, baud, 100, 33}, cfg.slave) {
    chip.set_log_sink(nullptr);
    user.set_inputs(pattern(len, 0x40));
    DirectBus bus(chip);
    user.init(bus);
    master.set_firmware([this, blocks](BusPort& b) {
      if (blocks) {
        user.isr(b);
      } else {
        BytewiseBus w(b);
        user.isr(w);
      }
    });
  }
  static ResponderConfig config(std::uint8_t len) {
    ResponderConfig rc;
    rc.user_watchdog = true;
    rc.slave.in_len = len;
    rc.slave.out_len = len;
    return rc;
  }
  ResponderConfig cfg;
  Chip chip;
  Responder user;
  DpMaster master;
};

// The responder's buffer copies as block transfers and byte by byte, on the host CPU behind the
// built-in master: the same interrupts at the same cycles, the same outputs and answers, the
// same chip at the end. At 12 Mbaud the firmware's copies overlap the answer on the line.
TEST(BlockTransfer, HostCpuFirmwareSameAsByteByByte) {
  for (Profile p : kAllProfiles) {
    for (const std::uint32_t baud : {12000000u, 1500000u}) {
      // Three Dout and three Din buffers fit the SPC3's 1.5 kB of RAM at 64 bytes.
      const std::uint8_t len = p == Profile::spc3 ? 64 : 244;
      Session blk(p, baud, len, true);
      Session byte(p, baud, len, false);
      ASSERT_TRUE(blk.master.startup(5000)) << profile_name(p);
      ASSERT_TRUE(byte.master.startup(5000)) << profile_name(p);
      for (int i = 0; i < 5; ++i) {
        const std::vector<std::uint8_t> out = pattern(len, static_cast<std::uint8_t>(i));
        const Exchange x = blk.master.data_exchange(out);
        const Exchange y = byte.master.data_exchange(out);
        ASSERT_TRUE(x.answer.has_value()) << profile_name(p);
        ASSERT_EQ(x.answer, y.answer) << profile_name(p);
        ASSERT_EQ(x.answer_start, y.answer_start) << profile_name(p);
        ASSERT_EQ(x.answer_end, y.answer_end) << profile_name(p);
        ASSERT_EQ(blk.chip.cycle(), byte.chip.cycle()) << profile_name(p) << " exchange " << i;
      }
      ASSERT_EQ(blk.user.interrupts, byte.user.interrupts) << profile_name(p);
      ASSERT_EQ(blk.user.outputs.size(), byte.user.outputs.size());
      for (std::size_t i = 0; i < blk.user.outputs.size(); ++i) {
        EXPECT_EQ(blk.user.outputs[i].cycle, byte.user.outputs[i].cycle);
        EXPECT_EQ(blk.user.outputs[i].data, byte.user.outputs[i].data);
      }
      EXPECT_EQ(blk.chip.dp_state(), DpState::Data_Exchange) << profile_name(p);
      EXPECT_EQ(blk.chip.save_state(), byte.chip.save_state()) << profile_name(p);
    }
  }
}

// --- the C HAL ---

// CopyToVpc3 & co. against Vpc3Read / Vpc3Write one byte at a time, on two handles: the same
// values and cycles, a block that wraps at 16 bits (the drivers' addresses) included.
TEST(BlockTransfer, HalFunctionsSameAsByteByByte) {
  for (const char* prof : {"spc3", "vpc3plus", "dpc31"}) {
    dpc31_chip* a = dpc31_create(prof, 0);
    dpc31_chip* b = dpc31_create(prof, 0);
    const std::vector<std::uint8_t> v = pattern(64, 0x21);
    const auto both = [&](auto block, auto bytes) {
      dpc31_select(a);
      block();
      dpc31_select(b);
      bytes();
      ASSERT_EQ(dpc31_cycle(a), dpc31_cycle(b)) << prof;
    };
    const std::uint16_t base = std::string(prof) == "dpc31" ? 0x0900 : 0x0100;  // user RAM
    both(
        [&] {
          CopyToVpc3(reinterpret_cast<std::uint8_t*>(std::uintptr_t{base}),
                     const_cast<std::uint8_t*>(v.data()), 64);
        },
        [&] {
          for (std::uint16_t i = 0; i < 64; ++i)
            Vpc3Write(static_cast<std::uint16_t>(base + i), v[i]);
        });
    std::vector<std::uint8_t> ra(64);
    std::vector<std::uint8_t> rb(64);
    both(
        [&] { CopyFromVpc3(ra.data(), reinterpret_cast<std::uint8_t*>(std::uintptr_t{base}), 64); },
        [&] {
          for (std::uint16_t i = 0; i < 64; ++i)
            rb[i] = Vpc3Read(static_cast<std::uint16_t>(base + i));
        });
    EXPECT_EQ(ra, v);
    EXPECT_EQ(rb, v);
    both([&] { Vpc3MemSet(static_cast<std::uint16_t>(base + 64), 0xA5, 32); },
         [&] {
           for (std::uint16_t i = 0; i < 32; ++i)
             Vpc3Write(static_cast<std::uint16_t>(base + 64 + i), 0xA5);
         });
    std::uint8_t ca = 0;
    both(
        [&] {
          ca = Vpc3MemCmp(reinterpret_cast<std::uint8_t*>(std::uintptr_t{base}),
                          reinterpret_cast<std::uint8_t*>(std::uintptr_t{base + 64u}), 32);
        },
        [&] {
          (void)Vpc3Read(base);
          (void)Vpc3Read(static_cast<std::uint16_t>(base + 64));
        });
    EXPECT_EQ(ca, 1);  // the first pair differs: two reads
    // Wrapping at 16 bits: FFFEh, FFFFh, then 0000h, 0001h (registers).
    dpc31_select(nullptr);
    const std::uint8_t w[4] = {0xFF, 0xFF, 0x00, 0x00};
    dpc31_copy_to(a, 0xFFFE, w, 4);
    for (std::uint16_t i = 0; i < 4; ++i)
      dpc31_write(b, static_cast<std::uint16_t>(0xFFFE + i), w[i]);
    EXPECT_EQ(dpc31_cycle(a), dpc31_cycle(b));
    const std::uint32_t size = std::string(prof) == "spc3"       ? 0x800
                               : std::string(prof) == "vpc3plus" ? 0x1000
                                                                 : 0x2000;
    for (std::uint32_t addr = 0; addr < size; ++addr)
      ASSERT_EQ(dpc31_peek(a, static_cast<std::uint16_t>(addr)),
                dpc31_peek(b, static_cast<std::uint16_t>(addr)))
          << prof << " " << addr;
    dpc31_destroy(a);
    dpc31_destroy(b);
  }
}

// A NULL local buffer with a length is a programming error: the error handler gets a message
// naming the function (default: printed, then abort), never a read of address 0.
TEST(BlockTransferDeathTest, NullLocalBufferIsReported) {
  dpc31_chip* c = dpc31_create("dpc31", 0);
  EXPECT_DEATH(dpc31_copy_to(c, 0x0900, nullptr, 4), "dpc31_copy_to: local buffer is NULL");
  dpc31_select(c);
  EXPECT_DEATH(CopyFromVpc3(nullptr, reinterpret_cast<std::uint8_t*>(std::uintptr_t{0x0900}), 4),
               "CopyFromVpc3: local buffer is NULL with length 4");
  CopyToVpc3(reinterpret_cast<std::uint8_t*>(std::uintptr_t{0x0900}), nullptr,
             0);  // nothing to copy
  EXPECT_EQ(dpc31_cycle(c), 0u);
  dpc31_destroy(c);
}

// s33 audit finding 1: the local buffer and the chip pointer swapped (both uint8_t *) read or wrote
// host memory at a chip address: SIGSEGV. A chip pointer holds a chip address, 0x0000..0xFFFF
// (dpc31_hal.h); a local buffer never lies there. Either the other way round is the handler's
// message, naming the function and the pointer, before any access.
TEST(BlockTransferDeathTest, SwappedPointersAreReported) {
  dpc31_chip* c = dpc31_create("dpc31", 0);
  const auto chip_ptr = [](std::uintptr_t a) { return reinterpret_cast<std::uint8_t*>(a); };
  std::uint8_t local[4] = {1, 2, 3, 4};
  EXPECT_DEATH(dpc31_copy_to(c, 0x0900, chip_ptr(0x40), 4),
               "dpc31_copy_to: local buffer 0x40 is a chip address \\(0x0000..0xFFFF\\), not host "
               "memory: the arguments swapped\\?");
  dpc31_select(c);
  EXPECT_DEATH(CopyToVpc3(local, chip_ptr(0x40), 4),
               "CopyToVpc3: chip pointer 0x[0-9a-f]+ is not a chip address \\(0x0000..0xFFFF\\): "
               "the arguments swapped\\?");
  EXPECT_DEATH(CopyFromVpc3(chip_ptr(0x0900), local, 4), "CopyFromVpc3: chip pointer 0x[0-9a-f]+ ");
  EXPECT_DEATH(CopyFromVpc3(chip_ptr(0x0040), chip_ptr(0x0900), 4),
               "CopyFromVpc3: local buffer 0x40 is a chip address");
  EXPECT_DEATH(Vpc3MemCmp(chip_ptr(0x0900), local, 1), "Vpc3MemCmp: chip pointer 0x[0-9a-f]+ ");
  EXPECT_DEATH(Vpc3MemCmp(chip_ptr(0x10000), chip_ptr(0x0900), 1),
               "Vpc3MemCmp: chip pointer 0x10000 is not a chip address");
  // The last chip address is one; a block of no bytes touches nothing, whatever its pointers.
  EXPECT_EQ(Vpc3MemCmp(chip_ptr(0xFFFF), chip_ptr(0xFFFF), 1), 0);
  EXPECT_EQ(dpc31_cycle(c), 8u);  // two reads, 4 clocks each (docs/timing.md)
  CopyToVpc3(local, chip_ptr(0x40), 0);
  EXPECT_EQ(dpc31_cycle(c), 8u);
  dpc31_select(nullptr);
  dpc31_destroy(c);
}

}  // namespace

// dpc31_hal.h: "Calling Vpc3Read & co. ... with no chip selected is a programming error: the
// handler gets a message; the default prints it to stderr and aborts." The message names the
// function, also after the selected chip was destroyed; a chip selected again is reached.
TEST(HalSelection, AccessWithNoChipSelectedIsAnError) {
  EXPECT_DEATH(Vpc3Write(0x04, 0xE0),
               "dpc31 HAL: Vpc3Write called with no chip selected \\(dpc31_select\\)");
  EXPECT_DEATH((void)Vpc3Read(0x00),
               "dpc31 HAL: Vpc3Read called with no chip selected \\(dpc31_select\\)");
  struct HalError {
    std::string what;
  };
  dpc31_set_error_handler([](const char* message) { throw HalError{message}; });
  dpc31_chip* c = dpc31_create("dpc31", 0);
  dpc31_select(c);
  Vpc3Write(0x04, 0xE5);  // Int_Mask_Reg, reserved bits 7..5 kept 1
  const std::uint64_t cycle = dpc31_cycle(c);
  dpc31_destroy(c);  // also deselects it
  std::string error;
  try {
    Vpc3Write(0x04, 0xE0);
  } catch (const HalError& e) {
    error = e.what;
  }
  EXPECT_EQ(error, "Vpc3Write called with no chip selected (dpc31_select)");
  error.clear();
  try {
    (void)Vpc3Read(0x00);
  } catch (const HalError& e) {
    error = e.what;
  }
  EXPECT_EQ(error, "Vpc3Read called with no chip selected (dpc31_select)");
  dpc31_set_error_handler(nullptr);
  dpc31_chip* d = dpc31_create("dpc31", 0);
  dpc31_select(d);
  Vpc3Write(0x04, 0xE5);
  EXPECT_EQ(dpc31_cycle(d), cycle);  // one access, 4 clocks on each chip
  dpc31_destroy(d);
}

// A NULL handle is a misuse the handler hears of, not a crash; dpc31_destroy(NULL) does nothing,
// as free(NULL) and dpc31_module_destroy(NULL) (the clean-up path after a failed create).
TEST(HalSelection, ANullHandleIsAnErrorAndDestroyingNullDoesNothing) {
  dpc31_destroy(nullptr);
  EXPECT_DEATH((void)dpc31_read(nullptr, 0),
               "dpc31 HAL: dpc31_read called with a NULL chip handle");
  struct HalError {
    std::string what;
  };
  dpc31_set_error_handler([](const char* message) { throw HalError{message}; });
  const auto error = [](auto&& f) {
    try {
      f();
    } catch (const HalError& e) {
      return e.what;
    }
    return std::string("no error");
  };
  EXPECT_EQ(error([] { (void)dpc31_cycle(nullptr); }),
            "dpc31_cycle called with a NULL chip handle");
  EXPECT_EQ(error([] { dpc31_run(nullptr, 1); }), "dpc31_run called with a NULL chip handle");
  EXPECT_EQ(error([] { dpc31_write(nullptr, 0, 0); }),
            "dpc31_write called with a NULL chip handle");
  EXPECT_EQ(error([] { dpc31_set_irq_callback(nullptr, nullptr, nullptr); }),
            "dpc31_set_irq_callback called with a NULL chip handle");
  dpc31_set_error_handler(nullptr);
}

// dpc31_hal.h: the handler must not return; one that does gets a line saying so, then the abort.
TEST(HalSelection, AHandlerThatReturnsAbortsWithALineSayingSo) {
  EXPECT_DEATH(
      {
        dpc31_set_error_handler([](const char*) {});
        (void)Vpc3Read(0);
      },
      "dpc31 HAL: the error handler returned from .Vpc3Read called with no chip selected "
      "\\(dpc31_select\\).; it must not \\(exit, longjmp\\): aborting");
}

// A C handler may longjmp out: nothing between the access function and the handler owns memory
// that the jump would leak (the message is the thread's buffer).
jmp_buf g_hal_jump;
TEST(HalSelection, LongjmpOutOfTheHandlerLeaksNothing) {
  if (!test::kHeapCounted) GTEST_SKIP() << "ASan's allocator is not malloc's";
  dpc31_set_error_handler([](const char*) { longjmp(g_hal_jump, 1); });
  std::int64_t before = 0;
  for (int i = 0; i < 1001; ++i) {
    if (i == 1) before = test::heap_in_use();  // after the first error's lazy set-up, if any
    // The message is longer than any short-string buffer.
    if (setjmp(g_hal_jump) == 0) (void)Vpc3Read(0);
  }
  const std::int64_t grown = test::heap_in_use() - before;
  dpc31_set_error_handler(nullptr);
  EXPECT_LE(grown, 0);
}
