// VCD reader (IEEE 1364-2005 §18): header into names and slots, then a buffered tokenizer that
// applies one time step per call. Memory: one read buffer (1 MiB, grows only for a longer
// token), the identifier table and the slots, i.e. proportional to the number of signals.
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "textfile.hpp"
#include "wave_reader_impl.hpp"

namespace dpc31::wavediff {

namespace {

constexpr std::size_t kBufSize = std::size_t{1} << 20;
// The longest valid token is a value of the widest $var (2^24 bits): 16 Mi characters. The
// buffer doubles from kBufSize, so 32 MiB holds it; a longer token is no VCD, refused before it
// costs more memory.
constexpr std::size_t kMaxToken = std::size_t{1} << 25;
constexpr std::uint32_t kNone = UINT32_MAX;
constexpr std::size_t kNoStep = SIZE_MAX;

// Identifier codes. VCD writers number their signals in base 94 over '!'..'~', so codes of 1 to
// 3 such characters (up to 94^3 signals) are the common case: they index a direct table, one
// tier per length, allocated when the first code of that length is declared (3.4 MB once there
// are 3-character codes). Every other code (longer, or with other bytes) goes to the fallback:
// packed into a 64-bit key in an open-addressing table up to 8 characters, a map beyond.
class IdTable {
 public:
  [[nodiscard]] std::uint32_t find(std::string_view id) const {
    const std::size_t d = direct_index(id);
    if (d != kNotDirect) return d < direct_.size() ? direct_[d] : kNone;
    return find_other(id);
  }
  void insert(std::string_view id, std::uint32_t v) {
    const std::size_t d = direct_index(id);
    if (d != kNotDirect) {
      if (d >= direct_.size()) direct_.resize(kTierEnd[id.size() - 1], kNone);
      direct_[d] = v;
      return;
    }
    if (id.size() > 8) {
      long_.emplace(std::string(id), v);
      return;
    }
    if ((count_ + 1) * 2 > keys_.size()) grow();
    put(pack(id), v);
    ++count_;
  }

 private:
  static constexpr std::size_t kNotDirect = SIZE_MAX;
  static constexpr std::size_t kRadix = '~' - '!' + 1;  // 94
  // End of each length's tier in direct_: lengths 1, 2 and 3 follow each other.
  static constexpr std::size_t kTierEnd[3] = {kRadix, kRadix + kRadix* kRadix,
                                              kRadix + kRadix* kRadix + kRadix* kRadix* kRadix};

  std::vector<std::uint32_t> direct_;
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> vals_;
  std::size_t count_ = 0;
  int shift_ = 64;
  std::unordered_map<std::string, std::uint32_t> long_;

