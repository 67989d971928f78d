// dpc31.Master (with its DPV1 services), dpc31.Firmware, dpc31.Responder, dpc31.Scenario and
// dpc31.wavediff in Python
// (docs/python.md): the session layer (session/*.hpp, installed as <dpc31/session/...>) and
// lib/wavediff's compare(), one call for one call.
#include <fmt/format.h>
#include <pybind11/operators.h>

#include <memory>
#include <thread>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "bind.hpp"
#include "cpu51_module.hpp"
#include "dp_master.hpp"
#include "dpv1_master.hpp"
#include "firmware_host.hpp"
#include "responder.hpp"
#include "scenario.hpp"
#include "scenario_lex.hpp"
#include "vocabulary.hpp"
#include "wavediff.hpp"

namespace dpc31::py_bind {

UartFault fault_of(const std::optional<std::string>& kind, std::optional<int> char_index) {
  UartFault f;
  if (!kind) {
    if (char_index) {
      throw py::value_error("fault_char without fault: name the fault (parity, start, stop)");
    }
    return f;
  }
  if (!parse_fault_kind(*kind, f.kind)) {
    throw py::value_error("fault '" + *kind + "': expected one of parity, start, stop");
  }
  if (char_index && *char_index < 0) {
    throw py::value_error("fault_char=" + std::to_string(*char_index) +
                          ": the telegram's characters count from 0 (the SD)");
  }
  f.char_index = char_index.value_or(-1);  // the last character (place_fault, vocabulary.hpp)
  return f;
}

std::vector<std::uint8_t> sendable(const fdl::Frame& f) {
  std::vector<std::uint8_t> out;
  if (!fdl::encode(f, out)) throw py::value_error(fdl::encode_refusal(f));
  return out;
}

namespace {

using U8 = std::uint8_t;
using U64 = std::uint64_t;

// A class bound without a keyword constructor gets one: T() with each keyword set as an
// attribute (an unknown keyword is an AttributeError).
template <typename T>
T with_kwargs(const py::kwargs& kw) {
  py::object o = py::cast(T{});
  for (const auto& [k, v] : kw) py::setattr(o, k, v);
  return o.cast<T>();
}

template <typename T, typename M>
auto bytes_property(M T::*member) {
  return std::make_pair([member](const T& t) { return to_bytes(t.*member); },
                        [member](T& t, const py::bytes& b) { t.*member = from_bytes(b); });
}

// A SlaveConfig field as a scenario's `slave` line takes it (vocabulary.hpp), else a ValueError
// naming it in the parser's words: a number in its range, up to `max` bytes (one at least).
template <typename F>
auto number_field(F SlaveConfig::*member, const ValueRange& r) {
  return std::make_pair(
      [member](const SlaveConfig& c) { return c.*member; },
      [member, &r](SlaveConfig& c, std::int64_t v) { c.*member = in_range<F>(r, v); });
}
auto bytes_field(std::vector<U8> SlaveConfig::*member, const char* what, bool non_empty,
                 std::size_t max) {
  return std::make_pair([member](const SlaveConfig& c) { return to_bytes(c.*member); },
                        [member, what, non_empty, max](SlaveConfig& c, const py::bytes& b) {
                          std::vector<U8> v = from_bytes(b);
                          if (non_empty && v.empty())
                            throw py::value_error(fmt::format("{}: at least one byte", what));
                          if (v.size() > max)
                            throw py::value_error(fmt::format("{}: more than {} bytes", what, max));
                          c.*member = std::move(v);
                        });
}

void bind_frames(py::module_& m) {
  py::class_<fdl::Frame>(m, "Frame", "An FDL telegram (include/dpc31/fdl.hpp).")
      .def(py::init([](std::int64_t da, std::int64_t sa, std::int64_t fc, const py::bytes& du,
                       std::optional<std::int64_t> dsap, std::optional<std::int64_t> ssap) {
             const auto sap = [](const char* what, const std::optional<std::int64_t>& v) {
               return v ? std::optional<U8>(byte_value(what, *v)) : std::nullopt;
             };
             return fdl::make_frame(byte_value("da", da), byte_value("sa", sa),
                                    byte_value("fc", fc), from_bytes(du), sap("dsap", dsap),
                                    sap("ssap", ssap));
           }),
           py::arg("da"), py::arg("sa"), py::arg("fc"), py::arg("du") = py::bytes(),
           py::arg("dsap") = py::none(), py::arg("ssap") = py::none())
      .def_readwrite("sd", &fdl::Frame::sd)
      .def_readwrite("da", &fdl::Frame::da)
      .def_readwrite("sa", &fdl::Frame::sa)
      .def_readwrite("fc", &fdl::Frame::fc)
      .def_readwrite("dsap", &fdl::Frame::dsap)
      .def_readwrite("ssap", &fdl::Frame::ssap)
      .def_property("du", bytes_property(&fdl::Frame::du).first,
                    bytes_property(&fdl::Frame::du).second)
      .def("encode", [](const fdl::Frame& f) { return to_bytes(sendable(f)); })
      .def_property_readonly("service", [](const fdl::Frame& f) { return service_name(f); })
      .def(py::self == py::self)
      .def("__repr__", [](const fdl::Frame& f) {
        return "<Frame " + service_name(f) + " da=" + std::to_string(f.da) +
               " sa=" + std::to_string(f.sa) + ">";
      });
  py::class_<Exchange>(m, "Exchange", "One request of the master and the answer it got.")
      .def_readonly("request", &Exchange::request)
      .def_readonly("request_start", &Exchange::request_start)
      .def_readonly("request_end", &Exchange::request_end)
      .def_readonly("answer", &Exchange::answer)
      .def_readonly("stray", &Exchange::stray)
      .def_readonly("answer_start", &Exchange::answer_start)
      .def_readonly("answer_end", &Exchange::answer_end)
      .def_readonly("wait_end", &Exchange::wait_end);
  py::class_<MasterCounters>(m, "MasterCounters")
      .def_readonly("requests", &MasterCounters::requests)
      .def_readonly("answered", &MasterCounters::answered)
      .def_readonly("no_answer", &MasterCounters::no_answer)
      .def_readonly("bad_answer", &MasterCounters::bad_answer)
      .def_readonly("noise", &MasterCounters::noise);
  py::class_<SlaveConfig>(m, "SlaveConfig", "The slave as the master parameterises it.")
      .def(py::init(&with_kwargs<SlaveConfig>))
      .def_property(
          "address", [](const SlaveConfig& c) { return c.address; },
          [](SlaveConfig& c, std::int64_t a) { c.address = in_range<U8>(kSlaveAddress, a); })
      .def_property("ident", number_field(&SlaveConfig::ident, kIdent).first,
                    number_field(&SlaveConfig::ident, kIdent).second)
      .def_property("cfg", bytes_field(&SlaveConfig::cfg, "cfg", true, fdl::kMaxDpData).first,
                    bytes_field(&SlaveConfig::cfg, "cfg", true, fdl::kMaxDpData).second)
      .def_property("in_len", number_field(&SlaveConfig::in_len, kInLen).first,
                    number_field(&SlaveConfig::in_len, kInLen).second)
      .def_property("out_len", number_field(&SlaveConfig::out_len, kOutLen).first,
                    number_field(&SlaveConfig::out_len, kOutLen).second)
      .def_readwrite("wd_on", &SlaveConfig::wd_on)
      .def_property("wd_fact1", number_field(&SlaveConfig::wd_fact1, kWdFactor1).first,
                    number_field(&SlaveConfig::wd_fact1, kWdFactor1).second)
      .def_property("wd_fact2", number_field(&SlaveConfig::wd_fact2, kWdFactor2).first,
                    number_field(&SlaveConfig::wd_fact2, kWdFactor2).second)
      .def_readwrite("wd_base_1ms", &SlaveConfig::wd_base_1ms)
      .def_property("group_ident", number_field(&SlaveConfig::group_ident, kGroupIdent).first,
                    number_field(&SlaveConfig::group_ident, kGroupIdent).second)
      .def_readwrite("sync_req", &SlaveConfig::sync_req)
      .def_readwrite("freeze_req", &SlaveConfig::freeze_req)
      .def_property("min_tsdr", number_field(&SlaveConfig::min_tsdr, kMinTsdr).first,
                    number_field(&SlaveConfig::min_tsdr, kMinTsdr).second)
      .def_property(
          "user_prm",
          bytes_field(&SlaveConfig::user_prm, "user_prm", false, fdl::kMaxDpData - 7).first,
          bytes_field(&SlaveConfig::user_prm, "user_prm", false, fdl::kMaxDpData - 7).second);
  py::class_<MasterSlave, SlaveConfig>(m, "MasterSlave",
                                       "A copy of the slave a master parameterises (Master.slave, "
                                       "SegmentMaster.slave, Station.slave): read-only.")
      .def("__setattr__", [](const MasterSlave& s, const std::string& name, const py::object&) {
        throw py::attribute_error(fmt::format(
            "{} is a read-only copy: setting its {} would change nothing the master sends; give "
            "the slave as {}",
            s.owner, name, s.given));
      });
}

// The run each user side runs with, by its address: every Firmware and Responder is made by a
// binding that gives it to a chip or segment at once. Read and written with the GIL held.
std::unordered_map<const void*, std::weak_ptr<const RunState>>& user_side_runs() {
  static std::unordered_map<const void*, std::weak_ptr<const RunState>> runs;
  return runs;
}

}  // namespace

void user_side_runs_with(const void* user_side, const std::shared_ptr<const RunState>& run) {
  auto& runs = user_side_runs();
  std::erase_if(runs, [](const auto& e) { return e.second.expired(); });
  runs[user_side] = run;
}

void enter_user_side(const void* user_side, bool changes) {
  const auto& runs = user_side_runs();
  const auto it = runs.find(user_side);
  if (it == runs.end()) return;
  if (const std::shared_ptr<const RunState> run = it->second.lock()) {
    enter_run(*run, changes, "user side", "outputs, interrupts, port, ...",
              "take or change what its ISR uses");
  }
}

namespace {

// A user side's records as Python sees them: copies (a list that referred into the user side's
// own vector pointed into freed memory once the ISR appended or keep_last_output() forgot).
template <typename UserSide>
std::vector<std::pair<U64, std::uint16_t>> interrupt_list(const UserSide& u) {
  enter_user_side(&u, false);
  return u.interrupts;
}

// ... handed over and forgotten: `interrupts` grows for as long as the user side runs, and each
// read of it converts every record.
template <typename UserSide>
std::vector<std::pair<U64, std::uint16_t>> take_interrupts(UserSide& u) {
  enter_user_side(&u, true);
  return std::exchange(u.interrupts, {});
}
constexpr const char* kTakeInterruptsDoc =
    "Returns interrupts (cycle, Int_Reg at each ISR entry) and forgets them: a long loop calls "
    "it, so memory stays flat; interrupts then holds only the ISR entries since.";

// A firmware's port writes as Python sees them: (cycle, port name, value).
py::list port_write_list(const FirmwareHost& f, const std::vector<FirmwareHost::PortWrite>& ws) {
  py::list l;
  for (const FirmwareHost::PortWrite& w : ws) {
    l.append(py::make_tuple(w.cycle, f.port_name(w.port), w.value));
  }
  return l;
}

// A Responder's counter, looked at.
template <std::uint32_t Responder::*Counter>
std::uint32_t counter(const Responder& r) {
  enter_user_side(&r, false);
  return r.*Counter;
}

// The user side a master's chip runs: a firmware (built-in or plug-in) or the built-in responder.
void bind_user_side(py::module_& m) {
  py::class_<FirmwareHost, std::shared_ptr<FirmwareHost>>(
      m, "Firmware", "A C firmware (built-in DO4 / CNT2, or a plug-in .so) on the host CPU.")
      .def_property_readonly("name",
                             [](const FirmwareHost& f) { return std::string(f.firmware().name); })
      .def(
          "port",
          [](const FirmwareHost& f, const std::string& name) {
            enter_user_side(&f, false);
            const std::int64_t v = f.port(name);
            // A scenario's `expect port` words; hw_input raises for an unknown name too.
            if (v < 0) {
              throw py::value_error(fmt::format("unknown port '{}' of {} ({})", name,
                                                f.firmware().name,
                                                scenario_lex::name_list(f.firmware().ports)));
            }
            return v;
          },
          py::arg("name"),
          "A port's current value (0 before its first write); ValueError for an unknown name")
      .def_property_readonly("port_writes",
                             [](const FirmwareHost& f) {
                               enter_user_side(&f, false);
                               return port_write_list(f, f.port_writes());
                             })
      .def(
          "take_port_writes",
          [](FirmwareHost& f) {
            enter_user_side(&f, true);
            return port_write_list(f, f.take_port_writes());
          },
          "Returns port_writes (cycle, port, value) and forgets them: a long loop calls it, so "
          "memory stays flat; port_writes then holds only the writes since.")
      .def_property_readonly("interrupts", interrupt_list<FirmwareHost>)
      .def("take_interrupts", take_interrupts<FirmwareHost>, kTakeInterruptsDoc)
      .def(
          "hw_input",
          [](FirmwareHost& f, const std::string& name, std::uint32_t value) {
            // From an observer: an input pin that changes at that cycle, as the firmware's own
            // hw_input takes it between two of its accesses.
            enter_user_side(&f, false);
            const std::string why = f.hw_input(name, value);
            if (!why.empty()) throw py::value_error(why);
          },
          py::arg("name"), py::arg("value"));
  py::class_<Responder::Output>(m, "Output")
      .def_readonly("cycle", &Responder::Output::cycle)
      .def_property_readonly("data", [](const Responder::Output& o) { return to_bytes(o.data); })
      .def_readonly("cleared", &Responder::Output::cleared);
  py::class_<Responder, std::shared_ptr<Responder>>(
      m, "Responder", "The minimal built-in user side (session/responder.hpp).")
      .def_property(
          "inputs",
          [](const Responder& r) {
            enter_user_side(&r, false);
            return to_bytes(r.inputs());
          },
          [](Responder& r, const py::bytes& b) {
            enter_user_side(&r, true);
            r.set_inputs(from_bytes(b));
          })
      .def_property_readonly(
          "outputs",
          [](const Responder& r) {
            enter_user_side(&r, false);
            return r.outputs;
          },
          "every fetch of new outputs since the last keep_last_output() (copies)")
      .def(
          "keep_last_output",
          [](Responder& r) {
            enter_user_side(&r, true);
            r.keep_last_output();
          },
          "Forgets every fetch in outputs but the last: a long loop calls it, so memory stays "
          "flat.")
      .def_property_readonly("interrupts", interrupt_list<Responder>)
      .def("take_interrupts", take_interrupts<Responder>, kTakeInterruptsDoc)
      .def_property_readonly("prm_accepted", counter<&Responder::prm_accepted>)
      .def_property_readonly("cfg_accepted", counter<&Responder::cfg_accepted>)
      .def_property_readonly("cfg_rejected", counter<&Responder::cfg_rejected>);
}

// DPV1 is modelled on the VPC3+ only (a scenario refuses `record`, `dpv1` and the DPV1 actions
// on another profile at its parse): a ValueError naming the chip's, before anything is sent.
void no_dpv1_but_on_vpc3plus(const Chip& chip, std::string_view what) {
  if (chip.profile().id != Profile::vpc3plus) {
    throw py::value_error(fmt::format("{} need a vpc3plus, not a {}: {}", what,
                                      profile_name(chip.profile().id), kDpv1OnVpc3plusOnly));
  }
}

using RecordArg = std::tuple<py::int_, py::int_, py::bytes>;

// run_responder's records=: (slot, index, data) each, as a scenario's `record` lines take them;
// a ValueError in their words, after the record's place in the list.
std::vector<Dpv1Record> dpv1_records(const std::vector<RecordArg>& given) {
  std::vector<Dpv1Record> out;
  for (const auto& [slot, index, data] : given) {
    const std::string at = fmt::format("records[{}]: ", out.size());
    try {
      Dpv1Record r{in_range<U8>(kRecordSlot, slot), in_range<U8>(kRecordIndex, index),
                   from_bytes(data)};
      if (r.data.size() > kRecordLength.max)
        throw py::value_error(fmt::format("data: more than {} bytes", kRecordLength.max));
      for (const Dpv1Record& o : out) {
        if (o.slot == r.slot && o.index == r.index)
          throw py::value_error(fmt::format("slot={} index={} given twice", r.slot, r.index));
      }
      out.push_back(std::move(r));
    } catch (const py::value_error& e) {
      throw py::value_error(at + e.what());
    }
  }
  return out;
}

// An 80C32 beside the chip, or the DPC31's C31 (session/cpu51_board.hpp, docs/cpu.md): it keeps
// the chip alive.
struct PyBoard {
  PyBoard(py::object chip_obj, const py::int_& clock_hz, std::optional<std::uint16_t> address,
          std::optional<std::uint16_t> code)
      : chip_ref(std::move(chip_obj)), chip(class_arg<PyChip>(chip_ref, "chip", "a dpc31.Chip")) {
    // A scenario's `cpu clock=` range.
    const auto hz = in_range<std::uint32_t>(named(kCpuClock, "hz"), clock_hz);
    cfg.hz = hz;
    cfg.c31 = code.has_value();
    if (code) cfg.code = *code;
    // An 80C32's set-ups that cannot work (the Motorola bus, behind the C31's controller): the
    // scenario's, bridge's and serve's one check. The C31's board checks its own chip.
    ChipOptions on;
    on.bus = chip.chip.bus_mode();
    on.irq_controller = chip.chip.irq_controller();
    if (const std::string why = cfg.chip_problem(on); !code && !why.empty())
      throw py::value_error(why);
    chip.enter(true);
    try {
      board = code ? std::make_unique<Cpu51Board>(chip.chip, hz, Cpu51Board::C31{*code})
                   : std::make_unique<Cpu51Board>(chip.chip, hz, *address);
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
  }
  py::object chip_ref;
  PyChip& chip;
  std::unique_ptr<Cpu51Board> board;
  Cpu51Config cfg;  // what load_hex checks the image against

  void run_until(std::uint64_t cycle) {
    while (chip.chip.cycle() < cycle && !chip.chip.stop_requested()) board->run_until(cycle);
  }
};

// P0..P3: the core masks the number (port_latch), so a larger one would be another port's; a
// negative one is no port either.
unsigned port_index(std::int64_t n) {
  if (n < 0 || n > 3) throw py::index_error(fmt::format("no port {} (0..3: P0..P3)", n));
  return static_cast<unsigned>(n);
}

void bind_board(py::module_& m) {
  py::class_<PyBoard>(m, "Cpu51Board",
                      "An 80C32 beside the chip (its XDATA window at `address`, X/INT on INT0), "
                      "or the DPC31's C31 (Cpu51Board.c31); docs/cpu.md.")
      .def(py::init([](py::object chip, const py::int_& hz, const py::int_& address) {
             return std::make_unique<PyBoard>(
                 std::move(chip), hz,
                 in_range<std::uint16_t>(named(kBoardBase, "address"), address), std::nullopt);
           }),
           py::arg("chip").none(true), py::arg("hz") = 24'000'000, py::arg("address") = 0x8000)
      .def_static(
          "c31",
          [](py::object chip, const py::int_& hz, const py::int_& code) {
            return std::make_unique<PyBoard>(std::move(chip), hz, std::nullopt,
                                             in_range<std::uint16_t>(kC31Code, code));
          },
          py::arg("chip").none(true), py::arg("hz") = 24'000'000, py::arg("code") = 0x1000,
          "The DPC31's C31: code from the chip's RAM at `code`, XDATA the chip's own space, INT0 "
          "its interrupt controller (the chip made with irq_controller='c31'); docs/dpc31.md.")
      .def(
          "load_hex",
          [](PyBoard& b, const std::string& path) {
            b.chip.enter(true);
            Cpu51Config cfg = b.cfg;
            cfg.hex = read_path_arg(path, "path");
            Cpu51Image image;
            std::string why;
            if (!load_cpu51_image(cfg, image, why)) raise(errors().input, why);
            if (cfg.c31) {
              b.board->load_c31_code(image.code, image.used);  // fits: checked by the load
            } else {
              b.board->cpu().load_code(0, image.code);
            }
            return image.size;
          },
          py::arg("path"),
          "Loads an Intel HEX image (SDCC's, Keil's) as program memory; InputError 'FILE:LINE: "
          "reason' for a bad record. Returns the bytes it gives.")
      .def(
          "run_until", [](PyBoard& b, U64 cycle) { b.chip.run([&] { b.run_until(cycle); }); },
          py::arg("cycle"),
          "Runs CPU and chip together until the chip's cycle is at least `cycle` (the CPU's "
          "step in progress ends).")
      .def(
          "port",
          [](const PyBoard& b, std::int64_t n) { return b.board->cpu().port_latch(port_index(n)); },
          py::arg("n"), "Port n's latch (0..3: P0..P3).")
      .def(
          "pins",
          [](const PyBoard& b, std::int64_t n) { return b.board->cpu().port_pins(port_index(n)); },
          py::arg("n"), "Port n's pins: the latch AND what the outside drives.")
      .def(
          "set_port_input",
          [](PyBoard& b, std::int64_t n, U8 value) {
            b.chip.enter(true);
            b.board->cpu().set_port_input(port_index(n), value);
          },
          py::arg("n"), py::arg("value"), "What the outside drives on port n (an address switch).")
      .def(
          "xdata", [](const PyBoard& b, std::uint16_t addr) { return b.board->ram(addr); },
          py::arg("addr"), "A byte of the board's RAM (XDATA outside the chip's window).")
      .def(
          "on_ram_write",
          [](PyBoard& b, py::function f) {
            b.board->on_ram_write = b.chip.observer<std::uint16_t, std::uint8_t, U64>(
                std::move(f),
                [](py::object& fn, std::uint16_t a, std::uint8_t v, U64 c) { fn(a, v, c); });
          },
          py::arg("callback"),
          "callback(addr, value, cycle) for every write to the board's RAM (an output latch), "
          "with the chip cycle its strobe ends.")
      .def(
          "on_serial",
          [](PyBoard& b, py::function f) {
            const auto serial = b.chip.observer<std::uint8_t, U64>(
                std::move(f), [](py::object& fn, std::uint8_t d, U64 c) { fn(d, c); });
            Cpu51Board& board = *b.board;
            board.cpu().on_serial_tx = [serial, &board](std::uint8_t d, bool, U64 machine_cycle) {
              serial(d, board.chip_cycle_of(machine_cycle * mcs51::clocks_per_cycle));
            };
          },
          py::arg("callback"),
          "callback(data, cycle) for every character the CPU's serial port sends (SBUF), with "
          "the chip cycle its TI is set (docs/cpu.md, \"Serial port\").")
      .def(
          "chip_cycle_of",
          [](const PyBoard& b, U64 clock) { return b.board->chip_cycle_of(clock); },
          py::arg("cpu_clock"), "The chip cycle of a CPU oscillator clock counted from reset.")
      .def_property_readonly("pc", [](const PyBoard& b) { return b.board->cpu().pc(); })
      .def_property_readonly("a", [](const PyBoard& b) { return b.board->cpu().a(); })
      .def_property_readonly("b", [](const PyBoard& b) { return b.board->cpu().b(); })
      .def_property_readonly("psw", [](const PyBoard& b) { return b.board->cpu().psw(); })
      .def_property_readonly("sp", [](const PyBoard& b) { return b.board->cpu().sp(); })
      .def_property_readonly("dptr", [](const PyBoard& b) { return b.board->cpu().dptr(); })
      .def_property_readonly("machine_cycles",
                             [](const PyBoard& b) { return b.board->cpu().cycles(); })
      .def_property_readonly("in_service",
                             [](const PyBoard& b) { return b.board->cpu().in_service(); })
      .def_property_readonly("chip", [](const PyBoard& b) { return b.chip_ref; });
}

// The built-in DP master on one chip's wire. It keeps the chip (and the user side) alive.
struct PyMaster {
  PyMaster(py::object chip_obj, const MasterConfig& mc, const SlaveConfig& sc)
      : chip_ref(std::move(chip_obj)),
        chip(chip_ref.cast<PyChip&>()),
        config(mc),
        m(std::make_unique<DpMaster>(chip.chip, mc, sc)) {
    ends_at_observer_error();
  }
  py::object chip_ref;
  PyChip& chip;
  MasterConfig config;
  std::unique_ptr<DpMaster> m;
  std::shared_ptr<FirmwareHost> firmware;
  std::shared_ptr<Responder> responder;
  py::object board;  // run_board's Cpu51Board
  Dpv1Rules dpv1_rules;
  std::unique_ptr<Dpv1Master> dpv1_m;  // on `m`: made at the first DPV1 service

