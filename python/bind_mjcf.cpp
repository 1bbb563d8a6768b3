// MJCF import (io/mjcf.hpp): fd.load_mjcf and fd.parse_mjcf give an MjcfRobot, a UrdfRobot with
// the file's actuators and MuJoCo's qpos0.
#include "bindings.hpp"
#include "featherdrive/io/mjcf.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

namespace {

// options (a UrdfOptions or None), then fixed_base (a bool or None) over it.
UrdfOptions mjcf_options(py::handle options, py::handle fixed_base, const char* function) {
  UrdfOptions o;
  if (!options.is_none()) {
    if (!py::isinstance<UrdfOptions>(options))
      throw py::type_error(std::string(function) + ": options must be a UrdfOptions, not " +
                           type_name(options));
    o = options.cast<UrdfOptions>();
  }
  if (!fixed_base.is_none()) {
    if (!py::isinstance<py::bool_>(fixed_base))
      throw py::type_error(std::string(function) + ": fixed_base must be a bool, not " +
                           type_name(fixed_base));
    o.fixed_base = fixed_base.cast<bool>();
  }
  return o;
}

}  // namespace

void featherdrive::python::bind_mjcf(py::module_& m) {
  py::class_<MjcfActuator>(m, "MjcfActuator",
                           "An MJCF actuator on a hinge or slide and its featherdrive form "
                           "(docs/mujoco_bridge.md, 'Importing MJCF').")
      .def_readonly("name", &MjcfActuator::name, "the actuator's name")
      .def_readonly("joint", &MjcfActuator::joint, "the joint it drives")
      .def_readonly("dof", &MjcfActuator::dof, "that joint's dof")
      .def_property_readonly(
          "kind", [](const MjcfActuator& a) { return std::string(to_string(a.kind)); },
          "'motor' | 'position' | 'velocity'")
      .def_readonly("gear", &MjcfActuator::gear, "joint effort = gear * actuator force")
      .def_readonly("gain", &MjcfActuator::gain, "kp, kv or the motor's gain")
      .def_readonly("force_lower", &MjcfActuator::force_lower, "forcerange (-inf: none)")
      .def_readonly("force_upper", &MjcfActuator::force_upper, "forcerange (inf: none)")
      .def_readonly("ctrl_lower", &MjcfActuator::ctrl_lower, "ctrlrange (-inf: none)")
      .def_readonly("ctrl_upper", &MjcfActuator::ctrl_upper, "ctrlrange (inf: none)")
      .def_readonly("actuator", &MjcfActuator::actuator,
                    "the ExplicitActuator it maps to (kind none for a motor); target ctrl / gear");

  py::class_<MjcfRobot, UrdfRobot>(m, "MjcfRobot",
                                   "A robot read from MJCF: a UrdfRobot (links are bodies, joint "
                                   "names the file's) with the actuators and MuJoCo's qpos0.")
      .def_readonly("actuators", &MjcfRobot::actuators, "list of MjcfActuator, MuJoCo's order")
      .def_property_readonly(
          "q0", [](const MjcfRobot& r) { return VecX(r.q0); },
          "MuJoCo's qpos0 as featherdrive's q (nq,), a copy: q equals MuJoCo's qpos");

  m.def(
      "apply_mjcf_actuators",
      [](const MjcfRobot& robot, Simulation& sim) {
        locked(sim, [&] { apply_mjcf_actuators(robot, sim); });
      },
      py::arg("robot"), py::arg("sim"),
      "Gives sim the explicit ideal_pd form of robot's position and velocity actuators (one per "
      "joint, gains summed); targets are ctrl / gear.");
  m.def(
      "load_mjcf",
      [](const std::filesystem::path& path, py::handle options, py::handle fixed_base) {
        return load_mjcf(path, mjcf_options(options, fixed_base, "load_mjcf"));
      },
      py::arg("path"), py::arg("options") = py::none(), py::arg("fixed_base") = py::none(),
      "Reads an MJCF file through MuJoCo 2.2.2's compiler; fixed_base (default True) welds a "
      "free root where it stands and overrides options.fixed_base. InputError (a ValueError) "
      "naming the file: MuJoCo's load error, tendons, equality constraints.");
  m.def(
      "parse_mjcf",
      [](const std::string& xml, const std::string& name, py::handle options,
         py::handle fixed_base) {
        return parse_mjcf(xml, name, mjcf_options(options, fixed_base, "parse_mjcf"));
      },
      py::arg("xml"), py::arg("name"), py::arg("options") = py::none(),
      py::arg("fixed_base") = py::none(), "Reads MJCF text; name stands for the file in messages.");
}
