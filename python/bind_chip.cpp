// dpc31.Chip and the register description in Python (docs/python.md): dpc31::Chip
// (include/dpc31/chip.hpp) one call for one call, with the names of the CLI and scenario files.
#include <dlfcn.h>
#include <fmt/format.h>

#include <algorithm>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include "bind.hpp"
#include "cleanup.hpp"
#include "dpc31/dpc31_version.h"
#include "dpc31/snapshot.hpp"
#include "firmware_host.hpp"
#include "vocabulary.hpp"
#include "wave_reader.hpp"

namespace dpc31::py_bind {

Errors& errors() {
  static Errors& e = *new Errors;  // never destroyed: it would outlive the interpreter
  return e;
}

void raise(const py::object& type, const std::string& message,
           std::initializer_list<std::pair<const char*, py::object>> attrs) {
  py::object exc = type(message);
  for (const auto& [name, value] : attrs) exc.attr(name) = value;
  PyErr_SetObject(type.ptr(), exc.ptr());
  throw py::error_already_set();
}

void raise_firmware(const FirmwarePlace& place, const std::string& reason) {
  const auto or_none = [](bool none, py::object v) { return none ? py::object(py::none()) : v; };
  raise(errors().firmware, place.message(reason),
        {{"file", py::str(place.file())},
         {"line", or_none(place.line() == 0, py::int_(place.line()))},
         {"step", or_none(place.step().empty(), py::str(place.step()))},
         {"reason", py::str(reason)}});
}

void enter_run(const RunState& run, bool changes, std::string_view who, std::string_view looks,
               std::string_view not_changes) {
  if (!run.busy) return;
  if (run.runner != std::this_thread::get_id()) {
    raise(errors().error,
          fmt::format("the {} is running in another thread (one thread at a time)", who));
  }
  if (changes) {
    raise(errors().error,
          fmt::format("the {} is running: an observer may look at it ({}) but not {}", who, looks,
                      not_changes));
  }
}

void PyChip::enter(bool mutating) const {
  enter_run(*run_, mutating, "chip", "peek, cycle, probe, ...", "access or step it");
}

void PyChip::enter_observers(std::string_view call) const {
  enter_run(*run_, true, "chip", "peek, cycle, probe, ...",
            fmt::format("add or remove observers ({}): change them after the call returns", call));
}

std::optional<py::function> callback_arg(const py::object& f, std::string_view call) {
  if (f.is_none()) return std::nullopt;
  if (!PyCallable_Check(f.ptr())) {
    throw py::type_error(
        fmt::format("{}: callback: a callable or None expected, got {}", call,
                    py::str(py::type::of(f).attr("__name__")).cast<std::string>()));
  }
  return py::reinterpret_borrow<py::function>(f);
}

void keep_as_context(const py::error_already_set& interrupt, std::exception_ptr pending) {
  if (!pending) return;
  try {
    std::rethrow_exception(pending);
  } catch (py::error_already_set& e) {
    PyException_SetContext(interrupt.value().ptr(), e.value().inc_ref().ptr());
  }
}

void PyChip::rethrow() {
  if (!error) return;
  std::exception_ptr e = std::exchange(error, nullptr);
  chip.clear_stop();
  std::rethrow_exception(e);
}

namespace {

template <typename T, typename Parse>
T parse_name(std::string_view what, std::string_view s, Parse parse, std::string_view allowed) {
  T v{};
  if (!parse(s, v)) {
    throw py::value_error(std::string(what) + " '" + std::string(s) + "': expected one of " +
                          std::string(allowed));
  }
  return v;
}

}  // namespace

ChipOptions chip_options(std::string_view profile, std::string_view bus, std::uint32_t clock_hz,
                         std::string_view engine, const std::optional<std::string>& variant,
                         std::string_view irq_controller) {
  ChipOptions o;
  o.profile = parse_name<Profile>(
      "profile", profile, [](std::string_view s, Profile& p) { return parse_profile(s, p); },
      "spc3, vpc3plus, dpc31");
  if (bus != "intel" && bus != "motorola") {
    throw py::value_error("bus '" + std::string(bus) + "': expected one of intel, motorola");
  }
  o.bus = bus == "intel" ? BusMode::intel : BusMode::motorola;
  o.clock_hz = clock_hz;
  if (engine != "event" && engine != "per-cycle") {
    throw py::value_error("engine '" + std::string(engine) + "': expected one of event, per-cycle");
  }
  o.engine = engine == "event" ? Engine::event : Engine::per_cycle;
  if (variant) {
    o.variant = parse_name<Vpc3Variant>(
        "variant", *variant,
        [](std::string_view s, Vpc3Variant& v) { return parse_vpc3_variant(s, v); }, "b, c, s");
  }
  o.irq_controller = parse_name<IrqController>(
      "irq_controller", irq_controller,
      [](std::string_view s, IrqController& c) { return parse_irq_controller(s, c); },
      "external, c31");
  return o;
}

const RegDesc& reg_desc(const Chip& chip, std::string_view name) {
  const RegDesc* r = find_reg(chip.profile(), name);
  if (r == nullptr) {
    throw py::value_error("no register '" + std::string(name) + "' in profile " +
                          std::string(chip.profile().name));
  }
  return *r;
}

RegId reg_id(const Chip& chip, std::string_view name) { return reg_desc(chip, name).id; }

py::bytes to_bytes(std::span<const std::uint8_t> b) {
  return {reinterpret_cast<const char*>(b.data()), b.size()};
}

std::vector<std::uint8_t> from_bytes(const py::bytes& b) {
  const std::string_view s = b;
  return {s.begin(), s.end()};
}

std::vector<std::uint8_t> bytes_like(py::handle o, std::string_view what) {
  if (py::isinstance<py::bytes>(o)) return from_bytes(py::reinterpret_borrow<py::bytes>(o));
  // bytearray, memoryview, array: their bytes as a snapshot's load takes them.
  if (PyObject_CheckBuffer(o.ptr()) != 0) return buffer_bytes(o, what);
  try {
    return o.cast<std::vector<std::uint8_t>>();
  } catch (const IntOutOfRange& e) {
    throw py::value_error(fmt::format("{}: {}", what, e.range));
  } catch (const py::cast_error&) {
    throw py::type_error(
        fmt::format("{}: bytes expected, got {}", what,
                    py::str(py::type::of(o).attr("__name__")).cast<std::string>()));
  }
}

std::string type_expected(std::string_view what, py::handle sample, py::handle got) {
  const auto name = [](py::handle o) {
    return py::str(py::type::of(o).attr("__name__")).cast<std::string>();
  };
  std::string expected = "a " + name(sample);
  if (py::isinstance<py::bool_>(sample)) {
    expected = "a bool";
  } else if (py::isinstance<py::int_>(sample)) {
    expected = "an int";
  } else if (py::isinstance<py::bytes>(sample)) {
    expected = "bytes";
  }
  return fmt::format("{}: {} expected, got {}", what, expected, name(got));
}

std::vector<std::uint8_t> buffer_bytes(py::handle o, std::string_view what) {
  if (PyObject_CheckBuffer(o.ptr()) == 0) {
    throw py::type_error(
        fmt::format("{}: a bytes-like object expected, got {}", what,
                    py::str(py::type::of(o).attr("__name__")).cast<std::string>()));
  }
  Py_buffer view{};
  if (PyObject_GetBuffer(o.ptr(), &view, PyBUF_FULL_RO) != 0) throw py::error_already_set();
  std::vector<std::uint8_t> v(static_cast<std::size_t>(view.len));
  const int copied = PyBuffer_ToContiguous(v.data(), &view, view.len, 'C');
  PyBuffer_Release(&view);
  if (copied != 0) throw py::error_already_set();
  return v;
}

std::string fspath_arg(const py::object& path, std::string_view what) {
  if (!py::isinstance<py::str>(path) && !py::isinstance<py::bytes>(path) &&
      !py::hasattr(path, "__fspath__")) {
    throw py::type_error(
        fmt::format("{}: a str or an os.PathLike expected, got {}", what,
                    py::str(py::type::of(path).attr("__name__")).cast<std::string>()));
  }
  const py::object p = py::module_::import("os").attr("fspath")(path);
  return path_arg(p.cast<std::string>(), what);
}

std::optional<std::string> fspath_arg_or_none(const py::object& path, std::string_view what) {
  if (path.is_none()) return std::nullopt;
  return fspath_arg(path, what);
}

std::vector<std::uint8_t> raw_telegram(py::handle data) {
  std::vector<std::uint8_t> v = bytes_like(data, "data");
  if (v.empty()) throw py::value_error("telegram: no bytes");
  if (v.size() > fdl::kMaxFrameLength) {
    throw py::value_error(fmt::format("telegram: more than {} bytes", fdl::kMaxFrameLength));
  }
  return v;
}

std::uint32_t profibus_rate(std::uint32_t baud) {
  if (const std::string e = not_a_profibus_rate(baud); !e.empty()) throw py::value_error(e);
  return baud;
}

void one_clock_a_bit(std::uint32_t clock_hz, std::uint32_t baud) {
  if (bit_cycles(clock_hz, baud) == 0) {
    throw py::value_error(
        fmt::format("clock_hz {}: less than one clock a bit at {} baud", clock_hz, baud));
  }
}

namespace {

// A Python int as an int64_t, one beyond that range as its nearer end: every range the module
// checks lies inside, so 2**63 is refused in the bus's or the byte's words, not int64_t's.
std::int64_t clamped(const py::int_& v) {
  int overflow = 0;
  const long long x = PyLong_AsLongLongAndOverflow(v.ptr(), &overflow);
  if (overflow != 0) {
    return overflow > 0 ? std::numeric_limits<std::int64_t>::max()
                        : std::numeric_limits<std::int64_t>::min();
  }
  return x;
}

std::string text_of(const py::int_& v) { return py::str(py::handle(v)).cast<std::string>(); }

// A block's length, after its address's check: 0 up to the whole address space, else a
// ValueError naming it ("length -1 is out of range (0..2048)"); it was called a block "ending
// beyond" the space, or given int64_t's range.
std::int64_t block_length(const Chip& chip, const AnyInt& addr, const AnyInt& n) {
  bus_addr(chip, addr);
  const std::int64_t limit = std::int64_t{1} << chip.profile().address_bits;
  const std::int64_t v = clamped(n.value);
  if (v < 0 || v > limit) {
    throw py::value_error(
        range_error_text("length", text_of(n.value), 0, static_cast<std::uint64_t>(limit)));
  }
  return v;
}

}  // namespace

std::uint32_t bus_addr(const Chip& chip, const AnyInt& addr, std::int64_t n) {
  const std::int64_t limit = std::int64_t{1} << chip.profile().address_bits;
  const std::int64_t a = clamped(addr.value);
  if (a < 0 || a >= limit) {
    throw py::value_error(
        range_error_text("addr", text_of(addr.value), 0, static_cast<std::uint64_t>(limit - 1)));
  }
  if (n < 0 || n > limit - a) {
    throw py::value_error("block " + std::to_string(a) + "+" + std::to_string(n) +
                          " ends beyond the address space (0.." + std::to_string(limit - 1) + ")");
  }
  return static_cast<std::uint32_t>(a);
}

namespace {

// A value of a register's bits (`mask`), in dpc31 serve's words when it is not one.
std::uint16_t reg_value(std::string_view what, const AnyInt& value, std::uint16_t mask) {
  const std::int64_t v = clamped(value.value);
  if (v < 0 || v > mask)
    throw py::value_error(range_error_text(what, text_of(value.value), 0, mask));
  return static_cast<std::uint16_t>(v);
}

}  // namespace

std::uint8_t byte_value(std::string_view what, const AnyInt& v) {
  return static_cast<std::uint8_t>(reg_value(what, v, 0xFF));
}

py::dict counters_dict(const FdlCounters& c) {
  py::dict d;
  for (const CounterField& f : fdl_counter_fields()) d[py::str(f.name)] = c.*f.member;
  return d;
}

namespace {

py::object opt_addr(std::int32_t a) { return a < 0 ? py::object(py::none()) : py::int_(a); }

const FieldDesc& field_of(const RegDesc& r, std::string_view name) {
  auto it = std::find_if(r.fields.begin(), r.fields.end(),
                         [&](const FieldDesc& f) { return f.name == name; });
  if (it == r.fields.end()) {
    throw py::value_error("register " + std::string(r.name) + " has no field '" +
                          std::string(name) + "'");
  }
  return *it;
}

std::uint16_t field_mask(const FieldDesc& f) {
  return static_cast<std::uint16_t>(((1U << f.width) - 1U) << f.lsb);
}

}  // namespace

std::uint16_t peek_field(const Chip& chip, std::string_view reg, std::string_view field) {
  const RegDesc& r = *find_reg(chip.profile(), reg_id(chip, reg));
  const FieldDesc& f = field_of(r, field);
  return static_cast<std::uint16_t>((chip.peek_reg(r.id) & field_mask(f)) >> f.lsb);
}

py::object addr_of(const Chip& chip, std::string_view name) {
  // Another profile's register: this profile lacks it (None); a name no profile has is refused.
  if (find_reg(chip.profile(), name) == nullptr && any_profile_has(name)) return py::none();
  return opt_addr(chip.addr_of(reg_id(chip, name)));
}

namespace {

py::list registers_of(const ProfileDesc& p) {
  py::list l;
  for (const RegDesc& r : p.regs) l.append(py::cast(&r, py::return_value_policy::reference));
  return l;
}

void bind_description(py::module_& m) {
  py::class_<FieldDesc>(m, "Field", "One field of a register (regs/dpc31_regs.json).")
      .def_readonly("name", &FieldDesc::name)
      .def_readonly("lsb", &FieldDesc::lsb)
      .def_readonly("width", &FieldDesc::width)
      .def_property_readonly("access",
                             [](const FieldDesc& f) { return std::string(access_name(f.access)); })
      .def_readonly("pulse", &FieldDesc::pulse)
      .def_readonly("desc", &FieldDesc::desc)
      .def_property_readonly("mask", &field_mask)
      .def("__repr__", [](const FieldDesc& f) {
        return "<Field " + std::string(f.name) + " [" + std::to_string(f.lsb + f.width - 1) + ":" +
               std::to_string(f.lsb) + "] " + std::string(access_name(f.access)) + ">";
      });
  py::class_<RegDesc>(m, "Register",
                      "One register or RAM cell of a profile, as the description has it.")
      .def_readonly("name", &RegDesc::name)
      .def_readonly("alias", &RegDesc::alias)
      .def_property_readonly("kind",
                             [](const RegDesc& r) { return std::string(kind_name(r.kind)); })
      .def_property_readonly("block",
                             [](const RegDesc& r) { return std::string(block_name(r.block)); })
      .def_readonly("width", &RegDesc::width)
      .def_property_readonly(
          "reset",
          [](const RegDesc& r) { return r.has_reset ? py::object(py::int_(r.reset)) : py::none(); })
      .def_property_readonly("read_addr", [](const RegDesc& r) { return opt_addr(r.read_addr); })
      .def_property_readonly("write_addr", [](const RegDesc& r) { return opt_addr(r.write_addr); })
      .def_readonly("documented", &RegDesc::documented)
      .def_readonly("source", &RegDesc::source)
      .def_readonly("note", &RegDesc::note)
      .def_readonly("desc", &RegDesc::desc)
      .def_property_readonly("fields",
                             [](const RegDesc& r) {
                               py::list l;
                               for (const FieldDesc& f : r.fields) {
                                 l.append(py::cast(&f, py::return_value_policy::reference));
                               }
                               return l;
                             })
      .def(
          "field", [](const RegDesc& r, std::string_view name) { return &field_of(r, name); },
          py::return_value_policy::reference, py::arg("name"))
      .def("__repr__", [](const RegDesc& r) {
        return "<Register " + std::string(r.name) + " " + std::string(kind_name(r.kind)) + ">";
      });
  py::class_<RegionDesc>(m, "Region", "A contiguous memory region of a profile.")
      .def_readonly("name", &RegionDesc::name)
      .def_readonly("begin", &RegionDesc::begin)
      .def_readonly("end", &RegionDesc::end)
      .def_readonly("ram", &RegionDesc::ram)
      .def_readonly("reserved", &RegionDesc::reserved)
      .def_readonly("desc", &RegionDesc::desc);

  const auto profile_of = [](std::string_view name) -> const ProfileDesc& {
    return profile_desc(chip_options(name, "intel", 0, "event", std::nullopt, "external").profile);
  };
  m.def(
      "registers", [profile_of](std::string_view p) { return registers_of(profile_of(p)); },
      py::arg("profile"), "Every register and RAM cell of a profile, in the description's order.");
  m.def(
      "register",
      [profile_of](std::string_view p, std::string_view name) {
        const RegDesc* r = find_reg(profile_of(p), name);
        if (r == nullptr) {
          throw py::value_error("no register '" + std::string(name) + "' in profile " +
                                std::string(p));
        }
        return r;
      },
      py::return_value_policy::reference, py::arg("profile"), py::arg("name"));
  m.def(
      "regions",
      [profile_of](std::string_view p) {
        py::list l;
        for (const RegionDesc& r : profile_of(p).regions) {
          l.append(py::cast(&r, py::return_value_policy::reference));
        }
        return l;
      },
      py::arg("profile"));
  m.def("profiles", [] {
    py::list l;
    for (Profile p : kAllProfiles) l.append(std::string(profile_name(p)));
    return l;
  });
}

void bind_values(py::module_& m) {
  py::enum_<DpState>(m, "DpState")
      .value("Wait_Prm", DpState::Wait_Prm)
      .value("Wait_Cfg", DpState::Wait_Cfg)
      .value("Data_Exchange", DpState::Data_Exchange);
  py::enum_<WdState>(m, "WdState")
      .value("Baud_Search", WdState::Baud_Search)
      .value("Baud_Control", WdState::Baud_Control)
      .value("DP_Control", WdState::DP_Control);
  py::class_<Telegram>(m, "Telegram", "A frame the chip received (RxD) or sent (TxD).")
      .def_readonly("from_chip", &Telegram::from_chip)
      .def_property_readonly("bytes", [](const Telegram& t) { return to_bytes(t.bytes); })
      .def_readonly("start", &Telegram::start)
      .def_readonly("end", &Telegram::end)
      .def("__repr__", [](const Telegram& t) {
        return "<Telegram " + std::string(t.from_chip ? "tx" : "rx") + " " +
               std::to_string(t.start) + ".." + std::to_string(t.end) + ">";
      });
  py::class_<ChipProbe>(m, "Probe", "The state signals of the chip in one look (Chip.probe()).")
      .def_readonly("dp_state", &ChipProbe::dp_state)
      .def_readonly("wd_state", &ChipProbe::wd_state)
      .def_readonly("baud_code", &ChipProbe::baud_code)
      .def_readonly("irr", &ChipProbe::irr)
      .def_readonly("dout_buffer_sm", &ChipProbe::dout_buffer_sm)
      .def_readonly("din_buffer_sm", &ChipProbe::din_buffer_sm)
      .def_readonly("diag_buffer_sm", &ChipProbe::diag_buffer_sm);
}

// Observers: on_X(callable) adds one, on_X(None) removes all of that kind (Chip's rule).
template <typename... Args, typename Setter, typename Convert>
void observe(PyChip& c, std::string_view call, const py::object& f, Setter set, Convert convert) {
  const std::optional<py::function> fn = callback_arg(f, call);
  c.enter_observers(call);
  if (!fn) {
    set(std::function<void(Args...)>{});
  } else {
    set(c.observer<Args...>(*fn, convert));
  }
}

// A property of the chip's running state: from another thread while the chip runs it is refused
// as peek is (PyChip::enter), not read while that thread writes it.
template <typename F>
auto looked(F f) {
  return [f](const PyChip& c) {
    c.enter(false);
    return f(c.chip);
  };
}

void bind_chip_class(py::module_& m) {
  using U8 = std::uint8_t;
  using U32 = std::uint32_t;
  using U64 = std::uint64_t;
  py::class_<PyChip>(m, "Chip", "One SPC3, VPC3+ or DPC31 on its parallel bus (dpc31::Chip).")
      .def(py::init([](std::string_view profile, std::string_view bus, U32 clock_hz,
                       std::string_view engine, const std::optional<std::string>& variant,
                       std::string_view irq_controller) {
             return std::make_unique<PyChip>(
                 chip_options(profile, bus, clock_hz, engine, variant, irq_controller));
           }),
           py::arg("profile") = "dpc31", py::arg("bus") = "intel", py::arg("clock_hz") = 0,
           py::arg("engine") = "event", py::arg("variant") = py::none(),
           py::arg("irq_controller") = "external")
      // run: the reset's edges reach the observers, whose exception is raised here; under a
      // Cpu51Board at the board's instant, where the chip's clock counts on (docs/cpu.md)
      .def("reset", [](PyChip& c) { c.run([&] { c.chip.reset(); }); })
      // the bus: each access takes bus_access_cycles clocks, the chip runs meanwhile
      .def(
          "read",
          [](PyChip& c, const AnyInt& a) {
            const U32 at = bus_addr(c.chip, a);
            return c.run([&] { return c.chip.read(at); });
          },
          py::arg("addr"))
      .def(
          "write",
          [](PyChip& c, const AnyInt& a, const AnyInt& v) {
            const U32 at = bus_addr(c.chip, a);
            const U8 b = byte_value("value", v);
            c.run([&] { c.chip.write(at, b); });
          },
          py::arg("addr"), py::arg("value"))
      .def(
          "read_block",
          [](PyChip& c, const AnyInt& a, const AnyInt& length) {
            const std::int64_t n = block_length(c.chip, a, length);
            const U32 at = bus_addr(c.chip, a, n);
            std::vector<U8> out(static_cast<std::size_t>(n));
            c.run([&] { c.chip.read_block(at, out); });
            return to_bytes(out);
          },
          py::arg("addr"), py::arg("length"))
      .def(
          "write_block",
          [](PyChip& c, const AnyInt& a, const py::object& b) {
            const std::vector<U8> v = bytes_like(b, "data");
            const U32 at = bus_addr(c.chip, a, static_cast<std::int64_t>(v.size()));
            c.run([&] { c.chip.write_block(at, v); });
          },
          py::arg("addr"), py::arg("data"))
      .def(
          "fill",
          [](PyChip& c, const AnyInt& a, const AnyInt& v, const AnyInt& length) {
            const std::int64_t n = block_length(c.chip, a, length);
            const U32 at = bus_addr(c.chip, a, n);
            const U8 b = byte_value("value", v);
            c.run([&] { c.chip.fill(at, b, static_cast<std::size_t>(n)); });
          },
          py::arg("addr"), py::arg("value"), py::arg("length"))
      .def(
          "equal",
          [](PyChip& c, const AnyInt& a, const AnyInt& b, const AnyInt& length) {
            const std::int64_t n = block_length(c.chip, a, length);
            const U32 at = bus_addr(c.chip, a, n);
            const U32 bt = bus_addr(c.chip, b, n);
            return c.run([&] { return c.chip.equal(at, bt, static_cast<std::size_t>(n)); });
          },
          py::arg("a"), py::arg("b"), py::arg("length"))
      // the debugger: no time, no side effects
      .def(
          "peek",
          [](const PyChip& c, const AnyInt& a) {
            c.enter(false);
            return c.chip.peek(bus_addr(c.chip, a));
          },
          py::arg("addr"))
      .def(
          "poke",
          [](PyChip& c, const AnyInt& a, const AnyInt& v) {
            const U32 at = bus_addr(c.chip, a);
            const U8 b = byte_value("value", v);
            c.enter(true);
            return c.chip.poke(at, b);
          },
          py::arg("addr"), py::arg("value"))
      .def(
          "peek_block",
          [](const PyChip& c, const AnyInt& a, const AnyInt& length) {
            const std::int64_t n = block_length(c.chip, a, length);
            const U32 at = bus_addr(c.chip, a, n);
            c.enter(false);
            std::vector<U8> out(static_cast<std::size_t>(n));
            for (std::size_t i = 0; i < out.size(); ++i)
              out[i] = c.chip.peek(at + static_cast<U32>(i));
            return to_bytes(out);
          },
          py::arg("addr"), py::arg("length"))
      .def(
          "peek_reg",
          [](const PyChip& c, std::string_view name) {
            c.enter(false);
            return c.chip.peek_reg(reg_id(c.chip, name));
          },
          py::arg("name"))
      .def(
          "poke_reg",
          [](PyChip& c, std::string_view name, const AnyInt& v) {
            // Checked against the register's bits before any access, in dpc31 serve's words.
            const RegDesc& r = reg_desc(c.chip, name);
            const std::uint16_t value = reg_value("value", v, r.mask());
            c.enter(true);
            return c.chip.poke_reg(r.id, value);
          },
          py::arg("name"), py::arg("value"))
      .def(
          "peek_field",
          [](const PyChip& c, std::string_view reg, std::string_view field) {
            c.enter(false);
            return peek_field(c.chip, reg, field);
          },
          py::arg("register"), py::arg("field"))
      .def(
          "addr_of", [](const PyChip& c, std::string_view name) { return addr_of(c.chip, name); },
          py::arg("name"))
      .def_property_readonly("registers",
                             [](const PyChip& c) { return registers_of(c.chip.profile()); })
      // time
      .def(
          "step",
          [](PyChip& c, U64 n) {
            c.run([&] {
              in_slices(
                  n, [&] { return c.chip.cycle(); }, [&](U64 k) { c.chip.step(k); },
                  // step(n) runs all n cycles after an observer's error too (docs/python.md).
                  [] { return false; });
            });
          },
          py::arg("cycles") = 1)
      .def(
          "step_until_irq",
          [](PyChip& c, U64 n) { return c.run([&] { return c.chip.step_until_irq(n); }); },
          py::arg("cycles"))
      .def_property_readonly("cycle", looked([](const Chip& c) { return c.cycle(); }))
      .def_property_readonly("clock_hz", [](const PyChip& c) { return c.chip.clock_hz(); })
      .def_property_readonly("bus_access_cycles",
                             [](const PyChip& c) { return c.chip.bus_access_cycles(); })
      // pins and state
      .def_property_readonly("x_int", looked([](const Chip& c) { return c.x_int_pin(); }))
      .def_property_readonly("irq_active", looked([](const Chip& c) { return c.irq_active(); }))
      .def_property_readonly("pb3", looked([](const Chip& c) { return c.pb3_pin(); }))
      .def_property_readonly("txd", looked([](const Chip& c) { return c.txd_pin(); }))
      .def_property_readonly("started", looked([](const Chip& c) { return c.started(); }))
      .def_property_readonly("dp_state", looked([](const Chip& c) { return c.dp_state(); }))
      .def_property_readonly("wd_state", looked([](const Chip& c) { return c.wd_state(); }))
      .def_property_readonly("station_address",
                             looked([](const Chip& c) { return c.station_address(); }))
      .def_property_readonly("bit_cycles", looked([](const Chip& c) { return c.bit_cycles(); }))
      .def_property_readonly("fdl_counters",
                             looked([](const Chip& c) { return counters_dict(c.fdl_counters()); }))
      .def_property_readonly("profile",
                             [](const PyChip& c) { return std::string(c.chip.profile().name); })
      .def_property_readonly("bus",
                             [](const PyChip& c) {
                               return c.chip.bus_mode() == BusMode::intel ? "intel" : "motorola";
                             })
      .def_property_readonly("variant",
                             [](const PyChip& c) {
                               const auto v = c.chip.vpc3_variant();
                               return v ? py::object(py::str(std::string(vpc3_variant_name(*v))))
                                        : py::none();
                             })
      .def("probe",
           [](const PyChip& c) {
             c.enter(false);
             return c.chip.probe();
           })
      .def_property_readonly("next_deadline",
                             looked([](const Chip& c) { return c.next_deadline(); }))
      .def_property_readonly("watchdog_due", looked([](const Chip& c) { return c.watchdog_due(); }))
      // the serial side
      .def(
          "drive_rxd",
          [](PyChip& c, U64 cycle, bool level) {
            c.enter(true);
            c.chip.drive_rxd(cycle, level);
          },
          py::arg("cycle"), py::arg("level"))
      .def(
          "drive_rxd_chars",
          [](PyChip& c, const py::object& b, U64 start, U32 bit_cycles) {
            std::vector<U8> data = bytes_like(b, "data");
            c.enter(true);
            return c.chip.drive_rxd_chars(data, start, bit_cycles);
          },
          py::arg("data"), py::arg("start"), py::arg("bit_cycles"))
      // observers
      .def(
          "on_irq_change",
          [](PyChip& c, const py::object& f) {
            observe<U64, bool>(
                c, "on_irq_change", f, [&](auto cb) { c.chip.on_irq_change(std::move(cb)); },
                [](const py::object& fn, U64 cy, bool a) { fn(cy, a); });
          },
          py::arg("callback"),
          "callback(cycle, active) whenever the interrupt becomes active or inactive (X/INT "
          "follows it through Mode_Reg0.INT_Pol; a polarity write moves the pin without a call); "
          "None "
          "removes all")
      .def(
          "on_pb3_change",
          [](PyChip& c, const py::object& f) {
            observe<U64, bool>(
                c, "on_pb3_change", f, [&](auto cb) { c.chip.on_pb3_change(std::move(cb)); },
                [](const py::object& fn, U64 cy, bool h) { fn(cy, h); });
          },
          py::arg("callback"))
      .def(
          "on_telegram",
          [](PyChip& c, const py::object& f) {
            observe<const Telegram&>(
                c, "on_telegram", f, [&](auto cb) { c.chip.on_telegram(std::move(cb)); },
                [](const py::object& fn, const Telegram& t) { fn(t); });
          },
          py::arg("callback"), "callback(Telegram) for every frame received and answer sent")
      .def(
          "on_bus_access",
          [](PyChip& c, const py::object& f) {
            observe<U64, const BusAccess&>(
                c, "on_bus_access", f, [&](auto cb) { c.chip.on_bus_access(std::move(cb)); },
                [](const py::object& fn, U64 cy, const BusAccess& a) {
                  // The C++ side has the byte of a write only (BusAccess::data): None for a read.
                  fn(cy, a.write, a.addr, a.write ? py::object(py::int_(a.data)) : py::none());
                });
          },
          py::arg("callback"),
          "callback(cycle, write, addr, data) for every CPU bus access (data None for a read)")
      // snapshots
      .def("save_state",
           [](const PyChip& c) {
             c.enter(false);
             return to_bytes(c.chip.save_state());
           })
      .def(
          "load_state",
          [](PyChip& c, const py::object& data) {
            const std::vector<std::uint8_t> bytes = buffer_bytes(data, "data");
            c.run([&] { c.chip.load_state(bytes); });
          },
          py::arg("data"))
      .def(
          "save_state_file",
          [](const PyChip& c, const py::object& path) {
            c.enter(false);
            c.chip.save_state_file(fspath_arg(path, "path"));
          },
          py::arg("path"))
      .def(
          "load_state_file",
          [](PyChip& c, const py::object& path) {
            const std::string file = read_path_arg(fspath_arg(path, "path"), "path");
            c.run([&] { c.chip.load_state_file(file); });
          },
          py::arg("path"));
}

// A firmware plug-in (dpc31_firmware.h) takes the HAL's functions from the program that loads it.
// Python loads this module and libdpc31emu.so with RTLD_LOCAL, where a plug-in's dlopen would not
// find them: the library is made global once.
void export_hal_symbols() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&profile_desc), &info) != 0 && info.dli_fname != nullptr) {
    dlopen(info.dli_fname, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL);
  }
}

}  // namespace

