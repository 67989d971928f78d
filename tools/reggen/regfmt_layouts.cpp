// The RAM layouts of a profile (regdesc.hpp LayoutDesc) for the C header and docs/registers.md.
#include <fmt/format.h>

#include "regfmt.hpp"

namespace dpc31::regfmt {

std::vector<LayoutDefine> layout_defines(const ProfileDesc& p) {
  std::vector<LayoutDefine> out;
  for (const LayoutDesc& l : p.layouts) {
    const std::string prefix = fmt::format("{}_{}", p.macro, l.name);
    out.push_back({{}, {}, fmt::format("{}: {} ({}); byte offsets", l.name, l.desc, l.source)});
    out.push_back({prefix + "_SIZE", fmt::format("{}u", l.size), "bytes"});
    for (const LayoutByte& b : l.bytes) {
      const std::string byte = fmt::format("{}_{}", prefix, b.name);
      out.push_back({byte, fmt::format("{}u", b.offset), std::string{b.desc}});
      for (const LayoutValue& v : b.values) {
        out.push_back({fmt::format("{}_{}{}", byte, v.name, v.mask ? "_Msk" : ""),
                       hex(v.value, 2) + "u", std::string{v.desc}});
      }
    }
  }
  return out;
}

std::vector<std::vector<std::string>> layout_rows(const LayoutDesc& l) {
  std::vector<std::vector<std::string>> rows{{"Offset", "Byte", "Bits and values", "Description"}};
  for (const LayoutByte& b : l.bytes) {
    std::string values;
    for (const LayoutValue& v : b.values) {
      if (!values.empty()) values += "; ";
      values +=
          fmt::format("{} {} {}: {}", v.mask ? "mask" : "value", hex(v.value, 2), v.name, v.desc);
    }
    rows.push_back({std::to_string(b.offset), std::string{b.name}, values, std::string{b.desc}});
  }
  return rows;
}

}  // namespace dpc31::regfmt
