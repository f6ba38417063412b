#include <atelier/io/obj.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/measure.h>
#include <atelier/systems/mesh/section.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "support/shapes.h"
#include "tests/support/shared_data.h"

using namespace atelier;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  const char* env = std::getenv("ATELIER_TMP");
  fs::path d = (env ? fs::path(env) : fs::temp_directory_path() / "atelier-tests") / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::shared_ptr<ReferenceBody> ball(int nu = 12, int nv = 8) {
  return shapes::body_from(shapes::uv_sphere(nu, nv));
}

}  // namespace

TEST(BodySet, StoresBodiesAsFloatColumnsAndChecksInput) {
  auto ref = ball();
  BodySet set(ref);
  const std::size_t n = set.node_count();
  std::vector<Vec3d> p = skin_positions(*ref);
  ASSERT_TRUE(set.add("a", std::span<const Vec3d>(p)));
  for (auto& q : p) q *= 2.0;
  ASSERT_TRUE(set.add("b", std::span<const Vec3d>(p)));
  EXPECT_EQ(set.size(), 2u);
  EXPECT_EQ(set.bytes_per_body(), 3 * n * sizeof(float));
  const auto b = set.positions(1);
  for (std::size_t v = 0; v < n; ++v) EXPECT_NEAR((b[v] - p[v]).norm(), 0.0, 1e-6);
  EXPECT_FLOAT_EQ(set.x(1)[3], static_cast<float>(p[3].x()));
  EXPECT_FLOAT_EQ(set.z(0)[3], static_cast<float>(p[3].z() / 2));
  std::vector<Vec3d> short_p(n - 1);
  auto s = set.add("short", std::span<const Vec3d>(short_p));
  EXPECT_EQ(s.code(), ErrorCode::kMismatch);
  EXPECT_NE(s.message().find("short"), std::string::npos);
  p[5].y() = std::nan("");
  s = set.add("nan", std::span<const Vec3d>(p));
  EXPECT_EQ(s.code(), ErrorCode::kDegenerate);
  EXPECT_NE(s.message().find("node 5"), std::string::npos);
  EXPECT_EQ(set.size(), 2u);
  set.clear();
  EXPECT_TRUE(set.empty());
}

// Issue 27: a finite double beyond the float range (1e300 in a body OBJ)
// was stored as infinity; the body is refused as non-finite once stored.
TEST(BodySet, CoordinatesBeyondTheFloatRangeAreRefused) {
  auto ref = ball();
  BodySet set(ref);
  std::vector<Vec3d> p = skin_positions(*ref);
  p[7].z() = -1e300;
  Status s = set.add("far", std::span<const Vec3d>(p));
  EXPECT_EQ(s.code(), ErrorCode::kDegenerate);
  EXPECT_NE(s.message().find("node 7"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("float"), std::string::npos) << s.message();
  EXPECT_TRUE(set.empty());
  // The largest float itself is stored as it is.
  p[7].z() = static_cast<double>(std::numeric_limits<float>::max());
  ASSERT_TRUE(set.add("edge", std::span<const Vec3d>(p)));
  EXPECT_EQ(set.z(0)[7], std::numeric_limits<float>::max());
  for (float v : set.z(0)) EXPECT_TRUE(std::isfinite(v));
}

TEST(BodySet, ObjDirectoryReportsBadFilesByNameAndLoadsTheRest) {
  auto ref = ball();
  const fs::path dir = fresh_dir("obj-bodies");
  // Two good bodies (scaled), one with another topology, one malformed.
  for (int k : {1, 2}) {
    Model m = ref->model;
    for (auto& q : m.nodes.position) q *= 1.0 + 0.1 * k;
    write_obj(m, dir / ("body" + std::to_string(k) + ".obj"));
  }
  write_obj(ball(10, 8)->model, dir / "body3_other.obj");
  std::ofstream(dir / "body4_bad.obj") << "v 0 0 0\nv 1 0 0\nf 1 2 9\n";
  ObjDirectorySource src(dir, ref);
  ASSERT_EQ(src.size(), 4u);
  BodySet out(ref);
  std::vector<BodyFailure> fail;
  src.generate(0, 10, out, fail, {});
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out.name(0), "body1");
  ASSERT_EQ(fail.size(), 2u);
  EXPECT_EQ(fail[0].name, "body3_other");
  EXPECT_EQ(fail[0].status.code(), ErrorCode::kMismatch);
  EXPECT_NE(fail[0].status.message().find("body3_other.obj"), std::string::npos) << fail[0].status.message();
  EXPECT_EQ(fail[1].name, "body4_bad");
  EXPECT_NE(fail[1].status.message().find("body4_bad.obj"), std::string::npos) << fail[1].status.message();
  // Positions round-trip through the files.
  const auto p = out.positions(1);
  const auto r = skin_positions(*ref);
  for (std::size_t v = 0; v < p.size(); ++v) EXPECT_NEAR((p[v] - 1.2 * r[v]).norm(), 0.0, 1e-6);
}

