#include "rtl_library.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <pwd.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "child.hpp"
#include "outfile.hpp"
#include "plugin_symbol.hpp"
#include "textfile.hpp"
#include "trust.hpp"

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
  [[nodiscard]] bool stopped() const override {
    return m_->stopped != nullptr && m_->stopped(model_) != 0;
  }

 private:
  std::shared_ptr<const RtlLibrary> lib_;  // the code stays loaded while a model lives
  const dpc31_rtl_model* m_;
  void* model_;
};

// What is wrong with the table dpc31_rtl_model_get() returned ("" if nothing): each entry is
// used, a NULL one would be called. `profile` gets the model's.
std::string table_problem(const dpc31_rtl_model* m, Profile& profile) {
  if (m == nullptr) return "dpc31_rtl_model_get() returned NULL, not a model";
  if (m->abi != DPC31_RTL_MODEL_ABI) {
    return fmt::format(
        "model interface version {}, this harness needs {} (rebuild it against this dpc31emu)",
        m->abi, DPC31_RTL_MODEL_ABI);
  }
  if (m->outputs != DPC31_RTL_OUTPUTS) {
    return fmt::format("the model has {} outputs, this harness compares {} (DPC31_RTL_OUTPUTS)",
                       m->outputs, DPC31_RTL_OUTPUTS);
  }
  const std::pair<const char*, bool> entries[] = {
      {"top", m->top != nullptr},          {"profile", m->profile != nullptr},
      {"create", m->create != nullptr},    {"destroy", m->destroy != nullptr},
      {"step", m->step != nullptr},        {"read_outputs", m->read_outputs != nullptr},
      {"trace_to", m->trace_to != nullptr}};
  for (const auto& [name, set] : entries) {
    if (!set) return fmt::format("the model's {} is NULL", name);
  }
  if (!parse_profile(m->profile, profile)) {
    return fmt::format("the model's profile '{}' is not spc3, vpc3plus or dpc31",
                       shown(m->profile));
  }
  return "";
}

}  // namespace

std::shared_ptr<const RtlLibrary> RtlLibrary::load(const std::string& path, std::string& error) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    error =
        fmt::format("{}: {}", path, fs::exists(path, ec) ? "not a regular file" : "no such file");
    return nullptr;
  }
  // Checked and loaded through one descriptor: what was checked is what runs, whatever is
  // swapped in at the path meanwhile (docs/security.md, "Code a command runs").
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    error = fmt::format("{}: {}", path, std::error_code(errno, std::generic_category()).message());
    return nullptr;
  }
  if (const std::string why = untrusted_code(fd, path); !why.empty()) {
    ::close(fd);
    error = fmt::format(
        "RTL model refused: {} (it runs as your code: another user could have "
        "changed it)",
        why);
    return nullptr;
  }
  const std::string by_fd = fmt::format("/proc/self/fd/{}", fd);
  // RTLD_LOCAL: each model keeps its own copy of Verilator's runtime.
  void* h = ::dlopen(by_fd.c_str(), RTLD_NOW | RTLD_LOCAL);
  ::close(fd);
  if (h == nullptr) {
    const char* const e = ::dlerror();
    error = e != nullptr ? e : by_fd + ": cannot be loaded";  // "FILE: reason"
    if (error.starts_with(by_fd)) error.replace(0, by_fd.size(), path);
    return nullptr;
  }
  using Entry = const dpc31_rtl_model* (*)();
  void* const sym = ::dlsym(h, "dpc31_rtl_model_get");
  if (const std::string why = sym != nullptr
                                  ? symbol_problem(sym, "dpc31_rtl_model_get", SymbolKind::function,
                                                   "dpc31_rtl_model.h")
                                  : std::string();
      !why.empty()) {
    error = fmt::format("{}: {}", path, why);
    ::dlclose(h);
    return nullptr;
  }
  const auto entry = reinterpret_cast<Entry>(sym);
  Profile profile = Profile::dpc31;
  // One call: the table checked is the table kept.
  const auto* const table = entry != nullptr ? entry() : nullptr;
  const std::string why = entry != nullptr
                              ? table_problem(table, profile)
                              : std::string(
                                    "no dpc31_rtl_model_get() entry point (not built "
                                    "by dpc31emu_verilate_model or dpc31 cosim --rtl)");
  if (!why.empty()) {
    error = fmt::format("{}: {}", path, why);
    ::dlclose(h);
    return nullptr;
  }
  return std::shared_ptr<const RtlLibrary>(new RtlLibrary(h, table, profile, path));
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

