// libFuzzer: model building and stepping from fuzzed parameters. The bytes decode into a small
// tree (1 to 5 links, every joint type, extreme masses, inertias, frames and axes), solver
// settings (dt, PGS/TGS, iterations), drives (type, gains, limits, targets), joint limits,
// friction, velocity limits, envelopes, applied forces, the initial state, actuators, delays, a
// floating root's world pose, the step guard, and collision shapes with a ground. Refused
// parameters (std::invalid_argument, ModelError) and DivergenceError are fine; a crash, undefined
// behaviour, a non-finite state or contact force without an error, a diverging step that changes
// the state, a checkpoint that does not restore bit for bit, or copies of one simulation in a
// Batch (its SIMD lanes where they take it) that part are bugs.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <string>

#include "check.hpp"
#include "featherdrive/algorithm/floating_base.hpp"
#include "featherdrive/io/checkpoint.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/model/model_variant.hpp"
#include "featherdrive/sim/batch.hpp"

using namespace featherdrive;

namespace {

// Reads the fuzz bytes; past the end every read gives 0.
class Bytes {
 public:
  Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  int small(int n) { return byte() % n; }
  bool flag() { return byte() & 1; }
  /// Mostly values a person might type, some extreme, some raw bits.
  double number() {
    static constexpr double kTable[] = {
        0.0, 1.0, -1.0, 0.5, 2.0, 10.0, 100.0, 1e3, 1e6, 1e-3, 1e-6, 1e-9, 1e12, 1e-12, 1e100,
        1e-100, 1e300, -1e300, 1e308, 1e-308, 5e-324, -5e-324, -0.0,
        std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
        std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
        std::numeric_limits<double>::quiet_NaN(), 1.0 / 60.0, 3.14159, 0.1, 0.25};
    constexpr int n = sizeof(kTable) / sizeof(kTable[0]);
    const uint8_t b = byte();
    if (b < 200) return kTable[b % n];
    if (b < 240) return (b - 220) * 0.37;  // small ordinary values
    uint64_t bits = 0;
    for (int i = 0; i < 8; ++i) bits |= static_cast<uint64_t>(byte()) << (8 * i);
    return std::bit_cast<double>(bits);
  }
  /// A positive value for settings that must be positive (so most runs get past validation).
  double positive() {
    const double v = std::abs(number());
    return v > 0.0 && std::isfinite(v) ? v : 1.0;
  }
  Vec3 vec3() { return Vec3(number(), number(), number()); }

 private:
  const uint8_t* data_;
  size_t size_, pos_ = 0;
};

template <class F>
void try_set(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument&) {
  }
}

