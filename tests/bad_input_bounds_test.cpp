// Small files that asked for gigabytes (issue 29, docs/security.md "Inputs: sizes"): VCD and FST
// declarations (long scope names, deep scopes) and deeply nested JSON for `cosim merge`. Each
// attack at the size it was found, under an address-space limit: exit 2 and one line.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <utility>

#include "bad_input.hpp"

using namespace badinput;

namespace {

// `depth` nested scopes of `name_len` bytes each, then `vars` variables in the innermost.
std::string vcd_long_scopes(int depth, std::size_t name_len, int vars) {
  std::string s = "$timescale 1ns $end\n";
  for (int i = 0; i < depth; ++i) {
    s += "$scope module s" + std::to_string(i) + "_" + std::string(name_len, 'n') + " $end\n";
  }
  for (int v = 0; v < vars; ++v) {
    s += "$var wire 1 v" + std::to_string(v) + " x" + std::to_string(v) + " $end\n";
  }
  for (int i = 0; i < depth; ++i) s += "$upscope $end\n";
  s += "$enddefinitions $end\n#0\n";
  for (int v = 0; v < vars; ++v) s += "0v" + std::to_string(v) + "\n";
  return s;
}

// `depth` nested scopes with a variable in each (the names grow with the depth).
std::string vcd_deep_scopes(int depth) {
  std::string s = "$timescale 1ns $end\n";
  for (int i = 0; i < depth; ++i) s += "$scope module a $end\n$var wire 1 ! x $end\n";
  for (int i = 0; i < depth; ++i) s += "$upscope $end\n";
  return s + "$enddefinitions $end\n#0\n0!\n";
}

// Under 2 GB of address space (the attacks took 1.9 to 8 GB), at most 60 s. ASan reserves far
// more address space for itself: there only the time is bounded.
std::string bounded(const std::string& cmd) {
#if defined(__SANITIZE_ADDRESS__)
  return "timeout 60 " + cmd;
#else
  return "ulimit -v 2000000; timeout 60 " + cmd;
#endif
}

}  // namespace

// The findings: a 1 MB VCD with long scope names and 1000 variables exhausted 8 GB (every
// variable's full name is the whole scope path); 30 000 nested scopes took over 3 GB; vcd2fst's
// FST of such files 1.9 GB. The limits (lib/wavediff/wave_reader_impl.hpp, Declarations): a
// scope path or full name of at most 16 KiB, 256 open scopes, 32 MiB of full names in all, 2^26
// bits of values.
TEST_F(BadInput, WaveformDeclarationsAreBounded) {
  file("ok.vcd", vcd_deep_scopes(2));
  file("long.vcd", vcd_long_scopes(60, 16000, 1000));
  file("deep.vcd", vcd_deep_scopes(30000));
  file("names.vcd", vcd_long_scopes(1, 16000, 2500));
  std::string wide = "$scope module t $end\n";
  for (int v = 0; v < 5; ++v) wide += "$var wire 16000000 w" + std::to_string(v) + " w $end\n";
  file("wide.vcd", wide + "$upscope $end\n$enddefinitions $end\n");
  const auto wavediff = [&](const std::string& f) {
    const std::string out = (root_ / "io" / "out").string();
    const std::string err = (root_ / "io" / "err").string();
    const testutil::CommandResult c = testutil::run_command(
        "cd " + (root_ / "work").string() + " && " +
        bounded(std::string(kCli) + " wavediff " + f + " ok.vcd >" + out + " 2>" + err));
    return Outcome{c.rc, slurp(out), slurp(err)};
  };
  // long.vcd: the second scope (line 3) makes the path 2 x (3 + 16000 + 1) bytes.
  expect_bad(wavediff("long.vcd"), "long.vcd:3: a scope path longer than 16384 bytes",
             "long scopes");
  // deep.vcd: scope k (from 1) on line 2k; the 257th is too deep.
  expect_bad(wavediff("deep.vcd"), "deep.vcd:514: scopes nested deeper than 256", "deep scopes");
  // names.vcd: variable v (line 3 + v) is "s0_nnn...n.xV": 16004 + 1 + digits(V) bytes.
  std::uint64_t sum = 0;
  int over = 0;
  for (; sum <= (std::uint64_t{32} << 20); ++over) sum += 16004 + 1 + std::to_string(over).size();
  expect_bad(wavediff("names.vcd"),
             "names.vcd:" + std::to_string(3 + over - 1) +
                 ": the variables' full names exceed 32 MiB in all",
             "full names");
  // wide.vcd: four of 16 000 000 bits fit in 2^26, the fifth (line 6) does not.
  expect_bad(wavediff("wide.vcd"), "wide.vcd:6: the variables exceed 64 Mi bits in all", "wide");
  // The same declarations as FST (gtkwave's vcd2fst): refused alike, at line 0 (the file).
  for (const std::string f : {"long", "deep"}) {
    ASSERT_EQ(testutil::run_command("cd " + (root_ / "work").string() + " && vcd2fst " + f +
                                    ".vcd " + f + ".fst >/dev/null 2>&1")
                  .rc,
              0);
  }
  // fstapi keeps at most 512 bytes of a scope name: the 33rd of these makes the path too long.
  expect_bad(wavediff("long.fst"), "long.fst:0: a scope path longer than 16384 bytes",
             "long scopes, FST");
  expect_bad(wavediff("deep.fst"), "deep.fst:0: scopes nested deeper than 256", "deep scopes, FST");
}

