#include <atelier/systems/garment/detail_template.h>

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include <atelier/engine/cpu_features.h>
#include <atelier/engine/parallel.h>
#include <atelier/systems/body/body_set.h>
#include "detail_template_detail.h"

namespace atelier {

using namespace detail_internal;

// ------------------------------------------------------------------ encode

Expected<DetailEncoding> encode_detail(const BodyPolygons& body, std::span<const Vec3d> bp,
                                       std::span<const Vec3d> garment, const DetailParams& params,
                                       const ExecContext& ctx) {
  const std::size_t np = body.size();
  if (np == 0) return Status(ErrorCode::kInvalidArgument, "encode_detail: the body has no polygons");
  if (bp.size() != body.node_count) {
    std::ostringstream s;
    s << "encode_detail: " << bp.size() << " body positions for a body of " << body.node_count << " nodes";
    return Status(ErrorCode::kMismatch, s.str());
  }
  for (std::size_t v = 0; v < garment.size(); ++v)
    if (!garment[v].allFinite()) {
      std::ostringstream s;
      s << "encode_detail: garment vertex " << v << " is not finite";
      return Status(ErrorCode::kDegenerate, s.str());
    }
  if (params.scaled_frames && !params.fitted_frames)
    return Status(ErrorCode::kInvalidArgument, "encode_detail: scaled frames need fitted frames");
  std::vector<FrameD> frames(np);
  par::for_each_n(ctx, np, [&](std::size_t f) { frames[f] = polygon_frame(body, SpanPos{bp}, f); });
  std::vector<Vec3d> centroids(np);
  std::vector<std::uint8_t> skip(np);
  std::size_t usable = 0;
  for (std::size_t f = 0; f < np; ++f) {
    centroids[f] = frames[f].c;
    skip[f] = frames[f].degenerate;
    usable += !skip[f];
  }
  std::size_t k = params.single_polygon        ? 1
                  : params.polygons_per_vertex ? params.polygons_per_vertex
                                               : static_cast<std::size_t>(std::lround(np / 100.0));
  k = std::max<std::size_t>(k, 1);
  if (usable < k) {
    std::ostringstream s;
    s << "encode_detail: the body has " << usable << " usable polygons, " << k << " are needed per vertex";
    return Status(ErrorCode::kInvalidArgument, s.str());
  }
  CentroidGrid grid;
  grid.build(centroids, skip, k, params.cell);

  DetailEncoding enc;
  if (params.fitted_frames) {
    enc.reference_corners.resize(body.face_nodes.size(), Eigen::Vector2f::Zero());
    for (std::size_t f = 0; f < np; ++f) {
      if (frames[f].degenerate) continue;
      for (std::uint32_t k = body.face_offsets[f]; k < body.face_offsets[f + 1]; ++k) {
        const Vec3d q = bp[body.face_nodes[k]] - frames[f].c;
        enc.reference_corners[k] =
            Eigen::Vector2f(static_cast<float>(q.dot(frames[f].y)), static_cast<float>(q.dot(frames[f].z)));
      }
    }
  }
  enc.scaled_frames = params.scaled_frames;
  enc.polygon_count = static_cast<std::uint32_t>(np);
  enc.body_node_count = body.node_count;
  enc.topology_hash = body.topology_hash;
  const std::size_t nv = garment.size();
  enc.row.resize(nv + 1);
  for (std::size_t v = 0; v <= nv; ++v) enc.row[v] = static_cast<std::uint32_t>(v * k);
  enc.polygon.resize(nv * k);
  enc.a.resize(nv * k);
  enc.b.resize(nv * k);
  enc.c.resize(nv * k);
  enc.d.resize(nv * k);
  const double eps = params.epsilon;
  const bool taper = params.tapered_weights && usable > k;
  const std::size_t kq = taper ? k + 1 : k;
  std::vector<std::uint32_t> nearest(nv * kq);
  grid.nearest_many(garment, kq, nearest, ctx);
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "encode_detail cancelled");
  ExecContext c = ctx;
  c.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 256);
  c.grain = ctx.grain ? ctx.grain : 256;
  par::for_each_block(c, nv, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> near;
    std::vector<std::array<double, 5>> coef;
    for (std::size_t v = begin; v < end; ++v) {
      const Vec3d& q = garment[v];
      near.assign(nearest.begin() + static_cast<std::ptrdiff_t>(v * kq),
                  nearest.begin() + static_cast<std::ptrdiff_t>((v + 1) * kq));
      double w_cut = 0;
      if (taper) {
        w_cut = 1.0 / (eps + std::pow((q - frames[near.back()].c).norm(), 3));
        near.pop_back();
      }
      // Entries in polygon order: decoding then walks frames monotonically.
      std::sort(near.begin(), near.end());
      coef.resize(k);
      double wsum = 0;
      for (std::size_t i = 0; i < k; ++i) {
        const FrameD& fr = frames[near[i]];
        const Vec3d dq = q - fr.c;
        const double w = 1.0 / (eps + std::pow(dq.norm(), 3)) - w_cut;  // eq. (10), tapered
        coef[i] = {w, dq.dot(fr.x), dq.dot(fr.y), dq.dot(fr.z), 0};     // eq. (9)
        wsum += w;
      }
      if (!(wsum > 0)) {  // all k as far as the cut-off: plain eq. (10)
        wsum = 0;
        for (std::size_t i = 0; i < k; ++i) {
          coef[i][0] += w_cut;
          wsum += coef[i][0];
        }
      }
      for (std::size_t i = 0; i < k; ++i) {
        const std::size_t e = v * k + i;
        const double a = coef[i][0] / wsum;
        enc.polygon[e] = near[i];
        enc.a[e] = static_cast<float>(a);
        enc.b[e] = static_cast<float>(a * coef[i][1]);
        enc.c[e] = static_cast<float>(a * coef[i][2]);
        enc.d[e] = static_cast<float>(a * coef[i][3]);
      }
    }
  });
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "encode_detail cancelled");
  return enc;
}

Status check_topology(const DetailEncoding& enc, const BodyPolygons& body) {
  if (enc.polygon_count != body.size() || enc.body_node_count != body.node_count ||
      enc.topology_hash != body.topology_hash) {
    std::ostringstream s;
    s << "the body's topology (" << body.node_count << " nodes, " << body.size()
      << " polygons) differs from the one the detail template was encoded on (" << enc.body_node_count << " nodes, "
      << enc.polygon_count << " polygons)";
    return {ErrorCode::kMismatch, s.str()};
  }
  return {};
}

}  // namespace atelier
