// The cost of ground contact (issue 34; docs/benchmarks.md, "Ground contact"): the standing Ant
// of examples/ant_standing.yaml, one Simulation step with its ground against the same step with
// the ground off (it then falls; every engine restarts every kResetInterval steps), and Batches
// of Ants on 1 and 2 threads beside MuJoCo 2.2.2's mj_step on the exported MJCF (its ground and
// shapes as geoms, contacts on, the drives' position actuators at their constant ctrl, PGS's
// timestep: one mj_step per step). Names: contact/ant/<engine>[/envs:<N>/threads:<T>].
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "featherdrive/io/mjcf_export.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/sim/batch.hpp"
#include "featherdrive/sim/gain_translation.hpp"
#include "peers.hpp"

namespace featherdrive::bench {
namespace {

constexpr int kStepsPerIteration = 10;

Simulation ant(SolverType solver, bool ground) {
  Scene scene = load_scene(FEATHERDRIVE_SOURCE_DIR "/examples/ant_standing.yaml");
  scene.options.solver = solver;
  scene.ground.enabled = ground;
  return make_simulation(scene);
}

void single(benchmark::State& state, SolverType solver, bool ground) {
  Simulation sim = ant(solver, ground);
  const VecX q0 = sim.q(), qd0 = sim.qd();
  int since_reset = 0;
  for (auto _ : state) {
    sim.step();
    if (++since_reset == kResetInterval) {
      sim.set_q(q0);
      sim.set_qd(qd0);
      since_reset = 0;
    }
  }
  benchmark::DoNotOptimize(sim.qd().data());
  state.counters["contacts"] = static_cast<double>(sim.contacts().size());
}

void batch(benchmark::State& state, SolverType solver, int count, int threads) {
  const Simulation prototype = ant(solver, true);
  Batch b(prototype, count);
  b.set_num_threads(threads);
  RowMatrix q(1, prototype.q().size());
  q.row(0) = prototype.q().transpose();
  std::vector<int> all(static_cast<size_t>(count));
  for (int e = 0; e < count; ++e) all[static_cast<size_t>(e)] = e;
  long steps = 0;
  for (auto _ : state) {
    b.step(kStepsPerIteration);
    if ((steps += kStepsPerIteration) % kResetInterval == 0) {
      state.PauseTiming();
      b.reset(all, q);
      state.ResumeTiming();
    }
  }
  state.counters["env_steps_per_second"] = benchmark::Counter(
      static_cast<double>(count) * kStepsPerIteration, benchmark::Counter::kIsIterationInvariantRate);
}

void mujoco(benchmark::State& state, int count, int threads) {
  const Simulation sim = ant(SolverType::pgs, true);
  const MjcfExport mjcf = export_mjcf(sim);
  int actuators = 0;
  for (const MjcfDrive& d : mjcf.drives) actuators += d.velocity_actuator >= 0 ? 2 : 1;
  VecX ctrl = VecX::Zero(actuators);
  for (const MjcfDrive& d : mjcf.drives) {
    const Drive& drive = sim.drive(d.dof);
    const auto [position, velocity] = mujoco_ctrl(d.mujoco, drive.target_position,
                                                  drive.target_velocity, sim.options().dt, 1);
    ctrl[d.position_actuator] = position;
    if (d.velocity_actuator >= 0) ctrl[d.velocity_actuator] = velocity;
  }
  mujoco_batch_from(state, mjcf.xml, sim.q(), ctrl, count, threads);
}

}  // namespace

void register_contact() {
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs})
    for (const bool ground : {true, false}) {
      const std::string name = std::string("contact/ant/featherdrive_") + to_string(solver) +
                               (ground ? "/ground" : "/no_ground");
      benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& s) {
        single(s, solver, ground);
      });
    }
  for (const int n : {1, 1024})
    for (const int t : {1, 2}) {
      const std::string tail = "/envs:" + std::to_string(n) + "/threads:" + std::to_string(t);
      for (const SolverType solver : {SolverType::pgs, SolverType::tgs})
        benchmark::RegisterBenchmark(
            (std::string("contact/ant/batch_") + to_string(solver) + tail).c_str(),
            [=](benchmark::State& s) { batch(s, solver, n, t); })
            ->UseRealTime();
      benchmark::RegisterBenchmark(("contact/ant/mujoco" + tail).c_str(),
                                   [=](benchmark::State& s) { mujoco(s, n, t); })
          ->UseRealTime();
    }
}

}  // namespace featherdrive::bench
