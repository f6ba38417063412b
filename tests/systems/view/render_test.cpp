// Ray-cast pictures (systems/render.h) against analytic projections: a sphere
// covers the disc it projects to (orthographic and perspective), is shaded by
// Lambert's law at its centre, an elongated box looks different from the
// front and the side, and pictures do not depend on the thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include <atelier/systems/view/render.h>

namespace atelier {
namespace {

struct TriMesh {
  std::vector<Vec3d> p;
  std::vector<Triangle> t;
};

// Icosphere: an icosahedron subdivided `levels` times, vertices on the sphere,
// counter-clockwise seen from outside.
TriMesh icosphere(int levels, double r, const Vec3d& c) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh m;
  m.p = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
         {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  m.t = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
         {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
         {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& v : m.p) v.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.p.push_back((m.p[a] + m.p[b]).normalized());
      const auto i = static_cast<std::uint32_t>(m.p.size() - 1);
      mid.emplace(key, i);
      return i;
    };
    std::vector<Triangle> next;
    for (const Triangle& t : m.t) {
      const std::uint32_t a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), d = midpoint(t[2], t[0]);
      next.push_back({t[0], a, d});
      next.push_back({t[1], b, a});
      next.push_back({t[2], d, b});
      next.push_back({a, b, d});
    }
    m.t = std::move(next);
  }
  for (auto& v : m.p) v = c + r * v;
  return m;
}

TriMesh box_mesh(const Vec3d& lo, const Vec3d& hi) {
  TriMesh m;
  for (int i = 0; i < 8; ++i) m.p.push_back({i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z()});
  auto quad = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    m.t.push_back({a, b, c});
    m.t.push_back({a, c, d});
  };
  quad(0, 2, 3, 1);  // z = lo
  quad(4, 5, 7, 6);  // z = hi
  quad(0, 1, 5, 4);  // y = lo
  quad(2, 6, 7, 3);  // y = hi
  quad(0, 4, 6, 2);  // x = lo
  quad(1, 3, 7, 5);  // x = hi
  return m;
}

BodyBvh make_bvh(const TriMesh& m) {
  BodyBvh b;
  EXPECT_TRUE(b.build(std::span<const Vec3d>(m.p), m.t).is_ok());
  EXPECT_TRUE(b.closed());
  return b;
}

// Pixels whose centre lies inside the disc of the given centre and radius
// (image coordinates): the brute-force expectation.
std::size_t disc_pixels(const Vec2d& c, double radius, std::uint32_t w, std::uint32_t h) {
  std::size_t n = 0;
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) n += (Vec2d(x + 0.5, y + 0.5) - c).norm() < radius;
  return n;
}

TEST(Render, OrthographicSphereCoversItsProjectedDisc) {
  const Vec3d centre(0.3, 1.1, -0.2);
  const double r = 0.5;
  const TriMesh s = icosphere(5, r, centre);
  const BodyBvh bvh = make_bvh(s);
  const RenderMesh mesh{&bvh, {0.6, 0.6, 0.6}};
  RenderParams p;
  p.width = 200;
  p.height = 160;
  p.margin = 0.25;
  auto res = render_scene(std::span(&mesh, 1), p);
  ASSERT_TRUE(res.has_value()) << res.status().to_string();
  // The picture frames the sphere's box with a margin, so the disc's radius
  // in pixels is r / half_height * H / 2; the camera keeps it centred.
  const CameraFrame cam = res->camera.frame().value();
  const Vec2d c = res->camera.project(centre).head<2>();
  EXPECT_NEAR(c.x(), p.width / 2.0, 1e-6);
  EXPECT_NEAR(c.y(), p.height / 2.0, 1e-6);
  const double rad = r / cam.half_height * p.height / 2.0;
  // Margin 0.25 of the 2r extent on each side: the picture is 3r high (the
  // mesh's box is a little smaller than the sphere's).
  EXPECT_NEAR(rad, p.height / 3.0, 0.01 * rad);
  const double expected = static_cast<double>(disc_pixels(c, rad, p.width, p.height));
  EXPECT_NEAR(static_cast<double>(res->covered_pixels), expected, 0.01 * expected);
  EXPECT_NEAR(static_cast<double>(res->covered_pixels), M_PI * rad * rad, 0.015 * M_PI * rad * rad);
  // Every covered pixel's depth puts its hit on the sphere.
  for (std::uint32_t y = 0; y < p.height; ++y)
    for (std::uint32_t x = 0; x < p.width; ++x) {
      const std::size_t i = y * p.width + x;
      if (res->mesh[i] < 0) continue;
      Vec3d o, d;
      cam.ray(x + 0.5, y + 0.5, p.width, p.height, o, d);
      EXPECT_NEAR((o + res->depth[i] * d - centre).norm(), r, 2e-3 * r);
    }
}

