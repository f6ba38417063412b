// Uniform 1-to-4 split, 200k -> 800k triangles (seed 000 section 4.2):
// subdivide_uniform (parallel index arithmetic) on 1 and 2 threads next to
// subdivide_uniform_naive (face by face through the Model primitives), and
// OpenMesh's Loop subdivider (same 1-to-4 topology plus smoothing) when
// available. Counter "faces/s" = output faces per second.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "bench/support/grid_arrays.h"
#include <atelier/storage/builder.h>
#include <atelier/systems/mesh/subdivide.h>

#ifdef ATELIER_HAVE_OPENMESH
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>
#endif

namespace {

using namespace atelier;

constexpr int kCells = 316;  // 2 * 316^2 = 199,712 triangles

using Grid = bench::GridArrays;

const Grid& grid_200k() {
  static const Grid g = bench::wavy_grid(kCells);
  return g;
}

const Model& model_200k() {
  static const Model m = [] {
    Model x;
    const Grid& g = grid_200k();
    (void)add_polygon_surface(x, "grid", {g.positions, g.offsets, g.nodes}).value();
    return x;
  }();
  return m;
}

void set_counters(benchmark::State& state, std::size_t faces_out) {
  state.counters["faces/s"] =
      benchmark::Counter(static_cast<double>(faces_out), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["faces_in"] = static_cast<double>(faces_out / 4);
  state.counters["faces_out"] = static_cast<double>(faces_out);
}

void BM_SubdivideUniform(benchmark::State& state) {
  const Model& base = model_200k();
  ExecContext ctx;
  ctx.threads = static_cast<int>(state.range(0));
  std::size_t out = 0;
  for (auto _ : state) {
    state.PauseTiming();
    Model m = base;
    state.ResumeTiming();
    auto r = subdivide_uniform(m, ctx);
    if (!r) state.SkipWithError(r.status().to_string().c_str());
    out = m.num_faces();
    state.PauseTiming();
    { Model sink = std::move(m); }  // free outside the timed region
    state.ResumeTiming();
  }
  set_counters(state, out);
}
BENCHMARK(BM_SubdivideUniform)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SubdivideUniformNaive(benchmark::State& state) {
  const Model& base = model_200k();
  std::size_t out = 0;
  for (auto _ : state) {
    state.PauseTiming();
    Model m = base;
    state.ResumeTiming();
    auto r = subdivide_uniform_naive(m);
    if (!r) state.SkipWithError(r.status().to_string().c_str());
    out = m.num_faces();
    state.PauseTiming();
    { Model sink = std::move(m); }
    state.ResumeTiming();
  }
  set_counters(state, out);
}
BENCHMARK(BM_SubdivideUniformNaive)->Unit(benchmark::kMillisecond)->UseRealTime();

#ifdef ATELIER_HAVE_OPENMESH
void BM_SubdivideOpenMeshLoop(benchmark::State& state) {
  using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;
  const Grid& g = grid_200k();
  Mesh base;
  {
    std::vector<Mesh::VertexHandle> vh;
    for (const Vec3d& p : g.positions) vh.push_back(base.add_vertex(Mesh::Point(float(p.x()), float(p.y()), float(p.z()))));
    for (std::size_t f = 0; f + 1 < g.offsets.size(); ++f) {
      const std::uint32_t* c = g.nodes.data() + g.offsets[f];
      base.add_face(vh[c[0]], vh[c[1]], vh[c[2]]);
    }
  }
  std::size_t out = 0;
  for (auto _ : state) {
    state.PauseTiming();
    Mesh mesh = base;
    OpenMesh::Subdivider::Uniform::LoopT<Mesh> loop;
    loop.attach(mesh);
    state.ResumeTiming();
    loop(1);
    state.PauseTiming();
    loop.detach();
    out = mesh.n_faces();
    state.ResumeTiming();
  }
  set_counters(state, out);
}
BENCHMARK(BM_SubdivideOpenMeshLoop)->Unit(benchmark::kMillisecond)->UseRealTime();
#endif

}  // namespace
