// Analytic test shapes as polygon soups (header-only, for any test folder).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/storage/builder.h>
#include <atelier/systems/body/reference_body.h>

namespace atelier::shapes {

struct Soup {
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> off{0}, idx;
  void face(std::initializer_list<std::uint32_t> f) {
    idx.insert(idx.end(), f);
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  }
  [[nodiscard]] PolygonSoupView arrays() const { return {p, off, idx}; }
};

/// Writes the soup as OBJ text with every double exactly (%.17g), each
/// vertex mapped by `map` first.
template <class Map>
void write_soup_obj(const Soup& s, const std::filesystem::path& file, Map map) {
  std::ofstream f(file);
  char line[128];
  for (const Vec3d& p : s.p) {
    const Vec3d q = map(p);
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", q.x(), q.y(), q.z());
    f << line;
  }
  for (std::size_t k = 0; k + 1 < s.off.size(); ++k) {
    f << 'f';
    for (std::uint32_t i = s.off[k]; i < s.off[k + 1]; ++i) f << ' ' << s.idx[i] + 1;
    f << '\n';
  }
}

/// Closed UV sphere of radius r: quads with triangle fans at the poles,
/// outward orientation. Vertex 0 is the north pole (+z).
inline Soup uv_sphere(int nu, int nv, double r = 1.0, Vec3d centre = Vec3d::Zero()) {
  Soup s;
  s.p.push_back(centre + Vec3d(0, 0, r));
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = M_PI * j / nv, ph = 2 * M_PI * (i + 0.5) / nu;
      s.p.push_back(centre + r * Vec3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  s.p.push_back(centre + Vec3d(0, 0, -r));
  auto ring = [&](int j, int i) { return static_cast<std::uint32_t>(1 + (j - 1) * nu + (i % nu)); };
  for (int i = 0; i < nu; ++i) s.face({0, ring(1, i), ring(1, i + 1)});
  for (int j = 1; j + 1 < nv; ++j)
    for (int i = 0; i < nu; ++i) s.face({ring(j, i), ring(j + 1, i), ring(j + 1, i + 1), ring(j, i + 1)});
  const auto south = static_cast<std::uint32_t>(s.p.size() - 1);
  for (int i = 0; i < nu; ++i) s.face({south, ring(nv - 1, i + 1), ring(nv - 1, i)});
  return s;
}

/// A reference body (no features) whose skin is the given soup.
inline std::shared_ptr<ReferenceBody> body_from(const Soup& s) {
  auto rb = std::make_shared<ReferenceBody>();
  auto surf = add_polygon_surface(rb->model, "skin", s.arrays());
  if (!surf) throw Error(surf.status());
  rb->skin = surf->idx;
  return rb;
}

}  // namespace atelier::shapes
