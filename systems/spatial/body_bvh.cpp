// BodyBvh implementation: the only file of Atelier that includes Embree.
#include <atelier/systems/spatial/body_bvh.h>

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <mutex>
#include <numbers>
#include <string>

#include <atelier/engine/parallel.h>

namespace atelier {

// ---------------------------------------------------------------------- Impl

struct BodyBvh::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  RTCGeometry geom = nullptr;
  bool committed = false;

  StridedPoints view;
  BvhParams params;
  std::vector<Triangle> tris;  // size n + 1: Embree may read past the last index triple
  std::size_t num_tris = 0;
  std::vector<Vec3d> pos;
  std::vector<float> fpos;  // padded float copy when the view cannot be shared
  const void* embree_vertices = nullptr;
  std::size_t embree_stride = 0;
  const void* bound_vertices = nullptr;  // what the Embree geometry currently points at
  std::size_t bound_stride = 0;
  bool shared = false;
  std::vector<std::uint8_t> used;

  // Pseudo-normals (Baerentzen & Aanaes 2005, section 3).
  // Computed once per commit from systems/spatial/triangle_query.h, so
  // that they equal the collision body's on-demand ones bit for bit.
  TriangleTopology topo;
  std::vector<Vec3d> face_n;                 // unit face normals
  std::vector<std::array<Vec3d, 3>> edge_n;  // sum of the two unit face normals
  std::vector<Vec3d> vert_n;                 // angle-weighted vertex normals

  Box3d box;
  double scale = 0.0;  // max |coordinate|, for the culling margin

  std::mutex error_mutex;
  std::string last_error;
  const CancelToken* cancel = nullptr;

  ~Impl() { release(); }
  void release() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
    scene = nullptr;
    device = nullptr;
    geom = nullptr;
    committed = false;
    bound_vertices = nullptr;
    bound_stride = 0;
  }
  [[nodiscard]] const Vec3d& corner(std::uint32_t t, int k) const noexcept { return pos[tris[t][k]]; }
};

namespace {

void embree_error(void* user, RTCError code, const char* str) {
  auto* im = static_cast<BodyBvh::Impl*>(user);
  std::lock_guard<std::mutex> lock(im->error_mutex);
  im->last_error = std::string("Embree error ") + std::to_string(static_cast<int>(code)) + ": " + (str ? str : "");
}

bool embree_progress(void* user, double) {
  const auto* im = static_cast<const BodyBvh::Impl*>(user);
  const bool go_on = !(im->cancel && im->cancel->cancelled());
  par::tsan_release(im);  // called on Embree's threads: see commit_impl
  return go_on;
}

Status check_device(BodyBvh::Impl& im, const char* what) {
  const RTCError e = rtcGetDeviceError(im.device);
  if (e == RTC_ERROR_NONE) return Status::ok();
  if (e == RTC_ERROR_CANCELLED) return {ErrorCode::kCancelled, std::string(what) + ": cancelled"};
  std::lock_guard<std::mutex> lock(im.error_mutex);
  return {ErrorCode::kInternal, std::string(what) + ": " + im.last_error};
}

void compute_normals(BodyBvh::Impl& im, const ExecContext& ctx) {
  const std::size_t n = im.num_tris;
  const std::span<const Vec3d> pos = im.pos;
  im.face_n.resize(n);
  par::for_each_n(ctx, n, [&](std::size_t t) { im.face_n[t] = unit_face_normal(im.tris[t], pos); });
  im.edge_n.resize(n);
  par::for_each_n(ctx, n, [&](std::size_t t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t o = im.topo.across(static_cast<std::uint32_t>(t), k);
      im.edge_n[t][k] = o == kNoTriangle ? im.face_n[t] : Vec3d(im.face_n[t] + im.face_n[o]);
    }
  });
  // Angle-weighted vertex normals, each gathered over its triangles in
  // triangle order: the sums do not depend on scheduling.
  im.vert_n.resize(im.pos.size());
  par::for_each_n(ctx, im.pos.size(), [&](std::size_t v) {
    im.vert_n[v] = vertex_pseudo_normal(im.topo, pos, static_cast<std::uint32_t>(v));
  });
}

