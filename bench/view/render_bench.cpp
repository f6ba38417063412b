// Pictures coloured per vertex (issue 26) beside the flat-coloured picture
// of the same scene: the cost of the barycentric colour lookup per hit.
// The scene is a report picture's: a closed body (a UV sphere, 20,000
// triangles) and a garment in front of it (a 100 x 100 grid, 20,000
// triangles), front view, 360 x 560 pixels, outlines on, one thread (the
// rows' parallel loop is the same for both rows, so the ratio is the
// per-pixel cost). Compare CPU time; the machine is shared.
#include <atelier/systems/view/colour_map.h>
#include <atelier/systems/view/render.h>
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

namespace {

using namespace atelier;

struct Scene {
  std::vector<Vec3d> body, garment, colours;
  std::vector<Triangle> body_tris, garment_tris;
};

const Scene& scene() {
  static const Scene s = [] {
    Scene s;
    const int nu = 100, nv = 100;
    s.body.push_back({0, 0.5, 0});
    for (int j = 1; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        const double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
        s.body.push_back({0.25 * std::sin(th) * std::cos(ph), 0.5 * std::cos(th), 0.25 * std::sin(th) * std::sin(ph)});
      }
    s.body.push_back({0, -0.5, 0});
    auto ring = [&](int j, int i) { return static_cast<std::uint32_t>(1 + (j - 1) * nu + ((i + nu) % nu)); };
    const auto south = static_cast<std::uint32_t>(s.body.size() - 1);
    for (int i = 0; i < nu; ++i) s.body_tris.push_back({0, ring(1, i + 1), ring(1, i)});
    for (int j = 1; j + 1 < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        s.body_tris.push_back({ring(j, i), ring(j, i + 1), ring(j + 1, i + 1)});
        s.body_tris.push_back({ring(j, i), ring(j + 1, i + 1), ring(j + 1, i)});
      }
    for (int i = 0; i < nu; ++i) s.body_tris.push_back({south, ring(nv - 1, i), ring(nv - 1, i + 1)});
    const int n = 100;
    std::vector<double> strain;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        s.garment.push_back({-0.2 + 0.4 * i / n, -0.3 + 0.6 * j / n, 0.3});
        strain.push_back(static_cast<double>(i + j) / (2 * n));
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const auto a = static_cast<std::uint32_t>(j * (n + 1) + i), b = a + 1, c = a + n + 1, d = c + 1;
        s.garment_tris.push_back({a, b, d});
        s.garment_tris.push_back({a, d, c});
      }
    s.colours = map_values(strain, 0.0, 1.0, ColourMap::kViridis).value();
    return s;
  }();
  return s;
}

void render(benchmark::State& state, bool per_vertex) {
  const Scene& s = scene();
  RenderTriangles g{s.garment, s.garment_tris, garment_colour(0)};
  if (per_vertex) {
    g.vertex_colours = s.colours;
    g.shading = 0.3;
  }
  const std::vector<RenderTriangles> meshes = {{s.body, s.body_tris, body_colour()}, g};
  RenderParams rp;
  rp.width = 360;
  rp.height = 560;
  rp.outlines = true;
  ExecContext ctx;
  ctx.threads = 1;
  for (auto _ : state) {
    auto r = render_scene(meshes, rp, ctx);
    if (!r) state.SkipWithError(r.status().to_string().c_str());
    benchmark::DoNotOptimize(r);
  }
  state.counters["pixels"] = 360.0 * 560.0;
}

void BM_RenderFlatColour(benchmark::State& state) {
  render(state, false);
}
void BM_RenderVertexColours(benchmark::State& state) {
  render(state, true);
}
BENCHMARK(BM_RenderFlatColour)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderVertexColours)->Unit(benchmark::kMillisecond);

}  // namespace
