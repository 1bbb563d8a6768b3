#include "mesh_hull.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "collada_mesh.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/io/files.hpp"
#include "mujoco_calls.hpp"

namespace featherdrive::mesh_hull {
namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string e = path.extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

Mat3 rotation_of(const mjtNum* q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

// Puts `bytes` into the VFS as `name`.
void add_file(mjVFS* vfs, const char* name, const std::string& bytes) {
  if (mj_makeEmptyFileVFS(vfs, name, static_cast<int>(bytes.size())) != 0)
    throw std::runtime_error("MuJoCo's virtual file system refused it");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs, name)], bytes.data(), bytes.size());
}

}  // namespace

bool readable_extension(const std::filesystem::path& path) {
  const std::string e = lower_extension(path);
  return e == ".stl" || e == ".obj" || e == ".msh" || e == ".dae";
}

std::vector<Vec3> vertices(const mjModel* m, int id) {
  const float* vert = m->mesh_vert + 3 * m->mesh_vertadr[id];
  std::vector<Vec3> out;
  auto push = [&](int v) { out.emplace_back(vert[3 * v], vert[3 * v + 1], vert[3 * v + 2]); };
  if (m->mesh_graphadr[id] < 0) {
    for (int v = 0; v < m->mesh_vertnum[id]; ++v) push(v);
    return out;
  }
  // mesh_graph: numvert, numface, vert_edgeadr[numvert], vert_globalid[numvert], ... (mjmodel.h)
  const int* graph = m->mesh_graph + m->mesh_graphadr[id];
  const int count = graph[0];
  for (int v = 0; v < count; ++v) push(graph[2 + count + v]);
  return out;
}

void sort_vertices(std::vector<Vec3>& v) {
  // By x, then y, then z, each descending: a box's hull lists its corners in the box path's
  // order (PhysX's, z fastest, + first: docs/math/contact.md, C1a), so the narrow phase meets
  // them, and the solver their rows, in the same order.
  std::sort(v.begin(), v.end(), [](const Vec3& a, const Vec3& b) {
    return std::tie(b.x(), b.y(), b.z()) < std::tie(a.x(), a.y(), a.z());
  });
}

namespace {

std::string read_mesh_file(const std::filesystem::path& path) {
  std::error_code code;
  if (!std::filesystem::is_regular_file(path, code))
    throw std::runtime_error(path.string() + " not found");
  const std::uintmax_t size = std::filesystem::file_size(path, code);
  if (code) throw std::runtime_error(path.string() + " cannot be read");
  if (size > kMaxInputBytes)
    throw std::runtime_error(path.string() + " is larger than " +
                             std::to_string(kMaxInputBytes >> 20) + " MiB");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + " cannot be opened");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw std::runtime_error(path.string() + " cannot be read");
  if (bytes.empty()) throw std::runtime_error(path.string() + " is empty");
  return bytes;
}

// Compiles the MJCF texts `steps` in turn (each must load), the mesh file's `bytes` in the VFS as
// `vfs_name` (none where it is empty); the last model, or std::runtime_error "MuJoCo cannot use
// it: <first clause>" with `vfs_name` shown as `shown`.
mujoco_calls::ModelPtr compile_steps(const std::vector<std::string>& steps,
                                     const std::string& vfs_name, const std::string& bytes,
                                     const std::string& shown) {
  mujoco_calls::route_warnings();
  const auto vfs = std::make_unique<mjVFS>();  // ~2 MB: not on the stack
  mj_defaultVFS(vfs.get());
  std::string error;
  std::vector<std::string> warnings;
  mujoco_calls::ModelPtr m;
  try {
    for (size_t k = 0; k < steps.size(); ++k)
      add_file(vfs.get(), ("step" + std::to_string(k) + ".xml").c_str(), steps[k]);
    if (!vfs_name.empty()) add_file(vfs.get(), vfs_name.c_str(), bytes);
    for (size_t k = 0; k < steps.size() && (k == 0 || m); ++k)
      m = mujoco_calls::load_xml(("step" + std::to_string(k) + ".xml").c_str(), vfs.get(), error,
                                 warnings);
  } catch (...) {
    mj_deleteVFS(vfs.get());
    throw;
  }
  mj_deleteVFS(vfs.get());
  if (!m) {
    // "Error: ...; Object name = m, id = 0, ...": the first clause names the problem.
    if (error.rfind("Error: ", 0) == 0) error = error.substr(7);
    error = error.substr(0, error.find(';'));
    if (error.size() > 3 && error.compare(error.size() - 3, 3, ": m") == 0)
      error.resize(error.size() - 3);  // the mesh's name in our XML
    for (size_t at; !vfs_name.empty() && (at = error.find(vfs_name)) != std::string::npos;)
      error.replace(at, vfs_name.size(), shown);
    throw std::runtime_error("MuJoCo cannot use it: " + error);
  }
  return m;
}

constexpr double kMaxVertexCoordinate = 1e6;  // m: far beyond any robot, well inside float32

