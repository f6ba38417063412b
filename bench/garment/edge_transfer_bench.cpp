// The edge transfer alone (issue 26, branch lanes13): male_casualsuit01
// (8,426 vertices) decoded on 64 random MakeHuman adults, transferred one
// body at a time (apply_edge_transfer, today's job path) against bodies as
// SIMD lanes (apply_edge_transfer_bodies on the 64 at once: 8 lanes with
// AVX-512, 4 with AVX2, 2 with SSE2, each lane taking the next body when
// its body stops). One thread;
// the counter ms_per_body is CPU time per body (the machine is shared:
// compare rows of one run). Each iteration restores the decoded garments
// (a copy, in every row). Skipped without the shared MakeHuman data.
//
//   BM_EdgeTransferMakeHuman/0/s: one body at a time
//   BM_EdgeTransferMakeHuman/1/s: lanes, the kernel cpu_features() picks
//   BM_EdgeTransferMakeHuman/2/s: lanes, AVX2 (4)
//   BM_EdgeTransferMakeHuman/3/s: lanes, baseline instruction set (SSE2, 2)
//   BM_EdgeTransferMakeHuman/4/s: lanes, AVX-512 (8)
// s = 0: the garment's own stop (each body its own number of sweeps, a
// group of lanes as many as its slowest); s > 0: exactly s accelerated
// sweeps for every body (the cost of a sweep, without that wait).
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/edge_transfer.h>
#include <atelier/systems/garment/makehuman_binding.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

using namespace atelier;
namespace fs = std::filesystem;

namespace {

struct TransferScene {
  bool ok = false;
  std::shared_ptr<GarmentFamily> family;
  std::unique_ptr<GarmentTemplate> garment;
  std::vector<std::vector<Vec3d>> bodies, decoded;
};

const TransferScene& transfer_scene() {
  static const TransferScene s = [] {
    TransferScene s;
    const fs::path dir = fs::path(ATELIER_BENCH_SHARED_DATA) / "makehuman";
    if (!fs::exists(dir / "base.obj")) return s;
    const makehuman::HumanLibrary lib = makehuman::HumanLibrary::load(dir);
    const ReferenceBody ref = makehuman::make_reference_body(lib);
    auto fam = GarmentFamily::of(ref);
    auto soup = makehuman::fitted_garment(lib, dir / "clothes" / "male_casualsuit01.mhclo");
    if (!fam || !soup) return s;
    s.family = std::make_shared<GarmentFamily>(std::move(*fam));
    auto enc = encode_garment(*s.family, "male_casualsuit01", std::move(*soup));
    if (!enc) return s;
    s.garment = std::make_unique<GarmentTemplate>(std::move(*enc));
    const auto params = makehuman::sample_adults(64, 1);
    const std::size_t nskin = s.family->reference_positions.size();
    std::vector<Vec3f> h(lib.vertex_count());
    for (const auto& p : params) {
      lib.build(p, h);
      std::vector<Vec3d> skin(nskin);
      for (std::size_t v = 0; v < nskin; ++v) skin[v] = makehuman::kMakeHumanToMetres * h[v].cast<double>();
      std::vector<Vec3d> g(s.garment->mesh.positions.size());
      if (!decode_detail(s.garment->encoding, s.family->polygons, skin, g)) return s;
      s.bodies.push_back(std::move(skin));
      s.decoded.push_back(std::move(g));
    }
    s.ok = true;
    return s;
  }();
  return s;
}

void BM_EdgeTransferMakeHuman(benchmark::State& st) {
  const TransferScene& s = transfer_scene();
  if (!s.ok) {
    st.SkipWithError("MakeHuman data absent");
    return;
  }
  const auto mode = st.range(0);
  EdgeTransfer t = s.garment->transfer;
  if (st.range(1) > 0) {  // a fixed number of sweeps: every lane stops with the others
    t.length_tolerance = 0;
    t.length_iterations = static_cast<int>(st.range(1));
  }
  const auto tris = s.family->collision->triangles();
  const std::size_t nb = s.bodies.size();
  std::vector<std::vector<Vec3d>> g = s.decoded;
  std::vector<std::span<const Vec3d>> bs(s.bodies.begin(), s.bodies.end());
  std::vector<std::span<Vec3d>> gs(g.begin(), g.end());
  std::vector<Status> status(nb);
  const EdgeTransferKernel kernel = mode == 1   ? EdgeTransferKernel::kAuto
                                    : mode == 2 ? EdgeTransferKernel::kAvx2
                                    : mode == 3 ? EdgeTransferKernel::kGeneric
                                                : EdgeTransferKernel::kAvx512;
  const ExecContext seq = ExecContext::sequential();
  for (auto _ : st) {
    for (std::size_t b = 0; b < nb; ++b) std::copy(s.decoded[b].begin(), s.decoded[b].end(), g[b].begin());
    if (mode == 0) {
      for (std::size_t b = 0; b < nb; ++b)
        if (!apply_edge_transfer(t, bs[b], tris, gs[b], seq)) st.SkipWithError("transfer failed");
    } else if (!apply_edge_transfer_bodies(t, bs, tris, gs, status, kernel)) {
      st.SkipWithError("transfer failed");
    }
    benchmark::DoNotOptimize(g.front().data());
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * nb));
  st.SetLabel(mode == 0 ? "one body at a time" : std::to_string(edge_transfer_lanes(kernel)) + " lanes");
  st.counters["ms_per_body"] = benchmark::Counter(
      1e-3 * static_cast<double>(nb), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_EdgeTransferMakeHuman)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {0, 16}})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime();

}  // namespace
