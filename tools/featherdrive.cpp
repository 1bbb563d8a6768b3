// The `featherdrive` command: `simulate` runs a scene file and writes its trajectory, `info` shows
// a URDF robot, `compare-physx` runs a scene in featherdrive and in PhysX (compare_physx.cpp);
// `sweep`, `fit` and `view` are Python modules (python_tool.cpp).
// Exit codes: 0 success, 2 bad input (one line on stderr), 1 anything else, 130 / 143 after
// SIGINT / SIGTERM (the run stops after a whole step; simulate keeps the rows written at --out).
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>

#include "check.hpp"
#include "cli_common.hpp"
#include "compare_physx.hpp"
#include "mujoco_commands.hpp"
#include "python_tool.hpp"
#include "scene_overrides.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/io/checkpoint.hpp"
#include "featherdrive/io/describe.hpp"
#include "featherdrive/io/files.hpp"
#include "featherdrive/io/mjcf.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/trajectory.hpp"
#include "featherdrive/model/dof_position.hpp"

namespace fs = std::filesystem;
using namespace featherdrive;

namespace {

struct SimulateArgs {
  std::string scene;
  std::string out;
  std::string plot;
  SceneOverrides overrides;
  std::string save_state;
  std::string load_state;
};

void print_warnings(const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) std::cerr << "featherdrive: warning: " << w << "\n";
}

// A root mean square without overflow: the sum of squares is kept scaled by the largest
// magnitude so far (as BLAS's nrm2 does), so errors near 1e308 give their RMS, not inf.
class Rms {
 public:
  void add(double x) {
    const double a = std::abs(x);
    if (a == 0.0) return;
    if (scale_ < a) {
      sum_ = 1.0 + sum_ * (scale_ / a) * (scale_ / a);
      scale_ = a;
    } else {
      sum_ += (a / scale_) * (a / scale_);
    }
  }
  double value(long n) const { return n > 0 ? scale_ * std::sqrt(sum_ / n) : 0.0; }

 private:
  double scale_ = 0.0, sum_ = 0.0;
};

class Progress {
 public:
  explicit Progress(int steps) : steps_(steps), enabled_(steps >= 1000 && isatty(STDERR_FILENO)) {}
  void update(int step) {
    if (!enabled_) return;
    const int percent = static_cast<int>(100LL * step / steps_);
    if (percent == last_) return;
    last_ = percent;
    const int filled = percent * 40 / 100;
    std::fprintf(stderr, "\r[%s%s] %3d%%", std::string(filled, '#').c_str(),
                 std::string(40 - filled, ' ').c_str(), percent);
    std::fflush(stderr);
  }
  void done() {
    if (enabled_) std::fprintf(stderr, "\r\033[K");
  }

 private:
  int steps_;
  bool enabled_;
  int last_ = -1;
};

// Per drive over the run: the error target - position (dof_position: a spherical axis's PhysX
// position), the largest force, and the steps at each bound. A bound counts where the step's
// force reached it: the drive's max_force (within 1e-9 of it), or a nonzero limit force.
struct DriveStats {
  Rms rms;
  double max_error = 0.0, max_force = 0.0;
  long at_max_force = 0, at_velocity_limit = 0, at_position_limit = 0;
  /// The largest change of the drive force (impulse / dt) in PGS's last position iteration.
  double max_change = 0.0;

  /// A drive whose last-iteration change reached this share of its largest force has not
  /// converged.
  static constexpr double kConvergence = 1e-2;
  bool converged() const { return !(max_change > kConvergence * max_force); }

  static double force_bound(const Simulation& sim, int dof) {
    const Drive& drive = sim.drive(dof);
    return std::min(drive.max_force, drive.max_impulse / sim.options().dt);
  }

  void add(const DriveSpec& d, const Simulation& sim, double t) {
    const double error = d.target_at(t).first - dof_position(sim.model(), sim.q(), d.dof);
    rms.add(error);
    max_error = std::max(max_error, std::abs(error));
    const double force = sim.drive_force()[d.dof] + sim.actuator_force()[d.dof];
    max_force = std::max(max_force, std::abs(force));
    const double bound = force_bound(sim, d.dof);
    if (std::isfinite(bound) && std::abs(sim.drive_force()[d.dof]) >= bound * (1.0 - 1e-9))
      ++at_max_force;
    if (sim.velocity_limit_force()[d.dof] != 0.0) ++at_velocity_limit;
    if (sim.limit_force()[d.dof] != 0.0) ++at_position_limit;
    max_change = std::max(max_change,
                          std::abs(sim.last_drive_impulse_change()[d.dof]) / sim.options().dt);
  }
};

