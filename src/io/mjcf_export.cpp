// MJCF export and the MuJoCo run beside featherdrive (mjcf_export.hpp).
#include "featherdrive/io/mjcf_export.hpp"

#include <mujoco/mujoco.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Eigenvalues>

#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "featherdrive/core/format.hpp"
#include "mujoco_calls.hpp"

namespace featherdrive {
namespace {

std::string nums(std::initializer_list<double> values) {
  std::string out;
  for (double v : values) out += (out.empty() ? "" : " ") + format_double(v);
  return out;
}

// XML attribute text: the five characters XML reserves, escaped.
std::string attr(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      case '\n':  // a literal line break in an attribute would read back as a space
        out += "&#10;";
        break;
      case '\r':
        out += "&#13;";
        break;
      case '\t':
        out += "&#9;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Per-dof joint attributes beyond the frame: range, damping, armature.
struct JointExtras {
  std::vector<std::string> text;  // per dof
};

// The exported geoms per model link, and the mesh assets they name.
struct GeomTable {
  std::vector<std::vector<const UrdfGeometry*>> of_link;
  std::vector<std::string> mesh_of;  // per options.geometry entry: its asset's name, or ""
  std::string assets;                // the <mesh> elements
};

GeomTable geom_table(const Model& model, const std::vector<UrdfGeometry>& geometry) {
  GeomTable table;
  table.of_link.resize(static_cast<size_t>(model.num_links()));
  std::map<std::string, int> link_of;
  for (int i = 0; i < model.num_links(); ++i) link_of.emplace(model.links[i].name, i);
  std::map<std::pair<std::string, std::string>, std::string> meshes;  // (file, scale) -> name
  for (const UrdfGeometry& g : geometry) {
    const auto link = link_of.find(g.body);
    if (link == link_of.end())
      throw InputError("geometry of link '" + g.link + "': the model has no link '" + g.body +
                       "'");
    table.of_link[static_cast<size_t>(link->second)].push_back(&g);
    std::string name;
    if (g.shape == UrdfGeometry::Shape::mesh) {
      const std::string scale = nums({g.scale.x(), g.scale.y(), g.scale.z()});
      auto [it, added] = meshes.emplace(std::make_pair(g.filename, scale), "");
      if (added) {
        it->second = "mesh" + std::to_string(meshes.size() - 1) + ":" +
                     std::filesystem::path(g.filename).stem().string();
        table.assets += "    <mesh name=\"" + attr(it->second) + "\" file=\"" + attr(g.filename) +
                        "\"" + (scale == "1 1 1" ? "" : " scale=\"" + scale + "\"") + "/>\n";
      }
      name = it->second;
    }
    table.mesh_of.push_back(name);
  }
  return table;
}

// A <geom> for g, whose frame is given in a link frame that sits at `offset` in the body frame.
std::string geom_text(const UrdfGeometry& g, const std::string& mesh, const Vec3& offset,
                      const std::string& indent) {
  const Vec3 p = offset + g.xyz;
  const Quat q(g.rotation);
  const std::string name =
      g.link + (g.collision ? ":collision" : ":visual") + std::to_string(g.index);
  std::string text = indent + "<geom name=\"" + attr(name) + "\" type=\"";
  switch (g.shape) {
    case UrdfGeometry::Shape::box:  // MuJoCo's size: half extents
      text += "box\" size=\"" + nums({g.size.x() / 2, g.size.y() / 2, g.size.z() / 2});
      break;
    case UrdfGeometry::Shape::cylinder:  // radius, half length
      text += "cylinder\" size=\"" + nums({g.size.x(), g.size.y() / 2});
      break;
    case UrdfGeometry::Shape::sphere:
      text += "sphere\" size=\"" + nums({g.size.x()});
      break;
    case UrdfGeometry::Shape::mesh:
      text += "mesh\" mesh=\"" + attr(mesh);
      break;
  }
  text += "\" pos=\"" + nums({p.x(), p.y(), p.z()}) + "\" quat=\"" +
          nums({q.w(), q.x(), q.y(), q.z()}) + "\"";
  // The URDF's collisions are for the eye: the model's shapes carry the contacts (shape_geom_text).
  text += std::string(" contype=\"0\" conaffinity=\"0\" group=\"") + (g.collision ? "0" : "1") + "\"";
  return text + "/>\n";
}

// The shapes exported as geoms: beside the ground (the plane, or none), and touching each other
// with self-collision.
struct ShapeExport {
  const Ground* ground = nullptr;
  bool self = false;
};

// A collision shape as a <geom>: contype 1 touches the plane (conaffinity 1); conaffinity 1 as well
// with self-collision, where MuJoCo then filters parent and child bodies as featherdrive does.
// Frictionless pairs are condim 1 (MuJoCo's pyramid of a zero friction is degenerate). MuJoCo
// combines two geoms' friction by their maximum and the plane has none, so the pair's friction
// is the shape's: the average of the two static frictions (PhysX's combine, docs/math/contact.md
// section 1), or the shape's own without a ground. offset as for geom_text.
std::string shape_name(const CollisionShape& s, size_t index) {
  return "shape:" + std::to_string(index) + (s.name.empty() ? "" : ":" + s.name);
}

std::string shape_geom_text(const CollisionShape& s, size_t index, const ShapeExport& e,
                            const Vec3& offset, const std::string& indent) {
  const Vec3 p = offset + s.position;
  const Quat q(s.rotation);
  std::string text = indent + "<geom name=\"" + attr(shape_name(s, index)) + "\" type=\"";
  switch (s.type) {
    case ShapeType::sphere:
      text += "sphere\" size=\"" + nums({s.size.x()});
      break;
    case ShapeType::capsule:  // radius, half length along z: MuJoCo's capsule
      text += "capsule\" size=\"" + nums({s.size.x(), s.size.y()});
      break;
    case ShapeType::box:
      text += "box\" size=\"" + nums({s.size.x(), s.size.y(), s.size.z()});
      break;
    case ShapeType::ellipsoid:
      text += "ellipsoid\" size=\"" + nums({s.size.x(), s.size.y(), s.size.z()});
      break;
    case ShapeType::cylinder:  // radius, half length along z: MuJoCo's cylinder
      text += "cylinder\" size=\"" + nums({s.size.x(), s.size.y()});
      break;
    case ShapeType::convex:  // the hull's vertices as an inline mesh (shape_mesh_assets)
      text += "mesh\" mesh=\"" + attr(shape_name(s, index));
      break;
  }
  const double mu = e.ground ? 0.5 * (s.material.static_friction +
                                      e.ground->material.static_friction)
                             : s.material.static_friction;
  return text + "\" pos=\"" + nums({p.x(), p.y(), p.z()}) + "\" quat=\"" +
         nums({q.w(), q.x(), q.y(), q.z()}) + "\" contype=\"1\" conaffinity=\"" +
         (e.self ? "1" : "0") + "\" condim=\"" +
         (mu > 0.0 ? "3" : "1") + "\" friction=\"" + nums({mu, 0.0, 0.0}) + "\" group=\"2\"/>\n";
}

// A massless moving link whose only child moves too and hangs at an unrotated frame: the pair is
// one MJCF body with two joints (MuJoCo's own form, which load_mjcf splits into such links), since
// MuJoCo refuses a moving body without mass.
bool joins_child(const Model& model, int i) {
  const Link& link = model.links[static_cast<size_t>(i)];
  if (i == 0 || link.nv == 0 || link.joint_type == JointType::floating || link.mass != 0.0 ||
      link.children.size() != 1)
    return false;
  const Link& child = model.links[static_cast<size_t>(link.children[0])];
  return child.nv > 0 && (child.tree_transform.E - Mat3::Identity()).cwiseAbs().maxCoeff() == 0.0;
}

// A body's opening tag, inertial and joints for the links `chain` (a link and the children it
// joins, joins_child); `shift` is the parent link frame's origin in the parent body's frame.
// Returns the last link frame's origin in this body's frame (each joint sits at its link's origin,
// with the axis in body coordinates: the chain's frames differ by translations only).
Vec3 open_body(const Model& model, const std::vector<int>& chain, const Vec3& shift, int depth,
               const JointExtras* extras, const GeomTable* geoms,
               const std::vector<UrdfGeometry>* geometry, const ShapeExport* shapes,
               std::ostringstream& xml) {
  const Link& first = model.links[static_cast<size_t>(chain.front())];
  const std::string indent(2 * static_cast<size_t>(depth), ' ');
  const Transform& X = first.tree_transform;
  const Vec3 origin = shift + X.r;
  const Quat rotation(X.E.transpose());  // the joint frame's orientation in the parent frame
  const Link& last = model.links[static_cast<size_t>(chain.back())];
  const std::string name = last.name == "world" ? "world_link" : last.name;
  xml << indent << "<body name=\"" << attr(name) << "\" pos=\""
      << nums({origin.x(), origin.y(), origin.z()}) << "\" quat=\""
      << nums({rotation.w(), rotation.x(), rotation.y(), rotation.z()}) << "\">\n";
  std::vector<Vec3> anchors{Vec3::Zero()};
  for (size_t k = 1; k < chain.size(); ++k)
    anchors.push_back(anchors.back() + model.links[static_cast<size_t>(chain[k])].tree_transform.r);
  const Vec3& offset = anchors.back();
  Eigen::SelfAdjointEigenSolver<Mat3> eig(last.inertia_com);
  Mat3 axes = eig.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
  const Quat principal(axes);
  const Vec3 moments = eig.eigenvalues();
  const Vec3 com = last.com + offset;
  xml << indent << "  <inertial pos=\"" << nums({com.x(), com.y(), com.z()}) << "\" quat=\""
      << nums({principal.w(), principal.x(), principal.y(), principal.z()}) << "\" mass=\""
      << format_double(last.mass) << "\" diaginertia=\""
      << nums({moments.x(), moments.y(), moments.z()}) << "\"/>\n";
  for (size_t k = 0; k < chain.size(); ++k) {
    const Link& link = model.links[static_cast<size_t>(chain[k])];
    const Vec3& a = link.axis;
    const Vec3& p = anchors[k];
    const std::string pos = k == 0 ? "" : "\" pos=\"" + nums({p.x(), p.y(), p.z()});
    const std::string joint = indent + "  <joint name=\"" + attr(link.joint_name) + "\" type=\"";
    const std::string more =
        extras && link.nv == 1 ? extras->text[static_cast<size_t>(link.v_index)] : "";
    switch (link.joint_type) {
      case JointType::fixed:
        break;
      case JointType::revolute:
      case JointType::prismatic:
        xml << joint << (link.joint_type == JointType::revolute ? "hinge" : "slide") << pos
            << "\" axis=\"" << nums({a.x(), a.y(), a.z()}) << "\"" << more << "/>\n";
        break;
      case JointType::spherical:
        xml << joint << "ball" << pos << "\"/>\n";
        break;
      case JointType::floating:
        xml << joint << "free\"/>\n";
        break;
    }
  }
  for (size_t k = 0; geoms && k < chain.size(); ++k)
    for (const UrdfGeometry* g : geoms->of_link[static_cast<size_t>(chain[k])])
      xml << geom_text(*g, geoms->mesh_of[static_cast<size_t>(g - geometry->data())], anchors[k],
                       indent + "  ");
  for (size_t k = 0; shapes && k < chain.size(); ++k)
    for (const CollisionShape& s : model.shapes)
      if (s.link == chain[k])
        xml << shape_geom_text(s, static_cast<size_t>(&s - model.shapes.data()), *shapes,
                               anchors[k], indent + "  ");
  return offset;
}

// The tree from the root, depth first with children in order, on an explicit stack: a chain may
// be longer than the call stack is deep. Bodies come in link order, so MuJoCo's joint, qpos and
// qvel order is ours.
void write_bodies(const Model& model, int depth, const JointExtras* extras,
                  const GeomTable* geoms, const std::vector<UrdfGeometry>* geometry,
                  const ShapeExport* shapes, std::ostringstream& xml) {
  struct Item {
    int link, depth;
    bool close;
    Vec3 shift;
  };
  std::vector<Item> stack{{0, depth, false, Vec3::Zero()}};
  std::vector<int> chain;
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    if (item.close) {
      xml << std::string(2 * static_cast<size_t>(item.depth), ' ') << "</body>\n";
      continue;
    }
    chain.assign(1, item.link);
    while (joins_child(model, chain.back()))
      chain.push_back(model.links[static_cast<size_t>(chain.back())].children[0]);
    const Vec3 shift = open_body(model, chain, item.shift, item.depth, extras, geoms, geometry, shapes, xml);
    stack.push_back({item.link, item.depth, true, Vec3::Zero()});
    const std::vector<int>& children = model.links[static_cast<size_t>(chain.back())].children;
    for (auto c = children.rbegin(); c != children.rend(); ++c)
      stack.push_back({*c, item.depth + 1, false, shift});
  }
}

std::string mjcf_text(const Model& model, double timestep, MujocoIntegrator integrator,
                      const JointExtras* extras, const std::string& actuators,
                      const MjcfExportOptions& options = {}, const std::string& equality = "",
                      const ShapeExport* shapes = nullptr) {
  std::ostringstream xml;
  const Vec3& g = model.gravity;
  const GeomTable geoms = geom_table(model, options.geometry);
  // Every body has its <inertial>: the geoms' volumes must not become mass.
  xml << "<mujoco model=\"" << attr(options.model_name) << "\">\n"
      << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
      << "  <option timestep=\"" << format_double(timestep) << "\" gravity=\""
      << nums({g.x(), g.y(), g.z()}) << "\" integrator=\""
      << (integrator == MujocoIntegrator::euler ? "Euler" : "implicit") << "\">\n";
  if (!shapes) xml << "    <flag contact=\"disable\"/>\n";
  xml << "  </option>\n";
  std::string assets = geoms.assets;
  for (size_t k = 0; shapes && k < model.shapes.size(); ++k) {
    const CollisionShape& s = model.shapes[k];
    if (s.type != ShapeType::convex) continue;
    std::string vertices;  // MuJoCo takes the hull of these
    for (const Vec3& v : s.vertices)
      vertices += (vertices.empty() ? "" : " ") + nums({v.x(), v.y(), v.z()});
    assets += "    <mesh name=\"" + attr(shape_name(s, k)) + "\" vertex=\"" + vertices + "\"/>\n";
  }
  if (!assets.empty()) xml << "  <asset>\n" << assets << "  </asset>\n";
  xml << "  <worldbody>\n";
  if (const Ground* ground = shapes ? shapes->ground : nullptr) {
    // The plane n . x = height; a zero size is MuJoCo's infinite plane.
    const Vec3 p = (ground->height * ground->normal).array() + 0.0;  // no -0 in the file
    const Vec3& n = ground->normal;
    xml << "    <geom name=\"featherdrive_ground\" type=\"plane\" size=\"0 0 1\" pos=\""
        << nums({p.x(), p.y(), p.z()}) << "\" zaxis=\"" << nums({n.x(), n.y(), n.z()})
        << "\" contype=\"0\" conaffinity=\"1\" condim=\"1\" friction=\"0 0 0\"/>\n";
  }
  write_bodies(model, 2, extras, &geoms, &options.geometry, shapes, xml);
  xml << "  </worldbody>\n";
  if (!equality.empty()) xml << "  <equality>\n" << equality << "  </equality>\n";
  if (!actuators.empty()) xml << "  <actuator>\n" << actuators << "  </actuator>\n";
  if (!options.scene_record.empty())
    xml << "  <custom>\n    <text name=\"" << kMjcfSceneText << "\" data=\""
        << attr(options.scene_record) << "\"/>\n  </custom>\n";
  xml << "</mujoco>\n";
  return xml.str();
}

// Mimic rows q_a + gear_ratio q_b + offset = 0 as joint equalities q_a = c0 + c1 q_b
// (polycoef c0 = -offset, c1 = -gear_ratio). MuJoCo's equality is a soft constraint,
// a_ref = -b v - k r: with impedance 0.9999 (mjMAXIMP) the row's acceleration is a_ref, and
// k = 1 / h^2, b = 1 / h (solref "-k -b") make MuJoCo's semi-implicit Euler step take (r, h v)
// to (0, -r): an error is gone after one step, its velocity after two (MuJoCo's timeconst
// form stops at refsafe's 2 h, which leaves 3/4 of an error per step).
std::string mimic_equalities(const Model& model, const std::vector<MimicJoint>& mimic,
                             double timestep, std::vector<std::string>& notes) {
  std::string xml, soft;
  const auto joint = [&](int dof) {
    return model.links[static_cast<size_t>(model.dof_link[static_cast<size_t>(dof)])].joint_name;
  };
  for (const MimicJoint& row : mimic) {
    xml += "    <joint joint1=\"" + attr(joint(row.dof_a)) + "\" joint2=\"" +
           attr(joint(row.dof_b)) + "\" polycoef=\"" +
           nums({-row.offset, -row.gear_ratio, 0.0, 0.0, 0.0}) + "\" solref=\"" +
           nums({-1.0 / (timestep * timestep), -1.0 / timestep}) + "\" solimp=\"0.9999 0.9999 0.001 0.5 2\"/>\n";
    if (row.natural_frequency > 0.0 && row.damping_ratio > 0.0) soft += " " + joint(row.dof_a);
  }
  if (!mimic.empty())
    notes.push_back(
        "mimic joints as <equality><joint>: MuJoCo's equality is a soft constraint, PhysX's "
        "mimic row a rigid one; MuJoCo damps joints after its constraint solve, so a damped "
        "joint's pair parts for a step");
  if (!soft.empty())
    notes.push_back("soft mimic rows exported as MuJoCo's stiffest equality:" + soft);
  return xml;
}

// Compiles XML text through MuJoCo's virtual file system (no file on disk).
mujoco_calls::ModelPtr compile(const std::string& xml, std::string& error) {
  auto vfs = std::make_unique<mjVFS>();  // ~2 MB: not on the stack
  mj_defaultVFS(vfs.get());
  const char* name = "featherdrive_export.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(xml.size())) != 0) {
    error = "MuJoCo's virtual file system refused the file";
    return nullptr;
  }
  const int index = mj_findFileVFS(vfs.get(), name);
  std::memcpy(vfs->filedata[index], xml.data(), xml.size());
  std::vector<std::string> warnings;  // the export is ours: what MuJoCo warns of is in its notes
  mujoco_calls::ModelPtr m = mujoco_calls::load_xml(name, vfs.get(), error, warnings);
  mj_deleteVFS(vfs.get());
  return m;
}

}  // namespace

