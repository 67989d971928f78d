#include "board.hpp"

#include <sys/uio.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <string>
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

void guard_hangs(const std::string& program, const std::string& firmware, const std::string& remove,
                 std::chrono::milliseconds limit) {
  static std::atomic<bool> started{false};
  if (started.exchange(true)) return;
  // The line is made here but for the spinning firmware's name and its place, which were made
  // before it ran: the watcher flushes stdout, writev(2)s them and _exits, allocating nothing and
  // touching nothing the spinning thread might hold.
  const std::string head = program + ": ";
  const std::string fallback = "firmware " + firmware;
  const std::string tail = " hangs: it ran " + std::to_string(limit.count()) +
                           " ms of host time without a bus access or a board hook call (a "
                           "while(1) loop, e.g. its fatal-error handler?); stopped\n";
  std::thread([head, fallback, tail, remove, limit] {
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
        if (!remove.empty()) ::unlink(remove.c_str());
        cleanup::remove_registered();  // the temporaries of output files: nothing half-written
        // The walk printed so far is kept (docs/bring-up.md tells the user to read it); stdout's
        // lock is only tried, so a firmware that spins inside a stdio call cannot block the exit.
        if (::ftrylockfile(stdout) == 0) {
          std::fflush(stdout);
          ::funlockfile(stdout);
        }
        const Hooks* const h = g_running.load(std::memory_order_acquire);
        const std::string& who = h != nullptr ? h->hang_name() : fallback;
        const std::string* const at = g_place.load(std::memory_order_acquire);
        const bool placed = at != nullptr && !at->empty();
        static const char kSep[] = ": ";
        std::array<iovec, 5> parts{
            {{const_cast<char*>(head.data()), head.size()},
             {placed ? const_cast<char*>(at->data()) : nullptr, placed ? at->size() : 0},
             {const_cast<char*>(kSep), placed ? sizeof kSep - 1 : 0},
             {const_cast<char*>(who.data()), who.size()},
             {const_cast<char*>(tail.data()), tail.size()}}};
        [[maybe_unused]] const ssize_t n = ::writev(2, parts.data(), parts.size());
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