  // Index in direct_ of a code of 1 to 3 characters from '!' to '~', else kNotDirect.
  static std::size_t direct_index(std::string_view id) {
    const std::size_t n = id.size();
    if (n == 0 || n > 3) return kNotDirect;
    std::size_t i = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t c = static_cast<unsigned char>(id[k]) - std::size_t{'!'};
      if (c >= kRadix) return kNotDirect;  // also below '!': unsigned wrap-around
      i = i * kRadix + c;
    }
    return n == 1 ? i : kTierEnd[n - 2] + i;
  }
  // Out of line, so that find() stays small enough to be inlined into the value parser.
  [[gnu::noinline]] [[nodiscard]] std::uint32_t find_other(std::string_view id) const {
    if (id.size() <= 8) {
      if (keys_.empty()) return kNone;
      const std::uint64_t k = pack(id);
      std::size_t i = hash(k);
      for (;;) {
        if (keys_[i] == k) return vals_[i];
        if (keys_[i] == 0) return kNone;
        i = (i + 1) & (keys_.size() - 1);
      }
    }
    auto it = long_.find(std::string(id));
    return it == long_.end() ? kNone : it->second;
  }
  // Byte by byte: a variable-length memcpy into the key stalls on store forwarding.
  static std::uint64_t pack(std::string_view id) {
    std::uint64_t k = 0;
    for (std::size_t i = 0; i < id.size(); ++i) {
      k |= std::uint64_t{static_cast<unsigned char>(id[i])} << (8 * i);
    }
    return k;  // never 0: identifier characters are printable
  }
  [[nodiscard]] std::size_t hash(std::uint64_t k) const {
    return static_cast<std::size_t>((k * 0x9E3779B97F4A7C15ULL) >> shift_);
  }
  void put(std::uint64_t k, std::uint32_t v) {
    std::size_t i = hash(k);
    while (keys_[i] != 0) i = (i + 1) & (keys_.size() - 1);
    keys_[i] = k;
    vals_[i] = v;
  }
  void grow() {
    std::vector<std::uint64_t> ok = std::move(keys_);
    std::vector<std::uint32_t> ov = std::move(vals_);
    const std::size_t n = ok.empty() ? 64 : ok.size() * 2;
    keys_.assign(n, 0);
    vals_.assign(n, kNone);
    shift_ = 64 - std::countr_zero(n);
    for (std::size_t i = 0; i < ok.size(); ++i) {
      if (ok[i] != 0) put(ok[i], ov[i]);
    }
  }
};

// Eight bytes at a time (SWAR). load8: unaligned little-endian load.
std::uint64_t load8(const char* p) {
  std::uint64_t x = 0;
  std::memcpy(&x, p, sizeof x);
  if constexpr (std::endian::native == std::endian::big) x = __builtin_bswap64(x);
  return x;
}
constexpr std::uint64_t kOnes = 0x0101010101010101ULL;
// Index (0..7) of the first byte of x at or below ' ' (whitespace and control), 8 if none. The
// borrow trick flags every byte below 0x21 (bytes from 0x80 never: they are token characters);
// it may also flag bytes after the first one below, never before, so the lowest flag is exact.
unsigned first_blank(std::uint64_t x) {
  const std::uint64_t m = (x - kOnes * 0x21) & ~x & (kOnes * 0x80);
  return m == 0 ? 8 : static_cast<unsigned>(std::countr_zero(m)) / 8;
}
// White space between VCD tokens (IEEE 1364-2005 18.2: tokens are separated by white space, which
// 3.2 names as blanks, tabs, newlines and form feeds) and CR (Windows line ends). Every other byte
// at or below ' ' (NUL, ESC, VT) marks a damaged or binary file: it split tokens as a blank would.
// For c <= ' ' only: one shift on the hot path.
constexpr std::uint64_t kBlanks =
    1ULL << ' ' | 1ULL << '\n' | 1ULL << '\t' | 1ULL << '\r' | 1ULL << '\f';
constexpr bool vcd_blank(unsigned char c) { return ((kBlanks >> c) & 1U) != 0; }
// All eight bytes are '0' or '1' (0x30, 0x31).
bool all_binary(std::uint64_t x) { return (x | kOnes) == kOnes * 0x31; }

// value_char() as a table: one load per character of a vector instead of a switch.
constexpr auto kValueChar = [] {
  std::array<char, 256> t{};
  for (std::size_t i = 0; i < t.size(); ++i) t[i] = value_char(static_cast<char>(i));
  return t;
}();

bool is_real_type(std::string_view t) { return t == "real" || t == "realtime" || t == "shortreal"; }

class VcdReader final : public WaveReader {
 public:
  VcdReader(const std::string& path, int fd, std::string_view prefix)
      : fd_{fd}, buf_(std::max(kBufSize, prefix.size())) {
    path_ = path;
    format_ = "vcd";
    if (!prefix.empty()) {
      std::memcpy(buf_.data(), prefix.data(), prefix.size());
      end_ = prefix.size();
      any_byte_ = true;
      last_byte_ = prefix.back();
    }
    parse_header();
    prime();
  }

  bool has_next() override { return has_next_; }
  std::uint64_t next_time() override { return pending_; }
  std::uint64_t line() const override { return line_; }
  const std::vector<std::uint32_t>& step() override;
  bool can_follow(const WaveReader& leader) const override;
  bool follow(const WaveReader& leader) override;