Status read_positions(BodyBvh::Impl& im, const ExecContext& ctx) {
  const StridedPoints& v = im.view;
  const std::size_t n = v.count;
  im.pos.resize(n);
  par::for_each_n(ctx, n, [&](std::size_t i) { im.pos[i] = v[i]; });
  // Referenced points must be finite (report the smallest bad index).
  for (std::size_t i = 0; i < n; ++i) {
    if (im.used[i] && !im.pos[i].allFinite()) {
      return {ErrorCode::kDegenerate, "BodyBvh: point " + std::to_string(i) + " has a non-finite coordinate"};
    }
  }
  Box3d box;
  for (std::size_t i = 0; i < n; ++i) {
    if (im.used[i]) box.extend(im.pos[i]);
  }
  im.box = box;
  im.scale = std::max(box.lo.cwiseAbs().maxCoeff(), box.hi.cwiseAbs().maxCoeff());
  // Embree's vertex buffer: the caller's floats when a 16-byte load of the
  // last vertex stays inside the caller's memory, else a padded float copy.
  im.shared = v.scalar == StridedPoints::Scalar::kFloat && (v.padded || v.stride >= 16) && v.stride % 4 == 0;
  if (im.shared) {
    im.fpos.clear();
    im.fpos.shrink_to_fit();
    im.embree_vertices = v.data;
    im.embree_stride = v.stride;
  } else {
    im.fpos.resize(3 * n + 1);
    im.fpos[3 * n] = 0.0f;
    par::for_each_n(ctx, n, [&](std::size_t i) {
      // Unused points may hold anything (dead slots): give Embree zeros.
      const Vec3d p = im.used[i] ? im.pos[i] : Vec3d::Zero();
      im.fpos[3 * i + 0] = static_cast<float>(p.x());
      im.fpos[3 * i + 1] = static_cast<float>(p.y());
      im.fpos[3 * i + 2] = static_cast<float>(p.z());
    });
    im.embree_vertices = im.fpos.data();
    im.embree_stride = 3 * sizeof(float);
  }
  return Status::ok();
}

Status commit_impl(BodyBvh::Impl& im, const ExecContext& ctx) {
  if (!im.device) return {ErrorCode::kInvalidArgument, "BodyBvh: commit() before build()"};
  if (ctx.cancelled()) return {ErrorCode::kCancelled, "BodyBvh: cancelled"};
  if (Status s = read_positions(im, ctx); !s) return s;
  compute_normals(im, ctx);
  if (ctx.cancelled()) return {ErrorCode::kCancelled, "BodyBvh: cancelled"};
  // Same buffer as before: tell Embree it changed, so a REFIT geometry is
  // refit rather than rebuilt. A new buffer is bound afresh.
  if (im.committed && im.bound_vertices == im.embree_vertices && im.bound_stride == im.embree_stride) {
    rtcUpdateGeometryBuffer(im.geom, RTC_BUFFER_TYPE_VERTEX, 0);
  } else {
    rtcSetSharedGeometryBuffer(im.geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, im.embree_vertices, 0,
                               im.embree_stride, im.view.count);
    im.bound_vertices = im.embree_vertices;
    im.bound_stride = im.embree_stride;
  }
  rtcCommitGeometry(im.geom);
  im.cancel = &ctx.cancel;
  par::in_arena(ctx, [&] { rtcCommitScene(im.scene); });
  par::tsan_acquire(&im);  // the progress callbacks Embree ran on its threads happened before
  im.cancel = nullptr;
  if (Status s = check_device(im, "BodyBvh commit"); !s) {
    im.committed = false;
    return s;
  }
  im.committed = true;
  return Status::ok();
}

// --------------------------------------------------------------- point query

struct PointQueryUser {
  const BodyBvh::Impl* im;
  Vec3d p;
  double margin;
  ClosestHit best;
};