constexpr mode_t kPrivateDir = 0700;

// `dir` and what is missing above it, each made mode 0700 whatever the umask (a directory we
// create is ours alone); then we dlopen what the cache holds, so the cache and every directory
// above it must be ours or root's and writable by nobody else (untrusted_directory). "" or one
// line.
std::string private_cache(const std::string& dir) {
  std::string made;
  for (const fs::path& part : fs::path(dir)) {
    made = made.empty() || made.back() == '/' ? made + part.string() : made + "/" + part.string();
    if (::mkdir(made.c_str(), kPrivateDir) == 0) {
      ::chmod(made.c_str(), kPrivateDir);
    } else if (errno != EEXIST) {
      return fmt::format("{}: {}", made, std::error_code(errno, std::generic_category()).message());
    }
  }
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    return fmt::format("{}: {}", dir, std::error_code(errno, std::generic_category()).message());
  }
  std::string why = untrusted_directory(fd, dir);
  ::close(fd);
  return why;
}

// A directory of the cache made mode 0700 whatever the umask; refused when something else is
// there already (a link, a file).
bool private_dir(const std::string& dir, std::string& error) {
  struct stat st {};
  if (::mkdir(dir.c_str(), kPrivateDir) == 0) {
    if (::chmod(dir.c_str(), kPrivateDir) == 0) return true;
  } else if (errno == EEXIST && ::lstat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    return true;
  }
  error = fmt::format("RTL cache {}: cannot make it a private directory", dir);
  return false;
}

// Sets the process's umask while it lives: what the build's children create is ours alone.
class Umask {
 public:
  explicit Umask(mode_t m) : old_(::umask(m)) {}
  ~Umask() { ::umask(old_); }
  Umask(const Umask&) = delete;
  Umask& operator=(const Umask&) = delete;

 private:
  mode_t old_;
};

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
// verilated_blocks.hpp, dpc31_rtl_model.h): <bindir>/DPC31_BIN_TO_DATA/cosim beside this dpc31,
// installed or in the build tree (lib/cosim/CMakeLists.txt copies them there), wherever the
// prefix was moved: no path of the machine that built it is compiled in.
struct Support {
  std::string cmake_file;
  std::string adapter_dir;
  std::string error;
};
Support support_files() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {{}, {}, "cannot find this program's own path (/proc/self/exe)"};
  const fs::path dir = (exe.parent_path() / DPC31_BIN_TO_DATA / "cosim").lexically_normal();
  return {(dir / "dpc31emu_rtl.cmake").string(), dir.string(), {}};
}

// Each named source, and what Verilator's preprocessor makes of them all, is read up to this.
constexpr std::size_t kMaxSourceBytes = 64u << 20;
constexpr std::size_t kMaxPreprocessed = 256u << 20;

// What CMake can carry as one item of a list in a -D value: no ';', no control character.
bool cmake_list_item(std::string_view s) {
  return std::none_of(s.begin(), s.end(), [](char c) {
    return c == ';' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
  });
}

