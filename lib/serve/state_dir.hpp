// The one directory `dpc31 serve`'s `save` and `load` may touch (--state-dir, docs/security.md):
// names relative to it, resolved component by component with openat() from the directory's file
// descriptor, never following a symbolic link, never leaving it ('..', absolute names), regular
// files only, nothing opened that could block (a FIFO). Errors name the file as the client gave
// it and say nothing about anything outside the directory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace dpc31::serve {

class StateDir {
 public:
  // How a refused or failed access is reported: `denied` for what the confinement refuses (the
  // name's form, a symlink, not a regular file), `failed` for what went wrong inside the
  // directory (no such file, I/O, a full disk, a file too large).
  struct Error {
    enum class Kind : std::uint8_t { denied, failed } kind;
    std::string message;  // one line, starting with the name as given
  };

  StateDir() = default;
  // Opens `dir` (it may be given through a symlink: the operator names it). Throws
  // std::runtime_error with a one-line message if it is not an accessible directory.
  explicit StateDir(const std::string& dir);
  ~StateDir();
  StateDir(StateDir&& o) noexcept;
  StateDir& operator=(StateDir&& o) noexcept;
  StateDir(const StateDir&) = delete;
  StateDir& operator=(const StateDir&) = delete;

  [[nodiscard]] bool is_open() const { return fd_ >= 0; }

  // What `save` may make the directory hold (docs/protocol.md, "Limits"): regular files in it and
  // its subdirectories (kMaxDepth deep), and their bytes (st_size), counted before every write;
  // a write beyond them fails with a message that names the limit. Replacing a file counts its
  // new size instead of the old one, not one more file.
  struct Quota {
    std::size_t files = 1024;
    std::uint64_t bytes = std::uint64_t{256} << 20;
  };
  static constexpr int kMaxDepth = 16;
  void set_quota(Quota q) { quota_ = q; }

  // Why `name` may not be used, "" if it may: empty, absolute, an empty component ("a//b", a
  // trailing '/'), a "." or ".." component, a component longer than 255 bytes.
  [[nodiscard]] static std::string check_name(std::string_view name);

  // The whole regular file `name`, at most `max` bytes. False with `error`.
  bool read(std::string_view name, std::size_t max, std::vector<std::uint8_t>& bytes,
            Error& error) const;
  // Replaces (or creates) the regular file `name` through a temporary and a rename inside the
  // directory of `name` (util/outfile, write_file_at). Subdirectories are not created. False with
  // `error`.
  bool write(std::string_view name, std::span<const std::uint8_t> bytes, Error& error) const;

 private:
  // The directory holding the last component of `name`, opened from fd_ without following
  // links (the caller closes it; it may be fd_ itself, then *owned is false), and that component.
  int parent_of(std::string_view name, std::string& leaf, bool& owned, Error& error) const;

  // Regular files and bytes under `dir` (not following links), stopping once both are known to
  // exceed the quota.
  void usage(int dir, int depth, std::size_t& files, std::uint64_t& bytes) const;

  int fd_ = -1;
  Quota quota_;
};

}  // namespace dpc31::serve
