// Checkpoints: a run interrupted by a checkpoint and resumed equals the uninterrupted run bit for
// bit; files that are truncated, corrupt, of another version or of another model are refused with
// a message that says so, and the simulation is left as it was.
#include "featherdrive/io/checkpoint.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "featherdrive/io/scene.hpp"
#include "featherdrive/model/model_variant.hpp"
#include "support/contact_models.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

namespace fs = std::filesystem;
using test::kInf;
using test::kExamples;

// Bitwise equality of two vectors (so -0.0 != 0.0 and NaN payloads count).
using test::same_bits;

void expect_same_state(const Simulation& a, const Simulation& b) {
  EXPECT_TRUE(same_bits(a.q(), b.q()));
  EXPECT_TRUE(same_bits(a.qd(), b.qd()));
  EXPECT_EQ(std::bit_cast<std::uint64_t>(a.time()), std::bit_cast<std::uint64_t>(b.time()));
  EXPECT_EQ(a.step_count(), b.step_count());
  EXPECT_TRUE(same_bits(a.drive_force(), b.drive_force()));
  EXPECT_TRUE(same_bits(a.limit_force(), b.limit_force()));
  EXPECT_TRUE(same_bits(a.friction_force(), b.friction_force()));
  EXPECT_TRUE(same_bits(a.velocity_limit_force(), b.velocity_limit_force()));
  for (const RowKindInfo& kind : row_kinds())
    EXPECT_TRUE(same_bits(a.row_force(kind.name), b.row_force(kind.name))) << kind.name;
}

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("featherdrive-checkpoint-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

std::string error_of(const std::string& bytes, Simulation& sim) {
  try {
    restore_checkpoint(bytes, sim, "state.ckpt");
  } catch (const CheckpointError& e) {
    return e.what();
  }
  return "(no error)";
}

// A floating random tree with spherical joints and every per-dof setting off its default.
Simulation busy_simulation(unsigned seed) {
  auto model = test::make_random_tree(seed, 6, /*floating=*/true, /*spherical=*/true, 0.01);
  SimulationOptions o;
  o.dt = 1.0 / 240.0;
  o.solver = SolverType::tgs;
  o.position_iterations = 3;
  o.velocity_iterations = 2;
  Simulation sim(model, o);
  std::mt19937 rng(seed);
  sim.set_q(test::random_configuration(*model, rng));
  sim.set_qd(test::random_vector(model->nv, rng, 0.5));
  sim.set_applied_force(test::random_vector(model->nv, rng, 0.3));
  bool impulse = false;
  for (const Link& l : model->links) {
    if (l.joint_type != JointType::revolute && l.joint_type != JointType::prismatic) continue;
    const int d = l.v_index;
    Drive drive{impulse ? DriveType::acceleration : DriveType::force, 40.0 + d, 3.0 + 0.1 * d,
                impulse ? kInf : 25.0, 0.1 * d, -0.05 * d, impulse ? 0.2 : kInf};
    impulse = !impulse;
    sim.set_drive(d, drive);
    sim.set_joint_limits(d, -0.5 - 0.01 * d, 0.7);
    sim.set_joint_friction(d, {0.02, 0.01, 0.003});
    sim.set_max_joint_velocity(d, 4.0 + d);
    sim.set_actuator_envelope(d, {30.0, 9.0, 0.5, 0.01});
    const double spring[] = {20.0 + d, 0.5, -0.1 * d};
    sim.set_row_parameters("joint_spring", d, spring);
  }
  return sim;
}

TEST(Checkpoint, RoundTripRestoresEverySetting) {
  Simulation a = busy_simulation(3);
  a.step(5);
  const std::string bytes = checkpoint_bytes(a);
  // A fresh simulation of the same model: every setting still at its default.
  Simulation b(a.model_ptr());
  restore_checkpoint(bytes, b, "state.ckpt");
  expect_same_state(a, b);
  EXPECT_EQ(b.options().dt, a.options().dt);
  EXPECT_EQ(b.options().solver, SolverType::tgs);
  EXPECT_EQ(b.options().position_iterations, 3);
  EXPECT_EQ(b.options().velocity_iterations, 2);
  EXPECT_TRUE(same_bits(b.applied_force(), a.applied_force()));
  for (int d = 0; d < a.model().nv; ++d) {
    EXPECT_EQ(b.drive(d).type, a.drive(d).type) << d;
    EXPECT_EQ(b.drive(d).stiffness, a.drive(d).stiffness) << d;
    EXPECT_EQ(b.drive(d).damping, a.drive(d).damping) << d;
    EXPECT_EQ(b.drive(d).max_force, a.drive(d).max_force) << d;
    EXPECT_EQ(b.drive(d).max_impulse, a.drive(d).max_impulse) << d;
    EXPECT_EQ(b.drive(d).target_position, a.drive(d).target_position) << d;
    EXPECT_EQ(b.drive(d).target_velocity, a.drive(d).target_velocity) << d;
    EXPECT_EQ(b.lower_limit(d), a.lower_limit(d)) << d;
    EXPECT_EQ(b.upper_limit(d), a.upper_limit(d)) << d;
    EXPECT_EQ(b.max_joint_velocity(d), a.max_joint_velocity(d)) << d;
    EXPECT_EQ(b.joint_friction(d).static_effort, a.joint_friction(d).static_effort) << d;
    EXPECT_EQ(b.joint_friction(d).dynamic_effort, a.joint_friction(d).dynamic_effort) << d;
    EXPECT_EQ(b.joint_friction(d).viscous, a.joint_friction(d).viscous) << d;
    EXPECT_EQ(b.actuator_envelope(d).max_effort, a.actuator_envelope(d).max_effort) << d;
    EXPECT_EQ(b.actuator_envelope(d).max_actuator_velocity,
              a.actuator_envelope(d).max_actuator_velocity) << d;
    EXPECT_EQ(b.actuator_envelope(d).speed_effort_gradient,
              a.actuator_envelope(d).speed_effort_gradient) << d;
    EXPECT_EQ(b.actuator_envelope(d).velocity_dependent_resistance,
              a.actuator_envelope(d).velocity_dependent_resistance) << d;
  }
  EXPECT_EQ(checkpoint_bytes(b), bytes);
}

TEST(Checkpoint, InterruptedRunEqualsUninterruptedRunBitForBit) {
  for (unsigned seed : {1u, 2u, 5u}) {
    Simulation whole = busy_simulation(seed);
    Simulation first = busy_simulation(seed);
    whole.step(40);
    first.step(17);
    const fs::path dir = temp_dir("resume");
    save_checkpoint(first, dir / "state.ckpt");
    Simulation resumed(first.model_ptr());  // defaults: the file must bring everything back
    load_checkpoint(dir / "state.ckpt", resumed);
    EXPECT_EQ(resumed.step_count(), 17);
    resumed.step(23);
    expect_same_state(whole, resumed);
    fs::remove_all(dir);
  }
}

// compat physx with PhysX's parameters away from their defaults on a floating tree (the momentum
// corrections, link damping, cfm and the transmitted-force friction all in play).
Simulation busy_physx_simulation(unsigned seed) {
  auto model = test::make_random_tree(seed, 6, /*floating=*/true, /*spherical=*/false, 0.01);
  SimulationOptions o;
  o.compat = Compat::physx;
  o.solver = seed % 2 ? SolverType::pgs : SolverType::tgs;
  Simulation sim(model, o);
  std::mt19937 rng(seed);
  sim.set_q(test::random_configuration(*model, rng));
  sim.set_qd(test::random_vector(model->nv, rng, 0.5));
  for (int i = 0; i < model->num_links(); ++i)
    sim.set_link_parameters(i, {0.01 * i, 0.1 + 0.02 * i, 0.2, 3.0 + i, 5.0});
  for (const Link& l : model->links)
    if (l.joint_type == JointType::revolute || l.joint_type == JointType::prismatic) {
      sim.set_drive(l.v_index, Drive{DriveType::force, 50.0, 4.0, kInf, 0.3, 0.0});
      sim.set_friction_coefficient(l.v_index, 0.02 * (l.v_index + 1));
    }
  return sim;
}

TEST(Checkpoint, CompatPhysxResumesBitForBitWithItsParameters) {
  for (unsigned seed : {4u, 7u}) {
    Simulation whole = busy_physx_simulation(seed);
    Simulation first = busy_physx_simulation(seed);
    whole.step(30);
    first.step(11);
    const std::string bytes = checkpoint_bytes(first);
    SimulationOptions o;
    o.compat = Compat::physx;
    Simulation resumed(first.model_ptr(), o);  // PhysX's defaults: the file must bring the rest
    restore_checkpoint(bytes, resumed, "state.ckpt");
    for (int i = 0; i < first.model().num_links(); ++i) {
      EXPECT_EQ(resumed.link_parameters(i).cfm_scale, first.link_parameters(i).cfm_scale);
      EXPECT_EQ(resumed.link_parameters(i).max_linear_velocity,
                first.link_parameters(i).max_linear_velocity);
    }
    for (int d = 0; d < first.model().nv; ++d)
      EXPECT_EQ(resumed.friction_coefficient(d), first.friction_coefficient(d));
    resumed.step(19);
    expect_same_state(whole, resumed);
    // Into a simulation of the other compat: refused, nothing changed.
    Simulation plain(first.model_ptr());
    const std::string before = checkpoint_bytes(plain);
    EXPECT_EQ(error_of(bytes, plain),
              "state.ckpt: the checkpoint is of a compat physx simulation, this simulation is "
              "compat none (compat is chosen when a simulation is made)");
    EXPECT_EQ(checkpoint_bytes(plain), before);
  }
}

TEST(Checkpoint, SceneWithSineTargetsResumesBitForBit) {
  const Scene scene = load_scene(kExamples + "arm7_tgs.yaml");
  const int n = 50, split = 21;
  Simulation whole = make_simulation(scene);
  for (int k = 0; k < n; ++k) {
    apply_targets(scene, whole, k);
    whole.step();
  }
  Simulation first = make_simulation(scene);
  for (int k = 0; k < split; ++k) {
    apply_targets(scene, first, k);
    first.step();
  }
  const std::string bytes = checkpoint_bytes(first);
  Simulation resumed = make_simulation(scene);
  restore_checkpoint(bytes, resumed, "arm7.ckpt");
  for (long k = resumed.step_count(); k < n; ++k) {
    apply_targets(scene, resumed, static_cast<int>(k));
    resumed.step();
  }
  expect_same_state(whole, resumed);
}

TEST(Checkpoint, TruncatedFilesAreRefusedAndLeaveTheSimulationAlone) {
  Simulation a = busy_simulation(4);
  a.step(3);
  const std::string bytes = checkpoint_bytes(a);
  Simulation b = busy_simulation(9);
  const std::string before = checkpoint_bytes(b);
  for (size_t size : {size_t{0}, size_t{5}, size_t{8}, size_t{20}, size_t{36}, size_t{44},
                      bytes.size() / 2, bytes.size() - 8, bytes.size() - 1}) {
    const std::string e = error_of(bytes.substr(0, size), b);
    EXPECT_NE(e.find("state.ckpt: truncated checkpoint"), std::string::npos) << size << ": " << e;
    EXPECT_EQ(checkpoint_bytes(b), before) << size;
  }
  // The file on disk, as the CLI reads it.
  const fs::path dir = temp_dir("truncated");
  write_bytes(dir / "cut.ckpt", bytes.substr(0, bytes.size() - 100));
  try {
    load_checkpoint(dir / "cut.ckpt", b);
    ADD_FAILURE() << "a truncated file loads";
  } catch (const CheckpointError& e) {
    // The header (36 bytes) and the checksum (8) frame the payload.
    EXPECT_EQ(std::string(e.what()), (dir / "cut.ckpt").string() +
                                         ": truncated checkpoint: the header announces a payload "
                                         "of " + std::to_string(bytes.size() - 44) +
                                         " bytes, the file has " +
                                         std::to_string(bytes.size() - 100));
  }
  fs::remove_all(dir);
}

TEST(Checkpoint, CorruptBytesFailTheChecksum) {
  Simulation a = busy_simulation(4);
  a.step(2);
  const std::string bytes = checkpoint_bytes(a);
  Simulation b = busy_simulation(4);
  const std::string before = checkpoint_bytes(b);
  for (size_t at : {size_t{40}, size_t{41}, bytes.size() / 2, bytes.size() - 9, bytes.size() - 1}) {
    std::string bad = bytes;
    bad[at] = static_cast<char>(bad[at] ^ 0x10);
    const std::string e = error_of(bad, b);
    EXPECT_NE(e.find("state.ckpt: corrupt checkpoint: checksum"), std::string::npos) << at << ": " << e;
    EXPECT_EQ(checkpoint_bytes(b), before);
  }
  std::string extra = bytes + "x";
  EXPECT_NE(error_of(extra, b).find("corrupt checkpoint: the header announces"), std::string::npos);
  EXPECT_NE(error_of("PK\x03\x04 not a checkpoint at all, a zip file header", b)
                .find("state.ckpt: not a featherdrive checkpoint"),
            std::string::npos);
}

TEST(Checkpoint, AnotherFormatVersionIsRefused) {
  Simulation a = busy_simulation(4);
  std::string bytes = checkpoint_bytes(a);
  bytes[8] = 1;  // the version, little-endian, right after the magic
  EXPECT_EQ(error_of(bytes, a),
            "state.ckpt: checkpoint format version 1 is not supported (this build reads versions 3 "
            "to 10)");
}

TEST(Checkpoint, AnotherModelIsRefused) {
  // Same sizes, one mass 1 ulp apart: only the fingerprint tells them apart.
  auto m1 = test::make_pendulum(1.0, 0.5);
  auto m2 = test::make_pendulum(std::nextafter(1.0, 2.0), 0.5);
  ASSERT_EQ(m1->nq, m2->nq);
  EXPECT_NE(model_fingerprint(*m1), model_fingerprint(*m2));
  EXPECT_EQ(model_fingerprint(*m1), model_fingerprint(*test::make_pendulum(1.0, 0.5)));
  Simulation s1(m1), s2(m2);
  s2.set_qd(VecX::Constant(1, 0.25));
  const std::string before = checkpoint_bytes(s2);
  const std::string e = error_of(checkpoint_bytes(s1), s2);
  EXPECT_NE(e.find("state.ckpt: the checkpoint is of a different model (nq 1, nv 1, fingerprint 0x"),
            std::string::npos) << e;
  EXPECT_NE(e.find("; this model: nq 1, nv 1, fingerprint 0x"), std::string::npos) << e;
  EXPECT_EQ(checkpoint_bytes(s2), before);

  // Different sizes: the URDF slider against the 3-link chain.
  const Scene slider = load_scene(kExamples + "slider.yaml");
  const Scene chain = load_scene(kExamples + "chain3.yaml");
  Simulation sc = make_simulation(chain);
  const std::string e2 = error_of(checkpoint_bytes(make_simulation(slider)), sc);
  EXPECT_NE(e2.find("the checkpoint is of a different model (nq 1, nv 1,"), std::string::npos) << e2;
  EXPECT_NE(e2.find("this model: nq 3, nv 3,"), std::string::npos) << e2;
}

TEST(Checkpoint, SavingIsAtomicAndLeavesNoTemporaryFiles) {
  const fs::path dir = temp_dir("atomic");
  Simulation a = busy_simulation(6);
  save_checkpoint(a, dir / "s.ckpt");
  a.step();
  save_checkpoint(a, dir / "s.ckpt");  // replaces the file
  EXPECT_EQ(read_bytes(dir / "s.ckpt"), checkpoint_bytes(a));
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "s.ckpt");
  }
  EXPECT_EQ(files, 1);
  EXPECT_THROW(save_checkpoint(a, dir / "no-such-folder" / "s.ckpt"), std::runtime_error);
  try {
    load_checkpoint(dir / "missing.ckpt", a);
    ADD_FAILURE() << "a missing file loads";
  } catch (const CheckpointError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.ckpt: cannot open the checkpoint"),
              std::string::npos);
  }
  fs::remove_all(dir);
}

