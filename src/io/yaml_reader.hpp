// The scene reader's YAML helpers, shared by the scene's sections (scene.cpp, fit_spec.cpp):
// every error names the file, the key path and the value.
#pragma once

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "featherdrive/io/error.hpp"
#include "featherdrive/io/urdf.hpp"

namespace featherdrive::scene_yaml {

// Reads YAML nodes and names the file, the key path and the value in every error.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& why) const {
    throw InputError(file_ + ": " + path + ": " + why);
  }
  [[noreturn]] void fail(const std::string& path, const YAML::Node& value,
                         const std::string& why) const {
    throw InputError(file_ + ": " + path + " = " + show(value) + ": " + why);
  }

  static std::string show(const YAML::Node& node) {
    if (!node.IsDefined() || node.IsNull()) return "null";
    if (node.IsScalar()) return node.Scalar();
    YAML::Emitter out;
    out.SetMapFormat(YAML::Flow);
    out.SetSeqFormat(YAML::Flow);
    out << node;
    return out.c_str();
  }

  /// A map whose keys are all in `allowed` (no check when `allowed` is empty) and appear once.
  void map(const YAML::Node& node, const std::string& path,
           const std::vector<std::string>& allowed) const {
    if (!node.IsMap()) fail(path, node, "must be a map (key: value, ...)");
    std::set<std::string> seen;
    for (const auto& kv : node) {
      if (!kv.first.IsScalar()) fail(path, kv.first, "keys must be names");
      const std::string key = kv.first.Scalar();
      const std::string at = join(path, key);
      if (!seen.insert(key).second) fail(at, "the key appears twice");
      if (allowed.empty()) continue;
      bool known = false;
      for (const std::string& a : allowed) known = known || a == key;
      if (!known) {
        std::string list;
        for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(at, "unknown key (expected one of: " + list + ")");
      }
    }
  }

  double number(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) fail(path, node, "must be a number");
    try {
      return node.as<double>();
    } catch (const YAML::Exception&) {
      fail(path, node, "must be a number");
    }
  }
  double finite(const YAML::Node& node, const std::string& path) const {
    const double v = number(node, path);
    if (!std::isfinite(v)) fail(path, node, "must be finite");
    return v;
  }
  double non_negative(const YAML::Node& node, const std::string& path) const {
    const double v = number(node, path);
    if (!std::isfinite(v) || v < 0.0) fail(path, node, "must be finite and >= 0");
    return v;
  }
  /// > 0; .inf allowed.
  double positive(const YAML::Node& node, const std::string& path) const {
    const double v = number(node, path);
    if (std::isnan(v) || v <= 0.0) fail(path, node, "must be > 0");
    return v;
  }
  /// An integer in [min, max], read in 64 bits before it is narrowed: a fraction, an exponent
  /// or a value out of range is refused, never truncated.
  long integer(const YAML::Node& node, const std::string& path, long min, long max) const {
    if (!node.IsScalar()) fail(path, node, "must be an integer");
    const std::string& text = node.Scalar();
    const char* begin = text.data();
    const char* end = begin + text.size();
    if (begin != end && *begin == '+' && end - begin > 1 && begin[1] != '-') ++begin;
    std::int64_t v = 0;
    const auto [stop, error] = std::from_chars(begin, end, v);
    if (begin == end || stop != end ||
        (error != std::errc() && error != std::errc::result_out_of_range))
      fail(path, node, "must be an integer");
    const bool negative = *begin == '-';
    if (error == std::errc::result_out_of_range ? negative : v < min)
      fail(path, node, "must be >= " + std::to_string(min));
    if (error == std::errc::result_out_of_range || v > max)
      fail(path, node, "must be <= " + std::to_string(max));
    return static_cast<long>(v);
  }
  bool boolean(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) fail(path, node, "must be true or false");
    try {
      return node.as<bool>();
    } catch (const YAML::Exception&) {
      fail(path, node, "must be true or false");
    }
  }
  std::string text(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar() || node.Scalar().empty()) fail(path, node, "must be a non-empty string");
    return node.Scalar();
  }
  Vec3 vec3(const YAML::Node& node, const std::string& path) const {
    if (!node.IsSequence() || node.size() != 3) fail(path, node, "must be a list of 3 numbers");
    Vec3 v;
    for (int i = 0; i < 3; ++i) v[i] = finite(node[i], path + "[" + std::to_string(i) + "]");
    return v;
  }

  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

// The one-dof joint a scene entry names, or an error that lists the joints there are.
inline int joint_dof(const Reader& r, const UrdfRobot& robot, const std::string& joint,
                     const std::string& path) {
  const Model& model = *robot.model;
  auto spherical = [&](int dof) {
    return model.links[model.dof_link[dof]].joint_type == JointType::spherical;
  };
  // A spherical joint's axes by their dof names (docs/math/spherical_joints.md).
  for (int d = 0; d < model.nv; ++d)
    if (model.dof_names[d] == joint && spherical(d)) return d;
  for (const Link& link : model.links) {
    if (link.joint_name != joint) continue;
    if (link.nv == 1) return link.v_index;
    if (link.joint_type == JointType::spherical)
      r.fail(path, "joint '" + joint + "' is spherical: name one of its axes, '" + joint +
                       ":twist', '" + joint + ":swing1' or '" + joint + ":swing2'");
    r.fail(path, "joint '" + joint + "' is " + to_string(link.joint_type) +
                     ": this setting acts on revolute, prismatic and spherical joints only");
  }
  for (const std::string& name : robot.joint_order)
    if (name == joint)
      r.fail(path, "joint '" + joint +
                       "' is fixed (merged into its parent): it has no degree of freedom");
  std::string list;
  for (int d : robot.dof_order)
    if (model.links[model.dof_link[d]].nv == 1 || spherical(d))
      list += (list.empty() ? "" : ", ") + model.dof_names[d];
  r.fail(path, "no joint named '" + joint + "' in " + robot.path.filename().string() +
                   " (moving joints: " + list + ")");
}

}  // namespace featherdrive::scene_yaml
