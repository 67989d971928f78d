// Segment scenarios: the parser and the runner (scenario_segment.hpp).
#include "scenario_segment.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <set>
#include <utility>

#include "dpc31/bus_port.hpp"
#include "dpc31/dp.hpp"
#include "firmware_host.hpp"
#include "responder.hpp"
#include "scenario_dpv1.hpp"
#include "scenario_lex.hpp"
#include "segment.hpp"
#include "textfile.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

namespace {

using namespace scenario_lex;  // NOLINT: the scenario's lexical helpers

// A single chip's command a segment does not have (docs/scenario-format.md "Segments"): refused
// as such, not as an unknown word. Its DPV1 is the gap docs/segment.md names.
bool single_chip_command(std::string_view c) {
  static constexpr std::array<std::string_view, 31> kOneChip = {"profile",
                                                                "variant",
                                                                "bus",
                                                                "hw",
                                                                "irq-controller",
                                                                "baud",
                                                                "slave",
                                                                "user",
                                                                "firmware",
                                                                "inputs",
                                                                "record",
                                                                "dpv1",
                                                                "exchange",
                                                                "gc",
                                                                "set_prm",
                                                                "chk_cfg",
                                                                "get_cfg",
                                                                "diag",
                                                                "fdl_status",
                                                                "read_inputs",
                                                                "read_outputs",
                                                                "set_slave_address",
                                                                "restart",
                                                                "reset",
                                                                "silence",
                                                                "foreign_master",
                                                                "corrupt",
                                                                "bad_fcs",
                                                                "request",
                                                                "read",
                                                                "write"};
  return std::find(kOneChip.begin(), kOneChip.end(), c) != kOneChip.end() ||
         std::find(scenario_dpv1::kActions.begin(), scenario_dpv1::kActions.end(), c) !=
             scenario_dpv1::kActions.end();
}

// The same for a single chip's `expect` kinds (`expect dpv1`, `expect answer`, ...).
bool single_chip_check(std::string_view what) {
  static constexpr std::array<std::string_view, 18> kOneChip = {
      "answer", "baud",       "cleared", "counter", "diag_byte", "dp_state",
      "dpv1",   "indication", "inputs",  "irq",     "irr_bit",   "outputs",
      "pb3",    "ram",        "read",    "reg",     "station",   "wd_state"};
  return std::find(kOneChip.begin(), kOneChip.end(), what) != kOneChip.end();
}

// Why `expect port` cannot name `name` of `fw` ("" when it can): the single chip's words.
std::string port_refused(const dpc31_firmware& fw, std::string_view name) {
  std::vector<const char*> ports;
  for (auto n = fw.ports; n && *n; ++n) ports.push_back(*n);
  ports.push_back(nullptr);
  if (name_index(ports.data(), name) >= 0) return "";
  return fmt::format("unknown port '{}' of {} ({})", shown(name), fw.name, name_list(ports.data()));
}

std::vector<std::string_view> words(std::string_view line) {
  const std::size_t hash = line.find('#');
  if (hash != std::string_view::npos) line = line.substr(0, hash);
  std::vector<std::string_view> out;
  for (std::string_view w : split(line, ' ')) {
    for (std::string_view x : split(w, '\t')) {
      if (!x.empty() && x != "\r") out.push_back(x.back() == '\r' ? x.substr(0, x.size() - 1) : x);
    }
  }
  return out;
}

class Parser {
 public:
  explicit Parser(SegmentScenario& s) : s_(s) {}

