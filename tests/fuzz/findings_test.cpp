// The findings of the fuzzers, each pinned down by what the product must do with the input that
// found it (docs/robustness.md, "Findings"). The inputs are also replayed by FuzzReplay.
#include <gtest/gtest.h>

#include <initializer_list>
#include <string>
#include <utility>

#include "wavediff.hpp"

namespace {

int wavediff_self(const std::string& file, std::string& err) {
  dpc31::wavediff::Options o;
  o.file_a = o.file_b = file;
  o.strip_auto = true;
  std::string out;
  return dpc31::wavediff::run(o, out, err);
}

const std::string kDir = std::string(FUZZ_DIR) + "/";

// fstapi followed a block length that wraps the file position around: it read the same block
// forever (dpc31 wavediff hung).
TEST(FuzzFindings, FstBlockChainRunningBackwardsIsBadInput) {
  std::string err;
  EXPECT_EQ(wavediff_self(kDir + "regressions/fst_reader/fstapi_block_chain_backwards", err), 2);
  EXPECT_NE(err.find(":0: not a readable FST file (truncated: the block at byte 330 ends past the "
                     "end of the file)"),
            std::string::npos)
      << err;
}

// fstapi mallocs an LZ4DUO hierarchy's inner length as given and writes through NULL when that
// fails (a segmentation fault in dpc31 wavediff); likewise its compressed length (a 4 GB malloc
// for a block that claims to run past the end of the file).
TEST(FuzzFindings, FstHierarchyWithAnAbsurdLengthIsBadInput) {
  for (const auto& [f, why] : std::initializer_list<std::pair<const char*, const char*>>{
           {"fstapi_lz4duo_hierarchy_huge_inner_length", "(truncated: the block at byte 523 "},
           // The same with the block's length made to fit the file: the size check itself.
           {"fstapi_lz4duo_hierarchy_huge_inner_length_in_file",
            "(corrupt: hierarchy block at byte 523 claims 38654705832 bytes uncompressed)"},
           {"fstapi_lz4duo_hierarchy_past_end_of_file", "(truncated: the block at byte "}}) {
    std::string err;
    EXPECT_EQ(wavediff_self(kDir + "regressions/fst_reader/" + f, err), 2) << f;
    EXPECT_NE(err.find(std::string(":0: not a readable FST file ") + why), std::string::npos)
        << f << err;
  }
}

// FstReader copied as many value bytes as the hierarchy's width from a buffer fstapi sizes by the
// geometry block's length (ASan: heap-buffer-overflow in FstReader::push; in the release build
// a file compared with itself "differed"). Both lengths are now compared before any value is
// read (issue 14, finding 3): a narrower geometry, and a variable-length one (fstapi then calls
// the variable-length callback with its own length).
TEST(FuzzFindings, FstValueLengthsMustMatchTheHierarchy) {
  for (const auto& [f, why] : std::initializer_list<std::pair<const char*, const char*>>{
           {"fst_geometry_narrower_than_hierarchy",
            "(corrupt: the variable 'addr' has 13 bits in the hierarchy and 1 bits in the geometry "
            "block)"},
           {"fst_geometry_varlen_for_a_16_bit_variable",
            "(corrupt: the variable 'irr' has 16 bits in the hierarchy and a variable length in "
            "the geometry block)"}}) {
    std::string err;
    EXPECT_EQ(wavediff_self(kDir + "regressions/fst_reader/" + f, err), 2) << f;
    // fstapi's own pass over the variable-length file in the guard child reads memory the
    // corrupt geometry makes it read; depending on what lies there it ends normally (then our
    // length check refuses the file), by a signal or by an ASan report (then the guard does):
    // rejected either way.
    const bool ours =
        err.find(std::string(":0: not a readable FST file ") + why) != std::string::npos;
    const bool guard = std::string_view(f).find("varlen") != std::string_view::npos &&
                       err.find(":0: not a readable FST file (corrupt or truncated: its reader ") !=
                           std::string::npos;
    EXPECT_TRUE(ours || guard) << f << err;
  }
}

// The checks refuse no real file: the seeds (vcd2fst output) still compare equal to themselves.
TEST(FuzzFindings, FstChecksPassRealFiles) {
  for (const char* f : {"emu.fst", "rtl.fst", "rtl_late_irq.fst"}) {
    std::string err;
    EXPECT_EQ(wavediff_self(kDir + "corpus/fst_reader/" + f, err), 0) << f << ": " << err;
  }
}

}  // namespace
