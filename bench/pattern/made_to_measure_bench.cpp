// Made-to-measure patterns (issue 22): bodies per second of the pattern sets
// of the project templates (the top's front and back bodies and yokes, cut
// along its marked seams, and its collar; the skirt; the trousers' three
// surfaces: 9 pieces per body), what `atelier regen
// --patterns` adds per body, over 8 sampled mannequins in parallel over
// bodies (one task per body, as the batch job runs), 1 or 2 threads.
//  * BM_MadeToMeasure_Patterns: write_made_to_measure_pattern on the
//    regenerated templates (seams, flattening, pattern, and with range(1) =
//    1 the SVG/DXF/CSV files into a temporary folder; 0: the pattern set
//    only);
//  * BM_MadeToMeasure_Regen: the regeneration alone (the batch job without
//    --patterns), the reference for the ratio;
//  * BM_MadeToMeasure_RegenAndPatterns: both, as `regen --patterns` does.
//  * ..._Prepared: the same with MadeToMeasurePatterns (made_to_measure.h),
//    prepared once per template on the first sampled body's garment (not
//    timed): flattening built once per piece topology (again for a body
//    whose seams open with other fans: its own open_seams per body), every
//    body warm-started from that reference (its pattern fitted to the body,
//    seam multipliers, Cholesky factor; MadeToMeasureOptions::warm_start,
//    the default).
// Counters bodies_per_s (items_per_second); iterations_per_body (phase 2
// L-BFGS iterations of all pieces per body) and warm_pieces_per_body.
#include <atelier/engine/parallel.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/pattern/made_to_measure.h>
#include <atelier/systems/profile/regenerate.h>
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>

#include "tests/support/project_templates.h"

using namespace atelier;

namespace {

namespace fs = std::filesystem;
constexpr std::size_t kBodies = 8;

Box3d roi() {
  Box3d b;
  for (const auto& t : testing::template_fixture().templates)
    for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v)
      if (t.model.alive(NodeIdx{v})) b.extend(t.model.position(NodeIdx{v}));
  return b;
}

const std::vector<std::vector<Vec3d>>& bodies() {
  static const auto b = [] {
    std::vector<std::vector<Vec3d>> out;
    for (const auto& p : sample_mannequins(kBodies, 2026))
      out.push_back(mannequin_positions(p, testing::template_fixture().topo).value());
    return out;
  }();
  return b;
}

Expected<std::vector<RegenResult>> regen(std::size_t i, ColliderPool& pool) {
  const auto& f = testing::template_fixture();
  static const Box3d box = roi();
  return regenerate_on_body(f.templates, f.body, bodies()[i], box, {}, {.use_grid = false}, ExecContext::sequential(),
                            pool);
}

const std::vector<std::vector<RegenResult>>& regenerated() {
  static const auto r = [] {
    std::vector<std::vector<RegenResult>> out;
    ColliderPool pool;
    for (std::size_t i = 0; i < kBodies; ++i) out.push_back(regen(i, pool).value());
    return out;
  }();
  return r;
}

/// Phase 2 figures of one body's pattern sets.
struct Tally {
  long iterations = 0, warm = 0;
  void add(const MadeToMeasureReport& r) {
    for (const PieceFlattening& p : r.files.flattening.pieces) iterations += p.iterations, warm += p.warm_started;
  }
};

Status patterns(const std::vector<RegenResult>& garments, bool files, const fs::path& dir, Tally& tally) {
  MadeToMeasureOptions o;
  o.files.svg = o.files.dxf = o.csv = files;
  for (std::size_t k = 0; k < garments.size(); ++k) {
    auto rep = write_made_to_measure_pattern(garments[k].model, o, dir / std::to_string(k), ExecContext::sequential());
    if (!rep) return rep.status();
    tally.add(*rep);
    if (rep->flipped) return Status(ErrorCode::kInternal, "flipped triangles");
  }
  return {};
}

