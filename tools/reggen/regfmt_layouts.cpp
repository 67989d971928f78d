// The RAM layouts of a profile (regdesc.hpp LayoutDesc) for the C header and docs/registers.md,
// and the word wrap the text emitters share.
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

std::vector<std::string> wrap(std::string_view text, std::size_t width) {
  std::vector<std::string> lines;
  std::string line;
  std::size_t pos = 0;
  while (pos < text.size()) {
    while (pos < text.size() && (text[pos] == ' ' || text[pos] == '\n')) ++pos;
    if (pos >= text.size()) break;
    std::size_t end = text.find_first_of(" \n", pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view word = text.substr(pos, end - pos);
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      lines.push_back(std::move(line));
      line.clear();
    }
    if (!line.empty()) line += ' ';
    line += word;
    pos = end;
  }
  if (!line.empty()) lines.push_back(std::move(line));
  return lines;
}

}  // namespace dpc31::regfmt
