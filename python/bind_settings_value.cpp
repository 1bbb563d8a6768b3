// Every setting as one value (sim/settings.hpp; docs/architecture.md, "Model, Settings, State,
// Workspace"): fd.Settings, Simulation.settings / set_settings, Simulation(model, settings),
// Batch(model, count, settings), and what the importers give: fd.robot_settings,
// fd.scene_settings.
#include "bindings.hpp"
#include "featherdrive/io/mjcf.hpp"
#include "featherdrive/io/scene.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

namespace {

// A vector field as a writable numpy view into the value (def_readwrite's is read-only).
template <class C>
void vector_field(C& c, const char* name, VecX Settings::*field, const char* doc) {
  c.def_property(
      name,
      py::cpp_function([field](Settings& s) -> VecX& { return s.*field; },
                       py::return_value_policy::reference_internal),
      [field](Settings& s, const VecX& v) { s.*field = v; }, doc);
}

}  // namespace

void featherdrive::python::bind_settings_value(py::module_& m) {
  auto settings = py::class_<Settings>(
      m, "Settings",
      "Every setting of a simulation as one value: options and, per dof, joint and link, drives, "
      "limits, friction, envelopes, actuators, delays, wrap, mimic rows, ground and contact "
      "options. The vectors are numpy arrays that write into the value; the lists (drives, "
      "friction, ...) are copies: assign a whole list to change one.")
      .def_static(
          "defaults",
          [](const ModelPtr& model, const std::optional<SimulationOptions>& options) {
            return Settings::defaults(*model, options.value_or(SimulationOptions{}));
          },
          py::arg("model"), py::arg("options") = py::none(),
          "What a new Simulation of model starts with (the model's limits, friction and "
          "velocity limits; PhysX's defaults with compat='physx').")
      .def(
          "validate", [](const Settings& s, const ModelPtr& model) { s.validate(*model); },
          py::arg("model"),
          "ValueError with the message of the first setting a Simulation setter would refuse.")
      .def("copy", [](const Settings& s) { return Settings(s); }, "An independent copy.")
      .def_readwrite("options", &Settings::options, "SimulationOptions (a copy)")
      .def_readwrite("drives", &Settings::drives, "list of Drive, one per dof")
      .def_readwrite("friction", &Settings::friction, "list of JointFriction, one per dof")
      .def_readwrite("envelopes", &Settings::envelopes, "list of ActuatorEnvelope, one per dof")
      .def_property(
          "revolute_wrap",
          [](const Settings& s) {
            std::vector<std::string> out;
            for (RevoluteWrap w : s.revolute_wrap) out.emplace_back(to_string(w));
            return out;
          },
          [](Settings& s, const std::vector<std::string>& wraps) {
            std::vector<RevoluteWrap> out;
            for (const std::string& w : wraps) out.push_back(parse_revolute_wrap(w));
            s.revolute_wrap = std::move(out);
          },
          "list of 'wrapped' or 'unwrapped', one per dof")
      .def_readwrite("drive_delay", &Settings::drive_delay, "list of int, steps, one per dof")
      .def_readwrite("actuators", &Settings::actuators, "list of ExplicitActuator, one per dof")
      .def_readwrite("link_parameters", &Settings::link_parameters,
                     "list of LinkParameters, one per link")
      .def_readwrite("mimic_joints", &Settings::mimic_joints, "list of MimicJoint")
      .def_readwrite("ground", &Settings::ground, "Ground (a copy)")
      .def_readwrite("contact", &Settings::contact, "ContactOptions (a copy)")
      .def("__repr__", [](const Settings& s) {
        return "Settings(nv=" + std::to_string(s.drives.size()) +
               ", links=" + std::to_string(s.link_parameters.size()) +
               ", dt=" + fmt(s.options.dt) + ", " + to_string(s.options.solver) + ")";
      });
  vector_field(settings, "lower_limit", &Settings::lower_limit, "(nv,), enforced where finite");
  vector_field(settings, "upper_limit", &Settings::upper_limit, "(nv,), enforced where finite");
  vector_field(settings, "max_joint_velocity", &Settings::max_joint_velocity,
               "(nv,); inf for none");
  vector_field(settings, "friction_coefficient", &Settings::friction_coefficient,
               "(nv,), PhysX's older joint friction");
  vector_field(settings, "actuator_feedforward", &Settings::actuator_feedforward,
               "(nv,), each actuator's feed-forward effort");

  auto sim = py::reinterpret_borrow<py::class_<Simulation, SimulationHolder>>(m.attr("Simulation"));
  sim.def(py::init([](ModelPtr model, const Settings& settings) {
            return Simulation(std::move(model), settings);
          }),
          py::arg("model"), py::arg("settings"),
          "A simulation with these settings (fd.robot_settings, fd.scene_settings, another's "
          "settings); ValueError as set_settings.")
      .def_property_readonly(
          "settings", [](const Simulation& s) { return locked(s, [&] { return s.settings(); }); },
          "Every setting as one Settings value (a copy).")
      .def(
          "set_settings",
          [](Simulation& s, const Settings& settings) {
            locked(s, [&] { s.set_settings(settings); });
          },
          py::arg("settings"),
          "Replaces every setting; ValueError naming the first bad one, and nothing changes "
          "then. Delay histories of the actuators and delays that change start over.");

  auto batch = py::reinterpret_borrow<py::class_<Batch, BatchHolder>>(m.attr("Batch"));
  batch.def(py::init([](ModelPtr model, py::handle count, const Settings& settings) {
              const int n = to_int(count, "count", 1, Batch::kMaxSize);
              return BatchHolder(new Batch(std::move(model), n, settings));
            }),
            py::arg("model"), py::arg("count"), py::arg("settings"),
            "count environments, each a new Simulation of model with these settings.");

  // The MJCF overload first: pybind11 takes the first that accepts the robot.
  const char* const robot_doc =
      "What the robot file says beyond the Model, as Settings: the defaults with options, its "
      "mimic rows, an MJCF file's actuators (as apply_mjcf_actuators) and joint springs (its "
      "hinges' and slides' stiffness), the effort limits as "
      "robot.options.effort says.";
  m.def(
      "robot_settings",
      [](const MjcfRobot& robot, const std::optional<SimulationOptions>& options) {
        return robot_settings(robot, options.value_or(SimulationOptions{}));
      },
      py::arg("robot"), py::arg("options") = py::none(), robot_doc);
  m.def(
      "robot_settings",
      [](const UrdfRobot& robot, const std::optional<SimulationOptions>& options) {
        return robot_settings(robot, options.value_or(SimulationOptions{}));
      },
      py::arg("robot"), py::arg("options") = py::none(), robot_doc);
  m.def("scene_settings", &scene_settings, py::arg("scene"),
        "Every setting the scene gives, as the Settings make_simulation's simulation holds; "
        "InputError (a ValueError) naming the scene and the first bad value.");
}
