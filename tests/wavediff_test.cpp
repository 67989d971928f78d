// dpc31 wavediff (docs/wavediff.md). Waveforms are generated here from small models or read from
// tests/data/wavediff/; every expected time, cycle and value is worked out by hand in the comment
// next to it.
#include "wavediff.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "synthetic_vcd.hpp"
#include "wavediff_cli.hpp"

namespace fs = std::filesystem;
using namespace dpc31::wavediff;

namespace {

// A scratch directory per test, removed afterwards.
class Dir {
 public:
  Dir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            fmt::format("wavediff_{}_{}_{}", info->test_suite_name(), info->name(), ::getpid());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~Dir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  Dir(const Dir&) = delete;
  Dir& operator=(const Dir&) = delete;
  [[nodiscard]] std::string path(const std::string& name) const { return (path_ / name).string(); }
  std::string file(const std::string& name, const std::string& content) const {
    std::ofstream f(path(name), std::ios::binary);
    f << content;
    return path(name);
  }

 private:
  fs::path path_;
};

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string bin(std::uint64_t v, int w) {
  std::string s;
  for (int b = w - 1; b >= 0; --b) s += ((v >> b) & 1) != 0 ? '1' : '0';
  return s;
}

std::string vcd_id(std::size_t i) {
  std::string id;
  do {
    id += static_cast<char>('!' + i % 94);
    i /= 94;
  } while (i != 0);
  return id;
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

std::string render(const Model& m, const Style& st) {
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
Model counter(int edges, std::uint64_t period = 10,
              const std::function<std::uint64_t(int)>& cnt_of = nullptr, bool with_real = false) {
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
std::uint64_t cnt_aa_at_7(int k) { return k == 7 ? 0xAA : static_cast<std::uint64_t>(k + 1); }

Options opts(const std::string& a, const std::string& b) {
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

Outcome run_opts(const Options& o) {
  Outcome r{0, {}, {}};
  r.rc = run(o, r.out, r.err);
  return r;
}

std::string vcd2fst() {
  std::string p = VCD2FST;
  if (p.empty() || p.find("NOTFOUND") != std::string::npos) p = "/usr/bin/vcd2fst";
  return p;
}

// Runs a program and waits for it; exit code, and the child's peak RSS in KiB.
int spawn(const std::vector<std::string>& args, long* maxrss_kib = nullptr,
          const std::string& out_file = "/dev/null") {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
    }
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  struct rusage ru {};
  ::wait4(pid, &status, 0, &ru);
  if (maxrss_kib != nullptr) *maxrss_kib = ru.ru_maxrss;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

TEST(WavediffBasic, IdenticalFilesExitZero) {
  Dir d;
  const Model m = counter(12);
  const auto a = d.file("a.vcd", render(m, {}));
  // Same run, other identifier codes and declaration order: a textual diff would differ.
  Style other;
  other.id_base = 40;
  other.reverse = true;
  const auto b = d.file("b.vcd", render(m, other));
  ASSERT_NE(slurp(a), slurp(b));
  const Outcome r = run_opts(opts(a, b));
  EXPECT_EQ(r.rc, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("compared 3 signals: 0 differ"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("result: same"), std::string::npos);
  EXPECT_EQ(run_opts(opts(a, a)).rc, 0);
}

TEST(WavediffBasic, OneBitDifferenceAtKnownTime) {
  Dir d;
  // flag is bit 2 of k+1 (k+1 = 4..7 set it): it rises at edge 3 (t = 35) and falls at edge 7
  // (t = 75), and k+1 = 9, 10 keep it 0. In B it rises at edge 3 too but never falls: the first
  // difference is at 75 ns, A=0 B=1, last common 1, and it lasts to the end.
  Model ma = counter(10);
  Model mb = counter(10);
  for (auto& [t, ch] : mb.at) {
    std::erase_if(ch, [t = t](const auto& c) { return c.first == 2 && t >= 75; });
  }
  const auto a = d.file("a.vcd", render(ma, {}));
  const auto b = d.file("b.vcd", render(mb, {}));
  Options o = opts(a, b);
  o.json_file = d.path("r.json");
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("first divergence: top.flag at 75ns (A #75, B #75): A=0 B=1, last common 1"),
            std::string::npos)
      << r.out;
  const auto j = nlohmann::json::parse(slurp(o.json_file));
  EXPECT_EQ(j["result"], "different");
  EXPECT_EQ(j["exit_code"], 1);
  EXPECT_EQ(j["first_divergence"]["signal"], "top.flag");
  EXPECT_EQ(j["first_divergence"]["time"], 75);
  EXPECT_EQ(j["first_divergence"]["time_text"], "75ns");
  EXPECT_EQ(j["first_divergence"]["a"], "0");
  EXPECT_EQ(j["first_divergence"]["b"], "1");
  EXPECT_EQ(j["first_divergence"]["last_common"], "1");
  EXPECT_EQ(j["first_divergence"]["open"], true);
  ASSERT_EQ(j["signals"].size(), 1u);
  EXPECT_EQ(j["signals"][0]["count"], 1);
}

TEST(WavediffBasic, VectorDifferenceGroupedPerSignal) {
  Dir d;
  // cnt differs at edges 2 and 7 (t = 25 and 75), each for one edge: two divergences, and a
  // 1-bit flag nowhere.
  const auto a = d.file("a.vcd", render(counter(10), {}));
  const auto b = d.file(
      "b.vcd", render(counter(10, 10,
                              [](int k) {
                                return k == 2 || k == 7 ? 0xAAu : static_cast<std::uint64_t>(k + 1);
                              }),
                      {}));
  const Report r = compare(opts(a, b));
  ASSERT_EQ(r.diffs.size(), 1u);
  const SignalDiff& s = r.diffs[0];
  EXPECT_EQ(s.name, "top.cnt");
  EXPECT_EQ(s.count, 2u);
  EXPECT_EQ(s.first.at.time, 25u);
  EXPECT_EQ(s.first.a, "00000011");
  EXPECT_EQ(s.first.b, "10101010");
  EXPECT_EQ(s.first.last_common, "00000010");
  EXPECT_FALSE(s.first.open);
  EXPECT_EQ(s.last.time, 75u);
}

TEST(WavediffTimescale, PsAndNsOfTheSameRunAreTheSame) {
  Dir d;
  const Model m = counter(12);
  const auto ns = d.file("ns.vcd", render(m, {}));
  Style ps;
  ps.timescale = "1 ps";
  ps.mult = 1000;
  const auto p = d.file("ps.vcd", render(m, ps));
  Style hps;
  hps.timescale = "100ps";
  hps.mult = 10;
  const auto h = d.file("100ps.vcd", render(m, hps));
  EXPECT_EQ(run_opts(opts(ns, p)).rc, 0);
  EXPECT_EQ(run_opts(opts(p, ns)).rc, 0);
  EXPECT_EQ(run_opts(opts(h, ns)).rc, 0);
  // A difference is reported in the finer unit and in each file's own units.
  const auto pd = d.file("ps_diff.vcd", render(counter(12, 10, cnt_aa_at_7), ps));
  const Report r = compare(opts(ns, pd));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.pow, 3);                          // 1 ps
  EXPECT_EQ(r.diffs[0].first.at.time, 75000u);  // 75 ns
  EXPECT_EQ(time_text(75000, r.pow), "75000ps");
  EXPECT_EQ(file_time(75000, r.pow, r.pow_a), "75");
  EXPECT_EQ(file_time(75000, r.pow, r.pow_b), "75000");
  EXPECT_EQ(file_time(1500, 3, 6), "1.5");
}

TEST(WavediffClock, DifferentTimeBasesSampleTheSame) {
  Dir d;
  // A: period 10 ns in a 1 ns file; B: period 20 ns in a 1 ps file. Event mode sees differences
  // everywhere; on the clock the two runs are the same, cycle by cycle.
  const auto a = d.file("a.vcd", render(counter(12), {}));
  Style ps;
  ps.timescale = "1ps";
  ps.mult = 1000;
  const auto b = d.file("b.vcd", render(counter(12, 20), ps));
  EXPECT_EQ(run_opts(opts(a, b)).rc, 1);
  Options o = opts(a, b);
  o.clock_a = "top.clk";
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 0) << r.out << r.err;
  const Report rep = compare(o);
  EXPECT_EQ(rep.edges, 12u);
  EXPECT_EQ(rep.compared, 2u);  // cnt and flag; the clock itself is not compared
}

TEST(WavediffClock, DifferenceAtEdgeSevenIsCycleSeven) {
  Dir d;
  const auto a = d.file("a.vcd", render(counter(12), {}));
  Style ps;
  ps.timescale = "1ps";
  ps.mult = 1000;
  const auto b = d.file("b.vcd", render(counter(12, 20, cnt_aa_at_7), ps));
  Options o = opts(a, b);
  o.clock_a = "top.clk";
  o.json_file = d.path("r.json");
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 1) << r.out;
  // Edge 7 (counting from 0): A at 10*7+5 = 75 ns, B at 20*7+10 = 150 ns = 150000 ps. The values
  // sampled after the edge: A 8, B 0xAA; before it both had 7.
  EXPECT_NE(r.out.find("first divergence: top.cnt at cycle 7 (A 75000ps, #75; B 150000ps, "
                       "#150000): A=00001000 (0x08) B=10101010 (0xaa), last common 00000111"),
            std::string::npos)
      << r.out;
  const auto j = nlohmann::json::parse(slurp(o.json_file));
  EXPECT_EQ(j["mode"], "clock");
  EXPECT_EQ(j["first_divergence"]["cycle"], 7);
  EXPECT_EQ(j["first_divergence"]["time_a"], "75");
  EXPECT_EQ(j["first_divergence"]["time_b"], "150000");
  EXPECT_EQ(j["signals"][0]["count"], 1);
  EXPECT_EQ(j["first_divergence"]["open"], false);

  // Falling edges: falling edge j is at 10(j+1) in A; the one at 80 (j = 7) sees 8 vs 0xAA.
  o.edge = Edge::falling;
  Report rf = compare(o);
  ASSERT_EQ(rf.diffs.size(), 1u);
  EXPECT_EQ(rf.diffs[0].first.at.cycle, 7u);
  // Both edges: rising k is edge 2k, so rising 7 is cycle 14.
  o.edge = Edge::both;
  Report rb = compare(o);
  ASSERT_EQ(rb.diffs.size(), 1u);
  EXPECT_EQ(rb.diffs[0].first.at.cycle, 14u);
  EXPECT_EQ(rb.diffs[0].count, 1u);
}

TEST(WavediffClock, ClockNamedDifferentlyInB) {
  Dir d;
  const auto a = d.file("a.vcd", render(counter(12), {}));
  Style s;
  s.rename["top.clk"] = "top.clock";
  const auto b = d.file("b.vcd", render(counter(12), s));
  Options o = opts(a, b);
  o.clock_a = "top.clk";
  o.clock_b = "top.clock";
  EXPECT_EQ(run_opts(o).rc, 0);
  // B with fewer edges: a difference of its own.
  const auto b11 = d.file("b11.vcd", render(counter(11), s));
  o.file_b = b11;
  const Report r = compare(o);
  ASSERT_EQ(r.structural.size(), 1u);
  EXPECT_EQ(r.structural[0].what, "clock: B has only 11 rising edges, A has more");
  EXPECT_FALSE(r.same());
}

TEST(WavediffVector, SplitBitsAgainstVector) {
  Dir d;
  const auto a = d.file("a.vcd", render(counter(12), {}));
  Style split;
  split.split = true;
  split.id_base = 7;
  const auto b = d.file("b.vcd", render(counter(12), split));
  EXPECT_NE(slurp(b).find("$var wire 1 ) cnt [7] $end"), std::string::npos);
  EXPECT_EQ(run_opts(opts(a, b)).rc, 0);
  EXPECT_EQ(run_opts(opts(b, a)).rc, 0);
  const auto bd = d.file("bd.vcd", render(counter(12, 10, cnt_aa_at_7), split));
  const Report r = compare(opts(a, bd));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].name, "top.cnt");
  EXPECT_EQ(r.diffs[0].first.b, "10101010");
  EXPECT_EQ(r.compared, 3u);
}

