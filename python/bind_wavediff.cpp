// dpc31.wavediff in Python (docs/python.md): lib/wavediff's compare(), as `dpc31 wavediff`.
#include <fmt/format.h>
#include <pybind11/operators.h>

#include <memory>
#include <thread>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "bind_session.hpp"
#include "wavediff.hpp"

namespace dpc31::py_bind {

void bind_wavediff(py::module_& m) {
  using namespace wavediff;
  py::class_<Point>(m, "WavePoint")
      .def_readonly("time", &Point::time)
      .def_readonly("time_b", &Point::time_b)
      .def_readonly("cycle", &Point::cycle)
      .def_readonly("own_a", &Point::own_a)
      .def_readonly("own_b", &Point::own_b);
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
      [](const py::object& a, const py::object& b, const std::optional<std::string>& clock,
         const std::optional<std::string>& clock_b, const std::string& strip_a,
         const std::string& strip_b, bool strip_auto, const py::object& map_file,
         std::vector<std::string> include, std::vector<std::string> exclude, bool ignore_missing,
         const std::string& xz, const py::object& diff_vcd, const std::string& edge,
         const std::string& start, const std::string& end, const std::string& tolerance,
         std::uint64_t tolerance_cycles) {
        Options o;
        o.file_a = read_path_arg(fspath_arg(a, "a"), "a");
        o.file_b = read_path_arg(fspath_arg(b, "b"), "b");
        o.clock_a = clock.value_or("");
        o.clock_b = clock_b.value_or("");
        o.strip_a = strip_a;
        o.strip_b = strip_b;
        o.strip_auto = strip_auto;
        o.map_file = fspath_arg(map_file, "map_file");
        o.include = std::move(include);
        o.exclude = std::move(exclude);
        o.ignore_missing = ignore_missing;
        o.diff_vcd = fspath_arg(diff_vcd, "diff_vcd");
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

}  // namespace dpc31::py_bind
