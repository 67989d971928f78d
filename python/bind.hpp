// The Python module dpc31 (docs/python.md): what its two translation units share. bind_chip.cpp
// binds the chip and the register description, bind_session.cpp the DP master, firmware,
// scenarios and wavediff. Only the public API (include/dpc31/, the installed session headers,
// lib/wavediff's compare()) is used.
#pragma once

#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/fdl.hpp"
#include "vocabulary.hpp"

namespace dpc31::py_bind {

namespace py = pybind11;

// A slave read back (Master.slave, SegmentMaster.slave, Station.slave): a copy, since the master is
// made anew when its user side starts. A field set on it would change nothing the master sends, so
// it raises instead (bind_configs); `owner` and `given` name the attribute and where the slave is
// given.
struct MasterSlave : SlaveConfig {
  const char* owner;
  const char* given;
};

// A Python int that an argument's C++ integer cannot hold: a ValueError in the module's range
// words, named by the argument it was given for once it leaves the call (name_int_arguments).
struct IntOutOfRange : py::value_error {
  IntOutOfRange(PyObject* v, std::string r)
      : py::value_error("value " + r), value(v), range(std::move(r)) {}
  PyObject* value;    // the int as given (call.args holds it while the call runs)
  std::string range;  // "V out of range (MIN..MAX)"
};

// Every function of the module (methods, properties, constructors) names the argument of an
// IntOutOfRange it raises: its keyword name, else the property's or function's name.
void name_int_arguments(const py::module_& m);

// An int taken by an argument's caster (in the order pybind11 loads them): CPython shares one
// object for equal small ints, so the argument that refused one is told apart from earlier
// arguments that took the same object by how many took it.
void int_taken(PyObject* v);

// An int of any size as given (an int, or what has __index__: a numpy integer, as the C++
// integers' casters take), for the arguments whose own range the module names for it (a bus
// address, a byte value: bus_addr, byte_value), where a C++ integer's caster names its own.
struct AnyInt {
  py::int_ value;
};

}  // namespace dpc31::py_bind

namespace pybind11::detail {

template <>
class type_caster<dpc31::py_bind::AnyInt> {
 public:
  PYBIND11_TYPE_CASTER(dpc31::py_bind::AnyInt, const_name("int"));
  bool load(handle src, bool /*convert*/) {
    // A float or a str is no int: pybind11's TypeError, as for a C++ integer.
    if (PyFloat_Check(src.ptr()) || !PyIndex_Check(src.ptr())) return false;
    object v = reinterpret_steal<object>(PyNumber_Index(src.ptr()));
    if (!v) throw error_already_set();
    value.value = reinterpret_borrow<pybind11::int_>(v);
    return true;
  }
};

// pybind11 takes an int that the argument's integer cannot hold (2**70 for a count, -1 for an
// unsigned) as a reason to try the next overload, and without one raises a TypeError that names
// no argument. The module has no overloads on integers: such an int is refused at once instead.
template <typename T>
class checked_int_caster {
  using Wide = std::conditional_t<std::is_signed_v<T>, long long, unsigned long long>;

 public:
  PYBIND11_TYPE_CASTER(T, const_name("int"));
  bool load(handle src, bool convert) {
    type_caster<Wide> wide;
    if (wide.load(src, convert) && std::in_range<T>(static_cast<Wide>(wide))) {
      value = static_cast<T>(static_cast<Wide>(wide));
      dpc31::py_bind::int_taken(src.ptr());
      return true;
    }
    if (!PyLong_Check(src.ptr())) return false;  // not an int: pybind11's TypeError
    throw dpc31::py_bind::IntOutOfRange(src.ptr(),
                                        std::string(str(src)) + " out of range (" +
                                            std::to_string(std::numeric_limits<T>::min()) + ".." +
                                            std::to_string(std::numeric_limits<T>::max()) + ")");
  }
  static handle cast(T v, return_value_policy policy, handle parent) {
    return type_caster<Wide>::cast(v, policy, parent);
  }
};
template <>
class type_caster<signed char> : public checked_int_caster<signed char> {};
template <>
class type_caster<unsigned char> : public checked_int_caster<unsigned char> {};
template <>
class type_caster<short> : public checked_int_caster<short> {};
template <>
class type_caster<unsigned short> : public checked_int_caster<unsigned short> {};
template <>
class type_caster<int> : public checked_int_caster<int> {};
template <>
class type_caster<unsigned> : public checked_int_caster<unsigned> {};
template <>
class type_caster<long> : public checked_int_caster<long> {};
template <>
class type_caster<unsigned long> : public checked_int_caster<unsigned long> {};

}  // namespace pybind11::detail