// Forging: `bytes` with `size` bytes at `at` set to `value` (little-endian) and the checksum
// (FNV-1a 64 of everything before it) computed again, so only the field's check can refuse it.
std::string forged(std::string bytes, size_t at, std::uint64_t value, size_t size = 8) {
  for (size_t i = 0; i < size; ++i) bytes[at + i] = static_cast<char>(value >> (8 * i));
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (size_t i = 0; i + 8 < bytes.size(); ++i) {
    h ^= static_cast<unsigned char>(bytes[i]);
    h *= 0x100000001b3ULL;
  }
  for (size_t i = 0; i < 8; ++i) bytes[bytes.size() - 8 + i] = static_cast<char>(h >> (8 * i));
  return bytes;
}
std::uint64_t bits(double v) {
  return std::bit_cast<std::uint64_t>(v);
}

// Version 8's ground and contact options (a byte and 10 doubles), then (the model has no shapes)
// version 9's self_collision byte, then version 10's row kinds, last before the checksum.
constexpr size_t kContactBytes = 1 + 10 * 8;
constexpr size_t kSelfCollisionBytes = 1;

// Version 10's row kinds of a model of nv dofs, as checkpoint.hpp lays them out: their count, then
// each kind's name, field names, values (nv x fields) and forces (nv).
size_t row_kind_bytes(size_t nv) {
  size_t n = 4;
  for (const RowKindInfo& kind : row_kinds()) {
    n += 8 + kind.name.size() + 4;
    for (const RowField& f : kind.fields) n += 8 + f.name.size();
    n += 8 * nv * (kind.fields.size() + 1);
  }
  return n;
}
// The header's nv (a u32 at byte 24).
size_t header_nv(const std::string& bytes) {
  size_t nv = 0;
  for (size_t i = 0; i < 4; ++i) nv |= static_cast<size_t>(static_cast<unsigned char>(bytes[24 + i])) << (8 * i);
  return nv;
}

