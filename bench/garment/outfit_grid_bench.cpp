// Inside tests of an outfit (several garment layers) against one body, per
// body, set-up included: where the OpenVDB signed-distance grid
// (systems/spatial/sdf_grid.h) could pay for its build (issue 19). The grid
// answers inside() exactly too (the BVH decides near the surface), so every
// method gives the same answers; they differ in cost only.
//
// Methods (second argument):
//  0. CollisionBody: set-up (refit) and exact signed distances with the
//     garment's hints (query_many), inside = distance < 0;
//  1. BodyBvh: commit the body, then exact inside tests without hints
//     (inside_many);
//  2, 3. BodyBvh commit, an OpenVDB grid over the outfit's box (8 mm, 4 mm
//     voxels), then SdfGrid::inside_many.
//
// With ../shared/data: the five MakeHuman garments fitted by their bindings
// on 8 random adults, then the five again offset outward by 5, 10 and 15 mm
// (up to 20 layers: 18,682 vertices per five). Without: mannequin skin
// bands at 4 to 80 mm from the skin on 8 sampled mannequins. Counter
// inside0: vertices inside the first body (the same for every method).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include <atelier/io/makehuman/mhclo.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/body/reference_body.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/spatial/collision_body.h>
#include <atelier/systems/spatial/sdf_grid.h>

using namespace atelier;
namespace fs = std::filesystem;

