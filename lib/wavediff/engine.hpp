// The comparison engine's own types, shared by its three files: wavediff.cpp (names to pairs and
// the walk over both files), diff_vcd.cpp (the diff VCD) and wavedrom.cpp (the WaveDrom excerpt).
// Not part of the library's interface (wavediff.hpp).
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "wave_reader.hpp"
#include "wavediff.hpp"

namespace dpc31::wavediff::detail {

inline constexpr std::uint32_t kNone = UINT32_MAX;

inline std::uint64_t pow10(int n) {
  std::uint64_t v = 1;
  for (int i = 0; i < n; ++i) v *= 10;
  return v;
}

inline std::string fmt_real(double d) {
  if (std::isnan(d)) return "x";
  return fmt::format("{}", d);
}

// ---------------------------------------------------------------------------------------------
// Signals of one side.

struct LSig {
  std::string name;  // matched name: after strip and --map
  std::string orig;  // after strip (B: before --map)
  std::uint32_t width = 1;
  bool real = false;
  int msb = -1;
  int lsb = -1;
  std::uint32_t slot = kNone;            // the whole slot, or
  std::vector<std::uint32_t> bit_slots;  // a joined vector: one 1-bit slot per bit, MSB first
  bool joined_member = false;            // a bit used by a joined vector
  mutable std::string scratch;
};

struct Side {
  std::unique_ptr<WaveReader> r;
  const char* label = "A";
  std::uint64_t div = 1;  // file units per common unit
  std::vector<LSig> sigs;
  std::vector<std::uint32_t> slot_begin;  // slot -> pairs watching it (CSR)
  std::vector<std::uint32_t> slot_pairs;

  [[nodiscard]] std::string_view bits(const LSig& l) const {
    if (l.bit_slots.empty()) return r->slots()[l.slot].bits;
    return joined_bits(l);
  }
  // Out of line: keeps bits() small enough to be inlined into compare().
  [[gnu::noinline]] std::string_view joined_bits(const LSig& l) const {
    l.scratch.resize(l.bit_slots.size());
    for (std::size_t i = 0; i < l.bit_slots.size(); ++i) {
      l.scratch[i] = r->slots()[l.bit_slots[i]].bits[0];
    }
    return l.scratch;
  }
  [[nodiscard]] double real(const LSig& l) const { return r->slots()[l.slot].value; }
  [[nodiscard]] std::string text(const LSig& l) const {
    return l.real ? fmt_real(real(l)) : std::string(bits(l));
  }
  // A time in the common unit, the coarser file's: rounded as the writers round a cycle's
  // time, halves up (docs/waveforms.md), so that dumps of one run at two units agree.
  [[nodiscard]] std::uint64_t norm(std::uint64_t t) const {
    return div == 1 ? t : t / div + (t % div >= div / 2 ? 1 : 0);
  }
  // The last file time that norm() brings to common time `t` or before.
  [[nodiscard]] std::uint64_t last_of(std::uint64_t t) const {
    if (div == 1) return t;
    std::uint64_t v = 0;
    return __builtin_mul_overflow(t, div, &v) || v > UINT64_MAX - div / 2 ? UINT64_MAX
                                                                          : v + div / 2 - 1;
  }
};

struct MapEntry {
  std::string a;
  std::string b;
  std::uint64_t line = 0;
  bool used_a = false;
  bool used_b = false;
};

// Names (names.cpp): a name without the stripped scope; the scopes every variable shares and
// their prefixes; the map file; the base and index of one bit of a split vector.
std::string strip_name(const std::string& name, const std::string& prefix);
std::vector<std::string> common_scopes(const std::vector<Var>& vars);
std::vector<std::string> prefixes(const std::vector<std::string>& scopes);
std::vector<MapEntry> read_map(const std::string& path);
bool bit_of(const std::string& name, std::string& base, int& idx);

// ---------------------------------------------------------------------------------------------

struct Pair {
  std::uint32_t a = 0;
  std::uint32_t b = 0;
  std::string name;
  bool real = false;
  bool dirty = false;
  bool stale = false;  // changed while B followed A, not compared since (Engine::stale_)
  bool a_changed = false;
  bool b_changed = false;
  bool differs = false;   // raw state at the last comparison
  bool mismatch = false;  // inside a stretch of difference
  std::uint64_t start_key = 0;
  Point start_pt;
  std::string start_a;
  std::string start_b;
  std::optional<std::string> start_common;
  std::string last_common;
  bool has_common = false;
  std::uint64_t count = 0;
  Divergence first;
  Point last;
};

class Engine;
using Hook = std::function<bool(Engine&, const Point&, bool full)>;

class Engine {
 public:
  explicit Engine(const Options& o) : o_(o) {}

