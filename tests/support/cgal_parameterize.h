// CGAL's Surface_mesh_parameterization (ARAP and LSCM) on a triangle soup:
// the peer of the flattening tests and benchmarks (issue 22). Test and
// benchmark code only; CGAL_EIGEN3_ENABLED must be defined (the build does it
// for the targets that include this).
#pragma once

#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/ARAP_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/LSCM_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>
#include <atelier/engine/math.h>
#include <atelier/storage/polygon_soup.h>

#include <vector>

namespace atelier::cgal_peer {

enum class Method { kArap, kLscm };

struct Result {
  bool ok = false;
  std::vector<Vec2d> uv;  // per soup vertex
};

/// Parameterizes the soup (triangles, one boundary) with CGAL's defaults:
/// ARAP_parameterizer_3 (lambda 1000, 50 iterations, LSCM start, MVC post
/// processing when flipped) or LSCM_parameterizer_3 (two pinned vertices).
inline Result parameterize(const PolygonSoup& soup, Method method) {
  using K = CGAL::Simple_cartesian<double>;
  using Mesh = CGAL::Surface_mesh<K::Point_3>;
  using VD = boost::graph_traits<Mesh>::vertex_descriptor;
  namespace SMP = CGAL::Surface_mesh_parameterization;
  Mesh mesh;
  std::vector<VD> v;
  v.reserve(soup.positions.size());
  for (const Vec3d& p : soup.positions) v.push_back(mesh.add_vertex(K::Point_3(p.x(), p.y(), p.z())));
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    const auto c = soup.face(f);
    std::vector<VD> corners;
    for (std::uint32_t i : c) corners.push_back(v[i]);
    if (mesh.add_face(corners) == Mesh::null_face()) return {};
  }
  const auto border = CGAL::Polygon_mesh_processing::longest_border(mesh).first;
  auto uvmap = mesh.add_property_map<VD, K::Point_2>("v:uv").first;
  SMP::Error_code err = SMP::ERROR_EMPTY_MESH;
  if (method == Method::kArap)
    err = SMP::parameterize(mesh, SMP::ARAP_parameterizer_3<Mesh>(), border, uvmap);
  else
    err = SMP::parameterize(mesh, SMP::LSCM_parameterizer_3<Mesh>(), border, uvmap);
  Result r;
  r.ok = err == SMP::OK;
  r.uv.resize(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) r.uv[i] = Vec2d(uvmap[v[i]].x(), uvmap[v[i]].y());
  return r;
}

/// E_L, E_A and flips of a parameterization of a triangle soup, with the
/// definitions of systems/pattern/flatten.h (E_L over unique edges).
struct Distortion {
  double length_error = 0, area_error = 0;
  std::size_t flipped = 0;
};
inline Distortion distortion(const PolygonSoup& soup, const std::vector<Vec2d>& uv, double scale = 1.0) {
  Distortion d;
  double dl = 0, sl = 0, da = 0, sa = 0;
  for (const auto& e : soup.edges()) {
    const double l = (soup.positions[e[0]] - soup.positions[e[1]]).norm();
    dl += std::abs(scale * (uv[e[0]] - uv[e[1]]).norm() - l);
    sl += l;
  }
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    const auto c = soup.face(f);
    const Vec3d& p0 = soup.positions[c[0]];
    const double a3 = 0.5 * (soup.positions[c[1]] - p0).cross(soup.positions[c[2]] - p0).norm();
    const Vec2d q1 = scale * (uv[c[1]] - uv[c[0]]), q2 = scale * (uv[c[2]] - uv[c[0]]);
    const double a2 = 0.5 * (q1.x() * q2.y() - q1.y() * q2.x());
    da += std::abs(a2 - a3);
    sa += a3;
    if (!(a2 > 0)) ++d.flipped;
  }
  d.length_error = dl / sl;
  d.area_error = da / sa;
  return d;
}

/// The uniform scale that gives the parameterization the surface's area
/// (LSCM's pinned vertices fix an arbitrary scale).
inline double area_scale(const PolygonSoup& soup, const std::vector<Vec2d>& uv) {
  double a3 = 0, a2 = 0;
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    const auto c = soup.face(f);
    const Vec3d& p0 = soup.positions[c[0]];
    a3 += 0.5 * (soup.positions[c[1]] - p0).cross(soup.positions[c[2]] - p0).norm();
    const Vec2d q1 = uv[c[1]] - uv[c[0]], q2 = uv[c[2]] - uv[c[0]];
    a2 += 0.5 * std::abs(q1.x() * q2.y() - q1.y() * q2.x());
  }
  return std::sqrt(a3 / a2);
}

}  // namespace atelier::cgal_peer
