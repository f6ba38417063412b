// Pieces to flatten (issue 22), as polygon soups of triangles: developable
// ones whose patterns are known exactly, a spherical cap, a bodice-like
// doubly curved panel. Shared by tests/systems/pattern and bench/pattern.
#pragma once

#include <atelier/engine/math.h>
#include <atelier/engine/random.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace atelier::flatten_shapes {

inline void tri(PolygonSoup& s, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  const std::uint32_t f[3] = {a, b, c};
  s.add_face(f);
}

/// nu x nv grid of points p(i, j) (i along u, j along v), each cell cut into
/// two CCW triangles (seen with u x v as the front) by alternating
/// diagonals.
template <class P>
PolygonSoup grid(int nu, int nv, P&& p) {
  PolygonSoup s;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) s.positions.push_back(p(i, j));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      if ((i + j) % 2 == 0) {
        tri(s, id(i, j), id(i + 1, j), id(i + 1, j + 1));
        tri(s, id(i, j), id(i + 1, j + 1), id(i, j + 1));
      } else {
        tri(s, id(i, j), id(i + 1, j), id(i, j + 1));
        tri(s, id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
      }
    }
  return s;
}

/// Cylinder patch of radius r, angle theta (about +z), height h: node (i, j)
/// at (r cos(theta i / nu), r sin(theta i / nu), h j / nv). Developable: its
/// pattern is a rectangle of width nu * 2 r sin(theta / (2 nu)) (the chords;
/// r theta in the limit) and height h, node (i, j) at (chord * i, h j / nv).
inline PolygonSoup cylinder_patch(double r, double theta, double h, int nu, int nv) {
  return grid(nu, nv, [&](int i, int j) {
    const double a = theta * i / nu;
    return Vec3d(r * std::cos(a), r * std::sin(a), h * j / nv);
  });
}