const char* to_string(DriveMapping mapping) {
  return mapping == DriveMapping::translated ? "translated" : "literal";
}

std::string model_to_mjcf(const Model& model, double dt) {
  if (!(dt >= kMinDt && dt <= kMaxDt))
    throw std::invalid_argument("model_to_mjcf: dt = " + format_double(dt) +
                                ": must be a normal number in [" + format_double(kMinDt) + ", " +
                                format_double(kMaxDt) + "] s");
  return mjcf_text(model, dt, MujocoIntegrator::euler, nullptr, "");
}

MjcfExport export_mjcf(const Simulation& sim, const MjcfExportOptions& options) {
  const Model& model = sim.model();
  const SimulationOptions& o = sim.options();
  MjcfExport out;
  out.integrator = options.integrator;
  const VecX m = effective_inertia(model, sim.q());
  JointExtras extras;
  extras.text.resize(static_cast<size_t>(model.nv));
  std::ostringstream actuators;
  int actuator = 0;
  std::string friction, velocity_limited, envelopes, clamped, limited, sprung;
  for (const Link& link : model.links) {
    if (link.nv != 1) continue;
    const int d = link.v_index;
    if (sim.has_actuator(d))  // "an explicit actuator" or "an implicit actuator"
      throw InputError("joint " + link.joint_name + ": an " +
                       to_string(sim.actuator(d).integration) +
                       " actuator cannot be exported to MuJoCo (use a drive)");
    if (sim.joint_friction(d).active() || sim.friction_coefficient(d) > 0.0)
      friction += " " + link.joint_name;
    if (std::isfinite(sim.max_joint_velocity(d))) velocity_limited += " " + link.joint_name;
    if (sim.actuator_envelope(d).active()) envelopes += " " + link.joint_name;
    double damping = 0.0, armature = model.armature[d];
    const Drive& drive = sim.drive(d);
    if (drive.type != DriveType::none) {
      if (drive.stiffness == 0.0 && drive.damping == 0.0)
        throw InputError("joint " + link.joint_name +
                         ": a drive with stiffness 0 and damping 0 has nothing to export");
      MjcfDrive& e = out.drives.emplace_back();
      e.joint = link.joint_name;
      e.dof = d;
      e.effective_inertia = m[d];
      if (options.drives == DriveMapping::translated) {
        TranslationOptions t;
        t.integrator = options.integrator;
        t.keep_timestep = options.keep_timestep;
        e.translation = translate_to_mujoco(m[d], drive, o, t);
        e.mujoco = e.translation.mujoco;
      } else {
        e.mujoco = literal_mujoco_drive(m[d], drive, options.integrator);
      }
      damping = e.mujoco.damping;
      armature += e.mujoco.armature;
      out.substeps = std::max(out.substeps, e.mujoco.substeps);
      const double max_force = std::min(drive.max_force, drive.max_impulse / o.dt);
      if (std::isfinite(max_force) && e.mujoco.damping > 0.0) clamped += " " + link.joint_name;
      const std::string limit = std::isfinite(max_force) ? " forcelimited=\"true\" forcerange=\"" +
                                                               nums({-max_force, max_force}) + "\""
                                                         : "";
      actuators << "    <position name=\"" << attr(link.joint_name + ":position") << "\" joint=\""
                << attr(link.joint_name) << "\" kp=\"" << format_double(e.mujoco.kp) << "\""
                << limit << "/>\n";
      e.position_actuator = actuator++;
      if (e.mujoco.kv > 0.0) {
        actuators << "    <velocity name=\"" << attr(link.joint_name + ":velocity") << "\" joint=\""
                  << attr(link.joint_name) << "\" kv=\"" << format_double(e.mujoco.kv) << "\""
                  << limit << "/>\n";
        e.velocity_actuator = actuator++;
      }
    }
    std::string& text = extras.text[static_cast<size_t>(d)];
    const double lo = sim.lower_limit(d), hi = sim.upper_limit(d);
    if (std::isfinite(lo) || std::isfinite(hi)) {
      limited += " " + link.joint_name;
      // MuJoCo wants both ends; an open end becomes a far one.
      const double far = 1e10;
      text += " limited=\"true\" range=\"" +
              nums({std::isfinite(lo) ? lo : -far, std::isfinite(hi) ? hi : far}) + "\"";
    }
    // A joint spring as MuJoCo's passive spring toward springref, its damper in the joint's.
    const std::vector<double> spring = sim.row_parameters(JointSpring::name, d);
    if (JointSpring::active(spring)) {
      sprung += " " + link.joint_name;
      if (spring[JointSpring::stiffness] > 0.0)
        text += " stiffness=\"" + format_double(spring[JointSpring::stiffness]) +
                "\" springref=\"" + format_double(spring[JointSpring::reference]) + "\"";
      damping += spring[JointSpring::damping];
    }
    if (damping > 0.0) text += " damping=\"" + format_double(damping) + "\"";
    if (armature > 0.0) text += " armature=\"" + format_double(armature) + "\"";
  }
  for (const Link& link : model.links)  // PhysX's axis positions have no MuJoCo counterpart
    for (int d = link.v_index; link.joint_type == JointType::spherical && d < link.v_index + 3; ++d)
      if (JointSpring::active(sim.row_parameters(JointSpring::name, d)))
        out.notes.push_back("joint spring of spherical axis " + model.dof_names[d] +
                            " not exported (MuJoCo's ball stiffness acts on the whole rotation)");
  // Every translated drive of a TGS scene has the same sub-steps (the position iterations).
  out.timestep = o.dt / out.substeps;
  const std::string equality = mimic_equalities(model, sim.mimic_joints(), out.timestep, out.notes);
  // The shapes go with the ground or with self-collision: alone they touch nothing.
  ShapeExport shapes;
  shapes.ground = sim.ground().enabled ? &sim.ground() : nullptr;
  shapes.self = sim.contact_options().self_collision && model.shapes.size() > 1;
  const bool contacts = !model.shapes.empty() && (shapes.ground || shapes.self);
  out.xml = mjcf_text(model, out.timestep, options.integrator, &extras, actuators.str(), options,
                      equality, contacts ? &shapes : nullptr);
  if (contacts && shapes.ground)
    out.notes.push_back(
        "ground contacts as MuJoCo's soft contacts (solref and solimp at MuJoCo's defaults, "
        "friction the pair's static friction, no restitution): MuJoCo lets the shapes sink "
        "into the ground and creep where PhysX's rows hold them");
  if (contacts && shapes.self)
    out.notes.push_back(
        "self-collision as MuJoCo's: its filter of parent and child bodies, a manifold per pair, "
        "soft contacts, the larger of two shapes' frictions where featherdrive averages them");
  if (!friction.empty())
    out.notes.push_back("joint friction not exported (MuJoCo's frictionloss is another law):" +
                        friction);
  if (!velocity_limited.empty())
    out.notes.push_back("joint velocity limits not exported (MuJoCo has none):" + velocity_limited);
  if (!clamped.empty())
    out.notes.push_back(
        "max_force: MuJoCo's forcerange clamps kp (ctrl - q) only, not the damping "
        "that carries the drive's implicit share; the engines part where a drive "
        "saturates:" +
        clamped);
  if (!limited.empty())
    out.notes.push_back(
        "joint limits as range: MuJoCo's limit is a soft constraint, PhysX's a "
        "solver row; they differ where a joint reaches its limit:" +
        limited);
  if (!envelopes.empty()) out.notes.push_back("actuator envelopes not exported:" + envelopes);
  if (!sprung.empty())
    out.notes.push_back(
        "joint springs as MuJoCo's stiffness and springref, an explicit passive force where "
        "featherdrive's row is implicit: they part by O(k dt^2 / m) per step:" +
        sprung);
  if (o.guard.enabled)
    out.notes.push_back(
        "step guard not exported: MuJoCo steps unguarded, featherdrive redoes the steps the guard "
        "rejects (docs/math/step_guard.md)");
  bool link_parameters = false;
  for (int i = 0; i < model.num_links(); ++i) {
    const LinkParameters& p = sim.link_parameters(i);
    link_parameters = link_parameters || p.cfm_scale > 0.0 || p.linear_damping > 0.0 ||
                      p.angular_damping > 0.0 || std::isfinite(p.max_linear_velocity) ||
                      std::isfinite(p.max_angular_velocity);
  }
  if (link_parameters) out.notes.push_back("link damping, velocity limits and cfm not exported");
  if (out.substeps > 1)
    out.notes.push_back("MuJoCo timestep dt / " + std::to_string(out.substeps) +
                        " (TGS's sub-steps); the ctrl follows TGS's interpolated target");
  return out;
}

