// fd.sweep: the gain sweep of python/featherdrive_sweep.py (docs/fitting.md, "Sweeps and Dask"),
// forwarded so that it is found beside the rest of the API.
#include "bindings.hpp"

namespace py = pybind11;

void featherdrive::python::bind_sweep(py::module_& m) {
  m.def(
      "sweep",
      [](py::args args, py::kwargs kwargs) {
        return py::module_::import("featherdrive_sweep").attr("sweep")(*args, **kwargs);
      },
      "sweep(scene, grid, joint=None, client=None, num_threads=0, chunk_size=None): the tracking "
      "error over a grid of gains, a SweepResult (featherdrive_sweep.sweep; docs/fitting.md).");
}
