// Helpers of the wavediff tests (tests/wavediff*_test.cpp): a tiny signal model rendered as VCD
// in several styles, option sets, and running the comparison in-process or through the binary.
#pragma once

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "run_command.hpp"
#include "synthetic_vcd.hpp"
#include "test_files.hpp"
#include "wavediff.hpp"
#include "wavediff_cli.hpp"

namespace wavediff_test {

namespace fs = std::filesystem;
using namespace dpc31::wavediff;
using testutil::slurp;

using Dir = testutil::TempDir;

inline std::string bin(std::uint64_t v, int w) {
  std::string s;
  for (int b = w - 1; b >= 0; --b) s += ((v >> b) & 1) != 0 ? '1' : '0';
  return s;
}

// A tiny signal model: names, widths, and value changes in time order (only real changes kept).
struct Sig {
  std::string name;  // hierarchical, e.g. "top.cnt"
  int width = 1;
  bool real = false;
};

struct Model {
  std::vector<Sig> sigs;
  std::map<std::uint64_t, std::vector<std::pair<int, std::string>>> at;
  std::map<int, std::string> cur;
  void set(std::uint64_t t, int sig, const std::string& v) {
    if (auto it = cur.find(sig); it != cur.end() && it->second == v) return;
    cur[sig] = v;
    at[t].emplace_back(sig, v);
  }
};

// How a model is written as VCD.
struct Style {
  std::string timescale = "1ns";
  std::uint64_t mult = 1;                     // file time = model time * mult
  std::string prefix;                         // scopes above the model's names ("tb.dut")
  bool split = false;                         // vectors as 1-bit variables name[7] ... name[0]
  std::size_t id_base = 0;                    // other identifier codes
  std::vector<std::string> codes;             // identifier codes in declaration order, if given
  bool reverse = false;                       // declarations in reverse order
  std::map<std::string, std::string> rename;  // model name -> name written
};

inline std::string render(const Model& m, const Style& st) {
  std::string h = "$date generated $end\n$version wavediff_test $end\n";
  h += fmt::format("$timescale {} $end\n", st.timescale);
  std::vector<std::vector<std::string>> ids(m.sigs.size());
  std::size_t next = st.id_base;
  auto new_id = [&] {
    const std::size_t i = next++;
    return st.codes.empty() ? vcd_id(i) : st.codes.at(i - st.id_base);
  };
  struct Decl {
    std::vector<std::string> scopes;
    std::string line;
  };
  std::vector<Decl> decls;
  for (std::size_t i = 0; i < m.sigs.size(); ++i) {
    const Sig& s = m.sigs[i];
    std::string name = s.name;
    if (auto it = st.rename.find(name); it != st.rename.end()) name = it->second;
    if (!st.prefix.empty()) name = st.prefix + "." + name;
    std::vector<std::string> parts;
    std::stringstream ss(name);
    for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
    const std::string leaf = parts.back();
    parts.pop_back();
    if (s.real) {
      ids[i].push_back(new_id());
      decls.push_back({parts, fmt::format("$var real 64 {} {} $end", ids[i][0], leaf)});
    } else if (s.width == 1) {
      ids[i].push_back(new_id());
      decls.push_back({parts, fmt::format("$var wire 1 {} {} $end", ids[i][0], leaf)});
    } else if (st.split) {
      for (int b = s.width - 1; b >= 0; --b) {
        ids[i].push_back(new_id());
        decls.push_back(
            {parts, fmt::format("$var wire 1 {} {} [{}] $end", ids[i].back(), leaf, b)});
      }
    } else {
      ids[i].push_back(new_id());
      decls.push_back({parts, fmt::format("$var wire {} {} {} [{}:0] $end", s.width, ids[i][0],
                                          leaf, s.width - 1)});
    }
  }
  if (st.reverse) std::reverse(decls.begin(), decls.end());
  std::vector<std::string> stack;
  for (const Decl& d : decls) {
    std::size_t common = 0;
    while (common < stack.size() && common < d.scopes.size() && stack[common] == d.scopes[common]) {
      ++common;
    }
    while (stack.size() > common) {
      h += "$upscope $end\n";
      stack.pop_back();
    }
    for (std::size_t k = common; k < d.scopes.size(); ++k) {
      h += fmt::format("$scope module {} $end\n", d.scopes[k]);
      stack.push_back(d.scopes[k]);
    }
    h += d.line + "\n";
  }
  while (!stack.empty()) {
    h += "$upscope $end\n";
    stack.pop_back();
  }
  h += "$enddefinitions $end\n";
  bool first = true;
  for (const auto& [t, changes] : m.at) {
    h += fmt::format("#{}\n", t * st.mult);
    if (first) h += "$dumpvars\n";
    for (const auto& [si, v] : changes) {
      const Sig& s = m.sigs[static_cast<std::size_t>(si)];
      const auto& id = ids[static_cast<std::size_t>(si)];
      if (s.real) {
        h += fmt::format("r{} {}\n", v, id[0]);
      } else if (s.width == 1) {
        h += v + id[0] + "\n";
      } else if (st.split) {
        for (std::size_t b = 0; b < id.size(); ++b) h += fmt::format("{}{}\n", v[b], id[b]);
      } else {
        h += fmt::format("b{} {}\n", v, id[0]);
      }
    }
    if (first) h += "$end\n";
    first = false;
  }
  return h;
}

// The counter used throughout: clk rises at period*k + period/2 (edge k, k = 0, 1, ...) and falls
// at period*(k+1); at rising edge k, cnt (8 bits) becomes cnt_of(k) (k+1 unless overridden) and
// flag becomes bit 2 of k+1. Edge 7 is at 75 with period 10; cnt is then 8, and 7 before it.
inline Model counter(int edges, std::uint64_t period = 10,
                     const std::function<std::uint64_t(int)>& cnt_of = nullptr,
                     bool with_real = false) {
  Model m;
  m.sigs = {{"top.clk", 1}, {"top.cnt", 8}, {"top.flag", 1}};
  if (with_real) m.sigs.push_back({"top.level", 64, true});
  m.set(0, 0, "0");
  m.set(0, 1, bin(0, 8));
  m.set(0, 2, "0");
  if (with_real) m.set(0, 3, "0");
  for (int k = 0; k < edges; ++k) {
    const std::uint64_t t = period * static_cast<std::uint64_t>(k) + period / 2;
    const std::uint64_t c = cnt_of ? cnt_of(k) : static_cast<std::uint64_t>(k + 1);
    m.set(t, 0, "1");
    m.set(t, 1, bin(c, 8));
    m.set(t, 2, (((k + 1) >> 2) & 1) != 0 ? "1" : "0");
    if (with_real) m.set(t, 3, fmt::format("{}", 0.5 * (k + 1)));
    m.set(period * static_cast<std::uint64_t>(k + 1), 0, "0");
  }
  return m;
}

// B's cnt at edge 7 is 0xAA instead of 8; from edge 8 on it agrees again.
inline std::uint64_t cnt_aa_at_7(int k) {
  return k == 7 ? 0xAA : static_cast<std::uint64_t>(k + 1);
}

// a.vcd: the 12-edge counter; b.vcd: the same with cnt AAh at edge 7 (75 to 85 ns). Their paths.
inline std::pair<std::string, std::string> counters_aa_at_7(Dir& d) {
  return {d.write("a.vcd", render(counter(12), {})),
          d.write("b.vcd", render(counter(12, 10, cnt_aa_at_7), {}))};
}

inline Options opts(const std::string& a, const std::string& b) {
  Options o;
  o.file_a = a;
  o.file_b = b;
  return o;
}

struct Outcome {
  int rc;
  std::string out;
  std::string err;
};

inline Outcome run_opts(const Options& o) {
  Outcome r{0, {}, {}};
  r.rc = run(o, r.out, r.err);
  return r;
}

inline std::string vcd2fst() {
  std::string p = VCD2FST;
  if (p.empty() || p.find("NOTFOUND") != std::string::npos) p = "/usr/bin/vcd2fst";
  return p;
}

using testutil::spawn;

}  // namespace wavediff_test