  // A DPV1 service of the master (session/dpv1_master.hpp), with the rules as Python set them.
  template <typename F>
  Dpv1Answer dpv1(F&& f) {
    no_dpv1_but_on_vpc3plus(chip.chip, "DPV1 services");
    if (!dpv1_m) dpv1_m = std::make_unique<Dpv1Master>(chip.chip, *m, dpv1_rules);
    dpv1_m->rules() = dpv1_rules;
    return act([&] { return f(*dpv1_m); });
  }

  template <typename F>
  auto act(F&& f) {
    return chip.run(std::forward<F>(f));
  }
  // An observer's exception ends the master's call after the wait it stopped (docs/python.md,
  // "The GIL"): the master clears the chip's stop after each wait and would go on.
  void ends_at_observer_error() {
    m->waited = [this] {
      if (chip.error) throw ObserverStopped{};
    };
  }
  // The user side sets the chip up before the master's first request, and the master counts
  // its bus idle from then on, as in a scenario (session/scenario_run.cpp): it is made anew.
  template <typename Init>
  void start_user_side(const SlaveConfig& slave, Init&& init) {
    if (firmware || responder || board || m->counters().requests != 0) {
      raise(errors().error,
            "the user side starts once, before the master's first request (docs/python.md)");
    }
    act([&] {
      DirectBus bus(chip.chip);
      init(bus);
    });
    dpv1_m.reset();  // it holds the master
    m = std::make_unique<DpMaster>(chip.chip, config, slave);
    ends_at_observer_error();
  }
};

// A Read (MSAC_C1 or on the connection) and a service with record data (Write, Data_Transport):
// one binding per Dpv1Master member.
// Slot, index, length and data in the scenario's ranges (vocabulary.hpp).
template <Dpv1Answer (Dpv1Master::*Read)(U8, U8, U8)>
Dpv1Answer read_record(PyMaster& pm, std::int64_t slot, std::int64_t index, std::int64_t length) {
  const auto s = in_range<U8>(kRecordSlot, slot);
  const auto i = in_range<U8>(kRecordIndex, index);
  const auto n = in_range<U8>(kRecordLength, length);
  return pm.dpv1([&](Dpv1Master& d) { return (d.*Read)(s, i, n); });
}
template <Dpv1Answer (Dpv1Master::*Send)(U8, U8, pdu::Bytes)>
Dpv1Answer send_record(PyMaster& pm, std::int64_t slot, std::int64_t index, const py::bytes& data) {
  const auto s = in_range<U8>(kRecordSlot, slot);
  const auto i = in_range<U8>(kRecordIndex, index);
  pdu::Bytes v = from_bytes(data);
  if (v.size() > kRecordLength.max)
    throw py::value_error(fmt::format("data: more than {} bytes", kRecordLength.max));
  return pm.dpv1([&](Dpv1Master& d) { return (d.*Send)(s, i, std::move(v)); });
}

// The master's DPV1 services (docs/dpv1.md, "The master's side"), one call for one call of
// Dpv1Master; each runs the chip until the response, the time-out or no answer.
void bind_dpv1(py::module_& m, py::class_<PyMaster>& master) {
  using O = Dpv1Answer::Outcome;
  py::enum_<O>(m, "Dpv1Outcome")
      .value("positive", O::positive)
      .value("negative", O::negative)
      .value("refused", O::refused)
      .value("no_answer", O::no_answer)
      .value("timeout", O::timeout)
      .value("malformed", O::malformed)
      .value("no_connection", O::no_connection);
  py::class_<Dpv1Rules>(m, "Dpv1Rules", "The master's DPV1 rules (retries, time-out, C2 SAP).")
      .def(py::init(&with_kwargs<Dpv1Rules>))
      .def_property(
          "retries", [](const Dpv1Rules& r) { return r.retries; },
          [](Dpv1Rules& r, const py::int_& v) { r.retries = in_range<std::uint32_t>(kRetries, v); })
      .def_property(
          "c1_response_timeout", [](const Dpv1Rules& r) { return r.c1_response_timeout; },
          [](Dpv1Rules& r, const py::int_& v) {
            // The scenario's `dpv1 c1_timeout=` range, under the property's name.
            r.c1_response_timeout =
                in_range<std::uint16_t>(named(kC1Timeout, "c1_response_timeout"), v);
          })
      .def_property(
          "c2_ssap", [](const Dpv1Rules& r) { return r.c2_ssap; },
          [](Dpv1Rules& r, const py::int_& v) { r.c2_ssap = in_range<U8>(kC2Ssap, v); });
  py::class_<Dpv1Answer>(m, "Dpv1Answer", "What a DPV1 service got (session/dpv1_master.hpp).")
      .def_readonly("outcome", &Dpv1Answer::outcome)
      .def_property_readonly("du", [](const Dpv1Answer& a) { return to_bytes(a.du); })
      .def_property_readonly("error",
                             [](const Dpv1Answer& a) -> std::optional<py::tuple> {
                               if (!a.error) return std::nullopt;
                               return py::make_tuple(a.error->error_decode, a.error->error_code_1,
                                                     a.error->error_code_2);
                             })
      .def_readonly("last", &Dpv1Answer::last)
      .def_readonly("polls", &Dpv1Answer::polls)
      .def_readonly("start", &Dpv1Answer::start)
      .def_readonly("end", &Dpv1Answer::end)
      .def("__repr__",
           [](const Dpv1Answer& a) { return "<Dpv1Answer " + answer_summary(a) + ">"; });
  master
      .def_property(
          // The master's own rules (def_property: reference_internal, the master kept alive):
          // `master.dpv1_rules.c1_response_timeout = 1` reaches the next service.
          "dpv1_rules", [](PyMaster& pm) -> Dpv1Rules& { return pm.dpv1_rules; },
          [](PyMaster& pm, const Dpv1Rules& r) { pm.dpv1_rules = r; })
      .def_property_readonly(
          "c2_sap",
          [](const PyMaster& pm) { return pm.dpv1_m ? pm.dpv1_m->c2_sap() : std::nullopt; })
      .def("dpv1_read", &read_record<&Dpv1Master::read>, py::arg("slot"), py::arg("index"),
           py::arg("length"), "MSAC_C1 Read (SAP 51 -> 51), polled until the response")
      .def("dpv1_write", &send_record<&Dpv1Master::write>, py::arg("slot"), py::arg("index"),
           py::arg("data"), "MSAC_C1 Write")
      .def(
          "alarm_ack",
          [](PyMaster& pm, std::int64_t slot, std::int64_t alarm_type, U8 specifier,
             std::int64_t sap) {
            const pdu::AlarmAck ack{in_range<U8>(kRecordSlot, slot),
                                    in_range<U8>(kAlarmType, alarm_type), specifier};
            const auto dsap = in_range<U8>(kAlarmSap, sap);
            return pm.dpv1([&](Dpv1Master& d) { return d.alarm_ack(ack, dsap); });
          },
          py::arg("slot"), py::arg("alarm_type"), py::arg("specifier"),
          py::arg("sap") = sap::MSAC_C1_Alarm,
          "MSAC_C1 Alarm_Ack (SAP 51 -> 50, or -> 51 with sap=51: the slave's SAP 50 or 51); "
          "specifier = Seq_Nr << 3 | Add_Ack << 2 | bits 1..0")
      .def(
          "c2_initiate",
          [](PyMaster& pm, std::int64_t send_timeout, std::uint16_t features_supported) {
            pdu::Initiate req;
            req.send_timeout = in_range<std::uint16_t>(kSendTimeout, send_timeout);
            req.features_supported = features_supported;
            return pm.dpv1([&](Dpv1Master& d) { return d.initiate(req); });
          },
          py::arg("send_timeout") = 100, py::arg("features_supported") = 1,
          "MSAC_C2 Initiate to SAP 49, then the connection's SAP polled for its response")
      .def("c2_read", &read_record<&Dpv1Master::c2_read>, py::arg("slot"), py::arg("index"),
           py::arg("length"))
      .def("c2_write", &send_record<&Dpv1Master::c2_write>, py::arg("slot"), py::arg("index"),
           py::arg("data"))
      .def("c2_transport", &send_record<&Dpv1Master::c2_transport>, py::arg("slot"),
           py::arg("index"), py::arg("data"))
      .def("c2_idle",
           [](PyMaster& pm) { return pm.dpv1([](Dpv1Master& d) { return d.c2_idle(); }); })
      .def(
          "c2_abort",
          [](PyMaster& pm, std::int64_t reason, std::int64_t instance) {
            const pdu::Abort a{0, in_range<U8>(kAbortInstance, instance),
                               in_range<U8>(kAbortReason, reason), 0};
            return pm.dpv1([&](Dpv1Master& d) { return d.c2_abort(a); });
          },
          py::arg("reason") = 0, py::arg("instance") = 2,
          "MSAC_C2 Abort on the open connection (Instance 2: the user)");
}

void bind_master(py::module_& m) {
  py::class_<PyMaster> master(m, "Master",
                              "The built-in DP master (class 1) on a chip's RxD/TxD (DpMaster).");
  master
      .def(py::init([](py::object chip, std::int64_t address, std::uint32_t baud,
                       std::int64_t slot_bits, std::int64_t idle_bits,
                       const std::optional<SlaveConfig>& slave) {
             // The checks of a scenario's `baud` and `master address= slot= idle=`; a bit at
             // least one clock of the chip (as a Segment's).
             PyChip& c = class_arg<PyChip>(chip, "chip", "a dpc31.Chip");
             const std::uint32_t rate = profibus_rate(baud);
             one_clock_a_bit(c.chip.clock_hz(), rate);
             const MasterConfig mc{in_range<U8>(kMasterAddress, address), rate,
                                   in_range<std::uint32_t>(kSlotBits, slot_bits),
                                   in_range<std::uint32_t>(kIdleBits, idle_bits)};
             const SlaveConfig sc = slave.value_or(SlaveConfig{});
             if (sc.wd_base_1ms && c.chip.profile().id == Profile::vpc3plus &&
                 (sc.user_prm.empty() || (sc.user_prm[0] & dpv1::status1::DPV1_Enable) == 0)) {
               throw py::value_error(wd_base_needs_dpv1("wd_base_1ms=True"));
             }
             c.enter(true);
             return std::make_unique<PyMaster>(std::move(chip), mc, sc);
           }),
           py::arg("chip").none(true), py::arg("address") = 2, py::arg("baud") = 1'500'000,
           py::arg("slot_bits") = 100, py::arg("idle_bits") = 33, py::arg("slave") = py::none())
      .def(
          "run_firmware",
          [](PyMaster& pm, const std::string& spec, bool gsd_defaults) {
            const dpc31_firmware& d = find_firmware(path_arg(spec, "firmware"));
            const SlaveConfig slave =
                gsd_defaults ? with_gsd_defaults(d, pm.m->slave()) : pm.m->slave();
            auto fw = std::make_shared<FirmwareHost>(d);
            pm.start_user_side(slave, [&](BusPort& bus) { fw->init(bus, slave.address); });
            pm.m->set_firmware(fw->program());
            user_side_runs_with(fw.get(), pm.chip.run_state());
            pm.firmware = fw;
            return fw;
          },
          py::arg("firmware"), py::arg("gsd_defaults") = true,
          "Runs a firmware (DO4, CNT2 or a plug-in path) on the host CPU: its init now, its ISR "
          "and main loop while the master runs the chip. gsd_defaults: the master's slave takes "
          "the "
          "firmware's Ident, Cfg, lengths and User_Prm (as a scenario's `firmware` line).")
      .def(
          "run_responder",
          [](PyMaster& pm, const py::bytes& inputs, bool sync_supported, bool freeze_supported,
             bool spec_clear_mode, const py::bytes& substitute, bool user_watchdog,
             bool dx_out_port, const std::vector<RecordArg>& records,
             const std::optional<py::int_>& work_cycles,
             const std::optional<py::int_>& wd_baud_control,
             const std::optional<py::int_>& user_wd_value) {
            ResponderConfig rc;
            if (pm.chip.chip.profile().id != Profile::dpc31) {  // as a scenario's `user` line
              if (dx_out_port) throw py::value_error(dx_out_port_is_for_dpc31("dx_out_port="));
              if (py::len(substitute) != 0)
                throw py::value_error(substitute_is_for_dpc31("substitute="));
            }
            // The `user` step's checks (scenario_parse.cpp): its ranges and words.
            if (wd_baud_control)
              rc.wd_baud_control = in_range<U8>(kWdBaudControl, *wd_baud_control);
            if (user_wd_value) {
              rc.user_wd_value = in_range<std::uint16_t>(kUserWdValue, *user_wd_value);
              if (pm.chip.chip.profile().id == Profile::dpc31 && !user_watchdog)
                throw py::value_error(user_wd_value_needs_user_wd("user_wd_value"));
            }
            // A scenario's `record` and `dpv1 work=` lines: the VPC3+'s only, and the time
            // spent on a record only where there is one (no silent options).
            if (!records.empty()) no_dpv1_but_on_vpc3plus(pm.chip.chip, "records");
            rc.dpv1.records = dpv1_records(records);
            if (work_cycles) {
              rc.dpv1.work_cycles =
                  in_range<std::uint64_t>(named(kWorkCycles, "work_cycles"), *work_cycles);
              if (records.empty())
                throw py::value_error("work_cycles: no records to work on (records=)");
            }
            rc.dpv1.c1_master = pm.config.address;  // as a scenario's (scenario_run.cpp)
            rc.slave = pm.m->slave();
            if (const std::string why = records_need_dpv1("records=", rc.slave.user_prm);
                !records.empty() && !why.empty())
              throw py::value_error(why);
            rc.sync_supported = sync_supported;
            rc.freeze_supported = freeze_supported;
            rc.spec_clear_mode = spec_clear_mode;
            rc.substitute = from_bytes(substitute);
            rc.user_watchdog = user_watchdog;
            rc.dx_out_port = dx_out_port;
            auto r = std::make_shared<Responder>(rc);
            r->set_inputs(from_bytes(inputs));
            pm.start_user_side(rc.slave, [&](BusPort& bus) { r->init(bus); });
            pm.m->set_firmware([r](BusPort& b) { r->isr(b); });
            user_side_runs_with(r.get(), pm.chip.run_state());
            pm.responder = r;
            return r;
          },
          py::arg("inputs") = py::bytes(), py::arg("sync_supported") = true,
          py::arg("freeze_supported") = true, py::arg("spec_clear_mode") = true,
          py::arg("substitute") = py::bytes(), py::arg("user_watchdog") = false,
          py::arg("dx_out_port") = false, py::arg("records") = std::vector<RecordArg>{},
          py::arg("work_cycles") = py::none(), py::arg("wd_baud_control") = py::none(),
          py::arg("user_wd_value") = py::none(),
          "Runs the built-in responder (session/responder.hpp) as the user side; on a vpc3plus "
          "it serves `records` [(slot, index, data)] over DPV1, `work_cycles` clocks per request "
          "(a scenario's `record` and `dpv1 work=` lines). wd_baud_control: WD_Baud_Control_Val "
          "(x 10 ms, 0x10 unless given); user_wd_value: R_User_WD_Value (0x1FF unless given; on "
          "a dpc31 only with user_watchdog), as a scenario's `user` line.")
      .def(
          "run_board",
          [](PyMaster& pm, py::object board) {
            PyBoard& b = class_arg<PyBoard>(board, "board", "a dpc31.Cpu51Board");
            if (&b.chip != &pm.chip) raise(errors().error, "the board is on another chip");
            if (pm.firmware || pm.responder || pm.board) {
              raise(errors().error, "the master's chip has a user side already");
            }
            // The board moves time while the master waits, as in a scenario's `cpu` header
            // (session/scenario_run.cpp): its CPU is the user side, from reset.
            pm.m->scheduler = [&b](U64 cycle) { b.run_until(cycle); };
            pm.board = std::move(board);
          },
          py::arg("board").none(true),
          "The CPU of a Cpu51Board is the user side: its image runs while the master runs the "
          "chip.")
      .def_property_readonly("firmware", [](const PyMaster& pm) { return pm.firmware; })
      .def_property_readonly("responder", [](const PyMaster& pm) { return pm.responder; })
      .def_property_readonly("chip", [](const PyMaster& pm) { return pm.chip_ref; })
      .def_property_readonly(
          "slave",
          [](const PyMaster& pm) {
            return MasterSlave{pm.m->slave(), "Master.slave", "Master(slave=SlaveConfig(...))"};
          })
      .def_property_readonly("bit_cycles", [](const PyMaster& pm) { return pm.m->bit_cycles(); })
      .def_property_readonly("counters",
                             [](const PyMaster& pm) {
                               pm.chip.enter(false);  // as the chip's state properties
                               return pm.m->counters();
                             })
      .def_property_readonly("history",
                             [](const PyMaster& pm) {
                               pm.chip.enter(false);  // as the chip's state properties
                               return pm.m->history();
                             })
      .def_property_readonly(
          "locks",
          [](const PyMaster& pm) {
            pm.chip.enter(false);
            return pm.m->locks();
          },
          "{slave address: master address}: a start-up that returned False because its slave is "
          "locked by another master (Slave_Diag's Master_Add) names it here")
      .def("clear_history", [](PyMaster& pm) { pm.m->clear_history(); })
      .def(
          "startup",
          [](PyMaster& pm, const py::int_& tries) {
            const int n = in_range<int>(kTries, tries);
            return pm.act([&] { return pm.m->startup(n); });
          },
          py::arg("tries") = kStartupTries)
      .def(
          "restart",
          [](PyMaster& pm, const py::int_& tries, std::uint32_t retries) {
            const int n = in_range<int>(kTries, tries);
            return pm.act([&] { return pm.m->restart(n, retries); });
          },
          py::arg("tries") = kStartupTries, py::arg("retries") = 1)
      .def(
          "data_exchange",
          [](PyMaster& pm, const py::object& out, const std::optional<std::string>& fault,
             std::optional<int> fault_char) {
            const std::vector<U8> v = bytes_like(out, "outputs");
            const UartFault f = fault_of(fault, fault_char);
            return pm.act([&] { return pm.m->data_exchange(v, f); });
          },
          py::arg("outputs"), py::arg("fault") = py::none(), py::arg("fault_char") = py::none())
      .def(
          "global_control",
          [](PyMaster& pm, U8 command, U8 groups) {
            return pm.act([&] { return pm.m->global_control(command, groups); });
          },
          py::arg("command"), py::arg("groups") = 0)
      .def("slave_diag", [](PyMaster& pm) { return pm.act([&] { return pm.m->slave_diag(); }); })
      .def("fdl_status", [](PyMaster& pm) { return pm.act([&] { return pm.m->fdl_status(); }); })
      .def(
          "set_prm",
          [](PyMaster& pm, U8 extra) { return pm.act([&] { return pm.m->set_prm(extra); }); },
          py::arg("station_status_extra") = 0)
      .def("chk_cfg", [](PyMaster& pm) { return pm.act([&] { return pm.m->chk_cfg(); }); })
      .def("get_cfg", [](PyMaster& pm) { return pm.act([&] { return pm.m->get_cfg(); }); })
      .def("read_inputs", [](PyMaster& pm) { return pm.act([&] { return pm.m->read_inputs(); }); })
      .def("read_outputs",
           [](PyMaster& pm) { return pm.act([&] { return pm.m->read_outputs(); }); })
      .def(
          "set_slave_address",
          [](PyMaster& pm, std::int64_t a, bool no_change) {
            const U8 new_address = in_range<U8>(kNewAddress, a);
            return pm.act([&] { return pm.m->set_slave_address(new_address, no_change); });
          },
          py::arg("new_address"), py::arg("no_add_change") = false)
      .def(
          "transact",
          [](PyMaster& pm, const fdl::Frame& req, const std::optional<std::string>& fault,
             std::optional<int> fault_char) {
            static_cast<void>(sendable(req));
            const UartFault f = fault_of(fault, fault_char);
            return pm.act([&] { return pm.m->transact(req, f); });
          },
          py::arg("request"), py::arg("fault") = py::none(), py::arg("fault_char") = py::none())
      .def(
          "transact_raw",
          [](PyMaster& pm, const py::object& raw, const std::optional<std::string>& fault,
             std::optional<int> fault_char) {
            const std::vector<U8> v = raw_telegram(raw);
            const UartFault f = fault_of(fault, fault_char);
            return pm.act([&] { return pm.m->transact_raw(v, f); });
          },
          py::arg("data"), py::arg("fault") = py::none(), py::arg("fault_char") = py::none())
      .def(
          "idle",
          [](PyMaster& pm, U64 cycles) {
            idle_in_slices(
                pm, cycles, [&] { return pm.chip.chip.cycle(); },
                [&] { return pm.chip.error != nullptr; });
          },
          py::arg("cycles"), "Time passes with a silent bus (cable pulled); the firmware runs.")
      .def(
          "line_noise",
          [](PyMaster& pm, const py::bytes& b, std::uint32_t idle_bits) {
            const std::vector<U8> v = from_bytes(b);
            pm.act([&] { pm.m->line_noise(v, idle_bits); });
          },
          py::arg("data"), py::arg("idle_bits"))
      .def(
          "glitch", [](PyMaster& pm, std::uint32_t low) { pm.act([&] { pm.m->glitch(low); }); },
          py::arg("low_cycles"))
      .def_static("diag_ready", &DpMaster::diag_ready, py::arg("diag_answer"));
  bind_dpv1(m, master);
}

// What a scenario run reports beyond ScenarioOutcome: every expect and step with its cycle.
struct ExpectResult {
  int line;
  std::string text;
  bool ok;
  U64 cycle;
};
struct StepRecord {
  int line;
  std::string text;
  U64 cycle;
};
struct ScenarioResult {
  ScenarioOutcome outcome;
  std::vector<std::string> walk;
  std::vector<ExpectResult> expects;
  std::vector<StepRecord> steps;
};

class Recorder final : public ScenarioObserver {
 public:
  explicit Recorder(ScenarioResult& r) : r_(r) {}
  void step_begins(U64 cycle, const ScenarioStep& st, std::string_view) override {
    r_.steps.push_back({st.line, st.text, cycle});
  }
  void expect_checked(U64 cycle, const ScenarioStep& st, bool ok, std::string_view) override {
    r_.expects.push_back({st.line, st.text, ok, cycle});
  }

