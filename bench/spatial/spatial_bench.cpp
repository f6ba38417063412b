// Spatial queries for collision avoidance (seed 000 section 4.2; issues 4
// and 7): Embree BVH build, exact closest point (near / far), exact signed
// distance, OpenVDB SDF build (full and region of interest) and inside tests
// with the exact fallback, on a 65k-triangle UV sphere with 200k random
// points in its bounding box, and on the MakeHuman skin when
// ../shared/data/makehuman/base.obj is present.
//
// Counters: items/s = queries per second (all threads). Peer figures from
// docs/performance-anchors.md: Embree closest point 1.2-2 M/s near, 0.16-0.25
// M/s far (2 threads); OpenVDB meshToLevelSet build 0.27/0.51/1.24 s at
// 100/200/400 voxels across; trilinear lookups 10-11 M/s per thread; issue
// goal: >= 10 M inside tests per second on 2 cores.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/spatial/sdf_grid.h>

namespace {

using namespace atelier;

struct Mesh {
  std::vector<Vec3d> positions;
  std::vector<Triangle> triangles;
  Box3d box;
};

/// UV sphere of radius 1: 2 * n_lon * (n_lat - 1) triangles.
Mesh uv_sphere(int n_lat, int n_lon) {
  Mesh m;
  m.positions.emplace_back(0, 0, 1);
  for (int i = 1; i < n_lat; ++i) {
    const double th = std::numbers::pi * i / n_lat;
    for (int j = 0; j < n_lon; ++j) {
      const double ph = 2 * std::numbers::pi * j / n_lon;
      m.positions.emplace_back(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    }
  }
  m.positions.emplace_back(0, 0, -1);
  const auto s = static_cast<std::uint32_t>(m.positions.size() - 1);
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(1 + i * n_lon + (j % n_lon)); };
  for (int j = 0; j < n_lon; ++j) m.triangles.push_back({0, id(0, j), id(0, j + 1)});
  for (int i = 0; i + 2 < n_lat; ++i) {
    for (int j = 0; j < n_lon; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  for (int j = 0; j < n_lon; ++j) m.triangles.push_back({id(n_lat - 2, j), s, id(n_lat - 2, j + 1)});
  for (const Vec3d& p : m.positions) m.box.extend(p);
  return m;
}

const Mesh& sphere65k() {
  static const Mesh m = uv_sphere(128, 256);  // 65,024 triangles
  return m;
}

std::uint64_t splitmix(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}
double uniform(std::uint64_t& s) { return double(splitmix(s) >> 11) * 0x1.0p-53; }

/// 200k points uniform in the bounding box ("far": most are far from the surface).
std::vector<Vec3d> box_points(const Box3d& box, std::size_t n, std::uint64_t seed) {
  std::vector<Vec3d> p(n);
  for (auto& q : p) {
    q = {box.lo.x() + (box.hi.x() - box.lo.x()) * uniform(seed), box.lo.y() + (box.hi.y() - box.lo.y()) * uniform(seed),
         box.lo.z() + (box.hi.z() - box.lo.z()) * uniform(seed)};
  }
  return p;
}

/// 200k points within +-1% of the radius from the unit sphere ("near").
std::vector<Vec3d> near_points(std::size_t n, std::uint64_t seed) {
  std::vector<Vec3d> p(n);
  for (auto& q : p) {
    Vec3d d;
    do {
      d = {2 * uniform(seed) - 1, 2 * uniform(seed) - 1, 2 * uniform(seed) - 1};
    } while (d.norm() < 0.1 || d.norm() > 1);
    q = d.normalized() * (0.99 + 0.02 * uniform(seed));
  }
  return p;
}

const std::vector<Vec3d>& far_pts() {
  static const auto p = box_points(sphere65k().box, 200'000, 1);
  return p;
}
const std::vector<Vec3d>& near_pts() {
  static const auto p = near_points(200'000, 2);
  return p;
}

const BodyBvh& sphere_bvh() {
  static const BodyBvh b = [] {
    BodyBvh bvh;
    if (!bvh.build(sphere65k().positions, sphere65k().triangles).is_ok()) std::abort();
    return bvh;
  }();
  return b;
}

ExecContext threads(int n) {
  ExecContext c;
  c.threads = n;
  return c;
}

void fail(benchmark::State& state, const Status& s) { state.SkipWithError(s.to_string().c_str()); }

// ---------------------------------------------------------------- BVH

void BM_BvhBuild_Sphere65k(benchmark::State& state) {
  const Mesh& m = sphere65k();
  for (auto _ : state) {
    BodyBvh bvh;
    const Status s = bvh.build(m.positions, m.triangles, {}, threads(static_cast<int>(state.range(0))));
    if (!s) return fail(state, s);
    benchmark::DoNotOptimize(bvh);
  }
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
}
BENCHMARK(BM_BvhBuild_Sphere65k)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_BvhCommitRefit_Sphere65k(benchmark::State& state) {
  std::vector<Vec3d> pos = sphere65k().positions;
  BodyBvh bvh;
  if (Status s = bvh.build(pos, sphere65k().triangles); !s) return fail(state, s);
  double scale = 1.0;
  for (auto _ : state) {
    scale = scale > 1.1 ? 1.0 : scale * 1.01;
    for (std::size_t i = 0; i < pos.size(); ++i) pos[i] = sphere65k().positions[i] * scale;
    if (Status s = bvh.commit(threads(2)); !s) return fail(state, s);
  }
}
BENCHMARK(BM_BvhCommitRefit_Sphere65k)->Unit(benchmark::kMillisecond)->UseRealTime();

void closest_points_bench(benchmark::State& state, const std::vector<Vec3d>& pts) {
  const BodyBvh& bvh = sphere_bvh();
  std::vector<ClosestHit> out(pts.size());
  const ExecContext ctx = threads(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    if (Status s = bvh.closest_points(pts, out, ctx); !s) return fail(state, s);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pts.size()));
}
void BM_ClosestPoint_Near(benchmark::State& state) { closest_points_bench(state, near_pts()); }
void BM_ClosestPoint_Far(benchmark::State& state) { closest_points_bench(state, far_pts()); }
BENCHMARK(BM_ClosestPoint_Near)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ClosestPoint_Far)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void signed_distance_bench(benchmark::State& state, const std::vector<Vec3d>& pts) {
  const BodyBvh& bvh = sphere_bvh();
  std::vector<double> out(pts.size());
  const ExecContext ctx = threads(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    if (Status s = bvh.signed_distances(pts, out, ctx); !s) return fail(state, s);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pts.size()));
}
void BM_ExactSignedDistance_Near(benchmark::State& state) { signed_distance_bench(state, near_pts()); }
void BM_ExactSignedDistance_Far(benchmark::State& state) { signed_distance_bench(state, far_pts()); }
BENCHMARK(BM_ExactSignedDistance_Near)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ExactSignedDistance_Far)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RayFirstHit(benchmark::State& state) {
  const BodyBvh& bvh = sphere_bvh();
  const std::vector<Vec3d>& o = far_pts();
  std::vector<Vec3d> d(o.size());
  std::uint64_t seed = 5;
  for (auto& v : d) v = Vec3d(2 * uniform(seed) - 1, 2 * uniform(seed) - 1, 2 * uniform(seed) - 1);
  std::vector<RayHit> out(o.size());
  const ExecContext ctx = threads(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    if (Status s = bvh.ray_first_hits(o, d, out, ctx); !s) return fail(state, s);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * o.size()));
}
BENCHMARK(BM_RayFirstHit)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// ---------------------------------------------------------------- SDF

