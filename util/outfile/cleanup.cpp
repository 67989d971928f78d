#include "cleanup.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>

namespace dpc31::cleanup {

namespace {

// Slots 0..kPaths-1 hold paths, kPaths.. child pids. state: 0 free, 1 being filled, 2 live.
constexpr int kPaths = 64;
constexpr int kChildren = 64;

enum class Kind : std::uint8_t { file, tree, dir };  // removed in this order

struct Slot {
  std::atomic<int> state{0};
  pid_t pid = 0;
  Kind kind = Kind::file;
  char path[PATH_MAX] = {};
};

Slot g_slots[kPaths + kChildren];
std::atomic<pid_t> g_owner{0};  // the process that installed: a forked child only re-raises
constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};

constexpr int kTreeDepth = 16;

// Removes `name` in the directory `at` and, if it is a directory, everything in it first.
// Async-signal-safe: openat, getdents64, unlinkat, close; no allocation (a small buffer per level
// on the stack). A pass that removed something is followed by another from the start, since a
// directory read while it changes may skip entries.
void remove_at(int at, const char* name, int depth) {
  if (::unlinkat(at, name, 0) == 0 || (errno != EISDIR && errno != EPERM)) return;
  const int fd = ::openat(at, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return;
  bool removed = depth < kTreeDepth;
  while (removed) {
    removed = false;
    ::lseek(fd, 0, SEEK_SET);
    alignas(struct dirent64) char buf[1024];
    for (ssize_t n = 0; (n = ::getdents64(fd, buf, sizeof buf)) > 0;) {
      for (ssize_t off = 0; off < n;) {
        const auto* d = reinterpret_cast<const struct dirent64*>(buf + off);
        off += d->d_reclen;
        const char* e = d->d_name;
        if (e[0] == '.' && (e[1] == 0 || (e[1] == '.' && e[2] == 0))) continue;
        remove_at(fd, e, depth + 1);
        removed = true;
      }
    }
  }
  ::close(fd);
  ::unlinkat(at, name, AT_REMOVEDIR);
}

// Async-signal-safe: only loads, kill(), unlink(), rmdir() and remove_at().
void remove_all(int sig) {
  for (int i = kPaths; i < kPaths + kChildren; ++i) {
    if (g_slots[i].state.load() == 2) ::kill(g_slots[i].pid, sig);
  }
  for (const Kind kind : {Kind::file, Kind::tree}) {  // a directory empties first
    for (int i = 0; i < kPaths; ++i) {
      if (g_slots[i].state.load() != 2 || g_slots[i].kind != kind) continue;
      if (kind == Kind::file) {
        ::unlink(g_slots[i].path);
      } else {
        remove_at(AT_FDCWD, g_slots[i].path, 0);
      }
    }
  }
  // A parent may sit in an earlier slot than its child: again while one went (each removal at
  // most once).
  for (bool removed = true; removed;) {
    removed = false;
    for (int i = 0; i < kPaths; ++i) {
      if (g_slots[i].state.load() != 2 || g_slots[i].kind != Kind::dir) continue;
      removed = ::rmdir(g_slots[i].path) == 0 || removed;
    }
  }
}

extern "C" void dpc31_cleanup_on_signal(int sig) {
  const int saved = errno;
  if (::getpid() == g_owner.load()) remove_all(sig);
  errno = saved;
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  ::sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  ::raise(sig);  // delivered when the handler returns: the process ends by the signal
}

int take(int from, int to) {
  for (int i = from; i < to; ++i) {
    int expected = 0;
    if (g_slots[i].state.compare_exchange_strong(expected, 1)) return i;
  }
  return -1;
}

}  // namespace

void remove_registered() { remove_all(SIGTERM); }

void remove_at_exit() {
  static std::once_flag once;
  static pid_t owner = 0;
  std::call_once(once, [] {
    owner = ::getpid();
    std::atexit([] {
      if (::getpid() == owner) remove_all(SIGTERM);
    });
  });
}

namespace {

// Sets `handler` for each of the three signals, except one that is ignored (nohup's SIGHUP, the
// SIGINT of a shell's background job: the caller of the program asked for that) and, with
// `only_default`, one that already has a handler of the program's own.
void set_handlers(void (*handler)(int), bool only_default) {
  for (const int sig : kSignals) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN ||
        (only_default && old.sa_handler != SIG_DFL)) {
      continue;
    }
    struct sigaction sa {};
    sa.sa_handler = handler;
    ::sigfillset(&sa.sa_mask);  // one handler run at a time
    ::sigaction(sig, &sa, nullptr);
  }
}

}  // namespace

void install() {
  static std::once_flag once;
  std::call_once(once, [] {
    g_owner = ::getpid();
    set_handlers(dpc31_cleanup_on_signal, true);
  });
}

void stop_on_signals(void (*handler)(int)) { set_handlers(handler, false); }

Entry& Entry::operator=(Entry&& o) noexcept {
  if (this != &o) {
    release();
    slot_ = o.slot_;
    o.slot_ = -1;
  }
  return *this;
}

void Entry::release() {
  if (slot_ >= 0) g_slots[slot_].state.store(0);
  slot_ = -1;
}

namespace {

int add_path(const std::string& p, Kind kind) {
  if (p.size() >= PATH_MAX) return -1;
  const int i = take(0, kPaths);
  if (i < 0) return -1;
  std::memcpy(g_slots[i].path, p.c_str(), p.size() + 1);
  g_slots[i].kind = kind;
  g_slots[i].state.store(2);
  return i;
}

}  // namespace

Entry Entry::path(const std::string& p) { return Entry(add_path(p, Kind::file)); }
Entry Entry::dir(const std::string& p) { return Entry(add_path(p, Kind::dir)); }
Entry Entry::tree(const std::string& p) { return Entry(add_path(p, Kind::tree)); }

Entry Entry::child(pid_t pid) {
  const int i = take(kPaths, kPaths + kChildren);
  if (i < 0) return {};
  g_slots[i].pid = pid;
  g_slots[i].state.store(2);
  return Entry(i);
}

}  // namespace dpc31::cleanup
