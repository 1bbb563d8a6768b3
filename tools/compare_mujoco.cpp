#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "compare_table.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/io/mjcf_export.hpp"
#include "featherdrive/io/physx_runner.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/model/dof_position.hpp"
#include "mujoco_commands.hpp"

namespace fs = std::filesystem;
using namespace featherdrive;

namespace {

MujocoIntegrator integrator_of(const std::string& name) {
  return name == "implicit" ? MujocoIntegrator::implicit : MujocoIntegrator::euler;
}

// One row per state of each engine: position (dof_position), qd and drive force of each column.
void append_row(JointTrajectory& out, const Model& model, double t, const VecX& q, const VecX& qd,
                const VecX& f) {
  out.t.push_back(t);
  auto& rq = out.q.emplace_back();
  auto& rqd = out.qd.emplace_back();
  auto& rf = out.f.emplace_back();
  for (const std::string& joint : out.joints) {  // 1-dof joints and spherical axes
    const int dof = model.dof_index(joint);
    rq.push_back(dof_position(model, q, dof));
    rqd.push_back(qd[dof]);
    rf.push_back(f[dof]);
  }
}

struct Compared {
  JointTrajectory fd, mj;
  TrajectoryComparison c;
  MjcfExport mjcf;
  int diverged_at = -1;  ///< the first step where MuJoCo diverged (and reset), or -1
};

// Runs the scene from `start` in both engines with the drives mapped as `mapping` says. A MuJoCo
// run that diverges keeps its rows up to there, and the comparison says inf.
Compared run_both(const Scene& scene, const Simulation& start, DriveMapping mapping,
                  MujocoIntegrator integrator) {
  MjcfExportOptions options;
  options.drives = mapping;
  options.integrator = integrator;
  Compared out;
  out.mjcf = export_mjcf(start, options);
  MujocoRun mj(out.mjcf);
  Simulation sim = start;
  mj.set_state(sim.q(), sim.qd());
  const Model& model = sim.model();
  out.fd = empty_trajectory(model);
  out.mj = empty_trajectory(model);
  const VecX zero = VecX::Zero(model.nv);
  append_row(out.fd, model, 0.0, sim.q(), sim.qd(), zero);
  append_row(out.mj, model, 0.0, mj.q(), mj.qd(), zero);
  for (int k = 0; k < scene.steps && !interrupted(); ++k) {
    apply_targets(scene, sim, k);
    mj.step(sim);  // the targets sim holds for this step
    sim.step();
    append_row(out.fd, model, sim.time(), sim.q(), sim.qd(),
               sim.drive_force() + sim.actuator_force());
    append_row(out.mj, model, sim.time(), mj.q(), mj.qd(), mj.drive_force());
    if (mj.diverged() && out.diverged_at < 0) out.diverged_at = k + 1;
  }
  // After MuJoCo diverges (and resets its state) the differences mean nothing: only the rows
  // before the diverging step are compared.
  if (out.diverged_at >= 0) {
    const auto keep = static_cast<size_t>(out.diverged_at);
    for (JointTrajectory* t : {&out.fd, &out.mj}) {
      t->t.resize(keep);
      t->q.resize(keep);
      t->qd.resize(keep);
      t->f.resize(keep);
    }
  }
  out.c = compare_trajectories(out.fd, out.mj);
  return out;
}

// A translated joint agrees with MuJoCo when its largest q difference is within this share of
// the run's scale (the largest |q| of MuJoCo's run; docs/mujoco_bridge.md, "Verdicts").
constexpr double kAgreement = 1e-6;

// Per drive, what the translated run shows: "exact" only where the 1-dof map is exact and the
// measured run agrees; else the difference and the likeliest reason.
std::vector<std::string> verdicts(const Compared& r, const Simulation& start) {
  std::vector<std::string> out;
  const SimulationOptions& o = start.options();
  for (const MjcfDrive& d : r.mjcf.drives) {
    if (r.diverged_at >= 0) {
      out.push_back("diverged at step " + std::to_string(r.diverged_at));
      continue;
    }
    const auto joint = static_cast<size_t>(
        std::find(r.fd.joints.begin(), r.fd.joints.end(), d.joint) - r.fd.joints.begin());
    double q_difference = 0.0;
    for (const JointDifference& j : r.c.joints)
      if (j.joint == d.joint) q_difference = j.q.value;
    const double relative = r.c.scale_q > 0.0 ? q_difference / r.c.scale_q
                            : q_difference > 0.0 ? std::numeric_limits<double>::infinity()
                                                 : 0.0;
    char figure[64];
    std::snprintf(figure, sizeof figure, "differs by %.2g of the scale", relative);
    if (relative <= kAgreement) {
      out.push_back(d.translation.exact ? "exact (1-dof map and run)"
                                        : "agrees in the run; 1-dof map: " + d.translation.note);
      continue;
    }
    // The drive's largest force: max_force, or max_impulse per step.
    const Drive& drive = start.drive(d.dof);
    const double limit = std::min(drive.max_force, drive.max_impulse / o.dt);
    // Saturated: featherdrive's drive reached its limit, or MuJoCo's force passed it (its
    // forcerange clips the actuator; the damping adds beyond).
    bool saturated = false;
    if (joint < r.fd.joints.size() && std::isfinite(limit))
      for (size_t k = 0; k < r.fd.rows(); ++k)
        saturated = saturated || std::abs(r.fd.f[k][joint]) >= limit * (1 - 1e-9) ||
                    std::abs(r.mj.f[k][joint]) > limit;
    std::string why;
    if (saturated)
      why = "max_force saturates (MuJoCo's forcerange clips the actuator, not the joint damping "
            "that carries the implicit share)";
    else if (start.model().nv > 1)
      why = "coupled joints (the 1-dof map sees one joint; " + std::string(to_string(o.solver)) +
            " " + std::to_string(o.position_iterations) + "/" +
            std::to_string(o.velocity_iterations) + " iterations)";
    else
      why = d.translation.exact ? "the run departs from the 1-dof map" : d.translation.note;
    out.push_back(std::string(figure) + ": " + why);
  }
  return out;
}

void print_drives(const MjcfExport& e, DriveMapping mapping, double dt,
                  const std::vector<std::string>& verdict) {
  std::printf("  %s drives: MuJoCo timestep %.6g s (%d per step), integrator %s\n",
              to_string(mapping), e.timestep, e.substeps, to_string(e.integrator));
  std::printf("  %-16s %10s %11s %11s %11s %11s  %s\n", "joint", "m", "kp dt^2/m", "kp", "kv",
              "damping", mapping == DriveMapping::translated ? "verdict (q difference / scale)" : "");
  for (size_t k = 0; k < e.drives.size(); ++k) {
    const MjcfDrive& d = e.drives[k];
    const MujocoDrive& mj = d.mujoco;
    std::string match;
    if (mapping == DriveMapping::translated && k < verdict.size()) match = verdict[k];
    std::printf("  %-16s %10.4g %11.4g %11.4g %11.4g %11.4g  %s\n", d.joint.c_str(),
                d.effective_inertia, mj.kp * dt * dt / d.effective_inertia, mj.kp, mj.kv,
                mj.damping, match.c_str());
  }
}

}  // namespace

