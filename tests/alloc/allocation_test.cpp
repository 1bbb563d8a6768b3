// The step allocates nothing once the simulation exists: every call to malloc, calloc, realloc and
// the aligned allocators in this process is counted while the steps run (operator new and Eigen's
// temporaries both end in malloc). A binary of its own, because it replaces the C allocator's entry
// points: with glibc it defines them and forwards to glibc's own; under AddressSanitizer, which
// owns malloc, it counts through the sanitizer's allocation hook instead.
#include <algorithm>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/center_of_mass.hpp"
#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/jacobian.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "featherdrive/sim/batch.hpp"
#include "featherdrive/sim/control_step.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/lane_contact_models.hpp"
#include "support/scoped_env.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define FEATHERDRIVE_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define FEATHERDRIVE_ASAN 1
#endif
#endif

namespace {

std::atomic<bool> counting{false};
std::atomic<long> allocations{0};

void count() {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace

#ifdef FEATHERDRIVE_ASAN
#include <sanitizer/allocator_interface.h>

namespace {
void on_malloc(const volatile void*, std::size_t) { count(); }
void on_free(const volatile void*) {}
const int hooks_installed = __sanitizer_install_malloc_and_free_hooks(on_malloc, on_free);
}  // namespace
#else
// glibc's allocator under its internal names; the definitions below take the public ones.
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t size) {
  count();
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  count();
  return __libc_realloc(p, size);
}
void free(void* p) { __libc_free(p); }
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  count();
  return __libc_memalign(alignment, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  count();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  count();
  void* p = __libc_memalign(alignment, size);
  if (!p) return 12;  // ENOMEM
  *out = p;
  return 0;
}
}
#endif

