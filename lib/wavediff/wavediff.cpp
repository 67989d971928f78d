// The comparison engine: names to pairs (strip, map, split vectors, filters), the time-ordered
// walk over both files (event mode) or over the clock edges of each (clock mode), difference
// stretches with tolerance. The merged waveforms and WaveDrom outputs: diff_vcd.cpp, merge.cpp,
// wavedrom.cpp.
#include "wavediff.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "engine.hpp"
#include "outfile.hpp"
#include "textfile.hpp"

namespace dpc31::wavediff {

namespace detail {

namespace {

// Warnings of one kind: the first kMaxWarnings, then one line with the count of the rest (50 000
// signals named twice were 100 000 lines on stderr).
class Warnings {
 public:
  static constexpr std::size_t kMaxWarnings = 10;
  // `more` is the last line's text after its count: "{where}: warning: N {more}".
  Warnings(std::vector<std::string>& out, std::string where, std::string more)
      : out_(out), where_(std::move(where)), more_(std::move(more)) {}
  void add(std::string warning) {
    if (n_++ < kMaxWarnings) out_.push_back(std::move(warning));
  }
  void finish() {
    if (n_ > kMaxWarnings)
      out_.push_back(fmt::format("{}: warning: {} more {}", where_, n_ - kMaxWarnings, more_));
  }

