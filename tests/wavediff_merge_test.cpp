// dpc31 wavediff --merge (docs/wavediff.md, "One file for a comparison"): A's and B's signals
// under a and b, a diff signal for each that is 1 exactly where they differ, as VCD or FST by the
// extension, and the GTKWave save file beside it. Expected times worked out by hand.
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "wavediff_model.hpp"

using namespace wavediff_test;

namespace {

const std::string kMergeHead =
    "$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! d $end\n"
    "$var wire 8 \" v [7:0] $end\n$upscope $end\n$enddefinitions $end\n";

// v: 10h from 0, 20h (A) or 21h (B, bit 0 set) from 50, 30h from 100; d toggles alike on both.
std::string merge_wave(bool b) {
  return kMergeHead + "#0\n0!\nb00010000 \"\n#25\n1!\n#50\nb0010000" + (b ? "1" : "0") +
         " \"\n#75\n0!\n#100\nb00110000 \"\n#150\n";
}

std::string merge_read(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Every time step of `path`: time -> the value of each named variable after it.
std::map<std::uint64_t, std::map<std::string, std::string>> merge_walk(const std::string& path) {
  auto r = open_wave(path);
  std::map<std::string, std::uint32_t> slot;
  for (const Var& v : r->vars()) slot[v.name] = v.slot;
  std::map<std::uint64_t, std::map<std::string, std::string>> out;
  while (r->has_next()) {
    r->step();
    for (const auto& [name, s] : slot) out[r->time()][name] = r->slots()[s].bits;
  }
  return out;
}

}  // namespace

TEST(WavediffMerge, DiffIsHighExactlyWhereOneBitDiffersInVcdAndFst) {
  Dir d;
  Options o = opts(d.write("a.vcd", merge_wave(false)), d.write("b.vcd", merge_wave(true)));
  for (const char* ext : {"vcd", "fst"}) {
    o.merge = d.file(fmt::format("m.{}", ext));
    ASSERT_EQ(run_opts(o).rc, 1) << ext;
    const auto steps = merge_walk(o.merge);
    ASSERT_EQ(steps.begin()->second.size(), 6u) << ext;  // a, b and diff of top.d and top.v
    // diff.top.v: 0 before 50, 1 over [50, 100) where B's bit 0 is set, 0 from 100.
    std::map<std::uint64_t, std::string> want = {{0, "0"}, {50, "1"}, {100, "0"}};
    std::string flag;
    for (const auto& [t, vals] : steps) {
      if (want.count(t) != 0) flag = want[t];
      EXPECT_EQ(vals.at("diff.top.v"), flag) << ext << " at " << t;
      EXPECT_EQ(vals.at("diff.top.d"), "0") << ext << " at " << t;
      EXPECT_EQ(vals.at("a.top.d"), vals.at("b.top.d")) << ext << " at " << t;
    }
    EXPECT_EQ(steps.at(50).at("a.top.v"), "00100000") << ext;
    EXPECT_EQ(steps.at(50).at("b.top.v"), "00100001") << ext;
    // The end of the comparison: a time step of its own in VCD (an FST reader walks changes).
    EXPECT_EQ(steps.rbegin()->first, std::string(ext) == "vcd" ? 150u : 100u) << ext;
    // The save file: the dump by its absolute path, each pair and its diff as one group.
    const std::string save = merge_read(d.file("m.gtkw"));
    EXPECT_NE(
        save.find(fmt::format("[dumpfile] \"{}\"", std::filesystem::absolute(o.merge).string())),
        std::string::npos);
    EXPECT_NE(save.find("@800200\n-top.d\n@28\na.top.d\n@28\nb.top.d\n@28\ndiff.top.d\n"
                        "@1000200\n-top.d\n"),
              std::string::npos)
        << save;
    EXPECT_NE(save.find("@800200\n-top.v\n@22\na.top.v[7:0]\n@22\nb.top.v[7:0]\n@28\n"
                        "diff.top.v\n@1000200\n-top.v\n"),
              std::string::npos)
        << save;
  }
}

// The save file opens GTKWave on the whole merged file (docs/wavediff.md, "One file for a
// comparison"): [timestart] its first time, the zoom -log2((LAST - FIRST) / 2), no marker (26
// times -1), times as GTKWave counts them, the file's x 10 in 10 ns units. merge_wave runs from
// #0 to #150 in 1 ns: -log2(75) = -6.228819. From #20 to #170 in 10 ns: GTKWave's 200 to 1700,
// -log2(1500 / 2) = -9.550747.
TEST(WavediffMerge, TheSaveFileOpensOnTheWholeMergedFile) {
  Dir d;
  std::string none;
  for (int i = 0; i < 26; ++i) none += " -1";
  const auto view = [&d](const Options& o) {
    EXPECT_EQ(run_opts(o).rc, 1);
    std::istringstream in(merge_read(d.file("m.gtkw")));
    std::vector<std::string> lines;
    for (std::string l; std::getline(in, l) && lines.size() < 5;) lines.push_back(l);
    return lines.size() == 5 ? lines[3] + "\n" + lines[4] : std::string();
  };
  Options o = opts(d.write("a.vcd", merge_wave(false)), d.write("b.vcd", merge_wave(true)));
  o.merge = d.file("m.vcd");
  EXPECT_EQ(view(o), "[timestart] 0\n*-6.228819 -1" + none);
  const std::string head =
      "$timescale 10ns $end\n$scope module top $end\n$var wire 1 ! d $end\n$upscope $end\n"
      "$enddefinitions $end\n#20\n0!\n#70\n";
  o = opts(d.write("a10.vcd", head + "1!\n#170\n"), d.write("b10.vcd", head + "0!\n#170\n"));
  for (const char* ext : {"vcd", "fst"}) {
    o.merge = d.file(fmt::format("m.{}", ext));
    EXPECT_EQ(view(o), "[timestart] 200\n*-9.550747 -1" + none) << ext;
  }
}

TEST(WavediffMerge, BadNamesAreRefusedBeforeAnyWork) {
  Dir d;
  Options o = opts(d.write("a.vcd", merge_wave(false)), d.write("b.vcd", merge_wave(true)));
  o.merge = d.file("m.txt");
  Outcome r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, fmt::format("dpc31 wavediff: --merge {}: the name must end in .vcd or .fst\n",
                               o.merge));
  EXPECT_FALSE(std::filesystem::exists(o.merge));
  EXPECT_FALSE(std::filesystem::exists(d.file("m.gtkw")));
  // The save file may not be an input or another output.
  o.merge = d.file("a.fst");
  o.json_file = d.file("a.gtkw");
  r = run_opts(o);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("--merge's save file"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(o.merge));
}
