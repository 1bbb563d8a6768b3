// Python: a scene's fit: section (Scene.fit, read-only) and fd.fit, which forwards to the
// pure-Python featherdrive_fit module beside this one (docs/fitting.md).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "featherdrive/io/fit_spec.hpp"
#include "featherdrive/io/scene.hpp"

namespace py = pybind11;
using namespace featherdrive;

void bind_fit(py::module_& m) {
  py::class_<FitParameter>(m, "FitParameter", "One entry of a scene's fit.parameters.")
      .def_property_readonly(
          "quantity", [](const FitParameter& p) { return std::string(to_string(p.quantity)); },
          "stiffness, damping, max_force, armature, friction.static, friction.dynamic, "
          "friction.viscous, friction_coefficient, delay or mass_scale")
      .def_readonly("names", &FitParameter::names, "joints (links for mass_scale)")
      .def_readonly("indices", &FitParameter::indices, "their dofs (model link indices)")
      .def_readonly("lower", &FitParameter::lower, "lower bound")
      .def_readonly("upper", &FitParameter::upper, "upper bound")
      .def_readonly("shared", &FitParameter::shared, "one value for all names")
      .def_readonly("initial", &FitParameter::initial,
                    "starting values, one per unknown (1 if shared)")
      .def_readonly("key", &FitParameter::key, "fit.parameters[i], for messages");

  py::class_<FitData>(m, "FitData", "A scene's fit.data: how the log is read.")
      .def_property_readonly(
          "resample",
          [](const FitData& d) {
            return d.resample == FitData::Resample::linear ? "linear" : "exact";
          },
          "exact (the log's steps are dt) or linear (interpolated onto dt)")
      .def_readonly("segment_steps", &FitData::segment_steps,
                    "steps per multiple-shooting segment (0: one segment)")
      .def_readonly("qd_weight", &FitData::qd_weight, "weight of the qd residual (0: q only)");

  py::class_<FitSpec>(m, "FitSpec", "A scene's fit: section.")
      .def_readonly("parameters", &FitSpec::parameters, "list of FitParameter")
      .def_readonly("data", &FitSpec::data, "FitData")
      .def("num_unknowns", &FitSpec::num_unknowns, "continuous unknowns (delay excluded)");

  py::reinterpret_borrow<py::class_<Scene>>(m.attr("Scene"))
      .def_readonly("fit", &Scene::fit, "FitSpec, or None without a fit: section");

  m.def(
      "fit",
      [](py::args args, py::kwargs kwargs) {
        return py::module_::import("featherdrive_fit").attr("fit")(*args, **kwargs);
      },
      "fit(scene, data, client=None, threads=None, out=None): featherdrive_fit.fit, the "
      "scene's fit: parameters fitted to the log `data` (docs/fitting.md).");
}