TEST(Render, PerspectiveSphereMatchesItsAngularRadius) {
  const Vec3d centre(0, 0, 0);
  const double r = 1.0;
  const BodyBvh bvh = make_bvh(icosphere(5, r, centre));
  const RenderMesh mesh{&bvh, {0.6, 0.6, 0.6}};
  RenderParams p;
  p.width = p.height = 160;
  p.projection = Projection::kPerspective;
  p.fov_degrees = 40.0;
  auto res = render_scene(std::span(&mesh, 1), p);
  ASSERT_TRUE(res.has_value()) << res.status().to_string();
  const CameraFrame cam = res->camera.frame().value();
  // A sphere at distance D subtends asin(r / D); on the image plane that is
  // tan(asin(r / D)) / tan(fov / 2) half-heights.
  const double dist = (cam.eye - centre).norm();
  const double rad = std::tan(std::asin(r / dist)) / cam.tan_half_fov * p.height / 2.0;
  EXPECT_LT(rad, p.height / 2.0);
  const double expected = static_cast<double>(disc_pixels({80, 80}, rad, p.width, p.height));
  EXPECT_NEAR(static_cast<double>(res->covered_pixels), expected, 0.015 * expected);
}

TEST(Render, LambertShadingAtTheSphereCentre) {
  const BodyBvh bvh = make_bvh(icosphere(5, 1.0, Vec3d::Zero()));
  const Vec3d colour(0.7, 0.4, 0.2);
  const RenderMesh mesh{&bvh, colour};
  RenderParams p;
  p.width = p.height = 101;  // odd: the centre pixel's ray hits the sphere's front pole
  p.ambient = 0.2;
  auto res = render_scene(std::span(&mesh, 1), p);
  ASSERT_TRUE(res.has_value());
  const CameraFrame cam = res->camera.frame().value();
  const Vec3d n = -cam.forward;
  const Vec3d light = (-cam.forward + 0.45 * cam.up - 0.3 * cam.right).normalized();
  const double k = p.ambient + (1.0 - p.ambient) * n.dot(light);
  const std::uint8_t* px = res->image.at(50, 50);
  for (int c = 0; c < 3; ++c) {
    const double lin = colour[c] * k;
    const double srgb = lin <= 0.0031308 ? 12.92 * lin : 1.055 * std::pow(lin, 1.0 / 2.4) - 0.055;
    EXPECT_NEAR(px[c], srgb * 255.0, 1.5) << "channel " << c;
  }
  // Background is the background colour, exactly.
  EXPECT_EQ(res->image.at(0, 0)[0], 255);
  EXPECT_EQ(res->mesh[0], -1);
}