 private:
  struct Fd {
    int fd;
    explicit Fd(int f) : fd(f) {}
    ~Fd() { ::close(fd); }
    Fd(const Fd&) = delete;
    Fd& operator=(const Fd&) = delete;
  };
  Fd fd_;
  std::vector<char> buf_;
  std::size_t pos_ = 0;
  std::size_t end_ = 0;
  bool eof_ = false;
  bool any_byte_ = false;
  char last_byte_ = '\n';
  bool cut_ = false;  // the token next_token() gave last runs into the end of the file
  std::uint64_t line_ = 1;
  std::uint64_t tok_line_ = 1;
  IdTable ids_;
  bool has_next_ = false;
  std::uint64_t pending_ = 0;
  bool has_pushed_ = false;
  std::string_view pushed_;
  std::string section_;  // open $dumpvars/$dumpon/$dumpoff/$dumpall section
  std::uint64_t section_line_ = 0;
  std::string scratch_;
  std::string_view* hold_ = nullptr;  // moved to scratch_ by refill() (see apply())
  bool first_step_ = true;
  // The bytes of the last step() (for follow()): buf_[step_begin_, pos_), kNoStep if they are not
  // all in the buffer. The line and the open section where it began.
  std::size_t step_begin_ = kNoStep;
  std::uint64_t step_line_ = 0;
  std::string step_section_;
  std::string codes_;  // the header's identifier codes and their slots, in order (can_follow)
  std::uint64_t dropped_ =
      0;  // bytes of the input before buf_[0]: pos_ is input byte dropped_ + pos_
  // follow(): input bytes [agree_b_, agree_b_ + agreed_) here equal the leader's from agree_a_ on.
  std::uint64_t agree_a_ = 0;
  std::uint64_t agree_b_ = 0;
  std::size_t agreed_ = 0;

  [[noreturn]] void error(std::uint64_t line, const std::string& what) const {
    // The token in hand was cut with the file's last line: that is the error, not what the cut
    // token would mean (a time "#125" of "#1255583333" going backwards, a keyword cut short).
    fail(path_, line, cut_ ? "truncated: the last line has no end of line" : what);
  }

  // Out of the token loops' way.
  [[noreturn, gnu::cold, gnu::noinline]] void bad_byte(char c, std::uint64_t line) const {
    error(line, not_text(static_cast<unsigned char>(c)));
  }

  // Reads more input after keeping buf_[keep_from, end_), or from the start of the current step
  // while that is at most half the buffer (follow() reads it; a longer step is not followed).
  // What is kept moves to the start: pos_, keep_from and step_begin_ move down with it. Called
  // with pos_ == end_ or (have()) pos_ == keep_from. False at end of file.
  bool refill(std::size_t& keep_from) {
    if (hold_ != nullptr) {  // a vector value that lives in the part about to be dropped
      scratch_.assign(*hold_);
      *hold_ = scratch_;
      hold_ = nullptr;
    }
    std::size_t from = keep_from;
    if (step_begin_ != kNoStep) {
      if (end_ - step_begin_ <= buf_.size() / 2) {
        from = std::min(from, step_begin_);
      } else {
        step_begin_ = kNoStep;
      }
    }
    const std::size_t keep = end_ - from;
    if (from > 0 && keep > 0) std::memmove(buf_.data(), buf_.data() + from, keep);
    if (keep == buf_.size()) {
      if (buf_.size() >= kMaxToken)
        error(line_,
              "a token longer than 32 MiB (the widest value, 2^24 bits, has 16 Mi characters)");
      buf_.resize(buf_.size() * 2);
    }
    end_ = keep;
    pos_ -= from;
    dropped_ += from;
    keep_from -= from;
    if (step_begin_ != kNoStep) step_begin_ -= from;
    if (eof_) return false;
    for (;;) {
      const ssize_t n = ::read(fd_.fd, buf_.data() + end_, buf_.size() - end_);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) error(line_, fmt::format("read error: {}", std::strerror(errno)));
      if (n == 0) {
        eof_ = true;
        return false;
      }
      end_ += static_cast<std::size_t>(n);
      any_byte_ = true;
      last_byte_ = buf_[end_ - 1];
      return true;
    }
  }

