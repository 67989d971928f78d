// dpc31.Segment in Python (docs/python.md, "A segment"): several chips on one line
// (session/segment.hpp), the built-in masters on it with their token visits (DpMaster), scripted
// senders, the bus check (session/bus_check.hpp), segment scenarios and the outputs of both
// (lib/segment_outputs), one call for one call.
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <variant>

#include "bind.hpp"
#include "bus_check.hpp"
#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "firmware_host.hpp"
#include "outfile.hpp"
#include "responder.hpp"
#include "scenario.hpp"
#include "scenario_segment.hpp"
#include "segment.hpp"
#include "segment_outputs.hpp"
#include "vocabulary.hpp"

namespace dpc31::py_bind {

namespace {

using U8 = std::uint8_t;
using U64 = std::uint64_t;
using Outputs = std::vector<std::vector<U8>>;

// dp_cycle's and use_token's outputs=: one bytes-like per slave (bytes, bytearray, or a list of
// ints), as data_exchange takes one and the stub says; None: zeros for every slave.
Outputs outputs_of(const py::object& o) {
  Outputs out;
  if (o.is_none()) return out;
  for (const py::handle item : o) {
    out.push_back(bytes_like(item, fmt::format("outputs[{}]", out.size())));
  }
  return out;
}

class PySegment;

// A chip station: the chip is the segment's, the user side is kept here. Its DP and watchdog
// state changes are recorded as the chip makes them (cycle, DP state, WD state).
struct PyStation {
  const PySegment* segment = nullptr;  // its owner
  std::size_t index = 0;
  std::string name;
  SlaveConfig slave;
  std::shared_ptr<FirmwareHost> firmware;
  std::shared_ptr<Responder> responder;
  std::vector<std::tuple<U64, DpState, WdState>> changes;
};

// The waveforms and the pcapng asked for (Segment(vcd=, fst=, pcapng=, signals=),
// SegmentScenario.run): wave::Options as `dpc31 run --vcd` / `--fst` makes them (1 ps, every
// cycle).
SegmentOutputOptions output_options(const std::optional<std::string>& vcd,
                                    const std::optional<std::string>& fst,
                                    const std::optional<std::string>& pcapng,
                                    const std::vector<std::string>& signals) {
  SegmentOutputOptions o;
  for (const auto& [path, is_fst] : {std::pair{vcd, false}, std::pair{fst, true}}) {
    if (!path) continue;
    wave::Options w;
    w.path = *path;
    w.fst = is_fst;
    w.signals = signals;
    o.waves.push_back(w);
  }
  o.pcap = pcapng.value_or("");
  return o;
}

// A file that cannot be made or written: dpc31.Error with its one line.
void check_output(bool ok, const std::string& error) {
  if (!ok) raise(errors().error, error);
}

// An output that is an input or another output (`dpc31 run`'s check, outfile::distinct, and its
// line), or an empty name (OutFile's words): a ValueError before anything is opened.
void check_distinct(const std::vector<outfile::Named>& inputs,
                    const std::optional<std::string>& vcd, const std::optional<std::string>& fst,
                    const std::optional<std::string>& pcapng) {
  for (const auto& [path, what] :
       {std::pair{&vcd, "vcd"}, std::pair{&fst, "fst"}, std::pair{&pcapng, "pcapng"}}) {
    // '' is no "not given": nothing would be written, silently.
    if (path_arg(*path, what) && (*path)->empty()) {
      throw py::value_error(std::string(what) +
                            ": an empty file name: nothing can be written there");
    }
  }
  const std::string same = outfile::distinct(
      inputs,
      // A script's print() goes to the standard output too: no /dev/stdout advice.
      {{"vcd", vcd.value_or(""), false},
       {"fst", fst.value_or(""), false},
       {"pcapng", pcapng.value_or(""), false}});
  if (!same.empty()) throw py::value_error(same);
}

// A look at a segment's running state (its cycle, a master's history, a bus check's counts): an
// observer of the running thread may, another thread may not.
void look_at_segment(const RunState& run) {
  enter_run(run, false, "segment", "history, counters, ...", "run it");
}

// check_bus's arguments as given; none: the masters' (their addresses, largest slot time, and
// with two or more of them the TTR they obey), followed as masters join.
struct CheckArgs {
  std::optional<U64> ttr;
  std::optional<std::uint32_t> slot_bits;
  std::uint32_t min_tsdr_bits = 11;
  std::uint32_t tsyn_bits = 33;
  std::optional<std::vector<U8>> masters;
};

// A master's ttr= beside the masters' before it, where the bus check takes its TTR from them: a
// scenario's `master` line refuses a second TTR so (docs/scenario-format.md, `segment`); "" fits.
std::string ttr_differs(U8 address, U64 ttr, const std::vector<U8>& addresses,
                        const std::vector<U64>& ttrs, std::size_t before) {
  for (std::size_t i = 0; i < before; ++i) {
    if (ttr != 0 && ttrs[i] != 0 && ttrs[i] != ttr) {
      return fmt::format(
          "master {}: ttr={} differs from master {}'s ttr={}: give the bus "
          "check's TTR (check_bus(ttr=BITS))",
          address, ttr, addresses[i], ttrs[i]);
    }
  }
  return {};
}

// The check's min TSDR above its slot time (no answer could be in time), refused at check_bus and
// at an add_master that lowers the slot time the check follows; "" fits.
std::string tsdr_above_slot(std::uint32_t min_tsdr_bits, std::uint32_t slot_bits) {
  if (min_tsdr_bits <= slot_bits) return {};
  return fmt::format("min_tsdr_bits {} above the slot time {}: no answer could be in time",
                     min_tsdr_bits, slot_bits);
}

// A bus check as Python holds it: shared with its segment, so one that a second check_bus()
// replaced keeps the counts it had (it sees no telegram after), never freed memory; its counts
// are the segment's running state.
struct PyBusCheck {
  std::shared_ptr<const BusCheck> check;
  std::shared_ptr<const RunState> run;
  [[nodiscard]] const BusCheck& looked() const {
    look_at_segment(*run);
    return *check;
  }
};

// The segment as Python holds it. The GIL is released while the line runs; a Python observer
// (on_telegram, on_collision) takes it again, and its exception is raised when the running call
// returns: a master's call ends after the wait it came in (DpMaster::waited), any other runs to
// its end; the observers are not called again in it. One thread at a time: a call while another
// runs it raises dpc31.Error.
class PySegment {
 public:
  PySegment(std::uint32_t baud_, std::uint32_t clock_hz) : seg(baud_, clock_hz), baud(baud_) {
    seg.on_telegram = [this](const LineTelegram& t) {
      if (check) check->telegram(t, seg.name(t.from));
      if (outputs) outputs->telegram(t);
      call(telegram_cb, t);
    };
    seg.on_collision = [this](const Collision& c) {
      if (check) check->collision(c, seg.name(c.first), seg.name(c.second));
      call(collision_cb, c);
    };
  }

