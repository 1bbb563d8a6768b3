// The stability check (docs/stability_check.md, eq. S1-S9).
#include "featherdrive/sim/stability_check.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/kinematics.hpp"

namespace featherdrive {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kMaxJointSubsteps = 1024;

std::string fmt(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

bool one_dof(JointType type) { return type == JointType::revolute || type == JointType::prismatic; }

double rho_of(double m, const JointGains& gains, const SimulationOptions& options) {
  return step_spectral_radius(joint_step_matrix(m, gains, options));
}

bool stable_at(double m, const JointGains& gains, const SimulationOptions& options) {
  return rho_of(m, gains, options) <= 1.0 + kStableTolerance;
}

// The smallest x in (lo, hi] with stable(x), given !stable(lo) and stable(hi), to a relative
// 1e-4 (eq. S8-S9).
template <class Stable>
double bisect(double lo, double hi, const Stable& stable) {
  for (int i = 0; i < 200 && hi - lo > 1e-4 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (stable(mid) ? hi : lo) = mid;
  }
  return hi;
}

// The smallest added amount (armature, damping) that makes the map stable: doubling from
// `start` up to `start` 2^60, then bisection; -1 where none does.
template <class Stable>
double smallest_addition(double start, const Stable& stable) {
  double lo = 0.0;
  for (double x = start; x <= start * 1.2e18; x *= 2.0) {
    if (stable(x)) return bisect(lo, x, stable);
    lo = x;
  }
  return -1.0;
}

// Eq. S7: the fewest sub-steps n in 1..1024 with a stable map at dt / n (doubling, then
// bisection between the last unstable and the first stable count); 0 where none is.
int smallest_substeps(double m, const JointGains& gains, const SimulationOptions& options) {
  auto stable_n = [&](int n) {
    SimulationOptions o = options;
    o.dt = options.dt / n;
    return stable_at(m, gains, o);
  };
  int lo = 1, hi = 0;
  for (int n = 1; n <= kMaxJointSubsteps; n *= 2) {
    if (stable_n(n)) {
      hi = n;
      break;
    }
    lo = n;
  }
  if (hi == 0) return 0;
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    (stable_n(mid) ? hi : lo) = mid;
  }
  return hi;
}

void find_joint_fixes(JointStability& j, const JointGains& gains,
                      const SimulationOptions& options) {
  j.substeps = smallest_substeps(j.mass, gains, options);
  j.armature = smallest_addition(
      j.mass, [&](double a) { return stable_at(j.mass + a, gains, options); });
  const double kd_scale = gains.law == JointLaw::drive && gains.drive.type == DriveType::acceleration
                              ? 1.0
                              : j.mass;
  j.damping = smallest_addition(1e-6 * kd_scale / options.dt, [&](double d) {
    JointGains g = gains;
    if (g.law == JointLaw::drive)
      g.drive.damping += d;
    else
      g.damping += d;
    return stable_at(j.mass, g, options);
  });
}

// The revolute and prismatic dofs and their q entries (the linearisation's coordinates).
struct Coordinates {
  std::vector<int> dof, q;
};
Coordinates linear_coordinates(const Model& model) {
  Coordinates c;
  for (const Link& l : model.links)
    if (one_dof(l.joint_type)) {
      c.dof.push_back(l.v_index);
      c.q.push_back(l.q_index);
    }
  return c;
}

// Eq. S4: forward differences of one step of copies of sim; NaN if a step diverges.
double linear_step_radius(const Simulation& sim, const Coordinates& c) {
  const int n = static_cast<int>(c.dof.size());
  if (n == 0) return 0.0;
  // About rest at the initial q: targets there, no velocity (the step from the initial state
  // itself starts a large motion whose one-step Jacobian says little about the next ones).
  Simulation rest = sim;
  {
    VecX qd = rest.qd();
    for (int i = 0; i < n; ++i) {
      const int dof = c.dof[static_cast<size_t>(i)];
      qd[dof] = 0.0;
      if (joint_gains(rest, dof).law != JointLaw::none)
        rest.set_drive_target(dof, rest.q()[c.q[static_cast<size_t>(i)]], 0.0);
    }
    rest.set_qd(qd);
  }
  auto state_after = [&](int coordinate, double eps, Eigen::VectorXd& out) {
    Simulation copy = rest;
    VecX q = copy.q(), qd = copy.qd();
    if (coordinate >= 0) {
      if (coordinate < n)
        q[c.q[static_cast<size_t>(coordinate)]] += eps;
      else
        qd[c.dof[static_cast<size_t>(coordinate - n)]] += eps;
      copy.set_q(q);
      copy.set_qd(qd);
    }
    copy.step();
    out.resize(2 * n);
    for (int i = 0; i < n; ++i) {
      out[i] = copy.q()[c.q[static_cast<size_t>(i)]];
      out[n + i] = copy.qd()[c.dof[static_cast<size_t>(i)]];
    }
  };
  try {
    Eigen::VectorXd base, moved;
    state_after(-1, 0.0, base);
    Eigen::MatrixXd J(2 * n, 2 * n);
    for (int k = 0; k < 2 * n; ++k) {
      const double x = k < n ? rest.q()[c.q[static_cast<size_t>(k)]]
                             : rest.qd()[c.dof[static_cast<size_t>(k - n)]];
      const double eps = 1e-7 * (1.0 + std::abs(x));
      state_after(k, eps, moved);
      J.col(k) = (moved - base) / eps;
    }
    if (!J.allFinite()) return kNaN;
    return Eigen::EigenSolver<Eigen::MatrixXd>(J, false).eigenvalues().cwiseAbs().maxCoeff();
  } catch (const DivergenceError&) {
    return kNaN;
  }
}

// Eq. S5-S6 on a run of `steps` steps of dt, made as steps * substeps steps of dt / substeps of a
// copy of sim. Returns "" when bounded, else how it diverged.
std::string trial_run(const Simulation& sim, int steps, int substeps,
                      const StabilityCheckOptions& options, double& worst) {
  Simulation copy = sim;
  if (substeps > 1) {
    SimulationOptions o = copy.options();
    o.dt /= substeps;
    copy.set_options(o);
  }
  const double e0 = check_energy(copy), scale = check_energy_scale(copy);
  worst = 0.0;
  for (int k = 0; k < steps * substeps; ++k) {
    if (options.before_step) options.before_step(copy, k, substeps);
    try {
      copy.step();
    } catch (const DivergenceError&) {
      return "DivergenceError at step " + std::to_string(k + 1);
    }
    const double ratio = (check_energy(copy) - e0) / scale;
    if (!(ratio <= options.energy_factor))
      return "energy rose " + fmt(ratio) + " E_ref at step " + std::to_string(k + 1);
    worst = std::max(worst, ratio);
  }
  return "";
}

}  // namespace

