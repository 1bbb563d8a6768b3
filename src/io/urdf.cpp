#include "featherdrive/io/urdf.hpp"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>

#include "featherdrive/core/format.hpp"
#include "featherdrive/io/files.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "input_error.hpp"
#include "mesh_hull.hpp"
#include "xml_text.hpp"

namespace featherdrive {
namespace {

using io_detail::fail;
using io_detail::kInf;

// urdfdom reports why a parse failed through console_bridge only; collect those messages so the
// error we throw carries them. console_bridge's handler is global, hence the lock.
class CollectMessages : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR)
      errors.push_back(text);
    else if (level == console_bridge::CONSOLE_BRIDGE_LOG_WARN)
      warnings.push_back(text);
  }
  std::vector<std::string> errors, warnings;
};

std::mutex console_mutex;

urdf::ModelInterfaceSharedPtr parse_with_urdfdom(const std::string& xml, const std::string& file,
                                                 std::vector<std::string>& warnings) {
  std::lock_guard<std::mutex> lock(console_mutex);
  CollectMessages collect;
  console_bridge::useOutputHandler(&collect);
  urdf::ModelInterfaceSharedPtr model;
  std::string exception;
  try {
    model = urdf::parseURDF(xml);
  } catch (const std::exception& e) {
    exception = e.what();
  }
  console_bridge::restorePreviousOutputHandler();
  for (const std::string& w : collect.warnings) warnings.push_back("urdfdom: " + w);
  // urdfdom logs some errors (bad numbers in <inertial>) and still returns a model; take any as
  // fatal.
  if (!model || !collect.errors.empty()) {
    std::string why;
    for (const std::string& e : collect.errors) why += (why.empty() ? "" : "; ") + e;
    if (!exception.empty()) why += (why.empty() ? "" : "; ") + exception;
    if (why.empty()) why = "urdfdom rejected the file";
    fail(file, "invalid URDF: " + why);
  }
  return model;
}

struct Pose {
  Mat3 R = Mat3::Identity();
  Vec3 p = Vec3::Zero();
  bool identity_rotation = true;  // exactly the identity: keeps joint rpy bit for bit
  Vec3 rpy = Vec3::Zero();        // of R; exact copy where R came straight from a URDF origin
};

Pose pose_of(const urdf::Pose& u) {
  Pose pose;
  pose.p = Vec3(u.position.x, u.position.y, u.position.z);
  const urdf::Rotation& r = u.rotation;
  if (!(r.x == 0.0 && r.y == 0.0 && r.z == 0.0 && r.w == 1.0)) {
    pose.R = Quat(r.w, r.x, r.y, r.z).normalized().toRotationMatrix();
    pose.identity_rotation = false;
    pose.rpy = rpy_from_rotation(pose.R);
  }
  return pose;
}

// a * b: b's frame given in a's frame, expressed in the frame a is given in.
Pose compose(const Pose& a, const Pose& b) {
  Pose c;
  c.p = a.identity_rotation ? Vec3(a.p + b.p) : Vec3(a.p + a.R * b.p);
  if (a.identity_rotation) {
    c.R = b.R;
    c.identity_rotation = b.identity_rotation;
    c.rpy = b.rpy;
  } else if (b.identity_rotation) {
    c.R = a.R;
    c.identity_rotation = false;
    c.rpy = a.rpy;
  } else {
    c.R = a.R * b.R;
    c.identity_rotation = false;
    c.rpy = rpy_from_rotation(c.R);
  }
  return c;
}

struct Body {
  double mass = 0.0;
  Vec3 com = Vec3::Zero();
  Mat3 inertia = Mat3::Zero();  // about com, in the frame's axes
  bool has_inertial = false;
};

// Two rigid bodies as one: masses add, the centre of mass is the weighted mean and each inertia
// moves to the common centre of mass by the parallel axis theorem.
Body combine(const Body& a, const Body& b) {
  // A massless frame adds nothing; keep the other body's numbers exactly.
  if (a.mass == 0.0 && a.inertia.isZero(0.0))
    return {b.mass, b.com, b.inertia, a.has_inertial || b.has_inertial};
  if (b.mass == 0.0 && b.inertia.isZero(0.0))
    return {a.mass, a.com, a.inertia, a.has_inertial || b.has_inertial};
  Body c;
  c.has_inertial = a.has_inertial || b.has_inertial;
  c.mass = a.mass + b.mass;
  if (c.mass <= 0.0) {
    c.inertia = a.inertia + b.inertia;
    return c;
  }
  c.com = (a.mass * a.com + b.mass * b.com) / c.mass;
  auto shift = [&](const Body& x) {
    const Vec3 d = x.com - c.com;
    return Mat3(x.inertia + x.mass * (d.squaredNorm() * Mat3::Identity() - d * d.transpose()));
  };
  c.inertia = shift(a) + shift(b);
  return c;
}

