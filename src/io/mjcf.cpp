#include "featherdrive/io/mjcf.hpp"

#include <mujoco/mujoco.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/io/files.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "featherdrive/spatial/spatial.hpp"
#include "input_error.hpp"
#include "mesh_hull.hpp"
#include "mjcf_document.hpp"
#include "mujoco_calls.hpp"

namespace featherdrive {
namespace {

using io_detail::fail;
using io_detail::kInf;

using mujoco_calls::one_line;

std::string name_of(const mjModel* m, mjtObj type, int id, const char* fallback) {
  const char* name = mj_id2name(m, type, id);
  return name && *name ? std::string(name) : std::string(fallback) + std::to_string(id);
}

// The names of all joints or bodies: an unnamed one gets prefix<id>, with '_' appended while a
// named one has that name, so that no two share a name.
std::vector<std::string> unique_names(const mjModel* m, mjtObj type, int count, const char* prefix) {
  std::vector<std::string> names(static_cast<size_t>(count));
  std::set<std::string> named;
  for (int i = 0; i < count; ++i) {
    const char* name = mj_id2name(m, type, i);
    if (name && *name) named.insert(names[static_cast<size_t>(i)] = name);
  }
  for (int i = 0; i < count; ++i) {
    std::string& name = names[static_cast<size_t>(i)];
    if (!name.empty()) continue;
    name = prefix + std::to_string(i);
    while (named.count(name)) name += "_";
  }
  return names;
}

struct Names {
  std::vector<std::string> joint, body;
  explicit Names(const mjModel* m)
      : joint(unique_names(m, mjOBJ_JOINT, m->njnt, "joint")),
        body(unique_names(m, mjOBJ_BODY, m->nbody, "body")) {}
};

Vec3 vec3(const mjtNum* p) { return Vec3(p[0], p[1], p[2]); }
Mat3 rotation(const mjtNum* quat) {
  return Quat(quat[0], quat[1], quat[2], quat[3]).normalized().toRotationMatrix();
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "'" : ", '") + n + "'";
  return out;
}

const char* equality_name(int type) {
  switch (type) {
    case mjEQ_CONNECT: return "connect";
    case mjEQ_WELD: return "weld";
    case mjEQ_JOINT: return "joint";
    case mjEQ_TENDON: return "tendon";
    case mjEQ_DISTANCE: return "distance";
    default: return "unknown";
  }
}

// A name no joint in `taken` has: base, then base_, base__, ...
std::string free_name(std::string base, const std::set<std::string>& taken) {
  while (taken.count(base)) base += "_";
  return base;
}

// Whether equality i is a mimic row: an active joint equality q1 = c0 + c1 q2 between two
// hinge or slide joints, c1 nonzero and no higher terms.
bool is_mimic(const mjModel* m, int i) {
  if (m->eq_type[i] != mjEQ_JOINT || !m->eq_active[i] || m->eq_obj2id[i] < 0) return false;
  for (const int j : {m->eq_obj1id[i], m->eq_obj2id[i]})
    if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE) return false;
  const mjtNum* c = m->eq_data + mjNEQDATA * i;
  return c[1] != 0.0 && c[2] == 0.0 && c[3] == 0.0 && c[4] == 0.0;
}

// What MJCF cannot bring over whole: refused with one line, before anything is built.
void refuse_unsupported(const mjModel* m, const Names& names, const std::string& file) {
  if (m->ntendon > 0)
    fail(file, "<tendon> '" + name_of(m, mjOBJ_TENDON, 0, "tendon") + "' (" +
                   std::to_string(m->ntendon) +
                   " in all): tendons are not supported (featherdrive has no tendon "
                   "constraints or tendon actuators)");
  for (int i = 0; i < m->neq; ++i)
    if (!is_mimic(m, i))
      fail(file, "<equality><" + std::string(equality_name(m->eq_type[i])) + "> '" +
                     name_of(m, mjOBJ_EQUALITY, i, "equality") + "' (" +
                     std::to_string(m->neq) + " in all): equality constraints are not supported");
  std::vector<std::string> free_bodies;
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] != mjJNT_FREE) continue;
    const int b = m->jnt_bodyid[j];
    if (m->body_jntnum[b] != 1)
      fail(file, "body '" + names.body[static_cast<size_t>(b)] + "': free joint '" +
                     names.joint[static_cast<size_t>(j)] +
                     "' is not the body's only joint (not supported)");
    free_bodies.push_back(names.body[static_cast<size_t>(b)]);
  }
  if (free_bodies.size() > 1)
    fail(file, "free bodies " + joined(free_bodies) +
                   ": featherdrive simulates one articulation with at most one free root");
}