  // Runs the line: the GIL released, then the bus check sees the idle line up to the line's time
  // and an observer's exception is raised. A call without a result gives std::monostate. The
  // outputs' line is attached at the first call that runs it (every station is on it then); a
  // station's init (`joins`) does not run the line.
  template <typename F>
  auto run(F&& f, bool joins = false) {
    enter();
    if (!outputs_error.empty()) raise(errors().error, outputs_error);
    if (outputs && !joins && !line_attached) {
      std::string e;
      if (!outputs->attach_line(seg, codes, e)) {
        outputs.reset();  // nothing will be written: its temporaries go now, not at collection
        outputs_error = e;
        raise(errors().error, e);
      }
      line_attached = true;
    }
    const Running running(*run_);
    auto r = [&] {
      try {
        return without_gil([&] {
          if constexpr (std::is_void_v<decltype(f())>) {
            f();
            return std::monostate{};
          } else {
            return f();
          }
        });
      } catch (const ObserverStopped&) {
        if (check) check->idle_until(seg.cycle());
        std::rethrow_exception(std::exchange(error_, nullptr));
      } catch (py::error_already_set& interrupt) {
        // Ctrl-C between two slices: the check sees the line up to there, the next call starts
        // clean.
        if (check) check->idle_until(seg.cycle());
        keep_as_context(interrupt, std::exchange(error_, nullptr));
        throw;
      }
    }();
    if (check) check->idle_until(seg.cycle());
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    return r;
  }
  // A master's wait ends here once an observer raised: read by the running thread only.
  [[nodiscard]] bool observer_failed() const { return error_ != nullptr; }
  // A look at the running state: an observer of this thread may, another thread may not.
  void look() const { look_at_segment(*run_); }
  void enter() const {
    if (run_->busy) {
      raise(errors().error, "the segment is running (another thread, or an observer)");
    }
  }
  // A station may join: with outputs, only before the line first runs (the waveform's scopes are
  // declared then). It joins with joined().
  void may_join() const {
    enter();
    if (line_attached) {
      raise(errors().error,
            "a station joins before the line first runs when the segment writes "
            "a waveform or a pcapng");
    }
  }
  // Station `index` joined with its code in the waveform's line.driver.
  std::size_t joined(std::size_t index, U8 code) {
    codes.push_back(code);
    return index;
  }
  // Shared with the stations' user sides (user_side_runs_with).
  [[nodiscard]] const std::shared_ptr<RunState>& run_state() const { return run_; }
  // The bus check's timing from check_args and the masters added so far.
  [[nodiscard]] BusTiming check_timing() const {
    const CheckArgs& a = check_args;
    const std::vector<U8> addresses = a.masters.value_or(master_addresses);
    U64 ttr = 0;
    if (a.ttr) {
      ttr = *a.ttr;
    } else if (addresses.size() > 1) {
      for (const U64 t : master_ttrs) ttr = t != 0 ? t : ttr;
    }
    return BusTiming{
        seg.bit_cycles(), a.min_tsdr_bits, a.slot_bits.value_or(master_slot_bits), a.tsyn_bits, ttr,
        addresses};
  }
  Chip& chip(const PyStation& s) {
    enter();
    return seg.chip(s.index);
  }

  Segment seg;
  std::uint32_t baud;
  std::vector<std::unique_ptr<PyStation>> stations;
  std::vector<U8> master_addresses;
  std::vector<U64> master_ttrs;          // each master's ttr= (0: none), as master_addresses
  std::uint32_t master_slot_bits = 100;  // the largest TSL of the masters added (100: none yet)
  std::shared_ptr<BusCheck> check;       // shared with the BusChecks Python holds
  CheckArgs check_args;                  // what check_bus was given (the rest: the masters')
  std::vector<std::string> check_log;
  std::shared_ptr<py::object> telegram_cb;
  std::shared_ptr<py::object> collision_cb;
  std::unique_ptr<SegmentOutputs> outputs;  // null: none asked, or close() wrote them
  std::vector<U8> codes;                    // each station's code in line.driver
  bool line_attached = false;
  std::string outputs_error;  // the outputs could not be attached: every later run says so