bool point_query_callback(RTCPointQueryFunctionArguments* args) {
  auto* u = static_cast<PointQueryUser*>(args->userPtr);
  const std::uint32_t t = args->primID;
  const BodyBvh::Impl& im = *u->im;
  const TrianglePoint r = closest_point_on_triangle(u->p, im.corner(t, 0), im.corner(t, 1), im.corner(t, 2));
  const double d = (u->p - r.point).norm();
  if (d < u->best.distance || (d == u->best.distance && t < u->best.triangle)) {
    u->best = {r.point, r.barycentric, d, t, r.feature};
    // Shrink the search sphere, but keep a margin: Embree culls with float
    // boxes of float vertices, our distances are in double, and ties must all
    // be visited for the smallest-index rule.
    const float radius = static_cast<float>(d * (1.0 + 1e-6) + u->margin);
    if (radius < args->query->radius) {
      args->query->radius = radius;
      return true;
    }
  }
  return false;
}

}  // namespace

// ------------------------------------------------------------------ BodyBvh

BodyBvh::BodyBvh() : impl_(std::make_unique<Impl>()) {}
BodyBvh::~BodyBvh() = default;
BodyBvh::BodyBvh(BodyBvh&&) noexcept = default;
BodyBvh& BodyBvh::operator=(BodyBvh&&) noexcept = default;

Status BodyBvh::build(const StridedPoints& points, std::span<const Triangle> triangles, const BvhParams& params,
                      const ExecContext& ctx) {
  if (!impl_) impl_ = std::make_unique<Impl>();
  Impl& im = *impl_;
  im.release();
  im.num_tris = 0;
  im.tris.clear();
  im.pos.clear();
  if (triangles.empty() || points.count == 0) {
    return {ErrorCode::kInvalidArgument, "BodyBvh: empty mesh (" + std::to_string(points.count) + " points, " +
                                             std::to_string(triangles.size()) + " triangles)"};
  }
  constexpr std::size_t kMax = std::numeric_limits<std::uint32_t>::max() - 1;
  if (points.count > kMax || triangles.size() > kMax) {
    return {ErrorCode::kInvalidArgument, "BodyBvh: more than 2^32-2 points or triangles"};
  }
  const std::size_t scalar_size = points.scalar == StridedPoints::Scalar::kFloat ? sizeof(float) : sizeof(double);
  if (!points.data || points.stride < 3 * scalar_size || points.stride % scalar_size != 0) {
    return {ErrorCode::kInvalidArgument,
            "BodyBvh: bad point view (null data or stride " + std::to_string(points.stride) + " bytes)"};
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      if (triangles[t][k] >= points.count) {
        return {ErrorCode::kInvalidArgument, "BodyBvh: triangle " + std::to_string(t) + " uses point " +
                                                 std::to_string(triangles[t][k]) + " but there are only " +
                                                 std::to_string(points.count) + " points"};
      }
    }
  }
  im.view = points;
  im.params = params;
  im.num_tris = triangles.size();
  im.tris.resize(im.num_tris + 1);
  std::copy(triangles.begin(), triangles.end(), im.tris.begin());
  im.tris.back() = {0, 0, 0};
  im.used.assign(points.count, 0);
  for (const Triangle& t : triangles) {
    for (std::uint32_t v : t) im.used[v] = 1;
  }
  auto topo = TriangleTopology::build(triangles, static_cast<std::uint32_t>(points.count), ctx);
  if (!topo) return {topo.status().code(), "BodyBvh: " + topo.status().message()};
  im.topo = std::move(*topo);

  im.device = rtcNewDevice("verbose=0");
  if (!im.device) return {ErrorCode::kInternal, "BodyBvh: rtcNewDevice failed"};
  rtcSetDeviceErrorFunction(im.device, embree_error, &im);
  im.scene = rtcNewScene(im.device);
  rtcSetSceneFlags(im.scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(im.scene, params.build_quality <= 0   ? RTC_BUILD_QUALITY_LOW
                                    : params.build_quality == 1 ? RTC_BUILD_QUALITY_MEDIUM
                                                                : RTC_BUILD_QUALITY_HIGH);
  rtcSetSceneProgressMonitorFunction(im.scene, embree_progress, &im);
  im.geom = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  if (params.refit_on_commit) rtcSetGeometryBuildQuality(im.geom, RTC_BUILD_QUALITY_REFIT);
  rtcSetSharedGeometryBuffer(im.geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, im.tris.data(), 0, sizeof(Triangle),
                             im.num_tris);
  // The scene holds the geometry; our pointer stays valid while the scene lives.
  rtcAttachGeometryByID(im.scene, im.geom, 0);
  rtcReleaseGeometry(im.geom);
  if (Status s = check_device(im, "BodyBvh build"); !s) return s;
  Status s = commit_impl(im, ctx);
  if (!s) {
    im.release();
    im.num_tris = 0;
  }
  return s;
}

