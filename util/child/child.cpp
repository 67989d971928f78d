#include "child.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "cleanup.hpp"

extern char** environ;

namespace dpc31::child {

namespace {

// In the child, first thing: it dies with the parent (SIGKILL when the parent's thread that
// forked it ends), also if the parent died before this line ran.
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

Result wait_for(pid_t pid, const std::string& what) {
  // Killed with the parent if a signal ends it (cleanup.hpp); the child's own PDEATHSIG covers
  // the parent dying any other way.
  const cleanup::Entry registered = cleanup::Entry::child(pid);
  Result r;
  int status = 0;
  struct rusage ru {};
  pid_t got = -1;
  do {
    got = ::wait4(pid, &status, 0, &ru);
  } while (got < 0 && errno == EINTR);
  if (got != pid) {
    r.error = what + "wait4 failed";
    return r;
  }
  r.maxrss_kib = ru.ru_maxrss;
  if (WIFEXITED(status)) {
    r.exit_code = WEXITSTATUS(status);
  } else {
    r.error = what + "ended by signal " + std::to_string(WTERMSIG(status));
  }
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
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    r.error = argv[0] + ": fork: " + std::strerror(errno);
    return r;
  }
  if (pid == 0) {
    die_with(parent);
    redirect(err_file);
    ::execve(args[0], args.data(), environ);
    ::_exit(127);  // as a shell does
  }
  return wait_for(pid, argv[0] + ": ");
}

Result call(const std::function<int()>& fn) {
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    Result r;
    r.error = std::string("fork: ") + std::strerror(errno);
    return r;
  }
  if (pid == 0) {
    die_with(parent);
    redirect(nullptr);
    int rc = 1;
    try {
      rc = fn();
    } catch (...) {
      rc = 1;
    }
    ::_exit(rc);
  }
  return wait_for(pid, "");
}

}  // namespace dpc31::child