void bind_chip(py::module_& m) {
  Errors& e = errors();
  e.error = py::exception<std::runtime_error>(m, "Error", PyExc_RuntimeError);
  const auto sub = [&](const char* name) {
    return py::reinterpret_steal<py::object>(
        PyErr_NewException((std::string("dpc31.") + name).c_str(), e.error.ptr(), nullptr));
  };
  e.snapshot = sub("SnapshotError");
  e.scenario = sub("ScenarioError");
  e.firmware = sub("FirmwareError");
  e.input = sub("InputError");
  m.attr("SnapshotError") = e.snapshot;
  m.attr("ScenarioError") = e.scenario;
  m.attr("FirmwareError") = e.firmware;
  // A scenario's run sets them (the `firmware` line or the step it faulted in); None elsewhere.
  for (const char* name : {"file", "line", "step", "reason"}) e.firmware.attr(name) = py::none();
  // Every ScenarioError of the module sets them; None on one raised by hand.
  for (const char* name : {"file", "line", "reason"}) e.scenario.attr(name) = py::none();
  m.attr("InputError") = e.input;
  // The emulator's errors as dpc31.Error and its subclasses, with the C++ message;
  // std::invalid_argument (a ChipOptions the chip refuses) as ValueError.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const py::builtin_exception&) {
      throw;
    } catch (const SnapshotError& x) {
      PyErr_SetString(errors().snapshot.ptr(), x.what());
    } catch (const FirmwareError& x) {
      PyErr_SetString(errors().firmware.ptr(), x.what());
    } catch (const wavediff::InputError& x) {
      PyErr_SetString(errors().input.ptr(), x.what());
    } catch (const std::invalid_argument& x) {
      PyErr_SetString(PyExc_ValueError, x.what());
    } catch (const std::runtime_error& x) {
      PyErr_SetString(errors().error.ptr(), x.what());
    }
  });
  bind_values(m);
  bind_description(m);
  bind_chip_class(m);
  export_hal_symbols();
}

