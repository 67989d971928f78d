// Firmware by name or as a run-time plug-in (dpc31/dpc31_firmware.h), and the C host of that
// header (dpc31_firmware_load, dpc31_module_*).
#include <dlfcn.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "cpu51_config.hpp"
#include "firmware.h"
#include "firmware_host.hpp"
#include "plugin_symbol.hpp"
#include "trust.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

bool is_plugin_path(const std::string& spec) {
  return spec.find('/') != std::string::npos ||
         (spec.size() >= 3 && spec.compare(spec.size() - 3, 3, ".so") == 0);
}

std::string builtin_firmware_names() {
  std::string all;
  for (int i = 0; dpc31_firmwares[i] != nullptr; ++i) {
    all += (i == 0 ? "" : ", ") + std::string(dpc31_firmwares[i]->name);
  }
  return all;
}

SlaveConfig with_gsd_defaults(const dpc31_firmware& fw, SlaveConfig base) {
  base.ident = fw.ident;
  base.cfg.assign(fw.cfg, fw.cfg + fw.cfg_len);
  base.in_len = fw.in_len;
  base.out_len = fw.out_len;
  base.user_prm.assign(fw.user_prm, fw.user_prm + fw.user_prm_len);
  return base;
}

std::string descriptor_problem(const dpc31_firmware* fw) {
  if (fw == nullptr) return "the descriptor pointer is NULL";
  if (fw->abi_version != DPC31_FIRMWARE_ABI_VERSION) {
    return "descriptor ABI version " + std::to_string(fw->abi_version) + ", this host takes " +
           std::to_string(DPC31_FIRMWARE_ABI_VERSION) + " (rebuild it against this dpc31emu)";
  }
  if (fw->name == nullptr || fw->name[0] == '\0') return "the descriptor has no name";
  if (std::string c = control_character_in(fw->name); !c.empty())
    return "the descriptor's name has a control character, " + c +
           " (a name is shown in logs and walks, one entry a line)";
  if (fw->init == nullptr) return "the descriptor has no init";
  if (fw->isr == nullptr && fw->main_step == nullptr) {
    return "the descriptor has neither isr nor main_step";
  }
  if (fw->cfg == nullptr || fw->cfg_len == 0)
    return "the descriptor has no Cfg bytes (cfg, cfg_len)";
  if (fw->user_prm == nullptr && fw->user_prm_len != 0) {
    return "the descriptor's user_prm is NULL with user_prm_len " +
           std::to_string(fw->user_prm_len);
  }
  if ((fw->hw_input == nullptr) != (fw->hw_inputs == nullptr)) {
    return "the descriptor has hw_input without hw_inputs or the other way round";
  }
  // The names a scenario's `expect port` and `hw` take: words, each once (as `ports=`).
  for (const auto& [list, what] : {std::pair{fw->ports, "port"}, {fw->hw_inputs, "input"}}) {
    std::vector<std::string> names;
    for (const char* const* n = list; n != nullptr && *n != nullptr; ++n) names.emplace_back(*n);
    if (std::string why = names_problem(names, what); !why.empty()) {
      return "the descriptor's " + std::string(what) + "s: " + why;
    }
  }
  return {};
}

