// Reports (text and JSON), time and bound parsing, and the command's exit codes.
#include <fmt/format.h>

#include <charconv>
#include <nlohmann/json.hpp>
#include <tuple>

#include "outfile.hpp"
#include "textfile.hpp"
#include "wavediff.hpp"

namespace dpc31::wavediff {

namespace {

__extension__ typedef unsigned __int128 U128;  // exact time arithmetic

struct Unit {
  const char* name;
  int pow;
};
constexpr Unit kUnits[] = {{"s", 15}, {"ms", 12}, {"us", 9}, {"ns", 6}, {"ps", 3}, {"fs", 0}};

std::string u128(U128 v) {
  if (v == 0) return "0";
  std::string s;
  while (v != 0) {
    s += static_cast<char>('0' + static_cast<int>(v % 10));
    v /= 10;
  }
  return {s.rbegin(), s.rend()};
}

std::string with_hex(const std::string& v) {
  const std::string hex = v.size() < 8 ? std::string() : bits_hex(v);
  return hex.empty() ? v : v + " (0x" + hex + ")";
}

std::string where(const Report& r, const Point& p) {
  if (r.clock_mode) {
    return fmt::format("cycle {} (A {}, #{}; B {}, #{})", p.cycle, time_text(p.time, r.pow),
                       p.own_a, time_text(p.time_b, r.pow), p.own_b);
  }
  return fmt::format("{} (A #{}, B #{})", time_text(p.time, r.pow),
                     file_time(p.time, r.pow, r.pow_a), file_time(p.time, r.pow, r.pow_b));
}

std::string short_where(const Report& r, const Point& p) {
  return r.clock_mode ? fmt::format("cycle {}", p.cycle) : time_text(p.time, r.pow);
}

std::string values(const Divergence& d) {
  std::string s = fmt::format("A={} B={}", with_hex(d.a), with_hex(d.b));
  s += d.last_common ? fmt::format(", last common {}", with_hex(*d.last_common))
                     : std::string(", no common value before");
  if (d.open) s += ", still different at the end";
  return s;
}

nlohmann::ordered_json point_json(const Report& r, const Point& p) {
  nlohmann::ordered_json j = {{"time", p.time}, {"time_text", time_text(p.time, r.pow)}};
  if (r.clock_mode) {  // each edge's own time in its file
    j["time_a"] = std::to_string(p.own_a);
    j["cycle"] = p.cycle;
    j["time_b"] = std::to_string(p.own_b);
    j["time_b_text"] = time_text(p.time_b, r.pow);
  } else {
    j["time_a"] = file_time(p.time, r.pow, r.pow_a);
    j["time_b"] = file_time(p.time, r.pow, r.pow_b);
  }
  return j;
}

nlohmann::ordered_json div_json(const Report& r, const std::string& name, const std::string& name_b,
                                const Divergence& d) {
  nlohmann::ordered_json j = point_json(r, d.at);
  j["signal"] = name;
  j["signal_b"] = name_b;
  j["a"] = d.a;
  j["b"] = d.b;
  j["last_common"] =
      d.last_common ? nlohmann::ordered_json(*d.last_common) : nlohmann::ordered_json(nullptr);
  j["open"] = d.open;
  return j;
}

}  // namespace

std::string time_text(std::uint64_t t, int pow) {
  for (const Unit& u : kUnits) {
    if (pow >= u.pow) {
      U128 v = t;
      for (int i = u.pow; i < pow; ++i) v *= 10;
      return u128(v) + u.name;
    }
  }
  return fmt::format("{}e{}fs", t, pow);
}

std::string file_time(std::uint64_t t, int pow, int file_pow) {
  // The finer file: the common time in its units (its own times were rounded to the common unit).
  if (pow > file_pow) return t == 0 ? "0" : std::to_string(t) + std::string(pow - file_pow, '0');
  std::uint64_t r = 1;
  for (int i = pow; i < file_pow; ++i) r *= 10;
  std::string s = std::to_string(t / r);
  std::uint64_t frac = t % r;
  if (frac != 0) {
    std::string f = std::to_string(frac);
    f = std::string(std::to_string(r).size() - 1 - f.size(), '0') + f;
    while (!f.empty() && f.back() == '0') f.pop_back();
    s += "." + f;
  }
  return s;
}

bool parse_duration(std::string_view text, std::uint64_t& fs, std::string& error) {
  if (text == "0") {
    fs = 0;
    return true;
  }
  std::size_t i = 0;
  while (i < text.size() && ((text[i] >= '0' && text[i] <= '9') || text[i] == '.')) ++i;
  const std::string_view num = text.substr(0, i);
  const std::string_view unit = text.substr(i);
  const Unit* u = nullptr;
  for (const Unit& x : kUnits) {
    if (unit == x.name) u = &x;
  }
  const auto dot = num.find('.');
  const std::string_view ip = num.substr(0, dot);
  const std::string_view fp =
      dot == std::string_view::npos ? std::string_view() : num.substr(dot + 1);
  if (u == nullptr || ip.empty() || (dot != std::string_view::npos && fp.empty()) ||
      fp.find('.') != std::string_view::npos) {
    error = fmt::format("'{}' is not a time (a number and s, ms, us, ns, ps or fs; e.g. 100ns)",
                        shown(text));
    return false;
  }
  if (static_cast<int>(fp.size()) > u->pow &&
      fp.find_first_not_of('0', static_cast<std::size_t>(u->pow)) != std::string_view::npos) {
    error = fmt::format("'{}' is finer than 1 fs", shown(text));
    return false;
  }
  U128 v = 0;
  for (char c : ip) v = v * 10 + static_cast<unsigned>(c - '0');
  for (int k = 0; k < u->pow; ++k) v *= 10;
  U128 f = 0;
  for (int k = 0; k < u->pow; ++k) {
    f = f * 10 + (static_cast<std::size_t>(k) < fp.size()
                      ? static_cast<unsigned>(fp[static_cast<std::size_t>(k)] - '0')
                      : 0);
  }
  v += f;
  if (v > UINT64_MAX || ip.size() > 30) {
    error = fmt::format("'{}' is too large (at most about 18000 s)", shown(text));
    return false;
  }
  fs = static_cast<std::uint64_t>(v);
  return true;
}

std::string take_window(std::string_view start, std::string_view end, std::string_view tolerance,
                        Options& o) {
  std::string why;
  for (const auto& [name, text, bound] :
       {std::tuple{"start", start, &o.start}, std::tuple{"end", end, &o.end}}) {
    if (text.empty()) continue;
    Bound b;
    if (!parse_bound(text, b, why)) return fmt::format("--{}: {}", name, why);
    *bound = b;
  }
  if (o.start && o.end && o.start->cycles == o.end->cycles && o.start->value > o.end->value)
    return "--start is after --end";
  if (!tolerance.empty() && !parse_duration(tolerance, o.tolerance_fs, why))
    return "--tolerance: " + why;
  return "";
}

bool parse_bound(std::string_view text, Bound& out, std::string& error) {
  if (!text.empty() && (text[0] == 'c' || text[0] == 'C')) {
    std::uint64_t n = 0;
    const char* b = text.data() + 1;
    const char* e = text.data() + text.size();
    auto r = std::from_chars(b, e, n);
    if (b == e || r.ec != std::errc() || r.ptr != e) {
      error = fmt::format("'{}' is not a cycle number (c123)", shown(text));
      return false;
    }
    out = {true, n};
    return true;
  }
  out.cycles = false;
  return parse_duration(text, out.value, error);
}

std::string text_report(const Report& r, unsigned max_signals) {
  std::string s;
  s += fmt::format("wavediff: A {} ({}, {})  B {} ({}, {})\n", r.file_a, r.format_a,
                   timescale_text(r.pow_a), r.file_b, r.format_b, timescale_text(r.pow_b));
  if (r.clock_mode) {
    s += fmt::format(
        "mode: clock-sampled on {} edges of A {} and B {}; cycle = edge index from 0; "
        "{} edges compared\n",
        edge_name(r.edge), r.clock_a, r.clock_b, r.edges);
  } else {
    s += fmt::format("mode: event (every time either side changes); times in {}\n",
                     timescale_text(r.pow));
  }
  s += fmt::format("compared {} signal{}: {} differ, {} only in A, {} only in B{}\n", r.compared,
                   r.compared == 1 ? "" : "s", r.diffs.size(), r.only_a.size(), r.only_b.size(),
                   r.ignore_missing ? " (ignored)" : "");
  auto list = [&](const char* title, const std::vector<std::string>& v) {
    if (v.empty()) return;
    s += fmt::format("{} ({}):", title, v.size());
    for (std::size_t i = 0; i < v.size() && i < max_signals; ++i) s += " " + v[i];
    if (v.size() > max_signals) s += fmt::format(" ... ({} more)", v.size() - max_signals);
    s += "\n";
  };
  list("only in A", r.only_a);
  list("only in B", r.only_b);
  for (const auto& st : r.structural) s += fmt::format("structural: {}: {}\n", st.signal, st.what);
  if (!r.diffs.empty()) {
    const SignalDiff& f = r.diffs.front();
    s += fmt::format("first divergence: {} at {}: {}\n", f.name, where(r, f.first.at),
                     values(f.first));
    s += fmt::format("signals that differ ({}{}):\n", r.diffs.size(),
                     r.diffs.size() > max_signals ? fmt::format(", first {} shown", max_signals)
                                                  : std::string());
    for (std::size_t i = 0; i < r.diffs.size() && i < max_signals; ++i) {
      const SignalDiff& d = r.diffs[i];
      s += fmt::format("  {}{}: {} divergence{}, first at {}, last at {}; first: {}\n", d.name,
                       d.name_b != d.name ? fmt::format(" (B {})", d.name_b) : std::string(),
                       d.count, d.count == 1 ? "" : "s", short_where(r, d.first.at),
                       short_where(r, d.last), values(d.first));
    }
  }
  s += fmt::format("result: {}\n", r.same() ? "same" : "different");
  return s;
}

std::string json_report(const Report& r) {
  nlohmann::ordered_json j;
  j["a"] = {{"file", r.file_a}, {"format", r.format_a}, {"timescale", timescale_text(r.pow_a)}};
  j["b"] = {{"file", r.file_b}, {"format", r.format_b}, {"timescale", timescale_text(r.pow_b)}};
  j["mode"] = r.clock_mode ? "clock" : "event";
  j["unit"] = timescale_text(r.pow);
  if (r.clock_mode) {
    j["clock"] = {
        {"a", r.clock_a}, {"b", r.clock_b}, {"edge", edge_name(r.edge)}, {"edges", r.edges}};
  }
  j["compared"] = r.compared;
  j["only_in_a"] = r.only_a;
  j["only_in_b"] = r.only_b;
  j["ignore_missing"] = r.ignore_missing;
  nlohmann::ordered_json st = nlohmann::ordered_json::array();
  for (const auto& x : r.structural) st.push_back({{"signal", x.signal}, {"what", x.what}});
  j["structural"] = st;
  nlohmann::ordered_json sig = nlohmann::ordered_json::array();
  for (const auto& d : r.diffs) {
    nlohmann::ordered_json e = {{"name", d.name}, {"name_b", d.name_b}, {"count", d.count}};
    e["first"] = div_json(r, d.name, d.name_b, d.first);
    e["last"] = point_json(r, d.last);
    sig.push_back(e);
  }
  j["first_divergence"] = r.diffs.empty() ? nlohmann::ordered_json(nullptr)
                                          : div_json(r, r.diffs.front().name,
                                                     r.diffs.front().name_b, r.diffs.front().first);
  j["signals"] = sig;
  j["warnings"] = r.warnings;
  j["result"] = r.same() ? "same" : "different";
  j["exit_code"] = r.same() ? 0 : 1;
  return j.dump(2) + "\n";
}

int run(const Options& o, std::string& out, std::string& err) {
  try {
    // Opened first, so that a bad path is found before the comparison; renamed into place only
    // with a complete report (on bad input there is none, docs/bad-input.md).
    outfile::OutFile json;
    if (!o.json_file.empty() && !json.open(o.json_file)) throw InputError(json.error());
    const Report r = compare(o);
    std::string warnings;
    for (const auto& w : r.warnings) warnings += w + "\n";
    if (!o.json_file.empty() && !(json.write(json_report(r)) && json.commit())) {
      throw InputError(json.error());
    }
    err += warnings;
    out += text_report(r, o.max_signals);
    return r.same() ? 0 : 1;
  } catch (const OptionError& e) {
    err += shown_line(fmt::format("dpc31 wavediff: {}", e.what())) + "\n";
    return 2;
  } catch (const InputError& e) {
    err += shown_line(e.what()) + "\n";  // one line whatever a name holds
    return 2;
  }
}

std::string vcd_id(std::size_t i) {
  std::string id;
  do {
    id += static_cast<char>('!' + i % 94);
    i /= 94;
  } while (i != 0);
  return id;
}

std::string bits_hex(std::string_view bits) {
  if (bits.empty() || bits.find_first_not_of("01") != std::string_view::npos) return {};
  std::string hex;
  const std::size_t lead = bits.size() % 4;
  for (std::size_t i = 0; i < bits.size();) {
    const std::size_t len = i == 0 && lead != 0 ? lead : 4;
    int x = 0;
    for (std::size_t k = 0; k < len; ++k) x = x * 2 + (bits[i + k] - '0');
    hex += "0123456789abcdef"[x];
    i += len;
  }
  return hex;
}

}  // namespace dpc31::wavediff
