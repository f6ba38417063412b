// `atelier flatten` (issue 22) on models written here: a two-piece skirt with
// its side seams (exit 0, files, JSON figures equal to the library's), a
// cap cut in two whose curved seam fails the 0.5% rule (exit 1), and pieces
// that cannot be flattened (exit 3, named).
#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/systems/pattern/flatten.h>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/flatten_shapes.h"
#include "tests/support/json_file.h"
#include "tests/support/run_command.h"

namespace atelier {
namespace {

using testing::run_cli;
using testing::scratch_dir;
namespace fs = std::filesystem;

using atelier::testing::read_json;

TEST(FlattenCli, SkirtPiecesFilesAndFigures) {
  const fs::path d = scratch_dir("flatten_cli");
  flatten_shapes::Skirt k = flatten_shapes::skirt(0.18, 0.27, 0.6, 14, 5);
  write_model(k.model, d / "skirt.atm");
  auto r = run_cli("flatten --mesh " + (d / "skirt.atm").string() + " --out " + (d / "out").string() +
                   " --dxf --notch-spacing 100 --grain 0 0 1 --mirror front --seam-allowance 12 --json " +
                   (d / "out" / "flatten.json").string());
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* f : {"front.svg", "back.svg", "front_mirrored.svg", "pattern.dxf", "front_strain.png",
                        "back_strain.png", "pattern.atm", "flatten.json"})
    EXPECT_TRUE(fs::exists(d / "out" / f)) << f;
  // The figures are the library's on the same model.
  Model m = k.model;
  FlattenOptions fo;
  fo.grain = Vec3d(0, 0, 1);
  auto lib = flatten_surfaces(m, fo);
  ASSERT_TRUE(lib);
  const auto j = read_json(d / "out" / "flatten.json");
  ASSERT_EQ(j["pieces"].size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& p = j["pieces"][i];
    const PieceFlattening& q = lib->pieces[i];
    EXPECT_EQ(p["name"], q.name);
    EXPECT_EQ(p["nodes"].get<std::size_t>(), q.nodes);
    EXPECT_EQ(p["distortion"]["length_error"].get<double>(), q.distortion.length_error);
    EXPECT_EQ(p["distortion"]["area_error"].get<double>(), q.distortion.area_error);
    EXPECT_EQ(p["distortion"]["flipped"].get<std::size_t>(), 0u);
    EXPECT_LT(p["distortion"]["length_error"].get<double>(), 1e-8);  // a cone frustum is developable
    EXPECT_GT(p["notches"].get<std::size_t>(), 4u);
  }
  ASSERT_EQ(j["seams"].size(), 2u);
  for (const auto& s : j["seams"]) {
    EXPECT_TRUE(s["ok"].get<bool>());
    EXPECT_LT(s["max_difference_mm"].get<double>(), 1e-6);
    ASSERT_EQ(s["members"].size(), 2u);
  }
  // The pattern travels with the model: pattern.atm holds it in nodes.uv.
  const Model back = read_model(d / "out" / "pattern.atm");
  ASSERT_EQ(back.nodes.uv.size(), m.nodes.uv.size());
  for (std::size_t v = 0; v < m.nodes.uv.size(); ++v) EXPECT_EQ(back.nodes.uv[v], m.nodes.uv[v]) << v;
}

// A cap split along a curved seam: flattened piece by piece (--free-seams)
// each side takes its own share of the strain and the seam is off its 3D
// length (exit 1, MISMATCH); by default both sides are held to the 3D
// length (FlattenOptions::seam_lengths) and the seam sews.
TEST(FlattenCli, CurvedSeamIsHeldToItsThreeDLengthUnlessFree) {
  const fs::path d = scratch_dir("flatten_cli_cap");
  flatten_shapes::SplitCap sc = flatten_shapes::split_cap(8, M_PI / 4, 0.15);
  write_model(sc.model, d / "cap.atm");
  const std::string args = "flatten --mesh " + (d / "cap.atm").string() + " --out " + (d / "out").string() +
                           " --no-strain-maps --json " + (d / "f.json").string();
  auto r = run_cli(args + " --free-seams");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("MISMATCH"), std::string::npos) << r.out;
  auto j = read_json(d / "f.json");
  ASSERT_EQ(j["seams"].size(), 1u);
  EXPECT_FALSE(j["seams"][0]["ok"].get<bool>());
  EXPECT_GT(j["seams"][0]["max_deviation_3d"].get<double>(), 0.005);
  EXPECT_FALSE(fs::exists(d / "out" / "upper_strain.png"));

  r = run_cli(args);
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("MISMATCH"), std::string::npos) << r.out;
  j = read_json(d / "f.json");
  ASSERT_EQ(j["seams"].size(), 1u);
  EXPECT_TRUE(j["seams"][0]["ok"].get<bool>()) << j.dump();
  EXPECT_LT(j["seams"][0]["max_deviation_3d"].get<double>(), 1e-6) << j.dump();
}

TEST(FlattenCli, PiecesThatCannotBeFlattenedAreNamed) {
  const fs::path d = scratch_dir("flatten_cli_bad");
  {
    std::ofstream f(d / "closed.obj");  // an octahedron in group "body"
    f << "g body\nv 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
         "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
  }
  auto r = run_cli("flatten --mesh " + (d / "closed.obj").string() + " --out " + (d / "out").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("closed.obj"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("surface 'body'"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("closed"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(d / "out" / "body.svg"));
  r = run_cli("flatten --mesh " + (d / "closed.obj").string() + " --out " + (d / "out").string() + " --surface sleeve");
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("no surface named 'sleeve'"), std::string::npos) << r.out;
  r = run_cli("flatten --out " + (d / "out").string());
  EXPECT_EQ(r.code, 2) << r.out;
}

}  // namespace
}  // namespace atelier
