// The unit sphere as a reference body and garment-like points around it:
// the shared fixture of the detail-template tests (detail_template_test,
// helper_truth_test).
#pragma once

#include <atelier/engine/random.h>
#include <atelier/systems/body/reference_body.h>
#include <atelier/systems/garment/detail_template.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "support/shapes.h"

namespace atelier::garment_test {

struct SphereBody {
  std::shared_ptr<ReferenceBody> ref;
  BodyPolygons poly;
  std::vector<Vec3d> pos;
};

/// A UV sphere of radius 1 (nu x nv) as a reference body, its p-polygons
/// and its positions.
inline SphereBody sphere_body(int nu = 40, int nv = 24) {
  SphereBody b;
  b.ref = shapes::body_from(shapes::uv_sphere(nu, nv));
  b.poly = BodyPolygons::from_model(b.ref->model);
  b.pos = skin_positions(*b.ref);
  return b;
}

/// Garment-like points: n random points on a shell 2-8 cm outside the unit
/// sphere.
inline std::vector<Vec3d> shell_points(std::size_t n, std::uint64_t seed) {
  SplitMix64 r(seed);
  std::vector<Vec3d> g;
  while (g.size() < n) {
    const Vec3d d(r.normal(), r.normal(), r.normal());
    if (d.norm() < 1e-6) continue;
    g.push_back(d.normalized() * r.uniform(1.02, 1.08));
  }
  return g;
}

}  // namespace atelier::garment_test
