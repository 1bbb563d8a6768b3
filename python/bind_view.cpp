// fd.view (python/featherdrive_view.py, docs/viewer.md) and what its page needs from C++: the
// world pose of every link over a run, links merged through fixed joints included.
#include <Eigen/Geometry>

#include "bindings.hpp"
#include "featherdrive/sim/state.hpp"

namespace py = pybind11;

namespace featherdrive::python {
namespace {

bool same_links(const Model* a, const Model& b) {
  if (!a || a->num_links() != b.num_links()) return false;
  for (int i = 0; i < b.num_links(); ++i)
    if (a->links[i].name != b.links[i].name) return false;
  return true;
}

// q rows (T, nq) -> the link names and their poses (T, L, 7): position, then the rotation as a
// unit quaternion (w, x, y, z). Model links first, then the robot's merged links (their frame is
// a fixed offset in the link they were merged into).
py::tuple link_world_poses(const ModelPtr& model, py::handle q_rows, py::handle robot_obj) {
  if (!model) throw py::type_error("model must be a Model, not None");
  const auto q = as_float_array(q_rows, "q");
  if (q.ndim() != 2 || q.shape(1) != model->nq)
    throw std::invalid_argument("q has shape " + shape_of(q) + ", expected (T, " +
                                std::to_string(model->nq) + ")");
  std::vector<std::string> names;
  std::vector<int> link_of;        // the model link each name's pose follows
  std::vector<MergedLink> offset;  // into is unused here
  for (int i = 0; i < model->num_links(); ++i) {
    names.push_back(model->links[i].name);
    link_of.push_back(i);
    offset.emplace_back();
  }
  if (!robot_obj.is_none()) {
    if (!py::isinstance<UrdfRobot>(robot_obj))
      throw py::type_error("robot must be a UrdfRobot or None, not " + type_name(robot_obj));
    const auto& robot = robot_obj.cast<const UrdfRobot&>();
    if (!same_links(robot.model.get(), *model))
      throw std::invalid_argument("robot: " + robot.path.string() +
                                  ": its links are not the model's");
    for (const auto& [name, merged] : robot.merged) {
      names.push_back(name);
      link_of.push_back(model->link_index(merged.into));
      offset.push_back(merged);
    }
  }
  const py::ssize_t rows = q.shape(0), count = static_cast<py::ssize_t>(names.size());
  py::array_t<double> poses({rows, count, py::ssize_t{7}});
  auto out = poses.mutable_unchecked<3>();
  Data data(*model);
  for (py::ssize_t t = 0; t < rows; ++t) {
    VecX row(model->nq);
    for (int k = 0; k < model->nq; ++k) row[k] = q.at(t, k);
    try {
      row = checked_configuration(*model, row);  // as Simulation::set_q checks and normalises
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("q row " + std::to_string(t) + ": " + e.what());
    }
    forward_kinematics(*model, data, row);
    for (py::ssize_t l = 0; l < count; ++l) {
      const int i = link_of[static_cast<size_t>(l)];
      const MergedLink& f = offset[static_cast<size_t>(l)];
      const Mat3 R = data.world_rotation[i] * f.rotation;
      const Vec3 p = data.world_position[i] + data.world_rotation[i] * f.xyz;
      const Eigen::Quaterniond r(R);
      const double v[7] = {p.x(), p.y(), p.z(), r.w(), r.x(), r.y(), r.z()};
      for (int k = 0; k < 7; ++k) out(t, l, k) = v[k];
    }
  }
  return py::make_tuple(names, poses);
}

}  // namespace

void bind_view(py::module_& m) {
  auto robot = py::reinterpret_borrow<py::class_<UrdfRobot>>(m.attr("UrdfRobot"));
  robot.def_property_readonly(
      "merged",
      [](const UrdfRobot& r) {
        py::dict out;
        for (const auto& [name, link] : r.merged)
          out[py::str(name)] = py::make_tuple(link.into, Vec3(link.xyz), Mat3(link.rotation));
        return out;
      },
      "{link: (into, xyz, rotation)}: the links merged through fixed joints, each with the link "
      "it went into and its frame's pose there.");
  m.def("link_world_poses", &link_world_poses, py::arg("model"), py::arg("q"),
        py::arg("robot") = py::none(),
        "(names, poses): every link's world pose at each row of q (T, nq), each row checked as "
        "Simulation.set_q checks it; poses (T, L, 7) are the position and the unit quaternion "
        "(w, x, y, z). With robot (a UrdfRobot of this model) the links merged through fixed "
        "joints follow the model's links.");
  m.def(
      "view",
      [](py::args args, py::kwargs kwargs) {
        return py::module_::import("featherdrive_view").attr("view")(*args, **kwargs);
      },
      "view(source, out=None, ...): the 3D viewer page of a scene, a CSV run or a Simulation "
      "(featherdrive_view.view; docs/viewer.md).");
}

}  // namespace featherdrive::python
