// Environment-steps per second of Batch through the SIMD lanes at each width against Batch with
// lanes off (a vector of Simulations) and MuJoCo's mj_step in a loop, on arm7, chain16 and MuJoCo's humanoid with its torso welded
// (examples/humanoid_hold.yaml), at 1, 8, 64 and 1024 environments on 1 and 2 threads, registered
// into featherdrive_bench (docs/simd_batch.md has the command; bench/plot_simd_batch.py the table
// and the plot). Names: simd_batch/<robot>/<engine>/envs:<N>/threads:<T>; engines batch (lanes
// off), simd_<isa> (lanes of that width, Batch::set_isa), mujoco.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bench_models.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/batch.hpp"
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
  batch.set_lanes(false);  // a vector of Simulations
  run(state, batch, robot.q0, count);
}

// A robot as loaded from its URDF: its joint limits, friction and velocity limits on, force
// drives of kStiffness / kDamping with the URDF's efforts (where > 0) as max_force, targets 0.3
// rad from q0 alternating in sign; fixed_base false gives its root a floating joint (no ground:
// it falls, and the benchmark's resets bring it back).
Simulation as_loaded(const std::string& urdf, bool fixed_base = true) {
  UrdfOptions options;
  options.fixed_base = fixed_base;
  const UrdfRobot robot = load_urdf(urdf, options);
  SimulationOptions o;
  o.dt = kDt;
  Simulation sim(robot.model, o);
  for (const Link& link : robot.model->links) {
    if (link.joint_type != JointType::revolute && link.joint_type != JointType::prismatic) continue;
    const int d = link.v_index;
    const double effort = robot.model->effort_limit[d];
    sim.set_drive(d, Drive{DriveType::force, kStiffness, kDamping,
                           effort > 0.0 ? effort : std::numeric_limits<double>::infinity(),
                           d % 2 ? 0.3 : -0.3, 0.0});
  }
  return sim;
}

// One Simulation stepping alone, and Batch(sim, N) as it comes (lanes when the settings allow;
// FEATHERDRIVE_SIMD picks the width), on robots as loaded. Names:
// batch_as_loaded/<robot>/<simulation|batch>/envs:<N>/threads:<T>.
void as_loaded_simulation(benchmark::State& state, const Simulation& prototype) {
  Simulation sim = prototype;
  const VecX q0 = sim.q();
  long steps = 0;
  for (auto _ : state) {
    sim.step(kStepsPerIteration);
    if ((steps += kStepsPerIteration) % kResetInterval == 0) {
      state.PauseTiming();
      sim.set_q(q0);
      sim.set_qd(VecX::Zero(sim.model().nv));
      state.ResumeTiming();
    }
  }
  state.counters["env_steps_per_second"] = benchmark::Counter(
      kStepsPerIteration, benchmark::Counter::kIsIterationInvariantRate);
}

void as_loaded_batch(benchmark::State& state, const Simulation& prototype, int count,
                     int threads) {
  Batch batch(prototype, count);
  batch.set_num_threads(threads);
  state.SetLabel(batch.step_path());
  run(state, batch, prototype.q(), count);
}