std::string scene_record(const std::string& scene_text, const Simulation& sim,
                         const std::string& file) {
  YAML::Node scene;
  try {
    scene = YAML::Load(scene_text);
  } catch (const YAML::Exception& e) {
    throw InputError(file + ": not YAML: " + e.msg);
  }
  if (!scene.IsMap()) throw InputError(file + ": the scene is not a YAML map");
  auto number = [](double v) {
    return std::isinf(v) ? std::string(v > 0 ? ".inf" : "-.inf") : format_double(v);
  };
  const Model& model = sim.model();
  YAML::Node joints = scene["joints"];
  if (!joints) joints = YAML::Node(YAML::NodeType::Map);
  for (int d = 0; d < model.nv; ++d) {
    const Link& link = model.links[static_cast<size_t>(model.dof_link[static_cast<size_t>(d)])];
    if (link.joint_type == JointType::floating) continue;
    const std::string& name = model.dof_names[static_cast<size_t>(d)];  // a ball joint's axes
    YAML::Node j = joints[name];
    if (!j) j = YAML::Node(YAML::NodeType::Map);
    j["lower"] = number(sim.lower_limit(d));
    j["upper"] = number(sim.upper_limit(d));
    j["armature"] = number(model.armature[d]);
    const JointFriction f = sim.joint_friction(d);
    YAML::Node friction(YAML::NodeType::Map);
    friction["static"] = number(f.static_effort);
    friction["dynamic"] = number(f.dynamic_effort);
    friction["viscous"] = number(f.viscous);
    j["friction"] = friction;
    if (std::isfinite(sim.max_joint_velocity(d)))
      j["max_velocity"] = number(sim.max_joint_velocity(d));
    joints[name] = j;
  }
  scene["joints"] = joints;
  YAML::Emitter out;
  out << scene;
  return std::string(out.c_str()) + "\n";
}

