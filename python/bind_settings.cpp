// Enums and the settings structs: Drive, JointFriction, actuators, LinkParameters, options.
#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

void featherdrive::python::bind_settings(py::module_& m) {
  // ---- enums ----------------------------------------------------------------------------------
  py::enum_<JointType>(m, "JointType", "The type of a link's inbound joint.")
      .value("fixed", JointType::fixed, "welds the link to its parent, 0 dofs")
      .value("revolute", JointType::revolute, "rotation about the axis, 1 dof")
      .value("prismatic", JointType::prismatic, "translation along the axis, 1 dof")
      .value("spherical", JointType::spherical, "free rotation: nq = 4 (quaternion), nv = 3")
      .value("floating", JointType::floating, "root only: nq = 7, nv = 6");
  py::enum_<DriveType>(m, "DriveType", "The kind of a joint drive.")
      .value("none", DriveType::none, "no drive on this dof")
      .value("force", DriveType::force, "stiffness in N/m or Nm/rad, damping in Ns/m or Nms/rad")
      .value("acceleration", DriveType::acceleration,
             "stiffness in 1/s^2, damping in 1/s: a mass-free response");
  py::enum_<SolverType>(m, "SolverType", "The constraint solver.")
      .value("pgs", SolverType::pgs, "projected Gauss-Seidel")
      .value("tgs", SolverType::tgs, "temporal Gauss-Seidel (sub-stepped)");

  // ---- settings structs -----------------------------------------------------------------------
  py::class_<Drive>(m, "Drive", "A drive's settings (all of them may change between steps).")
      .def(py::init([](py::handle type, double stiffness, double damping, double max_force,
                       double target_position, double target_velocity, double max_impulse) {
             Drive d;
             d.type = to_drive_type(type);
             d.stiffness = stiffness;
             d.damping = damping;
             d.max_force = max_force;
             d.target_position = target_position;
             d.target_velocity = target_velocity;
             d.max_impulse = max_impulse;
             return d;
           }),
           py::arg("type") = DriveType::force, py::arg("stiffness") = 0.0, py::arg("damping") = 0.0,
           py::arg("max_force") = kInf, py::arg("target_position") = 0.0,
           py::arg("target_velocity") = 0.0, py::arg("max_impulse") = kInf,
           "A drive; type is a DriveType or 'none' | 'force' | 'acceleration'. Checked when "
           "given to Simulation.set_drive.")
      .def_readwrite("type", &Drive::type, "DriveType")
      .def_readwrite("stiffness", &Drive::stiffness, "N/m or Nm/rad (force), 1/s^2 (acceleration)")
      .def_readwrite("damping", &Drive::damping, "Ns/m or Nms/rad (force), 1/s (acceleration)")
      .def_readwrite("max_force", &Drive::max_force,
                     "largest drive force; the step's impulse is limited to max_force * dt")
      .def_readwrite("target_position", &Drive::target_position, "target position (m or rad)")
      .def_readwrite("target_velocity", &Drive::target_velocity, "target velocity (m/s or rad/s)")
      .def_readwrite("max_impulse", &Drive::max_impulse,
                     "largest drive impulse of a step; set at most one of max_force, max_impulse")
      .def("__repr__", [](const Drive& d) {
        return std::string("Drive(type='") + to_string(d.type) +
               "', stiffness=" + fmt(d.stiffness) + ", damping=" + fmt(d.damping) +
               ", max_force=" + fmt(d.max_force) + ", target_position=" + fmt(d.target_position) +
               ", target_velocity=" + fmt(d.target_velocity) +
               ", max_impulse=" + fmt(d.max_impulse) + ")";
      });

  py::class_<JointFriction>(m, "JointFriction",
                            "Joint friction: static and dynamic efforts (N or Nm) and viscous "
                            "friction (Ns/m or Nms/rad).")
      .def(py::init([](double s, double d, double v) {
             return JointFriction{s, d, v};
           }),
           py::arg("static_effort") = 0.0, py::arg("dynamic_effort") = 0.0,
           py::arg("viscous") = 0.0, "Joint friction settings.")
      .def_readwrite("static_effort", &JointFriction::static_effort, "N or Nm")
      .def_readwrite("dynamic_effort", &JointFriction::dynamic_effort, "N or Nm")
      .def_readwrite("viscous", &JointFriction::viscous, "Ns/m or Nms/rad")
      .def("active", &JointFriction::active, "Whether any friction is set.");

  py::class_<ActuatorEnvelope>(m, "ActuatorEnvelope",
                               "A DC-motor-like limit on a drive's effort (none while "
                               "max_effort = 0).")
      .def(py::init([](double max_effort, double max_actuator_velocity, double gradient,
                       double resistance) {
             return ActuatorEnvelope{max_effort, max_actuator_velocity, gradient, resistance};
           }),
           py::arg("max_effort") = 0.0, py::arg("max_actuator_velocity") = kInf,
           py::arg("speed_effort_gradient") = 0.0, py::arg("velocity_dependent_resistance") = 0.0,
           "An actuator envelope.")
      .def_readwrite("max_effort", &ActuatorEnvelope::max_effort, "N or Nm; 0 = no envelope")
      .def_readwrite("max_actuator_velocity", &ActuatorEnvelope::max_actuator_velocity,
                     "m/s or rad/s")
      .def_readwrite("speed_effort_gradient", &ActuatorEnvelope::speed_effort_gradient,
                     "effort lost per unit speed")
      .def_readwrite("velocity_dependent_resistance",
                     &ActuatorEnvelope::velocity_dependent_resistance,
                     "opposing effort per unit speed")
      .def("active", &ActuatorEnvelope::active, "Whether the envelope limits the drive.");

  // Explicit actuators (docs/math/explicit_actuators.md): one class with a kind, and a factory
  // per Isaac Lab model with keyword arguments.
  py::enum_<ActuatorKind>(m, "ActuatorKind", "Which explicit actuator model (Isaac Lab's).")
      .value("none", ActuatorKind::none, "no explicit actuator")
      .value("ideal_pd", ActuatorKind::ideal_pd, "IdealPDActuator: PD clipped to effort_limit")
      .value("dc_motor", ActuatorKind::dc_motor, "DCMotor: within the torque-speed line")
      .value("remotized_pd", ActuatorKind::remotized_pd,
             "RemotizedPDActuator: within a position-dependent limit");
  py::enum_<ActuatorIntegration>(m, "ActuatorIntegration",
                                 "Where an actuator's law is evaluated "
                                 "(docs/math/implicit_actuators.md).")
      .value("explicit", ActuatorIntegration::explicit_law,
             "on the step-start state, applied through the step (Isaac Lab's)")
      .value("implicit", ActuatorIntegration::implicit_law,
             "at the step's end, solved as the dof's row: stable at any gain");
  py::class_<ExplicitActuator>(m, "ExplicitActuator",
                               "An explicit actuator of one joint; checked when given to "
                               "Simulation.set_actuator.")
      .def(py::init([](py::handle kind, double kp, double kd, double effort_limit, double sat,
                       double speed, py::handle lookup, py::handle delay, py::handle integration) {
             return make_actuator(to_actuator_kind(kind), kp, kd, effort_limit, sat, speed, lookup,
                                  delay, integration);
           }),
           py::arg("kind") = ActuatorKind::ideal_pd, py::kw_only(), py::arg("stiffness") = 0.0,
           py::arg("damping") = 0.0, py::arg("effort_limit") = kInf,
           py::arg("saturation_effort") = 0.0, py::arg("velocity_limit") = 0.0,
           py::arg("lookup") = py::none(), py::arg("delay") = 0,
           py::arg("integration") = ActuatorIntegration::explicit_law,
           "kind: an ActuatorKind or its name; lookup: (n, 2) rows of (position, max effort); "
           "integration: 'explicit' or 'implicit' (or an ActuatorIntegration).")
      .def_readwrite("kind", &ExplicitActuator::kind, "ActuatorKind")
      .def_readwrite("stiffness", &ExplicitActuator::stiffness, "N/m or Nm/rad")
      .def_readwrite("damping", &ExplicitActuator::damping, "Ns/m or Nms/rad")
      .def_readwrite("effort_limit", &ExplicitActuator::effort_limit,
                     "the actuator's clip (N or Nm), apart from a drive's max_force")
      .def_readwrite("saturation_effort", &ExplicitActuator::saturation_effort,
                     "dc_motor: stall effort")
      .def_readwrite("velocity_limit", &ExplicitActuator::velocity_limit, "dc_motor: no-load speed")
      .def_property(
          "lookup",
          [](const ExplicitActuator& a) {
            RowMatrix t(static_cast<Eigen::Index>(a.lookup.size()), 2);
            for (size_t i = 0; i < a.lookup.size(); ++i)
              t.row(static_cast<Eigen::Index>(i)) << a.lookup[i].first, a.lookup[i].second;
            return read_only(std::move(t));
          },
          [](ExplicitActuator& a, py::handle t) { a.lookup = to_lookup(t); },
          "remotized_pd: (n, 2) rows of (position, max effort) (a copy)")
      .def_property(
          "delay", [](const ExplicitActuator& a) { return a.delay; },
          [](ExplicitActuator& a, py::handle d) {
            a.delay = to_int(d, "delay", 0, kMaxActuatorDelay);
          },
          "physics steps between a command and its effort")
      .def_property(
          "integration", [](const ExplicitActuator& a) { return a.integration; },
          [](ExplicitActuator& a, py::handle i) { a.integration = to_actuator_integration(i); },
          "ActuatorIntegration: explicit (the default) or implicit")
      .def("__repr__", [](const ExplicitActuator& a) {
        return std::string("ExplicitActuator('") + to_string(a.kind) +
               "', stiffness=" + fmt(a.stiffness) + ", damping=" + fmt(a.damping) +
               ", effort_limit=" + fmt(a.effort_limit) +
               ", saturation_effort=" + fmt(a.saturation_effort) +
               ", velocity_limit=" + fmt(a.velocity_limit) +
               ", lookup=" + std::to_string(a.lookup.size()) +
               " points, delay=" + std::to_string(a.delay) +
               ", integration='" + to_string(a.integration) + "')";
      });
  m.def(
      "IdealPD",
      [](double kp, double kd, double effort_limit, py::handle delay, py::handle integration) {
        return make_actuator(ActuatorKind::ideal_pd, kp, kd, effort_limit, 0.0, 0.0, py::none(),
                             delay, integration);
      },
      py::kw_only(), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0,
      py::arg("effort_limit") = kInf, py::arg("delay") = 0,
      py::arg("integration") = ActuatorIntegration::explicit_law,
      "Isaac Lab's IdealPDActuator (DelayedPDActuator with a delay): an ExplicitActuator.");
  m.def(
      "DCMotor",
      [](double kp, double kd, double effort_limit, double sat, double speed, py::handle delay,
         py::handle integration) {
        return make_actuator(ActuatorKind::dc_motor, kp, kd, effort_limit, sat, speed, py::none(),
                             delay, integration);
      },
      py::kw_only(), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0,
      py::arg("effort_limit") = kInf, py::arg("saturation_effort"), py::arg("velocity_limit"),
      py::arg("delay") = 0, py::arg("integration") = ActuatorIntegration::explicit_law,
      "Isaac Lab's DCMotor: an ExplicitActuator.");
  m.def(
      "RemotizedPD",
      [](double kp, double kd, py::handle lookup, double effort_limit, py::handle delay,
         py::handle integration) {
        return make_actuator(ActuatorKind::remotized_pd, kp, kd, effort_limit, 0.0, 0.0, lookup,
                             delay, integration);
      },
      py::kw_only(), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0, py::arg("lookup"),
      py::arg("effort_limit") = kInf, py::arg("delay") = 0,
      py::arg("integration") = ActuatorIntegration::explicit_law,
      "Isaac Lab's RemotizedPDActuator: an ExplicitActuator; lookup (n, 2) rows of (position, "
      "max effort).");

  py::enum_<Compat>(m, "Compat", "Whose defaults and step details a simulation follows.")
      .value("none", Compat::none, "featherdrive's ideal articulation")
      .value("physx", Compat::physx, "PhysX 5.6.1's defaults (docs/physx_parity.md)");

  py::class_<LinkParameters>(m, "LinkParameters",
                             "PhysX's per-link parameters: cfm scale, linear and angular damping "
                             "[1/s], max linear [m/s] and angular [rad/s] velocity.")
      .def(py::init([](double cfm, double ld, double ad, double mlv, double mav) {
             return LinkParameters{cfm, ld, ad, mlv, mav};
           }),
           py::arg("cfm_scale") = 0.0, py::arg("linear_damping") = 0.0,
           py::arg("angular_damping") = 0.0, py::arg("max_linear_velocity") = kInf,
           py::arg("max_angular_velocity") = kInf, "Link parameters (inert by default).")
      .def_readwrite("cfm_scale", &LinkParameters::cfm_scale, "in [0, 1]")
      .def_readwrite("linear_damping", &LinkParameters::linear_damping, "1/s")
      .def_readwrite("angular_damping", &LinkParameters::angular_damping, "1/s")
      .def_readwrite("max_linear_velocity", &LinkParameters::max_linear_velocity,
                     "m/s; inf for none")
      .def_readwrite("max_angular_velocity", &LinkParameters::max_angular_velocity,
                     "rad/s; inf for none")
      .def("__repr__", [](const LinkParameters& p) {
        std::string s = "LinkParameters(cfm_scale=";
        s += fmt(p.cfm_scale);
        s += ", linear_damping=";
        s += fmt(p.linear_damping);
        s += ", angular_damping=";
        s += fmt(p.angular_damping);
        s += ", max_linear_velocity=";
        s += fmt(p.max_linear_velocity);
        s += ", max_angular_velocity=";
        s += fmt(p.max_angular_velocity);
        s += ")";
        return s;
      });

  // The step guard (docs/math/step_guard.md); each value is checked as validate_options does.
  auto checked_guard = [](const StepGuard& g) {
    SimulationOptions o;
    o.guard = g;
    validate_options(o);
    return g;
  };
  // A setter of one double field that leaves the guard as it was if the value is refused.
  auto checked_setter = [checked_guard](double StepGuard::*field) {
    return [checked_guard, field](StepGuard& g, double v) {
      StepGuard next = g;
      next.*field = v;
      g = checked_guard(next);
    };
  };
  py::class_<StepGuard>(m, "StepGuard",
                        "The step guard: a step in which a joint moves more than max_joint_step "
                        "or the energy grows more than the joint forces' work is redone as 2, 4, "
                        "... sub-steps, at most max_substeps.")
      .def(py::init([checked_guard](bool enabled, double max_joint_step, py::handle max_substeps,
                                    double energy_tolerance, double dissipation_share) {
             return checked_guard(StepGuard{enabled, max_joint_step,
                                            to_int(max_substeps, "guard.max_substeps", 2,
                                                   kMaxGuardSubsteps),
                                            energy_tolerance, dissipation_share});
           }),
           py::arg("enabled") = true, py::arg("max_joint_step") = 0.25,
           py::arg("max_substeps") = 64, py::arg("energy_tolerance") = 0.02,
           py::arg("dissipation_share") = 0.15,
           "A guard (on unless enabled=False). Raises ValueError naming guard.max_joint_step "
           "(finite > 0), guard.max_substeps (in [2, 4096]), guard.energy_tolerance "
           "(in (0, 1]) or guard.dissipation_share (in (0, 100]).")
      .def_readwrite("enabled", &StepGuard::enabled)
      .def_property(
          "max_joint_step", [](const StepGuard& g) { return g.max_joint_step; },
          checked_setter(&StepGuard::max_joint_step),
          "rad or m per (sub-)step; a spherical joint's or floating base's rotation angle")
      .def_property(
          "max_substeps", [](const StepGuard& g) { return g.max_substeps; },
          [](StepGuard& g, py::handle n) {
            g.max_substeps = to_int(n, "guard.max_substeps", 2, kMaxGuardSubsteps);
          },
          "in [2, 4096]")
      .def_property(
          "energy_tolerance", [](const StepGuard& g) { return g.energy_tolerance; },
          checked_setter(&StepGuard::energy_tolerance),
          "test (ii)'s share of the step's energy scale, in (0, 1]")
      .def_property(
          "dissipation_share", [](const StepGuard& g) { return g.dissipation_share; },
          checked_setter(&StepGuard::dissipation_share),
          "test (iii)'s share of the dampers' dissipation the run may create, in (0, 100]")
      .def("__repr__", [](const StepGuard& g) {
        return std::string("StepGuard(enabled=") + (g.enabled ? "True" : "False") +
               ", max_joint_step=" + fmt(g.max_joint_step) +
               ", max_substeps=" + std::to_string(g.max_substeps) +
               ", energy_tolerance=" + fmt(g.energy_tolerance) +
               ", dissipation_share=" + fmt(g.dissipation_share) + ")";
      });

  py::class_<SimulationOptions>(m, "SimulationOptions", "Time step and solver settings.")
      .def(py::init(&make_options), py::arg("dt") = 1.0 / 60.0, py::arg("solver") = "pgs",
           py::arg("position_iterations") = 4, py::arg("velocity_iterations") = 1,
           py::arg("compat") = "none",
           "Options; solver is 'pgs' or 'tgs'. Raises ValueError for dt <= 0, "
           "position_iterations < 1 or velocity_iterations < 0.")
      .def_readwrite("dt", &SimulationOptions::dt, "time step [s]")
      .def_readwrite("solver", &SimulationOptions::solver, "SolverType")
      .def_property(
          "position_iterations", [](const SimulationOptions& o) { return o.position_iterations; },
          [](SimulationOptions& o, py::handle n) {
            o.position_iterations = to_int(n, "position_iterations", 1);
          },
          ">= 1")
      .def_property(
          "velocity_iterations", [](const SimulationOptions& o) { return o.velocity_iterations; },
          [](SimulationOptions& o, py::handle n) {
            o.velocity_iterations = to_int(n, "velocity_iterations", 0);
          },
          ">= 0")
      .def_readwrite("compat", &SimulationOptions::compat, "Compat, chosen at construction")
      .def_readwrite("guard", &SimulationOptions::guard, "StepGuard (off by default)")
      .def("__repr__", [](const SimulationOptions& o) {
        return "SimulationOptions(dt=" + fmt(o.dt) + ", solver='" + to_string(o.solver) +
               "', position_iterations=" + std::to_string(o.position_iterations) +
               ", velocity_iterations=" + std::to_string(o.velocity_iterations) + ")";
      });
  m.def("validate_options", &validate_options, py::arg("options"),
        "Raises ValueError naming the field and value for bad options.");
}
