// URDF import, scenes and checkpoints.
#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

void featherdrive::python::bind_io(py::module_& m) {
  // ---- io -------------------------------------------------------------------------------------
  py::enum_<UrdfEffort>(m, "UrdfEffort", "What a URDF <limit effort> becomes.")
      .value("none", UrdfEffort::none, "informative only")
      .value("max_force", UrdfEffort::max_force, "every implicit drive's max_force")
      .value("effort_limit", UrdfEffort::effort_limit, "every explicit actuator's effort_limit");
  py::class_<UrdfOptions>(m, "UrdfOptions", "How to import a URDF.")
      .def(py::init([](bool fixed_base, py::handle gravity, py::handle effort) {
             UrdfOptions o;
             o.fixed_base = fixed_base;
             o.gravity = to_vec3(gravity, "gravity");
             o.effort = to_urdf_effort(effort);
             return o;
           }),
           py::arg("fixed_base") = true, py::arg("gravity") = py::make_tuple(0.0, 0.0, -9.81),
           py::arg("effort") = UrdfEffort::none,
           "fixed_base False gives the root a floating joint; effort: what <limit effort> "
           "becomes, 'none' | 'max_force' | 'effort_limit' (apply_urdf_effort_limits).")
      .def_property(
          "effort", [](const UrdfOptions& o) { return o.effort; },
          [](UrdfOptions& o, py::handle e) { o.effort = to_urdf_effort(e); },
          "UrdfEffort: none, max_force (drives) or effort_limit (explicit actuators)")
      .def_readwrite("fixed_base", &UrdfOptions::fixed_base, "root welded to the world")
      .def_property(
          "gravity", [](const UrdfOptions& o) { return o.gravity; },
          [](UrdfOptions& o, py::handle g) { o.gravity = to_vec3(g, "gravity"); }, "gravity (3,)");

  py::class_<UrdfMimic>(m, "UrdfMimic", "A <mimic> tag (read, not simulated).")
      .def_readonly("joint", &UrdfMimic::joint, "the mimicking joint")
      .def_readonly("leader", &UrdfMimic::leader, "the joint it follows")
      .def_readonly("multiplier", &UrdfMimic::multiplier, "joint = multiplier * leader + offset")
      .def_readonly("offset", &UrdfMimic::offset, "joint = multiplier * leader + offset");

  py::class_<UrdfRobot>(m, "UrdfRobot", "A robot read from URDF and its Model.")
      .def_readonly("path", &UrdfRobot::path, "the file")
      .def_readonly("input_files", &UrdfRobot::input_files,
                    "every file the loader read: the robot file, an MJCF's includes and its "
                    "mesh, skin, hfield and texture files (outputs must not replace them)")
      .def_readonly("name", &UrdfRobot::name, "<robot name>")
      .def_readonly("root_link", &UrdfRobot::root_link, "root link name")
      .def_readonly("root_joint", &UrdfRobot::root_joint, "name of the root's joint")
      .def_property_readonly(
          "options", [](const UrdfRobot& r) { return r.options; }, "the UrdfOptions (a copy)")
      .def_readwrite("links", &UrdfRobot::links,
                     "the LinkSpecs after merging (a copy; assign an edited list and call "
                     "rebuild())")
      .def_property_readonly(
          "model", [](const UrdfRobot& r) { return to_python(r.model); }, "The Model.")
      .def_readonly("joint_order", &UrdfRobot::joint_order, "every <joint> in document order")
      .def_readonly("dof_order", &UrdfRobot::dof_order, "model dofs in URDF document order")
      .def_readonly("mimics", &UrdfRobot::mimics, "list of UrdfMimic")
      .def_readonly("warnings", &UrdfRobot::warnings, "messages for the user")
      .def_readonly("effort_limits", &UrdfRobot::effort_limits, "URDF effort limit per joint")
      .def("rebuild", &UrdfRobot::rebuild, "Builds model from links again.");

  m.def(
      "apply_urdf_effort_limits",
      [](const UrdfRobot& robot, Simulation& sim) {
        locked(sim, [&] { apply_urdf_effort_limits(robot, sim); });
      },
      py::arg("robot"), py::arg("sim"),
      "Gives the URDF effort limits to sim's drives (max_force) or explicit actuators "
      "(effort_limit) that have none, as robot.options.effort says.");
  m.def("load_urdf", &load_urdf, py::arg("path"), py::arg("options") = UrdfOptions{},
        "Reads a URDF file; InputError (a ValueError) naming the file, element and value.");
  m.def("parse_urdf", &parse_urdf, py::arg("xml"), py::arg("name"),
        py::arg("options") = UrdfOptions{},
        "Reads URDF text; name stands for the file in messages.");

  py::class_<SineTarget>(m, "SineTarget", "offset + amplitude sin(2 pi frequency t + phase).")
      .def_readonly("amplitude", &SineTarget::amplitude, "amplitude")
      .def_readonly("frequency", &SineTarget::frequency, "Hz")
      .def_readonly("phase", &SineTarget::phase, "rad")
      .def_readonly("offset", &SineTarget::offset, "offset")
      .def("position", &SineTarget::position, py::arg("t"), "Target position at t.")
      .def("velocity", &SineTarget::velocity, py::arg("t"), "Target velocity at t.");

  py::class_<DriveSpec>(m, "DriveSpec", "A scene's drive on one joint.")
      .def_readonly("joint", &DriveSpec::joint, "joint name")
      .def_readonly("dof", &DriveSpec::dof, "dof index")
      .def_readonly("drive", &DriveSpec::drive, "the Drive")
      .def_readonly("sine", &DriveSpec::sine, "SineTarget or None")
      .def_readonly("actuator", &DriveSpec::actuator, "ExplicitActuator or None")
      .def("target_at", &DriveSpec::target_at, py::arg("t"), "(position, velocity) at t.");

  py::class_<Scene>(m, "Scene", "A scene file: robot, options, initial state and drives.")
      .def_readonly("path", &Scene::path, "the scene file")
      .def_readonly("model_path", &Scene::model_path, "the URDF")
      // Copies: a reference would let Python edit the scene's robot and options in place.
      .def_property_readonly(
          "robot", [](const Scene& s) { return s.robot; }, "the UrdfRobot (a copy)")
      .def_property_readonly(
          "options", [](const Scene& s) { return s.options; }, "the SimulationOptions (a copy)")
      .def_readonly("steps", &Scene::steps, "number of steps")
      .def_readonly("q0", &Scene::q0, "initial q (nq,)")
      .def_readonly("qd0", &Scene::qd0, "initial qd (nv,)")
      .def_readonly("drives", &Scene::drives, "list of DriveSpec in URDF joint order")
      .def_property_readonly(
          "model", [](const Scene& s) { return to_python(s.model()); }, "The Model.");

  m.def("load_scene", &load_scene, py::arg("path"),
        "Reads a scene file (YAML or JSON); InputError (a ValueError) naming the file, key and "
        "value.");
  m.def("parse_scene", &parse_scene, py::arg("text"), py::arg("path"),
        "Reads scene text; path names the file and anchors the model path.");
  m.def("make_simulation", &make_simulation, py::arg("scene"),
        "A Simulation in the scene's initial state with its drives and joint settings.");
  m.def(
      "apply_targets",
      [](const Scene& scene, Simulation& sim, py::handle step_index) {
        // k + 1 must fit the C++ int.
        const int k = to_int(step_index, "apply_targets: step_index", 0, kIntMax - 1);
        locked(sim, [&] { apply_targets(scene, sim, k); });
      },
      py::arg("scene"), py::arg("sim"), py::arg("step_index"),
      "Sets the sine targets for step k (0-based, at most 2**31 - 2): those at t = (k + 1) dt.");

  py::register_exception<CheckpointError>(m, "CheckpointError", PyExc_ValueError).doc() =
      "A file that is not a checkpoint of this model (truncated, corrupt, other version or "
      "model); a ValueError.";
  m.def(
      "save_checkpoint",
      [](const Simulation& sim, const std::filesystem::path& path) {
        locked_nogil(sim, [&] { save_checkpoint(sim, path); });
      },
      py::arg("sim"), py::arg("path"),
      "Writes the full simulation state (state, clock, inputs, settings, last forces) "
      "atomically, bit-exact.");
  m.def(
      "load_checkpoint",
      [](const std::filesystem::path& path, Simulation& sim) {
        locked_nogil(sim, [&] { load_checkpoint(path, sim); });
      },
      py::arg("path"), py::arg("sim"),
      "Restores a checkpoint into sim (same model) in place: views of sim stay valid and show "
      "the restored state. CheckpointError and sim unchanged otherwise.");
}
