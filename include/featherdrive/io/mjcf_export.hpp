// MJCF export: a featherdrive model, or a simulation with its drives, as a MuJoCo 2.2.2 file
// (contacts only between its shapes and its ground), and a MuJoCo run of it beside featherdrive's. docs/mujoco_bridge.md.
//
// Mapping: one <body> per link, nested as in the tree and written in link order, so MuJoCo's
// joint, qpos and qvel order is ours; a massless moving link whose only child moves and hangs at an
// unrotated frame shares that child's body (one body with several joints, each at its link's
// origin: MuJoCo's form of the links load_mjcf makes for such a body, which MuJoCo would refuse
// as a massless moving body). A body's pos/quat is the joint frame's pose in the
// parent link frame (tree_transform: E = R^T, r = origin); the joint sits at the body origin with
// its axis in body coordinates, so the body frame is our link frame; <inertial> takes the centre
// of mass and the principal axes and moments of our inertia about it (from Eigen: MuJoCo 2.2.2's
// own fullinertia diagonalisation stops ~1e-6 rad short of the axes). Fixed joints weld a body to
// its parent, spherical joints are ball joints, a floating root is a free joint (qvel differs:
// MuJoCo's is [world linear velocity; body angular velocity]). A link named "world" is written as
// "world_link" (MuJoCo reserves the name). Mimic rows q_a + gear_ratio q_b + offset = 0 are
// <equality><joint> q_a = -offset - gear_ratio q_b: MuJoCo's soft constraint at its stiffest.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "featherdrive/io/error.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/gain_translation.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

/// The model alone: gravity, timestep dt, Euler, contacts off; no limits, damping, armature or
/// actuators (the bodies and joints above).
std::string model_to_mjcf(const Model& model, double dt);

enum class DriveMapping {
  translated,  ///< translate_to_mujoco per drive (gain_translation.hpp)
  literal,     ///< the same kp and kd as position and velocity actuators
};
const char* to_string(DriveMapping mapping);

struct MjcfExportOptions {
  MujocoIntegrator integrator = MujocoIntegrator::euler;
  DriveMapping drives = DriveMapping::translated;
  bool keep_timestep = false;  ///< TranslationOptions::keep_timestep
  std::string model_name = "featherdrive";  ///< <mujoco model>: the robot's name
  /// Kept in the file as <custom><text name="featherdrive_scene"> (kMjcfSceneText): the scene the
  /// export came from (scene_record), which `translate --to physx` restores. Empty: none.
  std::string scene_record;
  /// <geom>s in the bodies of their `body` links (mjcf_geometry: meshes' filenames absolute):
  /// visuals in group 1 without contacts, collisions in group 0. Every body has its <inertial>
  /// and the compiler takes no inertia from geoms, so they leave the dynamics as they are.
  std::vector<UrdfGeometry> geometry;
};

/// robot.geometry for MjcfExportOptions::geometry, each mesh's filename resolved to an absolute
/// path: package://NAME/REST as packages[NAME]/REST, file://PATH as PATH, else relative to the
/// URDF's folder. Left out, with a line in `warnings` naming the URDF, the link and the value:
/// meshes MuJoCo 2.2.2 cannot load (not STL: COLLADA .dae ones share one line), missing files,
/// unmapped packages (one line per package), sizes and scales that are not finite and > 0.
std::vector<UrdfGeometry> mjcf_geometry(const UrdfRobot& robot,
                                        const std::map<std::string, std::string>& packages,
                                        std::vector<std::string>& warnings);

/// The name of the custom text that holds an export's scene_record.
inline constexpr const char* kMjcfSceneText = "featherdrive_scene";

/// The scene text to keep in an MJCF export of `sim` (make_simulation of that scene): the text
/// with what the MJCF cannot give back as the scene had it (each hinge's, slide's and ball
/// axis's limits, armature, friction and velocity limit: the MJCF's armature and damping carry
/// the drives' translation) written into its `joints` entries, so that the scene read with the
/// MJCF as its model is the scene read with its own. Throws InputError (naming `file`) for text
/// that is not a YAML map.
std::string scene_record(const std::string& scene_text, const Simulation& sim,
                         const std::string& file);

/// One driven dof in the export: its MuJoCo setting, the translation's verdict and its actuators'
/// indices in the file (velocity: -1 when there is none).
struct MjcfDrive {
  std::string joint;
  int dof = 0;
  double effective_inertia = 0.0;  ///< 1 / (M^-1)_jj at the simulation's q
  MujocoDrive mujoco;
  MujocoTranslation translation;  ///< translated exports only
  int position_actuator = -1;
  int velocity_actuator = -1;
};

struct MjcfExport {
  std::string xml;
  double timestep = 0.0;  ///< MuJoCo's: dt / substeps
  int substeps = 1;       ///< MuJoCo steps per featherdrive step
  MujocoIntegrator integrator = MujocoIntegrator::euler;
  std::vector<MjcfDrive> drives;
  std::vector<std::string> notes;  ///< what the file does not carry, one line each
};

/// The simulation as MJCF at its current state's configuration (for the effective inertias):
/// gravity, timestep, integrator, joint limits -> range, armature, drives -> actuators (position,
/// plus velocity when kv > 0; max_force / max_impulse -> forcerange) and joint damping as the
/// mapping says; a ground beside collision shapes -> a plane and shape geoms, contacts on
/// (docs/mujoco_bridge.md, "Ground contact"). Joint friction, velocity limits, link parameters
/// and actuator envelopes are not carried (notes says so). Throws InputError (one line naming the joint and the value) for what
/// MuJoCo cannot take: explicit actuators, a drive with neither stiffness nor damping.
MjcfExport export_mjcf(const Simulation& sim, const MjcfExportOptions& options = {});

/// MuJoCo 2.2.2 running an export beside featherdrive: same state, the drives' targets read from
/// a Simulation before each step. Needs no file (MuJoCo's virtual file system).
class MujocoRun {
 public:
  /// Compiles export.xml; throws std::runtime_error with MuJoCo's message when it refuses it.
  explicit MujocoRun(const MjcfExport& mjcf);
  ~MujocoRun();
  MujocoRun(const MujocoRun&) = delete;
  MujocoRun& operator=(const MujocoRun&) = delete;

  /// q and qd in featherdrive's order and convention (fixed-base models: the same vectors).
  void set_state(const VecX& q, const VecX& qd);
  /// One featherdrive step (substeps MuJoCo steps) with the drive targets sim.drive(dof) holds.
  /// Throws InputError naming the joint for targets whose ctrl MuJoCo would zero (beyond
  /// mjMAXVAL = 1e10).
  void step(const Simulation& targets);
  VecX q() const;
  VecX qd() const;
  /// The drive force of the last step per dof (impulse / dt, as featherdrive reports it): the
  /// actuators' forces and the damping that stands in for the drive, averaged over the sub-steps.
  const VecX& drive_force() const { return drive_force_; }
  int nv() const;
  /// Whether MuJoCo met a non-finite or huge acceleration in some step (it then resets its state
  /// to the model's reference, as mj_checkAcc does).
  bool diverged() const { return diverged_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  MjcfExport mjcf_;
  VecX drive_force_, velocity_start_;
  bool diverged_ = false;
};

/// MuJoCo's version, "2.2.2".
std::string mujoco_version();

/// Compiles MJCF text with MuJoCo and returns "" or MuJoCo's error (for checks and tests).
std::string mujoco_compile_error(const std::string& xml);

}  // namespace featherdrive
