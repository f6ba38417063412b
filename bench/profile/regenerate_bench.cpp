// Whole regeneration of each project template on one body (issue 4): the
// per-body collision set-up (Embree BVH, and the OpenVDB region-of-interest
// grid when enabled) plus regenerate() (node decoding, profiles, the
// modified variational subdivision with push-outs and collision-checked
// fairing, and the quality measures). Counters: output nodes, ms per body.
#include <benchmark/benchmark.h>

#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/profile/project_templates.h>
#include <atelier/systems/profile/regenerate.h>

using namespace atelier;

namespace {

struct Setup {
  MannequinTopology topo;
  ReferenceBody body;
  std::vector<ProfileTemplate> templates;
  std::vector<Vec3d> target;  // a sampled body, not the reference
  Box3d roi;
};

const Setup& setup() {
  static const Setup s = [] {
    Setup x;
    x.topo = make_mannequin_topology().value();
    x.body = make_mannequin(MannequinParams{}, x.topo).value();
    x.templates = make_project_templates(x.body).value();
    x.target = mannequin_positions(sample_mannequins(1, 31)[0], x.topo).value();
    for (const auto& t : x.templates)
      for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v) x.roi.extend(t.model.nodes.position[v]);
    return x;
  }();
  return s;
}

/// Args: template (0 top, 1 skirt, 2 trousers), levels, threads, grid (0/1).
void BM_RegenerateTemplate(benchmark::State& state) {
  const Setup& s = setup();
  const ProfileTemplate& t = s.templates[static_cast<std::size_t>(state.range(0))];
  RegenParams p;
  p.levels = static_cast<int>(state.range(1));
  ExecContext ctx;
  ctx.threads = static_cast<int>(state.range(2));
  ColliderParams cp;
  cp.use_grid = state.range(3) != 0;
  RegenQuality q;
  double grid_ms = 0;
  for (auto _ : state) {
    BodyCollider col;
    if (Status st = col.build(s.body.model, s.body.skin, s.target, s.roi, cp, ctx); !st) {
      state.SkipWithError(st.to_string().c_str());
      return;
    }
    auto r = regenerate(t, s.body, s.target, &col, p, ctx);
    if (!r) {
      state.SkipWithError(r.status().to_string().c_str());
      return;
    }
    q = r->quality;
    grid_ms = col.grid_build_ms();
    benchmark::DoNotOptimize(r->model.nodes.position.data());
  }
  state.SetLabel(t.name);
  state.counters["nodes"] = static_cast<double>(q.nodes);
  state.counters["inside"] = static_cast<double>(q.inside);
  state.counters["crack"] = q.crack;
  state.counters["grid_ms"] = grid_ms;
  state.counters["regen_ms"] = q.ms;
  state.counters["fair_ms"] = q.fair_ms;
  state.counters["fair_queries"] = static_cast<double>(q.fair_queries);
}
BENCHMARK(BM_RegenerateTemplate)
    ->ArgNames({"template", "levels", "threads", "grid"})
    ->ArgsProduct({{0, 1, 2}, {4}, {1, 2}, {0}})
    ->ArgsProduct({{0, 1, 2}, {4}, {2}, {1}})
    ->ArgsProduct({{1}, {5}, {2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
