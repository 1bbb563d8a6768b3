// Batch's SIMD lanes against the scalar step: every environment of a lane Batch of a prototype
// against the prototype stepped alone as a Simulation (another operation order).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"

namespace featherdrive::test {

/// The random trees' options in the lane tests: dt 5 ms, 4 position and 1 velocity iterations.
inline SimulationOptions lane_test_options(SolverType solver) {
  SimulationOptions o;
  o.dt = 0.005;
  o.solver = solver;
  o.position_iterations = 4;
  o.velocity_iterations = 1;
  return o;
}

/// The largest relative difference |a - b| / max(1, |b|) of a simulation against another: q,
/// qd, the output forces, each link's contact force and the contact reports (the same points,
/// link and shape, in the same order; a count that differs: infinity).
inline double simulation_difference(const Simulation& lane, const Simulation& alone) {
  double worst = 0.0;
  auto compare = [&](const VecView& a, const VecView& b) {
    worst = std::max(worst, relative_difference(a, b));
  };
  compare(lane.q(), alone.q());
  compare(lane.qd(), alone.qd());
  compare(lane.drive_force(), alone.drive_force());
  compare(lane.limit_force(), alone.limit_force());
  compare(lane.friction_force(), alone.friction_force());
  compare(lane.velocity_limit_force(), alone.velocity_limit_force());
  for (const RowKindInfo& kind : row_kinds())
    compare(lane.row_force(kind.name), alone.row_force(kind.name));
  auto near = [&](double a, double b) {
    worst = std::max(worst, std::abs(a - b) / std::max(1.0, std::abs(b)));
  };
  auto near3 = [&](const Vec3& a, const Vec3& b) {
    for (int k = 0; k < 3; ++k) near(a[k], b[k]);
  };
  for (size_t l = 0; l < alone.link_contact_force().size(); ++l)
    near3(lane.link_contact_force()[l], alone.link_contact_force()[l]);
  const auto a = lane.contacts(), b = alone.contacts();
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < a.size(); ++k) {
    if (a[k].link != b[k].link || a[k].shape != b[k].shape || a[k].other_link != b[k].other_link)
      return std::numeric_limits<double>::infinity();
    near3(a[k].position, b[k].position);
    near3(a[k].normal, b[k].normal);
    near(a[k].separation, b[k].separation);
    near(a[k].normal_impulse, b[k].normal_impulse);
    near3(a[k].friction_impulse, b[k].friction_impulse);
  }
  return worst;
}

/// simulation_difference of a lane environment e against a Simulation stepped alone.
inline double lane_difference(const Batch& lanes, int e, const Simulation& alone) {
  return simulation_difference(lanes.sim(e), alone);
}

/// How many starts a last bit off sample the scalar step's own sensitivity (nudge_start).
inline constexpr size_t kLastBitStarts = 8;

/// Start k of kLastBitStarts a last bit (of max(1, |x|), the scale differences are measured in)
/// off: k = 0-3 every q up, down, every qd up, down; k >= 4 each entry of q and qd up or down as
/// `signs` draws.
inline void nudge_start(Simulation& s, size_t k, std::mt19937& signs) {
  const auto last_bit = [](double v) {
    return std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(v));
  };
  if (k < 4) {
    const double way = k % 2 == 0 ? 1.0 : -1.0;
    VecX x = k < 2 ? VecX(s.q()) : VecX(s.qd());
    for (double& v : x) v += way * last_bit(v);
    if (k < 2) s.set_q(x);
    else s.set_qd(x);
    return;
  }
  VecX q = s.q(), qd = s.qd();
  for (double& v : q) v += (signs() % 2 == 0 ? 1.0 : -1.0) * last_bit(v);
  for (double& v : qd) v += (signs() % 2 == 0 ? 1.0 : -1.0) * last_bit(v);
  s.set_q(q);
  s.set_qd(qd);
}

/// Issue 32's bound of the lanes against the scalar step over 1000 steps.
inline constexpr double kLaneTolerance = 1e-12;