// The featherdrive form of actuator i, or a warning saying why it has none.
bool map_actuator(const mjModel* m, const Names& names, int i, const UrdfRobot& robot,
                  const std::map<std::string, int>& link_of_joint, MjcfActuator& out,
                  std::string& why_not) {
  out.name = name_of(m, mjOBJ_ACTUATOR, i, "actuator");
  const std::string who = "actuator '" + out.name + "'";
  if (m->actuator_trntype[i] != mjTRN_JOINT && m->actuator_trntype[i] != mjTRN_JOINTINPARENT) {
    why_not = who + ": its transmission is not a joint; ignored";
    return false;
  }
  const int j = m->actuator_trnid[2 * i];
  out.joint = names.joint[static_cast<size_t>(j)];
  if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE) {
    why_not = who + " on joint '" + out.joint +
              "': only hinge and slide joints are driven; ignored";
    return false;
  }
  if (m->actuator_dyntype[i] != mjDYN_NONE || m->actuator_gaintype[i] != mjGAIN_FIXED) {
    why_not = who + ": activation dynamics or a non-fixed gain are not supported; ignored";
    return false;
  }
  const mjtNum* gain = m->actuator_gainprm + mjNGAIN * i;
  const mjtNum* bias = m->actuator_biasprm + mjNBIAS * i;
  out.gain = gain[0];
  out.gear = m->actuator_gear[6 * i];
  const bool no_bias = m->actuator_biastype[i] == mjBIAS_NONE ||
                       (bias[0] == 0.0 && bias[1] == 0.0 && bias[2] == 0.0);
  if (m->actuator_biastype[i] != mjBIAS_NONE && m->actuator_biastype[i] != mjBIAS_AFFINE) {
    why_not = who + ": a bias other than affine is not supported; ignored";
    return false;
  }
  if (no_bias) {
    out.kind = MjcfActuatorKind::motor;
  } else if (bias[0] == 0.0 && bias[1] == -gain[0] && bias[2] == 0.0 && gain[0] > 0.0) {
    out.kind = MjcfActuatorKind::position;
  } else if (bias[0] == 0.0 && bias[1] == 0.0 && bias[2] == -gain[0] && gain[0] > 0.0) {
    out.kind = MjcfActuatorKind::velocity;
  } else {
    why_not = who + ": gain " + format_double(gain[0]) + " with bias [" + format_double(bias[0]) +
              ", " + format_double(bias[1]) + ", " + format_double(bias[2]) +
              "] is neither a motor, a position nor a velocity actuator; ignored";
    return false;
  }
  if (m->actuator_forcelimited[i]) {
    out.force_lower = m->actuator_forcerange[2 * i];
    out.force_upper = m->actuator_forcerange[2 * i + 1];
  }
  if (m->actuator_ctrllimited[i]) {
    out.ctrl_lower = m->actuator_ctrlrange[2 * i];
    out.ctrl_upper = m->actuator_ctrlrange[2 * i + 1];
  }
  const auto link = link_of_joint.find(out.joint);
  out.dof = link == link_of_joint.end() ? -1 : robot.model->links[link->second].v_index;
  if (out.kind != MjcfActuatorKind::motor) {
    const double gear2 = out.gear * out.gear;
    out.actuator.kind = ActuatorKind::ideal_pd;
    (out.kind == MjcfActuatorKind::position ? out.actuator.stiffness : out.actuator.damping) =
        out.gain * gear2;
    const double force = std::max(std::abs(out.force_lower), std::abs(out.force_upper));
    if (std::isfinite(force) && force > 0.0) out.actuator.effort_limit = std::abs(out.gear) * force;
  }
  return true;
}

// The largest joint effort an actuator gives: gear times its force bound (forcerange, and for a
// motor gain times ctrlrange).
double effort_of(const MjcfActuator& a) {
  double force = std::max(std::abs(a.force_lower), std::abs(a.force_upper));
  const double ctrl = std::max(std::abs(a.ctrl_lower), std::abs(a.ctrl_upper));
  if (a.kind == MjcfActuatorKind::motor) force = std::min(force, std::abs(a.gain) * ctrl);
  return std::abs(a.gear) * force;
}

// The tree: one link per body, or a chain of links for a body with several joints (every link
// but the last massless). A link frame is its body's frame moved by the body's joints so far and
// shifted to the last joint's anchor (jnt_pos), so that a hinge turns it about its own origin.
struct Converter {
  Converter(const mjModel* model, const Names& n, const std::string& f, const UrdfOptions& o)
      : m(model), names(n), file(f), options(o) {}
  const mjModel* m;
  const Names& names;
  std::string file;
  UrdfOptions options;
  MjcfRobot robot;
  std::vector<std::string> link_of_body;  // the link a body's children hang from
  std::vector<Vec3> anchor_of_body;       // that link's origin in the body frame
  std::set<std::string> joint_names;
  bool world_root = false;  // several top-level bodies, or one with hinge/slide/ball joints

  void add(LinkSpec spec) { robot.links.push_back(std::move(spec)); }

