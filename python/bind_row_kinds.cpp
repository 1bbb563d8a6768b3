// The row kinds (constraint/row_kinds.hpp) on the Python faces, by name, so that a kind added in
// C++ needs no binding of its own: fd.row_kinds(), Simulation.set_row_parameters, row_parameters,
// row_force, Batch.set_row_parameter, row_parameter, row_force, Settings.row_parameters.
#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

namespace {

py::list row_kind_list() {
  py::list kinds;
  for (const RowKindInfo& k : row_kinds()) {
    py::list fields;
    for (const RowField& f : k.fields)
      fields.append(py::dict(py::arg("name") = std::string(f.name),
                             py::arg("default") = f.default_value,
                             py::arg("doc") = std::string(f.doc)));
    kinds.append(py::dict(py::arg("name") = std::string(k.name),
                          py::arg("force") = std::string(k.force), py::arg("fields") = fields));
  }
  return kinds;
}

}  // namespace

void featherdrive::python::bind_row_kinds(py::module_& m) {
  m.def("row_kinds", &row_kind_list,
        "The row kinds the step solves besides drives, limits and friction (e.g. 'joint_spring'), "
        "each a dict: name, force (its output's name), fields (name, default, doc).");

  auto sim = py::reinterpret_borrow<py::class_<Simulation, SimulationHolder>>(m.attr("Simulation"));
  sim.def(
         "set_row_parameters",
         [](Simulation& s, const std::string& kind, py::handle joint, const py::kwargs& fields) {
           on_joint(s, joint, [&](int dof) {
             const RowKindInfo& k = row_kind(kind);
             std::vector<double> values = s.row_parameters(kind, dof);
             for (const auto& [name, value] : fields) {
               const std::string field = py::str(name).cast<std::string>();
               const int column = row_field_column(k, field);
               values[static_cast<size_t>(column - k.offset)] =
                   row_field_value(value, kind + "." + field);
             }
             s.set_row_parameters(kind, dof, values);
           });
         },
         py::arg("kind"), py::arg("joint"),
         "A row kind's fields on a joint (name or dof), by keyword, e.g. "
         "set_row_parameters('joint_spring', 'knee', stiffness=240.0, reference=0.1); the fields "
         "not given keep their values. ValueError naming the joint, field and value.")
      .def(
          "row_parameters",
          [](const Simulation& s, const std::string& kind, py::handle joint) {
            return on_joint(s, joint, [&](int dof) {
              const RowKindInfo& k = row_kind(kind);
              const std::vector<double> values = s.row_parameters(kind, dof);
              py::dict out;
              for (size_t j = 0; j < values.size(); ++j)
                out[py::str(std::string(k.fields[j].name))] = values[j];
              return out;
            });
          },
          py::arg("kind"), py::arg("joint"), "A row kind's fields on a joint, as a dict.")
      .def(
          "row_force",
          [](const Simulation& s, const std::string& kind) {
            return locked(s, [&] { return VecX(s.row_force(kind)); });
          },
          py::arg("kind"), "The force a row kind applied on each dof in the last step (nv,), a copy.");

  auto batch = py::reinterpret_borrow<py::class_<Batch, BatchHolder>>(m.attr("Batch"));
  batch
      .def(
          "set_row_parameter",
          [](Batch& b, const std::string& kind, const std::string& field, py::handle values,
             py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nv, kind + "." + field);
            locked(b, [&] { b.set_row_parameter(kind, field, ids, v); });
          },
          py::arg("kind"), py::arg("field"), py::arg("values"), py::arg("env_ids") = py::none(),
          "One field of a row kind on env_ids (None: all): a scalar, (nv,) or (k, nv), e.g. "
          "set_row_parameter('joint_spring', 'stiffness', k).")
      .def(
          "row_parameter",
          [](const Batch& b, const std::string& kind, const std::string& field) {
            return locked(b, [&] { return b.row_parameter(kind, field); });
          },
          py::arg("kind"), py::arg("field"), "(N, nv), a copy.")
      .def(
          "row_force",
          [](const Batch& b, const std::string& kind) {
            return locked(b, [&] { return b.row_force(kind); });
          },
          py::arg("kind"), "A row kind's forces of the last step (N, nv), a copy.");

  auto settings = py::reinterpret_borrow<py::class_<Settings>>(m.attr("Settings"));
  settings.def_property(
      "row_parameters",
      py::cpp_function([](Settings& s) -> MatX& { return s.row_parameters; },
                       py::return_value_policy::reference_internal),
      [](Settings& s, const MatX& v) { s.row_parameters = v; },
      "(nv, fields of every row kind), kind after kind (fd.row_kinds()); writes into the value");
}
