// The MuJoCo bridge (docs/mujoco_bridge.md): gain translation between featherdrive (PhysX) and
// MuJoCo 2.2.2 and the MJCF export.
#include "bindings.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/io/mjcf_export.hpp"
#include "featherdrive/io/mujoco_scene.hpp"
#include "featherdrive/sim/gain_translation.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

void featherdrive::python::bind_mujoco_bridge(py::module_& m) {
  py::enum_<MujocoIntegrator>(m, "MujocoIntegrator", "MuJoCo 2.2.2's integrator.")
      .value("euler", MujocoIntegrator::euler)
      .value("implicit", MujocoIntegrator::implicit);
  py::enum_<DriveMapping>(m, "DriveMapping", "How export_mjcf maps drives.")
      .value("translated", DriveMapping::translated)
      .value("literal", DriveMapping::literal);
  auto integrator = [](py::handle obj) {
    return to_enum<MujocoIntegrator>(
        obj, "integrator",
        {{"euler", MujocoIntegrator::euler}, {"implicit", MujocoIntegrator::implicit}},
        "'euler' or 'implicit'");
  };
  py::class_<DriveStepMap>(m, "DriveStepMap",
                           "One step of a joint: [q1, qd1] = A [q0, qd0] + B [x_T, v_T, f].")
      .def_readonly("A", &DriveStepMap::A)
      .def_readonly("B", &DriveStepMap::B);
  py::class_<MujocoDrive>(m, "MujocoDrive", "A MuJoCo setting for one joint (eq. B5-B7).")
      .def(py::init<>())
      .def_readwrite("kp", &MujocoDrive::kp)
      .def_readwrite("kv", &MujocoDrive::kv)
      .def_readwrite("damping", &MujocoDrive::damping)
      .def_readwrite("armature", &MujocoDrive::armature)
      .def_readwrite("ctrl_velocity_gain", &MujocoDrive::ctrl_velocity_gain)
      .def_readwrite("substeps", &MujocoDrive::substeps)
      .def_readwrite("interpolate_target", &MujocoDrive::interpolate_target)
      .def_readwrite("integrator", &MujocoDrive::integrator)
      .def("__repr__", [](const MujocoDrive& d) {
        return "MujocoDrive(kp=" + format_double(d.kp) + ", kv=" + format_double(d.kv) +
               ", damping=" + format_double(d.damping) + ", armature=" + format_double(d.armature) +
               ", substeps=" + std::to_string(d.substeps) + ")";
      });
  py::class_<MapDistance>(m, "MapDistance", "Step-response and pole distance of two steps.")
      .def_readonly("step_response", &MapDistance::step_response)
      .def_readonly("poles", &MapDistance::poles)
      .def_readonly("steps", &MapDistance::steps);
  py::class_<MujocoTranslation>(m, "MujocoTranslation", "translate_to_mujoco's result.")
      .def_readonly("mujoco", &MujocoTranslation::mujoco)
      .def_readonly("exact", &MujocoTranslation::exact)
      .def_readonly("reproducible", &MujocoTranslation::reproducible)
      .def_readonly("distance", &MujocoTranslation::distance)
      .def_readonly("note", &MujocoTranslation::note);
  py::class_<PhysxTranslation>(m, "PhysxTranslation", "translate_to_physx's result.")
      .def_readonly("drive", &PhysxTranslation::drive)
      .def_readonly("exact", &PhysxTranslation::exact)
      .def_readonly("reproducible", &PhysxTranslation::reproducible)
      .def_readonly("distance", &PhysxTranslation::distance)
      .def_readonly("note", &PhysxTranslation::note);
  m.def("physx_step_map", &physx_step_map, py::arg("m"), py::arg("drive"), py::arg("options"),
        "featherdrive's step of a lone drive on a dof of effective inertia m (eq. B1-B4).");
  m.def("mujoco_step_map", &mujoco_step_map, py::arg("m"), py::arg("drive"), py::arg("dt"),
        "MuJoCo's step of the joint over dt (eq. B5-B6).");
  m.def(
      "translate_to_mujoco",
      [integrator](double mass, const Drive& drive, const SimulationOptions& options,
                   py::handle mujoco_integrator, bool keep_timestep) {
        TranslationOptions t;
        t.integrator = integrator(mujoco_integrator);
        t.keep_timestep = keep_timestep;
        return translate_to_mujoco(mass, drive, options, t);
      },
      py::arg("m"), py::arg("drive"), py::arg("options"), py::arg("integrator") = "euler",
      py::arg("keep_timestep") = false,
      "The MuJoCo setting whose step matches the drive's (eq. B7-B10); ValueError for m <= 0 "
      "or a drive of type none.");
  m.def("translate_to_physx", &translate_to_physx, py::arg("m"), py::arg("mujoco"),
        py::arg("options"),
        "featherdrive's force drive closest to a MuJoCo setting (eq. B11-B12).");
  m.def(
      "effective_inertia",
      [](const Model& model, py::handle q) {
        return effective_inertia(model, to_vector(q, model.nq, "q"));
      },
      py::arg("model"), py::arg("q"), "1 / diag(M(q)^-1): the inertia each dof's drive sees.");
  m.def("model_to_mjcf", &model_to_mjcf, py::arg("model"), py::arg("dt"),
        "The model alone as MJCF text (Euler, contacts off).");
  m.def(
      "export_mjcf",
      [integrator](const Simulation& sim, py::handle drives, py::handle mujoco_integrator,
                   bool keep_timestep) {
        MjcfExportOptions o;
        o.drives = to_enum<DriveMapping>(
            drives, "drives",
            {{"translated", DriveMapping::translated}, {"literal", DriveMapping::literal}},
            "'translated' or 'literal'");
        o.integrator = integrator(mujoco_integrator);
        o.keep_timestep = keep_timestep;
        const MjcfExport e = locked(sim, [&] { return export_mjcf(sim, o); });
        py::dict out;
        out["xml"] = e.xml;
        out["timestep"] = e.timestep;
        out["substeps"] = e.substeps;
        out["notes"] = e.notes;
        py::list per_drive;
        for (const MjcfDrive& d : e.drives) {
          py::dict row;
          row["joint"] = d.joint;
          row["effective_inertia"] = d.effective_inertia;
          row["mujoco"] = d.mujoco;
          row["translation"] = d.translation;
          per_drive.append(row);
        }
        out["drives"] = per_drive;
        return out;
      },
      py::arg("sim"), py::arg("drives") = "translated", py::arg("integrator") = "euler",
      py::arg("keep_timestep") = false,
      "The simulation as MJCF with its drives translated (or literal): a dict with xml, "
      "timestep, substeps, notes and per drive its joint, effective_inertia, mujoco and "
      "translation. ValueError for what MuJoCo cannot take (explicit actuators).");
  m.def(
      "translate_mjcf_to_scene",
      [](const std::filesystem::path& mjcf, const std::filesystem::path& scene_path,
         const SimulationOptions& options, py::handle steps) {
        const SceneTranslation t =
            translate_mjcf_to_scene(mjcf, scene_path, options, to_int(steps, "steps", 0, kIntMax));
        py::dict out;
        out["yaml"] = t.yaml;
        out["dt"] = t.dt;
        out["integrator"] = t.integrator;
        out["notes"] = t.notes;
        py::list joints;
        for (const TranslatedJoint& j : t.joints) {
          py::dict row;
          row["joint"] = j.joint;
          row["effective_inertia"] = j.effective_inertia;
          row["mujoco"] = j.mujoco;
          row["physx"] = j.physx;
          joints.append(row);
        }
        out["joints"] = joints;
        return out;
      },
      py::arg("mjcf"), py::arg("scene_path"), py::arg("options") = SimulationOptions{},
      py::arg("steps") = 240,
      "An MJCF's position and velocity actuators and joint damping as featherdrive force "
      "drives (eq. B11-B12): a dict with the scene file's text (yaml; its model is the MJCF's "
      "path relative to scene_path's folder), dt, integrator, notes and per joint its "
      "effective_inertia, mujoco and physx translation. Nothing is written. InputError (a "
      "ValueError) for an MJCF MuJoCo refuses or without actuators to translate.");
}
