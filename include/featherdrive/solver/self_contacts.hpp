// Contacts between a robot's own shapes (docs/math/contact.md, section 14), solved where PhysX
// solves an articulation's self-collision: as constraints outside the joint sweep, each
// iteration before it. The rows couple two links, so their velocities come from the exact joint
// velocities at the pass's start and, within the pass, from the rows' mutual responses
// W = J M^-1 J^T (one sweep per row at set-up); one extra sweep applies the pass's impulses
// (C30, C31). Capacity is fixed from the model, so a step allocates nothing.
#pragma once

#include <optional>
#include <vector>

#include "featherdrive/constraint/contact_rows.hpp"
#include "featherdrive/constraint/shape_pairs.hpp"
#include "featherdrive/solver/gauss_seidel.hpp"

namespace featherdrive {

class SelfContacts {
 public:
  /// The most contact points a step keeps (the deepest pairs' manifolds, whole; C29, C29a).
  static constexpr int kMaxContacts = 32;

  SelfContacts() = default;
  explicit SelfContacts(const Model& model);

  bool any_pairs() const { return !pairs_.empty(); }
  int max_points() const { return capacity_; }

  /// The step's rows at data's poses (C29-C31): the pairs' contacts within the contact distance,
  /// their normal and two friction rows each, the rows' mutual responses. link_velocity: the
  /// links' velocities before the solve (frame 0); link_cfm: each link's cfm. Writes the contacts'
  /// reports from reports[first] on and returns their number.
  int setup(const Model& model, const Data& data, const ContactOptions& options,
            const std::vector<Vec6>& link_velocity, const VecX& link_cfm, int position_iterations,
            const ContactPhase& phase, std::vector<ContactReport>& reports, int first);
  /// setup in two: find, the narrow phase at data's poses (C29, C29a), which keeps this step's
  /// contacts and returns their number, then setup_rows, their rows (data's response must be
  /// the step's from then on). Batch's lanes give the response only where find found contacts.
  int find(const Model& model, const Data& data, const ContactOptions& options);
  int setup_rows(const Model& model, const Data& data, const ContactOptions& options,
                 const std::vector<Vec6>& link_velocity, const VecX& link_cfm,
                 int position_iterations, const ContactPhase& phase,
                 std::vector<ContactReport>& reports, int first);
  /// Every row once, in order, at the joint velocities qd (exact on entry), then the pass's
  /// impulses applied: qd is exact on exit.
  void solve(const Model& model, const Data& data, const ContactPhase& phase, VecX& qd);
  /// TGS: each row's displacement over a sub-step h at link velocities V (C25).
  void track(const std::vector<Vec6>& link_velocity, double h);
  /// The step's impulses into the reports from `first` on; adds each contact's force / dt to its
  /// link and the opposite to the other link.
  void report(double dt, std::vector<ContactReport>& reports, int first,
              std::vector<Vec3>& link_force) const;

 private:
  struct Row {
    int link_a = 0, link_b = 0;
    Vec6 J = Vec6::Zero();  ///< on link a; link b takes -J (frame 0)
    double mass = 0.0, impulse = 0.0, dx = 0.0;
  };
  double row_velocity(const Row& row, const std::vector<Vec6>& V) const {
    return row.J.dot(V[static_cast<size_t>(row.link_a)] - V[static_cast<size_t>(row.link_b)]);
  }
  void apply(int r, double delta);  ///< the pass's velocities and pending impulses

  std::vector<ShapePair> pairs_;
  int capacity_ = 0;
  std::vector<PairManifold> found_;    ///< per pair: this step's points
  std::vector<int> order_;             ///< pairs in contact; the first num_pairs_ are the step's
  ManifoldWorkspace manifold_;
  std::vector<ContactNormalRow> laws_; ///< per contact: the normal row's law (C2-C8)
  std::vector<double> static_limit_, dynamic_limit_, min_normal_;  ///< per contact
  std::vector<Vec3> t0_, t1_;          ///< per contact
  std::vector<Row> rows_;              ///< 3 per contact: normal, t0, t1
  std::vector<double> W_;              ///< rows x rows (capacity^2 * 9)
  std::vector<double> velocity_, pending_;  ///< per row, during a pass
  std::vector<Vec6> link_velocity_, link_impulse_;
  VecX scratch_;
  std::vector<char> marked_;           ///< links with shapes in a pair
  std::optional<SweepWorkspace> sweep_;
  int num_pairs_ = 0, num_contacts_ = 0, num_rows_ = 0;
  bool tgs_ = false;
};

}  // namespace featherdrive
