// Collision geometry and the ground (issue 34): ShapeType, Material, CollisionShape (read-only in
// Model.shapes), Ground, ContactOptions, ContactReport; Simulation.set_ground / ground /
// set_contact_options / contact_options / contacts / link_contact_force; UrdfRobot.ground.
#include "bindings.hpp"
#include "featherdrive/io/trajectory.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

namespace {

std::string material_repr(const Material& m) {
  return "Material(static_friction=" + fmt(m.static_friction) +
         ", dynamic_friction=" + fmt(m.dynamic_friction) + ", restitution=" + fmt(m.restitution) +
         ")";
}

}  // namespace

void featherdrive::python::bind_contact(py::module_& m) {
  py::enum_<ShapeType>(m, "ShapeType", "The kind of a collision shape.")
      .value("sphere", ShapeType::sphere, "size = (radius, 0, 0)")
      .value("capsule", ShapeType::capsule,
             "size = (radius, half length, 0); the segment along the shape's z")
      .value("box", ShapeType::box, "size = half extents along the shape's x, y, z")
      .value("ellipsoid", ShapeType::ellipsoid, "size = the semi-axes along the shape's x, y, z")
      .value("cylinder", ShapeType::cylinder,
             "size = (radius, half length, 0); the axis along the shape's z")
      .value("convex", ShapeType::convex,
             "a convex hull (of a mesh): CollisionShape.vertices in the shape frame; size unused");

  py::class_<Material>(m, "Material",
                       "Friction and restitution of a surface; a contact uses the average of its "
                       "two surfaces' values.")
      .def(py::init([](double s, double d, double r) { return Material{s, d, r}; }),
           py::arg("static_friction") = 0.5, py::arg("dynamic_friction") = 0.5,
           py::arg("restitution") = 0.0, "A material; checked where it is used.")
      .def_readwrite("static_friction", &Material::static_friction, ">= 0")
      .def_readwrite("dynamic_friction", &Material::dynamic_friction, ">= 0")
      .def_readwrite("restitution", &Material::restitution, "in [0, 1]")
      .def("__repr__", &material_repr);

  py::class_<CollisionShape>(m, "CollisionShape",
                             "A collision shape of a Model (read-only: Model.shapes; scenes add "
                             "them with the `shapes` key).")
      .def_readonly("name", &CollisionShape::name, "the file's name for it, or ''")
      .def_readonly("link", &CollisionShape::link, "index of the link that carries it")
      .def_readonly("type", &CollisionShape::type, "ShapeType")
      .def_readonly("size", &CollisionShape::size, "(3,): see ShapeType")
      .def_readonly("position", &CollisionShape::position, "origin in the link frame (3,)")
      .def_readonly("rotation", &CollisionShape::rotation, "axes in the link frame (3, 3)")
      .def_readonly("material", &CollisionShape::material, "Material")
      .def_property_readonly(
          "vertices",
          [](const CollisionShape& s) {
            py::array_t<double> out({static_cast<py::ssize_t>(s.vertices.size()), py::ssize_t{3}});
            auto w = out.mutable_unchecked<2>();
            for (size_t i = 0; i < s.vertices.size(); ++i)
              for (int k = 0; k < 3; ++k) w(static_cast<py::ssize_t>(i), k) = s.vertices[i][k];
            return out;
          },
          "convex: the hull's vertices in the shape frame, a new array (n, 3); else (0, 3)")
      .def("__repr__", [](const CollisionShape& s) {
        return std::string("CollisionShape('") + s.name + "', " + to_string(s.type) +
               ", link=" + std::to_string(s.link) + ")";
      });

  py::class_<Ground>(m, "Ground",
                     "The ground: the plane normal . x = height with a material; off unless "
                     "enabled.")
      .def(py::init([](bool enabled, double height, py::handle normal, const Material& material) {
             Ground g;
             g.enabled = enabled;
             g.height = height;
             g.normal = to_vec3(normal, "normal");
             g.material = material;
             return g;
           }),
           py::arg("enabled") = true, py::arg("height") = 0.0,
           py::arg("normal") = Vec3(0.0, 0.0, 1.0), py::arg("material") = Material{},
           "A ground (enabled by default); checked by Simulation.set_ground.")
      .def_readwrite("enabled", &Ground::enabled, "contacts with it when True")
      .def_readwrite("height", &Ground::height, "m")
      .def_property(
          "normal", [](const Ground& g) { return g.normal; },
          [](Ground& g, py::handle v) { g.normal = to_vec3(v, "normal"); },
          "(3,), normalised by set_ground")
      .def_readwrite("material", &Ground::material, "Material")
      .def("__repr__", [](const Ground& g) {
        return std::string("Ground(enabled=") + (g.enabled ? "True" : "False") +
               ", height=" + fmt(g.height) + ", normal=[" + fmt(g.normal.x()) + ", " +
               fmt(g.normal.y()) + ", " + fmt(g.normal.z()) + "], material=" +
               material_repr(g.material) + ")";
      });

  py::class_<ContactOptions>(m, "ContactOptions",
                             "PhysX 5.6.1's contact parameters, the same for every shape and the "
                             "ground (docs/math/contact.md, section 8).")
      .def(py::init([](double c, double r, double b, bool self) {
             return ContactOptions{c, r, b, self};
           }),
           py::arg("contact_offset") = 0.02, py::arg("rest_offset") = 0.0,
           py::arg("bounce_threshold") = 2.0, py::arg("self_collision") = false,
           "Contact options; checked by Simulation.set_contact_options.")
      .def_readwrite("contact_offset", &ContactOptions::contact_offset, "m, > rest_offset")
      .def_readwrite("rest_offset", &ContactOptions::rest_offset, "m, >= 0")
      .def_readwrite("bounce_threshold", &ContactOptions::bounce_threshold,
                     "m/s: slower impacts do not bounce")
      .def_readwrite("self_collision", &ContactOptions::self_collision,
                     "contacts between the robot's own shapes (links not parent and child)")
      .def("__repr__", [](const ContactOptions& c) {
        return "ContactOptions(contact_offset=" + fmt(c.contact_offset) +
               ", rest_offset=" + fmt(c.rest_offset) +
               ", bounce_threshold=" + fmt(c.bounce_threshold) +
               ", self_collision=" + (c.self_collision ? "True" : "False") + ")";
      });

  py::class_<ContactReport>(m, "ContactReport", "One contact point of the last step (read-only).")
      .def_readonly("link", &ContactReport::link, "index of the link")
      .def_readonly("shape", &ContactReport::shape, "index into Model.shapes")
      .def_readonly("other_link", &ContactReport::other_link,
                    "-1: the ground; else the link of the other shape (self-collision)")
      .def_readonly("other_shape", &ContactReport::other_shape,
                    "-1: the ground; else the other shape's index into Model.shapes")
      .def_readonly("position", &ContactReport::position,
                    "world frame, at the step's start (3,)")
      .def_readonly("normal", &ContactReport::normal,
                    "into the link: the ground's normal, or from the other shape (3,)")
      .def_readonly("separation", &ContactReport::separation,
                    "m at the step's start; < 0 penetrating")
      .def_readonly("normal_impulse", &ContactReport::normal_impulse, "N s along the normal")
      .def_readonly("friction_impulse", &ContactReport::friction_impulse,
                    "N s, world frame, tangential (3,)")
      .def("__repr__", [](const ContactReport& c) {
        return "ContactReport(link=" + std::to_string(c.link) +
               ", shape=" + std::to_string(c.shape) + ", separation=" + fmt(c.separation) +
               ", normal_impulse=" + fmt(c.normal_impulse) + ")";
      });

  auto model = py::reinterpret_borrow<py::class_<Model, ModelPtr>>(m.attr("Model"));
  model.def_readonly("shapes", &Model::shapes,
                     "the collision shapes, grouped by link in link order (list of "
                     "CollisionShape)")
      .def_readonly("unsupported_shapes", &Model::unsupported_shapes,
                    "collision geometry the file has that contacts cannot use yet (descriptions); "
                    "a ground is refused while there is any");

  auto sim = py::reinterpret_borrow<py::class_<Simulation, SimulationHolder>>(m.attr("Simulation"));
  sim.def(
         "set_ground",
         [](Simulation& s, const Ground& g) { locked(s, [&] { s.set_ground(g); }); },
         py::arg("ground"),
         "Sets the ground (normal normalised). ValueError naming the field and value, or the "
         "first shape contacts do not support (Model.unsupported_shapes) when enabled.")
      .def(
          "ground", [](const Simulation& s) { return locked(s, [&] { return s.ground(); }); },
          "The Ground (a copy).")
      .def(
          "set_contact_options",
          [](Simulation& s, const ContactOptions& o) {
            locked(s, [&] { s.set_contact_options(o); });
          },
          py::arg("options"),
          "Sets the ContactOptions. ValueError unless 0 <= rest_offset < contact_offset and "
          "bounce_threshold is finite and >= 0.")
      .def(
          "contact_options",
          [](const Simulation& s) { return locked(s, [&] { return s.contact_options(); }); },
          "The ContactOptions (a copy).")
      .def(
          "contacts",
          [](const Simulation& s) {
            return locked(s, [&] {
              const auto c = s.contacts();
              return std::vector<ContactReport>(c.begin(), c.end());
            });
          },
          "The contact points of the last step (list of ContactReport; empty without a ground).")
      .def(
          "link_contact_force",
          [](const Simulation& s) {
            return locked(s, [&] {
              const std::vector<Vec3>& f = s.link_contact_force();
              py::array_t<double> out({static_cast<py::ssize_t>(f.size()), py::ssize_t{3}});
              auto w = out.mutable_unchecked<2>();
              for (size_t i = 0; i < f.size(); ++i)
                for (int k = 0; k < 3; ++k)
                  w(static_cast<py::ssize_t>(i), k) = f[i][k];
              return out;
            });
          },
          "The ground's force on each link over the last step, world axes, N: a new array "
          "(num_links, 3).")
      .def(
          "foot_contact_force",
          [](const Simulation& s, py::handle links) {
            Foot foot;
            const bool one = py::isinstance<py::str>(links) || py::isinstance<py::int_>(links);
            const auto arg = py::reinterpret_borrow<py::object>(links);
            for (py::handle link : one ? py::list(py::make_tuple(arg)) : py::list(arg)) {
              const int l = frame_of(s.model(), link_arg(link)).link;
              if (std::find(foot.links.begin(), foot.links.end(), l) == foot.links.end())
                foot.links.push_back(l);
            }
            return locked(s, [&] { return foot_contact_force(s, foot); });
          },
          py::arg("links"),
          "The sum of link_contact_force over links (a foot's: names, merged links' names or "
          "indices, each counted once; one link alone is fine), world axes, N (3,).");

  auto robot = py::reinterpret_borrow<py::class_<UrdfRobot>>(m.attr("UrdfRobot"));
  robot.def_readonly("ground", &UrdfRobot::ground,
                     "the file's own floor (an MJCF plane on the world body) as a Ground, or "
                     "None; a scene of the file takes it unless it says `ground:`")
      .def_readonly("unsupported_shapes", &UrdfRobot::unsupported_shapes,
                    "collision geometry contacts cannot use yet (as Model.unsupported_shapes)");
  auto scene = py::reinterpret_borrow<py::class_<Scene>>(m.attr("Scene"));
  scene.def_readonly("ground", &Scene::ground, "the scene's Ground (key ground, or the file's)")
      .def_readonly("contact", &Scene::contact, "the scene's ContactOptions (key contact)")
      .def_property_readonly(
          "feet",
          [](const Scene& sc) {
            py::dict feet;  // in file order (dicts keep insertion order)
            for (const Foot& f : sc.feet) feet[py::str(f.name)] = f.link_names;
            return feet;
          },
          "the scene's feet (key feet): {name: [link names]}");
}
