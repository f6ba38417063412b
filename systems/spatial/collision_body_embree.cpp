// The collision body's Embree backend (CollisionBackend::kEmbree): Embree
// finds the candidate triangles, the exact distances, the tie rule and the
// sign are the collision body's own (collision_body_detail.h,
// triangle_query.h), so the answers equal the hand-written hierarchy's bit
// for bit.
//
//  * Set-up: one Embree device per topology and a pool of scenes, each a
//    triangle geometry of build quality RTC_BUILD_QUALITY_REFIT in a scene
//    of build quality LOW (the two-level mode, where Embree honours the
//    geometry's quality): built (SAH) on the first body it serves, then
//    refit (rtcUpdateGeometryBuffer, rtcCommitScene) on every later one.
//    A body borrows a scene from the pool for its lifetime, so concurrent
//    bodies of one topology (one per worker) each have their own, and a
//    new CollisionBody object costs a refit, not a build.
//  * Query: rtcPointQuery with a sphere whose radius starts at the hint
//    triangle's distance and shrinks, in the callback, to each nearer
//    triangle's. Embree culls in float, with boxes of float-rounded
//    vertices: radii carry a relative and an absolute margin (as
//    BodyBvh::closest_point(p, bound) does), so every triangle whose exact
//    distance could reach the best one, ties included, is visited.
//  * Clusters and batches (query_cluster, query_many): single queries,
//    the batch ordered by hint (see query_cluster_embree).
//
// The only source besides body_bvh.cpp that includes Embree
// (docs/architecture.md, third-party table): its headers dominate compile
// time, and this backend is Embree's whole use by the collision body.
#include <atelier/systems/spatial/collision_body.h>

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <atelier/engine/parallel.h>
#include "collision_body_detail.h"

namespace atelier {

// ------------------------------------------------------------ scenes


struct CollisionTopology::EmbreeScene {
  RTCScene scene = nullptr;
  RTCGeometry geom = nullptr;  // held by the scene
  float* vertices = nullptr;   // Embree's vertex buffer (padded by Embree)
  bool built = false;          // a first commit made the hierarchy: later ones refit
  bool broken = false;         // an Embree error: not returned to the pool
  EmbreeScene() = default;
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;
  ~EmbreeScene() {
    if (scene) rtcReleaseScene(scene);
  }
};

struct CollisionTopology::EmbreePool {
  RTCDevice device = nullptr;
  std::mutex mutex;
  std::vector<std::unique_ptr<EmbreeScene>> idle;
  std::string last_error;  // under `mutex`

  EmbreePool() = default;
  EmbreePool(const EmbreePool&) = delete;
  EmbreePool& operator=(const EmbreePool&) = delete;
  ~EmbreePool() {
    idle.clear();
    if (device) rtcReleaseDevice(device);
  }

  static void on_error(void* user, RTCError code, const char* str) {
    auto* pool = static_cast<EmbreePool*>(user);
    std::lock_guard<std::mutex> lock(pool->mutex);
    pool->last_error = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (str ? str : "");
  }

  [[nodiscard]] Status check(const char* what) {
    const RTCError e = rtcGetDeviceError(device);  // per thread
    if (e == RTC_ERROR_NONE) return Status::ok();
    std::lock_guard<std::mutex> lock(mutex);
    return Status(ErrorCode::kInternal, std::string("collision body (Embree) ") + what + ": " + last_error);
  }

