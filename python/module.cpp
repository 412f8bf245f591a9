// The `sextant` Python module: LCM logs, every sextant message as a dict, a live LCM bus through liblcm (no LCM
// Python package needed), `sextant optimize` and `sextant eval` as functions returning the CLI's JSON keys.
// See the README's Python section; tests in tests/python/.
#include "daemon/runtime/version.hpp"
#include "python/module_parts.hpp"

PYBIND11_MODULE(sextant, m) {
  m.doc() =
      "sextant: LCM logs, sextant messages as dicts, a live LCM bus, pose-graph optimization and trajectory "
      "evaluation (the `sextant` tool's optimize and eval)";
  m.attr("__version__") = sextant::version();
  sextant::python::register_messages(m);
  sextant::python::register_logs(m);
  sextant::python::register_bus(m);
  sextant::python::register_solvers(m);
}
