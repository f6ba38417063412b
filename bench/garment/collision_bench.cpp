// Collision pass (issue 7): the pass on one body including its per-body
// set-up (CollisionBody refit, then resolve_collisions), for a garment
// regenerated as the pipeline does it on bodies it was not encoded on:
// decoded by its detail template, then the edge transfer. Goal: <= 10 ms per body for ~10k garment
// vertices on 2 threads.
//
// With ../shared/data: MakeHuman's male_casualsuit01 (8,426 vertices) fitted
// by its binding on the default body, regenerated on 16 random adults.
// Without: the mannequin with a skin-band garment (the demo's shorts, widened
// to the torso) on 16 sampled mannequins.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <numeric>

#include <atelier/io/makehuman/makehuman.h>
#include <atelier/systems/garment/makehuman_binding.h>
#include <atelier/systems/garment/collision_pass.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/edge_transfer.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/body/reference_body.h>
#include <atelier/systems/mesh/fan_triangulation.h>

using namespace atelier;
namespace fs = std::filesystem;

namespace {

struct CollisionScene {
  std::string label;
  std::shared_ptr<const CollisionTopology> topo;
  std::vector<std::vector<Vec3d>> skins;    // per body
  std::vector<std::vector<Vec3d>> decoded;  // garment decoded on each body
  NodeAdjacency adj;
  ClearanceEncoding clear;
  EdgeTransfer transfer;
  std::vector<Triangle> triangles;
  std::size_t vertices = 0;
};

std::vector<std::array<std::uint32_t, 2>> soup_edges(const makehuman::BaseMesh& mesh) {
  std::vector<std::array<std::uint32_t, 2>> e;
  for (const auto& g : mesh.groups)
    for (std::size_t f = 0; f + 1 < g.face_offsets.size(); ++f)
      for (std::uint32_t k = g.face_offsets[f]; k < g.face_offsets[f + 1]; ++k) {
        const std::uint32_t a = g.face_nodes[k];
        const std::uint32_t b = g.face_nodes[k + 1 < g.face_offsets[f + 1] ? k + 1 : g.face_offsets[f]];
        e.push_back({std::min(a, b), std::max(a, b)});
      }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  return e;
}

// Encodes the garment (detail template + clearance) on the reference and
// decodes it on every body.
void finish(CollisionScene& s, const ReferenceBody& ref, std::span<const Vec3d> garment,
            std::span<const std::array<std::uint32_t, 2>> edges) {
  const BodyPolygons poly = BodyPolygons::from_model(ref.model);
  const std::vector<Vec3d> skin0 = skin_positions(ref);
  auto tris = fan_triangulate(ref.model).value();
  s.topo = CollisionTopology::build(tris.triangles, static_cast<std::uint32_t>(skin0.size())).value();
  CollisionBody cb0;
  if (Status st = cb0.build(s.topo, skin0); !st) throw Error(st);
  s.clear = encode_clearance(garment, cb0).value();
  s.adj = adjacency_from_edges(garment.size(), edges).value();
  const DetailEncoding enc = encode_detail(poly, skin0, garment).value();
  s.transfer = encode_edge_transfer(garment, edges, cb0).value();
  const EdgeTransfer& transfer = s.transfer;
  s.triangles = tris.triangles;
  PolygonFrames fr;
  for (const auto& skin : s.skins) {
    std::vector<Vec3d> out(garment.size());
    compute_frames(poly, skin, fr, {}, enc.reference_corners);
    decode_detail(enc, fr, out);
    if (Status st = apply_edge_transfer(transfer, skin, tris.triangles, out); !st) throw Error(st);
    s.decoded.push_back(std::move(out));
  }
  s.vertices = garment.size();
}

// `large`: with ../shared/data, two garments regenerated together as one
// vertex set of 10,925 (male_casualsuit01 and male_casualsuit03: the
// issue's 10k-vertex case; the largest single MakeHuman garment has 8,426).
CollisionScene make_scene(bool large) {
  CollisionScene s;
  const fs::path mh = fs::path(ATELIER_BENCH_SHARED_DATA) / "makehuman";
  // ATELIER_BENCH_PROCEDURAL=1 forces the procedural fallback.
  if (!std::getenv("ATELIER_BENCH_PROCEDURAL") && fs::exists(mh / "base.obj") &&
      fs::exists(mh / "clothes" / "male_casualsuit01.mhclo") &&
      fs::exists(mh / "clothes" / "male_casualsuit03.mhclo")) {
    const auto lib = makehuman::HumanLibrary::load(mh);
    const ReferenceBody ref = makehuman::make_reference_body(lib);
    std::vector<Vec3f> H(lib.vertex_count());
    lib.build(makehuman::MacroParams{}, H);
    std::vector<Vec3d> g;
    std::vector<std::array<std::uint32_t, 2>> edges;
    std::string names;
    for (const char* name : {"male_casualsuit01", "male_casualsuit03"}) {
      if (!large && !names.empty()) break;
      const auto binding = makehuman::read_mhclo(mh / "clothes" / (std::string(name) + ".mhclo"), lib.vertex_count());
      const makehuman::BaseMesh mesh = makehuman::read_base_mesh(mh / "clothes" / binding.obj_file);
      const auto base = static_cast<std::uint32_t>(g.size());
      for (const auto& e : soup_edges(mesh)) edges.push_back({base + e[0], base + e[1]});
      for (const Vec3d& q : makehuman::fit_binding(binding, H)) g.push_back(makehuman::kMakeHumanToMetres * q);
      names += (names.empty() ? "" : " + ") + std::string(name);
    }
    const std::size_t nskin = skin_positions(ref).size();
    for (const auto& prm : makehuman::sample_adults(16, 99)) {
      lib.build(prm, H);
      std::vector<Vec3d> skin(nskin);
      for (std::size_t v = 0; v < nskin; ++v) skin[v] = makehuman::kMakeHumanToMetres * H[v].cast<double>();
      s.skins.push_back(std::move(skin));
    }
    finish(s, ref, g, edges);
    s.label = "makehuman " + names + " (" + std::to_string(g.size()) + " v), 16 adults";
  } else {
    auto topo = make_mannequin_topology().value();
    const ReferenceBody ref = make_mannequin(MannequinParams{}, topo).value();
    const Model garment = skin_band_garment(ref, 0.55, 1.45, 0.004, 0.40, "suit").value();
    std::vector<Vec3d> g(garment.nodes.position.begin(), garment.nodes.position.end());
    std::vector<std::array<std::uint32_t, 2>> edges;
    for (std::uint32_t e = 0; e < garment.edges.slots.capacity(); ++e)
      edges.push_back({garment.tail(halfedge_of(EdgeIdx{e}, 0)).value, garment.tail(halfedge_of(EdgeIdx{e}, 1)).value});
    for (const auto& prm : sample_mannequins(16, 99)) s.skins.push_back(mannequin_positions(prm, topo).value());
    finish(s, ref, g, edges);
    s.label = "mannequin skin band (" + std::to_string(g.size()) + " v), 16 bodies";
  }
  return s;
}

const CollisionScene& scene(bool large = false) {
  if (large) {
    static const CollisionScene s = make_scene(true);
    return s;
  }
  static const CollisionScene s = make_scene(false);
  return s;
}

// Args: threads, and 1 for the 10,925-vertex set.
void BM_CollisionPassPerBody(benchmark::State& st) {
  const CollisionScene& s = scene(st.range(1) != 0);
  ExecContext ctx;
  ctx.threads = static_cast<int>(st.range(0));
  std::vector<Vec3d> g;
  std::size_t body = 0, pushed = 0, bodies = 0, queries = 0, faired = 0;
  for (auto _ : st) {
    const std::size_t b = body++ % s.skins.size();
    g = s.decoded[b];
    CollisionBodyParams cbp;
    for (const Vec3d& q : g) cbp.roi.extend(q);
    CollisionBody cb;
    if (Status e = cb.build(s.topo, s.skins[b], cbp, ctx); !e) st.SkipWithError(e.to_string().c_str());
    auto rep = resolve_collisions(g, s.adj, s.clear, cb, CollisionParams{}, ctx);
    if (!rep) st.SkipWithError(rep.status().to_string().c_str());
    pushed += rep->pushed;
    queries += rep->queries;
    faired += rep->faired;
    ++bodies;
    benchmark::DoNotOptimize(g.data());
  }
  st.counters["pushed/body"] = static_cast<double>(pushed) / std::max<std::size_t>(1, bodies);
  st.counters["faired/body"] = static_cast<double>(faired) / std::max<std::size_t>(1, bodies);
  st.counters["queries/body"] = static_cast<double>(queries) / std::max<std::size_t>(1, bodies);
  st.counters["vertices"] = static_cast<double>(s.vertices);
  st.SetLabel(s.label);
}
BENCHMARK(BM_CollisionPassPerBody)
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Exact queries alone: every decoded garment vertex of one body, with its
// encoded hint, on 1 thread (the pass's unit of work).
void BM_CollisionQuery(benchmark::State& st) {
  const CollisionScene& s = scene();
  CollisionBody cb;
  if (Status e = cb.build(s.topo, s.skins[0]); !e) st.SkipWithError(e.to_string().c_str());
  const auto& g = s.decoded[0];
  const bool hinted = st.range(0) != 0;
  std::vector<std::uint32_t> order(g.size());
  std::iota(order.begin(), order.end(), 0u);
  if (st.range(1))
    std::stable_sort(order.begin(), order.end(),
                     [&](auto a, auto b) { return s.clear.triangle[a] < s.clear.triangle[b]; });
  double sum = 0;
  for (auto _ : st)
    for (std::uint32_t v : order) sum += cb.query(g[v], hinted ? s.clear.triangle[v] : kNoTriangle).distance;
  benchmark::DoNotOptimize(sum);
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * g.size()));
  st.SetLabel(hinted ? "hinted" : "no hint");
}
BENCHMARK(BM_CollisionQuery)->Args({1, 0})->Args({1, 1})->Args({0, 0})->Unit(benchmark::kMillisecond);

