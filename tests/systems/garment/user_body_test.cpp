// Garments on a user's own body family (issue 26, "any reference body"): a
// family of bodies of an unknown topology (no feature curves), written in
// centimetres and Z-up, encodes and regenerates a garment to the same
// result as the same family in metres and Y-up.
#include <atelier/storage/validate.h>
#include <atelier/systems/body/body_file.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "support/run_command.h"
#include "support/shapes.h"

using namespace atelier;
namespace fs = std::filesystem;

namespace {

constexpr int kNu = 24, kNv = 16;

/// A body: an ellipsoid (semi-axes a, b, c along x, y, z) standing on y = 0.
shapes::Soup body(double a, double b, double c) {
  shapes::Soup s = shapes::uv_sphere(kNu, kNv);
  // Poles along engine y: (x, z, -y), a rotation. Float coordinates, as
  // bodies written by the engine have: 100 times them is exact.
  for (Vec3d& p : s.p) p = round_to_float(Vec3d(a * p.x(), c * p.z() + c, -b * p.y()));
  return s;
}

/// A tube around the reference body's middle rings, 1.5 cm outside it.
shapes::Soup band(double a, double b, double c) {
  shapes::Soup g;
  const int j0 = 5, j1 = 11;
  for (int j = j0; j <= j1; ++j)
    for (int i = 0; i < kNu; ++i) {
      const double th = M_PI * j / kNv, ph = 2 * M_PI * (i + 0.5) / kNu;
      const Vec3d u(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      // On a grid of 2^-16 m: garment files are read in float precision,
      // and 100 times such a coordinate is a float too (17 + 7 bits).
      const Vec3d q((a + 0.015) * u.x(), (c + 0.015) * u.z() + c, -(b + 0.015) * u.y());
      g.p.push_back((q * 65536).array().round().matrix() / 65536);
    }
  for (int j = 0; j < j1 - j0; ++j)
    for (int i = 0; i < kNu; ++i) {
      auto at = [&](int jj, int ii) { return static_cast<std::uint32_t>(jj * kNu + ii % kNu); };
      g.face({at(j, i), at(j + 1, i), at(j + 1, i + 1), at(j, i + 1)});
    }
  return g;
}

Vec3d identity(const Vec3d& p) {
  return p;
}
// Engine (X, Y, Z) in metres is file (X, -Z, Y) in centimetres.
Vec3d cm_z_up(const Vec3d& p) {
  return Vec3d(100 * p.x(), -100 * p.z(), 100 * p.y());
}

struct FamilyRun {
  std::vector<std::vector<Vec3d>> positions;  // per body, engine frame
  std::vector<GarmentQuality> quality;
};

FamilyRun encode_and_regenerate(const fs::path& dir, const BodyFrame& frame) {
  auto ref = read_reference_body(dir / "ref.obj", {.frame = frame});
  if (!ref) throw Error(ref.status());
  EXPECT_TRUE(validate(ref->model)) << validate(ref->model).message();
  EXPECT_TRUE(ref->curves.empty());
  auto g = encode_garment_file(*ref, dir / "band.obj", {.frame = frame});
  if (!g) throw Error(g.status());
  auto family = GarmentFamily::of(*ref);
  if (!family) throw Error(family.status());
  auto shared_ref = std::make_shared<const ReferenceBody>(std::move(*ref));
  ObjDirectorySource src(dir / "set", shared_ref, frame);
  BodySet set(shared_ref);
  std::vector<BodyFailure> failures;
  src.generate(0, src.size(), set, failures, {});
  EXPECT_TRUE(failures.empty());
  auto regen = GarmentRegenerator::create(std::make_shared<const GarmentFamily>(std::move(*family)),
                                          {std::make_shared<const GarmentTemplate>(std::move(*g))});
  if (!regen) throw Error(regen.status());
  std::vector<BodyGarments> out;
  if (Status s = regen->run(set, 0, set.size(), out); !s) throw Error(s);
  FamilyRun r;
  for (const BodyGarments& b : out) {
    EXPECT_TRUE(b.status) << b.status.message();
    r.positions.push_back(b.garments.at(0).positions);
    r.quality.push_back(b.garments.at(0).quality);
  }
  return r;
}

}  // namespace

TEST(UserBody, AFamilyInCentimetresZUpRegeneratesAsInMetresYUp) {
  const fs::path root = atelier::testing::scratch_dir("user_body_family");
  const double a = 0.17, b = 0.12, c = 0.85;
  for (const auto& [name, map] : {std::pair{"m", &identity}, std::pair{"cm", &cm_z_up}}) {
    const fs::path d = root / name;
    fs::create_directories(d / "set");
    shapes::write_soup_obj(body(a, b, c), d / "ref.obj", map);
    shapes::write_soup_obj(band(a, b, c), d / "band.obj", map);
    // The family: wider, deeper and taller bodies of the same topology.
    for (int k = 0; k < 4; ++k)
      shapes::write_soup_obj(body(a * (1 + 0.06 * k), b * (1 + 0.09 * (3 - k)), c * (1 + 0.02 * k)),
                 d / "set" / ("b" + std::to_string(k) + ".obj"), map);
  }
  const BodyFrame cm{0.01, UpAxis::kZ};
  const FamilyRun m = encode_and_regenerate(root / "m", {});
  const FamilyRun z = encode_and_regenerate(root / "cm", cm);
  ASSERT_EQ(m.positions.size(), 4u);
  ASSERT_EQ(z.positions.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    ASSERT_EQ(m.positions[k].size(), z.positions[k].size());
    double worst = 0;
    for (std::size_t v = 0; v < m.positions[k].size(); ++v) {
      const Vec3d& pm = m.positions[k][v];
      ASSERT_TRUE(pm.allFinite());
      // Engine frame: the same garment; and in the user's frame, the
      // garment in metres, Y-up mapped to centimetres, Z-up.
      worst = std::max(worst, (z.positions[k][v] - pm).norm() / pm.norm());
      EXPECT_LE((cm.to_file(z.positions[k][v]) - cm_z_up(pm)).norm(), 1e-9 * cm_z_up(pm).norm()) << k << " " << v;
    }
    // The inputs' coordinates times 100 are exact and dividing by 100
    // gives them back: the engine sees the same bits, and the results are
    // the same.
    EXPECT_EQ(worst, 0.0) << "body " << k;
    // The garment actually moved with the body, outside it.
    EXPECT_EQ(m.quality[k].inside, 0u) << k;
    EXPECT_EQ(z.quality[k].inside, m.quality[k].inside);
    EXPECT_EQ(z.quality[k].min_clearance, m.quality[k].min_clearance);
    EXPECT_EQ(z.quality[k].strain_max, m.quality[k].strain_max);
  }
  // Wider bodies give a wider garment: the result is not the reference garment.
  double x0 = 0, x3 = 0;
  for (const Vec3d& p : m.positions[0]) x0 = std::max(x0, p.x());
  for (const Vec3d& p : m.positions[3]) x3 = std::max(x3, p.x());
  EXPECT_GT(x3, x0 + 0.02);
}

TEST(UserBody, AGarmentFileInABadFrameOrOnAnOpenBodyIsRefusedNamingTheFile) {
  const fs::path d = atelier::testing::scratch_dir("user_body_bad");
  shapes::write_soup_obj(band(0.17, 0.12, 0.85), d / "band.obj", identity);
  // The band itself is open: as a reference body it is refused.
  auto open = read_reference_body(d / "band.obj");
  ASSERT_FALSE(open);
  EXPECT_NE(open.status().message().find("band.obj"), std::string::npos);
  EXPECT_NE(open.status().message().find("not closed"), std::string::npos) << open.status().message();
  shapes::write_soup_obj(body(0.17, 0.12, 0.85), d / "ref.obj", identity);
  auto ref = read_reference_body(d / "ref.obj");
  ASSERT_TRUE(ref) << ref.status().message();
  auto g = encode_garment_file(*ref, d / "band.obj", {.frame = {0.0, UpAxis::kY}});
  ASSERT_FALSE(g);
  EXPECT_NE(g.status().message().find("band.obj"), std::string::npos) << g.status().message();
  auto none = encode_garment_file(*ref, d / "none.obj");
  ASSERT_FALSE(none);
  EXPECT_NE(none.status().message().find("none.obj"), std::string::npos) << none.status().message();
}