// The checkpoint as an older version wrote it: the last `tail` bytes of the payload before
// version 10's row kinds dropped, and those.
std::string as_version(std::string bytes, std::uint64_t version, size_t tail) {
  tail += row_kind_bytes(header_nv(bytes));
  bytes.erase(bytes.size() - 8 - tail, tail);
  std::uint64_t payload = 0;
  for (size_t i = 0; i < 8; ++i)
    payload |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[28 + i])) << (8 * i);
  return forged(forged(bytes, 8, version, 4), 28, payload - tail);
}
std::string as_version7(const std::string& bytes) {
  return as_version(bytes, 7, kContactBytes + kSelfCollisionBytes);
}

// The payload after the 36-byte header: time, step count, dt, solver (1 byte), the iterations,
// compat (1 byte), q, qd, applied forces, then per dof its drive type (1 byte) and 17 doubles.
constexpr size_t kTime = 36, kSteps = 44, kDt = 52, kSolver = 60, kPositionIterations = 61,
                 kVelocityIterations = 69, kCompat = 77, kQ = 78;

TEST(Checkpoint, ForgedFieldsWithAValidChecksumAreRefusedNamingTheFieldAndValue) {
  Simulation a = busy_simulation(4);
  a.step(3);
  const std::string bytes = checkpoint_bytes(a);
  ASSERT_EQ(forged(bytes, kTime, bits(a.time())), bytes);  // the helper forges nothing by itself
  Simulation b = busy_simulation(4);                       // the same model, another state
  b.step();
  const std::string before = checkpoint_bytes(b);
  const Model& m = a.model();
  const size_t dof0 = kQ + 8 * static_cast<size_t>(m.nq + 2 * m.nv);  // dof 0's drive type
  struct Case {
    size_t at;
    std::uint64_t value;
    size_t size;
    std::string error;
  };
  const std::string clock = " is not one a run reaches (finite, >= 0, at most 2 * steps * 1000 s)";
  const Case cases[] = {
      {kSteps, 0x7fffffffffffffffULL, 8,
       "corrupt checkpoint: step count 9223372036854775807 is outside [0, 9007199254740992]"},
      {kSteps, (1ULL << 53) + 1, 8,
       "corrupt checkpoint: step count 9007199254740993 is outside [0, 9007199254740992]"},
      {kSteps, ~0ULL, 8, "corrupt checkpoint: step count -1 is outside [0, 9007199254740992]"},
      {kTime, bits(1e308), 8, "corrupt checkpoint: time 1e+308 s after 3 steps" + clock},
      {kTime, bits(6000.5), 8, "corrupt checkpoint: time 6000.5 s after 3 steps" + clock},
      {kTime, bits(kInf), 8, "corrupt checkpoint: time inf s after 3 steps" + clock},
      {kTime, bits(std::nan("")), 8, "corrupt checkpoint: time nan s after 3 steps" + clock},
      {kTime, bits(-0.5), 8, "corrupt checkpoint: time -0.5 s after 3 steps" + clock},
      {kDt, bits(1e-310), 8,
       "bad value in the checkpoint: simulation options: dt = 1e-310 must "
       "be a normal number in [2.2250738585072014e-308, 1000] s"},
      {kDt, bits(1e308), 8,
       "bad value in the checkpoint: simulation options: dt = 1e+308 must "
       "be a normal number in [2.2250738585072014e-308, 1000] s"},
      {kSolver, 7, 1, "corrupt checkpoint: solver = 7"},
      {kCompat, 9, 1, "corrupt checkpoint: compat = 9"},
      {kPositionIterations, 0, 8,
       "corrupt checkpoint: position_iterations 0 is outside [1, 1000000]"},
      {kPositionIterations, 1ULL << 32, 8,
       "corrupt checkpoint: position_iterations 4294967296 is outside [1, 1000000]"},
      {kVelocityIterations, ~0ULL, 8,
       "corrupt checkpoint: velocity_iterations -1 is outside [0, 1000000]"},
      {kQ, bits(std::nan("")), 8, "bad value in the checkpoint: q[0] = nan is not finite"},
      {dof0, 3, 1, "corrupt checkpoint: drive type 3 of dof 0"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(error_of(forged(bytes, c.at, c.value, c.size), b), "state.ckpt: " + c.error);
    EXPECT_EQ(checkpoint_bytes(b), before);
  }
  // The largest clock a run can reach loads.
  Simulation c = busy_simulation(4);
  restore_checkpoint(forged(forged(bytes, kSteps, 1ULL << 53), kTime, bits(1e19)), c, "big");
  EXPECT_EQ(c.step_count(), 1L << 53);
  EXPECT_EQ(c.time(), 1e19);
}

// Per-dof and per-link settings go through the setters; settings a joint cannot have must be the
// simulation's own.
TEST(Checkpoint, ForgedJointAndLinkSettingsAreRefused) {
  Simulation a = busy_simulation(4);
  const std::string bytes = checkpoint_bytes(a);
  const Model& m = a.model();
  const size_t dofs = kQ + 8 * static_cast<size_t>(m.nq + 2 * m.nv);
  const auto field = [&](int dof, int k) {
    return dofs + 137 * static_cast<size_t>(dof) + 1 + 8 * k;
  };
  int one = -1, multi = -1;  // a revolute/prismatic dof and one of the floating root
  for (int d = 0; d < m.nv; ++d) {
    const JointType t = m.links[m.dof_link[d]].joint_type;
    if (one < 0 && (t == JointType::revolute || t == JointType::prismatic)) one = d;
    if (multi < 0 && t == JointType::floating) multi = d;
  }
  ASSERT_GE(one, 0);
  ASSERT_GE(multi, 0);
  const std::string joint = m.links[m.dof_link[one]].joint_name;
  // Fields: 0..5 the drive's doubles, 6 lower, 7 upper, 8 max velocity, 9..11 friction.
  EXPECT_EQ(error_of(forged(bytes, field(one, 6), bits(kInf)), a),
            "state.ckpt: bad value in the checkpoint: limits on joint '" + joint +
                "': lower = inf leaves no position");
  EXPECT_EQ(error_of(forged(bytes, field(one, 7), bits(-kInf)), a),
            "state.ckpt: bad value in the checkpoint: limits on joint '" + joint +
                "': upper = -inf leaves no position");
  EXPECT_NE(error_of(forged(bytes, field(one, 0), bits(-1.0)), a).find("stiffness = -1"),
            std::string::npos);
  EXPECT_NE(error_of(forged(bytes, field(one, 9), bits(std::nan(""))), a).find("static_effort"),
            std::string::npos);
  EXPECT_EQ(error_of(forged(bytes, field(multi, 6), bits(0.0)), a),
            "state.ckpt: corrupt checkpoint: dof " + std::to_string(multi) +
                " of floating joint '" + m.links[m.dof_link[multi]].joint_name +
                "' has joint setting #0 = 0, which only a revolute, prismatic or spherical "
                "joint can change");
  // Link parameters follow the per-dof block: the first link's cfm_scale of 2 is out of [0, 1].
  const size_t links = dofs + 137 * static_cast<size_t>(m.nv);
  EXPECT_NE(error_of(forged(bytes, links, bits(2.0)), a).find("cfm_scale"), std::string::npos);
}

TEST(Checkpoint, TheClockAcceptsOnlyWhatARunReaches) {
  Simulation s(test::make_pendulum(1.0, 0.5));
  EXPECT_THROW(s.set_clock(0.5, 0), std::invalid_argument);  // time passes only with steps
  EXPECT_THROW(s.set_clock(2001.0, 1), std::invalid_argument);
  EXPECT_THROW(s.set_clock(1.0, kMaxStepCount + 1), std::invalid_argument);
  EXPECT_THROW(s.set_clock(1e308, kMaxStepCount), std::invalid_argument);
  s.set_clock(2000.0, 1);
  s.set_clock(0.0, kMaxStepCount);
  EXPECT_EQ(s.step_count(), kMaxStepCount);
  s.step();  // the count and the clock go on without overflow
  EXPECT_EQ(s.step_count(), kMaxStepCount + 1);
}

TEST(Checkpoint, ClockAndSetStateValidateTheirArguments) {
  Simulation s(test::make_random_tree(2, 3, true));
  EXPECT_THROW(s.set_clock(-1.0, 0), std::invalid_argument);
  EXPECT_THROW(s.set_clock(std::nan(""), 0), std::invalid_argument);
  EXPECT_THROW(s.set_clock(kInf, 0), std::invalid_argument);
  EXPECT_THROW(s.set_clock(0.0, -1), std::invalid_argument);
  s.set_clock(2.5, 150);
  EXPECT_EQ(s.time(), 2.5);
  EXPECT_EQ(s.step_count(), 150);
  const int nv = s.model().nv;
  const State good = s.state();
  // set_state refuses the state with a message containing `word`.
  auto expect_refused = [&](const State& bad, const char* word) {
    try {
      s.set_state(bad);
      ADD_FAILURE() << "restored a state that should be refused for " << word;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  State bad = good;
  bad.q[3] = 2.0;  // the floating root's quaternion w: norm 2
  expect_refused(bad, "has norm 2, expected 1");
  bad = good;
  bad.drive_force = VecX::Zero(nv + 1);
  expect_refused(bad, "drive_force");
  bad = good;
  bad.limit_force[0] = std::nan("");
  expect_refused(bad, "limit_force");
  EXPECT_EQ(s.q()[3], 1.0);
}

// Three actuators of the kinds ideal_pd, dc_motor and remotized_pd on dofs 0-2 of a 3-dof
// chain, from `pd`'s gains and delay, their limits scaled by `scale`.
void set_three_actuators(Simulation& sim, const ExplicitActuator& pd, double scale) {
  ExplicitActuator motor = pd;
  motor.kind = ActuatorKind::dc_motor;
  motor.saturation_effort = 9.0 * scale;
  motor.velocity_limit = 2.0;
  motor.delay = 1;
  ExplicitActuator table = pd;
  table.kind = ActuatorKind::remotized_pd;
  table.effort_limit = kInf;
  table.lookup = {{-0.5, 2.0 * scale}, {0.5, 5.0 * scale}};
  sim.set_actuator(0, pd);
  sim.set_actuator(1, motor);
  sim.set_actuator(2, table);
}

// Step k's commands of the three actuators.
void command_three_actuators(Simulation& sim, int k) {
  for (int d = 0; d < 3; ++d) {
    sim.set_drive_target(d, 0.3 * std::sin(0.4 * k + d), 0.1 * d);
    sim.set_actuator_feedforward(d, 0.05 * k - d);
  }
}

// Explicit actuators with delays resume bit for bit: their settings, feed-forward, delay rings
// and push counts are in the checkpoint (version 3).
TEST(Checkpoint, ExplicitActuatorsResumeWithTheirDelayHistories) {
  auto model = test::make_planar_chain(3, 1.0, 0.5);
  auto setup = [&] {
    Simulation sim(model);
    ExplicitActuator pd;
    pd.kind = ActuatorKind::ideal_pd;
    pd.stiffness = 40.0;
    pd.damping = 2.0;
    pd.effort_limit = 6.0;
    pd.delay = 3;
    set_three_actuators(sim, pd, 1.0);
    return sim;
  };
  const auto command = command_three_actuators;
  Simulation run = setup();
  for (int k = 0; k < 10; ++k) command(run, k), run.step();
  const std::string bytes = checkpoint_bytes(run);
  Simulation resumed(model);  // no actuators: the checkpoint brings them
  resumed.set_drive(1, Drive{DriveType::force, 5.0, 1.0});  // and clears what is not in it
  restore_checkpoint(bytes, resumed, "state.ckpt");
  EXPECT_EQ(checkpoint_bytes(resumed), bytes);
  EXPECT_EQ(resumed.actuators().pushes(0), 10);
  EXPECT_EQ(resumed.actuator_force(), run.actuator_force());
  for (int k = 10; k < 20; ++k)
    for (Simulation* s : {&run, &resumed}) command(*s, k), s->step();
  for (int i = 0; i < 3; ++i) {
    using std::bit_cast;
    EXPECT_EQ(bit_cast<std::uint64_t>(resumed.q()[i]), bit_cast<std::uint64_t>(run.q()[i]));
    EXPECT_EQ(bit_cast<std::uint64_t>(resumed.qd()[i]), bit_cast<std::uint64_t>(run.qd()[i]));
    EXPECT_EQ(resumed.actuator_force()[i], run.actuator_force()[i]);
  }
}

// Delayed implicit drives resume bit for bit mid-delay: the pending targets (ring and push count)
// are in the checkpoint (version 4). Without them the resumed run would differ: checked too.
TEST(Checkpoint, DriveDelaysResumeMidDelayWithTheirPendingTargets) {
  auto model = test::make_planar_chain(3, 1.0, 0.5);
  const int delays[] = {3, 0, 5};
  auto setup = [&] {
    Simulation sim(model);
    for (int d = 0; d < 3; ++d) {
      sim.set_drive(d, Drive{DriveType::force, 300.0, 15.0});
      sim.set_drive_delay(d, delays[d]);
    }
    return sim;
  };
  auto command = [](Simulation& sim, int k) {
    for (int d = 0; d < 3; ++d) sim.set_drive_target(d, 0.3 * std::sin(0.4 * k + d), 0.1 * d);
  };
  Simulation run = setup();
  for (int k = 0; k < 10; ++k) command(run, k), run.step();
  const std::string bytes = checkpoint_bytes(run);
  Simulation resumed(model);  // no drives, no delays: the checkpoint brings them
  Simulation naive = setup();  // the same delays with an empty history
  naive.set_drive_delay(1, 2);  // cleared by the restore, as it is not in the checkpoint
  restore_checkpoint(bytes, resumed, "state.ckpt");
  EXPECT_EQ(checkpoint_bytes(resumed), bytes);
  EXPECT_EQ(resumed.drive_delay(2), 5);
  EXPECT_EQ(resumed.drive_delays().pushes(2), 10);
  restore_checkpoint(bytes, naive, "state.ckpt");
  for (int d = 0; d < 3; ++d) naive.set_drive_delay(d, delays[d]);  // forgets the pending targets
  for (int k = 10; k < 20; ++k)
    for (Simulation* s : {&run, &resumed, &naive}) command(*s, k), s->step();
  expect_same_state(run, resumed);
  EXPECT_FALSE(same_bits(naive.q(), run.q()));
}

// The step guard's account (version 7), last before the checksum: three doubles, zero when the
// guard never ran.
constexpr size_t kAccountBytes = 24;

// Version 3 (before drive delays) is still read: a version-4 file without delays is version 3's
// bytes plus one zero delay per dof.
TEST(Checkpoint, VersionThreeIsStillRead) {
  Simulation a = busy_simulation(5);
  for (int d = 0; d < a.model().nv; ++d)  // not in a version 3 file
    if (dof_has_rows(a.model(), d)) a.set_row_parameters("joint_spring", d, std::vector<double>(3, 0.0));
  a.step(4);
  std::string bytes = as_version7(checkpoint_bytes(a));
  const size_t delays = 8 * static_cast<size_t>(a.model().nv);
  ASSERT_EQ(header_nv(bytes), static_cast<size_t>(a.model().nv));
  // Version 5's revolute wrap (a byte per dof) and mimic joints (their count), then version 7's
  // guard account, come last.
  const size_t coupling = static_cast<size_t>(a.model().nv) + 8 + kAccountBytes;
  ASSERT_EQ(bytes.substr(bytes.size() - 8 - coupling - delays, coupling + delays),
            std::string(coupling + delays, '\0'));
  bytes.erase(bytes.size() - 8 - coupling - delays, coupling + delays);
  std::uint64_t payload = 0;
  for (size_t i = 0; i < 8; ++i)
    payload |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[28 + i])) << (8 * i);
  const std::string v3 = forged(forged(bytes, 8, 3, 4), 28, payload - coupling - delays);
  Simulation b(a.model_ptr());
  int driven = -1;
  for (const Link& l : b.model().links)
    if (l.joint_type == JointType::revolute || l.joint_type == JointType::prismatic)
      driven = l.v_index;
  ASSERT_GE(driven, 0);
  b.set_drive(driven, Drive{DriveType::force, 1.0, 1.0});
  b.set_drive_delay(driven, 2);  // not in a version 3 file: cleared
  restore_checkpoint(v3, b, "old.ckpt");
  expect_same_state(a, b);
  EXPECT_EQ(checkpoint_bytes(b), checkpoint_bytes(a));
  // A forged delay is refused naming the dof.
  const std::string v7 = as_version7(checkpoint_bytes(a));
  const std::string bad = forged(v7, v7.size() - 8 - coupling - delays, ~0ULL);
  EXPECT_EQ(error_of(bad, b),
            "state.ckpt: corrupt checkpoint: drive delay -1 of dof 0 is outside [0, 100000]");
  // A forged push count that a later push would overflow.
  Simulation c = busy_simulation(5);
  c.set_drive_delay(driven, 1);
  c.step();
  const std::string with_delay = as_version7(checkpoint_bytes(c));
  // The delays: 8 bytes per dof, and for `driven` its push count and 2 targets after them.
  const size_t delays_at = with_delay.size() - 8 - coupling - (delays + 8 + 32);
  const size_t pushes_at = delays_at + 8 * static_cast<size_t>(driven) + 8;
  EXPECT_EQ(error_of(forged(with_delay, pushes_at, 0x7fffffffffffffffULL), c),
            "state.ckpt: bad value in the checkpoint: drive delay history of dof " +
                std::to_string(driven) + ": pushes = 9223372036854775807 must be in [0, 2^53]");
}

// Implicit actuators (docs/math/implicit_actuators.md) of each kind, with delays, under TGS: the
// integration is in the checkpoint (version 6) and the resumed run equals the uninterrupted one
// bit for bit.
TEST(Checkpoint, ImplicitActuatorsResumeBitForBit) {
  auto model = test::make_planar_chain(3, 1.0, 0.5);
  auto setup = [&] {
    SimulationOptions o;
    o.solver = SolverType::tgs;
    o.position_iterations = 3;
    Simulation sim(model, o);
    ExplicitActuator pd;
    pd.kind = ActuatorKind::ideal_pd;
    pd.stiffness = 4e4;  // kp dt^2 / m of order 10: the explicit law would diverge
    pd.damping = 20.0;
    pd.effort_limit = 600.0;
    pd.delay = 2;
    pd.integration = ActuatorIntegration::implicit_law;
    set_three_actuators(sim, pd, 10.0);
    return sim;
  };
  const auto command = command_three_actuators;
  Simulation run = setup();
  for (int k = 0; k < 10; ++k) command(run, k), run.step();
  const std::string bytes = checkpoint_bytes(run);
  Simulation resumed(model, run.options());
  restore_checkpoint(bytes, resumed, "state.ckpt");
  EXPECT_EQ(checkpoint_bytes(resumed), bytes);
  for (int d = 0; d < 3; ++d)
    EXPECT_EQ(resumed.actuator(d).integration, ActuatorIntegration::implicit_law) << d;
  for (int k = 10; k < 30; ++k)
    for (Simulation* s : {&run, &resumed}) command(*s, k), s->step();
  expect_same_state(run, resumed);
  EXPECT_TRUE(same_bits(resumed.actuator_force(), run.actuator_force()));
  EXPECT_NE(run.actuator_force().squaredNorm(), 0.0);
}

// Version 5 (before the integration) is still read, every actuator as explicit: version 6's bytes
// without the integration byte after each actuator's kind.
TEST(Checkpoint, VersionFiveActuatorsReadAsExplicit) {
  auto model = test::make_planar_chain(2, 1.0, 0.5);
  Simulation a(model);
  ExplicitActuator pd;
  pd.kind = ActuatorKind::ideal_pd;
  pd.stiffness = 30.0;
  pd.delay = 1;
  a.set_actuator(0, pd);
  a.set_actuator(1, pd);
  a.set_drive_target(1, 0.2, 0.0);
  a.step(3);
  const std::string bytes = as_version7(checkpoint_bytes(a));
  const size_t nv = 2;
  // From the end: checksum, mimic count, wrap bytes, drive delays, actuator forces; before them
  // each actuator: kind, integration, 5 settings, delay, table size, feed-forward, pushes and a
  // ring of 2 commands.
  const size_t per_actuator = 1 + 1 + 5 * 8 + 8 + 8 + 8 + 8 + 2 * 24;
  const size_t first =
      bytes.size() - 8 - kAccountBytes - 8 - nv - 8 * nv - 8 * nv - 2 * per_actuator;
  ASSERT_EQ(bytes[first], static_cast<char>(ActuatorKind::ideal_pd));
  ASSERT_EQ(bytes[first + per_actuator], static_cast<char>(ActuatorKind::ideal_pd));
  std::string v5 = bytes;
  v5.erase(v5.size() - 8 - kAccountBytes, kAccountBytes);  // version 7's, last
  v5.erase(first + per_actuator + 1, 1);  // the later one first: the offsets before it stay
  v5.erase(first + 1, 1);
  std::uint64_t payload = 0;
  for (size_t i = 0; i < 8; ++i)
    payload |= static_cast<std::uint64_t>(static_cast<unsigned char>(v5[28 + i])) << (8 * i);
  v5 = forged(forged(v5, 8, 5, 4), 28, payload - 2 - kAccountBytes);
  Simulation b(model);
  ExplicitActuator late = pd;
  late.integration = ActuatorIntegration::implicit_law;
  b.set_actuator(0, late);  // replaced by the file's explicit one
  restore_checkpoint(v5, b, "old.ckpt");
  expect_same_state(a, b);
  EXPECT_EQ(b.actuator(0).integration, ActuatorIntegration::explicit_law);
  EXPECT_EQ(checkpoint_bytes(b), checkpoint_bytes(a));
  // A forged integration is refused naming the dof.
  EXPECT_EQ(error_of(forged(bytes, first + 1, 7, 1), b),
            "state.ckpt: corrupt checkpoint: actuator integration 7 of dof 0");
}

// A guarded run: the guard's account (test (iii), docs/math/step_guard.md) is in the checkpoint
// (version 7), so the resumed run redoes the same steps and equals the uninterrupted one bit for
// bit; a version 6 file reads with an empty account; a forged account is refused.
// Contacts keep their friction anchors from step to step (docs/math/contact.md, C9): the
// quadruped standing on the ground resumes bit for bit, PGS and TGS, and a version 7 file (no
// anchors) resumes with none kept.
TEST(Checkpoint, ContactRunResumesBitForBit) {
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation run = test::quadruped_simulation(solver, 0.0);
    run.step(30);
    int kept = 0;
    for (const FrictionAnchors& a : run.state().friction_anchors) kept += a.count;
    ASSERT_GT(kept, 0);
    const std::string bytes = checkpoint_bytes(run);
    Simulation resumed = test::quadruped_simulation(solver, 0.0);
    restore_checkpoint(bytes, resumed, "state.ckpt");
    EXPECT_EQ(checkpoint_bytes(resumed), bytes);
    for (int k = 0; k < 40; ++k) run.step(), resumed.step();
    expect_same_state(run, resumed);
    ASSERT_EQ(run.contacts().size(), resumed.contacts().size());
    for (size_t c = 0; c < run.contacts().size(); ++c)
      EXPECT_EQ(bits(run.contacts()[c].normal_impulse), bits(resumed.contacts()[c].normal_impulse));
    // Without the anchors (as a version 7 file resumes) the run differs.
    Simulation fresh = test::quadruped_simulation(solver, 0.0);
    restore_checkpoint(bytes, fresh, "state.ckpt");
    State s = fresh.state();
    s.friction_anchors.clear();
    fresh.set_state(s);
    fresh.step(40);
    EXPECT_NE(bits(fresh.q()[2]), bits(run.q()[2]));
  }
}