/// Steps `count` copies of sim in lanes (asserting they do) and sim alone `steps` times, and
/// kLastBitStarts copies of sim alone started a last bit off (nudge_start); expects the largest
/// lane_difference within twice the largest nudged one, but at least kLaneTolerance and at most
/// ten times it, and prints both figures as "what: ...". The lanes are another operation order:
/// where a start's last bits move the scalar step by 7e-13 (compat physx's spherical trees), the
/// 1e-12 is the scalar step's own noise; the cap keeps the test's power where a last bit switches
/// the run to another branch (floating Atlas, PGS: 4 of 8 nudged runs 1e-2 away, the lanes
/// 1.9e-13). docs/simd_batch.md, "Against the scalar Simulation". Returns the lanes' figure.
inline double expect_lanes_as_alone(const Simulation& sim, int steps, const std::string& what,
                                    int count = 5) {
  Batch lanes(sim, count);
  EXPECT_NE(lanes.step_path().find("lanes"), std::string::npos) << what << lanes.step_path();
  Simulation alone = sim;
  std::vector<Simulation> nudged;
  std::mt19937 signs(1);
  for (size_t k = 0; k < kLastBitStarts; ++k) {
    nudged.push_back(sim);
    nudge_start(nudged.back(), k, signs);
  }
  lanes.step(steps);
  alone.step(steps);
  double worst = 0.0, own = 0.0;
  for (int e = 0; e < lanes.size(); ++e) worst = std::max(worst, lane_difference(lanes, e, alone));
  for (Simulation& s : nudged) {
    s.step(steps);
    own = std::max(own, simulation_difference(s, alone));
  }
  const double bound = std::clamp(2.0 * own, kLaneTolerance, 10.0 * kLaneTolerance);
  std::printf(
      "%s: largest relative difference %.1e, the scalar step's own from a start a last "
      "bit off %.1e, bound %.1e (docs/simd_batch.md)\n",
      what.c_str(), worst, own, bound);
  EXPECT_LE(worst, bound) << what;
  return worst;
}

/// batch_against_alone's figures: the lanes' largest lane_difference from each environment
/// stepped alone, the scalar step's own from a start changed in its last bits, and the
/// largest ratio of the two of one environment (its nudged difference taken as at least 1e-11).
/// Another operation order differs from the scalar step by the rounding of each operation, about
/// what a last-bit change of the start does; contact rows amplify either by orders of magnitude
/// (docs/simd_batch.md, "Contacts"), so each environment's ratio is bounded (kSensitivityFactor),
/// not the difference.
/// How far past an environment's own sampled sensitivity its lanes may be: the eight last-bit
/// changes sample a chaotic run's spread, they do not bound it (ratios up to 6.7 seen over the
/// contact cases of docs/simd_batch.md, "Contacts").
inline constexpr double kSensitivityFactor = 30.0;

struct LaneFigures {
  double lanes = 0.0;
  double nudged = 0.0;
  double ratio = 0.0;
};