TEST(WavediffVector, AscendingRangeKeepsBitOrder) {
  Dir d;
  // v [0:3] = b0001 means v[0]=0 v[1]=0 v[2]=0 v[3]=1; B gives the bits one by one.
  const auto a = d.file("a.vcd",
                        "$timescale 1ns $end\n$scope module top $end\n"
                        "$var wire 4 ! v [0:3] $end\n$upscope $end\n$enddefinitions $end\n"
                        "#0\nb0001 !\n#10\nb0011 !\n");
  const auto b = d.file("b.vcd",
                        "$timescale 1ns $end\n$scope module top $end\n"
                        "$var wire 1 a v [0] $end\n$var wire 1 b v [1] $end\n"
                        "$var wire 1 c v [2] $end\n$var wire 1 d v [3] $end\n"
                        "$upscope $end\n$enddefinitions $end\n"
                        "#0\n0a\n0b\n0c\n1d\n#10\n1c\n");
  const Outcome r = run_opts(opts(a, b));
  EXPECT_EQ(r.rc, 0) << r.out;
}

TEST(WavediffAlias, EveryNameOfAnIdGetsTheValues) {
  Dir d;
  // In A, top.a and top.u.a_copy are one id ('!'); in B they are two ids.
  const std::string head_a =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! a $end\n"
      "$scope module u $end\n$var wire 1 ! a_copy $end\n$upscope $end\n$upscope $end\n"
      "$enddefinitions $end\n";
  const auto a = d.file("a.vcd", head_a + "#0\n0!\n#10\n1!\n#20\n0!\n");
  const std::string head_b =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 x a $end\n"
      "$scope module u $end\n$var wire 1 y a_copy $end\n$upscope $end\n$upscope $end\n"
      "$enddefinitions $end\n";
  const auto b = d.file("b.vcd", head_b + "#0\n0x\n0y\n#10\n1x\n1y\n#20\n0x\n0y\n");
  EXPECT_EQ(run_opts(opts(a, b)).rc, 0);
  EXPECT_EQ(run_opts(opts(b, a)).rc, 0);
  // B's copy stays 1 at 20: only top.u.a_copy differs, from 20 ns.
  const auto b2 = d.file("b2.vcd", head_b + "#0\n0x\n0y\n#10\n1x\n1y\n#20\n0x\n");
  const Report r = compare(opts(a, b2));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].name, "top.u.a_copy");
  EXPECT_EQ(r.diffs[0].first.at.time, 20u);
  EXPECT_EQ(r.compared, 2u);
}

