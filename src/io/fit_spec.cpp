#include "featherdrive/io/fit_spec.hpp"

#include <cmath>
#include <set>
#include <utility>

#include "featherdrive/core/format.hpp"
#include "fit_spec_reader.hpp"

namespace featherdrive {
namespace {

using scene_yaml::Reader;

constexpr std::pair<FitQuantity, const char*> kNames[] = {
    {FitQuantity::stiffness, "stiffness"},
    {FitQuantity::damping, "damping"},
    {FitQuantity::max_force, "max_force"},
    {FitQuantity::armature, "armature"},
    {FitQuantity::friction_static, "friction.static"},
    {FitQuantity::friction_dynamic, "friction.dynamic"},
    {FitQuantity::friction_viscous, "friction.viscous"},
    {FitQuantity::friction_coefficient, "friction_coefficient"},
    {FitQuantity::delay, "delay"},
    {FitQuantity::mass_scale, "mass_scale"},
};

// The delay is searched over every integer in its bounds (docs/fitting.md): keep that short.
constexpr long kMaxFitDelay = 64;

bool on_drive(FitQuantity q) {
  return q == FitQuantity::stiffness || q == FitQuantity::damping || q == FitQuantity::max_force ||
         q == FitQuantity::delay;
}

// The scene's own value of `quantity` on dof or link `index`.
double scene_value(FitQuantity quantity, const Simulation& sim, int index) {
  switch (quantity) {
    case FitQuantity::stiffness:
      return sim.drive(index).stiffness;
    case FitQuantity::damping:
      return sim.drive(index).damping;
    case FitQuantity::max_force:
      return sim.drive(index).max_force;
    case FitQuantity::armature:
      return sim.model().armature[index];
    case FitQuantity::friction_static:
      return sim.joint_friction(index).static_effort;
    case FitQuantity::friction_dynamic:
      return sim.joint_friction(index).dynamic_effort;
    case FitQuantity::friction_viscous:
      return sim.joint_friction(index).viscous;
    case FitQuantity::friction_coefficient:
      return sim.friction_coefficient(index);
    case FitQuantity::delay:
      break;
    case FitQuantity::mass_scale:
      return 1.0;
    case FitQuantity::row_field:
      break;
  }
  return 0.0;
}

FitParameter read_parameter(const Reader& r, const YAML::Node& node, const std::string& key,
                            const Scene& scene, const Simulation& sim) {
  r.map(node, key, {"quantity", "joints", "links", "bounds", "shared", "initial"});
  const auto at = [&](const char* k) { return Reader::join(key, k); };
  FitParameter p;
  p.key = key;
  if (!node["quantity"]) r.fail(at("quantity"), "missing (stiffness, damping, ...)");
  const std::string name = r.text(node["quantity"], at("quantity"));
  bool known = false;
  std::string list;
  for (const auto& [q, spelling] : kNames) {
    list += (list.empty() ? "" : ", ") + std::string(spelling);
    if (name == spelling) p.quantity = q, known = true;
  }
  // A row kind's field: "<kind>.<field>" (constraint/row_kinds.hpp).
  for (const RowKindInfo& kind : row_kinds())
    for (const RowField& f : kind.fields) {
      const std::string spelling = std::string(kind.name) + "." + std::string(f.name);
      list += ", " + spelling;
      if (name != spelling) continue;
      p.quantity = FitQuantity::row_field;
      p.row_kind = kind.name;
      p.row_field_name = f.name;
      p.row_column = row_field_column(kind, f.name);
      known = true;
    }
  if (!known) r.fail(at("quantity"), node["quantity"], "unknown (expected one of: " + list + ")");

  const Model& m = *scene.model();
  const bool links = p.quantity == FitQuantity::mass_scale;
  const char* which = links ? "links" : "joints";
  if (node[links ? "joints" : "links"])
    r.fail(at(links ? "joints" : "links"), std::string("give ") + which + " for " + name);
  const YAML::Node names = node[which];
  if (!names) r.fail(at(which), "missing: the " + std::string(which) + " to fit, or all");
  if (names.IsScalar() && names.Scalar() == "all") {
    if (links) {
      for (int i = 0; i < m.num_links(); ++i)
        if (m.links[i].nv > 0) p.names.push_back(m.links[i].name), p.indices.push_back(i);
    } else if (on_drive(p.quantity)) {
      for (const DriveSpec& d : scene.drives)
        if (d.drive.type != DriveType::none) p.names.push_back(d.joint), p.indices.push_back(d.dof);
    } else {
      for (int d : scene.robot.dof_order)
        if (m.links[m.dof_link[d]].nv == 1)
          p.names.push_back(m.dof_names[d]), p.indices.push_back(d);
    }
  } else {
    if (!names.IsSequence() || names.size() == 0)
      r.fail(at(which), names, std::string("must be a list of names or all"));
    for (size_t i = 0; i < names.size(); ++i) {
      const std::string ip = std::string(at(which)) + "[" + std::to_string(i) + "]";
      const std::string n = r.text(names[i], ip);
      int index = -1;
      if (links) {
        for (int l = 0; l < m.num_links(); ++l)
          if (m.links[l].name == n && m.links[l].nv > 0) index = l;
        if (index < 0) r.fail(ip, names[i], "no moving link of that name");
      } else {
        index = scene_yaml::joint_dof(r, scene.robot, n, ip);
        if (on_drive(p.quantity) && sim.drive(index).type == DriveType::none)
          r.fail(ip, names[i], "the joint has no drive (drives: type none) to fit " + name);
      }
      p.names.push_back(n);
      p.indices.push_back(index);
    }
  }
  if (p.names.empty()) r.fail(at(which), names, "names nothing to fit");

  if (!node["bounds"]) r.fail(at("bounds"), "missing: [lower, upper]");
  const YAML::Node b = node["bounds"];
  if (!b.IsSequence() || b.size() != 2) r.fail(at("bounds"), b, "must be [lower, upper]");
  if (p.quantity == FitQuantity::delay) {
    p.lower = static_cast<double>(r.integer(b[0], at("bounds") + "[0]", 0, kMaxFitDelay));
    p.upper = static_cast<double>(r.integer(b[1], at("bounds") + "[1]", 0, kMaxFitDelay));
  } else {
    p.lower = r.finite(b[0], at("bounds") + "[0]");
    p.upper = r.finite(b[1], at("bounds") + "[1]");
    const bool positive =
        p.quantity == FitQuantity::mass_scale || p.quantity == FitQuantity::max_force;
    // A row kind's field: its own check below (a spring's reference may be negative).
    if (p.quantity != FitQuantity::row_field && (positive ? p.lower <= 0.0 : p.lower < 0.0))
      r.fail(at("bounds") + "[0]", b[0], positive ? "must be > 0" : "must be >= 0");
  }
  if (!(p.lower < p.upper) && !(p.quantity == FitQuantity::delay && p.lower == p.upper))
    r.fail(at("bounds"), b, "lower must be below upper");
  if (p.quantity == FitQuantity::row_field) {  // both ends must be values the setter takes
    const RowKindInfo& kind = row_kind(p.row_kind);
    for (size_t i = 0; i < p.indices.size(); ++i)
      for (const double end : {p.lower, p.upper}) {
        std::vector<double> values = sim.row_parameters(kind.name, p.indices[i]);
        values[static_cast<size_t>(p.row_column - kind.offset)] = end;
        try {
          check_row_parameters(m, p.indices[i], kind, values);
        } catch (const std::invalid_argument& e) {
          r.fail(at("bounds"), b, e.what());
        }
      }
  }

  p.shared = p.quantity == FitQuantity::delay;
  if (node["shared"]) {
    p.shared = r.boolean(node["shared"], at("shared"));
    if (p.quantity == FitQuantity::delay && !p.shared)
      r.fail(at("shared"), node["shared"], "delay is one value for all its joints");
  }
  const size_t unknowns = p.shared ? 1 : p.names.size();
  const auto check = [&](double v, const std::string& what) {
    if (!(v >= p.lower && v <= p.upper))
      r.fail(key, "the starting value " + what + " = " + format_double(v) + " is outside bounds [" +
                      format_double(p.lower) + ", " + format_double(p.upper) + "]");
  };
  if (node["initial"]) {
    const double v =
        p.quantity == FitQuantity::delay
            ? static_cast<double>(r.integer(node["initial"], at("initial"), 0, kMaxFitDelay))
            : r.finite(node["initial"], at("initial"));
    check(v, "initial");
    p.initial.assign(unknowns, v);
  } else if (p.quantity == FitQuantity::delay) {
    p.initial.assign(1, p.lower);
  } else {
    for (size_t i = 0; i < unknowns; ++i) {
      const double v = p.quantity == FitQuantity::row_field
                           ? sim.settings().row_parameters(p.indices[i], p.row_column)
                           : scene_value(p.quantity, sim, p.indices[i]);
      check(v, std::string("(the scene's ") + name + " of " + p.names[i] + "; give initial:)");
      p.initial.push_back(v);
    }
  }
  return p;
}

FitData read_data(const Reader& r, const YAML::Node& node) {
  r.map(node, "fit.data", {"resample", "segment_steps", "qd_weight"});
  FitData data;
  if (node["resample"]) {
    const std::string rule = r.text(node["resample"], "fit.data.resample");
    if (rule == "linear")
      data.resample = FitData::Resample::linear;
    else if (rule != "exact")
      r.fail("fit.data.resample", node["resample"], "must be exact or linear");
  }
  if (node["segment_steps"])
    data.segment_steps = static_cast<int>(
        r.integer(node["segment_steps"], "fit.data.segment_steps", 0, 1'000'000'000L));
  if (node["qd_weight"]) data.qd_weight = r.non_negative(node["qd_weight"], "fit.data.qd_weight");
  return data;
}

}  // namespace

const char* to_string(FitQuantity quantity) {
  for (const auto& [q, spelling] : kNames)
    if (q == quantity) return spelling;
  return quantity == FitQuantity::row_field ? "row field" : "?";
}

std::string FitParameter::spelling() const {
  return quantity == FitQuantity::row_field ? row_kind + "." + row_field_name
                                            : std::string(to_string(quantity));
}

int FitSpec::num_unknowns() const {
  int n = 0;
  for (const FitParameter& p : parameters)
    if (p.quantity != FitQuantity::delay) n += static_cast<int>(p.initial.size());
  return n;
}

FitSpec read_fit_spec(const Reader& r, const YAML::Node& node, const Scene& scene) {
  r.map(node, "fit", {"parameters", "data"});
  const Simulation sim = make_simulation(scene);
  FitSpec spec;
  const YAML::Node ps = node["parameters"];
  if (!ps) r.fail("fit.parameters", "missing: the list of parameters to fit");
  if (!ps.IsSequence() || ps.size() == 0)
    r.fail("fit.parameters", ps, "must be a non-empty list of {quantity, joints, bounds}");
  std::set<std::pair<std::string, int>> seen;
  bool delay = false;
  for (size_t i = 0; i < ps.size(); ++i) {
    const std::string key = "fit.parameters[" + std::to_string(i) + "]";
    FitParameter p = read_parameter(r, ps[i], key, scene, sim);
    if (p.quantity == FitQuantity::delay && std::exchange(delay, true))
      r.fail(key, "delay is fitted once (one value for every joint it names)");
    for (size_t j = 0; j < p.names.size(); ++j)
      if (!seen.insert({p.spelling(), p.indices[j]}).second)
        r.fail(key, p.spelling() + " of " + p.names[j] + " is fitted twice");
    spec.parameters.push_back(std::move(p));
  }
  if (node["data"]) spec.data = read_data(r, node["data"]);
  return spec;
}

}  // namespace featherdrive
