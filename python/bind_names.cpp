// Names: the model's and the URDF's joint and link names, sim.joint(name), example_path.
#include <map>

#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

namespace {

// ---- names and the joint accessor (issue 20) --------------------------------------------------
// sim.joint(name) returns a JointAccessor: it holds the Simulation's Python object (so the
// simulation lives as long as it) and reads or writes the simulation at call time, under its lock.
// One-dof joints give floats, multi-dof joints arrays (or lists of settings).

/// A ValueError message for a name that is not among `names`: the nearest ones, or the valid ones.
std::string unknown_name(const std::string& what, const std::string& name,
                         const std::vector<std::string>& names) {
  const auto near = py::module_::import("difflib")
                        .attr("get_close_matches")(name, names, 3, 0.6)
                        .cast<std::vector<std::string>>();
  const bool some = !near.empty();
  const std::vector<std::string>& list = some ? near : names;
  std::string msg = "no " + what + " named '" + name + "'; " +
                    (some ? "did you mean: " : "the " + what + "s are: ");
  for (size_t i = 0; i < std::min<size_t>(list.size(), 12); ++i) msg += (i ? ", " : "") + list[i];
  if (list.size() > 12) msg += ", ... (" + std::to_string(list.size()) + " in all)";
  return msg;
}

struct JointAccessor {
  py::object owner;  // the Simulation's Python object
  Simulation* sim;
  int link;
  Link joint;  // a copy: its names and indices are every model variant's
  const Link& info() const { return joint; }
  int dof() const { return info().v_index; }

  /// f(sim, dof) for a one-dof joint, else [f(sim, dof) for each dof], under the lock.
  template <class F>
  py::object per_dof(F f) const {
    const Link& l = info();
    return locked(*sim, [&]() -> py::object {
      if (l.nv == 1) return py::cast(std::invoke(f, *sim, l.v_index));
      py::list out;
      for (int k = 0; k < l.nv; ++k) out.append(py::cast(std::invoke(f, *sim, l.v_index + k)));
      return out;
    });
  }
  /// The joint's entries of an (nv,) vector: a float or a new array.
  py::object slice(VecView (Simulation::*v)() const) const {
    const Link& l = info();
    return locked(*sim, [&]() -> py::object {
      if (l.nv == 1) return py::float_((sim->*v)()[l.v_index]);
      return py::cast(VecX((sim->*v)().segment(l.v_index, l.nv)));
    });
  }
};

JointAccessor joint_accessor(py::object sim_obj, py::handle joint) {
  Simulation& s = sim_obj.cast<Simulation&>();
  const std::string name = to_str(joint, "joint");
  const std::shared_ptr<const Model> model = model_of(s);
  std::vector<std::string> moving;
  for (int i = 0; i < model->num_links(); ++i) {
    const Link& l = model->links[static_cast<size_t>(i)];
    if (l.joint_name == name && l.nv == 0)
      throw std::invalid_argument("joint '" + name + "' is fixed: it has no degree of freedom");
    if (l.joint_name == name) return JointAccessor{std::move(sim_obj), &s, i, l};
    if (l.nv > 0) moving.push_back(l.joint_name);
  }
  throw std::invalid_argument(unknown_name("joint", name, moving));
}

py::array int_array(const std::vector<int>& v) {
  py::array_t<long long> a(static_cast<py::ssize_t>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) a.mutable_data()[i] = v[i];
  a.attr("flags").attr("writeable") = false;
  return a;
}

}  // namespace