namespace featherdrive {
namespace {

using test::kInf;

// Counts the allocations made by `work`.
template <class Work>
long allocations_in(Work&& work) {
  allocations = 0;
  counting = true;
  work();
  counting = false;
  return allocations.load();
}

TEST(AllocationCounter, CountsEveryAllocator) {
  // The counter itself works, for each way memory is taken: operator new, malloc and Eigen's
  // dynamic temporaries (which call malloc directly).
  EXPECT_GE(allocations_in([] {
              std::vector<double> v;
              for (int i = 0; i < 100; ++i) v.push_back(i);
            }),
            1);
  EXPECT_EQ(allocations_in([] {
              void* volatile p = std::malloc(24);
              std::free(p);
            }),
            1);
  EXPECT_EQ(allocations_in([] {
              VecX a = VecX::Ones(40);
              VecX b = (a * 2.0).eval();
              EXPECT_EQ(b.size(), 40);
            }),
            2);
}

// Drives (some delayed), limits, friction, a velocity limit and an actuator envelope on every
// 1-dof joint.
void constrain_every_joint(Simulation& sim, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const Link& l : sim.model().links) {
    // Every axis of a spherical joint too (its rows: spherical_rows.cpp).
    if (l.joint_type != JointType::revolute && l.joint_type != JointType::prismatic &&
        l.joint_type != JointType::spherical)
      continue;
    for (int d = l.v_index; d < l.v_index + l.nv; ++d) {
      sim.set_drive(d, Drive{DriveType::force, 200.0, 20.0, kInf, 0.5 * u(rng), 0.0});
      sim.set_joint_limits(d, -0.3, 0.4);
      sim.set_joint_friction(d, JointFriction{0.5, 0.3, 0.1});
      sim.set_max_joint_velocity(d, 3.0);
      if (d % 2 == 0) sim.set_actuator_envelope(d, ActuatorEnvelope{50.0, 10.0, 1.0, 0.1});
      if (d % 3 == 1) sim.set_drive_delay(d, 1 + d % 4);  // rings sized here, not in the step
      if (d % 2 == 1) {  // a row kind (constraint/row_kinds.hpp)
        const double spring[] = {40.0, 1.0, 0.1};
        sim.set_row_parameters("joint_spring", d, spring);
      }
      if (l.joint_type == JointType::revolute && d % 2 == 1)
        sim.set_revolute_wrap(d, RevoluteWrap::wrapped);
    }
  }
  // Mimic rows between 1-dof joints, a chain of rows (no cycle), in different branches.
  std::vector<MimicJoint> rows;
  int previous = -1;
  for (const Link& l : sim.model().links) {
    if (l.nv != 1 || l.joint_type == JointType::spherical) continue;
    if (previous >= 0 && rows.size() < 3) rows.push_back({l.v_index, previous, -0.5, 0.01});
    previous = l.v_index;
  }
  sim.set_mimic_joints(rows);
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

// A guard bound so small that every step is redone.
SimulationOptions guard_redoing_every_step(SolverType solver) {
  SimulationOptions options;
  options.dt = 1.0 / 60.0;
  options.solver = solver;
  options.guard = {true, 1e-3, 16};
  return options;
}

// The step guard's redone steps (docs/math/step_guard.md) run on scratch sized with the options:
// every step redone, explicit actuators re-evaluated per sub-step.
TEST(StepAllocations, NoneInGuardedStepsThatAreRedone) {
  const auto tree = test::make_random_tree(11, 24, /*floating=*/true, true, 0.01);
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim(tree, guard_redoing_every_step(solver));
    std::mt19937 rng(3);
    constrain_every_joint(sim, rng);
    int actuated = 0;
    for (const Link& l : tree->links)
      if (l.joint_type == JointType::revolute && actuated++ < 3) {
        sim.set_drive(l.v_index, Drive{});
        ExplicitActuator a;
        a.kind = ActuatorKind::ideal_pd;
        a.stiffness = 300.0;
        a.damping = 5.0;
        sim.set_actuator(l.v_index, a);
      }
    sim.set_qd(test::random_vector(tree->nv, rng, 0.5));
    sim.step();
    const long n = allocations_in([&] {
      for (int k = 0; k < 20; ++k) sim.step();
    });
    EXPECT_EQ(n, 0) << to_string(solver);
    EXPECT_EQ(sim.guard_triggers(), 21) << to_string(solver);
  }
}

// A batch allocates its bookkeeping once per call (a slot per copy, TBB's arena), never per
// step: 1 step and 40 steps a call cost the same, on 1 and 2 threads.
TEST(BatchAllocations, PerCallNotPerStep) {
  auto model = test::make_random_tree(7, 10, true, true, 0.01);
  for (int threads : {1, 2}) {
    Batch batch(Simulation(model, SimulationOptions{}), 3);
    batch.set_num_threads(threads);
    std::mt19937 rng(5);
    for (int i = 0; i < batch.size(); ++i) constrain_every_joint(batch.sim(i), rng);
    batch.step();
    const long one = allocations_in([&] { batch.step(1); });
    const long many = allocations_in([&] { batch.step(40); });
    if (threads == 1) EXPECT_EQ(one, many) << threads << " threads";
    else EXPECT_LE(many, one + 8) << threads << " threads";  // TBB's scheduler may vary a little
    EXPECT_EQ(batch.sim(0).step_count(), 42);
  }
}

// The same through the SIMD lanes (a fixed base): the lanes' scratch and the clocks are made by
// the first call; on one thread a call allocates nothing, on two TBB's arena per call. With mimic
// rows, and with the control stages (drive delays, explicit actuators) too, which step the lanes
// one step a run, and with implicit actuators of every kind and convergence tracking.
TEST(BatchAllocations, LanesNoneOnOneThreadPerCallOnTwo) {
  auto model = test::make_random_tree(7, 10, false, false, 0.01);
  enum Control { none, control_stages, implicit_actuators };
  for (const Control control : {none, control_stages, implicit_actuators})
    for (int threads : {1, 2}) {
      Simulation prototype(model, SimulationOptions{});
      for (int d = 0; d < model->nv; ++d) {  // every row kind the lanes solve
        prototype.set_drive(d, Drive{DriveType::force, 400.0, 20.0, 50.0, 0.3, 0.0});
        prototype.set_joint_limits(d, -0.2, 0.2);
        prototype.set_joint_friction(d, JointFriction{0.1, 0.05, 0.01});
        prototype.set_max_joint_velocity(d, 0.5);
        if (control == none) continue;
        if (d % 3 == 0 || (control == implicit_actuators && d % 3 == 1)) {
          prototype.set_drive(d, Drive{});
          ExplicitActuator a;
          const int kind = control == implicit_actuators ? d % 3 + (d / 3) % 2 : d % 2;
          a.kind = kind == 0   ? ActuatorKind::remotized_pd
                   : kind == 1 ? ActuatorKind::ideal_pd
                               : ActuatorKind::dc_motor;
          a.stiffness = 100.0;
          a.damping = 5.0;
          if (a.kind == ActuatorKind::remotized_pd) a.lookup = {{-1.0, 2.0}, {1.0, 4.0}};
          if (a.kind == ActuatorKind::dc_motor) a.saturation_effort = 3.0, a.velocity_limit = 1.0;
          a.delay = 2;
          if (control == implicit_actuators) a.integration = ActuatorIntegration::implicit_law;
          prototype.set_actuator(d, a);
          prototype.set_drive_target(d, 0.3, 0.0);
        } else {
          prototype.set_drive_delay(d, 1 + d % 3);
        }
      }
      prototype.set_track_convergence(control == implicit_actuators);
      prototype.set_mimic_joints({{1, 0, -1.0, 0.0}, {3, 2, 0.5, 0.1, 20.0, 0.5}});
      Batch batch(prototype, 19);
      batch.set_num_threads(threads);
      batch.step();
      ASSERT_NE(batch.step_path().find("lanes"), std::string::npos) << batch.step_path();
      const long one = allocations_in([&] { batch.step(1); });
      const long many = allocations_in([&] { batch.step(40); });
      if (threads == 1) EXPECT_EQ(one, 0) << control;
      EXPECT_LE(many, one + 8) << threads << " threads, control " << control;
      EXPECT_EQ(batch.sim(0).step_count(), 42);
    }
}

// A batch of two lane groups (another dt), gravity per lane and one guarded environment, its
// environments handed out (looked at before every step): regrouping
// after a settings change may allocate, the steps after it do not, on one thread.
TEST(BatchAllocations, LaneGroupsAndAGuardedEnvironmentNoneOnOneThread) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  auto model = test::make_random_tree(7, 10, false, false, 0.01);
  Simulation prototype(model, SimulationOptions{});
  for (int d = 0; d < model->nv; ++d) {
    prototype.set_drive(d, Drive{DriveType::force, 400.0, 20.0, 50.0, 0.3, 0.0});
    prototype.set_joint_limits(d, -0.2, 0.2);
  }
  Batch batch(prototype, 9);
  batch.set_num_threads(1);
  SimulationOptions other = prototype.options();
  other.dt = 0.01;
  for (int e : {2, 5}) batch.sim(e).set_options(other);
  SimulationOptions guarded = prototype.options();
  guarded.guard.enabled = true;
  batch.sim(7).set_options(guarded);
  const int heavy[] = {1};
  batch.set_gravity(heavy, RowMatrix::Constant(1, 3, -4.0));
  batch.step();
  ASSERT_NE(batch.step_path().find("3 groups (6, 2, 1 environments; 1 at one lane)"),
            std::string::npos)
      << batch.step_path();
  EXPECT_EQ(allocations_in([&] { batch.step(1); }), 0);
  EXPECT_EQ(allocations_in([&] { batch.step(40); }), 0);
  batch.sim(3).set_options(other);  // into the other group: the next step regroups
  batch.step();
  ASSERT_NE(batch.step_path().find("3 groups (5, 3, 1 environments; 1 at one lane)"),
            std::string::npos)
      << batch.step_path();
  EXPECT_EQ(allocations_in([&] { batch.step(1); }), 0);
  EXPECT_EQ(allocations_in([&] { batch.step(40); }), 0);
  EXPECT_EQ(batch.step_count()[7], 84);
}

