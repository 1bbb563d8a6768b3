#include "featherdrive/io/trajectory.hpp"

#include "featherdrive/core/format.hpp"
#include "featherdrive/model/dof_position.hpp"

namespace featherdrive {
namespace {

// The q columns: a floating root's q entries (7, as q indices >= 0), then each dof with a
// position (dof_position) in URDF order, as -1 - dof.
std::vector<int> q_order(const UrdfRobot& robot) {
  const Model& model = *robot.model;
  std::vector<int> order;
  if (model.floating_base())
    for (int k = 0; k < model.links[0].nq; ++k) order.push_back(model.links[0].q_index + k);
  for (int d : robot.dof_order)
    if (has_dof_position(model, d)) order.push_back(-1 - d);
  return order;
}

}  // namespace

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::vector<int> target_dofs(const Scene& scene) {
  std::vector<int> dofs;
  for (int d : scene.robot.dof_order)
    for (const DriveSpec& spec : scene.drives)
      if (spec.dof == d && spec.drive.type != DriveType::none) dofs.push_back(d);
  return dofs;
}

std::vector<int> shape_links(const Model& model) {
  std::vector<int> links;
  for (const CollisionShape& s : model.shapes)  // grouped by link in link order
    if (links.empty() || links.back() != s.link) links.push_back(s.link);
  return links;
}

std::vector<std::string> trajectory_columns(const UrdfRobot& robot,
                                            const std::vector<int>& target_dofs,
                                            const std::vector<int>& contact_links,
                                            const std::vector<Foot>& feet) {
  const Model& model = *robot.model;
  std::vector<std::string> columns;
  if (model.floating_base())
    for (const char* c : {"x", "y", "z", "qw", "qx", "qy", "qz"})
      columns.push_back("q:" + model.links[0].joint_name + ":" + c);
  for (int d : robot.dof_order)
    if (has_dof_position(model, d)) columns.push_back("q:" + model.dof_names[d]);
  for (const char* prefix : {"qd:", "f:"})
    for (int d : robot.dof_order) columns.push_back(prefix + model.dof_names[d]);
  for (const char* prefix : {"target:", "target_velocity:"})
    for (int d : target_dofs) columns.push_back(prefix + model.dof_names[d]);
  for (int link : contact_links)
    for (const char* axis : {":fx", ":fy", ":fz"})
      columns.push_back("contact:" + model.links[static_cast<size_t>(link)].name + axis);
  for (const Foot& foot : feet)
    for (const char* axis : {":fx", ":fy", ":fz"}) columns.push_back("foot:" + foot.name + axis);
  return columns;
}

Vec3 foot_contact_force(const Simulation& sim, const Foot& foot) {
  Vec3 sum = Vec3::Zero();
  for (int link : foot.links) sum += sim.link_contact_force().at(static_cast<size_t>(link));
  return sum;
}

TrajectoryWriter::TrajectoryWriter(std::ostream& out, const UrdfRobot& robot,
                                   const std::vector<int>& target_dofs, bool guard_substeps,
                                   bool contact_forces, const std::vector<Foot>& feet)
    : out_(out), q_order_(q_order(robot)), v_order_(robot.dof_order), target_order_(target_dofs),
      contact_links_(contact_forces ? shape_links(*robot.model) : std::vector<int>{}),
      feet_(contact_forces ? feet : std::vector<Foot>{}), guard_substeps_(guard_substeps) {
  out_ << "step,t";
  for (const std::string& c : trajectory_columns(robot, target_dofs, contact_links_, feet_))
    out_ << ',' << csv_field(c);
  if (guard_substeps_) out_ << ",guard_substeps";
  out_ << '\n';
}

void TrajectoryWriter::write(long step, const Simulation& sim, bool initial) {
  out_ << step << ',' << format_double(sim.time());
  for (int i : q_order_)
    out_ << ',' << format_double(i >= 0 ? sim.q()[i] : dof_position(sim.model(), sim.q(), -1 - i));
  for (int d : v_order_) out_ << ',' << format_double(sim.qd()[d]);
  // The dof's driver: its implicit drive or its explicit actuator (a dof has at most one).
  for (int d : v_order_)
    out_ << ',' << format_double(initial ? 0.0 : sim.drive_force()[d] + sim.actuator_force()[d]);
  for (int d : target_order_) out_ << ',' << format_double(sim.drive(d).target_position);
  for (int d : target_order_) out_ << ',' << format_double(sim.drive(d).target_velocity);
  auto force = [&](const Vec3& f) {
    for (int k = 0; k < 3; ++k) out_ << ',' << format_double(initial ? 0.0 : f[k]);
  };
  for (int link : contact_links_) force(sim.link_contact_force()[static_cast<size_t>(link)]);
  for (const Foot& foot : feet_) force(foot_contact_force(sim, foot));
  if (guard_substeps_) out_ << ',' << (initial ? 1 : sim.guard_substeps());
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