  void convert_bodies() {
    for (int j = 0; j < m->njnt; ++j) joint_names.insert(names.joint[static_cast<size_t>(j)]);
    std::vector<int> tops;
    for (int b = 1; b < m->nbody; ++b)
      if (m->body_parentid[b] == 0) tops.push_back(b);
    if (tops.empty()) fail(file, "<worldbody> has no <body>: nothing to simulate");
    const int first = tops.front();
    const bool first_free = m->body_jntnum[first] == 1 &&
                            m->jnt_type[m->body_jntadr[first]] == mjJNT_FREE;
    world_root = tops.size() > 1 || !(m->body_jntnum[first] == 0 || first_free);
    if (world_root && !options.fixed_base)
      for (int b : tops)
        if (m->body_jntnum[b] == 1 && m->jnt_type[m->body_jntadr[b]] == mjJNT_FREE)
          fail(file, "body '" + names.body[static_cast<size_t>(b)] +
                         "': a free body beside other top-level bodies or joints (one "
                         "articulation with one root is supported; fixed_base welds it)");
    link_of_body.assign(static_cast<size_t>(m->nbody), "");
    anchor_of_body.assign(static_cast<size_t>(m->nbody), Vec3::Zero());
    if (world_root) {
      // MuJoCo's world body (a name no MJCF body may take) as a massless fixed root.
      robot.root_link = "world";
      robot.root_joint = free_name("root_joint", joint_names);
      LinkSpec world;
      world.name = "world";
      world.joint = fixed_joint(robot.root_joint);
      add(world);
      link_of_body[0] = "world";
    }
    for (int b = 1; b < m->nbody; ++b) convert_body(b);
  }

  void convert_body(int b) {
    const std::string body = names.body[static_cast<size_t>(b)];
    const int parent = m->body_parentid[b];
    const bool is_root = !world_root && parent == 0;
    // The body frame (before its joints move it) in the parent link frame.
    const Vec3 position = vec3(m->body_pos + 3 * b) - anchor_of_body[parent];
    const Mat3 R = rotation(m->body_quat + 4 * b);
    const int n = m->body_jntnum[b];
    const int first = m->body_jntadr[b];
    LinkSpec spec;
    spec.parent = is_root ? "" : link_of_body[parent];
    if (n == 0 || m->jnt_type[first] == mjJNT_FREE) {
      spec.name = body;
      if (is_root) {
        robot.root_link = body;
        const char* free = n ? mj_id2name(m, mjOBJ_JOINT, first) : nullptr;
        robot.root_joint = free && *free ? free : free_name("root_joint", joint_names);
      }
      const bool floating = n && !options.fixed_base;
      spec.joint = floating ? floating_joint(robot.root_joint)
                            : fixed_joint(is_root ? robot.root_joint
                                                  : free_name(body + "_weld", joint_names),
                                          position, rpy_from_rotation(R));
      if (!is_root) joint_names.insert(spec.joint.name);
      finish_body(b, spec, Vec3::Zero());
      return;
    }
    Vec3 previous_anchor = Vec3::Zero();
    for (int k = 0; k < n; ++k) {
      const int j = first + k;
      const std::string joint = names.joint[static_cast<size_t>(j)];
      const Vec3 anchor = vec3(m->jnt_pos + 3 * j);
      const Vec3 axis = vec3(m->jnt_axis + 3 * j);
      // Joint frame in the previous link frame: the body frame at the anchor (k = 0), or the
      // previous anchor moved to this one; a hinge's or slide's ref (qpos0) is taken back so
      // that featherdrive's q equals MuJoCo's qpos.
      Mat3 joint_R = k == 0 ? R : Mat3::Identity();
      Vec3 joint_p = k == 0 ? Vec3(position + R * anchor) : Vec3(anchor - previous_anchor);
      const double ref = m->qpos0[m->jnt_qposadr[j]];
      JointSpec& js = spec.joint;
      js = JointSpec{};
      js.name = joint;
      js.axis = axis;
      switch (m->jnt_type[j]) {
        case mjJNT_HINGE:
          js.type = JointType::revolute;
          if (ref != 0.0) joint_R = joint_R * Eigen::AngleAxisd(-ref, axis).toRotationMatrix();
          break;
        case mjJNT_SLIDE:
          js.type = JointType::prismatic;
          joint_p -= joint_R * (ref * axis);
          break;
        case mjJNT_BALL: js.type = JointType::spherical; break;
        default: fail(file, "joint '" + joint + "': unknown type " +
                                std::to_string(m->jnt_type[j]));
      }
      js.origin_xyz = joint_p;
      js.origin_rpy = rpy_from_rotation(joint_R);
      const int dof = m->jnt_dofadr[j];
      const int nv = js.type == JointType::spherical ? 3 : 1;
      js.armature.assign(m->dof_armature + dof, m->dof_armature + dof + nv);
      if (std::all_of(js.armature.begin(), js.armature.end(), [](double a) { return a == 0; }))
        js.armature.clear();
      js.damping = m->dof_damping[dof];
      js.friction = m->dof_frictionloss[dof];
      if (m->jnt_limited[j] && nv == 1) {
        js.lower_limit = m->jnt_range[2 * j];
        js.upper_limit = m->jnt_range[2 * j + 1];
      } else if (m->jnt_limited[j]) {
        ball_ranges.push_back(joint);
      }
      if (m->jnt_stiffness[j] != 0.0 && nv == 1) {
        robot.springs.push_back({joint, m->jnt_stiffness[j], m->qpos_spring[m->jnt_qposadr[j]]});
        springs.push_back(joint);
      } else if (m->jnt_stiffness[j] != 0.0) {
        ball_springs.push_back(joint);
      }
      if (js.damping != 0.0 || js.friction != 0.0) passive.push_back(joint);
      robot.joint_order.push_back(joint);
      spec.name = k + 1 == n ? body : body + "/" + joint;
      if (k + 1 < n) {
        add(spec);  // massless: only the body's last link carries its inertia
        spec.parent = spec.name;
      }
      previous_anchor = anchor;
    }
    finish_body(b, spec, previous_anchor);
  }

