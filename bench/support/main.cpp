// atelier_bench entry point: the benchmarks run under the memory policy the
// CLI uses for batch work (engine/memory.h), so figures describe the engine
// as deployed. ATELIER_BENCH_DEFAULT_MALLOC=1 keeps glibc's default policy
// (every large block freshly faulted) to measure the cold case.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <string_view>

#include <atelier/engine/memory.h>

int main(int argc, char** argv) {
  const char* cold = std::getenv("ATELIER_BENCH_DEFAULT_MALLOC");
  const bool policy = !(cold && std::string_view(cold) == "1") && atelier::apply_memory_policy();
  benchmark::AddCustomContext("memory_policy", policy ? "batch (freed memory kept mapped)" : "glibc default");
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