  // Next whitespace-separated token (a view into the buffer, valid until the next call).
  // Scans with local pointers: through the members, every byte would store pos_ and line_.
  bool next_token(std::string_view& tok) {
    cut_ = false;
    for (;;) {
      const char* const b = buf_.data();
      const char* p = b + pos_;
      const char* const e = b + end_;
      std::uint64_t lines = 0;
      while (p < e && static_cast<unsigned char>(*p) <= ' ') {
        if (!vcd_blank(static_cast<unsigned char>(*p))) [[unlikely]] {
          bad_byte(*p, line_ + lines);
        }
        lines += *p == '\n' ? 1 : 0;
        ++p;
      }
      line_ += lines;
      pos_ = static_cast<std::size_t>(p - b);
      if (p < e) break;
      std::size_t from = end_;
      if (!refill(from)) return false;
    }
    tok_line_ = line_;
    std::size_t start = pos_;
    for (;;) {
      const char* const b = buf_.data();
      const char* p = b + pos_;
      const char* const e = b + end_;
      while (e - p >= 8) {
        const unsigned k = first_blank(load8(p));
        p += k;
        if (k < 8) goto token_end;
      }
      while (p<e&& static_cast<unsigned char>(*p)> ' ') ++p;
    token_end:
      pos_ = static_cast<std::size_t>(p - b);
      if (p < e) {
        // A control byte inside a token ("#40\x0083333") is the file's error, before the piece
        // before it is taken for a token.
        if (!vcd_blank(static_cast<unsigned char>(*p))) [[unlikely]]
          bad_byte(*p, line_);
        break;
      }
      if (!refill(start)) {
        cut_ = true;
        break;
      }
    }
    tok = std::string_view(buf_.data() + start, pos_ - start);
    return true;
  }

  // At least n bytes from pos_ in the buffer; false if the input ends first or n does not fit.
  bool have(std::size_t n) {
    if (n > buf_.size()) return false;
    while (end_ - pos_ < n) {
      std::size_t from = pos_;
      if (!refill(from)) return end_ - pos_ >= n;
    }
    return true;
  }

  // Tokens up to $end (copied), for header sections.
  std::vector<std::string> until_end(std::string_view kw) {
    std::vector<std::string> out;
    const std::uint64_t at = tok_line_;
    std::string_view t;
    for (;;) {
      if (!next_token(t)) {
        error(tok_line_, fmt::format("truncated: end of file inside {} (from line {})", kw, at));
      }
      if (t == "$end") return out;
      out.emplace_back(t);
    }
  }

  void parse_header();
  void prime();
  void keyword(std::string_view t);
  void apply(std::string_view t);
  void at_eof();
  std::uint32_t lookup(std::string_view id, std::uint64_t line) const {
    const std::uint32_t s = ids_.find(id);
    if (s == kNone) error(line, fmt::format("undeclared identifier '{}'", shown(id)));
    return s;
  }
  std::uint64_t parse_time(std::string_view t) const {
    // Up to 19 digits cannot overflow: one pass without from_chars's checks per digit.
    if (const std::size_t len = t.size() - 1; len != 0 && len <= 19) {
      std::uint64_t v = 0;
      bool digits = true;
      for (std::size_t i = 1; i <= len; ++i) {
        const unsigned d = static_cast<unsigned char>(t[i]) - unsigned{'0'};
        digits = digits && d <= 9;
        v = v * 10 + d;
      }
      if (digits) return v;
    }
    std::uint64_t v = 0;
    const char* b = t.data() + 1;
    const char* e = t.data() + t.size();
    auto r = std::from_chars(b, e, v);
    if (b == e || r.ec != std::errc() || r.ptr != e) {
      error(tok_line_, fmt::format("bad time '{}'", shown(t)));
    }
    return v;
  }
};