namespace {

// dlopen looks a name without '/' up in the library path; the user meant the file.
std::string file_path(const std::string& spec) {
  return spec.find('/') == std::string::npos ? "./" + spec : spec;
}

// A plug-in as loaded (load_plugin). Its file stays open for as long as the process runs, as the
// library stays loaded: the copies (plugin_copy) are made from what was checked, and dlopen takes
// a name it has loaded before ("/proc/self/fd/N") for that library, so no later file may get the
// same descriptor number. The same file named again (dev, inode) is the library loaded before,
// without a dlopen.
struct Loaded {
  int fd = -1;
  dev_t dev = 0;
  ino_t ino = 0;
  std::string path;
  const dpc31_firmware* fw = nullptr;  // the library load_plugin loaded
  bool run = false;                    // a host has run it: its globals are no longer fresh
};
std::mutex g_loaded_mutex;
std::vector<std::unique_ptr<Loaded>> g_loaded;  // never freed: those libraries are never closed

Loaded* family_of(const dpc31_firmware* fw) {
  for (const auto& l : g_loaded) {
    if (l->fw == fw) return l.get();
  }
  return nullptr;
}

struct Library {
  void* handle;
  const dpc31_firmware* fw;
  int fd;  // the file it was loaded from
};

// The library open at `fd` (dlopen through /proc/self/fd/N) and its descriptor; `path` names it
// in messages. `fd` is closed when dlopen fails, else it stays open with the library.
Library open_library(int fd, const std::string& path, std::string_view hex_remedy) {
  // RTLD_NOW: an undefined symbol fails here, not in the middle of a run. RTLD_LOCAL: two
  // plug-ins may use the same names. The library load_plugin loads is never closed (its
  // descriptor is the firmware's for the process); a copy is closed with its last host.
  const std::string by_fd = "/proc/self/fd/" + std::to_string(fd);
  void* const lib = ::dlopen(by_fd.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (lib == nullptr) {
    // dlerror() names the descriptor's path: said with the user's.
    const char* const e = ::dlerror();
    std::string why = e != nullptr ? e : by_fd + ": cannot be loaded";
    if (why.starts_with(by_fd)) why.replace(0, by_fd.size(), path);
    // An Intel HEX record starts with ':': the user meant a CPU's program, not a plug-in.
    char first = 0;
    if (::pread(fd, &first, 1, 0) == 1 && first == ':')
      why += fmt::format("; it is an Intel HEX image, a CPU's program: {}", hex_remedy);
    ::close(fd);
    throw FirmwareError("cannot load firmware plug-in: " + why);
  }
  ::dlerror();
  void* const sym = ::dlsym(lib, DPC31_FIRMWARE_SYMBOL);
  if (sym == nullptr) {
    throw FirmwareError("firmware plug-in " + path +
                        " exports no " DPC31_FIRMWARE_SYMBOL
                        " (DPC31_FIRMWARE_EXPORT, dpc31/dpc31_firmware.h)");
  }
  if (const std::string why =
          symbol_problem(sym, DPC31_FIRMWARE_SYMBOL, SymbolKind::pointer, "dpc31/dpc31_firmware.h");
      !why.empty()) {
    throw FirmwareError("firmware plug-in " + path + ": " + why);
  }
  const dpc31_firmware* const fw = *static_cast<const dpc31_firmware* const*>(sym);
  const std::string problem = descriptor_problem(fw);
  if (!problem.empty()) throw FirmwareError("firmware plug-in " + path + ": " + problem);
  return {lib, fw, fd};
}

// Another copy of a loaded plug-in: its file's bytes in a new anonymous file (a new inode, so
// dlopen loads the library anew: its constructors run, its globals start as the file gives them).
// The anonymous file stays open with the copy (close_copy).
Library load_copy(const Loaded& l) {
  const auto fail = [&l](const std::string& what) {
    return FirmwareError("cannot load another copy of firmware plug-in " + l.path + ": " + what +
                         ": " + std::error_code(errno, std::generic_category()).message());
  };
  const int copy = ::memfd_create("dpc31-firmware-copy", MFD_CLOEXEC);
  if (copy < 0) throw fail("memfd_create");
  char buf[65536];
  for (off_t at = 0;;) {
    const ssize_t n = ::pread(l.fd, buf, sizeof buf, at);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const FirmwareError e = fail("read");
      ::close(copy);
      throw e;
    }
    if (n == 0) break;
    for (ssize_t done = 0; done < n;) {
      const ssize_t w = ::write(copy, buf + done, static_cast<std::size_t>(n - done));
      if (w < 0 && errno == EINTR) continue;
      if (w < 0) {
        const FirmwareError e = fail("write");
        ::close(copy);
        throw e;
      }
      done += w;
    }
    at += n;
  }
  return open_library(copy, l.path, kHexAtCpuDoor);  // loaded before: no Intel HEX image
}

// A directory in its place (an empty name is ./), a FIFO or a device is no library, whoever could
// change it.
void not_a_library(const std::string& path, const struct stat& st) {
  if (S_ISREG(st.st_mode)) return;
  throw FirmwareError("cannot load firmware plug-in: " + path +
                      (S_ISDIR(st.st_mode) ? ": is a directory" : ": not a regular file"));
}

const dpc31_firmware& load_plugin(const std::string& spec, std::string_view hex_remedy) {
  const std::string path = file_path(spec);
  // Checked and loaded through one descriptor: what was checked is what runs, whatever is renamed
  // or swapped in at the path meanwhile (docs/security.md, "Code a command runs").
  // Opened without waiting (a FIFO's open() waits for a writer: the run hung); the descriptor's
  // check below refuses a FIFO or a device.
  struct stat st {};
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    throw FirmwareError("cannot load firmware plug-in: " + path + ": " +
                        std::error_code(errno, std::generic_category()).message());
  }
  if (::fstat(fd, &st) != 0 || ::fcntl(fd, F_SETFL, O_RDONLY) != 0) {
    const int e = errno;
    ::close(fd);
    throw FirmwareError("cannot load firmware plug-in: " + path + ": " +
                        std::error_code(e, std::generic_category()).message());
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    not_a_library(path, st);
  }
  const std::string untrusted = untrusted_code(fd, path);
  if (!untrusted.empty()) {
    ::close(fd);
    throw FirmwareError("firmware plug-in refused: " + untrusted +
                        " (a plug-in runs as your code: another user could have changed it)");
  }
  const std::lock_guard<std::mutex> lock(g_loaded_mutex);
  for (const auto& known : g_loaded) {
    if (known->dev == st.st_dev && known->ino == st.st_ino) {
      ::close(fd);
      return *known->fw;
    }
  }
  const dpc31_firmware& fw = *open_library(fd, path, hex_remedy).fw;
  auto l = std::make_unique<Loaded>();
  l->fd = fd;
  l->dev = st.st_dev;
  l->ino = st.st_ino;
  l->path = path;
  l->fw = &fw;
  g_loaded.push_back(std::move(l));
  return fw;
}

