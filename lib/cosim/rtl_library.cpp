#include "rtl_library.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <pwd.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "child.hpp"
#include "outfile.hpp"

namespace dpc31::cosim {

namespace fs = std::filesystem;

// --- loading ---

namespace {

class LibDut final : public Dut {
 public:
  LibDut(std::shared_ptr<const RtlLibrary> lib, const dpc31_rtl_model* m, void* model)
      : lib_(std::move(lib)), m_(m), model_(model) {}
  ~LibDut() override { m_->destroy(model_); }
  LibDut(const LibDut&) = delete;
  LibDut& operator=(const LibDut&) = delete;

  void step(const Inputs& in) override {
    const dpc31_rtl_inputs r = rtl_inputs(in);
    m_->step(model_, &r);
  }
  [[nodiscard]] Outputs outputs() const override {
    Outputs o;
    m_->read_outputs(model_, o.v.data());
    return o;
  }
  [[nodiscard]] std::string name() const override { return "RTL"; }
  bool trace_to(const std::string& path) override {
    return m_->trace_to(model_, path.c_str()) != 0;
  }

 private:
  std::shared_ptr<const RtlLibrary> lib_;  // the code stays loaded while a model lives
  const dpc31_rtl_model* m_;
  void* model_;
};

}  // namespace

std::shared_ptr<const RtlLibrary> RtlLibrary::load(const std::string& path, std::string& error) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    error =
        fmt::format("{}: {}", path, fs::exists(path, ec) ? "not a regular file" : "no such file");
    return nullptr;
  }
  // dlopen searches the library path for a name without a slash: a file name means that file.
  const std::string name = path.find('/') == std::string::npos ? "./" + path : path;
  // RTLD_LOCAL: each model keeps its own copy of Verilator's runtime.
  void* h = ::dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (h == nullptr) {
    error = ::dlerror();  // "FILE: reason"
    return nullptr;
  }
  using Entry = const dpc31_rtl_model* (*)();
  const auto entry = reinterpret_cast<Entry>(::dlsym(h, "dpc31_rtl_model_get"));
  const dpc31_rtl_model* m = entry != nullptr ? entry() : nullptr;
  if (m == nullptr || m->abi != DPC31_RTL_MODEL_ABI || m->outputs != DPC31_RTL_OUTPUTS) {
    error = m == nullptr ? fmt::format(
                               "{}: no dpc31_rtl_model_get() entry point (not built by "
                               "dpc31emu_verilate_model or dpc31 cosim --rtl)",
                               path)
                         : fmt::format("{}: model interface version {}, this harness needs {}",
                                       path, m->abi, DPC31_RTL_MODEL_ABI);
    ::dlclose(h);
    return nullptr;
  }
  return std::shared_ptr<const RtlLibrary>(new RtlLibrary(h, m, path));
}

RtlLibrary::~RtlLibrary() { ::dlclose(handle_); }

std::unique_ptr<Dut> RtlLibrary::make_dut(const DutOptions& o, unsigned mutant_sel) const {
  void* model = model_->create(o.bus == BusMode::motorola ? 1 : 0, o.asic_type(), mutant_sel);
  if (model == nullptr) return nullptr;
  return std::make_unique<LibDut>(o.rtl, model_, model);
}

// --- building ---

std::string rtl_cache_dir() {
  if (const char* d = std::getenv("DPC31EMU_RTL_CACHE"); d != nullptr && *d != '\0') return d;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x != nullptr && *x == '/')
    return std::string(x) + "/dpc31emu/rtl";
  const char* home = std::getenv("HOME");
  if (home == nullptr || *home == '\0') {
    // Not /tmp: a model.so there could be anyone's, and we load it into our process.
    const passwd* pw = ::getpwuid(::geteuid());
    home = pw != nullptr ? pw->pw_dir : nullptr;
  }
  if (home == nullptr || *home == '\0') return {};
  return std::string(home) + "/.cache/dpc31emu/rtl";
}

