// `atelier extrude` on good and bad inputs (runs the built binary): a dome
// on an open cup closes it; a stroke far from the rim exits 3 with the
// stroke file named, writing no mesh but the --json error; usage errors exit 2.
#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/view/strokes.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "support/run_command.h"

namespace fs = std::filesystem;
using namespace atelier;

namespace {

constexpr int kRing = 24;

struct Files {
  fs::path dir, mesh, strokes;
};

/// An open cup (unit rings at y = 0, -0.5, -1, a bottom centre) and a dome
/// drawn on its rim (shifted up by `lift` pixels: far from the rim).
Files setup(const std::string& name, double lift = 0) {
  Files f;
  f.dir = atelier::testing::scratch_dir(name);
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> off{0}, idx;
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < kRing; ++i)
      p.push_back(Vec3d(std::cos(2 * M_PI * i / kRing), -0.5 * r, std::sin(2 * M_PI * i / kRing)));
  p.push_back(Vec3d(0, -1, 0));
  auto id = [](int r, int i) { return static_cast<std::uint32_t>(r * kRing + i % kRing); };
  auto face = [&](std::initializer_list<std::uint32_t> v) {
    idx.insert(idx.end(), v);
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  };
  for (int r = 0; r < 2; ++r)
    for (int i = 0; i < kRing; ++i) {
      face({id(r, i), id(r, i + 1), id(r + 1, i + 1)});
      face({id(r, i), id(r + 1, i + 1), id(r + 1, i)});
    }
  for (int i = 0; i < kRing; ++i) face({id(2, i), id(2, i + 1), 3 * kRing});
  Model m;
  (void)add_polygon_surface(m, "cup", PolygonSoupView{p, off, idx}).value();
  f.mesh = f.dir / "cup.obj";
  write_obj(m, f.mesh);
  StrokeFile s;
  s.camera = Camera::orthographic(Vec3d(0, 0, 5), Vec3d::Zero(), Vec3d::UnitY(), 1.5, 800, 800);
  auto px = [&](const Vec3d& q) { return Vec2d(s.camera.project(q).head<2>()); };
  Stroke base, dome;
  base.tool = dome.tool = StrokeTool::kExtrude;
  base.points = {px(Vec3d(-1, 0, 0)), px(Vec3d(1, 0, 0)), px(Vec3d(-1, 0, 0))};
  for (int i = 0; i <= 20; ++i) {
    const double t = M_PI * (1 - i / 20.0);
    dome.points.push_back(px(Vec3d(std::cos(t), std::sin(t), 0)) - Vec2d(0, lift));
  }
  s.strokes = {base, dome};
  f.strokes = f.dir / "strokes.json";
  EXPECT_TRUE(write_strokes(s, f.strokes));
  return f;
}

std::string args(const Files& f, const fs::path& out, const std::string& extra = "") {
  return "extrude --mesh " + f.mesh.string() + " --strokes " + f.strokes.string() + " --out " + out.string() + " " +
         extra;
}

}  // namespace