// The reader looks identifier codes of 1 to 3 characters from '!' to '~' up in a direct table
// (one tier per length) and every other code in a fallback table. The same model written with
// codes at the table's edges ('!' first, '~' last of each tier), with 4- to 16-character codes and
// with codes of other bytes must read the same: against a mutant in which signal i differs from
// time 2i+1 to 2i+2 only, each gives one divergence per signal with the same values.
TEST(WavediffIds, DirectTableAndFallbackCodesReadTheSame) {
  Dir d;
  const int widths[] = {1, 4, 1, 8, 16, 1, 12, 3, 1, 20, 2, 1, 9, 5};
  constexpr int kSigs = 14;
  auto value = [&](int i, std::uint64_t t, bool mutant) {
    const int w = widths[i];
    std::string v = bin((t / static_cast<std::uint64_t>(i % 3 + 1)) * 2654435761u + 7u * i, w);
    if (i % 5 == 4 && t % 4 == 0) v[0] = 'z';  // x and z go through the vector path too
    if (i % 5 == 2 && t % 3 == 0) v[static_cast<std::size_t>(w) - 1] = 'x';
    if (mutant && t == 2u * static_cast<std::uint64_t>(i) + 1) {
      char& c = v.back();
      c = c == '1' ? '0' : '1';
    }
    return v;
  };
  auto model = [&](bool mutant) {
    Model m;
    for (int i = 0; i < kSigs; ++i) m.sigs.push_back({fmt::format("top.s{}", i), widths[i]});
    m.sigs.push_back({"top.level", 64, true});
    for (std::uint64_t t = 0; t < 40; ++t) {
      for (int i = 0; i < kSigs; ++i) m.set(t, i, value(i, t, mutant));
      const bool bump = mutant && t == 2u * kSigs + 1;  // the real differs at 29 only
      m.set(t, kSigs, fmt::format("{}", 0.25 * static_cast<double>(t / 2) + (bump ? 1 : 0)));
    }
    return m;
  };
  Style short_codes;  // tiers 1, 2, 3 and both ends of each
  short_codes.codes = {"!",   "~",   "!!", "~~", "!~", "~!", "!!!", "~~~",
                       "~!!", "!~~", "\"", "}",  "a",  "zz", "q5"};
  Style long_codes;  // packed fallback up to 8 characters, map beyond
  long_codes.codes = {"!!!!",      "~~~~",  "!!!!!",   "~~~~~~~~",  "!~~~~~~~~", "abcdefghijklmnop",
                      "long_code", "!!!!~", "~!!!",    "!!!!!!!!!", "~!~!",      "zzzz",
                      "~~~~~",     "q5q5",  "\"\"\"\""};
  Style other_bytes;  // short codes outside '!'..'~': the fallback as well
  other_bytes.codes = {"\x7f",  "\xc3\xa9", "\x80",         "\xff\xff",     "!\x7f",
                       "\x7f!", "~\x80~",   "\xe2\x82\xac", "\x7f\x7f\x7f", "a\xff",
                       "\x81",  "\xfe",     "\x7f~",        "\x80\x80",     "\x9f"};
  const Model a = model(false);
  const auto f_short = d.file("short.vcd", render(a, short_codes));
  const auto fl = d.file("long.vcd", render(a, long_codes));
  const auto fo = d.file("other.vcd", render(a, other_bytes));
  const auto fm = d.file("mutant.vcd", render(model(true), {}));
  EXPECT_EQ(run_opts(opts(f_short, fl)).rc, 0);
  EXPECT_EQ(run_opts(opts(fl, fo)).rc, 0);
  EXPECT_EQ(run_opts(opts(fo, f_short)).rc, 0);
  auto text = [](const Report& r) {
    std::string out = fmt::format("compared {}\n", r.compared);
    for (const SignalDiff& s : r.diffs) {
      out += fmt::format("{} {} {} {} {} {} {} {}\n", s.name, s.count, s.first.at.time, s.first.a,
                         s.first.b, s.first.last_common.value_or("-"), s.first.open, s.last.time);
    }
    return out;
  };
  const Report rs = compare(opts(f_short, fm));
  ASSERT_EQ(rs.diffs.size(), static_cast<std::size_t>(kSigs + 1)) << text(rs);
  EXPECT_EQ(rs.compared, static_cast<std::size_t>(kSigs + 1));
  for (int i = 0; i < kSigs; ++i) {
    const SignalDiff& sd = rs.diffs[static_cast<std::size_t>(i)];
    const std::uint64_t t = 2u * static_cast<std::uint64_t>(i) + 1;
    EXPECT_EQ(sd.name, fmt::format("top.s{}", i));
    EXPECT_EQ(sd.count, 1u) << sd.name;
    EXPECT_EQ(sd.first.at.time, t) << sd.name;
    EXPECT_EQ(sd.first.a, value(i, t, false)) << sd.name;
    EXPECT_EQ(sd.first.b, value(i, t, true)) << sd.name;
    EXPECT_FALSE(sd.first.open) << sd.name;
  }
  EXPECT_EQ(rs.diffs[kSigs].name, "top.level");
  EXPECT_EQ(rs.diffs[kSigs].first.at.time, 29u);
  EXPECT_EQ(rs.diffs[kSigs].first.a, "3.5");  // 0.25 * 14
  EXPECT_EQ(rs.diffs[kSigs].first.b, "4.5");
  EXPECT_EQ(text(compare(opts(fl, fm))), text(rs));
  EXPECT_EQ(text(compare(opts(fo, fm))), text(rs));
  // With the sides swapped as well (B's reader uses the table).
  EXPECT_EQ(text(compare(opts(fm, f_short))), text(compare(opts(fm, fl))));
  // An undeclared code in each tier and in the fallback is still an error with its line (the
  // one after "#0" and "1!", which follow the header).
  Model one;
  one.sigs = {{"top.a", 1}};  // declared as '!'
  const std::string head = render(one, short_codes);
  const auto head_lines = static_cast<std::size_t>(std::count(head.begin(), head.end(), '\n'));
  // (A control character is quoted as \xHH in the error line, docs/bad-input.md.)
  for (const auto& [id, shown] :
       std::initializer_list<std::pair<const char*, const char*>>{{"~", "~"},
                                                                  {"!!", "!!"},
                                                                  {"~~~", "~~~"},
                                                                  {"!!!!", "!!!!"},
                                                                  {"~~~~~~~~~", "~~~~~~~~~"},
                                                                  {"\x7f", "\\x7F"}}) {
    const auto f = d.file("undeclared.vcd", head + "#0\n1!\n1" + std::string(id) + "\n");
    const Outcome r = run_opts(opts(f, f));
    EXPECT_EQ(r.rc, 2) << id;
    EXPECT_EQ(r.err, fmt::format("{}:{}: undeclared identifier '{}'\n", f, head_lines + 3, shown));
  }
}

