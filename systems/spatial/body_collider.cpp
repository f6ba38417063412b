#include <atelier/systems/spatial/body_collider.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include <atelier/systems/spatial/sdf_grid.h>
#include <atelier/systems/mesh/fan_triangulation.h>

namespace atelier {

struct BodyCollider::Impl {
  std::vector<Vec3d> positions;  // own copy: the BVH keeps a view of it
  SurfaceTriangles tris;
  BodyBvh bvh;
  SdfGrid grid;
  bool has_grid = false;
  double exact_band = 0;  // |grid value| below this: ask the BVH
  double grid_ms = 0;
  double radius = 0.03;
  // What update() needs to redo the per-body part.
  const Model* body = nullptr;
  SurfaceIdx skin;
  Box3d roi;
  ColliderParams params;
};

BodyCollider::BodyCollider() : impl_(std::make_unique<Impl>()) {}
BodyCollider::~BodyCollider() = default;
BodyCollider::BodyCollider(BodyCollider&&) noexcept = default;
BodyCollider& BodyCollider::operator=(BodyCollider&&) noexcept = default;

Status BodyCollider::build(const Model& body, SurfaceIdx skin, std::span<const Vec3d> positions, const Box3d& roi,
                           const ColliderParams& params, const ExecContext& ctx) {
  Impl& I = *impl_;
  I.body = nullptr;  // not reusable until this build succeeds
  if (positions.size() < body.nodes.slots.capacity())
    return Status(ErrorCode::kMismatch, "collider: " + std::to_string(positions.size()) + " positions for " +
                                            std::to_string(body.nodes.slots.capacity()) + " body nodes");
  I.positions.assign(positions.begin(), positions.begin() + static_cast<std::ptrdiff_t>(body.nodes.slots.capacity()));
  auto t = fan_triangulate(body, std::vector<SurfaceIdx>{skin});
  if (!t) return t.status();
  I.tris = std::move(*t);
  if (Status s = I.bvh.build(std::span<const Vec3d>(I.positions), I.tris.triangles, {}, ctx); !s) return s;
  if (Status s = I.bvh.require_closed(); !s) return Status(s.code(), "collider: body surface: " + s.message());
  I.body = &body;
  I.skin = skin;
  I.roi = roi;
  I.params = params;
  return build_grid(ctx);
}

bool BodyCollider::built() const noexcept { return impl_->body != nullptr && !impl_->bvh.empty(); }

bool BodyCollider::reusable_for(const Model& body, SurfaceIdx skin, const Box3d& roi,
                                const ColliderParams& params) const noexcept {
  const Impl& I = *impl_;
  const auto same_box = [](const Box3d& a, const Box3d& b) {
    return a.empty() == b.empty() && (a.empty() || (a.lo == b.lo && a.hi == b.hi));
  };
  return built() && I.body == &body && I.skin == skin && I.positions.size() == body.nodes.slots.capacity() &&
         I.tris.triangles.size() >= body.num_faces() && same_box(I.roi, roi) && I.params.use_grid == params.use_grid &&
         I.params.voxel_size == params.voxel_size && I.params.margin == params.margin &&
         I.params.query_radius == params.query_radius;
}

Status BodyCollider::update(std::span<const Vec3d> positions, const ExecContext& ctx) {
  Impl& I = *impl_;
  if (!built()) return Status(ErrorCode::kInvalidArgument, "collider: update() before build()");
  if (positions.size() < I.positions.size())
    return Status(ErrorCode::kMismatch, "collider: " + std::to_string(positions.size()) + " positions for " +
                                            std::to_string(I.positions.size()) + " body nodes");
  std::copy_n(positions.begin(), I.positions.size(), I.positions.begin());
  for (const auto& t : I.tris.triangles)
    for (std::uint32_t v : t)
      if (!I.positions[v].allFinite())
        return Status(ErrorCode::kDegenerate, "collider: body node " + std::to_string(v) + " is not finite");
  // The same memory, so the BVH's view is still right: commit re-reads it.
  if (Status s = I.bvh.commit(ctx); !s) return s;
  return build_grid(ctx);
}

Status BodyCollider::build_grid(const ExecContext& ctx) {
  Impl& I = *impl_;
  const ColliderParams& params = I.params;
  const Box3d& roi = I.roi;
  I.has_grid = false;
  I.radius = params.query_radius;
  if (params.use_grid) {
    const auto t0 = std::chrono::steady_clock::now();
    SdfParams sp;
    sp.voxel_size = params.voxel_size;
    if (!roi.empty()) {
      Box3d b = roi;
      b.lo.array() -= params.margin;
      b.hi.array() += params.margin;
      sp.roi.push_back(b);
    }
    if (Status s = I.grid.build(I.bvh, sp, ctx); !s) return s;
    I.has_grid = true;
    I.exact_band = sp.exact_band * sp.voxel_size;
    I.grid_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  return {};
}

double BodyCollider::signed_distance(const Vec3d& p) const {
  const Impl& I = *impl_;
  if (I.has_grid && I.grid.covers(p)) {
    const double d = I.grid.sample(p);
    // Far from the surface the grid's magnitude is a safe stand-in (the
    // fairing only needs "how far, roughly") and inside() gives the sign
    // (its contract covers regions without flood fill); near the surface
    // only the exact answer will do.
    if (std::isfinite(d) && std::abs(d) >= I.exact_band) return I.grid.inside(p) ? -std::abs(d) : std::abs(d);
  }
  return exact(p).distance;
}

SignedHit BodyCollider::exact(const Vec3d& p) const noexcept {
  const Impl& I = *impl_;
  // Successive queries of a thread come from nearby points (a node's
  // sub-steps, neighbouring nodes): the distance to the previous answer's
  // triangle bounds this one, so the BVH search starts with a tight sphere.
  // The answer is the exact closest point whatever the bound (ties still go
  // to the smallest triangle index), so the cache never changes a result.
  thread_local const Impl* owner = nullptr;
  thread_local std::uint32_t last = kNoTriangle;
  double bound = I.radius;
  const auto tris = I.bvh.triangles();
  if (owner == &I && last < tris.size()) {
    const auto pos = I.bvh.positions();
    const Triangle& t = tris[last];
    const double d0 = (p - closest_point_on_triangle(p, pos[t[0]], pos[t[1]], pos[t[2]]).point).norm();
    bound = std::min(bound, d0 * (1.0 + 1e-9) + 1e-12);
  }
  const SignedHit h = I.bvh.signed_distance(p, bound);
  owner = &I;
  last = h.closest.triangle;
  return h;
}
const BodyBvh& BodyCollider::bvh() const noexcept { return impl_->bvh; }
bool BodyCollider::has_grid() const noexcept { return impl_->has_grid; }
double BodyCollider::grid_build_ms() const noexcept { return impl_->grid_ms; }


std::unique_ptr<BodyCollider> ColliderPool::acquire() {
  std::lock_guard lock(mutex_);
  if (free_.empty()) return std::make_unique<BodyCollider>();
  auto c = std::move(free_.back());
  free_.pop_back();
  return c;
}

void ColliderPool::release(std::unique_ptr<BodyCollider> c) {
  if (!c) return;
  std::lock_guard lock(mutex_);
  free_.push_back(std::move(c));
}

}  // namespace atelier