// Batch(sim, N) against one Simulation in turns (batch_as_loaded/<robot>/paired/...): each
// iteration times kStepsPerIteration batch steps, then as many times N / 8 steps of the
// Simulation (each turn some milliseconds), so that this VM's slowdowns (+-25 % over seconds)
// fall on both alike. `ratio` is the batch's
// environment-steps per second over the Simulation's, both summed over the same run.
void as_loaded_paired(benchmark::State& state, const Simulation& prototype, int count,
                      int threads) {
  using Clock = std::chrono::steady_clock;
  Batch batch(prototype, count);
  batch.set_num_threads(threads);
  state.SetLabel(batch.step_path());
  Simulation sim = prototype;
  const VecX q0 = prototype.q();
  RowMatrix q(1, q0.size());
  q.row(0) = q0.transpose();
  std::vector<int> all(static_cast<size_t>(count));
  for (int e = 0; e < count; ++e) all[static_cast<size_t>(e)] = e;
  const int batch_steps = kStepsPerIteration;
  const int sim_chunk = std::max(1, count / 8);  // the Simulation's steps per batch step
  double batch_seconds = 0.0, sim_seconds = 0.0;
  long batch_env_steps = 0, sim_env_steps = 0;
  for (auto _ : state) {
    const Clock::time_point t0 = Clock::now();
    batch.step(batch_steps);
    const double b = std::chrono::duration<double>(Clock::now() - t0).count();
    double m = 0.0;
    for (int c = 0; c < batch_steps; ++c) {
      const Clock::time_point t1 = Clock::now();
      sim.step(sim_chunk);
      m += std::chrono::duration<double>(Clock::now() - t1).count();
      // Each restarts every kResetInterval of its own steps, untimed.
      if ((sim_env_steps + sim_chunk) / kResetInterval != sim_env_steps / kResetInterval) {
        sim.set_q(q0);
        sim.set_qd(VecX::Zero(sim.model().nv));
      }
      sim_env_steps += sim_chunk;
    }
    const long before = batch_env_steps / count;
    batch_env_steps += static_cast<long>(count) * batch_steps;
    if ((batch_env_steps / count) / kResetInterval != before / kResetInterval) batch.reset(all, q);
    batch_seconds += b;
    sim_seconds += m;
    state.SetIterationTime(b + m);
  }
  const double batch_rate = static_cast<double>(batch_env_steps) / batch_seconds;
  const double sim_rate = static_cast<double>(sim_env_steps) / sim_seconds;
  state.counters["batch_env_steps_per_second"] = batch_rate;
  state.counters["simulation_env_steps_per_second"] = sim_rate;
  state.counters["ratio"] = batch_rate / sim_rate;
}

// Lane groups (docs/simd_batch.md, "Lane groups"): 1024 arm7 as loaded with gravity of their
// own (one group), half of them at another dt (two groups), or one under the step guard (one
// group and one Simulation); `scalar` the same batch with lanes off, as every such batch stepped
// before groups. Names: batch_groups/arm7/<case>/<lanes|scalar>/envs:1024/threads:1.
void grouped_batch(benchmark::State& state, const Simulation& prototype, const std::string& kind,
                   bool lanes) {
  const int count = 1024;
  Batch batch(prototype, count);
  batch.set_num_threads(1);
  batch.set_lanes(lanes);
  if (kind == "gravity") {
    RowMatrix g(count, 3);
    for (int e = 0; e < count; ++e) g.row(e) << 0.01 * (e % 7), 0.0, -9.0 - 0.002 * e;
    std::vector<int> all(static_cast<size_t>(count));
    for (int e = 0; e < count; ++e) all[static_cast<size_t>(e)] = e;
    batch.set_gravity(all, g);
  } else if (kind == "two_dt") {
    SimulationOptions o = prototype.options();
    o.dt *= 0.5;
    for (int e = 0; e < count; e += 2) batch.sim(e).set_options(o);
  } else if (kind == "one_guarded") {
    SimulationOptions o = prototype.options();
    o.guard.enabled = true;
    batch.sim(5).set_options(o);
  }
  state.SetLabel(batch.step_path());
  run(state, batch, prototype.q(), count);
}

void lanes_batch(benchmark::State& state, const BenchRobot& robot, int count, int threads,
                 SimdIsa isa) {
  Batch batch(bench_simulation(robot), count);
  batch.set_isa(isa);
  batch.set_num_threads(threads);
  const std::string path = batch.step_path();
  if (path != std::string(to_string(isa)) + " lanes") return state.SkipWithError(path.c_str());
  run(state, batch, robot.q0, count);
}

