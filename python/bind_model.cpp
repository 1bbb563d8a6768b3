// Model (read-only), its links, and ModelBuilder with its joint and link specs.
#include "bindings.hpp"
#include "featherdrive/model/dof_position.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

namespace {

// The dofs argument of dof_positions / set_dof_positions: None (every dof with a position, in
// model order) or a sequence of dof indices, each with a position.
std::vector<int> position_dofs(const Model& model, py::handle dofs_obj) {
  std::vector<int> dofs;
  if (dofs_obj.is_none()) {
    for (int d = 0; d < model.nv; ++d)
      if (has_dof_position(model, d)) dofs.push_back(d);
    return dofs;
  }
  for (py::handle d : dofs_obj) {
    const int dof = to_int(d, "dofs[" + std::to_string(dofs.size()) + "]", 0, model.nv - 1);
    if (!has_dof_position(model, dof)) dof_position(model, model.neutral_configuration(), dof);
    dofs.push_back(dof);
  }
  return dofs;
}

// q as rows (T, nq), and whether it was one configuration (nq,).
std::pair<py::array_t<double, py::array::c_style>, bool> q_rows(const Model& model,
                                                                py::handle q_obj) {
  auto q = as_float_array(q_obj, "q");
  const bool single = q.ndim() == 1;
  if ((q.ndim() != 1 && q.ndim() != 2) || q.shape(q.ndim() - 1) != model.nq)
    throw std::invalid_argument("q has shape " + shape_of(q) + ", expected (" +
                                std::to_string(model.nq) + ",) or (T, " +
                                std::to_string(model.nq) + ")");
  return {q, single};
}

}  // namespace

