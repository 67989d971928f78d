// Internal: the two reader factories behind open_wave().
#pragma once

#include "wave_reader.hpp"

namespace dpc31::wavediff {

// Each input is opened once (a pipe, `<(cat a.vcd)`, can be read only once): `fd` is the open
// input, owned by the reader from here on. A VCD reader reads on from where `fd` is, after
// `prefix` (what format detection consumed from a pipe). The FST reader opens a seekable file
// by `access` (/proc/self/fd/N of `fd`, or of a memfd holding what a pipe gave); `path` names
// the input in messages.
std::unique_ptr<WaveReader> open_vcd(const std::string& path, int fd, std::string_view prefix);
std::unique_ptr<WaveReader> open_fst(const std::string& path, int fd, const std::string& access);

}  // namespace dpc31::wavediff
