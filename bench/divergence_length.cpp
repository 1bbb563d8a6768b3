// Where long chains diverge (docs/benchmarks.md): for each solver and number of physics steps per
// frame, the shortest benchmark chain (bench_models.hpp, make_chain) whose run diverges within a
// fixed time. Not a test: a measurement, printed as a table.
//   featherdrive_divergence_length [MAX_LINKS] [SECONDS] [GAIN] [-v]   defaults 1024, 10, 1000
//
// The run: the chain released from horizontal (joint 1, about y, at pi/2) under gravity with the
// benchmark's drives (1000 Nm/rad, 50 Nms/rad) towards its fixed random targets, frames of 1/60 s
// of k physics steps each (step_control, targets held), PGS and TGS with 4 position and 1 velocity
// iterations. It diverges if a step throws DivergenceError or the energy of a frame (kinetic +
// gravity + the drives' springs, 1/2 kp (q - target)^2) exceeds the initial one by more than
// GAIN times n m g (n l) / 2 (the chain's weight times its length): a passive system (constant
// targets, damped drives) cannot gain energy. Runs that diverge grow exponentially (10^6 to
// 10^58 times that within 10 s), stable ones stay below about 1, so the bound barely matters.
// -v prints every run. Doubling from 2 links, then bisection (assumes a longer chain is no
// more stable; the scan's runs in -v show where that fails).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_models.hpp"
#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/sim/control_step.hpp"

using namespace featherdrive;
using namespace featherdrive::bench;

namespace {

constexpr double kFrame = 1.0 / 60.0;
double kEnergyGain = 1000.0;  // GAIN

double energy(const Simulation& sim, Data& data, const VecX& target) {
  const Model& model = sim.model();
  forward_kinematics(model, data, sim.q(), sim.qd());
  double springs = 0.0;
  for (int d = 0; d < model.nv; ++d) {
    const double e = sim.q()[d] - target[d];
    springs += 0.5 * kStiffness * e * e;
  }
  return kinetic_energy(model, data, sim.qd()) + potential_energy(model, data) + springs;
}

struct Outcome {
  bool diverged = false;
  std::string why;
  double worst_gain = 0.0;  ///< the largest (E - E0) / scale seen
};

bool verbose = false;

Outcome run(int links, SolverType solver, int substeps, double seconds) {
  const BenchRobot robot = make_chain(links);
  SimulationOptions options;
  options.dt = kFrame / substeps;
  options.solver = solver;
  options.position_iterations = 4;
  options.velocity_iterations = 1;
  Simulation sim(robot.model, options);
  add_drives(sim, robot);
  VecX q = robot.q0;
  q[0] = std::numbers::pi / 2;  // the whole chain horizontal
  sim.set_q(q);
  Data data(*robot.model);
  const double e0 = energy(sim, data, robot.target);
  // The potential range: the chain's weight times its length (a drop of at most n l).
  const double scale = links * 1.0 * 9.81 * links * 0.5;
  const VecX velocity = VecX::Zero(robot.model->nv);
  const ControlStep control{substeps, TargetInterpolation::hold};
  const int frames = static_cast<int>(std::lround(seconds / kFrame));
  Outcome outcome;
  for (int f = 0; f < frames && !outcome.diverged; ++f) {
    try {
      step_control(sim, robot.target, velocity, control);
    } catch (const DivergenceError&) {
      outcome = {true, "DivergenceError at frame " + std::to_string(f), outcome.worst_gain};
      break;
    }
    const double gain = (energy(sim, data, robot.target) - e0) / scale;
    outcome.worst_gain = std::max(outcome.worst_gain, std::isnan(gain) ? INFINITY : gain);
    if (!(gain <= kEnergyGain))
      outcome = {true, "energy gain " + std::to_string(gain) + " x n m g n l / 2 at frame " +
                           std::to_string(f), outcome.worst_gain};
  }
  if (verbose)
    std::printf("  %s k=%d n=%d: %s, largest gain %.3g\n", to_string(solver), substeps, links,
                outcome.diverged ? outcome.why.c_str() : "stable", outcome.worst_gain);
  return outcome;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const int max_links = argc > 1 ? std::stoi(argv[1]) : 1024;
    const double seconds = argc > 2 ? std::stod(argv[2]) : 10.0;
    if (argc > 3) kEnergyGain = std::stod(argv[3]);
    verbose = argc > 4 && std::string(argv[4]) == "-v";
    std::printf("| solver | physics steps per frame (dt) | shortest diverging chain | how |\n");
    std::printf("|---|---|---|---|\n");
    for (SolverType solver : {SolverType::pgs, SolverType::tgs})
      for (int k : {1, 2, 4, 8}) {
        // Doubling from 2 links, then bisection between the last stable and the first diverging.
        int stable = 1, diverging = -1;
        Outcome outcome;
        for (int n = 2; n <= max_links; n *= 2) {
          outcome = run(n, solver, k, seconds);
          if (outcome.diverged) {
            diverging = n;
            break;
          }
          stable = n;
        }
        if (diverging > 0)
          while (diverging - stable > 1) {
            const int mid = (stable + diverging) / 2;
            const Outcome o = run(mid, solver, k, seconds);
            if (o.diverged)
              diverging = mid, outcome = o;
            else
              stable = mid;
          }
        const std::string length =
            diverging > 0 ? std::to_string(diverging) : "none up to " + std::to_string(max_links);
        std::printf("| %s | %d (%.4g ms) | %s | %s |\n", to_string(solver), k, 1e3 * kFrame / k,
                    length.c_str(), diverging > 0 ? outcome.why.c_str() : "");
        std::fflush(stdout);
      }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "featherdrive_divergence_length: %s\n", e.what());
    return 2;
  }
}