// A vector value is used in place in the read buffer (1 MiB) unless reading its identifier
// refills the buffer. The same changes, placed at every offset around the end of the first
// buffer by a header comment, read the same as without the comment; nine-valued letters
// (normalised into a copy) as well.
TEST(WavediffIds, VectorValuesAcrossTheReadBuffersEnd) {
  Dir d;
  const std::string decl =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 20 ~ v [19:0] $end\n"
      "$var wire 12 !!!!!!!!! w [11:0] $end\n$var wire 1 !! c $end\n$upscope $end\n"
      "$enddefinitions $end\n";
  std::string body;
  for (std::uint64_t t = 0; t < 64; ++t) {
    body += fmt::format("#{}\nb{} ~\n", t, bin(t * 40503u + 1, 20));
    body += t % 5 == 3 ? "bUWXZ-HL10101 !!!!!!!!!\n" : fmt::format("b{} !!!!!!!!!\n", bin(t, 12));
    body += fmt::format("{}!!\n", t & 1);
  }
  // A trailer of more than 1 MiB: the refill overwrites the whole buffer, so that a vector value
  // that had been left there would be lost.
  std::string trailer = "$comment";
  while (trailer.size() < (std::size_t{1} << 20) + 4096) trailer += " trailer";
  body += trailer + " $end\n";
  const auto ref = d.file("ref.vcd", decl + body);
  // The changes are about 3.5 KB: with a comment of `pad` bytes they start at 1 MiB - 1500 -
  // shift.
  const std::size_t pad = (std::size_t{1} << 20) - 1500 - decl.size();
  std::string comment;
  for (std::size_t shift = 0; shift < 48; ++shift) {
    comment = "$comment";
    while (comment.size() < pad - shift - 6) comment += " padding";
    comment.resize(pad - shift - 6, '_');
    comment += " $end\n";
    const auto f = d.file("shifted.vcd", comment + decl + body);
    const Outcome r = run_opts(opts(f, ref));
    EXPECT_EQ(r.rc, 0) << "shift " << shift << ": " << r.out << r.err;
  }
  // The comparison sees a difference in the same setting (so the loop above can fail).
  std::string other = body;
  const std::size_t at = other.find("#40\nb") + 5;  // v's leftmost bit at 40
  other[at] = other[at] == '0' ? '1' : '0';
  const auto f = d.file("shifted.vcd", comment + decl + other);
  const Report r = compare(opts(f, ref));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].name, "top.v");
  EXPECT_EQ(r.diffs[0].first.at.time, 40u);
  // The nine-valued letters as documented: U W X - read as x, Z as z, H L as 1 0.
  const auto nine = d.file("nine.vcd", decl + "#0\nbUWXZ-HL10101 !!!!!!!!!\n");
  EXPECT_EQ(run_opts(opts(nine, d.file("xz.vcd", decl + "#0\nbxxxzx1010101 !!!!!!!!!\n"))).rc, 0);
  EXPECT_EQ(run_opts(opts(nine, d.file("xz1.vcd", decl + "#0\nbxxxzx1010100 !!!!!!!!!\n"))).rc, 1);
}

TEST(WavediffMap, RenamesFromAMappingFile) {
  Dir d;
  const auto a = d.file("a.vcd", render(counter(12), {}));
  Style s;
  s.rename = {{"top.cnt", "top.count"}, {"top.flag", "top.flg"}};
  const auto b = d.file("b.vcd", render(counter(12), s));
  const auto map = d.file("names.map",
                          "# renames between the two dumps\n"
                          "\n"
                          "top.cnt = top.count\n"
                          "  top.flag=top.flg   # trailing comment\n");
  Options o = opts(a, b);
  const Report plain = compare(o);
  EXPECT_EQ(plain.only_a, (std::vector<std::string>{"top.cnt", "top.flag"}));
  EXPECT_EQ(plain.only_b, (std::vector<std::string>{"top.count", "top.flg"}));
  EXPECT_EQ(run_opts(o).rc, 1);
  o.ignore_missing = true;
  EXPECT_EQ(run_opts(o).rc, 0);
  o.ignore_missing = false;
  o.map_file = map;
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 0) << r.out << r.err;
  EXPECT_EQ(r.err, "");
  // The mapped name also joins split bits: top.count[7..0] in B against top.cnt in A.
  s.split = true;
  o.file_b = d.file("bs.vcd", render(counter(12), s));
  EXPECT_EQ(run_opts(o).rc, 0);
  // A difference is reported under A's name, with B's name beside it.
  o.file_b = d.file("bd.vcd", render(counter(12, 10, cnt_aa_at_7), s));
  const Outcome rd = run_opts(o);
  EXPECT_EQ(rd.rc, 1);
  EXPECT_NE(rd.out.find("  top.cnt (B top.count): 1 divergence, first at 75ns"), std::string::npos)
      << rd.out;
}

TEST(WavediffMap, ErrorsNameFileAndLine) {
  Dir d;
  const auto a = d.file("a.vcd", render(counter(3), {}));
  Options o = opts(a, a);
  o.map_file = d.file("bad.map", "# ok\ntop.cnt = top.count\ntop.flag top.flg\n");
  Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, o.map_file + ":3: expected 'nameA = nameB'\n");
  o.map_file = d.file("dup.map", "top.cnt = top.count\n\ntop.cnt = top.other\n");
  r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, o.map_file + ":3: 'top.cnt' is already mapped on line 1\n");
  o.map_file = d.path("missing.map");
  r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, o.map_file + ":0: cannot open: No such file or directory\n");
  // A name that is in neither file: a warning with file:line, not an error.
  o.map_file = d.file("unused.map", "top.nothere = top.neither\n");
  r = run_opts(o);
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.err, o.map_file + ":1: warning: no signal 'top.nothere' in A\n" + o.map_file +
                       ":1: warning: no signal 'top.neither' in B\n");
}

