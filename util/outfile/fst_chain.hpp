// The block chain of an FST file (fstapi.h: a type byte, a big-endian length that counts itself
// and the data, the data): walked by the FST reader's guard (lib/wavediff, docs/bad-input.md)
// and after each FST write, because fstapi does not check its own writes (a full file system
// leaves a short file and no error).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace dpc31::fst_chain {

struct Block {
  std::uint64_t pos;
  unsigned type;
  std::uint64_t len;
};

struct Chain {
  bool not_fst = false;  // no FST header block first
  bool gzip = false;     // a gzip-wrapped FST: one wrapper block, not walked
  std::vector<Block> blocks;
  std::string problem;  // the first break in the chain ("truncated: ...", "corrupt: ..."), or ""
};

// Reads the chain of the file open as `f` from its first byte; it must end exactly at the end of
// the file.
Chain walk(std::FILE* f);

// "" if `path` is a whole FST file as fstapi's writer leaves it on success: an unbroken chain
// with a geometry and a hierarchy block, and as many value-change blocks as its header counts.
// Otherwise what is wrong, for a message.
std::string incomplete(const std::string& path);

}  // namespace dpc31::fst_chain
