// Convex hulls of collision meshes through MuJoCo 2.2.2's compiler, which reads STL, OBJ and MSH
// files and computes each mesh's convex hull (mjModel::mesh_graph); COLLADA files are read here
// (collada_mesh.hpp) and their vertices given to it inline; docs/math/contact.md, G3.
#pragma once

#include <mujoco/mujoco.h>

#include <filesystem>
#include <string>
#include <vector>

#include "featherdrive/spatial/spatial.hpp"

namespace featherdrive::mesh_hull {

/// The file extensions (lower case) load reads: MuJoCo 2.2.2's STL, OBJ and MSH, and COLLADA.
bool readable_extension(const std::filesystem::path& path);

/// The hull's vertices of mesh `id` in a compiled model, in the mesh's frame (the geom's: MuJoCo
/// moves a mesh to its centre of mass and principal axes and puts the offset in geom_pos and
/// geom_quat). All the mesh's vertices where the model has no hull (compiler convexhull="false").
std::vector<Vec3> vertices(const mjModel* m, int id);

/// Sorts vertices by z, then y, then x (a box's hull in the box's corner order).
void sort_vertices(std::vector<Vec3>& vertices);

/// The hull's vertices of `points`, a subset of them (the doubles given, not MuJoCo's float32
/// copy), sorted. Throws std::runtime_error with a one-line reason where there are fewer than 4,
/// one is not finite or beyond 1e6 (m), they span no volume (within 1e-6 of their size) or
/// MuJoCo refuses them.
std::vector<Vec3> hull_of_points(const std::vector<Vec3>& points);

/// The hull's vertices of the mesh file at `path` scaled by `scale` (each > 0), in the file's
/// frame. Throws std::runtime_error with a one-line reason (no file name) where the file cannot
/// be read or MuJoCo refuses it (an unreadable or degenerate mesh: zero volume).
std::vector<Vec3> load(const std::filesystem::path& path, const Vec3& scale);

}  // namespace featherdrive::mesh_hull