TEST(Checkpoint, GuardedRunResumesBitForBit) {
  auto model = test::make_planar_chain(4, 1.0, 0.5);
  SimulationOptions o;
  o.guard.enabled = true;
  o.guard.max_joint_step = 0.05;  // the first steps from rest are redone
  Simulation run(model, o);
  for (int d = 0; d < model->nv; ++d) {
    run.set_drive(d, Drive{DriveType::force, 400.0, 20.0});
    run.set_drive_target(d, 0.6 * (d % 2 ? 1.0 : -1.0), 0.0);
  }
  run.step(15);
  ASSERT_GT(run.guard_triggers(), 0);
  ASSERT_GT(run.guard_account().scale, 0.0);
  ASSERT_GT(run.guard_account().dissipated, 0.0);
  const std::string bytes = checkpoint_bytes(run);
  Simulation resumed(model, o);
  restore_checkpoint(bytes, resumed, "state.ckpt");
  EXPECT_EQ(checkpoint_bytes(resumed), bytes);
  const long before = run.guard_triggers();
  for (int k = 0; k < 40; ++k) run.step(), resumed.step();
  expect_same_state(run, resumed);
  EXPECT_EQ(resumed.guard_triggers(), run.guard_triggers() - before);  // counters: not kept
  EXPECT_TRUE(same_bits(resumed.drive_force(), run.drive_force()));
  const GuardAccount& a = run.guard_account(), &b = resumed.guard_account();
  EXPECT_EQ(bits(a.created), bits(b.created));
  EXPECT_EQ(bits(a.dissipated), bits(b.dissipated));
  EXPECT_EQ(bits(a.scale), bits(b.scale));
  // Version 6: the same bytes without the account.
  std::string v6 = as_version7(bytes);
  v6.erase(v6.size() - 8 - kAccountBytes, kAccountBytes);
  std::uint64_t payload = 0;
  for (size_t i = 0; i < 8; ++i)
    payload |= static_cast<std::uint64_t>(static_cast<unsigned char>(v6[28 + i])) << (8 * i);
  v6 = forged(forged(v6, 8, 6, 4), 28, payload - kAccountBytes);
  Simulation old(model, o);
  State with_account = old.state();
  with_account.guard_account = {1.0, 2.0, 3.0};
  old.set_state(with_account);
  ASSERT_EQ(old.guard_account().scale, 3.0);
  restore_checkpoint(v6, old, "old.ckpt");
  EXPECT_EQ(old.guard_account().created, 0.0);
  EXPECT_EQ(old.guard_account().dissipated, 0.0);
  EXPECT_EQ(old.guard_account().scale, 0.0);
  // A negative dissipation is refused in one line.
  const std::string v7 = as_version7(bytes);
  const std::string bad = forged(v7, v7.size() - 8 - 16, std::bit_cast<std::uint64_t>(-1.0));
  EXPECT_EQ(error_of(bad, old),
            "state.ckpt: bad value in the checkpoint: guard account: dissipated = -1 must be "
            "finite and >= 0");
}

