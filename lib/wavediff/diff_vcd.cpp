// The merged waveform of wavediff --diff-vcd and --merge (merge.hpp): scopes a/, b/ and diff/
// with every compared signal under its own hierarchy, written while the comparison walks both
// files; and its VCD sink.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "merge.hpp"
#include "outfile.hpp"

namespace dpc31::wavediff::detail {

namespace {

std::vector<std::string> split_dots(const std::string& n) {
  std::vector<std::string> parts;
  std::size_t b = 0;
  for (std::size_t i = 0; i <= n.size(); ++i) {
    if (i == n.size() || n[i] == '.') {
      parts.push_back(n.substr(b, i - b));
      b = i + 1;
    }
  }
  return parts;
}

class VcdSink final : public WaveSink {
 public:
  VcdSink(const std::string& path, int pow) {
    if (!out_.open(path)) throw InputError(out_.error());
    line_ = fmt::format("$version dpc31 wavediff $end\n$timescale {} $end\n", timescale_text(pow));
  }
  void scope(const std::string& name) override {
    line_ += fmt::format("$scope module {} $end\n", name);
  }
  void upscope() override { line_ += "$upscope $end\n"; }
  void var(Kind kind, std::uint32_t width, const std::string& leaf) override {
    ids_.push_back(vcd_id(ids_.size()));
    widths_.push_back(width);
    const std::string& id = ids_.back();
    if (kind == Kind::integer) {
      line_ += fmt::format("$var integer {} {} {} $end\n", width, id, leaf);
    } else if (kind == Kind::real) {
      line_ += fmt::format("$var real 64 {} {} $end\n", id, leaf);
    } else if (width == 1) {
      line_ += fmt::format("$var wire 1 {} {} $end\n", id, leaf);
    } else {
      line_ += fmt::format("$var wire {} {} {} [{}:0] $end\n", width, id, leaf, width - 1);
    }
  }
  void end_header() override {
    line_ += "$enddefinitions $end\n";
    end_point();
  }
  void time(std::uint64_t t) override { line_ += fmt::format("#{}\n", t); }
  void bits(std::size_t var, std::string_view bits) override {
    if (widths_[var] == 1) {
      line_ += bits;
    } else {
      line_ += 'b';
      line_ += bits;
      line_ += ' ';
    }
    line_ += ids_[var];
    line_ += '\n';
  }
  void real(std::size_t var, double v) override {
    line_ += std::isnan(v) ? std::string("rnan") : fmt::format("r{}", v);
    line_ += ' ';
    line_ += ids_[var];
    line_ += '\n';
  }
  void end_point() override {
    if (!out_.write(line_)) throw InputError(out_.error());
    line_.clear();
  }
  void commit() override {
    if (!out_.commit()) throw InputError(out_.error());
  }

 private:
  outfile::OutFile out_;
  std::vector<std::string> ids_;
  std::vector<std::uint32_t> widths_;
  std::string line_;
};

}  // namespace

std::unique_ptr<WaveSink> vcd_sink(const std::string& path, int pow) {
  return std::make_unique<VcdSink>(path, pow);
}

MergedWave::MergedWave(std::unique_ptr<WaveSink> sink, Engine& e) : sink_(std::move(sink)) {
  const std::size_t n = e.pairs.size();
  var_.resize(n * 3);
  flag_.assign(n, -1);
  std::vector<std::pair<std::vector<std::string>, std::size_t>> order;
  for (std::size_t i = 0; i < n; ++i) order.emplace_back(split_dots(e.pairs[i].name), i);
  std::sort(order.begin(), order.end());
  WaveSink& w = *sink_;
  std::size_t next = 0;
  if (e.clock_mode()) {
    w.scope("wavediff");
    w.var(WaveSink::Kind::integer, 32, "cycle");
    cycle_var_ = next++;
    w.upscope();
  }
  const char* tops[3] = {"a", "b", "diff"};
  for (int side = 0; side < 3; ++side) {
    w.scope(tops[side]);
    std::vector<std::string> stack;
    for (const auto& [parts, i] : order) {
      std::size_t common = 0;
      while (common < stack.size() && common + 1 < parts.size() && stack[common] == parts[common]) {
        ++common;
      }
      for (; stack.size() > common; stack.pop_back()) w.upscope();
      for (std::size_t k = common; k + 1 < parts.size(); ++k) {
        w.scope(parts[k]);
        stack.push_back(parts[k]);
      }
      const Pair& p = e.pairs[i];
      if (side == 2) {
        w.var(WaveSink::Kind::wire, 1, parts.back());
      } else if (p.real) {
        w.var(WaveSink::Kind::real, 64, parts.back());
      } else {
        const LSig& l = side == 0 ? e.A.sigs[p.a] : e.B.sigs[p.b];
        w.var(WaveSink::Kind::wire, l.width, parts.back());
      }
      var_[i * 3 + static_cast<std::size_t>(side)] = next++;
    }
    for (; !stack.empty(); stack.pop_back()) w.upscope();
    w.upscope();
  }
  w.end_header();
}

void MergedWave::point(Engine& e, const Point& pt, bool full) {
  WaveSink& w = *sink_;
  if (!written_) first_ = pt.time;
  written_ = true;
  last_ = pt.time;
  w.time(pt.time);
  if (e.clock_mode()) w.bits(cycle_var_, fmt::format("{:b}", pt.cycle));
  auto value = [&w](std::size_t var, const Side& side, const LSig& l) {
    if (l.real) {
      w.real(var, side.real(l));
    } else {
      w.bits(var, side.bits(l));
    }
  };
  auto emit = [&](std::uint32_t pi) {
    const Pair& p = e.pairs[pi];
    if (full || p.a_changed) value(var_[pi * 3], e.A, e.A.sigs[p.a]);
    if (full || p.b_changed) value(var_[pi * 3 + 1], e.B, e.B.sigs[p.b]);
    const int f = p.differs ? 1 : 0;
    if (full || f != flag_[pi]) {
      w.bits(var_[pi * 3 + 2], f != 0 ? "1" : "0");
      flag_[pi] = static_cast<signed char>(f);
    }
  };
  if (full) {
    for (std::uint32_t pi = 0; pi < e.pairs.size(); ++pi) emit(pi);
  } else {
    for (const std::uint32_t pi : e.dirty) emit(pi);
  }
  w.end_point();
}

void MergedWave::commit() {
  sink_->commit();
  if (save_file.is_open() && !save_file.commit()) throw InputError(save_file.error());
}

std::shared_ptr<MergedWave> open_diff_vcd(const std::string& path, Engine& e) {
  return std::make_shared<MergedWave>(vcd_sink(path, e.pow), e);
}

}  // namespace dpc31::wavediff::detail
