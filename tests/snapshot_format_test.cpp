// The snapshot format (docs/snapshots.md): a round trip, the header, the sections' sizes, and
// files that are bad or crafted refused with the chip left as it was.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "harness.hpp"
#include "snapshot_session.hpp"
#include "test_util.hpp"

using namespace dpc31;
using namespace snapshot_session;

namespace {

TEST(SnapshotFormat, RoundTripGivesIdenticalBytes) {
  for (const Profile p : kAllProfiles) {
    SCOPED_TRACE(testutil::pname(p));
    Chip fresh({p, BusMode::intel, 0});
    Chip again({p, BusMode::intel, 0});
    again.load_state(fresh.save_state());
    EXPECT_EQ(again.save_state(), fresh.save_state());

    const Chip busy = mid_session(p);
    const Bytes s = busy.save_state();
    Chip c({p, BusMode::intel, 0});
    c.load_state(s);
    EXPECT_EQ(c.save_state(), s);
    EXPECT_EQ(c.cycle(), busy.cycle());
    EXPECT_EQ(memory_image(c), memory_image(busy));
  }
}

// An event latched in the save cycle still survives an acknowledge landing in that cycle (the
// lockstep harness strobes accesses per cycle, docs/timing.md "Order within one cycle").
TEST(SnapshotFormat, EventOfTheSaveCycleSurvivesAnAcknowledgeAfterLoad) {
  Chip a({Profile::spc3, BusMode::intel, 0});
  a.set_log_sink(nullptr);
  a.step(100);
  harness::asic_raise(a, irq::User_Timer_Clock);
  Chip b({Profile::spc3, BusMode::intel, 0});
  b.set_log_sink(nullptr);
  b.load_state(a.save_state());
  for (Chip* c : {&a, &b}) {
    harness::core(*c).write_now(static_cast<std::uint32_t>(c->addr_of(RegId::Int_Ack_Reg)),
                                static_cast<std::uint8_t>(irq::User_Timer_Clock));
    EXPECT_NE(c->peek_reg(RegId::Int_Req_Reg) & irq::User_Timer_Clock, 0u);
  }
}

TEST(SnapshotFormat, HeaderFields) {
  const Chip c({Profile::vpc3plus, BusMode::motorola, 20'000'000});
  const Bytes s = c.save_state();
  ASSERT_GE(s.size(), snap::kHeaderSize);
  EXPECT_EQ(std::string(s.begin(), s.begin() + 8), "DPC31SNP");
  EXPECT_EQ(s[8], snap::kFormatVersion);
  EXPECT_EQ(s[12], static_cast<std::uint8_t>(Profile::vpc3plus));
  EXPECT_EQ(s[13], static_cast<std::uint8_t>(BusMode::motorola));
  EXPECT_EQ(s[16] | s[17] << 8 | s[18] << 16 | s[19] << 24, 20'000'000);
  std::uint64_t length = 0;
  for (int i = 0; i < 8; ++i) length |= std::uint64_t{s[24 + i]} << (8 * i);
  EXPECT_EQ(length, s.size() - snap::kHeaderSize);
  // CRC-32 check value of "123456789".
  const std::string check = "123456789";
  EXPECT_EQ(snap::crc32({reinterpret_cast<const std::uint8_t*>(check.data()), check.size()}),
            0xCBF43926u);
}

// Each section's size after reset, summed from docs/snapshots.md's table (counts are u32; cycles
// u64; `b` and `u8` one byte): a field the code writes and the table lacks shows here.
TEST(SnapshotFormat, AfterResetEachSectionHasTheSizeTheTableGives) {
  const std::vector<std::pair<std::string, std::size_t>> kSections = {
      {"CORE", 8 + 1 + 1 + 1 + 1 + 2 + 1 + 1 + 1 + 1 + 4 + 1},
      {"LTCH", 4 + 2 * kRegIdCount},
      {"MEM ", 0},  // 4 + 2^address_bits, below
      {"IRQC", 8 + 8 + 8 + 2},
      {"BUFS", 4 + 4 + 2 + 7},
      {"DPSM", 1 + 2 + 2 + 4 + 1 + 1 + 3 + 1 + 2 + 2 + 1 + 1 + 3 + 2 + 2 + 1 + 4 + 1},
      {"TIMR", 8 + 1 + 8 + 1 + 8 + 8 + 8},
      {"MAC ", 0},  // its own fields lie between FDLA and USMP
      {"UART", 4 + 1 + 8 + 8 + 4 + 8 + 2 + 8 + 4},
      {"FDLA", (4 + 4 + 1 + 1) + (3 + 8 + 1 + 8 + 4 + 4 + 8 + 1)},  // then the MAC's fields
      {"USMP",
       (4 + 3 + 4 + 8 + 8 + 2 + 8 + 8 + 8) + 3 * (1 + 4 + 4 + 4) + (1 + 4 + 4 + 4 + 4 + 4) + 1},
      {"CNTR", 20 * 4},
      {"RQIF", 8 + 8 + 2 + 1},
      {"SAPL", 1 + 1 + 4 + 4},
      {"LOGS", 5 + (8 + 1) + 3 * (8 + 4)}};
  for (const auto& [profile, mem, total] :
       {std::tuple{Profile::spc3, 2048u, 2867u}, std::tuple{Profile::vpc3plus, 4096u, 4915u},
        std::tuple{Profile::dpc31, 8192u, 9011u}}) {
    const Bytes s = Chip(ChipOptions{profile}).save_state();
    EXPECT_EQ(s.size(), total) << "docs/snapshots.md gives the size after reset";
    std::size_t at = snap::kHeaderSize;
    for (std::size_t i = 0; i < kSections.size(); ++i) {
      const auto& [tag, size] = kSections[i];
      ASSERT_LE(at + 4, s.size());
      ASSERT_EQ(std::string(s.begin() + static_cast<std::ptrdiff_t>(at),
                            s.begin() + static_cast<std::ptrdiff_t>(at + 4)),
                tag);
      at += 4 + (tag == "MEM " ? 4 + mem : size);
    }
    EXPECT_EQ(at, s.size()) << "the payload ends after LOGS";
  }
}

// Loading `bytes` into `c` throws a SnapshotError whose message contains `expected`, and leaves
// the chip as it was.
void expect_refused(Chip& c, const Bytes& bytes, const std::string& expected) {
  const Bytes before = c.save_state();
  try {
    c.load_state(bytes);
    ADD_FAILURE() << "accepted; expected: " << expected;
  } catch (const SnapshotError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos)
        << "message: " << e.what() << "\nexpected: " << expected;
  }
  EXPECT_EQ(c.save_state(), before) << "a refused snapshot changed the chip";
}

void set_le(Bytes& b, std::size_t off, std::uint64_t v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) b[off + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// Recomputes the CRC (a crafted file: the container is fine, the payload is not).
void reseal(Bytes& b) {
  set_le(b, 24, b.size() - snap::kHeaderSize, 8);
  const std::span<const std::uint8_t> all(b);
  const std::uint32_t crc = snap::crc32(all.subspan(snap::kHeaderSize), snap::crc32(all.first(32)));
  set_le(b, 32, crc, 4);
}

TEST(SnapshotFormat, BadFilesAreRefusedAndLeaveTheChipUnchanged) {
  Chip target = mid_session(Profile::dpc31);
  const Bytes good = target.save_state();
  target.step(1000);  // the chip that refuses is in another state than the snapshot
  ASSERT_NE(good, target.save_state());

  Bytes b = good;
  b[0] = 'X';
  expect_refused(target, b, "not a dpc31emu snapshot (bad magic)");
  expect_refused(target, Bytes{'h', 'e', 'l', 'l', 'o', '\n'}, "bad magic");

  b = good;
  set_le(b, 8, snap::kFormatVersion + 1, 4);
  expect_refused(target, b, "snapshot format version 8 is newer than this build reads (7)");
  set_le(b, 8, 0, 4);
  expect_refused(target, b, "snapshot format version 0 is not supported");

  for (std::size_t n = 0; n < good.size(); ++n) {
    SCOPED_TRACE(n);
    expect_refused(target, Bytes(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n)),
                   "truncated snapshot: ");
    if (HasFailure()) break;
  }

  b = good;
  b.push_back(0);
  expect_refused(target, b, "trailing garbage: the file is");

  for (std::size_t i = snap::kHeaderSize; i < good.size(); ++i) {
    b = good;
    b[i] ^= 0x10;
    expect_refused(target, b, "corrupted snapshot: CRC32");
    if (HasFailure()) break;
  }
  b = good;
  b[32] ^= 0xFF;
  expect_refused(target, b, "corrupted snapshot: CRC32");

  expect_refused(target, Chip({Profile::spc3, BusMode::intel, 0}).save_state(),
                 "snapshot of a spc3 chip cannot be loaded into a dpc31 chip");
  expect_refused(target, Chip({Profile::dpc31, BusMode::motorola, 0}).save_state(),
                 "snapshot of a chip on the motorola bus cannot be loaded into a chip on the "
                 "intel bus");
  expect_refused(target, Chip({Profile::dpc31, BusMode::intel, 20'000'000}).save_state(),
                 "snapshot of a chip clocked at 20000000 Hz cannot be loaded into a chip "
                 "clocked at 48000000 Hz");
  b = good;
  set_le(b, 20, 0x12345678, 4);
  reseal(b);
  expect_refused(target, b, "snapshot written with another register description");
  // The engine is read with the payload, after the header's checks (docs/snapshots.md).
  expect_refused(target, Chip({Profile::dpc31, BusMode::intel, 0, Engine::per_cycle}).save_state(),
                 "malformed snapshot payload (section CORE, byte 22): the snapshot is of the other "
                 "engine (event / per_cycle)");
}

TEST(SnapshotFormat, CraftedPayloadsAreRefusedNotLoaded) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  target.step(1000);
  const std::size_t payload = good.size() - snap::kHeaderSize;

  // A payload cut anywhere, with a header that agrees: the reader notices where it ends.
  for (std::size_t n = 0; n < payload; n += (n < 200 || n + 300 > payload) ? 1 : 37) {
    SCOPED_TRACE(n);
    Bytes b(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(snap::kHeaderSize + n));
    reseal(b);
    expect_refused(target, b, "malformed snapshot payload");
    if (HasFailure()) break;
  }
  Bytes b = good;
  b.push_back(0);
  reseal(b);
  expect_refused(target, b, "1 bytes after the last section");

  // Values no chip can hold. CORE: tag, now (8), started, violation, large_ram, baud_code.
  // A cycle past the chip's last (Chip::kLastCycle, 2^62 - 1): the next step would wrap it.
  b = good;
  b[snap::kHeaderSize + 4 + 7] = 0x40;  // little-endian: bit 62 set
  reseal(b);
  expect_refused(target, b, "out of range (at most 4611686018427387903)");
  b = good;
  b[snap::kHeaderSize + 4 + 8 + 3] = 10;
  reseal(b);
  expect_refused(target, b, "(section CORE, byte 16): value 10 out of range (at most 9)");
  b = good;
  b[snap::kHeaderSize + 4 + 8] = 2;
  reseal(b);
  expect_refused(target, b, "boolean 2 is neither 0 nor 1");
  b = good;
  b[snap::kHeaderSize] = 'K';
  reseal(b);
  expect_refused(target, b, "section 'CORE' expected at byte 0");

  // Random damage with a valid CRC: refused or loaded, never a crash or a half-loaded chip.
  std::mt19937 rng(31);
  int refused = 0;
  for (int k = 0; k < 2000; ++k) {
    b = good;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f) {
      b[snap::kHeaderSize + rng() % payload] = static_cast<std::uint8_t>(rng());
    }
    reseal(b);
    Chip c({Profile::spc3, BusMode::intel, 0});
    const Bytes before = c.save_state();
    try {
      c.load_state(b);
      EXPECT_EQ(c.save_state(), b);
    } catch (const SnapshotError&) {
      ++refused;
      EXPECT_EQ(c.save_state(), before);
    }
  }
  EXPECT_GT(refused, 0);
}

// Where section `tag` begins in a snapshot (its first occurrence: the sections come before any
// RAM bytes that could spell it only where the test looks after them).
std::size_t section_at(const Bytes& b, std::string_view tag) {
  const auto at = std::search(b.begin(), b.end(), tag.begin(), tag.end());
  EXPECT_NE(at, b.end()) << "no section " << tag;
  return static_cast<std::size_t>(at - b.begin());
}