namespace dpc31::py_bind {

// The exception classes (dpc31.Error and its subclasses), created by bind_chip.
struct Errors {
  py::object error;     // dpc31.Error(RuntimeError): every error of the emulator
  py::object snapshot;  // dpc31.SnapshotError
  py::object scenario;  // dpc31.ScenarioError: .file, .line
  py::object firmware;  // dpc31.FirmwareError
  py::object input;     // dpc31.InputError: a waveform or file that cannot be read
};
Errors& errors();
// Raises `type(message)` with the attributes given (as a Python exception through C++).
[[noreturn]] void raise(const py::object& type, const std::string& message,
                        std::initializer_list<std::pair<const char*, py::object>> attrs = {});
// Raises FirmwareError with `dpc31 run`'s line (place.message(reason)) and its .file, .line,
// .step (None before a line or a step: a segment's stations starting) and .reason.
[[noreturn]] void raise_firmware(const FirmwarePlace& place, const std::string& reason);

// Runs `f` with the GIL released and returns what it returns (called with the GIL held).
template <typename F>
auto without_gil(F&& f) -> decltype(f()) {
  py::gil_scoped_release nogil;
  return f();
}

// A long run in slices, called without the GIL: between two slices the GIL is taken and Python's
// signal handlers run, so Ctrl-C raises KeyboardInterrupt at a slice's end, a cycle boundary
// (docs/python.md, "Ctrl-C"). `now()` is the run's time, `run_for(n)` runs n cycles of it; one
// that stops early (a wake-up) or after which `stopped()` holds (an observer's error, even in the
// slice's last cycle, where the run reached its target) ends the call there, as the whole call
// would have. A slice doubles while it takes under 20 ms, so a "no limit" on a chip without events
// is a few dozen slices, not 2^62 / slice.
template <typename Now, typename Run, typename Stopped>
void in_slices(std::uint64_t cycles, Now now, Run run_for, Stopped stopped) {
  std::uint64_t t = now();
  const std::uint64_t end = Chip::cycle_after(t, cycles);
  for (std::uint64_t slice = std::uint64_t{1} << 16;;) {
    const std::uint64_t n = std::min(end - t, slice);
    const auto started = std::chrono::steady_clock::now();
    run_for(n);
    const std::uint64_t reached = now();
    if (reached >= end || reached < t + n || stopped()) return;
    if (std::chrono::steady_clock::now() - started < std::chrono::milliseconds(20)) {
      slice = std::min(slice * 2, Chip::kLastCycle);
    } else {
      slice = std::max<std::uint64_t>(slice / 2, 1024);
    }
    const py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    t = reached;
  }
}

// A master's `idle(cycles)` so (Master.idle, SegmentMaster.idle): `now()` is its line's time.
template <typename PM, typename Now, typename Stopped>
void idle_in_slices(PM& pm, std::uint64_t cycles, Now now, Stopped stopped) {
  pm.act([&] {
    in_slices(
        cycles, now, [&](std::uint64_t k) { pm.m->idle(k); }, stopped);
  });
}

// A KeyboardInterrupt `interrupt` raised while an observer's error `pending` was kept: that error
// becomes the interrupt's __context__ (not lost, not raised by the next call).
void keep_as_context(const py::error_already_set& interrupt, std::exception_ptr pending);

// Who runs a chip or a segment now (and so the user sides on it): read and written with the GIL
// held only.
struct RunState {
  bool busy = false;
  std::thread::id runner;
};
// Marks `run` busy in this thread for as long as it lives.
class Running {
 public:
  explicit Running(RunState& run) : run_(run) {
    run_.busy = true;
    run_.runner = std::this_thread::get_id();
  }
  ~Running() { run_.busy = false; }
  Running(const Running&) = delete;
  Running& operator=(const Running&) = delete;

 private:
  RunState& run_;
};

// Refuses a call while `run` is busy: from another thread always, from the running thread (an
// observer) when it `changes` what the run uses. "the WHO is running: an observer may look at it
// (LOOKS) but not NOT_CHANGES".
void enter_run(const RunState& run, bool changes, std::string_view who, std::string_view looks,
               std::string_view not_changes);

// A user side (a Firmware or a Responder) runs whenever the chip or segment it was given to runs.
// While it runs, a call from another thread is refused, and from an observer (the running thread)
// one that takes or changes what its ISR may be using (`changes`); an observer may look.
void user_side_runs_with(const void* user_side, const std::shared_ptr<const RunState>& run);
void enter_user_side(const void* user_side, bool changes);

// Thrown out of a master's wait that an observer's exception stopped (DpMaster::waited): the
// master's call ends there, and PyChip::run raises the observer's exception instead.
struct ObserverStopped {};

// One chip as Python holds it. The GIL is released while the chip runs; Python observers take it
// again. An observer's exception stops the run (Chip::request_stop) and is raised when the call
// that ran the chip returns. While the chip runs (`busy`), only the thread running it may look
// at it (observers may peek), and nobody may run it again: a clear error instead of a data race.
class PyChip {
 public:
  explicit PyChip(const ChipOptions& o) : chip(o) {}
  Chip chip;

