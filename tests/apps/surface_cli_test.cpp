// `atelier surface` (issue 23): a curve network written here (a grid of
// crossing curves, in both the CURVE i and OBJ l formats) becomes an OBJ
// surface, a control mesh and a JSON report; bad input exits 3 naming the
// curve, usage errors exit 2.
#include <atelier/io/obj.h>
#include <atelier/storage/validate.h>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/json_file.h"
#include "tests/support/run_command.h"

using atelier::testing::run_cli;
using atelier::testing::scratch_dir;
namespace fs = std::filesystem;

namespace {

/// 4 curves along x and 3 along y crossing in a 3 x 2 grid of unit cells,
/// each running 0.25 past its last crossing; z a gentle bump.
void write_grid_curves(const fs::path& p, bool obj) {
  std::ofstream f(p);
  auto z = [](double x, double y) { return 0.2 * std::sin(x) * std::cos(y); };
  int id = 0, v = 0;
  std::vector<std::vector<int>> lines;
  auto curve = [&](auto&& at, double t0, double t1, int n) {
    if (!obj) f << "CURVE " << 3 * id++ << '\n';
    std::vector<int> l;
    for (int k = 0; k <= n; ++k) {
      const auto [x, y] = at(t0 + (t1 - t0) * k / n);
      f << (obj ? "v " : "") << x << ' ' << y << ' ' << z(x, y) << '\n';
      l.push_back(++v);
    }
    lines.push_back(l);
  };
  // Stations at multiples of 1/8 so that crossings are sample points of both curves.
  for (int j = 0; j <= 2; ++j) curve([&](double t) { return std::pair{t, double(j)}; }, -0.25, 3.25, 28);
  for (int i = 0; i <= 3; ++i) curve([&](double t) { return std::pair{double(i), t}; }, -0.25, 2.25, 20);
  if (obj)
    for (const auto& l : lines) {
      f << 'l';
      for (int k : l) f << ' ' << k;
      f << '\n';
    }
}

using atelier::testing::read_json;

}  // namespace

TEST(SurfaceCli, CurvesToSurfaceControlMeshAndReport) {
  const fs::path d = scratch_dir("surface_cli");
  for (bool obj : {false, true}) {
    const fs::path curves = d / (obj ? "grid.obj" : "grid.txt");
    write_grid_curves(curves, obj);
    const auto r = run_cli("surface --curves " + curves.string() + " --levels 2 --out " + (d / "s.obj").string() +
                           " --control " + (d / "c.obj").string() + " --json " + (d / "r.json").string());
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("pruned 14 dangling curve ends"), std::string::npos) << r.out;
    const nlohmann::json j = read_json(d / "r.json");
    EXPECT_EQ(j["curves"]["input"], 7);
    EXPECT_EQ(j["curves"]["intersections"], 12);
    EXPECT_EQ(j["curves"]["pruned_ends"], 14);
    EXPECT_EQ(j["cycles"]["faces"], 6);
    EXPECT_EQ(j["cycles"]["by_size"]["4"], 6);
    EXPECT_EQ(j["cycles"]["euler"], 1);
    EXPECT_LE(j["fairing"]["energy_after"].get<double>(), j["fairing"]["energy_before"].get<double>());
    EXPECT_LT(j["distance_to_curves"]["relative_max"].get<double>(), 2e-3);
    EXPECT_EQ(j["subdivision"]["per_level"].size(), 3u);
    const auto quads = j["control_mesh"]["quads"].get<std::size_t>();
    // The surface file is the last level: 16 quads per control quad.
    const atelier::Model s = atelier::read_obj(d / "s.obj");
    EXPECT_TRUE(atelier::validate(s)) << atelier::validate(s).to_string();
    EXPECT_EQ(s.num_faces(), 16 * quads);
    const atelier::Model c = atelier::read_obj(d / "c.obj");
    EXPECT_EQ(c.num_faces(), quads);
  }
}

TEST(SurfaceCli, BadInputAndUsage) {
  const fs::path d = scratch_dir("surface_cli_bad");
  {
    std::ofstream f(d / "one.txt");
    f << "CURVE 0\n0 0 0\n1 0 0\nCURVE 17\n2 2 2\n";
  }
  auto r = run_cli("surface --curves " + (d / "one.txt").string() + " --levels 1 --out " + (d / "x.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("CURVE 17"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("line 4"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(d / "x.obj"));
  {
    std::ofstream f(d / "open.txt");  // two crossing lines: nothing but dangling ends
    f << "CURVE 0\n-1 0 0\n1 0 0\nCURVE 1\n0 -1 0\n0 1 0\n";
  }
  r = run_cli("surface --curves " + (d / "open.txt").string() + " --levels 1 --out " + (d / "x.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("no cycle"), std::string::npos) << r.out;
  r = run_cli("surface --curves " + (d / "missing.txt").string() + " --levels 1 --out " + (d / "x.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  r = run_cli("surface --curves " + (d / "open.txt").string() + " --levels 1");
  EXPECT_EQ(r.code, 2) << r.out;
  r = run_cli("surface --curves " + (d / "open.txt").string() + " --out " + (d / "x.obj").string());
  EXPECT_EQ(r.code, 2) << r.out;  // --levels is required
  r = run_cli("surface --curves " + (d / "open.txt").string() + " --levels 1 --out " + (d / "x.ply").string());
  EXPECT_EQ(r.code, 2) << r.out;
  r = run_cli("surface --curves " + (d / "open.txt").string() + " --out " + (d / "x.obj").string() + " --levels 9");
  EXPECT_EQ(r.code, 2) << r.out;
}

TEST(SurfaceCli, SharedNetworkWithTracedMesh) {
  const fs::path data = fs::path(ATELIER_SHARED_DATA) / "curve-networks";
  if (!fs::exists(data / "hill_3.txt")) GTEST_SKIP() << "shared curve networks not found";
  const fs::path d = scratch_dir("surface_cli_hill");
  const auto r =
      run_cli("surface --curves " + (data / "hill_3.txt").string() + " --mesh " + (data / "hill.obj").string() +
              " --levels 2 --out " + (d / "hill.obj").string() + " --json " + (d / "hill.json").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const nlohmann::json j = read_json(d / "hill.json");
  EXPECT_EQ(j["curves"]["boundary_curves_added"], 1);
  EXPECT_EQ(j["cycles"]["faces"], 6);
  EXPECT_TRUE(j.contains("distance_to_traced"));
  EXPECT_LT(j["distance_to_curves"]["relative_max"].get<double>(), 2e-3);
}
