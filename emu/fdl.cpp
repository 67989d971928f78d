// PROFIBUS FDL telegram coding (chip-facts §8). Layout, with [DA..DU] the FCS range:
//   SD1 10 DA SA FC FCS 16          SD2 68 LE LEr 68 DA SA FC DU.. FCS 16
//   SD3 A2 DA SA FC DU(8) FCS 16    SD4 DC DA SA                    SC E5
// The address extension (DSAP, then SSAP) lives at the start of the DU, so SD1 cannot carry it.
#include "dpc31/fdl.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <utility>

#include "dpc31/names.hpp"
#include "snapshot.hpp"

namespace dpc31::fdl {

Frame make_frame(std::uint8_t da, std::uint8_t sa, std::uint8_t fc, std::vector<std::uint8_t> du,
                 std::optional<std::uint8_t> dsap, std::optional<std::uint8_t> ssap) {
  const bool sd1 = du.empty() && !dsap && !ssap;
  return Frame{sd1 ? SD1 : SD2, da, sa, fc, dsap, ssap, std::move(du)};
}

Frame sc() { return Frame{SC, 0, 0, 0, std::nullopt, std::nullopt, {}}; }

Frame token(std::uint8_t da, std::uint8_t sa) {
  return Frame{SD4, da, sa, 0, std::nullopt, std::nullopt, {}};
}

std::uint8_t fcs(std::span<const std::uint8_t> bytes) {
  // Eight bytes at a time (a 244-byte telegram is summed by every encode and decode): the even
  // and the odd bytes of a word added into four 16-bit lanes each, which cannot overflow within
  // 128 words (128 x 2 x 255 < 65536); mod 256 the lanes' sum is the bytes' sum.
  constexpr std::uint64_t kLanes = 0x00FF'00FF'00FF'00FFULL;
  std::uint32_t sum = 0;
  std::size_t i = 0;
  while (bytes.size() - i >= 8) {
    std::uint64_t lanes = 0;
    for (std::size_t words = 0; words < 128 && bytes.size() - i >= 8; ++words, i += 8) {
      std::uint64_t w = 0;
      std::memcpy(&w, bytes.data() + i, 8);
      lanes += (w & kLanes) + ((w >> 8) & kLanes);
    }
    for (; lanes != 0; lanes >>= 16) sum += static_cast<std::uint32_t>(lanes & 0xFFFF);
  }
  for (; i < bytes.size(); ++i) sum += bytes[i];
  return static_cast<std::uint8_t>(sum);
}

std::vector<std::uint8_t> encode(const Frame& f) {
  std::vector<std::uint8_t> out;
  encode(f, out);
  return out;
}

bool encode(const Frame& f, std::vector<std::uint8_t>& out) {
  out.clear();
  const std::size_t saps = (f.dsap ? 1U : 0U) + (f.ssap ? 1U : 0U);
  const bool no_data = saps == 0 && f.du.empty();
  // SC and SD4 carry no addresses beyond DA/SA and no data; refuse rather than drop data.
  if (f.sd == SC) {
    if (no_data) out.push_back(SC);
    return no_data;
  }
  if (f.da > kAddressMask || f.sa > kAddressMask) return false;
  if (f.sd == SD4) {
    if (no_data) out.assign({SD4, f.da, f.sa});
    return no_data;
  }
  // Further address extension is not supported, so a SAP byte must not claim it.
  if ((f.dsap && (*f.dsap & kExtension)) || (f.ssap && (*f.ssap & kExtension))) return false;

  const std::size_t le = 3 + saps + f.du.size();
  // The start of the frame (SD, or SD2 with LE, LEr), then the body in the same block (one
  // allocation per telegram: every request and answer is encoded).
  std::array<std::uint8_t, 4> head{};
  std::size_t body = 1;
  switch (f.sd) {
    case SD1:
      if (!no_data) return false;
      head[0] = SD1;
      break;
    case SD3:
      if (saps + f.du.size() != kSd3DataLength) return false;
      head[0] = SD3;
      break;
    case SD2: {
      if (le < kMinLe || le > kMaxLe) return false;
      const auto l = static_cast<std::uint8_t>(le);
      head = {SD2, l, l, SD2};
      body = head.size();
      break;
    }
    default:
      return false;
  }
  out.reserve(body + le + 2);
  out.assign(head.begin(), head.begin() + static_cast<std::ptrdiff_t>(body));
  out.push_back(static_cast<std::uint8_t>(f.da | (f.dsap ? kExtension : 0)));
  out.push_back(static_cast<std::uint8_t>(f.sa | (f.ssap ? kExtension : 0)));
  out.push_back(f.fc);
  if (f.dsap) out.push_back(*f.dsap);
  if (f.ssap) out.push_back(*f.ssap);
  out.insert(out.end(), f.du.begin(), f.du.end());
  out.push_back(fcs(std::span(out).subspan(body)));
  out.push_back(ED);
  return true;
}

std::string encode_refusal(const Frame& f) {
  std::vector<std::uint8_t> sent;
  if (encode(f, sent)) return {};
  const std::size_t saps = (f.dsap ? 1U : 0U) + (f.ssap ? 1U : 0U);
  const auto du = [&](std::string_view sd, std::string_view carries) {
    return fmt::format("du and SAPs: {} + {} bytes; an {} carries {}", f.du.size(), saps, sd,
                       carries);
  };
  const auto address = [](std::string_view what, unsigned v) {
    return fmt::format("{} {} is out of range (0..127)", what, v);
  };
  if (f.sd == SC) return du("SC (0xE5)", "none");
  if (f.sd != SD1 && f.sd != SD2 && f.sd != SD3 && f.sd != SD4) {
    return fmt::format(
        "sd 0x{:02X} is no start delimiter (SD1 0x10, SD2 0x68, SD3 0xA2, SD4 0xDC, SC 0xE5)",
        f.sd);
  }
  if (f.da > kAddressMask) return address("da", f.da);
  if (f.sa > kAddressMask) return address("sa", f.sa);
  if (f.sd == SD4) return du("SD4 (0xDC, the token)", "none");
  if (f.dsap && (*f.dsap & kExtension)) return address("dsap", *f.dsap);
  if (f.ssap && (*f.ssap & kExtension)) return address("ssap", *f.ssap);
  if (f.sd == SD1) return du("SD1 (0x10)", "none (an SD2 carries them)");
  if (f.sd == SD3) return du("SD3 (0xA2)", "exactly 8 together");
  return du("SD2 (0x68)", "1..246 together (244 of du beside both SAPs)");
}

constexpr std::array<std::string_view, 9> kErrorNames = {"none",        "bad_sd",   "truncated",
                                                         "le_mismatch", "bad_le",   "bad_fcs",
                                                         "wrong_ed",    "oversize", "bad_sap"};
static_assert(kErrorNames.size() == static_cast<std::size_t>(Error::bad_sap) + 1,
              "a new value: name it here");

std::string_view error_name(Error e) { return name_of(e, kErrorNames); }

Decoded decode(std::span<const std::uint8_t> bytes) {
  Decoded d;
  decode(bytes, d);
  return d;
}

void Decoded::clear() {
  error = Error::none;
  frame.sd = SD1;
  frame.da = 0;
  frame.sa = 0;
  frame.fc = 0;
  frame.dsap.reset();
  frame.ssap.reset();
  frame.du.clear();
}

void decode(std::span<const std::uint8_t> b, Decoded& out) {
  out.clear();
  Frame& f = out.frame;
  const auto fail = [&out](Error e) { out.error = e; };
  if (b.empty()) return fail(Error::truncated);
  f.sd = b[0];

  // 1. Framing, in the order the bytes arrive (as the Assembler sees it).
  std::size_t da_at = 1;  // index of DA
  std::size_t total = 0;  // whole frame length
  switch (b[0]) {
    case SC:
      if (b.size() > 1) fail(Error::oversize);
      return;  // sc(): the SD alone
    case SD4:
      total = 3;
      break;
    case SD1:
      total = 6;
      break;
    case SD3:
      total = 4 + kSd3DataLength + 2;
      break;
    case SD2: {
      if (b.size() < 3) return fail(Error::truncated);
      const std::size_t le = b[1];
      if (le != b[2]) return fail(Error::le_mismatch);
      if (le < kMinLe || le > kMaxLe) return fail(Error::bad_le);
      if (b.size() < 4) return fail(Error::truncated);
      if (b[3] != SD2) return fail(Error::bad_sd);
      da_at = 4;
      total = le + 6;
      break;
    }
    default:
      return fail(Error::bad_sd);
  }
  if (b.size() < total) return fail(Error::truncated);
  if (b.size() > total) return fail(Error::oversize);

  const bool dx = (b[da_at] & kExtension) != 0;
  const bool sx = (b[da_at + 1] & kExtension) != 0;
  f.da = b[da_at] & kAddressMask;
  f.sa = b[da_at + 1] & kAddressMask;
  if (f.sd == SD4) {
    // A token has no DU, so an extension bit can only be a corrupt address.
    if (dx || sx) fail(Error::bad_sap);
    return;
  }
  f.fc = b[da_at + 2];

  // 2. Integrity.
  const auto body = b.subspan(da_at, total - da_at - 2);  // DA..last DU byte
  if (fcs(body) != b[total - 2]) return fail(Error::bad_fcs);
  if (b[total - 1] != ED) return fail(Error::wrong_ed);

  // 3. Address extension: DSAP first, then SSAP, both at the start of the DU.
  const std::size_t saps = (dx ? 1U : 0U) + (sx ? 1U : 0U);
  std::size_t at = 3;
  if (saps > body.size() - at) {
    // SD2's LE was too short for the SAP bytes; SD1 has no DU at all (SD3 always has 8).
    return fail(f.sd == SD2 ? Error::bad_le : Error::bad_sap);
  }
  if (dx) {
    if (body[at] & kExtension) return fail(Error::bad_sap);
    f.dsap = body[at++];
  }
  if (sx) {
    if (body[at] & kExtension) return fail(Error::bad_sap);
    f.ssap = body[at++];
  }
  f.du.assign(body.begin() + static_cast<std::ptrdiff_t>(at), body.end());
}

Assembler::Status Assembler::fail(Error e) {
  error_ = e;
  status_ = Status::error;
  return status_;
}

Assembler::Status Assembler::push(std::uint8_t byte) {
  if (status_ == Status::error) return status_;
  if (status_ == Status::complete) return fail(Error::oversize);
  // Unreachable by construction (need_more implies size_ < expected_ <= 255); keeps the bound.
  if (size_ >= buf_.size()) return fail(Error::oversize);
  buf_[size_++] = byte;

  if (size_ == 1) {
    switch (byte) {
      case SC:
        expected_ = 1;
        break;
      case SD4:
        expected_ = 3;
        break;
      case SD1:
        expected_ = 6;
        break;
      case SD3:
        expected_ = 4 + kSd3DataLength + 2;
        break;
      case SD2:
        break;  // length known at LEr
      default:
        return fail(Error::bad_sd);
    }
  } else if (buf_[0] == SD2) {
    if (size_ == 3) {
      // Checked at LEr, as in decode, so both report the same error.
      if (buf_[1] != buf_[2]) return fail(Error::le_mismatch);
      if (buf_[1] < kMinLe || buf_[1] > kMaxLe) return fail(Error::bad_le);
      expected_ = std::size_t{buf_[1]} + 6;
    } else if (size_ == 4 && byte != SD2) {
      return fail(Error::bad_sd);
    }
  }
  if (expected_ != 0 && size_ == expected_) status_ = Status::complete;
  return status_;
}

std::size_t Assembler::push_block(std::span<const std::uint8_t> bytes) {
  std::size_t i = 0;
  // A good SD2 header whole (SD2, LE, LEr, SD2: what push() checks byte by byte, all passing) at
  // once; anything else byte by byte, where push() gives each verdict.
  if (size_ == 0 && status_ == Status::need_more && bytes.size() >= 4 && bytes[0] == SD2 &&
      bytes[1] == bytes[2] && bytes[1] >= kMinLe && bytes[1] <= kMaxLe && bytes[3] == SD2) {
    std::copy_n(bytes.begin(), 4, buf_.begin());
    size_ = 4;
    expected_ = std::size_t{bytes[1]} + 6;
    i = 4;
  }
  while (i < bytes.size() && status_ == Status::need_more) {
    // Past the SD (and for SD2 past the repeated SD) push() checks nothing but the length.
    if (expected_ != 0 && (buf_[0] != SD2 || size_ >= 4)) {
      const std::size_t n = std::min(bytes.size() - i, expected_ - size_);
      std::copy_n(bytes.begin() + static_cast<std::ptrdiff_t>(i), n, buf_.begin() + size_);
      size_ += n;
      i += n;
      if (size_ == expected_) status_ = Status::complete;
    } else {
      push(bytes[i++]);
    }
  }
  return i;
}

void Assembler::reset() {
  size_ = 0;
  expected_ = 0;
  status_ = Status::need_more;
  error_ = Error::none;
}

#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(Assembler) == 280, "a new member of Assembler: add it to Assembler::fields");
#endif

// Only the bytes collected so far: the rest of buf_ is never read.
template <typename Ar, typename Self>
void Assembler::fields(Ar& ar, Self& s) {
  ar.size(s.size_, kMaxFrameLength);
  ar.raw(std::span(s.buf_.data(), s.size_));
  ar.size(s.expected_, kMaxFrameLength);
  ar.bounded(s.status_, Status::error);
  ar.bounded(s.error_, Error::bad_sap);
}

void Assembler::save_state(snap::Writer& w) const {
  w.section("FDLA");
  fields(w, *this);
}

void Assembler::load_state(snap::Reader& r) {
  r.section("FDLA");
  buf_.fill(0);
  fields(r, *this);
}

}  // namespace dpc31::fdl