// The same points through CollisionBody::query_many, on 1 thread.
void BM_CollisionQueryMany(benchmark::State& st) {
  const CollisionScene& s = scene();
  CollisionBody cb;
  if (Status e = cb.build(s.topo, s.skins[0]); !e) st.SkipWithError(e.to_string().c_str());
  const auto& g = s.decoded[0];
  std::vector<BodyDistance> out(g.size());
  ExecContext one;
  one.threads = 1;
  for (auto _ : st) {
    if (Status e = cb.query_many(g, s.clear.triangle, out, one); !e) st.SkipWithError(e.to_string().c_str());
    benchmark::DoNotOptimize(out.data());
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * g.size()));
  st.SetLabel("hinted");
}
BENCHMARK(BM_CollisionQueryMany)->Unit(benchmark::kMillisecond);

// The edge transfer on one body (systems/edge_transfer.h): edge targets,
// right-hand side and the solve with the factor made at encoding.
void BM_EdgeTransfer(benchmark::State& st) {
  const CollisionScene& s = scene(st.range(0) != 0);
  std::vector<Vec3d> g;
  std::size_t body = 0;
  for (auto _ : st) {
    const std::size_t b = body++ % s.skins.size();
    g = s.decoded[b];
    if (Status e = apply_edge_transfer(s.transfer, s.skins[b], s.triangles, g); !e)
      st.SkipWithError(e.to_string().c_str());
    benchmark::DoNotOptimize(g.data());
  }
  st.counters["vertices"] = static_cast<double>(s.vertices);
  st.SetLabel(s.label);
}
BENCHMARK(BM_EdgeTransfer)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The set-up alone. Args: threads, and 1 for a first body (a new topology
// each time, its own construction not timed: Embree's device and SAH build)
// instead of a refit.
void BM_CollisionBodySetup(benchmark::State& st) {
  const CollisionScene& s = scene();
  ExecContext ctx;
  ctx.threads = static_cast<int>(st.range(0));
  const bool first = st.range(1) != 0;
  std::size_t body = 0;
  for (auto _ : st) {
    const std::size_t b = body++ % s.skins.size();
    std::shared_ptr<const CollisionTopology> topo = s.topo;
    if (first) {
      st.PauseTiming();
      topo = CollisionTopology::build(s.triangles, static_cast<std::uint32_t>(s.skins[b].size())).value();
      st.ResumeTiming();
    }
    CollisionBodyParams cbp;
    for (const Vec3d& q : s.decoded[b]) cbp.roi.extend(q);
    CollisionBody cb;
    if (Status e = cb.build(topo, s.skins[b], cbp, ctx); !e) st.SkipWithError(e.to_string().c_str());
    benchmark::DoNotOptimize(cb.positions().data());
    if (first) {
      st.PauseTiming();
      cb = CollisionBody();
      topo.reset();
      st.ResumeTiming();
    }
  }
  st.SetLabel(std::string(first ? "first body" : "refit") + ", " + s.label);
}
BENCHMARK(BM_CollisionBodySetup)->ArgsProduct({{1, 2}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
