// Python: a scene's fit: section (Scene.fit, read-only), fd.fit, which forwards to the
// pure-Python featherdrive_fit module beside this one (docs/fitting.md), fd.run_physx and
// fd.run_mujoco.
#include <cmath>

#include "bindings.hpp"
#include "featherdrive/io/fit_spec.hpp"
#include "featherdrive/io/mjcf_export.hpp"
#include "featherdrive/io/physx_runner.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

void featherdrive::python::bind_fit(py::module_& m) {
  py::class_<FitParameter>(m, "FitParameter", "One entry of a scene's fit.parameters.")
      .def_property_readonly(
          "quantity", [](const FitParameter& p) { return p.spelling(); },
          "stiffness, damping, max_force, armature, friction.static, friction.dynamic, "
          "friction.viscous, friction_coefficient, delay, mass_scale or a row kind's field "
          "(joint_spring.stiffness, ...)")
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

  // PhysX itself on a simulation, for logs that another engine made (tests, docs/fitting.md).
  m.def(
      "run_physx",
      [](const Simulation& sim, int steps, const RowMatrix& target_position,
         const std::vector<std::filesystem::path>& harness_dirs) {
        const Model& model = sim.model();
        if (target_position.rows() != steps || target_position.cols() != model.nv)
          throw std::invalid_argument(
              "run_physx: target_position is (" + std::to_string(target_position.rows()) + ", " +
              std::to_string(target_position.cols()) + "), expected (" + std::to_string(steps) +
              ", " + std::to_string(model.nv) + ")");
        // Under sim's lock: nothing else may change it while the harness reads it.
        const JointTrajectory px = locked(sim, [&] {
          std::vector<TargetsByJoint> targets(static_cast<size_t>(steps));
          for (int k = 0; k < steps; ++k)
            for (int d = 0; d < model.nv; ++d)
              if (sim.drive(d).type != DriveType::none)
                targets[static_cast<size_t>(k)][model.dof_names[d]] = {target_position(k, d), 0.0};
          return run_physx(find_physx(harness_dirs), sim, steps, targets);
        });
        RowMatrix q(static_cast<Eigen::Index>(px.rows()), model.nv), qd = q;
        for (size_t j = 0; j < px.joints.size(); ++j) {
          const int d = model.dof_index(px.joints[j]);
          for (size_t k = 0; k < px.rows(); ++k) {
            q(static_cast<Eigen::Index>(k), d) = px.q[k][j];
            qd(static_cast<Eigen::Index>(k), d) = px.qd[k][j];
          }
        }
        return py::make_tuple(q, qd);
      },
      py::arg("sim"), py::arg("steps"), py::arg("target_position"), py::arg("harness_dirs"),
      "(q, qd), (steps + 1, nv): PhysX 5.6.1 run by the harness of tests/physx (in "
      "$FEATHERDRIVE_PHYSX_DIR or the first of harness_dirs holding it) on sim's robot, state "
      "and settings, target_position[k] (velocity 0) set before step k + 1. RuntimeError when "
      "node or the harness is missing or PhysX refuses the scene.");

  // MuJoCo 2.2.2 on a simulation through the bridge (export_mjcf, MujocoRun), in-process.
  m.def(
      "run_mujoco",
      [](const Simulation& sim, int steps, const RowMatrix& target_position, py::handle drives,
         py::handle integrator) {
        MjcfExportOptions o;
        o.drives = to_enum<DriveMapping>(
            drives, "drives",
            {{"translated", DriveMapping::translated}, {"literal", DriveMapping::literal}},
            "'translated' or 'literal'");
        o.integrator = to_enum<MujocoIntegrator>(
            integrator, "integrator",
            {{"euler", MujocoIntegrator::euler}, {"implicit", MujocoIntegrator::implicit}},
            "'euler' or 'implicit'");
        // A copy holds the targets MujocoRun reads; sim itself is left as it was.
        Simulation copy = locked(sim, [&] { return sim; });
        const int nv = copy.model().nv;
        if (target_position.rows() != steps || target_position.cols() != nv)
          throw std::invalid_argument(
              "run_mujoco: target_position is (" + std::to_string(target_position.rows()) + ", " +
              std::to_string(target_position.cols()) + "), expected (" + std::to_string(steps) +
              ", " + std::to_string(nv) + ")");
        for (Eigen::Index k = 0; k < target_position.rows(); ++k)
          for (int d = 0; d < nv; ++d)
            if (!std::isfinite(target_position(k, d)))
              throw std::invalid_argument(
                  "run_mujoco: target_position[" + std::to_string(k) + ", " + std::to_string(d) +
                  "] = " + std::to_string(target_position(k, d)) + ": must be finite");
        const MjcfExport mjcf = export_mjcf(copy, o);
        RowMatrix q(steps + 1, nv), qd(steps + 1, nv);
        {
          py::gil_scoped_release nogil;
          MujocoRun mj(mjcf);
          mj.set_state(copy.q(), copy.qd());
          q.row(0) = mj.q().transpose();
          qd.row(0) = mj.qd().transpose();
          for (int k = 0; k < steps; ++k) {
            for (int d = 0; d < nv; ++d)
              if (copy.drive(d).type != DriveType::none)
                copy.set_drive_target(d, target_position(k, d), 0.0);
            mj.step(copy);
            // MuJoCo resets a diverging run to its reference state: say so rather than log it.
            if (mj.diverged() || !mj.q().allFinite() || !mj.qd().allFinite())
              throw DivergenceError("run_mujoco: MuJoCo diverged at step " +
                                    std::to_string(k + 1) + " (drives " + to_string(o.drives) +
                                    ", dt " + std::to_string(copy.options().dt) + " s)");
            q.row(k + 1) = mj.q().transpose();
            qd.row(k + 1) = mj.qd().transpose();
          }
        }
        return py::make_tuple(q, qd);
      },
      py::arg("sim"), py::arg("steps"), py::arg("target_position"),
      py::arg("drives") = "translated", py::arg("integrator") = "euler",
      "(q, qd), (steps + 1, nv): MuJoCo 2.2.2 in-process on sim's robot, state and drives "
      "exported by export_mjcf (drives 'translated' or 'literal', integrator 'euler' or "
      "'implicit'), target_position[k] (velocity 0) set before step k + 1; sim is not changed. "
      "ValueError for bad values or what MuJoCo cannot take; DivergenceError (a RuntimeError) "
      "when MuJoCo diverges.");
}