int compare_mujoco(const CompareMujocoArgs& args) {
  install_interrupt_handlers();
  if (!args.plot.empty()) check_plot_path("--plot", args.plot);
  if (args.translate_only && args.literal_only)
    throw std::invalid_argument("--translate and --literal: choose one (or neither for both)");
  Scene scene = args.overrides.load(args.scene);
  const Model& model = *scene.model();
  check_outputs({{"--plot", args.plot}},
                {{"the scene", args.scene}, {"the scene's model", scene.robot.path}},
                scene.robot.input_files);
  if (model.floating_base())
    throw std::invalid_argument(args.scene +
                                ": fixed_base = false: compare-mujoco compares "
                                "fixed-base robots (MuJoCo's free joint has other velocities)");
  for (const Link& l : model.links)
    if (l.joint_type == JointType::spherical)
      throw std::invalid_argument(
          args.scene + ": joint '" + l.joint_name +
          "' is spherical: compare-mujoco compares revolute and prismatic joints (MuJoCo's ball "
          "joint takes no actuator per axis and its qpos is a quaternion)");
  Simulation start = make_simulation(scene);
  // MuJoCo's frictionloss is another law and it has no joint velocity limits: both sides run
  // without them, and the output says so.
  std::string friction_off, velocity_limits_off, kinds_off;
  for (const Link& l : model.links) {
    if (l.nv != 1) continue;
    if (clear_row_kinds(start, l.v_index)) kinds_off += " " + l.joint_name;
    if (start.joint_friction(l.v_index).active() || start.friction_coefficient(l.v_index) > 0.0) {
      start.set_joint_friction(l.v_index, JointFriction{});
      start.set_friction_coefficient(l.v_index, 0.0);
      friction_off += " " + l.joint_name;
    }
    if (std::isfinite(start.max_joint_velocity(l.v_index))) {
      start.set_max_joint_velocity(l.v_index, std::numeric_limits<double>::infinity());
      velocity_limits_off += " " + l.joint_name;
    }
  }
  const MujocoIntegrator integrator = integrator_of(args.integrator);
  std::vector<DriveMapping> mappings;
  if (!args.literal_only) mappings.push_back(DriveMapping::translated);
  if (!args.translate_only) mappings.push_back(DriveMapping::literal);

  std::vector<Compared> runs;
  for (DriveMapping mapping : mappings) {
    try {
      runs.push_back(run_both(scene, start, mapping, integrator));
    } catch (const InputError& e) {  // what MuJoCo cannot take is the scene's fault
      throw std::invalid_argument(args.scene + ": " + e.what());
    }
    if (const int signal = interrupted()) {
      std::cerr << "featherdrive: interrupted (signal " << signal_name(signal)
                << "); nothing was compared\n";
      return 128 + signal;
    }
  }

  const SimulationOptions& o = scene.options;
  std::printf("%s: robot %s (%s), dt %.6g s, %s (%.4g s), solver %s %d/%d\n",
              args.scene.c_str(), scene.robot.name.c_str(), count_of(model.nv, "dof").c_str(),
              o.dt, count_of(scene.steps, "step").c_str(), scene.steps * o.dt,
              to_string(o.solver), o.position_iterations, o.velocity_iterations);
  const bool ground = start.ground().enabled && !model.shapes.empty();
  const bool self = start.contact_options().self_collision && model.shapes.size() > 1;
  std::printf("  featherdrive against MuJoCo %s (exported MJCF, %s, integrator %s)\n",
              mujoco_version().c_str(),
              ground && self ? "contacts with the ground and between shapes on"
              : ground       ? "contacts with the ground on"
              : self         ? "contacts between shapes on"
                             : "contacts off",
              to_string(integrator));
  if (!friction_off.empty())
    std::printf("  joint friction off on both sides (MuJoCo's frictionloss is another law):%s\n",
                friction_off.c_str());
  if (!velocity_limits_off.empty())
    std::printf("  joint velocity limits off on both sides (MuJoCo has none):%s\n",
                velocity_limits_off.c_str());
  if (!kinds_off.empty())
    std::printf("  joint springs off on both sides (MuJoCo's passive spring is explicit, "
                "featherdrive's row implicit):%s\n",
                kinds_off.c_str());
  for (const std::string& note : runs.front().mjcf.notes) std::printf("  note: %s\n", note.c_str());
  for (const Compared& r : runs) {
    const DriveMapping mapping = &r == &runs.front() && !args.literal_only
                                     ? DriveMapping::translated
                                     : DriveMapping::literal;
    std::printf("\n");
    print_drives(r.mjcf, mapping, o.dt,
                 mapping == DriveMapping::translated ? verdicts(r, start)
                                                     : std::vector<std::string>{});
    if (r.diverged_at >= 0)
      std::printf(
          "  MuJoCo diverged at step %d (a huge acceleration; MuJoCo resets its state "
          "then): the differences below are over steps 0 to %d\n",
          r.diverged_at, r.diverged_at - 1);
    print_difference_table(r.c, std::string("MuJoCo (") + to_string(mapping) + ")");
  }
  if (runs.size() == 2)
    std::printf(
        "\n  translated against literal, largest relative q difference: %.1e against "
        "%.1e\n",
        runs[0].c.relative_q(), runs[1].c.relative_q());

  if (!args.plot.empty()) {
    std::fflush(stdout);
    const PrivateTempDir tmp;
    const fs::path csv = tmp.path() / "mujoco-diff.csv";
    write_differences(csv, runs.front().fd, runs.front().mj);
    const std::string title = scene.robot.name + ": featherdrive - MuJoCo (" +
                              (args.literal_only ? "literal" : "translated") + " drives, " +
                              to_string(o.solver) + ", " +
                              fs::path(args.scene).filename().string() + ")";
    run_plot_script(FEATHERDRIVE_PHYSX_PLOT_SCRIPT, {csv.string()}, args.plot, title, tmp);
    std::printf("  plot: %s\n", args.plot.c_str());
  }
  return 0;
}

