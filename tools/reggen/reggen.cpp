// reggen: regs/dpc31_regs.json -> reg_ids.hpp, reg_fields.hpp, reg_tables.cpp, dpc31_regs.h,
// dpc31_regs.vh, registers.md. Every output is produced in memory first; a file is only replaced
// (temp file + rename) when its content changed, so a failed run leaves the old files and builds
// stay incremental. Exit codes: 0 ok, 1 I/O error, 2 bad input.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "outfile.hpp"
#include "regfmt.hpp"
#include "regjson.hpp"

namespace {

namespace fs = std::filesystem;

constexpr int kExitIo = 1;
constexpr int kExitBadInput = 2;

struct Output {
  fs::path path;  // relative to --out-dir
  std::string content;
};

class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

bool same_content(const fs::path& path, const std::string& content) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream old;
  old << in.rdbuf();
  return old.str() == content;
}

// Writes `content` to `path` through a temporary file in the same directory (dpc31::outfile);
// returns false when the file already held exactly that content (and was left untouched).
bool write_if_changed(const fs::path& path, const std::string& content) {
  if (same_content(path, content)) return false;
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec)
    throw IoError(fmt::format("{}: cannot create the directory: {}", path.parent_path().string(),
                              ec.message()));
  std::string error;
  if (!dpc31::outfile::write_file(path.string(), content, error)) throw IoError(error);
  return true;
}

std::vector<Output> generate(const dpc31::regjson::RegModel& model) {
  namespace rf = dpc31::regfmt;
  const auto profiles = model.profiles();
  return {
      {"include/dpc31/reg_ids.hpp", rf::emit_reg_ids(model.reg_names())},
      {"include/dpc31/reg_fields.hpp", rf::emit_reg_fields(profiles)},
      {"reg_tables.cpp", rf::emit_cpp_tables(profiles, model.timing(), model.reg_names())},
      {"include/dpc31/dpc31_regs.h", rf::emit_c_header(profiles)},
      {"dpc31_regs.vh", rf::emit_verilog(profiles)},
      {"registers.md", rf::emit_markdown(profiles)},
  };
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "reggen: generate the register tables, C header, Verilog include and register "
      "documentation from the register description"};
  std::string in_file;
  std::string out_dir;
  bool quiet = false;
  app.add_option("--in", in_file, "register description (regs/dpc31_regs.json)")->required();
  app.add_option("--out-dir", out_dir, "output directory")->required();
  app.add_flag("-q,--quiet", quiet, "print nothing on success");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    // One line and exit 2, as every bad input: CLI11's exit() adds a second line and returns
    // its own codes (106 for a missing option).
    std::string what = e.what();
    std::replace(what.begin(), what.end(), '\n', ' ');
    fmt::print(stderr, "reggen: {}\n", what);
    return kExitBadInput;
  }
  // A file where the directory goes is bad input, found before anything is generated.
  if (std::error_code ec; fs::exists(out_dir, ec) && !fs::is_directory(out_dir, ec)) {
    fmt::print(stderr, "reggen: --out-dir {}: not a directory\n", out_dir);
    return kExitBadInput;
  }

  std::vector<Output> outputs;
  try {
    const auto model = dpc31::regjson::RegModel::load(in_file);
    for (const auto& w : model->warnings()) fmt::print(stderr, "reggen: warning: {}\n", w);
    outputs = generate(*model);
  } catch (const dpc31::regjson::Error& e) {
    fmt::print(stderr, "{}\n", e.what());
    return kExitBadInput;
  } catch (const std::logic_error& e) {
    // An emitter refused the description (e.g. two registers producing the same macro name).
    fmt::print(stderr, "{}: {}\n", in_file, e.what());
    return kExitBadInput;
  }

  try {
    int changed = 0;
    for (const Output& o : outputs)
      changed += write_if_changed(fs::path(out_dir) / o.path, o.content) ? 1 : 0;
    if (!quiet) {
      fmt::print("reggen: {} of {} files in {} updated\n", changed, outputs.size(), out_dir);
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "reggen: {}\n", e.what());
    return kExitIo;
  }
  return 0;
}