// Three copies of `sim` stepped together: the lanes give every environment the same bits
// whatever its lane (docs/simd_batch.md), so the copies stay equal, finite or stopped alike.
void batch_steps(const Simulation& sim, int steps) {
  std::optional<Batch> maybe;
  try {
    maybe.emplace(sim, 3);
  } catch (const std::invalid_argument&) {
    return;
  }
  Batch& batch = *maybe;
  const Batch& view = batch;  // reading through sim(i) const leaves the lanes' packs as they are
  batch.set_num_threads(1);
  for (int k = 0; k < steps; ++k) {
    try {
      batch.step();
    } catch (const DivergenceError&) {
    }
    for (int i = 0; i < 3; ++i) fuzz::check_finite(view.sim(i));
    for (int i = 1; i < 3; ++i)
      if (!fuzz::same_bits(view.sim(i).q(), view.sim(0).q()) ||
          !fuzz::same_bits(view.sim(i).qd(), view.sim(0).qd()) ||
          view.sim(i).step_count() != view.sim(0).step_count())
        fuzz::bug("copies of one simulation in a Batch part");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Bytes in(data, size);
  ModelBuilder builder;
  if (in.flag()) builder.set_gravity(in.vec3());
  const int n = 1 + in.small(5);
  for (int i = 0; i < n; ++i) {
    LinkSpec link;
    link.name = "link" + std::to_string(i);
    link.parent = i == 0 ? "" : "link" + std::to_string(in.small(i));
    const bool plain = in.flag();  // plain: sane inertia; otherwise fuzzed values
    link.mass = plain ? 1.0 + in.small(10) : in.number();
    link.com = plain ? Vec3(0.0, 0.0, 0.1 * in.small(4)) : in.vec3();
    if (plain) {
      link.inertia = Mat3::Identity() * 0.01 * link.mass;
    } else {
      for (int r = 0; r < 3; ++r)
        for (int c = r; c < 3; ++c) link.inertia(r, c) = link.inertia(c, r) = in.number();
    }
    const std::string joint = "joint" + std::to_string(i);
    const Vec3 xyz = plain ? Vec3(0.0, 0.0, -0.2) : in.vec3();
    const Vec3 rpy = plain ? Vec3::Zero() : in.vec3();
    const Vec3 axis = in.flag() ? Vec3::Unit(in.small(3)) : in.vec3();
    switch (in.small(i == 0 ? 3 : 4)) {
      case 0: link.joint = fixed_joint(joint, xyz, rpy); break;
      case 1: link.joint = i == 0 ? floating_joint(joint) : revolute_joint(joint, axis, xyz, rpy); break;
      case 2: link.joint = prismatic_joint(joint, axis, xyz, rpy); break;
      default: link.joint = spherical_joint(joint, xyz, rpy); break;
    }
    if (in.flag()) link.joint.armature = {in.number()};
    if (in.flag()) {
      link.joint.lower_limit = in.number();
      link.joint.upper_limit = in.number();
    }
    if (in.flag()) link.joint.velocity_limit = in.number();
    if (in.flag()) link.joint.damping = in.number();
    if (in.flag()) link.joint.friction = in.number();
    builder.add_link(std::move(link));
  }
  std::shared_ptr<const Model> model;
  try {
    model = std::make_shared<const Model>(builder.build());
  } catch (const ModelError&) {
    return 0;
  }

  SimulationOptions options;
  options.dt = in.flag() ? in.number() : 1.0 / (30 << in.small(4));
  options.solver = in.flag() ? SolverType::tgs : SolverType::pgs;
  options.position_iterations = in.small(9);      // 0 is refused
  options.velocity_iterations = in.small(4) - 1;  // -1 is refused
  std::optional<Simulation> maybe;
  try {
    maybe.emplace(model, options);
  } catch (const std::invalid_argument&) {
    options = SimulationOptions{};
    maybe.emplace(model, options);
  }
  Simulation& sim = *maybe;

  const int nq = model->nq, nv = model->nv;
  if (in.flag()) {
    VecX q(nq);
    for (int i = 0; i < nq; ++i) q[i] = in.number();
    try_set([&] { sim.set_q(q); });
  }
  if (in.flag()) {
    VecX qd(nv);
    for (int i = 0; i < nv; ++i) qd[i] = in.number();
    try_set([&] { sim.set_qd(qd); });
  }
  if (in.flag()) {
    VecX tau(nv);
    for (int i = 0; i < nv; ++i) tau[i] = in.number();
    try_set([&] { sim.set_applied_force(tau); });
  }
  // Every dof, a spherical joint's three axes included (their rows: spherical_rows.cpp).
  for (int d = 0; d < nv; ++d) {
    if (in.flag()) {
      Drive drive;
      drive.type = static_cast<DriveType>(in.small(3));
      drive.stiffness = in.number();
      drive.damping = in.number();
      if (in.flag()) drive.max_force = in.number();
      else if (in.flag()) drive.max_impulse = in.number();
      drive.target_position = in.number();
      drive.target_velocity = in.number();
      try_set([&] { sim.set_drive(d, drive); });
    }
    if (in.flag()) {
      const double lower = in.number(), upper = in.number();
      try_set([&] { sim.set_joint_limits(d, lower, upper); });
    }
    if (in.flag()) {
      const JointFriction f{in.number(), in.number(), in.number()};
      try_set([&] { sim.set_joint_friction(d, f); });
    }
    if (in.flag()) {
      const double v = in.number();
      try_set([&] { sim.set_max_joint_velocity(d, v); });
    }
    if (in.flag()) {
      const ActuatorEnvelope e{in.number(), in.number(), in.number(), in.number()};
      try_set([&] { sim.set_actuator_envelope(d, e); });
    }
  }
  fuzz::check_finite(sim);

  const int steps = 1 + in.small(6);
  for (int k = 0; k < steps; ++k) {
    if (!fuzz::checked_step(sim)) break;
    if (in.flag()) {
      // A changed target between steps, as a trajectory sets it.
      const int d = nv > 0 ? in.small(nv) : 0;
      const double p = in.number(), v = in.number();
      if (nv > 0) try_set([&] { sim.set_drive_target(d, p, v); });
    }
  }

  // Then revolute wrap and mimic rows (read last, so that older inputs decode as they did).
  if (in.flag()) {
    for (int d = 0; d < nv; ++d)
      if (in.flag()) try_set([&] { sim.set_revolute_wrap(d, RevoluteWrap::wrapped); });
    std::vector<MimicJoint> rows(static_cast<size_t>(nv > 0 ? in.small(4) : 0));
    for (MimicJoint& m : rows)
      m = {in.small(nv), in.small(nv), in.number(), in.number(), in.number(), in.number()};
    try_set([&] { sim.set_mimic_joints(rows); });
    fuzz::check_finite(sim);
    for (int k = in.small(4); k > 0; --k)
      if (!fuzz::checked_step(sim)) break;
  }

  // Then actuators (both laws, delays, feed-forward), drive delays, a floating root placed in world
  // axes and the step guard (read last, so that older inputs decode as they did).
  if (in.flag()) {
    for (int d = 0; d < nv; ++d) {
      if (in.flag()) {
        ExplicitActuator a;
        a.kind = static_cast<ActuatorKind>(in.small(4));
        a.stiffness = in.number();
        a.damping = in.number();
        if (in.flag()) a.effort_limit = in.number();
        a.saturation_effort = in.number();
        a.velocity_limit = in.number();
        if (in.flag()) a.lookup = {{in.number(), in.number()}, {in.number(), in.number()}};
        a.delay = in.small(4);
        if (in.flag()) a.integration = ActuatorIntegration::implicit_law;
        try_set([&] { sim.set_actuator(d, a); });
        const double effort = in.number();
        if (in.flag()) try_set([&] { sim.set_actuator_feedforward(d, effort); });
      }
      if (in.flag()) {
        const int delay = in.small(4);
        try_set([&] { sim.set_drive_delay(d, delay); });
      }
    }
    if (in.flag()) {
      BaseState base;
      base.position = in.vec3();
      base.orientation = Quat(in.number(), in.number(), in.number(), in.number());
      base.linear_velocity = in.vec3();
      base.angular_velocity = in.vec3();
      VecX q = sim.q(), qd = sim.qd();
      try_set([&] {
        set_base_state(*model, base, q, qd);
        sim.set_q(q);
        sim.set_qd(qd);
      });
    }
    SimulationOptions o = sim.options();
    o.guard.enabled = in.flag();
    o.guard.max_joint_step = in.flag() ? in.number() : 0.01 * (1 + in.small(30));
    // At most 8 sub-steps and 3 steps (1 is refused): an input stays cheap beside CI's build.
    o.guard.max_substeps = std::min(1 + in.small(64), 8);
    if (in.flag()) o.guard.energy_tolerance = in.number();
    if (in.flag()) o.guard.dissipation_share = in.number();
    try_set([&] { sim.set_options(o); });
    fuzz::check_finite(sim);
    for (int k = std::min(in.small(6), 3); k > 0; --k)
      if (!fuzz::checked_step(sim)) break;
  }

  // Then collision shapes (sphere, capsule, box: sizes and poses sane or fuzzed) on random links
  // and a ground (height, normal, materials, contact options), so that the steps reach the contact
  // rows (docs/math/contact.md; read last, so that older inputs decode as they did).
  if (in.flag()) {
    using Shapes = std::vector<std::pair<std::string, CollisionShape>>;
    Shapes shapes(static_cast<size_t>(1 + in.small(4)));
    auto material = [&] {
      return in.flag() ? Material{} : Material{in.number(), in.number(), in.number()};
    };
    for (auto& [link, shape] : shapes) {
      link = model->links[static_cast<size_t>(in.small(model->num_links()))].name;
      shape.type = static_cast<ShapeType>(in.small(3));
      if (in.flag()) {
        shape.size = Vec3(0.05 * (1 + in.small(4)), 0.05 * (1 + in.small(4)), 0.05 * in.small(4));
        shape.position = Vec3(0.0, 0.0, -0.1 * in.small(3));
      } else {
        shape.size = in.vec3();
        shape.position = in.vec3();
        shape.rotation = Eigen::AngleAxisd(in.number(), Vec3::Unit(in.small(3))).toRotationMatrix();
      }
      shape.material = material();
    }
    try {
      auto shaped = std::make_shared<const Model>(with_shapes(*model, shapes));
      sim.set_model(shaped);
      model = std::move(shaped);
    } catch (const ModelError&) {
    }
    Ground ground;
    ground.enabled = true;
    ground.height = in.flag() ? in.number() : -0.1 * in.small(8);
    if (in.flag()) ground.normal = in.vec3();
    ground.material = material();
    try_set([&] { sim.set_ground(ground); });
    if (in.flag()) {
      const ContactOptions c{in.number(), in.number(), in.number()};
      try_set([&] { sim.set_contact_options(c); });
    }
    fuzz::check_finite(sim);
    for (int k = 1 + in.small(4); k > 0; --k)
      if (!fuzz::checked_step(sim)) break;
  }

  // Then the simulation as it is now, three times in a Batch (read last, so that older inputs
  // decode as they did).
  if (in.flag()) batch_steps(sim, 1 + in.small(3));

  // The checkpoint of whatever state this reached restores bit for bit into a fresh simulation.
  const std::string bytes = checkpoint_bytes(sim);
  Simulation other(model);
  try {
    restore_checkpoint(bytes, other, "fuzz.ckpt");
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s\n", e.what());
    fuzz::bug("a checkpoint of a valid simulation is refused");
  }
  if (checkpoint_bytes(other) != bytes) fuzz::bug("a checkpoint does not restore bit for bit");
  return 0;
}