// Batch's lane step allocates nothing on one thread (its scratch is made by the first call), and
// per call, not per step, on two (TBB's arena), at every width (set_isa), with drives and limits,
// on a fixed and on a floating base.
// FEATHERDRIVE_SIMD read at every step (its name and value compared, the CPU asked) allocates
// nothing either, at each width it forces and in one-lane blocks.
TEST(BatchAllocations, ForcedWidthNone) {
  auto model = test::make_random_tree(7, 6, /*floating=*/false);
  Simulation prototype(model, SimulationOptions{});
  for (int d = 0; d < model->nv; ++d)
    prototype.set_drive(d, Drive{DriveType::force, 200.0, 20.0, kInf, 0.3, 0.0});
  std::vector<std::string> widths = {"one"};
  for (SimdIsa isa : available_simd_isas()) widths.push_back(to_string(isa));
  for (const std::string& width : widths) {
    const test::ScopedEnv forced("FEATHERDRIVE_SIMD", width);
    Batch batch(prototype, 19);
    batch.set_num_threads(1);
    batch.step();
    ASSERT_NE(batch.step_path().find(width == "one" ? "at one lane" : width + " lanes"),
              std::string::npos)
        << batch.step_path();
    EXPECT_EQ(allocations_in([&] { batch.step(1); }), 0) << width;
  }
}

