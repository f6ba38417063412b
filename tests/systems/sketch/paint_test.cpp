#include <atelier/systems/sketch/paint.h>

#include <gtest/gtest.h>

#include <atelier/storage/validate.h>
#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;

TEST(Paint, Smoke) {
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  const std::vector<Vec2d> stroke = project(cam, {Vec3d(-1.4, 0.1, 0), Vec3d(1.4, 0.1, 0)});
  std::printf("faces %zu stroke %f %f -> %f %f\n", m.num_faces(), stroke[0].x(), stroke[0].y(), stroke[1].x(), stroke[1].y());
  auto r = trace_stroke(m, cam, stroke);
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_EQ(r->curves.size(), 1u);
  std::printf("visible: %zu points, length %.6f, crossed %zu\n", r->curves[0].points.size(), r->curves[0].length(),
              r->triangles_crossed);
  auto t = trace_stroke(m, cam, stroke, {.through = true});
  ASSERT_TRUE(t) << t.status().to_string();
  double L = 0;
  for (auto& c : t->curves) L += c.length();
  std::printf("through: %zu curves, length %.6f (circle %.6f)\n", t->curves.size(), L,
              2 * M_PI * std::sqrt(1 - 0.01));
}
