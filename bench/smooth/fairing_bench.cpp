// Umbrella fairing (issue 4): our 2nd-order umbrella against OpenMesh's
// JacobiLaplaceSmootherT in C1 mode (umbrella of umbrella, Jacobi) on the same
// mesh, the same fixed set and the same iteration count.
#include <benchmark/benchmark.h>

#include <map>

#include <atelier/engine/random.h>
#include <atelier/storage/builder.h>
#include <atelier/systems/smooth/fairing.h>
#include "tests/support/shapes.h"

#ifdef ATELIER_HAVE_OPENMESH
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Smoother/JacobiLaplaceSmootherT.hh>
#endif

using namespace atelier;

namespace {

constexpr int kIterations = 10;

// A noisy n x n triangulated grid (about n^2 vertices) with its outer two rings fixed.
struct GridCase {
  shapes::Soup soup;
  std::vector<std::uint8_t> fixed;
};

const GridCase& grid(int n) {
  static std::map<int, GridCase> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  GridCase g;
  SplitMix64 r(9);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) g.soup.p.emplace_back(i, j, 0.2 * r.normal());
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i * n + j); };
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < n; ++j) {
      g.soup.face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      g.soup.face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  g.fixed.assign(static_cast<std::size_t>(n) * n, 0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (i < 2 || j < 2 || i >= n - 2 || j >= n - 2) g.fixed[id(i, j)] = 1;
  return cache.emplace(n, std::move(g)).first->second;
}

/// Our fairing; with `planned`, the per-mesh set-up (FairPlan) is made
/// outside the timed region, as OpenMesh's smoother initialize() is below.
/// With `portable`, the SSE2 kernel even where AVX2 is available (the
/// kernels give bit-identical results; this shows what AVX2 buys).
void run_fairing(benchmark::State& st, bool planned, bool portable = false) {
  const int n = static_cast<int>(st.range(0));
  const GridCase& g = grid(n);
  Model m;
  (void)add_polygon_surface(m, "grid", g.soup.arrays());
  const NodeAdjacency adj = build_adjacency(m);
  ExecContext ctx;
  ctx.threads = static_cast<int>(st.range(1));
  FairParams prm;
  prm.iterations = kIterations;
  prm.allow_avx2 = !portable;
  std::vector<Vec3d> p = m.nodes.position;
  bool avx2 = false;
  for (auto _ : st) {
    st.PauseTiming();
    p = m.nodes.position;
    Expected<FairPlan> plan = Status{};
    if (planned) {
      plan = make_fair_plan(adj, g.fixed, prm, ctx);
      if (!plan) {
        st.SkipWithError(plan.status().to_string().c_str());
        return;
      }
    }
    st.ResumeTiming();
    Expected<FairReport> rep = planned ? fair_umbrella(std::span<Vec3d>(p), adj, *plan, prm, ctx)
                                       : fair_umbrella(std::span<Vec3d>(p), adj, g.fixed, prm, ctx);
    benchmark::DoNotOptimize(rep);
    avx2 = rep && rep->avx2;
  }
  const double vi = static_cast<double>(n) * n * kIterations;
  double moved = 0;
  for (std::size_t v = 0; v < p.size(); ++v) moved = std::max(moved, (p[v] - m.nodes.position[v]).norm());
  st.counters["max_move"] = moved;
  st.counters["ns/vertex/iter"] =
      benchmark::Counter(vi * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  st.SetLabel(std::string("atelier U2 Jacobi, ") + (avx2 ? "AVX2" : "SSE2") + " kernel, " +
              (planned ? "plan made outside the timing, " : "") + std::to_string(st.range(1)) + " threads");
}

void BM_FairUmbrella(benchmark::State& st) { run_fairing(st, false); }
BENCHMARK(BM_FairUmbrella)->Args({316, 1})->Args({316, 2})->Args({1000, 2})->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FairUmbrellaPlanned(benchmark::State& st) { run_fairing(st, true); }
BENCHMARK(BM_FairUmbrellaPlanned)->Args({316, 1})->Args({316, 2})->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FairUmbrellaPlannedPortable(benchmark::State& st) { run_fairing(st, true, true); }
BENCHMARK(BM_FairUmbrellaPlannedPortable)->Args({316, 1})->Args({316, 2})->Unit(benchmark::kMillisecond)->UseRealTime();

#ifdef ATELIER_HAVE_OPENMESH
using OMesh = OpenMesh::TriMesh_ArrayKernelT<>;
void BM_OpenMeshJacobiC1(benchmark::State& st) {
  const int n = static_cast<int>(st.range(0));
  const GridCase& g = grid(n);
  OMesh mesh;
  std::vector<OMesh::VertexHandle> vh;
  for (const auto& p : g.soup.p) vh.push_back(mesh.add_vertex(OMesh::Point(p.x(), p.y(), p.z())));
  for (std::size_t f = 0; f + 1 < g.soup.off.size(); ++f)
    mesh.add_face(vh[g.soup.idx[g.soup.off[f]]], vh[g.soup.idx[g.soup.off[f] + 1]], vh[g.soup.idx[g.soup.off[f] + 2]]);
  mesh.request_vertex_status();
  mesh.request_face_normals();
  mesh.request_vertex_normals();
  mesh.update_normals();
  for (std::size_t v = 0; v < vh.size(); ++v)
    if (g.fixed[v]) mesh.status(vh[v]).set_locked(true);
  std::vector<OMesh::Point> start;
  for (auto v : mesh.vertices()) start.push_back(mesh.point(v));
  for (auto _ : st) {
    st.PauseTiming();
    for (auto v : mesh.vertices()) mesh.set_point(v, start[v.idx()]);
    OpenMesh::Smoother::JacobiLaplaceSmootherT<OMesh> smoother(mesh);
    smoother.initialize(OpenMesh::Smoother::SmootherT<OMesh>::Tangential_and_Normal,
                        OpenMesh::Smoother::SmootherT<OMesh>::C1);
    st.ResumeTiming();
    smoother.smooth(kIterations);
  }
  // Sanity: OpenMesh must actually have moved the free vertices.
  double moved = 0;
  for (auto v : mesh.vertices()) moved = std::max(moved, double((mesh.point(v) - start[v.idx()]).norm()));
  st.counters["max_move"] = moved;
  const double vi = static_cast<double>(n) * n * kIterations;
  st.counters["ns/vertex/iter"] =
      benchmark::Counter(vi * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  st.SetLabel("OpenMesh JacobiLaplaceSmootherT C1, 1 thread");
}
BENCHMARK(BM_OpenMeshJacobiC1)->Arg(316)->Unit(benchmark::kMillisecond)->UseRealTime();
#endif

}  // namespace
