// The snapshot container (magic, version, header, CRC) and the field encoding the blocks share.
// Layout and messages: docs/snapshots.md.
#include "snapshot.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "dpc31/reg_ids.hpp"
#include "outfile.hpp"
#include "textfile.hpp"

namespace dpc31::snap {

namespace {

constexpr std::array<std::uint8_t, 8> kMagic = {'D', 'P', 'C', '3', '1', 'S', 'N', 'P'};
// Header offsets (docs/snapshots.md, "Byte layout").
constexpr std::size_t kOffVersion = 8;
constexpr std::size_t kOffProfile = 12;
constexpr std::size_t kOffBus = 13;
constexpr std::size_t kOffReserved = 14;
constexpr std::size_t kOffClock = 16;
constexpr std::size_t kOffRegisterMap = 20;
constexpr std::size_t kOffLength = 24;
constexpr std::size_t kOffCrc = 32;
static_assert(kOffCrc + 4 == kHeaderSize);

std::uint64_t get_le(std::span<const std::uint8_t> b, std::size_t off, std::size_t n) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) v |= std::uint64_t{b[off + i]} << (8 * i);
  return v;
}

void put_le(std::vector<std::uint8_t>& out, std::uint64_t v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

std::string bus_name(BusMode b) { return b == BusMode::intel ? "intel" : "motorola"; }

}  // namespace

// ---- Writer ----

void Writer::section(std::string_view tag) { out_.insert(out_.end(), tag.begin(), tag.end()); }

void Writer::put(std::uint64_t v, std::size_t n) { put_le(out_, v, n); }

void Writer::byte_vector(const std::vector<std::uint8_t>& v, std::size_t /*max*/) {
  put(v.size(), 4);
  raw(v);
}

void Writer::fixed_bytes(std::span<const std::uint8_t> b) {
  put(b.size(), 4);
  raw(b);
}

// ---- Reader ----

void Reader::fail(std::string_view what) const {
  throw SnapshotError(
      fmt::format("malformed snapshot payload (section {}, byte {}): {}", section_, pos_, what));
}

void Reader::fail_range(std::uint64_t v, std::uint64_t max) const {
  fail(fmt::format("value {} out of range (at most {})", v, max));
}

std::uint64_t Reader::get(std::size_t n) {
  if (in_.size() - pos_ < n) fail("ends inside a field");
  const std::uint64_t v = get_le(in_, pos_, n);
  pos_ += n;
  return v;
}

void Reader::section(std::string_view tag) {
  const std::size_t at = pos_;
  if (in_.size() - pos_ < tag.size() ||
      !std::equal(tag.begin(), tag.end(), in_.begin() + static_cast<std::ptrdiff_t>(pos_))) {
    fail(fmt::format("section '{}' expected at byte {}", tag, at));
  }
  pos_ += tag.size();
  section_ = std::string(tag.substr(0, tag.find_last_not_of(' ') + 1));
}

void Reader::operator()(bool& v) {
  const std::uint64_t b = get(1);
  if (b > 1) fail(fmt::format("boolean {} is neither 0 nor 1", b));
  v = b != 0;
}

std::size_t Reader::count(std::size_t max) {
  const std::uint64_t n = get(4);
  if (n > max) fail(fmt::format("count {} exceeds {}", n, max));
  // Every item takes at least one byte: a count beyond the input cannot be honest.
  if (n > in_.size() - pos_) fail(fmt::format("count {} exceeds the bytes left", n));
  return static_cast<std::size_t>(n);
}

void Reader::expect_count(std::size_t n) {
  const std::uint64_t got = get(4);
  if (got != n) fail(fmt::format("{} entries where this chip has {}", got, n));
}

void Reader::size(std::size_t& v, std::size_t max) {
  const std::uint64_t n = get(4);
  if (n > max) fail_range(n, max);
  v = static_cast<std::size_t>(n);
}

void Reader::raw(std::span<std::uint8_t> b) {
  if (in_.size() - pos_ < b.size()) fail("ends inside a field");
  std::copy_n(in_.begin() + static_cast<std::ptrdiff_t>(pos_), b.size(), b.begin());
  pos_ += b.size();
}

void Reader::byte_vector(std::vector<std::uint8_t>& v, std::size_t max) {
  v.resize(count(max));
  raw(v);
}

void Reader::fixed_bytes(std::span<std::uint8_t> b) {
  expect_count(b.size());
  raw(b);
}

void Reader::finish() const {
  if (pos_ != in_.size()) fail(fmt::format("{} bytes after the last section", in_.size() - pos_));
}

// ---- CRC, container ----