 private:
  ScenarioResult& r_;
};

[[noreturn]] void raise_scenario(const ScenarioError& e) {
  raise(errors().scenario, e.text(),
        {{"file", py::str(e.file)}, {"line", py::int_(e.line)}, {"reason", py::str(e.message)}});
}

void bind_scenarios(py::module_& m) {
  py::enum_<StepKind>(m, "StepKind")
      .value("startup", StepKind::startup)
      .value("restart", StepKind::restart)
      .value("exchange", StepKind::exchange)
      .value("gc", StepKind::gc)
      .value("diag", StepKind::diag)
      .value("fdl_status", StepKind::fdl_status)
      .value("set_prm", StepKind::set_prm)
      .value("chk_cfg", StepKind::chk_cfg)
      .value("get_cfg", StepKind::get_cfg)
      .value("read_inputs", StepKind::read_inputs)
      .value("read_outputs", StepKind::read_outputs)
      .value("set_slave_address", StepKind::set_slave_address)
      .value("foreign_master", StepKind::foreign_master)
      .value("silence", StepKind::silence)
      .value("inputs", StepKind::inputs)
      .value("hw", StepKind::hw)
      .value("corrupt", StepKind::corrupt)
      .value("bad_fcs", StepKind::bad_fcs)
      .value("expect", StepKind::expect)
      .value("write", StepKind::write)
      .value("read", StepKind::read)
      .value("send", StepKind::send)
      .value("request", StepKind::request)
      .value("dpv1", StepKind::dpv1);
  py::class_<ScenarioStep>(m, "Step", "One line of a scenario file.")
      .def_readonly("line", &ScenarioStep::line)
      .def_readonly("text", &ScenarioStep::text)
      .def_readonly("kind", &ScenarioStep::kind);
  py::class_<ExpectResult>(m, "ExpectResult",
                           "One expect of a run: its line, text, verdict, cycle.")
      .def_readonly("line", &ExpectResult::line)
      .def_readonly("text", &ExpectResult::text)
      .def_readonly("ok", &ExpectResult::ok)
      .def_readonly("cycle", &ExpectResult::cycle);
  py::class_<StepRecord>(m, "StepRecord", "One step of a run and the cycle it began at.")
      .def_readonly("line", &StepRecord::line)
      .def_readonly("text", &StepRecord::text)
      .def_readonly("cycle", &StepRecord::cycle);
  py::class_<ScenarioResult>(m, "ScenarioResult", "What a scenario run gave (dpc31 run's walk).")
      .def_property_readonly("ok", [](const ScenarioResult& r) { return r.outcome.ok(); })
      .def_property_readonly("final_cycle",
                             [](const ScenarioResult& r) { return r.outcome.final_cycle; })
      .def_property_readonly("dp_state", [](const ScenarioResult& r) { return r.outcome.dp; })
      .def_property_readonly("wd_state", [](const ScenarioResult& r) { return r.outcome.wd; })
      .def_property_readonly("passed", [](const ScenarioResult& r) { return r.outcome.passed; })
      .def_property_readonly("failed", [](const ScenarioResult& r) { return r.outcome.failed; })
      .def_property_readonly("failures", [](const ScenarioResult& r) { return r.outcome.failures; })
      .def_property_readonly(
          "counters", [](const ScenarioResult& r) { return counters_dict(r.outcome.counters); })
      .def_readonly("walk", &ScenarioResult::walk)
      .def_readonly("expects", &ScenarioResult::expects)
      .def_readonly("steps", &ScenarioResult::steps);
  py::class_<Scenario>(m, "Scenario", "A parsed scenario file (docs/scenario-format.md).")
      .def_static(
          "load",
          [](const std::string& path) {
            Scenario s;
            ScenarioError err;
            if (!load_scenario(read_path_arg(path, "path"), s, err)) raise_scenario(err);
            return s;
          },
          py::arg("path"))
      .def_static(
          "parse",
          [](std::string_view text, const std::string& file) {
            Scenario s;
            ScenarioError err;
            if (!parse_scenario(text, path_arg(file, "file"), s, err)) raise_scenario(err);
            return s;
          },
          py::arg("text"), py::arg("file") = "<string>")
      .def_readonly("file", &Scenario::file)
      .def_property_readonly(
          "profile", [](const Scenario& s) { return std::string(profile_name(s.chip.profile)); })
      .def_readonly("firmware", &Scenario::firmware)
      .def_readonly("steps", &Scenario::steps)
      .def_property_readonly("expects",
                             [](const Scenario& s) {
                               std::vector<ScenarioStep> e;
                               for (const ScenarioStep& st : s.steps) {
                                 if (st.kind == StepKind::expect) e.push_back(st);
                               }
                               return e;
                             })
      .def("run", [](const Scenario& s) {
        ScenarioResult r;
        Recorder rec(r);
        ScenarioHooks hooks;
        hooks.observer = &rec;
        // A firmware's fault names its place as `dpc31 run`'s line does: the `firmware` line
        // (its load, its init), then the step it runs in ("x.scn:10: dpv1_read").
        FirmwarePlace place(s.file, s.firmware_line);
        Scenario bound = s;
        if (ScenarioError err; !bind_plugin(bound, err)) {
          // The plug-in's load fails at the `firmware` line; a step naming a port or an input the
          // plug-in has not is the scenario's error, as `dpc31 run` reports it.
          if (err.line != s.firmware_line) raise_scenario(err);
          raise_firmware(place, err.message);
        }
        // A bad 80C32 image is an InputError before anything runs (docs/cpu.md), as in `run`.
        if (std::string why; !check_cpu_image(bound, why)) raise(errors().input, why);
        hooks.at_step = [&place](const ScenarioStep& st) { place.enter(st.line, st.text); };
        try {
          py::gil_scoped_release nogil;
          r.outcome = run_scenario(
              bound, [&](const std::string& l) { r.walk.push_back(l); }, LineSink{}, hooks);
        } catch (const FirmwareError& e) {
          raise_firmware(place, e.what());
        }
        return r;
      });
}

void bind_wavediff(py::module_& m) {
  using namespace wavediff;
  py::class_<Point>(m, "WavePoint")
      .def_readonly("time", &Point::time)
      .def_readonly("time_b", &Point::time_b)
      .def_readonly("cycle", &Point::cycle);
  py::class_<Divergence>(m, "Divergence")
      .def_readonly("at", &Divergence::at)
      .def_readonly("a", &Divergence::a)
      .def_readonly("b", &Divergence::b)
      .def_readonly("last_common", &Divergence::last_common)
      .def_readonly("open", &Divergence::open);
  py::class_<SignalDiff>(m, "SignalDiff", "One signal that differs: how often, and first where.")
      .def_readonly("name", &SignalDiff::name)
      .def_readonly("name_b", &SignalDiff::name_b)
      .def_readonly("count", &SignalDiff::count)
      .def_readonly("first", &SignalDiff::first)
      .def_readonly("last", &SignalDiff::last);
  py::class_<Structural>(m, "Structural")
      .def_readonly("signal", &Structural::signal)
      .def_readonly("what", &Structural::what);
  py::class_<Report>(m, "WaveReport", "The differences of two waveforms (docs/wavediff.md).")
      .def_property_readonly("same", &Report::same)
      .def_readonly("clock_mode", &Report::clock_mode)
      .def_readonly("pow", &Report::pow)
      .def_readonly("edges", &Report::edges)
      .def_readonly("compared", &Report::compared)
      .def_readonly("only_a", &Report::only_a)
      .def_readonly("only_b", &Report::only_b)
      .def_readonly("structural", &Report::structural)
      .def_readonly("diffs", &Report::diffs)
      .def_readonly("warnings", &Report::warnings)
      .def(
          "text", [](const Report& r, unsigned n) { return text_report(r, n); },
          py::arg("max_signals") = 20)
      .def("json", &json_report);
  m.def(
      "wavediff",
      [](const std::string& a, const std::string& b, const std::optional<std::string>& clock,
         const std::optional<std::string>& clock_b, const std::string& strip_a,
         const std::string& strip_b, bool strip_auto, const std::string& map_file,
         std::vector<std::string> include, std::vector<std::string> exclude, bool ignore_missing,
         const std::string& xz, const std::string& diff_vcd, const std::string& edge,
         const std::string& start, const std::string& end, const std::string& tolerance,
         std::uint64_t tolerance_cycles) {
        Options o;
        o.file_a = read_path_arg(a, "a");
        o.file_b = read_path_arg(b, "b");
        o.clock_a = clock.value_or("");
        o.clock_b = clock_b.value_or("");
        o.strip_a = strip_a;
        o.strip_b = strip_b;
        o.strip_auto = strip_auto;
        o.map_file = path_arg(map_file, "map_file");
        o.include = std::move(include);
        o.exclude = std::move(exclude);
        o.ignore_missing = ignore_missing;
        o.diff_vcd = path_arg(diff_vcd, "diff_vcd");
        if (xz == "strict" || xz == "wildcard" || xz == "zero") {
          o.xz = xz == "strict" ? XzPolicy::strict
                                : (xz == "wildcard" ? XzPolicy::wildcard : XzPolicy::zero);
        } else {
          throw py::value_error("xz '" + xz + "': expected one of strict, wildcard, zero");
        }
        if (edge != "rising" && edge != "falling" && edge != "both")
          throw py::value_error("edge '" + edge + "': expected one of rising, falling, both");
        o.edge = edge == "falling" ? Edge::falling : edge == "both" ? Edge::both : Edge::rising;
        o.tolerance_cycles = tolerance_cycles;
        // In the CLI's words, as compare() says the rest ("--tolerance-cycles needs --clock").
        if (const std::string why = take_window(start, end, tolerance, o); !why.empty())
          throw OptionError(why);
        py::gil_scoped_release nogil;
        return compare(o);
      },
      py::arg("a"), py::arg("b"), py::kw_only(), py::arg("clock") = py::none(),
      py::arg("clock_b") = py::none(), py::arg("strip_a") = "", py::arg("strip_b") = "",
      py::arg("strip_auto") = false, py::arg("map_file") = "",
      py::arg("include") = std::vector<std::string>{},
      py::arg("exclude") = std::vector<std::string>{}, py::arg("ignore_missing") = false,
      py::arg("xz") = "strict", py::arg("diff_vcd") = "", py::arg("edge") = "rising",
      py::arg("start") = "", py::arg("end") = "", py::arg("tolerance") = "",
      py::arg("tolerance_cycles") = 0,
      "Compares two waveforms (VCD or FST) as `dpc31 wavediff` does, with its options of the "
      "same names (start, end: '100ns' or 'c12'; tolerance: '5ns'; edge and tolerance_cycles "
      "with clock); no json, merge or wavedrom files: the report has .json() and .text(). Raises "
      "InputError, in the CLI's words.");
}

}  // namespace

void bind_session(py::module_& m) {
  bind_frames(m);
  bind_user_side(m);
  bind_board(m);
  bind_master(m);
  bind_scenarios(m);
  bind_wavediff(m);
}

}  // namespace dpc31::py_bind