TEST(MeshSection, CutsASphereInACircle) {
  auto ref = ball(48, 32);
  const auto p = skin_positions(*ref);
  for (double d : {0.0, 0.3, -0.55}) {
    auto chains = plane_section(ref->model, ref->skin, Vec3d(0, 0, 1), d, p);
    ASSERT_EQ(chains.size(), 1u) << d;
    EXPECT_TRUE(chains[0].closed);
    std::vector<Vec3d> pts;
    for (const auto& q : chains[0].points) {
      EXPECT_NEAR(q.p.z(), d, 1e-12);
      pts.push_back(q.p);
      // The stored location evaluates to the same point.
      const HalfedgeIdx h{q.where.element};
      const double u = q.where.param.x();
      EXPECT_LT(((1 - u) * p[ref->model.tail(h).value] + u * p[ref->model.head(h).value] - q.p).norm(), 1e-12);
    }
    // A polygon inscribed in the circle of radius sqrt(1-d^2) (the mesh is
    // inscribed in the unit sphere): slightly shorter than the circle.
    const double circle = 2 * M_PI * std::sqrt(1 - d * d);
    const double len = polyline_length(pts, true);
    EXPECT_LT(len, circle);
    EXPECT_GT(len, 0.98 * circle);
  }
}

namespace {
using atelier::testing::makehuman_dir;
const std::shared_ptr<const makehuman::HumanLibrary>& mh_lib() {
  static auto lib = std::make_shared<const makehuman::HumanLibrary>(makehuman::HumanLibrary::load(makehuman_dir()));
  return lib;
}
}  // namespace

#define REQUIRE_MAKEHUMAN()                      \
  if (!fs::exists(makehuman_dir() / "base.obj")) \
  GTEST_SKIP() << "MakeHuman data not found at " << makehuman_dir() << " (../shared/data absent)"

TEST(MakeHumanReference, SkinIsClosedAndFeaturesAreComplete) {
  REQUIRE_MAKEHUMAN();
  const ReferenceBody rb = makehuman::make_reference_body(*mh_lib());
  ASSERT_TRUE(validate(rb.model)) << validate(rb.model).to_string();
  ASSERT_TRUE(validate_features(rb)) << validate_features(rb).to_string();
  const auto t = count_topology(rb.model);
  EXPECT_EQ(t.faces, 13378);
  EXPECT_EQ(t.shells, 1);  // closed skin
  for (const char* c : {"neck", "bust", "underbust", "waist", "hip", "left_thigh", "right_thigh", "left_knee",
                        "right_knee", "left_ankle", "right_ankle", "centre_front", "centre_back", "left_side",
                        "right_side", "left_upperarm", "right_upperarm"})
    EXPECT_NE(rb.find_curve(c), nullptr) << c;
  for (const char* g : {"bust", "underbust", "waist"})
    for (const char* l : {"centre_front", "centre_back", "left_side", "right_side"}) {
      const std::string name = std::string(g) + "_x_" + l;
      const auto* fp = rb.find_point(name);
      ASSERT_NE(fp, nullptr) << name;
      auto fr = feature_frame(rb, fp->id);
      ASSERT_TRUE(fr) << name << ": " << fr.status().to_string();
      EXPECT_GT(std::abs(fr->triple()), 0.3) << name;
    }
  // Girths are plausible adult sizes (metres) and mirrored limbs match.
  auto len = [&](const char* c) {
    auto pl = feature_curve_polyline(rb, rb.find_curve(c)->id);
    return polyline_length(*pl, rb.find_curve(c)->closed);
  };
  EXPECT_GT(len("waist"), 0.6);
  EXPECT_LT(len("waist"), 1.0);
  EXPECT_GT(len("hip"), len("waist"));
  EXPECT_NEAR(len("left_thigh"), len("right_thigh"), 0.005);
  EXPECT_NEAR(len("left_ankle"), len("right_ankle"), 0.005);
  // Centre front runs from the neck down towards the crotch.
  auto cf = *feature_curve_polyline(rb, rb.find_curve("centre_front")->id);
  EXPECT_GT(cf.front().y(), cf.back().y() + 0.3);
  for (const auto& q : cf) EXPECT_NEAR(q.x(), 0.0, 1e-9);
}

TEST(MakeHumanReference, FeaturesFollowTheMorphedBody) {
  REQUIRE_MAKEHUMAN();
  auto ref = std::make_shared<const ReferenceBody>(makehuman::make_reference_body(*mh_lib()));
  auto params = makehuman::sample_adults(6, 42);
  makehuman::MakeHumanSource src(mh_lib(), params, ref);
  BodySet set(ref);
  std::vector<BodyFailure> fail;
  ExecContext ctx;
  src.generate(0, 6, set, fail, ctx);
  ASSERT_TRUE(fail.empty());
  ASSERT_EQ(set.size(), 6u);
  // Each body equals its own direct build, and waist girths differ between bodies.
  std::vector<double> waists;
  for (std::size_t b = 0; b < set.size(); ++b) {
    const auto p = set.positions(b);
    const auto direct = src.skin_positions(b);
    for (std::size_t v = 0; v < p.size(); v += 97) EXPECT_LT((p[v] - direct[v]).norm(), 1e-6);
    auto pl = feature_curve_polyline(*ref, ref->find_curve("waist")->id, p);
    waists.push_back(polyline_length(*pl, true));
    auto fr = feature_frame(*ref, ref->find_point("waist_x_centre_front")->id, p);
    ASSERT_TRUE(fr);
    EXPECT_GT(std::abs(fr->triple()), 0.3);
  }
  std::sort(waists.begin(), waists.end());
  EXPECT_GT(waists.back() - waists.front(), 0.02);
  // Same seed, same bodies: generation is deterministic across thread counts.
  BodySet again(ref);
  ExecContext one = ExecContext::sequential();
  src.generate(0, 6, again, fail, one);
  for (std::size_t b = 0; b < 6; ++b) {
    auto x1 = set.x(b), x2 = again.x(b);
    EXPECT_TRUE(std::equal(x1.begin(), x1.end(), x2.begin()));
  }
}