/// A ROI covering one side of the sphere (about where a garment panel would
/// lie): x in [0.5, 1.1], |y|, |z| <= 0.6.
std::vector<Box3d> sphere_roi() { return {Box3d{{0.5, -0.6, -0.6}, {1.1, 0.6, 0.6}}}; }

SdfParams sphere_params(int voxels_across, bool roi) {
  SdfParams p;
  p.voxel_size = 2.0 / voxels_across;
  if (roi) p.roi = sphere_roi();
  return p;
}

void BM_SdfBuild_Sphere65k(benchmark::State& state) {
  const SdfParams params = sphere_params(static_cast<int>(state.range(0)), state.range(1) != 0);
  SdfGrid grid;
  for (auto _ : state) {
    if (Status s = grid.build(sphere_bvh(), params, threads(2)); !s) return fail(state, s);
  }
  state.counters["triangles"] = static_cast<double>(grid.stats().source_triangles);
  state.counters["active_voxels"] = static_cast<double>(grid.stats().active_voxels);
  state.counters["MB"] = static_cast<double>(grid.stats().memory_bytes) / 1e6;
}
BENCHMARK(BM_SdfBuild_Sphere65k)
    ->ArgNames({"voxels", "roi"})
    ->ArgsProduct({{100, 200, 400}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

const SdfGrid& sphere_grid(bool roi) {
  static SdfGrid grids[2];
  SdfGrid& g = grids[roi ? 1 : 0];
  if (g.empty()) {
    if (!g.build(sphere_bvh(), sphere_params(200, roi), threads(2)).is_ok()) std::abort();
  }
  return g;
}

/// inside() with the exact fallback, 200k points in the bounding box
/// (full grid) or in the ROI (ROI grid).
void BM_SdfInside(benchmark::State& state) {
  const bool roi = state.range(1) != 0;
  const SdfGrid& grid = sphere_grid(roi);
  static const auto roi_pts = box_points(sphere_roi()[0], 200'000, 3);
  const std::vector<Vec3d>& pts = roi ? roi_pts : far_pts();
  std::vector<std::uint8_t> out(pts.size());
  const ExecContext ctx = threads(static_cast<int>(state.range(0)));
  InsideStats st;
  for (auto _ : state) {
    if (Status s = grid.inside_many(pts, out, ctx, &st); !s) return fail(state, s);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pts.size()));
  state.counters["exact_fraction"] = double(st.exact) / double(pts.size());
}
BENCHMARK(BM_SdfInside)
    ->ArgNames({"threads", "roi"})
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// Raw trilinear samples (no fallback), batched with one accessor per block.
void BM_SdfSample(benchmark::State& state) {
  const SdfGrid& grid = sphere_grid(false);
  const std::vector<Vec3d>& pts = far_pts();
  std::vector<double> out(pts.size());
  const ExecContext ctx = threads(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    if (Status s = grid.sample_many(pts, out, ctx); !s) return fail(state, s);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pts.size()));
}
BENCHMARK(BM_SdfSample)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

/// One Sampler (cached accessor) in a single-thread loop over near-surface
/// points sorted along the surface (the collision pass walks garment
/// vertices in order, so neighbouring queries share voxels).
void BM_SdfSamplerNearSorted(benchmark::State& state) {
  const SdfGrid& grid = sphere_grid(false);
  static const std::vector<Vec3d> pts = [] {
    std::vector<Vec3d> p = near_pts();
    std::sort(p.begin(), p.end(), [](const Vec3d& a, const Vec3d& b) {
      const double ta = std::atan2(a.y(), a.x()), tb = std::atan2(b.y(), b.x());
      const int ba = static_cast<int>(a.z() * 64), bb = static_cast<int>(b.z() * 64);
      return ba != bb ? ba < bb : ta < tb;
    });
    return p;
  }();
  SdfGrid::Sampler s = grid.sampler();
  for (auto _ : state) {
    double acc = 0;
    for (const Vec3d& p : pts) acc += s.sample(p);
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pts.size()));
}
BENCHMARK(BM_SdfSamplerNearSorted)->Unit(benchmark::kMillisecond);