 private:
  template <typename T>
  void call(const std::shared_ptr<py::object>& cb, const T& arg) {
    if (!cb) return;
    py::gil_scoped_acquire gil;
    if (error_) return;
    try {
      (*cb)(arg);
    } catch (py::error_already_set&) {
      error_ = std::current_exception();
    }
  }
  std::shared_ptr<RunState> run_ = std::make_shared<RunState>();
  std::exception_ptr error_;
};

// A name no station of the segment has yet (a chip's, a sender's, a master's), else a ValueError
// in a segment scenario's words: the name is the station's scope in the waveforms and names it in
// the log and in collisions. (Two stations at one address, named apart, stay possible: a
// collision's test.)
const std::string& new_station_name(const Segment& seg, const std::string& name) {
  for (std::size_t i = 0; i < seg.size(); ++i) {
    if (seg.name(i) == name) throw py::value_error(second_station_named(name));
  }
  return name;
}

// A built-in master on the segment (a sender station of its own). It keeps the segment alive.
struct PySegMaster {
  PySegMaster(py::object seg_obj, const MasterConfig& mc, std::vector<SlaveConfig> slaves)
      : seg_ref(std::move(seg_obj)), s(seg_ref.cast<PySegment&>()) {
    s.may_join();
    DpMaster::checked_slaves(slaves, mc.address);  // before the station joins: nothing half-made
    const std::size_t station = s.joined(
        s.seg.add_sender(new_station_name(s.seg, master_station_name(mc.address))), mc.address);
    m = std::make_unique<DpMaster>(s.seg, station, mc, std::move(slaves));
    m->waited = [this] {
      if (s.observer_failed()) throw ObserverStopped{};
    };
    s.master_slot_bits =
        s.master_addresses.empty() ? mc.slot_bits : std::max(s.master_slot_bits, mc.slot_bits);
    s.master_addresses.push_back(mc.address);
    s.master_ttrs.push_back(mc.ttr_bits);
    if (s.outputs) s.outputs->pair_within(s.master_slot_bits);
    if (s.check) s.check->retime(s.check_timing());  // a check running follows the masters
  }
  template <typename F>
  auto act(F&& f) {
    return s.run(std::forward<F>(f));
  }
  py::object seg_ref;
  PySegment& s;
  std::unique_ptr<DpMaster> m;
};

// Whose running state a property reads.
const PySegment& segment_of(const PySegment& s) { return s; }
const PySegment& segment_of(const PyStation& st) { return *st.segment; }
const PySegment& segment_of(const PySegMaster& pm) { return pm.s; }

// A property of the segment's running state (Segment.cycle, Station.changes, a master's history):
// refused to another thread while the segment runs (PySegment::look), not read while that thread
// writes it; an observer of the running thread may read it.
template <typename T, typename F>
auto looked(F f) {
  return [f](const T& x) {
    segment_of(x).look();
    return f(x);
  };
}

// The slaves of a master: station addresses (their SlaveConfig as the station was added) or
// SlaveConfigs as they are.
std::vector<SlaveConfig> slaves_of(const PySegment& s, const py::list& slaves) {
  std::vector<SlaveConfig> out;
  for (const py::handle h : slaves) {
    if (py::isinstance<SlaveConfig>(h)) {
      out.push_back(h.cast<SlaveConfig>());
      continue;
    }
    if (!py::isinstance<py::int_>(h)) {
      throw py::type_error(
          fmt::format("slaves[{}]: a station address or a SlaveConfig expected, got {}", out.size(),
                      py::str(py::type::of(h).attr("__name__")).cast<std::string>()));
    }
    const auto a = h.cast<py::int_>();
    const auto it = std::find_if(s.stations.begin(), s.stations.end(), [&a](const auto& st) {
      return a.equal(py::int_(st->slave.address));
    });
    if (it == s.stations.end())
      throw py::value_error("no station at address " + std::string(py::str(h)));
    out.push_back((*it)->slave);
  }
  if (out.empty()) throw py::value_error("a master needs at least one slave");
  return out;
}

void bind_line(py::module_& m) {
  py::class_<LineTelegram>(m, "LineTelegram", "One telegram on a segment's line.")
      .def_readonly("sender", &LineTelegram::from)
      .def_readonly("start", &LineTelegram::start)
      .def_readonly("end", &LineTelegram::end)
      .def_property_readonly("bytes", [](const LineTelegram& t) { return to_bytes(t.bytes); })
      .def_property_readonly(
          "fault",
          [](const LineTelegram& t) -> py::object {
            if (t.fault.kind == UartFault::Kind::none) return py::none();
            return py::str(std::string(fault_kind_name(t.fault.kind)));
          },
          "its first broken character's first error as send() names it ('parity', 'start', "
          "'stop'); None: every character good")
      .def_property_readonly(
          "fault_char",
          [](const LineTelegram& t) -> py::object {
            if (t.fault.kind == UartFault::Kind::none) return py::none();
            return py::int_(t.fault.char_index);
          },
          "the index of that character; None: every character good")
      .def_readonly("collided", &LineTelegram::collided,
                    "the rest of a telegram a collision cut (its sender drove into another's): "
                    "no telegram of its own to the bus check and the capture")
      .def("__repr__", [](const LineTelegram& t) {
        return "<LineTelegram from " + std::to_string(t.from) + " at " + std::to_string(t.start) +
               ", " + std::to_string(t.bytes.size()) + " bytes>";
      });
  py::class_<Collision>(m, "Collision", "Two stations driving the line at once.")
      .def_readonly("cycle", &Collision::cycle)
      .def_readonly("first", &Collision::first)
      .def_readonly("second", &Collision::second)
      .def_readonly("answer", &Collision::answer);
  py::class_<TokenVisit>(m, "TokenVisit", "What one visit of the token did (use_token).")
      .def_readonly("arrived", &TokenVisit::arrived, "the token's arrival, a cycle of the line")
      .def_readonly("rotation", &TokenVisit::rotation, "TRR in clock cycles (0: the ring's first)")
      .def_readonly("hold", &TokenVisit::hold, "TTH = TTR - TRR in clock cycles (0: a late token)")
      .def_readonly("polled", &TokenVisit::polled)
      .def_readonly("startup", &TokenVisit::startup)
      .def_readonly("gap", &TokenVisit::gap)
      .def_readonly("gap_answered", &TokenVisit::gap_answered);
  py::class_<PyBusCheck>(m, "BusCheck", "The bus check of a segment (docs/segment.md).")
      .def(
          "count",
          [](const PyBusCheck& c, const std::string& kind) {
            BusViolation v{};
            if (!parse_bus_violation(kind, v)) throw py::value_error("no violation '" + kind + "'");
            return c.looked().count(v);
          },
          py::arg("kind"))
      .def_property_readonly("counts",
                             [](const PyBusCheck& c) {
                               const BusCheck& check = c.looked();
                               py::dict d;
                               for (std::size_t i = 0; i < kBusViolationKinds; ++i) {
                                 const auto v = static_cast<BusViolation>(i);
                                 d[py::str(std::string(bus_violation_name(v)))] = check.count(v);
                               }
                               return d;
                             })
      .def_property_readonly("total", [](const PyBusCheck& c) { return c.looked().total(); });
}

void bind_station(py::module_& m) {
  using S = PyStation;
  // A read of the station's chip at the line's time (Segment::chip).
  const auto read = [](auto f) {
    return [f](py::object self) {
      S& st = self.cast<S&>();
      PySegment& seg = py::cast<PySegment&>(self.attr("_segment"));
      return f(seg.chip(st));
    };
  };
  py::class_<S>(m, "Station", py::dynamic_attr(),
                "A chip on a segment: its chip read at the line's time.")
      .def_readonly("index", &S::index)
      .def_readonly("name", &S::name)
      .def_property_readonly("slave",
                             [](const S& s) {
                               return MasterSlave{
                                   s.slave, "Station.slave",
                                   "Segment.add_station(..., slave=SlaveConfig(...))"};
                             })
      .def_property_readonly("address", [](const S& s) { return s.slave.address; })
      .def_readonly("firmware", &S::firmware)
      .def_readonly("responder", &S::responder)
      .def_property_readonly("changes", looked<S>([](const S& s) { return s.changes; }),
                             "(cycle, DpState, WdState) at each change of either, as the chip "
                             "made it")
      .def_property_readonly("cycle", read([](Chip& c) { return c.cycle(); }))
      .def_property_readonly("dp_state", read([](Chip& c) { return c.dp_state(); }))
      .def_property_readonly("wd_state", read([](Chip& c) { return c.wd_state(); }))
      .def_property_readonly("fdl_counters",
                             read([](Chip& c) { return counters_dict(c.fdl_counters()); }))
      .def_property_readonly("txd", read([](Chip& c) { return c.txd_pin(); }))
      .def_property_readonly("x_int", read([](Chip& c) { return c.x_int_pin(); }))
      .def_property_readonly("profile", read([](Chip& c) { return std::string(c.profile().name); }))
      .def_property_readonly("watchdog_due", read([](Chip& c) { return c.watchdog_due(); }))
      .def("probe", read([](Chip& c) { return c.probe(); }))
      // The chip's snapshot at the line's time (a Chip's save_state, docs/snapshots.md); no
      // load_state: it would move one chip's time and receiver under the line (docs/python.md).
      .def("save_state", read([](Chip& c) { return to_bytes(c.save_state()); }))
      .def(
          "peek",
          [read](py::object self, const AnyInt& a) {
            return read([a](Chip& c) { return c.peek(bus_addr(c, a)); })(std::move(self));
          },
          py::arg("addr"))
      .def(
          "peek_reg",
          [read](py::object self, const std::string& n) {
            return read([&n](Chip& c) { return c.peek_reg(reg_id(c, n)); })(std::move(self));
          },
          py::arg("name"))
      .def(
          "peek_field",
          [read](py::object self, const std::string& r, const std::string& f) {
            return read([&](Chip& c) { return peek_field(c, r, f); })(std::move(self));
          },
          py::arg("register"), py::arg("field"))
      .def(
          "addr_of",
          [read](py::object self, const std::string& n) {
            return read([&n](Chip& c) { return addr_of(c, n); })(std::move(self));
          },
          py::arg("name"));
}

// Station `st`'s user side set up on its chip, which has just joined: its state changes recorded,
// the firmware's or responder's init run, its ISR given to the segment.
void set_up(PySegment& s, PyStation& st, U8 address) {
  Chip& chip = s.seg.chip(st.index);
  chip.on_state_change([&st, &chip](U64 cycle) {
    const DpState dp = chip.dp_state();
    const WdState wd = chip.wd_state();
    if (st.changes.empty() || std::get<1>(st.changes.back()) != dp ||
        std::get<2>(st.changes.back()) != wd) {
      st.changes.emplace_back(cycle, dp, wd);
    }
  });
  DirectBus bus(chip);
  if (st.firmware) {
    st.firmware->init(bus, address);
    s.seg.set_firmware(st.index, st.firmware->program());
  } else {
    st.responder->init(bus);
    Responder* r = st.responder.get();
    s.seg.set_firmware(st.index, [r](BusPort& b) { r->isr(b); });
  }
}

// A chip station with its user side: a firmware (built-in name or plug-in path) or the built-in
// responder, set up on its chip now, as a segment scenario's `station` line does.
PyStation& add_station(py::object self, U8 address, const std::string& profile,
                       const std::optional<std::string>& variant,
                       const std::optional<std::string>& firmware,
                       const std::optional<std::string>& name, std::pair<U8, U8> wd,
                       const std::optional<SlaveConfig>& slave, const std::optional<bool>& user_wd,
                       const std::optional<std::uint16_t>& user_wd_value) {
  PySegment& s = self.cast<PySegment&>();
  s.may_join();
  if (std::find(s.master_addresses.begin(), s.master_addresses.end(), address) !=
      s.master_addresses.end())
    throw py::value_error(station_at_master(address));
  auto st = std::make_unique<PyStation>();
  st->segment = &s;
  const std::string whose = "station " + std::to_string(address);
  if (std::string why = station_name_refused(name.value_or(whose), whose); !why.empty())
    throw py::value_error(why);
  st->name = new_station_name(s.seg, name.value_or(whose));
  const std::string scope = station_scope(address, st->name);
  for (const auto& o : s.stations) {
    if (station_scope(o->slave.address, o->name) == scope)
      throw py::value_error(second_station_in_scope(st->name, o->name, scope));
  }
  SlaveConfig sc = slave.value_or(SlaveConfig{});
  sc.address = address;
  if (!slave) {
    sc.wd_fact1 = wd.first;
    sc.wd_fact2 = wd.second;
  }
  const ChipOptions opt =
      chip_options(profile, "intel", s.seg.clock_hz(), "event", variant, "external");
  // The checks of a segment scenario's `station` (the single chip's `user` step). user_wd is
  // None when not given: an explicit False beside a firmware is refused as user_wd=0 is there.
  if (firmware && (user_wd.has_value() || user_wd_value.has_value())) {
    throw py::value_error(
        refused_beside_firmware(user_wd.has_value() ? "user_wd" : "user_wd_value"));
  }
  if (user_wd_value && opt.profile == Profile::dpc31 && !user_wd.value_or(false))
    throw py::value_error(user_wd_value_needs_user_wd("user_wd_value"));
  if (firmware) {
    const dpc31_firmware& d = find_firmware(*firmware, kHexAtSegment);  // checked as a file name
    st->firmware = std::make_shared<FirmwareHost>(d);
    if (!slave) sc = with_gsd_defaults(d, sc);
  } else {
    ResponderConfig rc;
    rc.slave = sc;
    rc.user_watchdog = user_wd.value_or(false);
    rc.user_wd_value = user_wd_value.value_or(rc.user_wd_value);
    if (const std::string why = responder_layout_problem(profile_desc(opt.profile), rc);
        !why.empty())
      throw py::value_error("slave=SlaveConfig " + why);
    st->responder = std::make_shared<Responder>(rc);
  }
  st->slave = sc;
  PyStation& raw = *st;
  std::string out_error;
  s.run(
      [&] {
        st->index = s.seg.add_chip(st->name, opt);
        // Refused from here on (a waveform's scope, the firmware's init): the station leaves
        // again, the segment as it was (size, names, indices, waveforms).
        bool in_outputs = false;
        try {
          if (s.outputs) {
            in_outputs = s.outputs->add_station(s.seg, st->index, scope, out_error);
            if (!in_outputs) {
              s.seg.remove_last_chip();
              return;
            }
          }
          set_up(s, raw, address);
        } catch (...) {
          if (in_outputs) s.outputs->remove_station();
          s.seg.remove_last_chip();
          throw;
        }
        s.joined(st->index, address);
      },
      /*joins=*/true);
  check_output(out_error.empty(), out_error);
  // With the GIL held again: the registry of user sides is Python's state.
  user_side_runs_with(raw.firmware ? static_cast<const void*>(raw.firmware.get())
                                   : static_cast<const void*>(raw.responder.get()),
                      s.run_state());
  s.stations.push_back(std::move(st));
  return raw;
}

void bind_segment_class(py::module_& m) {
  using P = PySegment;
  py::class_<P>(m, "Segment",
                "A bus segment: chips, masters and scripted senders on one RS-485 line "
                "(docs/segment.md).")
      .def(py::init([](std::uint32_t baud, std::uint32_t clock_hz, const py::object& vcd_arg,
                       const py::object& fst_arg, const py::object& pcapng_arg,
                       const std::vector<std::string>& signals) {
             const auto vcd = fspath_arg_or_none(vcd_arg, "vcd");
             const auto fst = fspath_arg_or_none(fst_arg, "fst");
             const auto pcapng = fspath_arg_or_none(pcapng_arg, "pcapng");
             // A rate the chips' baud search finds (a scenario's `baud`), a bit at least one
             // clock.
             auto s = std::make_unique<P>(profibus_rate(baud), clock_hz);
             one_clock_a_bit(s->seg.clock_hz(), baud);
             if (vcd || fst || pcapng) {
               check_distinct({}, vcd, fst, pcapng);
               s->outputs =
                   std::make_unique<SegmentOutputs>(output_options(vcd, fst, pcapng, signals));
               std::string e;
               check_output(s->outputs->open(e), e);
             }
             return s;
           }),
           py::arg("baud") = 1'500'000, py::arg("clock_hz") = 0, py::kw_only(),
           py::arg("vcd") = py::none(), py::arg("fst") = py::none(), py::arg("pcapng") = py::none(),
           py::arg("signals") = std::vector<std::string>{},
           "The line at `baud`; the waveforms (`vcd`, `fst`: the line and a scope per station, "
           "`signals` globs) and the pcapng of the line asked for are written by close().")
      .def(
          "add_station",
          [](py::object self, std::int64_t address, const std::string& profile,
             const std::optional<std::string>& variant, const py::object& firmware,
             const std::optional<std::string>& name, std::pair<std::int64_t, std::int64_t> wd,
             const std::optional<SlaveConfig>& slave, const std::optional<bool>& user_wd,
             const std::optional<py::int_>& user_wd_value) {
            // The checks of a segment scenario's `station ADDRESS wd=F1,F2 user_wd_value=N`.
            std::optional<std::uint16_t> wd_value;
            if (user_wd_value) wd_value = in_range<std::uint16_t>(kUserWdValue, *user_wd_value);
            PyStation& st = add_station(
                self, in_range<U8>(kStationAddress, address), profile, variant,
                fspath_arg_or_none(firmware, "firmware"), name,
                {in_range<U8>(kWdFactor1, wd.first), in_range<U8>(kWdFactor2, wd.second)}, slave,
                user_wd, wd_value);
            py::object o = py::cast(&st, py::return_value_policy::reference);
            o.attr("_segment") = self;  // a station keeps its segment alive
            return o;
          },
          py::arg("address"), py::arg("profile") = "dpc31", py::arg("variant") = py::none(),
          py::arg("firmware") = py::none(), py::arg("name") = py::none(),
          py::arg("wd") = std::pair<std::int64_t, std::int64_t>{10, 10},
          py::arg("slave") = py::none(), py::arg("user_wd") = py::none(),
          py::arg("user_wd_value") = py::none(),
          "A chip at station `address` with a firmware (DO4, CNT2 or a plug-in path; the "
          "master's slave takes its GSD defaults) or the built-in responder (firmware=None); "
          "`wd` the watchdog factors its master sends; `slave` a SlaveConfig as it is instead; "
          "the responder's user watchdog served on every DX_Out (`user_wd`, unserved unless "
          "given) and its R_User_WD_Value (`user_wd_value`, 0x1FF unless given), as a "
          "scenario's `station`; either given beside `firmware` (even user_wd=False) is a "
          "ValueError.")
      .def_property_readonly("stations",
                             [](py::object self) {
                               py::list l;
                               for (const auto& st : self.cast<P&>().stations) {
                                 py::object o =
                                     py::cast(st.get(), py::return_value_policy::reference);
                                 o.attr("_segment") = self;
                                 l.append(o);
                               }
                               return l;
                             })
      .def(
          "add_sender",
          [](P& s, const std::string& name) {
            s.may_join();
            if (std::string why = station_name_refused(name, "a sender"); !why.empty())
              throw py::value_error(why);
            return s.joined(s.seg.add_sender(new_station_name(s.seg, name)),
                            wave::kDriverWithoutAddress);
          },
          py::arg("name"), "A station without a chip that drives the line with send(); its index.")
      .def(
          "add_master",
          [](py::object self, std::int64_t address, const py::list& slaves, std::int64_t ttr,
             std::int64_t gap, const std::optional<std::int64_t>& hsa, std::int64_t slot_bits,
             std::int64_t idle_bits) {
            P& s = self.cast<P&>();
            // The checks of a segment scenario's `master` line (0: no TTR, no GAP update).
            MasterConfig mc{in_range<U8>(kMasterAddress, address),
                            s.baud,
                            in_range<std::uint32_t>(kSlotBits, slot_bits),
                            in_range<std::uint32_t>(kIdleBits, idle_bits),
                            ttr == 0 ? 0 : in_range<U64>(kTtrBits, ttr),
                            gap == 0 ? U8{0} : in_range<U8>(kGapFactor, gap)};
            if (std::any_of(s.stations.begin(), s.stations.end(),
                            [&mc](const auto& st) { return st->slave.address == mc.address; }))
              throw py::value_error(master_at_station(mc.address));
            if (hsa) {
              mc.hsa = in_range<U8>(kHsa, *hsa);
              const std::string e = hsa_refused(mc.hsa, mc.gap_factor, mc.address);
              if (!e.empty()) throw py::value_error(e);
            }
            std::vector<SlaveConfig> sl = slaves_of(s, slaves);
            if (s.check && !s.check_args.ttr) {
              const std::string e = ttr_differs(mc.address, mc.ttr_bits, s.master_addresses,
                                                s.master_ttrs, s.master_addresses.size());
              if (!e.empty()) throw py::value_error(e);
            }
            if (s.check && !s.check_args.slot_bits) {  // the check retimed to the masters' TSL
              const std::string e = tsdr_above_slot(
                  s.check_args.min_tsdr_bits, s.master_addresses.empty()
                                                  ? mc.slot_bits
                                                  : std::max(s.master_slot_bits, mc.slot_bits));
              if (!e.empty()) throw py::value_error(e);
            }
            try {
              return std::make_unique<PySegMaster>(std::move(self), mc, std::move(sl));
            } catch (const std::invalid_argument& e) {
              throw py::value_error(e.what());
            }
          },
          py::arg("address"), py::arg("slaves"), py::kw_only(), py::arg("ttr") = 0,
          py::arg("gap") = 0, py::arg("hsa") = py::none(), py::arg("slot_bits") = 100,
          py::arg("idle_bits") = 33,
          "A built-in master polling `slaves` (station addresses or SlaveConfigs), obeying TTR "
          "`ttr` bit times (0: no limit) and the GAP update factor `gap` in use_token.")
      .def(
          "name", [](const P& s, std::size_t i) { return s.seg.name(i); }, py::arg("station"))
      .def_property_readonly("size", [](const P& s) { return s.seg.size(); })
      .def_property_readonly("cycle", looked<P>([](const P& s) { return s.seg.cycle(); }))
      .def_property_readonly("bit_cycles", [](const P& s) { return s.seg.bit_cycles(); })
      .def_property_readonly("clock_hz", [](const P& s) { return s.seg.clock_hz(); })
      .def(
          "run_until", [](P& s, U64 cycle) { s.run([&] { s.seg.run_until(cycle); }); },
          py::arg("cycle"), "Runs every station to `cycle`.")
      .def("align", [](P& s) { s.run([&] { s.seg.align(); }); })
      .def(
          "send",
          [](P& s, std::size_t sender, const py::object& data, std::optional<U64> start,
             const std::optional<std::string>& fault, std::optional<int> fault_char) {
            const std::vector<U8> v = raw_telegram(data);
            const UartFault f = fault_of(fault, fault_char);
            const U64 at = start.value_or(s.seg.cycle() + 33 * U64{s.seg.bit_cycles()});
            if (at < s.seg.cycle()) throw py::value_error("start is before the line's time");
            return s.run([&] { return s.seg.send(sender, v, at, f); });
          },
          py::arg("sender"), py::arg("data"), py::arg("start") = py::none(),
          py::arg("fault") = py::none(), py::arg("fault_char") = py::none(),
          "Bytes as back-to-back characters from sender station `sender` at `start` (default: "
          "TSYN, 33 bit times, from now); returns the end of the last stop bit.")
      .def(
          "pulse",
          [](P& s, std::size_t sender, U64 start, U64 low) {
            if (start < s.seg.cycle()) throw py::value_error("start is before the line's time");
            s.run([&] { s.seg.pulse(sender, start, low); });
          },
          py::arg("sender"), py::arg("start"), py::arg("low_cycles"))
      .def_property_readonly("collisions", looked<P>([](const P& s) { return s.seg.collisions(); }))
      .def(
          "on_telegram",
          [](P& s, const std::optional<py::function>& f) {
            s.enter();
            s.telegram_cb = f ? hold(*f) : nullptr;
          },
          py::arg("callback"), "callback(LineTelegram) for every telegram on the line; None: none")
      .def(
          "on_collision",
          [](P& s, const std::optional<py::function>& f) {
            s.enter();
            s.collision_cb = f ? hold(*f) : nullptr;
          },
          py::arg("callback"))
      .def("flush", [](P& s) { s.run([&] { s.seg.flush(); }); })
      .def(
          "close",
          [](P& s) {
            s.run([&] {
              s.seg.flush();
              s.seg.align();
            });
            if (!s.outputs) return;
            std::unique_ptr<SegmentOutputs> out = std::move(s.outputs);
            out->end(s.seg);
            std::string e;
            check_output(out->write(e), e);
          },
          "Flushes the line and writes the waveforms and the pcapng asked for, up to the line's "
          "time; the segment runs on without them.")
      .def(
          "check_bus",
          [](P& s, const std::optional<std::int64_t>& ttr,
             const std::optional<std::int64_t>& slot_bits, const py::int_& min_tsdr_bits,
             const py::int_& tsyn_bits, const std::optional<std::vector<std::int64_t>>& masters) {
            s.enter();
            // The ranges of a segment scenario's `segment ttr=` (0: none) and `slot=`, of a
            // station's min_tsdr= and a master's idle time (TSYN) and address.
            CheckArgs a;
            if (ttr) a.ttr = *ttr == 0 ? 0 : in_range<U64>(kTtrBits, *ttr);
            if (slot_bits)
              a.slot_bits = in_range<std::uint32_t>(named(kSlotBits, "slot_bits"), *slot_bits);
            a.min_tsdr_bits =
                in_range<std::uint32_t>(named(kMinTsdr, "min_tsdr_bits"), min_tsdr_bits);
            a.tsyn_bits = in_range<std::uint32_t>(named(kIdleBits, "tsyn_bits"), tsyn_bits);
            if (masters) {
              a.masters.emplace();
              for (const std::int64_t m : *masters)
                a.masters->push_back(in_range<U8>(kMasterAddress, m));
            }
            if (!a.ttr) {
              for (std::size_t i = 0; i < s.master_addresses.size(); ++i) {
                const std::string e = ttr_differs(s.master_addresses[i], s.master_ttrs[i],
                                                  s.master_addresses, s.master_ttrs, i);
                if (!e.empty()) throw py::value_error(e);
              }
            }
            const std::string above =
                tsdr_above_slot(a.min_tsdr_bits, a.slot_bits.value_or(s.master_slot_bits));
            if (!above.empty()) throw py::value_error(above);
            // The masters' own slot time by default: an answer a master waits for and takes is
            // neither late nor unsolicited (a segment scenario shares `s.slot_bits` so).
            s.check_args = std::move(a);
            const BusTiming t = s.check_timing();
            s.check_log.clear();
            s.check = std::make_shared<BusCheck>(t, [&s](const LogRecord& r) {
              s.check_log.push_back("[cycle " + std::to_string(r.cycle) + "] " + r.text);
            });
            s.check->watch_from(s.seg.cycle());
            return PyBusCheck{s.check, s.run_state()};
          },
          py::kw_only(), py::arg("ttr") = py::none(), py::arg("slot_bits") = py::none(),
          py::arg("min_tsdr_bits") = 11, py::arg("tsyn_bits") = 33, py::arg("masters") = py::none(),
          "The bus check on every telegram from now on (masters: the masters' addresses, for the "
          "token checks and TTO; default those added, now and later, none: no token checks; "
          "slot_bits: TSL, default the largest of the masters added, 100 without one; ttr: TTR "
          "in bit times, default the ttr= of the masters added with two or more, 0: no "
          "token_hold).")
      .def_property_readonly("bus_check",
                             [](const P& s) -> std::optional<PyBusCheck> {
                               if (!s.check) return std::nullopt;
                               return PyBusCheck{s.check, s.run_state()};
                             })
      .def_property_readonly("bus_log", [](P& s) {
        s.enter();  // the flush changes the running check's log
        if (s.check) s.check->flush();
        return s.check_log;
      });
}

// dp_cycle's skip=: stations of the segment, refused as a segment scenario's `cycle skip=` refuses
// an address (its range and its words).
std::vector<U8> skipped(const PySegment& s, const std::vector<py::int_>& skip) {
  constexpr ValueRange kSkipped{"station", 0, 126};
  std::vector<U8> out;
  for (const py::int_& v : skip) {
    const U8 a = in_range<U8>(kSkipped, v);
    if (std::none_of(s.stations.begin(), s.stations.end(),
                     [a](const auto& st) { return st->slave.address == a; }))
      throw py::value_error(fmt::format("no station {}", a));
    out.push_back(a);
  }
  return out;
}

// data_exchange's outputs.
std::vector<U8> outputs_arg(py::handle o) { return bytes_like(o, "outputs"); }

// A master's service that sends bytes (Data_Exchange's outputs, a raw telegram), without a fault;
// `Bytes` takes them from Python with its checks.
template <Exchange (DpMaster::*Service)(const std::vector<U8>&, UartFault), auto Bytes>
Exchange bytes_service(PySegMaster& pm, const py::object& data) {
  const std::vector<U8> v = Bytes(data);
  return pm.act([&] { return (*pm.m.*Service)(v, UartFault{}); });
}

void bind_seg_master(py::module_& m) {
  using M = PySegMaster;
  py::class_<M>(m, "SegmentMaster", "The built-in DP master on a segment (DpMaster).")
      .def_property_readonly("address", [](const M& pm) { return pm.m->address(); })
      .def_property_readonly("slave_count", [](const M& pm) { return pm.m->slave_count(); })
      .def_property_readonly("selected", looked<M>([](const M& pm) { return pm.m->selected(); }))
      .def_property_readonly("slave", looked<M>([](const M& pm) {
                               return MasterSlave{
                                   pm.m->slave(), "SegmentMaster.slave",
                                   "Segment.add_station(..., slave=SlaveConfig(...))"};
                             }))
      .def(
          "select",
          [](M& pm, std::size_t i) {
            pm.s.enter();
            if (i >= pm.m->slave_count()) throw py::index_error("no slave " + std::to_string(i));
            pm.m->select(i);
          },
          py::arg("index"))
      .def(
          "startup_all",
          [](M& pm, const py::int_& tries) {
            const int n = in_range<int>(kTries, tries);
            return pm.act([&] { return pm.m->startup_all(n); });
          },
          py::arg("tries") = kStartupTries)
      .def(
          "startup",
          [](M& pm, const py::int_& tries) {
            const int n = in_range<int>(kTries, tries);
            return pm.act([&] { return pm.m->startup(n); });
          },
          py::arg("tries") = kStartupTries)
      .def(
          "begin_startup",
          [](M& pm, const py::int_& tries) {
            const int n = in_range<int>(kTries, tries);
            pm.s.enter();
            pm.m->begin_startup(n);
          },
          py::arg("tries") = kStartupTries,
          "The start-up under the token: the next use_token visits spend their cycles on it.")
      .def_property_readonly("starting_up",
                             looked<M>([](const M& pm) { return pm.m->starting_up(); }))
      .def_property_readonly("started_up",
                             looked<M>([](const M& pm) { return pm.m->started_up(); }))
      .def(
          "dp_cycle",
          [](M& pm, const py::object& outputs_arg, const std::vector<py::int_>& skip_arg) {
            const Outputs outputs = outputs_of(outputs_arg);
            const std::vector<U8> skip = skipped(pm.s, skip_arg);
            return pm.act([&] {
              DpMaster& dm = *pm.m;
              if (skip.empty()) return dm.dp_cycle(outputs);
              dm.check_outputs(outputs);
              std::vector<Exchange> out;  // the slaves not skipped, as a scenario's `cycle skip=`
              for (std::size_t i = 0; i < dm.slave_count(); ++i) {
                dm.select(i);
                if (std::find(skip.begin(), skip.end(), dm.slave().address) != skip.end()) continue;
                out.push_back(dm.data_exchange(
                    i < outputs.size() ? outputs[i] : std::vector<U8>(dm.slave().out_len)));
              }
              dm.select(0);
              return out;
            });
          },
          py::arg("outputs") = py::none(), py::arg("skip") = std::vector<py::int_>{},
          "Data_Exchange with every slave in order (outputs[i] to slave i; zeros where none), "
          "but the station addresses in `skip`.")
      .def("data_exchange", &bytes_service<&DpMaster::data_exchange, &outputs_arg>,
           py::arg("outputs"))
      .def(
          "use_token",
          [](M& pm, U8 next, const py::object& outputs_arg) {
            const Outputs outputs = outputs_of(outputs_arg);
            return pm.act([&] { return pm.m->use_token(next, outputs); });
          },
          py::arg("next"), py::arg("outputs") = py::none(),
          "One visit of the token (TTR, the GAP update), then the token to `next`.")
      .def(
          "pass_token",
          [](M& pm, U8 next) {
            return pm.act([&] {
              const Exchange ex = pm.m->pass_token(next);
              // To no master of the segment: nobody takes it, the passer keeps it (EN 50170).
              const auto& ms = pm.s.master_addresses;
              if (std::find(ms.begin(), ms.end(), next) == ms.end()) pm.m->keep_token();
              return ex;
            });
          },
          py::arg("next"))
      .def(
          "wait_token",
          [](M& pm, U64 timeout) { return pm.act([&] { return pm.m->wait_token(timeout); }); },
          py::arg("timeout"))
      .def_property_readonly("token_rotation",
                             looked<M>([](const M& pm) { return pm.m->token_rotation(); }))
      .def("fdl_status", [](M& pm) { return pm.act([&] { return pm.m->fdl_status(); }); })
      .def("slave_diag", [](M& pm) { return pm.act([&] { return pm.m->slave_diag(); }); })
      .def(
          "global_control",
          [](M& pm, U8 command, U8 groups) {
            return pm.act([&] { return pm.m->global_control(command, groups); });
          },
          py::arg("command"), py::arg("groups") = 0)
      .def(
          "transact",
          [](M& pm, const fdl::Frame& req) {
            static_cast<void>(sendable(req));
            return pm.act([&] { return pm.m->transact(req); });
          },
          py::arg("request"))
      .def("transact_raw", &bytes_service<&DpMaster::transact_raw, &raw_telegram>, py::arg("data"))
      .def(
          "idle",
          [](M& pm, U64 cycles) {
            // An observer's error ends the call at the end of its slice (DpMaster::waited).
            idle_in_slices(
                pm, cycles, [&] { return pm.s.seg.cycle(); }, [] { return false; });
          },
          py::arg("cycles"), "Time passes with a silent line from this master.")
      .def_property_readonly("counters", looked<M>([](const M& pm) { return pm.m->counters(); }))
      .def_property_readonly("history", looked<M>([](const M& pm) { return pm.m->history(); }))
      .def_property_readonly(
          "locks", looked<M>([](const M& pm) { return pm.m->locks(); }),
          "{slave address: master address}: the slaves a start-up found locked by another master "
          "(Slave_Diag's Master_Add), which it left alone")
      .def("clear_history", [](M& pm) {
        pm.s.enter();
        pm.m->clear_history();
      });
}

// A segment scenario (docs/scenario-format.md, "Segments") and what its run gave.
struct SegmentRunResult {
  int exit_code = 0;
  std::vector<std::string> walk;
  std::vector<std::string> failures;
};

void bind_segment_scenario(py::module_& m) {
  py::class_<SegmentRunResult>(m, "SegmentScenarioResult", "What a segment scenario's run gave.")
      .def_property_readonly("ok", [](const SegmentRunResult& r) { return r.exit_code == 0; })
      .def_readonly("exit_code", &SegmentRunResult::exit_code)
      .def_readonly("walk", &SegmentRunResult::walk)
      .def_readonly("failures", &SegmentRunResult::failures);
  const auto fail = [](const ScenarioError& e) {
    raise(errors().scenario, e.text(),
          {{"file", py::str(e.file)}, {"line", py::int_(e.line)}, {"reason", py::str(e.message)}});
  };
  py::class_<SegmentScenario>(m, "SegmentScenario", "A parsed segment scenario file.")
      .def_static(
          "load",
          [fail](const py::object& path) {
            SegmentScenario s;
            Scenario single;
            ScenarioError err;
            // A file that cannot be read or is no scenario at all: Scenario.load's words for it.
            const std::string file = read_path_arg(fspath_arg(path, "path"), "path");
            const SegmentLoad l = load_segment_scenario(file, s, single, err);
            if (l == SegmentLoad::error) fail(err);
            if (l == SegmentLoad::not_segment) {
              fail(ScenarioError{file, 0, "not a segment scenario (use Scenario.load)"});
            }
            return s;
          },
          py::arg("path"))
      .def_static(
          "parse",
          [fail](std::string_view text, const std::string& file) {
            SegmentScenario s;
            ScenarioError err;
            // A single chip's text: what load says of its file (line 0, the text as a whole);
            // a text that is neither, the single chip's error, as load gives.
            if (!is_segment_scenario(text)) {
              Scenario single;
              if (!parse_scenario(text, path_arg(file, "file"), single, err)) fail(err);
              fail(ScenarioError{file, 0, "not a segment scenario (use Scenario.parse)"});
            }
            if (!parse_segment_scenario(text, path_arg(file, "file"), s, err)) fail(err);
            return s;
          },
          py::arg("text"), py::arg("file") = "<string>")
      .def_readonly("file", &SegmentScenario::file)
      .def_readonly("baud", &SegmentScenario::baud)
      .def(
          "run",
          [](const SegmentScenario& s, const py::object& vcd_arg, const py::object& fst_arg,
             const py::object& pcapng_arg, const std::vector<std::string>& signals) {
            const auto vcd = fspath_arg_or_none(vcd_arg, "vcd");
            const auto fst = fspath_arg_or_none(fst_arg, "fst");
            const auto pcapng = fspath_arg_or_none(pcapng_arg, "pcapng");
            std::vector<outfile::Named> inputs = {{"the scenario", s.file}};
            for (const std::string& p : segment_plugins(s))
              inputs.push_back({"the firmware plug-in", p});
            check_distinct(inputs, vcd, fst, pcapng);
            SegmentRunResult r;
            SegmentScenarioOutputs out(s, output_options(vcd, fst, pcapng, signals));
            std::string e;
            check_output(out.open(e), e);
            try {
              py::gil_scoped_release nogil;
              r.exit_code = run_segment_scenario(
                  s, [&](const std::string& l) { r.walk.push_back(l); },
                  [&](const std::string& l) { r.failures.push_back(l); }, &out);
            } catch (const SegmentOutputError& x) {
              raise(errors().error, x.what());
            } catch (const FirmwareError& x) {
              // The place `dpc31 run` names: the scenario while the stations start, then the
              // step ("x.scn:4: startup: station 6: firmware BAD: …"), as Scenario.run's.
              raise_firmware(out.firmware_place(), x.what());
            }
            // Nothing is written unless the run ended (as `dpc31 run`).
            if (out.ended()) check_output(out.write(e), e);
            return r;
          },
          py::kw_only(), py::arg("vcd") = py::none(), py::arg("fst") = py::none(),
          py::arg("pcapng") = py::none(), py::arg("signals") = std::vector<std::string>{},
          "Plays it as `dpc31 run` does; `vcd`, `fst`, `pcapng` write its waveforms and the "
          "pcapng of its line as `dpc31 run --vcd` / `--fst` / `--pcap` do.");
}

}  // namespace

void bind_segment(py::module_& m) {
  bind_line(m);
  bind_station(m);
  bind_segment_class(m);
  bind_seg_master(m);
  bind_segment_scenario(m);
}

}  // namespace dpc31::py_bind
