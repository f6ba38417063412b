// The collision body (collision_body.h): Embree finds the candidate
// triangles, the exact distances, the tie rule and the sign are ours
// (triangle_query.h).
//
//  * Set-up: one Embree device per topology and a pool of scenes, each a
//    triangle geometry of build quality RTC_BUILD_QUALITY_REFIT in a
//    dynamic scene of build quality LOW (the two-level mode, where Embree
//    honours the geometry's quality): built (SAH) on the first body it
//    serves, then refit (rtcUpdateGeometryBuffer, rtcCommitScene) on every
//    later one. A body borrows a scene from the pool for its lifetime, so
//    concurrent bodies of one topology (one per worker) each have their
//    own, and a new CollisionBody object costs a refit, not a build.
//  * Query: rtcPointQuery with a sphere whose radius starts at the hint
//    triangle's distance and shrinks, in the callback, to each nearer
//    triangle's. Embree culls in float, with boxes of float-rounded
//    vertices: radii carry a relative and an absolute margin (as
//    BodyBvh::closest_point(p, bound) does), so every triangle whose exact
//    distance could reach the best one, ties included, is visited, and the
//    answer is the smallest (distance, triangle index) over all triangles
//    whatever the hint and the scene's layout.
//
// One of the two sources that include Embree (docs/architecture.md,
// third-party table), with body_bvh.cpp.
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

namespace atelier {

// ------------------------------------------------------------ topology

Expected<std::shared_ptr<const CollisionTopology>> CollisionTopology::build(std::span<const Triangle> triangles,
                                                                            std::uint32_t point_count) {
  if (triangles.empty() || point_count == 0) return Status(ErrorCode::kInvalidArgument, "collision body: empty mesh");
  auto topo = TriangleTopology::build(triangles, point_count, ExecContext::sequential());
  if (!topo) return Status(topo.status().code(), "collision body: " + topo.status().message());
  if (!topo->closed())
    return Status(ErrorCode::kTopology, "collision body is not closed: " + topo->open_message() +
                                            " (inside and clearance need a closed, oriented body)");
  auto out = std::make_shared<CollisionTopology>();
  out->topo_ = std::move(*topo);
  return std::shared_ptr<const CollisionTopology>(std::move(out));
}

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
    auto* idx = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(s->geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                    3 * sizeof(std::uint32_t), tris.size()));
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

// ------------------------------------------------------------ body

Status CollisionBody::build(std::shared_ptr<const CollisionTopology> topology, std::span<const Vec3d> positions,
                            const CollisionBodyParams& /*params: see its comment*/, const ExecContext& ctx) {
  // A scene lent before goes back to the pool first, so that rebuilding a
  // body reuses it.
  scene_.reset();
  topo_.reset();
  if (!topology) return Status(ErrorCode::kInvalidArgument, "collision body: no topology");
  if (positions.size() != topology->point_count())
    return Status(ErrorCode::kMismatch, "collision body: " + std::to_string(positions.size()) +
                                            " positions for a topology of " + std::to_string(topology->point_count()) +
                                            " points");
  // Largest coordinate: Embree's vertices are floats, and the culling
  // margins are relative to it. (A nanosecond per point: not worth a
  // parallel loop's start-up.)
  double extent = 0;
  for (const Vec3d& q : positions) {
    if (!is_finite(q)) return Status(ErrorCode::kDegenerate, "collision body: non-finite position");
    extent = std::max(extent, q.cwiseAbs().maxCoeff());
  }
  if (!(extent < 1e30))
    return Status(ErrorCode::kInvalidArgument,
                  "collision body: a coordinate of magnitude " + std::to_string(extent) + " is beyond float range");
  const CollisionTopology& tp = *topology;
  std::call_once(tp.embree_once_, [&] {
    auto pool = std::make_shared<CollisionTopology::EmbreePool>();
    pool->device = rtcNewDevice("verbose=0");
    if (pool->device) rtcSetDeviceErrorFunction(pool->device, &CollisionTopology::EmbreePool::on_error, pool.get());
    tp.embree_pool_ = std::move(pool);
  });
  const auto& pool = tp.embree_pool_;
  if (!pool->device) return Status(ErrorCode::kInternal, "collision body: rtcNewDevice failed");
  auto scene = CollisionTopology::EmbreePool::lend(pool, tp);
  if (!scene) {
    if (Status s = pool->check("scene"); !s) return s;
    return Status(ErrorCode::kInternal, "collision body: could not make an Embree scene");
  }
  ExecContext lctx = ctx;
  lctx.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 4096);
  if (ctx.grain == 0) lctx.grain = 2048;
  float* v = scene->vertices;
  par::for_each_n(lctx, positions.size(), [&](std::size_t i) {
    for (int a = 0; a < 3; ++a) v[3 * i + a] = static_cast<float>(positions[i][a]);
  });
  if (scene->built) rtcUpdateGeometryBuffer(scene->geom, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(scene->geom);
  par::in_arena(ctx, [&] { rtcCommitScene(scene->scene); });
  if (Status s = pool->check("commit"); !s) {
    scene->broken = true;
    return s;
  }
  scene->built = true;
  pos_ = positions;
  extent_ = extent;
  topo_ = std::move(topology);
  scene_ = std::move(scene);
  return Status::ok();
}

