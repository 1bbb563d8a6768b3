// featherdrive's benchmarks and its peers', in one run (docs/benchmarks.md has the command, the
// machine and the results; bench/plot_benchmarks.py turns the JSON output into the tables and the
// plot). Names: step/<robot>/<engine>, kernel/<robot>/<kernel>, batch/<robot>/threads:<n>.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <map>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "bench_models.hpp"
#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/solver/gauss_seidel.hpp"
#include "peers.hpp"

namespace featherdrive::bench {
namespace {

const int kChainSizes[] = {1, 4, 16, 64, 256, 1024};

SimulationOptions options_for(SolverType solver) {
  SimulationOptions o;
  o.dt = kDt;
  o.solver = solver;
  o.position_iterations = 4;
  o.velocity_iterations = 1;
  return o;
}

void set_counters(benchmark::State& state, const Model& model) {
  state.counters["dofs"] = model.nv;
  state.counters["links"] = model.num_links();
}

// One Simulation::step per iteration, drives on every revolute joint.
void featherdrive_step(benchmark::State& state, const BenchRobot& robot, SolverType solver) {
  Simulation sim(robot.model, options_for(solver));
  add_drives(sim, robot);
  const VecX zero = VecX::Zero(robot.model->nv);
  sim.set_q(robot.q0);
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
  for (int i = 0; i < kRobots; ++i) {
    sims.push_back(std::make_unique<Simulation>(robot.model, options_for(SolverType::pgs)));
    add_drives(*sims.back(), robot);
    sims.back()->set_q(robot.q0);
  }
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