  // The body's inertia on its last link, whose origin is `anchor` in the body frame.
  void finish_body(int b, LinkSpec& spec, const Vec3& anchor) {
    const Mat3 Ri = rotation(m->body_iquat + 4 * b);
    spec.mass = m->body_mass[b];
    spec.com = vec3(m->body_ipos + 3 * b) - anchor;
    spec.inertia = Ri * vec3(m->body_inertia + 3 * b).asDiagonal() * Ri.transpose();
    link_of_body[static_cast<size_t>(b)] = spec.name;
    anchor_of_body[static_cast<size_t>(b)] = anchor;
    add(spec);
  }

  std::vector<std::string> springs, ball_springs, passive, ball_ranges;
};

const char* geom_type_name(int type) {
  switch (type) {
    case mjGEOM_PLANE: return "plane";
    case mjGEOM_HFIELD: return "hfield";
    case mjGEOM_SPHERE: return "sphere";
    case mjGEOM_CAPSULE: return "capsule";
    case mjGEOM_ELLIPSOID: return "ellipsoid";
    case mjGEOM_CYLINDER: return "cylinder";
    case mjGEOM_BOX: return "box";
    case mjGEOM_MESH: return "mesh";
    default: return "unknown";
  }
}

// The geoms that collide (contype or conaffinity set; the others are visual) as contact shapes
// on their bodies' links: sphere, capsule and cylinder (fromto is already size and pose in
// mjModel), box, ellipsoid and mesh (its convex hull),
// friction[0] as static and dynamic friction (MuJoCo's sliding friction; restitution 0). The
// first plane on the world body is the robot's ground (none where the file disables contacts);
// other world geoms are warned about, and
// the kinds contacts cannot use yet are listed (Model::unsupported_shapes).
// Returns the warning about the world's other geoms, or "".
std::string convert_geoms(const mjModel* m, const Converter& c, MjcfRobot& robot) {
  std::vector<std::string> world_geoms;
  // <option><flag contact="disable"/>: the file simulates no contacts, so it has no floor.
  const bool contacts = !(m->opt.disableflags & mjDSBL_CONTACT);
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_contype[g] == 0 && m->geom_conaffinity[g] == 0) continue;
    const char* given = mj_id2name(m, mjOBJ_GEOM, g);
    const std::string name = given ? given : "";
    const std::string label = name.empty() ? "#" + std::to_string(g) : "'" + name + "'";
    const int type = m->geom_type[g];
    const int b = m->geom_bodyid[g];
    const Mat3 R = rotation(m->geom_quat + 4 * g);
    const double friction = m->geom_friction[3 * g];
    if (b == 0) {
      if (type == mjGEOM_PLANE && !robot.ground && contacts) {
        Ground ground;
        ground.enabled = true;
        ground.normal = R.col(2);  // a plane geom's normal is its frame's z
        ground.height = ground.normal.dot(vec3(m->geom_pos + 3 * g));
        ground.material = Material{friction, friction, 0.0};
        robot.ground = ground;
      } else if (contacts) {
        world_geoms.push_back(std::string(geom_type_name(type)) + " " + label);
      }
      continue;
    }
    const std::string& link = c.link_of_body[static_cast<size_t>(b)];
    CollisionShape shape;
    shape.name = name;
    // The body frame and its last link's frame differ by the anchor only (Converter).
    shape.position = vec3(m->geom_pos + 3 * g) - c.anchor_of_body[static_cast<size_t>(b)];
    shape.rotation = R;
    shape.material = Material{friction, friction, 0.0};
    const mjtNum* size = m->geom_size + 3 * g;
    switch (type) {
      case mjGEOM_SPHERE:
        shape.type = ShapeType::sphere;
        shape.size = Vec3(size[0], 0.0, 0.0);
        break;
      case mjGEOM_CAPSULE:
        shape.type = ShapeType::capsule;
        shape.size = Vec3(size[0], size[1], 0.0);
        break;
      case mjGEOM_BOX:
        shape.type = ShapeType::box;
        shape.size = vec3(size);
        break;
      case mjGEOM_CYLINDER:  // size: radius, half length (fromto is resolved as for capsules)
        shape.type = ShapeType::cylinder;
        shape.size = Vec3(size[0], size[1], 0.0);
        break;
      case mjGEOM_MESH:  // its convex hull, in the geom's frame (docs/math/contact.md, G3)
        shape.type = ShapeType::convex;
        shape.vertices = mesh_hull::vertices(m, m->geom_dataid[g]);
        mesh_hull::sort_vertices(shape.vertices);
        break;
      case mjGEOM_ELLIPSOID:
        shape.type = ShapeType::ellipsoid;
        shape.size = vec3(size);
        break;
      default:
        robot.unsupported_shapes.push_back("link '" + link + "': " + geom_type_name(type) +
                                           " geom " + label);
        continue;
    }
    robot.shapes.emplace_back(link, std::move(shape));
  }
  std::string out;
  for (const std::string& g : world_geoms)
    out += (out.empty() ? "geoms of the world body other than its first plane (the ground) are "
                          "not simulated: " : ", ") + g;
  return out;
}