Status BodyBvh::commit(const ExecContext& ctx) {
  return commit_impl(*impl_, ctx);
}

Status BodyBvh::commit(const StridedPoints& points, const ExecContext& ctx) {
  Impl& im = *impl_;
  if (points.count != im.view.count) {
    return {ErrorCode::kMismatch, "BodyBvh::commit: " + std::to_string(points.count) + " points, built with " +
                                      std::to_string(im.view.count) + " (topology changes need build())"};
  }
  const std::size_t scalar_size = points.scalar == StridedPoints::Scalar::kFloat ? sizeof(float) : sizeof(double);
  if (!points.data || points.stride < 3 * scalar_size || points.stride % scalar_size != 0) {
    return {ErrorCode::kInvalidArgument, "BodyBvh::commit: bad point view"};
  }
  im.view = points;
  return commit_impl(im, ctx);
}

bool BodyBvh::empty() const noexcept {
  return !impl_ || !impl_->committed;
}
std::size_t BodyBvh::num_triangles() const noexcept {
  return impl_ ? impl_->num_tris : 0;
}
std::size_t BodyBvh::num_points() const noexcept {
  return impl_ ? impl_->pos.size() : 0;
}
std::span<const Vec3d> BodyBvh::positions() const noexcept {
  return impl_->pos;
}
std::span<const Triangle> BodyBvh::triangles() const noexcept {
  return {impl_->tris.data(), impl_->num_tris};
}
bool BodyBvh::zero_copy() const noexcept {
  return impl_->shared;
}
Box3d BodyBvh::bounds() const noexcept {
  return impl_->box;
}
bool BodyBvh::closed() const noexcept {
  return impl_ && impl_->committed && impl_->topo.closed();
}
Status BodyBvh::require_closed() const {
  if (empty()) return {ErrorCode::kInvalidArgument, "BodyBvh: not built"};
  if (!impl_->topo.closed())
    return {ErrorCode::kTopology, "BodyBvh: mesh is not closed and oriented: " + impl_->topo.open_message()};
  return Status::ok();
}

ClosestHit BodyBvh::closest_point(const Vec3d& p) const noexcept {
  return closest_point(p, std::numeric_limits<double>::infinity());
}

ClosestHit BodyBvh::closest_point(const Vec3d& p, double bound) const noexcept {
  const Impl& im = *impl_;
  if (!im.committed || !p.allFinite()) return {};
  const double margin = 1e-6 * (im.scale + p.cwiseAbs().maxCoeff());
  RTCPointQuery q;
  q.x = static_cast<float>(p.x());
  q.y = static_cast<float>(p.y());
  q.z = static_cast<float>(p.z());
  q.time = 0.0f;
  RTCPointQueryContext pctx;
  if (bound >= 0.0 && std::isfinite(bound)) {
    // Every triangle within `bound` has its box within the first radius, so
    // a best hit within `bound` is the same one the unbounded search finds.
    PointQueryUser user{&im, p, margin, {}};
    q.radius = static_cast<float>(bound * (1.0 + 1e-6) + margin);
    rtcInitPointQueryContext(&pctx);
    rtcPointQuery(im.scene, &q, &pctx, point_query_callback, &user);
    if (user.best.distance <= bound) return user.best;
  }
  PointQueryUser user{&im, p, margin, {}};
  q.radius = std::numeric_limits<float>::infinity();
  rtcInitPointQueryContext(&pctx);
  rtcPointQuery(im.scene, &q, &pctx, point_query_callback, &user);
  return user.best;
}

