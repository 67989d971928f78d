#include "pcapng.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "outfile.hpp"

namespace dpc31::capture {

namespace {

// draft-ietf-opsawg-pcapng §4: block types and option codes used here.
constexpr std::uint32_t kShb = 0x0A0D0D0A;
constexpr std::uint32_t kIdb = 0x00000001;
constexpr std::uint32_t kEpb = 0x00000006;
constexpr std::uint32_t kByteOrderMagic = 0x1A2B3C4D;
constexpr std::uint16_t kOptEndOfOpt = 0;
constexpr std::uint16_t kOptComment = 1;
constexpr std::uint16_t kShbUserAppl = 4;
constexpr std::uint16_t kIfName = 2;
constexpr std::uint16_t kIfTsresol = 9;
constexpr std::uint16_t kEpbFlags = 2;

constexpr std::uint64_t kNsPerS = 1'000'000'000;

// One block body, little-endian, with the 32-bit padding rules of §3.1 and §3.5.
class Block {
 public:
  void u16(std::uint16_t v) {
    b_.push_back(static_cast<std::uint8_t>(v));
    b_.push_back(static_cast<std::uint8_t>(v >> 8));
  }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) b_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) b_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void bytes(std::span<const std::uint8_t> d) { b_.insert(b_.end(), d.begin(), d.end()); }
  void pad() {
    while (b_.size() % 4 != 0) b_.push_back(0);
  }
  void option(std::uint16_t code, std::span<const std::uint8_t> value) {
    u16(code);
    u16(static_cast<std::uint16_t>(value.size()));
    bytes(value);
    pad();
    options_ = true;
  }
  // A text option: refused (std::length_error naming it) when its 16-bit length cannot hold it.
  void option(std::uint16_t code, std::string_view name, const std::string& s) {
    if (s.size() > kMaxOptionBytes) {
      throw std::length_error(fmt::format("{} of {} bytes: a pcapng option holds at most {}", name,
                                          s.size(), kMaxOptionBytes));
    }
    option(code, {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()});
  }
  // Type, total length, body, total length. The option list, if any, ends with opt_endofopt.
  std::vector<std::uint8_t> finish(std::uint32_t type) {
    if (options_) {
      u16(kOptEndOfOpt);
      u16(0);
    }
    const auto total = static_cast<std::uint32_t>(b_.size() + 12);
    Block out;
    out.u32(type);
    out.u32(total);
    out.bytes(b_);
    out.u32(total);
    return std::move(out.b_);
  }

 private:
  std::vector<std::uint8_t> b_;
  bool options_ = false;
};

}  // namespace

std::optional<std::uint64_t> cycles_to_ns(std::uint64_t cycle, std::uint32_t clock_hz) {
  if (clock_hz == 0) return std::nullopt;
  // cycle = q * hz + r with r < hz < 2^32, so r * 10^9 + hz / 2 < 2^62: no overflow.
  const std::uint64_t q = cycle / clock_hz;
  const std::uint64_t r = cycle % clock_hz;
  const std::uint64_t frac = (r * kNsPerS + clock_hz / 2) / clock_hz;  // <= 10^9
  if (q > (std::numeric_limits<std::uint64_t>::max() - frac) / kNsPerS) return std::nullopt;
  return q * kNsPerS + frac;
}

std::vector<std::uint8_t> section_header_block(const WriterOptions& opt) {
  Block b;
  b.u32(kByteOrderMagic);
  b.u16(1);                                          // major version
  b.u16(0);                                          // minor version
  b.u64(std::numeric_limits<std::uint64_t>::max());  // section length -1: not given
  if (!opt.application.empty()) b.option(kShbUserAppl, "shb_userappl", opt.application);
  return b.finish(kShb);
}

std::vector<std::uint8_t> interface_description_block(const WriterOptions& opt) {
  Block b;
  b.u16(kLinkTypeProfibusDl);
  b.u16(0);  // reserved
  b.u32(0);  // snaplen: no limit
  if (!opt.interface_name.empty()) b.option(kIfName, "if_name", opt.interface_name);
  const std::uint8_t tsresol = kTsresolNanoseconds;
  b.option(kIfTsresol, std::span<const std::uint8_t>(&tsresol, 1));
  return b.finish(kIdb);
}

std::vector<std::uint8_t> enhanced_packet_block(const Packet& p) {
  Block b;
  b.u32(0);  // interface 0
  b.u32(static_cast<std::uint32_t>(p.timestamp_ns >> 32));
  b.u32(static_cast<std::uint32_t>(p.timestamp_ns));
  b.u32(static_cast<std::uint32_t>(p.bytes.size()));  // captured
  b.u32(static_cast<std::uint32_t>(p.bytes.size()));  // original
  b.bytes(p.bytes);
  b.pad();
  if (p.direction != Direction::unknown || p.symbol_error) {
    const auto f = static_cast<std::uint32_t>(p.direction);
    const std::uint8_t flags[4] = {static_cast<std::uint8_t>(f), 0, 0,
                                   static_cast<std::uint8_t>(p.symbol_error ? 0x80 : 0)};
    b.option(kEpbFlags, flags);
  }
  if (!p.comment.empty()) b.option(kOptComment, "opt_comment", p.comment);
  return b.finish(kEpb);
}