namespace {

using Impl = py::handle (*)(py::detail::function_call&);
struct Wrapped {
  Impl impl;
  std::string name;  // for an argument without a keyword name: the property's or function's
};
std::unordered_map<const py::detail::function_record*, Wrapped>& wrapped() {
  static auto* w = new std::unordered_map<const py::detail::function_record*, Wrapped>;
  return *w;  // never destroyed: the functions outlive every static
}

// The ints the running call's casters took (int_taken); a nested call keeps its own. Only the
// first ones matter (its arguments load first): a body that casts ints for long records no more.
thread_local std::vector<PyObject*> t_taken;
thread_local int t_calls = 0;
constexpr std::size_t kTakenKept = 4096;

py::handle naming_impl(py::detail::function_call& call) {
  const Wrapped& w = wrapped().at(&call.func);
  std::vector<PyObject*> outer;
  outer.swap(t_taken);
  struct Restore {
    std::vector<PyObject*>& outer;
    ~Restore() { t_taken.swap(outer); }
  } restore{outer};
  ++t_calls;
  struct Leave {
    ~Leave() { --t_calls; }
  } leave;
  try {
    return w.impl(call);
  } catch (const IntOutOfRange& e) {
    // pybind11 loads the arguments in order and stops at the one that refuses: it is the
    // occurrence of the int (an argument, or an item of a tuple or list: wd=(1, 2**70)) after
    // those that took the very same object.
    std::size_t before =
        static_cast<std::size_t>(std::count(t_taken.begin(), t_taken.end(), e.value));
    std::string name = w.name;
    const auto is_it = [&](py::handle x) { return x.ptr() == e.value && before-- == 0; };
    // A constructor's first is not an object but its value_and_holder.
    for (std::size_t i = call.init_self ? 1 : 0; i < call.args.size(); ++i) {
      const py::handle a = call.args[i];
      bool found = is_it(a);
      if (!found && (PyTuple_Check(a.ptr()) || PyList_Check(a.ptr()))) {
        for (const py::handle x : a) {
          if ((found = is_it(x))) break;
        }
      }
      if (found) {
        if (i < call.func.args.size() && call.func.args[i].name != nullptr)
          name = call.func.args[i].name;
        break;
      }
    }
    throw py::value_error(name + " " + e.range);
  }
}

}  // namespace