void VcdReader::parse_header() {
  Declarations decl(path_);
  std::string_view t;
  bool seen_any = false;
  for (;;) {
    if (!next_token(t)) {
      if (!seen_any) error(1, "empty file");
      error(tok_line_, "truncated: end of file in the header (no $enddefinitions)");
    }
    // libsigrok's VCD export (0.5) opens with a non-standard "META samplerate: N" line: skipped,
    // so that sigrok-cli exports of logic-analyser captures compare.
    if (!seen_any && t == "META") {
      const std::uint64_t meta_line = tok_line_;
      do {
        if (!next_token(t))
          error(tok_line_, "truncated: end of file in the header (no $enddefinitions)");
      } while (tok_line_ == meta_line);
    }
    seen_any = true;
    if (t.empty() || t[0] != '$')
      error(tok_line_, fmt::format("unexpected '{}' in the header", shown(t)));
    const std::string kw(t);
    const std::uint64_t kw_line = tok_line_;
    if (kw == "$enddefinitions") {
      until_end(kw);
      break;
    }
    std::vector<std::string> a = until_end(kw);
    if (kw == "$scope") {
      if (a.size() != 2) error(kw_line, "bad $scope (expected '$scope type name $end')");
      decl.open_scope(a[1], kw_line);
    } else if (kw == "$upscope") {
      if (!decl.close_scope()) error(kw_line, "$upscope without $scope");
    } else if (kw == "$timescale") {
      std::string text;
      for (const auto& s : a) text += s;
      if (!parse_timescale(text, ts_pow_)) {
        error(kw_line,
              fmt::format("bad timescale '{}' (1, 10 or 100 of s ms us ns ps fs)", shown(text)));
      }
    } else if (kw == "$var") {
      // `$var TYPE SIZE ID NAME [RANGE] $end`: another word is a declaration a missing $end let
      // in, or a name with blanks, which no VCD has (they were joined into one name).
      constexpr const char* kVarForm = "(expected '$var type size id name [range] $end')";
      if (a.size() < 4) error(kw_line, fmt::format("bad $var {}", kVarForm));
      const bool range = a.size() == 5 && a[4].starts_with('[');
      if (a.size() > 4 && !range) {
        const std::string& extra = a[a[4].starts_with('[') ? 5 : 4];
        error(kw_line,
              fmt::format("bad $var: unexpected '{}' before its $end {}", shown(extra), kVarForm));
      }
      if (a[0] == "port") error(kw_line, "extended VCD ($var port) is not supported");
      if (a[0] == "string") error(kw_line, "string variables are not supported");
      unsigned width = 0;
      auto r = std::from_chars(a[1].data(), a[1].data() + a[1].size(), width);
      if (r.ec != std::errc() || r.ptr != a[1].data() + a[1].size() || width == 0 ||
          width > (1u << 24)) {
        error(kw_line, fmt::format("bad $var size '{}'", shown(a[1])));
      }
      const bool real = is_real_type(a[0]);
      const std::string ref = range ? a[3] + a[4] : a[3];
      Var v;
      split_reference(ref, v.name, v.msb, v.lsb);
      v.name = decl.name(v.name, kw_line);
      std::uint32_t slot = ids_.find(a[2]);
      if (slot == kNone) {
        decl.slot(real ? 64 : width, kw_line);
        slot = static_cast<std::uint32_t>(slots_.size());
        Slot s;
        s.real = real;
        s.width = real ? 64 : width;
        if (real) {
          s.value = std::numeric_limits<double>::quiet_NaN();
        } else {
          s.bits.assign(width, 'x');
        }
        slots_.push_back(std::move(s));
        ids_.insert(a[2], slot);
        codes_ += fmt::format("{} {}\n", a[2], slot);
      } else if (slots_[slot].real != real || (!real && slots_[slot].width != width)) {
        error(kw_line,
              fmt::format("identifier '{}' declared again with another type or size", shown(a[2])));
      }
      v.slot = slot;
      vars_.push_back(std::move(v));
    }
    // $date, $version, $comment and unknown header sections are skipped.
  }
  if (decl.depth() != 0) error(tok_line_, "$enddefinitions inside an open $scope");
}

void VcdReader::keyword(std::string_view t) {
  if (t == "$dumpvars" || t == "$dumpon" || t == "$dumpoff" || t == "$dumpall") {
    if (!section_.empty()) error(tok_line_, fmt::format("{} inside {}", t, section_));
    section_ = std::string(t);
    section_line_ = tok_line_;
  } else if (t == "$end") {
    if (section_.empty()) error(tok_line_, "$end without an open section");
    section_.clear();
  } else if (t == "$comment") {
    until_end("$comment");
  } else {
    error(tok_line_, fmt::format("unexpected '{}' after $enddefinitions", shown(t)));
  }
}

