// Bulk construction: a 1M-triangle grid built from flat arrays with
// add_polygon_surface (storage/builder.h), 1 and 2 threads; OpenMesh's
// add_vertex/add_face on the same arrays when available.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "bench/support/grid_arrays.h"
#include <atelier/storage/builder.h>

#ifdef ATELIER_HAVE_OPENMESH
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#endif

namespace {

using namespace atelier;

using bench::GridArrays;

// n x n cells, two triangles each: 2 n^2 faces (n = 708: 1.0M faces).
const GridArrays& grid_1m() {
  static const GridArrays g = bench::wavy_grid(708);
  return g;
}

void BM_BuildFromArrays(benchmark::State& state) {
  const GridArrays& g = grid_1m();
  ExecContext ctx;
  ctx.threads = static_cast<int>(state.range(0));
  const std::size_t nf = g.offsets.size() - 1;
  for (auto _ : state) {
    Model m;
    auto s = add_polygon_surface(m, "grid", {g.positions, g.offsets, g.nodes}, ctx);
    if (!s) state.SkipWithError(s.status().to_string().c_str());
    benchmark::DoNotOptimize(m.faces.halfedge.data());
  }
  state.counters["faces/s"] = benchmark::Counter(static_cast<double>(nf), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["faces"] = static_cast<double>(nf);
}
BENCHMARK(BM_BuildFromArrays)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

#ifdef ATELIER_HAVE_OPENMESH
void BM_BuildOpenMesh(benchmark::State& state) {
  const GridArrays& g = grid_1m();
  using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;
  const std::size_t nf = g.offsets.size() - 1;
  for (auto _ : state) {
    Mesh mesh;
    mesh.reserve(g.positions.size(), 3 * nf / 2 + g.positions.size(), nf);
    std::vector<Mesh::VertexHandle> vh;
    vh.reserve(g.positions.size());
    for (const Vec3d& p : g.positions) vh.push_back(mesh.add_vertex(Mesh::Point(float(p.x()), float(p.y()), float(p.z()))));
    for (std::size_t f = 0; f < nf; ++f) {
      const std::uint32_t* c = g.nodes.data() + g.offsets[f];
      mesh.add_face(vh[c[0]], vh[c[1]], vh[c[2]]);
    }
    benchmark::DoNotOptimize(mesh.n_faces());
  }
  state.counters["faces/s"] = benchmark::Counter(static_cast<double>(nf), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["faces"] = static_cast<double>(nf);
}
BENCHMARK(BM_BuildOpenMesh)->Unit(benchmark::kMillisecond)->UseRealTime();
#endif

}  // namespace
