// The step guard on the ground (docs/math/step_guard.md, eq. G-3a, G-3b): a redone step reports the
// contacts of its sub-steps and keeps their anchors, and the rows' work (eq. G-3a) is in the
// guard's energy test, so that landings and penetrating starts stay finite and bounded.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/contact_models.hpp"
#include "support/lane_contact_models.hpp"

namespace featherdrive {
namespace {

double total_mass(const Model& model) {
  double m = 0.0;
  for (const Link& link : model.links) m += link.mass;
  return m;
}

// Kinetic + gravity energy of the simulation's state (algorithm/energy.hpp).
double energy(const Simulation& s) {
  Data data(s.model());
  forward_kinematics(s.model(), data, s.q(), s.qd());
  return kinetic_energy(s.model(), data, s.qd()) + potential_energy(s.model(), data);
}

double vertical_contact_force(const Simulation& s) {
  double f = 0.0;
  for (const Vec3& l : s.link_contact_force()) f += l.z();
  return f;
}

// The quadruped dropped 0.2 m with a tight joint bound: the guard redoes its landing. Its vertical
// momentum is zero at the start and (settled) at the end, so the ground's impulse over the run,
// redone steps included, is the weight's: sum F_z dt = m g T. At rest every step's reports carry
// m g dt and the link forces m g.
TEST(GuardContact, RedoneLandingReportsTheGroundsImpulse) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs})
    for (int most : {8, 64}) {
      Simulation s = test::quadruped_simulation(solver, 0.2);
      SimulationOptions o = s.options();
      o.guard.enabled = true;
      o.guard.max_joint_step = 0.01;
      o.guard.max_substeps = most;
      s.set_options(o);
      const double weight = total_mass(s.model()) * test::kContactGravity;
      const double dt = o.dt;
      const std::string what =
          std::string(to_string(solver)) + ", max_substeps " + std::to_string(most);
      const int steps = 400;
      double impulse = 0.0;
      long redone_in_contact = 0;
      for (int k = 0; k < steps; ++k) {
        s.step();
        impulse += vertical_contact_force(s) * dt;
        if (s.guard_substeps() > 1 && !s.contacts().empty()) {
          ++redone_in_contact;
          EXPECT_GT(vertical_contact_force(s), 0.0) << what << " step " << k;
        }
      }
      EXPECT_GT(redone_in_contact, 0) << what;
      EXPECT_NEAR(impulse, weight * steps * dt, 1e-4 * weight * steps * dt) << what;
      double most_off = 0.0;
      for (int k = 0; k < 50; ++k) {
        s.step();
        double normal = 0.0;
        for (const ContactReport& c : s.contacts()) normal += c.normal_impulse * c.normal.z();
        most_off = std::max({most_off, std::abs(normal / (weight * dt) - 1.0),
                             std::abs(vertical_contact_force(s) / weight - 1.0)});
      }
      EXPECT_LE(most_off, 1e-9) << what;
      std::printf("%s: %ld redone steps in contact, impulse / (m g T) - 1 = %.1e, at rest %.1e\n",
                  what.c_str(), redone_in_contact, impulse / (weight * steps * dt) - 1.0,
                  most_off);
    }
}

// A tree half sunk into the ground (its root box's centre on it), guarded with up to 8 and 64
// sub-steps: no step diverges (before eq. G-3a, G-3b PGS reached NaN at the first step with 64).
// Its energy is not bounded yet: the push-out throws it, unguarded too (PGS 24 m, TGS 2.4 m;
// guarded 16 m and 3 m; docs/math/step_guard.md, "The sub-step law").

TEST(GuardContact, HalfSunkTreeStaysBounded) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs})
    for (int most : {8, 64}) {
      Simulation s = test::grounded_tree(4, solver, false);
      SimulationOptions o = s.options();
      o.guard.enabled = true;
      o.guard.max_joint_step = 0.05;
      o.guard.max_substeps = most;
      s.set_options(o);
      VecX q = s.q();
      q[2] = 0.0;
      s.set_q(q);
      s.set_qd(VecX::Zero(s.model().nv));
      const double start = energy(s);
      const std::string what =
          std::string(to_string(solver)) + ", max_substeps " + std::to_string(most);
      for (int k = 0; k < 300; ++k) ASSERT_NO_THROW(s.step()) << what << " step " << k;
      EXPECT_TRUE(s.q().allFinite() && s.qd().allFinite()) << what;
      EXPECT_GT(s.guard_triggers(), 0) << what;
      std::printf("%s: %ld steps redone, energy %.3g J from %.3g J, root at %.3g m\n", what.c_str(),
                  s.guard_triggers(), energy(s), start, s.q()[2]);
    }
}

}  // namespace
}  // namespace featherdrive
