// The contact rows between a robot's shapes and the ground, as PhysX 5.6.1 solves an
// articulation's contacts with a static plane (docs/math/contact.md): the narrow phase against
// the plane (section 1), one normal row per point (C2-C8) and patch friction with up to two
// anchors per shape (C9-C14), set up once per step and solved link by link inside the joint
// sweep (C15, C16). Capacity is fixed from the model's shapes, so a step allocates nothing.
#pragma once

#include <vector>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/constraint/contact.hpp"

namespace featherdrive {

/// Where a contact solve stands in the step.
struct ContactPhase {
  double dt = 0.0;      ///< the step
  double h = 0.0;       ///< PGS: dt; TGS: the sub-step dt / P
  bool tgs = false;
  bool velocity_iteration = false;
  double elapsed = 0.0;  ///< TGS: time from the step's start to this sub-step's start
  /// PGS: the time a penetration is pushed out over (C3), dt but a guard sub-step's: the whole
  /// step's (docs/math/step_guard.md, eq. G-3b); 0: dt.
  double push_dt = 0.0;
};

struct ContactNormalRow {
  Vec6 J = Vec6::Zero();         ///< a unit impulse along n at the point, as a spatial force (frame 0)
  Vec6 response = Vec6::Zero();  ///< Lambda_L J: the link's velocity change per unit impulse
  double mass = 0.0;             ///< 1 / (J . Lambda_L J + cfm_L) (C20)
  double separation = 0.0;       ///< p = d - R at set-up (C2); TGS: p_0 of C7
  double bias = 0.0;             ///< PGS: b (C3, 0 when bouncing); TGS: beta (C6)
  double target = 0.0;           ///< v_t: the bounce velocity (C8) or 0
  double dx = 0.0;               ///< TGS: n . the point's displacement since the step's start
  double impulse = 0.0;          ///< accumulated over the step
};

struct ContactFrictionRow {
  Vec6 J = Vec6::Zero();
  Vec6 response = Vec6::Zero();
  double mass = 0.0;             ///< 0.8 / (J . Lambda_L J + cfm_L) (C11)
  double error = 0.0;            ///< t . e: the kept anchor's drift from its ground point (C9)
  double dx = 0.0;               ///< TGS: t . the anchor's displacement since the step's start
  double impulse = 0.0;
};

/// The points of one shape on the ground: its normal rows, then its anchors' friction rows.
struct ContactPatch {
  int link = 0;
  int first_normal = 0, num_normals = 0;
  int first_friction = 0, num_anchors = 0;  ///< two friction rows per anchor (t0, t1)
  int anchor_point[2] = {0, 0};             ///< the normal row (and report) of each anchor
  double static_friction = 0.0;             ///< combined, halved with two anchors (C12)
  double dynamic_friction = 0.0;
  double min_normal_impulse = 0.0;          ///< N_min (C12)
  Vec3 t0 = Vec3::UnitX(), t1 = Vec3::UnitY();  ///< friction directions (C10)
  bool broken = false;                       ///< slipped this step (C13, C14)
};

/// A shape's friction anchors kept from the last step while its patch sticks (C9): each anchor's
/// point on the body (link frame) and on the ground (world). Part of a simulation's state.
struct FrictionAnchors {
  int count = 0;  ///< 0, 1 or 2
  Vec3 normal = Vec3::UnitZ();  ///< the ground's normal when they were made, link frame
  Vec3 body[2] = {Vec3::Zero(), Vec3::Zero()};
  Vec3 ground[2] = {Vec3::Zero(), Vec3::Zero()};
};

class ContactRows {
 public:
  ContactRows() = default;
  explicit ContactRows(const Model& model);

  /// Whether a link carries shapes (the sweep solves contacts there when the ground is on).
  const std::vector<char>& links_with_shapes() const { return has_shapes_; }
  bool any_shapes() const { return !patches_.empty(); }

