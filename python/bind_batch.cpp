// Batch: N environments stepped together; step_control for Simulation and Batch.
#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

namespace {

/// Environment i of b: a Python int in [0, size) (a negative one is refused, not counted from the
/// end: python/tests/test_errors.py).
int env_index(const Batch& b, py::handle i) {
  constexpr auto lo = std::numeric_limits<long long>::min();
  constexpr auto hi = std::numeric_limits<long long>::max();
  return index_in(to_int64(i, "environment index", lo, hi), b.size(), "environment index");
}

}  // namespace

std::optional<SimdIsa> featherdrive::python::to_isa(py::handle obj) {
  if (obj.is_none()) return std::nullopt;
  const std::string name = to_str(obj, "isa");
  for (SimdIsa isa : {SimdIsa::sse2, SimdIsa::avx2, SimdIsa::avx512})
    if (name == to_string(isa)) return isa;
  throw std::invalid_argument("isa = '" + name + "': expected 'sse2', 'avx2' or 'avx512'");
}

void featherdrive::python::bind_batch(py::module_& m) {
  // ---- batch ----------------------------------------------------------------------------------
  // States are read-only (N, n) views of the batch's arrays (reference_internal keeps the batch
  // alive); setters take env_ids (None: all) and values as a scalar, one row for every
  // environment named, or one row each.
  py::class_<Batch, BatchHolder>(m, "Batch",
                                 "N environments of one robot stepped together on all cores: in "
                                 "SIMD lanes where the settings allow (the same bits for any "
                                 "lane, width, batch size and threads; within 1e-12 of each "
                                 "stepped alone), else each bit-identical to stepping it alone. "
                                 "States are read-only (N, nq) / (N, nv) views of the batch's "
                                 "arrays; sim(i) is environment i, live.")
      .def("__repr__",
           [](const Batch& b) {
             return locked(b, [&] {
               const Simulation& s = b.sim(0);
               const SimulationOptions& o = s.options();
               std::ostringstream r;
               r << "Batch(N=" << b.size() << ", nq=" << b.model().nq << ", nv=" << b.model().nv
                 << ", " << to_string(o.solver) << " " << o.position_iterations << "/"
                 << o.velocity_iterations << ", dt=" << o.dt << ", num_threads="
                 << b.num_threads() << ")";
               return r.str();
             });
           })
      .def(py::init([](ModelPtr model, py::handle count, double dt, py::handle solver,
                       py::handle pi, py::handle vi, py::handle compat, py::handle kp,
                       py::handle kd, py::handle type) {
             const int n = to_int(count, "count", 1, Batch::kMaxSize);
             Simulation prototype(std::move(model), make_options(dt, solver, pi, vi, compat));
             initial_drives(prototype, kp, kd, type);
             return BatchHolder(new Batch(prototype, n));
           }),
           py::arg("model"), py::arg("count"), py::arg("dt") = 1.0 / 60.0,
           py::arg("solver") = "pgs", py::arg("position_iterations") = 4,
           py::arg("velocity_iterations") = 1, py::arg("compat") = "none",
           py::arg("stiffness") = py::none(), py::arg("damping") = py::none(),
           py::arg("drive_type") = "force",
           "count environments, each a new Simulation of model, with the arguments of "
           "Simulation(model, dt, ..., stiffness, damping, drive_type).")
      .def(py::init([](const Simulation& prototype, py::handle count) {
             const int n = to_int(count, "count", 1, Batch::kMaxSize);
             return locked(prototype, [&] { return BatchHolder(new Batch(prototype, n)); });
           }),
           py::arg("prototype"), py::arg("count"),
           "count copies of prototype: its state, drives, limits and other settings.")
      .def("__len__", &Batch::size, "Number of environments.")  // fixed at construction: no lock
      .def("size", &Batch::size, "Number of environments.")
      .def_property_readonly(
          "model", [](const Batch& b) { return to_python(model_of(b)); },
          "Environment 0's Model (all share its topology).")
      .def(
          "sim",
          [](Batch& b, py::handle i) -> Simulation& {
            Simulation& s = b.sim(env_index(b, i));
            auto lock = lock_for(&b);
            lock_table()[&s] = std::move(lock);  // the environment shares the batch's lock
            return s;
          },
          py::arg("i"), ref,
          "Environment i as a live Simulation (a reference into the batch: its q is row i of "
          "batch.q; it keeps the batch alive and shares its lock).")
      .def_property(
          "num_threads", [](const Batch& b) { return locked(b, [&] { return b.num_threads(); }); },
          [](Batch& b, py::handle threads) {
            const int n = to_int(threads, "num_threads", 0);
            locked(b, [&] { b.set_num_threads(n); });
          },
          "Threads step() uses: 0 = all cores (default), 1 = serial.")
      .def(
          "set_num_threads",
          [](Batch& b, py::handle threads) {
            const int n = to_int(threads, "num_threads", 0);
            locked(b, [&] { b.set_num_threads(n); });
          },
          py::arg("threads"), "Threads step() uses: 0 = all cores, 1 = serial; ValueError if < 0.")
      .def(
          "effective_num_threads",
          [](const Batch& b) { return locked(b, [&] { return b.effective_num_threads(); }); },
          "The threads step() will use.")
      .def_property(
          "lanes", [](const Batch& b) { return locked(b, [&] { return b.lanes(); }); },
          [](Batch& b, bool allowed) { locked(b, [&] { b.set_lanes(allowed); }); },
          "Whether step() may step the environments in SIMD lanes (default True): then each "
          "gives the same bits whatever its lane, the width, the batch size and the threads, "
          "within 1e-12 of its Simulation stepped alone; False: each is its Simulation, bit for "
          "bit.")
      .def_property_readonly(
          "step_path", [](Batch& b) { return locked(b, [&] { return b.step_path(); }); },
          "How the next step() runs: 'avx2 lanes' (one lane group), 'avx2 lanes: 2 groups (6, 2 "
          "environments)', the environments in one-lane blocks (a group of one) counted last "
          "('sse2 lanes (1 at one lane)', 'avx2 lanes: 2 groups (6, 1 environments; 1 at one "
          "lane)'), or 'scalar: ' and why (lanes off, FEATHERDRIVE_SIMD=scalar).")
      .def(
          "env_path",
          [](Batch& b, py::handle i) {
            const int index = env_index(b, i);
            return locked(b, [&] { return b.env_path(index); });
          },
          py::arg("i"),
          "How the next step() runs environment i: 'avx2 lanes, group 1', 'sse2 lanes, group 1 "
          "(one lane)' or 'scalar: ' and why.")
      .def_property(
          "isa",
          [](const Batch& b) { return locked(b, [&] { return std::string(to_string(b.isa())); }); },
          [](Batch& b, py::handle isa) {
            const std::optional<SimdIsa> i = to_isa(isa);
            locked(b, [&] { b.set_isa(i); });
          },
          "The lanes' instruction set: 'sse2', 'avx2' or 'avx512' (ValueError for one this CPU "
          "lacks), or None for the default (the widest, FEATHERDRIVE_SIMD, narrowed for small "
          "batches). Every width gives the same bits.")
      .def_property_readonly(
          "width", [](const Batch& b) { return locked(b, [&] { return b.width(); }); },
          "Environments per vector of isa: 2, 4 or 8.")
      .def_property_readonly(
          "step_count", [](const Batch& b) { return locked(b, [&] { return b.step_count(); }); },
          "Every environment's step count, a new list.")
      .def(
          "divergences",
          [](const Batch& b) {
            return locked(b, [&] {
              py::dict out;
              for (int e = 0; e < b.size(); ++e)
                if (const auto& d = b.divergences()[static_cast<size_t>(e)])
                  out[py::int_(e)] = d->message;
              return out;
            });
          },
          "{environment: message} of the environments that stopped in the last step().")
      .def(
          "simulation",
          [](const Batch& b, py::handle i) {
            const int index = env_index(b, i);
            return locked(b, [&] { return SimulationHolder(new Simulation(b.simulation(index))); });
          },
          py::arg("i"), "Environment i as a Simulation of its own (a copy), unlike sim(i).")
      .def(
          "set_options",
          [](Batch& b, const SimulationOptions& o) { locked(b, [&] { b.set_options(o); }); },
          py::arg("options"), "Sets every environment's options.")
      .def_property_readonly("q", &Batch::q, ref, "Configurations (N, nq), a read-only view.")
      .def_property_readonly("qd", &Batch::qd, ref, "Joint velocities (N, nv), a read-only view.")
      .def_property_readonly("applied_force", &Batch::applied_force, ref,
                             "Applied joint forces (N, nv), a read-only view.")
      .def_property_readonly("drive_force", &Batch::drive_force, ref,
                             "Drive forces of the last step (N, nv), a read-only view.")
      .def_property_readonly("limit_force", &Batch::limit_force, ref,
                             "Position-limit forces of the last step (N, nv), a read-only view.")
      .def_property_readonly("friction_force", &Batch::friction_force, ref,
                             "Joint-friction forces of the last step (N, nv), a read-only view.")
      .def_property_readonly("velocity_limit_force", &Batch::velocity_limit_force, ref,
                             "Velocity-limit forces of the last step (N, nv), a read-only view.")
      .def_property_readonly(
          "link_contact_force",
          [](const Batch& b) {
            return locked(b, [&] {
              const RowMatrix f = b.link_contact_force();  // row-major: (N, links, 3) as it is
              const std::vector<py::ssize_t> shape{f.rows(), f.cols() / 3, 3};
              return py::array_t<double>(shape, f.data());  // a copy
            });
          },
          "The ground's force on each link of every environment over the last step, world axes, "
          "N: a new array (N, num_links, 3).")
      .def(
          "contacts",
          [](const Batch& b, py::handle i) {
            return locked(b, [&] {
              const auto c = b.contacts(env_index(b, i));
              return std::vector<ContactReport>(c.begin(), c.end());
            });
          },
          py::arg("i"),
          "Environment i's contact points of the last step (list of ContactReport).")
      .def(
          "set_q",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nq, "q");
            locked(b, [&] { b.set_q(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Sets the configurations of env_ids (None: all): a scalar, (nq,) for each or (k, nq); "
          "quaternions are normalised.")
      .def(
          "set_qd",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nv, "qd");
            locked(b, [&] { b.set_qd(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Sets the joint velocities of env_ids (None: all): a scalar, (nv,) or (k, nv).")
      .def(
          "set_applied_force",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nv, "applied_force");
            locked(b, [&] { b.set_applied_force(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Sets the applied joint forces of env_ids (None: all): a scalar, (nv,) or (k, nv).")
      .def(
          "set_drive_targets",
          [](Batch& b, py::handle positions, py::handle velocities, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const int nv = model_of(b)->nv;
            const RowMatrix p = to_rows(positions, ids.size(), nv, "positions");
            const RowMatrix v = to_rows(velocities.is_none() ? py::float_(0.0) : velocities,
                                        ids.size(), nv, "velocities");
            locked(b, [&] { b.set_drive_targets(ids, p, v); });
          },
          py::arg("positions"), py::arg("velocities") = 0.0, py::arg("env_ids") = py::none(),
          "Target positions and velocities of env_ids (None: all), each a scalar, (nv,) or "
          "(k, nv); velocities default to 0. Nothing changes on a ValueError.")
      .def(
          "set_drive_gains",
          [](Batch& b, py::handle stiffness, py::handle damping, py::handle type,
             py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const int nv = model_of(b)->nv;
            const RowMatrix kp = to_rows(stiffness, ids.size(), nv, "stiffness");
            const RowMatrix kd = to_rows(damping, ids.size(), nv, "damping");
            const DriveType t = to_drive_type(type);
            locked(b, [&] { b.set_drive_gains(ids, kp, kd, t); });
          },
          py::arg("stiffness"), py::arg("damping"), py::arg("type") = DriveType::force,
          py::arg("env_ids") = py::none(),
          "Stiffness and damping of env_ids (None: all), each a scalar, (nv,) or (k, nv), as "
          "Simulation.set_drive_gains. Nothing changes on a ValueError.")
      .def(
          "set_drive",
          [](Batch& b, py::handle joint, const Drive& d) {
            const std::string j = to_str(joint, "joint");
            locked(b, [&] { b.set_drive(j, d); });
          },
          py::arg("joint"), py::arg("drive"), "The same Drive on one joint (name) of every copy.")
      .def(
          "set_actuator",
          [](Batch& b, py::handle joint, const ExplicitActuator& a, py::handle env_ids) {
            const NameOrIndex j = joint_arg(joint);
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            locked(b, [&] {
              // A copy with a drive refuses first (set_actuator's message, nothing set yet);
              // then the first copy checks what all share (joint, values).
              const int dof = dof_of(b.model(), j);
              for (int i : ids)
                if (a.kind != ActuatorKind::none && b.sim(i).drive(dof).type != DriveType::none)
                  b.sim(i).set_actuator(dof, a);
              for (int i : ids) b.sim(i).set_actuator(dof, a);
            });
          },
          py::arg("joint"), py::arg("actuator"), py::arg("env_ids") = py::none(),
          "The same ExplicitActuator on one joint (name or dof) of the copies env_ids (all for "
          "None), each with an empty delay history. Nothing changes on a ValueError.")
      .def(
          "reset",
          [](Batch& b, py::handle env_ids, py::handle q, py::handle qd) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const auto model = model_of(b);
            std::optional<RowMatrix> q0, qd0;
            if (!q.is_none()) q0 = to_rows(q, ids.size(), model->nq, "q");
            if (!qd.is_none()) qd0 = to_rows(qd, ids.size(), model->nv, "qd");
            locked(b, [&] { b.reset(ids, q0, qd0); });
          },
          py::arg("env_ids"), py::arg("q") = py::none(), py::arg("qd") = py::none(),
          "Starts env_ids (None: all) again: q (default: the batch's initial configuration), qd "
          "(default 0), applied and output forces 0, clock 0; drives and settings stay; the "
          "other environments are untouched.")
      .def(
          "set_armature",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nv, "armature");
            locked(b, [&] { b.set_armature(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Armature of env_ids (None: all): a scalar, (nv,) or (k, nv); each gets its own model.")
      .def(
          "set_joint_limits",
          [](Batch& b, py::handle lower, py::handle upper, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const int nv = model_of(b)->nv;
            const RowMatrix lo = to_rows(lower, ids.size(), nv, "lower");
            const RowMatrix hi = to_rows(upper, ids.size(), nv, "upper");
            locked(b, [&] { b.set_joint_limits(ids, lo, hi); });
          },
          py::arg("lower"), py::arg("upper"), py::arg("env_ids") = py::none(),
          "Joint limits of env_ids (None: all), each a scalar, (nv,) or (k, nv); dofs of "
          "a floating root must be given the -inf / inf they have.")
      .def(
          "set_joint_friction",
          [](Batch& b, py::handle static_effort, py::handle dynamic_effort, py::handle viscous,
             py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const int nv = model_of(b)->nv;
            const RowMatrix s = to_rows(static_effort, ids.size(), nv, "static");
            const RowMatrix d =
                dynamic_effort.is_none() ? s : to_rows(dynamic_effort, ids.size(), nv, "dynamic");
            const RowMatrix v = to_rows(viscous, ids.size(), nv, "viscous");
            locked(b, [&] { b.set_joint_friction(ids, s, d, v); });
          },
          py::arg("static"), py::arg("dynamic") = py::none(), py::arg("viscous") = 0.0,
          py::arg("env_ids") = py::none(),
          "Joint friction of env_ids (None: all), each a scalar, (nv,) or (k, nv); dynamic "
          "defaults to static.")
      .def(
          "set_max_joint_velocity",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nv, "max_velocity");
            locked(b, [&] { b.set_max_joint_velocity(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Largest |qd| of env_ids (None: all): a scalar, (nv,) or (k, nv); inf for none.")
      .def(
          "set_link_mass",
          &set_link_mass_of<Batch>,
          py::arg("link"), py::arg("mass"), py::arg("env_ids") = py::none(),
          py::arg("scale_inertia") = true,
          "Mass of a link (name or index) in env_ids (None: all): a scalar or (k,). "
          "scale_inertia: its inertia scales with the mass (Isaac Lab's mass randomisation).")
      .def(
          "set_link_com",
          [](Batch& b, py::handle link, py::handle com, py::handle env_ids) {
            const NameOrIndex l = link_arg(link);
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix c = to_rows(com, ids.size(), 3, "com", /*scalar_ok=*/false);
            locked(b, [&] { b.set_link_com(ids, link_of(b.model(), l), c); });
          },
          py::arg("link"), py::arg("com"), py::arg("env_ids") = py::none(),
          "Centre of mass (link frame) of a link in env_ids (None: all): (3,) or (k, 3).")
      .def(
          "set_gravity",
          [](Batch& b, py::handle gravity, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix g = to_rows(gravity, ids.size(), 3, "gravity", /*scalar_ok=*/false);
            locked(b, [&] { b.set_gravity(ids, g); });
          },
          py::arg("gravity"), py::arg("env_ids") = py::none(),
          "Gravity [m/s^2] of env_ids (None: all): (3,) or (k, 3), finite; the lanes take it "
          "per environment.")
      .def(
          "gravity", [](const Batch& b) { return locked(b, [&] { return b.gravity(); }); },
          "Every environment's gravity (N, 3), a copy.")
      .def(
          "armature", [](const Batch& b) { return locked(b, [&] { return b.armature(); }); },
          "Every environment's armature (N, nv), a copy.")
      .def(
          "drive_gains",
          [](const Batch& b) {
            return locked(b, [&] { return py::make_tuple(b.stiffness(), b.damping()); });
          },
          "(stiffness, damping), (N, nv) each, copies.")
      .def(
          "joint_limits",
          [](const Batch& b) {
            return locked(b, [&] { return py::make_tuple(b.lower_limit(), b.upper_limit()); });
          },
          "(lower, upper), (N, nv) each, copies.")
      .def(
          "joint_friction",
          [](const Batch& b) {
            return locked(b, [&] {
              return py::make_tuple(b.static_friction(), b.dynamic_friction(),
                                    b.viscous_friction());
            });
          },
          "(static, dynamic, viscous), (N, nv) each, copies.")
      .def(
          "max_joint_velocity",
          [](const Batch& b) { return locked(b, [&] { return b.max_joint_velocity(); }); },
          "(N, nv), a copy.")
      .def(
          "link_mass",
          [](const Batch& b, py::handle link) {
            const NameOrIndex l = link_arg(link);
            return locked(b, [&] { return b.link_mass(link_of(b.model(), l)); });
          },
          py::arg("link"), "A link's mass in every environment (N,), a copy.")
      .def(
          "link_com",
          [](const Batch& b, py::handle link) {
            const NameOrIndex l = link_arg(link);
            return locked(b, [&] { return b.link_com(link_of(b.model(), l)); });
          },
          py::arg("link"), "A link's centre of mass in every environment (N, 3), a copy.")
      .def(
          "observe",
          [](const Batch& b, py::handle fields) {
            const std::vector<Observation> f = to_observations(fields);
            return locked(b, [&] { return b.observe(f); });
          },
          py::arg("fields"),
          "The fields (names from q, qd, applied_force, drive_force, limit_force, "
          "friction_force, velocity_limit_force, target_position, target_velocity) side by "
          "side in one new (N, k) array.")
      .def(
          "frame_positions",
          [](const Batch& b, py::handle link, py::handle point) {
            const NameOrIndex l = link_arg(link);
            const Vec3 p = point.is_none() ? Vec3::Zero() : to_vec3(point, "point");
            return locked(b, [&] {
              const NamedFrame f = frame_of(b.model(), l);
              return b.frame_positions(f.link, point_on_link(f, p));
            });
          },
          py::arg("link"), py::arg("point") = py::none(),
          "World position of a point (frame coordinates, default its origin) on a link (name or "
          "index) or a merged link's frame (name) in every environment, (N, 3), a new array.")
      .def(
          "step",
          [](Batch& b, py::handle count) {
            const int n = to_int(count, "step: count", 0);
            // A copy that diverged stays at its step and diverges again in every later chunk
            // (same state, same inputs), so the last chunk's error names every diverged copy, as
            // one Batch::step(n) would.
            std::exception_ptr diverged;
            step_in_chunks(b, n, [&](int k) {
              try {
                b.step(k);
              } catch (const DivergenceError&) {
                diverged = std::current_exception();
              }
            });
            if (diverged) std::rethrow_exception(diverged);
          },
          py::arg("count") = 1,
          "Steps every copy count times, in parallel, without the GIL. A copy that diverges "
          "stops at that step with its state from before it; the others make all their steps; "
          "then DivergenceError names the lowest diverged copy (sim(i).step_count tells how far "
          "each got). Ctrl-C raises KeyboardInterrupt with every copy at a whole step.");

  // ---- control steps (sim/control_step.hpp): Simulation.step_control, Batch.step_control ------
  {
    auto control_of = [](py::handle substeps, py::handle targets) {
      ControlStep c;
      c.substeps = to_int(substeps, "step_control: substeps", 1, kMaxSubsteps);
      const std::string t = to_str(targets, "step_control: targets");
      if (t != "hold" && t != "linear")
        throw std::invalid_argument("step_control: targets = '" + t +
                                    "': must be 'hold' or 'linear'");
      c.targets = t == "linear" ? TargetInterpolation::linear : TargetInterpolation::hold;
      return c;
    };
    // A scalar for every copy and dof, (nv,) for every copy, or (N, nv).
    auto batch_targets = [](py::handle obj, const Batch& b, const std::string& what) {
      const int n = b.size();
      const RowMatrix rows = to_rows(obj, static_cast<size_t>(n), model_of(b)->nv, what);
      return rows.rows() == n ? rows : RowMatrix(rows.replicate(n, 1));
    };
    py::object sim_class = m.attr("Simulation"), batch_class = m.attr("Batch");
    sim_class.attr("step_control") = py::cpp_function(
        [control_of](Simulation& s, py::handle position, py::handle velocity, py::handle substeps,
                     py::handle targets) {
          const int nv = model_of(s)->nv;
          const VecX p = to_vector(position, nv, "step_control: target_position", true);
          const VecX v = to_vector(velocity, nv, "step_control: target_velocity", true);
          const ControlStep c = control_of(substeps, targets);
          step_in_chunks(s, 1, [&](int) { step_control(s, p, v, c); });
        },
        py::name("step_control"), py::is_method(sim_class), py::arg("target_position"),
        py::arg("target_velocity") = 0.0, py::arg("substeps") = 1, py::arg("targets") = "hold",
        "One control step: substeps physics steps of options.dt with the drive targets (nv,) or a "
        "scalar, held ('hold') or interpolated from the previous ones ('linear'; "
        "docs/math/control_step.md), without the GIL. DivergenceError names the sub-step.");
    batch_class.attr("step_control") = py::cpp_function(
        [control_of, batch_targets](Batch& b, py::handle position, py::handle velocity,
                                    py::handle substeps, py::handle targets) {
          const RowMatrix p = batch_targets(position, b, "step_control: target_position");
          const RowMatrix v = batch_targets(velocity, b, "step_control: target_velocity");
          const ControlStep c = control_of(substeps, targets);
          step_in_chunks(b, 1, [&](int) { step_control(b, p, v, c); });
        },
        py::name("step_control"), py::is_method(batch_class), py::arg("target_position"),
        py::arg("target_velocity") = 0.0, py::arg("substeps") = 1, py::arg("targets") = "hold",
        "Simulation.step_control for every copy: targets (N, nv), (nv,) for all or a scalar; "
        "divergence as Batch.step, per sub-step.");
  }
}