// The ground and the contact options are in the checkpoint (version 8): a resumed simulation
// has them, and its checkpoint is the same bytes; a version 7 file keeps the simulation's own.
TEST(Checkpoint, GroundAndContactOptionsAreKept) {
  auto model = test::make_planar_chain(2, 1.0, 0.5);
  Simulation a(model);
  Ground ground;
  ground.enabled = true;
  ground.height = -0.25;
  ground.normal = Vec3(0.0, 0.6, 0.8);
  ground.material = Material{0.9, 0.7, 0.1};
  a.set_ground(ground);
  a.set_contact_options(ContactOptions{0.03, 0.001, 1.5, true});
  a.step(3);
  const std::string bytes = checkpoint_bytes(a);
  Simulation b(model);
  restore_checkpoint(bytes, b, "state.ckpt");
  EXPECT_EQ(checkpoint_bytes(b), bytes);
  EXPECT_TRUE(b.ground().enabled);
  EXPECT_EQ(bits(b.ground().height), bits(-0.25));
  EXPECT_EQ(bits(b.ground().normal.y()), bits(a.ground().normal.y()));
  EXPECT_EQ(b.ground().material.dynamic_friction, 0.7);
  EXPECT_EQ(b.ground().material.restitution, 0.1);
  EXPECT_EQ(b.contact_options().contact_offset, 0.03);
  EXPECT_EQ(b.contact_options().rest_offset, 0.001);
  EXPECT_EQ(b.contact_options().bounce_threshold, 1.5);
  EXPECT_TRUE(b.contact_options().self_collision);
  // Version 8: self-collision off, the rest kept.
  Simulation d(model);
  restore_checkpoint(as_version(bytes, 8, kSelfCollisionBytes), d, "v8.ckpt");
  EXPECT_FALSE(d.contact_options().self_collision);
  EXPECT_EQ(d.contact_options().bounce_threshold, 1.5);
  // Version 7: the simulation keeps its own ground and options.
  Simulation c(model);
  Ground other;
  other.enabled = true;
  other.height = 3.0;
  c.set_ground(other);
  restore_checkpoint(as_version7(bytes), c, "old.ckpt");
  EXPECT_EQ(c.ground().height, 3.0);
  EXPECT_EQ(c.contact_options().contact_offset, ContactOptions{}.contact_offset);
  expect_same_state(a, c);
  // A forged ground is refused in one line.
  const size_t kinds = row_kind_bytes(header_nv(bytes));
  const size_t height_at = bytes.size() - 8 - kinds - kSelfCollisionBytes - kContactBytes + 1;
  EXPECT_EQ(error_of(forged(bytes, height_at, bits(std::numeric_limits<double>::infinity())), b),
            "state.ckpt: bad value in the checkpoint: ground.height = inf is not finite");
  const size_t offset_at = bytes.size() - 8 - kinds - kSelfCollisionBytes - 24;
  EXPECT_EQ(error_of(forged(bytes, offset_at, bits(-1.0)), b),
            "state.ckpt: bad value in the checkpoint: contact.contact_offset = -1, rest_offset = "
            "0.001: need 0 <= rest_offset < contact_offset");
}