  void command(int line, const std::vector<std::string_view>& w) {
    line_ = line;
    opts_.clear();
    pos_.clear();
    taken_.clear();
    for (std::size_t k = 1; k < w.size(); ++k) {
      const std::size_t eq = w[k].find('=');
      if (eq == std::string_view::npos) {
        pos_.push_back(w[k]);
      } else if (!opts_.emplace(w[k].substr(0, eq), w[k].substr(eq + 1)).second) {
        fail(fmt::format("option '{}' given twice", w[k].substr(0, eq)));
      }
    }
    const std::string_view c = w[0];
    if (first_ && c != "segment") fail("a segment scenario begins with 'segment'");
    const bool first = std::exchange(first_, false);
    const bool header = c == "segment" || c == "station" || c == "master" || c == "sender";
    if (header && !s_.steps.empty()) fail(fmt::format("'{}' after the first action", c));
    if (c == "segment") {
      // A second one would silently replace the first's settings (docs/scenario-format.md).
      if (!first) fail(fmt::format("'segment' given twice: first at line {}", segment_line_));
      segment_line_ = line;
      segment();
    } else if (c == "station") {
      station();
    } else if (c == "master") {
      master();
    } else if (c == "sender") {
      const std::string_view name = positional(0, "a sender's name");
      if (std::string why = station_name_refused(name, "a sender"); !why.empty()) fail(why);
      s_.senders.emplace_back(new_station_name(std::string(name)));
    } else {
      step(line, c);
    }
    no_words_left(c);
    for (const auto& [k, v] : opts_) fail(fmt::format("unknown option '{}' for {}", k, c));
  }

  // Checks that need the whole header: a master's slaves and a pass_token's master may be named
  // before the station or master line that makes them.
  void finish() {
    if (s_.stations.empty()) fail("a segment needs at least one station");
    if (s_.steps.empty()) fail("only header commands: nothing to run");
    if (s_.masters.empty()) {
      s_.masters.push_back({2, {}});
      for (std::size_t i = 0; i < s_.stations.size(); ++i) {
        if (s_.stations[i].slave.address == 2) {
          throw ParseFail{station_lines_[i],
                          station_at_master(2) + ", the default master: give a 'master' line"};
        }
      }
    }
    for (std::size_t i = 0; i < s_.masters.size(); ++i) {
      const std::vector<std::uint8_t>& slaves = s_.masters[i].slaves;
      for (auto it = slaves.begin(); it != slaves.end(); ++it) {
        if (!is_station(*it)) {
          throw ParseFail{master_lines_[i],
                          fmt::format("slaves={}: no station {}", master_slaves_[i], *it)};
        }
        if (std::find(slaves.begin(), it, *it) != it) {  // one FCB state per slave
          throw ParseFail{master_lines_[i],
                          fmt::format("slaves={}: station {} twice", master_slaves_[i], *it)};
        }
      }
    }
    for (const SegmentStep& st : s_.steps) {
      if (st.kind == SegmentStep::Kind::pass_token && find_master(st.address) == nullptr) {
        throw ParseFail{st.line,
                        fmt::format("pass_token from={}: no master of that address", st.address)};
      }
    }
    for (SegmentMaster& m : s_.masters) {
      if (m.slaves.empty()) {
        // Every address once: two stations on one address are polled as one (they collide).
        for (const SegmentStation& st : s_.stations) {
          if (std::find(m.slaves.begin(), m.slaves.end(), st.slave.address) == m.slaves.end())
            m.slaves.push_back(st.slave.address);
        }
      }
      if (!ttr_given_ && m.ttr_bits != 0) s_.ttr_bits = m.ttr_bits;
    }
  }

 private:
  std::string_view positional(std::size_t i, std::string_view what) {
    if (i >= pos_.size()) fail(fmt::format("missing {}", what));
    if (taken_.size() <= i) taken_.resize(i + 1);
    taken_[i] = what;
    return pos_[i];
  }

  // A word no command took is a mistyped option (`after_request 9`: the `=` missing), never
  // ignored: refused in the single chip's words, for every command at once.
  void no_words_left(std::string_view c) const {
    if (pos_.size() <= taken_.size()) return;
    const std::size_t first = c == "expect" ? 1 : 0;  // `expect KIND` names the command
    std::string takes;
    for (std::size_t i = first; i < taken_.size(); ++i) {
      if (i > first) takes += i + 1 == taken_.size() ? " and " : ", ";
      takes += taken_[i];
    }
    fail(fmt::format("'{}' takes {}; unexpected '{}'",
                     first == 0 ? std::string(c) : fmt::format("{} {}", c, pos_[0]),
                     takes.empty() ? "no arguments" : takes, shown(pos_[taken_.size()])));
  }

