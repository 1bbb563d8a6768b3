// A fixed number of steps of one benchmark robot, for profilers: the same instructions on every
// run, which Google Benchmark's timed loops cannot give (docs/benchmarks.md, "Where the
// instructions go").
//   featherdrive_profile ROBOT [pgs|tgs|prototype] [STEPS]   ROBOT: chainN, arm7 or humanoid
// (prototype: bench/chain_prototype.hpp, chains only).
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "bench_models.hpp"
#include "chain_prototype.hpp"

using namespace featherdrive;
using namespace featherdrive::bench;

int main(int argc, char** argv) {
  try {
    if (argc < 2)
      throw std::invalid_argument("usage: featherdrive_profile ROBOT [pgs|tgs|prototype] [STEPS]");
    const std::string name = argv[1];
    const std::string solver = argc > 2 ? argv[2] : "pgs";
    const int steps = argc > 3 ? std::stoi(argv[3]) : 200;
    BenchRobot robot;
    if (name == "arm7") robot = make_arm7();
    else if (name == "humanoid") robot = make_humanoid();
    else if (name.rfind("chain", 0) == 0) robot = make_chain(std::stoi(name.substr(5)));
    else throw std::invalid_argument("unknown robot " + name);
    if (solver != "pgs" && solver != "tgs" && solver != "prototype")
      throw std::invalid_argument("solver must be pgs, tgs or prototype");
    Simulation sim = bench_simulation(robot, solver == "tgs" ? SolverType::tgs : SolverType::pgs);
    if (solver == "prototype") {
      ChainPrototype prototype(sim);
      for (int k = 0; k < steps; ++k) prototype.step();
      std::printf("%s prototype: %d steps, %d dofs, q[0] = %.17g\n", name.c_str(), steps,
                  robot.model->nv, prototype.q()[0]);
      return 0;
    }
    sim.step(steps);
    std::printf("%s %s: %d steps, %d dofs, q[0] = %.17g\n", name.c_str(), solver.c_str(), steps,
                robot.model->nv, sim.q()[0]);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "featherdrive_profile: %s\n", e.what());
    return 2;
  }
}
