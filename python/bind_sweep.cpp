// fd.sweep: the gain sweep of python/featherdrive_sweep.py (docs/fitting.md, "Sweeps and Dask"),
// forwarded so that it is found beside the rest of the API; and the C++ commands' input rule
// (read_input_file), which the Python commands (fit, sweep, view) read their inputs through.
#include "bindings.hpp"
#include "featherdrive/io/files.hpp"

namespace py = pybind11;

void featherdrive::python::bind_sweep(py::module_& m) {
  m.def(
      "sweep",
      [](py::args args, py::kwargs kwargs) {
        return py::module_::import("featherdrive_sweep").attr("sweep")(*args, **kwargs);
      },
      "sweep(scene, grid, joint=None, client=None, num_threads=0, chunk_size=None, "
      "objective='rms'): the tracking error over a grid of gains, a SweepResult "
      "(featherdrive_sweep.sweep; docs/fitting.md).");

  m.attr("MAX_INPUT_BYTES") = py::int_(static_cast<unsigned long long>(kMaxInputBytes));
  m.def(
      "read_input_file",
      [](const std::filesystem::path& path, const std::string& what) {
        std::string bytes;
        {
          py::gil_scoped_release nogil;
          bytes = read_input_file(path, what.c_str());
        }
        return py::bytes(bytes);
      },
      py::arg("path"), py::arg("what") = "the file",
      "The bytes of an input file as the commands read them: InputError (a ValueError), one line "
      "naming the file, for a file that cannot be opened, a directory, a file that is not regular "
      "(a FIFO or a device: refused without reading) or one larger than MAX_INPUT_BYTES (64 MiB).");
}