  // The call that lets time pass: checks, releases the GIL around `f`, rethrows an observer's
  // exception. Called with the GIL held.
  template <typename F>
  auto run(F&& f) -> decltype(f()) {
    enter(true);
    const Running running(*run_);
    try {
      if constexpr (std::is_void_v<decltype(f())>) {
        without_gil(f);
        rethrow();
      } else {
        auto r = without_gil(f);
        rethrow();
        return r;
      }
    } catch (const ObserverStopped&) {
      rethrow();
      throw;
    } catch (py::error_already_set& interrupt) {
      // Ctrl-C between two slices: the next call starts clean.
      keep_as_context(interrupt, std::exchange(error, nullptr));
      chip.clear_stop();
      throw;
    }
  }
  // Checks that the caller may touch the chip now (mutating: it would change it).
  void enter(bool mutating) const;
  // Checks that `call` (on_irq_change, Cpu51Board.on_serial, ...) may add or remove an observer
  // now: not while the chip runs, whose list of observers an observer's own call is in.
  void enter_observers(std::string_view call) const;
  // A Python callable as an observer: called with the GIL, errors kept for rethrow().
  template <typename... Args, typename Convert>
  std::function<void(Args...)> observer(py::function f, Convert convert);
  void rethrow();

  // An observer raised: kept until the running call returns.
  std::exception_ptr error;

  // Shared with the user sides given to this chip (user_side_runs_with).
  [[nodiscard]] const std::shared_ptr<RunState>& run_state() const { return run_; }

