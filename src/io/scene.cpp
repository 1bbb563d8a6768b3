#include "featherdrive/io/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string_view>

#include "featherdrive/algorithm/floating_base.hpp"
#include "featherdrive/constraint/drive_range.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/io/files.hpp"
#include "featherdrive/io/mjcf.hpp"
#include "featherdrive/model/model_variant.hpp"
#include "fit_spec_reader.hpp"
#include "input_error.hpp"
#include "mesh_hull.hpp"
#include "yaml_reader.hpp"

namespace featherdrive {
namespace {

using io_detail::kInf;
using scene_yaml::joint_dof;
using scene_yaml::Reader;

// yaml-cpp parses nested nodes recursively (its own guard stops at 2000 levels, deep enough to
// overflow a small stack), so the nesting is measured first, without recursion: block levels by
// the indentation of each line and its leading "- ", "? ", ": " indicators, flow levels by the
// brackets outside quoted scalars and comments; block scalar content (| and >) is skipped. Where
// this reading differs from YAML's it counts more levels, not fewer.
void check_nesting(const std::string& text, const std::string& file) {
  std::vector<size_t> columns;  // the columns of the open block nodes, innermost last
  int flow = 0;
  char quote = 0;
  long block_scalar = -1;  // inside a block scalar: lines indented more than this are its text
  size_t line = 1;
  auto check = [&] {
    if (columns.size() + static_cast<size_t>(flow) > static_cast<size_t>(kMaxSceneDepth))
      throw InputError(file + ": line " + std::to_string(line) + ": nested deeper than " +
                       std::to_string(kMaxSceneDepth) + " levels (the bound)");
  };
  const size_t n = text.size();
  for (size_t i = 0; i < n; ++line) {
    const size_t eol = std::min(text.find('\n', i), n);
    size_t k = i;
    while (k < eol && text[k] == ' ') ++k;
    const long indent = static_cast<long>(k - i);
    const bool blank = k == eol || text[k] == '#' || text[k] == '\r';
    if (block_scalar >= 0 && (blank || indent > block_scalar)) {
      i = eol + 1;
      continue;
    }
    block_scalar = -1;
    bool start = true;  // where a node may begin: a quote or a bracket opens one
    if (!quote && flow == 0 && !blank) {
      while (!columns.empty() && columns.back() >= k - i) columns.pop_back();
      columns.push_back(k - i);
      check();
      while (k < eol && (text[k] == '-' || text[k] == '?' || text[k] == ':') &&
             (k + 1 == eol || text[k + 1] == ' ')) {
        for (++k; k < eol && text[k] == ' ';) ++k;
        columns.push_back(k - i);
        check();
      }
    }
    for (; k < eol; ++k) {
      const char c = text[k];
      if (quote) {
        if (quote == '"' && c == '\\')
          ++k;
        else if (c == quote && quote == '\'' && k + 1 < eol && text[k + 1] == '\'')
          ++k;
        else if (c == quote)
          quote = 0, start = false;
        continue;
      }
      if (c == ' ' || c == '\t' || c == '\r') continue;
      if (c == '#' && (k == i || text[k - 1] == ' ' || text[k - 1] == '\t')) break;
      const bool indicator = k + 1 == eol || text[k + 1] == ' ' || text[k + 1] == '\r';
      if (start && (c == '"' || c == '\'')) {
        quote = c;
      } else if ((c == '[' || c == '{') && (start || flow > 0)) {
        ++flow;
        check();
        start = true;
      } else if ((c == ']' || c == '}') && flow > 0) {
        --flow;
        start = false;
      } else if (c == ',' && flow > 0) {
        start = true;
      } else if ((c == ':' || c == '-' || c == '?') && indicator) {
        start = true;
      } else if ((c == '|' || c == '>') && start && flow == 0) {
        block_scalar = indent;
        break;
      } else {
        start = false;
      }
    }
    i = eol + 1;
  }
}

const std::vector<std::string> kDriveKeys = {"type",
                                             "stiffness",
                                             "damping",
                                             "max_force",
                                             "max_impulse",
                                             "target_position",
                                             "target_velocity",
                                             "target",
                                             "envelope",
                                             "actuator",
                                             "delay"};
const std::vector<std::string> kLinkKeys = {"cfm_scale", "linear_damping", "angular_damping",
                                            "max_linear_velocity", "max_angular_velocity"};

LinkSettings read_link(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.map(node, path, kLinkKeys);
  LinkSettings ls;
  const auto at = [&](const char* key) { return Reader::join(path, key); };
  if (node["cfm_scale"]) {
    const double v = r.number(node["cfm_scale"], at("cfm_scale"));
    if (!(v >= 0.0 && v <= 1.0)) r.fail(at("cfm_scale"), node["cfm_scale"], "must be in [0, 1]");
    ls.cfm_scale = v;
  }
  if (node["linear_damping"])
    ls.linear_damping = r.non_negative(node["linear_damping"], at("linear_damping"));
  if (node["angular_damping"])
    ls.angular_damping = r.non_negative(node["angular_damping"], at("angular_damping"));
  if (node["max_linear_velocity"])
    ls.max_linear_velocity = r.positive(node["max_linear_velocity"], at("max_linear_velocity"));
  if (node["max_angular_velocity"])
    ls.max_angular_velocity = r.positive(node["max_angular_velocity"], at("max_angular_velocity"));
  return ls;
}

// drives.J.actuator: an explicit actuator (explicit_actuator.hpp); keys left out keep their
// defaults, or those of drive_defaults.actuator.
ExplicitActuator read_actuator(const Reader& r, const YAML::Node& node, const std::string& path,
                               ExplicitActuator a, const std::string& joint) {
  r.map(node, path,
        {"type", "stiffness", "damping", "effort_limit", "saturation_effort", "velocity_limit",
         "lookup", "delay", "integration"});
  const auto at = [&](const char* key) { return Reader::join(path, key); };
  if (node["type"]) {
    const std::string type = r.text(node["type"], at("type"));
    if (type == "ideal_pd")
      a.kind = ActuatorKind::ideal_pd;
    else if (type == "dc_motor")
      a.kind = ActuatorKind::dc_motor;
    else if (type == "remotized_pd")
      a.kind = ActuatorKind::remotized_pd;
    else
      r.fail(at("type"), node["type"], "must be ideal_pd, dc_motor or remotized_pd");
  } else if (a.kind == ActuatorKind::none) {
    r.fail(at("type"), "missing (ideal_pd, dc_motor or remotized_pd)");
  }
  if (node["stiffness"]) a.stiffness = r.non_negative(node["stiffness"], at("stiffness"));
  if (node["damping"]) a.damping = r.non_negative(node["damping"], at("damping"));
  if (node["effort_limit"]) a.effort_limit = r.positive(node["effort_limit"], at("effort_limit"));
  if (node["saturation_effort"])
    a.saturation_effort = r.positive(node["saturation_effort"], at("saturation_effort"));
  if (node["velocity_limit"])
    a.velocity_limit = r.positive(node["velocity_limit"], at("velocity_limit"));
  if (node["delay"])
    a.delay = static_cast<int>(r.integer(node["delay"], at("delay"), 0, kMaxActuatorDelay));
  if (node["integration"]) {
    const std::string integration = r.text(node["integration"], at("integration"));
    if (integration == "explicit")
      a.integration = ActuatorIntegration::explicit_law;
    else if (integration == "implicit")
      a.integration = ActuatorIntegration::implicit_law;
    else
      r.fail(at("integration"), node["integration"], "must be explicit or implicit");
  }
  if (const YAML::Node table = node["lookup"]) {
    const std::string tpath = at("lookup");
    if (!table.IsSequence() || table.size() == 0)
      r.fail(tpath, table, "must be a list of [position, max effort] pairs");
    a.lookup.clear();
    for (size_t i = 0; i < table.size(); ++i) {
      const std::string ip = tpath + "[" + std::to_string(i) + "]";
      if (!table[i].IsSequence() || table[i].size() != 2)
        r.fail(ip, table[i], "must be a pair [position, max effort]");
      a.lookup.emplace_back(r.finite(table[i][0], ip + "[0]"),
                            r.non_negative(table[i][1], ip + "[1]"));
    }
  }
  try {
    validate_actuator(a, joint);
  } catch (const std::invalid_argument& e) {
    r.fail(path, e.what());
  }
  return a;
}

// A sine of time (drives.J.target.sine, applied_force.J.sine).
SineTarget read_sine(const Reader& r, const YAML::Node& s, const std::string& spath) {
  r.map(s, spath, {"amplitude", "frequency", "phase", "offset"});
  SineTarget sine;
  if (s["amplitude"]) sine.amplitude = r.finite(s["amplitude"], spath + ".amplitude");
  if (s["frequency"]) sine.frequency = r.non_negative(s["frequency"], spath + ".frequency");
  if (s["phase"]) sine.phase = r.finite(s["phase"], spath + ".phase");
  if (s["offset"]) sine.offset = r.finite(s["offset"], spath + ".offset");
  // The target |offset| + |amplitude| and its velocity's amplitude 2 pi f |amplitude| must stay
  // finite at every time (apply_targets still checks w t + phase for a huge t).
  if (!std::isfinite(std::abs(sine.offset) + std::abs(sine.amplitude)))
    r.fail(spath, s, "offset + amplitude overflows");
  const double w = 2.0 * std::numbers::pi * sine.frequency;
  if (!std::isfinite(w) || !std::isfinite(w * std::abs(sine.amplitude)))
    r.fail(spath, s, "the velocity amplitude 2 pi frequency amplitude overflows");
  return sine;
}

// A drive's targets within the range whose impulses a double resolves (drive_range.hpp,
// docs/math/implicit_drives.md eq. T1-T3).
// Only a target with a gain acts on the impulse (validate_drive's rule).
void check_target_range(const Reader& r, const YAML::Node& node, const std::string& path,
                        const Drive& drive, double position, double velocity) {
  const char* why = ": its drive impulse cannot be represented beside the step's other impulses";
  if (drive.type == DriveType::none) return;
  if (drive.stiffness > 0.0 && std::abs(position) > kMaxDriveTargetPosition)
    r.fail(path, node,
           "the target position reaches " + format_double(position) + ", beyond +-1e6 (m or rad)" +
               why);
  if (drive.damping > 0.0 && std::abs(velocity) > kMaxDriveTargetVelocity)
    r.fail(path, node,
           "the target velocity reaches " + format_double(velocity) +
               ", beyond +-1e6 (m/s or rad/s)" + why);
}

DriveSpec read_drive(const Reader& r, const YAML::Node& node, const std::string& path,
                     DriveSpec spec) {
  r.map(node, path, kDriveKeys);
  const auto at = [&](const char* key) { return Reader::join(path, key); };
  if (node["type"]) {
    const std::string type = r.text(node["type"], at("type"));
    if (type == "force")
      spec.drive.type = DriveType::force;
    else if (type == "acceleration")
      spec.drive.type = DriveType::acceleration;
    else if (type == "none")
      spec.drive.type = DriveType::none;
    else
      r.fail(at("type"), node["type"], "must be force, acceleration or none");
  }
  if (node["stiffness"]) spec.drive.stiffness = r.non_negative(node["stiffness"], at("stiffness"));
  if (node["damping"]) spec.drive.damping = r.non_negative(node["damping"], at("damping"));
  if (node["max_force"] && node["max_impulse"])
    r.fail(path, "set max_force (a force) or max_impulse (N s per step), not both");
  if (node["max_force"]) {
    spec.drive.max_force = r.positive(node["max_force"], at("max_force"));
    spec.drive.max_impulse = std::numeric_limits<double>::infinity();
  }
  if (node["max_impulse"]) {
    spec.drive.max_impulse = r.positive(node["max_impulse"], at("max_impulse"));
    spec.drive.max_force = std::numeric_limits<double>::infinity();
  }
  const bool constant = node["target_position"] || node["target_velocity"];
  if (constant && node["target"])
    r.fail(path,
           "give either target (a trajectory) or target_position / target_velocity, not both");
  if (constant) spec.sine.reset();
  if (node["target_position"]) {
    spec.drive.target_position = r.finite(node["target_position"], at("target_position"));
    check_target_range(r, node["target_position"], at("target_position"), spec.drive,
                       spec.drive.target_position, 0.0);
  }
  if (node["target_velocity"]) {
    spec.drive.target_velocity = r.finite(node["target_velocity"], at("target_velocity"));
    check_target_range(r, node["target_velocity"], at("target_velocity"), spec.drive, 0.0,
                       spec.drive.target_velocity);
  }
  if (node["target"]) {
    const std::string tpath = at("target");
    r.map(node["target"], tpath, {"sine"});
    if (!node["target"]["sine"]) r.fail(tpath, node["target"], "must name a trajectory (sine)");
    spec.sine = read_sine(r, node["target"]["sine"], tpath + ".sine");
    check_target_range(
        r, node["target"]["sine"], tpath + ".sine", spec.drive,
        std::abs(spec.sine->offset) + std::abs(spec.sine->amplitude),
        2.0 * std::numbers::pi * spec.sine->frequency * std::abs(spec.sine->amplitude));
  }
  if (node["envelope"]) {
    const std::string epath = at("envelope");
    const YAML::Node e = node["envelope"];
    r.map(e, epath,
          {"max_effort", "max_actuator_velocity", "speed_effort_gradient",
           "velocity_dependent_resistance"});
    ActuatorEnvelope env = spec.envelope.value_or(ActuatorEnvelope{});
    if (e["max_effort"]) env.max_effort = r.non_negative(e["max_effort"], epath + ".max_effort");
    if (e["max_actuator_velocity"])
      env.max_actuator_velocity =
          r.positive(e["max_actuator_velocity"], epath + ".max_actuator_velocity");
    if (e["speed_effort_gradient"])
      env.speed_effort_gradient =
          r.non_negative(e["speed_effort_gradient"], epath + ".speed_effort_gradient");
    if (e["velocity_dependent_resistance"])
      env.velocity_dependent_resistance = r.non_negative(e["velocity_dependent_resistance"],
                                                         epath + ".velocity_dependent_resistance");
    spec.envelope = env;
  }
  if (node["actuator"])
    spec.actuator = read_actuator(r, node["actuator"], at("actuator"),
                                  spec.actuator.value_or(ExplicitActuator{}),
                                  spec.joint.empty() ? "(every joint)" : spec.joint);
  if (spec.actuator && spec.drive.type != DriveType::none)
    r.fail(path, std::string("an explicit actuator and a ") + to_string(spec.drive.type) +
                     " drive on one joint: give the drive type: none");
  if (node["delay"]) {
    spec.delay = static_cast<int>(r.integer(node["delay"], at("delay"), 0, kMaxDelay));
    if (spec.delay > 0 && spec.drive.type == DriveType::none)
      r.fail(at("delay"), node["delay"],
             "delays a drive of type force or acceleration; this one has type none (an explicit "
             "actuator takes actuator.delay)");
  }
  return spec;
}

// joints.J.revolute, joint_defaults.revolute: PhysX's revolute joint type.
RevoluteWrap read_revolute(const Reader& r, const YAML::Node& node, const std::string& path) {
  const std::string text = r.text(node, path);
  try {
    return parse_revolute_wrap(text);
  } catch (const std::invalid_argument&) {
    r.fail(path, node, "must be wrapped (PhysX's eREVOLUTE) or unwrapped (eREVOLUTE_UNWRAPPED)");
  }
}

// A material's keys where the node has them (shapes[i], ground).
void read_material(const Reader& r, const YAML::Node& node, const std::string& path, Material& m) {
  const auto at = [&](const char* key) { return Reader::join(path, key); };
  if (node["static_friction"])
    m.static_friction = r.non_negative(node["static_friction"], at("static_friction"));
  if (node["dynamic_friction"])
    m.dynamic_friction = r.non_negative(node["dynamic_friction"], at("dynamic_friction"));
  if (node["restitution"]) {
    m.restitution = r.number(node["restitution"], at("restitution"));
    if (!(m.restitution >= 0.0 && m.restitution <= 1.0))
      r.fail(at("restitution"), node["restitution"], "must be in [0, 1]");
  }
}

// ground: {height, normal, static_friction, dynamic_friction, restitution}, or false (none, not
// even the robot file's floor) or true (the defaults).
[[gnu::noinline]] Ground read_ground(const Reader& r, const YAML::Node& node) {
  Ground ground;
  if (node.IsScalar()) {
    ground.enabled = r.boolean(node, "ground");
    return ground;
  }
  r.map(node, "ground", {"height", "normal", "static_friction", "dynamic_friction", "restitution"});
  ground.enabled = true;
  if (node["height"]) ground.height = r.finite(node["height"], "ground.height");
  if (node["normal"]) {
    ground.normal = r.vec3(node["normal"], "ground.normal");
    const double length = ground.normal.norm();
    if (!(length > 1e-12 && std::isfinite(length)))
      r.fail("ground.normal", node["normal"], "must be of finite non-zero length");
    ground.normal /= length;
  }
  read_material(r, node, "ground", ground.material);
  return ground;
}

// feet: {name: [link, ...]}: a link by its name or the name of a link merged into it; each link
// must carry shapes (else its force is always 0) and appear once in its foot.
[[gnu::noinline]] std::vector<Foot> read_feet(const Reader& r, const YAML::Node& node,
                                              const Model& model) {
  if (!node.IsMap()) r.fail("feet", node, "must be a map {name: [link, ...], ...}");
  r.map(node, "feet", {});
  std::vector<Foot> feet;
  for (const auto& kv : node) {
    Foot foot;
    foot.name = kv.first.Scalar();
    const std::string p = "feet." + foot.name;
    const YAML::Node& list = kv.second;
    if (!list.IsSequence() || list.size() == 0)
      r.fail(p, list, "must be a non-empty list of link names");
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string at = p + "[" + std::to_string(i) + "]";
      const std::string name = r.text(list[i], at);
      if (std::find(foot.link_names.begin(), foot.link_names.end(), name) != foot.link_names.end())
        r.fail(at, list[i], "appears twice in the foot");
      int link = 0;
      try {
        link = model.frame(name).link;
      } catch (const std::invalid_argument& error) {
        r.fail(at, list[i], error.what());
      }
      const bool has_shape = std::any_of(model.shapes.begin(), model.shapes.end(),
                                         [&](const CollisionShape& s) { return s.link == link; });
      if (!has_shape)
        r.fail(at, list[i],
               "link '" + model.links[static_cast<size_t>(link)].name +
                   "' has no collision shapes, so its contact force is always 0");
      foot.link_names.push_back(name);
      if (std::find(foot.links.begin(), foot.links.end(), link) == foot.links.end())
        foot.links.push_back(link);
    }
    feet.push_back(std::move(foot));
  }
  return feet;
}

// contact: {contact_offset, rest_offset, bounce_threshold, self_collision}.
[[gnu::noinline]] ContactOptions read_contact(const Reader& r, const YAML::Node& node) {
  r.map(node, "contact", {"contact_offset", "rest_offset", "bounce_threshold", "self_collision"});
  ContactOptions c;
  if (node["self_collision"])
    c.self_collision = r.boolean(node["self_collision"], "contact.self_collision");
  if (node["contact_offset"])
    c.contact_offset = r.finite(node["contact_offset"], "contact.contact_offset");
  if (node["rest_offset"])
    c.rest_offset = r.non_negative(node["rest_offset"], "contact.rest_offset");
  if (node["bounce_threshold"])
    c.bounce_threshold = r.non_negative(node["bounce_threshold"], "contact.bounce_threshold");
  if (!(c.contact_offset > c.rest_offset))
    r.fail(
        node["contact_offset"] ? "contact.contact_offset" : "contact",
        node["contact_offset"] ? node["contact_offset"] : node,
        "the contact offset must be above the rest offset (" + format_double(c.rest_offset) + ")");
  return c;
}

// shapes: [{link, type, radius, half_length, half_extents, radii, xyz, rpy, name, static_friction,
// dynamic_friction, restitution}]: each shape's keys are those of its type.
std::vector<std::pair<std::string, CollisionShape>> read_shapes(const Reader& r,
                                                                const YAML::Node& node,
                                                                const Model& model) {
  if (!node.IsSequence())
    r.fail("shapes", node,
           "must be a list of {link, type, ...} (sphere, capsule, box, ellipsoid, cylinder or "
           "convex)");
  std::vector<std::pair<std::string, CollisionShape>> shapes;
  for (size_t i = 0; i < node.size(); ++i) {
    const std::string p = "shapes[" + std::to_string(i) + "]";
    const YAML::Node e = node[i];
    const auto at = [&](const char* key) { return Reader::join(p, key); };
    r.map(e, p,
          {"link", "type", "radius", "half_length", "half_extents", "radii", "vertices", "xyz",
           "rpy", "name", "static_friction", "dynamic_friction", "restitution"});
    for (const char* key : {"link", "type"})
      if (!e[key]) r.fail(at(key), "missing");
    CollisionShape shape;
    const std::string link = r.text(e["link"], at("link"));
    try {
      (void)model.frame(link);  // a link, or a link merged into one (its shapes go there)
    } catch (const std::invalid_argument& error) {
      r.fail(at("link"), e["link"], error.what());
    }
    const std::string type = r.text(e["type"], at("type"));
    // The size keys of each type, in size's order; half_extents and radii (3 numbers) fill size.
    struct Kind {
      const char* name;
      ShapeType type;
      std::vector<const char*> sizes;
    };
    static const Kind kinds[] = {{"sphere", ShapeType::sphere, {"radius"}},
                                 {"capsule", ShapeType::capsule, {"radius", "half_length"}},
                                 {"box", ShapeType::box, {"half_extents"}},
                                 {"ellipsoid", ShapeType::ellipsoid, {"radii"}},
                                 {"cylinder", ShapeType::cylinder, {"radius", "half_length"}},
                                 {"convex", ShapeType::convex, {"vertices"}}};
    const Kind* kind = nullptr;
    for (const Kind& k : kinds)
      if (type == k.name) kind = &k;
    if (!kind)
      r.fail(at("type"), e["type"], "must be sphere, capsule, box, ellipsoid, cylinder or convex");
    shape.type = kind->type;
    const std::vector<const char*>& sizes = kind->sizes;
    for (const char* key : {"radius", "half_length", "half_extents", "radii", "vertices"}) {
      const bool wanted =
          std::find(sizes.begin(), sizes.end(), std::string_view(key)) != sizes.end();
      if (!wanted && e[key]) r.fail(at(key), e[key], "is not a size of a " + type);
      if (wanted && !e[key]) r.fail(at(key), std::string("missing (a ") + type + " needs it)");
    }
    auto positive = [&](const YAML::Node& v, const std::string& where) {
      const double x = r.number(v, where);
      if (!(std::isfinite(x) && x > 0.0)) r.fail(where, v, "must be finite and > 0");
      return x;
    };
    for (size_t k = 0; k < sizes.size(); ++k) {
      const YAML::Node v = e[sizes[k]];
      const std::string_view key = sizes[k];
      if (key == "vertices") {  // the hull of the points, as a URDF mesh's (G3)
        // Each step visits a hull's vertices; MuJoCo's compiler takes the hull.
        constexpr size_t kMostVertices = 1000;
        if (!v.IsSequence()) r.fail(at("vertices"), v, "must be a list of [x, y, z]");
        if (v.size() > kMostVertices)
          r.fail(at("vertices"), std::to_string(v.size()) + " points: at most " +
                                     std::to_string(kMostVertices) + " (the bound)");
        std::vector<Vec3> points;
        for (size_t j = 0; j < v.size(); ++j)
          points.push_back(r.vec3(v[j], at("vertices") + "[" + std::to_string(j) + "]"));
        try {
          shape.vertices = mesh_hull::hull_of_points(points);
        } catch (const std::runtime_error& error) {
          r.fail(at("vertices"), v, error.what());
        }
        continue;
      }
      if (key != "half_extents" && key != "radii") {
        shape.size[static_cast<int>(k)] = positive(v, at(sizes[k]));
        continue;
      }
      if (!v.IsSequence() || v.size() != 3) r.fail(at(sizes[k]), v, "must be a list of 3 numbers");
      for (int j = 0; j < 3; ++j)
        shape.size[j] = positive(v[j], at(sizes[k]) + "[" + std::to_string(j) + "]");
    }
    if (e["xyz"]) shape.position = r.vec3(e["xyz"], at("xyz"));
    if (e["rpy"]) shape.rotation = rotation_from_rpy(r.vec3(e["rpy"], at("rpy")));
    if (e["name"]) shape.name = r.text(e["name"], at("name"));
    if (const std::string why = name_problem(shape.name); !shape.name.empty() && !why.empty())
      r.fail(at("name"), "shape " + why);
    read_material(r, e, p, shape.material);
    shapes.emplace_back(link, std::move(shape));
  }
  return shapes;
}

// applied_force: {joint: force or {sine: ...}}.
[[gnu::noinline]] std::vector<AppliedForceSpec> read_applied_forces(const Reader& r,
                                                                    const YAML::Node& node,
                                                                    const UrdfRobot& robot) {
  r.map(node, "applied_force", {});
  std::map<int, AppliedForceSpec> by_dof;
  for (const auto& kv : node) {
    AppliedForceSpec f;
    f.joint = kv.first.Scalar();
    const std::string p = "applied_force." + f.joint;
    f.dof = joint_dof(r, robot, f.joint, p);
    if (kv.second.IsMap()) {
      r.map(kv.second, p, {"sine"});
      if (!kv.second["sine"]) r.fail(p, kv.second, "must be a force or {sine: ...}");
      f.sine = read_sine(r, kv.second["sine"], p + ".sine");
    } else {
      f.value = r.finite(kv.second, p);
    }
    by_dof[f.dof] = f;
  }
  std::vector<AppliedForceSpec> out;
  for (const int dof : robot.dof_order)
    if (const auto it = by_dof.find(dof); it != by_dof.end()) out.push_back(it->second);
  return out;
}

// mimic: [{follower, leader, gear_ratio, offset, natural_frequency, damping_ratio}], added to the
// URDF's rows (an entry replaces the URDF's row of its follower); the cycle check is
// validate_mimic_joints' (make_simulation).
[[gnu::noinline]] std::vector<MimicJoint> read_mimic(const Reader& r, const YAML::Node& node,
                                                     const UrdfRobot& robot) {
  if (!node.IsSequence()) r.fail("mimic", node, "must be a list of {follower, leader, gear_ratio}");
  std::vector<MimicJoint> rows = robot.mimic_joints;
  for (size_t i = 0; i < node.size(); ++i) {
    const std::string p = "mimic[" + std::to_string(i) + "]";
    const YAML::Node e = node[i];
    r.map(e, p,
          {"follower", "leader", "gear_ratio", "offset", "natural_frequency", "damping_ratio"});
    for (const char* key : {"follower", "leader", "gear_ratio"})
      if (!e[key]) r.fail(p + "." + key, "missing");
    MimicJoint m;
    m.dof_a = joint_dof(r, robot, r.text(e["follower"], p + ".follower"), p + ".follower");
    m.dof_b = joint_dof(r, robot, r.text(e["leader"], p + ".leader"), p + ".leader");
    if (m.dof_a == m.dof_b)
      r.fail(p + ".leader", e["leader"], "is the follower: a joint cannot mimic itself");
    m.gear_ratio = r.finite(e["gear_ratio"], p + ".gear_ratio");
    if (m.gear_ratio == 0.0) r.fail(p + ".gear_ratio", e["gear_ratio"], "must be nonzero");
    if (e["offset"]) m.offset = r.finite(e["offset"], p + ".offset");
    if (e["natural_frequency"])
      m.natural_frequency = r.non_negative(e["natural_frequency"], p + ".natural_frequency");
    if (e["damping_ratio"])
      m.damping_ratio = r.non_negative(e["damping_ratio"], p + ".damping_ratio");
    const auto same = std::find_if(rows.begin(), rows.end(),
                                   [&](const MimicJoint& x) { return x.dof_a == m.dof_a; });
    if (same != rows.end() && same - rows.begin() < static_cast<long>(robot.mimic_joints.size()))
      *same = m;
    else
      rows.push_back(m);
  }
  return rows;
}

// parse_scene's sections, each a function of its own. These and the readers parse_scene calls
// once are kept out of line ([[gnu::noinline]]): inlined into one function, they took the
// optimiser time superlinear in its size (docs/testing.md, "Where CI's time goes").

// dt, steps, compat, solver, control and guard.
[[gnu::noinline]] void read_options(const Reader& r, const YAML::Node& root, Scene& scene) {
  if (root["dt"]) {
    scene.options.dt = r.number(root["dt"], "dt");
    if (!std::isfinite(scene.options.dt) || scene.options.dt <= 0.0)
      r.fail("dt", root["dt"], "must be finite and > 0");
    if (scene.options.dt < kMinDt || scene.options.dt > kMaxDt)
      r.fail("dt", root["dt"],
             "must be in [" + format_double(kMinDt) + ", " + format_double(kMaxDt) +
                 "] s (a normal number)");
  }
  if (!root["steps"]) r.fail("steps", "missing: the number of steps to simulate");
  scene.steps = static_cast<int>(r.integer(root["steps"], "steps", 0, 1'000'000'000L));

  if (root["compat"]) {
    const std::string compat = r.text(root["compat"], "compat");
    if (compat == "physx")
      scene.options.compat = Compat::physx;
    else if (compat != "none")
      r.fail("compat", root["compat"], "must be none or physx");
  }
  if (const YAML::Node s = root["solver"]) {
    r.map(s, "solver", {"type", "position_iterations", "velocity_iterations"});
    if (s["type"]) {
      const std::string type = r.text(s["type"], "solver.type");
      if (type == "pgs")
        scene.options.solver = SolverType::pgs;
      else if (type == "tgs")
        scene.options.solver = SolverType::tgs;
      else
        r.fail("solver.type", s["type"], "must be pgs or tgs");
    }
    if (s["position_iterations"])
      scene.options.position_iterations = static_cast<int>(
          r.integer(s["position_iterations"], "solver.position_iterations", 1, kMaxIterations));
    if (s["velocity_iterations"])
      scene.options.velocity_iterations = static_cast<int>(
          r.integer(s["velocity_iterations"], "solver.velocity_iterations", 0, kMaxIterations));
  }

  if (const YAML::Node c = root["control"]) {
    r.map(c, "control", {"substeps", "targets"});
    if (c["substeps"])
      scene.control.substeps =
          static_cast<int>(r.integer(c["substeps"], "control.substeps", 1, kMaxSubsteps));
    if (c["targets"]) {
      const std::string targets = r.text(c["targets"], "control.targets");
      if (targets == "linear")
        scene.control.targets = TargetInterpolation::linear;
      else if (targets != "hold")
        r.fail("control.targets", c["targets"], "must be hold or linear");
    }
  }

  // The step guard (docs/math/step_guard.md): present = on, its bounds default.
  if (const YAML::Node g = root["guard"]) {
    r.map(g, "guard", {"max_joint_step", "max_substeps", "energy_tolerance", "dissipation_share"});
    scene.options.guard.enabled = true;
    if (g["max_joint_step"]) {
      const double bound = r.number(g["max_joint_step"], "guard.max_joint_step");
      if (!std::isfinite(bound) || bound <= 0.0)
        r.fail("guard.max_joint_step", g["max_joint_step"], "must be finite and > 0");
      scene.options.guard.max_joint_step = bound;
    }
    if (g["max_substeps"])
      scene.options.guard.max_substeps = static_cast<int>(
          r.integer(g["max_substeps"], "guard.max_substeps", 2, kMaxGuardSubsteps));
    if (g["energy_tolerance"]) {
      const double tolerance = r.number(g["energy_tolerance"], "guard.energy_tolerance");
      if (!(tolerance > 0.0 && tolerance <= 1.0))
        r.fail("guard.energy_tolerance", g["energy_tolerance"], "must be in (0, 1]");
      scene.options.guard.energy_tolerance = tolerance;
    }
    if (g["dissipation_share"]) {
      const double share = r.number(g["dissipation_share"], "guard.dissipation_share");
      if (!(share > 0.0 && share <= 100.0))
        r.fail("guard.dissipation_share", g["dissipation_share"], "must be in (0, 100]");
      scene.options.guard.dissipation_share = share;
    }
  }
}

// The keys of a joint's settings and of joint_defaults: their own, then each row kind's name.
std::vector<std::string> with_row_kinds(std::vector<std::string> keys) {
  for (const RowKindInfo& k : row_kinds()) keys.emplace_back(k.name);
  return keys;
}

// Each row kind given under `j` (a map of its fields; each a number, checked with the others by
// the kind's own check when the settings are made).
void read_row_kinds(const Reader& r, const YAML::Node& j, const std::string& path,
                    JointSettings& js) {
  for (const RowKindInfo& k : row_kinds()) {
    const YAML::Node node = j[std::string(k.name)];
    if (!node) continue;
    const std::string p = path + "." + std::string(k.name);
    std::vector<std::string> names;
    for (const RowField& f : k.fields) names.emplace_back(f.name);
    r.map(node, p, names);
    std::vector<std::optional<double>> values(k.fields.size());
    for (size_t f = 0; f < k.fields.size(); ++f)
      if (const YAML::Node v = node[names[f]]) values[f] = r.number(v, p + "." + names[f]);
    js.row_kinds[k.index] = values;
  }
}

// Joint settings, by dof (the robot rebuilt where one sets an armature).
[[gnu::noinline]] std::map<int, JointSettings> read_joints(const Reader& r,
                                                           const YAML::Node& joints, Scene& scene) {
  const Model* m = scene.robot.model.get();
  std::map<int, JointSettings> settings;
  r.map(joints, "joints", {});
  for (const auto& kv : joints) {
    const std::string name = kv.first.Scalar();
    const std::string path_j = "joints." + name;
    JointSettings js;
    js.joint = name;
    js.dof = joint_dof(r, scene.robot, name, path_j);
    const YAML::Node j = kv.second;
    r.map(j, path_j,
          with_row_kinds({"lower", "upper", "max_velocity", "friction", "friction_coefficient",
                          "armature", "revolute"}));
    read_row_kinds(r, j, path_j, js);
    if (j["revolute"]) js.revolute = read_revolute(r, j["revolute"], path_j + ".revolute");
    if (j["lower"]) js.lower = r.number(j["lower"], path_j + ".lower");
    if (j["upper"]) js.upper = r.number(j["upper"], path_j + ".upper");
    if (js.lower && (std::isnan(*js.lower) || *js.lower == kInf))
      r.fail(path_j + ".lower", j["lower"], "must be a number below .inf");
    if (js.upper && (std::isnan(*js.upper) || *js.upper == -kInf))
      r.fail(path_j + ".upper", j["upper"], "must be a number above -.inf");
    const double lower = js.lower.value_or(m->lower_limit[js.dof]);
    const double upper = js.upper.value_or(m->upper_limit[js.dof]);
    if (lower > upper)
      r.fail(path_j,
             "lower = " + format_double(lower) + " is above upper = " + format_double(upper));
    if (j["max_velocity"])
      js.max_velocity = r.positive(j["max_velocity"], path_j + ".max_velocity");
    if (j["armature"]) js.armature = r.non_negative(j["armature"], path_j + ".armature");
    if (j["friction_coefficient"])
      js.friction_coefficient =
          r.non_negative(j["friction_coefficient"], path_j + ".friction_coefficient");
    if (const YAML::Node f = j["friction"]) {
      const std::string fp = path_j + ".friction";
      r.map(f, fp, {"static", "dynamic", "viscous"});
      JointFriction fr{m->friction[js.dof], m->friction[js.dof], m->damping[js.dof]};
      if (f["static"]) fr.static_effort = r.non_negative(f["static"], fp + ".static");
      if (f["dynamic"]) fr.dynamic_effort = r.non_negative(f["dynamic"], fp + ".dynamic");
      if (f["viscous"]) fr.viscous = r.non_negative(f["viscous"], fp + ".viscous");
      try {
        validate_friction(fr, name);
      } catch (const std::invalid_argument& e) {
        r.fail(fp, e.what());
      }
      js.friction = fr;
    }
    settings[js.dof] = js;
  }
  bool rebuild = false;
  for (LinkSpec& link : scene.robot.links)
    for (const auto& [dof, js] : settings) {
      if (js.armature && link.joint.name == js.joint) {
        link.joint.armature = {*js.armature};
        rebuild = true;
      }
      // A spherical joint's axes each have their own (one JointSpec armature per dof).
      if (js.armature && link.joint.type == JointType::spherical &&
          m->links[m->dof_link[dof]].joint_name == link.joint.name) {
        std::vector<double>& armature = link.joint.armature;
        if (armature.size() != 3) armature.assign(3, armature.empty() ? 0.0 : armature[0]);
        armature[dof - m->links[m->dof_link[dof]].v_index] = *js.armature;
        rebuild = true;
      }
    }
  if (rebuild) scene.robot.rebuild();
  return settings;
}

// shapes, feet, contact and ground. Called after read_joints: shapes go onto the model its
// armature rebuilt, and robot.shapes keeps them for a later rebuild.
[[gnu::noinline]] void read_contact_parts(const Reader& r, const YAML::Node& root, Scene& scene) {
  const Model* m = scene.robot.model.get();
  if (root["shapes"]) {
    scene.shapes = read_shapes(r, root["shapes"], *m);
    try {
      scene.robot.model = std::make_shared<const Model>(with_shapes(*m, scene.shapes));
    } catch (const ModelError& e) {
      r.fail("shapes", e.what());
    }
    scene.robot.shapes.insert(scene.robot.shapes.end(), scene.shapes.begin(), scene.shapes.end());
    m = scene.robot.model.get();
  }
  if (root["feet"]) scene.feet = read_feet(r, root["feet"], *m);
  if (root["contact"]) scene.contact = read_contact(r, root["contact"]);
  if (root["ground"]) {
    scene.ground = read_ground(r, root["ground"]);
  } else if (scene.robot.ground && m->unsupported_shapes.empty()) {
    scene.ground = *scene.robot.ground;
  } else if (scene.robot.ground) {
    scene.robot.warnings.push_back(
        "the file's floor is not used as the ground: " + m->unsupported_shapes.front() +
        " is a shape contacts do not support yet (sphere, capsule, box, ellipsoid, cylinder, "
        "convex mesh)");
  }
}

// joint_defaults: what every joint takes unless its own settings say otherwise.
[[gnu::noinline]] JointSettings read_joint_defaults(const Reader& r, const YAML::Node& jd) {
  r.map(jd, "joint_defaults", with_row_kinds({"friction_coefficient", "max_velocity", "revolute"}));
  JointSettings js;
  read_row_kinds(r, jd, "joint_defaults", js);
  if (jd["revolute"]) js.revolute = read_revolute(r, jd["revolute"], "joint_defaults.revolute");
  if (jd["friction_coefficient"])
    js.friction_coefficient =
        r.non_negative(jd["friction_coefficient"], "joint_defaults.friction_coefficient");
  if (jd["max_velocity"])
    js.max_velocity = r.positive(jd["max_velocity"], "joint_defaults.max_velocity");
  return js;
}

// link_defaults and links (by name, in the model's order).
[[gnu::noinline]] void read_links(const Reader& r, const YAML::Node& root, Scene& scene) {
  const Model* m = scene.robot.model.get();
  if (const YAML::Node ld = root["link_defaults"])
    scene.link_defaults = read_link(r, ld, "link_defaults");
  if (const YAML::Node ls = root["links"]) {
    r.map(ls, "links", {});
    std::map<int, LinkSettings> by_index;
    for (const auto& kv : ls) {
      const std::string name = kv.first.Scalar();
      const std::string p = "links." + name;
      int index = -1;
      for (int i = 0; i < m->num_links(); ++i)
        if (m->links[i].name == name) index = i;
      if (index < 0) {
        std::string list;
        for (const Link& link : m->links) {
          if (!list.empty()) list += ", ";
          list += link.name;
        }
        r.fail(p, "no link named '" + name + "' in " + scene.robot.path.filename().string() +
                      " (links: " + list + "; links on fixed joints are merged into their parent)");
      }
      LinkSettings link = read_link(r, kv.second, p);
      link.link = name;
      link.index = index;
      by_index[index] = link;
    }
    for (const auto& [index, link] : by_index) scene.links.push_back(link);
  }
}

// The start: the model's neutral pose, then `initial` (joints by name, a floating root's pose).
[[gnu::noinline]] void read_initial(const Reader& r, const YAML::Node& root, Scene& scene) {
  const Model* m = scene.robot.model.get();
  scene.q0 = m->neutral_configuration();
  scene.qd0 = VecX::Zero(m->nv);
  if (const YAML::Node init = root["initial"]) {
    r.map(init, "initial", {"q", "qd", "base"});
    for (const char* which : {"q", "qd"}) {
      const YAML::Node values = init[which];
      if (!values) continue;
      const std::string p = std::string("initial.") + which;
      r.map(values, p, {});
      std::map<int, Vec3> rotation;  // spherical joints' PhysX positions, by link
      for (const auto& kv : values) {
        const std::string name = kv.first.Scalar();
        const int dof = joint_dof(r, scene.robot, name, p + "." + name);
        const double v = r.finite(kv.second, p + "." + name);
        const Link& link = m->links[m->dof_link[dof]];
        if (std::string(which) == "qd")
          scene.qd0[dof] = v;
        else if (link.joint_type == JointType::spherical)
          rotation.try_emplace(m->dof_link[dof], Vec3::Zero()).first->second[dof - link.v_index] =
              v;
        else
          scene.q0[link.q_index] = v;
      }
      // A spherical joint stands at exp(theta), theta its three positions (as PhysX poses it).
      for (const auto& [link, theta] : rotation) {
        const double angle = theta.norm();
        const Quat Q =
            angle > 0.0 ? Quat(Eigen::AngleAxisd(angle, theta / angle)) : Quat::Identity();
        scene.q0.segment<4>(m->links[link].q_index) << Q.w(), Q.x(), Q.y(), Q.z();
      }
    }
    // A floating root's pose and velocity in world axes (algorithm/floating_base.hpp).
    if (const YAML::Node b = init["base"]) {
      r.map(b, "initial.base", {"position", "orientation", "linear_velocity", "angular_velocity"});
      if (!m->floating_base())
        r.fail("initial.base", b, "the robot has no floating root (fixed_base: false gives one)");
      BaseState base = base_state(*m, scene.q0, scene.qd0);
      if (b["position"]) base.position = r.vec3(b["position"], "initial.base.position");
      if (const YAML::Node o = b["orientation"]) {
        if (!o.IsSequence() || o.size() != 4)
          r.fail("initial.base.orientation", o, "must be a list of 4 numbers (w, x, y, z)");
        double wxyz[4];
        for (int i = 0; i < 4; ++i)
          wxyz[i] = r.finite(o[i], "initial.base.orientation[" + std::to_string(i) + "]");
        if (!(Eigen::Vector4d(wxyz[0], wxyz[1], wxyz[2], wxyz[3]).norm() > 1e-150))
          r.fail("initial.base.orientation", o, "must not be zero");
        base.orientation = Quat(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
      }
      if (b["linear_velocity"])
        base.linear_velocity = r.vec3(b["linear_velocity"], "initial.base.linear_velocity");
      if (b["angular_velocity"])
        base.angular_velocity = r.vec3(b["angular_velocity"], "initial.base.angular_velocity");
      set_base_state(*m, base, scene.q0, scene.qd0);
    }
  }
}

// drive_defaults and drives; the drives and joint settings the scene keeps, in dof order.
[[gnu::noinline]] void read_drives(const Reader& r, const YAML::Node& root, Scene& scene,
                                   const std::map<int, JointSettings>& settings) {
  const Model* m = scene.robot.model.get();
  std::optional<DriveSpec> defaults;
  if (const YAML::Node d = root["drive_defaults"]) {
    defaults = read_drive(r, d, "drive_defaults", DriveSpec{});
    if (d.IsMap() && !d["type"])
      r.fail("drive_defaults.type", "missing (force, acceleration or none)");
  }
  std::map<int, DriveSpec> drives;
  if (defaults)
    for (int dof : scene.robot.dof_order)
      if (m->links[m->dof_link[dof]].nv == 1 ||
          m->links[m->dof_link[dof]].joint_type == JointType::spherical) {
        DriveSpec spec = *defaults;
        spec.joint = m->dof_names[dof];
        spec.dof = dof;
        drives[dof] = spec;
      }
  if (const YAML::Node ds = root["drives"]) {
    r.map(ds, "drives", {});
    for (const auto& kv : ds) {
      const std::string name = kv.first.Scalar();
      const std::string p = "drives." + name;
      const int dof = joint_dof(r, scene.robot, name, p);
      DriveSpec base = defaults.value_or(DriveSpec{});
      if (!defaults && kv.second.IsMap() && !kv.second["type"])
        r.fail(p + ".type", "missing (force, acceleration or none)");
      base.joint = name;
      DriveSpec spec = read_drive(r, kv.second, p, base);
      spec.dof = dof;
      drives[dof] = spec;
    }
  }
  for (int dof : scene.robot.dof_order) {
    if (auto it = drives.find(dof);
        it != drives.end() && (it->second.drive.type != DriveType::none || it->second.actuator))
      scene.drives.push_back(it->second);
    if (auto it = settings.find(dof); it != settings.end()) scene.joints.push_back(it->second);
  }
}

}  // namespace

void LinkSettings::apply_to(LinkParameters& p) const {
  if (cfm_scale) p.cfm_scale = *cfm_scale;
  if (linear_damping) p.linear_damping = *linear_damping;
  if (angular_damping) p.angular_damping = *angular_damping;
  if (max_linear_velocity) p.max_linear_velocity = *max_linear_velocity;
  if (max_angular_velocity) p.max_angular_velocity = *max_angular_velocity;
}

double SineTarget::position(double t) const {
  return offset + amplitude * std::sin(2.0 * std::numbers::pi * frequency * t + phase);
}
double SineTarget::velocity(double t) const {
  const double w = 2.0 * std::numbers::pi * frequency;
  return amplitude * w * std::cos(w * t + phase);
}

std::pair<double, double> DriveSpec::target_at(double t) const {
  if (sine) return {sine->position(t), sine->velocity(t)};
  return {drive.target_position, drive.target_velocity};
}

static void check_scene_start(const Scene& scene);

Scene load_scene(const std::filesystem::path& path) {
  return parse_scene(read_input_file(path), path);
}

Scene parse_scene(const std::string& text, const std::filesystem::path& path) {
  const Reader r(path.string());
  check_nesting(text, path.string());
  YAML::Node loaded;
  try {
    loaded = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw InputError(path.string() + ": line " + std::to_string(e.mark.line + 1) + ", column " +
                     std::to_string(e.mark.column + 1) + ": malformed YAML: " + e.msg);
  }
  const YAML::Node& root = loaded;  // const: lookups must not insert keys
  if (!root.IsMap())
    throw InputError(path.string() + ": the scene must be a map of keys (model, dt, steps, ...)");
  r.map(root, "", {"description", "model",          "fixed_base", "gravity",       "dt",
                   "steps",       "solver",         "compat",     "initial",       "drive_defaults",
                   "drives",      "joint_defaults", "joints",     "link_defaults", "links",
                   "control",     "urdf_effort",    "fit",        "applied_force", "mimic",
                   "guard",       "ground",         "contact",    "shapes",        "feet"});

  Scene scene;
  scene.path = path;
  if (root["description"]) r.text(root["description"], "description");
  if (!root["model"]) r.fail("model", "missing: the URDF file of the robot");
  const std::string model = r.text(root["model"], "model");
  scene.model_path = std::filesystem::path(model).is_absolute() ? std::filesystem::path(model)
                                                                : path.parent_path() / model;
  // A folder, FIFO or device is load_urdf's to refuse ("is not a regular file"); only a name
  // that is not there at all is this key's fault.
  std::error_code ec;
  if (!std::filesystem::exists(scene.model_path, ec))
    r.fail("model", root["model"],
           "no such file (looked for " +
               std::filesystem::absolute(scene.model_path).lexically_normal().string() + ")");
  UrdfOptions urdf;
  if (root["fixed_base"]) urdf.fixed_base = r.boolean(root["fixed_base"], "fixed_base");
  if (root["gravity"]) urdf.gravity = r.vec3(root["gravity"], "gravity");
  if (root["urdf_effort"]) {
    const std::string effort = r.text(root["urdf_effort"], "urdf_effort");
    if (effort == "max_force")
      urdf.effort = UrdfEffort::max_force;
    else if (effort == "effort_limit")
      urdf.effort = UrdfEffort::effort_limit;
    else if (effort != "none")
      r.fail("urdf_effort", root["urdf_effort"], "must be none, max_force or effort_limit");
  }
  scene.robot = load_robot(scene.model_path, urdf);  // URDF or MJCF

  read_options(r, root, scene);

  // Joint settings first: armature changes the model.
  std::map<int, JointSettings> settings;
  if (const YAML::Node joints = root["joints"]) settings = read_joints(r, joints, scene);
  read_contact_parts(r, root, scene);
  if (const YAML::Node jd = root["joint_defaults"])
    scene.joint_defaults = read_joint_defaults(r, jd);
  read_links(r, root, scene);
  read_initial(r, root, scene);
  read_drives(r, root, scene, settings);
  if (root["applied_force"])
    scene.applied_forces = read_applied_forces(r, root["applied_force"], scene.robot);
  scene.mimic =
      root["mimic"] ? read_mimic(r, root["mimic"], scene.robot) : scene.robot.mimic_joints;
  check_scene_start(scene);
  if (root["fit"]) scene.fit = read_fit_spec(r, root["fit"], scene);
  return scene;
}

// Runs f, an invalid_argument from it becoming the scene's InputError.
template <class F>
static auto naming_the_scene(const Scene& scene, F&& f) {
  try {
    return f();
  } catch (const InputError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw InputError(scene.path.string() + ": " + e.what());
  }
}

// A joint's row kinds into dof d's row parameters: the fields given, the others as they are,
// checked together (check_row_parameters).
static void apply_row_kinds(const Model& model, int d, const JointSettings& js, Settings& s) {
  for (const auto& [index, given] : js.row_kinds) {
    const RowKindInfo& kind = row_kinds()[static_cast<size_t>(index)];
    std::vector<double> values(kind.fields.size());
    for (size_t f = 0; f < values.size(); ++f)
      values[f] =
          given[f].value_or(s.row_parameters(d, kind.offset + static_cast<Eigen::Index>(f)));
    check_row_parameters(model, d, kind, values);
    for (size_t f = 0; f < values.size(); ++f)
      s.row_parameters(d, kind.offset + static_cast<Eigen::Index>(f)) = values[f];
  }
}

// Each value is checked where it is given, in the order the scene's keys apply, by the checks the
// Simulation setters use (settings.hpp), so a scene's first error is the one a setter would name.
Settings scene_settings(const Scene& scene) {
  return naming_the_scene(scene, [&] {
    const Model& model = *scene.model();
    validate_options(scene.options);
    Settings s = Settings::defaults(model, scene.options);
    apply_robot_springs(scene.robot, s);  // the file's own, before the scene's joint settings
    for (int i = 0; i < model.num_links(); ++i) {
      LinkParameters& p = s.link_parameters[static_cast<size_t>(i)];
      if (scene.link_defaults) scene.link_defaults->apply_to(p);
      for (const LinkSettings& ls : scene.links)
        if (ls.index == i) ls.apply_to(p);
      check_link_parameters_of(model, i, p);
    }
    if (scene.joint_defaults) {
      const JointSettings& jd = *scene.joint_defaults;
      for (int d = 0; d < model.nv; ++d) {  // every revolute, prismatic and spherical dof
        const JointType type = model.links[model.dof_link[d]].joint_type;
        if (type != JointType::revolute && type != JointType::prismatic &&
            type != JointType::spherical)
          continue;
        if (jd.revolute && type == JointType::revolute) {
          check_revolute_wrap(model, d, *jd.revolute);
          s.revolute_wrap[static_cast<size_t>(d)] = *jd.revolute;
        }
        if (jd.friction_coefficient) {
          check_friction_coefficient(model, d, *jd.friction_coefficient);
          s.friction_coefficient[d] = *jd.friction_coefficient;
        }
        if (jd.max_velocity && !std::isfinite(model.velocity_limit[d])) {
          check_max_joint_velocity(model, d, *jd.max_velocity);
          s.max_joint_velocity[d] = *jd.max_velocity;
        }
        apply_row_kinds(model, d, jd, s);
      }
    }
    for (const JointSettings& js : scene.joints) {
      const int d = js.dof;
      if (js.lower || js.upper) {
        const double lower = js.lower.value_or(s.lower_limit[d]);
        const double upper = js.upper.value_or(s.upper_limit[d]);
        check_joint_limits(model, d, lower, upper);
        s.lower_limit[d] = lower;
        s.upper_limit[d] = upper;
      }
      if (js.max_velocity) {
        check_max_joint_velocity(model, d, *js.max_velocity);
        s.max_joint_velocity[d] = *js.max_velocity;
      }
      if (js.friction) {
        check_joint_friction(model, d, *js.friction);
        s.friction[static_cast<size_t>(d)] = *js.friction;
      }
      if (js.friction_coefficient) {
        check_friction_coefficient(model, d, *js.friction_coefficient);
        s.friction_coefficient[d] = *js.friction_coefficient;
      }
      if (js.revolute) {
        check_revolute_wrap(model, d, *js.revolute);
        s.revolute_wrap[static_cast<size_t>(d)] = *js.revolute;
      }
      apply_row_kinds(model, d, js, s);
    }
    validate_mimic_joints(model, scene.mimic);
    s.mimic_joints = scene.mimic;
    check_contact_options(scene.contact);
    s.contact = scene.contact;
    check_ground(scene.ground);
    check_ground_supported(model, scene.ground);
    s.ground = scene.ground;
    for (const DriveSpec& spec : scene.drives) {
      const auto d = static_cast<size_t>(spec.dof);
      check_drive(model, spec.dof, spec.drive, s.actuators[d].kind);
      s.drives[d] = spec.drive;
      if (spec.delay > 0 && spec.drive.type != DriveType::none) {
        check_drive_delay(model, spec.dof, spec.delay, s.drives[d], s.actuators[d].kind);
        s.drive_delay[d] = spec.delay;
      }
      if (spec.envelope) {
        check_actuator_envelope(model, spec.dof, *spec.envelope);
        s.envelopes[d] = *spec.envelope;
      }
      if (spec.actuator) {
        check_actuator(model, spec.dof, *spec.actuator, s.drives[d]);
        s.actuators[d] = *spec.actuator;
      }
    }
    apply_urdf_effort_limits(scene.robot, s);
    s.validate(model);
    return s;
  });
}

Simulation make_simulation(const Scene& scene) {
  Simulation sim(scene.model(), scene_settings(scene));
  naming_the_scene(scene, [&] {
    sim.set_q(scene.q0);
    sim.set_qd(scene.qd0);
    apply_targets(scene, sim, 0);
  });
  return sim;
}

// The applied force of step k at time step dt (applied_force_at), finite or an InputError.
static VecX applied_force_of_step(const Scene& scene, int nv, double dt, int step_index) {
  VecX tau = VecX::Zero(nv);
  const double t = static_cast<double>(step_index) * dt;
  for (const AppliedForceSpec& f : scene.applied_forces) {
    tau[f.dof] = f.at(t);
    if (!std::isfinite(tau[f.dof]))
      throw InputError(scene.path.string() + ": applied_force." + f.joint +
                       ".sine: the force at t = " + format_double(t) +
                       " s is not finite (2 pi frequency t overflows)");
  }
  return tau;
}

VecX applied_force_at(const Scene& scene, const Simulation& sim, int step_index) {
  return applied_force_of_step(scene, sim.model().nv, sim.options().dt, step_index);
}

// Calls f(drive, position, velocity) with each sine drive's targets for step k at time step dt
// (apply_targets), each finite or an InputError.
template <class F>
static void for_each_sine_target(const Scene& scene, double dt, int step_index, F&& f) {
  // Control step m, sub-step j of k; times in double: (m + 1) k in int overflows for INT_MAX.
  const ControlStep& control = scene.control;
  const int k = control.substeps;
  const long m = (step_index >= 0 ? step_index : static_cast<long>(step_index) - (k - 1)) / k;
  const int j = static_cast<int>(step_index - m * k) + 1;  // m rounded down: j in [1, k]
  const double t = (static_cast<double>(m) + 1.0) * k * dt;
  const double t_prev = static_cast<double>(m) * k * dt;
  const bool linear = control.targets == TargetInterpolation::linear && j < k;
  for (const DriveSpec& d : scene.drives) {
    if (!d.sine) continue;
    const double position = d.sine->position(t), velocity = d.sine->velocity(t);
    const double prev_position = linear ? d.sine->position(t_prev) : position;
    const double prev_velocity = linear ? d.sine->velocity(t_prev) : velocity;
    if (!std::isfinite(position) || !std::isfinite(velocity) || !std::isfinite(prev_position) ||
        !std::isfinite(prev_velocity))
      throw InputError(scene.path.string() + ": drives." + d.joint +
                       ".target.sine: the target at t = " + format_double(t) +
                       " s is not finite (2 pi frequency t overflows)");
    f(d, substep_target(prev_position, position, j, k, control.targets),
      substep_target(prev_velocity, velocity, j, k, control.targets));
  }
}

void apply_targets(const Scene& scene, Simulation& sim, int step_index) {
  if (!scene.applied_forces.empty())
    sim.set_applied_force(applied_force_at(scene, sim, step_index));
  for_each_sine_target(scene, sim.options().dt, step_index,
                       [&](const DriveSpec& d, double position, double velocity) {
                         sim.set_drive_target(d.dof, position, velocity);
                       });
}

// What make_simulation refuses (the settings, the start state, step 0's targets and applied
// force), checked on values: a scene that loads also runs.
[[gnu::noinline]] static void check_scene_start(const Scene& scene) {
  const Settings settings = scene_settings(scene);
  const Model& model = *scene.model();
  naming_the_scene(scene, [&] {
    (void)checked_configuration(model, scene.q0);
    check_state_vector(scene.qd0, model.nv, "qd");
    const double dt = settings.options.dt;
    if (!scene.applied_forces.empty()) (void)applied_force_of_step(scene, model.nv, dt, 0);
    for_each_sine_target(scene, dt, 0, [&](const DriveSpec& d, double position, double velocity) {
      const auto dof = static_cast<size_t>(d.dof);
      Drive drive = settings.drives[dof];
      drive.target_position = position;
      drive.target_velocity = velocity;
      check_drive(model, d.dof, drive, settings.actuators[dof].kind);
    });
  });
}

Simulation run_scene(const Scene& scene,
                     const std::function<void(const Simulation&, int)>& on_state) {
  Simulation sim = make_simulation(scene);
  if (on_state) on_state(sim, 0);
  for (int k = 0; k < scene.steps; ++k) {
    apply_targets(scene, sim, k);
    sim.step();
    if (on_state) on_state(sim, k + 1);
  }
  return sim;
}

}  // namespace featherdrive