std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) != 0 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (const std::uint8_t b : bytes) crc = table[(crc ^ b) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

std::uint32_t register_map_fingerprint() {
  std::uint32_t crc = 0;
  for (const std::string_view name : kRegIdNames) {
    crc = crc32({reinterpret_cast<const std::uint8_t*>(name.data()), name.size()}, crc);
    const std::uint8_t sep = '\n';
    crc = crc32({&sep, 1}, crc);
  }
  return crc;
}

std::vector<std::uint8_t> seal(const Header& h, std::span<const std::uint8_t> payload) {
  std::vector<std::uint8_t> out(kMagic.begin(), kMagic.end());
  out.reserve(kHeaderSize + payload.size());
  put_le(out, kFormatVersion, 4);
  put_le(out, static_cast<std::uint8_t>(h.profile), 1);
  put_le(out, static_cast<std::uint8_t>(h.bus), 1);
  put_le(out, 0, 2);
  put_le(out, h.clock_hz, 4);
  put_le(out, h.register_map, 4);
  put_le(out, payload.size(), 8);
  const std::uint32_t crc = crc32(payload, crc32(out));
  put_le(out, crc, 4);
  out.insert(out.end(), payload.begin(), payload.end());
  return out;
}

std::span<const std::uint8_t> open(std::span<const std::uint8_t> bytes, const Header& chip) {
  const std::size_t n = bytes.size();
  if (!std::equal(bytes.begin(),
                  bytes.begin() + static_cast<std::ptrdiff_t>(std::min(n, kMagic.size())),
                  kMagic.begin())) {
    throw SnapshotError("not a dpc31emu snapshot (bad magic)");
  }
  // Magic and version are where they are in every format version; the rest is per version.
  if (n >= kOffVersion + 4) {
    const std::uint64_t v = get_le(bytes, kOffVersion, 4);
    if (v > kFormatVersion) {
      throw SnapshotError(fmt::format(
          "snapshot format version {} is newer than this build reads ({})", v, kFormatVersion));
    }
    if (v < kFormatVersion) {
      throw SnapshotError(
          fmt::format("snapshot format version {} is not supported (this build reads version {})",
                      v, kFormatVersion));
    }
  }
  if (n < kHeaderSize) {
    throw SnapshotError(
        fmt::format("truncated snapshot: {} bytes, the header alone is {}", n, kHeaderSize));
  }
  const std::uint64_t length = get_le(bytes, kOffLength, 8);
  if (length > n - kHeaderSize) {
    throw SnapshotError(fmt::format(
        "truncated snapshot: {} bytes, its header announces a {}-byte payload", n, length));
  }
  if (length < n - kHeaderSize) {
    throw SnapshotError(fmt::format("trailing garbage: the file is {} bytes, the snapshot {}", n,
                                    kHeaderSize + length));
  }
  const std::span<const std::uint8_t> payload = bytes.subspan(kHeaderSize);
  const auto stored = static_cast<std::uint32_t>(get_le(bytes, kOffCrc, 4));
  const std::uint32_t crc = crc32(payload, crc32(bytes.first(kOffCrc)));
  if (crc != stored) {
    throw SnapshotError(fmt::format(
        "corrupted snapshot: CRC32 {:08x} does not match the stored {:08x}", crc, stored));
  }
  const std::uint64_t profile = bytes[kOffProfile];
  const std::uint64_t bus = bytes[kOffBus];
  if (profile >= std::size(kAllProfiles) || bus > 1 || get_le(bytes, kOffReserved, 2) != 0) {
    throw SnapshotError(
        "malformed snapshot header: unknown profile or bus mode, or reserved bytes set");
  }
  const Header h{static_cast<Profile>(profile), static_cast<BusMode>(bus),
                 static_cast<std::uint32_t>(get_le(bytes, kOffClock, 4)),
                 static_cast<std::uint32_t>(get_le(bytes, kOffRegisterMap, 4))};
  if (h.profile != chip.profile) {
    throw SnapshotError(fmt::format("snapshot of a {} chip cannot be loaded into a {} chip",
                                    profile_name(h.profile), profile_name(chip.profile)));
  }
  if (h.bus != chip.bus) {
    throw SnapshotError(
        fmt::format("snapshot of a chip on the {} bus cannot be loaded into a chip on the {} bus",
                    bus_name(h.bus), bus_name(chip.bus)));
  }
  if (h.clock_hz != chip.clock_hz) {
    throw SnapshotError(fmt::format(
        "snapshot of a chip clocked at {} Hz cannot be loaded into a chip clocked at {} Hz",
        h.clock_hz, chip.clock_hz));
  }
  if (h.register_map != chip.register_map) {
    throw SnapshotError(fmt::format(
        "snapshot written with another register description (register map {:08x}, this build "
        "{:08x})",
        h.register_map, chip.register_map));
  }
  return payload;
}

// ---- files ----

void write_file_atomic(const std::string& path, std::span<const std::uint8_t> bytes) {
  std::string error;
  if (!outfile::write_file(path, {reinterpret_cast<const char*>(bytes.data()), bytes.size()},
                           error)) {
    throw SnapshotError(error);
  }
}

std::vector<std::uint8_t> read_file(const std::string& path) {
  if (path.empty()) throw SnapshotError(std::string(outfile::kEmptyReadName));  // no ": why"
  std::string text;
  std::string error;
  if (!read_text_file(path, kMaxFileSize, "snapshot", text, error)) {
    throw SnapshotError(fmt::format("{}: {}", path, error));
  }
  return {text.begin(), text.end()};
}

}  // namespace dpc31::snap
