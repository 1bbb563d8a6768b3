#include "featherdrive/io/trajectory.hpp"

#include "featherdrive/core/format.hpp"
#include "featherdrive/constraint/spherical_axes.hpp"

namespace featherdrive {
namespace {

// q entries of each dof column in URDF order; a floating root's q (7) comes first. A spherical
// axis's column is PhysX's position of dof d, from the quaternion: entry -1 - d.
std::vector<int> q_order(const UrdfRobot& robot) {
  const Model& model = *robot.model;
  std::vector<int> order;
  if (model.floating_base())
    for (int k = 0; k < model.links[0].nq; ++k) order.push_back(model.links[0].q_index + k);
  for (int d : robot.dof_order) {
    const Link& link = model.links[model.dof_link[d]];
    if (link.nv == 1) order.push_back(link.q_index);
    if (link.joint_type == JointType::spherical) order.push_back(-1 - d);
  }
  return order;
}

}  // namespace

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::vector<std::string> trajectory_columns(const UrdfRobot& robot) {
  const Model& model = *robot.model;
  std::vector<std::string> columns;
  if (model.floating_base())
    for (const char* c : {"x", "y", "z", "qw", "qx", "qy", "qz"})
      columns.push_back("q:" + model.links[0].joint_name + ":" + c);
  for (int d : robot.dof_order)
    if (model.links[model.dof_link[d]].nv == 1 ||
        model.links[model.dof_link[d]].joint_type == JointType::spherical)
      columns.push_back("q:" + model.dof_names[d]);
  for (const char* prefix : {"qd:", "f:"})
    for (int d : robot.dof_order) columns.push_back(prefix + model.dof_names[d]);
  return columns;
}

TrajectoryWriter::TrajectoryWriter(std::ostream& out, const UrdfRobot& robot)
    : out_(out), q_order_(q_order(robot)), v_order_(robot.dof_order) {
  out_ << "step,t";
  for (const std::string& c : trajectory_columns(robot)) out_ << ',' << csv_field(c);
  out_ << '\n';
}

void TrajectoryWriter::write(long step, const Simulation& sim, bool initial) {
  out_ << step << ',' << format_double(sim.time());
  for (int i : q_order_) {
    if (i >= 0) {
      out_ << ',' << format_double(sim.q()[i]);
      continue;
    }
    const Link& link = sim.model().links[sim.model().dof_link[-1 - i]];
    const double* x = sim.q().data() + link.q_index;
    const Vec3 theta = spherical_joint_positions(Quat(x[0], x[1], x[2], x[3]));
    out_ << ',' << format_double(theta[-1 - i - link.v_index]);
  }
  for (int d : v_order_) out_ << ',' << format_double(sim.qd()[d]);
  // The dof's driver: its implicit drive or its explicit actuator (a dof has at most one).
  for (int d : v_order_)
    out_ << ',' << format_double(initial ? 0.0 : sim.drive_force()[d] + sim.actuator_force()[d]);
  out_ << '\n';
}

TargetWriter::TargetWriter(std::ostream& out, const Scene& scene) : out_(out), scene_(scene) {
  out_ << "step,t";
  for (const DriveSpec& d : scene.drives) out_ << ',' << csv_field("target:" + d.joint);
  out_ << '\n';
}

void TargetWriter::write(long step, double t) {
  out_ << step << ',' << format_double(t);
  for (const DriveSpec& d : scene_.drives) out_ << ',' << format_double(d.target_at(t).first);
  out_ << '\n';
}

}  // namespace featherdrive
