// What the session bindings share (bind_session.cpp, bind_master.cpp, bind_scenario.cpp,
// bind_wavediff.cpp): the short integer names, the keyword constructor, the 80C32 board the
// master can run, and the binders of each part.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <utility>

#include "bind.hpp"
#include "cpu51_module.hpp"
#include "vocabulary.hpp"

namespace dpc31::py_bind {

using U8 = std::uint8_t;
using U64 = std::uint64_t;

// A class bound without a keyword constructor gets one: T() with each keyword set as an
// attribute (an unknown keyword is an AttributeError).
template <typename T>
T with_kwargs(const py::kwargs& kw) {
  py::object o = py::cast(T{});
  for (const auto& [k, v] : kw) {
    try {
      py::setattr(o, k, v);
    } catch (py::error_already_set& e) {
      // pybind11's "(): incompatible function arguments" names neither the keyword nor the type
      // it takes: the field's own value says that.
      if (!e.matches(PyExc_TypeError) || !py::hasattr(o, k)) throw;
      throw py::type_error(type_expected(py::str(k).cast<std::string>(), o.attr(k), v));
    }
  }
  return o.cast<T>();
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
  PyBoard(const PyBoard&) = delete;
  PyBoard& operator=(const PyBoard&) = delete;
  py::object chip_ref;
  PyChip& chip;
  std::unique_ptr<Cpu51Board> board;
  Cpu51Config cfg;  // what load_hex checks the image against

  void run_until(std::uint64_t cycle) {
    while (chip.chip.cycle() < cycle && !chip.chip.stop_requested()) board->run_until(cycle);
  }
  // Cpu51Board.run_until: to the cycle asked, as Chip.step(n), after an observer's exception too
  // (docs/python.md, "The GIL"): the stop the observer requested ends a master's wait (the
  // scheduler above), not this call. The observers are not called again.
  void run_to(std::uint64_t cycle) {
    run_until(cycle);
    if (!chip.error) return;
    chip.chip.clear_stop();
    run_until(cycle);
  }
};

// The parts of bind_session(), one file each.
void bind_master(py::module_& m);
void bind_scenarios(py::module_& m);
void bind_wavediff(py::module_& m);

}  // namespace dpc31::py_bind