  std::optional<std::string_view> take(std::string_view key) {
    const auto it = opts_.find(key);
    if (it == opts_.end()) return std::nullopt;
    std::string_view v = it->second;
    opts_.erase(it);
    return v;
  }
  std::uint64_t bit_cycles_() const { return bit_cycles(clock_hz(), s_.baud); }
  static std::uint32_t clock_hz() { return Chip().clock_hz(); }
  std::uint64_t time(std::string_view v) const { return duration(v, clock_hz(), bit_cycles_()); }

  void segment() {
    if (auto v = take("baud")) s_.baud = profibus_baud(*v);
    if (auto v = take("slot")) s_.slot_bits = static_cast<std::uint32_t>(number(*v, kSlotBits));
    if (auto v = take("ttr")) s_.ttr_bits = number(*v, "ttr", 256, 16'777'215);
    ttr_given_ = s_.ttr_bits != 0;
  }

  void station() {
    SegmentStation st;
    st.slave.address =
        static_cast<std::uint8_t>(number(positional(0, "a station address"), kStationAddress));
    if (find_master(st.slave.address) != nullptr) fail(station_at_master(st.slave.address));
    st.name = fmt::format("station {}", st.slave.address);
    if (auto v = take("name")) {
      if (std::string why = station_name_refused(*v, st.name); !why.empty()) fail(why);
      st.name = std::string(*v);
    }
    if (auto v = take("profile")) {
      if (!parse_profile(*v, st.chip.profile)) fail(fmt::format("unknown profile '{}'", *v));
    }
    if (auto v = take("variant")) {
      Vpc3Variant var{};
      if (st.chip.profile != Profile::vpc3plus || !parse_vpc3_variant(*v, var)) {
        fail(fmt::format("variant '{}': b, c or s, on profile=vpc3plus only", *v));
      }
      st.chip.variant = var;
    }
    if (auto v = take("firmware")) {
      st.firmware = std::string(*v);
      if (is_plugin_path(st.firmware)) {
        // Never loaded while parsing: bind_segment_plugins() loads it before the run.
        st.firmware = beside_file(s_.file, st.firmware);
        st.plugin_line = line_;
      } else {
        try {
          st.slave = with_gsd_defaults(find_firmware(st.firmware), st.slave);
        } catch (const FirmwareError& e) {
          fail(e.what());
        }
      }
    }
    user_side(st);
    if (auto v = take("wd")) {
      const std::vector<std::string_view> f = split(*v, ',');
      if (f.size() != 2) fail(fmt::format("wd='{}': two factors, as in wd=10,10", *v));
      st.slave.wd_fact1 = static_cast<std::uint8_t>(number(f[0], kWdFactor1));
      st.slave.wd_fact2 = static_cast<std::uint8_t>(number(f[1], kWdFactor2));
    }
    // The single chip's `slave` options of the same names, with their checks.
    if (auto v = take("min_tsdr"))
      st.slave.min_tsdr = static_cast<std::uint8_t>(number(*v, kMinTsdr));
    if (auto v = take("wd_base")) {
      if (*v != "1ms" && *v != "10ms") fail(fmt::format("wd_base '{}': 1ms or 10ms", *v));
      st.slave.wd_base_1ms = *v == "1ms";
      const std::vector<std::uint8_t>& up = st.slave.user_prm;  // a firmware's GSD defaults
      if (st.chip.profile == Profile::vpc3plus &&
          (up.empty() || (up[0] & dpv1::status1::DPV1_Enable) == 0))
        fail(wd_base_needs_dpv1("wd_base="));
      if (!st.slave.wd_base_1ms && !up.empty() && (up[0] & dpv1::status1::WD_Base) != 0)
        fail(wd_base_contradicts_user_prm());
    }
    new_station_name(st.name);
    const std::string scope = station_scope(st.slave.address, st.name);
    for (const SegmentStation& o : s_.stations) {
      if (station_scope(o.slave.address, o.name) == scope)
        fail(second_station_in_scope(st.name, o.name, scope));
    }
    s_.stations.push_back(std::move(st));
    station_lines_.push_back(line_);
  }

