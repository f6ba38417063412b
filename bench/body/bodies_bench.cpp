// Body sets (issue 3): generating 1,000 MakeHuman bodies in chunks, ms and
// memory per body. (Mannequins: bench/mannequin_bench.cpp.)
#include <benchmark/benchmark.h>

#include <filesystem>

#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/makehuman_body.h>

using namespace atelier;
namespace fs = std::filesystem;

namespace {

void BM_MakeHumanBodies_1000(benchmark::State& st) {
  const fs::path dir = fs::path(ATELIER_BENCH_SHARED_DATA) / "makehuman";
  if (!fs::exists(dir / "base.obj")) {
    st.SkipWithError("MakeHuman data absent");
    return;
  }
  static const auto lib = std::make_shared<const makehuman::HumanLibrary>(makehuman::HumanLibrary::load(dir));
  static const auto ref = std::make_shared<const ReferenceBody>(makehuman::make_reference_body(*lib));
  const auto params = makehuman::sample_adults(1000, 7);
  makehuman::MakeHumanSource src(lib, params, ref);
  ExecContext ctx;
  ctx.threads = static_cast<int>(st.range(0));
  BodySet chunk(ref);
  std::vector<BodyFailure> fail;
  constexpr std::size_t kChunk = 64;
  for (auto _ : st)
    for (std::size_t first = 0; first < params.size(); first += kChunk) {
      src.generate(first, kChunk, chunk, fail, ctx);
      benchmark::DoNotOptimize(chunk.x(0).data());
    }
  st.counters["bodies/s"] = benchmark::Counter(1000.0, benchmark::Counter::kIsIterationInvariantRate);
  // Stored per body (float SoA) and the transient full-mesh build (19,158 vertices).
  st.counters["stored_bytes/body"] = static_cast<double>(chunk.bytes_per_body());
  st.counters["transient_bytes/body"] = static_cast<double>(lib->vertex_count() * sizeof(Vec3f) +
                                                            ref->model.nodes.slots.capacity() * sizeof(Vec3d));
  st.SetLabel(std::to_string(st.range(0)) + " threads, chunks of 64");
}
BENCHMARK(BM_MakeHumanBodies_1000)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace
