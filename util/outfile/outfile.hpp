// Output files that appear whole or not at all (docs/bad-input.md): the bytes go to a temporary
// file in the target's directory (so that rename() is atomic), and commit() renames it over the
// target. Anything else (an error, an exception, a bad input found later) discards it: the
// temporary is removed and an existing target is left as it was.
#pragma once

#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "cleanup.hpp"

namespace dpc31::outfile {

// Why an empty name is refused: OutFile's and every output option's words (path_option.hpp).
inline constexpr std::string_view kEmptyName = "an empty file name: nothing can be written there";
// The same for an input (path_option.hpp, Chip::load_state_file).
inline constexpr std::string_view kEmptyReadName = "an empty file name: nothing can be read there";

// How every temporary's name begins: a name space of our own, which `dpc31 serve` keeps its
// clients' snapshot names out of (lib/serve/state_dir.cpp), so they cannot take its names.
inline constexpr std::string_view kTempPrefix = ".dpc31-";

// A fresh temporary in `path`'s directory, made by `create(name)`, which returns 0 or an errno
// value; EEXIST tries the next name ("DIR/.dpc31-<pid>.tmp", "DIR/.dpc31-<pid>-1.tmp", ...): short
// whatever `path`'s name, so that a name of 255 bytes can be written. Returns its name,
// or "" with a one-line `error`. For temporaries that are not plain files (bridge's symlink).
std::string create_temp(const std::string& path,
                        const std::function<int(const std::string&)>& create, std::string& error);

// rename(tmp, path); on failure the temporary is removed and `error` says why.
bool replace(const std::string& tmp, const std::string& path, std::string& error);

// The kernel's protected_symlinks rule, applied whatever the machine's setting (sysctl
// fs.protected_symlinks): a symbolic link on the way to `path` (any component) is not followed
// when it sits in a sticky directory writable by others (/tmp) and belongs neither to us (the
// effective uid) nor to that directory's owner: another user may have put it there to make us
// write where they chose. "" or one line naming the link and its owner.
std::string foreign_symlink(const std::string& path);

// Whether `path` reaches a file through a process's descriptor (/dev/stdout, /dev/fd/N,
// /proc/self/fd/N, /proc/PID/fd/N: a link in a /proc/PID/fd directory on the way): `link`, and
// `own` the descriptor's number when it is one of this process's, else -1. Such a target is
// written in place, never replaced, whatever file the descriptor holds.
struct Descriptor {
  bool link = false;
  int own = -1;
};
Descriptor descriptor_link(const std::string& path);

// A file written as it goes (a live log that a user tails), not through a temporary: a target
// that OutFile::open writes in place is written in place the same way (/dev/stdout redirected
// with `>>` is appended to, not truncated); anything else is created or truncated. nullptr with
// errno.
std::FILE* open_live(const std::string& path);

// A new directory only this user can enter (mkdtemp, mode 0700) in `parent`, or without it in the
// temporary directory (TMPDIR, as std::filesystem::temp_directory_path finds it), named
// `prefix`XXXXXX: a fixed name there could be a link another user made. "" with a one-line
// `error` that names the place.
std::string make_temp_dir(const std::string& prefix, std::string& error,
                          const std::string& parent = {});

// The directories a run makes for its outputs (an --out-dir, a --dump DIR, the parents they
// lacked): each is removed again if it is still empty when SIGINT, SIGTERM or SIGHUP ends the
// process (cleanup::Entry::dir), or when this object goes without keep(). Only a directory this
// process's own mkdir() made is listed, never one that was there before.
class MadeDirs {
 public:
  MadeDirs() = default;
  ~MadeDirs();
  MadeDirs(const MadeDirs&) = delete;
  MadeDirs& operator=(const MadeDirs&) = delete;
  // `dir` and each missing parent, one mkdir() each; false with `ec` if `dir` is no directory
  // then (what was made stays listed).
  bool make(const std::string& dir, std::error_code& ec);
  void add(const std::string& dir);  // one made elsewhere (make_temp_dir)
  void keep();                       // the run's outputs are in place: nothing is removed

 private:
  std::vector<std::string> dirs_;  // a parent before its children
  std::vector<cleanup::Entry> entries_;
};

class OutFile {
 public:
  OutFile() = default;
  ~OutFile();  // not committed: discarded
  OutFile(const OutFile&) = delete;
  OutFile& operator=(const OutFile&) = delete;