  // The single chip's `user` options that a station of its own may want, with its checks: the
  // user watchdog served on every DX_Out, R_User_WD_Value (docs/timing.md: without the service
  // an SPC3 or VPC3+ leaves Data_Exchange at its 512th Data_Exchange).
  void user_side(SegmentStation& st) {
    const std::optional<std::string_view> serve = take("user_wd");
    const std::optional<std::string_view> value = take("user_wd_value");
    if (serve) st.user_watchdog = flag(*serve, "user_wd");
    if (value) st.user_wd_value = static_cast<std::uint16_t>(number(*value, kUserWdValue));
    if (!st.firmware.empty() && (serve || value))
      fail(refused_beside_firmware(serve ? "user_wd" : "user_wd_value"));
    if (value && st.chip.profile == Profile::dpc31 && !st.user_watchdog)
      fail(user_wd_value_needs_user_wd("user_wd_value="));
  }

  void master() {
    SegmentMaster m;
    m.address =
        static_cast<std::uint8_t>(number(positional(0, "a master address"), kMasterAddress));
    // A second master at an address is a second station named 'master ADDR' (Python's words).
    new_station_name(master_station_name(m.address));
    if (is_station(m.address)) fail(master_at_station(m.address));
    const std::optional<std::string_view> slaves = take("slaves");
    if (slaves) m.slaves = bytes_list(*slaves);
    master_lines_.push_back(line_);
    master_slaves_.push_back(slaves.value_or(""));
    // The token rules of DpMaster::use_token (vocabulary.hpp).
    if (auto v = take("ttr")) m.ttr_bits = number(*v, kTtrBits);
    if (auto v = take("gap")) m.gap_factor = static_cast<std::uint8_t>(number(*v, kGapFactor));
    if (auto v = take("hsa")) {
      m.hsa = static_cast<std::uint8_t>(number(*v, kHsa));
      if (const std::string e = hsa_refused(m.hsa, m.gap_factor, m.address); !e.empty()) fail(e);
    }
    m.obeys_token = m.ttr_bits != 0 || m.gap_factor != 0;
    // One TTR for the bus check: the segment line's, else the masters' (all the same).
    for (const SegmentMaster& o : s_.masters) {
      if (!ttr_given_ && m.ttr_bits != 0 && o.ttr_bits != 0 && o.ttr_bits != m.ttr_bits) {
        fail(
            fmt::format("ttr={} differs from master {}'s ttr={}: give the bus check's TTR on the "
                        "segment line (segment ttr=BITS)",
                        m.ttr_bits, o.address, o.ttr_bits));
      }
    }
    s_.masters.push_back(std::move(m));
  }

  // One name a station: the chips', the senders' and the masters' names apart.
  const std::string& new_station_name(const std::string& name) {
    if (!station_names_.insert(name).second) fail(second_station_named(name));
    return name;
  }

  const SegmentMaster* find_master(std::uint8_t a) const {
    for (const SegmentMaster& m : s_.masters) {
      if (m.address == a) return &m;
    }
    return nullptr;
  }

  static std::vector<std::uint8_t> bytes_list(std::string_view v) {
    std::vector<std::uint8_t> out;
    for (std::string_view a : split(v, ','))
      out.push_back(static_cast<std::uint8_t>(number(a, "address", 0, 125)));
    return out;
  }

  bool is_station(std::uint8_t a) const {
    return std::any_of(s_.stations.begin(), s_.stations.end(),
                       [a](const SegmentStation& s) { return s.slave.address == a; });
  }

  std::uint8_t station_address(std::string_view v) const {
    const auto a = static_cast<std::uint8_t>(number(v, "station", 0, 126));
    if (!is_station(a)) fail(fmt::format("no station {}", a));
    return a;
  }