const char* to_string(JointLaw law) {
  switch (law) {
    case JointLaw::none: return "none";
    case JointLaw::drive: return "drive";
    case JointLaw::explicit_pd: return "explicit_pd";
    case JointLaw::implicit_pd: return "implicit_pd";
  }
  return "?";
}

// The one place that picks a dof's law; an actuator solved implicitly would be the map of a
// force drive with the actuator's gains (law drive).
JointGains joint_gains(const Simulation& sim, int dof) {
  JointGains g;
  if (sim.has_actuator(dof)) {
    const ExplicitActuator& a = sim.actuator(dof);
    // An implicit actuator's row is a force drive with its gains (implicit_actuators.md, I4).
    g.law = a.integration == ActuatorIntegration::implicit_law ? JointLaw::implicit_pd
                                                                : JointLaw::explicit_pd;
    g.stiffness = a.stiffness;
    g.damping = a.damping;
  } else if (sim.drive(dof).type != DriveType::none) {
    g.law = JointLaw::drive;
    g.drive = sim.drive(dof);
  }
  return g;
}

Eigen::Matrix2d explicit_pd_step_matrix(double m, double kp, double kd, double h) {
  const double a = h * h * kp / m, b = h * kd / m;
  Eigen::Matrix2d A;
  A << 1.0 - a, h * (1.0 - b), -a / h, 1.0 - b;
  return A;
}

