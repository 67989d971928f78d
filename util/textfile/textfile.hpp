// Reading an input file whole, with a size bound and a one-line reason when it cannot be read;
// or line by line, holding one line (TextLines).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace dpc31 {

// `what` names the kind of file in messages ("scenario", "trace"). False with `error` set. A named
// FIFO, a device or a socket is refused unopened ("not a regular file, not a trace file"); a pipe
// (`<(...)`, `/dev/stdin` from `|`) is read.
bool read_text_file(const std::string& path, std::size_t max_bytes, std::string_view what,
                    std::string& text, std::string& error);
// The descriptor read_text_file reads (the caller closes it), or -1 with `error` set: a FIFO, a
// device or a socket refused unopened, a directory named. `pipe`: an anonymous pipe, which can be
// read only once and not at an offset.
int open_text_file(const std::string& path, std::string_view what, std::string& error, bool& pipe);
// The same from a descriptor the caller opened and closes (a FIFO opened a second time would wait
// for another writer).
bool read_text_fd(int fd, std::size_t max_bytes, std::string_view what, std::string& text,
                  std::string& error);

// A text file line by line from a descriptor that can be read at an offset (a regular file), in
// 64 KiB pieces (pread: readers of one descriptor do not move each other). A line's text up to
// its first `comment` byte is held, at most `max_text` bytes of it; the comment is passed over
// unheld, and the whole line may have at most `max_line` bytes. Memory: a piece and a line's
// text, whatever the file holds.
class TextLines {
 public:
  struct Line {
    std::string_view text;     // up to the comment byte; valid until next()
    std::uint64_t offset = 0;  // of the line's first byte in the file
    bool ended = false;        // by '\n'; false: the file's last line, cut off
    bool too_long = false;     // the line over max_line: `text` is empty
    bool long_text = false;    // the text over max_text: `text` is empty
    bool nul = false;          // a NUL byte in the line (with `inspect`)
    bool control = false;      // a control byte other than tab, CR, LF (or DEL) in it (`inspect`)
  };
  // `inspect`: look at each byte for `nul` and `control` (a first reading; one that reads the
  // file again after it need not).
  TextLines(int fd, std::uint64_t offset, std::size_t max_text, std::uint64_t max_line,
            char comment, bool inspect);
  // The next line; false at the end of the file, or when a read failed (failed()).
  bool next(Line& line);
  [[nodiscard]] bool failed() const { return failed_; }

 private:
  bool fill();
  int fd_;
  std::uint64_t at_;  // the file offset of piece_'s end
  std::size_t max_text_;
  std::uint64_t max_line_;
  char comment_;
  bool inspect_;
  std::vector<char> piece_;
  std::size_t pos_ = 0;
  std::size_t end_ = 0;
  std::string text_;  // a line's text that began in an earlier piece
  bool failed_ = false;
};

// A line-based file cut off mid-line may still parse ("end 10000" cut to "end 1000"); every
// editor and writer ends the last line, so a file without that newline is taken as cut off.
// 0 if `text` is empty or ends with '\n', else the number of its last line, with `error` set.
int cut_off_line(std::string_view text, std::string& error);

// cut_off_line for a file whose format ignores blank lines, read line by line. A binary file (a
// control byte other than tab, CR, LF in it) seldom ends in a newline: it is parsed with its
// cut line blank, and an error `parse` finds before that line is the file's (refused at its first
// line, not for a cut end); one without any newline is parsed whole. A text file cut off is the
// cut's error whatever else: a check of the whole file (a fault with no request after it, a missing
// 'end' line) may name an earlier line only because the last one was cut. `parse(text, message)`
// returns the line it failed at with `message` set, or 0. 0 if the last line is not cut.
template <typename Parse>
int cut_or_earlier_error(std::string_view text, std::string& error, Parse parse) {
  const int cut = cut_off_line(text, error);
  if (cut == 0) return 0;
  const bool binary = std::any_of(text.begin(), text.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return (u < 0x20 && c != '\t' && c != '\r' && c != '\n') || u == 0x7F;
  });
  if (!binary) return cut;
  // A file without a newline at all is one line, the first: its error is the file's, as a
  // garbage first line with one would be (not a cut: nothing before it was whole).
  const std::size_t kept = cut == 1 ? text.size() : text.rfind('\n') + 1;
  std::string earlier;
  const int at = parse(std::string(text.substr(0, kept)) + '\n', earlier);
  if (at <= 0 || at > cut || (at == cut && cut != 1)) return cut;
  error = std::move(earlier);
  return at;
}

// The reason a text file holding the byte `c` (a control byte: not tab, CR, LF) is refused, for
// FILE:LINE: "a NUL byte: not a text file", "a control byte \x1B: not a text file".
std::string not_text(unsigned char c);

// A token as it may appear in a one-line message: printable (other bytes as \xHH), at most
// `max_chars` characters and "..." (a name its reader bounds already: kWhole, never cut).
inline constexpr std::size_t kWhole = std::string_view::npos;
std::string shown(std::string_view s, std::size_t max_chars = 40);
// A message that names files, as one line: its control bytes (a newline, an ESC in a file's
// name) as \xHH, the rest as it is (a name in UTF-8 stays readable).
std::string shown_line(std::string_view line);

}  // namespace dpc31
