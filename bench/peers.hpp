// The peer engines of the benchmarks, stepping the same robots with the same dt and drive gains:
// MuJoCo 2.2.2 (position actuators + joint damping) and Bullet 3.24's btMultiBody in double
// precision (explicit PD torques). docs/benchmarks.md says what each does per step.
#pragma once

#include <benchmark/benchmark.h>

#include <string>

#include "bench_models.hpp"

namespace featherdrive::bench {

enum class MujocoIntegrator { euler, implicit };

/// One mj_step per iteration.
void mujoco_step(benchmark::State& state, const BenchRobot& robot, MujocoIntegrator integrator);

/// `count` copies of the robot (MJCF as mujoco_step's, Euler), each one mj_step per iteration, on
/// `threads` threads (TBB); xml, when not empty, is the MJCF to load instead (its own actuators,
/// ctrl 0). The counter env_steps_per_second.
void mujoco_batch(benchmark::State& state, const BenchRobot& robot, const std::string& xml,
                  int count, int threads);

/// `count` copies of an MJCF (contacts as the file says), each from qpos0 with a constant ctrl,
/// one mj_step per iteration on `threads` threads, reset every kResetInterval steps.
void mujoco_batch_from(benchmark::State& state, const std::string& xml, const VecX& qpos0,
                       const VecX& ctrl, int count, int threads);

/// contact_bench.cpp: registers contact/ant/... (the standing Ant with and without its ground).
void register_contact();

/// simd_batch.cpp: registers simd_batch/<robot>/<engine>/envs:<N>/threads:<T>.
void register_simd_batch();

/// One btMultiBodyDynamicsWorld::stepSimulation per iteration, PD torques added before it.
void bullet_step(benchmark::State& state, const BenchRobot& robot);

}  // namespace featherdrive::bench