void VcdReader::apply(std::string_view t) {
  const char c = t[0];
  const std::uint64_t at = tok_line_;
  if (c == 'b' || c == 'B') {
    std::string_view val = t.substr(1);
    if (val.empty()) error(at, fmt::format("bad value '{}'", shown(t)));
    bool plain = true;  // only 0 1 x z: used as it is, without a copy
    std::size_t i0 = 0;
    while (val.size() - i0 >= 8 && all_binary(load8(val.data() + i0))) i0 += 8;
    for (const char ch : val.substr(i0)) {
      const char v = kValueChar[static_cast<unsigned char>(ch)];
      if (v == 0) error(at, fmt::format("bad vector value '{}'", shown(t)));
      plain = plain && v == ch;
    }
    if (!plain) {
      scratch_.resize(val.size());
      for (std::size_t i = 0; i < val.size(); ++i) {
        scratch_[i] = kValueChar[static_cast<unsigned char>(val[i])];
      }
      val = scratch_;
    } else {
      hold_ = &val;  // reading the identifier may refill the buffer under val
    }
    std::string_view id;
    bool has_id = false;
    {
      struct Release {  // also when next_token() throws
        std::string_view*& h;
        ~Release() { h = nullptr; }
      } release{hold_};
      has_id = next_token(id);
    }
    if (!has_id) {
      error(at, "truncated: vector value without identifier");
    }
    const std::uint32_t si = lookup(id, at);
    Slot& s = slots_[si];
    if (s.real) error(at, fmt::format("vector value for real variable '{}'", shown(id)));
    const std::size_t n = val.size();
    if (n >= s.width) {
      const std::size_t extra = n - s.width;
      for (std::size_t i = 0; i < extra; ++i) {
        if (val[i] != '0') {
          error(at,
                fmt::format("value of {} bits for '{}' declared with {}", n, shown(id), s.width));
        }
      }
      std::memcpy(s.bits.data(), val.data() + extra, s.width);
    } else {
      const char pad = val[0] == '1' ? '0' : val[0];
      const std::size_t fill = s.width - n;
      std::memset(s.bits.data(), pad, fill);
      std::memcpy(s.bits.data() + fill, val.data(), n);
    }
    touch(si);
    return;
  }
  if (c == 'r' || c == 'R') {
    double d = 0;
    const char* b = t.data() + 1;
    const char* e = t.data() + t.size();
    auto r = std::from_chars(b, e, d);
    if (b == e || r.ec != std::errc() || r.ptr != e)
      error(at, fmt::format("bad real value '{}'", shown(t)));
    std::string_view id;
    if (!next_token(id)) {
      error(at, "truncated: real value without identifier");
    }
    const std::uint32_t si = lookup(id, at);
    Slot& s = slots_[si];
    if (!s.real) error(at, fmt::format("real value for non-real variable '{}'", shown(id)));
    s.value = d;
    touch(si);
    return;
  }
  const char v = kValueChar[static_cast<unsigned char>(c)];
  if (v == 0) error(at, fmt::format("unexpected '{}'", shown(t)));
  if (t.size() < 2) error(at, fmt::format("value '{}' without identifier", shown(t)));
  const std::uint32_t si = lookup(t.substr(1), at);
  Slot& s = slots_[si];
  if (s.real) error(at, fmt::format("scalar value for real variable '{}'", shown(t.substr(1))));
  if (s.width == 1) {
    s.bits[0] = v;
  } else {
    std::memset(s.bits.data(), v == '1' ? '0' : v, s.width - 1);
    s.bits[s.width - 1] = v;
  }
  touch(si);
}

void VcdReader::at_eof() {
  if (!section_.empty()) {
    error(tok_line_,
          fmt::format("truncated: {} from line {} not closed by $end", section_, section_line_));
  }
  if (any_byte_ && last_byte_ != '\n') {
    error(tok_line_, "truncated: the last line has no end of line");
  }
}

void VcdReader::prime() {
  std::string_view t;
  for (;;) {
    if (!next_token(t)) {
      has_next_ = false;
      at_eof();
      return;
    }
    if (t[0] == '#') {
      pending_ = parse_time(t);
      has_next_ = true;
      return;
    }
    if (t[0] == '$') {
      keyword(t);
      continue;
    }
    pushed_ = t;  // a change before the first #time: time 0
    has_pushed_ = true;
    pending_ = 0;
    has_next_ = true;
    return;
  }
}

