// Drive delays: Simulation.set_drive_delay, Batch.set_drive_delay, DriveSpec.delay
// (sim/drive_delay.hpp; docs/math/implicit_drives.md, "Delay").
#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

void featherdrive::python::bind_delay(py::module_& m) {
  auto sim = py::reinterpret_borrow<py::class_<Simulation, SimulationHolder>>(m.attr("Simulation"));
  sim.def(
         "set_drive_delay",
         [](Simulation& s, py::handle joint, py::handle delay) {
           const int k = to_int(delay, "delay", std::numeric_limits<int>::min());
           on_joint(s, joint, [&](int dof) { s.set_drive_delay(dof, k); });
         },
         py::arg("joint"), py::arg("delay"),
         "The joint's (name or dof) implicit drive uses the targets set delay steps earlier "
         "(0 to 100000; 0: none) and its history starts over. ValueError without a drive of type "
         "force or acceleration; drive() keeps reporting the targets as set.")
      .def(
          "drive_delay",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.drive_delay(dof); });
          },
          py::arg("joint"), "The delay in steps of a joint's (name or dof) drive.")
      .def(
          "reset_drive_delay_history",
          [](Simulation& s) { locked(s, [&] { s.reset_drive_delay_history(); }); },
          "Empties every drive's delay history (the next step sees the targets set for it).");
  auto batch = py::reinterpret_borrow<py::class_<Batch, BatchHolder>>(m.attr("Batch"));
  batch
      .def(
          "set_drive_delay",
          [](Batch& b, py::handle delays, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(delays, ids.size(), model_of(b)->nv, "delays");
            locked(b, [&] { b.set_drive_delay(ids, v); });
          },
          py::arg("delays"), py::arg("env_ids") = py::none(),
          "Drive delays in steps (whole numbers) of env_ids (None: all): a scalar, (nv,) or "
          "(k, nv); their histories start over. Nothing changes on a ValueError.")
      .def(
          "drive_delay",
          [](const Batch& b) { return read_only(locked(b, [&] { return b.drive_delay(); })); },
          "The drive delays (N, nv), a new array.");
  auto spec = py::reinterpret_borrow<py::class_<DriveSpec>>(m.attr("DriveSpec"));
  spec.def_readonly("delay", &DriveSpec::delay, "the drive's delay in steps (key delay)");
}
