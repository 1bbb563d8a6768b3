// The step allocates nothing once the simulation exists: every global operator new in this binary
// is counted while the steps run. A binary of its own, because the counting operator new replaces
// the global one for everything linked with it.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <random>
#include <vector>

#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"

namespace {

std::atomic<bool> counting{false};
std::atomic<long> allocations{0};

void* allocate(std::size_t size) {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}

void* allocate_aligned(std::size_t size, std::align_val_t alignment) {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
  const std::size_t a = static_cast<std::size_t>(alignment);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}

}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void* operator new(std::size_t size, std::align_val_t a) { return allocate_aligned(size, a); }
void* operator new[](std::size_t size, std::align_val_t a) { return allocate_aligned(size, a); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace featherdrive {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Counts the allocations made by `work`.
template <class Work>
long allocations_in(Work&& work) {
  allocations = 0;
  counting = true;
  work();
  counting = false;
  return allocations.load();
}

TEST(AllocationCounter, CountsAllocations) {
  // The counter itself works: a vector that grows allocates.
  const long n = allocations_in([] {
    std::vector<double> v;
    for (int i = 0; i < 100; ++i) v.push_back(i);
  });
  EXPECT_GT(n, 0);
}

// Drives, limits, friction, a velocity limit and an actuator envelope on every 1-dof joint.
void constrain_every_joint(Simulation& sim, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const Link& l : sim.model().links) {
    if (l.joint_type != JointType::revolute && l.joint_type != JointType::prismatic) continue;
    const int d = l.v_index;
    sim.set_drive(d, Drive{DriveType::force, 200.0, 20.0, kInf, 0.5 * u(rng), 0.0});
    sim.set_joint_limits(d, -0.3, 0.4);
    sim.set_joint_friction(d, JointFriction{0.5, 0.3, 0.1});
    sim.set_max_joint_velocity(d, 3.0);
    if (d % 2 == 0) sim.set_actuator_envelope(d, ActuatorEnvelope{50.0, 10.0, 1.0, 0.1});
  }
}

struct Case {
  const char* name;
  bool floating;
  SolverType solver;
  Compat compat = Compat::none;
};

class StepAllocations : public ::testing::TestWithParam<Case> {};

TEST_P(StepAllocations, NoneAfterTheFirstStep) {
  const Case c = GetParam();
  // A spatial tree with revolute, prismatic, fixed and spherical joints, fixed or floating root,
  // and a chain (every link the child of the one before).
  auto tree = test::make_random_tree(11, 24, c.floating, true, 0.01);
  auto chain = test::make_planar_chain(12, 1.0, 0.5);
  for (const auto& model : {tree, chain}) {
    SimulationOptions options;
    options.dt = 1.0 / 240.0;
    options.solver = c.solver;
    options.position_iterations = 4;
    options.velocity_iterations = 1;
    options.compat = c.compat;  // physx: PhysX's parameters, link bias and momentum corrections
    Simulation sim(model, options);
    std::mt19937 rng(3);
    constrain_every_joint(sim, rng);
    sim.set_qd(test::random_vector(model->nv, rng, 0.5));
    sim.step();
    const long n = allocations_in([&] {
      for (int k = 0; k < 50; ++k) sim.step();
    });
    EXPECT_EQ(n, 0) << model->num_links() << " links";
    EXPECT_EQ(sim.step_count(), 51);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, StepAllocations,
                         ::testing::Values(Case{"fixed_pgs", false, SolverType::pgs},
                                           Case{"fixed_tgs", false, SolverType::tgs},
                                           Case{"floating_pgs", true, SolverType::pgs},
                                           Case{"floating_tgs", true, SolverType::tgs},
                                           Case{"physx_fixed_pgs", false, SolverType::pgs, Compat::physx},
                                           Case{"physx_floating_pgs", true, SolverType::pgs, Compat::physx},
                                           Case{"physx_floating_tgs", true, SolverType::tgs, Compat::physx}),
                         [](const auto& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace featherdrive
