// Batch's SIMD lanes: what the lane step supports, the per-lane parameters packed from
// Simulations, and the blocks run on threads (simd_lane_step.hpp). docs/simd_batch.md.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <memory>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "simd_plan.hpp"

namespace featherdrive {
struct Workspace;
struct GuardRow;
}

namespace featherdrive::simd {

/// Each environment's simulation and workspace, whose contact rows, reports and anchors the
/// lanes use as Simulation's step does (Batch fills it before a run; lane_contacts.cpp).
struct ContactLanes {
  struct Env {
    const Simulation* sim = nullptr;
    Workspace* ws = nullptr;
    /// Its step guard is on: the anchors of a step are kept once the guard keeps the step
    /// (lane_guard.cpp), not by the lane step.
    bool guarded = false;
  };
  std::vector<Env> envs;
};

/// The lanes' instruction set for `count` environments: default_simd_isa(), and without
/// FEATHERDRIVE_SIMD narrowed while a block of two vectors would hold more lanes than
/// environments (fewer padding lanes; every width gives the same bits).
SimdIsa lane_isa(int count);
/// Whether a lane group of `count` environments steps in one-lane blocks (a plain double a lane,
/// simd_lane_step_one.cpp) rather than vector blocks of lane_isa(count): a small group, where a
/// vector block's padding lanes cost more than the vectors save (docs/simd_batch.md, "One-lane
/// blocks"). Not while FEATHERDRIVE_SIMD names an instruction set.
bool one_lane_blocks(int count);

/// One environment's rows of the last lane step (Block::guard_rows: nv kGuardFields values) as
/// the step guard reads them (out: nv entries).
void unpack_guard_rows(const double* rows, int nv, std::vector<GuardRow>& out);

/// Whether two sets of mimic rows couple the same dofs in the same order.
bool same_mimic_dofs(const std::vector<MimicJoint>& a, const std::vector<MimicJoint>& b);

/// What one LaneEngine's plan fixes for all its lanes (the rest is per lane: drives, limits,
/// model parameters, gravity): the options of the step (dt, solver, iteration counts, compat),
/// the mimic rows' dofs and the links with collision shapes. Batch steps the environments that
/// agree in them as one lane group (docs/simd_batch.md, "Lane groups").
struct PlanKey {
  PlanKey(const SimulationOptions& options, const std::vector<MimicJoint>& mimic,
          const std::vector<char>& shape_links);
  /// Whether an environment of these settings belongs here (allocates nothing).
  bool matches(const SimulationOptions& options, const std::vector<MimicJoint>& mimic,
               const std::vector<char>& shape_links) const;
  double dt;
  SolverType solver;
  int position_iterations, velocity_iterations;
  Compat compat;
  /// The step guard: a guarded group steps one step a run (its guard tests each), so that the
  /// others keep many.
  bool guarded;
  std::vector<MimicJoint> mimic_joints;  ///< their dofs count (same_mimic_dofs)
  std::vector<char> shape_links;         ///< per link: it carries collision shapes
};

/// Every lane's remotized_pd tables (an implicit one's, else empty), at env * nv + dof: copies,
/// so that no lane points into a Simulation.
struct ActuatorTables {
  int nv = 0;
  std::vector<std::vector<std::pair<double, double>>> lookup;
};

class LaneEngine {
 public:
  /// `count` environments of the prototype's topology and options, each with its parameters.
  LaneEngine(const Simulation& prototype, int count);

  int size() const { return count_; }
  const Plan& plan() const { return plan_; }

  /// Whether the lanes solve contacts, the ground's or self contacts (Plan::contacts), and on
  /// which links (flags per link: those with shapes): those get their ground rows in the sweep
  /// (the self rows run before it), and their children's flags
  /// change as SweepWorkspace::set_contact_links changes them. Nothing changes when both are
  /// as they were.
  void set_contacts(bool on, const std::vector<char>& shape_links);
  /// The environments whose contact rows the lanes use (Plan::contacts).
  ContactLanes& contacts() { return contacts_; }

  /// Environment env's per-lane parameters from `sim` (same topology and options): drives
  /// (with targets) and implicit actuators (with the commands they saw last), joint limits,
  /// friction, velocity limits, wrap and mimic rows (whose dofs must be the plan's:
  /// same_mimic_dofs); its model's armature and link inertials. A link whose inertia is not
  /// diagonal makes the lanes use the general rotation for it from then on.
  void pack_drives(int env, const Simulation& sim);
  void pack_joints(int env, const Simulation& sim);
  void pack_model(int env, const Model& model);
  /// The command environment env's implicit actuator on dof sees this step (its control stage's).
  void set_command(int env, int dof, const ActuatorCommand& command);
  void pack(int env, const Simulation& sim) {
    pack_drives(env, sim);
    pack_joints(env, sim);
    pack_model(env, sim.model());
  }

  /// Whether sim's mimic rows couple the dofs the plan's do, in the same order (their gear
  /// ratios, offsets and softness may differ from lane to lane; their dofs may not).
  bool same_mimic_dofs(const Simulation& sim) const {
    return simd::same_mimic_dofs(sim.mimic_joints(), mimic_joints_);
  }

