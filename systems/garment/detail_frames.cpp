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

// ------------------------------------------------------------- body polygons


BodyPolygons BodyPolygons::from_model(const Model& body) {
  return from_model(body, SurfaceIdx{});
}

BodyPolygons BodyPolygons::from_model(const Model& body, SurfaceIdx surface) {
  BodyPolygons b;
  b.node_count = static_cast<std::uint32_t>(body.nodes.slots.capacity());
  std::vector<NodeIdx> fn;
  for (std::uint32_t f = 0; f < body.faces.slots.capacity(); ++f) {
    if (!body.alive(FaceIdx{f})) continue;
    if (surface.valid() && body.faces.surface[f] != surface) continue;
    body.face_nodes(FaceIdx{f}, fn);
    for (NodeIdx v : fn) b.face_nodes.push_back(v.value);
    b.face_offsets.push_back(static_cast<std::uint32_t>(b.face_nodes.size()));
  }
  std::uint64_t h = 0xcbf29ce484222325ull;
  h = fnv1a(h, &b.node_count, sizeof b.node_count);
  h = fnv1a(h, b.face_offsets.data(), b.face_offsets.size() * 4);
  h = fnv1a(h, b.face_nodes.data(), b.face_nodes.size() * 4);
  b.topology_hash = h;
  return b;
}


void compute_frames(const BodyPolygons& b, std::span<const Vec3d> p, PolygonFrames& out, const ExecContext& ctx,
                    std::span<const Eigen::Vector2f> ref, bool scaled) {
  const std::size_t n = b.size();
  out.centroid.resize(n);
  out.x.resize(n);
  out.y.resize(n);
  out.z.resize(n);
  out.degenerate.resize(n);
  const SpanPos pos{p};
  par::for_each_n(ctx, n, [&](std::size_t f) {
    const FrameD fr = polygon_frame(b, pos, f, ref, scaled);
    out.centroid[f] = fr.c.cast<float>();
    out.x[f] = fr.x.cast<float>();
    out.y[f] = fr.y.cast<float>();
    out.z[f] = fr.z.cast<float>();
    out.degenerate[f] = fr.degenerate;
  });
}

}  // namespace atelier