// "12.5 %" of the steps, or "-" where the joint has no such bound.
std::string share(long count, long steps, bool bounded) {
  if (!bounded) return "-";
  char text[32];
  std::snprintf(text, sizeof text, "%.1f %%", steps > 0 ? 100.0 * count / steps : 0.0);
  return text;
}

void print_drive_table(const Scene& scene, const Simulation& sim,
                       const std::vector<DriveStats>& stats, double t_end, long steps) {
  const Model& model = sim.model();
  std::printf("  per drive: errors target - position in rad (m on prismatic joints), forces in "
              "N m (N); share of steps at the bound ('-': none set)\n");
  // The driver of each row: the drive's type, or the actuator and where its law is solved (one
  // word, as the table's columns are split on spaces).
  auto driver = [](const DriveSpec& d) -> const char* {
    if (!d.actuator) return to_string(d.drive.type);
    return d.actuator->integration == ActuatorIntegration::implicit_law ? "actuator(implicit)"
                                                                         : "actuator";
  };
  int width = 12;
  for (const DriveSpec& d : scene.drives)
    width = std::max(width, static_cast<int>(std::strlen(driver(d))));
  std::printf("  %-16s %-*s %11s %11s %11s %11s %10s %10s %10s\n", "joint", width, "drive",
              "final error", "rms error", "max |error|", "max |force|", "max_force", "vel. limit",
              "pos. limit");
  std::string unconverged;
  for (size_t i = 0; i < stats.size(); ++i) {
    const DriveSpec& d = scene.drives[i];
    const DriveStats& s = stats[i];
    const double final_error = d.target_at(t_end).first - dof_position(model, sim.q(), d.dof);
    const bool limited =
        std::isfinite(sim.lower_limit(d.dof)) || std::isfinite(sim.upper_limit(d.dof));
    std::printf("  %-16s %-*s %11.3e %11.3e %11.3e %11.4g %10s %10s %10s\n", d.joint.c_str(),
                width, driver(d), final_error, s.rms.value(steps), s.max_error, s.max_force,
                share(s.at_max_force, steps, std::isfinite(DriveStats::force_bound(sim, d.dof)))
                    .c_str(),
                share(s.at_velocity_limit, steps, std::isfinite(sim.max_joint_velocity(d.dof)))
                    .c_str(),
                share(s.at_position_limit, steps, limited).c_str());
    if (!s.converged()) {
      char text[96];
      std::snprintf(text, sizeof text, " (by up to %.3g, %.2g %% of %.4g)", s.max_change,
                    100.0 * s.max_change / s.max_force, s.max_force);
      unconverged += (unconverged.empty() ? "" : ", ") + d.joint + text;
    }
  }
  if (unconverged.empty()) return;
  print_warnings({"not converged: the last of PGS's " +
                  std::to_string(sim.options().position_iterations) +
                  " position iterations still changed the drive force by more than " +
                  format_double(100.0 * DriveStats::kConvergence) + " % of its largest on " +
                  unconverged + "; raise position_iterations"});
}

