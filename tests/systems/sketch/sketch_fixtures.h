// Shared by the sketch tests: analytic meshes (icospheres, tubes, folds),
// cameras, and strokes made by projecting known 3D curves.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/model.h>
#include <atelier/systems/mesh/subdivide.h>
#include <atelier/systems/view/camera.h>

namespace atelier::sketch_test {

/// Icosphere of radius r: the icosahedron split `levels` times (1-to-4),
/// every node pushed onto the sphere. Closed, outward, triangles only.
inline Model icosphere(int levels, double r = 1.0, const Vec3d& centre = Vec3d::Zero()) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3d> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  const std::uint32_t f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                  {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                  {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                  {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  std::vector<std::uint32_t> off{0}, idx;
  for (auto& tri : f) {
    idx.insert(idx.end(), tri, tri + 3);
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  }
  for (auto& q : p) q = centre + r * q.normalized();
  Model m;
  (void)add_polygon_surface(m, "sphere", PolygonSoupView{p, off, idx}).value();
  for (int l = 0; l < levels; ++l) {
    (void)subdivide_uniform(m).value();
    for (auto& q : m.nodes.position) q = centre + r * (q - centre).normalized();
  }
  return m;
}

/// Orthographic camera looking down -z at the origin, the square
/// [-half, half]^2 filling a size x size viewport.
inline Camera front_ortho(double half = 1.5, int size = 800) {
  return Camera::orthographic(Vec3d(0, 0, 5), Vec3d::Zero(), Vec3d::UnitY(), half, size, size);
}

/// Perspective camera at `eye` looking at the origin.
inline Camera front_persp(const Vec3d& eye = Vec3d(0.3, 0.2, 4), int size = 800) {
  return Camera::look_at(eye, Vec3d::Zero(), Vec3d::UnitY(), 45.0, size, size);
}

/// Pixels of 3D points through a camera.
inline std::vector<Vec2d> project(const Camera& c, const std::vector<Vec3d>& pts) {
  std::vector<Vec2d> out;
  for (const auto& p : pts) out.push_back(c.project(p).head<2>());
  return out;
}

}  // namespace atelier::sketch_test