Eigen::Matrix2d joint_step_matrix(double m, const JointGains& gains,
                                  const SimulationOptions& options) {
  switch (gains.law) {
    case JointLaw::drive:
      return physx_step_map(m, gains.drive, options).A;
    case JointLaw::explicit_pd:
      return explicit_pd_step_matrix(m, gains.stiffness, gains.damping, options.dt);
    case JointLaw::implicit_pd: {
      Drive drive;
      drive.type = DriveType::force;
      drive.stiffness = gains.stiffness;
      drive.damping = gains.damping;
      return physx_step_map(m, drive, options).A;
    }
    case JointLaw::none:
      break;
  }
  return explicit_pd_step_matrix(m, 0.0, 0.0, options.dt);
}

double check_energy(const Simulation& sim) {
  const Model& model = sim.model();
  Data data(model);
  const VecX q = sim.q(), qd = sim.qd();
  forward_kinematics(model, data, q, qd);
  // An acceleration drive's spring is m kp with m the dof's effective inertia (eq. S5).
  VecX inertia;
  double springs = 0.0;
  for (const Link& l : model.links) {
    if (!one_dof(l.joint_type)) continue;
    const JointGains g = joint_gains(sim, l.v_index);
    double kp = g.law == JointLaw::explicit_pd || g.law == JointLaw::implicit_pd ? g.stiffness : 0.0;
    if (g.law == JointLaw::drive) {
      kp = g.drive.stiffness;
      if (g.drive.type == DriveType::acceleration) {
        if (inertia.size() == 0) inertia = effective_inertia(model, q);
        kp *= inertia[l.v_index];
      }
    }
    const double e = q[l.q_index] - sim.drive(l.v_index).target_position;
    springs += 0.5 * kp * e * e;
  }
  return kinetic_energy(model, data, qd) + potential_energy(model, data) + springs;
}

double check_energy_scale(const Simulation& sim) {
  const Model& model = sim.model();
  // W: every link's weight times the length of the path to its centre of mass (how far it can
  // fall), plus the initial kinetic and spring energy above the minimum.
  std::vector<double> reach(model.links.size(), 0.0);
  double weight = 0.0;
  for (size_t i = 0; i < model.links.size(); ++i) {
    const Link& l = model.links[i];
    const double parent = l.parent >= 0 ? reach[static_cast<size_t>(l.parent)] : 0.0;
    reach[i] = parent + l.tree_transform.r.norm();
    weight += l.mass * model.gravity.norm() * (reach[i] + l.com.norm());
  }
  Data data(model);
  const VecX q = sim.q(), qd = sim.qd();
  forward_kinematics(model, data, q, qd);
  const double free = check_energy(sim) - potential_energy(model, data);
  return std::max(weight + free, 1e-6);
}

namespace {

void validate(const StabilityCheckOptions& o) {
  auto refuse = [](const std::string& field, const std::string& value, const char* range) {
    throw std::invalid_argument("stability check: " + field + " = " + value + ": must be " + range);
  };
  const std::string most = std::to_string(kMaxTrialSteps);
  if (o.min_trial_steps < 0 || o.min_trial_steps > kMaxTrialSteps)
    refuse("min_trial_steps", std::to_string(o.min_trial_steps), ("in [0, " + most + "]").c_str());
  if (o.max_trial_steps < 0 || o.max_trial_steps > kMaxTrialSteps)
    refuse("max_trial_steps", std::to_string(o.max_trial_steps), ("in [0, " + most + "]").c_str());
  if (!std::isfinite(o.trial_seconds)) refuse("trial_seconds", fmt(o.trial_seconds), "finite");
  if (!(o.energy_factor > 0.0) || !std::isfinite(o.energy_factor))
    refuse("energy_factor", fmt(o.energy_factor), "finite and > 0");
  if (!(o.linear_tolerance >= 0.0)) refuse("linear_tolerance", fmt(o.linear_tolerance), ">= 0");
  if (o.max_robot_substeps < 1 || o.max_robot_substeps > 1024)
    refuse("max_robot_substeps", std::to_string(o.max_robot_substeps), "in [1, 1024]");
  if (o.robot_fix_length < 1 || o.robot_fix_length > 100)
    refuse("robot_fix_length", std::to_string(o.robot_fix_length), "in [1, 100]");
}

}  // namespace