TEST(BatchAllocations, LanesNoneAtEveryWidth) {
  for (const bool floating : {false, true}) {
  // Spherical joints too (compat none): their axes' positions are read per lane.
  auto model = test::make_random_tree(7, 10, floating, /*spherical=*/true, 0.01);
  Simulation prototype(model, SimulationOptions{});
  for (const Link& l : model->links) {
    const bool ball = l.joint_type == JointType::spherical;
    if (l.joint_type != JointType::revolute && l.joint_type != JointType::prismatic && !ball)
      continue;
    for (int a = 0; a < (ball ? 3 : 1); ++a) {
      prototype.set_drive(l.v_index + a, Drive{DriveType::force, 200.0, 20.0, kInf, 0.3, 0.0});
      prototype.set_joint_limits(l.v_index + a, -0.3, 0.4);
      const double spring[] = {40.0, 1.0, 0.1};  // a row kind
      if (a == 0) prototype.set_row_parameters("joint_spring", l.v_index + a, spring);
    }
  }
  for (SimdIsa isa : available_simd_isas())
    for (int threads : {1, 2}) {
      Batch batch(prototype, 19);
      batch.set_isa(isa);
      batch.set_num_threads(threads);
      batch.step();
      ASSERT_EQ(batch.step_path(), std::string(to_string(isa)) + " lanes");
      const long one = allocations_in([&] { batch.step(1); });
      const long many = allocations_in([&] { batch.step(40); });
      if (threads == 1) EXPECT_EQ(many, 0) << to_string(isa) << " floating " << floating;
      else EXPECT_LE(many, one + 8) << to_string(isa) << " floating " << floating;
      EXPECT_EQ(batch.step_count()[18], 42);
    }
  }
}

