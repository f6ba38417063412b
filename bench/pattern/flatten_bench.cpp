// Flattening (issue 22): our energy-based flattening (systems/pattern/
// flatten.h) beside CGAL's Surface_mesh_parameterization ARAP and LSCM with
// their defaults, on the same pieces: a bodice-like panel (positive and
// negative curvature) and a spherical cap of half-angle 45 degrees, each at
// about 5k, 30k and 100k vertices. Counters: E_L, E_A (flatten.h's
// definitions; LSCM also rescaled to the surface's area, since its two
// pinned vertices fix an arbitrary scale), flipped triangles, and for ours
// the phase 2 iterations. Ours includes build() (topology, checks, the
// symbolic analysis); a warm start from another body's pattern is the
// made-to-measure case (BM_Flatten_AtelierWarm).
#include <atelier/storage/builder.h>
#include <atelier/systems/pattern/flatten.h>
#include <benchmark/benchmark.h>

#include <map>

#include "tests/support/cgal_parameterize.h"
#include "tests/support/flatten_shapes.h"

using namespace atelier;

namespace {

// range(0): 0 bodice, 1 cap; range(1): 0 about 5k, 1 about 30k, 2 about 100k vertices.
const PolygonSoup& piece(int shape, int size) {
  static std::map<std::pair<int, int>, PolygonSoup> cache;
  const auto key = std::make_pair(shape, size);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  static const int bodice_n[3] = {70, 173, 315}, cap_rings[3] = {40, 100, 182};
  PolygonSoup s = shape == 0 ? flatten_shapes::bodice(bodice_n[size])
                             : flatten_shapes::spherical_cap(cap_rings[size], M_PI / 4, 0.15);
  return cache.emplace(key, std::move(s)).first->second;
}

const char* shape_name(int shape) {
  return shape == 0 ? "bodice" : "cap45";
}

void label(benchmark::State& st, const PolygonSoup& s, const std::string& who) {
  st.SetLabel(who + ", " + shape_name(static_cast<int>(st.range(0))) + " " + std::to_string(s.positions.size()) +
              " vertices");
}

void BM_Flatten_Atelier(benchmark::State& st) {
  const PolygonSoup& s = piece(static_cast<int>(st.range(0)), static_cast<int>(st.range(1)));
  Model m;
  if (!add_polygon_surface(m, "piece", s)) {
    st.SkipWithError("build failed");
    return;
  }
  ExecContext ctx;
  ctx.threads = static_cast<int>(st.range(2));
  std::vector<Vec2d> uv(m.nodes.position.size(), Vec2d::Zero());
  PieceFlattening last;
  for (auto _ : st) {
    Flattener fl;
    if (Status b = fl.build(m, SurfaceIdx{0}); !b) {
      st.SkipWithError(b.to_string().c_str());
      return;
    }
    auto r = fl.flatten(m.nodes.position, uv, false, ctx);
    if (!r) {
      st.SkipWithError(r.status().to_string().c_str());
      return;
    }
    last = std::move(*r);
  }
  st.counters["E_L"] = last.distortion.length_error;
  st.counters["E_A"] = last.distortion.area_error;
  st.counters["flips"] = static_cast<double>(last.distortion.flipped);
  st.counters["crossings"] = static_cast<double>(last.distortion.boundary_crossings);
  st.counters["iterations"] = last.iterations;
  st.counters["phase1_ms"] = last.phase1_ms;
  st.counters["phase2_ms"] = last.phase2_ms;
  label(st, s, "atelier, " + std::to_string(st.range(2)) + " thread(s)");
}
BENCHMARK(BM_Flatten_Atelier)
    ->ArgsProduct({{0, 1}, {0, 1, 2}, {1}})
    ->Args({0, 2, 2})
    ->Args({1, 2, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// The made-to-measure case: the same panel on another body (4% wider, 2%
/// shorter, a wave), warm-started from the first body's pattern with the
/// Flattener built once.
void BM_Flatten_AtelierWarm(benchmark::State& st) {
  const PolygonSoup& s = piece(static_cast<int>(st.range(0)), static_cast<int>(st.range(1)));
  Model m;
  if (!add_polygon_surface(m, "piece", s)) return st.SkipWithError("build failed");
  Flattener fl;
  if (!fl.build(m, SurfaceIdx{0})) return st.SkipWithError("build() failed");
  std::vector<Vec2d> first(m.nodes.position.size(), Vec2d::Zero());
  if (!fl.flatten(m.nodes.position, first)) return st.SkipWithError("flatten failed");
  std::vector<Vec3d> other = m.nodes.position;
  for (Vec3d& p : other) p = Vec3d(1.04 * p.x(), p.y() + 0.004 * std::sin(20 * p.z()), 0.98 * p.z());
  std::vector<Vec2d> uv;
  PieceFlattening last;
  for (auto _ : st) {
    st.PauseTiming();
    uv = first;
    st.ResumeTiming();
    auto r = fl.flatten(other, uv, true);
    if (!r) return st.SkipWithError(r.status().to_string().c_str());
    last = std::move(*r);
  }
  st.counters["E_L"] = last.distortion.length_error;
  st.counters["flips"] = static_cast<double>(last.distortion.flipped);
  st.counters["iterations"] = last.iterations;
  st.counters["warm"] = last.warm_started ? 1 : 0;
  label(st, s, "atelier warm start on another body, 1 thread");
}
BENCHMARK(BM_Flatten_AtelierWarm)->ArgsProduct({{0, 1}, {0, 1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();

void run_cgal(benchmark::State& st, cgal_peer::Method method) {
  const PolygonSoup& s = piece(static_cast<int>(st.range(0)), static_cast<int>(st.range(1)));
  cgal_peer::Result r;
  for (auto _ : st) {
    r = cgal_peer::parameterize(s, method);
    if (!r.ok) return st.SkipWithError("CGAL parameterization failed");
  }
  const auto d = cgal_peer::distortion(s, r.uv);
  st.counters["E_L"] = d.length_error;
  st.counters["E_A"] = d.area_error;
  st.counters["flips"] = static_cast<double>(d.flipped);
  if (method == cgal_peer::Method::kLscm) {
    const auto ds = cgal_peer::distortion(s, r.uv, cgal_peer::area_scale(s, r.uv));
    st.counters["E_L_rescaled"] = ds.length_error;
    st.counters["E_A_rescaled"] = ds.area_error;
  }
  label(st, s, method == cgal_peer::Method::kArap ? "CGAL ARAP (defaults), 1 thread" : "CGAL LSCM, 1 thread");
}

void BM_Flatten_CgalArap(benchmark::State& st) {
  run_cgal(st, cgal_peer::Method::kArap);
}
BENCHMARK(BM_Flatten_CgalArap)
    ->ArgsProduct({{0, 1}, {0, 1, 2}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Flatten_CgalLscm(benchmark::State& st) {
  run_cgal(st, cgal_peer::Method::kLscm);
}
BENCHMARK(BM_Flatten_CgalLscm)->ArgsProduct({{0, 1}, {0, 1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
