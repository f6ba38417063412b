// Colour maps and per-vertex colours (issue 26): viridis against
// matplotlib's published table at its ends and middle, the diverging map's
// symmetry, the colour bar's columns, and a rendered garment of uniform
// high strain showing the map's high colour where it covers the picture.
#include <atelier/systems/view/colour_map.h>
#include <atelier/systems/view/render.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace atelier {
namespace {

std::array<int, 3> bytes_of(const double (&rgb)[3]) {
  return {static_cast<int>(std::lround(rgb[0] * 255)), static_cast<int>(std::lround(rgb[1] * 255)),
          static_cast<int>(std::lround(rgb[2] * 255))};
}

void expect_near_bytes(std::array<std::uint8_t, 3> got, std::array<int, 3> want, int tol, const char* what) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(int{got[k]}, want[k], tol) << what << " channel " << k;
}

TEST(ColourMap, ViridisMatchesMatplotlibAtItsEndsAndMiddle) {
  // matplotlib's _viridis_data entries 0, 128 and 255 (sRGB in [0, 1]).
  constexpr double kFirst[3] = {0.267004, 0.004874, 0.329415};
  constexpr double kMiddle[3] = {0.127568, 0.566949, 0.550556};  // entry 128, t = 128/255
  constexpr double kLast[3] = {0.993248, 0.906157, 0.143936};
  expect_near_bytes(colour_map_bytes(ColourMap::kViridis, 0.0), bytes_of(kFirst), 1, "t = 0");
  expect_near_bytes(colour_map_bytes(ColourMap::kViridis, 1.0), bytes_of(kLast), 1, "t = 1");
  expect_near_bytes(colour_map_bytes(ColourMap::kViridis, 128.0 / 255.0), bytes_of(kMiddle), 3, "t = 0.5");
  // Clamped outside [0, 1]; NaN is the low end.
  EXPECT_EQ(colour_map_bytes(ColourMap::kViridis, -3.0), colour_map_bytes(ColourMap::kViridis, 0.0));
  EXPECT_EQ(colour_map_bytes(ColourMap::kViridis, 7.0), colour_map_bytes(ColourMap::kViridis, 1.0));
  EXPECT_EQ(colour_map_bytes(ColourMap::kViridis, std::nan("")), colour_map_bytes(ColourMap::kViridis, 0.0));
  // Perceptual: lightness (luma) grows monotonically along the map.
  double last = -1;
  for (int i = 0; i <= 50; ++i) {
    const Vec3d c = colour_map_linear(ColourMap::kViridis, i / 50.0);
    const double y = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    EXPECT_GT(y, last) << i;
    last = y;
  }
}

TEST(ColourMap, DivergingIsBlueWhiteRedAndSymmetricInLightness) {
  const auto lo = colour_map_bytes(ColourMap::kDiverging, 0.0), mid = colour_map_bytes(ColourMap::kDiverging, 0.5),
             hi = colour_map_bytes(ColourMap::kDiverging, 1.0);
  EXPECT_GT(lo[2], lo[0] + 100);                            // blue
  EXPECT_GT(hi[0], hi[2] + 100);                            // red
  for (int k = 0; k < 3; ++k) EXPECT_GE(mid[k], 240) << k;  // near white
  auto luma = [](double t) {
    const Vec3d c = colour_map_linear(ColourMap::kDiverging, t);
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
  };
  EXPECT_GT(luma(0.5), luma(0.25));
  EXPECT_GT(luma(0.5), luma(0.75));
  EXPECT_EQ(colour_map_name(ColourMap::kDiverging), "diverging");
  EXPECT_EQ(*colour_map_from_name("viridis"), ColourMap::kViridis);
  EXPECT_FALSE(colour_map_from_name("jet"));
}