std::vector<UrdfGeometry> mjcf_geometry(const UrdfRobot& robot,
                                        const std::map<std::string, std::string>& packages,
                                        std::vector<std::string>& warnings) {
  namespace fs = std::filesystem;
  const std::string file = robot.path.string();
  const fs::path folder = fs::absolute(robot.path).parent_path();
  std::vector<UrdfGeometry> out;
  std::string collada;  // the .dae meshes: one line for all
  int collada_count = 0, collada_collisions = 0;
  std::map<std::string, int> unmapped;  // package -> meshes left out: one line per package
  for (const UrdfGeometry& g : robot.geometry) {
    const std::string where = file + ": link '" + g.link + "' " +
                              (g.collision ? "<collision>" : "<visual>") + " ";
    auto skip = [&](const std::string& why) {
      warnings.push_back(where + why + ": left out of the MJCF");
    };
    if (g.shape != UrdfGeometry::Shape::mesh) {
      const int n = g.shape == UrdfGeometry::Shape::box        ? 3
                    : g.shape == UrdfGeometry::Shape::cylinder ? 2
                                                               : 1;
      if (!(g.size.head(n).array() > 0.0).all() || !g.size.allFinite()) {
        skip("size " + format_vec3(g.size) + ": must be finite and > 0");
        continue;
      }
      out.push_back(g);
      continue;
    }
    const std::string& name = g.filename;
    fs::path path;
    if (name.rfind("package://", 0) == 0) {
      const std::string rest = name.substr(10);
      const std::string package = rest.substr(0, rest.find('/'));
      const auto it = packages.find(package);
      if (it == packages.end()) {
        ++unmapped[package];
        continue;
      }
      path = fs::path(it->second) /
             (rest.size() > package.size() ? rest.substr(package.size() + 1) : "");
    } else if (name.rfind("file://", 0) == 0) {
      path = name.substr(7);
    } else if (name.find("://") != std::string::npos) {
      skip("mesh " + name + ": only package:// and file:// addresses are read");
      continue;
    } else {
      path = folder / name;
    }
    std::string extension = path.extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (extension == ".dae") {
      collada += (collada.empty() ? " link '" : ", '") + g.link + "' " + name;
      ++collada_count;
      collada_collisions += g.collision ? 1 : 0;
      continue;
    }
    if (extension != ".stl") {
      skip("mesh " + name + ": MuJoCo 2.2.2 loads STL meshes only here");
      continue;
    }
    std::error_code error;
    if (!fs::is_regular_file(path, error)) {
      skip("mesh " + name + ": " + path.string() + " not found");
      continue;
    }
    if (!g.scale.allFinite() || (g.scale.array() == 0.0).any()) {
      skip("mesh " + name + " scale " + format_vec3(g.scale) + ": must be finite and not 0");
      continue;
    }
    UrdfGeometry resolved = g;
    resolved.filename = fs::absolute(path).lexically_normal().string();
    out.push_back(std::move(resolved));
  }
  for (const auto& [package, count] : unmapped)
    warnings.push_back(file + ": " + std::to_string(count) + " mesh" + (count == 1 ? "" : "es") +
                       " of package '" + package + "' left out of the MJCF: it is not mapped "
                       "(--package " + package + "=DIR)");
  // What is left out is the drawn geom (geom_text: contype 0); a collision mesh's hull is a
  // model shape, which goes in as an inline vertex mesh where the MJCF has contacts.
  if (collada_count > 0) {
    const int visual = collada_count - collada_collisions;
    std::string kinds = std::to_string(visual) + " visual";
    if (collada_collisions > 0)
      kinds += ", " + std::to_string(collada_collisions) +
               " collision (their contact hulls go in as inline meshes with a ground or "
               "self-collision)";
    warnings.push_back(file + ": " + std::to_string(collada_count) + " COLLADA (.dae) mesh" +
                       (collada_count == 1 ? "" : "es") +
                       " left out of the MJCF's drawn geoms (MuJoCo 2.2.2 cannot load them; " +
                       kinds + "):" + collada);
  }
  return out;
}

