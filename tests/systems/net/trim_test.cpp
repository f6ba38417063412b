// Trimming by a curve (seed 004 section 6): a plane trimmed by a regular
// N-gon loses exactly its area (N/2) r^2 sin(2 pi / N); the kept and the
// enclosed parts add up; curve files are parsed strictly.
#include <atelier/systems/net/trim.h>
#include <gtest/gtest.h>

#include <cmath>

#include "net_shapes.h"

namespace atelier {
namespace {

/// The plane z = 0 over [-2, 2]^2 as k x k quads (an open net).
PolygonSoup plane(int k) {
  PolygonSoup s;
  for (int j = 0; j <= k; ++j)
    for (int i = 0; i <= k; ++i) s.positions.emplace_back(-2.0 + 4.0 * i / k, -2.0 + 4.0 * j / k, 0.0);
  auto v = [&](int i, int j) { return static_cast<std::uint32_t>(j * (k + 1) + i); };
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i)
      s.add_face(std::array<std::uint32_t, 4>{v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)});
  return s;
}

std::vector<Vec3d> ngon(int n, double r, const Vec3d& c, double phase) {
  std::vector<Vec3d> p;
  for (int i = 0; i < n; ++i) {
    const double a = phase + 2 * M_PI * i / n;
    p.push_back(c + r * Vec3d(std::cos(a), std::sin(a), 0));
  }
  return p;
}

TEST(NetTrim, PlaneLosesTheAreaOfTheNGon) {
  const PolygonSoup net = plane(9);
  for (int n : {3, 5, 8, 17}) {
    const double r = 1.1;
    auto t = trim_net(net, ngon(n, r, {0.013, -0.021, 0}, 0.3), {});
    ASSERT_TRUE(t.has_value()) << t.status().to_string();
    const double lost = t->area_before - t->area_after;
    EXPECT_NEAR(lost, 0.5 * n * r * r * std::sin(2 * M_PI / n), 1e-12 * t->area_before) << n;
    EXPECT_EQ(t->parts >= 2, true);
    // The trimmed plane is still a valid open net.
    Model m;
    auto surf = add_polygon_surface(m, "trimmed", t->result);
    ASSERT_TRUE(surf.has_value()) << surf.status().to_string();
    EXPECT_TRUE(validate(m).is_ok());
  }
}

TEST(NetTrim, KeptAndEnclosedPartsAddUp) {
  const PolygonSoup sphere = net_test::icosphere(3, 1.0, {0, 0, 0});
  // A loop around the sphere below its equator, on the sphere.
  std::vector<Vec3d> curve;
  for (int i = 0; i < 40; ++i) {
    const double a = 2 * M_PI * i / 40, z = -0.35;
    const double rr = std::sqrt(1 - z * z);
    curve.emplace_back(rr * std::cos(a), rr * std::sin(a), z);
  }
  TrimOptions o;
  o.height = 0.3;
  auto keep = trim_net(sphere, curve, o);
  ASSERT_TRUE(keep.has_value()) << keep.status().to_string();
  o.keep_enclosed = true;
  auto cap = trim_net(sphere, curve, o);
  ASSERT_TRUE(cap.has_value());
  EXPECT_EQ(keep->parts, 2u);
  EXPECT_NEAR(keep->area_after + cap->area_after, keep->area_before, 1e-12 * keep->area_before);
  EXPECT_LT(cap->area_after, keep->area_after);  // the enclosed part of a closed net is the smaller one
}

TEST(NetTrim, RefusesBadCurves) {
  const PolygonSoup net = plane(4);
  EXPECT_FALSE(trim_net(net, std::vector<Vec3d>{{0, 0, 0}, {1, 0, 0}}, {}).has_value());
  // A curve that does not enclose anything on the plane (outside it).
  auto off = trim_net(net, ngon(4, 0.5, {5, 5, 0}, 0), {});
  ASSERT_FALSE(off.has_value());
  EXPECT_NE(off.status().message().find("does not cut"), std::string::npos);
  EXPECT_THROW((void)parse_curve("1 2 3\n4 5\n", "c.txt"), Error);
  try {
    (void)parse_curve("# curve\n1 2 3\n\n4 five 6\n", "c.txt");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("c.txt"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("4"), std::string::npos);
  }
  EXPECT_THROW((void)parse_curve("1 2 nan\n", "c.txt"), Error);
  EXPECT_EQ(parse_curve("# x\n1 2 3\n 4 5 6 \n", "c.txt").size(), 2u);
}

}  // namespace
}  // namespace atelier