StabilityReport check_stability(const Simulation& sim, const StabilityCheckOptions& options) {
  validate(options);
  const Model& model = sim.model();
  const SimulationOptions& o = sim.options();
  StabilityReport report;
  const VecX q = sim.q();
  const VecX m = effective_inertia(model, q);
  std::string why;
  auto add_why = [&](const std::string& text) { why += (why.empty() ? "" : "; ") + text; };
  for (const Link& l : model.links) {
    const bool spherical = l.joint_type == JointType::spherical;
    if (!one_dof(l.joint_type) && !spherical) continue;
    for (int k = 0; k < l.nv; ++k) {
      JointStability j;
      j.joint = l.joint_name;
      j.dof = l.v_index + k;
      j.axis = spherical ? k : -1;
      j.mass = m[j.dof];
      const JointGains g = joint_gains(sim, j.dof);
      j.law = g.law;
      const bool acceleration = g.law == JointLaw::drive && g.drive.type == DriveType::acceleration;
      const double kp = g.law == JointLaw::drive ? g.drive.stiffness : g.stiffness;
      const double kd = g.law == JointLaw::drive ? g.drive.damping : g.damping;
      const double inertia = acceleration ? 1.0 : j.mass;
      j.stiffness_ratio = kp * o.dt * o.dt / inertia;
      j.damping_ratio = kp > 0.0 ? kd / (2.0 * std::sqrt(kp * inertia)) : kNaN;
      j.rho = rho_of(j.mass, g, o);
      j.stable = j.rho <= 1.0 + kStableTolerance;
      if (!j.stable) {
        if (options.find_fixes) find_joint_fixes(j, g, o);
        add_why((spherical ? j.joint + "[" + std::to_string(k) + "]" : j.joint) + " (" +
                to_string(g.law) + ": kp dt^2/m " + fmt(j.stiffness_ratio) + ", rho " +
                fmt(j.rho) + ")");
      }
      report.joints.push_back(j);
    }
  }

  RobotStability& r = report.robot;
  const Coordinates c = linear_coordinates(model);
  r.linear_dofs = static_cast<int>(c.dof.size());
  r.linear_rho = options.linearise ? linear_step_radius(sim, c) : kNaN;
  r.linear_stable = !options.linearise || r.linear_rho <= 1.0 + options.linear_tolerance;

  const double wanted = std::ceil(std::max(options.trial_seconds, 0.0) / o.dt);
  const int steps = options.max_trial_steps <= 0
                        ? 0
                        : static_cast<int>(std::clamp<double>(
                              wanted, std::min(options.min_trial_steps, options.max_trial_steps),
                              options.max_trial_steps));
  r.trial_steps = steps;
  if (steps > 0) {
    double worst = 0.0;
    const std::string diverged = trial_run(sim, steps, 1, options, worst);
    r.trial_bounded = diverged.empty();
    r.trial_note = r.trial_bounded ? "largest energy rise " + fmt(worst) + " E_ref" : diverged;
    if (!r.trial_bounded) add_why("robot (trial run: " + diverged + ")");
  } else if (!r.linear_stable) {  // the linearisation decides only without a trial (S4)
    add_why("robot (linearised step: rho " + fmt(r.linear_rho) + ")");
  }
  const bool joints_stable = std::all_of(report.joints.begin(), report.joints.end(),
                                         [](const JointStability& j) { return j.stable; });
  if (options.find_fixes && joints_stable && !r.trial_bounded)
    for (int k = 2; k <= options.max_robot_substeps; k *= 2) {
      double worst = 0.0;
      if (trial_run(sim, steps * options.robot_fix_length, k, options, worst).empty()) {
        r.substeps = k;
        break;
      }
    }
  report.stable = why.empty();
  report.verdict = report.stable ? "stable" : "unstable: " + why;
  return report;
}

}  // namespace featherdrive