// The answer kept for an FCB repetition is sent again as it is (DpStateMachine::service), so a
// snapshot whose kept answer is no valid telegram is refused: the chip would send it (found in
// the review of Fuzz.snapshot_loader's finding 9, docs/robustness.md). The kept answer is the
// DPSM section's only length-prefixed valid frame.
TEST(SnapshotFormat, AKeptAnswerThatIsNoTelegramIsRefused) {
  for (const Profile p : kAllProfiles) {
    SCOPED_TRACE(testutil::pname(p));
    Chip target = mid_session(p);
    const Bytes good = target.save_state();
    const std::size_t from = section_at(good, "DPSM"), to = section_at(good, "TIMR");
    ASSERT_LT(from, to);
    std::vector<std::pair<std::size_t, std::size_t>> kept;  // (first byte, length)
    for (std::size_t i = from; i + 4 < to; ++i) {
      const std::size_t n = good[i] | good[i + 1] << 8 | good[i + 2] << 16 | good[i + 3] << 24;
      if (n == 0 || i + 4 + n > to) continue;
      const std::span<const std::uint8_t> frame(good.data() + i + 4, n);
      if (fdl::decode(frame).error == fdl::Error::none) kept.emplace_back(i + 4, n);
    }
    ASSERT_EQ(kept.size(), 1u) << "the kept answer is not found in the snapshot";
    const auto [at, n] = kept.front();
    Bytes b = good;
    b[at + n - 1] ^= 0xFF;  // its last byte: the ED, or the short acknowledgement itself
    reseal(b);
    expect_refused(target, b, "the answer kept for a repetition is not a valid telegram");
    Chip again({p, BusMode::intel, 0});
    again.load_state(good);  // the one it really kept loads
    EXPECT_EQ(again.save_state(), good);
  }
}

// Where a snapshot's queue of line edges begins: its 32-bit count, found back from the field
// after it (`after` bytes before section `next`): count, then 9 bytes per edge (cycle, level).
std::size_t edge_queue_at(const Bytes& b, std::string_view next, std::size_t after) {
  const std::size_t end = section_at(b, next) - after;
  for (std::size_t n = 0; 9 * n + 4 <= end; ++n) {
    const std::size_t at = end - 9 * n - 4;
    if ((b[at] | b[at + 1] << 8 | b[at + 2] << 16 | std::size_t{b[at + 3]} << 24) == n) return at;
  }
  ADD_FAILURE() << "no edge queue before " << next;
  return 0;
}

std::uint64_t edge_cycle(const Bytes& b, std::size_t queue, std::size_t k) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < 8; ++i) v |= std::uint64_t{b[queue + 4 + 9 * k + i]} << (8 * i);
  return v;
}

// Chip::drive_rxd takes edges at non-decreasing cycles, and the chip's answer goes out in time
// order: a snapshot whose queued RxD or TxD edges run back in time is refused (the loader
// checked only that the RxD edges lie after the snapshot's cycle; found in the same review).
TEST(SnapshotFormat, LineEdgesOutOfTimeOrderAreRefused) {
  Chip target = mid_session(Profile::spc3);
  Bytes good = target.save_state();
  // CORE ends with the RxD queue and the line level (1 byte), then LTCH.
  const std::size_t rx = edge_queue_at(good, "LTCH", 1);
  ASSERT_GE(good[rx], 2u) << "the request on RxD has edges driven ahead";
  Bytes b = good;
  const std::uint64_t second = edge_cycle(good, rx, 1);
  set_le(b, rx + 4, second + 1, 8);  // the first edge after the second
  reseal(b);
  expect_refused(target, b, "RxD edges driven ahead out of time order");
  b = good;
  set_le(b, rx + 4, 0, 8);  // the first edge before the snapshot's cycle
  reseal(b);
  expect_refused(target, b, "or at or before the snapshot's cycle");

  Chip sending = mid_session(Profile::spc3, BusMode::intel, 0, true);
  good = sending.save_state();
  // The TxD queue: count, edges, then tx_next (4), tx_end (8), txd (1), then section USMP.
  const std::size_t tx = edge_queue_at(good, "USMP", 13);
  const std::size_t edges = good[tx] | good[tx + 1] << 8;
  const std::size_t next_at = tx + 4 + 9 * edges;
  const std::size_t next = good[next_at] | good[next_at + 1] << 8;
  ASSERT_GT(next, 0u) << "half the answer is out";
  ASSERT_LT(next + 1, edges) << "half the answer is still to come";
  b = good;
  set_le(b, tx + 4 + 9 * (next + 1), edge_cycle(good, tx, next) - 1, 8);  // before the one before
  reseal(b);
  expect_refused(sending, b, "TxD edges out of time order");
  b = good;
  set_le(b, next_at, 0, 4);  // the edges out already marked as still to come
  reseal(b);
  expect_refused(sending, b, "taken and to come on the wrong side of now");
  Chip again({Profile::spc3, BusMode::intel, 0});
  again.load_state(good);
  EXPECT_EQ(again.save_state(), good);
}

