// Stroke files driving the tools (systems/sketch/sketch.h).
#include <atelier/io/native.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/sketch/sketch.h>
#include <gtest/gtest.h>

#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;

namespace {

Stroke make(StrokeTool t, std::vector<Vec2d> pts, bool through = false, std::string name = "") {
  Stroke s;
  s.tool = t;
  s.points = std::move(pts);
  s.through = through || t == StrokeTool::kPaintThrough;
  s.name = std::move(name);
  return s;
}

std::vector<Vec2d> ring(const Camera& cam, const Vec3d& c, double r) {
  std::vector<Vec3d> p;
  for (int k = 0; k <= 36; ++k) p.push_back(c + r * Vec3d(std::cos(2 * M_PI * k / 36), std::sin(2 * M_PI * k / 36), 0));
  auto s = project(cam, p);
  s.back() = s.front();
  return s;
}

StrokeFile session(const Camera& cam) {
  StrokeFile f;
  f.camera = cam;
  f.strokes.push_back(
      make(StrokeTool::kPaint, project(cam, {Vec3d(-0.6, 0.7, 0), Vec3d(0.6, 0.65, 0)}), false, "mark"));
  f.strokes.push_back(make(StrokeTool::kCut, project(cam, {Vec3d(-1.5, -0.5, 0), Vec3d(1.5, -0.45, 0)}), true));
  f.strokes.push_back(make(StrokeTool::kPick, {cam.project(Vec3d(0.1, -0.8, 0.5)).head<2>()}));
  f.strokes.push_back(make(StrokeTool::kPartition, ring(cam, Vec3d(-0.35, 0.1, 0), 0.22)));
  f.strokes.push_back(make(StrokeTool::kPartition, ring(cam, Vec3d(0.35, 0.1, 0), 0.22)));
  return f;
}

}  // namespace

TEST(Sketch, AStrokeFileDrivesEveryTool) {
  Model m = icosphere(4);
  const Camera cam = front_persp();
  const StrokeFile f = session(cam);
  auto r = apply_strokes(m, f);
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  ASSERT_EQ(r->tools.size(), 3u);  // paint; cut + pick; two partition strokes
  EXPECT_EQ(r->failed, 0u);
  EXPECT_EQ(r->tools[0].tool, StrokeTool::kPaint);
  EXPECT_EQ(r->tools[0].name, "mark");
  ASSERT_EQ(r->tools[0].curves.size(), 1u);
  EXPECT_TRUE(m.alive(r->tools[0].curves[0]));  // painting keeps its curve
  EXPECT_EQ(r->tools[1].tool, StrokeTool::kCut);
  EXPECT_EQ(r->tools[1].strokes, 2u);
  ASSERT_EQ(r->tools[1].pieces.size(), 2u);
  EXPECT_GT(r->tools[1].removed_area, 0.0);
  // The picked (lower) side went.
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v})) {
      EXPECT_GT(m.nodes.position[v].y(), -0.9);
    }
  EXPECT_EQ(r->tools[2].strokes, 2u);
  EXPECT_EQ(r->tools[2].pieces.size(), 3u);
  EXPECT_EQ(m.num_surfaces(), 3u);
  EXPECT_EQ(m.num_joints(), 2u);
}

TEST(Sketch, SameBitsForOneAndTwoThreads) {
  const Camera cam = front_persp();
  const StrokeFile f = session(cam);
  Model a = icosphere(5), b = a;
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 1;
  ASSERT_TRUE(apply_strokes(a, f, {}, one));
  ASSERT_TRUE(apply_strokes(b, f, {}, two));
  EXPECT_EQ(diff_tables(a, b), "");
  EXPECT_EQ(serialize_model(a), serialize_model(b));
}

TEST(Sketch, AFailingStrokeLeavesTheModelAsItWas) {
  Model m = z_fold();
  const Camera cam = front_ortho();
  StrokeFile f;
  f.camera = cam;
  f.strokes.push_back(make(StrokeTool::kPaint, project(cam, {Vec3d(-0.9, 0.5, 0), Vec3d(0.2, 0.5, 0)}), false));
  f.strokes.push_back(
      make(StrokeTool::kCut, project(cam, {Vec3d(-1.2, 0.1, 0), Vec3d(1.2, 0.1, 0)}), false, "across the fold"));
  f.strokes.push_back(make(StrokeTool::kPaintThrough, project(cam, {Vec3d(-1.2, -0.3, 0), Vec3d(1.2, -0.3, 0)})));
  const Model before = m;
  auto r = apply_strokes(m, f);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("stroke 1 (cut 'across the fold')"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("fold"), std::string::npos);
  EXPECT_EQ(diff_tables(before, m), "");
  auto k = apply_strokes(m, f, {.keep_going = true});
  ASSERT_TRUE(k) << k.status().to_string();
  EXPECT_EQ(k->failed, 1u);
  ASSERT_EQ(k->tools.size(), 3u);
  EXPECT_TRUE(k->tools[0].status.is_ok());
  EXPECT_FALSE(k->tools[1].status.is_ok());
  EXPECT_EQ(k->tools[2].curves.size(), 3u);  // the penetrated stroke's three layers
  EXPECT_EQ(m.num_attrib_edges(), 4u);
  EXPECT_TRUE(validate(m));
}

TEST(Sketch, ACutThatFailsTakesItsCurveAway) {
  // The painted curve of a refused cut is not left behind.
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  StrokeFile f;
  f.camera = cam;
  f.strokes.push_back(make(StrokeTool::kCut, project(cam, {Vec3d(-1.5, 0.2, 0), Vec3d(1.5, 0.2, 0)})));  // visible only
  const Model before = m;
  auto r = apply_strokes(m, f, {.keep_going = true});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->failed, 1u);
  EXPECT_NE(r->tools[0].status.message().find("not separate"), std::string::npos) << r->tools[0].status.message();
  EXPECT_EQ(diff_tables(before, m), "");
}