  /// Entry `index` of environment env's parameters (simd_plan.hpp's DofParameter, LinkParameter).
  double parameter(int env, int index) const { return parameters_[at(env, index)]; }
  void set_parameter(int env, int index, double value) { parameters_[at(env, index)] = value; }

  /// A run's blocks (LanePool::run): begin_run() clears stopped_now(); the blocks of W lanes
  /// (W: the isa's width times its interleave, simd::interleave; 1 for one_lane) each make
  /// `steps` steps of their environments on the state arrays and clocks `arrays` points at (its
  /// other fields are the engine's to set). An environment stopped earlier (stop(e)) stays.
  void begin_run();
  int blocks(SimdIsa isa, bool one_lane) const;
  void run_block(const Block& arrays, int block, int steps, SimdIsa isa, bool one_lane,
                 double* scratch);
  /// Why environment e stopped (quantity 0: it did not), and whether in the last run.
  const Stop& stop(int e) const { return stops_[static_cast<size_t>(e)]; }
  bool stopped_now(int e) const { return stopped_now_[static_cast<size_t>(e)]; }
  void clear_stop(int e) { stops_[static_cast<size_t>(e)] = Stop{}; }
  /// Environment e steps on: the step it stopped in is redone by its guard (docs/simd_batch.md).
  void resume(int e) {
    clear_stop(e);
    stopped_now_[static_cast<size_t>(e)] = false;
  }
  /// Environment e stops with Simulation's own DivergenceError message (its guard's redo).
  void stop_with(int e, const std::string& message);
  /// A stopped environment's reason worded as Simulation's DivergenceError, at the clock it kept.
  std::string divergence_message(int e, const Model& model, long step_count, double time) const;

 private:
  size_t at(int env, int index) const {
    return static_cast<size_t>(((env / kGroup) * plan_.entries + index) * kGroup + env % kGroup);
  }

  int count_ = 0;
  std::vector<LinkConstants> links_;
  std::vector<char> shape_links_, first_child_free_;  // per link: contacts; first_child without them
  ContactLanes contacts_;
  std::vector<int> finish_after_;
  std::vector<MimicJoint> mimic_joints_;  // the prototype's
  std::vector<MimicConstants> mimic_;
  std::vector<int> mimic_dofs_;
  Plan plan_;
  std::vector<double> parameters_;  // packed in groups of kGroup environments
  ActuatorTables tables_;
  std::vector<Stop> stops_;
  std::vector<std::string> messages_;  // per environment: stop_with's
  std::unique_ptr<bool[]> stopped_now_;
};

/// One engine's run: its state arrays (Block::rows: its lanes' rows) and instruction set.
struct LaneJob {
  LaneEngine* engine = nullptr;
  Block arrays;
  SimdIsa isa = SimdIsa::sse2;
  bool one_lane = false;  ///< one-lane blocks (one_lane_blocks), not isa's
};

/// The threads that run the blocks of several engines (Batch's lane groups) together, with a
/// scratch per thread for any of their plans.
class LanePool {
 public:
  /// `steps` steps of every job's environments, all their blocks on `threads` threads.
  void run(const std::vector<LaneJob>& jobs, int steps, int threads);
  /// f(i) for i in [0, count), on the threads of the last run (its arena), else in turn: for
  /// work each environment does on its own (the step guard's), so the same for any threads.
  template <class F>
  void each(int count, F f) {
    if (run_threads_ <= 1 || !arena_) {
      for (int i = 0; i < count; ++i) f(i);
      return;
    }
    arena_->execute([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, count), [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i < r.end(); ++i) f(i);
      });
    });
  }

 private:
  double* scratch_of(int thread);
  std::vector<std::pair<int, int>> work_;     // (job, block)
  std::vector<std::vector<double>> scratch_;  // one per thread, 64 bytes of slack for alignment
  // Kept between calls: a fresh arena makes its workers join again each call, and with a few
  // blocks a call is over before they do.
  std::unique_ptr<tbb::task_arena> arena_;
  int arena_threads_ = 0;
  int run_threads_ = 1;  // the last run's threads (its arena's, when more than one)
};

/// Batch's lane groups: environments whose plans agree (PlanKey) share one engine, lane j of
/// group g being environment members[j]; an environment the lanes refuse steps as its
/// Simulation (group -1).
struct LaneGroup {
  PlanKey key;
  std::vector<int> members;
  SimdIsa isa = SimdIsa::sse2;
  bool one_lane = false;  ///< its blocks are of one lane (one_lane_blocks), not isa's
  std::unique_ptr<LaneEngine> engine;
};
struct LaneGroups {
  std::vector<LaneGroup> groups;
  std::vector<int> group_of, lane_of;  // per environment
  std::vector<LaneJob> jobs, stepwise;  // a call's runs of many steps; of one step a run
  LanePool pool;
};

}  // namespace featherdrive::simd
