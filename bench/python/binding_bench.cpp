// The Python binding's overhead (issue 25): regenerating 1,000 bodies
// through Python against the same job through the C++ API, side by side in
// one process.
//
// Method: this benchmark embeds the interpreter (pybind11/embed.h) and
// imports the built module (build/python/atelier), so both rows run in the
// same process, on the same machine state, on the same bodies: one float32
// (B, n, 3) array in memory, handed to Python as a numpy view (no copy),
// and the same garment template file (the demo's shorts on the default
// mannequin). Rows alternate under --benchmark_enable_random_interleaving.
//  * BM_BindingRegen/cpp: what a C++ program with bodies in an array does:
//    a BodySet filled from the array (BodySet::add per body) and
//    GarmentRegenerator::run over all bodies (the results stay in the
//    engine's vectors).
//  * BM_BindingRegen/python: Regenerator.run(bodies) from Python: argument
//    checks (shape, dtype, a NaN scan), the chunked body set, the GIL
//    released and the work on a worker thread, and the (B, m, 3) float64
//    positions and the structured quality array filled for Python (one
//    copy), i.e. everything a Python caller pays.
// Both use a Regenerator created once (its decoders are the same C++ work
// on both sides). The module holds its own copy of the engine (its symbols
// are local to the .so), compiled with the same flags.
//
// Run: build/bench/atelier_bench --benchmark_filter=BM_BindingRegen
//        --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
#ifdef ATELIER_HAVE_PYTHON
#include <atelier/storage/builder.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <benchmark/benchmark.h>
#include <pybind11/embed.h>
#include <pybind11/numpy.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace py = pybind11;
namespace fs = std::filesystem;
using namespace atelier;

namespace {

constexpr std::size_t kBodies = 1000;

double curve_height(const ReferenceBody& body, std::int32_t id) {
  auto pl = feature_curve_polyline(body, id);
  double y = 0;
  for (const Vec3d& p : *pl) y += p.y();
  return y / static_cast<double>(pl->size());
}

struct Job {
  std::shared_ptr<const ReferenceBody> reference;
  std::shared_ptr<const GarmentFamily> family;
  std::shared_ptr<const GarmentTemplate> shorts;
  std::vector<float> bodies;  // (kBodies, n, 3)
  std::size_t nodes = 0;
  fs::path atd;
};

/// The default mannequin, the demo's shorts (float32 vertices, saved as a
/// template and read back, as the Python side reads it) and 1,000 sampled
/// bodies in float32.
const Job& job() {
  static const Job j = [] {
    Job j;
    auto topo = make_mannequin_topology();
    j.reference = std::make_shared<const ReferenceBody>(*make_mannequin(MannequinParams{}, *topo));
    const ReferenceBody& ref = *j.reference;
    const double y_waist = curve_height(ref, kWaist), y_thigh = curve_height(ref, kThighLeft);
    const double y_knee = curve_height(ref, kKneeLeft);
    Model band = *skin_band_garment(ref, 0.5 * (y_thigh + y_knee), y_waist + 0.02, 0.008, 0.40, "shorts");
    PolygonSoup soup = polygon_soup(band);
    for (Vec3d& p : soup.positions) p = round_to_float(p);
    j.family = std::make_shared<const GarmentFamily>(*GarmentFamily::of(ref));
    const GarmentTemplate made = *encode_garment(*j.family, "shorts", std::move(soup));
    const fs::path dir = fs::temp_directory_path() / ("atelier-binding-bench-" + std::to_string(::getpid()));
    write_garment_template(made, dir);
    j.atd = dir / "shorts.atd";
    j.shorts = std::make_shared<const GarmentTemplate>(*read_garment_template(*j.family, j.atd));
    j.nodes = ref.model.nodes.slots.capacity();
    j.bodies.resize(kBodies * j.nodes * 3);
    for (std::size_t b = 0; b < kBodies; ++b) {
      const auto p = *mannequin_positions(sample_mannequin(1, b), *topo);
      for (std::size_t v = 0; v < j.nodes; ++v)
        for (int k = 0; k < 3; ++k) j.bodies[(b * j.nodes + v) * 3 + k] = static_cast<float>(p[v][k]);
    }
    return j;
  }();
  return j;
}

struct PythonSide {
  std::unique_ptr<py::scoped_interpreter> interpreter;
  py::object regenerator;
  py::object bodies;
};

PythonSide& python() {
  static PythonSide s = [] {
    PythonSide s;
    const Job& j = job();
    s.interpreter = std::make_unique<py::scoped_interpreter>();
    py::module_::import("sys").attr("path").attr("insert")(0, ATELIER_PYTHON_PATH);
    const py::module_ atelier = py::module_::import("atelier");
    const py::object family = atelier.attr("GarmentFamily")(atelier.attr("Mannequin")().attr("reference")());
    const py::object shorts = atelier.attr("read_garment_template")(family, j.atd.string());
    s.regenerator = atelier.attr("Regenerator")(shorts);
    // A view onto the C++ array: both sides read the same memory.
    s.bodies =
        py::array_t<float>({static_cast<py::ssize_t>(kBodies), static_cast<py::ssize_t>(j.nodes), py::ssize_t{3}},
                           j.bodies.data(), py::none());
    return s;
  }();
  return s;
}

void BM_BindingRegen_cpp(benchmark::State& state) {
  const Job& j = job();
  auto r = GarmentRegenerator::create(j.family, {j.shorts});
  ExecContext ctx;
  ctx.threads = static_cast<int>(state.range(0));
  std::vector<BodyGarments> out;
  std::size_t inside = 0;
  for (auto _ : state) {
    BodySet set(j.reference);
    set.reserve(kBodies);
    for (std::size_t b = 0; b < kBodies; ++b)
      if (!set.add("body-" + std::to_string(b),
                   std::span<const Vec3f>(reinterpret_cast<const Vec3f*>(j.bodies.data()) + b * j.nodes, j.nodes)))
        state.SkipWithError("bad body");
    if (!r->run(set, 0, kBodies, out, ctx)) state.SkipWithError("regeneration failed");
    inside = 0;
    for (const auto& b : out) inside += b.status ? b.garments[0].quality.inside : 1;
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["ms_per_body"] = benchmark::Counter(
      static_cast<double>(kBodies) * 1e-3, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["inside"] = static_cast<double>(inside);
}

void BM_BindingRegen_python(benchmark::State& state) {
  PythonSide& s = python();
  const py::object run = s.regenerator.attr("run");
  std::size_t inside = 0;
  for (auto _ : state) {
    py::object result = run(s.bodies, py::arg("threads") = state.range(0));
    inside = result.attr("quality")[py::int_(0)][py::str("inside")].attr("sum")().cast<std::size_t>();
    benchmark::DoNotOptimize(result.ptr());
  }
  state.counters["ms_per_body"] = benchmark::Counter(
      static_cast<double>(kBodies) * 1e-3, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["inside"] = static_cast<double>(inside);
}

}  // namespace

// threads: 0 = all cores (the default of both APIs), 1. The CPU column is
// the whole process's CPU time (every thread: the engine's workers, the
// binding's waiting thread and its signal checks), which a machine loaded
// by other work does not inflate as it does the wall time.
BENCHMARK(BM_BindingRegen_cpp)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("threads")
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_BindingRegen_python)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("threads")
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

#endif  // ATELIER_HAVE_PYTHON