/// Steps every environment of `lanes` (asserting it runs in lanes), a copy of each stepped alone
/// as a Simulation and eight more started a last bit off: every q, or every qd, up or down, and
/// four with each entry of q and qd up or down at random, `steps` times in `chunks` calls; returns
/// the largest differences after any call (the contacts of several steps compared), printed as
/// "what: ...". Eight, not four: where a contact switches on or off, a run's last-bit outcomes
/// fall into a few groups far apart, and four changes missed a group a third of the runs reach
/// (docs/simd_batch.md, "Contacts").
inline LaneFigures batch_against_alone(Batch& lanes, int steps, int chunks,
                                       const std::string& what) {
  EXPECT_NE(lanes.step_path().find("lanes"), std::string::npos) << what << lanes.step_path();
  const Batch& view = lanes;
  const auto n = static_cast<size_t>(lanes.size());
  std::vector<Simulation> alone, nudged;
  for (size_t e = 0; e < n; ++e) {
    alone.push_back(view.sim(static_cast<int>(e)));
    // q up, down; qd up, down: by the last bit of max(1, |x|), the scale the differences are
    // measured in (a zero's own last bit, a denormal, would change nothing).
    std::mt19937 signs(static_cast<unsigned>(e) + 1);
    for (size_t k = 0; k < kLastBitStarts; ++k) {
      nudged.push_back(alone.back());
      nudge_start(nudged.back(), k, signs);
    }
  }
  // At least 1e-11: without contacts the lanes' own order already parts from the scalar step's
  // by up to 4e-11 where a start's last bits change nothing (a compat physx tree falling 120 m).
  std::vector<double> apart(n, 0.0), own(n, 1e-11);
  for (int c = 0; c < chunks; ++c) {
    lanes.step(steps / chunks);
    for (size_t e = 0; e < n; ++e) {
      alone[e].step(steps / chunks);
      apart[e] = std::max(apart[e], lane_difference(view, static_cast<int>(e), alone[e]));
      for (size_t k = kLastBitStarts * e; k < kLastBitStarts * (e + 1); ++k) {
        nudged[k].step(steps / chunks);
        own[e] = std::max(own[e], simulation_difference(nudged[k], alone[e]));
      }
    }
  }
  LaneFigures f;
  for (size_t e = 0; e < n; ++e) {
    f.lanes = std::max(f.lanes, apart[e]);
    f.nudged = std::max(f.nudged, own[e]);
    f.ratio = std::max(f.ratio, apart[e] / own[e]);
  }
  std::printf("%s: largest relative difference %.1e, the scalar step's from a start a last bit off "
              "%.1e, largest ratio of an environment's %.2g (docs/simd_batch.md)\n",
              what.c_str(), f.lanes, f.nudged, f.ratio);
  return f;
}

/// The DivergenceError message of `steps` steps of sim (empty: none).
inline std::string divergence_of(Simulation& sim, int steps = 1) {
  try {
    sim.step(steps);
  } catch (const DivergenceError& e) {
    return e.what();
  }
  return {};
}

/// The DivergenceError message of `steps` steps of the batch (empty: none).
inline std::string divergence_of(Batch& batch, int steps) {
  try {
    batch.step(steps);
  } catch (const DivergenceError& e) {
    return e.what();
  }
  return {};
}

/// Three mimic rows on a random tree of at least 6 dofs: two rigid, one soft.
inline void set_three_mimic_rows(Simulation& sim) {
  const int nv = sim.model().nv;
  EXPECT_GE(nv, 6);
  sim.set_mimic_joints({{1, 0, -1.5, 0.05},
                        {4, 2, 0.8, -0.1},
                        {nv - 1, 3, -1.0, 0.0, /*natural_frequency=*/30.0, /*damping_ratio=*/0.7}});
}

/// give(sim, e) applied to every environment e of the batch and to a copy of the prototype per
/// environment, which are returned: the environments to step alone.
template <class Give>
std::vector<Simulation> give_each(Batch& batch, const Simulation& prototype, Give give) {
  std::vector<Simulation> alone;
  for (int e = 0; e < batch.size(); ++e) {
    give(batch.sim(e), e);
    alone.push_back(prototype);
    give(alone.back(), e);
  }
  return alone;
}

/// `steps` steps of the batch and of each environment's Simulation alone, in calls of 1 to 9
/// steps, call k's targets from command(sim, environment, k) in both.
template <class Command>
void step_with_commands(Batch& batch, std::vector<Simulation>& alone, int steps,
                        Command command) {
  for (int k = 0, done = 0; done < steps; ++k) {
    const int n = std::min(1 + k % 9, steps - done);
    for (int e = 0; e < batch.size(); ++e) {
      command(batch.sim(e), e, k);
      command(alone[static_cast<size_t>(e)], e, k);
    }
    batch.step(n);
    for (Simulation& s : alone) s.step(n);
    done += n;
  }
}

/// The largest differences of a batch's environments from their Simulations stepped alone.
struct LaneWorst {
  double state = 0.0;   ///< q, qd
  double force = 0.0;   ///< every output force, the actuators' too
  double change = 0.0;  ///< last_drive_impulse_change (convergence tracking)
};

