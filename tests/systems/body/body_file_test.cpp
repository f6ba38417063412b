// A user's own reference body from a file (systems/body/body_file.h): the
// frame's maps, the closed/oriented check on broken bodies, and a body set
// in another frame (issue 26, "any reference body").
#include <atelier/storage/validate.h>
#include <atelier/systems/body/body_file.h>
#include <atelier/systems/body/body_set.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "support/run_command.h"
#include "support/shapes.h"

using namespace atelier;
namespace fs = std::filesystem;

TEST(BodyFile, FrameMapsAreInverseRotationsAndZUpBecomesYUp) {
  const BodyFrame cm_z{0.01, UpAxis::kZ};
  // File up (+z) is engine up (+y); the map is a proper rotation (det +1).
  EXPECT_EQ(cm_z.to_engine(Vec3d(0, 0, 100)), Vec3d(0, 1, 0));
  const Vec3d ex = cm_z.to_engine(Vec3d(100, 0, 0)), ey = cm_z.to_engine(Vec3d(0, 100, 0)),
              ez = cm_z.to_engine(Vec3d(0, 0, 100));
  EXPECT_DOUBLE_EQ(ex.cross(ey).dot(ez), 1.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-200, 200);
  for (int i = 0; i < 100; ++i) {
    const Vec3d p(u(rng), u(rng), u(rng));
    EXPECT_LE((cm_z.to_file(cm_z.to_engine(p)) - p).norm(), 1e-13 * p.norm());
    const BodyFrame y{1.0, UpAxis::kY};
    EXPECT_EQ(y.to_engine(p), p);  // the identity is exact
  }
  EXPECT_TRUE(parse_up_axis("Z").has_value());
  EXPECT_FALSE(parse_up_axis("x").has_value());
  EXPECT_FALSE((BodyFrame{0.0, UpAxis::kY}.check()));
  EXPECT_FALSE((BodyFrame{std::nan(""), UpAxis::kY}.check()));
}

TEST(BodyFile, AClosedBodyInCentimetresZUpIsTheBodyInMetresYUp) {
  const fs::path d = atelier::testing::scratch_dir("body_file_frame");
  const shapes::Soup s = shapes::uv_sphere(16, 10, 0.2, Vec3d(0.1, 0.9, 0.05));
  shapes::write_soup_obj(s, d / "m.obj", [](const Vec3d& p) { return p; });
  // Engine (X, Y, Z) in metres is file (X, -Z, Y) in centimetres.
  shapes::write_soup_obj(s, d / "cm.obj", [](const Vec3d& p) { return Vec3d(100 * p.x(), -100 * p.z(), 100 * p.y()); });
  auto m = read_reference_body(d / "m.obj");
  auto c = read_reference_body(d / "cm.obj", {.frame = {0.01, UpAxis::kZ}});
  ASSERT_TRUE(m) << m.status().message();
  ASSERT_TRUE(c) << c.status().message();
  EXPECT_TRUE(validate(m->model)) << validate(m->model).message();
  EXPECT_TRUE(validate(c->model)) << validate(c->model).message();
  EXPECT_TRUE(m->curves.empty()) << "an unknown topology has no features";
  ASSERT_EQ(m->model.nodes.position.size(), s.p.size());
  ASSERT_EQ(c->model.nodes.position.size(), s.p.size());
  for (std::size_t v = 0; v < s.p.size(); ++v) {
    EXPECT_EQ(m->model.nodes.position[v], s.p[v]);  // %.17g round-trips exactly
    EXPECT_LE((c->model.nodes.position[v] - s.p[v]).norm(), 1e-15 * (1 + s.p[v].norm())) << v;
  }
  // A family member in the same frame, read by the directory source.
  fs::create_directories(d / "set");
  shapes::write_soup_obj(s, d / "set" / "b.obj",
             [](const Vec3d& p) { return Vec3d(100 * 1.1 * p.x(), -100 * p.z(), 100 * p.y()); });
  ObjDirectorySource src(d / "set", std::make_shared<const ReferenceBody>(std::move(*c)), BodyFrame{0.01, UpAxis::kZ});
  BodySet set(src.reference());
  std::vector<BodyFailure> failures;
  src.generate(0, 1, set, failures, {});
  ASSERT_TRUE(failures.empty()) << failures[0].status.message();
  const std::vector<Vec3d> p = set.positions(0);
  for (std::size_t v = 0; v < s.p.size(); ++v) {
    const Vec3d want(1.1 * s.p[v].x(), s.p[v].y(), s.p[v].z());
    EXPECT_LE((p[v] - want).norm(), 1e-6 * (1 + want.norm())) << v;  // stored as float
  }
  EXPECT_EQ(src.frame().up, UpAxis::kZ);
}