// Runs Verilator with `args` (its standard output and error into a file of the private cache),
// its output into `out`, bounded. False if it failed (`out` has its messages then).
bool run_verilator(const std::string& verilator, const std::vector<std::string>& args,
                   const std::string& cache, std::string& out) {
  const std::string file = fmt::format("{}/verilator-output.{}", cache, ::getpid());
  std::vector<std::string> argv = {"/bin/sh", "-c", "exec \"$@\" >&2", "sh", verilator};
  argv.insert(argv.end(), args.begin(), args.end());
  const child::Result r = child::run(argv, file);
  std::string why;
  const bool read = read_text_file(file, kMaxPreprocessed, "Verilator output", out, why);
  std::error_code ec;
  fs::remove(file, ec);
  if (!read) out = why;
  return read && r.exit_code == 0;
}

// The first construct of Verilator's preprocessed output (`line directives kept) that runs code
// of the host: $system (a shell command), $c / $cN (inline C++), `systemc_* (C++ pasted into the
// model), DPI imports (calls into any C function, system() too). "" or "FILE:LINE: what"; text in
// string literals does not count.
std::string host_code(std::string_view pre) {
  std::string file = "?";
  long line = 0;
  const auto ident = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
  };
  for (std::size_t pos = 0; pos < pre.size();) {
    const std::size_t eol = std::min(pre.find('\n', pos), pre.size());
    const std::string_view l = pre.substr(pos, eol - pos);
    pos = eol + 1;
    if (l.starts_with("`line ")) {
      // `line N "FILE" LEVEL: the next line is line N of FILE.
      line = std::strtol(std::string(l.substr(6)).c_str(), nullptr, 10) - 1;
      const std::size_t q = l.find('"');
      const std::size_t q2 = q == std::string_view::npos ? q : l.find('"', q + 1);
      if (q2 != std::string_view::npos) file = std::string(l.substr(q + 1, q2 - q - 1));
      continue;
    }
    ++line;
    const std::string at = fmt::format("{}:{}: ", file, line);
    if (l.find("`systemc_") != std::string_view::npos) {
      return at + "`systemc_ pastes C++ into the model";
    }
    bool in_string = false;
    for (std::size_t i = 0; i < l.size(); ++i) {
      if (in_string) {
        if (l[i] == '\\')
          ++i;
        else if (l[i] == '"')
          in_string = false;
        continue;
      }
      if (l[i] == '"') {
        in_string = true;
      } else if (l[i] == '$' && (i == 0 || !ident(l[i - 1]))) {
        std::size_t e = i + 1;
        while (e < l.size() && ident(l[e])) ++e;
        const std::string_view name = l.substr(i, e - i);
        if (name == "$system") return at + "$system runs a shell command";
        if (name.size() >= 2 && name[1] == 'c' &&
            std::all_of(name.begin() + 2, name.end(),
                        [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; })) {
          return at + std::string(name) + " runs inline C++";
        }
      } else if (l.compare(i, 6, "import") == 0 && (i == 0 || !ident(l[i - 1])) &&
                 l.find("\"DPI", i) != std::string_view::npos) {
        return at + "a DPI import calls C functions of the host";
      }
    }
  }
  return {};
}

