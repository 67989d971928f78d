#include "board.hpp"

#include <signal.h>
#include <sys/uio.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <string_view>
#include <thread>

#include "cleanup.hpp"
#include "dpc31/dpc31_firmware.h"

namespace dpc31::board {

namespace {

thread_local Hooks* t_hooks = nullptr;

// Written by the one thread that runs firmware, read by the watcher: plain loads and stores
// (no read-modify-write), so an access costs no locked instruction.
std::atomic<std::uint64_t> g_progress{0};
std::atomic<int> g_depth{0};
// The Hooks installed on that thread: the guard names the firmware that spins.
std::atomic<const Hooks*> g_running{nullptr};
std::atomic<const std::string*> g_place{nullptr};

// A release store: what the thread wrote before entering the firmware (the walk in standard
// output's buffer, the place) is the watcher's to read once it sees the firmware running.
void bump(std::atomic<int>& a, int by) {
  a.store(a.load(std::memory_order_relaxed) + by, std::memory_order_release);
}

Hooks& hooks(const char* fn) {
  if (t_hooks == nullptr) {
    std::fprintf(stderr, "dpc31: %s called with no firmware host running the firmware\n", fn);
    std::abort();
  }
  progress();
  return *t_hooks;
}

}  // namespace

Hooks* exchange(Hooks* h) {
  Hooks* const prev = t_hooks;
  t_hooks = h;
  g_running.store(h, std::memory_order_release);
  return prev;
}

void set_hang_place(const std::string* place) { g_place.store(place, std::memory_order_release); }

void firmware_entered() { bump(g_depth, 1); }
void firmware_left() { bump(g_depth, -1); }

void progress() {
  g_progress.store(g_progress.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
}

namespace {

// The guard's words, made once before any firmware runs: the watcher thread and the fatal-signal
// handler only read them.
struct Guard {
  std::string head;      // "PROGRAM: "
  std::string fallback;  // "firmware FIRMWARE"
  std::string remove;    // unlinked on the way out ("": none)
  int log_fd = -1;       // the line goes here too (-1: only stderr)
  pid_t owner = 0;       // the process that set the guard (a forked child inherits the handler)
};
Guard g_guard;

// "PROGRAM: PLACE: WHO" and the tail's pieces on stderr and the log, by writev: no allocation,
// nothing locked, so also from a signal handler.
void write_fault_line(std::initializer_list<std::string_view> tail) {
  const Hooks* const h = g_running.load(std::memory_order_acquire);
  const std::string& who = h != nullptr ? h->hang_name() : g_guard.fallback;
  const std::string* const at = g_place.load(std::memory_order_acquire);
  const bool placed = at != nullptr && !at->empty();
  static const char kSep[] = ": ";
  std::array<iovec, 7> parts{
      {{const_cast<char*>(g_guard.head.data()), g_guard.head.size()},
       {placed ? const_cast<char*>(at->data()) : nullptr, placed ? at->size() : 0},
       {const_cast<char*>(kSep), placed ? sizeof kSep - 1 : 0},
       {const_cast<char*>(who.data()), who.size()}}};
  std::size_t n = 4;
  for (const std::string_view t : tail) parts[n++] = {const_cast<char*>(t.data()), t.size()};
  for (const int fd : {2, g_guard.log_fd}) {
    if (fd >= 0) [[maybe_unused]]
      const ssize_t w = ::writev(fd, parts.data(), static_cast<int>(n));
  }
}

void remove_files() {
  if (!g_guard.remove.empty()) ::unlink(g_guard.remove.c_str());
  cleanup::remove_registered();  // the temporaries of output files: nothing half-written
}

// The signals a crash raises, as the line names them.
struct Fatal {
  int sig;
  std::string_view name;
};
constexpr Fatal kFatal[] = {
    {SIGSEGV, "SIGSEGV (a bad pointer?)"},
    {SIGBUS, "SIGBUS (a bad pointer?)"},
    {SIGILL, "SIGILL (an illegal instruction)"},
    {SIGFPE, "SIGFPE (a division by zero?)"},
    {SIGABRT, "SIGABRT (abort(), a failed assert?)"},
};

// Async-signal-safe but for the walk's flush (tried, as the hang watcher does): writev, unlink,
// kill (cleanup), sigaction, raise. The default action then ends the process by the signal, so
// its exit status stays the signal's.
// A forked child (util/child: a traced RTL model may die of SIGBUS on a full disk by design) only
// dies: the parent's temporaries and line are the parent's.
extern "C" void dpc31_on_fatal_signal(int sig) {
  if (::getpid() == g_guard.owner) {
    remove_files();
    const bool in_firmware = g_depth.load(std::memory_order_acquire) != 0;
    for (const Fatal& f : kFatal) {
      if (f.sig == sig) {
        write_fault_line({" crashed: ", f.name,
                          in_firmware ? " while its code ran; stopped\n"
                                      : " outside its code (in the emulator: please report it); "
                                        "stopped\n"});
      }
    }
    // The walk printed so far is kept, as at a hang (stdout to a file or a pipe is buffered);
    // the lock is only tried: a firmware that crashed inside a stdio call cannot block the exit.
    if (::ftrylockfile(stdout) == 0) {
      std::fflush(stdout);
      ::funlockfile(stdout);
    }
  }
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  ::sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  ::raise(sig);
}

// On an alternate stack: a firmware that overflowed its stack still gets its line.
void catch_fatal_signals() {
  static std::array<char, 64 * 1024> alt;
  stack_t ss{};
  ss.ss_sp = alt.data();
  ss.ss_size = alt.size();
  if (::sigaltstack(&ss, nullptr) != 0) return;
  struct sigaction sa {};
  sa.sa_handler = dpc31_on_fatal_signal;
  sa.sa_flags = SA_ONSTACK;
  ::sigfillset(&sa.sa_mask);
  for (const Fatal& f : kFatal) ::sigaction(f.sig, &sa, nullptr);
}

}  // namespace

void guard_hangs(const std::string& program, const std::string& firmware, const std::string& remove,
                 std::chrono::milliseconds limit, int log_fd) {
  static std::atomic<bool> started{false};
  if (started.exchange(true)) return;
  // The line is made here but for the firmware's name and its place, which were made before it
  // ran: the watcher and the signal handler flush nothing they might find locked, writev(2) them
  // and end the process, allocating nothing.
  g_guard = {program + ": ", "firmware " + firmware, remove, log_fd, ::getpid()};
  catch_fatal_signals();
  const std::string tail = " hangs: it ran " + std::to_string(limit.count()) +
                           " ms of host time without a bus access or a board hook call (a "
                           "while(1) loop, e.g. its fatal-error handler?); stopped\n";
  std::thread([tail, limit] {
    const auto tick = std::chrono::milliseconds(50);
    std::uint64_t seen = g_progress.load(std::memory_order_relaxed);
    std::chrono::milliseconds still{0};
    for (;;) {
      std::this_thread::sleep_for(tick);
      const std::uint64_t now = g_progress.load(std::memory_order_relaxed);
      if (now != seen || g_depth.load(std::memory_order_acquire) == 0) {
        seen = now;
        still = std::chrono::milliseconds(0);
        continue;
      }
      still += tick;
      if (still >= limit) {
        // The other thread cannot be stopped where it spins: end the process from here.
        remove_files();
        // The walk printed so far is kept (docs/bring-up.md tells the user to read it); stdout's
        // lock is only tried, so a firmware that spins inside a stdio call cannot block the exit.
        if (::ftrylockfile(stdout) == 0) {
          std::fflush(stdout);
          ::funlockfile(stdout);
        }
        write_fault_line({tail});
        ::_exit(2);
      }
    }
  }).detach();
}

}  // namespace dpc31::board

using dpc31::board::hooks;

extern "C" {

void dpc31_board_reset(int asserted) { hooks("dpc31_board_reset").reset_line(asserted != 0); }
void dpc31_board_int_enable(int enabled) {
  hooks("dpc31_board_int_enable").int_enable(enabled != 0);
}
void dpc31_board_wait_1ms(void) { hooks("dpc31_board_wait_1ms").wait_1ms(); }

}  // extern "C"