// Small lane groups (docs/simd_batch.md, "One-lane blocks"): `count` environments as one group in
// one-lane blocks (FEATHERDRIVE_SIMD=one while it runs) or in SSE2 blocks of two vectors
// (set_isa), and Batch(sim, 1) as it comes against the Simulation stepped alone. Names:
// lane_small_groups/<robot>/<one_lane|sse2>/envs:<N>/threads:1,
// lane_one/<robot>/<simulation|batch>/envs:1/threads:1.
void small_group(benchmark::State& state, const Simulation& prototype, int count, bool one_lane) {
  const char* was = std::getenv("FEATHERDRIVE_SIMD");
  const std::string before = was ? was : "";
  if (one_lane) setenv("FEATHERDRIVE_SIMD", "one", 1);
  {
    Batch batch(prototype, count);
    batch.set_num_threads(1);
    if (!one_lane) batch.set_isa(SimdIsa::sse2);
    const std::string path = batch.step_path();
    state.SetLabel(path);
    if (one_lane != (path.find("at one lane") != std::string::npos))
      state.SkipWithError(path.c_str());
    else
      run(state, batch, prototype.q(), count);
  }
  if (!was) unsetenv("FEATHERDRIVE_SIMD");
  else setenv("FEATHERDRIVE_SIMD", before.c_str(), 1);
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
  const std::string dart = "/usr/share/doc/dart/data/urdf/";
  static const std::vector<std::pair<std::string, Simulation>> loaded = {
      {"arm7", as_loaded(FEATHERDRIVE_SOURCE_DIR "/examples/arm7.urdf")},
      {"kr5", as_loaded(dart + "KR5/KR5 sixx R650.urdf")},
      {"wam", as_loaded(dart + "wam/wam.urdf")},
      {"atlas_floating",
       as_loaded("/usr/share/doc/dart/data/sdf/atlas/atlas_v3_no_head.urdf", false)}};
  for (const auto& [name, sim] : loaded) {
    const Simulation* prototype = &sim;
    benchmark::RegisterBenchmark(("batch_as_loaded/" + name + "/simulation").c_str(),
                                 [=](benchmark::State& s) { as_loaded_simulation(s, *prototype); })
        ->UseRealTime();
    for (int t : kThreads)
      benchmark::RegisterBenchmark(
          ("batch_as_loaded/" + name + "/batch/envs:1024/threads:" + std::to_string(t)).c_str(),
          [=](benchmark::State& s) { as_loaded_batch(s, *prototype, 1024, t); })
          ->UseRealTime();
    benchmark::RegisterBenchmark(
        ("batch_as_loaded/" + name + "/paired/envs:1024/threads:2").c_str(),
        [=](benchmark::State& s) { as_loaded_paired(s, *prototype, 1024, 2); })
        ->UseManualTime();
  }
  for (const char* kind : {"gravity", "two_dt", "one_guarded"})
    for (const bool lanes : {true, false}) {
      const Simulation* prototype = &loaded.front().second;
      const std::string k = kind;
      benchmark::RegisterBenchmark(("batch_groups/arm7/" + k + (lanes ? "/lanes" : "/scalar") +
                                    "/envs:1024/threads:1")
                                       .c_str(),
                                   [=](benchmark::State& s) { grouped_batch(s, *prototype, k, lanes); })
          ->UseRealTime();
    }
  static const std::vector<std::pair<std::string, Simulation>> small = {
      loaded.front(), {"chain16", bench_simulation(make_chain(16))},
      {"chain256", bench_simulation(make_chain(256))}};
  for (const auto& [name, sim] : small) {
    const Simulation* prototype = &sim;
    for (int n = 1; n <= 4 && name != "chain256"; ++n)
      for (const bool one : {true, false})
        benchmark::RegisterBenchmark(
            ("lane_small_groups/" + name + (one ? "/one_lane" : "/sse2") + "/envs:" +
             std::to_string(n) + "/threads:1")
                .c_str(),
            [=](benchmark::State& s) { small_group(s, *prototype, n, one); })
            ->UseRealTime();
    benchmark::RegisterBenchmark(("lane_one/" + name + "/simulation/envs:1/threads:1").c_str(),
                                 [=](benchmark::State& s) { as_loaded_simulation(s, *prototype); })
        ->UseRealTime();
    benchmark::RegisterBenchmark(("lane_one/" + name + "/batch/envs:1/threads:1").c_str(),
                                 [=](benchmark::State& s) { as_loaded_batch(s, *prototype, 1, 1); })
        ->UseRealTime();
  }
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
              [=](benchmark::State& s) { lanes_batch(s, *robot, n, t, isa); })
              ->UseRealTime();
        const std::string* xml = r.name == "humanoid" ? &humanoid_xml : nullptr;
        benchmark::RegisterBenchmark((name + "mujoco" + tail).c_str(), [=](benchmark::State& s) {
          mujoco_batch(s, *robot, xml ? *xml : std::string(), n, t);
        })->UseRealTime();
      }
  }
}

}  // namespace featherdrive::bench
