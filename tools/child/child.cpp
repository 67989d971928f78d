#include "child.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

extern char** environ;

namespace dpc31::child {

namespace {

Result wait_for(pid_t pid, const std::string& what) {
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
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, stderr_file.empty() ? "/dev/null" : stderr_file.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    r.error = argv[0] + ": " + std::strerror(rc);
    return r;
  }
  return wait_for(pid, argv[0] + ": ");
}

Result call(const std::function<int()>& fn) {
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = ::fork();
  if (pid < 0) {
    Result r;
    r.error = std::string("fork: ") + std::strerror(errno);
    return r;
  }
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) {
      ::dup2(null, 1);
      ::dup2(null, 2);
    }
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