// The step guard in the lanes (docs/simd_batch.md, "The step guard"): every environment's step
// tested on the lanes' rows, a bound so small that the guarded ones are redone by their scalar
// sub-steps, one environment in three unguarded; none on one thread at every width, per call,
// not per step, on two (the redos run on the lanes' threads).
TEST(BatchAllocations, LanesGuardedNoneAtEveryWidth) {
  auto model = test::make_random_tree(11, 10, false, /*spherical=*/true, 0.01);
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const SimulationOptions o = guard_redoing_every_step(solver);
    Simulation prototype(model, o);
    std::mt19937 rng(3);
    constrain_every_joint(prototype, rng);
    prototype.set_qd(test::random_vector(model->nv, rng, 0.5));
    for (SimdIsa isa : available_simd_isas())
      for (int threads : {1, 2}) {
        Batch batch(prototype, 11);
        for (int e = 0; e < batch.size(); e += 3) {
          SimulationOptions off = o;
          off.guard.enabled = false;
          batch.sim(e).set_options(off);
        }
        batch.set_isa(isa);
        batch.set_num_threads(threads);
        batch.step();
        // The unguarded ones a group of their own (many steps a run).
        ASSERT_EQ(batch.step_path().find(std::string(to_string(isa)) + " lanes: 2 groups (4, 7"),
                  0u)
            << batch.step_path();
        const long one = allocations_in([&] { batch.step(1); });
        const long many = allocations_in([&] { batch.step(20); });
        if (threads == 1) EXPECT_EQ(many, 0) << to_string(isa);
        else EXPECT_LE(many, one + 8) << to_string(isa) << ", 2 threads";
        EXPECT_EQ(batch.sim(1).guard_triggers(), 22) << to_string(isa);
        EXPECT_EQ(batch.sim(0).guard_triggers(), 0) << to_string(isa);
      }
  }
}

// The contacts of the last environment of 11 in lanes of `isa` on one thread, over 30 steps after
// the first call (which makes the scratch), in which nothing is allocated.
struct LaneContactCount {
  int contacts = 0, self = 0;
};
LaneContactCount lane_contacts_allocating_nothing(const Simulation& prototype, SimdIsa isa) {
  Batch batch(prototype, 11);
  batch.set_isa(isa);
  batch.set_num_threads(1);
  batch.step();
  EXPECT_EQ(batch.step_path(), std::string(to_string(isa)) + " lanes");
  LaneContactCount count;
  EXPECT_EQ(allocations_in([&] {
              for (int k = 0; k < 30; ++k) {
                batch.step();
                for (const ContactReport& c : batch.contacts(10)) {
                  ++count.contacts;
                  count.self += c.other_link >= 0;
                }
              }
            }),
            0)
      << to_string(isa);
  return count;
}

// The floating root's box half in the ground, the ground on: contact rows from the first step.
void sink_root_half(Simulation& s) {
  VecX q = s.q();
  q[2] = 0.05;
  s.set_q(q);
  Ground ground;
  ground.enabled = true;
  s.set_ground(ground);
}

// The same with ground contacts in the lanes (each environment's ContactRows, per lane): a
// floating tree with a shape of each kind on its links, half sunk into the ground, PGS and TGS,
// unguarded and guarded (its landing redone, the start's reports kept), at every width, none on
// one thread.
TEST(BatchAllocations, LanesWithGroundContactsNoneAtEveryWidth) {
  Model m = *test::make_random_tree(5, 8, true, /*spherical=*/true, 0.01);
  for (int i = 0; i < m.num_links(); ++i) {
    CollisionShape s;
    s.link = i;
    constexpr ShapeType kinds[] = {ShapeType::box, ShapeType::sphere, ShapeType::capsule,
                                   ShapeType::cylinder};
    s.type = kinds[i % 4];
    s.size = Vec3(0.1, 0.08, 0.06);
    m.shapes.push_back(s);
  }
  auto model = std::make_shared<const Model>(m);
  for (SolverType solver : {SolverType::pgs, SolverType::tgs})
  for (const bool guard : {false, true}) {
    SimulationOptions o;
    o.solver = solver;
    o.guard = {guard, 0.05, 2};
    Simulation prototype(model, o);
    sink_root_half(prototype);
    for (SimdIsa isa : available_simd_isas()) {
      Batch batch(prototype, 11);
      batch.set_isa(isa);
      batch.set_num_threads(1);
      batch.step();
      ASSERT_EQ(batch.step_path(), std::string(to_string(isa)) + " lanes");
      EXPECT_EQ(allocations_in([&] { batch.step(30); }), 0) << to_string(isa) << guard;
      // Guarded, PGS's redone push-out throws the tree off the ground (as Simulation's does).
      if (guard) EXPECT_GT(batch.sim(10).guard_triggers(), 0) << to_string(isa);
      else EXPECT_GT(batch.contacts(10).size(), 0u);
    }
  }
}