std::string mujoco_version() {
  return mj_versionString();
}

std::string mujoco_compile_error(const std::string& xml) {
  std::string error;
  const auto m = compile(xml, error);
  return m ? "" : error;
}

struct MujocoRun::Impl {
  mujoco_calls::ModelPtr m;
  mujoco_calls::DataPtr d;
};

MujocoRun::MujocoRun(const MjcfExport& mjcf) : impl_(std::make_unique<Impl>()), mjcf_(mjcf) {
  // MuJoCo would print a diverging step's warning on stdout; MujocoRun reads mjData's warning
  // counters instead and says so in its own words.
  mujoco_calls::route_warnings();
  std::string error;
  impl_->m = compile(mjcf.xml, error);
  if (!impl_->m) throw std::runtime_error("MuJoCo refused the exported model: " + error);
  impl_->d.reset(mj_makeData(impl_->m.get()));
  drive_force_ = VecX::Zero(impl_->m->nv);
  velocity_start_ = VecX::Zero(impl_->m->nv);
}

MujocoRun::~MujocoRun() = default;

int MujocoRun::nv() const {
  return impl_->m->nv;
}

void MujocoRun::set_state(const VecX& q, const VecX& qd) {
  mjModel* m = impl_->m.get();
  if (q.size() != m->nq || qd.size() != m->nv)
    throw std::invalid_argument("MujocoRun::set_state: sizes " + std::to_string(q.size()) + ", " +
                                std::to_string(qd.size()) + " for nq " + std::to_string(m->nq) +
                                ", nv " + std::to_string(m->nv));
  std::copy(q.data(), q.data() + m->nq, impl_->d->qpos);
  std::copy(qd.data(), qd.data() + m->nv, impl_->d->qvel);
  mj_forward(m, impl_->d.get());
}