// An FST from a pipe is copied into memory first (fstapi seeks): `wavediff /dev/zero a.vcd` (a
// first byte 0 reads as FST) filled 9.5 GB in 8 s. At most 1 GiB is held: a pipe of exactly that
// much is read whole (and is no FST), one byte more is refused. Bounded input, and a timeout.
TEST_F(BadInput, AnFstFromAPipeIsBoundedInMemory) {
  file("ok.vcd", vcd_deep_scopes(2));
  const std::uint64_t cap = std::uint64_t{1} << 30;
  for (const auto& [bytes, line] :
       {std::pair{cap, std::string("/dev/stdin:0: not a readable FST file")},
        std::pair{cap + 1, std::string("/dev/stdin:0: an FST from a pipe is held in memory, at "
                                       "most 1 GiB: give a larger one as a file")}}) {
    const std::string out = (root_ / "io" / "out").string();
    const std::string err = (root_ / "io" / "err").string();
    const testutil::CommandResult c = testutil::run_command(
        "cd " + (root_ / "work").string() + " && head -c " + std::to_string(bytes) +
        " /dev/zero | (" + bounded(kCli + " wavediff /dev/stdin ok.vcd >" + out + " 2>" + err) +
        ")");
    expect_bad(Outcome{c.rc, slurp(out), slurp(err)}, line, std::to_string(bytes) + " bytes");
  }
}

// A --map is read as the other text inputs are, up to its cap of 16 MiB (docs/security.md,
// "Inputs: sizes"): `--map /dev/zero` grew without bound, and under a memory limit the read
// failed and the map was taken as read so far, silently (exit 0, "same" where the map's
// renames made "different"). A pipe of exactly the cap is read whole; one byte more is refused;
// a read that fails (/proc/self/mem at address 0: EIO) is an error at its line.
TEST_F(BadInput, AWavediffMapIsBoundedAndItsReadChecked) {
  file("ok.vcd", vcd_deep_scopes(2));
  const std::string out = (root_ / "io" / "out").string();
  const std::string err = (root_ / "io" / "err").string();
  const std::string cd = "cd " + (root_ / "work").string() + " && ";
  auto wavediff = [&](const std::string& feed, const std::string& map) {
    const testutil::CommandResult c = testutil::run_command(
        cd + feed + "(" +
        bounded(kCli + " wavediff ok.vcd ok.vcd --map " + map + " >" + out + " 2>" + err) + ")");
    return Outcome{c.rc, slurp(out), slurp(err)};
  };
  expect_bad(wavediff("", "/dev/zero"),
             "/dev/zero:0: too large for a wavediff map (more than 16777216 bytes)", "/dev/zero");
  const std::uint64_t cap = std::uint64_t{16} << 20;
  const std::string comments = "yes '# a comment' | head -c ";
  const Outcome whole = wavediff(comments + std::to_string(cap) + " | ", "/dev/stdin");
  EXPECT_EQ(whole.rc, 0) << whole.err;
  expect_bad(wavediff(comments + std::to_string(cap + 1) + " | ", "/dev/stdin"),
             "/dev/stdin:0: too large for a wavediff map (more than 16777216 bytes)", "cap + 1");
  expect_bad(wavediff("", "/proc/self/mem"), "/proc/self/mem:1: cannot read the file",
             "a read that fails");
}

// The findings, as reproduced: a shard's summary with 400 KB of nested arrays in a result made
// `cosim merge` crash (SIGSEGV, the recursion of comparing and printing), with 40 KB it printed
// 800 MB. JSON deeper than 16 levels is refused while it is parsed, nothing printed.
TEST_F(BadInput, CosimMergeRefusesDeeplyNestedJson) {
  const Outcome shard = dpc31("cosim --quiet --seeds 2 --cycles 100 --shard 1/2");
  ASSERT_EQ(shard.rc, 0) << shard.err;
  const Outcome other = dpc31("cosim --quiet --seeds 2 --cycles 100 --shard 2/2");
  ASSERT_EQ(other.rc, 0) << other.err;
  file("s2.json", other.out);
  const std::size_t seed = shard.out.find("\"seed\"");
  ASSERT_NE(seed, std::string::npos) << shard.out;
  for (const std::size_t depth : {200'000u, 20'000u}) {
    std::string deep = shard.out;
    deep.insert(seed, "\"x\": " + std::string(depth, '[') + std::string(depth, ']') + ", ");
    file("deep.json", deep);
    const Outcome r = dpc31("cosim merge deep.json s2.json");
    expect_bad(r,
               "dpc31 cosim merge: deep.json: nested deeper than 16 levels: not the JSON summary "
               "of a `dpc31 cosim --shard` run",
               std::to_string(2 * depth) + " bytes of arrays in a result");
    EXPECT_EQ(r.out, "");
  }
  file("arrays.json", std::string(17, '[') + std::string(17, ']'));
  expect_bad(dpc31("cosim merge arrays.json"),
             "dpc31 cosim merge: arrays.json: nested deeper than 16 levels: not the JSON summary "
             "of a `dpc31 cosim --shard` run",
             "17 levels");
  file("arrays.json", std::string(16, '[') + std::string(16, ']'));
  expect_bad(dpc31("cosim merge arrays.json"),
             "dpc31 cosim merge: arrays.json: not the JSON summary of a `dpc31 cosim --shard` run",
             "16 levels: parsed, then refused by its shape");
}