// A copy no host holds any more: unloaded, and its anonymous file closed. A library that stays
// loaded all the same (one marked NODELETE, e.g. by a C++ unique symbol) keeps its name
// "/proc/self/fd/N", so its file stays open too: a later copy opened as N would be taken for it.
void close_copy(const Library& copy) {
  ::dlclose(copy.handle);
  const std::string by_fd = "/proc/self/fd/" + std::to_string(copy.fd);
  if (void* const still = ::dlopen(by_fd.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NOLOAD)) {
    ::dlclose(still);
    return;
  }
  ::close(copy.fd);
}

}  // namespace

std::shared_ptr<const dpc31_firmware> plugin_copy(const dpc31_firmware& fw) {
  const std::lock_guard<std::mutex> lock(g_loaded_mutex);
  Loaded* const l = family_of(&fw);
  if (l == nullptr) return {&fw, [](const dpc31_firmware*) {}};
  // The library load_plugin loaded runs once: its globals are fresh only until a host ran it.
  if (!l->run) {
    l->run = true;
    return {l->fw, [](const dpc31_firmware*) {}};
  }
  const Library copy = load_copy(*l);
  return {copy.fw, [copy](const dpc31_firmware*) { close_copy(copy); }};
}

std::string hex_at_command(std::string_view command) {
  return fmt::format(
      "`dpc31 {}` cannot run an 80C32 image; `dpc31 run` (the header cpu 80c32 firmware FILE), "
      "`dpc31 bridge` and `dpc31 serve` (--cpu 80c32) can",
      command);
}

