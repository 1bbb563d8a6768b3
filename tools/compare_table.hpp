// What compare-physx and compare-mujoco share: the table of the largest differences per joint
// and the differences over time for the plot script (tools/plot_physx_diff.py).
#pragma once

#include <filesystem>
#include <string>

#include "featherdrive/io/physx_runner.hpp"

/// The per-joint table of compare_trajectories(fd, other), its scale and the largest relative
/// differences; `other` names the reference engine ("PhysX") in the header lines.
void print_difference_table(const featherdrive::TrajectoryComparison& c, const std::string& other);

/// The differences fd - other per row as CSV for the plot script:
/// step,t,dq:<joint>...,dqd:<joint>...,df:<joint>... (columns matched by name).
void write_differences(const std::filesystem::path& path, const featherdrive::JointTrajectory& fd,
                       const featherdrive::JointTrajectory& other);