  // Creates the temporary. False with error() if `path` is a directory, ends in '/', is the
  // running program (/proc/self/exe), a symbolic link to nothing, another user's link in a sticky
  // directory (foreign_symlink), or the temporary cannot be created; nothing is touched then. A
  // file still open is discarded first. A `path` that is not a regular file (a device, a FIFO:
  // /dev/null), or reaches one through a descriptor (descriptor_link: /dev/stdout redirected to a
  // file), is written in place, never removed or replaced; a symlink to a file is followed: the
  // link stays, the file it names is replaced. The temporary is removed if a signal ends the
  // process (cleanup.hpp).
  bool open(const std::string& path);
  // Buffered stream on the temporary (fmt::print, fwrite); nullptr when not open.
  std::FILE* stream();
  // For bytes written as the work goes that must still come after what the command prints (a
  // trace streamed during a run, `dpc31 run --record /dev/stdout`): a target written in place
  // gets them at commit(), from a scratch file (as library_path()'s) that write() and stream()
  // use from now on; a regular target's temporary is such a file already. False with error().
  bool spool();
  bool write(std::string_view bytes);
  // For a library that writes a file by name (fstapi, Verilator's FST tracer: they unlink the
  // name, create it again, seek in it and keep NAME.hier next to it while they write): a regular
  // file for it. The temporary for a regular target; for a device or a FIFO a scratch file in a
  // private directory (mkdtemp) of TMPDIR, which commit() copies into it. "" with error() if
  // that cannot be made.
  std::string library_path();
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] bool is_open() const { return !tmp_.empty(); }

  // Flushes, syncs and renames the temporary over the target, whose permission bits the new file
  // has (open() set them; another hard link to the old file keeps the old bytes). False with
  // error() if any write since open() failed or the rename fails; the temporary is then removed.
  bool commit();
  // commit() for what a library wrote to library_path() as FST: first checks that none of
  // fstapi's unchecked writes failed since library_path() (fst_hooks.h: its scratch files) and
  // that it left a whole file (fst_chain::incomplete), else discards it with a one-line error().
  // `failed_elsewhere`: the library wrote in a child process, which counted a failure there.
  bool commit_fst(bool failed_elsewhere = false);
  // Removes the temporary; the target stays as it was.
  void discard();

  // The first error, one line naming the target: "" if none.
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  bool fail(std::string msg);
  // The scratch file of a direct target, its private directory made first: "" with error().
  std::string scratch_path();
  std::string path_;    // as given, for messages
  std::string target_;  // what is replaced: the path, or the file a symlink names
  std::string tmp_;
  bool direct_ = false;         // a device, FIFO or descriptor, written in place
  std::string scratch_dir_;     // library_path() of a direct target: the private directory
  std::FILE* spool_ = nullptr;  // spool(): the scratch file, instead of f_
  std::optional<unsigned long> fst_failures_;  // dpc31_fst_failed_writes() at library_path()
  cleanup::Entry tmp_entry_;
  std::vector<cleanup::Entry> scratch_entries_;  // the scratch files, their .hier, the directory
  std::FILE* f_ = nullptr;
  std::unique_ptr<char[]> buf_;  // the stream's buffer, outlives f_
  std::string error_;
};

// The whole file at once through an OutFile. False with a one-line `error`.
bool write_file(const std::string& path, std::string_view bytes, std::string& error);

// A file a command names on its command line, for distinct(): the option ("--json") or the
// argument's role ("the scenario"), and the path. `stdout_may_stand_in`: the user named this
// one file and may name /dev/stdout instead (not a name derived from another: a segment's
// station trace, a file in cosim's directory; not a library call's argument).
struct Named {
  std::string what;
  std::string path;
  bool stdout_may_stand_in = true;
};

// Refuses, before any work, an output that is one of the inputs or another output (the same
// file by st_dev and st_ino when it exists, else the same absolute path once the directory part
// is resolved): "" or one line. The running program (/proc/self/exe) is always one of the inputs.
// Devices and FIFOs may be named several times, and so may a descriptor (/dev/stdout to a file)
// (--vcd /dev/null --fst /dev/null). Empty paths (options not given) are skipped.
std::string distinct(const std::vector<Named>& inputs, const std::vector<Named>& outputs);

// The whole file `name` (one component, no '/') in the directory open as `dirfd`, relative to it
// and without following symlinks: the temporary is made with openat(O_CREAT | O_EXCL |
// O_NOFOLLOW), written, fsync'ed and renameat()'ed over `name`. An existing `name` that is not a
// regular file (a symlink, a FIFO, a device, a directory), or is the running program, is refused
// and left alone. Messages name `shown` (the name as the user gave it), never the directory.
// False with a one-line `error`; the temporary is removed then. (`dpc31 serve`'s `save` in its
// --state-dir.)
bool write_file_at(int dirfd, const std::string& name, std::string_view bytes,
                   const std::string& shown, std::string& error);

}  // namespace dpc31::outfile
