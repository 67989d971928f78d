// Fuzz targets vcd_reader and fst_reader: `dpc31 wavediff A B` with the input as both files
// (--strip auto), through wavediff::run as the command runs it: the readers, the name matching,
// the comparison and the report. Bad input must come back as exit code 2 with a message.
//
// fstapi (third-party) calls exit(255) when a block does not decompress; the product then exits
// 255 (docs/wavediff.md). The fuzz build compiles fstapi with exit() turned into
// dpc31_fuzz_fstapi_exit (lib/wavediff/CMakeLists.txt), which throws FstapiExit, so the run
// goes on and the exit is counted instead of ending the fuzzer; the default build keeps exit().
#include <sys/mman.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <string_view>

#include "fuzz_targets.hpp"
#include "wave_reader.hpp"
#include "wavediff.hpp"

namespace dpc31::fuzz {

struct FstapiExit {
  int code;
};

namespace {

// The input as a file without touching the disk: a memfd, opened by path as the CLI opens files.
class MemFile {
 public:
  MemFile(const std::uint8_t* data, std::size_t size) : fd_(memfd_create("fuzz-wave", 0)) {
    if (fd_ < 0) {
      std::perror("memfd_create");
      std::abort();
    }
    std::size_t off = 0;
    while (off < size) {
      const ssize_t n = write(fd_, data + off, size - off);
      if (n <= 0) {
        std::perror("write");
        std::abort();
      }
      off += static_cast<std::size_t>(n);
    }
  }
  ~MemFile() { close(fd_); }
  MemFile(const MemFile&) = delete;
  MemFile& operator=(const MemFile&) = delete;
  [[nodiscard]] std::string path() const { return "/proc/self/fd/" + std::to_string(fd_); }

 private:
  int fd_;
};

int wavediff_self(const std::uint8_t* data, std::size_t size) {
  const MemFile f(data, size);
  wavediff::Options o;
  o.file_a = o.file_b = f.path();
  o.strip_auto = true;
  std::string out, err;
  int rc = 0;
  try {
    rc = wavediff::run(o, out, err);
  } catch (const FstapiExit&) {
    return 0;  // fstapi gave up on a corrupt block (the product: exit 255)
  }
  if (rc == 2 && err.empty()) {
    std::fprintf(stderr, "fuzz: wavediff exit 2 without a message\n");
    std::abort();
  }
  if (rc == 1) {
    // The same file against itself can only differ where it reads differently twice.
    std::fprintf(stderr, "fuzz: a waveform differs from itself:\n%s\n", out.c_str());
    std::abort();
  }
  return 0;
}

// The reader's header: opened as `format`, with variables declared.
std::string wave_check(const std::uint8_t* data, std::size_t size, std::string_view format) {
  const MemFile f(data, size);
  try {
    const std::unique_ptr<wavediff::WaveReader> r = wavediff::open_wave(f.path());
    if (r->format() != format) return std::string("read as ") + r->format();
    return r->vars().empty() ? "no variables" : "";
  } catch (const wavediff::InputError& e) {
    return e.what();
  } catch (const FstapiExit&) {
    return "fstapi gave up";
  }
}

}  // namespace

int vcd_reader(const std::uint8_t* data, std::size_t size) { return wavediff_self(data, size); }
int fst_reader(const std::uint8_t* data, std::size_t size) { return wavediff_self(data, size); }
std::string vcd_reader_check(const std::uint8_t* data, std::size_t size) {
  return wave_check(data, size, "vcd");
}
std::string fst_reader_check(const std::uint8_t* data, std::size_t size) {
  return wave_check(data, size, "fst");
}

}  // namespace dpc31::fuzz

#ifdef DPC31_FUZZ_FSTAPI_EXIT_HOOK
extern "C" [[noreturn]] void dpc31_fuzz_fstapi_exit(int code) {
  throw dpc31::fuzz::FstapiExit{code};
}
#endif