std::string joint_type_name(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE:
      return "revolute";
    case urdf::Joint::CONTINUOUS:
      return "continuous";
    case urdf::Joint::PRISMATIC:
      return "prismatic";
    case urdf::Joint::FLOATING:
      return "floating";
    case urdf::Joint::PLANAR:
      return "planar";
    case urdf::Joint::FIXED:
      return "fixed";
    default:
      return "unknown";
  }
}

// The maps between joint_order and the model's dofs and links (UrdfRobot), one lookup per joint.
void map_urdf_joints(UrdfRobot& robot, const urdf::ModelInterface& urdf_model) {
  const Model& model = *robot.model;
  std::map<std::string, int> link_of;
  for (int i = 0; i < model.num_links(); ++i) link_of.emplace(model.links[i].name, i);
  const size_t n = robot.joint_order.size();
  robot.dof_of_urdf_joint.assign(n, -1);
  robot.link_of_urdf_joint.assign(n, -1);
  robot.urdf_joint_of_dof.assign(static_cast<size_t>(model.nv), -1);
  for (size_t j = 0; j < n; ++j) {
    const urdf::JointConstSharedPtr joint = urdf_model.getJoint(robot.joint_order[j]);
    if (!joint) continue;
    std::string child = joint->child_link_name;
    if (const auto m = robot.merged.find(child); m != robot.merged.end()) child = m->second.into;
    const auto link = link_of.find(child);
    if (link == link_of.end()) continue;
    robot.link_of_urdf_joint[j] = link->second;
    if (joint->type == urdf::Joint::FIXED) continue;
    const int dof = model.links[link->second].v_index;
    robot.dof_of_urdf_joint[j] = dof;
    for (int d = dof; d < dof + model.links[link->second].nv; ++d)  // a spherical joint's three
      robot.urdf_joint_of_dof[static_cast<size_t>(d)] = static_cast<int>(j);
  }
}

// Each link's visuals and collisions, placed in its anchor's frame (in_anchor: the link frame's
// pose there). Links not reached from the root have no anchor and are left out.
void collect_geometry(UrdfRobot& robot, const urdf::ModelInterface& urdf_model,
                      const std::vector<std::string>& link_order,
                      const std::map<std::string, std::string>& anchor,
                      const std::map<std::string, Pose>& in_anchor) {
  auto add = [&](const std::string& link, bool collision, int index, const std::string& name,
                 const urdf::Pose& origin, const urdf::GeometrySharedPtr& g) {
    if (!g) return;
    UrdfGeometry out;
    out.link = link;
    out.name = name;
    out.body = anchor.at(link);
    out.collision = collision;
    out.index = index;
    const Pose pose = compose(in_anchor.at(link), pose_of(origin));
    out.xyz = pose.p;
    out.rotation = pose.R;
    switch (g->type) {
      case urdf::Geometry::BOX: {
        const urdf::Vector3& d = static_cast<const urdf::Box&>(*g).dim;
        out.shape = UrdfGeometry::Shape::box;
        out.size = Vec3(d.x, d.y, d.z);
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& c = static_cast<const urdf::Cylinder&>(*g);
        out.shape = UrdfGeometry::Shape::cylinder;
        out.size = Vec3(c.radius, c.length, 0.0);
        break;
      }
      case urdf::Geometry::SPHERE:
        out.shape = UrdfGeometry::Shape::sphere;
        out.size = Vec3(static_cast<const urdf::Sphere&>(*g).radius, 0.0, 0.0);
        break;
      case urdf::Geometry::MESH: {
        const auto& m = static_cast<const urdf::Mesh&>(*g);
        out.shape = UrdfGeometry::Shape::mesh;
        out.filename = m.filename;
        out.scale = Vec3(m.scale.x, m.scale.y, m.scale.z);
        break;
      }
      default:
        return;
    }
    robot.geometry.push_back(std::move(out));
  };
  for (const std::string& name : link_order) {
    const urdf::LinkConstSharedPtr link = urdf_model.getLink(name);
    if (!link || !anchor.count(name)) continue;
    for (size_t k = 0; k < link->visual_array.size(); ++k)
      if (link->visual_array[k])
        add(name, false, static_cast<int>(k), link->visual_array[k]->name,
            link->visual_array[k]->origin,
            link->visual_array[k]->geometry);
    for (size_t k = 0; k < link->collision_array.size(); ++k)
      if (link->collision_array[k])
        add(name, true, static_cast<int>(k), link->collision_array[k]->name,
            link->collision_array[k]->origin,
            link->collision_array[k]->geometry);
  }
}

