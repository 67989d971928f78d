// What a process must not leave behind when SIGINT, SIGTERM or SIGHUP ends it
// (docs/bad-input.md): the temporaries of its output files, its scratch directories and its child
// processes. The handler (async-signal-safe: fixed slots, kill(), unlink(), rmdir() and the
// system calls of a directory walk) sends the same signal to every registered child, removes every
// registered path and tree, restores the default action and raises the signal again, so the
// process still ends by it.
#pragma once

#include <sys/types.h>

#include <string>

namespace dpc31::cleanup {

// Installs the handler for each of the three signals whose action is still the default (an
// ignored SIGHUP under nohup stays ignored; a handler of the program's own stays). Once; main()
// calls it first.
void install();

// Makes `handler` the action of each of the three signals that is not ignored, replacing
// install()'s: for a program that stops in order on them (`dpc31 serve`). An ignored one stays
// ignored, as install() leaves it (`nohup dpc31 serve ... &` survives its terminal's hangup).
void stop_on_signals(void (*handler)(int));

// Also at the process's exit (std::atexit), does what remove_registered does with what is still
// registered then: for a library in another program's process (the Python module), whose
// objects need not be destroyed before it exits. Once; a forked child's exit leaves them alone.
void remove_at_exit();

// Removes every registered path and signals (SIGTERM) every registered child now, from any
// thread, without ending the process: for a program that ends itself with _exit (the firmware
// hang guard, session/board.hpp).
void remove_registered();

// A registered path or child; release() (or the destructor) takes it off the list. A path too
// long for a slot, or a full list (64 of each), is not covered: the registration is then empty.
class Entry {
 public:
  Entry() = default;
  ~Entry() { release(); }
  Entry(Entry&& o) noexcept : slot_(o.slot_) { o.slot_ = -1; }
  Entry& operator=(Entry&& o) noexcept;
  Entry(const Entry&) = delete;
  Entry& operator=(const Entry&) = delete;
  void release();

  static Entry path(const std::string& p);  // unlink()ed
  static Entry dir(const std::string& p);   // rmdir()ed, after the paths
  // A private scratch directory, removed with everything in it (not following links; at most
  // 16 levels deep). Only for a directory this process made (mkdtemp) and nothing else writes
  // to once the process's children have ended (util/child waits for them).
  static Entry tree(const std::string& p);
  static Entry child(pid_t pid);  // signalled; a negative pid: that process group

 private:
  explicit Entry(int slot) : slot_(slot) {}
  int slot_ = -1;
};

}  // namespace dpc31::cleanup