void warn_about_ignored(const mjModel* m, const Converter& c, const UrdfOptions& options,
                        std::vector<std::string>& warnings) {
  // The pairs of the robot's own geoms MuJoCo lets collide: contype / conaffinity match, on
  // bodies that are not welded together nor (filterparent) parent and child.
  int pairs = 0;
  const bool filter_parent = !(m->opt.disableflags & mjDSBL_FILTERPARENT);
  for (int g1 = 0; g1 < m->ngeom; ++g1)
    for (int g2 = g1 + 1; g2 < m->ngeom; ++g2) {
      const int w1 = m->body_weldid[m->geom_bodyid[g1]], w2 = m->body_weldid[m->geom_bodyid[g2]];
      if (w1 == 0 || w2 == 0 || w1 == w2) continue;  // the world's geoms are the ground's
      if (filter_parent && (m->body_weldid[m->body_parentid[w1]] == w2 ||
                            m->body_weldid[m->body_parentid[w2]] == w1))
        continue;
      pairs += (m->geom_contype[g1] & m->geom_conaffinity[g2]) ||
               (m->geom_contype[g2] & m->geom_conaffinity[g1]);
    }
  if (pairs > 0 && !(m->opt.disableflags & mjDSBL_CONTACT))
    warnings.push_back(std::to_string(pairs) + " pairs of the robot's own geoms collide in " +
                       "MuJoCo; featherdrive's shapes collide with each other only with contact: " +
                       "{self_collision: true} (off by default; parent and child links never)");
  if (!c.springs.empty())
    warnings.push_back("joint stiffness becomes a joint spring toward springref, solved as an "
                       "implicit row, not MuJoCo's explicit passive force, on joints " +
                       joined(c.springs));
  if (!c.ball_springs.empty())
    warnings.push_back("joint stiffness (MuJoCo's passive spring) is not simulated on ball "
                       "joints " + joined(c.ball_springs));
  if (!c.passive.empty())
    warnings.push_back("joint damping and frictionloss become joint friction (viscous = damping, "
                       "static = dynamic = frictionloss), solved as rows, not MuJoCo's passive "
                       "forces, on joints " + joined(c.passive));
  if (!c.ball_ranges.empty())
    warnings.push_back("ball joint ranges (cones) are not simulated on joints " +
                       joined(c.ball_ranges));
  if (vec3(m->opt.gravity) != options.gravity)
    warnings.push_back("<option gravity> = " + format_vec3(vec3(m->opt.gravity)) +
                       " is not used; gravity is " + format_vec3(options.gravity));
}