// Shapes make the model: a checkpoint of a model with other shapes is refused; a model without
// shapes keeps the fingerprint it had before shapes existed (older checkpoints still load).
TEST(Checkpoint, ShapesArePartOfTheModelFingerprint) {
  const auto plain = test::make_pendulum(1.0, 0.5);
  CollisionShape ball;
  ball.type = ShapeType::sphere;
  ball.size = Vec3(0.1, 0.0, 0.0);
  const std::string link = plain->links.back().name;
  const auto a = std::make_shared<const Model>(with_shapes(*plain, {{link, ball}}));
  ball.size.x() = std::nextafter(0.1, 1.0);
  const auto b = std::make_shared<const Model>(with_shapes(*plain, {{link, ball}}));
  EXPECT_NE(model_fingerprint(*a), model_fingerprint(*plain));
  EXPECT_NE(model_fingerprint(*a), model_fingerprint(*b));
  Simulation sa(a), sb(b);
  EXPECT_NE(error_of(checkpoint_bytes(sa), sb).find("the checkpoint is of a different model"),
            std::string::npos);
  Simulation same(std::make_shared<const Model>(*a));
  restore_checkpoint(checkpoint_bytes(sa), same, "state.ckpt");
}

// The row kinds go by name (version 10): a kind or a field this build does not know is refused,
// naming it; the springs' settings and forces resume bit for bit.
TEST(Checkpoint, RowKindsResumeAndUnknownOnesAreRefused) {
  Simulation a = busy_simulation(4);
  a.step(5);
  ASSERT_NE(a.row_force("joint_spring").norm(), 0.0);
  const std::string bytes = checkpoint_bytes(a);
  Simulation b(a.model_ptr(), a.options());
  restore_checkpoint(bytes, b, "state.ckpt");
  expect_same_state(a, b);
  for (int d = 0; d < a.model().nv; ++d)
    EXPECT_EQ(b.row_parameters("joint_spring", d), a.row_parameters("joint_spring", d));
  a.step(20);
  b.step(20);
  expect_same_state(a, b);
  const size_t kind = bytes.find("joint_spring");
  ASSERT_NE(kind, std::string::npos);
  Simulation c(a.model_ptr(), a.options());
  EXPECT_EQ(error_of(forged(bytes, kind + 11, 'G', 1), c),
            "state.ckpt: the checkpoint has row kind 'joint_sprinG', which this build does not "
            "know (row kinds: joint_spring)");
  const size_t field = bytes.find("reference", kind);
  ASSERT_NE(field, std::string::npos);
  EXPECT_EQ(error_of(forged(bytes, field, 'R', 1), c),
            "state.ckpt: the checkpoint's row kind 'joint_spring' has field 'Reference', which "
            "this build does not know");
  // A forged negative stiffness is refused by the setting's own check, naming the joint.
  int sprung = -1;
  for (int d = a.model().nv - 1; d >= 0; --d)
    if (a.row_parameters("joint_spring", d)[0] != 0.0) sprung = d;
  ASSERT_GE(sprung, 0);
  const size_t stiffness_at = field + 9 + 3 * 8 * static_cast<size_t>(sprung);
  EXPECT_EQ(error_of(forged(bytes, stiffness_at, bits(-1.0)), c),
            "state.ckpt: bad value in the checkpoint: joint spring of joint '" +
                a.model().dof_names[sprung] + "': stiffness = -1 must be finite and >= 0");
}

}  // namespace
}  // namespace featherdrive