TEST(ExtrudeCli, DomeClosesTheCup) {
  const Files f = setup("extrude-cli-ok");
  auto r = atelier::testing::run_cli(args(f, f.dir / "out.obj", "--no-optimise --json " + (f.dir / "r.json").string()));
  ASSERT_EQ(r.code, 0) << r.out;
  const Model m = read_obj(f.dir / "out.obj");
  ASSERT_TRUE(validate(m));
  const TopologyCounts t = count_topology(m);
  EXPECT_EQ(t.nodes - t.edges + t.faces, 2);
  EXPECT_EQ(t.shells, 1);
  std::ifstream in(f.dir / "r.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_TRUE(j["ok"].get<bool>());
  const std::size_t K = j["copies"].get<std::size_t>();
  EXPECT_EQ(j["swept_nodes"].get<std::size_t>(), kRing * (K - 1) + 1);
  EXPECT_EQ(m.num_nodes(), std::size_t{3 * kRing + 1} + kRing * (K - 1) + 1);
}

TEST(ExtrudeCli, BadStrokesExit3AndWriteNoMesh) {
  const Files f = setup("extrude-cli-far", 100);
  auto r = atelier::testing::run_cli(args(f, f.dir / "out.obj", "--json " + (f.dir / "r.json").string()));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("strokes.json"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("does not start near the base curve"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(f.dir / "out.obj"));
  std::ifstream in(f.dir / "r.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_FALSE(j["ok"].get<bool>());
  EXPECT_EQ(atelier::testing::run_cli("extrude --mesh " + f.mesh.string()).code, 2);
}

TEST(ExtrudeCli, AsSurfaceOutsideABody) {
  const Files f = setup("extrude-cli-joint");
  // A closed box |x|, |z| <= 0.3, 0.6 <= y <= 1.2 that the dome's top enters.
  std::vector<Vec3d> p;
  for (int k = 0; k < 8; ++k) p.push_back(Vec3d(k & 1 ? 0.3 : -0.3, k & 2 ? 1.2 : 0.6, k & 4 ? 0.3 : -0.3));
  const std::vector<std::uint32_t> idx{0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4,
                                       2, 6, 7, 2, 7, 3, 0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6};
  std::vector<std::uint32_t> off;
  for (std::uint32_t i = 0; i <= 12; ++i) off.push_back(3 * i);
  Model box;
  ASSERT_TRUE(add_polygon_surface(box, "box", PolygonSoupView{p, off, idx}));
  write_obj(box, f.dir / "box.obj");
  auto r = atelier::testing::run_cli(args(f, f.dir / "out.atm",
                                          "--as-surface --body " + (f.dir / "box.obj").string() +
                                              " --clearance 0.01 --json " + (f.dir / "r.json").string()));
  ASSERT_EQ(r.code, 0) << r.out;
  const Model m = read_model(f.dir / "out.atm");
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_EQ(m.num_surfaces(), 2u);
  EXPECT_EQ(m.num_joints(), 1u);
  std::ifstream in(f.dir / "r.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_GT(j["pushed"].get<std::size_t>(), 0u);
  EXPECT_EQ(j["inside_after"].get<std::size_t>(), 0u);
  EXPECT_EQ(j["joints"].get<std::size_t>(), 1u);
  // Independently: no node inside the box.
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
    if (!m.alive(NodeIdx{v})) continue;
    const Vec3d q = m.position(NodeIdx{v});
    EXPECT_FALSE(std::abs(q.x()) < 0.3 && std::abs(q.z()) < 0.3 && q.y() > 0.6 && q.y() < 1.2) << "node " << v;
  }
}

namespace {

/// Two open cups side by side at x = +2 and x = -2, one the exact
/// reflection of the other across x = 0, the dome drawn on the right one.
Files setup_pair(const std::string& name) {
  Files f;
  f.dir = atelier::testing::scratch_dir(name);
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> off{0}, idx;
  auto face = [&](std::initializer_list<std::uint32_t> v) {
    idx.insert(idx.end(), v);
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  };
  for (int side = 0; side < 2; ++side) {
    const std::uint32_t o = static_cast<std::uint32_t>(p.size());
    const double sx = side == 0 ? 1 : -1;
    for (int r = 0; r < 3; ++r)
      for (int i = 0; i < kRing; ++i)
        p.push_back(Vec3d(sx * (2 + std::cos(2 * M_PI * i / kRing)), -0.5 * r, std::sin(2 * M_PI * i / kRing)));
    p.push_back(Vec3d(sx * 2, -1, 0));
    auto id = [&](int r, int i) { return o + static_cast<std::uint32_t>(r * kRing + i % kRing); };
    // The reflected cup's faces run the other way round (outward normals).
    auto tri = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      if (side == 0)
        face({a, b, c});
      else
        face({c, b, a});
    };
    for (int r = 0; r < 2; ++r)
      for (int i = 0; i < kRing; ++i) {
        tri(id(r, i), id(r, i + 1), id(r + 1, i + 1));
        tri(id(r, i), id(r + 1, i + 1), id(r + 1, i));
      }
    for (int i = 0; i < kRing; ++i) tri(id(2, i), id(2, i + 1), o + 3 * kRing);
  }
  Model m;
  (void)add_polygon_surface(m, "cups", PolygonSoupView{p, off, idx}).value();
  f.mesh = f.dir / "cups.obj";
  write_obj(m, f.mesh);
  StrokeFile s;
  s.camera = Camera::orthographic(Vec3d(2, 0, 5), Vec3d(2, 0, 0), Vec3d::UnitY(), 1.5, 800, 800);
  auto px = [&](const Vec3d& q) { return Vec2d(s.camera.project(q).head<2>()); };
  Stroke base, dome;
  base.tool = dome.tool = StrokeTool::kExtrude;
  base.points = {px(Vec3d(1, 0, 0)), px(Vec3d(3, 0, 0)), px(Vec3d(1, 0, 0))};
  for (int i = 0; i <= 20; ++i) {
    const double t = M_PI * (1 - i / 20.0);
    dome.points.push_back(px(Vec3d(2 + std::cos(t), std::sin(t), 0)));
  }
  s.strokes = {base, dome};
  f.strokes = f.dir / "strokes.json";
  EXPECT_TRUE(write_strokes(s, f.strokes));
  return f;
}

}  // namespace

TEST(ExtrudeCli, MirrorDomesCloseBothCups) {
  const Files f = setup_pair("extrude-cli-mirror");
  for (const std::string opt : {"--mirror x", "--mirror-plane 0,0,0,-3,0,0"}) {
    auto r = atelier::testing::run_cli(
        args(f, f.dir / "out.obj", "--no-optimise " + opt + " --json " + (f.dir / "r.json").string()));
    ASSERT_EQ(r.code, 0) << opt << ": " << r.out;
    const Model m = read_obj(f.dir / "out.obj");
    ASSERT_TRUE(validate(m));
    const TopologyCounts t = count_topology(m);
    EXPECT_EQ(t.shells, 2);
    EXPECT_EQ(t.nodes - t.edges + t.faces, 4);  // two closed spheres
    std::ifstream in(f.dir / "r.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_TRUE(j["mirrored"].get<bool>());
    const std::size_t K = j["copies"].get<std::size_t>();
    EXPECT_EQ(j["mirror_nodes"].get<std::size_t>(), kRing * (K - 1) + 1);
    EXPECT_EQ(m.num_nodes(), 2 * (std::size_t{3 * kRing + 1} + kRing * (K - 1) + 1));
    // Every node has its reflection across x = 0 among the nodes (OBJ
    // round trip: printed to 17 digits).
    for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
      const Vec3d q = m.position(NodeIdx{v});
      double best = INFINITY;
      for (std::uint32_t w = 0; w < m.nodes.slots.capacity(); ++w)
        best = std::min(best, (m.position(NodeIdx{w}) - Vec3d(-q.x(), q.y(), q.z())).norm());
      EXPECT_LT(best, 1e-12) << "node " << v;
    }
  }
  // A bad plane is a usage error; --mirror and --mirror-plane exclude each other.
  EXPECT_EQ(atelier::testing::run_cli(args(f, f.dir / "bad.obj", "--mirror-plane 0,0,0,0,0,0")).code, 2);
  EXPECT_EQ(atelier::testing::run_cli(args(f, f.dir / "bad.obj", "--mirror-plane 1,2,x")).code, 2);
  EXPECT_EQ(atelier::testing::run_cli(args(f, f.dir / "bad.obj", "--mirror x --mirror-plane 0,0,0,1,0,0")).code, 2);
  EXPECT_FALSE(fs::exists(f.dir / "bad.obj"));
}

TEST(ExtrudeCli, RecipeReplaysTheDomeOnAnotherCup) {
  // Recorded on the cup, replayed on the cup (the same mesh) and on the cup
  // scaled by 2 about the origin: the dome follows B, so without the
  // optimisation its new nodes lie on the sphere of radius 2.
  const Files f = setup("extrude-cli-recipe");
  const fs::path recipe = f.dir / "dome.recipe.json";
  auto r = atelier::testing::run_cli(args(f, f.dir / "out.obj", "--no-optimise --recipe-out " + recipe.string()));
  ASSERT_EQ(r.code, 0) << r.out;
  ASSERT_TRUE(fs::exists(recipe));
  const Model cup = read_obj(f.mesh), once = read_obj(f.dir / "out.obj");
  Model big = cup;
  for (auto& p : big.nodes.position) p *= 2;
  write_obj(big, f.dir / "big.obj");
  const std::string replay = " --replay " + recipe.string() + " --no-optimise --out ";
  r = atelier::testing::run_cli("extrude --mesh " + f.mesh.string() + replay + (f.dir / "again.obj").string());
  ASSERT_EQ(r.code, 0) << r.out;
  r = atelier::testing::run_cli("extrude --mesh " + (f.dir / "big.obj").string() + replay + (f.dir / "big_out.obj").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const Model again = read_obj(f.dir / "again.obj"), big_out = read_obj(f.dir / "big_out.obj");
  ASSERT_TRUE(validate(again));
  ASSERT_TRUE(validate(big_out));
  ASSERT_EQ(again.num_nodes(), once.num_nodes());
  ASSERT_EQ(big_out.num_nodes(), once.num_nodes());
  for (std::uint32_t v = 0; v < once.nodes.slots.capacity(); ++v) {
    EXPECT_NEAR((again.position(NodeIdx{v}) - once.position(NodeIdx{v})).norm(), 0, 1e-9) << v;
    if (v > 3 * kRing) {
      EXPECT_NEAR(big_out.position(NodeIdx{v}).norm(), 2.0, 1e-6) << v;
    }
  }
  const TopologyCounts t = count_topology(big_out);
  EXPECT_EQ(t.nodes - t.edges + t.faces, 2);
  // Neither or both inputs: usage (2); a bad recipe: exit 3 naming it.
  EXPECT_EQ(atelier::testing::run_cli("extrude --mesh " + f.mesh.string() + " --out " + (f.dir / "x.obj").string()).code, 2);
  {
    std::ofstream bad(f.dir / "bad.json");
    bad << "{\"format\": \"atelier extrusion recipe\"}";
  }
  r = atelier::testing::run_cli("extrude --mesh " + f.mesh.string() + " --replay " + (f.dir / "bad.json").string() +
                                " --out " + (f.dir / "x.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("bad.json"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(f.dir / "x.obj"));
}
