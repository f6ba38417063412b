#include <atelier/systems/view/camera.h>

#include <gtest/gtest.h>

#include <cmath>

namespace atelier {
namespace {

TEST(Camera, ProjectAndRayAreInverse) {
  for (const Camera& cam : {Camera::look_at(Vec3d(3, -2, 1.5), Vec3d(0, 0, 0.5), Vec3d(0, 0, 1), 45, 800, 600),
                            Camera::orthographic(Vec3d(3, -2, 1.5), Vec3d(0, 0, 0.5), Vec3d(0, 0, 1), 1.5, 800, 600)}) {
    ASSERT_TRUE(cam.check());
    for (const Vec3d& p : {Vec3d(0.1, 0.2, 0.3), Vec3d(-0.4, 0.3, 0.9), Vec3d(0.7, -0.6, 0.1)}) {
      const Vec3d px = cam.project(p);
      const auto [o, d] = cam.ray(px.head<2>());
      EXPECT_NEAR(d.norm(), 1.0, 1e-12);
      // p lies on the ray: its distance to the line is zero.
      EXPECT_LT((p - o - (p - o).dot(d) * d).norm(), 1e-9);
    }
  }
}

TEST(Camera, FrameMatchesTheMatrixRays) {
  for (const Camera& cam : {Camera::look_at(Vec3d(3, -2, 1.5), Vec3d(0, 0, 0.5), Vec3d(0, 0, 1), 45, 800, 600),
                            Camera::orthographic(Vec3d(3, -2, 1.5), Vec3d(0, 0, 0.5), Vec3d(0, 0, 1), 1.5, 800, 600)}) {
    auto f = cam.frame();
    ASSERT_TRUE(f.has_value()) << f.status().to_string();
    EXPECT_LT((f->eye - Vec3d(3, -2, 1.5)).norm(), 1e-12);
    EXPECT_EQ(f->projection == Projection::kPerspective, cam.perspective());
    for (const Vec2d px : {Vec2d(10.5, 20.5), Vec2d(400, 300), Vec2d(799, 1)}) {
      Vec3d o, d;
      f->ray(px.x(), px.y(), 800, 600, o, d);
      const auto [o2, d2] = cam.ray(px);
      EXPECT_LT((d - d2).norm(), 1e-9);
      EXPECT_LT((o2 - o - (o2 - o).dot(d) * d).norm(), 1e-7);  // same line
    }
  }
}

TEST(Camera, FrameBoxFramesTheBoxCentre) {
  Box3d box;
  box.extend(Vec3d(-1, 0, -0.5));
  box.extend(Vec3d(1, 2, 0.5));
  for (View v : {View::kFront, View::kSide, View::kBack})
    for (Projection pr : {Projection::kOrthographic, Projection::kPerspective}) {
      auto cam = frame_box(box, v, pr, 300, 400);
      ASSERT_TRUE(cam.has_value());
      const Vec3d c = cam->project(Vec3d(0, 1, 0));
      EXPECT_NEAR(c.x(), 150, 1e-9);
      EXPECT_NEAR(c.y(), 200, 1e-9);
      // Every corner is inside the picture.
      for (int k = 0; k < 8; ++k) {
        const Vec3d q(k & 1 ? 1 : -1, k & 2 ? 2 : 0, k & 4 ? 0.5 : -0.5);
        const Vec3d p = cam->project(q);
        EXPECT_GE(p.x(), 0);
        EXPECT_LE(p.x(), 300);
        EXPECT_GE(p.y(), 0);
        EXPECT_LE(p.y(), 400);
      }
    }
  EXPECT_FALSE(frame_box(Box3d{}, View::kFront, Projection::kOrthographic, 10, 10).has_value());
  EXPECT_FALSE(frame_box(box, View::kFront, Projection::kOrthographic, 0, 10).has_value());
}

TEST(Camera, BadMatricesAreNamed) {
  Camera c;
  c.projection.setZero();
  EXPECT_EQ(c.check().code(), ErrorCode::kInvalidArgument);
  c = Camera{};
  c.view(0, 0) = std::nan("");
  EXPECT_NE(c.check().message().find("non-finite"), std::string::npos);
  c = Camera{};
  c.width = 0;
  EXPECT_FALSE(c.check());
  c = Camera::look_at(Vec3d(0, 0, 3), Vec3d::Zero(), Vec3d::UnitY(), 40, 100, 100);
  c.projection(0, 2) = 0.3;  // off-centre
  EXPECT_EQ(c.frame().status().code(), ErrorCode::kUnsupported);
}

}  // namespace
}  // namespace atelier
