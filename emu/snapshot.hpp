// Snapshot encoding shared by the blocks (docs/snapshots.md). Each block lists its fields once,
// in a template run with a Writer (save) or a Reader (load):
//
//   template <typename Ar, typename S> void fields(Ar& ar, S& s) { ar(s.a); ar.bounded(s.e, 2); }
//   void save_state(snap::Writer& w, const Block& s) { w.section("BLCK"); fields(w, s); }
//   void load_state(snap::Reader& r, Block& s) { r.section("BLCK"); fields(r, s); }
//
// so save and load cannot drift apart. Everything is little-endian; the Reader checks every
// length and range and throws SnapshotError, never reads past its input.
#pragma once

#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "dpc31/regdesc.hpp"
#include "dpc31/snapshot.hpp"

namespace dpc31::snap {

// Fields taken by operator(): unsigned integers and enums (stored with the size of their
// unsigned underlying type); bool has its own overload (one byte, 0 or 1).
template <typename T>
concept Scalar = (std::unsigned_integral<T> && !std::same_as<T, bool>) || std::is_enum_v<T>;

class Writer {
 public:
  // A 4-character section tag, checked on load (a writer/reader mismatch fails at the section).
  void section(std::string_view tag);
  void operator()(bool v) { out_.push_back(v ? 1 : 0); }
  template <Scalar T>
  void operator()(T v) {
    put(static_cast<std::uint64_t>(v), sizeof(T));
  }
  // A value that must not exceed `max` (checked on load).
  template <Scalar T>
  void bounded(T v, T /*max*/) {
    (*this)(v);
  }
  // A std::size_t, stored as 32 bits.
  void size(std::size_t v, std::size_t /*max*/) { put(v, 4); }
  // A byte vector of at most `max` bytes: 32-bit length, then the bytes.
  void byte_vector(const std::vector<std::uint8_t>& v, std::size_t /*max*/);
  // Bytes whose number the loading chip already knows (RAM): 32-bit length (checked), bytes.
  void fixed_bytes(std::span<const std::uint8_t> b);
  // Bytes without a length (the field before them gave it).
  void raw(std::span<const std::uint8_t> b) { out_.insert(out_.end(), b.begin(), b.end()); }
  template <typename T, std::size_t N>
  void array(const std::array<T, N>& a) {
    put(N, 4);
    for (const T& x : a) (*this)(x);
  }
  // A container of items: 32-bit count, then item(ar, x) for each.
  template <typename C, typename F>
  void sequence(const C& c, std::size_t /*max*/, F&& item) {
    put(c.size(), 4);
    for (const auto& x : c) item(*this, x);
  }
  // Another block's state: its save_state member or free function.
  template <typename T>
  void block(const T& x) {
    if constexpr (requires { x.save_state(*this); }) {
      x.save_state(*this);
    } else {
      save_state(*this, x);
    }
  }
  [[nodiscard]] const std::vector<std::uint8_t>& bytes() const { return out_; }

 private:
  void put(std::uint64_t v, std::size_t n);
  std::vector<std::uint8_t> out_;
};

class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> in) : in_(in) {}

  void section(std::string_view tag);
  void operator()(bool& v);
  template <Scalar T>
  void operator()(T& v) {
    v = static_cast<T>(get(sizeof(T)));
  }
  template <Scalar T>
  void bounded(T& v, T max) {
    (*this)(v);
    if (v > max) fail_range(static_cast<std::uint64_t>(v), static_cast<std::uint64_t>(max));
  }
  void size(std::size_t& v, std::size_t max);
  void byte_vector(std::vector<std::uint8_t>& v, std::size_t max);
  void fixed_bytes(std::span<std::uint8_t> b);
  void raw(std::span<std::uint8_t> b);
  template <typename T, std::size_t N>
  void array(std::array<T, N>& a) {
    expect_count(N);
    for (T& x : a) (*this)(x);
  }
  template <typename C, typename F>
  void sequence(C& c, std::size_t max, F&& item) {
    c.clear();
    c.resize(count(max));
    for (auto& x : c) item(*this, x);
  }
  template <typename T>
  void block(T& x) {
    if constexpr (requires { x.load_state(*this); }) {
      x.load_state(*this);
    } else {
      load_state(*this, x);
    }
  }
  // After the last field: the payload must be used up.
  void finish() const;
  // Refuses a value that breaks a block's invariant (a crafted file with a valid CRC).
  [[noreturn]] void fail(std::string_view what) const;

 private:
  std::uint64_t get(std::size_t n);
  std::size_t count(std::size_t max);  // 32-bit count, at most max and at most what is left
  void expect_count(std::size_t n);
  [[noreturn]] void fail_range(std::uint64_t v, std::uint64_t max) const;

  std::span<const std::uint8_t> in_;
  std::size_t pos_ = 0;
  std::string section_ = "header";
};

// Number of members of an aggregate (an array member counts once per element). The blocks
// static_assert it next to their field lists, so a new member cannot be left out silently.
namespace detail {
struct AnyMember {
  template <typename T>
  operator T() const;  // never defined: unevaluated contexts only
};
}  // namespace detail

template <typename T, typename... A>
consteval std::size_t member_count() {
  if constexpr (requires { T{A{}..., detail::AnyMember{}}; }) {
    return member_count<T, A..., detail::AnyMember>();
  } else {
    return sizeof...(A);
  }
}

// CRC-32 (IEEE 802.3, reflected, polynomial EDB88320h, as zlib's crc32()).
[[nodiscard]] std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);

// The container around a payload (docs/snapshots.md, "Byte layout").
inline constexpr std::uint32_t kFormatVersion = 7;
inline constexpr std::size_t kHeaderSize = 36;
// load_state_file refuses larger files (a snapshot is about 8 KB plus what is queued).
inline constexpr std::size_t kMaxFileSize = kMaxSnapshotFileBytes;

struct Header {
  Profile profile;
  BusMode bus;
  std::uint32_t clock_hz;
  std::uint32_t register_map;  // register_map_fingerprint() of the build that wrote it
};

// CRC-32 of the RegId names in order: snapshots store latches by RegId, so a build with another
// register description cannot read them.
[[nodiscard]] std::uint32_t register_map_fingerprint();

[[nodiscard]] std::vector<std::uint8_t> seal(const Header& h,
                                             std::span<const std::uint8_t> payload);
// Checks magic, version, length, CRC, then that the header matches `chip`; returns the payload.
[[nodiscard]] std::span<const std::uint8_t> open(std::span<const std::uint8_t> bytes,
                                                 const Header& chip);

// Writes `bytes` to a temporary file next to `path` and renames it over `path`; on any error
// the temporary file is removed and SnapshotError("PATH: reason") thrown.
void write_file_atomic(const std::string& path, std::span<const std::uint8_t> bytes);
// The whole file (at most kMaxFileSize bytes); SnapshotError("PATH: reason") when unreadable; for
// "" the words of an empty option, no "PATH: ".
[[nodiscard]] std::vector<std::uint8_t> read_file(const std::string& path);

}  // namespace dpc31::snap
