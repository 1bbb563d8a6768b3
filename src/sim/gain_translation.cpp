// Per-step maps of a lone drive in both engines and the translation between them
// (docs/mujoco_bridge.md, eq. B1-B12).
#include "featherdrive/sim/gain_translation.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/sim/control_step.hpp"

namespace featherdrive {
namespace {

using Row3 = Eigen::Matrix<double, 1, 3>;

struct ForceGains {
  double kp, kd;
};

// An acceleration drive is the force drive with gains times m (eq. B4: x^alpha = 1 / (a + 1)
// equals the force drive's 1 / (a r + 1) for m kp, m kd).
ForceGains force_gains(double m, const Drive& drive) {
  const double scale = drive.type == DriveType::acceleration ? m : 1.0;
  return {drive.stiffness * scale, drive.damping * scale};
}

// One implicit sub-step of h ending the sub-step `time_to_end` before the step's end, composed
// onto (A, B): eq. B1-B2, v1 = (m v0 + h (kp (x_T - time_to_end v_T - x0) + kd v_T)) /
// (m + h kd + h^2 kp), x1 = x0 + h v1.
void compose_implicit(double m, ForceGains g, double h, double time_to_end, DriveStepMap& map) {
  const double alpha = m / (m + h * g.kd + h * h * g.kp);
  const double c = alpha * h * g.kp / m;
  Eigen::Matrix2d P;
  P << 1.0 - h * c, h * alpha, -c, alpha;
  Row3 q;
  q << c, alpha * h / m * (g.kd - g.kp * time_to_end), 0.0;
  Eigen::Matrix<double, 2, 3> Q;
  Q.row(0) = h * q;
  Q.row(1) = q;
  map.A = P * map.A;
  map.B = P * map.B + Q;
}

DriveStepMap identity_map() {
  DriveStepMap map;
  map.A.setIdentity();
  map.B.setZero();
  return map;
}

void check_inertia(double m) {
  if (!(m > 0.0) || !std::isfinite(m))
    throw std::invalid_argument("effective inertia m = " + format_double(m) +
                                ": must be finite and > 0");
}

void check_step(double dt) {
  if (!(dt >= kMinDt && dt <= kMaxDt))
    throw std::invalid_argument("dt = " + format_double(dt) + ": must be a normal number in [" +
                                format_double(kMinDt) + ", " + format_double(kMaxDt) + "] s");
}

void check_gain(const char* name, double value) {
  if (!std::isfinite(value) || value < 0.0)
    throw std::invalid_argument(std::string("MuJoCo setting: ") + name + " = " +
                                format_double(value) + ": must be finite and >= 0");
}

// A translated gain that does not fit a double (or is NaN) is refused, not written.
void check_result(const char* name, double value) {
  if (!std::isfinite(value))
    throw std::invalid_argument(std::string("the translated ") + name + " = " +
                                format_double(value) +
                                " is not a finite number: the gains or the inertia are out of "
                                "range");
}

std::complex<double> pole(const Eigen::Matrix2d& A, int k) {
  const double tr = A.trace(), det = A.determinant();
  const std::complex<double> root = std::sqrt(std::complex<double>(tr * tr / 4.0 - det));
  return tr / 2.0 + (k == 0 ? root : -root);
}

// Sub-step gains (h^2 kp, h kd) of an implicit step of h with inertia m whose map has trace tr
// and determinant det (eq. B11): det = m / (m + h kd + h^2 kp), tr = 1 + det - h^2 kp det / m.
ForceGains implicit_gains_for_poles(double m, double h, double tr, double det) {
  const double h2kp = (1.0 + det - tr) * m / det;
  const double hkd = m / det - m - h2kp;
  return {h2kp / (h * h), hkd / h};
}

std::string fmt(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.4g", v);
  return buffer;
}

}  // namespace

double step_spectral_radius(const Eigen::Matrix2d& A) {
  return std::max(std::abs(pole(A, 0)), std::abs(pole(A, 1)));
}

const char* to_string(MujocoIntegrator integrator) {
  return integrator == MujocoIntegrator::euler ? "euler" : "implicit";
}

DriveStepMap physx_step_map(double m, const Drive& drive, const SimulationOptions& options) {
  check_inertia(m);
  validate_options(options);
  validate_drive(drive, "(translated)");
  const ForceGains g = drive.type == DriveType::none ? ForceGains{0.0, 0.0} : force_gains(m, drive);
  const double dt = options.dt;
  const bool tgs = options.solver == SolverType::tgs;
  const int n = tgs ? options.position_iterations : 1;
  const double h = dt / n;
  DriveStepMap map = identity_map();
  map.B(1, 2) = dt / m;  // the free velocity v* = v + dt f / m, once per step (eq. B3)
  for (int i = 1; i <= n; ++i) compose_implicit(m, g, h, tgs ? dt - i * h : 0.0, map);
  return map;
}

std::pair<double, double> mujoco_ctrl(const MujocoDrive& drive, double x_target, double v_target,
                                      double dt, int substep) {
  double position = x_target + drive.ctrl_velocity_gain * v_target;
  if (drive.interpolate_target) position -= (dt - substep * (dt / drive.substeps)) * v_target;
  return {position, v_target};
}

void validate_mujoco_drive(const MujocoDrive& drive) {
  check_gain("kp", drive.kp);
  check_gain("kv", drive.kv);
  check_gain("damping", drive.damping);
  check_gain("armature", drive.armature);
  if (!std::isfinite(drive.ctrl_velocity_gain))
    throw std::invalid_argument("MuJoCo setting: ctrl_velocity_gain = " +
                                format_double(drive.ctrl_velocity_gain) + ": must be finite");
  if (drive.substeps < 1 || drive.substeps > kMaxSubsteps)
    throw std::invalid_argument("MuJoCo setting: substeps = " + std::to_string(drive.substeps) +
                                ": must be in [1, " + std::to_string(kMaxSubsteps) + "]");
  if (drive.integrator != MujocoIntegrator::euler && drive.integrator != MujocoIntegrator::implicit)
    throw std::invalid_argument("MuJoCo setting: integrator = " +
                                std::to_string(static_cast<int>(drive.integrator)) +
                                ": must be euler or implicit");
}

DriveStepMap mujoco_step_map(double m, const MujocoDrive& drive, double dt) {
  check_inertia(m);
  validate_mujoco_drive(drive);
  check_step(dt);
  const double h = dt / drive.substeps;
  const double mass = m + drive.armature;
  // Euler: damping implicit, kv explicit; implicit: both implicit (eq. B5-B6).
  const bool implicit = drive.integrator == MujocoIntegrator::implicit;
  const double b = drive.damping + (implicit ? drive.kv : 0.0);
  const double kv_explicit = implicit ? 0.0 : drive.kv;
  const double mu = 1.0 / (mass + h * b);
  DriveStepMap map = identity_map();
  for (int i = 1; i <= drive.substeps; ++i) {
    Eigen::Matrix2d P;
    P << 1.0 - h * h * drive.kp * mu, h * (mass - h * kv_explicit) * mu, -h * drive.kp * mu,
        (mass - h * kv_explicit) * mu;
    // ctrl = x_T + (g - interpolation) v_T for the position actuator, v_T for the velocity one.
    const double ctrl_v = mujoco_ctrl(drive, 0.0, 1.0, dt, i).first;
    Row3 q;
    q << h * drive.kp * mu, h * mu * (drive.kp * ctrl_v + drive.kv), h * mu;
    Eigen::Matrix<double, 2, 3> Q;
    Q.row(0) = h * q;
    Q.row(1) = q;
    map.A = P * map.A;
    map.B = P * map.B + Q;
  }
  return map;
}

bool stable(const DriveStepMap& map) {
  return step_spectral_radius(map.A) < 1.0 + 1e-12;
}

MapDistance map_distance(const DriveStepMap& a, const DriveStepMap& b, int steps) {
  MapDistance d;
  const double radius = std::max(step_spectral_radius(a.A), step_spectral_radius(b.A));
  if (steps <= 0) {
    // Until the slower response has settled to 1e-4 of the step (10 000 steps at most).
    steps = radius < 1.0 ? static_cast<int>(std::ceil(std::log(1e-4) / std::log(radius))) : 1000;
    steps = std::clamp(steps, 100, 10000);
  }
  d.steps = steps;
  Eigen::Vector2d sa = Eigen::Vector2d::Zero(), sb = Eigen::Vector2d::Zero();
  const Eigen::Vector3d unit_step(1.0, 0.0, 0.0);
  for (int k = 0; k < steps; ++k) {
    sa = a.A * sa + a.B * unit_step;
    sb = b.A * sb + b.B * unit_step;
    const double diff = std::abs(sa[0] - sb[0]);
    if (!std::isfinite(diff)) {
      d.step_response = std::numeric_limits<double>::infinity();
      break;
    }
    d.step_response = std::max(d.step_response, diff);
  }
  const std::complex<double> pa0 = pole(a.A, 0), pa1 = pole(a.A, 1);
  const std::complex<double> pb0 = pole(b.A, 0), pb1 = pole(b.A, 1);
  d.poles = std::min(std::max(std::abs(pa0 - pb0), std::abs(pa1 - pb1)),
                     std::max(std::abs(pa0 - pb1), std::abs(pa1 - pb0)));
  return d;
}

MujocoDrive literal_mujoco_drive(double m, const Drive& drive, MujocoIntegrator integrator) {
  check_inertia(m);
  validate_drive(drive, "(translated)");
  const ForceGains g = force_gains(m, drive);
  MujocoDrive out;
  out.kp = g.kp;
  out.kv = g.kd;
  out.integrator = integrator;
  check_result("kp", out.kp);
  check_result("kv", out.kv);
  return out;
}

MujocoTranslation translate_to_mujoco(double m, const Drive& drive,
                                      const SimulationOptions& options,
                                      const TranslationOptions& translation) {
  check_inertia(m);
  validate_options(options);
  validate_drive(drive, "(translated)");
  if (drive.type == DriveType::none)
    throw std::invalid_argument("translate_to_mujoco: the drive has type none");
  const DriveStepMap physx = physx_step_map(m, drive, options);
  const ForceGains g = force_gains(m, drive);
  const double dt = options.dt;
  const bool tgs = options.solver == SolverType::tgs;
  const int n = tgs ? options.position_iterations : 1;
  MujocoTranslation out;
  MujocoDrive& mj = out.mujoco;
  mj.integrator = translation.integrator;
  mj.kp = g.kp;
  mj.ctrl_velocity_gain = g.kp > 0.0 ? g.kd / g.kp : 0.0;
  if (n == 1 || !translation.keep_timestep) {
    // Eq. B7-B8: MuJoCo at PhysX's (sub-)step h with joint damping kd + h kp is the same
    // implicit step, the stiffness's implicit share carried by the damping.
    const double h = dt / n;
    mj.damping = g.kd + h * g.kp;
    mj.substeps = n;
    mj.interpolate_target = n > 1;
  } else {
    // Eq. B9-B10: at MuJoCo's timestep dt, match trace and determinant with armature and damping
    // at the same kp (the same steady state under a load).
    const double tr = physx.A.trace(), det = physx.A.determinant();
    const double mu = (1.0 + det - tr) / (dt * dt * g.kp);
    const double mass = det / mu;
    mj.armature = mass - m;
    mj.damping = (1.0 / mu - mass) / dt;
    if (!(g.kp > 0.0) || !(mu > 0.0) || mj.armature < 0.0 || mj.damping < 0.0 ||
        !std::isfinite(mj.armature + mj.damping)) {
      out.reproducible = false;
      out.note = "not reproducible at MuJoCo timestep dt: TGS " + std::to_string(n) +
                 " sub-steps at kp dt^2/m = " + fmt(g.kp * dt * dt / m) + " would need armature " +
                 fmt(mj.armature) + " and damping " + fmt(mj.damping);
      // The closer (in step response) of two settings without armature: the damping that
      // matches TGS's decay (det A), and one implicit step of dt (eq. B7 with h = dt).
      MujocoDrive decay = mj, one_step = mj;
      decay.armature = one_step.armature = 0.0;
      decay.damping = std::max(0.0, (m / det - m) / dt);
      one_step.damping = g.kd + dt * g.kp;
      const bool decay_closer = map_distance(physx, mujoco_step_map(m, decay, dt)).step_response <
                                map_distance(physx, mujoco_step_map(m, one_step, dt)).step_response;
      mj = decay_closer ? decay : one_step;
      out.note += decay_closer ? "; closest: armature 0, the damping of TGS's decay"
                               : "; closest: armature 0, damping kd + dt kp (one implicit step)";
    }
  }
  check_result("kp", mj.kp);
  check_result("damping", mj.damping);
  check_result("armature", mj.armature);
  check_result("ctrl_velocity_gain", mj.ctrl_velocity_gain);
  out.distance = map_distance(physx, mujoco_step_map(m, mj, dt));
  out.exact = out.reproducible && out.distance.step_response <= 1e-9;
  if (out.reproducible && !out.exact && out.note.empty())
    out.note = "poles matched; the step response differs by " + fmt(out.distance.step_response) +
               " of the step";
  if (g.kp == 0.0 && out.note.empty())
    out.note = "no stiffness: a velocity target is not carried (MuJoCo damps towards 0)";
  return out;
}

PhysxTranslation translate_to_physx(double m, const MujocoDrive& mujoco,
                                    const SimulationOptions& options) {
  check_inertia(m);
  validate_options(options);
  validate_mujoco_drive(mujoco);
  if (mujoco.substeps != 1)
    throw std::invalid_argument(
        "translate_to_physx: substeps = " + std::to_string(mujoco.substeps) + ": must be 1");
  const double dt = options.dt;
  const double mass = m + mujoco.armature;  // MuJoCo's armature becomes featherdrive's
  const DriveStepMap target = mujoco_step_map(m, mujoco, dt);
  const bool tgs = options.solver == SolverType::tgs;
  const int n = tgs ? options.position_iterations : 1;
  const double h = dt / n;
  PhysxTranslation out;
  out.drive.type = DriveType::force;
  // Eq. B11-B12: PhysX's step is n implicit sub-steps of h; its poles are the n-th powers of the
  // sub-step's, so the sub-step takes the principal n-th roots of MuJoCo's poles.
  std::complex<double> s0 = pole(target.A, 0), s1 = pole(target.A, 1);
  bool real_roots = true;
  if (n > 1) {
    if (s0.imag() == 0.0 && s1.imag() == 0.0 && (s0.real() < 0.0 || s1.real() < 0.0))
      real_roots = false;  // a negative real pole has no real n-th root pair for even n
    s0 = std::pow(s0, 1.0 / n);
    s1 = std::pow(s1, 1.0 / n);
  }
  const double tr = (s0 + s1).real(), det = (s0 * s1).real();
  ForceGains g =
      real_roots && det > 0.0 ? implicit_gains_for_poles(mass, h, tr, det) : ForceGains{-1.0, -1.0};
  if (!(g.kp >= 0.0) || !(g.kd >= 0.0) || !std::isfinite(g.kp + g.kd)) {
    out.reproducible = false;
    out.note = "not reproducible: MuJoCo's step (poles " + fmt(std::abs(pole(target.A, 0))) + ", " +
               fmt(std::abs(pole(target.A, 1))) +
               " in modulus) is less damped than any implicit drive at this dt (it needs "
               "stiffness " +
               fmt(g.kp) + ", damping " + fmt(g.kd) +
               "); closest: MuJoCo's stiffness without damping";
    g = {mujoco.kp, 0.0};
  }
  check_result("stiffness", g.kp);
  check_result("damping", g.kd);
  out.drive.stiffness = g.kp;
  out.drive.damping = g.kd;
  out.distance = map_distance(target, physx_step_map(mass, out.drive, options));
  out.exact = out.reproducible && out.distance.step_response <= 1e-9;
  if (out.reproducible && std::abs(g.kp - mujoco.kp) > 1e-9 * std::max(1.0, mujoco.kp))
    out.note = "poles matched with stiffness " + fmt(g.kp) + " against MuJoCo's " + fmt(mujoco.kp) +
               ": the steady state under a load differs";
  if (out.reproducible && !out.exact)
    out.note += std::string(out.note.empty() ? "poles matched" : "") +
                "; TGS's sub-steps move the position within the step, so the step "
                "response differs by " +
                fmt(out.distance.step_response) + " of the step";
  return out;
}

VecX effective_inertia(const Model& model, const VecX& q) {
  if (q.size() != model.nq)
    throw std::invalid_argument("effective_inertia: q has " + std::to_string(q.size()) +
                                " entries, the model " + std::to_string(model.nq));
  for (Eigen::Index i = 0; i < q.size(); ++i)
    if (!std::isfinite(q[i]))
      throw std::invalid_argument("effective_inertia: q[" + std::to_string(i) +
                                  "] = " + format_double(q[i]) + ": must be finite");
  Data data(model);
  const VecX m = inverse_mass_diagonal(model, data, q).cwiseInverse();
  for (Eigen::Index i = 0; i < m.size(); ++i)
    if (!(m[i] > 0.0) || !std::isfinite(m[i]))
      throw std::invalid_argument("effective_inertia: dof " + std::to_string(i) +
                                  " has effective inertia " + format_double(m[i]) +
                                  ": the mass matrix is singular or out of range at q");
  return m;
}

}  // namespace featherdrive