// A massless subtree, or two joints of one body moving it the same way, leave a direction of
// motion without inertia: ABA would divide by zero. ABA factors the mass matrix (det M is the
// product of det D_i, D_i = S_i^T IA_i S_i + armature: the inertia joint i moves with every joint
// below it free), so M is singular exactly when some D_i is. Each D_i is compared with its own
// scale, IA_i's largest entry at the link's origin, so that a long chain's conditioning does not
// count against it. O(n), at qpos0.
void check_well_posed(const MjcfRobot& robot, const std::string& file) {
  const Model& model = *robot.model;
  if (model.nv == 0) return;
  Data data(model);
  forward_kinematics(model, data, robot.q0);
  articulated_inertias(model, data);
  // Children come after parents: a singular D_i spoils its ancestors' IA only, so the first one
  // found from the end is a cause.
  for (int i = model.num_links() - 1; i >= 0; --i) {
    const int nv = data.info[i].nv;
    if (nv == 0) continue;
    const int v = data.info[i].v_index;
    // At the link origin p (world axes): IA_p = Y^T IA Y and S_p = Y^-1 S, Y = [1 0; [p]x 1].
    const Vec3 p = data.world_position[i] - data.frame_origin;
    Mat6 Y = Mat6::Identity();
    Y.bottomLeftCorner<3, 3>() = skew(p);
    const Mat6 IA = Y.transpose() * data.articulated_inertia[i] * Y;
    // A floating root's S in frame 0 is diag(R, R) (its origin is frame 0's), not stored.
    MatX S = MatX::Zero(6, nv);
    if (nv == 1) S = data.one_dof[i].S;
    else if (nv == 3) S = data.motion_subspace[i];
    else S.topLeftCorner<3, 3>() = S.bottomRightCorner<3, 3>() = data.world_rotation[i];
    S.bottomRows<3>() -= skew(p) * S.topRows<3>();
    MatX D = S.transpose() * IA * S;
    for (int k = 0; k < nv; ++k) D(k, k) += model.armature[v + k];
    const double scale = IA.cwiseAbs().maxCoeff() * S.colwise().squaredNorm().maxCoeff() +
                         model.armature.segment(v, nv).maxCoeff();
    const double pivot =
        nv == 1 ? D(0, 0) : Eigen::SelfAdjointEigenSolver<MatX>(D).eigenvalues()[0];
    if (pivot > 1e-9 * scale) continue;
    const Link& link = model.links[static_cast<size_t>(i)];
    fail(file, "joint '" + link.joint_name + "' (link '" + link.name +
                   "') moves no inertia at qpos0 (the mass matrix's pivot " +
                   format_double(pivot) + " against " + format_double(scale) +
                   "): no mass below it, or another joint of its body moving it the same way; "
                   "give the body mass or the joint armature");
  }
}