namespace {

struct Outfit {
  std::string label;
  std::shared_ptr<const CollisionTopology> topo;
  std::vector<Triangle> triangles;
  std::vector<std::vector<Vec3d>> skins;                // per body
  std::vector<std::vector<std::vector<Vec3d>>> layers;  // per body, per layer
  std::vector<std::vector<std::uint32_t>> hints;        // per layer (the reference body's closest triangles)
};

// The garment offset outward by `offset` along the body's outward
// direction at each vertex's closest point.
std::vector<Vec3d> offset_layer(std::span<const Vec3d> garment, const CollisionBody& cb, double offset) {
  std::vector<BodyDistance> d(garment.size());
  if (Status s = cb.query_many(garment, {}, d); !s) throw Error(s);
  std::vector<Vec3d> layer(garment.size());
  for (std::size_t v = 0; v < garment.size(); ++v) layer[v] = garment[v] + offset * d[v].normal;
  return layer;
}

Outfit make_outfit() {
  Outfit o;
  const fs::path mh = fs::path(ATELIER_BENCH_SHARED_DATA) / "makehuman";
  const char* names[] = {"male_casualsuit01", "male_casualsuit03", "male_worksuit01", "female_casualsuit01",
                         "female_sportsuit01"};
  bool have = !std::getenv("ATELIER_BENCH_PROCEDURAL") && fs::exists(mh / "base.obj");
  for (const char* n : names) have = have && fs::exists(mh / "clothes" / (std::string(n) + ".mhclo"));
  constexpr int kOffsets = 4;
  if (have) {
    const auto lib = makehuman::HumanLibrary::load(mh);
    const ReferenceBody ref = makehuman::make_reference_body(lib);
    const std::vector<Vec3d> skin0 = skin_positions(ref);
    o.triangles = fan_triangulate(ref.model).value().triangles;
    o.topo = CollisionTopology::build(o.triangles, static_cast<std::uint32_t>(skin0.size())).value();
    std::vector<makehuman::GarmentBinding> bindings;
    for (const char* n : names)
      bindings.push_back(makehuman::read_mhclo(mh / "clothes" / (std::string(n) + ".mhclo"), lib.vertex_count()));
    std::vector<Vec3f> H(lib.vertex_count());
    auto fitted = [&](const makehuman::GarmentBinding& b) {
      std::vector<Vec3d> g;
      for (const Vec3d& q : makehuman::fit_binding(b, H)) g.push_back(makehuman::kMakeHumanToMetres * q);
      return g;
    };
    // Layers: the five garments at offset 0, then again 5 mm out, and so
    // on. Hints from the default body.
    lib.build(makehuman::MacroParams{}, H);
    CollisionBody cb0;
    if (Status s = cb0.build(o.topo, skin0); !s) throw Error(s);
    std::vector<std::vector<std::uint32_t>> hint_of;
    for (const auto& b : bindings) {
      const std::vector<Vec3d> g = fitted(b);
      std::vector<BodyDistance> d(g.size());
      if (Status s = cb0.query_many(g, {}, d); !s) throw Error(s);
      hint_of.emplace_back(g.size());
      for (std::size_t v = 0; v < g.size(); ++v) hint_of.back()[v] = d[v].triangle;
    }
    for (int k = 0; k < kOffsets; ++k) o.hints.insert(o.hints.end(), hint_of.begin(), hint_of.end());
    for (const auto& prm : makehuman::sample_adults(8, 7)) {
      lib.build(prm, H);
      std::vector<Vec3d> skin(skin0.size());
      for (std::size_t v = 0; v < skin.size(); ++v) skin[v] = makehuman::kMakeHumanToMetres * H[v].cast<double>();
      CollisionBody cb;
      if (Status s = cb.build(o.topo, skin); !s) throw Error(s);
      o.layers.emplace_back();
      for (int k = 0; k < kOffsets; ++k)
        for (const auto& b : bindings) o.layers.back().push_back(offset_layer(fitted(b), cb, 0.005 * k));
      o.skins.push_back(std::move(skin));
    }
    o.label = "makehuman, 5 garments x 4 offsets";
  } else {
    auto mtopo = make_mannequin_topology().value();
    const ReferenceBody ref = make_mannequin(MannequinParams{}, mtopo).value();
    const std::vector<Vec3d> skin0 = skin_positions(ref);
    o.triangles = fan_triangulate(ref.model).value().triangles;
    o.topo = CollisionTopology::build(o.triangles, static_cast<std::uint32_t>(skin0.size())).value();
    const Model band = skin_band_garment(ref, 0.55, 1.45, 0.004, 0.40, "suit").value();
    // Band vertices are skin vertices pushed out: each layer is the band on
    // the body at hand, pushed farther.
    const std::vector<Vec3d> g0(band.nodes.position.begin(), band.nodes.position.end());
    CollisionBody cb0;
    if (Status s = cb0.build(o.topo, skin0); !s) throw Error(s);
    std::vector<BodyDistance> d0(g0.size());
    if (Status s = cb0.query_many(g0, {}, d0); !s) throw Error(s);
    std::vector<std::uint32_t> h(g0.size());
    for (std::size_t v = 0; v < g0.size(); ++v) h[v] = d0[v].triangle;
    for (const auto& prm : sample_mannequins(8, 7)) {
      std::vector<Vec3d> skin = mannequin_positions(prm, mtopo).value();
      CollisionBody cb;
      if (Status s = cb.build(o.topo, skin); !s) throw Error(s);
      o.layers.emplace_back();
      // The band's closest points on this body, as a garment on it.
      std::vector<Vec3d> on(g0.size());
      for (std::size_t v = 0; v < g0.size(); ++v) on[v] = cb.query_triangle(g0[v], h[v]).closest;
      std::vector<BodyDistance> d(g0.size());
      if (Status s = cb.query_many(on, h, d); !s) throw Error(s);
      for (int k = 0; k < 5 * kOffsets; ++k) {
        std::vector<Vec3d> layer(g0.size());
        for (std::size_t v = 0; v < g0.size(); ++v) layer[v] = on[v] + 0.004 * (k + 1) * d[v].normal;
        o.layers.back().push_back(std::move(layer));
      }
      o.skins.push_back(std::move(skin));
    }
    for (int k = 0; k < 5 * kOffsets; ++k) o.hints.push_back(h);
    o.label = "mannequin skin bands";
  }
  return o;
}

const Outfit& outfit() {
  static const Outfit o = make_outfit();
  return o;
}

// Args: layers, method (see the top), threads.
void BM_OutfitInside(benchmark::State& st) {
  const Outfit& o = outfit();
  const auto layers = static_cast<std::size_t>(st.range(0));
  const int method = static_cast<int>(st.range(1));
  ExecContext ctx;
  ctx.threads = static_cast<int>(st.range(2));
  // Each body's points and hints, gathered once (not timed).
  std::vector<std::vector<Vec3d>> pts(o.skins.size());
  std::vector<std::uint32_t> hints;
  Box3d box;
  for (std::size_t b = 0; b < o.skins.size(); ++b)
    for (std::size_t l = 0; l < layers; ++l) {
      pts[b].insert(pts[b].end(), o.layers[b][l].begin(), o.layers[b][l].end());
      if (b == 0) hints.insert(hints.end(), o.hints[l].begin(), o.hints[l].end());
    }
  for (const auto& p : pts)
    for (const Vec3d& q : p) box.extend(q);
  box.lo.array() -= 0.01;
  box.hi.array() += 0.01;
  const std::size_t n = pts[0].size();
  std::vector<std::uint8_t> inside(n);
  std::vector<BodyDistance> dist(n);
  // The BVH keeps a view of this buffer: each body is copied in and committed.
  std::vector<Vec3d> skin_buf = o.skins[0];
  BodyBvh bvh;
  if (Status s = bvh.build(std::span<const Vec3d>(skin_buf), o.triangles, {}, ctx); !s)
    st.SkipWithError(s.to_string().c_str());
  std::size_t body = 0, inside0 = 0, exact = 0, from_grid = 0;
  for (auto _ : st) {
    const std::size_t b = body++ % o.skins.size();
    if (method == 0) {
      CollisionBody cb;
      if (Status s = cb.build(o.topo, o.skins[b], {}, ctx); !s) st.SkipWithError(s.to_string().c_str());
      if (Status s = cb.query_many(pts[b], hints, dist, ctx); !s) st.SkipWithError(s.to_string().c_str());
      if (b == 0) {
        inside0 = 0;
        for (std::size_t i = 0; i < n; ++i) inside0 += dist[i].distance < 0;
      }
    } else {
      std::copy(o.skins[b].begin(), o.skins[b].end(), skin_buf.begin());
      if (Status s = bvh.commit(ctx); !s) st.SkipWithError(s.to_string().c_str());
      if (method == 1) {
        if (Status s = bvh.inside_many(pts[b], inside, ctx); !s) st.SkipWithError(s.to_string().c_str());
      } else {
        SdfParams sp;
        sp.voxel_size = method == 2 ? 0.008 : 0.004;
        sp.roi.push_back(box);
        SdfGrid grid;
        if (Status s = grid.build(bvh, sp, ctx); !s) st.SkipWithError(s.to_string().c_str());
        InsideStats is;
        if (Status s = grid.inside_many(pts[b], inside, ctx, &is); !s) st.SkipWithError(s.to_string().c_str());
        exact += is.exact;
        from_grid += is.from_grid;
      }
      if (b == 0) inside0 = static_cast<std::size_t>(std::count(inside.begin(), inside.end(), 1));
    }
  }
  static const char* kNames[] = {"collision body, hinted", "BodyBvh exact", "OpenVDB grid 8 mm", "OpenVDB grid 4 mm"};
  st.SetLabel(std::string(kNames[method]) + ", " + o.label);
  st.counters["points"] = static_cast<double>(n);
  st.counters["inside0"] = static_cast<double>(inside0);
  if (method >= 2)
    st.counters["exact_share"] = static_cast<double>(exact) / std::max<std::size_t>(1, exact + from_grid);
}
BENCHMARK(BM_OutfitInside)
    ->ArgNames({"layers", "method", "threads"})
    ->ArgsProduct({{1, 5, 20}, {0, 1, 2, 3}, {2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