void featherdrive::python::bind_names(py::module_& m) {
  auto model = py::reinterpret_borrow<py::class_<Model, ModelPtr>>(m.attr("Model"));
  model
      .def_property_readonly(
          "link_names",
          [](const Model& mo) {
            std::vector<std::string> names;
            for (const Link& l : mo.links) names.push_back(l.name);
            return names;
          },
          "Link names in link order (depth-first preorder; a new list).")
      .def_property_readonly(
          "joint_names",
          [](const Model& mo) {
            std::vector<std::string> names;
            for (const Link& l : mo.links) names.push_back(l.joint_name);
            return names;
          },
          "Each link's inbound joint name, in link order (the root's joint first; a new list).");
  auto robot = py::reinterpret_borrow<py::class_<UrdfRobot>>(m.attr("UrdfRobot"));
  robot
      .def_property_readonly(
          "urdf_joint_names", [](const UrdfRobot& r) { return r.joint_order; },
          "Every <joint> name in file order, fixed ones included.")
      .def_property_readonly(
          "dof_of_urdf_joint", [](const UrdfRobot& r) { return int_array(r.dof_of_urdf_joint); },
          "First dof of each urdf_joint_names entry, -1 for a fixed joint.")
      .def_property_readonly(
          "link_of_urdf_joint", [](const UrdfRobot& r) { return int_array(r.link_of_urdf_joint); },
          "Model link of each joint's child (fixed: the link it merged into).")
      .def_property_readonly(
          "urdf_joint_of_dof", [](const UrdfRobot& r) { return int_array(r.urdf_joint_of_dof); },
          "Index in urdf_joint_names of each dof's joint, -1 for a floating "
          "root's dofs.");

  py::class_<JointAccessor> joint(m, "JointAccessor",
                                  "One joint of a Simulation by name (Simulation.joint): reads and "
                                  "writes the simulation at call time. One-dof joints give floats, "
                                  "multi-dof joints arrays or lists.");
  joint
      .def_property_readonly(
          "name", [](const JointAccessor& j) { return j.info().joint_name; }, "joint name")
      .def_property_readonly(
          "type", [](const JointAccessor& j) { return j.info().joint_type; }, "JointType")
      .def_property_readonly(
          "dof", [](const JointAccessor& j) { return j.info().v_index; },
          "first dof index (into qd and the forces)")
      .def_property_readonly(
          "nv", [](const JointAccessor& j) { return j.info().nv; }, "dofs")
      .def_property_readonly(
          "link", [](const JointAccessor& j) { return j.link; }, "index of the joint's child link")
      .def_property_readonly(
          "q",
          [](const JointAccessor& j) -> py::object {
            const Link& l = j.info();
            return locked(*j.sim, [&]() -> py::object {
              if (l.nq == 1) return py::float_(j.sim->q()[l.q_index]);
              return py::cast(VecX(j.sim->q().segment(l.q_index, l.nq)));
            });
          },
          "position (float) or the joint's q entries (a new array)")
      .def(
          "set_target",
          [](JointAccessor& j, double position, double velocity) {
            locked(*j.sim, [&] { j.sim->set_drive_target(j.dof(), position, velocity); });
          },
          py::arg("position"), py::arg("velocity") = 0.0,
          "Sets the drive's target; ValueError if the joint has no drive.")
      .def_property(
          "drive", [](const JointAccessor& j) { return j.per_dof(&Simulation::drive); },
          [](JointAccessor& j, const Drive& d) {
            locked(*j.sim, [&] { j.sim->set_drive(j.dof(), d); });
          },
          "the Drive (a copy); assign a Drive to set it")
      .def_property(
          "limits",
          [](const JointAccessor& j) {
            return j.per_dof([](const Simulation& s, int d) {
              return std::make_pair(s.lower_limit(d), s.upper_limit(d));
            });
          },
          [](JointAccessor& j, std::pair<double, double> l) {
            locked(*j.sim, [&] { j.sim->set_joint_limits(j.dof(), l.first, l.second); });
          },
          "(lower, upper) position limits; assign a pair to set them (+-inf: none)")
      .def_property(
          "friction", [](const JointAccessor& j) { return j.per_dof(&Simulation::joint_friction); },
          [](JointAccessor& j, const JointFriction& f) {
            locked(*j.sim, [&] { j.sim->set_joint_friction(j.dof(), f); });
          },
          "the JointFriction (a copy); assign one to set it")
      .def_property(
          "max_velocity",
          [](const JointAccessor& j) { return j.per_dof(&Simulation::max_joint_velocity); },
          [](JointAccessor& j, double v) {
            locked(*j.sim, [&] { j.sim->set_max_joint_velocity(j.dof(), v); });
          },
          "largest |qd| (inf: none)")
      .def(
          "row_parameters",
          [](const JointAccessor& j, const std::string& kind) {
            const RowKindInfo& k = row_kind(kind);
            return j.per_dof([&](const Simulation& s, int d) {
              const std::vector<double> values = s.row_parameters(kind, d);
              std::map<std::string, double> out;
              for (size_t f = 0; f < values.size(); ++f)
                out[std::string(k.fields[f].name)] = values[f];
              return out;
            });
          },
          py::arg("kind"), "a row kind's fields (fd.row_kinds()) as a dict, one per dof")
      .def(
          "set_row_parameters",
          [](JointAccessor& j, const std::string& kind, const py::kwargs& fields) {
            const RowKindInfo& k = row_kind(kind);
            locked(*j.sim, [&] {
              // Every dof of the joint (a spherical joint's three axes), checked before any
              // changes.
              std::vector<std::vector<double>> next;
              for (int d = j.dof(); d < j.dof() + j.info().nv; ++d) {
                std::vector<double> values = j.sim->row_parameters(kind, d);
                for (const auto& [name, value] : fields) {
                  const std::string field = py::str(name).cast<std::string>();
                  values[static_cast<size_t>(row_field_column(k, field) - k.offset)] =
                      row_field_value(value, kind + "." + field);
                }
                check_row_parameters(j.sim->model(), d, k, values);
                next.push_back(values);
              }
              for (int d = j.dof(); d < j.dof() + j.info().nv; ++d)
                j.sim->set_row_parameters(kind, d, next[static_cast<size_t>(d - j.dof())]);
            });
          },
          py::arg("kind"),
          "a row kind's fields by keyword on every dof of the joint; the others keep theirs")
      .def(
          "row_force",
          [](const JointAccessor& j, const std::string& kind) {
            return j.per_dof([&](const Simulation& s, int d) -> double { return s.row_force(kind)[d]; });
          },
          py::arg("kind"), "the force the row kind applied in the last step")
      .def("__repr__", [](const JointAccessor& j) {
        return "JointAccessor('" + j.info().joint_name + "', " + to_string(j.info().joint_type) +
               ", dof " + std::to_string(j.info().v_index) + ")";
      });
  using Vector = VecView (Simulation::*)() const;
  for (const auto& [name, vector] : {std::pair<const char*, Vector>{"qd", &Simulation::qd},
                                     {"drive_force", &Simulation::drive_force},
                                     {"limit_force", &Simulation::limit_force},
                                     {"friction_force", &Simulation::friction_force},
                                     {"applied_force", &Simulation::applied_force}})
    joint.def_property_readonly(
        name, [v = vector](const JointAccessor& j) { return j.slice(v); },
        "the joint's entries of the simulation's vector of that name "
        "(a float, or a new array), read now");

  m.def(
      "example_path",
      [](py::handle name) {
        const std::string n = to_str(name, "name");
        const auto os = py::module_::import("os");
        const py::object dir = os.attr("path").attr("join")(
            os.attr("path").attr("dirname")(py::module_::import("featherdrive").attr("__file__")),
            "examples");
        const auto robots = py::module_::import("builtins")
                                .attr("sorted")(os.attr("listdir")(dir))
                                .cast<std::vector<std::string>>();
        if (std::find(robots.begin(), robots.end(), n) == robots.end())
          throw std::invalid_argument("example_path: " + unknown_name("example robot", n, robots));
        return os.attr("path").attr("join")(dir, n).cast<std::string>();
      },
      py::arg("name"),
      "The path of an example robot (examples/NAME, copied beside the module when it was built), "
      "e.g. example_path('arm7.urdf'); ValueError naming the ones there are.");

  auto sim = py::reinterpret_borrow<py::class_<Simulation, SimulationHolder>>(m.attr("Simulation"));
  sim.def("joint", &joint_accessor, py::arg("name"),
          "A live accessor of the named joint (q, qd, forces, drive, set_target, limits, friction, "
          "max_velocity); ValueError naming the nearest joint names for an unknown one.");
}