TEST(WavediffStrip, ExplicitAndAutomaticTopScopes) {
  Dir d;
  Style sa;
  sa.prefix = "tb.dut";
  Style sb;
  sb.prefix = "TOP";
  const auto a = d.file("a.vcd", render(counter(12), sa));
  const auto b = d.file("b.vcd", render(counter(12), sb));
  Options o = opts(a, b);
  const Report none = compare(o);
  EXPECT_EQ(none.compared, 0u);
  EXPECT_EQ(none.only_a.size(), 3u);
  EXPECT_EQ(run_opts(o).rc, 1);
  o.strip_a = "tb.dut";
  o.strip_b = "TOP";
  EXPECT_EQ(run_opts(o).rc, 0);
  o.strip_a.clear();
  o.strip_b.clear();
  o.strip_auto = true;
  const Report aut = compare(o);
  EXPECT_EQ(aut.compared, 3u);
  EXPECT_TRUE(aut.same());
  // Only one side wrapped: auto strips that side only.
  o.file_b = d.file("plain.vcd", render(counter(12), {}));
  EXPECT_EQ(compare(o).compared, 3u);
  o.strip_auto = false;
  o.strip_a = "tb.nothere";
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, a + ":0: no signal under scope 'tb.nothere'\n");
}

TEST(WavediffFilter, IncludeAndExcludeGlobs) {
  Dir d;
  Model ma = counter(10);
  Model mb = counter(10);
  ma.sigs.push_back({"top.dbg_state", 2});
  mb.sigs.push_back({"top.dbg_state", 2});
  ma.set(30, 3, "01");
  mb.set(30, 3, "10");  // differs from 30 ns on
  const auto a = d.file("a.vcd", render(ma, {}));
  const auto b = d.file("b.vcd", render(mb, {}));
  Options o = opts(a, b);
  EXPECT_EQ(run_opts(o).rc, 1);
  o.exclude = {"*.dbg_*"};
  Report r = compare(o);
  EXPECT_EQ(r.compared, 3u);
  EXPECT_TRUE(r.same());
  o.exclude.clear();
  o.include = {"top.d?g*"};
  r = compare(o);
  EXPECT_EQ(r.compared, 1u);
  ASSERT_EQ(r.diffs.size(), 1u);
  // dbg_state is first set at 30 ns; before that both are x (equal).
  EXPECT_EQ(r.diffs[0].first.at.time, 30u);
  o.include = {"top.cn?", "top.f???"};  // not top.clk
  r = compare(o);
  EXPECT_EQ(r.compared, 2u);
  EXPECT_TRUE(r.same());
  EXPECT_TRUE(glob_match("top.cnt[3]", "top.cnt[3]"));  // brackets are literal
  EXPECT_FALSE(glob_match("top.cnt[3]", "top.cnt3"));
  EXPECT_TRUE(glob_match("*", "a.b.c"));
  EXPECT_FALSE(glob_match("a?", "a"));
}

TEST(WavediffTolerance, ShiftedEdgesInTimeAndCycles) {
  Dir d;
  const std::string head =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! d $end\n"
      "$var wire 1 \" clk $end\n$upscope $end\n$enddefinitions $end\n";
  // A: d rises at 100, falls at 200. B: 3 ns later each time. Differences [100,103) and
  // [200,203): 3 ns each.
  const auto a = d.file("a.vcd", head + "#0\n0!\n#100\n1!\n#200\n0!\n#300\n");
  const auto b = d.file("b.vcd", head + "#0\n0!\n#103\n1!\n#203\n0!\n#300\n");
  Options o = opts(a, b);
  Report r = compare(o);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].count, 2u);
  EXPECT_EQ(r.diffs[0].first.at.time, 100u);
  EXPECT_EQ(r.diffs[0].last.time, 200u);
  o.tolerance_fs = 5'000'000;  // 5 ns
  EXPECT_EQ(run_opts(o).rc, 0);
  o.tolerance_fs = 3'000'000;  // exactly the shift: still within
  EXPECT_EQ(run_opts(o).rc, 0);
  o.tolerance_fs = 2'000'000;
  EXPECT_EQ(run_opts(o).rc, 1);
  // B stuck at 1: different over [0,100) (dropped with a 1 us tolerance) and from 200 to the
  // end, which never goes away and is reported whatever the tolerance.
  const auto c = d.file("c.vcd", head + "#0\n1!\n#300\n");
  o.file_b = c;
  o.tolerance_fs = 1'000'000'000;
  r = compare(o);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].count, 1u);
  EXPECT_EQ(r.diffs[0].first.at.time, 200u);
  EXPECT_TRUE(r.diffs[0].first.open);

  // Clock mode: A's d rises at edge 5 (sampled 1 from cycle 5), B's at edge 6: one cycle.
  std::string ca = head + "#0\n0!\n0\"\n";
  std::string cb = ca;
  for (int k = 0; k < 10; ++k) {
    ca += fmt::format("#{}\n1\"\n{}", 10 * k + 5, k == 5 ? "1!\n" : "");
    cb += fmt::format("#{}\n1\"\n{}", 10 * k + 5, k == 6 ? "1!\n" : "");
    ca += fmt::format("#{}\n0\"\n", 10 * k + 10);
    cb += fmt::format("#{}\n0\"\n", 10 * k + 10);
  }
  Options oc = opts(d.file("ca.vcd", ca), d.file("cb.vcd", cb));
  oc.clock_a = "top.clk";
  r = compare(oc);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].first.at.cycle, 5u);
  EXPECT_EQ(r.diffs[0].first.a, "1");
  EXPECT_EQ(r.diffs[0].first.b, "0");
  oc.tolerance_cycles = 1;
  EXPECT_EQ(run_opts(oc).rc, 0);
  // Tolerance of the wrong kind for the mode: bad input.
  oc.tolerance_fs = 1000;
  EXPECT_EQ(run_opts(oc).rc, 2);
}

