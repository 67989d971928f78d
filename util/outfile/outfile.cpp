#include "outfile.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <utility>

#include "fst_chain.hpp"
#include "fst_hooks.h"
#include "textfile.hpp"

namespace dpc31::outfile {

namespace {

constexpr std::size_t kBufferBytes = 64 * 1024;

std::string errno_text(int e) { return std::error_code(e, std::generic_category()).message(); }

// The program this process runs: an input of every command, so never an output (`bridge --pcap
// build/bin/dpc31` renamed its capture over the program). By device and inode, as distinct().
bool is_running_program(const struct stat& st) {
  struct stat exe {};
  return S_ISREG(st.st_mode) && ::stat("/proc/self/exe", &exe) == 0 && exe.st_dev == st.st_dev &&
         exe.st_ino == st.st_ino;
}

std::string running_program() {
  std::array<char, 4096> buf{};
  const ssize_t n = ::readlink("/proc/self/exe", buf.data(), buf.size() - 1);
  return n > 0 ? std::string(buf.data(), static_cast<std::size_t>(n)) : "/proc/self/exe";
}

std::string running_program_refused(const std::string& path) {
  return fmt::format("{}: cannot write: is the running program {}", path, running_program());
}

// Whether rename() into `path` fails with ENAMETOOLONG: its last component longer than its
// directory's file system takes (NAME_MAX where it cannot be asked), or the whole over PATH_MAX.
bool name_too_long(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash + 1);
  const std::size_t name = slash == std::string::npos ? path.size() : path.size() - slash - 1;
  const long max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  return name > static_cast<std::size_t>(max > 0 ? max : NAME_MAX) || path.size() >= PATH_MAX;
}

}  // namespace

std::string create_temp(const std::string& path,
                        const std::function<int(const std::string&)>& create, std::string& error) {
  // "" would make ".PID.tmp" in the working directory and then fail to rename it over nothing.
  if (path.empty()) {
    error = kEmptyName;
    return {};
  }
  // A short name in the target's directory, whatever the target's: a name of 255 bytes, the
  // most a file system takes, stays possible. The pid keeps two processes apart; the counter two
  // temporaries of one process (or a leftover of a killed run with a recycled pid).
  const std::string dir = path.substr(0, path.rfind('/') + 1);
  for (int attempt = 0; attempt < 100; ++attempt) {
    const std::string tmp =
        attempt == 0 ? fmt::format("{}{}{}.tmp", dir, kTempPrefix, ::getpid())
                     : fmt::format("{}{}{}-{}.tmp", dir, kTempPrefix, ::getpid(), attempt);
    const int e = create(tmp);
    if (e == 0) return tmp;
    if (e != EEXIST) {
      error = fmt::format("{}: cannot create the temporary file {}: {}", path, tmp, errno_text(e));
      return {};
    }
  }
  error = fmt::format("{}: cannot create a temporary file: every name is taken", path);
  return {};
}

bool replace(const std::string& tmp, const std::string& path, std::string& error) {
  if (::rename(tmp.c_str(), path.c_str()) == 0) return true;
  error = fmt::format("{}: cannot rename the temporary file over it: {}", path, errno_text(errno));
  ::unlink(tmp.c_str());
  return false;
}

namespace {

// Walks `path` as the kernel resolves it: component by component, a link's target spliced in.
// `visit(dir, here, lst)` sees each symbolic link (`here`, in the resolved directory `dir`) before
// it is followed; a non-empty answer ends the walk with it.
template <typename Visit>
std::string walk_links(const std::string& path, Visit visit) {
  std::string done = path.starts_with('/') ? "" : ".";
  std::string rest = path;
  for (int links = 0; !rest.empty();) {
    const std::size_t slash = rest.find('/');
    const std::string name = rest.substr(0, slash);
    rest = slash == std::string::npos ? "" : rest.substr(slash + 1);
    if (name.empty() || name == ".") continue;
    const std::string dir = done.empty() ? "/" : done;
    const std::string here = done + "/" + name;
    struct stat lst {};
    if (::lstat(here.c_str(), &lst) != 0) return {};  // nothing further to follow
    if (!S_ISLNK(lst.st_mode)) {
      done = here;
      continue;
    }
    if (std::string verdict = visit(dir, here, lst); !verdict.empty()) return verdict;
    if (++links > 40) return {};  // a loop: open() reports it
    std::array<char, 4096> buf{};
    const ssize_t n = ::readlink(here.c_str(), buf.data(), buf.size());
    if (n <= 0) return {};
    const std::string target(buf.data(), static_cast<std::size_t>(n));
    if (target.starts_with('/')) done.clear();
    rest = rest.empty() ? target : target + "/" + rest;
  }
  return {};
}

}  // namespace

std::string foreign_symlink(const std::string& path) {
  return walk_links(
      path,
      [&path](const std::string& dir, const std::string& here,
              const struct stat& lst) -> std::string {
        struct stat dst {};
        if (::stat(dir.c_str(), &dst) == 0 && (dst.st_mode & S_ISVTX) != 0 &&
            (dst.st_mode & S_IWOTH) != 0 && lst.st_uid != ::geteuid() && lst.st_uid != dst.st_uid) {
          return fmt::format(
              "{}: cannot write: {} is a symbolic link of uid {} in the sticky directory {}, which "
              "belongs to neither you nor that directory's owner (not followed: protected "
              "symlinks)",
              path, here, lst.st_uid, dir);
        }
        return {};
      });
}

Descriptor descriptor_link(const std::string& path) {
  Descriptor d;
  const std::string self = std::to_string(::getpid());
  walk_links(
      path,
      [&](const std::string& dir, const std::string& here, const struct stat&) -> std::string {
        // /proc/PID/fd or /proc/PID/task/TID/fd (/dev/fd and /proc/self resolve to these).
        if (!dir.starts_with("/proc/") || !dir.ends_with("/fd")) return {};
        const std::string pid = dir.substr(6, dir.find('/', 6) - 6);
        const std::string n = here.substr(dir.size() + 1);
        d.link = true;
        if (pid == self && !n.empty() && n.size() < 10 &&
            n.find_first_not_of("0123456789") == std::string::npos) {
          d.own = std::stoi(n);
        }
        return "stop";
      });
  return d;
}

namespace {

// A target written in place (OutFile::open): our own descriptor through a duplicate, so that the
// shell's `>>` or `>` holds (its offset, O_APPEND); another process's regular file appended to,
// never truncated. -1 with errno.
int open_in_place(const std::string& path, const Descriptor& d, const struct stat& st) {
  if (d.own >= 0) {
    std::fflush(stdout);  // what the command printed so far comes first
    std::fflush(stderr);
    return ::fcntl(d.own, F_DUPFD_CLOEXEC, 0);
  }
  return ::open(path.c_str(), O_WRONLY | (S_ISREG(st.st_mode) ? O_APPEND : O_TRUNC) | O_CLOEXEC);
}

}  // namespace

std::FILE* open_live(const std::string& path) {
  struct stat st {};
  const Descriptor d = descriptor_link(path);
  const bool in_place = ::stat(path.c_str(), &st) == 0 && (!S_ISREG(st.st_mode) || d.link);
  const int fd = in_place ? open_in_place(path, d, st)
                          : ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) return nullptr;
  std::FILE* f = ::fdopen(fd, "w");
  if (f == nullptr) {
    const int e = errno;
    ::close(fd);
    errno = e;
  }
  return f;
}

OutFile::~OutFile() { discard(); }

bool OutFile::fail(std::string msg) {
  if (error_.empty()) error_ = shown_line(msg);  // one line whatever the name holds
  return false;
}

bool OutFile::open(const std::string& path) {
  discard();
  error_.clear();
  fst_failures_.reset();
  path_ = path;
  target_ = path;
  direct_ = false;
  int fd = -1;
  if (std::string foreign = foreign_symlink(path); !foreign.empty()) return fail(foreign);
  struct stat st {};
  struct stat lst {};
  if (::stat(path.c_str(), &st) != 0 && ::lstat(path.c_str(), &lst) == 0 && S_ISLNK(lst.st_mode)) {
    // Creating what a dangling link names would write wherever whoever made the link chose.
    return fail(fmt::format("{}: cannot write: a symbolic link to a missing file", path));
  }
  if (::stat(path.c_str(), &st) == 0) {
    // Found before any work is done, not at the rename after it.
    if (S_ISDIR(st.st_mode)) return fail(fmt::format("{}: cannot write: is a directory", path));
    if (is_running_program(st)) return fail(running_program_refused(path));
    const Descriptor d = descriptor_link(path);
    if (!S_ISREG(st.st_mode) || d.link) {
      // A device, a FIFO (/dev/null) or a descriptor (/dev/stdout, /dev/fd/N, /proc/self/fd/N,
      // whatever its stream is): there is no file of ours to replace, and renaming over it would
      // put a plain file in its place, or replace the file the shell opened. Written in place.
      fd = open_in_place(path, d, st);
      if (fd < 0) return fail(fmt::format("{}: cannot write: {}", path, errno_text(errno)));
      direct_ = true;
      tmp_ = path;
    } else if (std::unique_ptr<char, decltype(&std::free)> real(::realpath(path.c_str(), nullptr),
                                                                &std::free);
               real) {
      target_ = real.get();  // a symlink stays a symlink: the file it names is replaced
    }
  }
  if (!direct_ && path.ends_with('/')) {
    // No such directory (else it was refused above): a file's name does not end in '/'.
    return fail(fmt::format("{}: cannot write: a file name cannot end in '/'", path));
  }
  // The temporary's name is short whatever the target's: a name its file system cannot hold
  // would be found only at the rename, after the work.
  if (!direct_ && name_too_long(target_)) {
    return fail(fmt::format("{}: cannot write: {}", path, errno_text(ENAMETOOLONG)));
  }
  if (!direct_) {
    std::string error;
    tmp_ = create_temp(
        target_,
        [&fd](const std::string& name) {
          fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
          return fd < 0 ? errno : 0;
        },
        error);
    if (tmp_.empty()) return fail(error);
    tmp_entry_ = cleanup::Entry::path(tmp_);
    // The replacement keeps the file's permission bits: a file made private stays private.
    if (S_ISREG(st.st_mode) && ::fchmod(fd, st.st_mode & 07777) != 0) {
      const int e = errno;
      ::close(fd);
      discard();
      return fail(fmt::format("{}: cannot write: {}", path, errno_text(e)));
    }
  }
  f_ = ::fdopen(fd, "wb");
  if (f_ == nullptr) {
    const int e = errno;
    ::close(fd);
    discard();
    return fail(fmt::format("{}: cannot write: {}", path, errno_text(e)));
  }
  // Large writes: waveforms and captures are written in many small pieces.
  // (glibc ignores the size without a buffer of our own.)
  if (!buf_) buf_ = std::make_unique<char[]>(kBufferBytes);
  std::setvbuf(f_, buf_.get(), _IOFBF, kBufferBytes);
  return true;
}

std::FILE* OutFile::stream() { return spool_ != nullptr ? spool_ : f_; }

bool OutFile::spool() {
  if (tmp_.empty()) return fail(fmt::format("{}: not open for writing", path_));
  if (!direct_ || spool_ != nullptr) return true;
  const std::string scratch = scratch_path();
  if (scratch.empty()) return false;
  spool_ = std::fopen(scratch.c_str(), "wbe");
  if (spool_ == nullptr) return fail(fmt::format("{}: cannot write: {}", path_, errno_text(errno)));
  return true;
}

std::string make_temp_dir(const std::string& prefix, std::string& error,
                          const std::string& parent) {
  // The variables std::filesystem::temp_directory_path reads, in its order; an empty one is
  // unset, as mktemp(1) and Python's tempfile take it (a CI job's exported empty TMPDIR).
  std::string tmp = parent;
  std::string where = parent;
  for (const char* name : {"TMPDIR", "TMP", "TEMP", "TEMPDIR"}) {
    if (const char* v = std::getenv(name); tmp.empty() && v != nullptr && *v != '\0') {
      tmp = v;
      where = fmt::format("{}={}", name, v);
    }
  }
  if (tmp.empty()) tmp = where = "/tmp";
  std::string dir = (std::filesystem::path(tmp) / (prefix + "XXXXXX")).string();
  if (::mkdtemp(dir.data()) != nullptr) return dir;
  error = fmt::format("cannot create a directory in {}: {}", where, errno_text(errno));
  return {};
}

MadeDirs::~MadeDirs() {
  for (auto d = dirs_.rbegin(); d != dirs_.rend(); ++d) ::rmdir(d->c_str());  // the empty ones
}

bool MadeDirs::make(const std::string& dir, std::error_code& ec) {
  ec.clear();
  std::filesystem::path prefix;
  for (const std::filesystem::path& part : std::filesystem::path(dir)) {
    prefix /= part;
    if (part.empty()) continue;  // the end of "d/"
    if (::mkdir(prefix.c_str(), 0777) == 0) {
      add(prefix.string());
    } else if (errno != EEXIST) {
      ec.assign(errno, std::generic_category());
      return false;
    }
  }
  if (std::filesystem::is_directory(dir, ec)) return true;
  if (!ec) ec = std::make_error_code(std::errc::not_a_directory);
  return false;
}

void MadeDirs::add(const std::string& dir) {
  dirs_.push_back(dir);
  entries_.push_back(cleanup::Entry::dir(dir));
}

void MadeDirs::keep() {
  dirs_.clear();
  entries_.clear();
}

std::string OutFile::library_path() {
  if (tmp_.empty()) {
    fail(fmt::format("{}: not open for writing", path_));
    return {};
  }
  // Before the library writes: commit_fst() compares (fst_hooks.h).
  if (!fst_failures_) fst_failures_ = dpc31_fst_failed_writes();
  if (!direct_) {
    if (scratch_entries_.empty()) scratch_entries_.push_back(cleanup::Entry::path(tmp_ + ".hier"));
    return tmp_;
  }
  return scratch_path();
}

std::string OutFile::scratch_path() {
  if (scratch_dir_.empty()) {
    std::string error;
    scratch_dir_ = make_temp_dir("dpc31-out-", error);
    if (scratch_dir_.empty()) {
      fail(fmt::format("{}: {}", path_, error));
      return {};
    }
    // Files first, then the directory (the handler removes in that order anyway).
    scratch_entries_.push_back(cleanup::Entry::path(scratch_dir_ + "/out"));
    scratch_entries_.push_back(cleanup::Entry::path(scratch_dir_ + "/out.hier"));
    scratch_entries_.push_back(cleanup::Entry::dir(scratch_dir_));
  }
  return scratch_dir_ + "/out";
}

bool OutFile::commit_fst(bool failed_elsewhere) {
  const std::string written = library_path();
  if (written.empty()) return false;
  // A write fstapi did not check failed (a scratch file in /tmp, the .hier next to the file): a
  // whole-looking file with wrong values, so the walk below cannot tell.
  if (failed_elsewhere || dpc31_fst_failed_writes() != *fst_failures_) {
    const int err = failed_elsewhere ? 0 : dpc31_fst_last_errno();
    discard();
    return fail(
        fmt::format("{}: cannot write: a write of the FST writer failed ({}): is the file "
                    "system full?",
                    path_, err != 0 ? errno_text(err) : "its scratch files"));
  }
  const std::string problem = fst_chain::incomplete(written);
  if (problem.empty()) {
    // The library wrote a file of its own under the name (commit() syncs only the one open()
    // made): synced here before the rename.
    const int fd = ::open(written.c_str(), O_RDONLY | O_CLOEXEC);
    const bool synced = fd >= 0 && ::fsync(fd) == 0;
    if (fd >= 0) ::close(fd);
    if (!synced) {
      fail(fmt::format("{}: cannot write: {}", path_, errno_text(errno)));
      discard();
      return false;
    }
    return commit();
  }
  discard();
  return fail(
      fmt::format("{}: cannot write: the FST writer left an incomplete file ({}): is the "
                  "file system full?",
                  path_, problem));
}

bool OutFile::write(std::string_view bytes) {
  if (f_ == nullptr) return fail(fmt::format("{}: not open for writing", path_));
  if (std::fwrite(bytes.data(), 1, bytes.size(), stream()) != bytes.size()) {
    return fail(fmt::format("{}: cannot write: {}", path_, errno_text(errno)));
  }
  return true;
}

