// momentum_law for double against second forms (docs/math/physx_departures.md, PD-4, PD-5, PD-8
// to PD-11): the compound inertia and the momenta summed from their definitions with Eigen's
// products and inverse on random poses, and the rigid correction checked by the momenta it leaves
// (a conservation law, not its own formula).
#include "featherdrive/sim/momentum_law.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "featherdrive/spatial/types.hpp"

namespace featherdrive {
namespace {

Vec3 random_vector(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Vec3(u(rng), u(rng), u(rng));
}

// Links of a random pose and velocities as momentum_law reads them; positions relative to an
// origin of the test's choice.
struct Links {
  std::vector<Mat3> R, Ic;
  std::vector<Vec3> c, w, v;
  std::vector<double> m;

  int size() const { return static_cast<int>(m.size()); }
  double mass(int i) const { return m[i]; }
  const double* com(int i) const { return c[i].data(); }
  void world_inertia(int i, double* I) const { momentum_law::world_inertia(R[i], Ic[i], I); }
  void world_inertia_times(int i, const double* x, double* Ix) const {
    momentum_law::world_inertia_times(R[i], Ic[i], x, Ix);
  }
  void velocity(int i, double* wi, double* vi) const {
    for (int r = 0; r < 3; ++r) wi[r] = w[i][r], vi[r] = v[i][r];
  }
  double total_mass() const {
    double M = 0.0;
    for (double x : m) M += x;
    return M;
  }
  Vec3 centre(double M) const {
    Vec3 C = Vec3::Zero();
    for (int i = 0; i < size(); ++i) C += m[i] * c[i];
    return C / M;
  }
};

Links random_links(std::mt19937_64& rng, int n) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0.1, 5.0);
  Links l;
  for (int i = 0; i < n; ++i) {
    l.R.push_back(Quat(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix());
    Mat3 G;
    for (int e = 0; e < 9; ++e) G(e / 3, e % 3) = g(rng);
    l.Ic.push_back(0.1 * G * G.transpose() + 0.01 * Mat3::Identity());
    l.c.push_back(random_vector(rng, 2.0));
    l.w.push_back(random_vector(rng, 3.0));
    l.v.push_back(random_vector(rng, 3.0));
    l.m.push_back(u(rng));
  }
  return l;
}

Mat3 eigen_compound(const Links& l, const Vec3& C) {
  Mat3 I = Mat3::Zero();
  for (int i = 0; i < l.size(); ++i) {
    const Vec3 r = l.c[i] - C;
    I += l.R[i] * l.Ic[i] * l.R[i].transpose() +
         l.m[i] * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
  }
  return I;
}

// P and L about C summed from the definitions: L = sum I_i w_i + m_i r_i x v_i (the COM's
// velocity drops out, sum m_i r_i = 0).
void eigen_momentum(const Links& l, const Vec3& C, Vec3& P, Vec3& L) {
  P.setZero();
  L.setZero();
  for (int i = 0; i < l.size(); ++i) {
    P += l.m[i] * l.v[i];
    L += l.R[i] * l.Ic[i] * l.R[i].transpose() * l.w[i] + l.m[i] * (l.c[i] - C).cross(l.v[i]);
  }
}

Mat3 from_rows(const double* a) {
  Mat3 m;
  for (int e = 0; e < 9; ++e) m(e / 3, e % 3) = a[e];
  return m;
}

// PD-8, PD-9: the world inertia and its product with a vector against Eigen's, the compound
// inverse times Eigen's compound inertia the identity.
TEST(MomentumLaw, CompoundInverseTimesEigensCompoundInertiaIsIdentity) {
  std::mt19937_64 rng(32);
  for (int trial = 0; trial < 200; ++trial) {
    const Links l = random_links(rng, 1 + trial % 12);
    const Vec3 C = l.centre(l.total_mass());
    for (int i = 0; i < l.size(); ++i) {
      double I[9], Iw[3];
      l.world_inertia(i, I);
      const Mat3 expected = l.R[i] * l.Ic[i] * l.R[i].transpose();
      EXPECT_LT((from_rows(I) - expected).norm(), 1e-14 * expected.norm());
      l.world_inertia_times(i, l.w[i].data(), Iw);
      EXPECT_LT((Vec3(Iw[0], Iw[1], Iw[2]) - expected * l.w[i]).norm(),
                1e-14 * expected.norm() * l.w[i].norm());
    }
    double inv[9];
    momentum_law::compound_inverse(l, l.size(), C.data(), inv);
    const Mat3 product = from_rows(inv) * eigen_compound(l, C);
    EXPECT_LT((product - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-12) << "trial " << trial;
  }
}

// PD-10 against the direct sums, and the same from positions relative to another origin (only
// differences enter).
TEST(MomentumLaw, MomentaAsDirectSums) {
  std::mt19937_64 rng(33);
  for (int trial = 0; trial < 200; ++trial) {
    Links l = random_links(rng, 1 + trial % 12);
    const double M = l.total_mass();
    const Vec3 C = l.centre(M);
    Vec3 P, L, P_eigen, L_eigen;
    momentum_law::momentum(l, l.size(), C.data(), M, P.data(), L.data());
    eigen_momentum(l, C, P_eigen, L_eigen);
    const double scale = 1.0 + P_eigen.norm() + L_eigen.norm();
    EXPECT_LT((P - P_eigen).norm(), 1e-13 * scale);
    EXPECT_LT((L - L_eigen).norm(), 1e-13 * scale);
    Vec3 P_only;
    momentum_law::momentum(l, l.size(), C.data(), M, P_only.data(), static_cast<double*>(nullptr));
    EXPECT_EQ(P_only, P);
    const Vec3 origin = random_vector(rng, 10.0);
    for (Vec3& c : l.c) c -= origin;
    Vec3 P_moved, L_moved;
    const Vec3 C_moved = C - origin;
    momentum_law::momentum(l, l.size(), C_moved.data(), M, P_moved.data(), L_moved.data());
    EXPECT_EQ(P_moved, P);
    EXPECT_LT((L_moved - L).norm(), 1e-12 * scale);
  }
}

// PD-4, PD-5 by what they do: every link moved by the field (dw, dv + dw x r_i) has the target
// linear momentum and its angular momentum scaled by the ratio; the root's twist moved by
// move_root carries that field (its centre of mass gains dv + dw x (c_0 - C)).
TEST(MomentumLaw, RigidCorrectionGivesTheTargetMomenta) {
  std::mt19937_64 rng(34);
  std::uniform_real_distribution<double> u(0.0, 2.0);
  for (int trial = 0; trial < 200; ++trial) {
    Links l = random_links(rng, 1 + trial % 12);
    const double M = l.total_mass();
    const Vec3 C = l.centre(M);
    Vec3 P1, L1;
    momentum_law::momentum(l, l.size(), C.data(), M, P1.data(), L1.data());
    const Vec3 target = random_vector(rng, 5.0);
    const double ratio = u(rng);
    double inv[9];
    momentum_law::compound_inverse(l, l.size(), C.data(), inv);
    Vec3 dw, dv;
    momentum_law::rigid_correction(l, l.size(), inv, C.data(), M, P1.data(), L1.data(), ratio,
                                   target.data(), dw.data(), dv.data());
    const Vec3 p0 = random_vector(rng, 2.0);  // a root origin
    Vec3 w0 = l.w[0], vo = l.v[0] - l.w[0].cross(l.c[0] - p0);
    momentum_law::move_root(dw.data(), dv.data(), p0.data(), C.data(), w0.data(), vo.data());
    for (int i = 0; i < l.size(); ++i) {
      const Vec3 field = dv + dw.cross(l.c[i] - C);
      if (i == 0) {
        EXPECT_LT((w0 - (l.w[0] + dw)).norm(), 1e-12 * (1.0 + w0.norm()));
        const Vec3 com_velocity = vo + w0.cross(l.c[0] - p0);
        EXPECT_LT((com_velocity - (l.v[0] + field)).norm(), 1e-12 * (1.0 + com_velocity.norm()));
      }
      l.w[i] += dw;
      l.v[i] += field;
    }
    Vec3 P, L;
    eigen_momentum(l, C, P, L);
    EXPECT_LT((P - target).norm(), 1e-12 * (1.0 + target.norm())) << "trial " << trial;
    EXPECT_NEAR(L.norm(), ratio * L1.norm(), 1e-12 * (1.0 + L1.norm())) << "trial " << trial;
  }
}

// PD-11: the root's centre of mass keeps its velocity from the start pose to the new one; the
// shift puts the centre of mass at C_start + P dt / M.
TEST(MomentumLaw, EndOfStepKeepsTheRootsComVelocityAndShiftsTheCom) {
  std::mt19937_64 rng(35);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 w0 = random_vector(rng, 3.0), vo = random_vector(rng, 3.0);
    const Vec3 c_s = random_vector(rng, 2.0), p_s = random_vector(rng, 2.0);
    const Vec3 c_n = random_vector(rng, 2.0), p_n = random_vector(rng, 2.0);
    Vec3 vo_n;
    momentum_law::keep_root_com_velocity(w0.data(), vo.data(), c_s.data(), p_s.data(),
                                         c_n.data(), p_n.data(), vo_n.data());
    const Vec3 before = vo + w0.cross(c_s - p_s), after = vo_n + w0.cross(c_n - p_n);
    EXPECT_LT((after - before).norm(), 1e-13 * (1.0 + before.norm() + 10.0 * w0.norm()));
    const Vec3 C_s = random_vector(rng, 5.0), C_n = random_vector(rng, 5.0),
               P = random_vector(rng, 5.0);
    const double per_mass = 0.01 / 3.7;
    Vec3 shift;
    momentum_law::com_shift(C_s.data(), P.data(), per_mass, C_n.data(), shift.data());
    EXPECT_LT((C_n + shift - (C_s + P * per_mass)).norm(), 1e-14 * 10.0);
  }
}

// The targets' external wrenches: a force f through a point x adds dt f to P and dt (x - C) x f
// to L about C, whether given as a root wrench (n = (x - p0) x f at the root's origin p0, plus
// gravity M g at C) or as a link wrench about frame 0's origin.
TEST(MomentumLaw, ExternalWrenchesAsForcesThroughAPoint) {
  std::mt19937_64 rng(36);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 x = random_vector(rng, 3.0), f = random_vector(rng, 10.0),
               C = random_vector(rng, 3.0), p0 = random_vector(rng, 3.0),
               g = random_vector(rng, 10.0);
    const double dt = 0.004, M = 7.5;
    const Vec3 expected_L = dt * (x - C).cross(f);
    const Vec3 n = (x - p0).cross(f);
    Vec3 P = Vec3::Zero(), L = Vec3::Zero();
    momentum_law::add_root_wrench(dt, M, g.data(), n.data(), f.data(), p0.data(), C.data(),
                                  P.data(), L.data());
    EXPECT_LT((P - dt * (M * g + f)).norm(), 1e-14 * (1.0 + P.norm()));
    EXPECT_LT((L - expected_L).norm(), 1e-14 * 100.0);
    Vec6 F;
    F << x.cross(f), f;
    P.setZero();
    L.setZero();
    momentum_law::add_link_wrench(dt, F.data(), C.data(), P.data(), L.data());
    EXPECT_LT((P - dt * f).norm(), 1e-14 * (1.0 + P.norm()));
    EXPECT_LT((L - expected_L).norm(), 1e-14 * 100.0);
  }
}

}  // namespace
}  // namespace featherdrive
