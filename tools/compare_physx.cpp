#include "compare_physx.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <stdexcept>

#include "cli_common.hpp"
#include "compare_table.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/io/physx_runner.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/trajectory.hpp"

namespace fs = std::filesystem;
using namespace featherdrive;

namespace {

// PhysX stores iteration counts in 8 bits (setSolverIterationCounts).
void check_physx_iterations(const ComparePhysxArgs& args, const SimulationOptions& o) {
  auto check = [&](int value, bool from_cli, const char* option, const char* key, int lowest) {
    if (value >= lowest && value <= 255) return;
    std::string m = from_cli ? std::string(option) : args.scene + ": " + key;
    m += " = " + std::to_string(value) + ": PhysX allows " + std::to_string(lowest) + " to 255";
    throw std::invalid_argument(m);
  };
  check(o.position_iterations, args.overrides.position_iterations.has_value(),
        "--position-iterations", "solver.position_iterations", 1);
  check(o.velocity_iterations, args.overrides.velocity_iterations.has_value(),
        "--velocity-iterations", "solver.velocity_iterations", 0);
}

}  // namespace

int compare_physx(const ComparePhysxArgs& args) {
  install_interrupt_handlers();
  if (!args.plot.empty()) check_plot_path("--plot", args.plot);
  Scene scene = args.overrides.load(args.scene);
  check_physx_iterations(args, scene.options);
  const Model& model = *scene.model();
  check_outputs({{"--plot", args.plot}},
                {{"the scene", args.scene}, {"the scene's model", scene.robot.path}},
                scene.robot.input_files);

  Simulation sim = make_simulation(scene);
  // The harness cannot set PhysX's static/dynamic/viscous friction (URDF <dynamics> gives the
  // arm some): both sides run without it, and the output says so.
  std::string friction_off, kinds_off;
  for (int d = 0; d < model.nv; ++d) {  // a spherical joint's axes by their dof names
    if (sim.joint_friction(d).active()) {
      sim.set_joint_friction(d, JointFriction{});
      friction_off += " " + model.dof_names[d];
    }
    if (clear_row_kinds(sim, d)) kinds_off += " " + model.dof_names[d];
  }

  // The targets of every step as the harness takes them (entry k before step k + 1), from the
  // scene's own rule on a copy.
  std::vector<TargetsByJoint> targets;
  {
    bool any_sine = false;
    for (const DriveSpec& d : scene.drives) any_sine = any_sine || d.sine.has_value();
    Simulation copy = sim;
    for (int k = 0; any_sine && k < scene.steps && !interrupted(); ++k) {
      apply_targets(scene, copy, k);
      TargetsByJoint& t = targets.emplace_back();
      for (const DriveSpec& d : scene.drives)
        if (d.sine)
          t[d.joint] = {copy.drive(d.dof).target_position, copy.drive(d.dof).target_velocity};
    }
  }
  // The joint forces of every step where the scene varies them (applied_force with a sine).
  std::vector<ForcesByJoint> forces;
  for (const AppliedForceSpec& f : scene.applied_forces)
    for (int k = 0; f.sine && k < scene.steps; ++k) {
      if (forces.size() <= static_cast<size_t>(k)) forces.emplace_back();
      forces[static_cast<size_t>(k)][f.joint] = f.at(k * scene.options.dt);
    }
  try {
    (void)physx_scene_json(sim, 0);  // what PhysX cannot represent is the input's fault
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(args.scene + ": " + e.what());
  }

  const PhysxInstall physx =
      find_physx({FEATHERDRIVE_PHYSX_BUILD_DIR, FEATHERDRIVE_PHYSX_SOURCE_DIR});

  JointTrajectory fd = empty_trajectory(model);
  fd.contact_links = physx_contact_links(sim);
  {
    Simulation run = sim;
    append_state(fd, run);
    for (double& f : fd.f[0]) f = 0.0;  // row 0: no step has run (the harness's convention)
    for (int k = 0; k < scene.steps && !interrupted(); ++k) {
      apply_targets(scene, run, k);
      run.step();
      append_state(fd, run);
    }
  }
  if (const int signal = interrupted()) {
    std::cerr << "featherdrive: interrupted at step " << fd.rows() - 1 << " of " << scene.steps
              << " of featherdrive's run (signal " << signal_name(signal)
              << "); nothing was compared\n";
    return 128 + signal;
  }
  JointTrajectory px;
  try {
    px = run_physx(physx, sim, scene.steps, targets, forces);
  } catch (const PhysxError& e) {
    if (e.harness_exit == 2)  // the harness refused a value of the exported scene
      throw std::invalid_argument(args.scene + ": PhysX refused the scene: " + e.what());
    throw;
  }
  const TrajectoryComparison c = compare_trajectories(fd, px);

  const SimulationOptions& o = sim.options();
  std::printf("%s: robot %s (%s), dt %.6g s, %s (%.4g s), solver %s %d/%d\n",
              args.scene.c_str(), scene.robot.name.c_str(), count_of(model.nv, "dof").c_str(),
              o.dt, count_of(scene.steps, "step").c_str(), scene.steps * o.dt,
              to_string(o.solver), o.position_iterations, o.velocity_iterations);
  std::printf("  featherdrive (float64) against PhysX 5.6.1 (float32, %s)\n",
              physx.dir.string().c_str());
  if (!friction_off.empty())
    std::printf("  joint friction off on both sides (PhysX's cannot be set):%s\n",
                friction_off.c_str());
  if (!kinds_off.empty())
    std::printf("  joint springs off on both sides (PhysX has none):%s\n", kinds_off.c_str());
  if (model.floating_base()) std::printf("  the floating root's pose is not compared\n");
  print_difference_table(c, "PhysX");
  if (!px.contact_links.empty()) {
    // PhysX's bindings report normal impulses only (tests/physx/README.md, "Contact forces").
    const ContactComparison cc = compare_contact_forces(fd, px, sim.ground().normal);
    std::printf("  the ground's normal force per link (PhysX reports no friction): largest "
                "|featherdrive - PhysX|, at step; relative: / PhysX's largest, %.4g N\n",
                cc.scale);
    for (const auto& [link, d] : cc.links)
      std::printf("  %-16s %10.2e %5zu %9.1e\n", link.c_str(), d.value, d.row,
                  cc.scale > 0.0 ? d.value / cc.scale
                  : d.value > 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
  }

  if (!args.plot.empty()) {
    std::fflush(stdout);
    const PrivateTempDir tmp;
    const fs::path csv = tmp.path() / "physx-diff.csv";
    write_differences(csv, fd, px);
    std::string title = scene.robot.name;
    title += ": featherdrive - PhysX, ";
    title += to_string(o.solver);
    title += " (";
    title += fs::path(args.scene).filename().string();
    title += ")";
    run_plot_script(FEATHERDRIVE_PHYSX_PLOT_SCRIPT, {csv.string()}, args.plot, title, tmp);
    std::printf("  plot: %s\n", args.plot.c_str());
  }
  return 0;
}
