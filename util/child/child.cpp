#include "child.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/signalfd.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>

#include "cleanup.hpp"

extern char** environ;

namespace dpc31::child {

namespace {

using Clock = std::chrono::steady_clock;

// The signals that end the process and that cleanup.hpp acts on, less those it ignores (SIGHUP
// under nohup: a held signal would be queued even though ignored).
sigset_t ending_signals() {
  sigset_t set;
  ::sigemptyset(&set);
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction now {};
    if (::sigaction(sig, nullptr, &now) == 0 && now.sa_handler != SIG_IGN) ::sigaddset(&set, sig);
  }
  return set;
}

// The ending signals blocked in this thread for a child's lifetime, readable from a signalfd:
// blocked before the fork, so that none is lost or acted on before the child's group exists.
class Held {
 public:
  Held() {
    const sigset_t set = ending_signals();
    ::pthread_sigmask(SIG_BLOCK, &set, &old_);
    fd_ = ::signalfd(-1, &set, SFD_CLOEXEC | SFD_NONBLOCK);
  }
  ~Held() {
    if (fd_ >= 0) ::close(fd_);
    ::pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  Held(const Held&) = delete;
  Held& operator=(const Held&) = delete;
  [[nodiscard]] int fd() const { return fd_; }
  // In the child, first thing after the fork: its own process group (so that a signal passed on
  // reaches what it starts too), the parent's signal mask, no signalfd, and SIGPIPE and SIGXFSZ
  // back to their defaults: the CLI ignores them for its own writes, and an ignored disposition
  // would pass through exec to the tools it runs (make, the compiler, Verilator), whose pipes
  // rely on SIGPIPE.
  void in_child() const {
    ::setpgid(0, 0);
    if (fd_ >= 0) ::close(fd_);
    ::signal(SIGPIPE, SIG_DFL);
    ::signal(SIGXFSZ, SIG_DFL);
    ::pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  // The signal read, or 0.
  [[nodiscard]] int take() const {
    struct signalfd_siginfo si {};
    return fd_ >= 0 && ::read(fd_, &si, sizeof si) == static_cast<ssize_t>(sizeof si)
               ? static_cast<int>(si.ssi_signo)
               : 0;
  }

 private:
  sigset_t old_{};
  int fd_ = -1;
};

// In the child: it dies with the parent (SIGKILL when the parent's thread that forked it ends),
// also if the parent died before this line ran. The parent waits for it on a signal, so this only
// acts when the parent was killed outright (SIGKILL, a crash).
void die_with(pid_t parent) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(127);
}

// The child's standard output on /dev/null, its standard error on `stderr_file` or /dev/null.
void redirect(const char* stderr_file) {
  const int null = ::open("/dev/null", O_WRONLY);
  const int err =
      stderr_file == nullptr ? null : ::open(stderr_file, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (null >= 0) ::dup2(null, 1);
  if (err >= 0) ::dup2(err, 2);
}

// Waits for the child `pid` (the leader of its own group). A held signal is passed on to the group
// once (`passed_on`), SIGKILL follows after kGraceSeconds; once the child has ended, whatever of
// its group is left is killed, so that nothing writes into files the parent removes next.
Result wait_for(pid_t pid, const Held& held, const std::string& what, int& passed_on) {
  // Also signalled by the cleanup handler if another thread of this process takes the signal.
  const cleanup::Entry registered = cleanup::Entry::child(-pid);
  // Readable when the child ends (Linux 5.3; glibc 2.36's <sys/pidfd.h> lacks extern "C", so the
  // system call itself); without it, 20 ms polls.
  const int pidfd = static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));
  Result r;
  int status = 0;
  struct rusage ru {};
  Clock::time_point kill_at = Clock::time_point::max();
  for (;;) {
    const pid_t got = ::wait4(pid, &status, WNOHANG, &ru);
    if (got == pid) break;
    if (got < 0 && errno != EINTR) {
      r.error = what + "wait4 failed";
      if (pidfd >= 0) ::close(pidfd);
      return r;
    }
    int timeout_ms = pidfd >= 0 ? -1 : 20;
    if (kill_at != Clock::time_point::max()) {
      const auto left = std::chrono::ceil<std::chrono::milliseconds>(kill_at - Clock::now());
      const int left_ms = static_cast<int>(std::max<std::int64_t>(0, left.count()));
      timeout_ms = timeout_ms < 0 ? left_ms : std::min(timeout_ms, left_ms);
    }
    struct pollfd fds[2] = {{held.fd(), POLLIN, 0}, {pidfd, POLLIN, 0}};
    ::poll(fds, 2, timeout_ms);
    if (const int sig = held.take(); sig != 0 && passed_on == 0) {
      passed_on = sig;
      ::kill(-pid, sig);
      kill_at = Clock::now() + std::chrono::seconds(kGraceSeconds);
    }
    if (Clock::now() >= kill_at) {
      ::kill(-pid, SIGKILL);
      kill_at = Clock::time_point::max();
    }
  }
  if (pidfd >= 0) ::close(pidfd);
  if (passed_on != 0) {
    // What the child started and left running (a compiler under a killed make): ended too, and
    // waited for (at most a second: a zombie of a parent that does not reap stays in the group).
    ::kill(-pid, SIGKILL);
    for (int i = 0; i < 100 && ::kill(-pid, 0) == 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  r.maxrss_kib = ru.ru_maxrss;
  if (WIFEXITED(status)) {
    r.exit_code = WEXITSTATUS(status);
  } else {
    r.error = what + "ended by signal " + std::to_string(WTERMSIG(status));
  }
  return r;
}

// Forks; the child runs `in_child` (which must not return), the parent waits for it. A signal
// passed on during the wait is raised again in this process once the child is gone.
Result start(const std::function<void()>& in_child, const std::string& what) {
  int passed_on = 0;
  Result r;
  {
    const Held held;
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid < 0) {
      r.error = what + "fork: " + std::strerror(errno);
      return r;
    }
    if (pid == 0) {
      held.in_child();
      die_with(parent);
      in_child();
      ::_exit(127);
    }
    ::setpgid(pid, pid);  // also here: the group exists before the first signal is passed on
    r = wait_for(pid, held, what, passed_on);
  }
  if (passed_on != 0) ::raise(passed_on);  // the cleanup handler, and the end, come now
  return r;
}

}  // namespace

Result run(const std::vector<std::string>& argv, const std::string& stderr_file) {
  Result r;
  if (argv.empty()) {
    r.error = "no program";
    return r;
  }
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  if (::access(args[0], X_OK) != 0) {
    r.error = argv[0] + ": " + std::strerror(errno);
    return r;
  }
  const char* err_file = stderr_file.empty() ? nullptr : stderr_file.c_str();
  return start(
      [&] {
        redirect(err_file);
        ::execve(args[0], args.data(), environ);
        ::_exit(127);  // as a shell does
      },
      argv[0] + ": ");
}

Result call(const std::function<int()>& fn) {
  std::fflush(nullptr);  // nothing buffered is written twice
  return start(
      [&] {
        redirect(nullptr);
        int rc = 1;
        try {
          rc = fn();
        } catch (...) {
          rc = 1;
        }
        ::_exit(rc);
      },
      "");
}

void stop_point(std::string_view name) {
  const char* at = std::getenv("DPC31_STOP_AT");
  if (at == nullptr || name != at) return;
  std::fprintf(stderr, "%s: stopped at %.*s\n", program_invocation_short_name,
               static_cast<int>(name.size()), name.data());
  std::fflush(stderr);
  ::raise(SIGSTOP);
}

}  // namespace dpc31::child
