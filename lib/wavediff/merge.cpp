// wavediff --merge (docs/wavediff.md, "One file for a comparison"): the merged waveform of
// merge.hpp as VCD or FST, chosen by the name's extension, and a GTKWave save file beside it
// that shows each compared signal as a group: a.<name>, b.<name> and diff.<name>.
#include "merge.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "gtkw_view.hpp"
#include "gtkwave/fstapi.h"
#include "outfile.hpp"

namespace dpc31::wavediff {

std::string save_file_name(const std::string& merge) {
  const std::filesystem::path p(merge);
  return std::filesystem::path(p).replace_extension(".gtkw").string();
}

namespace detail {

namespace {

bool ends_with(const std::string& s, std::string_view end) {
  return s.size() >= end.size() && s.compare(s.size() - end.size(), end.size(), end) == 0;
}

class FstSink final : public WaveSink {
 public:
  FstSink(const std::string& path, int pow) {
    if (!out_.open(path)) throw InputError(out_.error());
    // fstapi opens the file by name (it unlinks it first): a regular file of ours.
    const std::string name = out_.library_path();
    if (name.empty()) throw InputError(out_.error());
    ctx_ = fstWriterCreate(name.c_str(), 1);
    if (ctx_ == nullptr) throw InputError(fmt::format("{}: cannot write", path));
    fstWriterSetTimescale(ctx_, pow - 15);
    fstWriterSetVersion(ctx_, "dpc31 wavediff");
  }
  ~FstSink() override {
    if (ctx_ != nullptr) fstWriterClose(ctx_);  // unfinished: out_ discards it
  }
  FstSink(const FstSink&) = delete;
  FstSink& operator=(const FstSink&) = delete;

  void scope(const std::string& name) override {
    fstWriterSetScope(ctx_, FST_ST_VCD_MODULE, name.c_str(), nullptr);
  }
  void upscope() override { fstWriterSetUpscope(ctx_); }
  void var(Kind kind, std::uint32_t width, const std::string& leaf) override {
    const fstVarType t = kind == Kind::integer ? FST_VT_VCD_INTEGER
                         : kind == Kind::real  ? FST_VT_VCD_REAL
                                               : FST_VT_VCD_WIRE;
    handles_.push_back(fstWriterCreateVar(ctx_, t, FST_VD_IMPLICIT, width, leaf.c_str(), 0));
    widths_.push_back(width);
  }
  void end_header() override {}
  void time(std::uint64_t t) override { fstWriterEmitTimeChange(ctx_, t); }
  void bits(std::size_t var, std::string_view bits) override {
    // fstapi takes exactly `width` characters.
    const std::size_t w = widths_[var];
    value_.assign(w > bits.size() ? w - bits.size() : 0, '0');
    value_ += bits.substr(bits.size() > w ? bits.size() - w : 0);
    fstWriterEmitValueChange(ctx_, handles_[var], value_.c_str());
  }
  void real(std::size_t var, double v) override {
    fstWriterEmitValueChange(ctx_, handles_[var], &v);
  }
  void end_point() override {}
  void commit() override {
    fstWriterClose(ctx_);
    ctx_ = nullptr;
    if (!out_.commit_fst()) throw InputError(out_.error());
  }

 private:
  outfile::OutFile out_;
  void* ctx_ = nullptr;
  std::vector<fstHandle> handles_;
  std::vector<std::uint32_t> widths_;
  std::string value_;
};

// The save file: GTKWave 3.3's format (what its File > Write Save File writes): the dump file,
// the view (gtkw_view.hpp), then traces with their display flags; a group is a blank trace with
// the group-begin flag (@800200) and one with the group-end flag (@1000200) around its members.
// Its head is written before the walk, the rest once the walk has given the first and last times.
std::string save_head(const std::string& dump) {
  std::error_code ec;
  const std::filesystem::path abs = std::filesystem::absolute(dump, ec);
  return fmt::format(
      "[*] dpc31 wavediff --merge: each compared signal as a group of a.NAME, b.NAME and "
      "diff.NAME (1 = they differ)\n[dumpfile] \"{}\"\n[savefile] \"{}\"\n",
      ec ? dump : abs.string(),
      ec ? save_file_name(dump) : std::filesystem::path(abs).replace_extension(".gtkw").string());
}

std::string save_traces(const Engine& e) {
  std::string s;
  std::vector<std::size_t> order(e.pairs.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&e](std::size_t x, std::size_t y) { return e.pairs[x].name < e.pairs[y].name; });
  if (e.clock_mode()) s += "@24\nwavediff.cycle[31:0]\n";
  for (const std::size_t i : order) {
    const Pair& p = e.pairs[i];
    s += fmt::format("@800200\n-{}\n", p.name);
    for (int side = 0; side < 2; ++side) {
      const std::string full = fmt::format("{}.{}", side == 0 ? "a" : "b", p.name);
      if (p.real) {
        s += fmt::format("@40020\n{}\n", full);  // TR_REAL | TR_RJUSTIFY
        continue;
      }
      const std::uint32_t w = (side == 0 ? e.A.sigs[p.a] : e.B.sigs[p.b]).width;
      // Vectors in hex, bits in binary (TR_HEX / TR_BIN, right-justified).
      s += w == 1 ? fmt::format("@28\n{}\n", full) : fmt::format("@22\n{}[{}:0]\n", full, w - 1);
    }
    s += fmt::format("@28\ndiff.{}\n@1000200\n-{}\n", p.name, p.name);
  }
  return s;
}

}  // namespace

std::unique_ptr<WaveSink> fst_sink(const std::string& path, int pow) {
  return std::make_unique<FstSink>(path, pow);
}

std::shared_ptr<MergedWave> open_merge(const std::string& path, Engine& e) {
  const bool fst = ends_with(path, ".fst");
  if (!fst && !ends_with(path, ".vcd")) {
    throw OptionError(fmt::format("--merge {}: the name must end in .vcd or .fst", path));
  }
  auto m = std::make_shared<MergedWave>(fst ? fst_sink(path, e.pow) : vcd_sink(path, e.pow), e);
  const std::string save = save_file_name(path);
  if (!m->save_file.open(save) || !m->save_file.write(save_head(path))) {
    throw InputError(m->save_file.error());
  }
  return m;
}

void merged_point(MergedWave& m, Engine& e, const Point& pt, bool full) { m.point(e, pt, full); }

void commit_merged(MergedWave& m, const Engine& e) {
  if (m.save_file.is_open() &&
      !m.save_file.write(gtkw::view_lines(m.first_time(), m.last_time(), e.pow, {}) +
                         save_traces(e))) {
    throw InputError(m.save_file.error());
  }
  m.commit();
}

}  // namespace detail
}  // namespace dpc31::wavediff