TEST(ColourMap, MapValuesAndTheColourBar) {
  const std::vector<double> v = {0.0, 5.0, 10.0};
  auto c = map_values(v, 0.0, 10.0, ColourMap::kViridis);
  ASSERT_TRUE(c);
  EXPECT_TRUE((*c)[0].isApprox(colour_map_linear(ColourMap::kViridis, 0.0)));
  EXPECT_TRUE((*c)[1].isApprox(colour_map_linear(ColourMap::kViridis, 0.5)));
  EXPECT_TRUE((*c)[2].isApprox(colour_map_linear(ColourMap::kViridis, 1.0)));
  const std::vector<double> bad = {1.0, std::nan("")};
  EXPECT_FALSE(map_values(bad, 0.0, 1.0, ColourMap::kViridis));
  EXPECT_FALSE(map_values(v, 2.0, 1.0, ColourMap::kViridis));
  auto bar = colour_bar(ColourMap::kViridis, 101, 5);
  ASSERT_TRUE(bar);
  for (std::uint32_t x : {0u, 50u, 100u})
    for (std::uint32_t y : {0u, 4u}) {
      const auto want = colour_map_bytes(ColourMap::kViridis, x / 100.0);
      EXPECT_TRUE(std::equal(want.begin(), want.end(), bar->at(x, y))) << x << "," << y;
    }
  EXPECT_FALSE(colour_bar(ColourMap::kViridis, 1, 5));
}

// A body (a box) and in front of it a garment (a grid) stretched 1.3 times
// in both directions: every edge strains 30%, the map's top of a 0-30% range.
TEST(ColourMap, AGarmentOfUniformHighStrainShowsTheMapsHighColour) {
  std::vector<Vec3d> body = {{-0.2, -0.2, -0.2}, {0.2, -0.2, -0.2}, {-0.2, 0.2, -0.2}, {0.2, 0.2, -0.2},
                             {-0.2, -0.2, 0.0},  {0.2, -0.2, 0.0},  {-0.2, 0.2, 0.0},  {0.2, 0.2, 0.0}};
  std::vector<Triangle> body_tris = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                     {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  const int n = 6;
  std::vector<Vec3d> rest, worn;
  std::vector<Triangle> tris;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      rest.push_back({-0.1 + 0.2 * i / n, -0.1 + 0.2 * j / n, 0.05});
      worn.push_back({1.3 * rest.back().x(), 1.3 * rest.back().y(), 0.05});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      tris.push_back({a, b, d});
      tris.push_back({a, d, c});
    }
  // Per-vertex strain: the largest |l / l0 - 1| of the vertex's edges.
  std::vector<double> strain(worn.size(), 0.0);
  for (const Triangle& t : tris)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = t[e], b = t[(e + 1) % 3];
      const double s = 100 * std::abs((worn[a] - worn[b]).norm() / (rest[a] - rest[b]).norm() - 1.0);
      strain[a] = std::max(strain[a], s);
      strain[b] = std::max(strain[b], s);
    }
  for (double s : strain) ASSERT_NEAR(s, 30.0, 1e-9);
  auto colours = map_values(strain, 0.0, 30.0, ColourMap::kViridis);
  ASSERT_TRUE(colours);
  RenderParams rp;
  rp.width = 80;
  rp.height = 80;
  RenderTriangles g{worn, tris, garment_colour(0)};
  g.vertex_colours = *colours;
  g.shading = 0.0;
  const std::vector<RenderTriangles> scene = {{body, body_tris, body_colour()}, g};
  auto r = render_scene(scene, rp);
  ASSERT_TRUE(r) << r.status().to_string();
  const auto high = colour_map_bytes(ColourMap::kViridis, 1.0);
  std::size_t garment_pixels = 0;
  for (std::uint32_t y = 0; y < 80; ++y)
    for (std::uint32_t x = 0; x < 80; ++x) {
      if (r->mesh[y * 80 + x] != 1) continue;
      ++garment_pixels;
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(int{r->image.at(x, y)[k]}, int{high[k]}, 1) << x << "," << y;
    }
  // The garment covers the picture's middle (0.52 of the 0.4 m frame's width).
  EXPECT_EQ(r->mesh[40 * 80 + 40], 1);
  EXPECT_GT(garment_pixels, 1000u);
  // The body around it keeps its own colour, lit.
  EXPECT_EQ(r->mesh[8 * 80 + 8], 0);
  EXPECT_NE(r->image.at(8, 8)[0], high[0]);

  // Colours are checked: one per position, finite, and a shading in [0, 1].
  RenderTriangles wrong = g;
  wrong.vertex_colours = std::span<const Vec3d>(colours->data(), 3);
  EXPECT_FALSE(render_scene(std::vector<RenderTriangles>{wrong}, rp));
  RenderTriangles dark = g;
  dark.shading = 1.5;
  EXPECT_FALSE(render_scene(std::vector<RenderTriangles>{dark}, rp));
}

}  // namespace
}  // namespace atelier