// ---------------------------------------------------------------- MakeHuman

/// ../shared/data beside the project root (this file is bench/spatial_bench.cpp),
/// or $ATELIER_SHARED_DATA.
std::filesystem::path shared_data() {
  if (const char* env = std::getenv("ATELIER_SHARED_DATA")) return env;
#ifdef ATELIER_SHARED_DATA
  return ATELIER_SHARED_DATA;
#else
  return std::filesystem::path(__FILE__).parent_path().parent_path().parent_path() / "shared" / "data";
#endif
}

/// The `body` group of base.obj (decimetres), quads fan-triangulated.
const Mesh* makehuman_skin() {
  static const Mesh* m = []() -> Mesh* {
    const std::filesystem::path path = shared_data() / "makehuman" / "base.obj";
    std::ifstream in(path);
    if (!in) return nullptr;
    auto* mesh = new Mesh;
    std::string line, group;
    std::vector<std::uint32_t> face;
    while (std::getline(in, line)) {
      if (line.rfind("v ", 0) == 0) {
        Vec3d p;
        if (std::sscanf(line.c_str() + 2, "%lf %lf %lf", &p.x(), &p.y(), &p.z()) == 3) mesh->positions.push_back(p);
      } else if (line.rfind("g ", 0) == 0) {
        group = line.substr(2);
        while (!group.empty() && (group.back() == '\r' || group.back() == ' ')) group.pop_back();
      } else if (line.rfind("f ", 0) == 0 && group == "body") {
        face.clear();
        const char* c = line.c_str() + 2;
        while (*c) {
          while (*c == ' ') ++c;
          if (!*c || *c == '\r') break;
          face.push_back(static_cast<std::uint32_t>(std::strtoul(c, nullptr, 10) - 1));
          while (*c && *c != ' ') ++c;
        }
        for (std::size_t j = 1; j + 1 < face.size(); ++j) mesh->triangles.push_back({face[0], face[j], face[j + 1]});
      }
    }
    for (const Triangle& t : mesh->triangles)
      for (auto v : t) mesh->box.extend(mesh->positions[v]);
    return mesh;
  }();
  return m;
}