namespace {

// We dlopen what the cache holds, so it must be ours alone: owned by us, writable by nobody else
// (where it points to, if it is a symlink). Empty: fine; else the one-line reason.
std::string cache_not_private(const std::string& cache) {
  struct stat st {};
  if (::stat(cache.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) return "not a directory";
  if (st.st_uid != ::geteuid()) return "owned by another user";
  if ((st.st_mode & (S_IWGRP | S_IWOTH)) != 0) return "writable by others";
  return {};
}

}  // namespace

namespace {

// 64-bit FNV-1a: a cache key, not a security measure (the cache is the user's own directory).
struct Fnv {
  std::uint64_t h = 0xcbf29ce484222325ull;
  // The length too, so that ("ab", "c") and ("a", "bc") differ.
  void add(std::string_view s) {
    bytes(s);
    bytes(fmt::format("|{}|", s.size()));
  }
  void bytes(std::string_view s) {
    for (const char c : s) {
      h ^= static_cast<unsigned char>(c);
      h *= 0x100000001b3ull;
    }
  }
};

bool slurp(const fs::path& p, std::string& out) {
  std::ifstream f(p, std::ios::binary);
  if (!f) return false;
  std::ostringstream s;
  s << f.rdbuf();
  out = s.str();
  return !f.bad();
}

// A program on PATH, as a shell finds it; "" when there is none.
std::string on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  for (std::string d; std::getline(dirs, d, ':');) {
    const std::string p = (d.empty() ? "." : d) + "/" + name;
    if (::access(p.c_str(), X_OK) == 0) return p;
  }
  return "";
}

// The directory with dpc31emu_rtl.cmake and the adapter (rtl_model_entry.cpp,
// verilated_blocks.hpp, dpc31_rtl_model.h): next to an installed dpc31
// (<bindir>/DPC31_BIN_TO_DATA/cosim), else the source tree this dpc31 was built from.
struct Support {
  std::string cmake_file;
  std::string adapter_dir;
};
Support support_files() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = exe.parent_path() / DPC31_BIN_TO_DATA / "cosim";
    if (fs::exists(installed / "dpc31emu_rtl.cmake", ec))
      return {(installed / "dpc31emu_rtl.cmake").lexically_normal().string(),
              installed.lexically_normal().string()};
  }
  return {DPC31_RTL_CMAKE, DPC31_RTL_ADAPTER_DIR};
}

// The one line that says why a step of the build failed: our port check's, Verilator's first
// error or warning (-Wall makes warnings fatal), or the compiler's first error; "" if none.
std::string why_failed(const std::string& log) {
  std::string verilator;
  std::string compiler;
  std::istringstream is(log);
  for (std::string line; std::getline(is, line);) {
    if (const std::size_t at = line.find("dpc31emu: "); at != std::string::npos)
      return line.substr(at + 10);
    if (verilator.empty() && (line.rfind("%Error", 0) == 0 || line.rfind("%Warning", 0) == 0))
      verilator = "Verilator: " + line;
    if (compiler.empty() && line.find("error:") != std::string::npos) compiler = line;
  }
  return !verilator.empty() ? verilator : compiler;
}

std::string read_log(const std::string& path) {
  std::string s;
  slurp(path, s);
  return s;
}

bool valid_define(const std::string& d) {
  const std::string name = d.substr(0, d.find('='));
  return !name.empty() &&
         (std::isalpha(static_cast<unsigned char>(name[0])) != 0 || name[0] == '_') &&
         std::all_of(name.begin(), name.end(), [](char c) {
           return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
         });
}

// Holds an exclusive lock on a file while it lives: one build per key at a time, so parallel
// shards that start together wait for the first one's build and then load its result.
class FileLock {
 public:
  explicit FileLock(const std::string& path)
      : fd_(::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
    if (fd_ >= 0) {
      while (::flock(fd_, LOCK_EX) != 0 && errno == EINTR) {
      }
    }
  }
  ~FileLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  [[nodiscard]] bool ok() const { return fd_ >= 0; }

 private:
  int fd_;
};

}  // namespace