  /// The step's rows from the step-start poses (data's world poses and response Lambda), the
  /// links' velocities before the solve (frame 0, gravity of the step included) and each link's
  /// cfm. Writes one report per point (position, normal, separation) into `reports` (at least
  /// max_points() long) and returns their number.
  int setup(const Model& model, const Data& data, const Ground& ground,
             const ContactOptions& options, const std::vector<Vec6>& link_velocity,
             const VecX& link_cfm, int position_iterations, const ContactPhase& phase,
             std::vector<ContactReport>& reports);

  /// Whether link has rows this step (solve_link would change nothing otherwise).
  bool link_has_rows(int link) const {
    return link_end_patch_[static_cast<size_t>(link)] > link_first_patch_[static_cast<size_t>(link)];
  }
  /// Solves link's rows at its velocity v + dv (frame 0) and adds their velocity change to dv;
  /// returns the spatial impulse they applied (frame 0).
  Vec6 solve_link(int link, const Vec6& v, Vec6& dv, const ContactPhase& phase);

  /// TGS: the points' and anchors' displacements over a sub-step h at link velocities V.
  void track(const std::vector<Vec6>& link_velocity, double h);

  /// The impulses of the step into the reports, and each link's contact force (sum / dt).
  void report(double dt, std::vector<ContactReport>& reports, std::vector<Vec3>& link_force) const;
  /// The work of the step's impulses at link velocities V (frame 0, about the set-up's origin):
  /// sum over rows of impulse J . V (docs/math/step_guard.md, eq. G-3a).
  double work(const std::vector<Vec6>& link_velocity) const;
  /// The step's end: the anchors of the patches that stuck are kept for the next step, the others
  /// dropped (C9).
  void conclude();

  /// The kept anchors, one entry per shape.
  const std::vector<FrictionAnchors>& anchors() const { return anchors_; }
  /// Throws std::invalid_argument for another number of shapes, a count outside [0, 2] or a
  /// non-finite point.
  void set_anchors(const std::vector<FrictionAnchors>& anchors);
  void check_anchors(const std::vector<FrictionAnchors>& anchors) const;
  /// Forgets every kept anchor (the robot was moved by hand).
  void clear_anchors();

  bool empty() const { return num_patches_ == 0; }
  /// The most points the shapes can have on the ground at once.
  int max_points() const { return static_cast<int>(normals_.size()); }

 private:
  std::vector<char> has_shapes_;
  std::vector<int> link_first_patch_, link_end_patch_;  ///< this step's patches per link
  std::vector<ContactNormalRow> normals_;
  std::vector<ContactFrictionRow> frictions_;
  std::vector<ContactPatch> patches_;
  std::vector<FrictionAnchors> anchors_;       ///< kept from the last step, per shape
  std::vector<FrictionAnchors> next_anchors_;  ///< this step's, per shape
  std::vector<int> shape_patch_;               ///< this step's patch of each shape, or -1
  std::vector<Vec3> points_;                   ///< the narrow phase's points of one shape
  std::vector<double> separations_;
  std::vector<char> taken_;                    ///< the reduction's chosen points (G3)
  std::vector<double> reach_;                  ///< per shape: its farthest hull vertex's distance
  int num_normals_ = 0, num_frictions_ = 0, num_patches_ = 0;
  Vec3 normal_ = Vec3::UnitZ();
};

/// A normal row's law from its separation d at set-up and its normal velocity vn then (C2-C8):
/// separation, bias and target; impulse and dx start at 0. tgs_share is s of C6.
void setup_normal_law(ContactNormalRow& row, double d, double vn, double restitution,
                      const ContactOptions& options, const ContactPhase& phase, double tgs_share);
/// The impulse change of a normal row at normal velocity vn (C4, C5; TGS C7), not below
/// -row.impulse.
double normal_row_delta(const ContactNormalRow& row, double vn, const ContactPhase& phase);
/// TGS's share s of a penetration corrected per sub-step (C6).
double tgs_penetration_share(int position_iterations);

/// Every link's spatial velocity in frame 0 for joint velocities qd, with the step-start
/// subspaces the sweep uses (data's S_i): V_i = V_parent + S_i qd_i. O(n).
void link_velocities0(const Model& model, const Data& data, const VecX& qd, std::vector<Vec6>& V);

}  // namespace featherdrive