TEST(BodyFile, OpenFlippedInwardAndWrongTopologyBodiesAreNamedWithTheReason) {
  const fs::path d = atelier::testing::scratch_dir("body_file_bad");
  shapes::Soup s = shapes::uv_sphere(12, 8, 0.3);
  shapes::write_soup_obj(s, d / "good.obj", [](const Vec3d& p) { return p; });
  // Open: the north cap's fan removed.
  {
    shapes::Soup open;
    open.p = s.p;
    for (std::size_t k = 12; k + 1 < s.off.size(); ++k) {
      open.idx.insert(open.idx.end(), s.idx.begin() + s.off[k], s.idx.begin() + s.off[k + 1]);
      open.off.push_back(static_cast<std::uint32_t>(open.idx.size()));
    }
    shapes::write_soup_obj(open, d / "open.obj", [](const Vec3d& p) { return p; });
  }
  // One face turned the other way (read_obj names the two faces and their lines).
  {
    shapes::Soup flip = s;
    std::reverse(flip.idx.begin() + flip.off[20], flip.idx.begin() + flip.off[21]);
    shapes::write_soup_obj(flip, d / "flip.obj", [](const Vec3d& p) { return p; });
  }
  // Every face turned: closed and consistent, but facing inward.
  {
    shapes::Soup in = s;
    for (std::size_t k = 0; k + 1 < in.off.size(); ++k)
      std::reverse(in.idx.begin() + in.off[k], in.idx.begin() + in.off[k + 1]);
    shapes::write_soup_obj(in, d / "inward.obj", [](const Vec3d& p) { return p; });
  }
  struct Case {
    const char* file;
    const char* says;
  };
  for (const Case& c : {Case{"open.obj", "not closed"}, Case{"flip.obj", "orient"}, Case{"inward.obj", "point inward"},
                        Case{"missing.obj", "no such file"}}) {
    auto r = read_reference_body(d / c.file);
    ASSERT_FALSE(r) << c.file;
    EXPECT_NE(r.status().message().find(c.file), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find(c.says), std::string::npos) << r.status().message();
  }
  auto bad_scale = read_reference_body(d / "good.obj", {.frame = {-1.0, UpAxis::kY}});
  EXPECT_FALSE(bad_scale);
  // A family member of another topology: a failure naming the file; the others complete.
  auto ref = read_reference_body(d / "good.obj");
  ASSERT_TRUE(ref) << ref.status().message();
  fs::create_directories(d / "set");
  fs::copy_file(d / "good.obj", d / "set" / "a.obj");
  shapes::write_soup_obj(shapes::uv_sphere(10, 8, 0.3), d / "set" / "b.obj", [](const Vec3d& p) { return p; });
  ObjDirectorySource src(d / "set", std::make_shared<const ReferenceBody>(std::move(*ref)), BodyFrame{});
  BodySet set(src.reference());
  std::vector<BodyFailure> failures;
  src.generate(0, 2, set, failures, {});
  EXPECT_EQ(set.size(), 1u);
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_NE(failures[0].status.message().find("b.obj"), std::string::npos) << failures[0].status.message();
  EXPECT_NE(failures[0].status.message().find("topology differs"), std::string::npos) << failures[0].status.message();
}