// A mesh's file: package://NAME/REST in the nearest folder NAME above the URDF (else REST in the
// URDF's folder, the package's root as DART's files have it), file://PATH, or relative to the
// URDF's folder.
std::filesystem::path mesh_path(const std::string& file, const std::string& name,
                                const std::string& what) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::absolute(fs::path(file)).parent_path();
  if (name.rfind("package://", 0) == 0) {
    const std::string rest = name.substr(10);
    const size_t slash = rest.find('/');
    const std::string package = rest.substr(0, slash);
    const fs::path inside =
        slash == std::string::npos ? fs::path() : fs::path(rest.substr(slash + 1));
    for (fs::path f = folder; !f.empty(); f = f.parent_path()) {
      if (f.filename() == package) return f / inside;
      if (f == f.parent_path()) break;
    }
    return folder / inside;
  }
  if (name.rfind("file://", 0) == 0) return name.substr(7);
  if (name.find("://") != std::string::npos)
    fail(file, what + ": only package:// and file:// addresses are read");
  return folder / name;
}

// The collisions as contact shapes on their model links (boxes: half the URDF's full extents);
// what contacts cannot use yet is listed (docs/math/contact.md, section 10).
void collision_shapes(UrdfRobot& robot, const std::string& file) {
  for (const UrdfGeometry& g : robot.geometry) {
    if (!g.collision) continue;
    const std::string who = "link '" + g.link + "': <collision" +
                            (g.name.empty() ? "> #" + std::to_string(g.index)
                                            : " name='" + g.name + "'>");
    CollisionShape shape;
    shape.name = g.name;
    shape.position = g.xyz;
    shape.rotation = g.rotation;
    switch (g.shape) {
      case UrdfGeometry::Shape::box:
        if (!(g.size.allFinite() && g.size.minCoeff() > 0.0))
          fail(file, who + " <box size> = " + format_vec3(g.size) + ": must be finite and > 0");
        shape.type = ShapeType::box;
        shape.size = 0.5 * g.size;
        break;
      case UrdfGeometry::Shape::sphere:
        if (!(std::isfinite(g.size.x()) && g.size.x() > 0.0))
          fail(file, who + " <sphere radius> = " + format_double(g.size.x()) +
                         ": must be finite and > 0");
        shape.type = ShapeType::sphere;
        shape.size = g.size;
        break;
      case UrdfGeometry::Shape::cylinder:
        // <cylinder radius length>: the full length along z; the shape keeps half of it.
        if (!(std::isfinite(g.size.x()) && g.size.x() > 0.0))
          fail(file, who + " <cylinder radius> = " + format_double(g.size.x()) +
                         ": must be finite and > 0");
        if (!(std::isfinite(g.size.y()) && g.size.y() > 0.0))
          fail(file, who + " <cylinder length> = " + format_double(g.size.y()) +
                         ": must be finite and > 0");
        shape.type = ShapeType::cylinder;
        shape.size = Vec3(g.size.x(), 0.5 * g.size.y(), 0.0);
        break;
      case UrdfGeometry::Shape::mesh: {
        // The mesh's convex hull (docs/math/contact.md, G3), its vertices in the geometry frame.
        const std::string mesh = who + " <mesh filename> = '" + g.filename + "'";
        if (!(g.scale.allFinite() && g.scale.minCoeff() > 0.0))
          fail(file, who + " <mesh scale> = " + format_vec3(g.scale) + ": must be finite and > 0");
        const std::filesystem::path path = mesh_path(file, g.filename, mesh);
        if (!mesh_hull::readable_extension(path)) {
          robot.unsupported_shapes.push_back("link '" + g.link + "': mesh collision '" +
                                             g.filename + "' (meshes are read from STL, OBJ, " +
                                             "MSH, DAE)");
          continue;
        }
        try {
          shape.vertices = mesh_hull::load(path, g.scale);
        } catch (const std::runtime_error& e) {
          fail(file, mesh + ": " + e.what());
        }
        shape.type = ShapeType::convex;
        break;
      }
    }
    robot.shapes.emplace_back(g.body, std::move(shape));
  }
}

}  // namespace

