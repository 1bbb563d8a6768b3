// Revolute wrap and mimic joints: Simulation.set_revolute_wrap, add_mimic_joint, MimicJoint,
// Scene.mimic (docs/math/revolute_wrap.md, docs/math/mimic_joints.md).
#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

void featherdrive::python::bind_joints(py::module_& m) {
  py::class_<MimicJoint>(m, "MimicJoint",
                         "A mimic joint: the row q[follower] + gear_ratio q[leader] + offset = 0 "
                         "(PhysX's PxArticulationMimicJoint; URDF's multiplier m and offset o are "
                         "gear_ratio -m and offset -o), rigid unless natural_frequency and "
                         "damping_ratio are both > 0.")
      .def_readonly("follower", &MimicJoint::dof_a, "the follower's dof (PhysX's joint A)")
      .def_readonly("leader", &MimicJoint::dof_b, "the leader's dof (PhysX's joint B)")
      .def_readonly("gear_ratio", &MimicJoint::gear_ratio)
      .def_readonly("offset", &MimicJoint::offset)
      .def_readonly("natural_frequency", &MimicJoint::natural_frequency, "rad/s; <= 0: rigid")
      .def_readonly("damping_ratio", &MimicJoint::damping_ratio, "<= 0: rigid")
      .def("__repr__", [](const MimicJoint& j) {
        return "MimicJoint(follower=" + std::to_string(j.dof_a) +
               ", leader=" + std::to_string(j.dof_b) + ", gear_ratio=" + fmt(j.gear_ratio) +
               ", offset=" + fmt(j.offset) + ", natural_frequency=" + fmt(j.natural_frequency) +
               ", damping_ratio=" + fmt(j.damping_ratio) + ")";
      });
  auto sim = py::reinterpret_borrow<py::class_<Simulation, SimulationHolder>>(m.attr("Simulation"));
  sim.def(
         "set_revolute_wrap",
         [](Simulation& s, py::handle joint, const std::string& wrap) {
           const RevoluteWrap w = parse_revolute_wrap(wrap);
           on_joint(s, joint, [&](int dof) { s.set_revolute_wrap(dof, w); });
         },
         py::arg("joint"), py::arg("wrap"),
         "'wrapped' (PhysX's eREVOLUTE: the position returns into [-2 pi, 2 pi] after each step) "
         "or 'unwrapped' (eREVOLUTE_UNWRAPPED) for a revolute joint (name or dof). Default "
         "unwrapped; wrapped with compat='physx'.")
      .def(
          "revolute_wrap",
          [](const Simulation& s, py::handle joint) {
            return on_joint(s, joint, [&](int dof) { return to_string(s.revolute_wrap(dof)); });
          },
          py::arg("joint"), "'wrapped' or 'unwrapped'.")
      .def(
          "add_mimic_joint",
          [](Simulation& s, py::handle follower, py::handle leader, double gear_ratio,
             double offset, double natural_frequency, double damping_ratio) {
            const NameOrIndex f = joint_arg(follower), l = joint_arg(leader);
            locked(s, [&] {
              std::vector<MimicJoint> rows = s.mimic_joints();
              rows.push_back({dof_of(s.model(), f), dof_of(s.model(), l), gear_ratio, offset,
                              natural_frequency, damping_ratio});
              s.set_mimic_joints(rows);
            });
          },
          py::arg("follower"), py::arg("leader"), py::arg("gear_ratio"), py::arg("offset") = 0.0,
          py::arg("natural_frequency") = 0.0, py::arg("damping_ratio") = 0.0,
          "Adds the row q[follower] + gear_ratio q[leader] + offset = 0 (joints by name or dof). "
          "ValueError for a joint that is not revolute or prismatic, a joint mimicking itself, a "
          "gear ratio 0 or not finite, or a cycle of mimic joints; nothing changes then.")
      .def(
          "clear_mimic_joints", [](Simulation& s) { locked(s, [&] { s.set_mimic_joints({}); }); },
          "Removes every mimic joint.")
      .def(
          "mimic_joints",
          [](const Simulation& s) { return locked(s, [&] { return s.mimic_joints(); }); },
          "The mimic joints (a list of MimicJoint, copies).");
  auto scene = py::reinterpret_borrow<py::class_<Scene>>(m.attr("Scene"));
  scene
      .def_readonly("mimic", &Scene::mimic,
                    "the mimic joints: the URDF's <mimic> rows, then the scene's mimic list")
      .def_property_readonly(
          "applied_forces",
          [](const Scene& s) {
            py::dict forces;
            for (const AppliedForceSpec& f : s.applied_forces)
              forces[py::str(f.joint)] = f.sine ? py::cast(*f.sine) : py::cast(f.value);
            return forces;
          },
          "applied_force: {joint: force (N or Nm) or SineTarget}, a new dict");
}
