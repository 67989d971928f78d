// The WaveDrom excerpt of wavediff --wavedrom: a second pass that keeps the last N points before
// the first divergence and N after.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine.hpp"

namespace dpc31::wavediff::detail {

namespace {

struct DromSample {
  std::string label;
  std::vector<std::string> a;
  std::vector<std::string> b;
  std::vector<bool> differs;
};

std::string drom_label(const std::string& v, bool real) {
  if (real) return v;
  const std::string hex = v.size() <= 4 ? std::string() : bits_hex(v);
  return hex.empty() ? v : "0x" + hex;
}

nlohmann::ordered_json drom_row(const std::string& name, const std::vector<std::string>& values,
                                bool real, std::uint32_t width) {
  std::string wave;
  nlohmann::ordered_json data = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string& v = values[i];
    if (i > 0 && v == values[i - 1]) {
      wave += '.';
      continue;
    }
    if (!real && width == 1 && v.size() == 1) {
      wave += v[0];
    } else if (!real && v.find_first_not_of('x') == std::string::npos) {
      wave += 'x';
    } else if (!real && v.find_first_not_of('z') == std::string::npos) {
      wave += 'z';
    } else {
      wave += '=';
      data.push_back(drom_label(v, real));
    }
  }
  return {{"name", name}, {"wave", wave}, {"data", data}};
}

}  // namespace

std::string wavedrom_text(const Options& o, const Report& rep) {
  Engine e(o);
  Report scratch;
  e.setup(scratch);
  std::vector<std::uint32_t> sel;
  std::unordered_map<std::string, std::uint32_t> by_name;
  for (std::uint32_t i = 0; i < e.pairs.size(); ++i) by_name.emplace(e.pairs[i].name, i);
  for (const SignalDiff& d : rep.diffs) {
    if (sel.size() >= 8) break;
    if (auto it = by_name.find(d.name); it != by_name.end()) sel.push_back(it->second);
  }
  const SignalDiff& first = rep.diffs.front();
  const std::uint64_t key = rep.clock_mode ? first.first.at.cycle : first.first.at.time;
  const std::size_t w = o.wavedrom_window;
  std::deque<DromSample> ring;
  bool found = false;
  std::size_t after = 0;
  e.run([&](Engine& en, const Point& pt, bool) {
    DromSample s;
    s.label = rep.clock_mode ? std::to_string(pt.cycle) : time_text(pt.time, en.pow);
    for (const std::uint32_t pi : sel) {
      const Pair& p = en.pairs[pi];
      s.a.push_back(en.A.text(en.A.sigs[p.a]));
      s.b.push_back(en.B.text(en.B.sigs[p.b]));
      s.differs.push_back(p.differs);
    }
    ring.push_back(std::move(s));
    const std::uint64_t k = rep.clock_mode ? pt.cycle : pt.time;
    if (!found) {
      if (k >= key) {
        found = true;
      } else if (ring.size() > w) {
        ring.pop_front();
      }
      return true;
    }
    return ++after < w;
  });
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  std::vector<std::string> labels;
  for (const auto& s : ring) labels.push_back(s.label);
  {
    nlohmann::ordered_json data = labels;
    rows.push_back({{"name", rep.clock_mode ? "cycle" : "time"},
                    {"wave", std::string(labels.size(), '=')},
                    {"data", data}});
  }
  for (std::size_t k = 0; k < sel.size(); ++k) {
    const Pair& p = e.pairs[sel[k]];
    std::vector<std::string> va;
    std::vector<std::string> vb;
    std::vector<std::string> vd;
    for (const auto& s : ring) {
      va.push_back(s.a[k]);
      vb.push_back(s.b[k]);
      vd.emplace_back(s.differs[k] ? "1" : "0");
    }
    rows.push_back(drom_row(p.name + " (a)", va, p.real, e.A.sigs[p.a].width));
    rows.push_back(drom_row(p.name + " (b)", vb, p.real, e.B.sigs[p.b].width));
    rows.push_back(drom_row(p.name + " (diff)", vd, false, 1));
  }
  const std::string when = rep.clock_mode ? fmt::format("cycle {}", first.first.at.cycle)
                                          : time_text(first.first.at.time, rep.pow);
  nlohmann::ordered_json j = {
      {"signal", rows},
      {"head", {{"text", fmt::format("first divergence: {} at {}", first.name, when)}}},
      {"foot", {{"text", fmt::format("a: {}  b: {}", o.file_a, o.file_b)}}}};
  return j.dump(2) + '\n';
}

}  // namespace dpc31::wavediff::detail
