// Export of a simulation to the PhysX comparison harness's JSON description
// (tests/physx/README.md, format "featherdrive-physx/2"), so that PhysX 5.6.1 can run the same
// robot, drives, solver settings and initial state, with its collision shapes and the ground.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

/// Drive targets (position, velocity) by joint name, set before one step.
using TargetsByJoint = std::map<std::string, std::pair<double, double>>;
/// Joint forces by joint name, applied through one step (PhysX's cache jointForce).
using ForcesByJoint = std::map<std::string, double>;

/// The JSON scene for the harness: the model with its collision shapes, the current state, drives,
/// limits, velocity limits and armature of `sim`, its ground and contact options, its solver
/// options, `steps` steps and `targets[k]` applied
/// before step k + 1 (a spherical joint's axes by their dof names, `ball:twist`); `forces[k]` are
/// the joint forces of step k + 1 (a joint it does not name, or a step past its end, has sim's
/// applied force). Revolute joints are PhysX's eREVOLUTE where sim wraps them, else
/// eREVOLUTE_UNWRAPPED. Throws std::invalid_argument for what the harness cannot represent (a root
/// joint other than fixed or floating, mimic joints, joint friction, actuator envelopes, a
/// spherical joint whose axes differ in max velocity or friction coefficient: PhysX has one of
/// each per joint).
std::string physx_scene_json(const Simulation& sim, int steps,
                             const std::vector<TargetsByJoint>& targets = {},
                             const std::vector<ForcesByJoint>& forces = {});

}  // namespace featherdrive
