// The stability check (docs/stability_check.md): fd.check(scene path or Simulation).
#include "bindings.hpp"
#include "featherdrive/io/scene_check.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

void featherdrive::python::bind_check(py::module_& m) {
  py::enum_<JointLaw>(m, "JointLaw", "What acts on a dof in the one-joint step map.")
      .value("none", JointLaw::none)
      .value("drive", JointLaw::drive)
      .value("explicit_pd", JointLaw::explicit_pd)
      .value("implicit_pd", JointLaw::implicit_pd);
  py::class_<JointStability>(m, "JointStability",
                             "One dof's one-joint step map at the initial state and its fixes.")
      .def_readonly("joint", &JointStability::joint)
      .def_readonly("dof", &JointStability::dof)
      .def_readonly("axis", &JointStability::axis)
      .def_readonly("law", &JointStability::law)
      .def_readonly("mass", &JointStability::mass)
      .def_readonly("stiffness_ratio", &JointStability::stiffness_ratio)
      .def_readonly("damping_ratio", &JointStability::damping_ratio)
      .def_readonly("rho", &JointStability::rho)
      .def_readonly("stable", &JointStability::stable)
      .def_readonly("substeps", &JointStability::substeps)
      .def_readonly("armature", &JointStability::armature)
      .def_readonly("damping", &JointStability::damping)
      .def("__repr__", [](const JointStability& j) {
        return "JointStability(" + j.joint + (j.axis >= 0 ? "[" + std::to_string(j.axis) + "]" : "") +
               ", rho=" + std::to_string(j.rho) + (j.stable ? ", stable)" : ", unstable)");
      });
  py::class_<RobotStability>(m, "RobotStability", "The whole robot: linearised step, trial run.")
      .def_readonly("linear_rho", &RobotStability::linear_rho)
      .def_readonly("linear_dofs", &RobotStability::linear_dofs)
      .def_readonly("linear_stable", &RobotStability::linear_stable)
      .def_readonly("trial_steps", &RobotStability::trial_steps)
      .def_readonly("trial_bounded", &RobotStability::trial_bounded)
      .def_readonly("trial_note", &RobotStability::trial_note)
      .def_readonly("substeps", &RobotStability::substeps);
  py::class_<StabilityReport>(m, "StabilityReport", "fd.check's result.")
      .def_readonly("joints", &StabilityReport::joints)
      .def_readonly("robot", &StabilityReport::robot)
      .def_readonly("stable", &StabilityReport::stable)
      .def_readonly("verdict", &StabilityReport::verdict)
      .def("__repr__", [](const StabilityReport& r) { return "StabilityReport(" + r.verdict + ")"; });
  m.def(
      "check",
      [](py::object what, std::optional<int> trial_steps) -> StabilityReport {
        StabilityCheckOptions options;
        if (trial_steps) options.min_trial_steps = options.max_trial_steps = *trial_steps;
        if (py::isinstance<Simulation>(what)) {
          const Simulation& sim = what.cast<const Simulation&>();
          StabilityReport report;
          locked_nogil(sim, [&] { report = check_stability(sim, options); });
          return report;
        }
        if (!py::isinstance<py::str>(what) &&
            !py::isinstance(what, py::module_::import("os").attr("PathLike")))
          throw py::type_error("check: expected a scene path (str or os.PathLike) or a "
                               "Simulation, got " +
                               std::string(py::str(what.get_type().attr("__name__"))));
        const std::filesystem::path path = what.cast<std::filesystem::path>();
        py::gil_scoped_release nogil;
        return check_scene(load_scene(path), options);
      },
      py::arg("scene"), py::arg("trial_steps") = py::none(),
      "Will the run stay bounded? Per dof the one-joint step map at the initial state (and the "
      "smallest substeps, armature and damping that make an unstable one stable), for the robot "
      "a linearised step and a trial run (a scene's: following its targets). .verdict is "
      "'stable' or 'unstable: ...', .stable the same as a bool. trial_steps: the trial's length "
      "(default: 2 s, 500 to 1000 steps; 0: none, the linearised step decides). ValueError for "
      "a bad scene or trial_steps outside [0, 100000].");
}
