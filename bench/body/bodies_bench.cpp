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

// Issue 26: drawing one adult. Sliders only (the uniform height slider, the
// old draw) side by side with the stature draw that regen's MakeHuman
// source now makes per body (its sliders plus the height slider inverted
// from a drawn stature), and one body's full build for scale.
const makehuman::HumanLibrary* bench_library() {
  const fs::path dir = fs::path(ATELIER_BENCH_SHARED_DATA) / "makehuman";
  if (!fs::exists(dir / "base.obj")) return nullptr;
  static const makehuman::HumanLibrary lib = makehuman::HumanLibrary::load(dir);
  return &lib;
}

void BM_MakeHumanAdult_Sliders(benchmark::State& st) {
  std::size_t i = 0;
  for (auto _ : st) benchmark::DoNotOptimize(makehuman::sample_adult(7, i++).height);
}
BENCHMARK(BM_MakeHumanAdult_Sliders)->Unit(benchmark::kMicrosecond);

void BM_MakeHumanAdult_Stature(benchmark::State& st) {
  const makehuman::HumanLibrary* lib = bench_library();
  if (!lib) return st.SkipWithError("MakeHuman data absent");
  std::size_t i = 0;
  for (auto _ : st) benchmark::DoNotOptimize(makehuman::sample_adult(*lib, 7, i++).height);
}
BENCHMARK(BM_MakeHumanAdult_Stature)->Unit(benchmark::kMicrosecond);

void BM_MakeHumanAdult_Build(benchmark::State& st) {
  const makehuman::HumanLibrary* lib = bench_library();
  if (!lib) return st.SkipWithError("MakeHuman data absent");
  std::vector<Vec3f> full(lib->vertex_count());
  std::size_t i = 0;
  for (auto _ : st) {
    lib->build(makehuman::sample_adult(7, i++), full);
    benchmark::DoNotOptimize(full.data());
  }
}
BENCHMARK(BM_MakeHumanAdult_Build)->Unit(benchmark::kMicrosecond);

}  // namespace