void featherdrive::python::bind_model(py::module_& m) {
  // ---- model ----------------------------------------------------------------------------------
  py::class_<Link>(m, "Link", "A link of a Model and its inbound joint (read-only).")
      .def_readonly("name", &Link::name, "link name")
      .def_readonly("parent", &Link::parent, "index of the parent link, -1 for the world")
      .def_readonly("children", &Link::children, "indices of the child links")
      .def_readonly("mass", &Link::mass, "kg")
      .def_readonly("com", &Link::com, "centre of mass in the link frame (3,)")
      .def_readonly("inertia_com", &Link::inertia_com, "inertia about the centre of mass (3, 3)")
      .def_readonly("joint_name", &Link::joint_name, "name of the inbound joint")
      .def_readonly("joint_type", &Link::joint_type, "JointType of the inbound joint")
      .def_readonly("axis", &Link::axis, "unit joint axis in the joint frame (3,)")
      .def_readonly("q_index", &Link::q_index, "first entry of this joint in q")
      .def_readonly("v_index", &Link::v_index, "first entry of this joint in qd")
      .def_readonly("nq", &Link::nq, "entries of this joint in q")
      .def_readonly("nv", &Link::nv, "dofs of this joint")
      .def_readonly("subtree_end", &Link::subtree_end, "links [index, subtree_end) are its subtree")
      .def("__repr__", [](const Link& l) {
        return "Link('" + l.name + "', joint='" + l.joint_name + "', " + to_string(l.joint_type) +
               ")";
      });

  py::class_<Model, ModelPtr>(m, "Model",
                              "The immutable description of an articulation; one Model serves "
                              "many simulations.")
      .def_readonly("nq", &Model::nq, "size of the configuration vector q")
      .def_readonly("nv", &Model::nv, "number of dofs (size of qd)")
      .def_readonly("gravity", &Model::gravity, "gravity (3,) [m/s^2]")
      .def_readonly("links", &Model::links, "the links in depth-first preorder (list of Link)")
      .def_readonly("armature", &Model::armature, "per dof (nv,)")
      .def_readonly("lower_limit", &Model::lower_limit, "per dof (nv,); -inf where unbounded")
      .def_readonly("upper_limit", &Model::upper_limit, "per dof (nv,); +inf where unbounded")
      .def_readonly("effort_limit", &Model::effort_limit, "per dof (nv,); informative")
      .def_readonly("velocity_limit", &Model::velocity_limit, "per dof (nv,)")
      .def_readonly("damping", &Model::damping, "viscous joint damping per dof (nv,)")
      .def_readonly("friction", &Model::friction, "Coulomb joint friction per dof (nv,)")
      .def_readonly("dof_link", &Model::dof_link, "the link owning each dof")
      .def_readonly("dof_names", &Model::dof_names,
                    "joint name of each dof ('joint:twist', ':swing1', ':swing2' for spherical, "
                    "'joint:wx' ... ':vz' for floating)")
      .def("floating_base", &Model::floating_base, "Whether the root has a floating joint.")
      .def("num_links", &Model::num_links, "Number of links.")
      .def("link_index", &Model::link_index, py::arg("name"),
           "Index of the named link; ValueError if there is none.")
      .def("joint_link_index", &Model::joint_link_index, py::arg("joint_name"),
           "Index of the link whose inbound joint has this name; ValueError if there is none.")
      .def("dof_index", &Model::dof_index, py::arg("joint_name"),
           "First dof of the named joint; ValueError if there is none or it has no dofs.")
      .def("neutral_configuration", &Model::neutral_configuration,
           "q with every joint at its reference (nq,).")
      .def("__repr__", [](const Model& mo) {
        return "Model(links=" + std::to_string(mo.num_links()) + ", nq=" + std::to_string(mo.nq) +
               ", nv=" + std::to_string(mo.nv) + ")";
      });

  py::class_<JointSpec>(m, "JointSpec",
                        "The inbound joint of a link, as in URDF (see revolute_joint etc.).")
      .def(py::init<>(), "A fixed joint at the parent's origin.")
      .def_readwrite("name", &JointSpec::name, "joint name")
      .def_readwrite("type", &JointSpec::type, "JointType")
      .def_property(
          "origin_xyz", [](const JointSpec& j) { return j.origin_xyz; },
          [](JointSpec& j, py::handle v) { j.origin_xyz = to_vec3(v, "origin_xyz"); },
          "joint frame position in the parent link frame (3,)")
      .def_property(
          "origin_rpy", [](const JointSpec& j) { return j.origin_rpy; },
          [](JointSpec& j, py::handle v) { j.origin_rpy = to_vec3(v, "origin_rpy"); },
          "joint frame roll, pitch, yaw in the parent link frame (3,)")
      .def_property(
          "axis", [](const JointSpec& j) { return j.axis; },
          [](JointSpec& j, py::handle v) { j.axis = to_vec3(v, "axis"); },
          "axis in the joint frame (3,), not zero")
      .def_readwrite("armature", &JointSpec::armature,
                     "[] (none), [a] (every dof) or one value per dof")
      .def_readwrite("lower_limit", &JointSpec::lower_limit, "m or rad; -inf for none")
      .def_readwrite("upper_limit", &JointSpec::upper_limit, "m or rad; +inf for none")
      .def_readwrite("effort_limit", &JointSpec::effort_limit, "N or Nm (informative)")
      .def_readwrite("velocity_limit", &JointSpec::velocity_limit, "m/s or rad/s")
      .def_readwrite("damping", &JointSpec::damping, "viscous joint damping")
      .def_readwrite("friction", &JointSpec::friction, "Coulomb joint friction");

  py::class_<LinkSpec>(m, "LinkSpec", "A link description for ModelBuilder (see make_link).")
      .def(py::init<>(), "An empty link description.")
      .def_readwrite("name", &LinkSpec::name, "link name")
      .def_readwrite("parent", &LinkSpec::parent, "parent link name, '' for the root")
      .def_readwrite("mass", &LinkSpec::mass, "kg")
      .def_property(
          "com", [](const LinkSpec& l) { return l.com; },
          [](LinkSpec& l, py::handle v) { l.com = to_vec3(v, "com"); },
          "centre of mass in the link frame (3,)")
      .def_property(
          "inertia", [](const LinkSpec& l) { return l.inertia; },
          [](LinkSpec& l, py::handle v) { l.inertia = to_mat3(v, "inertia"); },
          "inertia tensor about the centre of mass, link axes (3, 3)")
      .def_readwrite("joint", &LinkSpec::joint, "the inbound JointSpec");

  const auto zero3 = py::make_tuple(0.0, 0.0, 0.0);
  m.def(
      "fixed_joint",
      [](std::string name, py::handle xyz, py::handle rpy) {
        return fixed_joint(std::move(name), to_vec3(xyz, "xyz"), to_vec3(rpy, "rpy"));
      },
      py::arg("name"), py::arg("xyz") = zero3, py::arg("rpy") = zero3, "A fixed JointSpec.");
  m.def(
      "revolute_joint",
      [](std::string name, py::handle axis, py::handle xyz, py::handle rpy) {
        return revolute_joint(std::move(name), to_vec3(axis, "axis"), to_vec3(xyz, "xyz"),
                              to_vec3(rpy, "rpy"));
      },
      py::arg("name"), py::arg("axis"), py::arg("xyz") = zero3, py::arg("rpy") = zero3,
      "A revolute JointSpec about axis (3,) at origin (xyz, rpy).");
  m.def(
      "prismatic_joint",
      [](std::string name, py::handle axis, py::handle xyz, py::handle rpy) {
        return prismatic_joint(std::move(name), to_vec3(axis, "axis"), to_vec3(xyz, "xyz"),
                               to_vec3(rpy, "rpy"));
      },
      py::arg("name"), py::arg("axis"), py::arg("xyz") = zero3, py::arg("rpy") = zero3,
      "A prismatic JointSpec along axis (3,) at origin (xyz, rpy).");
  m.def(
      "spherical_joint",
      [](std::string name, py::handle xyz, py::handle rpy) {
        return spherical_joint(std::move(name), to_vec3(xyz, "xyz"), to_vec3(rpy, "rpy"));
      },
      py::arg("name"), py::arg("xyz") = zero3, py::arg("rpy") = zero3, "A spherical JointSpec.");
  m.def("floating_joint", &floating_joint, py::arg("name"), "A floating JointSpec (root only).");
  m.def(
      "make_link",
      [](std::string name, std::string parent, double mass, py::handle com, py::handle inertia,
         JointSpec joint) {
        return make_link(std::move(name), std::move(parent), mass, to_vec3(com, "com"),
                         to_mat3(inertia, "inertia"), std::move(joint));
      },
      py::arg("name"), py::arg("parent"), py::arg("mass"), py::arg("com"), py::arg("inertia"),
      py::arg("joint"),
      "A LinkSpec: mass, centre of mass (3,), inertia about it (3, 3) and inbound joint; "
      "parent '' for the root.");

  py::class_<ModelBuilder>(m, "ModelBuilder", "Builds a Model from LinkSpecs, validating once.")
      .def(py::init<>(), "An empty builder; gravity (0, 0, -9.81).")
      .def(
          "set_gravity",
          [](ModelBuilder& b, py::handle g) -> ModelBuilder& {
            return b.set_gravity(to_vec3(g, "gravity"));
          },
          py::arg("gravity"), ref, "Sets gravity (3,); returns the builder.")
      .def("add_link", &ModelBuilder::add_link, py::arg("link"), ref,
           "Adds a LinkSpec; returns the builder.")
      .def(
          "build", [](const ModelBuilder& b) { return std::make_shared<Model>(b.build()); },
          "Validates everything and returns the Model; ModelError (a ValueError) naming the "
          "link or joint, field and value.");

  // ---- dof positions (model/dof_position.hpp) -------------------------------------------------
  m.def(
      "has_dof_position",
      [](const ModelPtr& model, py::handle dof) {
        return has_dof_position(*model, to_int(dof, "dof", 0, model->nv - 1));
      },
      py::arg("model"), py::arg("dof"),
      "Whether the dof has a position of its own: a 1-dof joint's or a spherical joint's axis "
      "(not a floating root's).");
  m.def(
      "dof_positions",
      [](const ModelPtr& model, py::handle q_obj, py::handle dofs_obj) -> py::array {
        const auto [q, single] = q_rows(*model, q_obj);
        const std::vector<int> dofs = position_dofs(*model, dofs_obj);
        const py::ssize_t rows = single ? 1 : q.shape(0), n = static_cast<py::ssize_t>(dofs.size());
        py::array_t<double> out({rows, n});
        auto o = out.mutable_unchecked<2>();
        for (py::ssize_t t = 0; t < rows; ++t)
          for (py::ssize_t j = 0; j < n; ++j)
            o(t, j) = dof_position(*model, q.data() + t * model->nq, dofs[static_cast<size_t>(j)]);
        if (single) return out.attr("reshape")(n);
        return out;
      },
      py::arg("model"), py::arg("q"), py::arg("dofs") = py::none(),
      "Each dof's position in q (nq,) or rows of q (T, nq): q's entry for a 1-dof joint, PhysX's "
      "position of a spherical joint's axis (the rotation vector of its quaternion), as the "
      "trajectory CSV's q:<dof> columns. dofs: indices (default: every dof with a position, in "
      "model order; a floating root's have none). Returns (len(dofs),) or (T, len(dofs)).");
  m.def(
      "set_dof_positions",
      [](const ModelPtr& model, py::handle q_obj, py::handle dofs_obj, py::handle values_obj) {
        const auto [q, single] = q_rows(*model, q_obj);
        const std::vector<int> dofs = position_dofs(*model, dofs_obj);
        const auto values = as_float_array(values_obj, "values");
        const py::ssize_t rows = single ? 1 : q.shape(0), n = static_cast<py::ssize_t>(dofs.size());
        if (values.size() != rows * n || values.ndim() != q.ndim())
          throw std::invalid_argument("values has shape " + shape_of(values) + ", expected " +
                                      (single ? "(" + std::to_string(n) + ",)"
                                              : "(" + std::to_string(rows) + ", " +
                                                    std::to_string(n) + ")"));
        py::array_t<double> out = py::module_::import("numpy").attr("array")(q);  // a copy
        double* x = out.mutable_data();
        for (py::ssize_t t = 0; t < rows; ++t)
          for (py::ssize_t j = 0; j < n; ++j)
            set_dof_position(*model, x + t * model->nq, dofs[static_cast<size_t>(j)],
                             values.data()[t * n + j]);
        return out;
      },
      py::arg("model"), py::arg("q"), py::arg("dofs"), py::arg("values"),
      "A copy of q (nq,) or (T, nq) with the dofs' positions set, the inverse of dof_positions: "
      "a spherical joint's quaternion becomes exp(theta), theta its three axis positions with "
      "the given ones replaced. dofs as in dof_positions; values (len(dofs),) or (T, len(dofs)).");
}