  // A new scene over the topology's triangles (indices copied into an
  // Embree-owned buffer: the scene may outlive a body, never the pool).
  [[nodiscard]] std::unique_ptr<EmbreeScene> make_scene(const CollisionTopology& topo) {
    auto s = std::make_unique<EmbreeScene>();
    s->scene = rtcNewScene(device);
    if (!s->scene) return nullptr;
    // LOW and DYNAMIC: the two-level structure, whose per-geometry
    // hierarchy follows the geometry's quality (REFIT); without DYNAMIC
    // every commit rebuilt it (7.5 ms instead of 0.2 ms on the MakeHuman
    // skin). COMPACT: leaves hold triangle indices only, so a refit
    // recomputes boxes and copies no vertices (0.18 ms against 0.34 ms with
    // ROBUST's vertex leaves); the point query reads no leaf data anyway,
    // and ROBUST changes ray traversal only: the culling margins below
    // cover float rounding.
    rtcSetSceneBuildQuality(s->scene, RTC_BUILD_QUALITY_LOW);
    rtcSetSceneFlags(s->scene, static_cast<RTCSceneFlags>(RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_COMPACT));
    s->geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!s->geom) return nullptr;
    rtcSetGeometryBuildQuality(s->geom, RTC_BUILD_QUALITY_REFIT);
    const auto tris = topo.triangles();
    auto* idx = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
        s->geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), tris.size()));
    s->vertices = static_cast<float*>(rtcSetNewGeometryBuffer(s->geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), topo.point_count()));
    if (!idx || !s->vertices) {
      rtcReleaseGeometry(s->geom);
      return nullptr;
    }
    for (std::size_t t = 0; t < tris.size(); ++t)
      for (int k = 0; k < 3; ++k) idx[3 * t + k] = tris[t][k];
    rtcAttachGeometryByID(s->scene, s->geom, 0);
    rtcReleaseGeometry(s->geom);  // the scene holds it
    return s;
  }

  // Lends an idle scene (or a new one); it comes back when its last holder
  // lets go.
  [[nodiscard]] static std::shared_ptr<EmbreeScene> lend(const std::shared_ptr<EmbreePool>& pool,
                                                         const CollisionTopology& topo) {
    std::unique_ptr<EmbreeScene> s;
    {
      std::lock_guard<std::mutex> lock(pool->mutex);
      if (!pool->idle.empty()) {
        s = std::move(pool->idle.back());
        pool->idle.pop_back();
      }
    }
    if (!s) s = pool->make_scene(topo);
    if (!s) return nullptr;
    return std::shared_ptr<EmbreeScene>(s.release(), [pool](EmbreeScene* x) {
      std::unique_ptr<EmbreeScene> back(x);
      if (back->broken) return;
      std::lock_guard<std::mutex> lock(pool->mutex);
      pool->idle.push_back(std::move(back));
    });
  }
};

Status CollisionBody::build_embree(const ExecContext& ctx) {
  const CollisionTopology& tp = *topo_;
  std::call_once(tp.embree_once_, [&] {
    auto pool = std::make_shared<CollisionTopology::EmbreePool>();
    pool->device = rtcNewDevice("verbose=0");
    if (pool->device) rtcSetDeviceErrorFunction(pool->device, &CollisionTopology::EmbreePool::on_error, pool.get());
    tp.embree_pool_ = std::move(pool);
  });
  const auto& pool = tp.embree_pool_;
  if (!pool->device) return Status(ErrorCode::kInternal, "collision body (Embree): rtcNewDevice failed");
  // Largest coordinate: Embree's vertices are floats, and the culling
  // margins are relative to it.
  extent_ = 0;
  for (const Vec3d& q : pos_) extent_ = std::max(extent_, q.cwiseAbs().maxCoeff());
  if (!(extent_ < 1e30))
    return Status(ErrorCode::kInvalidArgument, "collision body (Embree): a coordinate of magnitude " +
                                                   std::to_string(extent_) + " is beyond float range");
  auto lease = CollisionTopology::EmbreePool::lend(pool, tp);
  if (!lease) {
    if (Status s = pool->check("scene"); !s) return s;
    return Status(ErrorCode::kInternal, "collision body (Embree): could not make a scene");
  }
  ExecContext lctx = ctx;
  lctx.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 4096);
  if (ctx.grain == 0) lctx.grain = 2048;
  float* v = lease->vertices;
  par::for_each_n(lctx, pos_.size(), [&](std::size_t i) {
    for (int a = 0; a < 3; ++a) v[3 * i + a] = static_cast<float>(pos_[i][a]);
  });
  if (lease->built) rtcUpdateGeometryBuffer(lease->geom, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(lease->geom);
  par::in_arena(ctx, [&] { rtcCommitScene(lease->scene); });
  if (Status s = pool->check("commit"); !s) {
    lease->broken = true;
    return s;
  }
  lease->built = true;
  embree_ = std::move(lease);
  return Status::ok();
}

