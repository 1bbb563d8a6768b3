// The instruction sets of Batch's SIMD lanes, and featherdrive.SimdBatch: a deprecated function
// kept for old scripts, now a Batch that must step in lanes (docs/simd_batch.md).
#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

void featherdrive::python::bind_simd(py::module_& m) {
  m.def(
      "available_simd_isas",
      [] {
        std::vector<std::string> out;
        for (SimdIsa isa : available_simd_isas()) out.push_back(to_string(isa));
        return out;
      },
      "The instruction sets Batch.isa can take on this CPU, narrowest first.");
  m.def(
      "SimdBatch",
      [](const Simulation& prototype, py::handle count, py::handle isa) {
        if (PyErr_WarnEx(PyExc_DeprecationWarning,
                         "featherdrive.SimdBatch is deprecated: use featherdrive.Batch(prototype, "
                         "count), which steps in SIMD lanes where the settings allow "
                         "(Batch.step_path, Batch.isa)",
                         1) < 0)
          throw py::error_already_set();
        const int n = to_int(count, "count", 1, Batch::kMaxSize);
        const std::optional<SimdIsa> i = to_isa(isa);
        return locked(prototype, [&] {
          BatchHolder batch(new Batch(prototype, n));
          batch->set_isa(i);
          // What SimdBatch refused: a prototype the lanes do not step, in one line.
          const std::string path = batch->step_path();
          const std::string scalar = "scalar: ";
          if (path.rfind(scalar, 0) == 0)
            throw std::invalid_argument("SimdBatch: " + path.substr(scalar.size()) +
                                        ": not stepped in SIMD lanes (docs/simd_batch.md); "
                                        "Batch steps it as Simulations");
          return batch;
        });
      },
      py::arg("prototype"), py::arg("count"), py::arg("isa") = py::none(),
      "Deprecated: Batch(prototype, count) with Batch.isa = isa, ValueError naming the setting "
      "when the lanes would not step it (Batch.step_path).");
}
