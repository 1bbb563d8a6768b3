// Environment-steps per second of the SIMD Batch against the scalar Batch and MuJoCo's mj_step in
// a loop, on arm7, chain16 and MuJoCo's humanoid with its torso welded
// (examples/humanoid_hold.yaml), at 1, 8, 64 and 1024 environments on 1 and 2 threads, registered
// into featherdrive_bench (docs/simd_batch.md has the command; bench/plot_simd_batch.py the table
// and the plot). Names: simd_batch/<robot>/<engine>/envs:<N>/threads:<T>; engines batch,
// simd_<isa>, mujoco.
#include <benchmark/benchmark.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bench_models.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/sim/simd_batch.hpp"
#include "peers.hpp"

namespace featherdrive::bench {
namespace {

constexpr int kStepsPerIteration = 10;
const int kSizes[] = {1, 8, 64, 1024};
const int kThreads[] = {1, 2};

template <class B>
void run(benchmark::State& state, B& batch, const VecX& q0, int count) {
  RowMatrix q(1, q0.size());
  q.row(0) = q0.transpose();
  std::vector<int> all(static_cast<size_t>(count));
  for (int e = 0; e < count; ++e) all[static_cast<size_t>(e)] = e;
  long steps = 0;
  for (auto _ : state) {
    batch.step(kStepsPerIteration);
    if ((steps += kStepsPerIteration) % kResetInterval == 0) {
      state.PauseTiming();
      batch.reset(all, q);
      state.ResumeTiming();
    }
  }
  state.counters["env_steps_per_second"] =
      benchmark::Counter(static_cast<double>(count) * kStepsPerIteration,
                         benchmark::Counter::kIsIterationInvariantRate);
}

void scalar_batch(benchmark::State& state, const BenchRobot& robot, int count, int threads) {
  Batch batch(bench_simulation(robot), count);
  batch.set_num_threads(threads);
  run(state, batch, robot.q0, count);
}

void simd_batch(benchmark::State& state, const BenchRobot& robot, int count, int threads,
                SimdIsa isa) {
  SimdBatch batch(bench_simulation(robot), count, isa);
  batch.set_num_threads(threads);
  run(state, batch, robot.q0, count);
}

// MuJoCo's humanoid with its free joint removed (the torso welded where the file puts it).
std::string welded_humanoid_xml() {
  std::ifstream in("/usr/share/mujoco/model/humanoid/humanoid.xml");
  std::stringstream s;
  s << in.rdbuf();
  std::string xml = s.str();
  const std::string free = "<freejoint name=\"root\"/>";
  if (const auto at = xml.find(free); at != std::string::npos) xml.erase(at, free.size());
  return xml;
}

BenchRobot humanoid_hold() {
  const Scene scene = load_scene(FEATHERDRIVE_SOURCE_DIR "/examples/humanoid_hold.yaml");
  const Simulation sim = make_simulation(scene);
  BenchRobot robot;
  robot.name = "humanoid";
  robot.model = sim.model_ptr();
  robot.q0 = sim.q();
  robot.target = VecX::Zero(robot.model->nv);
  return robot;
}

}  // namespace

void register_simd_batch() {
  static std::vector<BenchRobot> robots = {make_arm7(), make_chain(16), humanoid_hold()};
  robots[1].name = "chain16";
  static const std::string humanoid_xml = welded_humanoid_xml();
  for (const BenchRobot& r : robots) {
    const BenchRobot* robot = &r;
    for (int n : kSizes)
      for (int t : kThreads) {
        const std::string tail = "/envs:" + std::to_string(n) + "/threads:" + std::to_string(t);
        const std::string name = "simd_batch/" + r.name + "/";
        benchmark::RegisterBenchmark((name + "batch" + tail).c_str(), [=](benchmark::State& s) {
          scalar_batch(s, *robot, n, t);
        })->UseRealTime();
        for (SimdIsa isa : available_simd_isas())
          benchmark::RegisterBenchmark(
              (name + "simd_" + to_string(isa) + tail).c_str(),
              [=](benchmark::State& s) { simd_batch(s, *robot, n, t, isa); })
              ->UseRealTime();
        const std::string* xml = r.name == "humanoid" ? &humanoid_xml : nullptr;
        benchmark::RegisterBenchmark((name + "mujoco" + tail).c_str(), [=](benchmark::State& s) {
          mujoco_batch(s, *robot, xml ? *xml : std::string(), n, t);
        })->UseRealTime();
      }
  }
}

}  // namespace featherdrive::bench