/// A whole cone cut open along one ray: half-angle alpha at the apex (the
/// origin, axis -z... pointing down: node (i, j) at slant distance
/// s = s0 + (s1 - s0) j / nv and angle 2 pi i / nu, i = 0..nu (the first and
/// last ray are distinct nodes at the same place). With s0 = 0 the apex is
/// one node with a fan of triangles. Developable: its pattern is a sector of
/// angle nu * 2 asin(sin(alpha) sin(pi / nu)) (2 pi sin(alpha) in the
/// limit), node (i, j) at radius s and angle i * that / nu.
inline PolygonSoup cone(double alpha, double s0, double s1, int nu, int nv) {
  const double sa = std::sin(alpha), ca = std::cos(alpha);
  auto at = [&](int i, int j) {
    const double s = s0 + (s1 - s0) * j / nv, a = 2 * M_PI * i / nu;
    return Vec3d(s * sa * std::cos(a), s * sa * std::sin(a), -s * ca);
  };
  if (s0 > 0) return grid(nu, nv, [&](int i, int j) { return at(i, nv - j); });
  PolygonSoup s;
  s.positions.push_back(Vec3d::Zero());
  for (int j = 1; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) s.positions.push_back(at(i, j));
  auto id = [&](int i, int j) { return j == 0 ? 0u : static_cast<std::uint32_t>(1 + (j - 1) * (nu + 1) + i); };
  // Front = outside (the surface normal points away from the axis).
  for (int i = 0; i < nu; ++i) tri(s, 0, id(i + 1, 1), id(i, 1));
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      tri(s, id(i, j), id(i + 1, j), id(i + 1, j + 1));
      tri(s, id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  // The triangles above are CCW seen from inside; flip them all.
  for (std::size_t f = 0; f < s.face_count(); ++f)
    std::swap(s.face_nodes[s.face_offsets[f] + 1], s.face_nodes[s.face_offsets[f] + 2]);
  return s;
}

/// An irregular planar triangulation: a jittered n x n grid of the unit
/// square scaled by `size`, then moved by the rigid motion (R, t).
inline PolygonSoup planar_patch(int n, double size, const Mat3d& R, const Vec3d& t, std::uint64_t seed = 5) {
  SplitMix64 rng(seed);
  PolygonSoup s = grid(n, n, [&](int i, int j) {
    const double jx = (i > 0 && i < n) ? 0.3 * (rng.uniform() - 0.5) : 0.0;
    const double jy = (j > 0 && j < n) ? 0.3 * (rng.uniform() - 0.5) : 0.0;
    return Vec3d(size * (i + jx) / n, size * (j + jy) / n, 0);
  });
  for (Vec3d& p : s.positions) p = R * p + t;
  return s;
}

/// Hexagonal disk of `rings` rings (1 + 3 rings (rings + 1) nodes) on a
/// sphere of radius r, as a cap of the given half-angle (radians): ring k at
/// polar angle half_angle * k / rings (azimuthal equidistant layout).
inline PolygonSoup spherical_cap(int rings, double half_angle, double r = 1.0) {
  PolygonSoup s;
  auto put = [&](double rho, double phi) {
    const double th = half_angle * rho;
    s.positions.emplace_back(r * std::sin(th) * std::cos(phi), r * std::sin(th) * std::sin(phi), r * std::cos(th));
  };
  put(0, 0);
  std::vector<std::uint32_t> start(rings + 1, 0);
  for (int k = 1; k <= rings; ++k) {
    start[k] = static_cast<std::uint32_t>(s.positions.size());
    for (int i = 0; i < 6 * k; ++i) put(double(k) / rings, 2 * M_PI * i / (6 * k));
  }
  auto id = [&](int k, int i) {
    return k == 0 ? 0u : start[k] + static_cast<std::uint32_t>(((i % (6 * k)) + 6 * k) % (6 * k));
  };
  for (int k = 1; k <= rings; ++k)
    for (int sec = 0; sec < 6; ++sec)
      for (int j = 0; j < k; ++j) {
        const int o = sec * k + j, in = sec * (k - 1) + j;
        tri(s, id(k - 1, in), id(k, o), id(k, o + 1));
        if (j < k - 1) tri(s, id(k - 1, in), id(k, o + 1), id(k - 1, in + 1));
      }
  return s;
}

/// A bodice-like front panel (metres): 0.4 m wide, 0.6 m tall, wrapped on an
/// elliptic cylinder with two bust bumps and a waist, so it has positive and
/// negative Gaussian curvature like a garment piece. n x n cells.
inline PolygonSoup bodice(int n) {
  return grid(n, n, [&](int i, int j) {
    const double u = -0.2 + 0.4 * i / n, z = 0.6 * j / n;
    const double waist = 1.0 - 0.12 * std::exp(-std::pow((z - 0.25) / 0.12, 2));
    const double a = 0.17 * waist, b = 0.11 * waist;
    const double th = u / 0.2 * 1.1;  // about +-63 degrees around the body
    double y = b * std::cos(th), x = a * std::sin(th);
    const double bump = 0.035 * (std::exp(-(std::pow((u - 0.09) / 0.05, 2) + std::pow((z - 0.42) / 0.06, 2))) +
                                 std::exp(-(std::pow((u + 0.09) / 0.05, 2) + std::pow((z - 0.42) / 0.06, 2))));
    y += bump;
    return Vec3d(x, -y, z);
  });
}

/// A joint of two chains of nodes given in the same 3D direction (both
/// members positive): a seam between two pieces.
inline JointIdx join(Model& m, const std::vector<NodeIdx>& a, const std::vector<NodeIdx>& b) {
  auto chain = [&](const std::vector<NodeIdx>& n) {
    std::vector<HalfedgeIdx> hs;
    for (std::size_t i = 0; i + 1 < n.size(); ++i) hs.push_back(m.find_halfedge(n[i], n[i + 1]));
    return m.new_mesh_edge(m.nodes.surface[n[0].value], hs);
  };
  const MeshEdgeIdx ma = chain(a), mb = chain(b);
  const JointMember mem[2] = {{ma, true}, {mb, true}};
  return m.new_joint(mem);
}

/// A skirt (a cone frustum about +z: radius r_hem at z = 0, r_top at z = h)
/// in two pieces, "front" (angles 0..pi) and "back" (pi..2 pi), each nu x nv
/// cells with the front of the faces outside, joined by two side seams:
/// seam_a at angle 0 (front's i = 0, back's i = nu), seam_b at angle pi.
struct Skirt {
  Model model;
  SurfaceIdx front, back;
  JointIdx seam_a, seam_b;
  int nu = 0, nv = 0;
  double h = 0;
  [[nodiscard]] NodeIdx node(SurfaceIdx s, int i, int j) const {
    return NodeIdx{static_cast<std::uint32_t>((s == front ? 0 : (nu + 1) * (nv + 1)) + j * (nu + 1) + i)};
  }
};

inline Skirt skirt(double r_top, double r_hem, double h, int nu, int nv) {
  Skirt k;
  k.h = h, k.nu = nu, k.nv = nv;
  for (int half = 0; half < 2; ++half) {
    PolygonSoup s = grid(nu, nv, [&](int i, int j) {
      const double a = M_PI * (half + double(i) / nu), t = double(j) / nv, r = r_hem + (r_top - r_hem) * t;
      return Vec3d(r * std::cos(a), r * std::sin(a), h * t);
    });
    auto surf = add_polygon_surface(k.model, half == 0 ? "front" : "back", s);
    if (!surf) throw Error(surf.status());
    (half == 0 ? k.front : k.back) = surf->idx;
  }
  std::vector<NodeIdx> fa, ba, fb, bb;
  for (int j = 0; j <= nv; ++j) {
    fa.push_back(k.node(k.front, 0, j));
    ba.push_back(k.node(k.back, nu, j));
    fb.push_back(k.node(k.front, nu, j));
    bb.push_back(k.node(k.back, 0, j));
  }
  k.seam_a = join(k.model, fa, ba);
  k.seam_b = join(k.model, fb, bb);
  return k;
}

/// A spherical cap (spherical_cap) cut along its diameter y = 0 into an
/// "upper" (y > 0) and a "lower" half joined by one seam, the chain running
/// from x = -R to x = +R in both.
struct SplitCap {
  Model model;
  SurfaceIdx upper, lower;
  JointIdx seam;
  std::vector<NodeIdx> upper_chain, lower_chain;
};

inline SplitCap split_cap(int rings, double half_angle, double r) {
  const PolygonSoup cap = spherical_cap(rings, half_angle, r);
  SplitCap sc;
  std::vector<std::vector<std::uint32_t>> local(2, std::vector<std::uint32_t>(cap.positions.size(), UINT32_MAX));
  std::uint32_t base[2] = {0, 0};
  for (int half = 0; half < 2; ++half) {
    PolygonSoup s;
    for (std::size_t f = 0; f < cap.face_count(); ++f) {
      const auto c = cap.face(f);
      Vec3d centre = Vec3d::Zero();
      for (std::uint32_t v : c) centre += cap.positions[v];
      if ((centre.y() > 0) != (half == 0)) continue;
      std::uint32_t t[3];
      for (int i = 0; i < 3; ++i) {
        if (local[half][c[i]] == UINT32_MAX) {
          local[half][c[i]] = static_cast<std::uint32_t>(s.positions.size());
          s.positions.push_back(cap.positions[c[i]]);
        }
        t[i] = local[half][c[i]];
      }
      s.add_face(t);
    }
    base[half] = static_cast<std::uint32_t>(sc.model.nodes.slots.capacity());
    auto surf = add_polygon_surface(sc.model, half == 0 ? "upper" : "lower", s);
    if (!surf) throw Error(surf.status());
    (half == 0 ? sc.upper : sc.lower) = surf->idx;
  }
  // Ring k's nodes at angles pi (index 3k) and 0 (index 0).
  std::vector<std::uint32_t> diameter;
  for (int k = rings; k >= 1; --k) diameter.push_back(static_cast<std::uint32_t>(1 + 3 * k * (k - 1) + 3 * k));
  diameter.push_back(0);
  for (int k = 1; k <= rings; ++k) diameter.push_back(static_cast<std::uint32_t>(1 + 3 * k * (k - 1)));
  for (std::uint32_t v : diameter) {
    sc.upper_chain.push_back(NodeIdx{base[0] + local[0][v]});
    sc.lower_chain.push_back(NodeIdx{base[1] + local[1][v]});
  }
  sc.seam = join(sc.model, sc.upper_chain, sc.lower_chain);
  return sc;
}

}  // namespace atelier::flatten_shapes