// `from` copied to `to` (mode 0700 whatever the umask) through a temporary and a rename.
bool copy_private(const std::string& from, const std::string& to, std::string& error) {
  const std::string tmp = to + ".tmp";
  ::unlink(tmp.c_str());
  const int in = ::open(from.c_str(), O_RDONLY | O_CLOEXEC);
  const int out = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0700);
  bool ok = in >= 0 && out >= 0 && ::fchmod(out, 0700) == 0;
  std::array<char, 64 * 1024> buf{};
  for (ssize_t n = 0; ok && (n = ::read(in, buf.data(), buf.size())) != 0;) {
    ok = n > 0 && ::write(out, buf.data(), static_cast<std::size_t>(n)) == n;
  }
  ok = ok && ::fsync(out) == 0;
  const int e = errno;
  if (in >= 0) ::close(in);
  if (out >= 0 && ::close(out) != 0) ok = false;
  if (ok && ::rename(tmp.c_str(), to.c_str()) == 0) return true;
  ::unlink(tmp.c_str());
  error = fmt::format("{}: {}", to, std::error_code(e, std::generic_category()).message());
  return false;
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
      : fd_(::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0600)) {
    if (fd_ >= 0) {
      ::fchmod(fd_, 0600);
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
    if (!valid_define(d) || !cmake_list_item(d)) {
      error = fmt::format("--define {}: not NAME or NAME=VALUE{}", shown(d),
                          valid_define(d) ? " (no ';' or control character in VALUE)" : "");
      return false;
    }
  }
  std::vector<std::string> sources;
  std::error_code ec;
  for (const std::string& s : b.sources) {
    if (!fs::exists(s, ec)) {
      error = fmt::format("--rtl {}: no such file", s);
      return false;
    }
    if (!fs::is_regular_file(s, ec)) {
      error = fmt::format("--rtl {}: not a readable regular file", s);
      return false;
    }
    if (fs::file_size(s, ec) > kMaxSourceBytes) {
      error = fmt::format("--rtl {}: larger than {} MiB", s, kMaxSourceBytes >> 20);
      return false;
    }
    const std::string abs = fs::absolute(s, ec).lexically_normal().string();
    // The names reach CMake as the value of a -D option (data), and a list of them: ';' would
    // split one, a control character would break CMakeCache.txt's lines.
    if (!cmake_list_item(abs)) {
      error = fmt::format("--rtl {}: a file name with ';' or a control character cannot be built",
                          shown(s));
      return false;
    }
    // Verilator (5.006) cuts a source's path at its first blank in its own file:line records:
    // the run then ends in a lint warning about a file that does not exist.
    if (abs.find(' ') != std::string::npos) {
      error = fmt::format(
          "--rtl {}: a path with a blank cannot be built (Verilator cuts file names at the first "
          "blank): move or link the sources to a path without one",
          shown(s));
      return false;
    }
    sources.push_back(abs);
  }
  const std::string verilator = on_path("verilator");
  const std::string cmake = on_path("cmake");
  if (verilator.empty() || cmake.empty()) {
    error = fmt::format("--rtl needs {} on PATH (docs/golden-model.md)",
                        verilator.empty() ? "verilator" : "cmake");
    return false;
  }
  const Support support = support_files();
  if (!support.error.empty()) {
    error = support.error;
    return false;
  }
  Fnv key;
  key.add("dpc31emu rtl model 2");
  for (const std::string& f : {support.cmake_file, support.adapter_dir + "/rtl_model_entry.cpp",
                               support.adapter_dir + "/verilated_blocks.hpp",
                               support.adapter_dir + "/dpc31_rtl_model.h"}) {
    std::string text;
    std::string why;
    if (!read_text_file(f, kMaxSourceBytes, "adapter file", text, why)) {
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
  if (const std::string why = private_cache(cache); !why.empty()) {
    error = fmt::format(
        "RTL cache {}: {}; the models in it are loaded into this process, so it "
        "must be yours alone (set DPC31EMU_RTL_CACHE to a private directory)",
        cache, why);
    return false;
  }
  const Umask private_files(077);  // the children's files too (Verilator, CMake, the compiler)
  // Verilator's version (its banner) is part of the key: a new Verilator, a new model.
  std::string version;
  if (!run_verilator(verilator, {"--version"}, cache, version)) {
    error = fmt::format("{} --version failed", verilator);
    return false;
  }
  key.add(version);
  // The key is what Verilator reads: the named sources and every file they `include, as its
  // preprocessor puts them together (bounded), with the defines applied.
  std::vector<std::string> pp_args = {"-E"};
  for (const std::string& s : sources) {
    pp_args.push_back("-I" + fs::path(s).parent_path().string());
  }
  for (const std::string& d : b.defines) pp_args.push_back("-D" + d);
  pp_args.insert(pp_args.end(), sources.begin(), sources.end());
  std::string pre;
  if (!run_verilator(verilator, pp_args, cache, pre)) {
    const std::string why = why_failed(pre);
    error = !why.empty() ? why : "Verilator's preprocessor failed on the --rtl sources";
    return false;
  }
  if (!b.host_code) {
    if (const std::string found = host_code(pre); !found.empty()) {
      error = found +
              ": it would run on this machine inside dpc31 with your rights; refused "
              "unless --rtl-host-code is given (docs/golden-model.md)";
      return false;
    }
  }
  key.add(pre);
  key.add(b.host_code ? "host code allowed" : "");
  for (const std::string& s : sources) key.add(fs::path(s).filename().string());
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

  // A fresh build: a CMake project of one call to dpc31emu_verilate_model(). Its text is ours
  // alone: every name the user gave (sources, defines, the cache's path) reaches CMake as the
  // value of a -D option, data that is never read as CMake code.
  fs::remove_all(dir, ec);
  if (!private_dir(dir, error) || !private_dir(dir + "/project", error)) return false;
  const std::string list = R"(cmake_minimum_required(VERSION 3.16)
project(dpc31emu_rtl_model CXX)
# Through ccache when there is one, paths relative to the entry: a model built again in another
# entry (a new Verilator, other defines) reuses the compiles that did not change.
get_filename_component(entry "${CMAKE_CURRENT_LIST_DIR}" DIRECTORY)
find_program(ccache_program ccache)
if(ccache_program)
  set(CMAKE_CXX_COMPILER_LAUNCHER ${CMAKE_COMMAND} -E env "CCACHE_BASEDIR=${entry}"
    CCACHE_NOHASHDIR=1 ${ccache_program})
endif()
set(DPC31EMU_RTL_ADAPTER_DIR "${DPC31_RTL_ADAPTER}")
include("${DPC31_RTL_CMAKE}")
dpc31emu_verilate_model(TARGET model TOP "${DPC31_RTL_TOP}" PROFILE "${DPC31_RTL_PROFILE}"
  SOURCES ${DPC31_RTL_SOURCES} DEFINES ${DPC31_RTL_DEFINES})
)";
  if (!outfile::write_file(dir + "/project/CMakeLists.txt", list, error)) return false;
  const auto joined = [](const std::vector<std::string>& v) {
    std::string out;
    for (const std::string& x : v) out += (out.empty() ? "" : ";") + x;
    return out;
  };
  if (progress != nullptr) {
    fmt::print(progress, "dpc31 cosim: building the RTL model (first use of these sources) in {}\n",
               dir);
    std::fflush(progress);
  }
  // Verilator runs at the configure step: its errors are in configure.log.
  const std::string configure_log = dir + "/configure.log";
  const child::Result conf = child::run(
      {cmake, "-S", dir + "/project", "-B", dir + "/build", "-DCMAKE_BUILD_TYPE=RelWithDebInfo",
       "-DDPC31_RTL_ADAPTER:STRING=" + support.adapter_dir,
       "-DDPC31_RTL_CMAKE:STRING=" + support.cmake_file, "-DDPC31_RTL_TOP:STRING=" + b.top,
       "-DDPC31_RTL_PROFILE:STRING=" + std::string(profile_desc(b.profile).name),
       "-DDPC31_RTL_SOURCES:STRING=" + joined(sources),
       "-DDPC31_RTL_DEFINES:STRING=" + joined(b.defines)},
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
  // model.so appears whole or not at all: it marks a finished build. Mode 0700 whatever the umask.
  if (!copy_private(built, model_path, error)) return false;
  fs::remove_all(dir + "/build", ec);  // the objects are in ccache, if anywhere
  // The logs are for a failed build: verilate() passes Verilator's output on only when it fails
  // (-Wall makes a warning one), and a build that succeeded has no errors to show.
  fs::remove(configure_log, ec);
  fs::remove(build_log, ec);
  return true;
}

}  // namespace dpc31::cosim