bool OutFile::commit() {
  if (tmp_.empty()) return fail(fmt::format("{}: not open for writing", path_));
  // /dev/stdout: what the command printed before comes first, also before a scratch file's bytes
  // (more than the stream's buffer go to the descriptor at once).
  if (direct_) std::fflush(stdout);
  if (spool_ != nullptr) {
    if (std::fflush(spool_) != 0 || std::ferror(spool_) != 0)
      fail(fmt::format("{}: cannot write: {}", path_, errno_text(errno)));
    if (std::fclose(std::exchange(spool_, nullptr)) != 0)
      fail(fmt::format("{}: cannot write: {}", path_, errno_text(errno)));
  }
  if (!scratch_dir_.empty() && error_.empty()) {
    // A device or FIFO target: what the library (or spool()) wrote to the scratch file goes into
    // it now.
    std::FILE* in = std::fopen((scratch_dir_ + "/out").c_str(), "rb");
    if (in == nullptr)
      fail(fmt::format("{}: cannot read the scratch file: {}", path_, errno_text(errno)));
    char buf[64 * 1024];
    for (std::size_t n = 0; in != nullptr && (n = std::fread(buf, 1, sizeof buf, in)) > 0;) {
      if (!write(std::string_view(buf, n))) break;
    }
    if (in != nullptr) std::fclose(in);
  }
  // Errors of stdio surface at the flush; an fsync before the rename so that a crash leaves the
  // old file or the new one, never an empty one.
  if (std::fflush(f_) != 0 || std::ferror(f_) != 0) {
    fail(fmt::format("{}: cannot write: {}", path_, errno_text(errno)));
  } else if (!direct_ && ::fsync(::fileno(f_)) != 0) {
    fail(fmt::format("{}: cannot write: {}", path_, errno_text(errno)));
  }
  const int rc = std::fclose(f_);
  f_ = nullptr;
  if (rc != 0) fail(fmt::format("{}: cannot write: {}", path_, errno_text(errno)));
  if (direct_) {
    discard();  // the scratch directory
    return error_.empty();
  }
  std::string error;
  if (error_.empty() && !replace(tmp_, target_, error)) fail(error);
  if (!error_.empty()) {
    discard();
    return false;
  }
  tmp_.clear();
  discard();  // the registrations
  return true;
}

void OutFile::discard() {
  if (spool_ != nullptr) std::fclose(std::exchange(spool_, nullptr));
  if (f_ != nullptr) {
    std::fclose(f_);
    f_ = nullptr;
  }
  if (!tmp_.empty()) {
    if (!direct_) {  // a device is not ours to remove
      ::unlink(tmp_.c_str());
      ::unlink((tmp_ + ".hier").c_str());  // fstapi's, if a library wrote it
    }
    tmp_.clear();
  }
  if (!scratch_dir_.empty()) {
    ::unlink((scratch_dir_ + "/out").c_str());
    ::unlink((scratch_dir_ + "/out.hier").c_str());
    ::rmdir(scratch_dir_.c_str());
    scratch_dir_.clear();
  }
  tmp_entry_.release();
  scratch_entries_.clear();
}

bool write_file(const std::string& path, std::string_view bytes, std::string& error) {
  OutFile f;
  if (f.open(path) && f.write(bytes) && f.commit()) return true;
  error = f.error();
  return false;
}

