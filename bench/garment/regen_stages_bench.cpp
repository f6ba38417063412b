// Where one regenerated body's time goes (issue 26, branch regen16;
// docs/performance.md, "fifth round"): male_casualsuit01 on 32 random
// MakeHuman adults, each stage of GarmentRegenerator::run's per-body work
// timed on its own with the thread's CPU clock, one thread:
//
//   build_ms       HumanLibrary::build and the skin in double
//   transfer_ms    apply_edge_transfer_bodies, 16 bodies as lanes (as run())
//   transfer1_ms   apply_edge_transfer, one body at a time
//   refit_ms       CollisionBody::build (float copy, Embree refit)
//   pass_ms        resolve_collisions with the final distances
//   queries        the pass's exact body queries per body
//   query_us       one exact query at the pass's final positions, with the
//                  template's hint (the pass's first queries use these)
//   best_hint_us   the same with the answer itself as the hint
//   answer_us      the answer's triangle alone (query_triangle): what a
//                  query costs without proving that no triangle is nearer
//
// The one-body decode (decode_detail) is left out: the job decodes in
// batches (detail_decode_batch.cpp), about a tenth of its cost. Skipped
// without the shared MakeHuman data.
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/garment/collision_pass.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/edge_transfer.h>
#include <atelier/systems/garment/makehuman_binding.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <benchmark/benchmark.h>

#include <ctime>
#include <filesystem>
#include <memory>

using namespace atelier;
namespace fs = std::filesystem;

namespace {

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

void BM_RegenStagesMakeHuman(benchmark::State& st) {
  const fs::path dir = fs::path(ATELIER_BENCH_SHARED_DATA) / "makehuman";
  if (!fs::exists(dir / "base.obj")) {
    st.SkipWithError("MakeHuman data absent");
    return;
  }
  const makehuman::HumanLibrary lib = makehuman::HumanLibrary::load(dir);
  const ReferenceBody ref = makehuman::make_reference_body(lib);
  auto fam = GarmentFamily::of(ref);
  auto soup = makehuman::fitted_garment(lib, dir / "clothes" / "male_casualsuit01.mhclo");
  if (!fam || !soup) {
    st.SkipWithError("could not set up the MakeHuman family or garment");
    return;
  }
  auto g = encode_garment(*fam, "male_casualsuit01", std::move(*soup));
  if (!g) {
    st.SkipWithError(g.status().to_string().c_str());
    return;
  }
  const std::size_t nb = 32, nskin = fam->reference_positions.size(), nv = g->mesh.positions.size();
  const auto params = makehuman::sample_adults(nb, 7);
  const ExecContext seq = ExecContext::sequential();
  const auto tris = fam->collision->triangles();
  double build = 0, lanes = 0, one = 0, refit = 0, pass = 0, q_hint = 0, q_best = 0, q_tri = 0, queries = 0;
  std::size_t nq = 0;
  for (auto _ : st) {
    build = lanes = one = refit = pass = q_hint = q_best = q_tri = queries = 0;
    nq = 0;
    std::vector<std::vector<Vec3d>> skin(nb, std::vector<Vec3d>(nskin)), dec(nb, std::vector<Vec3d>(nv)), dec1;
    std::vector<Vec3f> h(lib.vertex_count());
    for (std::size_t b = 0; b < nb; ++b) {
      double t = thread_cpu_ms();
      lib.build(params[b], h);
      for (std::size_t v = 0; v < nskin; ++v) skin[b][v] = makehuman::kMakeHumanToMetres * h[v].cast<double>();
      build += thread_cpu_ms() - t;
      if (!decode_detail(g->encoding, fam->polygons, skin[b], dec[b], seq)) st.SkipWithError("decode failed");
    }
    dec1 = dec;
    for (std::size_t b0 = 0; b0 < nb; b0 += 16) {
      const std::size_t k = std::min<std::size_t>(16, nb - b0);
      std::vector<std::span<const Vec3d>> bs(skin.begin() + static_cast<std::ptrdiff_t>(b0),
                                             skin.begin() + static_cast<std::ptrdiff_t>(b0 + k));
      std::vector<std::span<Vec3d>> gs(dec.begin() + static_cast<std::ptrdiff_t>(b0),
                                       dec.begin() + static_cast<std::ptrdiff_t>(b0 + k));
      std::vector<Status> status(k);
      const double t = thread_cpu_ms();
      if (!apply_edge_transfer_bodies(g->transfer, bs, tris, gs, status)) st.SkipWithError("transfer failed");
      lanes += thread_cpu_ms() - t;
    }
    for (std::size_t b = 0; b < nb; ++b) {
      double t = thread_cpu_ms();
      if (!apply_edge_transfer(g->transfer, skin[b], tris, dec1[b], seq)) st.SkipWithError("transfer failed");
      one += thread_cpu_ms() - t;
      t = thread_cpu_ms();
      CollisionBody cb;
      if (!cb.build(fam->collision, skin[b], {}, seq)) st.SkipWithError("collision body failed");
      refit += thread_cpu_ms() - t;
      t = thread_cpu_ms();
      std::vector<BodyDistance> fin;
      auto rep = resolve_collisions(dec[b], g->adjacency, g->clearance, cb, {}, fin, seq);
      pass += thread_cpu_ms() - t;
      if (!rep) {
        st.SkipWithError(rep.status().to_string().c_str());
        break;
      }
      queries += static_cast<double>(rep->queries);
      const std::vector<Vec3d>& p = dec[b];
      std::vector<BodyDistance> a(nv);
      double sink = 0;
      t = thread_cpu_ms();
      for (std::size_t v = 0; v < nv; ++v) a[v] = cb.query(p[v], g->clearance.triangle[v]);
      q_hint += thread_cpu_ms() - t;
      t = thread_cpu_ms();
      for (std::size_t v = 0; v < nv; ++v) sink += cb.query(p[v], a[v].triangle).distance;
      q_best += thread_cpu_ms() - t;
      t = thread_cpu_ms();
      for (std::size_t v = 0; v < nv; ++v) sink += cb.query_triangle(p[v], a[v].triangle).distance;
      q_tri += thread_cpu_ms() - t;
      benchmark::DoNotOptimize(sink);
      nq += nv;
    }
  }
  const double n = static_cast<double>(nb), q = static_cast<double>(std::max<std::size_t>(nq, 1));
  st.counters["build_ms"] = build / n;
  st.counters["transfer_ms"] = lanes / n;
  st.counters["transfer1_ms"] = one / n;
  st.counters["refit_ms"] = refit / n;
  st.counters["pass_ms"] = pass / n;
  st.counters["queries"] = queries / n;
  st.counters["query_us"] = 1e3 * q_hint / q;
  st.counters["best_hint_us"] = 1e3 * q_best / q;
  st.counters["answer_us"] = 1e3 * q_tri / q;
}
BENCHMARK(BM_RegenStagesMakeHuman)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