void MujocoRun::step(const Simulation& targets) {
  mjModel* m = impl_->m.get();
  mjData* d = impl_->d.get();
  const double dt = targets.options().dt;
  drive_force_.setZero();
  for (int i = 1; i <= mjcf_.substeps; ++i) {
    for (const MjcfDrive& e : mjcf_.drives) {
      const Drive& drive = targets.drive(e.dof);
      const auto [position, velocity] =
          mujoco_ctrl(e.mujoco, drive.target_position, drive.target_velocity, dt, i);
      // MuJoCo zeroes (with a warning) a ctrl beyond mjMAXVAL: the run would answer target 0.
      for (const double ctrl : {position, velocity})
        if (!(std::abs(ctrl) <= mjMAXVAL))
          throw InputError("joint " + e.joint + ": the drive's targets (position " +
                           format_double(drive.target_position) + ", velocity " +
                           format_double(drive.target_velocity) + ") make MuJoCo's ctrl " +
                           format_double(ctrl) + ", beyond the " + format_double(mjMAXVAL) +
                           " MuJoCo takes (it would run with ctrl 0)");
      d->ctrl[e.position_actuator] = position;
      if (e.velocity_actuator >= 0) d->ctrl[e.velocity_actuator] = velocity;
    }
    // The actuator forces of this sub-step are those of its start state.
    mj_forward(m, d);
    for (const MjcfDrive& e : mjcf_.drives) {
      double f = d->actuator_force[e.position_actuator];
      if (e.velocity_actuator >= 0) f += d->actuator_force[e.velocity_actuator];
      drive_force_[e.dof] += f;
    }
    for (const MjcfDrive& e : mjcf_.drives) velocity_start_[e.dof] = d->qvel[e.dof];
    const int bad = d->warning[mjWARN_BADQACC].number;
    mj_step(m, d);
    if (d->warning[mjWARN_BADQACC].number != bad) diverged_ = true;
    // The implicit share at the new velocity: the damping that stands in for the drive, and
    // under the implicit integrator the velocity actuator's change over the sub-step.
    for (const MjcfDrive& e : mjcf_.drives) {
      const double v1 = d->qvel[e.dof];
      double f = -e.mujoco.damping * v1;
      if (e.velocity_actuator >= 0 && e.mujoco.integrator == MujocoIntegrator::implicit)
        f -= e.mujoco.kv * (v1 - velocity_start_[e.dof]);
      drive_force_[e.dof] += f;
    }
  }
  drive_force_ /= mjcf_.substeps;
}

VecX MujocoRun::q() const {
  return Eigen::Map<const VecX>(impl_->d->qpos, impl_->m->nq);
}

VecX MujocoRun::qd() const {
  return Eigen::Map<const VecX>(impl_->d->qvel, impl_->m->nv);
}

}  // namespace featherdrive