std::string distinct(const std::vector<Named>& inputs, const std::vector<Named>& outputs) {
  struct Id {
    bool exists = false;
    bool special = false;  // a device or a FIFO
    bool descriptor = false;
    dev_t dev = 0;
    ino_t ino = 0;
    std::string abs;
  };
  const auto id_of = [](const std::string& p) {
    Id id;
    struct stat st {};
    if (::stat(p.c_str(), &st) == 0) {
      id.exists = true;
      id.special = !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
      // /dev/stdout to a file: written in place, so outputs may share it as a device; it is
      // still compared with the inputs.
      id.descriptor = descriptor_link(p).link;
      id.dev = st.st_dev;
      id.ino = st.st_ino;
    }
    std::error_code ec;
    id.abs = std::filesystem::weakly_canonical(std::filesystem::absolute(p, ec), ec).string();
    if (ec) id.abs = p;
    return id;
  };
  const auto same = [](const Id& a, const Id& b) {
    if (a.exists && b.exists) return a.dev == b.dev && a.ino == b.ino;
    return a.abs == b.abs;
  };
  std::vector<Named> all_inputs = inputs;
  all_inputs.push_back({"the running program", running_program()});
  std::vector<Id> out_ids;
  for (const Named& o : outputs) out_ids.push_back(o.path.empty() ? Id{} : id_of(o.path));
  // The file the shell redirected the standard output to: renamed over, what the command prints
  // there would go with the old file (/dev/stdout writes into it instead: a descriptor).
  struct stat out1 {};
  const bool stdout_file = ::fstat(STDOUT_FILENO, &out1) == 0 && S_ISREG(out1.st_mode);
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    if (outputs[k].path.empty() || out_ids[k].special) continue;
    if (stdout_file && out_ids[k].exists && !out_ids[k].descriptor &&
        out_ids[k].dev == out1.st_dev && out_ids[k].ino == out1.st_ino) {
      return shown_line(fmt::format(
          "{} {}: is the file the standard output goes to: what is printed there would be lost{}",
          outputs[k].what, outputs[k].path,
          outputs[k].stdout_may_stand_in ? " (name /dev/stdout to write into it)" : ""));
    }
    for (const Named& in : all_inputs) {
      if (!in.path.empty() && same(out_ids[k], id_of(in.path))) {
        return shown_line(fmt::format("{} {}: is {} {}: an output must not replace an input",
                                      outputs[k].what, outputs[k].path, in.what, in.path));
      }
    }
    for (std::size_t j = 0; j < k; ++j) {
      if (!outputs[j].path.empty() && !out_ids[k].descriptor && !out_ids[j].descriptor &&
          same(out_ids[k], out_ids[j])) {
        return shown_line(
            fmt::format("{} {} and {} {} are the same file: each output needs its own",
                        outputs[j].what, outputs[j].path, outputs[k].what, outputs[k].path));
      }
    }
  }
  return {};
}

bool write_file_at(int dirfd, const std::string& name, std::string_view bytes,
                   const std::string& shown, std::string& error) {
  struct stat st {};
  const bool exists = ::fstatat(dirfd, name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0;
  if (exists && is_running_program(st)) {
    error = running_program_refused(shown);
    return false;
  }
  if (exists && !S_ISREG(st.st_mode)) {
    error = fmt::format("{}: cannot write: {}", shown,
                        S_ISLNK(st.st_mode)   ? "a symbolic link (not followed)"
                        : S_ISDIR(st.st_mode) ? "is a directory"
                                              : "not a regular file");
    return false;
  }
  int fd = -1;
  std::string create_error;
  const std::string tmp = create_temp(
      name,
      [&](const std::string& t) {
        fd = ::openat(dirfd, t.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
        return fd < 0 ? errno : 0;
      },
      create_error);
  if (tmp.empty()) {
    // create_temp names `name`; say it as the user did.
    error = shown + create_error.substr(name.size());
    return false;
  }
  const auto fail = [&](const char* what, int e) {
    error = fmt::format("{}: {}: {}", shown, what, errno_text(e));
    if (fd >= 0) ::close(fd);
    ::unlinkat(dirfd, tmp.c_str(), 0);
    return false;
  };
  // The replacement keeps the file's permission bits, as OutFile's does.
  if (exists && ::fchmod(fd, st.st_mode & 07777) != 0) return fail("cannot write", errno);
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return fail("cannot write", n < 0 ? errno : ENOSPC);
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) return fail("cannot write", errno);
  const int rc = ::close(fd);
  fd = -1;
  if (rc != 0) return fail("cannot write", errno);
  if (::renameat(dirfd, tmp.c_str(), dirfd, name.c_str()) != 0) {
    return fail("cannot rename the temporary file over it", errno);
  }
  return true;
}

}  // namespace dpc31::outfile