// One-lane blocks (docs/simd_batch.md, "One-lane blocks"): an environment alone in its group
// (another dt) beside a group of two, a floating tree with spherical joints, mimic rows and
// ground contacts, unguarded and guarded: none on one thread, per call, not per step, on two.
TEST(BatchAllocations, OneLaneBlocksNone) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  Model m = *test::make_random_tree(5, 8, true, /*spherical=*/true, 0.01);
  for (int i = 0; i < m.num_links(); ++i) {
    CollisionShape s;
    s.link = i;
    s.type = i % 2 ? ShapeType::sphere : ShapeType::box;
    s.size = Vec3(0.1, 0.08, 0.06);
    m.shapes.push_back(s);
  }
  auto model = std::make_shared<const Model>(m);
  std::vector<int> single;  // 1-dof joints' dofs
  for (const Link& l : model->links)
    if (l.joint_type == JointType::revolute || l.joint_type == JointType::prismatic)
      single.push_back(l.v_index);
  ASSERT_GE(single.size(), 3u);
  for (const bool guard : {false, true})
    for (int threads : {1, 2}) {
      SimulationOptions o;
      o.guard = {guard, 0.05, 2};
      Simulation prototype(model, o);
      for (int d : single)
        prototype.set_drive(d, Drive{DriveType::force, 200.0, 20.0, kInf, 0.3, 0.0});
      prototype.set_mimic_joints({{single[1], single[0], -1.5, 0.05}});
      sink_root_half(prototype);
      Batch batch(prototype, 3);
      SimulationOptions other = o;
      other.dt *= 0.5;
      batch.sim(1).set_options(other);
      batch.set_num_threads(threads);
      batch.step();
      ASSERT_EQ(batch.step_path(), "sse2 lanes: 2 groups (2, 1 environments; 1 at one lane)");
      const long one = allocations_in([&] { batch.step(1); });
      const long many = allocations_in([&] { batch.step(30); });
      if (threads == 1) EXPECT_EQ(many, 0) << guard;
      else EXPECT_LE(many, one + 8) << guard << ", 2 threads";
      EXPECT_EQ(batch.step_count()[1], 32);
      EXPECT_EQ(batch.step_count()[2], 32);
    }
}

// The same with self-collision in the lanes (each environment's SelfContacts, and the response its
// rows sweep, per lane): a robot whose box rests on its plate on the ground, PGS and TGS, compat
// none and physx, at every width, none on one thread.
TEST(BatchAllocations, LanesWithSelfContactsNoneAtEveryWidth) {
  for (const Compat compat : {Compat::none, Compat::physx})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      const Simulation prototype = test::self_touching_robot(solver, compat);
      for (SimdIsa isa : available_simd_isas()) {
        const LaneContactCount count = lane_contacts_allocating_nothing(prototype, isa);
        EXPECT_EQ(count.self, 30 * 4) << to_string(isa);  // the box's four corners each step
      }
    }
}