const dpc31_firmware& find_firmware(const std::string& spec, std::string_view hex_remedy) {
  if (is_plugin_path(spec)) return load_plugin(spec, hex_remedy);
  const dpc31_firmware* fw = dpc31_find_firmware(spec.c_str());
  if (fw == nullptr) {
    throw FirmwareError("unknown firmware '" + spec + "' (" + builtin_firmware_names() +
                        ", or a plug-in path such as ./libmine.so)");
  }
  return *fw;
}

}  // namespace dpc31

struct dpc31_module {
  dpc31_module(dpc31::ChipOptions o, const dpc31_firmware& fw) : chip(o), host(fw) {}
  dpc31::Chip chip;
  dpc31::FirmwareHost host;
  std::unique_ptr<dpc31::Cpu> cpu;
  std::string error;
};

extern "C" {

const dpc31_firmware* dpc31_firmware_load(const char* path, char* err, size_t err_size) {
  try {
    // file_path would make "" the directory "./": the reason names what the caller gave.
    if (path == nullptr || *path == '\0')
      throw std::invalid_argument(std::string("cannot load firmware plug-in: no path given (") +
                                  (path == nullptr ? "NULL" : "an empty string") + ")");
    return &dpc31::find_firmware(
        dpc31::file_path(path),
        "an 80C32 image runs on a dpc31::Cpu51Board (C++, docs/cpu.md), or with --cpu 80c32 at "
        "`dpc31 run`, `dpc31 bridge` and `dpc31 serve`");
  } catch (const std::exception& e) {
    if (err != nullptr && err_size > 0) {
      std::strncpy(err, e.what(), err_size - 1);
      err[err_size - 1] = '\0';
    }
    return nullptr;
  }
}

dpc31_module* dpc31_module_create(const char* profile, int motorola, const dpc31_firmware* fw,
                                  uint8_t station_address) {
  dpc31::ChipOptions o;
  if (profile == nullptr || !dpc31::parse_profile(profile, o.profile)) return nullptr;
  if (!dpc31::descriptor_problem(fw).empty()) return nullptr;
  if (!dpc31::kStationAddress.holds(station_address)) return nullptr;
  o.bus = motorola != 0 ? dpc31::BusMode::motorola : dpc31::BusMode::intel;
  std::unique_ptr<dpc31_module> m;
  try {
    // A plug-in's private copy may fail to load (no file descriptor, memfd_create): NULL, as the
    // header says, never an exception out of a C function.
    m = std::make_unique<dpc31_module>(o, *fw);
  } catch (const std::exception&) {
    return nullptr;
  }
  try {
    dpc31::DirectBus bus(m->chip);
    m->host.init(bus, station_address);
  } catch (const std::exception& e) {
    m->error = e.what();
  }
  m->cpu = std::make_unique<dpc31::Cpu>(m->chip, m->host.program());
  return m.release();
}

void dpc31_module_destroy(dpc31_module* module) {
  if (module == nullptr) return;
  module->cpu.reset();  // unwinds the firmware's stack before the chip goes away
  delete module;
}

int dpc31_module_run(dpc31_module* module, uint64_t cycles) {
  if (!module->error.empty()) return -1;
  try {
    module->cpu->run_until(dpc31::Chip::cycle_after(module->chip.cycle(), cycles));
  } catch (const std::exception& e) {
    module->error = e.what();
    return -1;
  }
  return 0;
}

const char* dpc31_module_error(const dpc31_module* module) { return module->error.c_str(); }
uint64_t dpc31_module_cycle(const dpc31_module* module) { return module->chip.cycle(); }
uint8_t dpc31_module_peek(const dpc31_module* module, uint16_t addr) {
  return module->chip.peek(addr);
}
int64_t dpc31_module_port(const dpc31_module* module, const char* name) {
  return module->host.port(name != nullptr ? name : "");
}

}  // extern "C"