std::optional<Packet> telegram_packet(const Telegram& t, std::uint32_t clock_hz,
                                      bool cycle_comments) {
  const std::optional<std::uint64_t> ns = cycles_to_ns(t.start, clock_hz);
  if (!ns) return std::nullopt;
  Packet p;
  p.timestamp_ns = *ns;
  p.direction = t.from_chip ? Direction::outbound : Direction::inbound;
  p.bytes = t.bytes;
  if (cycle_comments) p.comment = fmt::format("cycles {}-{}", t.start, t.end);
  return p;
}

struct PcapngWriter::State {
  WriterOptions opt;
  outfile::OutFile out;
  std::string error;
  std::uint64_t packets = 0;
  // The chip's answers not yet written, with the chip's clock: attach() writes in start order.
  std::vector<std::pair<Telegram, std::uint32_t>> held;

  bool fail(std::string msg) {
    if (error.empty()) error = std::move(msg);
    return false;
  }
  bool put(const std::vector<std::uint8_t>& block) {
    if (!out.is_open()) return fail("no capture file is open");
    if (!error.empty()) return false;
    if (!out.write({reinterpret_cast<const char*>(block.data()), block.size()})) {
      return fail(out.error());
    }
    return true;
  }
  bool add(const Packet& p) {
    try {
      if (!put(enhanced_packet_block(p))) return false;
    } catch (const std::length_error& e) {
      return fail(fmt::format("packet {}: {}", packets + 1, e.what()));
    }
    ++packets;
    return true;
  }
  bool add(const Telegram& t, std::uint32_t clock_hz) {
    if (!out.is_open()) return fail("no capture file is open");
    const std::optional<Packet> p = telegram_packet(t, clock_hz, opt.cycle_comments);
    if (!p) {
      return fail(fmt::format("the telegram at cycle {} has no timestamp at {} Hz (out of range)",
                              t.start, clock_hz));
    }
    return add(*p);
  }
  // The chip reports an answer when it decides it, before its first start bit, and a received
  // telegram at its end. So a received one never starts before any telegram reported after it,
  // while a request that started after the answer was decided (the master gave up at its slot
  // time) can start before that answer: answers wait for a received telegram that starts later,
  // or for close().
  void report(const Telegram& t, std::uint32_t clock_hz) {
    if (t.from_chip) {
      held.emplace_back(t, clock_hz);
      return;
    }
    flush_held(t.start);
    add(t, clock_hz);
  }
  void flush_held(std::uint64_t up_to) {
    auto it = held.begin();
    for (; it != held.end() && it->first.start <= up_to; ++it) add(it->first, it->second);
    held.erase(held.begin(), it);
  }
};

PcapngWriter::PcapngWriter(WriterOptions opt) : state_(std::make_shared<State>()) {
  state_->opt = std::move(opt);
}

PcapngWriter::~PcapngWriter() = default;  // the OutFile discards what was not closed

bool PcapngWriter::open(const std::string& path) {
  State& s = *state_;
  s.out.discard();
  s.error.clear();
  s.packets = 0;
  s.held.clear();
  // Both blocks before the file: an option they cannot hold leaves nothing behind.
  std::vector<std::uint8_t> shb;
  std::vector<std::uint8_t> idb;
  try {
    shb = section_header_block(s.opt);
    idb = interface_description_block(s.opt);
  } catch (const std::length_error& e) {
    return s.fail(fmt::format("{}: {}", path, e.what()));
  }
  if (!s.out.open(path)) return s.fail(s.out.error());
  return s.put(shb) && s.put(idb);
}

bool PcapngWriter::add(const Packet& p) { return state_->add(p); }

bool PcapngWriter::add(const Telegram& t, std::uint32_t clock_hz) {
  return state_->add(t, clock_hz);
}

void PcapngWriter::attach(Chip& chip) {
  const std::uint32_t hz = chip.clock_hz();
  std::weak_ptr<State> weak = state_;
  chip.on_telegram([weak, hz](const Telegram& t) {
    const std::shared_ptr<State> s = weak.lock();
    if (!s || !s->out.is_open()) return;  // writer gone or closed
    s->report(t, hz);
  });
}

bool PcapngWriter::close() {
  State& s = *state_;
  if (!s.out.is_open()) return s.fail("no capture file is open");
  s.flush_held(std::numeric_limits<std::uint64_t>::max());
  if (!s.error.empty()) {
    s.out.discard();
    return false;
  }
  return s.out.commit() || s.fail(s.out.error());
}

void PcapngWriter::discard() {
  state_->out.discard();
  state_->held.clear();
}

bool PcapngWriter::is_open() const { return state_->out.is_open(); }
const std::string& PcapngWriter::error() const { return state_->error; }
std::uint64_t PcapngWriter::packets() const { return state_->packets; }

}  // namespace dpc31::capture
