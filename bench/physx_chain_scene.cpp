// The benchmark chain of issue 35's stability table as a scene of the PhysX harness
// (tests/physx/README.md), for bench/physx_chain_divergence.js (docs/benchmarks.md, "Where long
// chains diverge"): make_chain(N) with gravity off, the benchmark drives towards its fixed random
// targets, dt 1/60, 4 position and 1 velocity iterations, from rest at q = 0.
//   featherdrive_physx_chain_scene N pgs|tgs STEPS > chainN.json
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "bench_models.hpp"
#include "featherdrive/io/physx_scene.hpp"

using namespace featherdrive;
using namespace featherdrive::bench;

int main(int argc, char** argv) {
  try {
    if (argc != 4) throw std::invalid_argument("usage: N pgs|tgs STEPS");
    const int n = std::stoi(argv[1]);
    const std::string solver = argv[2];
    if (solver != "pgs" && solver != "tgs")
      throw std::invalid_argument("solver '" + solver + "' must be pgs or tgs");
    BenchRobot robot = make_chain(n);
    auto model = std::make_shared<Model>(*robot.model);
    model->gravity.setZero();
    robot.model = model;
    SimulationOptions options;
    options.dt = 1.0 / 60.0;
    options.solver = solver == "pgs" ? SolverType::pgs : SolverType::tgs;
    options.position_iterations = 4;
    options.velocity_iterations = 1;
    Simulation sim(robot.model, options);
    add_drives(sim, robot);
    sim.set_q(robot.q0);
    std::cout << physx_scene_json(sim, std::stoi(argv[3]));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "featherdrive_physx_chain_scene: %s\n", e.what());
    return 2;
  }
}