Vec3 rpy_from_rotation(const Mat3& R) {
  // R = Rz(yaw) Ry(pitch) Rx(roll): R(2,0) = -sin(pitch), R(1,0)/R(0,0) = tan(yaw) and
  // R(2,1)/R(2,2) = tan(roll) while cos(pitch) != 0.
  const double c = std::hypot(R(0, 0), R(1, 0));
  const double pitch = std::atan2(-R(2, 0), c);
  if (c > 1e-6) return Vec3(std::atan2(R(2, 1), R(2, 2)), pitch, std::atan2(R(1, 0), R(0, 0)));
  // Gimbal lock: only roll -/+ yaw is defined; put it all in roll.
  return Vec3(std::atan2(-R(1, 2), R(1, 1)), pitch, 0.0);
}

void UrdfRobot::rebuild() {
  ModelBuilder builder;
  builder.set_gravity(options.gravity);
  for (const LinkSpec& l : links) builder.add_link(l);
  for (const auto& [name, m] : merged) builder.add_frame(name, m.into, m.xyz, m.rotation);
  for (const auto& [link, shape] : shapes) builder.add_shape(link, shape);
  for (const std::string& what : unsupported_shapes) builder.add_unsupported_shape(what);
  try {
    model = std::make_shared<const Model>(builder.build());
  } catch (const ModelError& e) {
    std::string what = e.what();
    if (what.rfind("model: ", 0) == 0) what = what.substr(7);
    fail(path.string(), what);
  }
}

UrdfRobot load_urdf(const std::filesystem::path& path, const UrdfOptions& options) {
  UrdfRobot robot = parse_urdf(read_input_file(path), path.string(), options);
  robot.path = path;
  robot.input_files = {path};  // featherdrive reads no mesh of a URDF
  return robot;
}