// ------------------------------------------------------------ queries

namespace {

// Culling radius for a squared distance d2: its root with a relative and
// an absolute margin (float vertices and boxes, float query point, float
// distance arithmetic are each off by far less), rounded to float.
inline float cull_radius(double d2, double margin) noexcept {
  return static_cast<float>(std::sqrt(d2) * (1.0 + 1e-6) + margin);
}

inline double cull_margin(double extent, const Vec3d& p) noexcept {
  return 1e-6 * (extent + p.cwiseAbs().maxCoeff());
}

inline void set_point(RTCPointQuery& q, const Vec3d& p, float radius) noexcept {
  q.x = static_cast<float>(p.x());
  q.y = static_cast<float>(p.y());
  q.z = static_cast<float>(p.z());
  q.time = 0.0f;
  q.radius = radius;
}

template <class BestT>
struct Nearest {
  const Triangle* tris;
  const Vec3d* pos;
  Vec3d p;
  double margin;
  BestT* best;
};

// One candidate triangle of a single query: its exact distance, the tie
// rule of Best, and a smaller sphere when it is the new best.
template <class BestT>
bool visit_nearest(RTCPointQueryFunctionArguments* args) {
  auto& u = *static_cast<Nearest<BestT>*>(args->userPtr);
  const std::uint32_t t = args->primID;
  if (t == u.best->t) return false;  // the hint, already measured
  const Triangle& c = u.tris[t];
  const TrianglePoint r = closest_point_on_triangle(u.p, u.pos[c[0]], u.pos[c[1]], u.pos[c[2]]);
  if (!u.best->take((u.p - r.point).squaredNorm(), t, r)) return false;
  const float radius = cull_radius(u.best->d2, u.margin);
  if (radius >= args->query->radius) return false;
  args->query->radius = radius;
  return true;
}

}  // namespace

BodyDistance CollisionBody::query_embree(const Vec3d& p, std::uint32_t hint) const noexcept {
  Best best = start_from_hint(p, hint);
  Nearest<Best> u{topo_->triangles().data(), pos_.data(), p, cull_margin(extent_, p), &best};
  RTCPointQuery q;
  set_point(q, p, best.t == kNoTriangle ? std::numeric_limits<float>::infinity() : cull_radius(best.d2, u.margin));
  RTCPointQueryContext qc;
  rtcInitPointQueryContext(&qc);
  rtcPointQuery(embree_->scene, &q, &qc, &visit_nearest<Best>, &u);
  if (best.t == kNoTriangle) return {};  // a non-finite point
  return signed_distance(p, best.t, best.r);
}

// Clusters: the same single queries. (One rtcPointQuery per cluster of 8,
// a sphere around the cluster's box collecting the candidates for every
// point, as the hierarchy does with leaves, gathered 147 triangles on
// average on the MakeHuman garment and overflowed a cap of 192 in half the
// clusters: 8.8 ms against 5.4 ms for the 8,426 vertices one by one.)
void CollisionBody::query_cluster_embree(const std::uint32_t* idx, std::size_t n, std::span<const Vec3d> p,
                                         std::span<const std::uint32_t> hint,
                                         std::span<BodyDistance> out) const noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = idx ? idx[i] : i;
    out[k] = query_embree(p[k], hint[k]);
  }
}

}  // namespace atelier
