// Signal names to pairs: the common scope stripped (--strip), the map file (--map), vectors split
// into bits where the other side has single bits, and the filters' glob (the comparison itself:
// wavediff.cpp).
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <unordered_map>
#include <unordered_set>

#include "engine.hpp"
#include "textfile.hpp"

namespace dpc31::wavediff {

namespace detail {

std::string strip_name(const std::string& name, const std::string& prefix) {
  if (prefix.empty()) return name;
  if (name.size() > prefix.size() + 1 && name.compare(0, prefix.size(), prefix) == 0 &&
      name[prefix.size()] == '.') {
    return name.substr(prefix.size() + 1);
  }
  return name;
}

// The scope components shared by every name of a side ("TOP", "tb", "dut" ...).
std::vector<std::string> common_scopes(const std::vector<Var>& vars) {
  std::vector<std::string> common;
  bool first = true;
  for (const Var& v : vars) {
    std::vector<std::string> parts;
    std::size_t b = 0;
    for (std::size_t i = 0; i < v.name.size(); ++i) {
      if (v.name[i] == '.') {
        parts.push_back(v.name.substr(b, i - b));
        b = i + 1;
      }
    }
    if (first) {
      common = parts;
      first = false;
    } else {
      std::size_t k = 0;
      while (k < common.size() && k < parts.size() && common[k] == parts[k]) ++k;
      common.resize(k);
    }
  }
  return common;
}

std::vector<std::string> prefixes(const std::vector<std::string>& scopes) {
  std::vector<std::string> out{""};
  std::string p;
  for (const auto& s : scopes) {
    p += (p.empty() ? "" : ".") + s;
    out.push_back(p);
  }
  return out;
}

std::vector<MapEntry> read_map(const std::string& path) {
  // Read whole up to a cap, as the other text inputs are (docs/security.md, "Inputs: sizes"): a
  // map without a newline (/dev/zero) grew without bound, and a read that failed ended the map
  // there unnoticed.
  constexpr std::size_t kMaxMapBytes = std::size_t{16} << 20;
  constexpr std::size_t kMaxLineBytes = std::size_t{64} << 10;
  // An ifstream opened a directory and read nothing from it: that would be an empty map.
  if (std::filesystem::is_directory(path)) fail(path, 0, "cannot open: is a directory");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(path, 0, fmt::format("cannot open: {}", std::strerror(errno)));
  std::string text;
  std::string why;
  const bool read = read_text_fd(fd, kMaxMapBytes, "wavediff map", text, why);
  ::close(fd);
  if (!read) {
    // A failed read names the line it stopped in; the cap is the file's.
    const auto at = static_cast<std::uint64_t>(std::count(text.begin(), text.end(), '\n')) + 1;
    fail(path, text.size() > kMaxMapBytes ? 0 : at, why);
  }
  std::vector<MapEntry> out;
  std::unordered_map<std::string, std::uint64_t> seen_a;
  std::unordered_map<std::string, std::uint64_t> seen_b;
  std::uint64_t n = 0;
  auto trim = [](std::string_view s) {
    const auto b = s.find_first_not_of(" \t\r");
    if (b == std::string_view::npos) return std::string();
    const auto e = s.find_last_not_of(" \t\r");
    return std::string(s.substr(b, e - b + 1));
  };
  for (std::string_view rest = text; !rest.empty();) {
    const auto nl = rest.find('\n');
    std::string_view line = rest.substr(0, nl);
    rest.remove_prefix(nl == std::string_view::npos ? rest.size() : nl + 1);
    ++n;
    if (line.size() > kMaxLineBytes) {
      fail(path, n, fmt::format("line longer than {} bytes", kMaxLineBytes));
    }
    // A NUL cut the name where it was printed; no signal name holds a control byte.
    if (const auto bad = std::find_if(line.begin(), line.end(),
                                      [](char c) {
                                        const auto u = static_cast<unsigned char>(c);
                                        return (u < 0x20 && c != '\t' && c != '\r') || u == 0x7F;
                                      });
        bad != line.end()) {
      fail(path, n, not_text(static_cast<unsigned char>(*bad)));
    }
    if (const auto hash = line.find('#'); hash != std::string_view::npos)
      line = line.substr(0, hash);
    const std::string entry = trim(line);
    if (entry.empty()) continue;
    const auto eq = entry.find('=');
    if (eq == std::string::npos || entry.find('=', eq + 1) != std::string::npos) {
      fail(path, n, "expected 'nameA = nameB'");
    }
    const std::string_view whole = entry;
    MapEntry e{trim(whole.substr(0, eq)), trim(whole.substr(eq + 1)), n};
    auto blank = [](const std::string& s) {
      return s.empty() || s.find_first_of(" \t") != std::string::npos;
    };
    if (blank(e.a) || blank(e.b)) fail(path, n, "expected 'nameA = nameB' (one name on each side)");
    if (auto it = seen_a.find(e.a); it != seen_a.end()) {
      fail(path, n, fmt::format("'{}' is already mapped on line {}", shown(e.a), it->second));
    }
    if (auto it = seen_b.find(e.b); it != seen_b.end()) {
      fail(path, n, fmt::format("'{}' is already mapped on line {}", shown(e.b), it->second));
    }
    seen_a.emplace(e.a, n);
    seen_b.emplace(e.b, n);
    out.push_back(std::move(e));
  }
  return out;
}

// "base[3]" or "base(3)": the base and index of a one-bit signal of a split vector.
bool bit_of(const std::string& name, std::string& base, int& idx) {
  if (name.size() < 4) return false;
  const char close = name.back();
  const char open = close == ']' ? '[' : close == ')' ? '(' : 0;
  if (open == 0) return false;
  const auto p = name.rfind(open);
  if (p == std::string::npos || p == 0 || p + 2 >= name.size()) return false;
  int v = 0;
  for (std::size_t i = p + 1; i + 1 < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9' || v > 100'000'000) return false;
    v = v * 10 + (name[i] - '0');
  }
  base = name.substr(0, p);
  idx = v;
  return true;
}

void Engine::build_names(Side& s, const std::string& strip, std::vector<MapEntry>* map) {
  std::unordered_map<std::string, MapEntry*> b2a;
  if (map != nullptr) {
    for (MapEntry& e : *map) b2a.emplace(e.b, &e);
  }
  s.sigs.clear();
  for (const Var& v : s.r->vars()) {
    const Slot& sl = s.r->slots()[v.slot];
    LSig l;
    l.orig = strip_name(v.name, strip);
    l.name = l.orig;
    if (map != nullptr) {
      if (auto it = b2a.find(l.orig); it != b2a.end()) {
        l.name = it->second->a;
        it->second->used_b = true;
      } else {
        std::string base;
        int idx = 0;
        if (bit_of(l.orig, base, idx)) {
          if (auto jt = b2a.find(base); jt != b2a.end()) {
            l.name = jt->second->a + l.orig.substr(base.size());
            jt->second->used_b = true;
          }
        }
      }
    }
    l.width = sl.width;
    l.real = sl.real;
    l.msb = v.msb;
    l.lsb = v.lsb;
    l.slot = v.slot;
    s.sigs.push_back(std::move(l));
  }
}

void Engine::join_bits(Side& s, const Side& other) {
  std::unordered_set<std::string> own;
  for (const LSig& l : s.sigs) own.insert(l.name);
  std::unordered_map<std::string, std::uint32_t> theirs;
  for (std::uint32_t i = 0; i < other.sigs.size(); ++i) theirs.emplace(other.sigs[i].name, i);
  std::map<std::string, std::vector<std::pair<int, std::uint32_t>>> groups;
  for (std::uint32_t i = 0; i < s.sigs.size(); ++i) {
    const LSig& l = s.sigs[i];
    std::string base;
    int idx = 0;
    if (l.width == 1 && !l.real && l.bit_slots.empty() && bit_of(l.name, base, idx)) {
      groups[base].emplace_back(idx, i);
    }
  }
  for (auto& [base, members] : groups) {
    if (own.count(base) != 0) continue;
    auto it = theirs.find(base);
    if (it == theirs.end() || other.sigs[it->second].real) continue;
    std::sort(members.begin(), members.end());
    bool ok = true;
    for (std::size_t k = 1; k < members.size(); ++k) {
      ok = ok && members[k].first == members[k - 1].first + 1;
    }
    if (!ok) continue;
    const LSig& o = other.sigs[it->second];
    const int lo = members.front().first;
    const int hi = members.back().first;
    // Leftmost bit first, as the other side declares its range: [hi:lo] unless it is [lo:hi].
    const bool ascending = o.msb >= 0 && o.lsb >= 0 && o.msb < o.lsb && o.msb == lo && o.lsb == hi;
    LSig j;
    j.name = base;
    const LSig& m0 = s.sigs[members.front().second];
    j.orig = m0.orig.substr(0, m0.orig.size() - (m0.name.size() - base.size()));
    j.width = static_cast<std::uint32_t>(members.size());
    j.msb = ascending ? lo : hi;
    j.lsb = ascending ? hi : lo;
    for (std::size_t k = 0; k < members.size(); ++k) {
      const auto& m = members[ascending ? k : members.size() - 1 - k];
      j.bit_slots.push_back(s.sigs[m.second].slot);
      s.sigs[m.second].joined_member = true;
    }
    s.sigs.push_back(std::move(j));
  }
}

}  // namespace detail

bool glob_match(std::string_view p, std::string_view s) {
  std::size_t pi = 0;
  std::size_t si = 0;
  std::size_t star = std::string_view::npos;
  std::size_t mark = 0;
  while (si < s.size()) {
    if (pi < p.size() && (p[pi] == '?' || p[pi] == s[si])) {
      ++pi;
      ++si;
    } else if (pi < p.size() && p[pi] == '*') {
      star = pi++;
      mark = si;
    } else if (star != std::string_view::npos) {
      pi = star + 1;
      si = ++mark;
    } else {
      return false;
    }
  }
  while (pi < p.size() && p[pi] == '*') ++pi;
  return pi == p.size();
}

}  // namespace dpc31::wavediff