BodyDistance CollisionBody::query_triangle(const Vec3d& p, std::uint32_t t) const noexcept {
  const Triangle& tr = topo_->triangles()[t];
  return signed_distance(p, t, closest_point_on_triangle(p, pos_[tr[0]], pos_[tr[1]], pos_[tr[2]]));
}

BodyDistance CollisionBody::signed_distance(const Vec3d& p, std::uint32_t t, const TrianglePoint& r) const noexcept {
  // The pseudo-normal of the closest feature, computed on demand (most
  // queries land on faces), and the sign rule of triangle_query.h.
  const Vec3d pn = pseudo_normal(topo_->triangle_topology(), pos_, t, r.feature);
  BodyDistance out;
  out.closest = r.point;
  out.barycentric = r.barycentric;
  out.triangle = t;
  const Vec3d d = p - r.point;
  const double len = d.norm();
  const double sign = pseudo_normal_sign(p, r.point, pn);
  out.distance = sign * len;
  // Outward direction: the distance gradient off the surface, the
  // pseudo-normal on it.
  const double pl = pn.norm();
  out.normal = len > 1e-12 ? Vec3d(sign * d / len) : (pl > 0 ? Vec3d(pn / pl) : Vec3d::UnitZ());
  return out;
}

// The best triangle so far: smallest squared distance (exact, double), ties
// to the smaller triangle index, so the answer depends neither on the order
// in which Embree visits the triangles nor on the hint.
struct CollisionBody::Best {
  double d2 = std::numeric_limits<double>::infinity();
  std::uint32_t t = kNoTriangle;
  TrianglePoint r;
  bool take(double d, std::uint32_t tri, const TrianglePoint& at) noexcept {
    if (d < d2 || (d == d2 && tri < t)) {
      d2 = d;
      t = tri;
      r = at;
      return true;
    }
    return false;
  }
};

CollisionBody::Best CollisionBody::start_from_hint(const Vec3d& p, std::uint32_t hint) const noexcept {
  Best b;
  if (hint < topo_->triangles().size()) {
    // On a body of the same topology the hint's distance bounds the answer.
    // (A greedy walk from the hint to nearer neighbours tightened the bound
    // but cost more than it pruned: 12% slower queries on MakeHuman bodies,
    // measured with the former hand-written hierarchy.)
    const Triangle& tr = topo_->triangles()[hint];
    b.r = closest_point_on_triangle(p, pos_[tr[0]], pos_[tr[1]], pos_[tr[2]]);
    b.d2 = (p - b.r.point).squaredNorm();
    b.t = hint;
  }
  return b;
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

BodyDistance CollisionBody::query(const Vec3d& p, std::uint32_t hint) const noexcept {
  Best best = start_from_hint(p, hint);
  Nearest<Best> u{topo_->triangles().data(), pos_.data(), p, cull_margin(extent_, p), &best};
  RTCPointQuery q;
  set_point(q, p, best.t == kNoTriangle ? std::numeric_limits<float>::infinity() : cull_radius(best.d2, u.margin));
  RTCPointQueryContext qc;
  rtcInitPointQueryContext(&qc);
  rtcPointQuery(scene_->scene, &q, &qc, &visit_nearest<Best>, &u);
  if (best.t == kNoTriangle) return {};  // a non-finite point
  return signed_distance(p, best.t, best.r);
}

// Single queries in parallel. (Clusters of 8 neighbours sharing one
// rtcPointQuery, a sphere around the cluster's box collecting every
// point's candidates as the former hierarchy did with its leaves, gathered
// 147 triangles on average on the MakeHuman garment and overflowed a cap of
// 192 in half the clusters: 8.8 ms against 5.4 ms for its 8,426 vertices one
// by one. Ordering the points by hint first changed nothing either.)
Status CollisionBody::query_many(std::span<const Vec3d> p, std::span<const std::uint32_t> hint,
                                 std::span<BodyDistance> out, const ExecContext& ctx) const {
  const std::size_t n = p.size();
  if (empty()) return Status(ErrorCode::kInvalidArgument, "query_many: collision body not built");
  if (out.size() != n || (!hint.empty() && hint.size() != n))
    return Status(ErrorCode::kMismatch, "query_many: " + std::to_string(n) + " points, " + std::to_string(hint.size()) +
                                            " hints and " + std::to_string(out.size()) + " outputs");
  // Queries are about a microsecond each: split much smaller loops than the
  // default threshold assumes.
  ExecContext qctx = ctx;
  qctx.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 256);
  if (ctx.grain == 0) qctx.grain = 64;
  par::for_each_n(qctx, n, [&](std::size_t v) { out[v] = query(p[v], hint.empty() ? kNoTriangle : hint[v]); });
  return Status::ok();
}

}  // namespace atelier