MjcfRobot convert(const mjModel* m, const std::string& file, const UrdfOptions& options,
                  std::vector<std::string> warnings) {
  const Names names(m);
  refuse_unsupported(m, names, file);
  Converter c(m, names, file, options);
  c.robot.path = file;
  c.robot.options = options;
  c.robot.name = m->names;  // the model's name comes first in MuJoCo's name buffer
  c.convert_bodies();
  MjcfRobot& robot = c.robot;
  const std::string world_geoms = convert_geoms(m, c, robot);
  robot.rebuild();
  const std::shared_ptr<const Model> built = robot.model;  // rebuilt below with effort limits
  const Model& model = *built;

  // MuJoCo's qpos0 in our q: same joint order, same layout per joint.
  robot.q0 = VecX::Zero(model.nq);
  // The link of each joint name, once (a search per joint is quadratic in large models).
  std::map<std::string, int> link_of_joint;
  for (int i = 0; i < model.num_links(); ++i) link_of_joint.emplace(model.links[i].joint_name, i);
  for (int j = 0; j < m->njnt; ++j) {
    auto it = link_of_joint.find(names.joint[static_cast<size_t>(j)]);
    // An unnamed free joint is the floating root's, named root_joint here.
    if (m->jnt_type[j] == mjJNT_FREE && model.floating_base())
      it = link_of_joint.find(robot.root_joint);
    if (it == link_of_joint.end()) continue;
    const Link& link = model.links[static_cast<size_t>(it->second)];
    if (link.nq > 0)
      robot.q0.segment(link.q_index, link.nq) =
          Eigen::Map<const VecX>(m->qpos0 + m->jnt_qposadr[j], link.nq);
  }
  for (const Link& link : model.links)
    if (link.joint_type == JointType::spherical) robot.q0[link.q_index] = 1.0;

  // The file-order maps: MuJoCo's joint order is our link order, so dofs keep their order.
  const size_t n = robot.joint_order.size();
  robot.dof_of_urdf_joint.assign(n, -1);
  robot.link_of_urdf_joint.assign(n, -1);
  robot.urdf_joint_of_dof.assign(static_cast<size_t>(model.nv), -1);
  robot.dof_order.clear();
  for (int d = 0; d < model.nv; ++d) robot.dof_order.push_back(d);
  for (size_t j = 0; j < n; ++j) {
    const auto it = link_of_joint.find(robot.joint_order[j]);
    if (it == link_of_joint.end()) continue;
    const Link& link = model.links[static_cast<size_t>(it->second)];
    robot.link_of_urdf_joint[j] = it->second;
    robot.dof_of_urdf_joint[j] = link.v_index;
    for (int d = 0; d < link.nv; ++d)
      robot.urdf_joint_of_dof[static_cast<size_t>(link.v_index + d)] = static_cast<int>(j);
  }

  std::map<std::string, double> effort;  // summed over each joint's actuators
  for (int i = 0; i < m->nu; ++i) {
    MjcfActuator actuator;
    std::string why_not;
    if (!map_actuator(m, names, i, robot, link_of_joint, actuator, why_not)) {
      warnings.push_back(why_not);
      continue;
    }
    const std::string who = "actuator '" + actuator.name + "' on joint '" + actuator.joint + "'";
    if (actuator.gear == 0.0 || !std::isfinite(actuator.gear))
      fail(file, who + ": gear = " + format_double(actuator.gear) +
                     ": the joint force is gear times the actuator's, and its target ctrl / gear");
    const double gain = actuator.actuator.stiffness + actuator.actuator.damping;
    if (!std::isfinite(gain))
      fail(file, who + ": gain " + format_double(actuator.gain) + " x gear^2 (gear " +
                     format_double(actuator.gear) + ") = " + format_double(gain) +
                     ": does not fit a double");
    if (actuator.force_lower != -actuator.force_upper && actuator.kind != MjcfActuatorKind::motor)
      warnings.push_back("actuator '" + actuator.name + "': forcerange [" +
                         format_double(actuator.force_lower) + ", " +
                         format_double(actuator.force_upper) +
                         "] is not symmetric; effort_limit takes the larger bound");
    effort[actuator.joint] += effort_of(actuator);
    robot.actuators.push_back(std::move(actuator));
  }
  // Model::effort_limit and effort_limits are informative, as a URDF's <limit effort>.
  for (LinkSpec& spec : robot.links)
    if (spec.joint.type == JointType::revolute || spec.joint.type == JointType::prismatic) {
      const auto it = effort.find(spec.joint.name);
      robot.effort_limits[spec.joint.name] = spec.joint.effort_limit =
          it == effort.end() ? kInf : it->second;
    }
  if (!effort.empty()) robot.rebuild();
  // Joint equalities (refuse_unsupported let only these through) as a URDF's mimic tags.
  // MuJoCo's law is relative to qpos0 (the joints' refs r): q1 - r1 = c0 + c1 (q2 - r2), so
  // joint1 = c1 joint2 + c0 + r1 - c1 r2.
  for (int i = 0; i < m->neq; ++i) {
    const mjtNum* c = m->eq_data + mjNEQDATA * i;
    const int j1 = m->eq_obj1id[i], j2 = m->eq_obj2id[i];
    UrdfMimic& tag = robot.mimics.emplace_back();
    tag.joint = names.joint[static_cast<size_t>(j1)];
    tag.leader = names.joint[static_cast<size_t>(j2)];
    tag.multiplier = c[1];
    tag.offset = c[0] + m->qpos0[m->jnt_qposadr[j1]] - c[1] * m->qpos0[m->jnt_qposadr[j2]];
    MimicJoint& row = robot.mimic_joints.emplace_back();
    row.dof_a = robot.model->dof_index(tag.joint);
    row.dof_b = robot.model->dof_index(tag.leader);
    row.gear_ratio = -tag.multiplier;
    row.offset = -tag.offset;
  }
  try {
    validate_mimic_joints(*robot.model, robot.mimic_joints);
  } catch (const std::invalid_argument& e) {
    fail(file, std::string("<equality><joint>: ") + e.what());
  }
  warn_about_ignored(m, c, options, warnings);
  if (!world_geoms.empty()) warnings.push_back(world_geoms);
  if (!options.fixed_base && !robot.model->floating_base())
    warnings.push_back("fixed_base is false but no body has a free joint: the root stays welded");
  robot.warnings = std::move(warnings);
  check_well_posed(robot, file);
  return std::move(robot);
}

MjcfRobot load(const char* filename, const mjVFS* vfs, const std::string& file,
               const UrdfOptions& options, std::vector<std::filesystem::path>& files) {
  std::vector<std::string> warnings;
  std::string error;
  const mujoco_calls::ModelPtr m =
      mujoco_calls::load_xml(filename, vfs, error, warnings, &files);
  if (!m) fail(file, "MuJoCo cannot load it: " + error);
  MjcfRobot robot = convert(m.get(), file, options, std::move(warnings));
  robot.input_files = std::move(files);
  return robot;
}

}  // namespace

const char* to_string(MjcfActuatorKind kind) {
  switch (kind) {
    case MjcfActuatorKind::motor: return "motor";
    case MjcfActuatorKind::position: return "position";
    case MjcfActuatorKind::velocity: return "velocity";
  }
  return "unknown";
}

MjcfRobot load_mjcf(const std::filesystem::path& path, const UrdfOptions& options) {
  std::vector<std::filesystem::path> files;  // load_xml checks the document and fills it
  MjcfRobot robot = load(path.c_str(), nullptr, path.string(), options, files);
  robot.path = path;
  return robot;
}

std::vector<std::filesystem::path> mjcf_input_files(const std::filesystem::path& path) {
  return mjcf_document::check(path.string(), nullptr, path.string());
}

