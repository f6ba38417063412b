// Mirrored pairs (issue 21, ExtrudeOptions::mirror): the dome of
// extrude_bench.cpp drawn on the right one of two cups that mirror each other
// across x = 0 (each ~10k faces: ring of 256, 20 rows), with and without the
// mirror. BM_ExtrudeMirror/<mirror>: 0 the single extrusion, 1 the pair
// (the drawn part optimised once, reflected onto the left cup). No peer
// library mirrors an extrusion: the single call is the reference, reported
// as the ratio pair / single (2 would be two independent extrusions).
#include <atelier/storage/builder.h>
#include <atelier/systems/sketch/extrude.h>
#include <benchmark/benchmark.h>

#include "extrude_timing.h"

#include <cmath>
#include <vector>

namespace {

using namespace atelier;

/// Two unit cups, axes x = +2 and x = -2, open at y = 0, the left one the
/// exact reflection of the right one (faces reversed: outward normals).
Model cups(int n, int rows) {
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> off{0}, idx;
  auto face = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, bool flip) {
    if (flip) std::swap(a, c);
    idx.insert(idx.end(), {a, b, c});
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  };
  for (int side = 0; side < 2; ++side) {
    const auto o = static_cast<std::uint32_t>(p.size());
    const double sx = side == 0 ? 1 : -1;
    for (int r = 0; r <= rows; ++r)
      for (int i = 0; i < n; ++i)
        p.push_back(Vec3d(sx * (2 + std::cos(2 * M_PI * i / n)), -double(r) / rows, std::sin(2 * M_PI * i / n)));
    p.push_back(Vec3d(sx * 2, -1, 0));
    const auto bottom = static_cast<std::uint32_t>(p.size() - 1);
    auto id = [&](int r, int i) { return o + static_cast<std::uint32_t>(r * n + i % n); };
    for (int r = 0; r < rows; ++r)
      for (int i = 0; i < n; ++i) {
        face(id(r, i), id(r, i + 1), id(r + 1, i + 1), side == 1);
        face(id(r, i), id(r + 1, i + 1), id(r + 1, i), side == 1);
      }
    for (int i = 0; i < n; ++i) face(id(rows, i), id(rows, i + 1), bottom, side == 1);
  }
  Model m;
  (void)add_polygon_surface(m, "cups", PolygonSoupView{p, off, idx}).value();
  return m;
}

ExtrudeStrokes dome(int k = 64) {
  ExtrudeStrokes in;
  const Camera cam = Camera::orthographic(Vec3d(2, 0, 5), Vec3d(2, 0, 0), Vec3d::UnitY(), 1.5, 800, 800);
  in.base_camera = in.sweep_camera = cam;
  auto px = [&](const Vec3d& q) { return Vec2d(cam.project(q).head<2>()); };
  in.base = {px(Vec3d(1, 0, 0)), px(Vec3d(3, 0, 0)), px(Vec3d(1, 0, 0))};
  std::vector<Vec2d> s;
  for (int i = 0; i <= 2 * k; ++i) {
    const double t = M_PI * (1.0 - double(i) / (2 * k));
    s.push_back(px(Vec3d(2 + std::cos(t), std::sin(t), 0)));
  }
  in.sweep = {s};
  return in;
}

void BM_ExtrudeMirror(benchmark::State& state) {
  const Model base = cups(256, 20);
  ExtrudeOptions opt;
  if (state.range(0) != 0) opt.mirror = SymmetryPlane{};
  const ExtrudeStrokes in = dome();
  ExtrudeReport last;
  if (!bench::time_extrude(state, base, in, opt, last)) return;
  state.counters["faces_added"] = static_cast<double>(last.faces_added);
}
BENCHMARK(BM_ExtrudeMirror)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
