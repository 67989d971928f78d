// dpc31.Frame, dpc31.Firmware, dpc31.Responder and dpc31.Cpu51Board in Python (docs/python.md):
// the session layer (session/*.hpp, installed as <dpc31/session/...>), one call for one call;
// dpc31.Master, dpc31.Scenario and dpc31.wavediff are bind_master.cpp, bind_scenario.cpp and
// bind_wavediff.cpp.
#include "bind_session.hpp"

#include <fmt/format.h>
#include <pybind11/operators.h>

#include <memory>
#include <thread>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

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

template <typename T, typename M>
auto bytes_property(M T::*member) {
  return std::make_pair([member](const T& t) { return to_bytes(t.*member); },
                        [member](T& t, const py::object& b) { t.*member = bytes_like(b, "du"); });
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
                        [member, what, non_empty, max](SlaveConfig& c, const py::object& b) {
                          std::vector<U8> v = bytes_like(b, what);
                          if (non_empty && v.empty())
                            throw py::value_error(fmt::format("{}: at least one byte", what));
                          if (v.size() > max)
                            throw py::value_error(fmt::format("{}: more than {} bytes", what, max));
                          c.*member = std::move(v);
                        });
}

void bind_frames(py::module_& m) {
  py::class_<fdl::Frame>(m, "Frame", "An FDL telegram (include/dpc31/fdl.hpp).")
      .def(py::init([](const AnyInt& da, const AnyInt& sa, const AnyInt& fc, const py::object& du,
                       const std::optional<AnyInt>& dsap, const std::optional<AnyInt>& ssap) {
             const auto sap = [](const char* what, const std::optional<AnyInt>& v) {
               return v ? std::optional<U8>(byte_value(what, *v)) : std::nullopt;
             };
             return fdl::make_frame(byte_value("da", da), byte_value("sa", sa),
                                    byte_value("fc", fc), bytes_like(du, "du"), sap("dsap", dsap),
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
      .def_readonly("noise", &MasterCounters::noise)
      .def_readonly("late", &MasterCounters::late);
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
          [](Responder& r, const py::object& b) {
            std::vector<U8> v = bytes_like(b, "inputs");
            enter_user_side(&r, true);
            r.set_inputs(std::move(v));
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

}  // namespace

namespace {

// P0..P3: the core masks the number (port_latch), so a larger one would be another port's; a
// negative one is no port either.
unsigned port_index(std::int64_t n) {
  if (n < 0 || n > 3) throw py::index_error(fmt::format("no port {} (0..3: P0..P3)", n));
  return static_cast<unsigned>(n);
}

// A register of the programmer's model: the running CPU changes it, so another thread is refused
// it while the board runs (an observer may look).
template <auto Get>
auto cpu_state(const PyBoard& b) {
  b.chip.enter(false);
  return (b.board->cpu().*Get)();
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
          [](PyBoard& b, const py::object& path) {
            b.chip.enter(true);
            Cpu51Config cfg = b.cfg;
            cfg.hex = read_path_arg(fspath_arg(path, "path"), "path");
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
          "run_until", [](PyBoard& b, U64 cycle) { b.chip.run([&] { b.run_to(cycle); }); },
          py::arg("cycle"),
          "Runs CPU and chip together until the chip's cycle is at least `cycle` (the CPU's "
          "step in progress ends).")
      // run: the chip's reset edges reach the observers, whose exception is raised here
      .def(
          "reset", [](PyBoard& b) { b.chip.run([&] { b.board->reset(); }); },
          "The board's RESET, which CPU and chip share (docs/cpu.md, \"The board's reset\"): both "
          "reset at the board's instant, the CPU from 0000h (a power-down ends), RAM kept.")
      .def(
          "port",
          [](const PyBoard& b, std::int64_t n) {
            b.chip.enter(false);  // the running CPU writes it
            return b.board->cpu().port_latch(port_index(n));
          },
          py::arg("n"), "Port n's latch (0..3: P0..P3).")
      .def(
          "pins",
          [](const PyBoard& b, std::int64_t n) {
            b.chip.enter(false);
            return b.board->cpu().port_pins(port_index(n));
          },
          py::arg("n"), "Port n's pins: the latch AND what the outside drives.")
      .def(
          "set_port_input",
          [](PyBoard& b, std::int64_t n, U8 value) {
            b.chip.enter(true);
            b.board->cpu().set_port_input(port_index(n), value);
          },
          py::arg("n"), py::arg("value"), "What the outside drives on port n (an address switch).")
      .def(
          "xdata",
          [](const PyBoard& b, std::uint16_t addr) {
            b.chip.enter(false);
            return b.board->ram(addr);
          },
          py::arg("addr"), "A byte of the board's RAM (XDATA outside the chip's window).")
      .def(
          "on_ram_write",
          [](PyBoard& b, const py::object& f) {
            const std::optional<py::function> fn = callback_arg(f, "on_ram_write");
            b.chip.enter_observers("on_ram_write");
            b.board->on_ram_write = nullptr;
            if (!fn) return;
            b.board->on_ram_write = b.chip.observer<std::uint16_t, std::uint8_t, U64>(
                *fn, [](py::object& cb, std::uint16_t a, std::uint8_t v, U64 c) { cb(a, v, c); });
          },
          py::arg("callback"),
          "callback(addr, value, cycle) for every write to the board's RAM (an output latch), "
          "with the chip cycle its strobe ends; None removes it.")
      .def(
          "on_serial",
          [](PyBoard& b, const py::object& f) {
            const std::optional<py::function> fn = callback_arg(f, "on_serial");
            b.chip.enter_observers("on_serial");
            Cpu51Board& board = *b.board;
            board.cpu().on_serial_tx = nullptr;
            if (!fn) return;
            const auto serial = b.chip.observer<std::uint8_t, U64>(
                *fn, [](py::object& cb, std::uint8_t d, U64 c) { cb(d, c); });
            board.cpu().on_serial_tx = [serial, &board](std::uint8_t d, bool, U64 machine_cycle) {
              serial(d, board.chip_cycle_of(machine_cycle * mcs51::clocks_per_cycle));
            };
          },
          py::arg("callback"),
          "callback(data, cycle) for every character the CPU's serial port sends (SBUF), with "
          "the chip cycle its TI is set (docs/cpu.md, \"Serial port\"); None removes it.")
      .def(
          "chip_cycle_of",
          [](const PyBoard& b, U64 clock) {
            b.chip.enter(false);
            return b.board->chip_cycle_of(clock);
          },
          py::arg("cpu_clock"), "The chip cycle of a CPU oscillator clock counted from reset.")
      .def_property_readonly("pc", cpu_state<&mcs51::Cpu::pc>)
      .def_property_readonly("a", cpu_state<&mcs51::Cpu::a>)
      .def_property_readonly("b", cpu_state<&mcs51::Cpu::b>)
      .def_property_readonly("psw", cpu_state<&mcs51::Cpu::psw>)
      .def_property_readonly("sp", cpu_state<&mcs51::Cpu::sp>)
      .def_property_readonly("dptr", cpu_state<&mcs51::Cpu::dptr>)
      .def_property_readonly("machine_cycles", cpu_state<&mcs51::Cpu::cycles>)
      .def_property_readonly("in_service", cpu_state<&mcs51::Cpu::in_service>)
      .def_property_readonly("chip", [](const PyBoard& b) { return b.chip_ref; });
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
