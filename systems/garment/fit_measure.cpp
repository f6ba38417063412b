#include <atelier/engine/parallel.h>
#include <atelier/systems/garment/fit_measure.h>
#include <atelier/systems/mesh/normals.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace atelier {

namespace {

Status check_finite(std::span<const Vec3d> p, const char* what) {
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!p[i].allFinite())
      return Status(ErrorCode::kInvalidArgument, std::string(what) + " vertex " + std::to_string(i) + " is not finite");
  return {};
}

}  // namespace

double quantile_in_place(std::vector<double>& v, double q) {
  if (v.empty()) return 0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

Expected<FitMeasure> measure_fit(const FitInput& in, const FitMeasureParams& params, const ExecContext& ctx) {
  if (in.garment.empty()) return Status(ErrorCode::kInvalidArgument, "the garment has no vertices");
  if (in.body_triangles.empty()) return Status(ErrorCode::kInvalidArgument, "the body has no triangles");
  if (Status s = check_finite(in.garment, "garment"); !s) return s;
  if (Status s = check_finite(in.body_points, "body"); !s) return s;
  const std::size_t n = in.garment.size();
  for (std::size_t k = 0; k < in.garment_edges.size(); ++k)
    for (std::uint32_t v : in.garment_edges[k])
      if (v >= n)
        return Status(ErrorCode::kInvalidArgument, "garment edge " + std::to_string(k) + " names vertex " +
                                                       std::to_string(v) + " of " + std::to_string(n));
  const bool source = !in.source_garment.empty();
  if (source && in.source_garment.size() != n)
    return Status(ErrorCode::kMismatch, "the source garment has " + std::to_string(in.source_garment.size()) +
                                            " vertices, the garment " + std::to_string(n));
  const bool body_strain = source && !in.source_body_points.empty();
  if (body_strain && in.source_body_points.size() != in.body_points.size())
    return Status(ErrorCode::kMismatch, "the source body has " + std::to_string(in.source_body_points.size()) +
                                            " points, the body " + std::to_string(in.body_points.size()) +
                                            " (they must share one topology)");
  if (source)
    if (Status s = check_finite(in.source_garment, "source garment"); !s) return s;
  if (body_strain)
    if (Status s = check_finite(in.source_body_points, "source body"); !s) return s;

  BodyBvh body;
  if (Status s = body.build(in.body_points, in.body_triangles, {}, ctx); !s) return s;
  if (Status s = body.require_closed(); !s) return Status(s.code(), "body: " + s.message());
  std::vector<double> sd(n);
  if (Status s = body.signed_distances(in.garment, sd, ctx); !s) return s;

  FitMeasure m;
  m.vertices = n;
  m.edges = in.garment_edges.size();
  double sum = 0;
  m.clearance_min = sd[0];
  for (double d : sd) {  // sequential, fixed order: identical for any thread count
    m.inside += d < 0;
    m.inside_tolerance += d < -params.inside_tolerance;
    m.max_depth = std::max(m.max_depth, -d);
    m.clearance_min = std::min(m.clearance_min, d);
    sum += d;
  }
  m.clearance_mean = sum / static_cast<double>(n);
  std::vector<double> sorted = sd;
  m.clearance_p50 = quantile_in_place(sorted, 0.5);
  m.clearance_p95 = quantile_in_place(sorted, 0.95);
  if (!source) return m;

  m.has_source = true;
  BodyBvh source_body;
  std::vector<double> sd0(n);
  if (body_strain) {
    if (Status s = source_body.build(in.source_body_points, in.body_triangles, {}, ctx); !s) return s;
    if (Status s = source_body.signed_distances(in.source_garment, sd0, ctx); !s) return s;
    double c = 0;
    for (std::size_t v = 0; v < n; ++v) c += (sd[v] - sd0[v]) * (sd[v] - sd0[v]);
    m.clearance_change_rms = std::sqrt(c / static_cast<double>(n));
  }
  const std::size_t ne = in.garment_edges.size();
  std::vector<double> strain(ne, -1), excess(ne, -1);  // -1: a zero-length source edge, skipped
  par::for_each_n(ctx, ne, [&](std::size_t k) {
    const auto [a, b] = in.garment_edges[k];
    const Vec3d e0 = in.source_garment[b] - in.source_garment[a];
    const double l0 = e0.norm();
    if (!(l0 > 0)) return;
    const double s = (in.garment[b] - in.garment[a]).norm() / l0 - 1;
    strain[k] = std::abs(s);
    if (!body_strain) return;
    const ClosestHit hit = source_body.closest_point(0.5 * (in.source_garment[a] + in.source_garment[b]));
    const Triangle& t = in.body_triangles[hit.triangle];
    const Mat3d b0 = triangle_basis(in.source_body_points, t);
    if (std::abs(b0.determinant()) < 1e-30) {  // degenerate source triangle: no affine map
      excess[k] = std::abs(s);
      return;
    }
    const double sb = (triangle_basis(in.body_points, t) * b0.inverse() * e0).norm() / l0 - 1;
    excess[k] = std::abs(s - sb);
  });
  const auto kept = [](std::vector<double>& v) {
    v.erase(std::remove(v.begin(), v.end(), -1.0), v.end());
    return quantile_in_place(v, 0.95);
  };
  m.edge_strain_p95 = kept(strain);
  if (body_strain) {
    m.has_source_body = true;
    m.excess_strain_p95 = kept(excess);
  }
  return m;
}

Expected<std::size_t> count_inside_layer(std::span<const Vec3d> outer, std::span<const BodyDistance> on_body,
                                         const BodyBvh& inner, const LayerPenetrationParams& params,
                                         std::vector<std::uint8_t>* inside) {
  if (outer.size() != on_body.size())
    return Status(ErrorCode::kMismatch, "layer penetration: " + std::to_string(outer.size()) + " vertices, " +
                                            std::to_string(on_body.size()) + " body distances");
  if (inner.empty())
    return Status(ErrorCode::kInvalidArgument, "layer penetration: the inner garment has no triangles");
  if (!(params.probe > 0) || !std::isfinite(params.probe) || !(params.tolerance >= 0) ||
      !(params.tolerance < params.probe))
    return Status(ErrorCode::kInvalidArgument, "layer penetration: need a positive probe and 0 <= tolerance < probe");
  if (inside) inside->assign(outer.size(), 0);
  std::size_t n = 0;
  for (std::size_t v = 0; v < outer.size(); ++v) {
    const BodyDistance& b = on_body[v];
    if (!(b.distance > 0) || !b.closest.allFinite() || !b.normal.allFinite() || b.normal.squaredNorm() == 0) continue;
    const RayHit h = inner.ray_first_hit(b.closest, b.normal.normalized(), b.distance + params.probe);
    if (h.hit && h.t > b.distance + params.tolerance) {
      ++n;
      if (inside) (*inside)[v] = 1;
    }
  }
  return n;
}

Expected<std::size_t> lift_over_lower_layers(std::span<Vec3d> outer, std::span<BodyDistance> on_body,
                                             std::span<const BodyBvh> lower, const CollisionBody& body, double probe,
                                             double gap, int rounds) {
  if (outer.size() != on_body.size())
    return Status(ErrorCode::kMismatch, "lift_over_lower_layers: " + std::to_string(outer.size()) + " vertices, " +
                                            std::to_string(on_body.size()) + " body distances");
  if (!(probe > 0) || !(gap > 0) || !std::isfinite(probe) || !std::isfinite(gap))
    return Status(ErrorCode::kInvalidArgument, "lift_over_lower_layers: probe and gap must be positive and finite");
  for (std::size_t k = 0; k < lower.size(); ++k)
    if (lower[k].empty())
      return Status(ErrorCode::kInvalidArgument,
                    "lift_over_lower_layers: lower layer " + std::to_string(k) + " has no committed BVH");
  std::size_t total = 0;
  for (int round = 0; round < rounds; ++round) {
    std::size_t lifted = 0;
    for (std::size_t k = 0; k < lower.size(); ++k)
      for (std::size_t v = 0; v < outer.size(); ++v) {
        BodyDistance& b = on_body[v];
        if (!(b.distance > 0) || b.normal.squaredNorm() == 0) continue;
        const Vec3d n = b.normal.normalized();
        const RayHit h = lower[k].ray_first_hit(b.closest, n, b.distance + probe);
        if (!h.hit || h.t <= b.distance) continue;
        outer[v] = b.closest + (h.t + gap) * n;
        b = body.query(outer[v], b.triangle);
        ++lifted;
      }
    total += lifted;
    if (lifted == 0) break;
  }
  return total;
}

}  // namespace atelier
