// Detail templates (issue 5): p-polygon search against nanoflann and brute
// force, decoding throughput next to a STREAM-style bandwidth probe, batched
// decoding, and 1,000 MakeHuman bodies end to end.
#include <benchmark/benchmark.h>

#include <chrono>
#include <filesystem>
#include <memory>

#include <atelier/engine/parallel.h>
#include <atelier/engine/random.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/body/makehuman_body.h>
#include "tests/support/shapes.h"

#ifdef ATELIER_HAVE_NANOFLANN
#include <nanoflann.hpp>
#endif

using namespace atelier;
namespace fs = std::filesystem;

namespace {

fs::path mh_dir() {
  return fs::path(ATELIER_BENCH_SHARED_DATA) / "makehuman";
}

struct Scene {
  std::shared_ptr<const makehuman::HumanLibrary> lib;  // null without the data
  std::shared_ptr<ReferenceBody> ref;
  BodyPolygons poly;
  std::vector<Vec3d> pos;
  std::vector<Vec3d> garment;  // 30k points 5-30 mm outside the skin
  std::string body_name;
};

const Scene& scene() {
  static const Scene s = [] {
    Scene s;
    if (fs::exists(mh_dir() / "base.obj")) {
      s.lib = std::make_shared<const makehuman::HumanLibrary>(makehuman::HumanLibrary::load(mh_dir()));
      s.ref = std::make_shared<ReferenceBody>(makehuman::make_reference_body(*s.lib));
      s.body_name = "makehuman skin (13,378 quads)";
    } else {
      s.ref = shapes::body_from(shapes::uv_sphere(160, 84, 0.3));
      s.body_name = "uv sphere (13,440 polygons)";
    }
    s.poly = BodyPolygons::from_model(s.ref->model);
    s.pos = skin_positions(*s.ref);
    PolygonFrames fr;
    compute_frames(s.poly, s.pos, fr);
    SplitMix64 r(1);
    // Garment-like: points near consecutive polygons (mesh order, as a
    // garment's own vertex order is spatially coherent).
    for (std::size_t i = 0; s.garment.size() < 30'000; ++i) {
      const std::size_t f = (i / 3) % s.poly.size();
      if (fr.degenerate[f]) continue;
      s.garment.push_back(fr.centroid[f].cast<double>() + r.uniform(0.005, 0.03) * fr.x[f].cast<double>() +
                          0.004 * Vec3d(r.normal(), r.normal(), r.normal()));
    }
    return s;
  }();
  return s;
}

ExecContext threads(int t) {
  ExecContext c;
  c.threads = t;
  return c;
}

std::vector<Vec3d> centroids(const Scene& s, std::vector<std::uint8_t>& skip) {
  PolygonFrames fr;
  compute_frames(s.poly, s.pos, fr);
  std::vector<Vec3d> c;
  for (auto& x : fr.centroid) c.push_back(x.cast<double>());
  skip = fr.degenerate;
  return c;
}

constexpr std::size_t kNq = 134;  // round(13378 / 100)

void BM_PPolygonSearch_Grid(benchmark::State& st) {
  const Scene& s = scene();
  std::vector<std::uint8_t> skip;
  const auto c = centroids(s, skip);
  CentroidGrid grid;
  grid.build(c, skip, kNq);
  const ExecContext ctx = threads(static_cast<int>(st.range(0)));
  // Every query's k polygons are kept (what encoding needs), nearest first.
  std::vector<std::uint32_t> out(s.garment.size() * kNq);
  for (auto _ : st) {
    grid.nearest_many(s.garment, kNq, out, ctx);
    benchmark::DoNotOptimize(out.data());
  }
  st.counters["queries/s"] =
      benchmark::Counter(static_cast<double>(s.garment.size()), benchmark::Counter::kIsIterationInvariantRate);
  st.SetLabel(s.body_name + ", k=134");
}
BENCHMARK(BM_PPolygonSearch_Grid)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

#ifdef ATELIER_HAVE_NANOFLANN
struct Cloud {
  const std::vector<Vec3d>* p;
  [[nodiscard]] std::size_t kdtree_get_point_count() const { return p->size(); }
  [[nodiscard]] double kdtree_get_pt(std::size_t i, std::size_t d) const { return (*p)[i][static_cast<int>(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};
void BM_PPolygonSearch_Nanoflann(benchmark::State& st) {
  const Scene& s = scene();
  std::vector<std::uint8_t> skip;
  auto all = centroids(s, skip);
  std::vector<Vec3d> c;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (!skip[i]) c.push_back(all[i]);
  Cloud cloud{&c};
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 3>;
  Tree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  tree.buildIndex();
  const ExecContext ctx = threads(static_cast<int>(st.range(0)));
  for (auto _ : st) {
    par::for_each_block(ctx, s.garment.size(), [&](std::size_t b, std::size_t e) {
      std::vector<std::size_t> idx(kNq);
      std::vector<double> d2(kNq);
      for (std::size_t v = b; v < e; ++v) {
        nanoflann::KNNResultSet<double> rs(kNq);
        rs.init(idx.data(), d2.data());
        tree.findNeighbors(rs, s.garment[v].data(), nanoflann::SearchParams());
        benchmark::DoNotOptimize(idx.data());
      }
    });
  }
  st.counters["queries/s"] =
      benchmark::Counter(static_cast<double>(s.garment.size()), benchmark::Counter::kIsIterationInvariantRate);
  st.SetLabel("nanoflann KD-tree, k=134");
}
BENCHMARK(BM_PPolygonSearch_Nanoflann)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
#endif

void BM_PPolygonSearch_BruteForce(benchmark::State& st) {
  const Scene& s = scene();
  std::vector<std::uint8_t> skip;
  const auto c = centroids(s, skip);
  const std::size_t n = 500;  // a sample: brute force is slow
  std::vector<std::uint32_t> out;
  for (auto _ : st)
    for (std::size_t v = 0; v < n; ++v) {
      nearest_brute_force(c, skip, s.garment[v], kNq, out);
      benchmark::DoNotOptimize(out.data());
    }
  st.counters["queries/s"] = benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate);
  st.SetLabel("1 thread");
}
BENCHMARK(BM_PPolygonSearch_BruteForce)->Unit(benchmark::kMillisecond)->UseRealTime();

// ---- decoding: 30k vertices x 200 p-polygons

const DetailEncoding& encoding200() {
  static const DetailEncoding e = [] {
    const Scene& s = scene();
    DetailParams p;
    p.polygons_per_vertex = 200;
    return encode_detail(s.poly, s.pos, s.garment, p).value();
  }();
  return e;
}

void BM_Encode_30k(benchmark::State& st) {
  const Scene& s = scene();
  const ExecContext ctx = threads(static_cast<int>(st.range(0)));
  for (auto _ : st) benchmark::DoNotOptimize(encode_detail(s.poly, s.pos, s.garment, {}, ctx));
  st.SetLabel("30k vertices, N_q=134");
}
BENCHMARK(BM_Encode_30k)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// STREAM triad a = b + 3c over three 128 MB arrays (far beyond the caches).
struct Triad {
  static constexpr std::size_t n = std::size_t{1} << 25;
  std::vector<float> a = std::vector<float>(n, 1.0f), b = std::vector<float>(n, 2.0f), c = std::vector<float>(n, 0.5f);
  [[nodiscard]] static constexpr double bytes() { return 3.0 * n * sizeof(float); }
  void run(const ExecContext& ctx) {
    par::for_each_block(ctx, n, [&](std::size_t lo, std::size_t hi) {
      for (std::size_t i = lo; i < hi; ++i) a[i] = b[i] + 3.0f * c[i];
    });
    benchmark::ClobberMemory();
  }
  // The best of `reps` runs, in bytes per second.
  [[nodiscard]] double best_rate(const ExecContext& ctx, int reps = 5) {
    double best = 0;
    for (int r = 0; r < reps; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      run(ctx);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      best = std::max(best, bytes() / s);
    }
    return best;
  }
};

// One probe for the whole binary: its 384 MB are allocated and touched once.
Triad& triad() {
  static Triad t;
  return t;
}

void BM_StreamTriad(benchmark::State& st) {
  Triad& t = triad();
  const ExecContext ctx = threads(static_cast<int>(st.range(0)));
  for (auto _ : st) t.run(ctx);
  st.counters["bytes/s"] = benchmark::Counter(Triad::bytes(), benchmark::Counter::kIsIterationInvariantRate);
  st.SetLabel("STREAM triad probe");
}
BENCHMARK(BM_StreamTriad)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Decode_OneBody(benchmark::State& st) {
  const Scene& s = scene();
  const DetailEncoding& e = encoding200();
  const ExecContext ctx = threads(static_cast<int>(st.range(0)));
  PolygonFrames fr;
  compute_frames(s.poly, s.pos, fr, ctx, e.reference_corners);
  std::vector<Vec3d> out(e.vertex_count());
  const auto allow = static_cast<DecodeKernel>(st.range(1));
  DecodeKernel ran = allow;
  const auto t0 = std::chrono::steady_clock::now();
  for (auto _ : st) {
    ran = decode_detail(e, fr, out, ctx, allow);
    benchmark::DoNotOptimize(out.data());
  }
  const double per_body = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() /
                          static_cast<double>(st.iterations());
  // The goal in this run's own terms: time per body over the time the
  // triad probe, run right after on as many threads, needs to stream the
  // encoding's bytes once (the bandwidth floor). Goal: at most 2. The
  // probe runs after the timed loop, outside its timing.
  const double floor_s = static_cast<double>(e.bytes()) / triad().best_rate(ctx);
  st.counters["floor ms"] = 1e3 * floor_s;
  st.counters["x floor"] = per_body / floor_s;
  st.counters["entries/s"] =
      benchmark::Counter(static_cast<double>(e.entries()), benchmark::Counter::kIsIterationInvariantRate);
  st.counters["bytes/s"] =
      benchmark::Counter(static_cast<double>(e.bytes()), benchmark::Counter::kIsIterationInvariantRate);
  const char* names[] = {"auto", "AVX-512", "AVX2", "portable"};
  st.SetLabel(std::string("30k x 200, frames precomputed, ") + names[static_cast<int>(ran)] + " kernel");
}
// Arguments: threads, kernel (0: the widest the CPU has, 2: AVX2).
BENCHMARK(BM_Decode_OneBody)
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({1, 2})
    ->Args({2, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Frames_OneBody(benchmark::State& st) {
  const Scene& s = scene();
  const DetailEncoding& e = encoding200();
  const ExecContext ctx = threads(static_cast<int>(st.range(0)));
  PolygonFrames fr;
  for (auto _ : st) {
    compute_frames(s.poly, s.pos, fr, ctx, e.reference_corners);
    benchmark::DoNotOptimize(fr.x.data());
  }
  st.SetLabel("fitted frames of 13k polygons (part of a body's decoding)");
}
BENCHMARK(BM_Frames_OneBody)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_DecoderBuild(benchmark::State& st) {
  const DetailEncoding& e = encoding200();
  const ExecContext ctx = threads(static_cast<int>(st.range(0)));
  for (auto _ : st) benchmark::DoNotOptimize(DetailDecoder(e, ctx).runs());
  st.SetLabel("30k x 200 encoding rearranged for batches (once per encoding)");
}
BENCHMARK(BM_DecoderBuild)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The scene's body scaled by random factors in [0.9, 1.1] (the same bodies
// for every batched benchmark).
BodySet scaled_bodies(const Scene& s, std::size_t n) {
  BodySet set(s.ref);
  SplitMix64 r(5);
  std::vector<Vec3d> p(s.pos.size());
  for (std::size_t b = 0; b < n; ++b) {
    const double k = r.uniform(0.9, 1.1);
    for (std::size_t v = 0; v < p.size(); ++v) p[v] = s.pos[v] * k;
    (void)set.add("b", std::span<const Vec3d>(p));
  }
  return set;
}

void decode_batched(benchmark::State& st, DecodeKernel kernel) {
  const Scene& s = scene();
  const DetailEncoding& e = encoding200();
  const std::size_t bodies = static_cast<std::size_t>(st.range(1));
  const BodySet set = scaled_bodies(s, bodies);
  std::vector<Vec3f> out(bodies * e.vertex_count());
  const ExecContext ctx = threads(static_cast<int>(st.range(0)));
  const DetailDecoder dec(e, ctx);  // once per encoding, outside the timing (as FairPlan)
  DecodeWorkspace ws;               // buffers kept from batch to batch, as a caller decoding many batches does
  ws.allow = kernel;
  for (auto _ : st) {
    (void)decode_detail_batch(dec, s.poly, set, 0, bodies, out, ws, ctx);
    benchmark::DoNotOptimize(out.data());
  }
  st.counters["bodies/s"] =
      benchmark::Counter(static_cast<double>(bodies), benchmark::Counter::kIsIterationInvariantRate);
  st.counters["ms/body"] =
      benchmark::Counter(static_cast<double>(bodies) / 1000.0,
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  st.counters["entries/run"] = static_cast<double>(dec.entries()) / static_cast<double>(dec.runs());
  const char* names[] = {"auto", "AVX-512", "AVX2", "portable"};
  st.SetLabel(std::string("30k x 200, frames included, ") + names[static_cast<int>(ws.ran)] + " kernel");
}
// The widest kernel the CPU has (AVX-512 where present).
void BM_Decode_Batched(benchmark::State& st) {
  decode_batched(st, DecodeKernel::kAuto);
}
BENCHMARK(BM_Decode_Batched)->Args({2, 16})->Args({2, 64})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();
// The AVX2 kernel on the same data, for the ratio in one run.
void BM_Decode_Batched_AVX2(benchmark::State& st) {
  decode_batched(st, DecodeKernel::kAvx2);
}
BENCHMARK(BM_Decode_Batched_AVX2)->Args({2, 16})->Args({1, 16})->Unit(benchmark::kMillisecond)->UseRealTime();

// A garment over part of the body, as real ones are: 10k points near the
// polygons of a band of the body's height (a top, on the human body), the
// default N_q. A pass computes the frames of the polygons it uses only.
void BM_Decode_Batched_Band(benchmark::State& st) {
  const Scene& s = scene();
  static const DetailEncoding e = [&] {
    PolygonFrames fr;
    compute_frames(s.poly, s.pos, fr);
    double lo = 1e300, hi = -1e300;
    for (const Vec3f& c : fr.centroid) lo = std::min(lo, double{c.y()}), hi = std::max(hi, double{c.y()});
    std::vector<std::size_t> band;
    for (std::size_t f = 0; f < s.poly.size(); ++f) {
      const double h = (fr.centroid[f].y() - lo) / (hi - lo);
      if (!fr.degenerate[f] && h > 0.55 && h < 0.8) band.push_back(f);
    }
    SplitMix64 r(2);
    std::vector<Vec3d> g;
    for (std::size_t i = 0; g.size() < 10'000; ++i) {
      const std::size_t f = band[(i / 3) % band.size()];
      g.push_back(fr.centroid[f].cast<double>() + r.uniform(0.005, 0.03) * fr.x[f].cast<double>() +
                  0.004 * Vec3d(r.normal(), r.normal(), r.normal()));
    }
    return encode_detail(s.poly, s.pos, g, DetailParams{}).value();
  }();
  const BodySet set = scaled_bodies(s, 16);
  std::vector<Vec3f> out(16 * e.vertex_count());
  const ExecContext ctx = threads(static_cast<int>(st.range(0)));
  const DetailDecoder dec(e, ctx);
  DecodeWorkspace ws;
  for (auto _ : st) {
    (void)decode_detail_batch(dec, s.poly, set, 0, 16, out, ws, ctx);
    benchmark::DoNotOptimize(out.data());
  }
  st.counters["ms/body"] =
      benchmark::Counter(16.0 / 1000.0, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  st.counters["polygons used"] = static_cast<double>(dec.used_polygons().size());
  st.counters["entries/vertex"] = static_cast<double>(dec.entries()) / static_cast<double>(e.vertex_count());
  st.SetLabel("10k-vertex band garment, default N_q, batches of 16, frames included");
}
BENCHMARK(BM_Decode_Batched_Band)->Arg(2)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MakeHuman_EndToEnd_1000(benchmark::State& st) {
  const Scene& s = scene();
  if (!s.lib) {
    st.SkipWithError("MakeHuman data absent");
    return;
  }
  DetailParams prm;
  const DetailEncoding e = encode_detail(s.poly, s.pos, s.garment, prm).value();
  auto params = makehuman::sample_adults(1000, 3);
  makehuman::MakeHumanSource src(s.lib, params, s.ref);
  const ExecContext ctx = threads(2);
  const DetailDecoder dec(e, ctx);  // made once with the encoding
  DecodeWorkspace ws;
  BodySet chunk(s.ref);
  std::vector<BodyFailure> fail;
  const std::size_t B = 32;
  std::vector<Vec3f> out(B * e.vertex_count());
  for (auto _ : st) {
    for (std::size_t first = 0; first < params.size(); first += B) {
      src.generate(first, B, chunk, fail, ctx);
      (void)decode_detail_batch(dec, s.poly, chunk, 0, chunk.size(),
                                std::span<Vec3f>(out.data(), chunk.size() * e.vertex_count()), ws, ctx);
    }
  }
  st.counters["bodies/s"] = benchmark::Counter(1000.0, benchmark::Counter::kIsIterationInvariantRate);
  st.SetLabel("generation + frames + decoding, 30k-vertex garment, N_q=134, 2 threads");
}
BENCHMARK(BM_MakeHuman_EndToEnd_1000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace
