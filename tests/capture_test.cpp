// Telegram captures (docs/capture.md): the pcapng writer's bytes against
// draft-ietf-opsawg-pcapng field by field, cycle -> ns conversion, failures that must be reported,
// and the whole path: a DP start-up on the chip, captured, dissected by tshark with
// lib/capture/profibus_dl.lua. Expected bytes, block lengths and dissector fields are worked out by
// hand.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dp_master.hpp"
#include "pcapng.hpp"
#include "responder.hpp"
#include "scenario.hpp"
#include "test_files.hpp"

using namespace dpc31;
using namespace dpc31::capture;
namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

namespace {

using testutil::TempDir;

Bytes read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

std::uint32_t le32(const Bytes& b, std::size_t off) {
  return static_cast<std::uint32_t>(b.at(off) | b.at(off + 1) << 8 | b.at(off + 2) << 16 |
                                    static_cast<std::uint32_t>(b.at(off + 3)) << 24);
}
std::uint16_t le16(const Bytes& b, std::size_t off) {
  return static_cast<std::uint16_t>(b.at(off) | b.at(off + 1) << 8);
}
std::string str(const Bytes& b, std::size_t off, std::size_t n) {
  return {b.begin() + static_cast<std::ptrdiff_t>(off),
          b.begin() + static_cast<std::ptrdiff_t>(off + n)};
}
Bytes sub(const Bytes& b, std::size_t off, std::size_t n) {
  return {b.begin() + static_cast<std::ptrdiff_t>(off),
          b.begin() + static_cast<std::ptrdiff_t>(off + n)};
}

// FDL_Status request 2 -> 5 and its answer at 1.5 Mbaud (T = 32 clocks at 48 MHz, 11 bits per
// character): FCS 05+02+49 = 50h, 02+05+00 = 07h.
const Bytes kFdlStatusReq = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
const Bytes kFdlStatusAns = {0x10, 0x02, 0x05, 0x00, 0x07, 0x16};

}  // namespace

// Layout (all little-endian):
//   SHB   0..44: 24 fixed + shb_userappl "dpc31emu" (4 + 8) + opt_endofopt (4) + 4 = 44
//   IDB  44..88: 16 fixed + if_name "dpc31" (4 + 5 + 3 pad) + if_tsresol (4 + 1 + 3 pad)
//                + opt_endofopt (4) + 4 = 44
//   EPB  88..164: 28 fixed + 6 data + 2 pad + epb_flags (4 + 4)
//                + opt_comment "cycles 48000-50112" (4 + 18 + 2 pad) + opt_endofopt (4) + 4 = 76
//   EPB 164..240: the same sizes for the answer.
TEST(Capture, TwoPacketFileFieldByField) {
  TempDir dir;
  const std::string path = dir.file("two.pcapng");
  PcapngWriter w;
  ASSERT_TRUE(w.open(path)) << w.error();
  // 48000 cycles = 1 ms; the answer starts 11 bit times after the request's 6 characters.
  ASSERT_TRUE(w.add(Telegram{false, kFdlStatusReq, 48000, 50112}, 48'000'000)) << w.error();
  ASSERT_TRUE(w.add(Telegram{true, kFdlStatusAns, 50464, 52576}, 48'000'000)) << w.error();
  EXPECT_EQ(w.packets(), 2u);
  ASSERT_TRUE(w.close()) << w.error();
  EXPECT_EQ(dir.tree(), std::vector<std::string>{"two.pcapng"});  // no temporary left

  const Bytes b = read_file(path);
  ASSERT_EQ(b.size(), 240u);

  // Section Header Block (§4.1)
  EXPECT_EQ(sub(b, 0, 4), (Bytes{0x0A, 0x0D, 0x0D, 0x0A}));  // block type, palindromic
  EXPECT_EQ(le32(b, 4), 44u);                                // block total length
  EXPECT_EQ(sub(b, 8, 4), (Bytes{0x4D, 0x3C, 0x2B, 0x1A}));  // byte-order magic, little-endian
  EXPECT_EQ(le16(b, 12), 1u);                                // major version
  EXPECT_EQ(le16(b, 14), 0u);                                // minor version
  EXPECT_EQ(sub(b, 16, 8), Bytes(8, 0xFF));                  // section length -1
  EXPECT_EQ(le16(b, 24), 4u);                                // shb_userappl
  EXPECT_EQ(le16(b, 26), 8u);
  EXPECT_EQ(str(b, 28, 8), "dpc31emu");
  EXPECT_EQ(le32(b, 36), 0u);   // opt_endofopt: code 0, length 0
  EXPECT_EQ(le32(b, 40), 44u);  // trailing block total length

  // Interface Description Block (§4.2)
  EXPECT_EQ(le32(b, 44), 1u);
  EXPECT_EQ(le32(b, 48), 44u);
  EXPECT_EQ(le16(b, 52), 257u);  // LINKTYPE_PROFIBUS_DL
  EXPECT_EQ(le16(b, 54), 0u);    // reserved
  EXPECT_EQ(le32(b, 56), 0u);    // snaplen: no limit
  EXPECT_EQ(le16(b, 60), 2u);    // if_name
  EXPECT_EQ(le16(b, 62), 5u);
  EXPECT_EQ(str(b, 64, 5), "dpc31");
  EXPECT_EQ(sub(b, 69, 3), Bytes(3, 0));  // padding to 32 bits
  EXPECT_EQ(le16(b, 72), 9u);             // if_tsresol
  EXPECT_EQ(le16(b, 74), 1u);
  EXPECT_EQ(b[76], 9u);  // 10^-9 s
  EXPECT_EQ(sub(b, 77, 3), Bytes(3, 0));
  EXPECT_EQ(le32(b, 80), 0u);  // opt_endofopt
  EXPECT_EQ(le32(b, 84), 44u);

  // Enhanced Packet Blocks (§4.3): 48000 cycles at 48 MHz = 1 000 000 ns = 000F4240h;
  // 50464 cycles = 1 051 333.3 ns -> 1 051 333 = 00100AC5h.
  struct Expect {
    std::size_t at;
    std::uint32_t ts_low;
    const Bytes* data;
    std::uint32_t flags;
    const char* comment;
  };
  const Expect epbs[] = {{88, 0x000F4240, &kFdlStatusReq, 1, "cycles 48000-50112"},
                         {164, 0x00100AC5, &kFdlStatusAns, 2, "cycles 50464-52576"}};
  for (const Expect& e : epbs) {
    SCOPED_TRACE(e.at);
    const std::size_t o = e.at;
    EXPECT_EQ(le32(b, o), 6u);       // block type
    EXPECT_EQ(le32(b, o + 4), 76u);  // block total length
    EXPECT_EQ(le32(b, o + 8), 0u);   // interface ID
    EXPECT_EQ(le32(b, o + 12), 0u);  // timestamp, upper 32 bits
    EXPECT_EQ(le32(b, o + 16), e.ts_low);
    EXPECT_EQ(le32(b, o + 20), 6u);  // captured length
    EXPECT_EQ(le32(b, o + 24), 6u);  // original length
    EXPECT_EQ(sub(b, o + 28, 6), *e.data);
    EXPECT_EQ(sub(b, o + 34, 2), Bytes(2, 0));
    EXPECT_EQ(le16(b, o + 36), 2u);  // epb_flags
    EXPECT_EQ(le16(b, o + 38), 4u);
    EXPECT_EQ(le32(b, o + 40), e.flags);  // bits 1:0: 01 inbound, 10 outbound
    EXPECT_EQ(le16(b, o + 44), 1u);       // opt_comment
    EXPECT_EQ(le16(b, o + 46), 18u);
    EXPECT_EQ(str(b, o + 48, 18), e.comment);
    EXPECT_EQ(sub(b, o + 66, 2), Bytes(2, 0));
    EXPECT_EQ(le32(b, o + 68), 0u);  // opt_endofopt
    EXPECT_EQ(le32(b, o + 72), 76u);
  }
}

// Without optional strings: no option list at all where nothing is optional (no opt_endofopt).
TEST(Capture, BlocksWithoutOptions) {
  const WriterOptions bare{"", "", false};
  const Bytes shb = section_header_block(bare);
  ASSERT_EQ(shb.size(), 28u);  // 24 fixed + 4
  EXPECT_EQ(le32(shb, 4), 28u);
  EXPECT_EQ(le32(shb, 24), 28u);

  const Bytes idb = interface_description_block(bare);
  ASSERT_EQ(idb.size(), 32u);  // 16 + if_tsresol 8 + opt_endofopt 4 + 4
  EXPECT_EQ(le32(idb, 4), 32u);
  EXPECT_EQ(le16(idb, 16), 9u);
  EXPECT_EQ(le32(idb, 24), 0u);
  EXPECT_EQ(le32(idb, 28), 32u);

  // A 1-byte SC with no direction: 28 + 1 + 3 pad + 4 = 36; a 4-byte token-sized packet: 36.
  const Bytes sc = {0xE5};
  const Bytes epb = enhanced_packet_block(Packet{0x1'0000'0002, Direction::unknown, sc, ""});
  ASSERT_EQ(epb.size(), 36u);
  EXPECT_EQ(le32(epb, 4), 36u);
  EXPECT_EQ(le32(epb, 12), 1u);  // upper 32 bits of the timestamp
  EXPECT_EQ(le32(epb, 16), 2u);
  EXPECT_EQ(sub(epb, 28, 4), (Bytes{0xE5, 0, 0, 0}));
  EXPECT_EQ(le32(epb, 32), 36u);
  const Bytes four = {1, 2, 3, 4};
  EXPECT_EQ(enhanced_packet_block(Packet{0, Direction::unknown, four, ""}).size(), 36u);

  // Every block is a multiple of 4 long, whatever the data length.
  for (std::size_t n = 0; n <= 9; ++n) {
    const Bytes d(n, 0x55);
    const Bytes blk = enhanced_packet_block(Packet{0, Direction::inbound, d, "x"});
    EXPECT_EQ(blk.size() % 4, 0u) << n;
    EXPECT_EQ(le32(blk, 4), blk.size()) << n;
  }
}

TEST(Capture, TimestampConversion) {
  // round(cycle * 10^9 / clock_hz), halves up.
  EXPECT_EQ(cycles_to_ns(0, 48'000'000), 0u);
  EXPECT_EQ(cycles_to_ns(1, 48'000'000), 21u);  // 20.83
  EXPECT_EQ(cycles_to_ns(2, 48'000'000), 42u);  // 41.67
  EXPECT_EQ(cycles_to_ns(3, 48'000'000), 63u);  // 62.5: half up
  EXPECT_EQ(cycles_to_ns(48'000'000, 48'000'000), 1'000'000'000u);
  EXPECT_EQ(cycles_to_ns(48'000'001, 48'000'000), 1'000'000'021u);
  EXPECT_EQ(cycles_to_ns(1, 3), 333'333'333u);
  EXPECT_EQ(cycles_to_ns(2, 3), 666'666'667u);
  EXPECT_EQ(cycles_to_ns(7, 1'000'000'000), 7u);
  // No intermediate overflow: (2^64 - 1) / (2^32 - 1) = 2^32 + 1 exactly.
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
  EXPECT_EQ(cycles_to_ns(kMax, 0xFFFFFFFFu), 4'294'967'297'000'000'000u);
  EXPECT_EQ(cycles_to_ns(kMax, 1'000'000'000), kMax);
  // Out of range and no clock.
  EXPECT_EQ(cycles_to_ns(kMax, 48'000'000), std::nullopt);
  EXPECT_EQ(cycles_to_ns(1, 0), std::nullopt);
  // Monotonic, never more than half a nanosecond off.
  for (const std::uint32_t hz : {48'000'000u, 36'000'000u, 24'576'000u}) {
    std::uint64_t prev = 0;
    for (std::uint64_t c = 0; c < 5000; ++c) {
      const std::uint64_t ns = *cycles_to_ns(c, hz);
      EXPECT_GE(ns, prev);
      const std::int64_t diff2 = static_cast<std::int64_t>(2 * ns * hz) -
                                 static_cast<std::int64_t>(2 * c * 1'000'000'000u);
      EXPECT_LE(diff2, static_cast<std::int64_t>(hz));
      EXPECT_GT(diff2, -static_cast<std::int64_t>(hz));
      prev = ns;
    }
  }
  // A telegram is stamped with its start cycle.
  const auto p = telegram_packet(Telegram{true, {0xE5}, 96, 448}, 48'000'000, true);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->timestamp_ns, 2000u);
  EXPECT_EQ(p->direction, Direction::outbound);
  EXPECT_EQ(p->comment, "cycles 96-448");
  EXPECT_FALSE(telegram_packet(Telegram{true, {0xE5}, kMax, kMax}, 48'000'000, true));
}

TEST(Capture, OpenFailureIsReported) {
  TempDir dir;
  const std::string path = dir.file("missing/sub/x.pcapng");
  PcapngWriter w;
  EXPECT_FALSE(w.open(path));
  EXPECT_FALSE(w.is_open());
  EXPECT_NE(w.error().find("cannot create"), std::string::npos) << w.error();
  EXPECT_NE(w.error().find(path), std::string::npos) << w.error();
  EXPECT_NE(w.error().find("No such file or directory"), std::string::npos) << w.error();
  EXPECT_FALSE(w.add(Telegram{false, kFdlStatusReq, 0, 2112}, 48'000'000));
  EXPECT_FALSE(w.close());
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(dir.tree().empty());
}

TEST(Capture, TargetUntouchedUntilClose) {
  TempDir dir;
  const std::string path = dir.file("c.pcapng");
  { std::ofstream(path) << "old"; }
  {
    PcapngWriter w;
    ASSERT_TRUE(w.open(path)) << w.error();
    ASSERT_TRUE(w.add(Telegram{false, kFdlStatusReq, 0, 2112}, 48'000'000));
    EXPECT_EQ(read_file(path), (Bytes{'o', 'l', 'd'}));
    EXPECT_EQ(dir.tree().size(), 2u);  // the target and the temporary
    // Destroyed without close(): the capture is discarded.
  }
  EXPECT_EQ(read_file(path), (Bytes{'o', 'l', 'd'}));
  EXPECT_EQ(dir.tree(), std::vector<std::string>{"c.pcapng"});

  PcapngWriter w;
  ASSERT_TRUE(w.open(path)) << w.error();
  w.discard();
  EXPECT_FALSE(w.is_open());
  EXPECT_EQ(dir.tree(), std::vector<std::string>{"c.pcapng"});
  ASSERT_TRUE(w.open(path)) << w.error();
  ASSERT_TRUE(w.close()) << w.error();
  EXPECT_EQ(read_file(path).size(), 88u);  // SHB + IDB: an empty capture
  EXPECT_EQ(dir.tree(), std::vector<std::string>{"c.pcapng"});
}

TEST(Capture, RenameFailureIsReported) {
  TempDir dir;
  const std::string path = dir.file("is_a_directory");
  // A directory in the way is found by open(), before any telegram is captured.
  fs::create_directory(path);
  PcapngWriter w;
  EXPECT_FALSE(w.open(path));
  EXPECT_EQ(w.error(), path + ": cannot write: is a directory");
  EXPECT_EQ(dir.tree(), std::vector<std::string>{"is_a_directory"});
  // One that appears while the capture is open makes the rename fail.
  fs::remove(path);
  ASSERT_TRUE(w.open(path)) << w.error();
  fs::create_directory(path);
  EXPECT_FALSE(w.close());
  EXPECT_NE(w.error().find("cannot rename"), std::string::npos) << w.error();
  EXPECT_EQ(dir.tree(), std::vector<std::string>{"is_a_directory"});  // temporary removed
}

// A full disk, as the file size limit (SIGXFSZ ignored, so write() fails with EFBIG).
TEST(Capture, WriteFailureIsReportedNeverSilent) {
  TempDir dir;
  const std::string path = dir.file("full.pcapng");
  rlimit old{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  const auto old_handler = ::signal(SIGXFSZ, SIG_IGN);
  rlimit lim = old;
  lim.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &lim), 0);

  PcapngWriter w;
  const bool opened = w.open(path);
  // 400 telegrams of 255 bytes (about 120 KiB) are flushed in 64 KiB pieces: an add() fails.
  const Bytes big(255, 0x42);
  std::size_t failed_at = 0;
  for (std::size_t i = 0; i < 400 && failed_at == 0; ++i) {
    if (!w.add(Telegram{false, big, i * 100, i * 100 + 50}, 48'000'000)) failed_at = i + 1;
  }
  const bool later_add = w.add(Telegram{false, kFdlStatusReq, 0, 1}, 48'000'000);
  const bool closed = w.close();
  ::setrlimit(RLIMIT_FSIZE, &old);
  ::signal(SIGXFSZ, old_handler);

  ASSERT_TRUE(opened) << w.error();
  EXPECT_GT(failed_at, 0u);
  EXPECT_FALSE(later_add);  // the first error sticks
  EXPECT_FALSE(closed);
  EXPECT_NE(w.error().find("cannot write"), std::string::npos) << w.error();
  EXPECT_NE(w.error().find("File too large"), std::string::npos) << w.error();
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(dir.tree().empty());

  // The same at close(): everything still buffered, the flush fails there.
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &lim), 0);
  ::signal(SIGXFSZ, SIG_IGN);
  PcapngWriter w2;
  const bool opened2 = w2.open(path);
  bool all_added = true;
  for (std::size_t i = 0; i < 40; ++i) {
    all_added = w2.add(Telegram{false, big, i * 100, i * 100 + 50}, 48'000'000) && all_added;
  }
  const bool closed2 = w2.close();
  ::setrlimit(RLIMIT_FSIZE, &old);
  ::signal(SIGXFSZ, old_handler);
  ASSERT_TRUE(opened2) << w2.error();
  EXPECT_TRUE(all_added);
  EXPECT_FALSE(closed2);
  EXPECT_NE(w2.error().find("File too large"), std::string::npos) << w2.error();
  EXPECT_FALSE(fs::exists(path));
}

namespace {

// The start-up of protocol_test's Bench: master 2, slave 5 (dpc31), 1.5 Mbaud, default
// SlaveConfig (cfg 13h 23h, WD on with factors 10/10, ident 0C31h), then one Data_Exchange with
// outputs 01..04 and a Global_Control Clear (02h) to all.
struct Startup {
  Chip chip{{Profile::dpc31, BusMode::intel, 0}};
  Responder user{ResponderConfig{}};
  std::unique_ptr<DpMaster> master;
  std::vector<Telegram> seen;  // what the chip reported, by an independent observer

  Startup() {
    chip.set_log_sink(nullptr);
    user.set_inputs({0xA1, 0xA2, 0xA3, 0xA4});
    DirectBus bus(chip);
    user.init(bus);
    master = std::make_unique<DpMaster>(chip, MasterConfig{2, 1'500'000, 100, 33}, SlaveConfig{});
    master->set_firmware([this](BusPort& c) { user.isr(c); });
    chip.on_telegram([this](const Telegram& t) { seen.push_back(t); });
  }
  bool run() {
    if (!master->startup()) return false;
    master->data_exchange({0x01, 0x02, 0x03, 0x04});
    master->global_control(0x02, 0);
    return true;
  }
};

struct Run {
  int status = -1;
  std::string out;
};

// Runs a shell command: its exit status (as from pclose) and stdout.
Run run(const std::string& cmd) {
  Run r;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (p == nullptr) return r;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  r.status = ::pclose(p);
  return r;
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::vector<std::string> lines(const std::string& s) {
  std::vector<std::string> v;
  std::istringstream in(s);
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

// tshark with the dissector, isolated from the user's Wireshark configuration and plugins. The
// tests that use it fail (not skip) when tshark is missing.
bool have_tshark() {
  const Run which = run("command -v tshark");
  return which.status == 0 && !which.out.empty();
}
constexpr const char* kNoTshark =
    "tshark not found on PATH: install it (setup.sh does: apt-get install tshark)";

std::string tshark(const TempDir& dir, const std::string& args, std::string* err = nullptr) {
  const std::string home = dir.file("home");
  fs::create_directories(home);
  const std::string err_file = dir.file("tshark.err");
  const Run r = run("env HOME=" + quote(home) + " XDG_CONFIG_HOME=" + quote(home) +
                    " tshark -n -X lua_script:" + quote(DPC31_DISSECTOR) + " " + args + " 2>" +
                    quote(err_file));
  const Bytes e = read_file(err_file);
  const std::string stderr_text(e.begin(), e.end());
  if (err != nullptr) *err = stderr_text;
  EXPECT_EQ(r.status, 0) << "tshark " << args << "\n" << stderr_text;
  EXPECT_EQ(stderr_text.find("Lua"), std::string::npos) << stderr_text;
  return r.out;
}

// tshark 4.0 prints booleans in -T fields as 1/0, later versions as True/False.
std::string normalise_bools(std::string s) {
  const std::pair<std::string, std::string> words[] = {{"True", "1"}, {"False", "0"}};
  for (const auto& [from, to] : words) {
    for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at)) {
      s.replace(at, from.size(), to);
    }
  }
  return s;
}

}  // namespace

// A DP start-up recorded by `w` into `path`: false (with the reason) when any step fails.
::testing::AssertionResult record_startup(const std::string& path, Startup& s, PcapngWriter& w) {
  if (!w.open(path)) return ::testing::AssertionFailure() << w.error();
  w.attach(s.chip);
  if (!s.run()) return ::testing::AssertionFailure() << "the start-up failed";
  if (!w.close()) return ::testing::AssertionFailure() << w.error();
  return ::testing::AssertionSuccess();
}

TEST(Capture, AttachRecordsEveryTelegram) {
  TempDir dir;
  const std::string path = dir.file("startup.pcapng");
  Startup s;
  PcapngWriter w;
  ASSERT_TRUE(record_startup(path, s, w));
  ASSERT_EQ(w.packets(), s.seen.size());
  ASSERT_GE(s.seen.size(), 13u);

  // The file is the header blocks followed by one EPB per telegram, in the order reported.
  const Bytes b = read_file(path);
  std::size_t at = 88;
  for (const Telegram& t : s.seen) {
    const Bytes epb = enhanced_packet_block(*telegram_packet(t, 48'000'000, true));
    ASSERT_EQ(sub(b, at, epb.size()), epb);
    at += epb.size();
  }
  EXPECT_EQ(at, b.size());

  // Telegrams after close() are ignored; the observer survives the writer.
  {
    PcapngWriter gone;
    ASSERT_TRUE(gone.open(dir.file("gone.pcapng")));
    gone.attach(s.chip);
  }
  s.master->data_exchange({0x05, 0x06, 0x07, 0x08});
  EXPECT_EQ(w.packets(), s.seen.size() - 2);
  EXPECT_EQ(dir.tree(), std::vector<std::string>{"startup.pcapng"});
}

// A text option's length is 16 bits (draft-ietf-opsawg-pcapng §3.5: Option Length), so 65535 bytes
// is the longest: written, and tshark reads it back whole. One byte more used to be written with
// its length wrapped (65536 -> 0), add() and close() reporting success, and tshark refused the
// whole file ("Not enough data to handle option of length ..."). Now it is refused, never cut: the
// first error is kept (docs/capture.md, "File format"), close() fails, the target stays as it was;
// a header option too long (if_name, shb_userappl) fails open() before any file is made.
TEST(Capture, AnOptionLongerThanSixteenBitsIsRefusedNeverWrittenCorrupt) {
  ASSERT_TRUE(have_tshark()) << kNoTshark;
  TempDir dir;
  const std::string path = dir.file("long.pcapng");
  {
    PcapngWriter w;
    ASSERT_TRUE(w.open(path)) << w.error();
    ASSERT_TRUE(w.add(Packet{0, Direction::inbound, kFdlStatusReq, std::string(65535, 'c')}));
    ASSERT_TRUE(w.add(Packet{1000, Direction::outbound, kFdlStatusAns, "x"}));
    ASSERT_TRUE(w.close()) << w.error();
  }
  std::string err;
  const std::string fields =
      tshark(dir, "-r " + quote(path) + " -T fields -e frame.number -e frame.comment", &err);
  EXPECT_EQ(err.find("corrupt"), std::string::npos) << err;
  EXPECT_EQ(fields, "1\t" + std::string(65535, 'c') + "\n2\tx\n");

  TempDir out;  // tshark's home is in `dir`
  const std::string target = out.file("long.pcapng");
  { std::ofstream(target) << "old"; }
  PcapngWriter w;
  ASSERT_TRUE(w.open(target)) << w.error();
  ASSERT_TRUE(w.add(Packet{0, Direction::inbound, kFdlStatusReq, "first"}));
  EXPECT_FALSE(w.add(Packet{1000, Direction::outbound, kFdlStatusAns, std::string(65536, 'c')}));
  EXPECT_EQ(w.error(), "packet 2: opt_comment of 65536 bytes: a pcapng option holds at most 65535");
  EXPECT_FALSE(w.add(Packet{2000, Direction::inbound, kFdlStatusReq, "after"}));
  EXPECT_EQ(w.packets(), 1u);
  EXPECT_FALSE(w.close());
  EXPECT_EQ(w.error(), "packet 2: opt_comment of 65536 bytes: a pcapng option holds at most 65535");
  EXPECT_EQ(read_file(target), (Bytes{'o', 'l', 'd'}));
  EXPECT_EQ(out.tree(), std::vector<std::string>{"long.pcapng"});

  for (const auto& [opt, name] :
       {std::pair{WriterOptions{"dpc31emu", std::string(70000, 'i'), true}, "if_name"},
        std::pair{WriterOptions{std::string(65536, 'a'), "dpc31", true}, "shb_userappl"}}) {
    PcapngWriter bad(opt);
    EXPECT_FALSE(bad.open(target));
    EXPECT_FALSE(bad.is_open());
    EXPECT_EQ(bad.error(), target + ": " + name + " of " + (name[0] == 'i' ? "70000" : "65536") +
                               " bytes: a pcapng option holds at most 65535");
    EXPECT_FALSE(bad.add(Packet{0, Direction::inbound, kFdlStatusReq, ""}));
    EXPECT_FALSE(bad.close());
    EXPECT_EQ(read_file(target), (Bytes{'o', 'l', 'd'}));
    EXPECT_EQ(out.tree(), std::vector<std::string>{"long.pcapng"});
  }
  // The pure encoder refuses it too, naming the option.
  EXPECT_THROW((void)enhanced_packet_block(
                   Packet{0, Direction::unknown, kFdlStatusReq, std::string(65536, 'c')}),
               std::length_error);
}

// A late answer (docs/capture.md "Order"): the slave's MinTSDR 150 bit times is above the master's
// slot time 100, at 12 Mbaud (T = 4 clocks, docs/timing.md). The Set_Prm (19 characters, 209 T =
// 836 clocks) ends at E; its SC starts at E + 150 T = E + 600 and lasts 11 T = 44 clocks (the
// "answer" row); the master gave up at E + 100 T and, the Set_Prm unanswered, asks Slave_Diag
// (11 characters, 484 clocks; docs/scenario-format.md `startup`) TSYN later, at E + 133 T =
// E + 532 ("The master's wait"): before the SC, which the chip decided first. The capture is in
// start order all the same.
TEST(Capture, ALateAnswerIsWrittenAfterTheRequestThatStartedBeforeIt) {
  ASSERT_TRUE(have_tshark()) << kNoTshark;
  TempDir dir;
  Scenario sc;
  ScenarioError err;
  ASSERT_TRUE(
      parse_scenario("profile spc3\nbaud 12000000\nmaster address=2 slot=100\n"
                     "slave address=5 min_tsdr=150\nstartup tries=6\n",
                     "late.scn", sc, err))
      << err.text();
  PcapngWriter w;
  ASSERT_TRUE(w.open(dir.file("late.pcapng"))) << w.error();
  ScenarioHooks hooks;
  hooks.at_start = [&w](Chip& chip) { w.attach(chip); };
  run_scenario(sc, {}, {}, hooks);
  ASSERT_TRUE(w.close()) << w.error();

  struct Frame {
    std::uint64_t start, end, len;
  };
  std::vector<Frame> frames;
  for (const std::string& l : lines(tshark(dir, "-r " + quote(dir.file("late.pcapng")) +
                                                    " -T fields -e frame.len -e frame.comment"))) {
    Frame f{};
    ASSERT_EQ(std::sscanf(l.c_str(), "%lu\tcycles %lu-%lu", &f.len, &f.start, &f.end), 3) << l;
    if (!frames.empty()) {
      EXPECT_GE(f.start, frames.back().start) << l;
    }
    frames.push_back(f);
  }
  const auto set_prm =
      std::find_if(frames.begin(), frames.end(), [](const Frame& f) { return f.len == 19; });
  ASSERT_GE(std::distance(set_prm, frames.end()), 3);
  const std::uint64_t e = set_prm->end;
  EXPECT_EQ(set_prm->end - set_prm->start, 836u);
  EXPECT_EQ(set_prm[1].len, 11u);  // the Slave_Diag
  EXPECT_EQ(set_prm[1].start, e + 532);
  EXPECT_EQ(set_prm[1].end, e + 532 + 484);
  EXPECT_EQ(set_prm[2].len, 1u);  // the Set_Prm's SC
  EXPECT_EQ(set_prm[2].start, e + 600);
  EXPECT_EQ(set_prm[2].end, e + 644);
}

// The whole path. Expected fields by hand from the telegrams (FCB/FCV per EN 50170: the first SRD
// after FDL_Status carries FCB 1, FCV 1, then FCB alternates):
//   FDL_Status     10 05 02 49 50 16           FC 49h = request, FDL_Status (9)
//   answer         10 02 05 00 07 16           FC 00h = slave, OK
//   Slave_Diag     68 05 05 68 85 82 7D 3C 3E FE 16       DSAP 60, FC 7Dh = SRD_high FCB 1 FCV 1
//   answer         68 0B 0B 68 82 85 08 3E 3C 02 05 00 FF 0C 31 CC 16   FC 08h = DL, DSAP 62
//   Set_Prm        68 0D 0D 68 85 82 5D 3D 3E 88 0A 0A 00 0C 31 00 00 B8 16   DSAP 61, FCB 0
//   answer         E5
//   Chk_Cfg        68 07 07 68 85 82 7D 3E 3E 13 23 36 16                DSAP 62
//   answer         E5
//   Slave_Diag     FC 5Dh; answer FC 08h, DSAP 62
//   Data_Exchange  68 07 07 68 05 02 7D 01 02 03 04 8E 16    no SAPs
//   answer         68 07 07 68 02 05 08 A1 A2 A3 A4 99 16
//   Global_Control 68 07 07 68 FF 82 46 3A 3E 02 00 41 16    DA 127 (ext), SDN_high 46h, DSAP 58
TEST(Capture, TsharkDecodesADpStartup) {
  ASSERT_TRUE(have_tshark()) << kNoTshark;
  TempDir dir;
  const std::string path = dir.file("startup.pcapng");
  Startup s;
  PcapngWriter w;
  ASSERT_TRUE(record_startup(path, s, w));
  ASSERT_EQ(s.seen.size(), 13u);

  const std::string out =
      tshark(dir, "-r " + quote(path) +
                      " -T fields -e profibus.sd -e profibus.da -e profibus.sa -e profibus.fc"
                      " -e profibus.dsap -e profibus.fcs_ok");
  const std::vector<std::string> expected = {
      "0x10\t5\t2\t0x49\t\t1",      // FDL_Status request
      "0x10\t2\t5\t0x00\t\t1",      // FDL_Status answer
      "0x68\t5\t2\t0x7d\t60\t1",    // Slave_Diag
      "0x68\t2\t5\t0x08\t62\t1",    // its answer, to the master's SAP 62
      "0x68\t5\t2\t0x5d\t61\t1",    // Set_Prm
      "0xe5\t\t\t\t\t",             // SC
      "0x68\t5\t2\t0x7d\t62\t1",    // Chk_Cfg
      "0xe5\t\t\t\t\t",             // SC
      "0x68\t5\t2\t0x5d\t60\t1",    // Slave_Diag
      "0x68\t2\t5\t0x08\t62\t1",    // its answer: ready
      "0x68\t5\t2\t0x7d\t\t1",      // Data_Exchange (default SAP)
      "0x68\t2\t5\t0x08\t\t1",      // its answer with the inputs
      "0x68\t127\t2\t0x46\t58\t1",  // Global_Control, broadcast, SDN_high
  };
  EXPECT_EQ(lines(normalise_bools(out)), expected) << out;

  // Services, LE, SSAP, DU, direction (epb_flags) and the comment with the cycles.
  const std::string more = tshark(
      dir, "-r " + quote(path) +
               " -T fields -E separator=, -e profibus.service -e profibus.le -e profibus.ssap"
               " -e profibus.du -e frame.packet_flags_direction");
  const std::vector<std::string> expected_more = {
      "FDL_Status request,,,,0x00000001",
      "FDL_Status response,,,,0x00000002",
      "Slave_Diag request,5,62,,0x00000001",
      "Slave_Diag response,11,60,020500ff0c31,0x00000002",
      "Set_Prm request,13,62,880a0a000c310000,0x00000001",
      "Set_Prm response,,,,0x00000002",
      "Chk_Cfg request,7,62,1323,0x00000001",
      "Chk_Cfg response,,,,0x00000002",
      "Slave_Diag request,5,62,,0x00000001",
      "Slave_Diag response,11,60,000c00020c31,0x00000002",
      "Data_Exchange request,7,,01020304,0x00000001",
      "Data_Exchange response,7,,a1a2a3a4,0x00000002",
      "Global_Control request,7,62,0200,0x00000001",
  };
  EXPECT_EQ(lines(more), expected_more) << more;

  // Timestamps (ns) and comments against the telegrams the chip reported.
  const std::string times = tshark(dir, "-r " + quote(path) +
                                            " -T fields -E separator=, -e frame.time_epoch -e "
                                            "frame.comment");
  const std::vector<std::string> got = lines(times);
  ASSERT_EQ(got.size(), s.seen.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    const std::uint64_t ns = *cycles_to_ns(s.seen[i].start, 48'000'000);
    char expect[96];
    std::snprintf(expect, sizeof expect, "%llu.%09llu,cycles %llu-%llu",
                  static_cast<unsigned long long>(ns / 1'000'000'000u),
                  static_cast<unsigned long long>(ns % 1'000'000'000u),
                  static_cast<unsigned long long>(s.seen[i].start),
                  static_cast<unsigned long long>(s.seen[i].end));
    EXPECT_EQ(got[i], expect) << i;
  }

  // Display filters on the profibus.* fields.
  const std::string filtered =
      tshark(dir, "-r " + quote(path) +
                      " -Y 'profibus.dsap == 61 || (profibus.sd == 0xe5 && frame.number > 7)'"
                      " -T fields -e frame.number");
  EXPECT_EQ(lines(filtered), (std::vector<std::string>{"5", "8"}));
  const std::string bad = tshark(dir, "-r " + quote(path) +
                                          " -Y '!profibus.fcs_ok' -T fields "
                                          "-e frame.number");
  EXPECT_EQ(lines(bad), (std::vector<std::string>{"6", "8"}));  // SCs have no FCS
}

// An SC answers the request just before it (docs/capture.md, profibus.service: "a response's from
// the request it answers"): after an FDL_Status 2 -> 5 (10 05 02 49 50 16) an SC is its answer;
// after the same request, a token 2 -> 5 (DC 05 02) and then an SC, the SC answers no request.
TEST(Capture, TsharkGivesAnScOnlyTheServiceOfTheRequestJustBeforeIt) {
  ASSERT_TRUE(have_tshark()) << kNoTshark;
  TempDir dir;
  const std::string path = dir.file("sc.pcapng");
  const std::vector<Bytes> packets = {
      kFdlStatusReq, {0xE5}, kFdlStatusReq, {0xDC, 0x05, 0x02}, {0xE5}};
  PcapngWriter w(WriterOptions{"", "", false});
  ASSERT_TRUE(w.open(path)) << w.error();
  for (const Bytes& p : packets) ASSERT_TRUE(w.add(Packet{0, Direction::inbound, p, ""}));
  ASSERT_TRUE(w.close()) << w.error();
  const std::string out = tshark(
      dir, "-r " + quote(path) + " -T fields -E separator=, -e profibus.service -e _ws.col.Info");
  EXPECT_EQ(lines(out), (std::vector<std::string>{
                            "FDL_Status request,FDL_Status request 2 → 5  FDL_Status",
                            "FDL_Status response,SC short acknowledge (FDL_Status)",
                            "FDL_Status request,FDL_Status request 2 → 5  FDL_Status",
                            "Token,SD4 token 2 → 5",
                            ",SC short acknowledge",
                        }))
      << out;
}

// Malformed telegrams: an expert info each, never a Lua error.
TEST(Capture, TsharkReportsMalformedFrames) {
  ASSERT_TRUE(have_tshark()) << kNoTshark;
  TempDir dir;
  const std::string path = dir.file("bad.pcapng");
  const std::vector<std::pair<Bytes, std::string>> cases = {
      {{}, "Empty frame"},
      {{0x10}, "Frame truncated: SD1 needs 6 bytes, 1 present"},
      {{0x10, 0x05, 0x02, 0x49, 0x51, 0x16}, "Bad FCS 51h, sum of DA..DU is 50h"},
      {{0x10, 0x05, 0x02, 0x49, 0x50, 0x17}, "End delimiter 17h is not 16h"},
      {{0x68, 0x05, 0x06, 0x68, 0x85, 0x82, 0x7D, 0x3C, 0x3E, 0xFE, 0x16}, "LE 5, LEr 6"},
      {{0x68, 0x05, 0x05, 0x69, 0x85, 0x82, 0x7D, 0x3C, 0x3E, 0xFE, 0x16},
       "Repeated start delimiter 69h is not 68h"},
      {{0x68, 0x02, 0x02, 0x68, 0x85, 0x82, 0x07, 0x16}, "LE 2 outside 4..249"},
      {{0x68, 0x05, 0x05, 0x68, 0x85, 0x82, 0x7D, 0x3C},
       "Frame truncated: SD2 needs 11 bytes, 8 present"},
      {{0x10, 0x05, 0x02, 0x49, 0x50, 0x16, 0x00}, "1 byte(s) after the end of the frame"},
      {{0x42, 0x01}, "Unknown start delimiter 42h"},
      // SD3: 8 data bytes 01..08, FCS should be 05+02+7D+24h = A8h.
      {{0xA2, 0x05, 0x02, 0x7D, 1, 2, 3, 4, 5, 6, 7, 8, 0xA4, 0x16},
       "Bad FCS A4h, sum of DA..DU is A8h"},
      {{0x10, 0x85, 0x02, 0x49, 0xD0, 0x16}, "DSAP announced, but the frame has no data field"},
      {{0x68, 0x05, 0x05, 0x68, 0x85, 0x82, 0x7D, 0xBC, 0x3E, 0x7E, 0x16},
       "DSAP announces a further extension (unsupported)"},
      {{0x68, 0xFF, 0xFF, 0x68, 0x85}, "LE 255 outside 4..249"},
  };
  PcapngWriter w(WriterOptions{"", "", false});
  ASSERT_TRUE(w.open(path)) << w.error();
  for (const auto& c : cases) ASSERT_TRUE(w.add(Packet{0, Direction::inbound, c.first, ""}));
  ASSERT_TRUE(w.close()) << w.error();

  const std::string out = tshark(dir, "-o profibus.all_unknown_encap:TRUE -r " + quote(path) +
                                          " -T fields -E occurrence=f -e _ws.expert.message");
  std::vector<std::string> expected;
  for (const auto& c : cases) expected.push_back(c.second);
  EXPECT_EQ(lines(out), expected) << out;

  // Whole trees, with and without the preference: no Lua error, no dissector error; without
  // it, packets that do not start with a start delimiter are left to the data dissector.
  for (const char* pref : {"TRUE", "FALSE"}) {
    const std::string tree =
        tshark(dir, std::string("-o profibus.all_unknown_encap:") + pref + " -V -r " + quote(path));
    EXPECT_EQ(tree.find("Lua"), std::string::npos) << tree;
    EXPECT_EQ(tree.find("Dissector error"), std::string::npos) << tree;
    EXPECT_EQ(tree.find("Malformed Packet"), std::string::npos) << tree;
  }
  const std::string protos = tshark(dir, "-r " + quote(path) +
                                             " -T fields -e _ws.col.Protocol -e frame.number"
                                             " -Y 'frame.number == 1 || frame.number == 10'");
  EXPECT_EQ(lines(protos), (std::vector<std::string>{"UNKNOWN\t1", "UNKNOWN\t10"})) << protos;
}

// --- DPV1: the dissector decodes the data units on the slave's SAPs 0..51 ---

// The shipped capture of traces/do4_dpv1_vpc3plus.scn (`dpc31 run ... --pcap`, our capture
// door), its DPV1 data units field by field as IEC 61158-6 type 3 lays them out (function number,
// Slot_Number, Index, Length, data; a negative response: function | 80h, Error_Decode,
// Error_Code_1 = class | code, Error_Code_2), derived from the scenario's telegrams:
//   Read request   5E 00 01 02          slot 0 index 1 length 2
//   Read response  5E 00 01 02 01 09    the record: OSPMode 1, replacement value 9
//   Read request   5E 00 07 02          index 7 (no such record)
//   negative       DE 80 B0 00          Read, DPV1, class 11 (access) code 0 (invalid index)
//   Write request  5F 00 01 02 01 06
//   Write response 5F 00 01 02
//   Alarm_Ack      5C 00 01 01          to SAP 50: slot 0, Alarm_Type 1 (Diagnosis), Specifier
//                                       01h = Seq_Nr 0, appears; the response echoes it from 50
// Polls (SRD without data) and the SC answers carry no data unit: no DPV1 fields.
TEST(Capture, TsharkDecodesTheShippedDpv1Capture) {
  ASSERT_TRUE(have_tshark()) << kNoTshark;
  TempDir dir;
  const std::string path = std::string(DPC31_TEST_DATA) + "/capture/do4_dpv1_vpc3plus.pcapng";
  const std::string out = tshark(
      dir, "-r " + quote(path) +
               " -Y profibus.dpv1.function -T fields -E separator=, -e profibus.dsap"
               " -e profibus.ssap -e profibus.dpv1.function -e profibus.dpv1.negative"
               " -e profibus.dpv1.slot -e profibus.dpv1.index -e profibus.dpv1.length"
               " -e profibus.dpv1.data -e profibus.dpv1.error_decode -e profibus.dpv1.error_code_1"
               " -e profibus.dpv1.error_class -e profibus.dpv1.error_code"
               " -e profibus.dpv1.error_code_2");
  const std::vector<std::string> expected = {
      "51,51,0x5e,0,0,1,2,,,,,,",     "51,51,0x5e,0,0,1,2,0109,,,,,",
      "51,51,0x5e,0,0,7,2,,,,,,",     "51,51,0x5e,1,,,,,0x80,0xb0,11,0,0x00",
      "51,51,0x5f,0,0,1,2,0106,,,,,", "51,51,0x5f,0,0,1,2,,,,,,",
      "50,51,0x5c,0,0,,,,,,,,",       "51,50,0x5c,0,0,,,,,,,,",
  };
  EXPECT_EQ(lines(normalise_bools(out)), expected) << out;
  const std::string alarm = tshark(dir, "-r " + quote(path) +
                                            " -Y 'profibus.dpv1.function == 0x5c' -T fields"
                                            " -E separator=, -e profibus.dpv1.alarm_type"
                                            " -e profibus.dpv1.seq_nr -e profibus.dpv1.spec");
  EXPECT_EQ(lines(alarm), (std::vector<std::string>{"1,0,1", "1,0,1"})) << alarm;
  const std::string info =
      tshark(dir, "-r " + quote(path) + " -Y profibus.dpv1.negative -T fields -e _ws.col.Info");
  EXPECT_NE(info.find("DPV1 Read negative B0h invalid index"), std::string::npos) << info;
}

// The other DPV1 data units, built by hand into SD2 telegrams and written by the pcapng writer:
//   Alarm_Ack  5C 00 01 09: slot 0, Alarm_Type 1 (Diagnosis), Specifier 09h = Seq_Nr 1,
//              Add_Ack 0, specifier 1 (appears)
//   Initiate request  57 00 00 00 01 2C 01 00 00 00 00 00 00 02 00 02 01 02 03 04:
//              Send_Timeout 012Ch = 300, Features_Supported 0100h (Features_Supported_1 01h:
//              Read/Write, the byte order docs/dpv1.md gives), Profile_Features_Supported 0,
//              Profile_Ident_Number 0, S_Type 0, S_Len 2, D_Type 0, D_Len 2, S_Addr 0102,
//              D_Addr 0304
//   Initiate response 57 F0 01 00 00 00 00 00 00 02 00 02 03 04 01 02: Max_Len_Data_Unit 240
//   Abort      58 00 13 00: Subnet 0, Instance 1 (MSAC_C2, bits 5..4), Reason_Code 3 (bits 3..0)
//   a Write request cut after the slot: an expert info, no Lua error.
TEST(Capture, TsharkDecodesDpv1AlarmAckInitiateAbort) {
  ASSERT_TRUE(have_tshark()) << kNoTshark;
  TempDir dir;
  const std::string path = dir.file("dpv1.pcapng");
  const auto frame = [](bool request, std::uint8_t slave_sap, Bytes du) {
    return request ? fdl::encode(fdl::make_frame(5, 2, 0x4D, std::move(du), slave_sap, 51))
                   : fdl::encode(fdl::make_frame(2, 5, 0x08, std::move(du), 51, slave_sap));
  };
  const std::vector<Bytes> packets = {
      frame(true, 50, {0x5C, 0x00, 0x01, 0x09}),
      frame(true, 49, {0x57, 0x00, 0x00, 0x00, 0x01, 0x2C, 0x01, 0x00, 0x00, 0x00,
                       0x00, 0x00, 0x00, 0x02, 0x00, 0x02, 0x01, 0x02, 0x03, 0x04}),
      frame(false, 48,
            {0x57, 0xF0, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x00, 0x02, 0x03, 0x04,
             0x01, 0x02}),
      frame(true, 48, {0x58, 0x00, 0x13, 0x00}),
      frame(true, 51, {0x5F, 0x00}),
  };
  PcapngWriter w(WriterOptions{"", "", false});
  ASSERT_TRUE(w.open(path)) << w.error();
  for (const Bytes& p : packets) ASSERT_TRUE(w.add(Packet{0, Direction::inbound, p, ""}));
  ASSERT_TRUE(w.close()) << w.error();
  const std::string out = tshark(
      dir, "-r " + quote(path) +
               " -T fields -E separator=, -e profibus.dpv1.function -e profibus.dpv1.slot"
               " -e profibus.dpv1.alarm_type -e profibus.dpv1.seq_nr -e profibus.dpv1.add_ack"
               " -e profibus.dpv1.spec -e profibus.dpv1.send_timeout"
               " -e profibus.dpv1.max_len_data_unit -e profibus.dpv1.features_supported"
               " -e profibus.dpv1.s_len -e profibus.dpv1.d_len -e profibus.dpv1.s_addr"
               " -e profibus.dpv1.d_addr -e profibus.dpv1.subnet -e profibus.dpv1.instance"
               " -e profibus.dpv1.reason_code -e _ws.expert.message");
  const std::vector<std::string> expected = {
      "0x5c,0,1,1,0,1,,,,,,,,,,,",
      "0x57,,,,,,300,,0x0100,2,2,0102,0304,,,,",
      "0x57,,,,,,,240,0x0100,2,2,0304,0102,,,,",
      "0x58,,,,,,,,,,,,,0,1,3,",
      "0x5f,0,,,,,,,,,,,,,,,Write: the data unit ends at byte 2",
  };
  EXPECT_EQ(lines(normalise_bools(out)), expected) << out;
  const std::string tree = tshark(dir, "-V -r " + quote(path));
  EXPECT_EQ(tree.find("Dissector error"), std::string::npos) << tree;
}
