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
  return e == ".stl" || e == ".obj" || e == ".msh";
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
  // By z, then y, then x: a box's hull lists its corners in the box path's order (x fastest),
  // so the narrow phase meets them, and the solver their rows, in the same order.
  std::sort(v.begin(), v.end(), [](const Vec3& a, const Vec3& b) {
    return std::tie(a.z(), a.y(), a.x()) < std::tie(b.z(), b.y(), b.x());
  });
}

std::vector<Vec3> load(const std::filesystem::path& path, const Vec3& scale) {
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
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw std::runtime_error(path.string() + " cannot be read");
  if (bytes.empty()) throw std::runtime_error(path.string() + " is empty");
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
  mujoco_calls::route_warnings();
  const auto vfs = std::make_unique<mjVFS>();  // ~2 MB: not on the stack
  mj_defaultVFS(vfs.get());
  std::string error;
  std::vector<std::string> warnings;
  mujoco_calls::ModelPtr m;
  try {
    add_file(vfs.get(), "check.xml", check);
    add_file(vfs.get(), "hull.xml", hull);
    add_file(vfs.get(), mesh_name.c_str(), bytes);
    m = mujoco_calls::load_xml("check.xml", vfs.get(), error, warnings);
    if (m) m = mujoco_calls::load_xml("hull.xml", vfs.get(), error, warnings);
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
    for (size_t at; (at = error.find(mesh_name)) != std::string::npos;)
      error.replace(at, mesh_name.size(), path.filename().string());
    throw std::runtime_error("MuJoCo cannot use it: " + error);
  }
  const Vec3 p(m->geom_pos[0], m->geom_pos[1], m->geom_pos[2]);
  const Mat3 R = rotation_of(m->geom_quat);
  std::vector<Vec3> out = vertices(m.get(), m->geom_dataid[0]);
  for (Vec3& v : out) v = p + R * v;
  sort_vertices(out);
  return out;
}

}  // namespace featherdrive::mesh_hull
