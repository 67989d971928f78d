// Reading an input file whole, with a size bound and a one-line reason when it cannot be read.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace dpc31 {

// `what` names the kind of file in messages ("scenario", "trace"). False with `error` set.
bool read_text_file(const std::string& path, std::size_t max_bytes, std::string_view what,
                    std::string& text, std::string& error);

}  // namespace dpc31