/// The largest relative difference of every output force, the actuators' too.
inline double force_difference(const Simulation& a, const Simulation& b) {
  return std::max({relative_difference(a.drive_force(), b.drive_force()),
                   relative_difference(a.limit_force(), b.limit_force()),
                   relative_difference(a.friction_force(), b.friction_force()),
                   relative_difference(a.velocity_limit_force(), b.velocity_limit_force()),
                   relative_difference(a.actuator_force(), b.actuator_force())});
}

/// The scalar step's own spread of the output forces: `starts` stepped `steps` times with
/// step_with_commands' calls and commands, against kLastBitStarts copies of each a last bit off
/// (nudge_start); the largest force_difference at the end. Where two rows' large forces cancel
/// (a velocity limit holding a drive back), their split moves by more than q and qd do.
template <class Command>
double own_force_spread(const std::vector<Simulation>& starts, int steps, Command command) {
  std::vector<Simulation> reference = starts, nudged;
  for (size_t e = 0; e < starts.size(); ++e) {
    std::mt19937 signs(static_cast<unsigned>(e) + 1);
    for (size_t k = 0; k < kLastBitStarts; ++k) {
      nudged.push_back(starts[e]);
      nudge_start(nudged.back(), k, signs);
    }
  }
  for (int k = 0, done = 0; done < steps; ++k) {
    const int n = std::min(1 + k % 9, steps - done);
    for (size_t e = 0; e < starts.size(); ++e) {
      command(reference[e], static_cast<int>(e), k);
      reference[e].step(n);
      for (size_t j = kLastBitStarts * e; j < kLastBitStarts * (e + 1); ++j) {
        command(nudged[j], static_cast<int>(e), k);
        nudged[j].step(n);
      }
    }
    done += n;
  }
  double spread = 0.0;
  for (size_t j = 0; j < nudged.size(); ++j)
    spread = std::max(spread, force_difference(nudged[j], reference[j / kLastBitStarts]));
  return spread;
}

/// Environment e of the batch against `alone` (its settings, stepped alone): q, qd, every output
/// force and the tracked drive changes into `worst` (|a - b| / max(1, |b|)); the clock and the
/// delay and actuator histories (what a checkpoint of sim(e) writes) exactly.
inline void compare_with_alone(const Batch& batch, int e, const Simulation& alone,
                               LaneWorst& worst, const std::string& what) {
  const Simulation& s = batch.sim(e);
  worst.state = std::max({worst.state, relative_difference(s.q(), alone.q()),
                          relative_difference(s.qd(), alone.qd())});
  worst.force = std::max(worst.force, force_difference(s, alone));
  worst.change = std::max(worst.change, relative_difference(s.last_drive_impulse_change(),
                                                            alone.last_drive_impulse_change()));
  // relative_difference passes NaN over: every compared value must be finite.
  ASSERT_TRUE(s.q().allFinite() && s.qd().allFinite() && s.actuator_force().allFinite() &&
              s.last_drive_impulse_change().allFinite())
      << what << " env " << e;
  ASSERT_EQ(s.step_count(), alone.step_count()) << what << " env " << e;
  ASSERT_EQ(s.track_convergence(), alone.track_convergence()) << what << " env " << e;
  for (int d = 0; d < s.model().nv; ++d) {
    ASSERT_EQ(s.drive_delays().pushes(d), alone.drive_delays().pushes(d)) << what << " dof " << d;
    if (alone.drive_delays().delayed(d))
      for (size_t k = 0; k < alone.drive_delays().ring(d).size(); ++k) {
        EXPECT_EQ(s.drive_delays().ring(d)[k].position, alone.drive_delays().ring(d)[k].position);
        EXPECT_EQ(s.drive_delays().ring(d)[k].velocity, alone.drive_delays().ring(d)[k].velocity);
      }
    ASSERT_EQ(s.actuators().pushes(d), alone.actuators().pushes(d)) << what << " dof " << d;
    if (alone.has_actuator(d))  // the commands as set: the same bits
      for (size_t k = 0; k < alone.actuators().ring(d).size(); ++k) {
        EXPECT_EQ(s.actuators().ring(d)[k].position, alone.actuators().ring(d)[k].position);
        EXPECT_EQ(s.actuators().ring(d)[k].effort, alone.actuators().ring(d)[k].effort);
      }
  }
}

}  // namespace featherdrive::test
