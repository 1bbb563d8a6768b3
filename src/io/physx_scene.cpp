#include "featherdrive/io/physx_scene.hpp"

#include "featherdrive/core/format.hpp"

#include <Eigen/Cholesky>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/constraint/spherical_axes.hpp"

namespace featherdrive {
namespace {

// JSON has no infinity: the harness reads 1e30 as "none".
std::string json_num(double v) {
  if (std::isinf(v)) v = v > 0 ? 1e30 : -1e30;
  return format_double(v);
}

std::string json_vec(const Vec3& v) {
  return "[" + json_num(v.x()) + ", " + json_num(v.y()) + ", " + json_num(v.z()) + "]";
}

std::string quat(const Mat3& R) {
  const Quat q(R);
  return "[" + json_num(q.w()) + ", " + json_num(q.x()) + ", " + json_num(q.y()) + ", " +
         json_num(q.z()) + "]";
}

// A JSON string: quote and backslash escaped, control characters as \u00XX (names come from
// URDFs and Python and may hold anything).
std::string str(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u == 0x7f) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", u);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// One dof's armature, limits and drive (a revolute or prismatic joint, or a spherical axis),
// each field as `, "key": value`; `name` names it in errors.
std::string dof_fields(const Simulation& sim, int d, const std::string& name) {
  if (sim.joint_friction(d).active())
    throw std::invalid_argument("physx export: joint '" + name +
                                "' has static/dynamic/viscous friction, which the harness "
                                "cannot set");
  if (sim.actuator_envelope(d).active())
    throw std::invalid_argument("physx export: joint '" + name +
                                "' has an actuator envelope, which the harness cannot set");
  // PhysX has no actuator models (Isaac Lab evaluates them outside it): the harness would run
  // the dof undriven.
  if (sim.has_actuator(d))
    throw std::invalid_argument("physx export: joint '" + name + "' has an " +
                                to_string(sim.actuator(d).integration) + " " +
                                to_string(sim.actuator(d).kind) +
                                " actuator, which the harness cannot set (give it a drive)");
  for (const RowKindInfo& kind : row_kinds()) {
    const std::vector<double> values = sim.row_parameters(kind.name, d);
    if (kind.active(values))
      throw std::invalid_argument("physx export: joint '" + name + "' has a " +
                                  std::string(kind.name) +
                                  ", which PhysX has no counterpart for (clear it to compare)");
  }
  std::ostringstream js;
  js << "\"armature\": " << json_num(sim.model().armature[d]);
  if (sim.applied_force()[d] != 0.0)
    js << ", \"applied_force\": " << json_num(sim.applied_force()[d]);
  if (std::isfinite(sim.lower_limit(d)) || std::isfinite(sim.upper_limit(d)))
    js << ", \"limits\": {\"lower\": " << json_num(sim.lower_limit(d))
       << ", \"upper\": " << json_num(sim.upper_limit(d)) << "}";
  const Drive& drive = sim.drive(d);
  if (drive.type != DriveType::none)
    js << ", \"drive\": {\"type\": " << str(to_string(drive.type))
       << ", \"stiffness\": " << json_num(drive.stiffness)
       << ", \"damping\": " << json_num(drive.damping) << ", \"max_force\": "
       << json_num(std::isfinite(drive.max_impulse) ? drive.max_impulse : drive.max_force)
       << ", \"target_position\": " << json_num(drive.target_position)
       << ", \"target_velocity\": " << json_num(drive.target_velocity) << "}";
  return js.str();
}

// A spherical joint (eSPHERICAL): PhysX has one max velocity and one friction coefficient per
// joint and armature, limits and a drive per axis.
std::string spherical_fields(const Simulation& sim, const Link& l) {
  const int d = l.v_index;
  for (int k = 1; k < 3; ++k)
    for (const auto& [what, value] :
         {std::pair{"max_velocity", &Simulation::max_joint_velocity},
          std::pair{"friction_coefficient", &Simulation::friction_coefficient}})
      if ((sim.*value)(d + k) != (sim.*value)(d))
        throw std::invalid_argument("physx export: joint '" + l.joint_name + "' has " + what + " " +
                                    json_num((sim.*value)(d + k)) + " on axis " +
                                    sim.model().dof_names[d + k] + " but " +
                                    json_num((sim.*value)(d)) + " on " + sim.model().dof_names[d] +
                                    "; PhysX has one per spherical joint");
  std::ostringstream js;
  js << ", \"max_velocity\": " << json_num(sim.max_joint_velocity(d))
     << ", \"friction_coefficient\": " << json_num(sim.friction_coefficient(d))
     << ",\n       \"axes\": [";
  for (int k = 0; k < 3; ++k)
    js << (k ? ",\n                {" : "{") << dof_fields(sim, d + k, sim.model().dof_names[d + k])
       << "}";
  js << "]";
  return js.str();
}

// A massless link below a fixed root (e.g. one of the links of an MJCF body with several joints)
// gets kHelperMass times the mass and mean principal moment of the first link with mass below it,
// at its origin: PhysX needs a positive mass on every link (docs/physx_parity.md bounds the error).
constexpr double kHelperMass = 1e-6;

void helper_inertial(const Model& model, int i, double& mass, Mat3& inertia) {
  int body = i;
  while (model.links[static_cast<size_t>(body)].mass == 0.0 &&
         !model.links[static_cast<size_t>(body)].children.empty())
    body = model.links[static_cast<size_t>(body)].children.front();
  const Link& b = model.links[static_cast<size_t>(body)];
  if (b.mass == 0.0) return;  // nothing moves below it: left to the harness's check
  mass = kHelperMass * b.mass;
  inertia = Mat3::Identity() * (kHelperMass * b.inertia_com.trace() / 3.0);
}

// A material's fields, each as `, "key": value`.
std::string material_fields(const Material& m) {
  return ", \"static_friction\": " + json_num(m.static_friction) +
         ", \"dynamic_friction\": " + json_num(m.dynamic_friction) +
         ", \"restitution\": " + json_num(m.restitution);
}

// The link's collision shapes as `"shapes": [...],` (empty for none), in the link frame with the
// shape's own conventions (a capsule along its z: the harness turns it onto PhysX's x).
std::string shapes_field(const Model& model, int link, bool ground) {
  std::ostringstream js;
  bool first = true;
  for (const CollisionShape& shape : model.shapes) {
    if (shape.link != link) continue;
    // The harness builds PhysX's sphere, capsule and box geometries only. Without the ground
    // the others touch nothing (links do not collide with each other) and are left out.
    const bool buildable = shape.type == ShapeType::sphere || shape.type == ShapeType::capsule ||
                           shape.type == ShapeType::box;
    if (!buildable && !ground) continue;
    if (!buildable)
      throw std::invalid_argument("physx export: shape " +
                                  (shape.name.empty() ? std::string("#") : "'" + shape.name + "'") +
                                  " (" + to_string(shape.type) + ") of link '" +
                                  model.links[static_cast<size_t>(link)].name +
                                  "': the PhysX harness builds spheres, capsules and boxes only "
                                  "(leave the ground off to compare without them)");
    js << (first ? "\"shapes\": [\n       {" : ",\n       {") << "\"name\": " << str(shape.name)
       << ", \"type\": " << str(to_string(shape.type));
    if (shape.type == ShapeType::box)
      js << ", \"half_extents\": " << json_vec(shape.size);
    else
      js << ", \"radius\": " << json_num(shape.size.x());
    if (shape.type == ShapeType::capsule) js << ", \"half_length\": " << json_num(shape.size.y());
    js << ", \"xyz\": " << json_vec(shape.position) << ", \"quat\": " << quat(shape.rotation)
       << material_fields(shape.material) << "}";
    first = false;
  }
  if (!first) js << "],\n     ";
  return js.str();
}

// The ground (when enabled) and the contact options (docs/math/contact.md, section 8).
std::string contact_fields(const Simulation& sim) {
  std::ostringstream js;
  const Ground& g = sim.ground();
  if (g.enabled)
    js << "  \"ground\": {\"height\": " << json_num(g.height)
       << ", \"normal\": " << json_vec(g.normal) << material_fields(g.material) << "},\n";
  const ContactOptions& c = sim.contact_options();
  js << "  \"contact\": {\"contact_offset\": " << json_num(c.contact_offset)
     << ", \"rest_offset\": " << json_num(c.rest_offset)
     << ", \"bounce_threshold\": " << json_num(c.bounce_threshold) << "},\n";
  return js.str();
}

}  // namespace

std::string physx_scene_json(const Simulation& sim, int steps,
                             const std::vector<TargetsByJoint>& targets,
                             const std::vector<ForcesByJoint>& forces) {
  const Model& model = sim.model();
  const SimulationOptions& o = sim.options();
  const JointType root_type = model.links[0].joint_type;
  if (root_type != JointType::fixed && root_type != JointType::floating)
    throw std::invalid_argument("physx export: the root joint '" + model.links[0].joint_name +
                                "' is " + to_string(root_type) +
                                "; PhysX needs a fixed or floating root");
  if (o.guard.enabled)
    throw std::invalid_argument(
        "physx export: the step guard (guard:) has no PhysX counterpart: PhysX would run every "
        "step unguarded (remove guard: to compare)");
  if (!sim.mimic_joints().empty())
    throw std::invalid_argument("physx export: " + describe(model, sim.mimic_joints()[0]) +
                                ": the WebAssembly PhysX has no mimic joints");
  if (sim.contact_options().self_collision)
    throw std::invalid_argument(
        "physx export: contact.self_collision: the harness builds no self-collision (remove it "
        "to compare)");
  Data data(model);
  forward_kinematics(model, data, sim.q(), sim.qd());

  std::ostringstream js;
  js << "{\n  \"format\": \"featherdrive-physx/2\",\n";
  js << "  \"dt\": " << json_num(o.dt) << ",\n  \"steps\": " << steps << ",\n";
  js << "  \"gravity\": " << json_vec(model.gravity) << ",\n";
  js << "  \"solver\": {\"type\": " << str(to_string(o.solver))
     << ", \"position_iterations\": " << o.position_iterations
     << ", \"velocity_iterations\": " << o.velocity_iterations << "},\n";
  // PhysX has one flag per articulation: max_force values are forces, or all are impulses.
  bool any_force_limit = false, any_impulse_limit = false;
  for (int d = 0; d < model.nv; ++d) {
    any_force_limit = any_force_limit || std::isfinite(sim.drive(d).max_force);
    any_impulse_limit = any_impulse_limit || std::isfinite(sim.drive(d).max_impulse);
  }
  if (any_force_limit && any_impulse_limit)
    throw std::invalid_argument(
        "physx export: PhysX cannot mix max_force and max_impulse drives in one articulation");
  js << "  \"drive_limits_are_forces\": " << (any_impulse_limit ? "false" : "true") << ",\n";
  js << "  \"floating_base\": " << (model.floating_base() ? "true" : "false") << ",\n";
  {
    const Mat3& R = data.world_rotation[0];
    const Vec6& v = data.velocity[0];  // body frame
    js << "  \"root\": {\"position\": " << json_vec(data.world_position[0])
       << ", \"quat\": " << quat(R) << ", \"angular_velocity\": " << json_vec(R * v.head<3>())
       << ", \"linear_velocity\": " << json_vec(R * v.tail<3>()) << "},\n";
  }
  js << contact_fields(sim) << "  \"links\": [\n";
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& l = model.links[i];
    // PhysX needs a positive mass and inertia on every link; a fixed root's (e.g. a URDF's empty
    // world link) never enters the dynamics, so a unit one stands in for a missing one.
    const bool stand_in = i == 0 && !model.floating_base() &&
                          !(l.mass > 0.0 && l.inertia_com.llt().info() == Eigen::Success);
    Mat3 I = stand_in ? Mat3::Identity() : l.inertia_com;
    double mass = stand_in ? 1.0 : l.mass;
    if (i > 0 && l.mass == 0.0) helper_inertial(model, i, mass, I);
    js << "    {\"name\": " << str(l.name) << ", \"parent\": " << l.parent
       << ", \"mass\": " << json_num(mass) << ", \"com\": " << json_vec(l.com) << ", \"inertia\": ["
       << json_num(I(0, 0)) << ", " << json_num(I(1, 1)) << ", " << json_num(I(2, 2)) << ", "
       << json_num(I(0, 1)) << ", " << json_num(I(0, 2)) << ", " << json_num(I(1, 2))
       << "],\n     ";
    // PhysX's link parameters, as featherdrive has them (so Compat::physx gives PhysX's defaults).
    const LinkParameters& lp = sim.link_parameters(i);
    js << "\"cfm_scale\": " << json_num(lp.cfm_scale)
       << ", \"linear_damping\": " << json_num(lp.linear_damping)
       << ", \"angular_damping\": " << json_num(lp.angular_damping)
       << ", \"max_linear_velocity\": " << json_num(lp.max_linear_velocity)
       << ", \"max_angular_velocity\": " << json_num(lp.max_angular_velocity) << ",\n     ";
    js << shapes_field(model, i, sim.ground().enabled) << "\"joint\": ";
    if (i == 0) {
      js << "null}";
    } else {
      const char* type = l.joint_type == JointType::revolute    ? "revolute"
                         : l.joint_type == JointType::prismatic ? "prismatic"
                         : l.joint_type == JointType::spherical ? "spherical"
                                                                : "fixed";
      js << "{\"name\": " << str(l.joint_name) << ", \"type\": " << str(type)
         << ", \"origin\": {\"xyz\": " << json_vec(l.tree_transform.r)
         << ", \"quat\": " << quat(l.tree_transform.E.transpose())
         << "}, \"axis\": " << json_vec(l.axis);
      if (l.nv == 1) {
        const int d = l.v_index;
        js << ", " << dof_fields(sim, d, l.joint_name)
           << ", \"max_velocity\": " << json_num(sim.max_joint_velocity(d))
           << ", \"friction_coefficient\": " << json_num(sim.friction_coefficient(d));
        if (l.joint_type == JointType::revolute && sim.revolute_wrap(d) == RevoluteWrap::wrapped)
          js << ", \"wrapped\": true";
      }
      if (l.joint_type == JointType::spherical) js << spherical_fields(sim, l);
      js << "}}";
    }
    js << (i + 1 < model.num_links() ? ",\n" : "\n");
  }
  js << "  ],\n  \"initial\": {\"q\": {";
  // A spherical joint's axes by their dof names, at PhysX's positions from the quaternion.
  bool first = true;
  for (const Link& l : model.links) {
    if (l.nv == 1) {
      js << (first ? "" : ", ") << str(l.joint_name) << ": " << json_num(sim.q()[l.q_index]);
      first = false;
    }
    if (l.joint_type != JointType::spherical) continue;
    const double* x = sim.q().data() + l.q_index;
    const Vec3 position = spherical_joint_positions(Quat(x[0], x[1], x[2], x[3]));
    for (int k = 0; k < 3; ++k) {
      js << (first ? "" : ", ") << str(model.dof_names[l.v_index + k]) << ": "
         << json_num(position[k]);
      first = false;
    }
  }
  js << "}, \"qd\": {";
  first = true;
  for (const Link& l : model.links) {
    if (l.nv != 1 && l.joint_type != JointType::spherical) continue;
    for (int d = l.v_index; d < l.v_index + l.nv; ++d) {
      js << (first ? "" : ", ") << str(model.dof_names[d]) << ": " << json_num(sim.qd()[d]);
      first = false;
    }
  }
  js << "}},\n  \"targets\": [";
  for (size_t k = 0; k < targets.size(); ++k) {
    js << (k ? ",\n    {" : "\n    {");
    first = true;
    for (const auto& [joint, target] : targets[k]) {
      js << (first ? "" : ", ") << str(joint) << ": [" << json_num(target.first) << ", "
         << json_num(target.second) << "]";
      first = false;
    }
    js << "}";
  }
  js << "]";
  if (!forces.empty()) {
    js << ",\n  \"forces\": [";
    for (size_t k = 0; k < forces.size(); ++k) {
      js << (k ? ",\n    {" : "\n    {");
      first = true;
      for (const auto& [joint, force] : forces[k]) {
        js << (first ? "" : ", ") << str(joint) << ": " << json_num(force);
        first = false;
      }
      js << "}";
    }
    js << "]";
  }
  js << "\n}\n";
  return js.str();
}

}  // namespace featherdrive
