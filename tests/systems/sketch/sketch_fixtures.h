// Shared by the sketch tests: analytic meshes (icospheres, tubes, folds),
// cameras, and strokes made by projecting known 3D curves.
#pragma once

#include <atelier/engine/math.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/model.h>
#include <atelier/systems/mesh/subdivide.h>
#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/sketch/paint.h>
#include <atelier/systems/view/camera.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <vector>

namespace atelier::sketch_test {

/// Icosphere of radius r: the icosahedron split `levels` times (1-to-4),
/// every node pushed onto the sphere. Closed, outward, triangles only.
inline Model icosphere(int levels, double r = 1.0, const Vec3d& centre = Vec3d::Zero()) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3d> p = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  const std::uint32_t f[20][3] = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                  {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                  {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
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

namespace atelier::sketch_test {

/// A polygon soup builder.
struct Soup {
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> off{0}, idx;
  void face(std::initializer_list<std::uint32_t> f) {
    idx.insert(idx.end(), f);
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  }
  [[nodiscard]] PolygonSoupView view() const { return {p, off, idx}; }
};

/// An (nu+1) x (nv+1) grid of quads (or triangles) over f(u, v), u, v in
/// [0, 1]; faces counter-clockwise in (u, v).
template <class F>
Soup grid(int nu, int nv, F f, bool triangles = false) {
  Soup s;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) s.p.push_back(f(double(i) / nu, double(j) / nv));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      if (triangles) {
        s.face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        s.face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        s.face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      }
    }
  return s;
}

/// A Z-fold strip seen from +z: panel A (front, facing +z) for x in
/// [-1, 0.5], folding back under itself (panel B, facing -z) to x = -0.5,
/// then forward again (panel C) to x = 1, farther back. From the front the
/// visible surface jumps from A to C at x = 0.5 (seed 001 Fig. 10).
inline Model z_fold(int n = 10) {
  auto f = [](double u, double v) {
    const double t = 3 * u, y = -1 + 2 * v;
    if (t <= 1) return Vec3d(-1 + 1.5 * t, y, 0.5);
    if (t <= 2) return Vec3d(0.5 - (t - 1), y, 0.5 - 0.5 * (t - 1));
    return Vec3d(-0.5 + 1.5 * (t - 2), y, -0.5 * (t - 2));
  };
  Model m;
  (void)add_polygon_surface(m, "fold", grid(3 * n, n, f).view()).value();
  return m;
}

/// Pixel distance from q to the polyline.
inline double distance_to_polyline(const std::vector<Vec2d>& line, const Vec2d& q) {
  double best = INFINITY;
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const Vec2d a = line[i], d = line[i + 1] - a;
    const double t = std::clamp((q - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * d - q).norm());
  }
  return best;
}

/// The boundary loop (of any surface) that minimises score(mean position).
template <class F>
std::vector<NodeIdx> best_loop(const Model& m, F score) {
  std::vector<char> seen(m.halfedges.next.size(), 0);
  std::vector<NodeIdx> best;
  double best_s = INFINITY;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e})) continue;
    for (unsigned side = 0; side < 2; ++side) {
      HalfedgeIdx h = halfedge_of(EdgeIdx{e}, side);
      if (seen[h.value] || m.face(h).valid() || !m.face(twin(h)).valid()) continue;
      std::vector<NodeIdx> loop;
      Vec3d c = Vec3d::Zero();
      // Walk the faceless halfedges (each node's faceless outgoing one).
      for (HalfedgeIdx g = h; g.valid() && !seen[g.value];) {
        seen[g.value] = 1;
        loop.push_back(m.tail(g));
        c += m.position(m.tail(g));
        HalfedgeIdx next;
        m.for_each_outgoing(m.head(g), [&](HalfedgeIdx k) {
          if (!next.valid() && !m.face(k).valid() && m.face(twin(k)).valid()) next = k;
        });
        g = next;
      }
      c /= static_cast<double>(loop.size());
      if (const double sc = score(c); sc < best_s) best_s = sc, best = loop;
    }
  }
  return best;
}

/// The painted curves' attribute edges, in curve order.
inline std::vector<AttribEdge> edges_of(const PaintResult& p) {
  std::vector<AttribEdge> e;
  for (const auto& c : p.curves) e.insert(e.end(), c.edges.begin(), c.edges.end());
  return e;
}

/// Sum of the faces' fan areas (of surface `only` when given).
inline double fan_area(const Model& m, SurfaceIdx only = {}) {
  double a = 0;
  std::vector<NodeIdx> c;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f}) || (only.valid() && m.faces.surface[f] != only)) continue;
    m.face_nodes(FaceIdx{f}, c);
    for (std::size_t k = 1; k + 1 < c.size(); ++k)
      a += 0.5 * (m.position(c[k]) - m.position(c[0])).cross(m.position(c[k + 1]) - m.position(c[0])).norm();
  }
  return a;
}

/// Volume enclosed by a closed, consistently oriented model (divergence
/// theorem over the faces' fans; positive when the faces face outwards).
inline double signed_volume(const Model& m) {
  double v = 0;
  std::vector<NodeIdx> f;
  for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i) {
    if (!m.alive(FaceIdx{i})) continue;
    m.face_nodes(FaceIdx{i}, f);
    for (std::size_t k = 1; k + 1 < f.size(); ++k)
      v += m.position(f[0]).dot(m.position(f[k]).cross(m.position(f[k + 1]))) / 6.0;
  }
  return v;
}

/// Bounding box of the live nodes.
inline Box3d bounds(const Model& m) {
  Box3d b;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v})) b.extend(m.position(NodeIdx{v}));
  return b;
}

/// The as-surface extrusion gave the plain extrusion's part in a surface of
/// its own: the same faces, B's nodes once more on the part's side, one more
/// surface, and every face the plain extrusion added in the part's surface.
inline void expect_part_in_its_own_surface(const Model& m, const Model& plain, const Model& before,
                                           const ExtrudeReport& r) {
  EXPECT_EQ(m.num_faces(), plain.num_faces());
  EXPECT_EQ(m.num_nodes(), plain.num_nodes() + r.base.size());
  EXPECT_EQ(m.num_surfaces(), before.num_surfaces() + 1);
  std::size_t part_faces = 0;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f)
    part_faces += m.alive(FaceIdx{f}) && m.faces.surface[f] == r.part_surface;
  EXPECT_EQ(part_faces, plain.num_faces() - before.num_faces());
}

}  // namespace atelier::sketch_test