MjcfRobot parse_mjcf(const std::string& xml, const std::string& name,
                     const UrdfOptions& options) {
  if (xml.find('\0') != std::string::npos) fail(name, "a NUL character in the text");
  if (xml.empty()) fail(name, "empty text (an MJCF file is <mujoco>...</mujoco>)");
  if (xml.size() > kMaxInputBytes)
    fail(name, "the text is larger than " + std::to_string(kMaxInputBytes >> 20) + " MiB");
  // mjVFS holds 2000 file names of 1000 bytes: too large for the stack.
  const auto vfs = std::make_unique<mjVFS>();
  mujoco_calls::route_warnings();  // MuJoCo's errors throw from here on
  mj_defaultVFS(vfs.get());
  const char* filename = "model.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), filename, static_cast<int>(xml.size())) != 0)
    fail(name, "MuJoCo's virtual file system refused the text");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), filename)], xml.data(), xml.size());
  MjcfRobot robot;
  try {
    std::vector<std::filesystem::path> files = mjcf_document::check(filename, vfs.get(), name);
    robot = load(filename, vfs.get(), name, options, files);
  } catch (...) {
    mj_deleteVFS(vfs.get());
    throw;
  }
  mj_deleteVFS(vfs.get());
  return robot;
}

// Each dof's actuator: a position and a velocity actuator on one joint become one.
static std::map<int, ExplicitActuator> actuators_by_dof(const MjcfRobot& robot) {
  std::map<int, ExplicitActuator> by_dof;
  for (const MjcfActuator& a : robot.actuators) {
    if (a.actuator.kind == ActuatorKind::none) continue;
    const auto [it, first] = by_dof.emplace(a.dof, a.actuator);
    if (first) continue;
    ExplicitActuator& both = it->second;
    both.stiffness += a.actuator.stiffness;
    both.damping += a.actuator.damping;
    both.effort_limit += a.actuator.effort_limit;
  }
  return by_dof;
}

void apply_mjcf_actuators(const MjcfRobot& robot, Simulation& sim) {
  for (const auto& [dof, actuator] : actuators_by_dof(robot)) sim.set_actuator(dof, actuator);
}

Settings robot_settings(const MjcfRobot& robot, const SimulationOptions& options) {
  validate_options(options);
  Settings settings = Settings::defaults(*robot.model, options);
  settings.mimic_joints = robot.mimic_joints;
  for (const auto& [dof, actuator] : actuators_by_dof(robot))
    settings.actuators[static_cast<size_t>(dof)] = actuator;
  apply_robot_springs(robot, settings);
  apply_urdf_effort_limits(robot, settings);
  settings.validate(*robot.model);
  return settings;
}

std::string describe_actuators(const MjcfRobot& robot) {
  if (robot.actuators.empty()) return "";
  std::ostringstream out;
  out << "\nMJCF actuators (" << robot.actuators.size() << "):\n";
  auto range = [](double lo, double hi) {
    return std::isfinite(lo) || std::isfinite(hi)
               ? "[" + format_double(lo) + ", " + format_double(hi) + "]"
               : std::string("none");
  };
  for (const MjcfActuator& a : robot.actuators) {
    out << "  " << a.name << ": " << to_string(a.kind) << " on " << a.joint << ", gain "
        << format_double(a.gain) << ", gear " << format_double(a.gear) << ", forcerange "
        << range(a.force_lower, a.force_upper) << ", ctrlrange "
        << range(a.ctrl_lower, a.ctrl_upper) << " -> ";
    if (a.actuator.kind == ActuatorKind::none)
      out << "no drive (give one in the scene)\n";
    else
      out << "ideal_pd stiffness " << format_double(a.actuator.stiffness) << ", damping "
          << format_double(a.actuator.damping) << ", effort_limit "
          << format_double(a.actuator.effort_limit) << ", target ctrl / gear\n";
  }
  return out.str();
}

UrdfRobot load_robot(const std::filesystem::path& path, const UrdfOptions& options) {
  if (is_mjcf_file(path)) return load_mjcf(path, options);
  return load_urdf(path, options);
}

bool is_mjcf_file(const std::filesystem::path& path) {
  if (path.extension() == ".urdf") return false;
  std::string text;
  try {
    text = read_input_file(path);
  } catch (const InputError&) {
    return path.extension() == ".xml";  // the loader chosen reports the error
  }
  // The first element that is not a declaration, comment or doctype.
  for (size_t i = text.find('<'); i != std::string::npos; i = text.find('<', i + 1)) {
    if (text.compare(i, 4, "<!--") == 0) {
      i = text.find("-->", i);
      if (i == std::string::npos) break;
      continue;
    }
    if (text.compare(i, 2, "<?") == 0 || text.compare(i, 2, "<!") == 0) continue;
    return text.compare(i + 1, 6, "mujoco") == 0;
  }
  return path.extension() == ".xml";
}

}  // namespace featherdrive