int simulate(const SimulateArgs& args) {
  install_interrupt_handlers();
  if (!args.plot.empty()) check_plot_path("--plot", args.plot);
  Scene scene = args.overrides.load(args.scene);
  const Model& model = *scene.model();
  check_outputs({{"--out", args.out}, {"--plot", args.plot}, {"--save-state", args.save_state}},
                {{"the scene", args.scene},
                 {"the scene's model", scene.robot.path},
                 {"the --load-state checkpoint", args.load_state}},
                scene.robot.input_files);

  // The simulation: the scene's, or the scene's model with the state and settings of a
  // checkpoint; the command line's solver settings apply on top of either.
  Simulation sim = make_simulation(scene);
  if (!args.load_state.empty()) {
    load_checkpoint(args.load_state, sim);
    SimulationOptions o = sim.options();
    o.guard = scene.options.guard;  // the scene's: checkpoints do not keep the guard
    args.overrides.apply(o);
    sim.set_options(o);
    if (sim.step_count() + scene.steps > std::numeric_limits<int>::max())
      throw std::invalid_argument(args.load_state + ": step count " +
                                  std::to_string(sim.step_count()) + " + " +
                                  std::to_string(scene.steps) + " steps is too large");
  }
  const SimulationOptions& options = sim.options();
  const double dt = options.dt;
  const int first = static_cast<int>(sim.step_count());  // 0 unless resumed

  // The trajectory goes to a temporary file beside --out, renamed over it at the end (or at an
  // interrupt); with only a plot wanted, to a private temporary folder, as do the targets.
  std::optional<PrivateTempDir> tmp;
  std::optional<AtomicFile> out_file;
  std::optional<std::ofstream> plot_csv, targets_file;
  fs::path csv_path = args.out, targets_path;
  if (!args.plot.empty()) {
    tmp.emplace();
    targets_path = tmp->path() / "targets.csv";
    targets_file.emplace(targets_path);
    if (csv_path.empty()) {
      csv_path = tmp->path() / "trajectory.csv";
      plot_csv.emplace(csv_path);
    }
  }
  if (!args.out.empty()) {
    make_parent_folders(args.out);
    out_file.emplace(args.out, "the trajectory");
  }
  std::ostream* csv_stream = out_file ? &out_file->stream() : plot_csv ? &*plot_csv : nullptr;
  std::optional<TrajectoryWriter> csv;
  std::optional<TargetWriter> targets;
  if (csv_stream)
    csv.emplace(*csv_stream, scene.robot, target_dofs(scene), options.guard.enabled,
                sim.ground().enabled || sim.contact_options().self_collision, scene.feet);
  if (targets_file) targets.emplace(*targets_file, scene);
  // Every temporary is closed and written, or the run fails here.
  auto finish_temporaries = [&] {
    for (std::optional<std::ofstream>* f : {&plot_csv, &targets_file})
      if (*f) {
        (*f)->close();
        if (!**f) throw RunError("cannot write a temporary file in " + tmp->path().string());
      }
  };

  const size_t n = scene.drives.size();
  std::vector<DriveStats> stats(n);
  // The step's drive impulse change in PGS's last position iteration, for the convergence note.
  if (options.solver == SolverType::pgs) sim.set_track_convergence(true);
  Progress progress(scene.steps);
  const auto start = std::chrono::steady_clock::now();
  if (targets) targets->write(first, first * dt);
  // Row k: the state before step k and the targets of step k (fit reads a log so); the last row
  // gets the targets the next step would have.
  auto write_row = [&](int k, const Simulation& s) {
    if (csv) csv->write(k, s, /*initial=*/k == first && args.load_state.empty());
  };
  int last = first;  // the last whole step written
  int largest_substeps = 1;  // the step guard's largest n
  for (int k = first; k < first + scene.steps && !interrupted(); ++k) {
    apply_targets(scene, sim, k);
    write_row(k, sim);
    try {
      sim.step();
    } catch (const DivergenceError&) {  // --out keeps the steps before it, for a post-mortem
      if (out_file) out_file->commit();
      throw;
    }
    const double t = (k + 1) * dt;
    largest_substeps = std::max(largest_substeps, sim.guard_substeps());
    for (size_t i = 0; i < n; ++i) stats[i].add(scene.drives[i], sim, t);
    if (targets) targets->write(k + 1, t);
    last = k + 1;
    progress.update(k + 1 - first);
  }
  if (csv) {
    Simulation next = sim;  // the targets of the step after the last, without changing sim
    apply_targets(scene, next, last);
    write_row(last, next);
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.done();
  if (const int signal = interrupted()) {
    // The rows written so far are whole: --out keeps them; no checkpoint, no plot.
    if (out_file) out_file->commit();
    std::fflush(stdout);
    std::cerr << "featherdrive: interrupted at step " << last << " of " << first + scene.steps
              << " (signal " << signal_name(signal) << "); "
              << (out_file ? "the trajectory " + args.out + " holds steps " +
                                 std::to_string(first) + ".." + std::to_string(last)
                           : std::string("no trajectory was written"))
              << "\n";
    return 128 + signal;
  }
  finish_temporaries();
  if (out_file) out_file->commit();
  if (!args.save_state.empty()) save_checkpoint(sim, args.save_state);

  std::printf("%s: robot %s (%s), dt %.6g s, %s (%.4g s)\n", args.scene.c_str(),
              scene.robot.name.c_str(), count_of(model.nv, "dof").c_str(), dt,
              count_of(scene.steps, "step").c_str(), scene.steps * dt);
  if (!args.load_state.empty())
    std::printf("  resumed from %s at step %d\n", args.load_state.c_str(), first);
  std::printf("  solver %s: %d position / %d velocity iterations\n", to_string(options.solver),
              options.position_iterations, options.velocity_iterations);
  if (sim.ground().enabled) {
    const ContactOptions& c = sim.contact_options();
    std::printf("  ground: %s; contact offset %.6g m, rest offset %.6g m, bounce threshold "
                "%.6g m/s\n",
                describe_ground(sim.ground()).c_str(), c.contact_offset, c.rest_offset,
                c.bounce_threshold);
  }
  if (sim.contact_options().self_collision)
    std::printf("  self-collision: on (shapes on links that are not parent and child)\n");
  // Each row kind's dofs, their fields and the last step's force (Simulation::row_force).
  for (const RowKindInfo& kind : row_kinds()) {
    std::string dofs;
    for (int d = 0; d < model.nv; ++d) {
      const std::vector<double> values = sim.row_parameters(kind.name, d);
      if (!kind.active(values)) continue;
      dofs += "\n    " + model.dof_names[d] + ":";
      for (size_t j = 0; j < values.size(); ++j)
        dofs += " " + std::string(kind.fields[j].name) + " " + format_double(values[j]);
      char force[32];
      std::snprintf(force, sizeof force, "%.6g", sim.row_force(kind.name)[d]);
      dofs += std::string(", last step's force ") + force;
    }
    if (!dofs.empty()) std::printf("  %s:%s\n", std::string(kind.name).c_str(), dofs.c_str());
  }
  if (!model.shapes.empty())
    std::printf("  collision shapes (%zu):\n%s", model.shapes.size(),
                describe_shapes(model, "    ").c_str());
  if ((sim.ground().enabled || sim.contact_options().self_collision) && !scene.feet.empty()) {
    // The last step's ground force on each foot (the CSV's foot:<name> columns), and their sum
    // against the robot's weight, which a robot at rest on its feet carries.
    std::printf("  feet: the last step's ground force, world axes, N\n");
    auto vec = [](const Vec3& v) {
      char text[96];
      std::snprintf(text, sizeof text, "[%.6g, %.6g, %.6g]", v.x(), v.y(), v.z());
      return std::string(text);
    };
    Vec3 total = Vec3::Zero();
    for (const Foot& foot : scene.feet) {
      std::string links;
      for (const std::string& l : foot.link_names) links += (links.empty() ? "" : " + ") + l;
      const Vec3 f = foot_contact_force(sim, foot);
      total += f;
      std::printf("    %-12s %s (%s)\n", foot.name.c_str(), vec(f).c_str(), links.c_str());
    }
    double mass = 0.0;
    for (const Link& link : model.links) mass += link.mass;
    std::printf("    %-12s %s (the robot's weight m |g| = %.6g N)\n", "sum",
                vec(total).c_str(), mass * model.gravity.norm());
  }
  if (scene.control.substeps > 1)
    std::printf("  control step: %d physics steps, targets %s\n", scene.control.substeps,
                to_string(scene.control.targets));
  if (options.guard.enabled)
    std::printf("  step guard (max_joint_step %.6g, max_substeps %d, energy_tolerance %.6g, "
                "dissipation_share %.6g): %s redone, largest %d sub-steps, %ld exhausted\n",
                options.guard.max_joint_step, options.guard.max_substeps,
                options.guard.energy_tolerance, options.guard.dissipation_share,
                count_of(sim.guard_triggers(), "step").c_str(), largest_substeps,
                sim.guard_exhausted());
  if (n > 0) print_drive_table(scene, sim, stats, (first + scene.steps) * dt, scene.steps);
  std::printf("  wall time %.3f s, %.0f steps/s\n", wall, wall > 0.0 ? scene.steps / wall : 0.0);
  if (!args.out.empty()) std::printf("  trajectory: %s\n", args.out.c_str());
  if (!args.save_state.empty()) std::printf("  state: %s\n", args.save_state.c_str());
  if (!args.plot.empty()) {
    std::fflush(stdout);
    run_plot_script(FEATHERDRIVE_PLOT_SCRIPT, {csv_path.string(), targets_path.string()},
                    args.plot,
                    scene.robot.name + " - " + to_string(options.solver) + " (" +
                        fs::path(args.scene).filename().string() + ")",
                    *tmp);
    std::printf("  plot: %s\n", args.plot.c_str());
  }
  return 0;
}

int info(const std::string& urdf, bool floating) {
  UrdfOptions options;
  options.fixed_base = !floating;
  if (is_mjcf_file(urdf)) {  // MJCF: the robot, then what its actuators become
    const MjcfRobot robot = load_mjcf(urdf, options);
    print_warnings(robot.warnings);
    std::cout << describe(robot) << describe_actuators(robot);
    return 0;
  }
  const UrdfRobot robot = load_urdf(urdf, options);
  print_warnings(robot.warnings);
  std::cout << describe(robot);
  return 0;
}

// One line on stderr, whatever the message holds.
void report(const std::string& message) {
  std::string line = message;
  std::replace(line.begin(), line.end(), '\n', ' ');
  std::cerr << "featherdrive: " << line << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "featherdrive: articulated robots with implicit PD joint drives (PhysX-style PGS and TGS)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("featherdrive ") + FEATHERDRIVE_VERSION);

  SimulateArgs sim_args;
  CLI::App* sim_cmd = app.add_subcommand("simulate", "Run a scene file and write its trajectory");
  sim_cmd->add_option("scene", sim_args.scene, "Scene file (YAML or JSON)")->required();
  sim_cmd->add_option("--out", sim_args.out,
                      "Trajectory CSV: step,t,q:<joint>...,qd:<joint>...,f:<joint>...,"
                      "target:<joint>...,target_velocity:<joint>... (a log fit reads)");
  sim_cmd->add_option("--plot", sim_args.plot, "PNG of positions against targets and drive forces");
  sim_args.overrides.add_options(sim_cmd);
  sim_cmd->add_option("--save-state", sim_args.save_state,
                      "Write a checkpoint of the final state and settings (written atomically)");
  sim_cmd->add_option("--load-state", sim_args.load_state,
                      "Resume from a checkpoint of the scene's model: it replaces the scene's "
                      "initial state, drives, joint settings and solver options; the command "
                      "line's overrides still apply; --steps counts the steps after it");

  std::string urdf;
  bool floating = false;
  CLI::App* info_cmd =
      app.add_subcommand("info", "Show a URDF or MJCF robot: tree, dofs, masses, inertias, limits");
  info_cmd->add_option("robot", urdf, "URDF or MJCF (.xml) file")->required();
  info_cmd->add_flag("--floating", floating, "Import with a floating root instead of a fixed base");

  ComparePhysxArgs cmp_args;
  CLI::App* cmp_cmd = app.add_subcommand(
      "compare-physx",
      "Run a scene in featherdrive and in PhysX 5.6.1 (node and the harness of tests/physx, "
      "`make physx`) and show the largest differences per joint");
  cmp_cmd->add_option("scene", cmp_args.scene, "Scene file (YAML or JSON)")->required();
  cmp_cmd->add_option("--plot", cmp_args.plot, "PNG of the differences over time per joint");
  cmp_args.overrides.add_options(cmp_cmd, " (PhysX: 1 to 255)", " (PhysX: 0 to 255)");
  MujocoCommands mujoco(app);  // compare-mujoco, translate (compare_mujoco.cpp, translate.cpp)
  CheckArgs check_args;
  CLI::App* check_cmd = add_check_command(app, check_args);  // check.cpp

  add_python_tool(app, argc, argv, "sweep", "featherdrive_sweep",
                  "Map the drives' tracking error over a grid of gains (CSV and heat map)");
  add_python_tool(app, argc, argv, "fit", "featherdrive_fit",
                  "Fit drive parameters to a logged trajectory");
  add_python_tool(app, argc, argv, "view", "featherdrive_view",  // docs/viewer.md
                  "Write a self-contained HTML page that plays a run on the robot in 3D");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::string first = argc > 1 ? argv[1] : "";
    if (!first.empty() && first[0] != '-' && first != "simulate" && first != "info" &&
        first != "compare-physx" && first != "compare-mujoco" && first != "translate" &&
        first != "sweep" && first != "fit" && first != "view" && first != "check")
      report("unknown command '" + first + "' (expected simulate, info, compare-physx, "
             "compare-mujoco, translate, check, sweep, fit or view; see featherdrive --help)");
    else
      report(std::string(e.what()) + " (see featherdrive --help)");
    return 2;
  }

  try {
    if (*sim_cmd) {
      sim_args.overrides.parse();
      return simulate(sim_args);
    }
    if (*cmp_cmd) {
      cmp_args.overrides.parse();
      return compare_physx(cmp_args);
    }
    if (mujoco.selected()) return mujoco.run();
    if (*check_cmd) {
      check_args.overrides.parse();
      return check_scene_command(check_args);
    }
    return info(urdf, floating);
  } catch (const std::invalid_argument& e) {  // bad input: InputError and the core's validation
    report(e.what());
    return 2;
  } catch (const std::exception& e) {  // DivergenceError, files that cannot be written, ...
    if (const int signal = interrupted()) {  // e.g. the plot script or PhysX killed by Ctrl-C
      report(std::string("interrupted (signal ") + signal_name(signal) + "): " + e.what());
      return 128 + signal;
    }
    report(e.what());
    return 1;
  }
}
