// The timed loop the extrusion benchmarks share: a fresh copy of the base
// model per iteration (untimed), one extrude() call on one thread (timed),
// the last report kept for the counters.
#pragma once

#include <atelier/systems/sketch/extrude.h>
#include <benchmark/benchmark.h>

namespace atelier::bench {

/// Returns false (the benchmark marked skipped) when extrude fails.
inline bool time_extrude(benchmark::State& state, const Model& base, const ExtrudeStrokes& in,
                         const ExtrudeOptions& opt, ExtrudeReport& last) {
  for (auto _ : state) {
    state.PauseTiming();
    Model m = base;
    state.ResumeTiming();
    auto r = extrude(m, in, opt, ExecContext::sequential());
    if (!r) {
      state.SkipWithError(r.status().message().c_str());
      return false;
    }
    last = *r;
    benchmark::DoNotOptimize(m.num_faces());
  }
  state.counters["faces_in"] = static_cast<double>(base.num_faces());
  return true;
}

}  // namespace atelier::bench