UrdfRobot parse_urdf(const std::string& xml, const std::string& file, const UrdfOptions& options) {
  UrdfRobot robot;
  robot.path = file;
  robot.options = options;
  if (!options.gravity.allFinite())
    fail(file, "gravity = " + format_vec3(options.gravity) + ": must be finite");

  // TinyXML (urdfdom's own XML reader) for the XML error position and the document order that
  // urdfdom's maps do not keep.
  try {
    xml_text::check_utf8(xml);
    xml_text::check_nesting(xml, kMaxUrdfDepth);
  } catch (const std::runtime_error& e) {
    fail(file, e.what());
  }
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  if (doc.Error())
    fail(file, "line " + std::to_string(doc.ErrorRow()) + ", column " +
                   std::to_string(doc.ErrorCol()) + ": malformed XML: " + doc.ErrorDesc());
  const TiXmlElement* robot_xml = doc.RootElement();
  if (!robot_xml || std::string(robot_xml->Value()) != "robot")
    fail(file, std::string("the root element is <") + (robot_xml ? robot_xml->Value() : "") +
                   ">, expected <robot>");
  std::vector<std::string> link_order;
  std::map<std::string, std::string> parent_of;     // child link -> parent link, from <joint>s
  std::map<std::string, std::string> parent_joint;  // child link -> its joint
  for (const TiXmlElement* e = robot_xml->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const char* name = e->Attribute("name");
    const std::string tag = e->Value();
    if ((tag == "link" || tag == "joint") && name)
      if (const std::string why = name_problem(name); !why.empty()) fail(file, tag + " " + why);
    if (tag == "link" && name) link_order.push_back(name);
    if (tag == "joint" && name) {
      robot.joint_order.push_back(name);
      const TiXmlElement* parent = e->FirstChildElement("parent");
      const TiXmlElement* child = e->FirstChildElement("child");
      const char* p = parent ? parent->Attribute("link") : nullptr;
      const char* c = child ? child->Attribute("link") : nullptr;
      if (p && c && std::string(p) == c)
        fail(file, "joint '" + std::string(name) + "': parent and child are both link '" + c + "'");
      if (!p || !c) continue;
      // urdfdom would hang the link under both parents (and a cycle through the second one made
      // the tree walk below endless).
      if (auto [it, added] = parent_joint.emplace(c, name); !added)
        fail(file, "link '" + std::string(c) + "' is the child of two joints, '" + it->second +
                       "' and '" + name + "'");
      parent_of.emplace(c, p);
    }
  }
  // A cycle of joints is refused here: urdfdom would build it from shared pointers and leak it.
  // Each link is marked by the first walk up that reaches it, so this is O(n) for any chain.
  std::map<std::string, std::string> walk;  // link -> the link whose walk reached it first
  for (const auto& [start, unused] : parent_of) {
    std::string link = start;
    while (walk.emplace(link, start).second) {
      auto it = parent_of.find(link);
      if (it == parent_of.end()) break;
      link = it->second;
    }
    if (walk[link] == start && parent_of.count(link))
      fail(file, "the joints form a cycle through link '" + link + "'");
  }

  // <joint type="spherical"> and its synonym "ball", an extension urdfdom refuses: urdfdom reads
  // them as continuous joints, built as spherical below (docs/conventions.md, "URDF").
  std::set<std::string> spherical;
  for (TiXmlElement* e = doc.RootElement()->FirstChildElement("joint"); e;
       e = e->NextSiblingElement("joint")) {
    const char* type = e->Attribute("type");
    const char* name = e->Attribute("name");
    if (!type || !name || (std::string(type) != "spherical" && std::string(type) != "ball"))
      continue;
    spherical.insert(name);
    e->SetAttribute("type", "continuous");
  }
  std::string rewritten;
  if (!spherical.empty()) {
    TiXmlPrinter printer;
    doc.Accept(&printer);
    rewritten = printer.CStr();
  }
  const urdf::ModelInterfaceSharedPtr urdf_model =
      parse_with_urdfdom(spherical.empty() ? xml : rewritten, file, robot.warnings);
  // urdfdom's links own their children, so freeing a long chain recursed once per link: cut the
  // links apart first (the map still owns every one).
  struct Unlink {
    urdf::ModelInterface& model;
    ~Unlink() {
      for (auto& [name, link] : model.links_) link->child_links.clear();
    }
  } unlink{*urdf_model};
  robot.name = urdf_model->getName();
  const urdf::LinkConstSharedPtr root = urdf_model->getRoot();
  robot.root_link = root->name;

  // Joint types first: an unsupported type is the clearest message for such a file.
  for (const std::string& name : robot.joint_order) {
    const urdf::JointConstSharedPtr j = urdf_model->getJoint(name);
    if (!j) continue;
    const std::string type = joint_type_name(j->type);
    if (j->type == urdf::Joint::FLOATING || j->type == urdf::Joint::PLANAR)
      fail(file, "joint '" + name + "' type = " + type +
                     ": not supported (featherdrive imports fixed, revolute, continuous, "
                     "prismatic and spherical joints; a floating root comes from fixed_base: "
                     "false)");
    if (j->type == urdf::Joint::UNKNOWN) fail(file, "joint '" + name + "' has an unknown type");
  }

  // Inertials, checked where they are written.
  std::map<std::string, Body> own;
  for (const std::string& name : link_order) {
    const urdf::LinkConstSharedPtr link = urdf_model->getLink(name);
    Body b;
    if (link && link->inertial) {
      const urdf::Inertial& in = *link->inertial;
      const std::string where = "link '" + name + "' <inertial>";
      if (!std::isfinite(in.mass) || in.mass < 0.0)
        fail(file,
             where + "<mass value> = " + format_double(in.mass) + ": must be finite and >= 0");
      const double entries[] = {in.ixx, in.ixy, in.ixz, in.iyy, in.iyz, in.izz};
      const char* names[] = {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"};
      for (int k = 0; k < 6; ++k)
        if (!std::isfinite(entries[k]))
          fail(file, where + "<inertia " + names[k] + "> = " + format_double(entries[k]) +
                         ": must be finite");
      const Pose origin = pose_of(in.origin);
      if (!origin.p.allFinite())
        fail(file, where + "<origin xyz> = " + format_vec3(origin.p) + ": must be finite");
      Mat3 I;
      I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
      b.mass = in.mass;
      b.com = origin.p;
      b.inertia = origin.identity_rotation ? I : Mat3(origin.R * I * origin.R.transpose());
      if (!b.inertia.allFinite())
        fail(file, where + "<inertia>: turned by <origin rpy> = " + format_vec3(origin.rpy) +
                       " it overflows");
      b.has_inertial = true;
    }
    own[name] = b;
  }

  // Each link's anchor: itself when it is the root or behind a moving joint, else its parent's
  // anchor; and its frame's pose in the anchor's frame. Parents first (walk from the root).
  std::map<std::string, std::string> anchor;
  std::map<std::string, Pose> in_anchor;
  std::map<std::string, Pose> joint_origin;  // of each kept non-root link, in its anchor parent
  std::map<std::string, Body> body;          // per kept link, merged
  std::vector<urdf::LinkConstSharedPtr> stack{root};
  anchor[root->name] = root->name;
  in_anchor[root->name] = Pose{};
  while (!stack.empty()) {
    const urdf::LinkConstSharedPtr link = stack.back();
    stack.pop_back();
    const std::string& a = anchor[link->name];
    Body& target = body[a];
    if (a == link->name) {
      target = combine(target, own[link->name]);
    } else {
      const Pose& p = in_anchor[link->name];
      Body moved = own[link->name];
      moved.com = p.identity_rotation ? Vec3(p.p + moved.com) : Vec3(p.p + p.R * moved.com);
      if (!p.identity_rotation) moved.inertia = p.R * moved.inertia * p.R.transpose();
      target = combine(target, moved);
      // Finite inputs can still overflow in the parallel axis shift (m d^2) or the mass sum.
      if (!(std::isfinite(target.mass) && target.com.allFinite() && target.inertia.allFinite()))
        fail(file, "link '" + link->name +
                       "' <inertial><origin xyz> = " + format_vec3(own[link->name].com) +
                       ", mass " + format_double(own[link->name].mass) + ": merged into link '" +
                       a + "' (fixed joints), the combined inertia overflows");
    }
    for (const urdf::JointSharedPtr& j : link->child_joints) {
      const urdf::LinkConstSharedPtr child = urdf_model->getLink(j->child_link_name);
      if (!child) continue;
      const Pose origin =
          compose(in_anchor[link->name], pose_of(j->parent_to_joint_origin_transform));
      if (!origin.p.allFinite())
        fail(file, "joint '" + j->name + "' <origin xyz> = " + format_vec3(origin.p) +
                       ": must be finite");
      if (j->type == urdf::Joint::FIXED) {
        anchor[child->name] = a;
        in_anchor[child->name] = origin;
        robot.merged[child->name] = MergedLink{a, origin.p, origin.R};
      } else {
        anchor[child->name] = child->name;
        in_anchor[child->name] = Pose{};
        joint_origin[child->name] = origin;
      }
      stack.push_back(child);
    }
  }

  collect_geometry(robot, *urdf_model, link_order, anchor, in_anchor);
  collision_shapes(robot, file);

  // The root's joint needs a name no URDF joint has.
  robot.root_joint = "root_joint";
  {
    const std::set<std::string> taken(robot.joint_order.begin(), robot.joint_order.end());
    while (taken.count(robot.root_joint)) robot.root_joint += "_";
  }

  for (const std::string& name : link_order) {
    if (!anchor.count(name) || anchor[name] != name) continue;
    const urdf::LinkConstSharedPtr link = urdf_model->getLink(name);
    const Body& b = body[name];
    const bool is_root = name == root->name;
    const bool moves = !is_root || !options.fixed_base;
    if (moves && !b.has_inertial)
      fail(file, "link '" + name + "' has no <inertial> (mass and inertia)" +
                     (is_root ? ": a floating root needs one (or use fixed_base: true)"
                              : ": a link behind a moving joint needs one"));
    if (moves && !(b.mass > 0.0))
      fail(file, "link '" + name + "' <inertial><mass value> = " + format_double(b.mass) +
                     ": must be > 0 for a link that moves");
    LinkSpec spec;
    spec.name = name;
    spec.mass = b.mass;
    spec.com = b.com;
    spec.inertia = b.inertia;
    if (is_root) {
      spec.joint =
          options.fixed_base ? fixed_joint(robot.root_joint) : floating_joint(robot.root_joint);
    } else {
      const urdf::JointConstSharedPtr j = link->parent_joint;
      spec.parent = anchor[j->parent_link_name];
      const Pose& origin = joint_origin[name];
      spec.joint.name = j->name;
      spec.joint.origin_xyz = origin.p;
      spec.joint.origin_rpy = origin.rpy;
      spec.joint.axis = Vec3(j->axis.x, j->axis.y, j->axis.z);
      const std::string where = "joint '" + j->name + "' <limit";
      switch (j->type) {
        case urdf::Joint::REVOLUTE:
        case urdf::Joint::PRISMATIC:
          spec.joint.type =
              j->type == urdf::Joint::REVOLUTE ? JointType::revolute : JointType::prismatic;
          if (j->limits) {
            spec.joint.lower_limit = j->limits->lower;
            spec.joint.upper_limit = j->limits->upper;
            if (std::isnan(j->limits->lower) || j->limits->lower == kInf)
              fail(file, where + " lower> = " + format_double(j->limits->lower) +
                             ": must be a number below inf");
            if (std::isnan(j->limits->upper) || j->limits->upper == -kInf)
              fail(file, where + " upper> = " + format_double(j->limits->upper) +
                             ": must be a number above -inf");
            if (j->limits->lower > j->limits->upper)
              fail(file, where + " lower> = " + format_double(j->limits->lower) +
                             ": is above upper = " + format_double(j->limits->upper));
            if (j->limits->lower == j->limits->upper)
              robot.warnings.push_back("joint '" + j->name + "': <limit> lower = upper = " +
                                       format_double(j->limits->lower) + ": the joint cannot move");
          }
          break;
        case urdf::Joint::CONTINUOUS:
          spec.joint.type = spherical.count(j->name) ? JointType::spherical : JointType::revolute;
          // A spherical joint's position limits are per axis, in the scene (PhysX's [-pi, pi]).
          if (spherical.count(j->name) && j->limits &&
              (j->limits->lower != 0.0 || j->limits->upper != 0.0))
            robot.warnings.push_back("joint '" + j->name + "' is spherical: <limit lower upper> "
                                     "is not read (limits are set per axis in the scene: joints: "
                                     "{" + j->name + ":twist: {lower: .., upper: ..}})");
          break;
        default:
          fail(file,
               "joint '" + j->name + "' type = " + joint_type_name(j->type) + ": not supported");
      }
      if (j->limits) {
        // URDF requires effort and velocity; 0 is commonly written for "unknown".
        const double effort = j->limits->effort, velocity = j->limits->velocity;
        if (!(effort >= 0.0))
          fail(file, where + " effort> = " + format_double(effort) + ": must be >= 0");
        if (!(velocity >= 0.0))
          fail(file, where + " velocity> = " + format_double(velocity) + ": must be >= 0");
        if (effort > 0.0) spec.joint.effort_limit = effort;
        if (velocity > 0.0)
          spec.joint.velocity_limit = velocity;
        else
          robot.warnings.push_back("joint '" + j->name +
                                   "': <limit velocity> = 0 read as no velocity limit");
      }
      robot.effort_limits[j->name] = spec.joint.effort_limit;
      if (j->dynamics) {
        const std::string d = "joint '" + j->name + "' <dynamics ";
        if (!std::isfinite(j->dynamics->damping) || j->dynamics->damping < 0.0)
          fail(file, d + "damping> = " + format_double(j->dynamics->damping) +
                         ": must be finite and >= 0");
        if (!std::isfinite(j->dynamics->friction) || j->dynamics->friction < 0.0)
          fail(file, d + "friction> = " + format_double(j->dynamics->friction) +
                         ": must be finite and >= 0");
        spec.joint.damping = j->dynamics->damping;
        spec.joint.friction = j->dynamics->friction;
      }
    }
    robot.links.push_back(std::move(spec));
  }

  // Mimic tags, in document order.
  for (const std::string& name : robot.joint_order) {
    const urdf::JointConstSharedPtr j = urdf_model->getJoint(name);
    if (!j || !j->mimic) continue;
    robot.mimics.push_back({name, j->mimic->joint_name, j->mimic->multiplier, j->mimic->offset});
  }

  robot.rebuild();
  const Model& model = *robot.model;
  if (model.floating_base())
    for (int d = 0; d < model.links[0].nv; ++d) robot.dof_order.push_back(d);
  std::map<std::string, int> dof_of;  // one lookup per joint: Model::dof_index searches
  for (const Link& link : model.links)
    if (link.nv == 1 || link.joint_type == JointType::spherical)
      dof_of.emplace(link.joint_name, link.v_index);
  for (const std::string& name : robot.joint_order) {
    const urdf::JointConstSharedPtr j = urdf_model->getJoint(name);
    if (!j || j->type == urdf::Joint::FIXED) continue;
    const int first = dof_of.at(name);
    for (int d = first; d < first + model.links[model.dof_link[first]].nv; ++d)
      robot.dof_order.push_back(d);
  }
  map_urdf_joints(robot, *urdf_model);
  // q_joint = multiplier q_leader + offset is PhysX's q_a + gear_ratio q_b + offset' = 0 with
  // gear_ratio = -multiplier, offset' = -offset.
  for (const UrdfMimic& m : robot.mimics) {
    const std::string what = "joint '" + m.joint + "': <mimic joint='" + m.leader + "'>";
    auto dof = [&](const std::string& joint) {
      for (const Link& link : model.links)
        if (link.joint_name == joint && link.nv == 1) return link.v_index;
      fail(file, what + ": '" + joint + "' is not a revolute or prismatic joint of the robot");
    };
    robot.mimic_joints.push_back({dof(m.joint), dof(m.leader), -m.multiplier, -m.offset});
    try {
      validate_mimic_joints(model, robot.mimic_joints);
    } catch (const std::invalid_argument& e) {
      fail(file, what + ": " + e.what());
    }
  }
  return robot;
}

const char* to_string(UrdfEffort effort) {
  switch (effort) {
    case UrdfEffort::none: return "none";
    case UrdfEffort::max_force: return "max_force";
    case UrdfEffort::effort_limit: return "effort_limit";
  }
  return "unknown";
}

void apply_urdf_effort_limits(const UrdfRobot& robot, Settings& settings) {
  if (robot.options.effort == UrdfEffort::none) return;
  for (const Link& link : robot.model->links) {
    const auto it = robot.effort_limits.find(link.joint_name);
    if (link.nv != 1 || it == robot.effort_limits.end() || !std::isfinite(it->second)) continue;
    const auto dof = static_cast<size_t>(link.v_index);
    if (robot.options.effort == UrdfEffort::max_force) {
      Drive& drive = settings.drives[dof];
      if (drive.type != DriveType::none && !std::isfinite(drive.max_force) &&
          !std::isfinite(drive.max_impulse))
        drive.max_force = it->second;
    } else {
      ExplicitActuator& actuator = settings.actuators[dof];
      if (actuator.kind != ActuatorKind::none && !std::isfinite(actuator.effort_limit))
        actuator.effort_limit = it->second;
    }
  }
}

// Through the setters, one changed dof at a time (an actuator's delay history starts over).
void apply_urdf_effort_limits(const UrdfRobot& robot, Simulation& sim) {
  Settings settings = sim.settings();
  apply_urdf_effort_limits(robot, settings);
  for (int d = 0; d < sim.model().nv; ++d) {
    const auto k = static_cast<size_t>(d);
    if (settings.drives[k].max_force != sim.drive(d).max_force) sim.set_drive(d, settings.drives[k]);
    if (!(settings.actuators[k] == sim.settings().actuators[k]))
      sim.set_actuator(d, settings.actuators[k]);
  }
}

void apply_robot_springs(const UrdfRobot& robot, Settings& settings) {
  const RowKindInfo& kind = row_kind(JointSpring::name);
  for (const UrdfRobot::Spring& s : robot.springs) {
    const int dof = robot.model->dof_index(s.joint);
    settings.row_parameters(dof, kind.offset + JointSpring::stiffness) = s.stiffness;
    settings.row_parameters(dof, kind.offset + JointSpring::reference) = s.reference;
  }
}

Settings robot_settings(const UrdfRobot& robot, const SimulationOptions& options) {
  validate_options(options);
  Settings settings = Settings::defaults(*robot.model, options);
  settings.mimic_joints = robot.mimic_joints;
  apply_robot_springs(robot, settings);
  apply_urdf_effort_limits(robot, settings);
  settings.validate(*robot.model);
  return settings;
}

}  // namespace featherdrive
