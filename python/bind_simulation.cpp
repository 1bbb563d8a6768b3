// Simulation: state views, drives, joint settings, stepping.
#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

void featherdrive::python::bind_simulation(py::module_& m) {
  // ---- simulation -----------------------------------------------------------------------------
  // Every method holds the object's lock (see Hold) while it reads or writes the simulation, and
  // converts its Python arguments before (a conversion may run Python code that uses the object).
  // The views (q, qd, ...) are taken without it: creating one reads nothing.
  py::class_<Simulation, SimulationHolder>(m, "Simulation",
                                           "One simulation of a Model: state, drives, joint "
                                           "settings and the forces of the last step.")
      .def("__repr__",
           [](const Simulation& s) {
             return locked(s, [&] {
               const SimulationOptions& o = s.options();
               std::ostringstream r;
               r << "Simulation(nq=" << s.model().nq << ", nv=" << s.model().nv << ", "
                 << to_string(o.solver) << " " << o.position_iterations << "/"
                 << o.velocity_iterations << ", dt=" << o.dt << ", step " << s.step_count()
                 << ", t=" << s.time() << ")";
               return r.str();
             });
           })
      .def(
          py::init([](ModelPtr model, double dt, py::handle solver, py::handle pi, py::handle vi,
                      py::handle compat, py::handle kp, py::handle kd, py::handle type) {
            Simulation s(std::move(model), make_options(dt, solver, pi, vi, compat));
            initial_drives(s, kp, kd, type);
            return s;
          }),
          py::arg("model"), py::arg("dt") = 1.0 / 60.0, py::arg("solver") = "pgs",
          py::arg("position_iterations") = 4, py::arg("velocity_iterations") = 1,
          py::arg("compat") = "none", py::arg("stiffness") = py::none(),
          py::arg("damping") = py::none(), py::arg("drive_type") = "force",
          (std::string("A simulation at the neutral configuration, at rest; solver ") + kSolverDoc +
           ". Given stiffness or damping (a scalar for every revolute and "
           "prismatic dof, or (nv,) with 0 on other dofs), every such dof gets a drive of "
           "drive_type ('force' or 'acceleration'); else no dof has a drive.")
              .c_str())
      .def(py::init([](ModelPtr model, const SimulationOptions& o) {
             return Simulation(std::move(model), o);
           }),
           py::arg("model"), py::arg("options"), "A simulation with these options.")
      .def(
          "copy", [](const Simulation& s) { return locked(s, [&] { return Simulation(s); }); },
          "An independent copy (same model, state and settings).")
      .def_property_readonly(
          "model", [](const Simulation& s) { return to_python(model_of(s)); }, "The Model.")
      .def_property_readonly(
          "options", [](const Simulation& s) { return locked(s, [&] { return s.options(); }); },
          "The SimulationOptions (a copy; set_options changes them).")
      .def(
          "set_options",
          [](Simulation& s, const SimulationOptions& o) { locked(s, [&] { s.set_options(o); }); },
          py::arg("options"), "Replaces the options; ValueError for bad ones.")
      .def_property_readonly("q", &Simulation::q, ref, "Configuration (nq,), read-only view.")
      .def_property_readonly("qd", &Simulation::qd, ref, "Joint velocities (nv,), read-only view.")
      .def(
          "set_q",
          [](Simulation& s, py::handle q) {
            const VecX v = to_vector(q, model_of(s)->nq, "q");
            locked(s, [&] { s.set_q(v); });
          },
          py::arg("q"), "Sets the configuration (nq,); quaternions are normalised.")
      .def(
          "set_qd",
          [](Simulation& s, py::handle qd) {
            const VecX v = to_vector(qd, model_of(s)->nv, "qd");
            locked(s, [&] { s.set_qd(v); });
          },
          py::arg("qd"), "Sets the joint velocities (nv,).")
      .def(
          "set_base_state",
          [](Simulation& s, py::handle position, py::handle orientation,
             py::handle linear_velocity, py::handle angular_velocity) {
            const Model& m = *model_of(s);
            auto given = [](py::handle x, Eigen::Index n, const char* what) {
              return x.is_none() ? std::optional<VecX>() : std::optional<VecX>(to_vector(x, n, what));
            };
            const auto p = given(position, 3, "base position");
            const auto o = given(orientation, 4, "base orientation");
            const auto v = given(linear_velocity, 3, "base linear_velocity");
            const auto w = given(angular_velocity, 3, "base angular_velocity");
            locked(s, [&] {
              BaseState base = base_state(m, s.q(), s.qd());  // what is not given stays
              if (p) base.position = *p;
              if (o) base.orientation = Quat((*o)[0], (*o)[1], (*o)[2], (*o)[3]);
              if (v) base.linear_velocity = *v;
              if (w) base.angular_velocity = *w;
              VecX q = s.q(), qd = s.qd();
              set_base_state(m, base, q, qd);
              s.set_q(q);
              s.set_qd(qd);
            });
          },
          py::arg("position") = py::none(), py::arg("orientation") = py::none(),
          py::arg("linear_velocity") = py::none(), py::arg("angular_velocity") = py::none(),
          "Places a floating root: its origin's position, orientation (w, x, y, z), the origin's "
          "velocity and the angular velocity, all in world axes; what is not given stays. "
          "ValueError without a floating root or for a zero orientation.")
      .def(
          "base_state",
          [](const Simulation& s) {
            const auto model = model_of(s);  // it takes the lock itself
            const BaseState b = locked(s, [&] { return base_state(*model, s.q(), s.qd()); });
            py::dict d;
            d["position"] = VecX(b.position);
            d["orientation"] = VecX(Eigen::Vector4d(b.orientation.w(), b.orientation.x(),
                                                    b.orientation.y(), b.orientation.z()));
            d["linear_velocity"] = VecX(b.linear_velocity);
            d["angular_velocity"] = VecX(b.angular_velocity);
            return d;
          },
          "The floating root's position, orientation (w, x, y, z), linear and angular velocity "
          "in world axes, as a dict of arrays. ValueError without a floating root.")
      .def_property_readonly(
          "time", [](const Simulation& s) { return locked(s, [&] { return s.time(); }); },
          "Simulated time [s].")
      .def_property_readonly(
          "step_count",
          [](const Simulation& s) { return locked(s, [&] { return s.step_count(); }); },
          "Steps made.")
      .def_property_readonly(
          "guard_substeps",
          [](const Simulation& s) { return locked(s, [&] { return s.guard_substeps(); }); },
          "Sub-steps the step guard took for the last step (1: not redone).")
      .def_property_readonly(
          "guard_triggers",
          [](const Simulation& s) { return locked(s, [&] { return s.guard_triggers(); }); },
          "Steps the step guard redid since construction or reset_guard_counters().")
      .def_property_readonly(
          "guard_exhausted",
          [](const Simulation& s) { return locked(s, [&] { return s.guard_exhausted(); }); },
          "Steps whose max_substeps sub-steps still failed the guard's tests.")
      .def(
          "reset_guard_counters",
          [](Simulation& s) { locked(s, [&] { s.reset_guard_counters(); }); },
          "Zeroes guard_triggers and guard_exhausted.")
      .def(
          "set_applied_force",
          [](Simulation& s, py::handle tau) {
            const VecX v = to_vector(tau, model_of(s)->nv, "applied_force");
            locked(s, [&] { s.set_applied_force(v); });
          },
          py::arg("tau"), "Joint forces applied through each step (nv,), e.g. feed-forward.")
      .def_property_readonly("applied_force", &Simulation::applied_force, ref,
                             "Applied joint forces (nv,), read-only view.")
      .def(
          "set_drive",
          [](Simulation& s, py::handle joint, const Drive& d) {
            on_joint(s, joint, [&](int dof) { s.set_drive(dof, d); });
          },
          py::arg("joint"), py::arg("drive"),
          "Sets the Drive of a joint (name) or dof (index); ValueError naming the joint and "
          "field for bad values.")
      .def(
          "drive",
          [](const Simulation& s, py::handle joint) {
            return on_joint(s, joint, [&](int dof) { return s.drive(dof); });
          },
          py::arg("joint"), "The Drive (a copy) of a joint (name) or dof (index).")
      .def(
          "set_drive_target",
          [](Simulation& s, py::handle joint, double position, double velocity) {
            on_joint(s, joint, [&](int dof) { s.set_drive_target(dof, position, velocity); });
          },
          py::arg("joint"), py::arg("position"), py::arg("velocity") = 0.0,
          "Sets one joint's drive target position and velocity.")
      .def(
          "set_drive_targets",
          [](Simulation& s, py::handle positions, py::object velocities) {
            const int nv = model_of(s)->nv;
            const VecX p = to_vector(positions, nv, "positions");
            const VecX v =
                velocities.is_none() ? VecX::Zero(nv) : to_vector(velocities, nv, "velocities");
            locked(s, [&] { set_drive_targets(s, p, v); });
          },
          py::arg("positions"), py::arg("velocities") = py::none(),
          "Sets every dof's target position and velocity (nv,) each; velocities default to 0. "
          "Nothing changes on a ValueError.")
      .def(
          "set_drive_gains",
          [](Simulation& s, py::handle stiffness, py::handle damping, py::handle type) {
            const int nv = model_of(s)->nv;
            const VecX kp = to_vector(stiffness, nv, "stiffness", true);
            const VecX kd = to_vector(damping, nv, "damping", true);
            const DriveType t = to_drive_type(type);
            locked(s, [&] { set_drive_gains(s, kp, kd, t); });
          },
          py::arg("stiffness"), py::arg("damping"), py::arg("type") = DriveType::force,
          "Sets every dof's stiffness and damping ((nv,) each, or a scalar for all) and makes "
          "the drives of revolute and prismatic joints `type` (default force), keeping "
          "max_force and targets. Other joints' dofs must get 0. Nothing changes on a ValueError.")
      .def(
          "set_joint_limits",
          [](Simulation& s, py::handle joint, double lower, double upper) {
            on_joint(s, joint, [&](int dof) { s.set_joint_limits(dof, lower, upper); });
          },
          py::arg("joint"), py::arg("lower"), py::arg("upper"),
          "Position limits of a revolute or prismatic joint (name or dof); +-inf for none.")
      .def(
          "lower_limit",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.lower_limit(dof); });
          },
          py::arg("joint"), "Lower position limit of a joint (name or dof).")
      .def(
          "upper_limit",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.upper_limit(dof); });
          },
          py::arg("joint"), "Upper position limit of a joint (name or dof).")
      .def(
          "set_joint_friction",
          [](Simulation& s, py::handle joint, const JointFriction& f) {
            on_joint(s, joint, [&](int dof) { s.set_joint_friction(dof, f); });
          },
          py::arg("joint"), py::arg("friction"), "JointFriction of a joint (name or dof).")
      .def(
          "joint_friction",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.joint_friction(dof); });
          },
          py::arg("joint"), "The JointFriction (a copy) of a joint (name or dof).")
      .def(
          "set_max_joint_velocity",
          [](Simulation& s, py::handle joint, double v) {
            on_joint(s, joint, [&](int dof) { s.set_max_joint_velocity(dof, v); });
          },
          py::arg("joint"), py::arg("max_velocity"),
          "Largest |qd| of a joint (name or dof); inf for none.")
      .def(
          "max_joint_velocity",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.max_joint_velocity(dof); });
          },
          py::arg("joint"), "Largest |qd| of a joint (name or dof).")
      .def(
          "set_friction_coefficient",
          [](Simulation& s, py::handle joint, double c) {
            on_joint(s, joint, [&](int dof) { s.set_friction_coefficient(dof, c); });
          },
          py::arg("joint"), py::arg("coefficient"),
          "PhysX's older joint friction coefficient of a joint (name or dof): the friction impulse "
          "of a solve is at most coefficient * h * |F|, F the force the joint transmits.")
      .def(
          "friction_coefficient",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.friction_coefficient(dof); });
          },
          py::arg("joint"), "The friction coefficient of a joint (name or dof).")
      .def(
          "set_link_parameters",
          [](Simulation& s, py::handle link, const LinkParameters& p) {
            const NameOrIndex l = link_arg(link);
            locked(s, [&] { s.set_link_parameters(link_of(s.model(), l), p); });
          },
          py::arg("link"), py::arg("parameters"), "LinkParameters of a link (name or index).")
      .def(
          "link_parameters",
          [](const Simulation& s, py::handle link) {
            const NameOrIndex l = link_arg(link);
            return locked(s, [&] { return s.link_parameters(link_of(s.model(), l)); });
          },
          py::arg("link"), "The LinkParameters (a copy) of a link (name or index).")
      .def(
          "set_actuator_envelope",
          [](Simulation& s, py::handle joint, const ActuatorEnvelope& e) {
            on_joint(s, joint, [&](int dof) { s.set_actuator_envelope(dof, e); });
          },
          py::arg("joint"), py::arg("envelope"), "ActuatorEnvelope of a joint (name or dof).")
      .def(
          "actuator_envelope",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.actuator_envelope(dof); });
          },
          py::arg("joint"), "The ActuatorEnvelope (a copy) of a joint (name or dof).")
      .def(
          "set_actuator",
          [](Simulation& s, py::handle joint, const ExplicitActuator& a) {
            on_joint(s, joint, [&](int dof) { s.set_actuator(dof, a); });
          },
          py::arg("joint"), py::arg("actuator"),
          "Sets the ExplicitActuator of a joint (name or dof; kind 'none' clears it) and empties "
          "its delay history. ValueError beside a drive whose type is not 'none'.")
      .def(
          "actuator",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.actuator(dof); });
          },
          py::arg("joint"), "The ExplicitActuator (a copy) of a joint (name or dof).")
      .def(
          "clear_actuator",
          [](Simulation& s, py::handle j) {
            on_joint(s, j, [&](int dof) { s.clear_actuator(dof); });
          },
          py::arg("joint"), "Removes a joint's explicit actuator.")
      .def(
          "set_actuator_feedforward",
          [](Simulation& s, py::handle j, double effort) {
            on_joint(s, j, [&](int dof) { s.set_actuator_feedforward(dof, effort); });
          },
          py::arg("joint"), py::arg("effort"),
          "Feed-forward effort of a joint's actuator, delayed and clipped with its PD effort.")
      .def(
          "reset_actuator_history",
          [](Simulation& s) { locked(s, [&] { s.reset_actuator_history(); }); },
          "Empties every actuator's delay history (the next step sees its own command).")
      .def_property_readonly("actuator_force", &Simulation::actuator_force, ref,
                             "Explicit actuators' effort in the last step (nv,), read-only view.")
      .def_property_readonly("drive_force", &Simulation::drive_force, ref,
                             "Drive force of each dof in the last step (nv,), read-only view.")
      .def_property_readonly("limit_force", &Simulation::limit_force, ref,
                             "Position-limit force of each dof in the last step (nv,), view.")
      .def_property_readonly("friction_force", &Simulation::friction_force, ref,
                             "Joint-friction force of each dof in the last step (nv,), view.")
      .def_property_readonly("velocity_limit_force", &Simulation::velocity_limit_force, ref,
                             "Velocity-limit force of each dof in the last step (nv,), view.")
      .def(
          "step",
          [](Simulation& s, py::handle count) {
            const int n = to_int(count, "step: count", 0);
            step_in_chunks(s, n, [&](int k) { s.step(k); });
          },
          py::arg("count") = 1,
          "Advances count steps of options.dt without the GIL. DivergenceError (a RuntimeError) "
          "if a step would give a non-finite value: the state is that before the step that "
          "diverged, the steps before it are kept. Ctrl-C raises KeyboardInterrupt with the state "
          "of the last whole step (step_count tells how many were made).");

  m.def(
      "set_drive_targets",
      [](Simulation& s, py::handle positions, py::handle velocities) {
        const int nv = model_of(s)->nv;
        const VecX p = to_vector(positions, nv, "positions");
        const VecX v = to_vector(velocities, nv, "velocities");
        locked(s, [&] { set_drive_targets(s, p, v); });
      },
      py::arg("sim"), py::arg("positions"), py::arg("velocities"),
      "The C++ free function; the same as sim.set_drive_targets(positions, velocities).");
  m.def(
      "set_drive_gains",
      [](Simulation& s, py::handle stiffness, py::handle damping, py::handle type) {
        const int nv = model_of(s)->nv;
        const VecX kp = to_vector(stiffness, nv, "stiffness", true);
        const VecX kd = to_vector(damping, nv, "damping", true);
        const DriveType t = to_drive_type(type);
        locked(s, [&] { set_drive_gains(s, kp, kd, t); });
      },
      py::arg("sim"), py::arg("stiffness"), py::arg("damping"), py::arg("type") = DriveType::force,
      "The C++ free function; the same as sim.set_drive_gains(stiffness, damping, type).");
}
