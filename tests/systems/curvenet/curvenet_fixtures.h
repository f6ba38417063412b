// Curve networks for the curvenet tests: synthetic ones whose faces are
// known by construction (grids, a cube's wireframe, a torus grid) and the
// shared networks of ../shared/data/curve-networks.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <atelier/io/curve_network.h>
#include <atelier/io/obj.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>

namespace atelier::curvenet_test {


/// n + 1 points from a to b.
inline std::vector<Vec3d> line(const Vec3d& a, const Vec3d& b, int n = 8) {
  std::vector<Vec3d> p;
  for (int i = 0; i <= n; ++i) p.push_back(a + (b - a) * (static_cast<double>(i) / n));
  return p;
}

/// Curves along x and y of a grid with nx x ny cells of size h (z = a
/// gentle wave of amplitude z_wave), each curve overshooting its last
/// crossing by `overshoot` (dangling ends). Crossings are sample points of
/// both curves, so the polylines meet exactly there.
inline PolylineSet grid_network(int nx, int ny, double h = 1.0, double overshoot = 0.0, double z_wave = 0.0) {
  PolylineSet s;
  auto z = [&](double x, double y) { return z_wave * std::sin(0.7 * x) * std::cos(0.5 * y); };
  auto stations = [&](int n) {
    std::vector<double> t;
    if (overshoot > 0) t.push_back(-overshoot);
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 8; ++k) t.push_back(k == 0 ? i * h : (i + k / 8.0) * h);
    t.push_back(n * h);
    if (overshoot > 0) t.push_back(n * h + overshoot);
    return t;
  };
  std::int64_t id = 0;
  for (int j = 0; j <= ny; ++j) {
    std::vector<Vec3d> p;
    for (double x : stations(nx)) p.emplace_back(x, j * h, z(x, j * h));
    s.add(id++, p);
  }
  for (int i = 0; i <= nx; ++i) {
    std::vector<Vec3d> p;
    for (double y : stations(ny)) p.emplace_back(i * h, y, z(i * h, y));
    s.add(id++, p);
  }
  return s;
}

/// The 12 edges of the cube [0, a]^3 as curves ending exactly at its corners.
inline PolylineSet cube_wireframe(double a = 1.0) {
  PolylineSet s;
  std::int64_t id = 0;
  for (int c = 0; c < 8; ++c)
    for (int k = 0; k < 3; ++k) {
      if (c & (1 << k)) continue;
      const Vec3d p(c & 1 ? a : 0, c & 2 ? a : 0, c & 4 ? a : 0);
      Vec3d q = p;
      q[k] = a;
      s.add(id++, line(p, q, 6));
    }
  return s;
}

/// A torus (radii R, r) with `nu` closed meridians (around the tube) and
/// `nv` closed parallels (around the axis); each closed curve repeats its
/// first point at its end, and the crossings are sample points of both.
inline PolylineSet torus_grid(int nu, int nv, double R = 3.0, double r = 1.0, int per_span = 8) {
  PolylineSet s;
  auto at = [&](double u, double v) {
    return Vec3d((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
  };
  auto u_of = [&](int i) { return 2 * kPi * (i + 0.1) / nu; };  // meridians off the coordinate planes
  auto v_of = [&](int j) { return 2 * kPi * (j + 0.25) / nv; };
  std::int64_t id = 0;
  for (int i = 0; i < nu; ++i) {
    std::vector<Vec3d> p;
    for (int j = 0; j < nv; ++j)
      for (int k = 0; k < per_span; ++k)
        p.push_back(at(u_of(i), k == 0 ? v_of(j) : v_of(j) + 2 * kPi * k / (nv * per_span)));
    p.push_back(p.front());
    s.add(id++, p);
  }
  for (int j = 0; j < nv; ++j) {
    std::vector<Vec3d> p;
    for (int i = 0; i < nu; ++i)
      for (int k = 0; k < per_span; ++k)
        p.push_back(at(k == 0 ? u_of(i) : u_of(i) + 2 * kPi * k / (nu * per_span), v_of(j)));
    p.push_back(p.front());
    s.add(id++, p);
  }
  return s;
}

inline std::filesystem::path shared_networks() {
  return std::filesystem::path(ATELIER_SHARED_DATA) / "curve-networks";
}

#define ATELIER_REQUIRE_SHARED_NETWORKS()                                                      \
  do {                                                                                         \
    if (!std::filesystem::exists(::atelier::curvenet_test::shared_networks() / "roof_75.txt")) \
      GTEST_SKIP() << "shared curve networks not found";                                       \
  } while (0)

inline PolylineSet shared_network(const std::string& name) {
  return read_curve_network(shared_networks() / (name + ".txt"));
}

/// An OBJ mesh as a polygon soup in the file's vertex order.
inline PolygonSoup read_soup(const std::filesystem::path& path) {
  const Model m = read_obj(path);
  PolygonSoup s;
  const auto src = m.nodes.props.find<std::int32_t>("source_vertex");
  std::vector<std::uint32_t> index(m.nodes.slots.capacity(), 0);
  std::size_t nv = 0;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}))
      nv = std::max<std::size_t>(nv, static_cast<std::size_t>(src.valid() ? src[NodeIdx{v}] : v) + 1);
  s.positions.assign(nv, Vec3d::Zero());
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v})) {
      index[v] = src.valid() ? static_cast<std::uint32_t>(src[NodeIdx{v}]) : v;
      s.positions[index[v]] = m.nodes.position[v];
    }
  std::vector<NodeIdx> corners;
  std::vector<std::uint32_t> f;
  for (std::uint32_t k = 0; k < m.faces.slots.capacity(); ++k) {
    if (!m.alive(FaceIdx{k})) continue;
    m.face_nodes(FaceIdx{k}, corners);
    f.clear();
    for (NodeIdx v : corners) f.push_back(index[v.value]);
    s.add_face(f);
  }
  return s;
}

}  // namespace atelier::curvenet_test