 private:
  std::shared_ptr<RunState> run_ = std::make_shared<RunState>();
};

// An observer argument `callback` of `call`: a callable, or None (nullopt: remove), else a
// TypeError naming the argument (pybind11's cast names neither).
std::optional<py::function> callback_arg(const py::object& f, std::string_view call);

// A Python object kept by C++ code that may copy it without the GIL: the reference is dropped
// with the GIL held.
inline std::shared_ptr<py::object> hold(py::object o) {
  return {new py::object(std::move(o)), [](py::object* p) {
            py::gil_scoped_acquire gil;
            delete p;
          }};
}

template <typename... Args, typename Convert>
std::function<void(Args...)> PyChip::observer(py::function f, Convert convert) {
  return [this, fn = hold(std::move(f)), convert](Args... args) {
    py::gil_scoped_acquire gil;
    if (error) return;  // the first error ends the run; later calls are not made
    try {
      convert(*fn, args...);
    } catch (py::error_already_set&) {
      error = std::current_exception();
      chip.request_stop();
    }
  };
}

// Names <-> values of the options (ValueError naming the allowed ones).
ChipOptions chip_options(std::string_view profile, std::string_view bus, std::uint32_t clock_hz,
                         std::string_view engine, const std::optional<std::string>& variant,
                         std::string_view irq_controller);
RegId reg_id(const Chip& chip, std::string_view name);
// A register field's value by names (ValueError for a name the profile lacks), a register's
// address (None where the profile has none): Chip.peek_field / addr_of, and a segment's stations.
std::uint16_t peek_field(const Chip& chip, std::string_view reg, std::string_view field);
py::object addr_of(const Chip& chip, std::string_view name);
py::bytes to_bytes(std::span<const std::uint8_t> b);
std::vector<std::uint8_t> from_bytes(const py::bytes& b);
// Bytes as the module takes them: a bytes-like object (`bytes`, `bytearray`, `memoryview`,
// `array`: its bytes) or a list of ints 0..255, else a TypeError / ValueError named `what`
// ("outputs[0]: 300 out of range (0..255)").
std::vector<std::uint8_t> bytes_like(py::handle o, std::string_view what);
// "{what}: an int expected, got str": the type `sample` (the field's value) has, the one `got`
// has; for a TypeError that names its argument where pybind11's names none.
std::string type_expected(std::string_view what, py::handle sample, py::handle got);
// The bytes of any object with the buffer protocol (bytes, bytearray, memoryview, array): a
// snapshot. Anything else is a TypeError that names its type, never its contents.
std::vector<std::uint8_t> buffer_bytes(py::handle o, std::string_view what);
// A raw telegram (transact_raw, Segment.send): 1 to 255 bytes (bytes-like) as a scenario's `send
// BYTES`, else a ValueError ("telegram: more than 255 bytes", "telegram: no bytes").
std::vector<std::uint8_t> raw_telegram(py::handle data);
py::dict counters_dict(const FdlCounters& c);
// `v` within `r` as the type the C++ takes, else a ValueError with the scenario parser's words
// for it (vocabulary.hpp): both doors refuse a value alike.
template <typename T>
T in_range(const ValueRange& r, std::int64_t v) {
  if (v < 0 || !r.holds(static_cast<std::uint64_t>(v)))
    throw py::value_error(out_of_range(r, std::to_string(v)));
  return static_cast<T>(v);
}
// The same for an argument taken as any Python int: 2**70 is refused in `r`'s range too, where
// a C++ integer's caster would name its own.
template <typename T>
T in_range(const ValueRange& r, const py::int_& v) {
  int overflow = 0;
  const long long x = PyLong_AsLongLongAndOverflow(v.ptr(), &overflow);
  if (overflow != 0 || x < 0 || !r.holds(static_cast<std::uint64_t>(x)))
    throw py::value_error(out_of_range(r, py::str(py::handle(v)).cast<std::string>()));
  return static_cast<T>(x);
}
// `r` under the Python argument's name where it differs from the scenario's word: the message
// names what the caller wrote.
constexpr ValueRange named(const ValueRange& r, std::string_view python_name) {
  return {python_name, r.min, r.max};
}
// An argument that must be the module's class T: a TypeError naming the argument and the type
// given (pybind11's cast error, a RuntimeError, named neither).
template <typename T>
T& class_arg(py::handle o, std::string_view what, std::string_view expected) {
  if (!py::isinstance<T>(o)) {
    throw py::type_error(std::string(what) + ": " + std::string(expected) + " expected, got " +
                         py::str(py::type::of(o).attr("__name__")).cast<std::string>());
  }
  return o.cast<T&>();
}
// A file name from Python as the C library will take it: a NUL byte would end it there (another
// file), so a ValueError as Python's own open() raises. `what` is the argument's name.
inline const std::string& path_arg(const std::string& path, std::string_view what) {
  if (path.find('\0') != std::string::npos)
    throw py::value_error(std::string(what) + ": embedded null byte");
  return path;
}
// A file to read: '' is no file (the CLI's words for `--opt ''`), a ValueError as path_arg's.
inline const std::string& read_path_arg(const std::string& path, std::string_view what) {
  if (path_arg(path, what).empty())
    throw py::value_error(std::string(what) + ": an empty file name: nothing can be read there");
  return path;
}
// A file name given as a str or an os.PathLike (pathlib.Path), as open() takes it (os.fspath),
// then path_arg's check; another type is a TypeError naming the argument.
std::string fspath_arg(const py::object& path, std::string_view what);
// The same for an argument whose None is "not given".
std::optional<std::string> fspath_arg_or_none(const py::object& path, std::string_view what);
inline const std::optional<std::string>& path_arg(const std::optional<std::string>& path,
                                                  std::string_view what) {
  if (path) path_arg(*path, what);
  return path;
}
// A PROFIBUS rate, else a ValueError as the scenario's `baud` says it.
std::uint32_t profibus_rate(std::uint32_t baud);
// A ValueError when a bit at `baud` is less than one clock of `clock_hz` (no bit time).
void one_clock_a_bit(std::uint32_t clock_hz, std::uint32_t baud);
// An address on the chip's bus with `n` bytes from it inside (`n` 0: the address alone), else a
// ValueError in `dpc31 serve`'s words: the chip would take the upper bits off (and log it per
// byte).
std::uint32_t bus_addr(const Chip& chip, const AnyInt& a, std::int64_t n = 0);
// Python's fault= and fault_char= as a UartFault, else a ValueError; no fault_char: the last
// character, as a scenario's `corrupt` (DpMaster and Segment place it: vocabulary.hpp).
UartFault fault_of(const std::optional<std::string>& kind, std::optional<int> char_index);
// A byte `what` (0..255), else a ValueError.
std::uint8_t byte_value(std::string_view what, const AnyInt& v);
// The bytes of a frame, else a ValueError naming its first field fdl::encode refuses and that
// field's range (Frame.encode, and the masters' transact before they send).
std::vector<std::uint8_t> sendable(const fdl::Frame& f);

void bind_chip(py::module_& m);
void bind_session(py::module_& m);
void bind_segment(py::module_& m);

}  // namespace dpc31::py_bind
