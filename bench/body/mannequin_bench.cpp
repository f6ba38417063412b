// Reference bodies: generating 1,000 procedural mannequins (systems/mannequin.h)
// at the default resolution, 1 and 2 threads (parallel over bodies), as full
// ReferenceBody models and as position arrays only (the body-set fast path);
// counters give ms per body and bytes per body.
#include <benchmark/benchmark.h>

#include <chrono>
#include <vector>

#include <atelier/engine/parallel.h>
#include <atelier/systems/body/mannequin.h>

namespace {

using namespace atelier;

constexpr std::size_t kBodies = 1000;

const MannequinTopology& default_topology() {
  static const MannequinTopology t = make_mannequin_topology().value();
  return t;
}

const std::vector<MannequinParams>& sampled() {
  static const std::vector<MannequinParams> p = sample_mannequins(kBodies, 1);
  return p;
}

template <class T>
std::size_t bytes(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

// Heap bytes held by the main columns of a body's model (tables, not
// allocator overhead) plus its feature tables.
std::size_t model_bytes(const ReferenceBody& b) {
  const Model& m = b.model;
  std::size_t s = bytes(m.nodes.position) + bytes(m.nodes.position_backup) + bytes(m.nodes.uv) + bytes(m.nodes.out) +
                  bytes(m.nodes.surface) + bytes(m.nodes.in_face);
  s += bytes(m.edges.flags) + bytes(m.edges.mesh_edge);
  s += bytes(m.halfedges.tail) + bytes(m.halfedges.face) + bytes(m.halfedges.next) + bytes(m.halfedges.prev) +
       bytes(m.halfedges.vnext) + bytes(m.halfedges.vprev);
  s += bytes(m.faces.halfedge) + bytes(m.faces.surface) + bytes(m.faces.flags);
  s += bytes(m.attrib_nodes.kind) + bytes(m.attrib_nodes.element) + bytes(m.attrib_nodes.corner) +
       bytes(m.attrib_nodes.param) + bytes(m.attrib_nodes.position) + bytes(m.attrib_nodes.owner) +
       bytes(m.attrib_nodes.surface);
  for (std::size_t r = 0; r < m.attrib_edges.nodes.rows(); ++r) s += m.attrib_edges.nodes.size(r) * sizeof(AttribNodeIdx);
  s += (m.nodes.slots.capacity() + m.edges.slots.capacity() + m.faces.slots.capacity()) * 2 * sizeof(std::uint32_t);
  return s;
}

void BM_Mannequins1000(benchmark::State& state) {
  const MannequinTopology& t = default_topology();
  const auto& params = sampled();
  ExecContext ctx;
  ctx.threads = static_cast<int>(state.range(0));
  std::size_t mem = 0, faces = 0;
  double seconds = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto bodies = make_mannequins(params, t, ctx);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!bodies) {
      state.SkipWithError(bodies.status().to_string().c_str());
      return;
    }
    mem = model_bytes(bodies->front());
    faces = bodies->front().model.num_faces();
    benchmark::DoNotOptimize(bodies->back().model.nodes.position.data());
  }
  state.counters["ms_per_body"] = 1e3 * seconds / double(state.iterations() * kBodies);
  state.counters["bytes_per_body"] = double(mem);
  state.counters["faces"] = double(faces);
}
BENCHMARK(BM_Mannequins1000)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

void BM_MannequinPositions1000(benchmark::State& state) {
  const MannequinTopology& t = default_topology();
  const auto& params = sampled();
  ExecContext ctx;
  ctx.threads = static_cast<int>(state.range(0));
  ctx.sequential_threshold = 2;
  ctx.grain = 1;
  std::vector<std::vector<Vec3d>> out(kBodies);
  double seconds = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    par::for_each_n(ctx, kBodies, [&](std::size_t i) { out[i] = mannequin_positions(params[i], t).value(); });
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    benchmark::DoNotOptimize(out.back().data());
  }
  state.counters["ms_per_body"] = 1e3 * seconds / double(state.iterations() * kBodies);
  state.counters["bytes_per_body"] = double(t.num_nodes * sizeof(Vec3d));
}
BENCHMARK(BM_MannequinPositions1000)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

void BM_MannequinTopology(benchmark::State& state) {
  for (auto _ : state) {
    auto t = make_mannequin_topology();
    benchmark::DoNotOptimize(t->face_nodes.data());
  }
}
BENCHMARK(BM_MannequinTopology)->Unit(benchmark::kMillisecond);

}  // namespace
