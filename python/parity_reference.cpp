// The C++ side of python/tests/test_parity.py: a fixed scenario on a URDF robot stepped from C++,
// then q, qd, drive_force and limit_force printed one vector a line as hex floats (%a), which
// Python's float.hex() reproduces exactly.
//
//   python_parity_reference ROBOT.urdf pgs|tgs STEPS
//
// The scenario (the test sets the same one up through the Python module): dt = 1/60, 4 position
// and 1 velocity iterations; dof d starts at q = 0.1 (d + 1), qd = -0.05 d, and has a force drive
// with stiffness 1000 (d + 1), damping 50 + 10 d, target position 0.5 - 0.1 d, target velocity 0.2.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace {

void print(const char* name, const featherdrive::VecX& x) {
  std::printf("%s", name);
  for (Eigen::Index i = 0; i < x.size(); ++i) std::printf(" %a", x[i]);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace featherdrive;
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s ROBOT.urdf pgs|tgs STEPS\n", argv[0]);
    return 2;
  }
  try {
    const UrdfRobot robot = load_urdf(argv[1]);
    SimulationOptions options;
    options.dt = 1.0 / 60.0;
    options.solver = std::string(argv[2]) == "tgs" ? SolverType::tgs : SolverType::pgs;
    options.position_iterations = 4;
    options.velocity_iterations = 1;
    Simulation sim(robot.model, options);
    const Model& model = sim.model();
    VecX q = sim.q(), qd = VecX::Zero(model.nv);
    for (int d = 0; d < model.nv; ++d) {
      q[model.links[model.dof_link[d]].q_index] = 0.1 * (d + 1);
      qd[d] = -0.05 * d;
      Drive drive;
      drive.type = DriveType::force;
      drive.stiffness = 1000.0 * (d + 1);
      drive.damping = 50.0 + 10.0 * d;
      drive.target_position = 0.5 - 0.1 * d;
      drive.target_velocity = 0.2;
      sim.set_drive(model.links[model.dof_link[d]].joint_name, drive);
    }
    sim.set_q(q);
    sim.set_qd(qd);
    sim.step(std::atoi(argv[3]));
    print("q", sim.q());
    print("qd", sim.qd());
    print("drive_force", sim.drive_force());
    print("limit_force", sim.limit_force());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "python_parity_reference: %s\n", e.what());
    return 1;
  }
  return 0;
}
