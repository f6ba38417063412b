// Catmull-Clark with creases (issue 23) next to OpenSubdiv 3.5 (Debian
// libosd-dev), and the whole curves-to-surface pipeline per shared network.
//
// Input of the Catmull-Clark benchmarks: a 316 x 316 quad grid (100,489
// control vertices, 99,856 quads), gently waved, with a crease polyline on
// every 8th row and column and a corner where two cross (like a curve
// network's control mesh), refined 3 levels (6.39 M vertices).
//   *_Refine:    topology of every level + positions (OpenSubdiv: Far
//                TopologyRefinerFactory + RefineUniform(3) + PrimvarRefiner
//                (double) Interpolate per level, its single-threaded path);
//   *_Positions: positions only, the topology made beforehand (OpenSubdiv:
//                PrimvarRefiner Interpolate);
//   OpenSubdiv_StencilTable / _OmpStencils: OpenSubdiv's multi-threaded
//                path: stencil table (setup), then Osd::OmpEvaluator on
//                float buffers with omp_set_num_threads(threads).
// Counter "vertices/s": output vertices per second.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <atelier/io/curve_network.h>
#include <atelier/io/obj.h>
#include <atelier/systems/curvenet/catmull_clark.h>
#include <atelier/systems/curvenet/curve_surface.h>

#ifdef ATELIER_HAVE_OPENSUBDIV
#include <omp.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/osd/bufferDescriptor.h>
#include <opensubdiv/osd/ompEvaluator.h>
#endif

namespace {

using namespace atelier;

constexpr int kCells = 316;
constexpr int kLevels = 3;

struct CreasedGrid {
  PolygonSoup mesh;
  std::vector<std::array<std::uint32_t, 2>> creases;
  std::vector<std::uint32_t> corners;
};

const CreasedGrid& grid() {
  static const CreasedGrid g = [] {
    CreasedGrid c;
    const int n = kCells;
    auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) c.mesh.positions.emplace_back(i, j, 2.0 * std::sin(0.05 * i) * std::cos(0.07 * j));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::uint32_t q[] = {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
        c.mesh.add_face(q);
      }
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        if (j % 8 == 0 && i < n) c.creases.push_back({id(i, j), id(i + 1, j)});
        if (i % 8 == 0 && j < n) c.creases.push_back({id(i, j), id(i, j + 1)});
        if (i % 8 == 0 && j % 8 == 0) c.corners.push_back(id(i, j));
      }
    return c;
  }();
  return g;
}

ExecContext threads(const benchmark::State& state) {
  ExecContext ctx;
  ctx.threads = static_cast<int>(state.range(0));
  return ctx;
}