  void setup(Report& rep);
  void run(const Hook& hook);
  void finish(Report& rep);

  const Options& o_;
  Side A;
  Side B;
  std::vector<Pair> pairs;
  std::vector<std::uint32_t> dirty;
  int pow = 0;
  std::uint32_t clock_a = kNone;  // LSig indices
  std::uint32_t clock_b = kNone;

  [[nodiscard]] bool clock_mode() const { return !o_.clock_a.empty(); }

 private:
  std::uint64_t tol_ = 0;
  // Equal stretches (docs/wavediff.md): follow_ once setup finds that B can take A's steps
  // (the same slots, the same pairs on them); following_ while B does, every slot holding the
  // same value on both sides; stale_ the pairs changed meanwhile (their last common value is
  // brought up to date when following ends). mismatches_: pairs inside a stretch of difference.
  bool follow_ = false;
  bool following_ = false;
  std::vector<std::uint32_t> stale_;
  std::uint64_t mismatches_ = 0;
  std::uint64_t steps_ = 0;
  std::uint64_t followed_ = 0;  // steps B took from A, in all
  std::uint64_t stretch_ = 0;   // of them, since following began
  std::uint64_t retry_at_ = 0;
  std::uint64_t backoff_ = 1;

  void build_names(Side& s, const std::string& strip, std::vector<MapEntry>* map);
  void join_bits(Side& s, const Side& other);
  std::uint32_t find_clock(const Side& s, const std::string& name) const;
  void mark(Side& s, bool is_a);
  // Every step of `s` at common time t (several when its unit is the finer one).
  void mark_time(Side& s, bool is_a, std::uint64_t t);
  void mark_changed(Side& s, const std::vector<std::uint32_t>& changed, bool is_a);
  [[nodiscard]] bool can_follow() const;
  void try_follow();
  void stop_following();
  bool follow_steps(std::uint64_t end, std::uint64_t& t);
  void keep_common(Pair& p, std::string_view bits, double real);
  void compare(std::uint32_t pi, std::uint64_t key, const Point& pt);
  void compare_all(std::uint64_t key, const Point& pt);
  void compare_dirty(std::uint64_t key, const Point& pt);
  // One point of the walk: compare (everything at the first), call the hook; false: stop.
  bool step(std::uint64_t key, const Point& pt, bool& started, const Hook& hook);
  void clear_dirty();
  void record(Pair& p, bool open);
  void run_events(const Hook& hook);
  void run_clock(const Hook& hook);
  std::uint64_t to_common(std::uint64_t fs, bool round_up) const {
    const std::uint64_t u = pow10(pow);
    return fs / u + (round_up && fs % u != 0 ? 1 : 0);
  }
  std::vector<Structural> clock_structural_;
  std::uint64_t edges_ = 0;
};

// The merged waveforms (merge.hpp): opened before the walk, fed every compared point, renamed
// into place after it. --diff-vcd (diff_vcd.cpp); --merge, VCD or FST by the name's extension,
// with its GTKWave save file (merge.cpp).
class MergedWave;
std::shared_ptr<MergedWave> open_diff_vcd(const std::string& path, Engine& e);
std::shared_ptr<MergedWave> open_merge(const std::string& path, Engine& e);
void merged_point(MergedWave& m, Engine& e, const Point& pt, bool full);
void commit_merged(MergedWave& m, const Engine& e);

// The WaveDrom excerpt around the first divergence (wavedrom.cpp): a second pass.
std::string wavedrom_text(const Options& o, const Report& rep);

}  // namespace dpc31::wavediff::detail