TEST(WavediffXz, StrictWildcardZero) {
  Dir d;
  const std::string head =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! d $end\n"
      "$var wire 4 \" v [3:0] $end\n$upscope $end\n$enddefinitions $end\n";
  auto cmp = [&](const std::string& a, const std::string& b, XzPolicy p) {
    Options o = opts(d.file("a.vcd", head + a), d.file("b.vcd", head + b));
    o.xz = p;
    return run_opts(o).rc;
  };
  // d: x in A where B has 1; then both 1.
  const std::string a1 = "#0\nx!\nb0000 \"\n#10\n1!\n";
  const std::string b1 = "#0\n1!\nb0000 \"\n#10\n1!\n";
  EXPECT_EQ(cmp(a1, b1, XzPolicy::strict), 1);
  EXPECT_EQ(cmp(a1, b1, XzPolicy::wildcard), 0);
  EXPECT_EQ(cmp(a1, b1, XzPolicy::zero), 1);  // x reads 0, B has 1
  // x against 0: the same under zero.
  const std::string b0 = "#0\n0!\nb0000 \"\n#10\n1!\n";
  EXPECT_EQ(cmp(a1, b0, XzPolicy::zero), 0);
  EXPECT_EQ(cmp(a1, b0, XzPolicy::strict), 1);
  // z against x: different when strict, same otherwise.
  const std::string az = "#0\nz!\nb0000 \"\n";
  const std::string ax = "#0\nx!\nb0000 \"\n";
  EXPECT_EQ(cmp(az, ax, XzPolicy::strict), 1);
  EXPECT_EQ(cmp(az, ax, XzPolicy::wildcard), 0);
  EXPECT_EQ(cmp(az, ax, XzPolicy::zero), 0);
  // Vectors bit by bit: 1x0z against 1100 and 1000.
  const std::string av = "#0\n0!\nb1x0z \"\n";
  const std::string b1100 = "#0\n0!\nb1100 \"\n";
  const std::string b1000 = "#0\n0!\nb1000 \"\n";
  EXPECT_EQ(cmp(av, b1100, XzPolicy::strict), 1);
  EXPECT_EQ(cmp(av, b1100, XzPolicy::wildcard), 0);
  EXPECT_EQ(cmp(av, b1100, XzPolicy::zero), 1);  // 1000 against 1100
  EXPECT_EQ(cmp(av, b1000, XzPolicy::zero), 0);
  // Extension: "bx" fills the vector with x; "b1" with zeros on the left.
  EXPECT_EQ(cmp("#0\n0!\nbx \"\n", "#0\n0!\nbxxxx \"\n", XzPolicy::strict), 0);
  EXPECT_EQ(cmp("#0\n0!\nb1 \"\n", "#0\n0!\nb0001 \"\n", XzPolicy::strict), 0);
}

TEST(WavediffWindow, StartAndEndInTimeAndCycles) {
  Dir d;
  // cnt differs from 75 to 85 ns (edge 7 only).
  const auto a = d.file("a.vcd", render(counter(12), {}));
  const auto b = d.file("b.vcd", render(counter(12, 10, cnt_aa_at_7), {}));
  Options o = opts(a, b);
  std::string why;
  Bound bd;
  ASSERT_TRUE(parse_bound("70ns", bd, why));
  o.end = bd;
  EXPECT_EQ(run_opts(o).rc, 0);
  o.end.reset();
  ASSERT_TRUE(parse_bound("0.09us", bd, why));  // 90 ns
  EXPECT_EQ(bd.value, 90'000'000u);
  o.start = bd;
  EXPECT_EQ(run_opts(o).rc, 0);
  // Starting inside the difference: reported at the start of the window, 78 ns.
  ASSERT_TRUE(parse_bound("78ns", bd, why));
  o.start = bd;
  Report r = compare(o);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].first.at.time, 78u);
  // Cycles in clock mode.
  o.start.reset();
  o.clock_a = "top.clk";
  ASSERT_TRUE(parse_bound("c6", bd, why));
  o.end = bd;
  EXPECT_EQ(run_opts(o).rc, 0);
  ASSERT_TRUE(parse_bound("c8", bd, why));
  o.end.reset();
  o.start = bd;
  EXPECT_EQ(run_opts(o).rc, 0);
  ASSERT_TRUE(parse_bound("c7", bd, why));
  o.start = bd;
  o.end = bd;
  r = compare(o);
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].first.at.cycle, 7u);
  EXPECT_EQ(r.edges, 1u);
  // Parsing.
  EXPECT_FALSE(parse_bound("100", bd, why));
  EXPECT_FALSE(parse_bound("5 parsecs", bd, why));
  EXPECT_FALSE(parse_bound("1.5fs", bd, why));
  EXPECT_FALSE(parse_bound("cx", bd, why));
  ASSERT_TRUE(parse_bound("2us", bd, why));
  EXPECT_EQ(bd.value, 2'000'000'000u);
  ASSERT_TRUE(parse_bound("5ms", bd, why));
  EXPECT_EQ(bd.value, 5'000'000'000'000u);
  // Cycle bounds need a clock.
  o.clock_a.clear();
  EXPECT_EQ(run_opts(o).rc, 2);
}

TEST(WavediffOutputs, DiffVcdParsesBack) {
  Dir d;
  const auto a = d.file("a.vcd", render(counter(12), {}));
  const auto b = d.file("b.vcd", render(counter(12, 10, cnt_aa_at_7), {}));
  Options o = opts(a, b);
  o.diff_vcd = d.path("diff.vcd");
  EXPECT_EQ(run_opts(o).rc, 1);
  auto r = open_wave(o.diff_vcd);
  EXPECT_EQ(r->timescale_pow(), 6);
  std::map<std::string, std::uint32_t> slot;
  for (const Var& v : r->vars()) slot[v.name] = v.slot;
  for (const char* n : {"a.top.clk", "a.top.cnt", "a.top.flag", "b.top.clk", "b.top.cnt",
                        "b.top.flag", "diff.top.clk", "diff.top.cnt", "diff.top.flag"}) {
    EXPECT_EQ(slot.count(n), 1u) << n;
  }
  EXPECT_EQ(slot.size(), 9u);
  // Walk it: the flag of cnt is 1 exactly from 75 to 85 ns; a and b carry the two values.
  std::map<std::uint64_t, std::string> flag;
  std::map<std::uint64_t, std::string> bval;
  while (r->has_next()) {
    r->step();
    flag[r->time()] = r->slots()[slot["diff.top.cnt"]].bits;
    bval[r->time()] = r->slots()[slot["b.top.cnt"]].bits;
    EXPECT_EQ(r->slots()[slot["diff.top.clk"]].bits, "0");
  }
  EXPECT_EQ(flag[70], "0");
  EXPECT_EQ(flag[75], "1");
  EXPECT_EQ(flag[80], "1");
  EXPECT_EQ(flag[85], "0");
  EXPECT_EQ(bval[75], "10101010");
  EXPECT_EQ(flag.rbegin()->first, 120u);

  // Clock mode: the time axis is A's edge times, with the cycle number beside it.
  o.clock_a = "top.clk";
  EXPECT_EQ(run_opts(o).rc, 1);
  auto rc = open_wave(o.diff_vcd);
  std::uint32_t cyc = 0;
  std::uint32_t f = 0;
  for (const Var& v : rc->vars()) {
    if (v.name == "wavediff.cycle") cyc = v.slot;
    if (v.name == "diff.top.cnt") f = v.slot;
  }
  std::map<std::uint64_t, std::string> cycles;
  std::map<std::uint64_t, std::string> flags;
  while (rc->has_next()) {
    rc->step();
    cycles[rc->time()] = rc->slots()[cyc].bits;
    flags[rc->time()] = rc->slots()[f].bits;
  }
  EXPECT_EQ(cycles.size(), 12u);
  EXPECT_EQ(cycles[75], bin(7, 32));
  EXPECT_EQ(flags[75], "1");
  EXPECT_EQ(flags[85], "0");
}

