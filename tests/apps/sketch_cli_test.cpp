// `atelier sketch` on good and bad inputs (runs the built binary).
#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/view/strokes.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "support/run_command.h"
#include "support/shapes.h"

namespace fs = std::filesystem;
using namespace atelier;

namespace {

using Run = atelier::testing::CommandResult;
using atelier::testing::run_cli;

struct SketchFiles {
  fs::path dir, mesh, strokes;
};

Stroke stroke(StrokeTool t, const Camera& cam, std::vector<Vec3d> pts, bool through = false) {
  Stroke s;
  s.tool = t;
  s.through = through || t == StrokeTool::kPaintThrough;
  for (const Vec3d& p : pts) s.points.push_back(cam.project(p).head<2>());
  return s;
}

SketchFiles sketch_setup(const std::string& name, bool fold = false) {
  SketchFiles f;
  f.dir = atelier::testing::scratch_dir(name);
  f.mesh = f.dir / "sphere.obj";
  Model m;
  (void)add_polygon_surface(m, "sphere", shapes::uv_sphere(32, 16).arrays()).value();
  write_obj(m, f.mesh);
  StrokeFile s;
  s.camera = Camera::orthographic(Vec3d(0, 0, 5), Vec3d::Zero(), Vec3d::UnitY(), 1.5, 800, 800);
  const Camera& c = s.camera;
  s.strokes.push_back(stroke(StrokeTool::kPaint, c, {Vec3d(-0.5, 0.6, 0), Vec3d(0.5, 0.62, 0)}));
  s.strokes.push_back(stroke(StrokeTool::kCut, c, {Vec3d(-1.4, -0.5, 0), Vec3d(1.4, -0.45, 0)}, true));
  s.strokes.push_back(stroke(StrokeTool::kPick, c, {Vec3d(0, -0.8, 0)}));
  std::vector<Vec3d> ring;
  for (int k = 0; k <= 24; ++k)
    ring.push_back(Vec3d(0.25 * std::cos(2 * M_PI * k / 24), 0.25 * std::sin(2 * M_PI * k / 24), 0));
  ring.back() = ring.front();
  s.strokes.push_back(stroke(StrokeTool::kPartition, c, ring));
  if (fold) s.strokes.insert(s.strokes.begin(), stroke(StrokeTool::kCut, c, {Vec3d(-1.4, 0.2, 0), Vec3d(1.4, 0.2, 0)}));
  f.strokes = f.dir / "strokes.json";
  EXPECT_TRUE(write_strokes(s, f.strokes));
  return f;
}

std::string sketch_args(const SketchFiles& f, const fs::path& out, const std::string& extra = "") {
  return "sketch --mesh " + f.mesh.string() + " --strokes " + f.strokes.string() + " --out " + out.string() + " " +
         extra;
}

}  // namespace

TEST(SketchCli, PaintsCutsAndPartitionsIntoGroups) {
  const SketchFiles f = sketch_setup("sketch-cli-ok");
  auto r = run_cli(sketch_args(f, f.dir / "out.obj", "--json " + (f.dir / "report.json").string()));
  ASSERT_EQ(r.code, 0) << r.out;
  // Pieces become OBJ groups.
  const Model m = read_obj(f.dir / "out.obj");
  EXPECT_EQ(m.num_surfaces(), 2u);
  std::ifstream in(f.dir / "out.obj");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(text.find("g sphere\n"), std::string::npos);
  EXPECT_NE(text.find("g sphere.1\n"), std::string::npos);
  // The report: what each tool did.
  const auto j = nlohmann::json::parse(std::ifstream(f.dir / "report.json"));
  EXPECT_TRUE(j["ok"].get<bool>());
  ASSERT_EQ(j["tools"].size(), 3u);
  EXPECT_EQ(j["tools"][0]["tool"], "paint");
  EXPECT_GT(j["tools"][0]["curves"][0]["length"].get<double>(), 0.9);
  EXPECT_EQ(j["tools"][0]["polylines"].size(), 1u);
  EXPECT_EQ(j["tools"][1]["tool"], "cut");
  EXPECT_EQ(j["tools"][1]["pieces"].size(), 2u);
  EXPECT_GT(j["tools"][1]["removed_area"].get<double>(), 0.0);
  EXPECT_GT(j["tools"][1]["faces_added"].get<int>(), 0);
  EXPECT_EQ(j["tools"][2]["pieces"].size(), 2u);
  EXPECT_TRUE(j["tools"][2]["curves"][0]["closed"].get<bool>());
  // The native format keeps the painted curves and the joint.
  auto a = run_cli(sketch_args(f, f.dir / "out.atm"));
  ASSERT_EQ(a.code, 0) << a.out;
  const Model n = read_model(f.dir / "out.atm");
  EXPECT_TRUE(validate(n));
  EXPECT_EQ(n.num_joints(), 1u);
  EXPECT_GE(n.num_attrib_edges(), 3u);
}

