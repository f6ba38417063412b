// `atelier measure` on meshes written here: a box body, whose distances are
// known in closed form, a garment grid over it, and the same pair stretched.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/json_file.h"
#include "tests/support/run_command.h"

using atelier::testing::run_cli;
using atelier::testing::scratch_dir;
namespace fs = std::filesystem;

namespace {

// The box [-ax, ax] x [-1, 1] x [-1, 1] as an OBJ of 6 outward quads.
void write_box(const fs::path& p, double ax) {
  std::ofstream f(p);
  for (int i = 0; i < 8; ++i)
    f << "v " << (i & 1 ? ax : -ax) << ' ' << (i & 2 ? 1 : -1) << ' ' << (i & 4 ? 1 : -1) << '\n';
  f << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
}

// An n x n grid of quads at height z over [-0.5 sx, 0.5 sx] x [-0.5, 0.5].
void write_grid(const fs::path& p, int n, double z, double sx) {
  std::ofstream f(p);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      f << "v " << sx * (-0.5 + i / double(n - 1)) << ' ' << -0.5 + j / double(n - 1) << ' ' << z << '\n';
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i + 1;
      f << "f " << a << ' ' << a + 1 << ' ' << a + n + 1 << ' ' << a + n << '\n';
    }
}

using atelier::testing::read_json;

}  // namespace

TEST(MeasureCli, ClearanceStrainAndExitCodes) {
  const fs::path d = scratch_dir("measure_cli");
  write_box(d / "body.obj", 1.0);
  write_box(d / "wide.obj", 2.0);
  write_grid(d / "design.obj", 5, 1.1, 1.0);  // 0.1 m over the top face
  write_grid(d / "follow.obj", 5, 1.1, 2.0);  // carried by the body's stretch
  write_grid(d / "sunk.obj", 5, 0.7, 1.0);    // 0.3 m inside

  auto r = run_cli("measure --body " + (d / "body.obj").string() + " --garment " + (d / "design.obj").string() +
                   " --json " + (d / "fit.json").string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("25 vertices"), std::string::npos) << r.out;
  auto j = read_json(d / "fit.json");
  EXPECT_EQ(j["inside"], 0);
  EXPECT_NEAR(j["clearance_m"]["min"].get<double>(), 0.1, 1e-12);
  EXPECT_NEAR(j["clearance_m"]["p95"].get<double>(), 0.1, 1e-12);
  EXPECT_FALSE(j.contains("edge_strain_p95"));

  r = run_cli("measure --body " + (d / "wide.obj").string() + " --garment " + (d / "follow.obj").string() +
              " --source-body " + (d / "body.obj").string() + " --source-garment " + (d / "design.obj").string() +
              " --json " + (d / "follow.json").string());
  ASSERT_EQ(r.code, 0) << r.out;
  j = read_json(d / "follow.json");
  EXPECT_NEAR(j["edge_strain_p95"].get<double>(), 1.0, 1e-12);  // x edges doubled
  EXPECT_NEAR(j["excess_edge_strain_p95"].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(j["clearance_change_rms_m"].get<double>(), 0.0, 1e-12);

  // Penetration: exit code 1 and the depth.
  r = run_cli("measure --body " + (d / "body.obj").string() + " --garment " + (d / "sunk.obj").string() + " --json " +
              (d / "sunk.json").string());
  EXPECT_EQ(r.code, 1) << r.out;
  j = read_json(d / "sunk.json");
  EXPECT_EQ(j["inside"], 25);
  EXPECT_NEAR(j["max_depth_m"].get<double>(), 0.3, 1e-12);
}

TEST(MeasureCli, BadInputNamesTheProblem) {
  const fs::path d = scratch_dir("measure_cli_bad");
  write_box(d / "body.obj", 1.0);
  write_grid(d / "g.obj", 4, 1.1, 1.0);
  write_grid(d / "g5.obj", 5, 1.1, 1.0);
  {
    std::ofstream f(d / "open.obj");  // the box without its last face
    for (int i = 0; i < 8; ++i)
      f << "v " << (i & 1 ? 1 : -1) << ' ' << (i & 2 ? 1 : -1) << ' ' << (i & 4 ? 1 : -1) << '\n';
    f << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\n";
    std::ofstream b(d / "broken.obj");
    b << "v 0 0 0\nv 1 0 0\nf 1 2 7\n";
  }
  auto r = run_cli("measure --body " + (d / "missing.obj").string() + " --garment " + (d / "g.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("missing.obj: no such file"), std::string::npos) << r.out;

  r = run_cli("measure --body " + (d / "open.obj").string() + " --garment " + (d / "g.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("body"), std::string::npos) << r.out;

  r = run_cli("measure --body " + (d / "body.obj").string() + " --garment " + (d / "broken.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("broken.obj"), std::string::npos) << r.out;

  r = run_cli("measure --body " + (d / "body.obj").string() + " --garment " + (d / "g.obj").string() +
              " --source-garment " + (d / "g5.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("do not have the same vertices"), std::string::npos) << r.out;

  r = run_cli("measure --garment " + (d / "g.obj").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--body"), std::string::npos) << r.out;
}