TEST(WavediffOutputs, WavedromAroundTheFirstDivergence) {
  Dir d;
  const auto a = d.file("a.vcd", render(counter(12), {}));
  const auto b = d.file("b.vcd", render(counter(12, 10, cnt_aa_at_7), {}));
  Options o = opts(a, b);
  o.wavedrom = d.path("w.json");
  o.wavedrom_window = 3;
  EXPECT_EQ(run_opts(o).rc, 1);
  const auto j = nlohmann::json::parse(slurp(o.wavedrom));
  ASSERT_TRUE(j.contains("signal"));
  const auto& s = j["signal"];
  ASSERT_EQ(s.size(), 4u);
  // Events are every 5 ns; three before 75, 75, three after.
  EXPECT_EQ(s[0]["name"], "time");
  EXPECT_EQ(s[0]["data"], nlohmann::json({"60ns", "65ns", "70ns", "75ns", "80ns", "85ns", "90ns"}));
  EXPECT_EQ(s[1]["name"], "top.cnt (a)");
  EXPECT_EQ(s[1]["wave"], "==.=.=.");  // 6, 7, 7, 8, 8, 9, 9
  EXPECT_EQ(s[1]["data"], nlohmann::json({"0x06", "0x07", "0x08", "0x09"}));
  EXPECT_EQ(s[2]["name"], "top.cnt (b)");
  EXPECT_EQ(s[2]["data"], nlohmann::json({"0x06", "0x07", "0xaa", "0x09"}));
  EXPECT_EQ(s[3]["name"], "top.cnt (diff)");
  EXPECT_EQ(s[3]["wave"], "0..1.0.");
  EXPECT_EQ(j["head"]["text"], "first divergence: top.cnt at 75ns");

  // Clock mode: cycles 4..10 around cycle 7.
  o.clock_a = "top.clk";
  EXPECT_EQ(run_opts(o).rc, 1);
  const auto jc = nlohmann::json::parse(slurp(o.wavedrom));
  EXPECT_EQ(jc["signal"][0]["name"], "cycle");
  EXPECT_EQ(jc["signal"][0]["data"], nlohmann::json({"4", "5", "6", "7", "8", "9", "10"}));
  EXPECT_EQ(jc["signal"][3]["wave"], "0..10..");
}

TEST(WavediffMalformed, OneLineErrorWithFileAndLine) {
  Dir d;
  const std::string good = render(counter(2), {});
  const auto ok = d.file("ok.vcd", good);
  struct Case {
    const char* name;
    std::string content;
    std::string expect;  // after "file:"
  };
  const std::string head =
      "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! a $end\n"
      "$var wire 4 \" v [3:0] $end\n$upscope $end\n$enddefinitions $end\n";  // 6 lines
  const std::vector<Case> cases = {
      {"empty", "", "1: empty file"},
      {"blank", "  \n\n", "1: empty file"},
      {"truncated_header", "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! a $end\n",
       "3: truncated: end of file in the header (no $enddefinitions)"},
      {"truncated_var", "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! a",
       "3: truncated: end of file inside $var (from line 3)"},
      {"truncated_line", head + "#0\n0!\nb0000 \"\n#10\n1!\nb0101 \"",
       "12: truncated: the last line has no end of line"},
      {"truncated_vector", head + "#0\n0!\nb0000 \"\n#10\nb0101\n",
       "11: truncated: vector value without identifier"},
      {"truncated_dumpvars", head + "#0\n$dumpvars\n0!\n",
       "9: truncated: $dumpvars from line 8 not closed by $end"},
      {"undeclared", head + "#0\n0!\n#5\n1%\n", "10: undeclared identifier '%'"},
      {"bad_timescale", "$timescale 3 ns $end\n$enddefinitions $end\n",
       "1: bad timescale '3ns' (1, 10 or 100 of s ms us ns ps fs)"},
      {"bad_timescale_unit", "$timescale 1 ks $end\n$enddefinitions $end\n",
       "1: bad timescale '1ks' (1, 10 or 100 of s ms us ns ps fs)"},
      {"backwards", head + "#0\n0!\n#20\n1!\n#10\n0!\n", "11: time goes backwards (#10 after 20)"},
      {"garbage", head + "#0\n0!\nhello world\n", "9: unexpected 'hello'"},
      {"garbage_vector", head + "#0\nb01q2 \"\n", "8: bad vector value 'b01q2'"},
      {"garbage_time", head + "#0\n0!\n#1x\n", "9: bad time '#1x'"},
      {"garbage_header", "hello\n", "1: unexpected 'hello' in the header"},
      {"too_wide", head + "#0\nb10000 \"\n", "8: value of 5 bits for '\"' declared with 4"},
  };
  for (const Case& c : cases) {
    const auto f = d.file(std::string(c.name) + ".vcd", c.content);
    for (bool as_a : {true, false}) {
      const Outcome r = run_opts(as_a ? opts(f, ok) : opts(ok, f));
      EXPECT_EQ(r.rc, 2) << c.name;
      EXPECT_EQ(r.err, f + ":" + c.expect + "\n") << c.name;
      EXPECT_EQ(r.out, "") << c.name;
    }
  }
  const Outcome m = run_opts(opts(d.path("missing.vcd"), ok));
  EXPECT_EQ(m.rc, 2);
  EXPECT_EQ(m.err, d.path("missing.vcd") + ":0: cannot open: No such file or directory\n");
  const Outcome dir = run_opts(opts(ok, d.path("")));
  EXPECT_EQ(dir.rc, 2);
  // Not an FST although it starts like one.
  const auto fake = d.file("fake.fst", std::string("\0garbage", 8));
  const Outcome ff = run_opts(opts(fake, ok));
  EXPECT_EQ(ff.rc, 2);
  EXPECT_EQ(ff.err, fake + ":0: not a readable FST file\n");
}