namespace {

template <class T, class F>
Status batched(const char* what, bool ready, std::span<const Vec3d> in, std::span<T> out, const ExecContext& ctx,
               F&& f) {
  if (!ready) return {ErrorCode::kInvalidArgument, std::string(what) + ": BVH not built"};
  if (in.size() != out.size()) {
    return {ErrorCode::kMismatch, std::string(what) + ": " + std::to_string(in.size()) + " inputs, " +
                                      std::to_string(out.size()) + " outputs"};
  }
  std::atomic<bool> stopped{false};
  par::for_each_block(ctx, in.size(), [&](std::size_t b, std::size_t e) {
    if (ctx.cancelled()) {
      stopped.store(true, std::memory_order_relaxed);
      return;
    }
    for (std::size_t i = b; i < e; ++i) out[i] = f(in[i]);
  });
  if (stopped.load()) return {ErrorCode::kCancelled, std::string(what) + ": cancelled"};
  return Status::ok();
}

}  // namespace

Status BodyBvh::closest_points(std::span<const Vec3d> in, std::span<ClosestHit> out, const ExecContext& ctx) const {
  return batched("BodyBvh::closest_points", !empty(), in, out, ctx,
                 [this](const Vec3d& p) { return closest_point(p); });
}

RayHit BodyBvh::ray_first_hit(const Vec3d& origin, const Vec3d& dir, double tmax) const noexcept {
  const Impl& im = *impl_;
  RayHit out;
  if (!im.committed || !origin.allFinite() || !dir.allFinite() || dir.squaredNorm() == 0.0 || !(tmax >= 0.0)) {
    return out;
  }
  RTCIntersectContext ictx;
  rtcInitIntersectContext(&ictx);
  RTCRayHit rh;
  rh.ray.org_x = static_cast<float>(origin.x());
  rh.ray.org_y = static_cast<float>(origin.y());
  rh.ray.org_z = static_cast<float>(origin.z());
  rh.ray.dir_x = static_cast<float>(dir.x());
  rh.ray.dir_y = static_cast<float>(dir.y());
  rh.ray.dir_z = static_cast<float>(dir.z());
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = tmax >= static_cast<double>(std::numeric_limits<float>::max()) ? std::numeric_limits<float>::infinity()
                                                                               : static_cast<float>(tmax);
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(im.scene, &ictx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return out;
  const std::uint32_t t = rh.hit.primID;
  out.hit = true;
  out.triangle = t;
  out.t = rh.ray.tfar;
  out.barycentric = {1.0 - rh.hit.u - rh.hit.v, rh.hit.u, rh.hit.v};
  // Refine in double on the hit triangle (Moller-Trumbore): Embree works in
  // float, the collision pass wants the surface point to double precision.
  const Vec3d& a = im.corner(t, 0);
  const Vec3d e1 = im.corner(t, 1) - a, e2 = im.corner(t, 2) - a;
  const Vec3d pv = dir.cross(e2);
  const double det = e1.dot(pv);
  if (det != 0.0) {
    const double inv = 1.0 / det;
    const Vec3d tv = origin - a;
    const double u = tv.dot(pv) * inv;
    const Vec3d qv = tv.cross(e1);
    const double v = dir.dot(qv) * inv;
    const double tt = e2.dot(qv) * inv;
    if (std::isfinite(tt) && tt >= 0.0 && tt <= tmax) {
      out.t = tt;
      out.barycentric = {1.0 - u - v, u, v};
    }
  }
  out.point = origin + out.t * dir;
  out.normal = im.face_n[t];
  return out;
}

Status BodyBvh::ray_first_hits(std::span<const Vec3d> origins, std::span<const Vec3d> dirs, std::span<RayHit> out,
                               const ExecContext& ctx) const {
  if (dirs.size() != origins.size()) {
    return {ErrorCode::kMismatch, "BodyBvh::ray_first_hits: origins and directions differ in size"};
  }
  const Vec3d* d0 = dirs.data();
  const Vec3d* o0 = origins.data();
  return batched("BodyBvh::ray_first_hits", !empty(), origins, out, ctx,
                 [&](const Vec3d& o) { return ray_first_hit(o, d0[&o - o0]); });
}

SignedHit BodyBvh::signed_distance_to(const Vec3d& p, std::uint32_t t) const noexcept {
  const Impl& im = *impl_;
  SignedHit out;
  if (!im.committed || t >= im.num_tris) return out;
  const TrianglePoint r = closest_point_on_triangle(p, im.corner(t, 0), im.corner(t, 1), im.corner(t, 2));
  const double d = (p - r.point).norm();
  out.closest = {r.point, r.barycentric, d, t, r.feature};
  Vec3d n = im.face_n[t];
  switch (r.feature) {
    case TriFeature::kVertex0:
      n = im.vert_n[im.tris[t][0]];
      break;
    case TriFeature::kVertex1:
      n = im.vert_n[im.tris[t][1]];
      break;
    case TriFeature::kVertex2:
      n = im.vert_n[im.tris[t][2]];
      break;
    case TriFeature::kEdge01:
      n = im.edge_n[t][0];
      break;
    case TriFeature::kEdge12:
      n = im.edge_n[t][1];
      break;
    case TriFeature::kEdge20:
      n = im.edge_n[t][2];
      break;
    case TriFeature::kFace:
      break;
  }
  // Baerentzen & Aanaes, theorem 1: sign of (p - c) . n_pseudo at the closest
  // feature is the inside/outside sign for a closed oriented mesh.
  out.distance = pseudo_normal_sign(p, r.point, n) * d;
  const double len = n.norm();
  out.normal = len > 0.0 ? Vec3d(n / len) : Vec3d::Zero();
  return out;
}

SignedHit BodyBvh::signed_distance(const Vec3d& p) const noexcept {
  return signed_distance(p, std::numeric_limits<double>::infinity());
}

SignedHit BodyBvh::signed_distance(const Vec3d& p, double bound) const noexcept {
  const ClosestHit c = closest_point(p, bound);
  if (c.triangle == kNoTriangle) return {};
  return signed_distance_to(p, c.triangle);
}

Status BodyBvh::signed_distances(std::span<const Vec3d> in, std::span<double> out, const ExecContext& ctx) const {
  if (Status s = require_closed(); !s) return s;
  return batched("BodyBvh::signed_distances", !empty(), in, out, ctx,
                 [this](const Vec3d& p) { return signed_distance(p).distance; });
}

Status BodyBvh::inside_many(std::span<const Vec3d> in, std::span<std::uint8_t> out, const ExecContext& ctx) const {
  if (Status s = require_closed(); !s) return s;
  return batched("BodyBvh::inside_many", !empty(), in, out, ctx,
                 [this](const Vec3d& p) { return static_cast<std::uint8_t>(signed_distance(p).distance < 0.0); });
}

double BodyBvh::winding_number(const Vec3d& p) const noexcept {
  const Impl& im = *impl_;
  if (!im.committed) return 0.0;
  // Van Oosterom & Strackee: tan(Omega / 2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|).
  double sum = 0.0;
  for (std::uint32_t t = 0; t < im.num_tris; ++t) {
    const Vec3d a = im.corner(t, 0) - p, b = im.corner(t, 1) - p, c = im.corner(t, 2) - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    sum += 2.0 * std::atan2(num, den);
  }
  return sum / (4.0 * std::numbers::pi);
}

Status BodyBvh::winding_numbers(std::span<const Vec3d> in, std::span<double> out, const ExecContext& ctx) const {
  ExecContext c = ctx;
  c.grain = ctx.grain ? ctx.grain : 16;  // each point costs a pass over all triangles
  c.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 64);
  return batched("BodyBvh::winding_numbers", !empty(), in, out, c,
                 [this](const Vec3d& p) { return winding_number(p); });
}

}  // namespace atelier