  // The station an expect checks: a station's name= or an address that one station has. Two
  // chips may share an address (they collide): the address alone would pick one in silence.
  std::size_t checked_station(SegmentStep& st, std::string_view v) const {
    const auto named = std::find_if(s_.stations.begin(), s_.stations.end(),
                                    [v](const SegmentStation& s) { return s.name == v; });
    std::uint64_t a = 0;
    const bool address = parse_u64(v, a);
    if (named != s_.stations.end()) {
      if (address && a <= 126 && a != named->slave.address &&
          is_station(static_cast<std::uint8_t>(a)))
        fail(fmt::format("'{}' is the name of one station and the address of another", v));
      st.station = named->slave.address;
      return static_cast<std::size_t>(named - s_.stations.begin());
    }
    if (!address) fail(fmt::format("no station named '{}'", v));
    st.station = station_address(v);
    std::vector<std::size_t> at;
    for (std::size_t i = 0; i < s_.stations.size(); ++i) {
      if (s_.stations[i].slave.address == st.station) at.push_back(i);
    }
    if (at.size() > 1) {
      std::string names;
      for (const std::size_t i : at) {
        names += fmt::format("{}'{}' at line {}", names.empty() ? "" : ", ", s_.stations[i].name,
                             station_lines_[i]);
      }
      fail(fmt::format("station {} names {} stations ({}): give the name of the one to check",
                       st.station, at.size(), names));
    }
    return at.front();
  }

  void step(int line, std::string_view c) {
    using K = SegmentStep::Kind;
    SegmentStep st;
    st.line = line;
    if (c == "startup") {
      st.kind = K::startup;
    } else if (c == "cycle") {
      st.kind = K::cycle;
      st.count = number(positional(0, "the number of rotations"), "rotations", 1, 1'000'000);
      if (auto v = take("skip")) {
        st.skip = station_address(*v);
        // use_token polls every slave of the master in turn: it has no slave to leave out.
        for (const SegmentMaster& m : s_.masters) {
          if (m.obeys_token) {
            fail(
                fmt::format("cycle skip=: master {} obeys the token (ttr=, gap=) and polls all "
                            "its slaves",
                            m.address));
          }
        }
      }
    } else if (c == "run") {
      st.kind = K::run;
      st.time = time(positional(0, "a time"));
    } else if (c == "send") {
      st.kind = K::send;
      st.name = std::string(take("from").value_or(""));
      if (std::find(s_.senders.begin(), s_.senders.end(), st.name) == s_.senders.end()) {
        fail(fmt::format("send from='{}': no sender of that name", st.name));
      }
      st.time = time(take("after").value_or("33bits"));
      if (pos_.size() > 1) spaced_bytes("send", pos_[1]);
      st.bytes = bytes(positional(0, "the bytes"), "telegram", 255);
    } else if (c == "pass_token") {
      st.kind = K::pass_token;
      st.address = static_cast<std::uint8_t>(number(take("from").value_or(""), "from", 0, 126));
      st.station = static_cast<std::uint8_t>(number(take("to").value_or(""), "to", 0, 126));
    } else if (c == "expect") {
      expect(st, positional(0, "what to expect"));
    } else if (c == "cpu") {
      // A station is driven by its host's firmware; no door puts a CPU board on a segment.
      fail(fmt::format("'cpu' is a single chip's header: {}", kHexAtSegment));
    } else if (single_chip_command(c)) {
      fail(fmt::format("'{}' is a single chip's command: not on a segment", c));
    } else {
      fail(fmt::format("unknown command '{}'", c));
    }
    s_.steps.push_back(std::move(st));
  }