// Each latch is the register's flip-flops: no more bits than the register has (docs/registers.md
// gives the widths), none for a register the profile lacks. Fuzz.snapshot_loader's finding 9
// (docs/robustness.md): MinTSDR_Val (8 bits) loaded as FFFFh delayed the answer by 65 535 bit
// times, past what any request could explain.
TEST(SnapshotFormat, ALatchWiderThanItsRegisterIsRefused) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  const std::size_t ltch = section_at(good, "LTCH");
  const auto latch_at = [&](RegId id) { return ltch + 8 + 2 * static_cast<std::size_t>(id); };
  Bytes b = good;
  set_le(b, latch_at(RegId::MinTSDR_Val), 0xFFFF, 2);
  reseal(b);
  expect_refused(target, b, "latch MinTSDR_Val is FFFFh: more than its 8 bits");
  b = good;
  set_le(b, latch_at(RegId::MinTSDR_Val), 0x00FF, 2);  // the widest an 8-bit register holds
  reseal(b);
  Chip widest({Profile::spc3, BusMode::intel, 0});
  widest.load_state(b);
  EXPECT_EQ(widest.save_state(), b);
  // The SPC3 has no DPC31 C31_Control.
  ASSERT_EQ(find_reg(profile_desc(Profile::spc3), RegId::C31_Control), nullptr);
  b = good;
  set_le(b, latch_at(RegId::C31_Control), 0x0001, 2);
  reseal(b);
  expect_refused(target, b, "is 0001h on a chip without that register");
}

// A block the profile lacks stays as reset left it, and both receivers listen at the rate of the
// search code (Mac::listen). Fuzz.snapshot_loader's finding 10 (docs/robustness.md): an SPC3
// with the DPC31's DPS_User_Watchdog due read a cell the SPC3 does not have; a receiver bit time
// of 0 divided by zero.
TEST(SnapshotFormat, ABlockTheChipLacksOrABitTimeOfNoRateIsRefused) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  Bytes b = good;
  set_le(b, section_at(good, "RQIF") + 4, 0, 8);  // the DPS_User_Watchdog's timer due at cycle 0
  reseal(b);
  expect_refused(target, b, "the request interface is not idle on a chip without one");
  b = good;
  b[section_at(good, "SAPL") + 4] = 1;  // DPV1_Enable taken
  reseal(b);
  expect_refused(target, b, "the SAP list is not off on a chip without one");
  const std::uint32_t t = target.bit_cycles();
  const std::string wrong = fmt::format("a receiver's bit time is not {} clocks", t);
  for (const std::string_view receiver : {"UART", "USMP"}) {  // the event and per-cycle ones
    for (const std::uint32_t other : {0u, t + 1}) {
      SCOPED_TRACE(fmt::format("{} {}", receiver, other));
      b = good;
      set_le(b, section_at(good, receiver) + 4, other, 4);
      reseal(b);
      expect_refused(target, b, wrong);
    }
  }
}