TEST(WavediffFst, VcdAgainstItsVcd2fstConversion) {
  Dir d;
  const std::string tool = vcd2fst();
  ASSERT_TRUE(fs::exists(tool)) << "vcd2fst not found: install Debian's gtkwave (setup.sh does)";
  const auto a = d.file("a.vcd", render(counter(40, 10, nullptr, true), {}));
  const auto f = d.path("a.fst");
  ASSERT_EQ(spawn({tool, a, f}), 0);
  EXPECT_EQ(run_opts(opts(a, f)).rc, 0);
  EXPECT_EQ(run_opts(opts(f, a)).rc, 0);
  EXPECT_EQ(run_opts(opts(f, f)).rc, 0);
  {
    auto r = open_wave(f);
    EXPECT_STREQ(r->format(), "fst");
    EXPECT_EQ(r->timescale_pow(), 6);
  }
  // A difference against the FST: the same time and values as VCD against VCD.
  const auto b = d.file("b.vcd", render(counter(40, 10, cnt_aa_at_7, true), {}));
  const Report r = compare(opts(f, b));
  ASSERT_EQ(r.diffs.size(), 1u);
  EXPECT_EQ(r.diffs[0].name, "top.cnt");
  EXPECT_EQ(r.diffs[0].first.at.time, 75u);
  EXPECT_EQ(r.diffs[0].first.a, "00001000");
  EXPECT_EQ(r.diffs[0].first.b, "10101010");
  // Split bits and another timescale through FST too, in clock mode against a 1 ps VCD.
  Style split;
  split.split = true;
  split.timescale = "10ps";
  split.mult = 100;
  const auto s = d.file("s.vcd", render(counter(40, 10, nullptr, true), split));
  const auto sf = d.path("s.fst");
  ASSERT_EQ(spawn({tool, s, sf}), 0);
  EXPECT_EQ(run_opts(opts(a, sf)).rc, 0);
  Options oc = opts(sf, b);
  oc.clock_a = "top.clk";
  const Report rc = compare(oc);
  ASSERT_EQ(rc.diffs.size(), 1u);
  EXPECT_EQ(rc.diffs[0].first.at.cycle, 7u);
  // --end lets the FST reader stop early; the result is the same.
  Options oe = opts(f, b);
  Bound e;
  std::string why;
  ASSERT_TRUE(parse_bound("100ns", e, why));
  oe.end = e;
  EXPECT_EQ(compare(oe).diffs.size(), 1u);
}

TEST(WavediffData, HandWrittenPairWithStripMapAndSplitBits) {
  // tests/data/wavediff: an emulator-style dump (tb.dut, 1 ns, vectors, an alias) and an
  // RTL-style dump (TOP, 1 ps, split bits, other names and id codes) of the same 6 cycles.
  const std::string dir = WAVEDIFF_DATA;
  Options o = opts(dir + "/emu.vcd", dir + "/rtl.vcd");
  o.strip_auto = true;
  o.map_file = dir + "/emu_rtl.map";
  const Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("compared 6 signals: 0 differ, 0 only in A, 0 only in B"), std::string::npos)
      << r.out;
  o.clock_a = "clk";
  EXPECT_EQ(run_opts(o).rc, 0);
  // The RTL dump with a bug: x_int falls at edge 4 instead of edge 3, so the samples of cycle 3
  // differ (A 0, B 1) and agree again from cycle 4.
  o.file_b = dir + "/rtl_late_irq.vcd";
  const Outcome late = run_opts(o);
  EXPECT_EQ(late.rc, 1);
  EXPECT_NE(late.out.find("first divergence: x_int at cycle 3 (A 70000ps, #70; B 70000ps, "
                          "#70000): A=0 B=1, last common 1"),
            std::string::npos)
      << late.out;
  o.tolerance_cycles = 1;
  EXPECT_EQ(run_opts(o).rc, 0);
}

TEST(WavediffCli, ThroughTheDpc31Binary) {
  Dir d;
  const auto a = d.file("a.vcd", render(counter(12), {}));
  const auto b = d.file("b.vcd", render(counter(12, 10, cnt_aa_at_7), {}));
  const std::string cli = DPC31_CLI;
  EXPECT_EQ(spawn({cli, "wavediff", a, a}), 0);
  const auto out = d.path("out.txt");
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--json", d.path("r.json")}, nullptr, out), 1);
  EXPECT_NE(slurp(out).find("first divergence: top.cnt at 75ns"), std::string::npos);
  EXPECT_EQ(nlohmann::json::parse(slurp(d.path("r.json")))["first_divergence"]["time"], 75);
  // Repeated --include before the positionals.
  EXPECT_EQ(spawn({cli, "wavediff", "--include", "top.clk", "--include", "top.f*", a, b}), 0);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--exclude", "*cnt"}), 0);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--clock", "top.clk", "--end", "c6"}), 0);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--tolerance", "10ns"}), 0);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--tolerance", "10"}, nullptr, out), 2);
  EXPECT_EQ(slurp(out),
            "dpc31 wavediff: --tolerance: '10' is not a time (a number and s, ms, us, ns, ps or "
            "fs; e.g. 100ns)\n");
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--xz", "maybe"}), 2);
  EXPECT_EQ(spawn({cli, "wavediff", a}), 2);
  EXPECT_EQ(spawn({cli, "wavediff", a, b, "--start", "c3"}, nullptr, out), 2);
  EXPECT_EQ(slurp(out), "wavediff: cycle bounds (c123) need --clock\n");
  EXPECT_EQ(spawn({cli, "wavediff", a, d.path("nope.vcd")}, nullptr, out), 2);
  EXPECT_EQ(slurp(out), d.path("nope.vcd") + ":0: cannot open: No such file or directory\n");
  // The same parser in-process.
  CLI::App app;
  CliArgs args;
  add_subcommand(app, args);
  std::vector<std::string> argv = {"wavediff", a,         b,         "--clock", "top.clk",
                                   "--edge",   "falling", "--start", "c2",      "--xz",
                                   "zero",     "--strip", "auto"};
  std::reverse(argv.begin(), argv.end());
  app.parse(argv);
  EXPECT_EQ(args.opt.file_a, a);
  EXPECT_EQ(args.opt.clock_a, "top.clk");
  EXPECT_EQ(args.edge, "falling");
  EXPECT_EQ(args.start, "c2");
  EXPECT_EQ(args.strip, "auto");
}

// ---------------------------------------------------------------------------------------------
// Streaming: memory does not grow with the file.

TEST(WavediffStreaming, FiftyMegabytesInBoundedMemory) {
  Dir d;
  const auto a = d.path("big_a.vcd");
  const auto b = d.path("big_b.vcd");
  std::string error;
  // One bit of one vector differs at step 400000.
  ASSERT_TRUE(write_synthetic_vcd_pair(a, b, {520'000, {400'000}}, error)) << error;
  const auto size = fs::file_size(a);
  EXPECT_GT(size, 50'000'000u);
  long rss = 0;
  const auto out = d.path("out.txt");
  const int rc = spawn({DPC31_CLI, "wavediff", a, b, "--json", d.path("r.json")}, &rss, out);
  EXPECT_EQ(rc, 1) << slurp(out);
  const auto j = nlohmann::json::parse(slurp(d.path("r.json")));
  EXPECT_EQ(j["first_divergence"]["time"], 4'000'000);  // step 400000 at 10 ps a step
  // wait4's peak RSS of the child also counts what the forked test process had resident (a few
  // MiB), so this is an upper bound; under AddressSanitizer that is the shadow memory: no bound.
#if !defined(__SANITIZE_ADDRESS__)
  EXPECT_LT(rss, 64 * 1024) << "peak RSS " << rss << " KiB";
#endif
  // Throughput is measured in bench/bench_wavediff.cpp (BM_WavediffLargePair), not here.
}
