// Whether a file that will run as code in this process (a firmware plug-in, a user's RTL model,
// the RTL cache's entries) can have been put there or changed by another user (docs/security.md,
// "Code a command runs"). The kernel's own rules for the same question: protected_symlinks and
// the sticky bit.
#pragma once

#include <string>

namespace dpc31 {

// Why the file open as `fd` (named `shown` in messages) must not be trusted, or "": it must be a
// regular file owned by us (the effective uid) or root, writable by neither its group nor others,
// and so must every directory on its real path (from /proc/self/fd: the file the descriptor
// holds, whatever link or rename led there). A directory writable by others is taken only with
// the sticky bit (/tmp) and when the next name in it is ours or root's: others cannot rename or
// remove what is ours there. One line, e.g. "./fw.so is owned by uid 65534, not by you (uid 0)
// or root".
std::string untrusted_code(int fd, const std::string& shown);

// The same for the directory open as `fd` (the RTL cache's directories): the directory itself
// and every directory above it.
std::string untrusted_directory(int fd, const std::string& shown);

// The same for a scenario read from `fd`, which may name code to run: a regular file or a named
// FIFO (or a device) judged as untrusted_code judges a file; an anonymous pipe (no path:
// `run <(cat s.scn)`, `| run /dev/stdin`) is the piping user's own.
std::string untrusted_input(int fd, const std::string& shown);

}  // namespace dpc31