const std::vector<std::uint32_t>& VcdReader::step() {
  changed_.clear();
  ++stamp_;
  step_begin_ = kNoStep;
  if (!has_next_) return changed_;
  if (!first_step_ && pending_ < time_) error(tok_line_, "time goes backwards");
  first_step_ = false;
  time_ = pending_;
  if (has_pushed_) {
    has_pushed_ = false;
    apply(pushed_);
  } else {
    step_begin_ = pos_;
    step_line_ = line_;
    if (step_section_ != section_) step_section_ = section_;
  }
  std::string_view t;
  for (;;) {
    if (!next_token(t)) {
      has_next_ = false;
      at_eof();
      return changed_;
    }
    const char c = t[0];
    if (c == '#') {
      const std::uint64_t nt = parse_time(t);
      if (nt < time_) {
        error(tok_line_, fmt::format("time goes backwards ({} after {})", shown(t), time_));
      }
      if (nt == time_) continue;
      pending_ = nt;
      return changed_;
    }
    if (c == '$') {
      keyword(t);
    } else {
      apply(t);
    }
  }
}

bool VcdReader::can_follow(const WaveReader& leader) const {
  const auto* l = dynamic_cast<const VcdReader*>(&leader);
  if (l == nullptr || l->ts_pow_ != ts_pow_ || l->codes_ != codes_) return false;
  if (l->slots_.size() != slots_.size()) return false;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (l->slots_[i].width != slots_[i].width || l->slots_[i].real != slots_[i].real) return false;
  }
  return true;
}

bool VcdReader::follow(const WaveReader& leader) {
  const auto& l = static_cast<const VcdReader&>(leader);
  // The leader's step ran from its next time, like ours, to another one, not to the end of its
  // input (at_eof's checks are left to our own step()).
  if (l.step_begin_ == kNoStep || !l.has_next_ || !has_next_ || has_pushed_ ||
      pending_ != l.time_ || section_ != l.step_section_) {
    return false;
  }
  step_begin_ = kNoStep;  // our own last step's bytes are not needed any more
  const std::size_t n = l.pos_ - l.step_begin_;
  const std::uint64_t at_a = l.dropped_ + l.step_begin_;
  const std::uint64_t at_b = dropped_ + pos_;
  if (at_a != agree_a_ || at_b != agree_b_) agreed_ = 0;  // not where the last comparison ended
  if (n > agreed_) {
    // Compare ahead, once for many steps: all the leader has read from its step on (at least
    // this step), against as much of ours; agreed_ is the length of the equal prefix.
    if (!have(n)) return false;
    const char* const a = l.buf_.data() + l.step_begin_;
    const char* const b = buf_.data() + pos_;
    const std::size_t m = std::min(l.end_ - l.step_begin_, end_ - pos_);
    constexpr std::size_t kChunk = 4096;
    std::size_t k = 0;
    while (k < m && std::memcmp(a + k, b + k, std::min(kChunk, m - k)) == 0) k += kChunk;
    if (k < m) {
      while (a[k] == b[k]) ++k;  // the first difference, inside the chunk that differs
    } else {
      k = m;
    }
    agreed_ = k;
    if (n > agreed_) {
      agreed_ = 0;
      return false;
    }
  }
  agreed_ -= n;
  agree_a_ = at_a + n;
  agree_b_ = at_b + n;
  pos_ += n;
  tok_line_ = line_ + (l.tok_line_ - l.step_line_);
  line_ += l.line_ - l.step_line_;
  time_ = l.time_;
  pending_ = l.pending_;
  first_step_ = false;
  if (section_ != l.section_) section_ = l.section_;
  ++stamp_;
  changed_.clear();
  for (const std::uint32_t si : l.changed_) {
    Slot& s = slots_[si];
    const Slot& from = l.slots_[si];
    std::memcpy(s.bits.data(), from.bits.data(), s.bits.size());
    s.value = from.value;
    s.stamp = stamp_;
  }
  return true;
}

}  // namespace

std::unique_ptr<WaveReader> open_vcd(const std::string& path, int fd, std::string_view prefix) {
  return std::make_unique<VcdReader>(path, fd, prefix);
}

}  // namespace dpc31::wavediff
