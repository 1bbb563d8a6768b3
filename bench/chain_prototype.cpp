#include "chain_prototype.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "featherdrive/spatial/sincos.hpp"

namespace featherdrive::bench {
namespace {

using proto::Pair;
using proto::V6;

inline double sum(Pair x) {
  return x[0] + x[1];
}

inline double dot(const V6& a, const V6& b) {
  return sum(a.p[0] * b.p[0] + a.p[1] * b.p[1] + a.p[2] * b.p[2]);
}

// y + s x
inline V6 axpy(double s, const V6& x, const V6& y) {
  const Pair k = {s, s};
  return V6{{y.p[0] + k * x.p[0], y.p[1] + k * x.p[1], y.p[2] + k * x.p[2]}};
}

inline V6 operator+(const V6& a, const V6& b) {
  return V6{{a.p[0] + b.p[0], a.p[1] + b.p[1], a.p[2] + b.p[2]}};
}

inline double at(const V6& v, int i) {
  return v.p[i / 2][i % 2];
}

// M x for M given by its columns.
inline V6 times(const V6* M, const V6& x) {
  V6 y = axpy(at(x, 0), M[0], V6{});
  for (int j = 1; j < 6; ++j) y = axpy(at(x, j), M[j], y);
  return y;
}

inline V6 make6(const double* top, const double* bottom) {
  return V6{{Pair{top[0], top[1]}, Pair{top[2], bottom[0]}, Pair{bottom[1], bottom[2]}}};
}

inline void cross3(const double* a, const double* b, double* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

[[noreturn]] void refuse(const std::string& what) {
  throw std::invalid_argument("ChainPrototype: " + what);
}

// R's columns A1 and A2 turned by the angle of (c, s) about column A (R = R_p R(e_A, q)).
template <int A>
inline void turn(double* R, double c, double s) {
  constexpr int A1 = A == 2 ? 0 : A + 1, A2 = A == 0 ? 2 : A - 1;
  for (int a = 0; a < 3; ++a) {
    const double x = R[3 * A1 + a], y = R[3 * A2 + a];
    R[3 * A1 + a] = c * x + s * y;
    R[3 * A2 + a] = c * y - s * x;
  }
}

}  // namespace

ChainPrototype::ChainPrototype(const Simulation& sim) {
  const Model& model = sim.model();
  const SimulationOptions& o = sim.options();
  if (o.solver != SolverType::pgs || o.compat != Compat::none)
    refuse("the options must be PGS with compat none");
  if (model.num_links() < 2 || model.links[0].joint_type != JointType::fixed ||
      !model.links[0].tree_transform.E.isIdentity(0.0) ||
      !model.links[0].tree_transform.r.isZero(0.0))
    refuse("link 0 must be fixed at the origin");
  if (!sim.applied_force().isZero(0.0)) refuse("applied forces must be zero");
  n_ = model.nv;
  dt_ = o.dt;
  position_iterations_ = o.position_iterations;
  velocity_iterations_ = o.velocity_iterations;
  for (int k = 0; k < 3; ++k) gravity_[k] = model.gravity[k];
  links_.resize(static_cast<size_t>(n_));
  bodies_.resize(static_cast<size_t>(n_));
  hot_.assign(static_cast<size_t>(n_ + 1), Hot{});
  dofs_.assign(static_cast<size_t>(n_), Dof{});
  q_.resize(static_cast<size_t>(n_));
  qd_.resize(static_cast<size_t>(n_));
  for (int i = 0; i < n_; ++i) {
    const featherdrive::Link& l = model.links[static_cast<size_t>(i + 1)];
    Link& k = links_[static_cast<size_t>(i)];
    const std::string name = "link '" + l.name + "'";
    if (l.parent != i || l.joint_type != JointType::revolute || l.v_index != i || l.q_index != i)
      refuse(name + " must be a revolute child of the link before it");
    if (!l.tree_transform.E.isIdentity(0.0)) refuse(name + " must not rotate its joint frame");
    int axis = -1;
    for (int a = 0; a < 3; ++a)
      if (std::abs(l.axis[a]) == 1.0) axis = a;
    if (axis < 0) refuse(name + " must turn about a coordinate axis");
    if (!Mat3(l.inertia_com.diagonal().asDiagonal()).isApprox(l.inertia_com, 0.0))
      refuse(name + " must have a diagonal inertia");
    if (std::isfinite(model.lower_limit[i]) || std::isfinite(model.upper_limit[i]) ||
        std::isfinite(model.velocity_limit[i]) || model.damping[i] != 0.0 ||
        model.friction[i] != 0.0)
      refuse(name + " must have no limits, damping or friction");
    const Drive& drive = sim.drive(i);
    if (drive.type != DriveType::force) refuse(name + " must have a force drive");
    k.A = axis;
    k.A1 = axis == 2 ? 0 : axis + 1;
    k.A2 = axis == 0 ? 2 : axis - 1;
    k.sign = l.axis[axis];
    for (int a = 0; a < 3; ++a) {
      k.r[a] = l.tree_transform.r[a];
      k.com[a] = l.com[a];
      k.moment[a] = l.inertia_com(a, a);
    }
    k.mass = l.mass;
    k.armature = model.armature[i];
    const double h = dt_;
    k.drive_a = h * (h * drive.stiffness + drive.damping);
    k.drive_b = h * drive.damping * drive.target_velocity;
    k.h_kp = h * drive.stiffness;
    k.target = drive.target_position;
    dofs_[static_cast<size_t>(i)].max_impulse = std::min(drive.max_force * dt_, drive.max_impulse);
    q_[static_cast<size_t>(i)] = sim.q()[i];
    qd_[static_cast<size_t>(i)] = sim.qd()[i];
  }
}

void ChainPrototype::set_state(const std::vector<double>& q, const std::vector<double>& qd) {
  if (q.size() != q_.size() || qd.size() != qd_.size()) refuse("set_state: sizes differ from nv");
  q_ = q;
  qd_ = qd;
}

std::vector<double> ChainPrototype::drive_force() const {
  std::vector<double> f(static_cast<size_t>(n_));
  for (int i = 0; i < n_; ++i)
    f[static_cast<size_t>(i)] = dofs_[static_cast<size_t>(i)].accumulated / dt_;
  return f;
}

void ChainPrototype::step() {
  const int n = n_;
  const double dt = dt_;
  Link* const links = links_.data();
  Body* const bodies = bodies_.data();
  Hot* const hot = hot_.data();
  Dof* const dofs = dofs_.data();
  double* const q = q_.data();
  double* const qd = qd_.data();

  // Pass 1, root to tip: pose, S, the body's inertia in frame 0, velocity, c = v x S qd and
  // pA = v x* I v (docs/math/unit_response.md, "Frame 0").
  double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // column-major: R[3 * column + row]
  double p[3] = {0, 0, 0}, w[3] = {0, 0, 0}, vo[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const Link& k = links[i];
    Body& b = bodies[i];
    Hot& J = hot[i];
    double s, c;
    sincos_inline(k.sign * q[i], s, c);
    for (int a = 0; a < 3; ++a) p[a] += R[a] * k.r[0] + R[3 + a] * k.r[1] + R[6 + a] * k.r[2];
    if (k.A == 0)
      turn<0>(R, c, s);
    else if (k.A == 1)
      turn<1>(R, c, s);
    else
      turn<2>(R, c, s);
    const double* const column = R + 3 * k.A;
    const double axis[3] = {k.sign * column[0], k.sign * column[1], k.sign * column[2]};
    double pxa[3];
    cross3(p, axis, pxa);
    J.S = make6(axis, pxa);
    // I = [A, mc x; (mc x)^T, m 1], A = R Ic R^T + m (c^T c 1 - c c^T).
    double com[3], mc[3];
    for (int a = 0; a < 3; ++a) {
      com[a] = p[a] + R[a] * k.com[0] + R[3 + a] * k.com[1] + R[6 + a] * k.com[2];
      mc[a] = k.mass * com[a];
    }
    const double mcc = mc[0] * com[0] + mc[1] * com[1] + mc[2] * com[2];
    double A[3][3];
    for (int r = 0; r < 3; ++r)
      for (int t = r; t < 3; ++t) {
        double e = k.moment[0] * R[r] * R[t] + k.moment[1] * R[3 + r] * R[3 + t] +
                   k.moment[2] * R[6 + r] * R[6 + t] - mc[r] * com[t];
        if (r == t) e += mcc;
        A[r][t] = A[t][r] = e;
      }
    const double m = k.mass, x = mc[0], y = mc[1], z = mc[2];
    V6* const I = b.IA;
    I[0] = V6{{Pair{A[0][0], A[1][0]}, Pair{A[2][0], 0.0}, Pair{-z, y}}};
    I[1] = V6{{Pair{A[0][1], A[1][1]}, Pair{A[2][1], z}, Pair{0.0, -x}}};
    I[2] = V6{{Pair{A[0][2], A[1][2]}, Pair{A[2][2], -y}, Pair{x, 0.0}}};
    I[3] = V6{{Pair{0.0, z}, Pair{-y, m}, Pair{0.0, 0.0}}};
    I[4] = V6{{Pair{-z, 0.0}, Pair{x, 0.0}, Pair{m, 0.0}}};
    I[5] = V6{{Pair{y, -x}, Pair{0.0, 0.0}, Pair{0.0, m}}};
    const double rate = qd[i];
    const double wJ[3] = {rate * axis[0], rate * axis[1], rate * axis[2]};
    const double vJ[3] = {rate * pxa[0], rate * pxa[1], rate * pxa[2]};
    for (int a = 0; a < 3; ++a) w[a] += wJ[a], vo[a] += vJ[a];
    double ct[3], cb[3], t1[3], t2[3];
    cross3(w, wJ, ct);
    cross3(w, vJ, t1);
    cross3(vo, wJ, t2);
    for (int a = 0; a < 3; ++a) cb[a] = t1[a] + t2[a];
    b.c = make6(ct, cb);
    // h = I v from the parts; pA = [w x h_top + vo x h_bottom; w x h_bottom].
    double h_top[3], h_bottom[3], mcxv[3], mcxw[3], pt[3], pb[3];
    cross3(mc, vo, mcxv);
    cross3(mc, w, mcxw);
    for (int a = 0; a < 3; ++a) {
      h_top[a] = A[a][0] * w[0] + A[a][1] * w[1] + A[a][2] * w[2] + mcxv[a];
      h_bottom[a] = m * vo[a] - mcxw[a];
    }
    cross3(w, h_top, t1);
    cross3(vo, h_bottom, t2);
    for (int a = 0; a < 3; ++a) pt[a] = t1[a] + t2[a];
    cross3(w, h_bottom, pb);
    b.pA = make6(pt, pb);
  }

  // Pass 2, tip to root: U = IA S, D^-1, u; the child's Ia and pa carried to its parent.
  V6 carried_IA[6] = {}, carried_pA = {};
  for (int i = n - 1; i >= 0; --i) {
    Body& b = bodies[i];
    Hot& J = hot[i];
    V6* const IA = b.IA;
    for (int j = 0; j < 6; ++j) IA[j] = IA[j] + carried_IA[j];
    const V6 pA = b.pA + carried_pA;
    b.pA = pA;
    J.U = times(IA, J.S);
    const double D_inv = 1.0 / (dot(J.S, J.U) + links[i].armature);
    J.D_inv = D_inv;
    const double u = -dot(J.S, pA);
    b.u = u;
    const double s = D_inv * (u - dot(J.U, b.c));
    carried_pA = axpy(s, J.U, pA + times(IA, b.c));
    for (int j = 0; j < 6; ++j) carried_IA[j] = axpy(-D_inv * at(J.U, j), J.U, IA[j]);
  }

  // Pass 3, root to tip: accelerations and the free velocity; the response (Lambda, W, G,
  // (M^-1)_ii; docs/math/unit_response.md) and the drive rows (eq. 13-15, 20-22), all frozen for
  // the step.
  V6 acc = {{Pair{0.0, 0.0}, Pair{0.0, -gravity_[0]}, Pair{-gravity_[1], -gravity_[2]}}};
  V6 Lambda[6] = {};
  for (int i = 0; i < n; ++i) {
    const Body& b = bodies[i];
    Hot& J = hot[i];
    acc = acc + b.c;
    const double D_inv = J.D_inv;
    const double qdd = D_inv * (b.u - dot(J.U, acc));
    acc = axpy(qdd, J.S, acc);
    qd[i] += dt * qdd;
    J.W = times(Lambda, J.U);
    const double r = D_inv + D_inv * D_inv * dot(J.U, J.W);
    J.r = r;
    J.G = axpy(-D_inv, J.W, axpy(r, J.S, V6{}));
    // Lambda = T + S G^T - W (D^-1 S)^T, column by column.
    for (int j = 0; j < 6; ++j)
      Lambda[j] = axpy(-at(J.S, j) * D_inv, J.W, axpy(at(J.G, j), J.S, Lambda[j]));
    if (i > 0) {
      const Hot& P = hot[i - 1];
      J.parent_S = dot(J.U, P.S);
      J.base_per_parent_base = -D_inv * J.parent_S;
      J.base_per_parent_impulse = P.D_inv * (D_inv * dot(J.U, P.W)) + P.r * J.base_per_parent_base;
    }
    const Link& k = links[i];
    const double x = 1.0 / (k.drive_a * r + 1.0);
    J.row_T = x * (k.drive_b + k.h_kp * (k.target - q[i]));
    J.row_V = -x * k.drive_a;
    J.row_m = 1.0 - x;
    dofs[i].accumulated = 0.0;
  }

  for (int it = 0; it < position_iterations_; ++it) sweep();
  for (int i = 0; i < n; ++i) q[i] += dt * qd[i];
  for (int it = 0; it < velocity_iterations_; ++it) sweep();
}

// One Gauss-Seidel sweep (include/featherdrive/solver/gauss_seidel.hpp's chain run): root to
// tip, each row sees its exact velocity through base, the part of its joint's velocity change
// from the rows before it; tip to root, the impulses handed up finish each joint's velocity.
void ChainPrototype::sweep() {
  const int n = n_;
  const Hot* const hot = hot_.data();
  Dof* const dofs = dofs_.data();
  double* const qd = qd_.data();
  V6 dv = {};
  double base = 0.0;
  for (int i = 0; i < n; ++i) {
    const Hot& J = hot[i];
    const Hot& C = hot[i + 1];  // zero after the last
    const double ahead = -C.D_inv * dot(C.U, dv) + base * C.base_per_parent_base;
    Dof& f = dofs[i];
    double lambda = J.row_T + J.row_m * f.accumulated + J.row_V * (qd[i] + base);
    const double bound = f.max_impulse;
    lambda = lambda > bound ? bound : lambda < -bound ? -bound : lambda;
    const double impulse = lambda - f.accumulated;
    f.accumulated = lambda;
    f.impulse = impulse;
    const double change = base + J.r * impulse;
    f.entry_change = change;
    dv = axpy(change, J.S, axpy(-J.D_inv * impulse, J.W, dv));
    base = ahead + impulse * C.base_per_parent_impulse;
  }
  V6 pA = {};
  double x = 0.0;  // S_i^T pA
  for (int i = n - 1; i >= 0; --i) {
    const Hot& J = hot[i];
    const Dof& f = dofs[i];
    const double beta = J.D_inv * (f.impulse - x);
    qd[i] += f.entry_change - dot(J.G, pA);
    if (i > 0) x = dot(hot[i - 1].S, pA) + beta * J.parent_S;
    pA = axpy(beta, J.U, pA);
  }
}

}  // namespace featherdrive::bench
