// The diff VCD of wavediff --diff-vcd: scopes a/, b/ and diff/ with every compared signal under
// its own hierarchy, written while the comparison walks both files.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "engine.hpp"
#include "outfile.hpp"

namespace dpc31::wavediff::detail {

namespace {

std::vector<std::string> split_dots(const std::string& n) {
  std::vector<std::string> parts;
  std::size_t b = 0;
  for (std::size_t i = 0; i <= n.size(); ++i) {
    if (i == n.size() || n[i] == '.') {
      parts.push_back(n.substr(b, i - b));
      b = i + 1;
    }
  }
  return parts;
}

}  // namespace

class DiffVcd {
 public:
  DiffVcd(const std::string& path, Engine& e) {
    if (!out_.open(path)) throw InputError(out_.error());
    const std::size_t n = e.pairs.size();
    ids_.resize(n * 3);
    for (std::size_t i = 0; i < ids_.size(); ++i) ids_[i] = vcd_id(i);
    cycle_id_ = vcd_id(ids_.size());
    flag_.assign(n, -1);
    std::vector<std::pair<std::vector<std::string>, std::size_t>> order;
    for (std::size_t i = 0; i < n; ++i) order.emplace_back(split_dots(e.pairs[i].name), i);
    std::sort(order.begin(), order.end());
    std::string h =
        fmt::format("$version dpc31 wavediff $end\n$timescale {} $end\n", timescale_text(e.pow));
    if (e.clock_mode()) {
      h += fmt::format(
          "$scope module wavediff $end\n$var integer 32 {} cycle $end\n$upscope $end\n", cycle_id_);
    }
    const char* tops[3] = {"a", "b", "diff"};
    for (int side = 0; side < 3; ++side) {
      h += fmt::format("$scope module {} $end\n", tops[side]);
      std::vector<std::string> stack;
      for (const auto& [parts, i] : order) {
        std::size_t common = 0;
        while (common < stack.size() && common + 1 < parts.size() &&
               stack[common] == parts[common]) {
          ++common;
        }
        while (stack.size() > common) {
          h += "$upscope $end\n";
          stack.pop_back();
        }
        for (std::size_t k = common; k + 1 < parts.size(); ++k) {
          h += fmt::format("$scope module {} $end\n", parts[k]);
          stack.push_back(parts[k]);
        }
        const Pair& p = e.pairs[i];
        const std::string& leaf = parts.back();
        const std::string& id = ids_[i * 3 + static_cast<std::size_t>(side)];
        if (side == 2) {
          h += fmt::format("$var wire 1 {} {} $end\n", id, leaf);
        } else if (p.real) {
          h += fmt::format("$var real 64 {} {} $end\n", id, leaf);
        } else {
          const LSig& l = side == 0 ? e.A.sigs[p.a] : e.B.sigs[p.b];
          if (l.width == 1) {
            h += fmt::format("$var wire 1 {} {} $end\n", id, leaf);
          } else {
            h += fmt::format("$var wire {} {} {} [{}:0] $end\n", l.width, id, leaf, l.width - 1);
          }
        }
      }
      while (!stack.empty()) {
        h += "$upscope $end\n";
        stack.pop_back();
      }
      h += "$upscope $end\n";
    }
    h += "$enddefinitions $end\n";
    put(h);
  }
  DiffVcd(const DiffVcd&) = delete;
  DiffVcd& operator=(const DiffVcd&) = delete;

  void point(Engine& e, const Point& pt, bool full) {
    std::string& s = line_;
    s.clear();
    s += fmt::format("#{}\n", pt.time);
    if (e.clock_mode()) s += fmt::format("b{:b} {}\n", pt.cycle, cycle_id_);
    auto emit = [&](std::uint32_t pi) {
      const Pair& p = e.pairs[pi];
      if (full || p.a_changed) value(s, e.A, e.A.sigs[p.a], ids_[pi * 3]);
      if (full || p.b_changed) value(s, e.B, e.B.sigs[p.b], ids_[pi * 3 + 1]);
      const int f = p.differs ? 1 : 0;
      if (full || f != flag_[pi]) {
        s += static_cast<char>('0' + f);
        s += ids_[pi * 3 + 2];
        s += '\n';
        flag_[pi] = static_cast<signed char>(f);
      }
    };
    if (full) {
      for (std::uint32_t pi = 0; pi < e.pairs.size(); ++pi) emit(pi);
    } else {
      for (const std::uint32_t pi : e.dirty) emit(pi);
    }
    put(s);
  }

  // Renames the whole file into place; without it the destructor discards it.
  void commit() {
    if (!out_.commit()) throw InputError(out_.error());
  }

 private:
  outfile::OutFile out_;
  std::vector<std::string> ids_;
  std::string cycle_id_;
  std::vector<signed char> flag_;
  std::string line_;

  void put(const std::string& s) {
    if (!out_.write(s)) throw InputError(out_.error());
  }
  static void value(std::string& s, const Side& side, const LSig& l, const std::string& id) {
    if (l.real) {
      const double d = side.real(l);
      s += std::isnan(d) ? std::string("rnan") : fmt::format("r{}", d);
      s += ' ';
    } else if (l.width == 1) {
      s += side.bits(l);
    } else {
      s += 'b';
      s += side.bits(l);
      s += ' ';
    }
    s += id;
    s += '\n';
  }
};

std::shared_ptr<DiffVcd> open_diff_vcd(const std::string& path, Engine& e) {
  return std::make_shared<DiffVcd>(path, e);
}
void diff_vcd_point(DiffVcd& d, Engine& e, const Point& pt, bool full) { d.point(e, pt, full); }
void commit_diff_vcd(DiffVcd& d) { d.commit(); }

}  // namespace dpc31::wavediff::detail
