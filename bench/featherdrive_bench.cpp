// featherdrive's benchmarks and its peers', in one run (docs/benchmarks.md has the command, the
// machine and the results; bench/plot_benchmarks.py turns the JSON output into the tables and the
// plot). Names: step/<robot>/<engine>, kernel/<robot>/<kernel>, batch/<robot>/threads:<n>.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "bench_models.hpp"
#include "chain_prototype.hpp"
#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/solver/gauss_seidel.hpp"
#include "peers.hpp"

namespace featherdrive::bench {
namespace {

const int kChainSizes[] = {1, 4, 16, 64, 256, 1024};

void set_counters(benchmark::State& state, const Model& model) {
  state.counters["dofs"] = model.nv;
  state.counters["links"] = model.num_links();
}

// One Simulation::step per iteration, drives on every revolute joint.
void featherdrive_step(benchmark::State& state, const BenchRobot& robot, SolverType solver) {
  Simulation sim = bench_simulation(robot, solver);
  const VecX zero = VecX::Zero(robot.model->nv);
  int since_reset = 0;
  for (auto _ : state) {
    sim.step();
    if (++since_reset == kResetInterval) {
      sim.set_q(robot.q0);
      sim.set_qd(zero);
      since_reset = 0;
    }
  }
  benchmark::DoNotOptimize(sim.qd().data());
  set_counters(state, *robot.model);
}

// The chain prototype against Simulation::step from the same start: the largest difference of q,
// qd and the drive force over 10 steps, relative to the largest magnitude of each. It grows with
// the chain's length as the SIMD lanes' does (chain16 2e-15, chain256 1e-12 after one step: the
// rounding of a long chain's ill-conditioned dynamics; docs/benchmarks.md).
double prototype_difference(const BenchRobot& robot) {
  Simulation sim = bench_simulation(robot);
  ChainPrototype prototype(sim);
  double worst = 0.0;
  auto compare = [&worst](const VecView& a, const std::vector<double>& b) {
    double scale = 1e-300, diff = 0.0;
    for (int d = 0; d < a.size(); ++d) {
      scale = std::max(scale, std::abs(a[d]));
      diff = std::max(diff, std::abs(a[d] - b[static_cast<size_t>(d)]));
    }
    worst = std::max(worst, diff / scale);
  };
  for (int k = 0; k < 10; ++k) {
    sim.step();
    prototype.step();
    compare(sim.q(), prototype.q());
    compare(sim.qd(), prototype.qd());
    compare(sim.drive_force(), prototype.drive_force());
  }
  return worst;
}

// One ChainPrototype::step per iteration, as featherdrive_step; refused unless it agrees with
// Simulation::step within 1e-9.
void prototype_step(benchmark::State& state, const BenchRobot& robot) {
  const double difference = prototype_difference(robot);
  if (!(difference <= 1e-9)) {
    char text[80];
    std::snprintf(text, sizeof text, "the prototype differs from Simulation by %.3g", difference);
    state.SkipWithError(text);
    return;
  }
  Simulation sim = bench_simulation(robot);
  ChainPrototype prototype(sim);
  const std::vector<double> q0(robot.q0.data(), robot.q0.data() + robot.q0.size());
  const std::vector<double> zero(q0.size(), 0.0);
  int since_reset = 0;
  for (auto _ : state) {
    prototype.step();
    if (++since_reset == kResetInterval) {
      prototype.set_state(q0, zero);
      since_reset = 0;
    }
  }
  benchmark::DoNotOptimize(prototype.qd().data());
  state.counters["difference"] = difference;
  set_counters(state, *robot.model);
}

// A state that is not the neutral one, for the kernels.
struct KernelState {
  explicit KernelState(const BenchRobot& robot) : data(*robot.model), q(robot.q0), v(robot.target) {
    const Model& model = *robot.model;
    for (int d = 0; d < model.nv; ++d)
      if (is_driven(model, d)) q[model.links[model.dof_link[d]].q_index] = robot.target[d];
    tau = VecX::Constant(model.nv, 0.1);
    forward_kinematics(model, data, q, v);
    aba_from_kinematics(model, data, v, tau);
    articulated_response(model, data);
  }
  Data data;
  VecX q, v, tau;
};

enum class Kernel { kinematics, aba, articulated_response, sweep };

void featherdrive_kernel(benchmark::State& state, const BenchRobot& robot, Kernel kernel) {
  const Model& model = *robot.model;
  KernelState s(robot);
  SweepWorkspace ws(model);
  VecX qd = s.v;
  VecX gain = VecX::Zero(model.nv);
  for (int d = 0; d < model.nv; ++d) {
    ws.has_rows[d] = is_driven(model, d) ? 1 : 0;
    gain[d] = 0.5 / s.data.inverse_mass_diagonal[d];  // a damper taking half the velocity away
  }
  for (auto _ : state) {
    switch (kernel) {
      case Kernel::kinematics: forward_kinematics(model, s.data, s.q, s.v); break;
      case Kernel::aba: aba_from_kinematics(model, s.data, s.v, s.tau); break;
      case Kernel::articulated_response: articulated_response(model, s.data); break;
      case Kernel::sweep:
        gauss_seidel_sweep(model, s.data, ws, qd,
                           [&gain](int dof, double v) { return -gain[dof] * v; });
        break;
    }
    benchmark::ClobberMemory();
  }
  set_counters(state, model);
}

// Robot-steps per second of many independent arms sharing one Model, on `threads` cores.
void featherdrive_batch(benchmark::State& state, const BenchRobot& robot, int threads) {
  constexpr int kRobots = 64;
  constexpr int kStepsPerTask = 10;
  std::vector<std::unique_ptr<Simulation>> sims;
  for (int i = 0; i < kRobots; ++i)
    sims.push_back(std::make_unique<Simulation>(bench_simulation(robot)));
  const VecX zero = VecX::Zero(robot.model->nv);
  tbb::task_arena arena(threads);
  for (auto _ : state) {
    arena.execute([&] {
      tbb::parallel_for(0, kRobots, [&](int i) {
        Simulation& sim = *sims[static_cast<size_t>(i)];
        for (int k = 0; k < kStepsPerTask; ++k) sim.step();
        if (sim.step_count() % kResetInterval == 0) {
          sim.set_q(robot.q0);
          sim.set_qd(zero);
        }
      });
    });
  }
  state.counters["robot_steps_per_second"] = benchmark::Counter(
      static_cast<double>(kRobots * kStepsPerTask), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["threads"] = threads;
  set_counters(state, *robot.model);
}

void register_all() {
  static std::vector<BenchRobot> robots;
  for (int n : kChainSizes) robots.push_back(make_chain(n));
  robots.push_back(make_arm7());
  robots.push_back(make_humanoid());
  for (const BenchRobot& robot : robots) {
    const std::string prefix = "step/" + robot.name + "/";
    const BenchRobot* r = &robot;
    benchmark::RegisterBenchmark((prefix + "featherdrive_pgs").c_str(),
                                 [r](benchmark::State& s) { featherdrive_step(s, *r, SolverType::pgs); });
    if (robot.name.rfind("chain", 0) == 0)
      benchmark::RegisterBenchmark((prefix + "prototype_pgs").c_str(),
                                   [r](benchmark::State& s) { prototype_step(s, *r); });
    benchmark::RegisterBenchmark((prefix + "featherdrive_tgs").c_str(),
                                 [r](benchmark::State& s) { featherdrive_step(s, *r, SolverType::tgs); });
    benchmark::RegisterBenchmark((prefix + "mujoco_euler").c_str(), [r](benchmark::State& s) {
      mujoco_step(s, *r, MujocoIntegrator::euler);
    });
    benchmark::RegisterBenchmark((prefix + "mujoco_implicit").c_str(), [r](benchmark::State& s) {
      mujoco_step(s, *r, MujocoIntegrator::implicit);
    });
    benchmark::RegisterBenchmark((prefix + "bullet").c_str(),
                                 [r](benchmark::State& s) { bullet_step(s, *r); });
  }
  const std::pair<Kernel, const char*> kernels[] = {{Kernel::kinematics, "kinematics"},
                                                    {Kernel::aba, "aba"},
                                                    {Kernel::articulated_response, "articulated_response"},
                                                    {Kernel::sweep, "sweep"}};
  for (const BenchRobot& robot : robots)
    for (const auto& [kernel, name] : kernels) {
      const BenchRobot* r = &robot;
      const Kernel k = kernel;
      benchmark::RegisterBenchmark(("kernel/" + robot.name + "/" + name).c_str(),
                                   [r, k](benchmark::State& s) { featherdrive_kernel(s, *r, k); });
    }
  const BenchRobot* arm = &robots[std::size(kChainSizes)];
  std::set<int> thread_counts = {1, static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))};
  for (int threads : thread_counts)
    benchmark::RegisterBenchmark(("batch/arm7/threads:" + std::to_string(threads)).c_str(),
                                 [arm, threads](benchmark::State& s) { featherdrive_batch(s, *arm, threads); })
        ->UseRealTime();
  register_simd_batch();
  register_contact();
}

}  // namespace
}  // namespace featherdrive::bench

int main(int argc, char** argv) {
  featherdrive::bench::register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