void set_rate(benchmark::State& state, std::size_t vertices) {
  state.counters["vertices/s"] =
      benchmark::Counter(static_cast<double>(vertices), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["control_vertices"] = static_cast<double>(grid().mesh.positions.size());
  state.counters["vertices_out"] = static_cast<double>(vertices);
}

void BM_CatmullClark_Atelier_Refine(benchmark::State& state) {
  const CreasedGrid& g = grid();
  const ExecContext ctx = threads(state);
  CatmullClarkOptions o;
  o.levels = kLevels;
  std::size_t out = 0;
  for (auto _ : state) {
    auto r = CatmullClarkRefiner::create(g.mesh, g.mesh.positions.size(), g.creases, g.corners, o, ctx);
    if (!r) state.SkipWithError(r.status().to_string().c_str());
    std::vector<Vec3d> p;
    if (Status s = r->refine(g.mesh.positions, p, ctx); !s) state.SkipWithError(s.to_string().c_str());
    out = p.size();
    benchmark::DoNotOptimize(p.data());
  }
  set_rate(state, out);
}
BENCHMARK(BM_CatmullClark_Atelier_Refine)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_CatmullClark_Atelier_Positions(benchmark::State& state) {
  const CreasedGrid& g = grid();
  const ExecContext ctx = threads(state);
  CatmullClarkOptions o;
  o.levels = kLevels;
  auto r = CatmullClarkRefiner::create(g.mesh, g.mesh.positions.size(), g.creases, g.corners, o, ctx);
  if (!r) {
    state.SkipWithError(r.status().to_string().c_str());
    return;
  }
  // Every level in one buffer, as OpenSubdiv's PrimvarRefiner is given.
  std::vector<Vec3d> all(r->total_vertex_count());
  std::copy(g.mesh.positions.begin(), g.mesh.positions.end(), all.begin());
  for (auto _ : state) {
    if (Status s = r->refine_all(all, ctx); !s) state.SkipWithError(s.to_string().c_str());
    benchmark::DoNotOptimize(all.data());
  }
  set_rate(state, r->vertex_count(r->levels()));
}
BENCHMARK(BM_CatmullClark_Atelier_Positions)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

#ifdef ATELIER_HAVE_OPENSUBDIV
namespace osd = OpenSubdiv;

struct OsdPoint {
  double x, y, z;
  void Clear(void* = nullptr) { x = y = z = 0; }
  void AddWithWeight(const OsdPoint& s, double w) {
    x += w * s.x;
    y += w * s.y;
    z += w * s.z;
  }
};

/// Far's topology refiner for the grid with the same creases and corners.
std::unique_ptr<osd::Far::TopologyRefiner> osd_refiner(bool refine = true) {
  const CreasedGrid& g = grid();
  static std::vector<int> nverts, idx, crease_idx, corner_idx;
  static std::vector<float> crease_w, corner_w;
  if (nverts.empty()) {
    nverts.assign(g.mesh.face_count(), 4);
    idx.assign(g.mesh.face_nodes.begin(), g.mesh.face_nodes.end());
    for (const auto& c : g.creases) {
      crease_idx.push_back(static_cast<int>(c[0]));
      crease_idx.push_back(static_cast<int>(c[1]));
    }
    corner_idx.assign(g.corners.begin(), g.corners.end());
    crease_w.assign(g.creases.size(), osd::Sdc::Crease::SHARPNESS_INFINITE);
    corner_w.assign(g.corners.size(), osd::Sdc::Crease::SHARPNESS_INFINITE);
  }
  using Descriptor = osd::Far::TopologyDescriptor;
  Descriptor d;
  d.numVertices = static_cast<int>(g.mesh.positions.size());
  d.numFaces = static_cast<int>(g.mesh.face_count());
  d.numVertsPerFace = nverts.data();
  d.vertIndicesPerFace = idx.data();
  d.numCreases = static_cast<int>(g.creases.size());
  d.creaseVertexIndexPairs = crease_idx.data();
  d.creaseWeights = crease_w.data();
  d.numCorners = static_cast<int>(g.corners.size());
  d.cornerVertexIndices = corner_idx.data();
  d.cornerWeights = corner_w.data();
  osd::Sdc::Options options;
  options.SetVtxBoundaryInterpolation(osd::Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
  std::unique_ptr<osd::Far::TopologyRefiner> r(osd::Far::TopologyRefinerFactory<Descriptor>::Create(
      d, osd::Far::TopologyRefinerFactory<Descriptor>::Options(osd::Sdc::SCHEME_CATMARK, options)));
  if (refine) r->RefineUniform(osd::Far::TopologyRefiner::UniformOptions(kLevels));
  return r;
}

std::size_t osd_interpolate(const osd::Far::TopologyRefiner& r, std::vector<OsdPoint>& buf) {
  const CreasedGrid& g = grid();
  buf.resize(static_cast<std::size_t>(r.GetNumVerticesTotal()));
  for (std::size_t v = 0; v < g.mesh.positions.size(); ++v)
    buf[v] = {g.mesh.positions[v].x(), g.mesh.positions[v].y(), g.mesh.positions[v].z()};
  osd::Far::PrimvarRefinerReal<double> primvar(r);
  OsdPoint* src = buf.data();
  for (int l = 1; l <= kLevels; ++l) {
    OsdPoint* dst = src + r.GetLevel(l - 1).GetNumVertices();
    primvar.Interpolate(l, src, dst);
    src = dst;
  }
  return static_cast<std::size_t>(r.GetLevel(kLevels).GetNumVertices());
}

void BM_CatmullClark_OpenSubdiv_Refine(benchmark::State& state) {
  std::size_t out = 0;
  std::vector<OsdPoint> buf;
  for (auto _ : state) {
    auto r = osd_refiner();
    out = osd_interpolate(*r, buf);
    benchmark::DoNotOptimize(buf.data());
  }
  set_rate(state, out);
}
BENCHMARK(BM_CatmullClark_OpenSubdiv_Refine)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_CatmullClark_OpenSubdiv_Positions(benchmark::State& state) {
  auto r = osd_refiner();
  std::vector<OsdPoint> buf;
  std::size_t out = 0;
  for (auto _ : state) {
    out = osd_interpolate(*r, buf);
    benchmark::DoNotOptimize(buf.data());
  }
  set_rate(state, out);
}
BENCHMARK(BM_CatmullClark_OpenSubdiv_Positions)->Unit(benchmark::kMillisecond)->UseRealTime();

std::unique_ptr<const osd::Far::StencilTable> osd_stencils() {
  auto r = osd_refiner();
  osd::Far::StencilTableFactory::Options o;
  o.generateIntermediateLevels = false;
  o.generateOffsets = true;
  return std::unique_ptr<const osd::Far::StencilTable>(osd::Far::StencilTableFactory::Create(*r, o));
}

void BM_CatmullClark_OpenSubdiv_StencilTable(benchmark::State& state) {
  std::size_t out = 0;
  for (auto _ : state) {
    auto st = osd_stencils();
    out = static_cast<std::size_t>(st->GetNumStencils());
    benchmark::DoNotOptimize(st.get());
  }
  set_rate(state, out);
}
BENCHMARK(BM_CatmullClark_OpenSubdiv_StencilTable)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_CatmullClark_OpenSubdiv_OmpStencils(benchmark::State& state) {
  const CreasedGrid& g = grid();
  auto st = osd_stencils();
  std::vector<float> src;
  for (const Vec3d& p : g.mesh.positions)
    for (int k = 0; k < 3; ++k) src.push_back(static_cast<float>(p[k]));
  std::vector<float> dst(3 * static_cast<std::size_t>(st->GetNumStencils()));
  const osd::Osd::BufferDescriptor desc(0, 3, 3);
  omp_set_num_threads(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    osd::Osd::OmpEvaluator::EvalStencils(src.data(), desc, dst.data(), desc, &st->GetSizes()[0], &st->GetOffsets()[0],
                                         &st->GetControlIndices()[0], &st->GetWeights()[0], 0, st->GetNumStencils());
    benchmark::DoNotOptimize(dst.data());
  }
  set_rate(state, static_cast<std::size_t>(st->GetNumStencils()));
}
BENCHMARK(BM_CatmullClark_OpenSubdiv_OmpStencils)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
#endif

// ---- the whole pipeline per shared network (2 levels, as `atelier surface`).
void BM_SurfaceFromCurves(benchmark::State& state, const char* name, const char* mesh) {
  const std::filesystem::path dir = std::filesystem::path(ATELIER_BENCH_SHARED_DATA) / "curve-networks";
  if (!std::filesystem::exists(dir / (std::string(name) + ".txt"))) {
    state.SkipWithError("shared curve networks not found");
    return;
  }
  const PolylineSet curves = read_curve_network(dir / (std::string(name) + ".txt"));
  Model traced_model;
  PolygonSoup traced;
  if (*mesh) {
    traced_model = read_obj(dir / (std::string(mesh) + ".obj"));
    traced.positions = traced_model.nodes.position;
    std::vector<NodeIdx> corners;
    std::vector<std::uint32_t> face;
    for (std::uint32_t k = 0; k < traced_model.faces.slots.capacity(); ++k) {
      if (!traced_model.alive(FaceIdx{k})) continue;
      traced_model.face_nodes(FaceIdx{k}, corners);
      face.clear();
      for (NodeIdx v : corners) face.push_back(v.value);
      traced.add_face(face);
    }
  }
  CurveSurfaceOptions o;
  o.levels = 2;
  ExecContext ctx;
  ctx.threads = static_cast<int>(state.range(0));
  std::size_t faces = 0;
  for (auto _ : state) {
    auto s = surface_from_curves(curves, traced, o, ctx);
    if (!s) {
      state.SkipWithError(s.status().to_string().c_str());
      break;
    }
    faces = s->refined.mesh.face_count();
    benchmark::DoNotOptimize(s->model.num_faces());
  }
  state.counters["curves"] = static_cast<double>(curves.size());
  state.counters["faces_out"] = static_cast<double>(faces);
}
BENCHMARK_CAPTURE(BM_SurfaceFromCurves, shell_100, "shell_100", "")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_SurfaceFromCurves, roof_75, "roof_75", "")->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_SurfaceFromCurves, kagome_114_regular, "kagome_114_regular", "")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_SurfaceFromCurves, hill_3_traced, "hill_3", "hill")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_SurfaceFromCurves, shell_3_traced, "shell_3", "shell")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_SurfaceFromCurves, tent_3_regular_curves, "tent_3_regular_curves", "")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
