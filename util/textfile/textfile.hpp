// Reading an input file whole, with a size bound and a one-line reason when it cannot be read.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace dpc31 {

// `what` names the kind of file in messages ("scenario", "trace"). False with `error` set.
bool read_text_file(const std::string& path, std::size_t max_bytes, std::string_view what,
                    std::string& text, std::string& error);

// A line-based file cut off mid-line may still parse ("end 10000" cut to "end 1000"); every
// editor and writer ends the last line, so a file without that newline is taken as cut off.
// 0 if `text` is empty or ends with '\n', else the number of its last line, with `error` set.
int cut_off_line(std::string_view text, std::string& error);

// A token as it may appear in a one-line message: printable (other bytes as \xHH), at most 40
// characters and "...".
std::string shown(std::string_view s);

}  // namespace dpc31
