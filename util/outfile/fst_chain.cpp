#include "fst_chain.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "gtkwave/fstapi.h"

namespace dpc31::fst_chain {

namespace {

constexpr std::uint64_t kHeaderLength = 329;  // fstapi's FST_HDRSIZE: the length of block 0
constexpr long kSectionCount = 65;            // fstapi's FST_HDR_OFFS_SECTION_CNT

std::uint64_t big_endian(const unsigned char* b, std::size_t n) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) v = v << 8 | b[i];
  return v;
}

}  // namespace

Chain walk(std::FILE* f) {
  Chain c;
  std::uint64_t size = 0;
  if (std::fseek(f, 0, SEEK_END) == 0 && std::ftell(f) > 0) {
    size = static_cast<std::uint64_t>(std::ftell(f));
  }
  unsigned char head[9];
  std::uint64_t pos = 0;
  for (bool first = true; pos < size && c.problem.empty(); first = false) {
    std::size_t n = 0;
    if (std::fseek(f, static_cast<long>(pos), SEEK_SET) == 0) n = std::fread(head, 1, 9, f);
    if (first && n > 0 && head[0] == FST_BL_ZWRAPPER) {
      c.gzip = true;  // left to fstapi
      return c;
    }
    const std::uint64_t len = n > 1 ? big_endian(head + 1, n - 1) : 0;
    const unsigned type = head[0];
    if (first && (n < 9 || type != FST_BL_HDR || len != kHeaderLength || 1 + len > size)) {
      c.not_fst = true;
      return c;
    }
    if (n < 9) {
      c.problem = fmt::format("truncated: the block at byte {} has no header", pos);
    } else if (type > FST_BL_VCDATA_DYN_ALIAS2 && type != FST_BL_SKIP) {
      c.problem = fmt::format("corrupt: unknown block type {} at byte {}", type, pos);
    } else if (len < 8) {
      c.problem = fmt::format("corrupt: block length {} at byte {}", len, pos);
    } else if (len > size - pos - 1) {
      // Also a length that would wrap the position around (fstapi would loop forever).
      c.problem = fmt::format("truncated: the block at byte {} ends past the end of the file", pos);
    } else {
      c.blocks.push_back({pos, type, len});
      pos += 1 + len;
    }
  }
  if (size == 0) c.not_fst = true;
  return c;
}

std::string incomplete(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return fmt::format("cannot read it back: {}", std::strerror(errno));
  const Chain c = walk(f);
  unsigned char count[8] = {};
  const bool counted =
      std::fseek(f, kSectionCount, SEEK_SET) == 0 && std::fread(count, 1, 8, f) == 8;
  std::fclose(f);
  if (c.not_fst || c.gzip) return "no FST header";
  if (!c.problem.empty()) return c.problem;
  const auto has = [&c](std::initializer_list<unsigned> types) {
    return std::any_of(c.blocks.begin(), c.blocks.end(), [&](const Block& b) {
      return std::find(types.begin(), types.end(), b.type) != types.end();
    });
  };
  if (!has({FST_BL_GEOM})) return "no geometry block";
  if (!has({FST_BL_HIER, FST_BL_HIER_LZ4, FST_BL_HIER_LZ4DUO})) return "no hierarchy block";
  const auto sections = static_cast<std::uint64_t>(
      std::count_if(c.blocks.begin(), c.blocks.end(), [](const Block& b) {
        return b.type == FST_BL_VCDATA || b.type == FST_BL_VCDATA_DYN_ALIAS ||
               b.type == FST_BL_VCDATA_DYN_ALIAS2;
      }));
  if (!counted || big_endian(count, 8) != sections) {
    return fmt::format("{} value-change blocks where the header counts {}", sections,
                       big_endian(count, 8));
  }
  return {};
}

}  // namespace dpc31::fst_chain