bool build_rtl_model(const RtlBuild& b, std::string& model_path, std::string& error,
                     std::FILE* progress) {
  // Everything that can be checked without Verilator first, each a line of its own.
  if (b.sources.empty()) {
    error = "--rtl needs at least one Verilog file";
    return false;
  }
  if (b.top.empty()) {
    error = "--rtl needs --top MODULE (the top module of your sources)";
    return false;
  }
  if (!std::all_of(b.top.begin(), b.top.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
      })) {
    error = fmt::format("--top {}: not a Verilog module name", b.top);
    return false;
  }
  for (const std::string& d : b.defines) {
    if (!valid_define(d)) {
      error = fmt::format("--define {}: not NAME or NAME=VALUE", d);
      return false;
    }
  }
  Fnv key;
  key.add("dpc31emu rtl model 1");
  std::vector<std::string> sources;
  std::vector<fs::path> dirs;
  std::error_code ec;
  for (const std::string& s : b.sources) {
    std::string text;
    if (!fs::exists(s, ec)) {
      error = fmt::format("--rtl {}: no such file", s);
      return false;
    }
    if (!fs::is_regular_file(s, ec) || !slurp(s, text)) {
      error = fmt::format("--rtl {}: not a readable regular file", s);
      return false;
    }
    const fs::path abs = fs::absolute(s, ec).lexically_normal();
    sources.push_back(abs.string());
    key.add(abs.filename().string());
    key.add(text);
    if (std::find(dirs.begin(), dirs.end(), abs.parent_path()) == dirs.end())
      dirs.push_back(abs.parent_path());
  }
  // The files an `include can reach: every Verilog file in the sources' directories (the -I
  // directories), by name and content, in name order.
  for (const fs::path& d : dirs) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(d, ec)) {
      const std::string ext = e.path().extension().string();
      if (e.is_regular_file(ec) && (ext == ".v" || ext == ".vh" || ext == ".sv" || ext == ".svh"))
        files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
      std::string text;
      slurp(f, text);
      key.add(f.filename().string());
      key.add(text);
    }
  }
  const std::string verilator = on_path("verilator");
  const std::string cmake = on_path("cmake");
  if (verilator.empty() || cmake.empty()) {
    error = fmt::format("--rtl needs {} on PATH (docs/golden-model.md)",
                        verilator.empty() ? "verilator" : "cmake");
    return false;
  }
  const Support support = support_files();
  for (const std::string& f : {support.cmake_file, support.adapter_dir + "/rtl_model_entry.cpp",
                               support.adapter_dir + "/verilated_blocks.hpp",
                               support.adapter_dir + "/dpc31_rtl_model.h"}) {
    std::string text;
    if (!slurp(f, text)) {
      error = fmt::format("{}: missing (a broken installation of dpc31emu?)", f);
      return false;
    }
    key.add(text);
  }
  const std::string cache = rtl_cache_dir();
  if (cache.empty()) {
    error = "RTL cache: no home directory; set DPC31EMU_RTL_CACHE to a private directory";
    return false;
  }
  fs::create_directories(cache, ec);
  if (ec) {
    error = fmt::format("RTL cache {}: {}", cache, ec.message());
    return false;
  }
  if (const std::string why = cache_not_private(cache); !why.empty()) {
    error = fmt::format(
        "RTL cache {}: {}; the models in it are loaded into this process, so it "
        "must be yours alone (set DPC31EMU_RTL_CACHE to a private directory)",
        cache, why);
    return false;
  }
  // Verilator's version (its banner) is part of the key: a new Verilator, a new model.
  std::string version;
  {
    const std::string out = fmt::format("{}/verilator-version.{}", cache, ::getpid());
    const child::Result r =
        child::run({"/bin/sh", "-c", "exec \"$0\" --version >&2", verilator}, out);
    slurp(out, version);
    fs::remove(out, ec);
    if (r.exit_code != 0) {
      error = fmt::format("{} --version failed", verilator);
      return false;
    }
  }
  key.add(version);
  key.add(b.top);
  key.add(std::string(profile_desc(b.profile).name));
  for (const std::string& d : b.defines) key.add(d);
  if (const char* cxx = std::getenv("CXX")) key.add(cxx);
  const std::string dir = fmt::format("{}/{:016x}", cache, key.h);
  model_path = dir + "/model.so";

  FileLock lock(dir + ".lock");
  if (!lock.ok()) {
    error = fmt::format("RTL cache {}: cannot create the lock file", cache);
    return false;
  }
  if (fs::exists(model_path, ec)) return true;  // built before (or by a shard that came first)

  // A fresh build: a CMake project of one call to dpc31emu_verilate_model().
  fs::remove_all(dir, ec);
  fs::create_directories(dir + "/project", ec);
  const auto quoted = [](const std::string& s) { return "[==[" + s + "]==]"; };
  std::string list = "cmake_minimum_required(VERSION 3.16)\nproject(dpc31emu_rtl_model CXX)\n";
  // Through ccache when there is one, paths relative to the entry: a model built again in
  // another entry (a new Verilator, other defines) reuses the compiles that did not change.
  list += fmt::format("set(entry {})\nfind_program(ccache_program ccache)\nif(ccache_program)\n",
                      quoted(dir));
  list +=
      "  set(CMAKE_CXX_COMPILER_LAUNCHER ${CMAKE_COMMAND} -E env \"CCACHE_BASEDIR=${entry}\" "
      "CCACHE_NOHASHDIR=1 ${ccache_program})\nendif()\n";
  list += fmt::format("set(DPC31EMU_RTL_ADAPTER_DIR {})\ninclude({})\n",
                      quoted(support.adapter_dir), quoted(support.cmake_file));
  list += "dpc31emu_verilate_model(TARGET model TOP " + b.top + " PROFILE " +
          std::string(profile_desc(b.profile).name) + "\n  SOURCES";
  for (const std::string& s : sources) list += " " + quoted(s);
  if (!b.defines.empty()) {
    list += "\n  DEFINES";
    for (const std::string& d : b.defines) list += " " + quoted(d);
  }
  list += ")\n";
  if (!outfile::write_file(dir + "/project/CMakeLists.txt", list, error)) return false;
  if (progress != nullptr) {
    fmt::print(progress, "dpc31 cosim: building the RTL model (first use of these sources) in {}\n",
               dir);
    std::fflush(progress);
  }
  // Verilator runs at the configure step: its errors are in configure.log.
  const std::string configure_log = dir + "/configure.log";
  const child::Result conf = child::run(
      {cmake, "-S", dir + "/project", "-B", dir + "/build", "-DCMAKE_BUILD_TYPE=RelWithDebInfo"},
      configure_log);
  if (conf.exit_code != 0) {
    const std::string why = why_failed(read_log(configure_log));
    error = !why.empty() ? why
                         : fmt::format("configuring the RTL build failed (log: {})", configure_log);
    return false;
  }
  const std::string build_log = dir + "/build.log";
  const unsigned jobs = std::max(1u, std::thread::hardware_concurrency());
  const child::Result build =
      child::run({cmake, "--build", dir + "/build", "--parallel", std::to_string(jobs)}, build_log);
  std::string built = dir + "/build/model.so";
  if (build.exit_code != 0 || !fs::exists(built, ec)) {
    const std::string why = why_failed(read_log(build_log));
    error = why.rfind("Verilator: ", 0) == 0 || why.find(": port ") != std::string::npos
                ? why
                : fmt::format("C++ build of the RTL model failed: {} (log: {})",
                              why.empty() ? "see the log" : why, build_log);
    return false;
  }
  // model.so appears whole or not at all: it marks a finished build.
  fs::copy_file(built, model_path + ".tmp", fs::copy_options::overwrite_existing, ec);
  if (!ec) fs::rename(model_path + ".tmp", model_path, ec);
  if (ec) {
    error = fmt::format("{}: {}", model_path, ec.message());
    return false;
  }
  fs::remove_all(dir + "/build", ec);  // the objects are in ccache, if anywhere
  return true;
}  // namespace

}  // namespace dpc31::cosim