void int_taken(PyObject* v) {
  if (t_calls > 0 && t_taken.size() < kTakenKept) t_taken.push_back(v);
}

namespace {

// The records of a pybind11 function (a builtin whose self is its record capsule; a method is
// one inside an instancemethod), overloads included.
void wrap(py::handle f, const std::string& name) {
  if (PyInstanceMethod_Check(f.ptr())) f = PyInstanceMethod_GET_FUNCTION(f.ptr());
  if (!PyCFunction_Check(f.ptr())) return;
  py::handle self = PyCFunction_GET_SELF(f.ptr());
  if (!self || !py::isinstance<py::capsule>(self)) return;
  const auto cap = py::reinterpret_borrow<py::capsule>(self);
  if (!py::detail::is_function_record_capsule(cap)) return;
  for (auto* r = cap.get_pointer<py::detail::function_record>(); r != nullptr; r = r->next) {
    if (r->impl == naming_impl) continue;
    wrapped().emplace(r, Wrapped{r->impl, name});
    r->impl = naming_impl;
  }
}

// The module's functions and its classes' (nested ones too, each once).
void wrap_scope(py::handle scope, const std::string& module, std::set<PyObject*>& seen) {
  seen.insert(scope.ptr());
  for (const auto& item : scope.attr("__dict__").attr("items")()) {
    const auto key = item[py::int_(0)].cast<std::string>();
    const py::object v = item[py::int_(1)];
    if (py::isinstance<py::type>(v)) {
      if (py::str(v.attr("__module__")).cast<std::string>() == module && !seen.contains(v.ptr()))
        wrap_scope(v, module, seen);
    } else if (PyObject_TypeCheck(v.ptr(), &PyProperty_Type)) {
      wrap(v.attr("fget"), key);
      wrap(v.attr("fset"), key);
    } else if (py::isinstance(v, py::module_::import("builtins").attr("staticmethod"))) {
      wrap(v.attr("__func__"), key);
    } else {
      wrap(v, key);
    }
  }
}

}  // namespace

void name_int_arguments(const py::module_& m) {
  std::set<PyObject*> seen;
  wrap_scope(m, py::str(m.attr("__name__")).cast<std::string>(), seen);
}

}  // namespace dpc31::py_bind

PYBIND11_MODULE(_dpc31, m) {
  m.doc() = "dpc31emu: the SPC3 / VPC3+ / DPC31 PROFIBUS-DP slave ASICs, cycle-accurate";
  // dpc31.__version__: the loaded libdpc31emu.so's, not this module's build (docs/python.md).
  m.attr("__version__") = dpc31emu_version();
  // No output's temporary outlives the script: a SIGTERM or SIGHUP the script has no handler of
  // its own for, and its exit, remove what is unfinished (Python need not destroy a Segment
  // that an uncaught exception's traceback still holds).
  dpc31::cleanup::install();
  dpc31::cleanup::remove_at_exit();
  dpc31::py_bind::bind_chip(m);
  dpc31::py_bind::bind_session(m);
  dpc31::py_bind::bind_segment(m);
  dpc31::py_bind::name_int_arguments(m);
}
