// Running PhysX 5.6.1 itself on a featherdrive simulation and comparing the two trajectories.
// PhysX is the comparison harness of tests/physx/ (harness.js on the npm package
// physx-js-webidl, run by node): this file exports the scene (physx_scene_json), runs node on it
// and reads the harness's CSV. Nothing here needs node at build or link time; only calling
// run_physx does.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "featherdrive/io/physx_scene.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

/// The harness could not be found or run, or its output could not be read. `harness_exit` is the
/// harness's exit status when it ran and failed (2: it refused the scene), else -1.
class PhysxError : public std::runtime_error {
 public:
  explicit PhysxError(const std::string& message, int harness_exit = -1)
      : std::runtime_error(message), harness_exit(harness_exit) {}
  int harness_exit;
};

/// Joint trajectories of the harness CSV's form: one column per 1-dof joint, row k the state
/// after step k (row 0 the initial state).
struct JointTrajectory {
  std::vector<std::string> joints;
  std::vector<double> t;                      ///< [row]
  std::vector<std::vector<double>> q, qd, f;  ///< [row][joint]
  /// The harness's floating root, [row][13]: root:px py pz qw qx qy qz (link frame pose), world
  /// angular velocity wx wy wz, world velocity of the link origin vx vy vz; empty without them.
  std::vector<std::vector<double>> root;
  /// With a ground: the links that have shapes (the harness's contact:<link>:fx,fy,fz columns) and
  /// per row the ground's force on each over the step [row][link] (world frame, N; row 0 zero).
  /// PhysX's are its reported normal impulses summed over the link's points, over dt: the
  /// bindings report no friction impulses (tests/physx/README.md, "Contact forces").
  std::vector<std::string> contact_links;
  std::vector<std::vector<Vec3>> contact_force;
  size_t rows() const { return q.size(); }
};

/// Reads a CSV of the harness (tests/physx/README.md) or of `featherdrive simulate` for a robot
/// without a floating root: step,t,q:<joint>...,qd:<joint>...,f:<joint>... (other columns, e.g.
/// the harness's root:* columns, are read into `root` when all 13 are there, its
/// contact:<link>:fx,fy,fz into `contact_force`, others ignored). Fields
/// may be quoted as RFC 4180 says (a joint name with a comma). `name` is the file named in
/// messages. Throws PhysxError naming the file, line, column and value for a missing column, a
/// short row or a bad number.
JointTrajectory parse_joint_csv(const std::string& text, const std::string& name);
JointTrajectory read_joint_csv(const std::filesystem::path& path);

/// What the harness reports as a joint's force (every row PhysX solves on the dof: drive, limit,
/// friction, velocity limit), from featherdrive's side.
double physx_joint_force(const Simulation& sim, int dof);

/// Appends sim's state as one row of `out`, whose `joints` name the columns (1-dof joints of sim's
/// model, in any order); f is physx_joint_force; `contact_links`, when named, get
/// sim.link_contact_force(). Throws std::invalid_argument for a name that is not a 1-dof joint or
/// a link of the model.
void append_state(JointTrajectory& out, const Simulation& sim);

/// An empty trajectory with the columns PhysX reports for sim's model: its 1-dof joints in link
/// order.
JointTrajectory empty_trajectory(const Model& model);

/// The links the harness reports contact forces for (JointTrajectory::contact_links): with the
/// ground enabled, every link with shapes in link order; none without it.
std::vector<std::string> physx_contact_links(const Simulation& sim);

/// Where node and the installed harness are: `dir` holds harness.js and
/// node_modules/physx-js-webidl (what tests/physx/install.sh DIR makes).
struct PhysxInstall {
  std::string node;
  std::filesystem::path dir;
};

/// How to get the harness installed, for messages.
std::string physx_install_hint();

/// Finds node on $PATH and the harness: in $FEATHERDRIVE_PHYSX_DIR when set, else in the first of
/// `default_dirs` that holds it. Throws PhysxError with one line saying what is missing and how
/// to install it.
PhysxInstall find_physx(const std::vector<std::filesystem::path>& default_dirs);

/// Exports sim (its current state and settings) with `steps` steps and targets[k] set before
/// step k + 1, runs the harness and returns its trajectory (steps + 1 rows). Where
/// $FEATHERDRIVE_PHYSX_SERVER names the socket of a running `node harness.js --serve SOCKET`
/// (the tests start one: PhysX then loads once, not once per run), the run goes there; when
/// none answers, node is started as usual. The files go to a
/// fresh temporary folder, removed afterwards unless the run fails (the message names it).
JointTrajectory run_physx(const PhysxInstall& physx, const Simulation& sim, int steps,
                          const std::vector<TargetsByJoint>& targets = {},
                          const std::vector<ForcesByJoint>& forces = {});

/// Runs a program (argv[0] a path, or a name looked up on PATH) without a shell and waits for
/// it; its stdout goes to the caller's, its stderr to `stderr_path` unless that is empty. Returns
/// the exit status, or -1 when it could not be started or did not exit normally.
int run_program(const std::vector<std::string>& argv,
                const std::filesystem::path& stderr_path = {});

/// The largest difference of a - b in one quantity of one joint, and the row where it occurs
/// (the first such row).
struct LargestDifference {
  double value = 0.0;  ///< |a - b|
  size_t row = 0;
};

struct JointDifference {
  std::string joint;
  LargestDifference q, qd, f;
};

/// Per joint, the largest |a - b| in q, qd and f over all rows; `scale` is the largest |q|,
/// |qd|, |f| of `reference` over all joints and rows, the yardstick of the relative figures.
struct TrajectoryComparison {
  std::vector<JointDifference> joints;
  double scale_q = 0.0, scale_qd = 0.0, scale_f = 0.0;
  /// The largest difference over all joints relative to the scale; where the scale is 0, 0 for
  /// no difference and infinity for any (never a misleading 0).
  double relative_q() const;
  double relative_qd() const;
  double relative_f() const;
};

/// Per link, the largest |n . (a - reference)| of the contact forces (n the ground's normal: PhysX
/// reports normal impulses only) and the row where it occurs; `scale` is the largest |n . f| of
/// `reference` over all links and rows.
struct ContactComparison {
  std::vector<std::pair<std::string, LargestDifference>> links;
  double scale = 0.0;
};

/// Compares the contact forces of `a` with `reference`'s link by link (matched by name). Throws
/// PhysxError when the row counts differ or a link of `reference` is missing from `a`.
ContactComparison compare_contact_forces(const JointTrajectory& a, const JointTrajectory& reference,
                                         const Vec3& normal);

/// Compares `a` with `reference` joint by joint (matched by name) and row by row. Throws
/// PhysxError when the row counts differ or a joint of `reference` is missing from `a`.
TrajectoryComparison compare_trajectories(const JointTrajectory& a,
                                          const JointTrajectory& reference);

}  // namespace featherdrive