MujocoCommands::MujocoCommands(CLI::App& app) {
  compare_ = app.add_subcommand(
      "compare-mujoco",
      "Run a scene in featherdrive and in MuJoCo 2.2.2 (exported MJCF; contacts only with the scene's "
      "ground) and show "
      "the largest differences per joint, with translated and with literal drive gains");
  compare_->add_option("scene", compare_args_.scene, "Scene file (YAML or JSON)")->required();
  compare_->add_option("--plot", compare_args_.plot, "PNG of the differences over time per joint");
  compare_
      ->add_option("--integrator", compare_args_.integrator,
                   "MuJoCo's: euler (default) or "
                   "implicit")
      ->check(CLI::IsMember({"euler", "implicit"}));
  compare_->add_flag("--translate", compare_args_.translate_only, "Only the translated gains");
  compare_->add_flag("--literal", compare_args_.literal_only,
                     "Only the literal gains (the same numbers in both engines)");
  compare_args_.overrides.add_options(compare_);

  translate_ = app.add_subcommand(
      "translate",
      "Translate drive gains between engines: --to mujoco writes a scene's robot as MJCF with "
      "translated actuators; --to physx writes a featherdrive scene from an MJCF's actuators; "
      "both print the match per joint");
  translate_
      ->add_option("input", translate_args_.scene,
                   "--to mujoco: a scene file; --to physx: an MJCF file")
      ->required();
  translate_->add_option("--to", translate_args_.to, "mujoco or physx")
      ->required()
      ->check(CLI::IsMember({"mujoco", "physx"}));
  translate_->add_option("--out", translate_args_.out, "The MJCF (or scene) file to write")
      ->required();
  translate_
      ->add_option("--integrator", translate_args_.integrator,
                   "MuJoCo's: euler (default) or implicit")
      ->check(CLI::IsMember({"euler", "implicit"}));
  translate_->add_flag("--keep-timestep", translate_args_.keep_timestep,
                       "Keep MuJoCo's timestep at the scene's dt for TGS (no sub-steps): the "
                       "poles are matched with armature, where MuJoCo can");
  translate_args_.overrides.add_options(translate_);
  translate_->add_option("--package", translate_args_.packages,
                         "NAME=DIR: where the URDF's package://NAME/ meshes are (repeatable)");
}

int MujocoCommands::run() {
  if (*compare_) {
    compare_args_.overrides.parse();
    return compare_mujoco(compare_args_);
  }
  translate_args_.overrides.parse();
  return translate(translate_args_);
}