 private:
  std::vector<std::string>& out_;
  std::string where_;
  std::string more_;
  std::size_t n_ = 0;
};

bool bits_equal(std::string_view a, std::string_view b, XzPolicy p) {
  if (a.size() == b.size() && a == b) return true;
  if (p == XzPolicy::strict && a.size() == b.size()) return false;
  const std::size_t n = std::max(a.size(), b.size());
  const std::size_t pa = n - a.size();
  const std::size_t pb = n - b.size();
  for (std::size_t i = 0; i < n; ++i) {
    char ca = i < pa ? '0' : a[i - pa];
    char cb = i < pb ? '0' : b[i - pb];
    if (ca == cb) continue;
    const bool xa = ca == 'x' || ca == 'z';
    const bool xb = cb == 'x' || cb == 'z';
    if (p == XzPolicy::wildcard) {
      if (xa || xb) continue;
      return false;
    }
    if (p == XzPolicy::zero) {
      if (xa) ca = '0';
      if (xb) cb = '0';
      if (ca == cb) continue;
    }
    return false;
  }
  return true;
}

}  // namespace

std::uint32_t Engine::find_clock(const Side& s, const std::string& name) const {
  for (std::uint32_t pass = 0; pass < 3; ++pass) {
    for (std::uint32_t i = 0; i < s.sigs.size(); ++i) {
      const LSig& l = s.sigs[i];
      if (!l.bit_slots.empty()) continue;
      const std::string& n = pass == 0 ? l.name : pass == 1 ? l.orig : s.r->vars()[i].name;
      if (n == name) return i;
    }
  }
  fail(s.r->path(), 0, fmt::format("no clock signal '{}'", shown(name)));
}

void Engine::setup(Report& rep) {
  // A pipe, FIFO or device named twice (`wavediff /dev/stdin /dev/stdin`) is one stream: B's
  // reader would get what A's left of it, an empty file or a header cut in the middle.
  if (struct stat a{}, b{}; ::stat(o_.file_a.c_str(), &a) == 0 &&
                            ::stat(o_.file_b.c_str(), &b) == 0 && a.st_dev == b.st_dev &&
                            a.st_ino == b.st_ino && !S_ISREG(a.st_mode) && !S_ISDIR(a.st_mode)) {
    fail(o_.file_b, 0,
         fmt::format("the same stream as A ({}), which can be read only once: save it to a file "
                     "to compare it with itself",
                     o_.file_a));
  }
  A.r = open_wave(o_.file_a);
  B.r = open_wave(o_.file_b);
  A.label = "A";
  B.label = "B";
  pow = std::max(A.r->timescale_pow(), B.r->timescale_pow());
  A.div = pow10(pow - A.r->timescale_pow());
  B.div = pow10(pow - B.r->timescale_pow());

  rep.clock_mode = clock_mode();
  rep.file_a = o_.file_a;
  rep.file_b = o_.file_b;
  rep.format_a = A.r->format();
  rep.format_b = B.r->format();
  rep.pow_a = A.r->timescale_pow();
  rep.pow_b = B.r->timescale_pow();
  rep.pow = pow;
  rep.edge = o_.edge;
  rep.ignore_missing = o_.ignore_missing;

  if (clock_mode()) {
    if (o_.tolerance_fs != 0)
      throw OptionError("--tolerance is for event mode; use --tolerance-cycles");
  } else {
    if (o_.tolerance_cycles != 0) throw OptionError("--tolerance-cycles requires --clock");
    if ((o_.start && o_.start->cycles) || (o_.end && o_.end->cycles)) {
      throw OptionError("cycle bounds (c123) need --clock");
    }
    if (!o_.clock_b.empty()) throw OptionError("--clock-b requires --clock");
    if (o_.edge != Edge::rising) throw OptionError("--edge requires --clock");
  }
  tol_ = clock_mode() ? o_.tolerance_cycles : to_common(o_.tolerance_fs, false);
  if (!clock_mode() && o_.end) {  // an FST reader may skip the blocks after the window
    const std::uint64_t e = to_common(o_.end->value, false);
    A.r->set_limit_end(A.last_of(e));
    B.r->set_limit_end(B.last_of(e));
  }

  std::vector<MapEntry> map;
  if (!o_.map_file.empty()) map = read_map(o_.map_file);

  // Strip: explicit scopes, or (auto) the depths that match the most names.
  std::string sa = o_.strip_a;
  std::string sb = o_.strip_b;
  auto check_strip = [](const Side& s, const std::string& p) {
    if (p.empty()) return;
    for (const Var& v : s.r->vars()) {
      if (strip_name(v.name, p) != v.name) return;
    }
    fail(s.r->path(), 0, fmt::format("no signal under scope '{}'", shown(p)));
  };
  check_strip(A, sa);
  check_strip(B, sb);
  if (o_.strip_auto) {
    const auto pa = o_.strip_a.empty() ? prefixes(common_scopes(A.r->vars()))
                                       : std::vector<std::string>{o_.strip_a};
    const auto pb = o_.strip_b.empty() ? prefixes(common_scopes(B.r->vars()))
                                       : std::vector<std::string>{o_.strip_b};
    std::size_t best = 0;
    std::size_t best_depth = SIZE_MAX;
    for (std::size_t i = 0; i < pa.size(); ++i) {
      std::unordered_set<std::string> names;
      for (const Var& v : A.r->vars()) names.insert(strip_name(v.name, pa[i]));
      for (std::size_t k = 0; k < pb.size(); ++k) {
        std::vector<MapEntry> scratch = map;
        build_names(B, pb[k], &scratch);
        std::size_t n = 0;
        for (const LSig& l : B.sigs) n += names.count(l.name);
        if (n > best || (n == best && i + k < best_depth)) {
          best = n;
          best_depth = i + k;
          sa = pa[i];
          sb = pb[k];
        }
      }
    }
  }
  build_names(A, sa, nullptr);
  build_names(B, sb, &map);
  join_bits(A, B);
  join_bits(B, A);
  if (!map.empty()) {
    std::unordered_set<std::string> an;
    for (const LSig& l : A.sigs) an.insert(l.name);
    Warnings not_a(rep.warnings, o_.map_file, "names of the map not in A");
    Warnings not_b(rep.warnings, o_.map_file, "names of the map not in B");
    // Whole names (Reader::kMaxName bounds them): hierarchical ones often share 40 characters.
    for (MapEntry& e : map) {
      if (an.count(e.a) == 0) {
        not_a.add(fmt::format("{}:{}: warning: no signal '{}' in A", o_.map_file, e.line,
                              shown(e.a, kWhole)));
      }
      if (!e.used_b) {
        not_b.add(fmt::format("{}:{}: warning: no signal '{}' in B", o_.map_file, e.line,
                              shown(e.b, kWhole)));
      }
    }
    not_a.finish();
    not_b.finish();
  }

  if (clock_mode()) {
    clock_a = find_clock(A, o_.clock_a);
    clock_b = find_clock(B, o_.clock_b.empty() ? A.sigs[clock_a].name : o_.clock_b);
    for (auto [s, c] : {std::pair{&A, clock_a}, std::pair{&B, clock_b}}) {
      if (s->sigs[c].real || s->sigs[c].width != 1) {
        fail(s->r->path(), 0,
             fmt::format("clock '{}' is not a 1-bit signal", shown(s->sigs[c].name)));
      }
    }
    rep.clock_a = A.sigs[clock_a].name;
    rep.clock_b = B.sigs[clock_b].orig;
  }

  // Pairs by name, after the filters.
  auto wanted = [this](const std::string& n) {
    bool in = o_.include.empty();
    for (const auto& g : o_.include) in = in || glob_match(g, n);
    for (const auto& g : o_.exclude) in = in && !glob_match(g, n);
    return in;
  };
  auto index = [&](Side& s, std::uint32_t clock) {
    std::map<std::string, std::uint32_t> m;
    Warnings twice(rep.warnings, s.r->path(), "signals named twice, the second ignored");
    for (std::uint32_t i = 0; i < s.sigs.size(); ++i) {
      const LSig& l = s.sigs[i];
      if (l.joined_member || i == clock || !wanted(l.name)) continue;
      if (!m.emplace(l.name, i).second) {
        twice.add(fmt::format("{}: warning: two signals named '{}', the second ignored",
                              s.r->path(), l.name));
      }
    }
    twice.finish();
    return m;
  };
  const auto ia = index(A, clock_a);
  const auto ib = index(B, clock_b);
  for (const auto& [name, i] : ia) {
    auto it = ib.find(name);
    if (it == ib.end()) {
      rep.only_a.push_back(name);
      continue;
    }
    const LSig& la = A.sigs[i];
    const LSig& lb = B.sigs[it->second];
    if (la.real != lb.real) {
      rep.structural.push_back(
          {name, fmt::format("real in {}, {} bits in {}", la.real ? "A" : "B",
                             la.real ? lb.width : la.width, la.real ? "B" : "A")});
      continue;
    }
    if (!la.real && la.width != lb.width) {
      rep.structural.push_back(
          {name,
           fmt::format("{} bits in A, {} bits in B (compared zero-extended)", la.width, lb.width)});
    }
    Pair p;
    p.a = i;
    p.b = it->second;
    p.name = name;
    p.real = la.real;
    pairs.push_back(std::move(p));
  }
  for (const auto& [name, i] : ib) {
    if (ia.count(name) == 0) rep.only_b.push_back(B.sigs[i].orig);
  }
  rep.compared = pairs.size();
  // Nothing compared is no verdict: with --ignore-missing it would pass as "same" (an RTL whose
  // top scope was renamed, a --strip gone wrong).
  if (pairs.empty() && rep.structural.empty() &&
      (o_.ignore_missing || (rep.only_a.empty() && rep.only_b.empty()))) {
    throw OptionError(
        fmt::format("no signals to compare: no signal of {} matched one of {} (check "
                    "--strip, --map and --include/--exclude)",
                    o_.file_a, o_.file_b));
  }

  // Which pairs each slot feeds.
  for (Side* s : {&A, &B}) {
    std::vector<std::vector<std::uint32_t>> lists(s->r->slots().size());
    for (std::uint32_t pi = 0; pi < pairs.size(); ++pi) {
      const LSig& l = s->sigs[s == &A ? pairs[pi].a : pairs[pi].b];
      if (l.bit_slots.empty()) {
        lists[l.slot].push_back(pi);
      } else {
        for (std::uint32_t sl : l.bit_slots) lists[sl].push_back(pi);
      }
    }
    s->slot_begin.assign(lists.size() + 1, 0);
    for (std::size_t k = 0; k < lists.size(); ++k) {
      s->slot_begin[k + 1] = s->slot_begin[k] + static_cast<std::uint32_t>(lists[k].size());
      s->slot_pairs.insert(s->slot_pairs.end(), lists[k].begin(), lists[k].end());
    }
  }
  follow_ = o_.follow_equal_bytes && !clock_mode() && can_follow();
}

// B can take A's steps where the bytes agree: its reader can (the same identifier codes for the
// same slots), and every pair watches the same slots on both sides, so that the same changes
// mark the same pairs and leave them equal.
bool Engine::can_follow() const {
  if (!B.r->can_follow(*A.r) || A.div != B.div) return false;
  if (A.slot_begin != B.slot_begin || A.slot_pairs != B.slot_pairs) return false;
  return std::all_of(pairs.begin(), pairs.end(), [this](const Pair& p) {
    const LSig& la = A.sigs[p.a];
    const LSig& lb = B.sigs[p.b];
    return la.slot == lb.slot && la.bit_slots == lb.bit_slots;
  });
}

// After a compared point: B follows A from here if every slot holds the same value on both sides
// (then no pair differs). Tried again after a doubling number of points (up to 1024) when that
// fails, or when following stopped at once: files whose bytes never agree pay little for it.
void Engine::try_follow() {
  if (mismatches_ != 0 || ++steps_ < retry_at_) return;
  const std::vector<Slot>& sa = A.r->slots();
  const std::vector<Slot>& sb = B.r->slots();
  for (std::size_t i = 0; i < sa.size(); ++i) {
    if (sa[i].bits != sb[i].bits || std::memcmp(&sa[i].value, &sb[i].value, sizeof(double)) != 0) {
      retry_at_ = steps_ + backoff_;
      backoff_ = std::min<std::uint64_t>(backoff_ * 2, 1024);
      return;
    }
  }
  following_ = true;
  stretch_ = 0;
}

// B has not followed A's last step: its values are still those before it, A's as well. The pairs
// changed while following were equal at every point; their last common value is the current one.
// A stretch shorter than 64 steps counts as a failed try.
void Engine::stop_following() {
  following_ = false;
  if (stretch_ < 64) {
    retry_at_ = steps_ + backoff_;
    backoff_ = std::min<std::uint64_t>(backoff_ * 2, 1024);
  } else {
    backoff_ = 1;
  }
  for (const std::uint32_t pi : stale_) {
    Pair& p = pairs[pi];
    p.stale = false;
    const LSig& lb = B.sigs[p.b];
    // The values before A's last step on both sides: B's own, A's already moved on.
    keep_common(p, p.real ? std::string_view{} : B.bits(lb), p.real ? B.real(lb) : 0);
  }
  stale_.clear();
}

// B takes A's steps while their bytes agree (the same changes on both sides: all stay equal), up
// to the end of the window. False at a step B did not take: A's changes in it are marked, `t` is
// its time, and B's next time is t as well (it was A's before that step).
bool Engine::follow_steps(std::uint64_t end, std::uint64_t& t) {
  for (;;) {
    const auto& changed = A.r->step();
    if (!B.r->follow(*A.r)) {
      stop_following();
      mark_changed(A, changed, true);
      t = A.norm(A.r->time());
      return false;
    }
    ++followed_;
    ++stretch_;
    for (const std::uint32_t slot : changed) {
      for (std::uint32_t k = A.slot_begin[slot]; k < A.slot_begin[slot + 1]; ++k) {
        Pair& p = pairs[A.slot_pairs[k]];
        if (!p.stale) {
          p.stale = true;
          stale_.push_back(A.slot_pairs[k]);
        }
      }
    }
    if (A.norm(A.r->next_time()) > end) return true;  // follow() leaves both a next step
  }
}

void Engine::keep_common(Pair& p, std::string_view bits, double real) {
  if (p.real) {
    p.last_common = fmt_real(real);
  } else if (p.last_common.size() == bits.size()) {
    // On every equal comparison: a plain copy, not string::assign's general replace.
    std::memcpy(p.last_common.data(), bits.data(), bits.size());
  } else {
    p.last_common.assign(bits);
  }
  p.has_common = true;
}

void Engine::mark(Side& s, bool is_a) { mark_changed(s, s.r->step(), is_a); }

void Engine::mark_time(Side& s, bool is_a, std::uint64_t t) {
  do {
    mark(s, is_a);
  } while (s.div != 1 && s.r->has_next() && s.norm(s.r->next_time()) == t);
}

void Engine::mark_changed(Side& s, const std::vector<std::uint32_t>& changed, bool is_a) {
  for (const std::uint32_t slot : changed) {
    for (std::uint32_t k = s.slot_begin[slot]; k < s.slot_begin[slot + 1]; ++k) {
      const std::uint32_t pi = s.slot_pairs[k];
      Pair& p = pairs[pi];
      if (!p.dirty) {
        p.dirty = true;
        dirty.push_back(pi);
      }
      (is_a ? p.a_changed : p.b_changed) = true;
    }
  }
}

void Engine::clear_dirty() {
  for (const std::uint32_t pi : dirty) {
    Pair& p = pairs[pi];
    p.dirty = p.a_changed = p.b_changed = false;
  }
  dirty.clear();
}

void Engine::record(Pair& p, bool open) {
  if (p.count == 0) {
    p.first.at = p.start_pt;
    p.first.a = p.start_a;
    p.first.b = p.start_b;
    p.first.last_common = p.start_common;
    p.first.open = open;
  }
  ++p.count;
  p.last = p.start_pt;
}

void Engine::compare(std::uint32_t pi, std::uint64_t key, const Point& pt) {
  Pair& p = pairs[pi];
  const LSig& la = A.sigs[p.a];
  const LSig& lb = B.sigs[p.b];
  bool eq = false;
  std::string_view va;
  std::string_view vb;
  if (p.real) {
    const double x = A.real(la);
    const double y = B.real(lb);
    eq = x == y || (std::isnan(x) && std::isnan(y));
  } else {
    va = A.bits(la);
    vb = B.bits(lb);
    eq = bits_equal(va, vb, o_.xz);
  }
  p.differs = !eq;
  if (!eq) {
    if (!p.mismatch) {
      p.mismatch = true;
      ++mismatches_;
      p.start_key = key;
      p.start_pt = pt;
      if (p.real) {
        p.start_a = fmt_real(A.real(la));
        p.start_b = fmt_real(B.real(lb));
      } else {
        p.start_a.assign(va);
        p.start_b.assign(vb);
      }
      if (p.has_common) {
        p.start_common = p.last_common;
      } else {
        p.start_common.reset();
      }
    }
    return;
  }
  if (p.mismatch) {
    p.mismatch = false;
    --mismatches_;
    if (key - p.start_key > tol_) record(p, false);
  }
  keep_common(p, va, p.real ? A.real(la) : 0);
}

void Engine::compare_all(std::uint64_t key, const Point& pt) {
  for (std::uint32_t pi = 0; pi < pairs.size(); ++pi) compare(pi, key, pt);
}

void Engine::compare_dirty(std::uint64_t key, const Point& pt) {
  for (const std::uint32_t pi : dirty) compare(pi, key, pt);
}

bool Engine::step(std::uint64_t key, const Point& pt, bool& started, const Hook& hook) {
  const bool full = !started;
  if (full) {
    compare_all(key, pt);  // the first point compares every pair
    started = true;
  } else {
    compare_dirty(key, pt);
  }
  const bool go_on = !hook || hook(*this, pt, full);
  clear_dirty();
  return go_on;
}

void Engine::run(const Hook& hook) {
  if (clock_mode()) {
    run_clock(hook);
  } else {
    run_events(hook);
  }
}

void Engine::run_events(const Hook& hook) {
  const bool has_start = o_.start.has_value();
  const std::uint64_t start = has_start ? to_common(o_.start->value, true) : 0;
  const std::uint64_t end = o_.end ? to_common(o_.end->value, false) : UINT64_MAX;
  bool started = false;
  bool any = false;
  const bool may_follow = follow_ && !hook;
  for (;;) {
    const bool ha = A.r->has_next();
    const bool hb = B.r->has_next();
    if (!ha && !hb) break;
    const std::uint64_t ta = ha ? A.norm(A.r->next_time()) : UINT64_MAX;
    const std::uint64_t tb = hb ? B.norm(B.r->next_time()) : UINT64_MAX;
    std::uint64_t t = std::min(ta, tb);
    if (t > end) break;
    if (!started && has_start && any && t > start) {
      const Point ps{start, start, 0};
      compare_all(start, ps);
      started = true;
      clear_dirty();
      if (hook && !hook(*this, ps, true)) return;
    }
    bool a_marked = false;
    if (following_) {
      if (ta == t && tb == t) {
        if (follow_steps(end, t)) continue;
        a_marked = true;  // at the new t, B's next time
      } else {
        stop_following();
      }
    }
    if (ta == t && !a_marked) mark_time(A, true, t);
    if (tb == t || a_marked) mark_time(B, false, t);
    any = true;
    if (t < start) {
      clear_dirty();
      continue;
    }
    if (!step(t, Point{t, t, 0}, started, hook)) return;
    if (may_follow) try_follow();
  }
  if (following_) stop_following();
  if (!started && any && has_start && start <= end) {
    const Point ps{start, start, 0};
    compare_all(start, ps);
    clear_dirty();
    if (hook) hook(*this, ps, true);
  }
}

void Engine::run_clock(const Hook& hook) {
  struct Clk {
    Side* s;
    std::uint32_t slot;
    char prev = 'x';
  };
  Clk ca{&A, A.sigs[clock_a].slot};
  Clk cb{&B, B.sigs[clock_b].slot};
  const Edge edge = o_.edge;
  auto advance = [&](Clk& c, bool is_a) {
    while (c.s->r->has_next()) {
      mark(*c.s, is_a);
      const char now = c.s->r->slots()[c.slot].bits[0];
      bool e = false;
      if (c.prev == '0' && now == '1') e = edge != Edge::falling;
      if (c.prev == '1' && now == '0') e = edge != Edge::rising;
      c.prev = now;
      if (e) return true;
    }
    return false;
  };
  const auto& sb = o_.start;
  const auto& eb = o_.end;
  const std::uint64_t start_t = sb && !sb->cycles ? to_common(sb->value, true) : 0;
  const std::uint64_t end_t = eb && !eb->cycles ? to_common(eb->value, false) : UINT64_MAX;
  const std::uint64_t start_c = sb && sb->cycles ? sb->value : 0;
  const std::uint64_t end_c = eb && eb->cycles ? eb->value : UINT64_MAX;
  bool started = false;
  for (std::uint64_t n = 0;; ++n) {
    if (n > end_c) break;
    const bool ea = advance(ca, true);
    const bool eb2 = advance(cb, false);
    if (!ea || !eb2) {
      if (ea && A.norm(A.r->time()) <= end_t) {
        clock_structural_.push_back(
            {A.sigs[clock_a].name,
             fmt::format("clock: B has only {} {} edges, A has more", n, edge_name(edge))});
      } else if (eb2 && !ea && !(o_.end && !o_.end->cycles)) {
        clock_structural_.push_back(
            {A.sigs[clock_a].name,
             fmt::format("clock: A has only {} {} edges, B has more", n, edge_name(edge))});
      }
      break;
    }
    const Point pt{A.norm(A.r->time()), B.norm(B.r->time()), n, A.r->time(), B.r->time()};
    if (pt.time > end_t) break;
    if (n < start_c || pt.time < start_t) {
      clear_dirty();
      continue;
    }
    ++edges_;
    if (!step(n, pt, started, hook)) return;
  }
}

void Engine::finish(Report& rep) {
  for (Pair& p : pairs) {
    if (p.mismatch) {
      p.mismatch = false;
      record(p, true);
    }
  }
  rep.structural.insert(rep.structural.end(), clock_structural_.begin(), clock_structural_.end());
  rep.edges = edges_;
  rep.followed = followed_;
  std::vector<const Pair*> d;
  for (const Pair& p : pairs) {
    if (p.count > 0) d.push_back(&p);
  }
  const bool cm = clock_mode();
  std::stable_sort(d.begin(), d.end(), [cm](const Pair* x, const Pair* y) {
    return cm ? x->first.at.cycle < y->first.at.cycle : x->first.at.time < y->first.at.time;
  });
  for (const Pair* p : d) {
    SignalDiff s;
    s.name = p->name;
    s.name_b = B.sigs[p->b].orig;
    s.count = p->count;
    s.first = p->first;
    s.last = p->last;
    rep.diffs.push_back(std::move(s));
  }
}

}  // namespace detail

using detail::Engine;
using detail::Hook;

const char* edge_name(Edge e) {
  return e == Edge::rising ? "rising" : e == Edge::falling ? "falling" : "both";
}

Report compare(const Options& o) {
  // No output may replace an input, from every door (the CLI, Python): checked before any file
  // is read or opened.
  const std::string same = outfile::distinct(
      {{"A", o.file_a}, {"B", o.file_b}, {"--map", o.map_file}},
      {{"--json", o.json_file},
       {"--diff-vcd", o.diff_vcd},
       {"--wavedrom", o.wavedrom},
       {"--merge", o.merge},
       {"--merge's save file", o.merge.empty() ? std::string() : save_file_name(o.merge), false}});
  if (!same.empty()) throw OptionError(same);
  Report rep;
  Engine e(o);
  e.setup(rep);
  // Every output is opened before the comparison and renamed into place after it, all or none
  // (docs/bad-input.md).
  outfile::OutFile drom;
  if (!o.wavedrom.empty() && !drom.open(o.wavedrom)) throw InputError(drom.error());
  std::vector<std::shared_ptr<detail::MergedWave>> merged;
  if (!o.diff_vcd.empty()) merged.push_back(detail::open_diff_vcd(o.diff_vcd, e));
  if (!o.merge.empty()) merged.push_back(detail::open_merge(o.merge, e));
  Hook hook;
  if (!merged.empty()) {
    hook = [&merged](Engine& en, const Point& pt, bool full) {
      for (const auto& m : merged) detail::merged_point(*m, en, pt, full);
      return true;
    };
  }
  e.run(hook);
  e.finish(rep);
  if (drom.is_open()) {
    const std::string text = rep.diffs.empty()
                                 ? R"({"signal": [], "head": {"text": "no divergence"}})"
                                   "\n"
                                 : detail::wavedrom_text(o, rep);
    if (!drom.write(text)) throw InputError(drom.error());
  }
  for (const auto& m : merged) detail::commit_merged(*m, e);
  if (drom.is_open() && !drom.commit()) throw InputError(drom.error());
  return rep;
}

}  // namespace dpc31::wavediff
