// Throughput of the high-level edit operators (seed 000 Table 3) on a
// 200k-triangle grid: edge_split and edge_collapse at random edges, and
// edge_swap. Counter "ops/s" = successful operations per second; refused
// collapses/swaps (link condition, boundary) are counted in "refused".
// The "/ring_check" variants keep EditOptions::check_ring_nodes on (one scan
// of the node table per call, O(V)); the others switch it off, as a caller
// that knows the mesh has no stand-alone vertices would. OpenMesh's
// split / is_collapse_ok+collapse / is_flip_ok+flip on the same grid are the
// peer figures when OpenMesh is available.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include <atelier/storage/builder.h>
#include <atelier/systems/mesh/edit.h>

#ifdef ATELIER_HAVE_OPENMESH
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#endif

namespace {

using namespace atelier;

constexpr int kEditCells = 316;  // 2 * 316^2 = 199,712 triangles

Model make_edit_grid() {
  const int n = kEditCells;
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> off{0}, idx;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) p.emplace_back(i, j, 0.05 * std::sin(0.1 * i) * std::cos(0.1 * j));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      for (auto v : {id(i, j), id(i + 1, j), id(i + 1, j + 1)}) idx.push_back(v);
      off.push_back(static_cast<std::uint32_t>(idx.size()));
      for (auto v : {id(i, j), id(i + 1, j + 1), id(i, j + 1)}) idx.push_back(v);
      off.push_back(static_cast<std::uint32_t>(idx.size()));
    }
  Model m;
  (void)add_polygon_surface(m, "grid", {p, off, idx}).value();
  return m;
}

const Model& edit_grid() {
  static const Model m = make_edit_grid();
  return m;
}

/// Random live edge (edge slots are dense enough that rejection is cheap).
EdgeIdx random_edge(const Model& m, std::mt19937& rng) {
  std::uniform_int_distribution<std::uint32_t> d(0, static_cast<std::uint32_t>(m.edges.slots.capacity() - 1));
  for (;;) {
    const EdgeIdx e{d(rng)};
    if (m.alive(e)) return e;
  }
}

Vec3d mid(const Model& m, EdgeIdx e) {
  return 0.5 * (m.position(m.tail(halfedge_of(e, 0))) + m.position(m.head(halfedge_of(e, 0))));
}

template <class Op>
void run_edit(benchmark::State& state, Op op, std::size_t reset_every) {
  Model m = edit_grid();
  std::mt19937 rng(42);
  std::size_t done = 0, refused = 0, since_reset = 0;
  for (auto _ : state) {
    if (since_reset == reset_every) {  // keep the mesh near 200k faces
      state.PauseTiming();
      m = edit_grid();
      since_reset = 0;
      state.ResumeTiming();
    }
    const EdgeIdx e = random_edge(m, rng);
    if (op(m, e))
      ++done;
    else
      ++refused;
    ++since_reset;
  }
  state.counters["ops/s"] = benchmark::Counter(static_cast<double>(done), benchmark::Counter::kIsRate);
  state.counters["refused"] = static_cast<double>(refused);
  state.counters["faces"] = static_cast<double>(m.num_faces());
}

void BM_EdgeSplit(benchmark::State& state) {
  EditOptions opt;
  opt.check_ring_nodes = state.range(0) != 0;
  run_edit(
      state, [&](Model& m, EdgeIdx e) { return edge_split(m, m.handle(e), mid(m, e), opt).has_value(); }, 50'000);
}
BENCHMARK(BM_EdgeSplit)->ArgName("ring_check")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_EdgeCollapse(benchmark::State& state) {
  EditOptions opt;
  opt.check_ring_nodes = state.range(0) != 0;
  run_edit(
      state, [&](Model& m, EdgeIdx e) { return edge_collapse(m, m.handle(e), mid(m, e), opt).has_value(); }, 30'000);
}
BENCHMARK(BM_EdgeCollapse)->ArgName("ring_check")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_EdgeSwap(benchmark::State& state) {
  EditOptions opt;
  opt.check_ring_nodes = false;
  run_edit(state, [&](Model& m, EdgeIdx e) { return edge_swap(m, m.handle(e), opt).has_value(); }, 1'000'000);
}
BENCHMARK(BM_EdgeSwap)->Unit(benchmark::kMicrosecond);

#ifdef ATELIER_HAVE_OPENMESH
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

OmMesh make_om_grid() {
  const Model& src = edit_grid();
  OmMesh om;
  om.request_vertex_status();
  om.request_edge_status();
  om.request_face_status();
  std::vector<OmMesh::VertexHandle> vh;
  for (std::uint32_t v = 0; v < src.nodes.slots.capacity(); ++v) {
    const Vec3d& p = src.position(NodeIdx{v});
    vh.push_back(om.add_vertex(OmMesh::Point(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()))));
  }
  std::vector<NodeIdx> c;
  for (std::uint32_t f = 0; f < src.faces.slots.capacity(); ++f) {
    src.face_nodes(FaceIdx{f}, c);
    om.add_face(vh[c[0].value], vh[c[1].value], vh[c[2].value]);
  }
  return om;
}

template <class Op>
void run_om(benchmark::State& state, Op op, std::size_t reset_every) {
  const OmMesh base = make_om_grid();
  OmMesh om = base;
  std::mt19937 rng(42);
  std::size_t done = 0, refused = 0, since_reset = 0;
  for (auto _ : state) {
    if (since_reset == reset_every) {
      state.PauseTiming();
      om = base;
      since_reset = 0;
      state.ResumeTiming();
    }
    std::uniform_int_distribution<int> d(0, static_cast<int>(om.n_edges()) - 1);
    OmMesh::EdgeHandle e;
    do {
      e = om.edge_handle(d(rng));
    } while (om.status(e).deleted());
    if (op(om, e))
      ++done;
    else
      ++refused;
    ++since_reset;
  }
  state.counters["ops/s"] = benchmark::Counter(static_cast<double>(done), benchmark::Counter::kIsRate);
  state.counters["refused"] = static_cast<double>(refused);
}

void BM_OpenMeshEdgeSplit(benchmark::State& state) {
  run_om(
      state,
      [](OmMesh& om, OmMesh::EdgeHandle e) {
        const auto h = om.halfedge_handle(e, 0);
        const auto p = 0.5f * (om.point(om.from_vertex_handle(h)) + om.point(om.to_vertex_handle(h)));
        om.split(e, om.add_vertex(p));
        return true;
      },
      50'000);
}
BENCHMARK(BM_OpenMeshEdgeSplit)->Unit(benchmark::kMicrosecond);

void BM_OpenMeshEdgeCollapse(benchmark::State& state) {
  run_om(
      state,
      [](OmMesh& om, OmMesh::EdgeHandle e) {
        const auto h = om.halfedge_handle(e, 0);
        if (!om.is_collapse_ok(h)) return false;
        const auto p = 0.5f * (om.point(om.from_vertex_handle(h)) + om.point(om.to_vertex_handle(h)));
        om.set_point(om.to_vertex_handle(h), p);
        om.collapse(h);
        return true;
      },
      30'000);
}
BENCHMARK(BM_OpenMeshEdgeCollapse)->Unit(benchmark::kMicrosecond);

void BM_OpenMeshEdgeFlip(benchmark::State& state) {
  run_om(
      state,
      [](OmMesh& om, OmMesh::EdgeHandle e) {
        if (!om.is_flip_ok(e)) return false;
        om.flip(e);
        return true;
      },
      1'000'000);
}
BENCHMARK(BM_OpenMeshEdgeFlip)->Unit(benchmark::kMicrosecond);
#endif

}  // namespace