// Throws where the points span no volume: qhull (inside MuJoCo's compiler) would print its
// report on stderr before MuJoCo refuses them, and MuJoCo holds the points as float32, so
// anything thinner than a few float roundings of the points' size is flat to it.
void check_volume(const std::vector<Vec3>& points) {
  if (points.size() < 4)
    throw std::runtime_error(std::to_string(points.size()) +
                             " vertices: a hull needs 4 that span a volume");
  double size = 0.0;
  for (const Vec3& p : points) {
    // MuJoCo holds vertices in float32 and computes the hull's volume and inertia from them.
    if (!(p.cwiseAbs().maxCoeff() <= kMaxVertexCoordinate))
      throw std::runtime_error("a vertex " + format_vec3(p) + " is not finite or beyond " +
                               format_double(kMaxVertexCoordinate) + " m");
    size = std::max(size, p.cwiseAbs().maxCoeff());
  }
  // The largest tetrahedron of four extreme points: the farthest from the first point, the
  // farthest from their line, the farthest from their plane.
  const Vec3& a = points[0];
  auto farthest = [&](auto&& distance) {
    const Vec3* best = &a;
    double d = -1.0;
    for (const Vec3& p : points)
      if (const double e = distance(p); e > d) d = e, best = &p;
    return std::pair{*best, d};
  };
  const auto [b, ab] = farthest([&](const Vec3& p) { return (p - a).norm(); });
  const Vec3 u = (b - a).normalized();
  const auto [c, line] = farthest([&](const Vec3& p) { return (p - a).cross(u).norm(); });
  const Vec3 n = u.cross(c - a).normalized();
  const double plane = farthest([&](const Vec3& p) { return std::abs(n.dot(p - a)); }).second;
  const double tolerance = 1e-6 * size;
  if (!(ab > tolerance && line > tolerance && plane > tolerance))
    throw std::runtime_error("its vertices span no volume (all within " + format_double(tolerance) +
                             " m of a plane)");
}

}  // namespace

std::vector<Vec3> hull_of_points(const std::vector<Vec3>& points) {
  check_volume(points);
  // An inline vertex mesh: MuJoCo takes its hull and keeps the vertices in the given order, so the
  // hull's vertex ids index `points` and the hull is the given doubles, not MuJoCo's floats.
  std::ostringstream xml;
  xml.precision(17);
  xml << "<mujoco><asset><mesh name='m' vertex='";
  for (const Vec3& p : points) xml << p.x() << ' ' << p.y() << ' ' << p.z() << ' ';
  xml << "'/></asset><worldbody><geom type='mesh' mesh='m'/></worldbody></mujoco>";
  const mujoco_calls::ModelPtr m = compile_steps({xml.str()}, "", "", "");
  if (m->mesh_vertnum[0] != static_cast<int>(points.size()) || m->mesh_graphadr[0] < 0)
    throw std::runtime_error("MuJoCo did not keep the vertices as given");
  const int* graph = m->mesh_graph + m->mesh_graphadr[0];
  std::vector<Vec3> out;
  for (int v = 0; v < graph[0]; ++v)
    out.push_back(points[static_cast<size_t>(graph[2 + graph[0] + v])]);
  sort_vertices(out);
  return out;
}

std::vector<Vec3> load(const std::filesystem::path& path, const Vec3& scale) {
  const std::string bytes = read_mesh_file(path);
  if (lower_extension(path) == ".dae") {
    std::vector<Vec3> points = collada::vertices(bytes);
    for (Vec3& p : points) p = p.cwiseProduct(scale);
    return hull_of_points(points);
  }
  // The mesh by a fixed name, so that its path needs no escaping in the XML.
  const std::string mesh_name = "featherdrive_mesh" + lower_extension(path);
  std::ostringstream asset;
  asset.precision(17);
  asset << "<asset><mesh name='m' file='" << mesh_name << "' scale='" << scale.x() << ' '
        << scale.y() << ' ' << scale.z() << "'/></asset>";
  // First without the hull, as a moving body's geom: MuJoCo refuses a mesh of zero volume there
  // before its hull library (qhull) would fail on it, printing to stderr. Then the hull, as a
  // geom of the world body: its pose is the offset MuJoCo gave the mesh.
  const std::string check = "<mujoco><compiler convexhull='false'/>" + asset.str() +
                            "<worldbody><body><freejoint/><geom type='mesh' mesh='m'/></body>"
                            "</worldbody></mujoco>";
  const std::string hull =
      "<mujoco>" + asset.str() + "<worldbody><geom type='mesh' mesh='m'/></worldbody></mujoco>";
  const mujoco_calls::ModelPtr m =
      compile_steps({check, hull}, mesh_name, bytes, path.filename().string());
  const Vec3 p(m->geom_pos[0], m->geom_pos[1], m->geom_pos[2]);
  const Mat3 R = rotation_of(m->geom_quat);
  std::vector<Vec3> out = vertices(m.get(), m->geom_dataid[0]);
  for (Vec3& v : out) v = p + R * v;
  sort_vertices(out);
  return out;
}

}  // namespace featherdrive::mesh_hull
