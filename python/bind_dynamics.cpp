// Kinematics and dynamics queries: Simulation methods and module functions of (model, q, qd).
#include "bindings.hpp"
#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/sim/state.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

namespace {

// ---- kinematics and dynamics ------------------------------------------------------------------
// Queries at a state: a Simulation's current q and qd (copied under its lock, then computed on a
// private workspace) or a model at a given q (and qd), checked as Simulation.set_q and set_qd
// check them. Every result is a new numpy array (a copy). Conventions: docs/conventions.md,
// "Kinematics and dynamics".

struct KinematicState {
  std::shared_ptr<const Model> model;
  VecX q, qd;
};

KinematicState state_of(const Simulation& s) {
  return locked(s, [&] { return KinematicState{s.model_ptr(), s.q(), s.qd()}; });
}

/// q (and qd unless None; zero then) checked and normalised as Simulation's setters do.
KinematicState state_at(const ModelPtr& model, py::handle q, py::handle qd) {
  if (!model) throw py::type_error("model must be a Model, not None");
  KinematicState state{model, checked_configuration(*model, to_vector(q, model->nq, "q")),
                       VecX::Zero(model->nv)};
  if (!qd.is_none()) {
    state.qd = to_vector(qd, model->nv, "qd");
    check_state_vector(state.qd, model->nv, "qd");
  }
  return state;
}

ReferenceFrame to_reference(py::handle obj) {
  return to_enum<ReferenceFrame>(
      obj, "frame",
      {{"local", ReferenceFrame::local}, {"world_aligned", ReferenceFrame::world_aligned}},
      "'local' or 'world_aligned'");
}

Vec3 to_point(py::handle obj) {
  return obj.is_none() ? Vec3::Zero() : Vec3(to_finite_vector(obj, 3, "point"));
}

/// A link's or named frame's query (a merged link's name gives its frame on the link it merged
/// into): the state's kinematics (with velocities) and the frame.
struct LinkQuery {
  KinematicState state;
  Data data;
  NamedFrame frame;
  LinkQuery(KinematicState s, py::handle link_obj)
      : state(std::move(s)), data(*state.model), frame(frame_of(*state.model, link_arg(link_obj))) {
    forward_kinematics(*state.model, data, state.q, state.qd);
  }
  const Model& model() const { return *state.model; }
  Vec3 point(py::handle p) const { return point_on_link(frame, to_point(p)); }
  /// Rows [angular; linear] in link axes -> in the frame's axes where `reference` is local.
  template <class M>
  void to_frame_axes(M& rows, ReferenceFrame reference) const {
    if (reference != ReferenceFrame::local) return;
    rows.template topRows<3>() = frame.rotation.transpose() * rows.template topRows<3>().eval();
    rows.template bottomRows<3>() =
        frame.rotation.transpose() * rows.template bottomRows<3>().eval();
  }
};

py::tuple link_pose_of(const LinkQuery& k) {
  return py::make_tuple(frame_rotation(k.model(), k.data, k.frame),
                        frame_position(k.model(), k.data, k.frame));
}

Vec6 frame_velocity_of(const LinkQuery& k, py::handle point, py::handle frame) {
  return frame_velocity(k.model(), k.data, k.frame, to_point(point), to_reference(frame));
}

MatX jacobian_of(const LinkQuery& k, py::handle point, py::handle frame) {
  MatX J;
  const ReferenceFrame r = to_reference(frame);
  frame_jacobian(k.model(), k.data, k.frame.link, k.point(point), r, J);
  k.to_frame_axes(J, r);
  return J;
}

Vec6 jacobian_dot_of(const LinkQuery& k, py::handle point, py::handle frame) {
  const ReferenceFrame r = to_reference(frame);
  Vec6 a = jacobian_dot_times_v(k.model(), k.data, k.frame.link, k.point(point), r);
  k.to_frame_axes(a, r);
  return a;
}

/// A (n,) vector of finite values: ValueError naming the entry otherwise.
VecX finite_vector(py::handle obj, Eigen::Index n, const std::string& what) {
  VecX v = to_vector(obj, n, what);
  for (Eigen::Index i = 0; i < n; ++i)
    if (!std::isfinite(v[i]))
      throw std::invalid_argument(what + "[" + std::to_string(i) + "] = " +
                                  py::repr(py::float_(v[i])).cast<std::string>() +
                                  " is not finite");
  return v;
}

/// The whole robot's queries (no link).
struct RobotQuery {
  KinematicState state;
  Data data;
  explicit RobotQuery(KinematicState s) : state(std::move(s)), data(*state.model) {
    forward_kinematics(*state.model, data, state.q, state.qd);
  }
  const Model& model() const { return *state.model; }
  MatX mass_matrix() { return crba(model(), data, state.q); }
  VecX bias_forces() { return nonlinear_effects(model(), data, state.q, state.qd); }
  VecX gravity_forces() { return generalized_gravity(model(), data, state.q); }
  VecX inverse_dynamics(py::handle qdd) {
    return rnea(model(), data, state.q, state.qd, to_finite_vector(qdd, model().nv, "qdd"));
  }
  VecX forward_dynamics(py::handle tau) {
    return aba(model(), data, state.q, state.qd, finite_vector(tau, model().nv, "tau"));
  }
  /// MuJoCo's qfrc_bias: b in MuJoCo's velocities. They differ from ours only at a floating
  /// root, whose qvel is A v with A = [0 R; 1 0] (world velocity of the origin, then body-frame
  /// angular velocity; R the root's orientation) and whose d/dt qvel = A qdd + c, c = [R (w x u);
  /// 0] for v = [w; u]: M_mj = A M A^T and qfrc_bias = A (b - M A^T c), A orthogonal
  /// (docs/conventions.md, "Kinematics and dynamics").
  VecX mujoco_qfrc_bias() {
    const Model& m = model();
    const Mat3 R = data.world_rotation[0];
    VecX b = nonlinear_effects(m, data, state.q, state.qd);
    if (!m.floating_base()) return b;
    VecX At_c = VecX::Zero(m.nv);  // A^T c = [0; w x u]
    At_c.segment<3>(3) = state.qd.head<3>().cross(state.qd.segment<3>(3));
    b -= crba(m, data, state.q) * At_c;
    const Vec3 angular = b.head<3>();
    b.head<3>() = R * b.segment<3>(3);
    b.segment<3>(3) = angular;
    return b;
  }
  Vec3 com() { return center_of_mass(model(), data); }
  Vec3 com_velocity() { return center_of_mass_velocity(model(), data); }
  MatX com_jacobian() {
    MatX J;
    center_of_mass_jacobian(model(), data, J);
    return J;
  }
};

/// A whole-robot query as a Simulation method and as a module function of (model, q) or, with
/// with_qd, (model, q, qd).
template <class R>
void def_robot_query(py::class_<Simulation, SimulationHolder>& sim, py::module_& m,
                     const char* name, R (RobotQuery::*query)(), bool with_qd,
                     const std::string& doc) {
  sim.def(
      name, [query](const Simulation& s) { return (RobotQuery(state_of(s)).*query)(); },
      (doc + " At the simulation's current q and qd; a new array (a copy).").c_str());
  if (with_qd)
    m.def(
        name,
        [query](const ModelPtr& mo, py::handle q, py::handle qd) {
          return (RobotQuery(state_at(mo, q, qd)).*query)();
        },
        py::arg("model"), py::arg("q"), py::arg("qd"),
        (doc + " At q (nq,) and qd (nv,), checked "
               "as Simulation.set_q and set_qd check them; a new array.")
            .c_str());
  else
    m.def(
        name,
        [query](const ModelPtr& mo, py::handle q) {
          return (RobotQuery(state_at(mo, q, py::none())).*query)();
        },
        py::arg("model"), py::arg("q"),
        (doc + " At q (nq,), checked as Simulation.set_q checks it; a new array.").c_str());
}

/// (N, k) rows as a new (N, shape...) array.
py::array reshaped(const RowMatrix& rows, std::initializer_list<Eigen::Index> shape) {
  std::vector<py::ssize_t> dims{static_cast<py::ssize_t>(rows.rows())};
  for (Eigen::Index d : shape) dims.push_back(static_cast<py::ssize_t>(d));
  py::array_t<double> out(dims);
  if (rows.size() > 0)
    std::memcpy(out.mutable_data(), rows.data(), sizeof(double) * static_cast<size_t>(rows.size()));
  return out;
}

constexpr const char* kFrameDoc =
    " frame: 'world_aligned' (world axes, origin at the point; the default) or 'local' (the "
    "link's axes). Spatial vectors are [angular; linear].";

}  // namespace

