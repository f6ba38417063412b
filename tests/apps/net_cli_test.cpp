// `atelier boolean`, `trim` and `round` (issue 24) on files written here:
// volumes in the JSON report against the analytic ones, exit codes and
// messages for bad input, nothing written on failure.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/json_file.h"
#include "tests/support/run_command.h"

using atelier::testing::run_cli;
using atelier::testing::scratch_dir;
namespace fs = std::filesystem;

namespace {

// The box [lo, hi] as an OBJ of 6 outward quads.
void write_box(const fs::path& p, const double lo[3], const double hi[3]) {
  std::ofstream f(p);
  for (int i = 0; i < 8; ++i)
    f << "v " << (i & 1 ? hi[0] : lo[0]) << ' ' << (i & 2 ? hi[1] : lo[1]) << ' ' << (i & 4 ? hi[2] : lo[2]) << '\n';
  f << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
}

using atelier::testing::read_json;

TEST(NetCli, BooleanVolumesAndReport) {
  const fs::path d = scratch_dir("net_cli_boolean");
  const double a0[3] = {0, 0, 0}, a1[3] = {1, 1, 1}, b0[3] = {.5, .25, -.5}, b1[3] = {1.5, 1.25, .5};
  write_box(d / "a.obj", a0, a1);
  write_box(d / "b.obj", b0, b1);
  const struct {
    const char* op;
    double volume;
  } cases[] = {{"intersection", 0.1875}, {"union", 1.8125}, {"difference", 0.8125}};
  for (const auto& c : cases) {
    const auto r = run_cli("boolean --op " + std::string(c.op) + " " + (d / "a.obj").string() + " " +
                           (d / "b.obj").string() + " --out " + (d / "r.obj").string() + " --json " +
                           (d / "r.json").string() + " --seam-out " + (d / "seam.txt").string());
    ASSERT_EQ(r.code, 0) << r.out;
    const auto j = read_json(d / "r.json");
    EXPECT_NEAR(j["volume"]["result"].get<double>(), c.volume, 1e-12) << c.op;
    EXPECT_EQ(j["intersection_polygons"].get<int>(), 1);
    EXPECT_TRUE(fs::exists(d / "r.obj"));
    const auto v = run_cli("validate " + (d / "r.obj").string());
    EXPECT_EQ(v.code, 0) << v.out;
  }
  // Round off the union's seam.
  ASSERT_EQ(run_cli("boolean --op union " + (d / "a.obj").string() + " " + (d / "b.obj").string() + " --out " +
                    (d / "u.obj").string() + " --seam-out " + (d / "seam.txt").string())
                .code,
            0);
  const auto r = run_cli("round --mesh " + (d / "u.obj").string() + " --seam " + (d / "seam.txt").string() + " --out " +
                         (d / "round.obj").string() + " --json " + (d / "round.json").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = read_json(d / "round.json");
  EXPECT_LE(j["energy"]["after"].get<double>(), j["energy"]["before"].get<double>());
}

// Several B: A minus B1 minus B2 in one command, each net prepared once and
// the first result prepared without a re-check; the volume against the
// analytic one and against two one-call commands, the steps in the report.
TEST(NetCli, BooleanChainOfSeveralOperands) {
  const fs::path d = scratch_dir("net_cli_chain");
  const double a0[3] = {0, 0, 0}, a1[3] = {1, 1, 1}, b0[3] = {.5, .25, -.5}, b1[3] = {1.5, 1.25, .5},
               c0[3] = {-.5, -.5, -.5}, c1[3] = {.3, .2, 1.5};
  write_box(d / "a.obj", a0, a1);
  write_box(d / "b1.obj", b0, b1);
  write_box(d / "b2.obj", c0, c1);
  const std::string a = (d / "a.obj").string(), b1s = (d / "b1.obj").string(), b2s = (d / "b2.obj").string();
  auto r = run_cli("boolean --op difference " + a + " " + b1s + " " + b2s + " --out " + (d / "chain.obj").string() +
                   " --json " + (d / "chain.json").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = read_json(d / "chain.json");
  // 1 - 0.1875 (B1) - 0.06 (B2: [0, .3] x [0, .2] x [0, 1] of A, apart from B1)
  EXPECT_NEAR(j["volume"]["result"].get<double>(), 0.7525, 1e-12);
  ASSERT_EQ(j["steps"].size(), 2u);
  EXPECT_NEAR(j["steps"][0]["volume"].get<double>(), 0.8125, 1e-12);
  EXPECT_EQ(j["steps"][1]["b"].get<std::string>(), b2s);
  EXPECT_EQ(run_cli("validate " + (d / "chain.obj").string()).code, 0);
  // The same two steps as one-call commands.
  ASSERT_EQ(run_cli("boolean --op difference " + a + " " + b1s + " --out " + (d / "s1.obj").string()).code, 0);
  ASSERT_EQ(run_cli("boolean --op difference " + (d / "s1.obj").string() + " " + b2s + " --out " +
                    (d / "s2.obj").string() + " --json " + (d / "s2.json").string())
                .code,
            0);
  EXPECT_NEAR(read_json(d / "s2.json")["volume"]["result"].get<double>(), j["volume"]["result"].get<double>(), 1e-14);
  // A bad operand later in the chain is named, and nothing is written.
  {
    std::ofstream f(d / "open.obj");
    for (int i = 0; i < 8; ++i) f << "v " << (i & 1) << ' ' << (i >> 1 & 1) << ' ' << (i >> 2 & 1) << '\n';
    f << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\n";
  }
  r = run_cli("boolean --op difference " + a + " " + b1s + " " + (d / "open.obj").string() + " --out " +
              (d / "bad.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("open.obj"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(d / "bad.obj"));
}

TEST(NetCli, BadInputIsRefusedAndNothingIsWritten) {
  const fs::path d = scratch_dir("net_cli_bad");
  const double a0[3] = {0, 0, 0}, a1[3] = {1, 1, 1};
  write_box(d / "a.obj", a0, a1);
  {  // open box: one face missing
    std::ofstream f(d / "open.obj");
    for (int i = 0; i < 8; ++i) f << "v " << (i & 1) << ' ' << (i >> 1 & 1) << ' ' << (i >> 2 & 1) << '\n';
    f << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\n";
  }
  auto r = run_cli("boolean --op union " + (d / "a.obj").string() + " " + (d / "open.obj").string() + " --out " +
                   (d / "out.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("open.obj"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("face"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(d / "out.obj"));
  r = run_cli("boolean --op xor " + (d / "a.obj").string() + " " + (d / "a.obj").string() + " --out " +
              (d / "out.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("xor"), std::string::npos);
  r = run_cli("boolean " + (d / "a.obj").string() + " " + (d / "missing.obj").string() + " --out " +
              (d / "out.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  r = run_cli("boolean " + (d / "a.obj").string());
  EXPECT_EQ(r.code, 2) << r.out;
  {  // malformed curve and seam files name file and line
    std::ofstream(d / "curve.txt") << "0 0 0\n1 0 zero\n";
    std::ofstream(d / "seam.txt") << "0 1\n2 -4\n";
  }
  r = run_cli("trim --mesh " + (d / "a.obj").string() + " --curve " + (d / "curve.txt").string() + " --out " +
              (d / "out.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("curve.txt"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("line 2"), std::string::npos) << r.out;
  r = run_cli("round --mesh " + (d / "a.obj").string() + " --seam " + (d / "seam.txt").string() + " --out " +
              (d / "out.obj").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("seam.txt"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(d / "out.obj"));
}

TEST(NetCli, TrimRemovesTheEnclosedPart) {
  const fs::path d = scratch_dir("net_cli_trim");
  {  // a 4 x 4 quad plane over [-2, 2]^2 and a square curve of side 1 on it
    std::ofstream f(d / "plane.obj");
    for (int j = 0; j <= 4; ++j)
      for (int i = 0; i <= 4; ++i) f << "v " << -2 + i << ' ' << -2 + j << " 0\n";
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        const int a = j * 5 + i + 1;
        f << "f " << a << ' ' << a + 1 << ' ' << a + 6 << ' ' << a + 5 << '\n';
      }
    std::ofstream(d / "curve.txt") << "# a square\n-0.3 -0.4 0\n0.7 -0.4 0\n0.7 0.6 0\n-0.3 0.6 0\n";
  }
  const auto r = run_cli("trim --mesh " + (d / "plane.obj").string() + " --curve " + (d / "curve.txt").string() +
                         " --out " + (d / "t.obj").string() + " --json " + (d / "t.json").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = read_json(d / "t.json");
  EXPECT_NEAR(j["area"]["before"].get<double>() - j["area"]["after"].get<double>(), 1.0, 1e-12);
}

}  // namespace
