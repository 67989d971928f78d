#include "textfile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

namespace dpc31 {

bool read_text_file(const std::string& path, std::size_t max_bytes, std::string_view what,
                    std::string& text, std::string& error) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    error = "no such file";
    return false;
  }
  if (std::filesystem::is_directory(path, ec)) {
    error = fmt::format("is a directory, not a {} file", what);
    return false;
  }
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    error = "cannot open the file";
    return false;
  }
  text.assign(max_bytes + 1, '\0');
  f.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (f.bad()) {
    error = "cannot read the file";
    return false;
  }
  text.resize(static_cast<std::size_t>(f.gcount()));
  if (text.size() > max_bytes) {
    error = fmt::format("too large for a {} (more than {} bytes)", what, max_bytes);
    return false;
  }
  return true;
}

int cut_off_line(std::string_view text, std::string& error) {
  if (text.empty() || text.back() == '\n') return 0;
  error = "truncated: the last line has no end of line";
  return static_cast<int>(std::count(text.begin(), text.end(), '\n')) + 1;
}

std::string shown(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7F) {
      out += static_cast<char>(c);
    } else {
      out += fmt::format("\\x{:02X}", c);
    }
  }
  if (s.size() > 40) out += "...";
  return out;
}

}  // namespace dpc31