void featherdrive::python::bind_dynamics(py::module_& m) {
  py::enum_<ReferenceFrame>(m, "ReferenceFrame",
                            "Axes of a spatial velocity or Jacobian: local (the link's) or "
                            "world_aligned (the world's), origin at the point either way.")
      .value("local", ReferenceFrame::local)
      .value("world_aligned", ReferenceFrame::world_aligned);

  auto sim = py::reinterpret_borrow<py::class_<Simulation, SimulationHolder>>(m.attr("Simulation"));
  const auto link = py::arg("link");
  const auto point = py::arg("point") = py::none();
  const auto frame = py::arg("frame") = "world_aligned";
  const auto model = py::arg("model"), q = py::arg("q"), qd = py::arg("qd");
  const std::string at_sim = " At the simulation's current q and qd; a new array (a copy).";
  const std::string at_q = " At q (nq,), checked as Simulation.set_q checks it; a new array.";
  const std::string at_qd =
      " At q (nq,) and qd (nv,), checked as Simulation.set_q and set_qd check them; a new array.";
  const std::string pose_doc =
      "(R, p) of a link (name or index) or of a link merged into one through fixed joints "
      "(name; its frame keeps its offset in that link): its axes R (3, 3) and origin p (3,) in "
      "the world. ValueError naming the nearest names for an unknown one.";
  const std::string point_doc =
      "World position (3,) of a point (3,) fixed on a link (name or index) or a merged link "
      "(name), given in that frame.";
  const std::string velocity_doc =
      std::string(
          "Spatial velocity (6,) [omega; velocity of the point] of a point on a link "
          "(point in the link frame; None: the link origin).") +
      kFrameDoc;
  const std::string jacobian_doc =
      std::string(
          "J (6, nv) with J qd = frame_velocity(link, point, frame); columns for qd "
          "(a floating root's body-frame twist).") +
      kFrameDoc;
  const std::string jdot_doc =
      std::string(
          "dJ/dt qd (6,) for jacobian(link, point, frame): the acceleration at qdd = 0, "
          "gravity excluded; classical (d/dt [omega; point velocity]) when "
          "world_aligned, spatial in the link's axes when local.") +
      kFrameDoc;
  const std::string mass_doc = "Joint-space inertia M(q) (nv, nv), armature included (CRBA).";
  const std::string bias_doc =
      "Bias forces b = C(q, qd) qd + g(q) (nv,): M qdd + b = tau in featherdrive's velocities "
      "qd. MuJoCo's qfrc_bias on a fixed base; with a floating root they differ (MuJoCo's qvel "
      "is A qd, not qd): mujoco_qfrc_bias gives MuJoCo's.";
  const std::string mujoco_bias_doc =
      "MuJoCo's qfrc_bias (nv,) at this state: bias_forces in MuJoCo's velocities. With a "
      "floating root qvel = A qd, A = [0 R; 1 0] (world velocity of the root's origin, then its "
      "body-frame angular velocity), and qfrc_bias = A (b - M A^T c), c = [R (w x v); 0]; on a "
      "fixed base it equals bias_forces (docs/conventions.md).";
  const std::string fd_doc =
      "Forward dynamics qdd (nv,) = M^-1 (tau - b) for joint forces tau (nv,, finite) (ABA): the "
      "rigid bodies and armature only, no drives, limits, friction or damping.";
  const std::string gravity_doc = "g(q) (nv,): the joint forces that hold q still against gravity.";
  const std::string id_doc =
      "Inverse dynamics tau = M qdd + b (nv,) for joint accelerations qdd (nv,) (RNEA).";
  const std::string com_doc = "Centre of mass (3,) of the whole robot, world coordinates.";
  const std::string comv_doc = "Velocity (3,) of the centre of mass, world coordinates.";
  const std::string comj_doc = "J_com (3, nv): J_com qd is the centre of mass's velocity.";

  // On a Simulation.
  sim.def(
         "link_pose",
         [](const Simulation& s, py::handle l) { return link_pose_of(LinkQuery(state_of(s), l)); },
         link, (pose_doc + at_sim).c_str())
      .def(
          "frame_position",
          [](const Simulation& s, py::handle l, py::handle p) {
            const Vec3 pt = Vec3(to_finite_vector(p, 3, "point"));
            LinkQuery k(state_of(s), l);
            return frame_position(k.model(), k.data, k.frame, pt);
          },
          link, py::arg("point"), (point_doc + at_sim).c_str())
      .def(
          "frame_velocity",
          [](const Simulation& s, py::handle l, py::handle p, py::handle f) {
            return frame_velocity_of(LinkQuery(state_of(s), l), p, f);
          },
          link, point, frame, (velocity_doc + at_sim).c_str())
      .def(
          "jacobian",
          [](const Simulation& s, py::handle l, py::handle p, py::handle f) {
            return jacobian_of(LinkQuery(state_of(s), l), p, f);
          },
          link, point, frame, (jacobian_doc + at_sim).c_str())
      .def(
          "jacobian_dot_times_qd",
          [](const Simulation& s, py::handle l, py::handle p, py::handle f) {
            return jacobian_dot_of(LinkQuery(state_of(s), l), p, f);
          },
          link, point, frame, (jdot_doc + at_sim).c_str())
      .def(
          "inverse_dynamics",
          [](const Simulation& s, py::handle qdd) {
            return RobotQuery(state_of(s)).inverse_dynamics(qdd);
          },
          py::arg("qdd"), (id_doc + at_sim).c_str())
      .def(
          "forward_dynamics",
          [](const Simulation& s, py::handle tau) {
            return RobotQuery(state_of(s)).forward_dynamics(tau);
          },
          py::arg("tau"), (fd_doc + at_sim).c_str());
  def_robot_query(sim, m, "mujoco_qfrc_bias", &RobotQuery::mujoco_qfrc_bias, true,
                  mujoco_bias_doc);
  def_robot_query(sim, m, "mass_matrix", &RobotQuery::mass_matrix, false, mass_doc);
  def_robot_query(sim, m, "bias_forces", &RobotQuery::bias_forces, true, bias_doc);
  def_robot_query(sim, m, "gravity_forces", &RobotQuery::gravity_forces, false, gravity_doc);
  def_robot_query(sim, m, "center_of_mass", &RobotQuery::com, false, com_doc);
  def_robot_query(sim, m, "center_of_mass_velocity", &RobotQuery::com_velocity, true, comv_doc);
  def_robot_query(sim, m, "center_of_mass_jacobian", &RobotQuery::com_jacobian, false, comj_doc);

  // The same as module functions of (model, q[, qd]).
  m.def(
      "link_pose",
      [](const ModelPtr& mo, py::handle q_, py::handle l) {
        return link_pose_of(LinkQuery(state_at(mo, q_, py::none()), l));
      },
      model, q, link, (pose_doc + at_q).c_str());
  m.def(
      "frame_position",
      [](const ModelPtr& mo, py::handle q_, py::handle l, py::handle p) {
        const Vec3 pt = Vec3(to_finite_vector(p, 3, "point"));
        LinkQuery k(state_at(mo, q_, py::none()), l);
        return frame_position(k.model(), k.data, k.frame, pt);
      },
      model, q, link, py::arg("point"), (point_doc + at_q).c_str());
  m.def(
      "frame_velocity",
      [](const ModelPtr& mo, py::handle q_, py::handle qd_, py::handle l, py::handle p,
         py::handle f) { return frame_velocity_of(LinkQuery(state_at(mo, q_, qd_), l), p, f); },
      model, q, qd, link, point, frame, (velocity_doc + at_qd).c_str());
  m.def(
      "jacobian",
      [](const ModelPtr& mo, py::handle q_, py::handle l, py::handle p, py::handle f) {
        return jacobian_of(LinkQuery(state_at(mo, q_, py::none()), l), p, f);
      },
      model, q, link, point, frame, (jacobian_doc + at_q).c_str());
  m.def(
      "jacobian_dot_times_qd",
      [](const ModelPtr& mo, py::handle q_, py::handle qd_, py::handle l, py::handle p,
         py::handle f) { return jacobian_dot_of(LinkQuery(state_at(mo, q_, qd_), l), p, f); },
      model, q, qd, link, point, frame, (jdot_doc + at_qd).c_str());
  m.def(
      "inverse_dynamics",
      [](const ModelPtr& mo, py::handle q_, py::handle qd_, py::handle qdd) {
        return RobotQuery(state_at(mo, q_, qd_)).inverse_dynamics(qdd);
      },
      model, q, qd, py::arg("qdd"), (id_doc + at_qd).c_str());
  m.def(
      "forward_dynamics",
      [](const ModelPtr& mo, py::handle q_, py::handle qd_, py::handle tau) {
        return RobotQuery(state_at(mo, q_, qd_)).forward_dynamics(tau);
      },
      model, q, qd, py::arg("tau"), (fd_doc + at_qd).c_str());

  // Batch: the same queries for every environment at once, (N, ...) new arrays; each row is
  // what the environment's own Simulation method returns.
  auto batch = py::reinterpret_borrow<py::class_<Batch, BatchHolder>>(m.attr("Batch"));
  const std::string per_env = " Every environment at its own state and model, on num_threads "
                              "threads; a new array.";
  batch
      .def(
          "link_poses",
          [](const Batch& b, py::handle l) {
            const NameOrIndex li = link_arg(l);
            const RowMatrix rows = locked(b, [&] { return b.link_poses(link_of(b.model(), li)); });
            py::array_t<double> R({rows.rows(), Eigen::Index{3}, Eigen::Index{3}});
            py::array_t<double> p({rows.rows(), Eigen::Index{3}});
            for (Eigen::Index i = 0; i < rows.rows(); ++i) {
              std::memcpy(R.mutable_data(i), rows.row(i).data(), 9 * sizeof(double));
              std::memcpy(p.mutable_data(i), rows.row(i).data() + 9, 3 * sizeof(double));
            }
            return py::make_tuple(R, p);
          },
          link, ("(R, p) of a link (name or index) in every environment: R (N, 3, 3), p (N, 3), "
                 "as Simulation.link_pose." + per_env).c_str())
      .def(
          "jacobians",
          [](const Batch& b, py::handle l, py::handle p, py::handle f) {
            const NameOrIndex li = link_arg(l);
            const Vec3 pt = to_point(p);
            const ReferenceFrame rf = to_reference(f);
            const int nv = model_of(b)->nv;
            return reshaped(locked(b, [&] {
              return b.frame_jacobians(link_of(b.model(), li), pt, rf);
            }), {6, nv});
          },
          link, point, frame,
          ("J (N, 6, nv), each environment's Simulation.jacobian(link, point, frame)." +
           std::string(kFrameDoc) + per_env).c_str())
      .def(
          "mass_matrices",
          [](const Batch& b) {
            const int nv = model_of(b)->nv;
            return reshaped(locked(b, [&] { return b.mass_matrices(); }), {nv, nv});
          },
          ("M (N, nv, nv), each environment's Simulation.mass_matrix()." + per_env).c_str())
      .def(
          "bias_forces",
          [](const Batch& b) { return locked(b, [&] { return b.bias_forces(); }); },
          ("b (N, nv), each environment's Simulation.bias_forces()." + per_env).c_str());
}
