#include "featherdrive/solver/self_contacts.hpp"

#include <algorithm>
#include <cmath>

#include "featherdrive/constraint/contact_laws.hpp"

namespace featherdrive {
using namespace contact_laws;  // constants and the small laws both row kinds share
namespace {

constexpr double kTgsFrictionBias = 0.8;  // C14

// PhysX's default cfm of a link (C19, cfmScale 0.025): 0.025 times the largest linear response of
// an impulse at its centre of mass.
double default_cfm(const Model& model, const Data& data, int link) {
  constexpr double kCfmScale = 0.025;
  const Vec3 com = data.world_position[link] +
                   data.world_rotation[link] * model.links[static_cast<size_t>(link)].com -
                   data.frame_origin;
  double largest = 0.0;
  for (int k = 0; k < 3; ++k) {
    const Vec6 J = spatial_force(com, Vec3::Unit(k));
    largest = std::max(largest, row_response(J, data.response[link] * J, data.response[link]));
  }
  return kCfmScale * largest;
}

}  // namespace

SelfContacts::SelfContacts(const Model& model) : pairs_(self_collision_pairs(model)) {
  if (pairs_.empty()) return;
  int most = 0;  // C29a: a manifold for a pair_manifold pair, else one point
  for (const ShapePair& p : pairs_)
    most += pair_manifold(model.shapes[static_cast<size_t>(p.a)],
                          model.shapes[static_cast<size_t>(p.b)])
                ? kManifoldPoints
                : 1;
  capacity_ = std::min(most, kMaxContacts);
  manifold_ = ManifoldWorkspace(model.shapes);
  const auto c = static_cast<size_t>(capacity_);
  found_.resize(pairs_.size());
  order_.resize(pairs_.size());
  laws_.resize(c);
  static_limit_.resize(c);
  dynamic_limit_.resize(c);
  min_normal_.resize(c);
  t0_.resize(c);
  t1_.resize(c);
  rows_.resize(3 * c);
  W_.resize(9 * c * c);
  velocity_.resize(3 * c);
  pending_.resize(3 * c);
  const auto n = static_cast<size_t>(model.num_links());
  link_velocity_.assign(n, Vec6::Zero());
  link_impulse_.assign(n, Vec6::Zero());
  scratch_ = VecX::Zero(model.nv);
  marked_.assign(n, 0);
  for (const ShapePair& p : pairs_)
    for (const int s : {p.a, p.b})
      marked_[static_cast<size_t>(model.shapes[static_cast<size_t>(s)].link)] = 1;
  sweep_.emplace(model);
  sweep_->set_contact_links(marked_);
}

int SelfContacts::setup(const Model& model, const Data& data, const ContactOptions& options,
                        const std::vector<Vec6>& link_velocity, const VecX& link_cfm,
                        int position_iterations, const ContactPhase& phase,
                        std::vector<ContactReport>& reports, int first) {
  find(model, data, options);
  return setup_rows(model, data, options, link_velocity, link_cfm, position_iterations, phase,
                    reports, first);
}

int SelfContacts::find(const Model& model, const Data& data, const ContactOptions& options) {
  const double contact_distance = 2.0 * options.contact_offset;  // C1
  // The narrow phase (C29, C29a), then the deepest pairs whose points fit, whole.
  int found = 0;
  for (size_t p = 0; p < pairs_.size(); ++p) {
    const CollisionShape& a = model.shapes[static_cast<size_t>(pairs_[p].a)];
    const CollisionShape& b = model.shapes[static_cast<size_t>(pairs_[p].b)];
    if (shape_pair_manifold(data, a, b, contact_distance, manifold_, found_[p]))
      order_[static_cast<size_t>(found++)] = static_cast<int>(p);
  }
  auto deeper = [this](int x, int y) {
    const double sx = found_[static_cast<size_t>(x)].deepest;
    const double sy = found_[static_cast<size_t>(y)].deepest;
    return sx < sy || (sx == sy && x < y);
  };
  int points = 0;
  num_pairs_ = 0;
  if (found > 0) {
    std::sort(order_.begin(), order_.begin() + found, deeper);
    for (int k = 0; k < found; ++k) {
      const int p = order_[static_cast<size_t>(k)];
      const int count = found_[static_cast<size_t>(p)].count;
      if (points + count > capacity_) continue;
      points += count;
      order_[static_cast<size_t>(num_pairs_++)] = p;
    }
  }
  std::sort(order_.begin(), order_.begin() + num_pairs_);  // pair order: deterministic
  num_contacts_ = points;
  num_rows_ = 3 * num_contacts_;
  return num_contacts_;
}

int SelfContacts::setup_rows(const Model& model, const Data& data, const ContactOptions& options,
                             const std::vector<Vec6>& link_velocity, const VecX& link_cfm,
                             int position_iterations, const ContactPhase& phase,
                             std::vector<ContactReport>& reports, int first) {
  tgs_ = phase.tgs;
  const Vec3& origin = data.frame_origin;
  const double share = tgs_penetration_share(position_iterations);
  int c = 0;
  for (int q = 0; q < num_pairs_; ++q)
    for (int i = 0; i < found_[static_cast<size_t>(order_[static_cast<size_t>(q)])].count;
         ++i, ++c) {
      const int p = order_[static_cast<size_t>(q)];
      const PairManifold& contact = found_[static_cast<size_t>(p)];
      const CollisionShape& a = model.shapes[static_cast<size_t>(pairs_[static_cast<size_t>(p)].a)];
      const CollisionShape& b = model.shapes[static_cast<size_t>(pairs_[static_cast<size_t>(p)].b)];
      const Vec3& n = contact.normal;
      const Vec3 r = contact.points[i] - origin;
      // C10: along the points' relative sliding velocity, else any direction across n.
      const Vec6 dV =
          link_velocity[static_cast<size_t>(a.link)] - link_velocity[static_cast<size_t>(b.link)];
      const Vec3 v = dV.tail<3>() + dV.head<3>().cross(r);
      const Vec3 v_t = v - n * n.dot(v);
      Vec3& t0 = t0_[static_cast<size_t>(c)];
      t0 = v_t.squaredNorm() > 1e-4 ? Vec3(v_t.normalized()) : fallback_tangent(n);
      t1_[static_cast<size_t>(c)] = n.cross(t0);
      const Vec3* directions[3] = {&n, &t0, &t1_[static_cast<size_t>(c)]};
      for (int k = 0; k < 3; ++k) {
        Row& row = rows_[static_cast<size_t>(3 * c + k)];
        row.link_a = a.link;
        row.link_b = b.link;
        row.J = spatial_force(r, *directions[k]);
        row.impulse = row.dx = 0.0;
      }
      const double mu_s = 0.5 * (a.material.static_friction + b.material.static_friction);
      const double mu_d = 0.5 * (a.material.dynamic_friction + b.material.dynamic_friction);
      static_limit_[static_cast<size_t>(c)] = mu_s;
      dynamic_limit_[static_cast<size_t>(c)] = mu_d;
      ContactReport& report = reports[static_cast<size_t>(first + c)];
      report.link = a.link;
      report.shape = pairs_[static_cast<size_t>(p)].a;
      report.other_link = b.link;
      report.other_shape = pairs_[static_cast<size_t>(p)].b;
      report.position = contact.points[i];
      report.normal = n;
      report.separation = contact.separations[i];
      ContactNormalRow& law = laws_[static_cast<size_t>(c)];
      setup_normal_law(law, contact.separations[i],
                       row_velocity(rows_[static_cast<size_t>(3 * c)], link_velocity),
                       0.5 * (a.material.restitution + b.material.restitution), options, phase,
                       share);
    }
  // W = J M^-1 J^T, column by column: a unit impulse of row i through one sweep from rest (C30).
  const auto R = static_cast<size_t>(num_rows_);
  for (size_t i = 0; i < R; ++i) {
    const Row& row = rows_[i];
    link_impulse_[static_cast<size_t>(row.link_a)] += row.J;
    link_impulse_[static_cast<size_t>(row.link_b)] -= row.J;
    scratch_.setZero();
    gauss_seidel_sweep(
        model, data, *sweep_, scratch_, [](int, double) { return 0.0; },
        [&](int link, Vec6& dv) {
          const Vec6& F = link_impulse_[static_cast<size_t>(link)];
          dv += data.response[link] * F;
          return F;
        });
    link_impulse_[static_cast<size_t>(row.link_a)].setZero();
    link_impulse_[static_cast<size_t>(row.link_b)].setZero();
    link_velocities0(model, data, scratch_, link_velocity_);
    for (size_t j = 0; j < R; ++j) W_[j * R + i] = row_velocity(rows_[j], link_velocity_);
  }
  for (int c = 0; c < num_contacts_; ++c) {
    const int a = rows_[static_cast<size_t>(3 * c)].link_a,
              b = rows_[static_cast<size_t>(3 * c)].link_b;
    // C32: at least PhysX's default cfm, whatever the compat mode.
    const double cfm = std::max(
        {link_cfm[a], link_cfm[b], default_cfm(model, data, a), default_cfm(model, data, b)});
    // C22a on W_ii = J (Lambda_a + Lambda_b - Lambda_ab - Lambda_ba) J: the cross responses'
    // entries are bounded by the two links' diagonals, so their sum bounds the rounding.
    const double largest = data.response[a].diagonal().maxCoeff() +
                           data.response[b].diagonal().maxCoeff();
    for (int k = 0; k < 3; ++k) {
      Row& row = rows_[static_cast<size_t>(3 * c + k)];
      const double u = row_response(W_[static_cast<size_t>(3 * c + k) * (R + 1)], row.J, largest);
      row.mass = row_mass(k == 0 ? 1.0 : kFrictionMassScale, u + cfm);  // C20, C22, C22a
    }
    ContactNormalRow& law = laws_[static_cast<size_t>(c)];
    law.mass = rows_[static_cast<size_t>(3 * c)].mass;
    const double vn = row_velocity(rows_[static_cast<size_t>(3 * c)], link_velocity);
    const double p0 = law.separation;
    min_normal_[static_cast<size_t>(c)] =  // C12, one point
        kMinNormalShare *
        std::max(law.mass * (law.target - vn - std::max(p0 / phase.dt, 0.0)), 0.0);
  }
  return num_contacts_;
}

void SelfContacts::apply(int r, double delta) {
  const auto R = static_cast<size_t>(num_rows_);
  const double* column = W_.data() + static_cast<size_t>(r);
  for (size_t j = 0; j < R; ++j) velocity_[j] += column[j * R] * delta;
  pending_[static_cast<size_t>(r)] += delta;
  rows_[static_cast<size_t>(r)].impulse += delta;
}

void SelfContacts::solve(const Model& model, const Data& data, const ContactPhase& phase,
                         VecX& qd) {
  if (num_contacts_ == 0) return;
  link_velocities0(model, data, qd, link_velocity_);
  for (int r = 0; r < num_rows_; ++r) {
    velocity_[static_cast<size_t>(r)] = row_velocity(rows_[static_cast<size_t>(r)], link_velocity_);
    pending_[static_cast<size_t>(r)] = 0.0;
  }
  for (int c = 0; c < num_contacts_; ++c) {
    const int rn = 3 * c;
    ContactNormalRow& law = laws_[static_cast<size_t>(c)];
    law.impulse = rows_[static_cast<size_t>(rn)].impulse;
    law.dx = rows_[static_cast<size_t>(rn)].dx;
    apply(rn, normal_row_delta(law, velocity_[static_cast<size_t>(rn)], phase));
    // C12-C14 with one anchor at the point and no kept error.
    const double N =
        std::max(rows_[static_cast<size_t>(rn)].impulse, min_normal_[static_cast<size_t>(c)]);
    const double static_limit = static_limit_[static_cast<size_t>(c)] * N;
    const double dynamic_limit = dynamic_limit_[static_cast<size_t>(c)] * N;
    if (!tgs_) {
      for (int r = rn + 1; r <= rn + 2; ++r) {
        const Row& row = rows_[static_cast<size_t>(r)];
        double next = row.impulse - row.mass * velocity_[static_cast<size_t>(r)];
        if (std::abs(next) > static_limit) next = std::clamp(next, -dynamic_limit, dynamic_limit);
        apply(r, next - row.impulse);
      }
    } else {
      double next[2];
      for (int k = 0; k < 2; ++k) {
        const Row& row = rows_[static_cast<size_t>(rn + 1 + k)];
        next[k] = row.impulse - row.mass * (velocity_[static_cast<size_t>(rn + 1 + k)] +
                                            kTgsFrictionBias / phase.h * row.dx);
      }
      const double magnitude = std::hypot(next[0], next[1]);
      if (magnitude > static_limit) {
        const double scale = std::min(dynamic_limit, magnitude) / magnitude;
        next[0] *= scale;
        next[1] *= scale;
      }
      for (int k = 0; k < 2; ++k)
        apply(rn + 1 + k, next[k] - rows_[static_cast<size_t>(rn + 1 + k)].impulse);
    }
  }
  // The pass's impulses on their links, through one sweep (C31).
  for (int r = 0; r < num_rows_; ++r) {
    const Row& row = rows_[static_cast<size_t>(r)];
    const double p = pending_[static_cast<size_t>(r)];
    link_impulse_[static_cast<size_t>(row.link_a)] += p * row.J;
    link_impulse_[static_cast<size_t>(row.link_b)] -= p * row.J;
  }
  gauss_seidel_sweep(
      model, data, *sweep_, qd, [](int, double) { return 0.0; },
      [&](int link, Vec6& dv) {
        const Vec6 F = link_impulse_[static_cast<size_t>(link)];
        link_impulse_[static_cast<size_t>(link)].setZero();
        dv += data.response[link] * F;
        return F;
      });
}

void SelfContacts::track(const std::vector<Vec6>& link_velocity, double h) {
  for (int r = 0; r < num_rows_; ++r)
    rows_[static_cast<size_t>(r)].dx +=
        h * row_velocity(rows_[static_cast<size_t>(r)], link_velocity);
}

void SelfContacts::report(double dt, std::vector<ContactReport>& reports, int first,
                          std::vector<Vec3>& link_force) const {
  for (int c = 0; c < num_contacts_; ++c) {
    ContactReport& report = reports[static_cast<size_t>(first + c)];
    const Row* rows = &rows_[static_cast<size_t>(3 * c)];
    report.normal_impulse = rows[0].impulse;
    report.friction_impulse = rows[1].impulse * t0_[static_cast<size_t>(c)] +
                              rows[2].impulse * t1_[static_cast<size_t>(c)];
    const Vec3 force = (rows[0].impulse * report.normal + report.friction_impulse) / dt;
    link_force[static_cast<size_t>(rows[0].link_a)] += force;
    link_force[static_cast<size_t>(rows[0].link_b)] -= force;
  }
}

}  // namespace featherdrive
