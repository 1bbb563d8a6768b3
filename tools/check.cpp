#include "check.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "featherdrive/io/scene_check.hpp"

using namespace featherdrive;

namespace {

std::string number(double v, const char* format = "%.4g") {
  if (std::isnan(v)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, format, v);
  return text;
}

std::string dof_name(const JointStability& j) {
  return j.axis < 0 ? j.joint : j.joint + "[" + std::to_string(j.axis) + "]";
}

// "substeps 3 (dt 0.0033)" etc.; "none" where no value up to the search's end works.
std::string fixes(const JointStability& j, double dt, int control) {
  std::string s = "substeps ";
  s += j.substeps > 0 ? std::to_string(j.substeps) + " (dt " + number(dt / j.substeps) +
                            ", control substeps " + std::to_string(control * j.substeps) + ")"
                      : "none up to 1024";
  s += j.armature >= 0.0 ? ", armature +" + number(j.armature) : ", armature: none";
  s += j.damping >= 0.0 ? ", damping +" + number(j.damping) : ", damping: none";
  return s;
}

}  // namespace

CLI::App* add_check_command(CLI::App& app, CheckArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "check",
      "Will the scene's run stay bounded? Per joint the step map's spectral radius, a trial run "
      "of the robot, the smallest fixes; last line 'verdict: stable' or 'verdict: unstable: ...'");
  cmd->add_option("scene", args.scene, "Scene file (YAML or JSON)")->required();
  args.overrides.add_options(cmd);
  cmd->add_option("--trial-steps", args.trial_steps,
                  "Steps of the robot's trial run, 0 to " + std::to_string(kMaxTrialSteps) +
                      " (default: 2 s of the scene's time, at least 500 and at most 1000 steps); "
                      "0: no trial, the linearised step decides")
      ->type_name("INT");
  return cmd;
}

int check_scene_command(const CheckArgs& args) {
  // The scene's run length is not what check runs: refused rather than ignored.
  if (args.overrides.steps_text)
    throw std::invalid_argument("--steps = " + *args.overrides.steps_text +
                                ": check runs no scene steps; its trial's length is --trial-steps");
  StabilityCheckOptions options;
  if (args.trial_steps)
    options.min_trial_steps = options.max_trial_steps =
        integer_option("--trial-steps", *args.trial_steps, 0, kMaxTrialSteps);
  const Scene scene = args.overrides.load(args.scene);
  const StabilityReport report = check_scene(scene, options);
  const SimulationOptions& o = scene.options;
  const int control = scene.control.substeps;
  std::printf("%s: robot %s, dt %.6g s, solver %s %d/%d", args.scene.c_str(),
              scene.robot.name.c_str(), o.dt, to_string(o.solver), o.position_iterations,
              o.velocity_iterations);
  if (control > 1) std::printf(", control substeps %d", control);
  std::printf("\n  per dof at the initial state: m = 1 / (M^-1)_jj; kp dt^2/m (acceleration "
              "drives: kp dt^2); zeta = kd / (2 sqrt(kp m));\n  rho: spectral radius of the "
              "one-joint step map (a control step's: rho^%d)\n", control);
  std::printf("  %-20s %-12s %11s %11s %9s %11s  %s\n", "joint", "law", "m", "kp dt^2/m", "zeta",
              "rho", "stable");
  for (const JointStability& j : report.joints)
    std::printf("  %-20s %-12s %11s %11s %9s %11s  %s\n", dof_name(j).c_str(),
                to_string(j.law), number(j.mass).c_str(), number(j.stiffness_ratio).c_str(),
                number(j.damping_ratio, "%.3g").c_str(), number(j.rho, "%.6f").c_str(),
                j.stable ? "yes" : "no");
  const RobotStability& r = report.robot;
  std::printf("  robot: linearised step (%d revolute/prismatic dofs, at rest at the initial q): "
              "rho %s\n", r.linear_dofs, number(r.linear_rho, "%.6f").c_str());
  if (r.trial_steps > 0)
    std::printf("  robot: trial run of %d steps (%.4g s): %s (%s)\n", r.trial_steps,
                r.trial_steps * o.dt, r.trial_bounded ? "bounded" : "diverged",
                r.trial_note.c_str());
  bool any_fix = false;
  for (const JointStability& j : report.joints)
    if (!j.stable) {
      if (!any_fix) std::printf("  fixes (each alone makes the joint's map stable):\n");
      any_fix = true;
      std::printf("    %s: %s\n", dof_name(j).c_str(), fixes(j, o.dt, control).c_str());
    }
  if (!r.trial_bounded) {
    const bool joints_stable = !any_fix;
    if (joints_stable)
      std::printf("  fix for the robot: %s\n",
                  r.substeps > 0 ? ("substeps " + std::to_string(r.substeps) + " (dt " +
                                    number(o.dt / r.substeps) + ", control substeps " +
                                    std::to_string(control * r.substeps) + ") keep the trial "
                                    "bounded").c_str()
                                 : "none: the trial diverges at up to 64 substeps");
  }
  std::printf("verdict: %s\n", report.verdict.c_str());
  return 0;
}
