// Checkpoints: the whole state of a Simulation in a file, restored bit for bit, so that a run
// interrupted by a checkpoint and resumed equals the uninterrupted run.
//
// The file (all integers little-endian, doubles as their IEEE-754 bits):
//   "FDCKPT\r\n"  magic, 8 bytes
//   u32           format version (kCheckpointVersion)
//   u64           model fingerprint (model_fingerprint)
//   u32, u32      nq, nv of the model
//   u64           payload size in bytes
//   payload       time, step count, solver options (compat included), q, qd, applied forces, per
//                 dof the drive, limits, friction, max velocity, envelope and friction
//                 coefficient, per link its LinkParameters, then the last step's drive, limit,
//                 friction and velocity-limit forces, then per dof its explicit actuator (kind;
//                 if any: its integration (version 6), settings, table, feed-forward, pushes
//                 and its delay ring of
//                 delay + 1 commands) and the last step's actuator forces, then per dof the
//                 implicit drive's delay (if > 0: pushes and its ring of delay + 1 targets),
//                 then per dof its revolute wrap and the mimic joints (count, then each one's
//                 dofs, gear ratio, offset, natural frequency and damping ratio), then the
//                 step guard's account (created, dissipated, scale; version 7), then the
//                 ground (enabled u8, height, normal, static and dynamic friction,
//                 restitution), the contact options (contact offset, rest offset, bounce
//                 threshold) and per shape its kept friction anchors (count u8, normal, two body
//                 points, two ground points; version 8)
//   u64           FNV-1a 64 checksum of everything before it
// docs/testing.md lists the errors a bad file gets.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "featherdrive/io/error.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

/// 2: compat, the joint friction coefficient and the link parameters (PhysX's) added.
/// 3: explicit actuators with their delay histories, so a delayed actuator resumes bit for bit.
/// 4: the implicit drives' delays with their pending targets. Version 3 is still read (no
/// drive delays).
/// 5: revolute wrap and mimic joints. Versions 3 and 4 are still read (the simulation keeps its
/// own).
/// 6: an actuator's integration (explicit or implicit). Versions 3 to 5 read as explicit.
/// 7: the step guard's account (docs/math/step_guard.md, test (iii)). Versions 3 to 6 read with
/// an empty account.
/// 8: the ground and the contact options (issue 34; contacts keep no state between steps).
/// Versions 3 to 7 read with the simulation's own. (The comment "keep no state" predates the kept
/// friction anchors, which follow the settings.)
/// 9: the contact options's self_collision. Versions 3 to 8 read with it off.
/// 10: the row kinds (constraint/row_kinds.hpp) by name, with their fields' names and forces, so
/// that a kind added later needs no new version. Versions 3 to 9 read with the simulation's own
/// row kind settings and no row kind forces.
inline constexpr std::uint32_t kCheckpointVersion = 10;
inline constexpr std::uint32_t kOldestCheckpointVersion = 3;

/// A checkpoint that cannot be read or does not fit the simulation: the message names the file
/// and what is wrong (truncated, corrupt, another format version, another model).
class CheckpointError : public InputError {
 public:
  using InputError::InputError;
};

/// A hash of what makes a model: per link its name, parent, joint name and type, mass, centre of
/// mass, inertia, joint frame and axis, and the model's nq, nv, gravity, armature and joint limits.
/// With collision shapes, also each shape's link, type, size, pose and material (a model without
/// shapes keeps the fingerprint it had before shapes existed).
/// Computed from the bits of the doubles, so it is the same on every run and machine.
std::uint64_t model_fingerprint(const Model& model);

/// The checkpoint of `sim` as bytes.
std::string checkpoint_bytes(const Simulation& sim);

/// Restores `sim` from checkpoint bytes; `name` stands for the file in messages. The step guard's
/// options stay sim's (the file keeps its account, not its options). Throws
/// CheckpointError and leaves `sim` unchanged when the bytes are not a checkpoint of sim's model.
void restore_checkpoint(const std::string& bytes, Simulation& sim, const std::string& name);

/// Writes the checkpoint atomically: a temporary file in the same folder, fsync, rename (and an
/// fsync of the folder). Throws std::runtime_error when the file cannot be written.
void save_checkpoint(const Simulation& sim, const std::filesystem::path& path);

/// Reads a checkpoint file into `sim` (see restore_checkpoint).
void load_checkpoint(const std::filesystem::path& path, Simulation& sim);

}  // namespace featherdrive