const std::vector<MadeToMeasurePatterns>& prepared(bool files) {
  static const auto make = [](bool f) {
    MadeToMeasureOptions o;
    o.files.svg = o.files.dxf = o.csv = f;
    std::vector<MadeToMeasurePatterns> out(regenerated()[0].size());
    for (std::size_t k = 0; k < out.size(); ++k)
      if (Status st = out[k].prepare(regenerated()[0][k].model, o); !st) throw Error(st);
    return out;
  };
  static const auto with = make(true), without = make(false);
  return files ? with : without;
}

Status patterns_prepared(const std::vector<RegenResult>& garments, bool files, const fs::path& dir, Tally& tally) {
  const auto& p = prepared(files);
  for (std::size_t k = 0; k < garments.size(); ++k) {
    auto rep = p[k].write(garments[k].model, dir / std::to_string(k), ExecContext::sequential());
    if (!rep) return rep.status();
    tally.add(*rep);
    if (rep->flipped) return Status(ErrorCode::kInternal, "flipped triangles");
  }
  return {};
}

ExecContext over_bodies(const benchmark::State& st) {
  ExecContext c;
  c.threads = static_cast<int>(st.range(0));
  c.sequential_threshold = 1;
  c.grain = 1;
  return c;
}

void run(benchmark::State& st, bool do_regen, bool do_patterns, bool files, bool reuse = false) {
  const ExecContext ctx = over_bodies(st);
  (void)regenerated();
  if (reuse) (void)prepared(files);
  const fs::path dir = fs::temp_directory_path() / ("atelier_mtm_bench_" + std::to_string(::getpid()));
  ColliderPool pool;
  std::vector<std::string> errors(kBodies);
  std::vector<Tally> tally(kBodies);
  for (auto _ : st) {
    par::for_each_n(ctx, kBodies, [&](std::size_t i) {
      const std::vector<RegenResult>* g = &regenerated()[i];
      Expected<std::vector<RegenResult>> fresh = std::vector<RegenResult>{};
      if (do_regen) {
        fresh = regen(i, pool);
        if (!fresh) {
          errors[i] = fresh.status().to_string();
          return;
        }
        g = &*fresh;
      }
      if (do_patterns)
        if (Status s = reuse ? patterns_prepared(*g, files, dir / std::to_string(i), tally[i])
                             : patterns(*g, files, dir / std::to_string(i), tally[i]);
            !s)
          errors[i] = s.to_string();
    });
    for (const auto& e : errors)
      if (!e.empty()) {
        st.SkipWithError(e.c_str());
        return;
      }
  }
  fs::remove_all(dir);
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * kBodies));
  st.counters["bodies_per_s"] =
      benchmark::Counter(static_cast<double>(st.iterations() * kBodies), benchmark::Counter::kIsRate);
  if (do_patterns) {
    long it = 0, warm = 0;
    for (const Tally& t : tally) it += t.iterations, warm += t.warm;
    const double runs = static_cast<double>(st.iterations() * kBodies);
    st.counters["iterations_per_body"] = static_cast<double>(it) / runs;
    st.counters["warm_pieces_per_body"] = static_cast<double>(warm) / runs;
  }
}

void BM_MadeToMeasure_Patterns(benchmark::State& st) {
  run(st, false, true, st.range(1) != 0);
}
void BM_MadeToMeasure_Regen(benchmark::State& st) {
  run(st, true, false, false);
}
void BM_MadeToMeasure_RegenAndPatterns(benchmark::State& st) {
  run(st, true, true, true);
}

void BM_MadeToMeasure_PatternsPrepared(benchmark::State& st) {
  run(st, false, true, st.range(1) != 0, true);
}
void BM_MadeToMeasure_RegenAndPatternsPrepared(benchmark::State& st) {
  run(st, true, true, true, true);
}

}  // namespace

BENCHMARK(BM_MadeToMeasure_PatternsPrepared)
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->ArgNames({"threads", "files"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_MadeToMeasure_RegenAndPatternsPrepared)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_MadeToMeasure_Patterns)
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->ArgNames({"threads", "files"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_MadeToMeasure_Regen)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MadeToMeasure_RegenAndPatterns)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