// The kinematics and dynamics queries on a reused Data and reused outputs: none after the first
// round (which sizes the Jacobians), on fixed and floating random trees with every joint type.
TEST(QueryAllocations, NoneOnReusedWorkspace) {
  for (bool floating : {false, true}) {
    auto model = test::make_random_tree(13, 24, floating, true, 0.01);
    Data data(*model);
    std::mt19937 rng(9);
    const VecX q = test::random_configuration(*model, rng);
    const VecX v = test::random_vector(model->nv, rng);
    const VecX a = test::random_vector(model->nv, rng);
    const Vec3 point(0.1, -0.2, 0.05);
    MatX J, J_com;
    double sink = 0.0;
    auto round = [&] {
      forward_kinematics(*model, data, q, v);
      for (int i = 0; i < model->num_links(); ++i) {
        for (ReferenceFrame f : {ReferenceFrame::local, ReferenceFrame::world_aligned}) {
          frame_jacobian(*model, data, i, point, f, J);
          link_jacobian(*model, data, i, f, J);
          sink += jacobian_dot_times_v(*model, data, i, point, f).sum();
          sink += frame_velocity(*model, data, i, point, f).sum();
          sink += link_velocity(*model, data, i, f).sum();
        }
        sink += frame_position(*model, data, i, point).sum();
      }
      sink += center_of_mass(*model, data).sum() + center_of_mass_velocity(*model, data).sum();
      center_of_mass_jacobian(*model, data, J_com);
      sink += crba(*model, data, q).sum() + rnea(*model, data, q, v, a).sum();
      sink += nonlinear_effects(*model, data, q, v).sum();
      sink += generalized_gravity(*model, data, q).sum();
      sink += aba(*model, data, q, v, a).sum();
    };
    round();
    EXPECT_EQ(allocations_in(round), 0) << (floating ? "floating" : "fixed");
    EXPECT_TRUE(std::isfinite(sink));
  }
}

// A control step (sim/control_step.hpp) sets targets and steps: none after the first call, which
// sizes its per-thread scratch, in both modes and with an observer.
TEST(ControlStepAllocations, NoneAfterTheFirstCall) {
  auto model = test::make_random_tree(17, 12, true, true, 0.01);
  Simulation sim(model, SimulationOptions{});
  std::mt19937 rng(4);
  constrain_every_joint(sim, rng);
  VecX p = 0.1 * test::random_vector(model->nv, rng);
  for (int d = 0; d < model->nv; ++d)
    if (sim.drive(d).type == DriveType::none) p[d] = 0.0;  // no target without a drive
  const VecX minus_p = -p;
  const VecX v = VecX::Zero(model->nv);
  int substeps = 0;
  const SubstepObserver count_substeps = [&](const Simulation&, int) { ++substeps; };
  step_control(sim, p, v, ControlStep{2, TargetInterpolation::linear});
  const long n = allocations_in([&] {
    step_control(sim, minus_p, v, ControlStep{4, TargetInterpolation::linear}, count_substeps);
    step_control(sim, p, v, ControlStep{3, TargetInterpolation::hold});
  });
  EXPECT_EQ(n, 0);
  EXPECT_EQ(substeps, 4);
  EXPECT_EQ(sim.step_count(), 9);
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

// Explicit actuators of every kind, with delays, on the planar chain: none after the first step
// (their delay rings are sized when they are set); every other one implicit (solved as a row),
// under PGS and TGS.
TEST(ExplicitActuatorAllocations, NoneInTheStep) {
  auto model = test::make_planar_chain(6, 1.0, 0.5);
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o;
    o.solver = solver;
    Simulation sim(model, o);
    for (int d = 0; d < model->nv; ++d) {
      ExplicitActuator a;
      a.kind = d % 3 == 0 ? ActuatorKind::ideal_pd
               : d % 3 == 1 ? ActuatorKind::dc_motor : ActuatorKind::remotized_pd;
      a.stiffness = 50.0;
      a.damping = 2.0;
      a.effort_limit = 20.0;
      if (a.kind == ActuatorKind::dc_motor) a.saturation_effort = 30.0, a.velocity_limit = 4.0;
      if (a.kind == ActuatorKind::remotized_pd) a.lookup = {{-1.0, 5.0}, {0.0, 15.0}, {1.0, 8.0}};
      a.delay = d;
      if (d % 2 == 1) a.integration = ActuatorIntegration::implicit_law;
      sim.set_actuator(d, a);
      sim.set_drive_target(d, 0.2, 0.0);
    }
    sim.step();
    EXPECT_EQ(allocations_in([&] {
                for (int k = 0; k < 30; ++k) sim.step();
              }),
              0);
    EXPECT_NE(sim.actuator_force().squaredNorm(), 0.0);
  }
}

