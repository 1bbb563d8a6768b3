// Checkpoints: a run interrupted by a checkpoint and resumed equals the uninterrupted run bit for
// bit; files that are truncated, corrupt, of another version or of another model are refused with
// a message that says so, and the simulation is left as it was.
#include "featherdrive/io/checkpoint.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "featherdrive/io/scene.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

namespace fs = std::filesystem;
constexpr double kInf = std::numeric_limits<double>::infinity();
const std::string kExamples = std::string(FEATHERDRIVE_SOURCE_DIR) + "/examples/";

// Bitwise equality of two vectors (so -0.0 != 0.0 and NaN payloads count).
bool same_bits(const VecX& a, const VecX& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

void expect_same_state(const Simulation& a, const Simulation& b) {
  EXPECT_TRUE(same_bits(a.q(), b.q()));
  EXPECT_TRUE(same_bits(a.qd(), b.qd()));
  EXPECT_EQ(std::bit_cast<std::uint64_t>(a.time()), std::bit_cast<std::uint64_t>(b.time()));
  EXPECT_EQ(a.step_count(), b.step_count());
  EXPECT_TRUE(same_bits(a.drive_force(), b.drive_force()));
  EXPECT_TRUE(same_bits(a.limit_force(), b.limit_force()));
  EXPECT_TRUE(same_bits(a.friction_force(), b.friction_force()));
  EXPECT_TRUE(same_bits(a.velocity_limit_force(), b.velocity_limit_force()));
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
            "state.ckpt: checkpoint format version 1 is not supported (this build reads version 2)");
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

TEST(Checkpoint, ClockAndRestoreStateValidateTheirArguments) {
  Simulation s(test::make_random_tree(2, 3, true));
  EXPECT_THROW(s.set_clock(-1.0, 0), std::invalid_argument);
  EXPECT_THROW(s.set_clock(std::nan(""), 0), std::invalid_argument);
  EXPECT_THROW(s.set_clock(kInf, 0), std::invalid_argument);
  EXPECT_THROW(s.set_clock(0.0, -1), std::invalid_argument);
  s.set_clock(2.5, 150);
  EXPECT_EQ(s.time(), 2.5);
  EXPECT_EQ(s.step_count(), 150);
  const int nv = s.model().nv;
  const VecX z = VecX::Zero(nv);
  VecX q = s.q();
  q[3] = 2.0;  // the floating root's quaternion w: norm 2
  try {
    s.restore_state(q, z, z, z, z);
    ADD_FAILURE() << "a quaternion of norm 2 is restored";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("has norm 2, expected 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(s.restore_state(s.q(), VecX::Zero(nv + 1), z, z, z), std::invalid_argument);
  VecX bad = z;
  bad[0] = std::nan("");
  EXPECT_THROW(s.restore_state(s.q(), z, bad, z, z), std::invalid_argument);
  EXPECT_EQ(s.q()[3], 1.0);
}

}  // namespace
}  // namespace featherdrive