  void expect(SegmentStep& st, std::string_view what) {
    using K = SegmentStep::Kind;
    if (what == "state") {
      st.kind = K::expect_state;
      st.station_index = checked_station(st, positional(1, "a station"));
      const std::string_view dp = positional(2, "a DP state");
      bool ok = false;
      for (const DpState d : {DpState::Wait_Prm, DpState::Wait_Cfg, DpState::Data_Exchange}) {
        if (dp_state_name(d) == dp) {
          st.dp = d;
          ok = true;
        }
      }
      if (!ok) fail(fmt::format("unknown DP state '{}'", dp));
      if (auto v = take("wd")) {
        for (const WdState w : {WdState::Baud_Search, WdState::Baud_Control, WdState::DP_Control}) {
          if (wd_state_name(w) == *v) st.wd = w;
        }
        if (!st.wd) fail(fmt::format("unknown watchdog state '{}'", *v));
      }
      if (auto v = take("after_request"))
        st.after_request = number(*v, "after_request", 0, UINT32_MAX);
    } else if (what == "tsdr") {
      st.kind = K::expect_tsdr;
      st.count = number(positional(1, "the bit times"), "TSDR", 11, 255);
    } else if (what == "watchdog_expired") {
      st.kind = K::expect_expired;
      st.station_index = checked_station(st, positional(1, "a station"));
      st.time = time(take("twd").value_or(""));
    } else if (what == "bus_violation") {
      st.kind = K::expect_violation;
      if (!parse_bus_violation(positional(1, "a violation kind"), st.violation)) {
        fail(fmt::format("unknown bus violation '{}'", pos_[1]));
      }
      st.count = number(positional(2, "a count"), "count", 0, 1'000'000'000);
      // The header is complete here: the bus check's TTR is known (SegmentRun's BusTiming).
      const bool ttr =
          ttr_given_ || std::any_of(s_.masters.begin(), s_.masters.end(),
                                    [](const SegmentMaster& m) { return m.ttr_bits != 0; });
      if (st.violation == BusViolation::token_hold && (s_.masters.size() < 2 || !ttr)) {
        fail(
            "token_hold is checked on a line with two or more masters and a TTR (segment "
            "ttr=BITS or master ... ttr=BITS): without them it would always count 0");
      }
    } else if (what == "visit") {
      visit(st);
    } else if (what == "port") {
      port(st);
    } else if (what == "collisions") {
      st.kind = K::expect_collisions;
      st.count = number(positional(1, "a count"), "count", 0, 1'000'000'000);
    } else if (single_chip_check(what)) {
      fail(fmt::format("'expect {}' is a single chip's check: not on a segment", what));
    } else {
      fail(fmt::format("unknown expect '{}'", what));
    }
  }

  // `expect port STATION NAME VALUE`: the single chip's `expect port NAME VALUE` of a station's
  // firmware. A plug-in's port names are checked when bind_segment_plugins() loads it.
  void port(SegmentStep& st) {
    st.kind = SegmentStep::Kind::expect_port;
    st.station_index = checked_station(st, positional(1, "a station"));
    st.name = std::string(positional(2, "a port name"));
    st.count = number(positional(3, "a port value"), "port value", 0, 0xFFFF'FFFF);
    const SegmentStation* def = &s_.stations[st.station_index];
    if (def->firmware.empty()) {
      fail(fmt::format("'expect port' needs a firmware: station {} runs the built-in user side",
                       st.station));
    }
    if (def->plugin_line == 0) {
      if (const std::string why = port_refused(find_firmware(def->firmware), st.name); !why.empty())
        fail(why);
    }
  }

  // `expect visit ADDR polled=A,B|none startup=A,A,B|none rotation=BITS hold=BITS
  // gap=ADDR|none gap_answered=yes|no`
  void visit(SegmentStep& st) {
    st.kind = SegmentStep::Kind::expect_visit;
    st.address = static_cast<std::uint8_t>(number(positional(1, "a master"), "master", 0, 126));
    const SegmentMaster* m = find_master(st.address);
    if (m == nullptr) fail(fmt::format("no master {}", st.address));
    if (!m->obeys_token) {
      fail(fmt::format("master {} does not obey the token: give it ttr= or gap=", st.address));
    }
    SegmentStep::Visit& v = st.visit;
    const auto addresses = [](std::string_view list) {
      return list == "none" ? std::vector<std::uint8_t>() : bytes_list(list);
    };
    if (auto p = take("polled")) v.polled = addresses(*p);
    if (auto p = take("startup")) v.startup = addresses(*p);
    if (auto r = take("rotation")) v.rotation_bits = number(*r, "rotation", 0, UINT32_MAX);
    if (auto h = take("hold")) v.hold_bits = number(*h, "hold", 0, UINT32_MAX);
    if (auto g = take("gap")) {
      v.gap = *g == "none" ? std::optional<std::uint8_t>()
                           : std::optional<std::uint8_t>(
                                 static_cast<std::uint8_t>(number(*g, "gap address", 0, 126)));
    }
    if (auto a = take("gap_answered")) {
      if (*a != "yes" && *a != "no") fail(fmt::format("gap_answered='{}': yes or no", *a));
      v.gap_answered = *a == "yes";
    }
  }

  SegmentScenario& s_;
  bool first_ = true;
  int segment_line_ = 0;  // the `segment` line
  bool ttr_given_ = false;
  int line_ = 0;
  std::vector<int> station_lines_;               // each station's line, in s_.stations' order
  std::vector<int> master_lines_;                // each master's line, in s_.masters' order
  std::vector<std::string_view> master_slaves_;  // ... and its slaves= as written
  std::set<std::string> station_names_;          // the chips', senders' and masters' so far
  std::map<std::string_view, std::string_view> opts_;
  std::vector<std::string_view> pos_;
  std::vector<std::string_view> taken_;  // what each positional word the command took is
};

}  // namespace

bool is_segment_scenario(std::string_view text) {
  for (std::string_view line : split(without_bom(text), '\n')) {
    const std::vector<std::string_view> w = words(line);
    if (!w.empty()) return w[0] == "segment";
  }
  return false;
}

bool parse_segment_scenario(std::string_view text, const std::string& file, SegmentScenario& out,
                            ScenarioError& err) {
  out = SegmentScenario{};
  out.file = file;
  Parser p(out);
  int line = 0;
  try {
    for (std::string_view l : split(without_bom(text), '\n')) {
      ++line;
      const std::vector<std::string_view> w = words(l);
      if (!w.empty()) p.command(line, w);
      if (!w.empty() && !out.steps.empty() && out.steps.back().line == line) {
        out.steps.back().text = std::string(l.substr(0, l.find('#')));
      }
    }
    line = 0;
    p.finish();
  } catch (const ParseFail& f) {
    err = ScenarioError{file, f.line != 0 ? f.line : line, f.message};
    return false;
  }
  return true;
}

SegmentLoad load_segment_scenario(const std::string& path, SegmentScenario& out, Scenario& single,
                                  ScenarioError& err) {
  std::string text;
  std::string untrusted;
  if (!read_scenario_file(path, text, untrusted, err)) return SegmentLoad::error;
  return parse_segment_file(text, path, untrusted, out, single, err);
}

SegmentLoad parse_segment_file(std::string_view text, const std::string& path,
                               const std::string& untrusted, SegmentScenario& out, Scenario& single,
                               ScenarioError& err) {
  if (!is_segment_scenario(text)) {
    return parse_scenario_file(text, path, untrusted, single, err) ? SegmentLoad::not_segment
                                                                   : SegmentLoad::error;
  }
  err = ScenarioError{path, 0, {}};
  if ((err.line = cut_off_line(text, err.message)) != 0) return SegmentLoad::error;
  if (!parse_segment_scenario(text, path, out, err)) return SegmentLoad::error;
  out.untrusted = untrusted;
  return SegmentLoad::ok;
}

std::vector<std::string> segment_plugins(const SegmentScenario& s) {
  std::vector<std::string> out;
  for (const SegmentStation& st : s.stations) {
    if (st.plugin_line != 0) out.push_back(st.firmware);
  }
  return out;
}

bool bind_segment_plugins(SegmentScenario& s, ScenarioError& err) {
  if (s.plugins_bound) return true;
  for (std::size_t i = 0; i < s.stations.size(); ++i) {
    SegmentStation& st = s.stations[i];
    if (st.plugin_line == 0) continue;
    if (!s.untrusted.empty()) {
      err = ScenarioError{s.file, st.plugin_line, plugin_refused_untrusted(s.untrusted)};
      return false;
    }
    const dpc31_firmware* fw = nullptr;
    try {
      fw = &find_firmware(st.firmware, kHexAtSegment);
      st.slave = with_gsd_defaults(*fw, st.slave);
    } catch (const FirmwareError& e) {
      err = ScenarioError{s.file, st.plugin_line, e.what()};
      return false;
    }
    for (const SegmentStep& step : s.steps) {
      if (step.kind != SegmentStep::Kind::expect_port || step.station_index != i) continue;
      if (std::string why = port_refused(*fw, step.name); !why.empty()) {
        err = ScenarioError{s.file, step.line, std::move(why)};
        return false;
      }
    }
  }
  s.plugins_bound = true;
  return true;
}

}  // namespace dpc31