TEST(SketchCli, BadStrokeFilesNameTheFileAndTheJsonLocation) {
  const SketchFiles f = sketch_setup("sketch-cli-bad-strokes");
  const fs::path out = f.dir / "out.obj";
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(f.dir / name) << text;
    return f.dir / name;
  };
  const std::string cam =
      R"("camera": {"view": [1,0,0,0, 0,1,0,0, 0,0,1,-5, 0,0,0,1], "projection": [1,0,0,0, 0,1,0,0, 0,0,-0.1,0, 0,0,0,1], "viewport": [800, 800]})";
  struct Case {
    std::string name, text, expect;
  };
  const Case cases[] = {
      {"nan.json", "{" + cam + R"(, "strokes": [{"points": [[1, NaN], [3, 4]], "tool": "paint"}]})", "non-finite"},
      {"missing.json", "{" + cam + R"(, "strokes": [{"tool": "paint"}]})", "at /strokes/0: missing key \"points\""},
      {"one.json", "{" + cam + R"(, "strokes": [{"points": [[1, 2]], "tool": "cut"}]})", "/strokes/0/points"},
      {"singular.json",
       R"({"camera": {"view": [1,0,0,0, 0,1,0,0, 0,0,1,-5, 0,0,0,1], "projection": [0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,0], "viewport": [8, 8]}, "strokes": []})",
       "singular"},
      {"syntax.json", "{\n  \"camera\": [}", "syntax.json:2:"},
  };
  for (const Case& c : cases) {
    const fs::path p = write(c.name, c.text);
    auto r = run_cli("sketch --mesh " + f.mesh.string() + " --strokes " + p.string() + " --out " + out.string());
    EXPECT_EQ(r.code, 3) << c.name << ": " << r.out;
    EXPECT_NE(r.out.find(p.string()), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.name << ": " << r.out;
    EXPECT_FALSE(fs::exists(out));
  }
  auto missing = run_cli("sketch --mesh " + f.mesh.string() + " --strokes " + (f.dir / "nope.json").string() +
                         " --out " + out.string());
  EXPECT_EQ(missing.code, 3) << missing.out;
  EXPECT_NE(missing.out.find("nope.json"), std::string::npos);
}

TEST(SketchCli, BadMeshesAndOptions) {
  const SketchFiles f = sketch_setup("sketch-cli-bad-mesh");
  const fs::path out = f.dir / "out.obj";
  for (const char* bad : {"obj_nonmanifold_edge.obj", "obj_nan_coordinate.obj", "ply_ascii_truncated.ply"}) {
    const fs::path p = fs::path(ATELIER_TEST_DATA) / "malformed" / bad;
    auto r = run_cli("sketch --mesh " + p.string() + " --strokes " + f.strokes.string() + " --out " + out.string());
    EXPECT_EQ(r.code, 3) << bad << ": " << r.out;
    EXPECT_NE(r.out.find(bad), std::string::npos) << r.out;
  }
  auto nomesh = run_cli("sketch --mesh " + (f.dir / "none.obj").string() + " --strokes " + f.strokes.string() +
                        " --out " + out.string());
  EXPECT_EQ(nomesh.code, 3);
  EXPECT_NE(nomesh.out.find("none.obj"), std::string::npos);
  EXPECT_EQ(run_cli(sketch_args(f, f.dir / "out.xyz")).code, 3);
  auto surf = run_cli(sketch_args(f, out, "--surface collar"));
  EXPECT_EQ(surf.code, 3);
  EXPECT_NE(surf.out.find("no surface named 'collar'"), std::string::npos);
  EXPECT_EQ(run_cli("sketch --mesh " + f.mesh.string()).code, 2);  // usage
  EXPECT_FALSE(fs::exists(out));
}

TEST(SketchCli, AFailingStrokeStopsOrIsSkipped) {
  // A visible-only cut of a closed sphere separates nothing.
  const SketchFiles f = sketch_setup("sketch-cli-fail", true);
  const fs::path out = f.dir / "out.obj";
  auto r = run_cli(sketch_args(f, out, "--json " + (f.dir / "r.json").string()));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("stroke 0 (cut)"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(out));
  const auto j = nlohmann::json::parse(std::ifstream(f.dir / "r.json"));
  EXPECT_FALSE(j["ok"].get<bool>());
  auto k = run_cli(sketch_args(f, out, "--keep-going --json " + (f.dir / "k.json").string()));
  EXPECT_EQ(k.code, 1) << k.out;
  EXPECT_TRUE(fs::exists(out));
  const auto jk = nlohmann::json::parse(std::ifstream(f.dir / "k.json"));
  EXPECT_EQ(jk["failed"], 1);
  EXPECT_FALSE(jk["tools"][0]["ok"].get<bool>());
  EXPECT_TRUE(jk["tools"][1]["ok"].get<bool>());
}
