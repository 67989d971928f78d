// The board hooks of dpc31/dpc31_firmware.h (reset line, interrupt input, Vpc3Wait_1ms) reach the
// host that runs the firmware on the calling thread (FirmwareHost), like the HAL's access
// functions reach the selected bus (hal.hpp). The host CPU (cpu.hpp) keeps the selection of each
// side when it switches between firmware and bus side.
//
// The hang guard: a firmware that spins without a bus access and without a hook call (a
// `while (1);` fatal-error loop) cannot be stopped from inside the process's one thread; a
// watcher thread notices that no progress was made for a while and ends the process with one line
// (docs/decisions.md).
#pragma once

#include <chrono>
#include <string>

namespace dpc31::board {

class Hooks {
 public:
  virtual void reset_line(bool asserted) = 0;
  virtual void int_enable(bool enabled) = 0;
  virtual void wait_1ms() = 0;
  // How the hang guard names the firmware ("firmware DO4", "station 5: firmware DO4"): read by the
  // guard's thread while the firmware spins, so it must not change while the firmware runs.
  [[nodiscard]] virtual const std::string& hang_name() const = 0;

 protected:
  ~Hooks() = default;
};

// Installs `h` for the calling thread and returns the one it replaces.
Hooks* exchange(Hooks* h);

// The firmware's code is running (from a host's call into it until it returns or yields).
void firmware_entered();
void firmware_left();
// It made progress: a bus access, an idle wait, a hook call.
void progress();

// How long firmware code may run without progress before the guard stops the process.
inline constexpr std::chrono::milliseconds kHangLimit{2000};

// Where the program called the firmware from, "x.scn:10: dpv1_read" (nullptr or empty: it says
// nothing): read by the guard's thread as Hooks::hang_name is, so the caller changes it only while
// no firmware code runs.
void set_hang_place(const std::string* place);

// set_hang_place(&place) for its life.
class HangPlace {
 public:
  explicit HangPlace(const std::string& place) { set_hang_place(&place); }
  ~HangPlace() { set_hang_place(nullptr); }
  HangPlace(const HangPlace&) = delete;
  HangPlace& operator=(const HangPlace&) = delete;
};

// Starts the watcher (once per process): when firmware code has run for `limit` of host time
// without progress, it removes `remove` (a file the program made, e.g. the bridge's symlink; empty:
// none), writes out what standard output holds (the walk up to the hang), prints "PROGRAM: PLACE:
// WHO hangs: ..." on stderr and exits with 2. PLACE is set_hang_place's (left out when none); WHO
// is the spinning firmware's Hooks::hang_name, or "firmware FIRMWARE" when no Hooks are installed.
// The line also goes to `log_fd` (a log file the program flushes line by line; -1: none).
// A fatal signal (SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT: a crash in the firmware's code, or in
// what it called) gets the same removal and line, "PROGRAM: PLACE: WHO crashed: SIGSEGV ...", from
// a handler on an alternate stack, which then raises the signal again with its default action:
// the process ends by it.
void guard_hangs(const std::string& program, const std::string& firmware,
                 const std::string& remove = {}, std::chrono::milliseconds limit = kHangLimit,
                 int log_fd = -1);

}  // namespace dpc31::board
