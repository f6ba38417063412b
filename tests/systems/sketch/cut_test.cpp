#include <atelier/systems/sketch/cut.h>

#include <gtest/gtest.h>

#include <atelier/storage/validate.h>
#include <atelier/systems/sketch/paint.h>
#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;

namespace {
std::vector<Vec3d> circle(const Vec3d& c, double r, int n) {
  std::vector<Vec3d> p;
  for (int i = 0; i <= n; ++i) {
    const double a = 2 * M_PI * i / n;
    p.push_back(c + r * Vec3d(std::cos(a), std::sin(a), 0));
  }
  p.back() = p.front();
  return p;
}
}  // namespace

TEST(Cut, Smoke) {
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  auto p1 = paint_stroke(m, cam, project(cam, {Vec3d(-1.4, 0.1, 0), Vec3d(1.4, 0.1, 0)}), {.through = true});
  ASSERT_TRUE(p1) << p1.status().to_string();
  std::vector<AttribEdge> curves;
  for (auto& c : p1->curves) curves.insert(curves.end(), c.edges.begin(), c.edges.end());
  auto pick = locate_pixel(m, cam, cam.project(Vec3d(0, 0.8, 0)).head<2>());
  ASSERT_TRUE(pick);
  auto r = cut_along_curves(m, curves, {.pick = pick->location});
  ASSERT_TRUE(r) << r.status().to_string();
  EXPECT_TRUE(validate(m)) << validate(m).to_string();
  std::printf("pieces %zu removed %.6f kept %.6f faces removed %zu\n", r->pieces.size(), r->removed_area,
              r->kept_area, r->faces_removed);
}

TEST(Partition, Smoke) {
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  std::vector<AttribEdge> curves;
  for (Vec3d c : {Vec3d(-0.4, 0.1, 0), Vec3d(0.4, -0.2, 0)}) {
    auto p = paint_stroke(m, cam, project(cam, circle(c, 0.3, 40)));
    ASSERT_TRUE(p) << p.status().to_string();
    ASSERT_EQ(p->curves.size(), 1u);
    EXPECT_TRUE(p->curves[0].closed);
    for (auto& e : p->curves[0].edges) curves.push_back(e);
  }
  auto r = partition_along_curves(m, curves);
  ASSERT_TRUE(r) << r.status().to_string();
  EXPECT_TRUE(validate(m)) << validate(m).to_string();
  std::printf("pieces %zu joints %zu surfaces %zu\n", r->pieces.size(), r->joints.size(), m.num_surfaces());
  for (auto& p : r->pieces) std::printf("  piece faces %zu area %.6f\n", p.faces, p.area);
}