// Columns and rows holding covered pixels: the silhouette's extent.
std::pair<int, int> extent(const RenderResult& r) {
  const auto w = static_cast<int>(r.image.width), h = static_cast<int>(r.image.height);
  int x0 = w, x1 = -1, y0 = h, y1 = -1;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (r.mesh[static_cast<std::size_t>(y * w + x)] >= 0) {
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
  return {x1 - x0 + 1, y1 - y0 + 1};
}

TEST(Render, FrontAndSideViewsOfAnElongatedBox) {
  // 2 wide (x), 1 high (y), 0.5 deep (z): the front shows 2 x 1, the side
  // 0.5 x 1, both framed in the same orthographic box.
  const BodyBvh bvh = make_bvh(box_mesh({-1, 0, -0.25}, {1, 1, 0.25}));
  const RenderMesh mesh{&bvh, {0.5, 0.5, 0.5}};
  RenderParams p;
  p.width = p.height = 200;
  p.margin = 0.0;
  p.frame.extend({-1, -0.5, -1});
  p.frame.extend({1, 1.5, 1});  // a 2 x 2 x 2 frame: 100 pixels per unit in every view
  p.view = View::kFront;
  auto front = render_scene(std::span(&mesh, 1), p);
  p.view = View::kSide;
  auto side = render_scene(std::span(&mesh, 1), p);
  ASSERT_TRUE(front.has_value() && side.has_value());
  EXPECT_NE(front->image, side->image);
  const auto [fw, fh] = extent(*front);
  const auto [sw, sh] = extent(*side);
  EXPECT_NEAR(fw, 200, 1);
  EXPECT_NEAR(fh, 100, 1);
  EXPECT_NEAR(sw, 50, 1);
  EXPECT_NEAR(sh, 100, 1);
  EXPECT_NEAR(static_cast<double>(front->covered_pixels), 200.0 * 100.0, 300.0);
  EXPECT_NEAR(static_cast<double>(side->covered_pixels), 50.0 * 100.0, 150.0);
}

TEST(Render, NearestMeshWinsAndOutlinesFollowTheSilhouette) {
  // A small sphere in front of a big one: its pixels belong to mesh 1.
  const BodyBvh big = make_bvh(icosphere(4, 1.0, Vec3d::Zero()));
  const BodyBvh small = make_bvh(icosphere(4, 0.3, Vec3d(0, 0, 1.2)));
  const RenderMesh meshes[] = {{&big, body_colour()}, {&small, garment_colour(0)}};
  RenderParams p;
  p.width = p.height = 120;
  p.outlines = true;
  auto res = render_scene(meshes, p);
  ASSERT_TRUE(res.has_value());
  EXPECT_EQ(res->mesh[60 * 120 + 60], 1);
  const Vec2d c = res->camera.project(Vec3d(0, 0, 1.2)).head<2>();
  const double rad_small = 0.3 / res->camera.frame()->half_height * p.height / 2.0;
  std::size_t ones = 0, outline = 0;
  for (std::size_t i = 0; i < res->mesh.size(); ++i) {
    ones += res->mesh[i] == 1;
    const std::uint8_t* px = res->image.pixels.data() + 3 * i;
    const bool dark = px[0] == px[1] && px[1] == px[2] && px[0] < 100;
    outline += dark;
    if (dark) {
      EXPECT_GE(res->mesh[i], 0);  // outlines lie on meshes, never on the background
    }
  }
  const double expected = static_cast<double>(disc_pixels(c, rad_small, p.width, p.height));
  EXPECT_NEAR(static_cast<double>(ones), expected, 0.03 * expected);
  // Outline pixels: about the two circles' perimeters (one pixel wide each).
  const double rad_big = 1.0 / res->camera.frame()->half_height * p.height / 2.0;
  const double perimeters = 2 * M_PI * (rad_big + rad_small);
  EXPECT_GT(static_cast<double>(outline), 0.7 * perimeters);
  EXPECT_LT(static_cast<double>(outline), 2.0 * perimeters);
}

TEST(Render, DeterministicAcrossThreadCounts) {
  const BodyBvh a = make_bvh(icosphere(4, 1.0, Vec3d::Zero()));
  const BodyBvh b = make_bvh(box_mesh({-0.4, -1.5, 0.5}, {0.4, 1.5, 1.5}));
  const RenderMesh meshes[] = {{&a, body_colour()}, {&b, garment_colour(1)}};
  RenderParams p;
  p.width = 96;
  p.height = 128;
  p.supersample = 2;
  p.outlines = true;
  p.projection = Projection::kPerspective;
  ExecContext one = ExecContext::sequential();
  ExecContext two;
  two.threads = 2;
  ExecContext all;
  auto r1 = render_scene(meshes, p, one);
  auto r2 = render_scene(meshes, p, two);
  auto r0 = render_scene(meshes, p, all);
  ASSERT_TRUE(r1.has_value() && r2.has_value() && r0.has_value());
  EXPECT_EQ(r1->image, r2->image);
  EXPECT_EQ(r1->image, r0->image);
  EXPECT_EQ(r1->mesh, r2->mesh);
  EXPECT_GT(r1->covered_pixels, 0u);
}

TEST(Render, ProgressCancellationAndErrors) {
  const BodyBvh a = make_bvh(icosphere(2, 1.0, Vec3d::Zero()));
  const RenderMesh mesh{&a, body_colour()};
  RenderParams p;
  p.width = 32;
  p.height = 24;
  ExecContext ctx = ExecContext::sequential();
  std::size_t last = 0, calls = 0;
  ctx.progress = [&](std::string_view stage, std::size_t done, std::size_t total) {
    EXPECT_EQ(stage, "render");
    EXPECT_EQ(total, 24u);
    last = done;
    ++calls;
  };
  ASSERT_TRUE(render_scene(std::span(&mesh, 1), p, ctx).has_value());
  EXPECT_EQ(last, 24u);
  EXPECT_EQ(calls, 24u);
  ExecContext cancelled;
  cancelled.cancel.cancel();
  EXPECT_EQ(render_scene(std::span(&mesh, 1), p, cancelled).status().code(), ErrorCode::kCancelled);
  EXPECT_EQ(render_scene(std::span<const RenderMesh>{}, p).status().code(), ErrorCode::kInvalidArgument);
  BodyBvh empty;
  const RenderMesh bad{&empty, body_colour()};
  EXPECT_EQ(render_scene(std::span(&bad, 1), p).status().code(), ErrorCode::kInvalidArgument);
  p.width = 0;
  EXPECT_EQ(render_scene(std::span(&mesh, 1), p).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Render, TriangleArraysAndSideBySide) {
  const TriMesh s = icosphere(3, 1.0, Vec3d::Zero());
  const TriMesh b = box_mesh({-1.5, -0.2, 0.9}, {1.5, 0.2, 1.2});
  const BodyBvh bs = make_bvh(s), bb = make_bvh(b);
  const RenderMesh via_bvh[] = {{&bs, body_colour()}, {&bb, garment_colour(0)}};
  const RenderTriangles via_arrays[] = {{s.p, s.t, body_colour()}, {b.p, b.t, garment_colour(0)}};
  RenderParams p;
  p.width = 60;
  p.height = 50;
  p.outlines = true;
  auto r1 = render_scene(via_bvh, p);
  auto r2 = render_scene(via_arrays, p);
  ASSERT_TRUE(r1.has_value() && r2.has_value());
  EXPECT_EQ(r1->image, r2->image);
  std::vector<Triangle> broken = b.t;
  broken[3][1] = 999;
  const RenderTriangles bad[] = {{s.p, s.t, body_colour()}, {b.p, broken, garment_colour(0)}};
  auto rb = render_scene(bad, p);
  ASSERT_FALSE(rb.has_value());
  EXPECT_NE(rb.status().message().find("mesh 1"), std::string::npos) << rb.status().message();

  // Front (60 x 50) and side (30 x 70) pictures side by side, 4 pixels apart.
  p.view = View::kSide;
  p.width = 30;
  p.height = 70;
  auto side = render_scene(via_arrays, p);
  ASSERT_TRUE(side.has_value());
  const RgbImage both_in[] = {r1->image, side->image};
  auto both = side_by_side(both_in, 4, Vec3d(0, 0, 0));
  ASSERT_TRUE(both.has_value());
  EXPECT_EQ(both->width, 60u + 4u + 30u);
  EXPECT_EQ(both->height, 70u);
  for (std::uint32_t y = 0; y < 70; ++y)
    for (std::uint32_t x = 0; x < both->width; ++x) {
      const std::uint8_t* got = both->at(x, y);
      const std::uint8_t* want = nullptr;
      if (x < 60 && y < 50) want = r1->image.at(x, y);
      if (x >= 64) want = side->image.at(x - 64, y);
      for (int c = 0; c < 3; ++c) ASSERT_EQ(got[c], want ? want[c] : 0) << x << "," << y;
    }
  EXPECT_EQ(side_by_side({}).status().code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace atelier
