// The step guard on the benchmark chain (docs/benchmarks.md, "Where long chains diverge"; issue
// 35): make_chain(n) (axes cycling y, z, x, 1 kg, 0.5 m) with the benchmark's drives (1000 Nm/rad,
// 50 Nms/rad towards its random targets in +-0.5 rad), gravity off, from rest at q = 0, dt 1/60 s,
// 4 position and 1 velocity iterations, STEPS steps. Per solver and n, four ways of stepping:
// unguarded, guarded (options.guard on, its defaults), guarded with tests (i) and (ii) alone
// (dissipation_share 100 leaves test (iii) no say), 8 fixed sub-steps per step (step_control,
// substeps 8, targets held), and a reference for the tracking: TGS 4/1 at dt / 32 (32 sub-steps,
// targets held). Not a test: a measurement, printed as a table.
//   featherdrive_guard_chain [STEPS] [N ...]   defaults 10000, 2 4 8 16 32 48 64 96 128 192 256
//
// Diverged: DivergenceError, or the energy (kinetic + the drives' springs 1/2 kp (q - target)^2)
// above its initial value by more than 1000 n m g (n l) / 2, divergence_length.cpp's bound (the
// system is passive: it cannot gain energy). Tracking: the RMS of q - target at the end. Cost:
// wall time per step of the whole run (one core), where the run stayed bounded.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench_models.hpp"
#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/sim/control_step.hpp"

using namespace featherdrive;
using namespace featherdrive::bench;

namespace {

enum class Mode { unguarded, guarded, tests12, substeps8, reference };

struct Outcome {
  bool diverged = false;
  long steps = 0;    ///< steps made (to the divergence)
  double rms = NAN;  ///< final RMS of q - target
  double us_per_step = 0.0;
  long triggers = 0, exhausted = 0;
  int largest_n = 1;
};

double energy(const Simulation& sim, Data& data, const VecX& target) {
  const Model& model = sim.model();
  forward_kinematics(model, data, sim.q(), sim.qd());
  const double springs = 0.5 * kStiffness * (sim.q() - target).squaredNorm();
  return kinetic_energy(model, data, sim.qd()) + potential_energy(model, data) + springs;
}

Outcome run(int links, SolverType solver, Mode mode, long steps) {
  const BenchRobot robot = make_chain(links);
  auto model = std::make_shared<Model>(*robot.model);
  model->gravity.setZero();
  SimulationOptions options;
  options.dt = 1.0 / 60.0;
  options.solver = mode == Mode::reference ? SolverType::tgs : solver;
  options.position_iterations = 4;
  options.velocity_iterations = 1;
  options.guard.enabled = mode == Mode::guarded || mode == Mode::tests12;
  if (mode == Mode::tests12) options.guard.dissipation_share = 100.0;
  const int k = mode == Mode::substeps8 ? 8 : mode == Mode::reference ? 32 : 1;
  if (k > 1) options.dt /= k;
  Simulation sim(model, options);
  add_drives(sim, robot);
  Data data(*model);
  const double e0 = energy(sim, data, robot.target);
  const double bound = 1000.0 * links * 1.0 * 9.81 * links * 0.5;
  const VecX zero = VecX::Zero(model->nv);
  const ControlStep control{k, TargetInterpolation::hold};
  Outcome out;
  const auto start = std::chrono::steady_clock::now();
  for (long s = 0; s < steps; ++s) {
    try {
      if (k > 1)
        step_control(sim, robot.target, zero, control);
      else
        sim.step();
    } catch (const DivergenceError&) {
      out.diverged = true;
      break;
    }
    ++out.steps;
    if (options.guard.enabled) out.largest_n = std::max(out.largest_n, sim.guard_substeps());
    if (s % 100 == 99 || s == steps - 1) {  // the energy test every 100 steps and at the end
      const double e = energy(sim, data, robot.target);
      if (!(e - e0 <= bound)) {
        out.diverged = true;
        break;
      }
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.us_per_step = 1e6 * seconds / std::max(1L, out.steps);
  out.rms = std::sqrt((sim.q() - robot.target).squaredNorm() / model->nv);
  out.triggers = sim.guard_triggers();
  out.exhausted = sim.guard_exhausted();
  return out;
}

std::string cell(const Outcome& o, bool guard = false) {
  char buf[160];
  if (o.diverged)
    std::snprintf(buf, sizeof buf, "diverged at step %ld", o.steps + 1);
  else
    std::snprintf(buf, sizeof buf, "RMS %.1e, %.3g us", o.rms, o.us_per_step);
  std::string s = buf;
  if (guard) {
    std::snprintf(buf, sizeof buf, "; %ld redone (%ld exh.), n <= %d", o.triggers, o.exhausted,
                  o.largest_n);
    s += buf;
  }
  return s;
}

std::string ratio(const Outcome& a, const Outcome& b) {
  if (a.diverged || b.diverged) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", a.us_per_step / b.us_per_step);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  const long steps = argc > 1 ? std::stol(argv[1]) : 10000;
  std::vector<int> sizes;
  for (int i = 2; i < argc; ++i) sizes.push_back(std::stoi(argv[i]));
  if (sizes.empty()) sizes = {2, 4, 8, 16, 32, 48, 64, 96, 128, 192, 256};
  std::printf(
      "| solver | N | unguarded | guarded (defaults) | guarded, tests (i) and (ii) alone | "
      "8 fixed sub-steps | reference, TGS at dt / 32 | cost guarded / unguarded, / 8 "
      "sub-steps |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  std::vector<Outcome> reference(sizes.size());
  for (SolverType solver : {SolverType::pgs, SolverType::tgs})
    for (size_t i = 0; i < sizes.size(); ++i) {
      const int n = sizes[i];
      const Outcome u = run(n, solver, Mode::unguarded, steps);
      const Outcome g = run(n, solver, Mode::guarded, steps);
      const Outcome t = run(n, solver, Mode::tests12, steps);
      const Outcome f = run(n, solver, Mode::substeps8, steps);
      // The reference does not depend on the solver compared: once per N.
      if (solver == SolverType::pgs) reference[i] = run(n, solver, Mode::reference, steps);
      const Outcome& r = reference[i];
      std::printf("| %s 4/1 | %d | %s | %s | %s | %s | %s | %s, %s |\n", to_string(solver), n,
                  cell(u).c_str(), cell(g, true).c_str(), cell(t, true).c_str(), cell(f).c_str(),
                  cell(r).c_str(), ratio(g, u).c_str(), ratio(g, f).c_str());
      std::fflush(stdout);
    }
  return 0;
}
