// The peer engines of the benchmarks, stepping the same robots with the same dt and drive gains:
// MuJoCo 2.2.2 (position actuators + joint damping) and Bullet 3.24's btMultiBody in double
// precision (explicit PD torques). docs/benchmarks.md says what each does per step.
#pragma once

#include <benchmark/benchmark.h>

#include "bench_models.hpp"

namespace featherdrive::bench {

enum class MujocoIntegrator { euler, implicit };

/// One mj_step per iteration.
void mujoco_step(benchmark::State& state, const BenchRobot& robot, MujocoIntegrator integrator);

/// One btMultiBodyDynamicsWorld::stepSimulation per iteration, PD torques added before it.
void bullet_step(benchmark::State& state, const BenchRobot& robot);

}  // namespace featherdrive::bench