// What the log has said (section LOGS, versions 6 and 7) as the log can have said it: an
// over-long length cell is logged only beyond 244 (docs/timing.md, "Length cells"), an SPC3's wait
// for New_Din_Buffer_Cmd began at or before the snapshot's cycle (at its User_Cfg_Data_Okay read),
// and a folded log names an address exactly when it has counted an occurrence (the first names
// the cause).
TEST(SnapshotFormat, ALogMemoryTheLogCannotHaveIsRefused) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  const std::size_t logs = section_at(good, "LOGS") + 4;
  Bytes b = good;
  b[logs] = 244;  // R_Len_Din_Buf
  reseal(b);
  expect_refused(
      target, b,
      "R_Len_Din_Buf logged as over-long at 244, within the 244 bytes of a DP data unit");
  b = good;
  set_le(b, logs + 5 + 9, 1, 8);  // unmapped accesses: one counted, no address
  reseal(b);
  expect_refused(target, b, "a folded log of 1 occurrences with 0 addresses logged");

  // An SPC3 with a Din buffer waits after its Cfg OK (SPC3 p.31; docs/decisions.md) from the
  // completion cycle of the User_Cfg_Data_Okay read.
  Chip waiting(ChipOptions{Profile::spc3});
  const auto at = [&waiting](RegId id) { return static_cast<std::uint32_t>(waiting.addr_of(id)); };
  waiting.write(at(RegId::R_Len_Din_Buf), 4);
  harness::asic_prm_received(waiting);
  ASSERT_EQ(waiting.read(at(RegId::User_Prm_Data_Okay)), 0x00);
  harness::asic_cfg_received(waiting);
  ASSERT_EQ(waiting.read(at(RegId::User_Cfg_Data_Okay)), 0x00);
  ASSERT_EQ(waiting.dp_state(), DpState::Wait_Cfg);
  const std::uint64_t now = waiting.cycle();
  const Bytes wait = waiting.save_state();
  const std::size_t since = section_at(wait, "LOGS") + 4 + 5;
  b = wait;
  set_le(b, since, now, 8);
  reseal(b);
  EXPECT_EQ(b, wait) << "the wait began at the read's completion cycle";
  set_le(b, since, now + 1, 8);
  reseal(b);
  expect_refused(target, b,
                 fmt::format("the wait for New_Din_Buffer_Cmd begins at cycle {}, after the "
                             "snapshot's {}",
                             now + 1, now));
}

// Diag_Buffer_SM's two buffers as the manuals move them: one with the user and one with the
// ASIC, or one waiting with the ASIC while the other is sent; never Nil, never both in one state
// (SPC3 manual, Diag_Buffer_SM; the fuzz checker's "both diag buffers with the user", finding 11
// of docs/robustness.md).
TEST(SnapshotFormat, TwoDiagBuffersInOneStateAreRefused) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  const std::size_t diag = section_at(good, "BUFS") + 4 + 8;  // after Dout d n u f, Din d n u f
  const auto with = [&](std::uint8_t first, std::uint8_t second) {
    Bytes b = good;
    b[diag] = first;
    b[diag + 1] = second;
    reseal(b);
    return b;
  };
  constexpr std::uint8_t nil = 0, user = 1, asic = 2, send = 3;
  for (const auto& [x, y] :
       {std::pair{user, user}, {asic, asic}, {send, send}, {nil, user}, {asic, nil}}) {
    SCOPED_TRACE(fmt::format("{} {}", x, y));
    expect_refused(target, with(x, y), "the diag buffers are both in one state, or one is Nil");
  }
  for (const auto& [x, y] : {std::pair{user, asic}, {asic, user}, {user, send}, {send, asic}}) {
    SCOPED_TRACE(fmt::format("{} {}", x, y));
    Chip c({Profile::spc3, BusMode::intel, 0});
    c.load_state(with(x, y));
    EXPECT_EQ(c.peek_reg(RegId::Diag_Buffer_SM), y << 2 | x);
  }
}

// X/INT as last shown (CORE irq_line) must be what IRR, IMR and the EOI time make it: a chip tells
// on_irq_change only where the two differ, so a stale one hid the next activation (CI's fuzz run,
// docs/robustness.md). PB3 is the DPC31's, high only while DX_Out is pending.
TEST(SnapshotFormat, XIntOrPb3OtherThanTheInterruptsMakeThemIsRefused) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  const std::size_t line = section_at(good, "CORE") + 4 + 15;  // after now, 3 b, baud, u16, b
  ASSERT_LE(good[line], 1);
  const bool active = target.irq_active();
  ASSERT_EQ(good[line], active ? 1 : 0);
  Bytes b = good;
  b[line] = active ? 0 : 1;
  reseal(b);
  expect_refused(target, b,
                 fmt::format("X/INT shown {} where IRR, IMR and the EOI time make it {}",
                             active ? "inactive" : "active", active ? "active" : "inactive"));
  b = good;
  b[line + 1] = 1;  // pb3 on an SPC3
  reseal(b);
  expect_refused(target, b, "PB3 high without a DX_Out pending on a DPC31");
}

}  // namespace
