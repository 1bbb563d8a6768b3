// `make run`: a small arm falling under gravity, with a one-screen summary.
#include <cstdio>

#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/simulation.hpp"

using namespace featherdrive;

int main() {
  ModelBuilder b;
  b.add_link(make_link("base", "", 2.0, Vec3::Zero(), Mat3::Identity() * 0.01, fixed_joint("fix")));
  const char* names[] = {"shoulder", "elbow", "wrist"};
  std::string parent = "base";
  for (int i = 0; i < 3; ++i) {
    LinkSpec l = make_link(std::string(names[i]) + "_link", parent, 1.0 - 0.25 * i,
                           Vec3(0.15, 0, 0), Vec3(1e-3, 8e-3, 8e-3).asDiagonal(),
                           revolute_joint(names[i], Vec3::UnitY(),
                                          i == 0 ? Vec3(0, 0, 0.1) : Vec3(0.3, 0, 0)));
    b.add_link(l);
    parent = l.name;
  }
  auto model = std::make_shared<const Model>(b.build());
  SimulationOptions options;
  options.dt = 1.0 / 240.0;
  Simulation sim(model, options);
  std::printf("featherdrive demo: a 3-link arm falling under gravity (dt = 1/240 s)\n\n");
  std::printf("%8s %12s %12s %12s\n", "t [s]", "shoulder", "elbow", "wrist");
  for (int k = 0; k <= 240; ++k) {
    if (k % 24 == 0)
      std::printf("%8.3f %12.5f %12.5f %12.5f\n", sim.time(), sim.q()[0], sim.q()[1], sim.q()[2]);
    if (k < 240) sim.step();
  }
  std::printf("\n%d links, %d dofs, %ld steps simulated.\n", model->num_links(), model->nv,
              sim.step_count());
  return 0;
}
