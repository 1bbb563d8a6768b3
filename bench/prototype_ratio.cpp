// Simulation::step against the chain prototype (chain_prototype.hpp) on the benchmark chain, in
// alternating windows of a few hundred steps: each pair of windows is timed within milliseconds
// of each other, so the ratio survives the VM's drift in speed, which single benchmark runs do not
// (docs/benchmarks.md, "The single step and its prototype").
//   featherdrive_prototype_ratio [N] [ROUNDS]     N: chain length (256), ROUNDS: pairs (41)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_models.hpp"
#include "chain_prototype.hpp"

using namespace featherdrive;
using namespace featherdrive::bench;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const int n = argc > 1 ? std::stoi(argv[1]) : 256;
    const int rounds = argc > 2 ? std::stoi(argv[2]) : 41;
    if (n < 1 || rounds < 1) throw std::invalid_argument("N and ROUNDS must be >= 1");
    const BenchRobot robot = make_chain(n);
    Simulation sim = bench_simulation(robot);
    ChainPrototype prototype(sim);
    const int window = std::max(1, 100000 / n);  // steps per window: about 5 ms
    const VecX zero = VecX::Zero(robot.model->nv);
    const std::vector<double> q0(robot.q0.data(), robot.q0.data() + robot.q0.size());
    const std::vector<double> zeros(q0.size(), 0.0);
    using Clock = std::chrono::steady_clock;
    std::vector<double> ours, theirs, ratio;
    for (int r = -1; r < rounds; ++r) {  // round -1 warms up
      sim.set_q(robot.q0);
      sim.set_qd(zero);
      prototype.set_state(q0, zeros);
      const auto t0 = Clock::now();
      for (int k = 0; k < window; ++k) sim.step();
      const auto t1 = Clock::now();
      for (int k = 0; k < window; ++k) prototype.step();
      const auto t2 = Clock::now();
      if (r < 0) continue;
      const double a = std::chrono::duration<double, std::micro>(t1 - t0).count() / window;
      const double b = std::chrono::duration<double, std::micro>(t2 - t1).count() / window;
      ours.push_back(a);
      theirs.push_back(b);
      ratio.push_back(a / b);
    }
    std::printf(
        "chain%d, %d rounds of %d steps each: Simulation::step %.2f us (%.4f us per dof), "
        "prototype %.2f us (%.4f us per dof), ratio %.3f (medians; ratio range %.3f-%.3f)\n",
        n, rounds, window, median(ours), median(ours) / n, median(theirs), median(theirs) / n,
        median(ratio), *std::min_element(ratio.begin(), ratio.end()),
        *std::max_element(ratio.begin(), ratio.end()));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "featherdrive_prototype_ratio: %s\n", e.what());
    return 2;
  }
}