void BM_MakeHuman_BvhBuild(benchmark::State& state) {
  const Mesh* m = makehuman_skin();
  if (!m) return state.SkipWithError("../shared/data/makehuman/base.obj not found");
  BodyBvh bvh;
  for (auto _ : state) {
    if (Status s = bvh.build(m->positions, m->triangles, {}, threads(2)); !s) return fail(state, s);
  }
  state.counters["triangles"] = static_cast<double>(m->triangles.size());
  state.counters["closed"] = bvh.closed() ? 1 : 0;
}
BENCHMARK(BM_MakeHuman_BvhBuild)->Unit(benchmark::kMillisecond)->UseRealTime();

/// SDF of the skin: range(0) = voxel size in 0.1 mm (units are decimetres:
/// 20 = 2 mm), range(1) = 1 for a ROI around the torso (where a top lies).
void BM_MakeHuman_SdfBuild(benchmark::State& state) {
  const Mesh* m = makehuman_skin();
  if (!m) return state.SkipWithError("../shared/data/makehuman/base.obj not found");
  static BodyBvh bvh;
  if (bvh.empty()) {
    if (Status s = bvh.build(m->positions, m->triangles, {}, threads(2)); !s) return fail(state, s);
  }
  if (!bvh.closed()) return fail(state, bvh.require_closed());
  SdfParams p;
  p.voxel_size = static_cast<double>(state.range(0)) * 1e-3;  // 0.1 mm in dm
  if (state.range(1)) {
    // Torso: 45-80% of the height (y up), full width and depth.
    const double y0 = m->box.lo.y(), hgt = m->box.hi.y() - m->box.lo.y();
    Box3d roi = m->box;
    roi.lo.y() = y0 + 0.45 * hgt;
    roi.hi.y() = y0 + 0.80 * hgt;
    roi.lo.x() = -0.25 * (m->box.hi.x() - m->box.lo.x());
    roi.hi.x() = 0.25 * (m->box.hi.x() - m->box.lo.x());
    p.roi = {roi};
  }
  SdfGrid grid;
  for (auto _ : state) {
    if (Status s = grid.build(bvh, p, threads(2)); !s) return fail(state, s);
  }
  state.counters["triangles"] = static_cast<double>(grid.stats().source_triangles);
  state.counters["active_voxels"] = static_cast<double>(grid.stats().active_voxels);
  state.counters["MB"] = static_cast<double>(grid.stats().memory_bytes) / 1e6;
}
BENCHMARK(BM_MakeHuman_SdfBuild)
    ->ArgNames({"voxel_0.1mm", "roi"})
    ->ArgsProduct({{20, 40, 80}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