// Ground contact and self-collision (docs/math/contact.md): a shape of each kind in turn on every
// link of a floating tree that starts half sunk into the ground, its links' shapes overlapping,
// under PGS and TGS, and a copy of such a simulation: the contact rows and reports are sized with
// the model's shapes.
TEST(ContactAllocations, NoneInTheStep) {
  Model m = *test::make_random_tree(11, 12, true, true, 0.01);
  for (int i = 0; i < m.num_links(); ++i) {
    CollisionShape s;
    s.link = i;
    constexpr ShapeType kinds[] = {ShapeType::sphere, ShapeType::capsule,   ShapeType::box,
                                   ShapeType::ellipsoid, ShapeType::cylinder, ShapeType::convex};
    s.type = kinds[i % 6];
    s.size = Vec3(0.2, 0.15, 0.1);
    if (s.type == ShapeType::convex)  // a grid of 25 points below and one above: reduced to 4
      for (int k = 0; k < 26; ++k)
        s.vertices.emplace_back(k < 25 ? Vec3(0.05 * (k % 5), 0.05 * (k / 5), -0.1)
                                       : Vec3(0, 0, 0.1));
    m.shapes.push_back(s);
  }
  // Links 2 and 8 (neither parent nor child) stand 0.54 m apart: spheres of 0.3 m overlap.
  for (const int link : {2, 8}) {
    CollisionShape s;
    s.link = link;
    s.size = Vec3(0.3, 0, 0);
    m.shapes.push_back(s);
  }
  {  // and world-aligned cubes there, whose faces meet: a manifold of several points (C29a)
    Data posed(m);
    forward_kinematics(m, posed, m.neutral_configuration());
    for (const int link : {2, 8}) {
      CollisionShape s;
      s.link = link;
      s.type = ShapeType::box;
      s.size = Vec3(0.3, 0.3, 0.3);
      s.rotation = posed.world_rotation[link].transpose();
      m.shapes.push_back(s);
    }
  }
  std::stable_sort(m.shapes.begin(), m.shapes.end(),
                   [](const CollisionShape& a, const CollisionShape& b) { return a.link < b.link; });
  auto model = std::make_shared<const Model>(m);
  Data data(*model);
  forward_kinematics(*model, data, model->neutral_configuration());
  double low = data.world_position[0].z();
  for (int i = 0; i < model->num_links(); ++i) low = std::min(low, data.world_position[i].z());
  // compat physx: TGS tracks the links' posed centres of mass through the sub-steps (C25a).
  for (const auto& [solver, compat] : {std::pair{SolverType::pgs, Compat::none},
                                       std::pair{SolverType::tgs, Compat::none},
                                       std::pair{SolverType::tgs, Compat::physx}}) {
    SimulationOptions o;
    o.solver = solver;
    o.compat = compat;
    Simulation sim(model, o);
    Ground ground;
    ground.enabled = true;
    ground.height = low + 0.1;
    sim.set_ground(ground);
    ContactOptions contact;
    contact.self_collision = true;  // the links' shapes overlap too (contact.md, section 14)
    sim.set_contact_options(contact);
    sim.step();
    int self = 0, most = 0;  // the first step's: the overlapping links then push apart
    for (const ContactReport& c : sim.contacts()) {
      if (c.other_link < 0) continue;
      ++self;
      int same = 0;  // the points of c's pair: a manifold (C29a) has several
      for (const ContactReport& d : sim.contacts())
        same += d.shape == c.shape && d.other_shape == c.other_shape ? 1 : 0;
      most = std::max(most, same);
    }
    EXPECT_GT(self, 0);
    EXPECT_GT(most, 1);
    Simulation copy = sim;
    EXPECT_EQ(allocations_in([&] {
                for (int k = 0; k < 30; ++k) sim.step();
                for (int k = 0; k < 30; ++k) copy.step();
              }),
              0);
    EXPECT_GT(sim.contacts().size(), 0u);
  }
}

}  // namespace
}  // namespace featherdrive
