// Curve-network files: the `CURVE i` format and OBJ `l` polylines (issue 23):
// what is read, exact round trips, and a clean error naming the file, line
// and curve for every kind of malformed input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "io_test_support.h"
#include <atelier/io/curve_network.h>
#include <atelier/io/obj.h>

using namespace atelier;
using namespace atelier::test;

namespace {

std::string parse_error_of(std::string_view text) {
  auto r = parse_curve_network(text, "net.txt");
  EXPECT_FALSE(r) << "accepted: " << text;
  if (r) return {};
  EXPECT_EQ(r.status().code(), ErrorCode::kParse);
  return r.status().message();
}

void write_text(const std::filesystem::path& p, const std::string& s) {
  std::ofstream f(p, std::ios::binary);
  f << s;
}

}  // namespace

TEST(CurveNetworkFile, ReadsCurvesWithGapsCommentsAndLineEndings) {
  const std::string text =
      "# a network\r\nCURVE 3\r\n0 0 0\r\n1 0 0\t\r\n\r\n2 0.5 -1e-3 # a comment\nCURVE 10\n0 1 0\n  +1 1 0\nCURVE "
      "-2\n5 5 5\n6 6 6\n";
  auto r = parse_curve_network(text, "net.txt");
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_EQ(r->size(), 3u);
  EXPECT_EQ(r->ids, (std::vector<std::int64_t>{3, 10, -2}));
  EXPECT_EQ(r->lines, (std::vector<std::uint64_t>{2, 7, 10}));
  ASSERT_EQ(r->curve(0).size(), 3u);
  EXPECT_EQ(r->curve(0)[2], Vec3d(2, 0.5, -1e-3));
  EXPECT_EQ(r->curve(1)[1], Vec3d(1, 1, 0));
  EXPECT_EQ(r->curve(2).size(), 2u);
  EXPECT_EQ(r->describe(1), "CURVE 10 (net.txt: line 7)");
}

TEST(CurveNetworkFile, MalformedInputIsRefusedNamingLineAndCurve) {
  EXPECT_NE(parse_error_of("0 0 0\nCURVE 1\n0 0 0\n1 1 1\n").find("line 1: a point before the first"),
            std::string::npos);
  EXPECT_NE(parse_error_of("CURVE 1\n0 0 0\n1 x 1\n").find("line 3: CURVE 1: non-numeric token 'x'"),
            std::string::npos);
  EXPECT_NE(parse_error_of("CURVE 4\n0 0 0\n1 nan 1\n").find("line 3: CURVE 4: NaN/inf"), std::string::npos);
  EXPECT_NE(parse_error_of("CURVE 4\n0 0 0\n1 inf 1\n").find("NaN/inf"), std::string::npos);
  EXPECT_NE(parse_error_of("CURVE 4\n0 0 0\n1 1\n").find("line 3: CURVE 4: a point has 2 values"), std::string::npos);
  EXPECT_NE(parse_error_of("CURVE 4\n0 0 0\n1 1 1 1\n").find("has 4 values"), std::string::npos);
  EXPECT_NE(parse_error_of("CURVE 7\n0 0 0\nCURVE 8\n0 0 0\n1 1 1\n").find("CURVE 7 (net.txt: line 1) has 1 point"),
            std::string::npos);
  EXPECT_NE(parse_error_of("CURVE 7\n0 0 0\n1 1 1\nCURVE 8\n").find("CURVE 8 (net.txt: line 4) has 0 points"),
            std::string::npos);
  EXPECT_NE(
      parse_error_of("CURVE 7\n0 0 0\n1 1 1\nCURVE 7\n0 0 0\n2 2 2\n").find("line 4: CURVE 7 repeats the id of line 1"),
      std::string::npos);
  EXPECT_NE(parse_error_of("CURVE x\n0 0 0\n1 1 1\n").find("curve id 'x' is not an integer"), std::string::npos);
  EXPECT_NE(parse_error_of("CURVE\n0 0 0\n1 1 1\n").find("`CURVE <integer id>`"), std::string::npos);
  EXPECT_NE(parse_error_of("CURVE 99999999999999999999\n0 0 0\n1 1 1\n").find("not an integer"), std::string::npos);
  EXPECT_NE(parse_error_of("").find("no curve"), std::string::npos);
  EXPECT_NE(parse_error_of("# nothing\n\n").find("no curve"), std::string::npos);
  EXPECT_NE(parse_error_of(std::string("CURVE 1\n0 0 0\n1 1 \0 1\n", 22)).find("line 3"), std::string::npos);
}

TEST(CurveNetworkFile, ArbitraryBytesNeverCrash) {
  // Fuzz-style: truncations and byte flips of a valid file are either read
  // or refused with kParse, never anything else.
  const std::string good = "CURVE 1\n0 0 0\n1 2 3\n4 5 6\nCURVE 2\n-1 -2 -3e10\n7 8 9\n";
  std::uint64_t seed = 12345;
  for (int trial = 0; trial < 2000; ++trial) {
    std::string t = good;
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    const std::size_t cut = (seed >> 33) % (good.size() + 1);
    if (trial % 2)
      t.resize(cut);
    else
      t[cut % t.size()] = static_cast<char>(seed >> 56);
    auto r = parse_curve_network(t, "fuzz");
    if (!r)
      EXPECT_EQ(r.status().code(), ErrorCode::kParse) << r.status().to_string();
    else
      for (std::size_t c = 0; c < r->size(); ++c) EXPECT_GE(r->curve(c).size(), 2u);
  }
}

TEST(CurveNetworkFile, WriteReadRoundTripIsExact) {
  TempDir dir;
  PolylineSet s;
  const Vec3d a[] = {{0.1, 1.0 / 3.0, -2.5e-300}, {1e300, -0.0, 7}};
  const Vec3d b[] = {{std::nextafter(1.0, 2.0), 2, 3}, {4, 5, 6}, {7, 8, 9.000000000000002}};
  s.add(5, a);
  s.add(-1, b);
  write_curve_network(s, dir.path() / "n.txt");
  const PolylineSet r = read_curve_network(dir.path() / "n.txt");
  EXPECT_EQ(r.points, s.points);
  EXPECT_EQ(r.offsets, s.offsets);
  EXPECT_EQ(r.ids, s.ids);
  // Non-finite points and 1-point curves are refused before anything is written.
  PolylineSet bad = s;
  bad.points[1].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(write_curve_network(bad, dir.path() / "bad.txt"), Error);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "bad.txt"));
}

TEST(CurveNetworkFile, ObjPolylinesReadAndWrite) {
  TempDir dir;
  write_text(dir.path() / "l.obj",
             "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1 2 3\nl 1 2 3\nl -1 -4/1 \\\n 2\n# comment\n");
  const PolylineSet p = read_obj_polylines(dir.path() / "l.obj");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p.curve(0).size(), 3u);
  EXPECT_EQ(p.curve(1)[0], Vec3d(0, 1, 0));
  EXPECT_EQ(p.curve(1)[1], Vec3d(0, 0, 0));
  EXPECT_EQ(p.curve(1)[2], Vec3d(1, 0, 0));
  EXPECT_EQ(p.lines, (std::vector<std::uint64_t>{7, 8}));
  // read_curve_network dispatches on the extension.
  EXPECT_EQ(read_curve_network(dir.path() / "l.obj").points, p.points);
  // The mesh reader still skips `l` (its faces are unchanged).
  const Model m = read_obj(dir.path() / "l.obj");
  EXPECT_EQ(m.num_faces(), 1u);
  // Round trip through write_obj_polylines.
  write_obj_polylines(p, dir.path() / "out.obj");
  const PolylineSet q = read_obj_polylines(dir.path() / "out.obj");
  EXPECT_EQ(q.points, p.points);
  EXPECT_EQ(q.offsets, p.offsets);
}

TEST(CurveNetworkFile, MalformedObjPolylinesAreRefused) {
  auto err = [](const std::string& text) -> std::string {
    try {
      (void)read_obj_polylines_from_string(text, "l.obj");
    } catch (const Error& e) {
      EXPECT_EQ(e.status().code(), ErrorCode::kParse);
      return e.what();
    }
    ADD_FAILURE() << "accepted: " << text;
    return {};
  };
  EXPECT_NE(err("v 0 0 0\nv 1 1 1\nl 1\n").find("line 3: polyline has 1 vertices"), std::string::npos);
  EXPECT_NE(err("v 0 0 0\nv 1 1 1\nl 1 3\n").find("line 3: bad index: vertex index 3 out of range"), std::string::npos);
  EXPECT_NE(err("v 0 0 0\nv 1 1 1\nl 1 0\n").find("index 0"), std::string::npos);
  EXPECT_NE(err("v 0 0 0\nv 1 1 1\nl 1 a\n").find("non-numeric token 'a' in polyline"), std::string::npos);
  EXPECT_NE(err("v 0 0 0\nv 1 1 1\nl 1 -5\n").find("refers before the first"), std::string::npos);
  EXPECT_NE(err("v 0 0 0\nv 1 1 1\nf 1 2 1\n").find("no polyline"), std::string::npos);
  EXPECT_NE(err("v 0 nan 0\nv 1 1 1\nl 1 2\n").find("NaN"), std::string::npos);
}

TEST(CurveNetworkFile, SharedNetworksParse) {
  const std::filesystem::path dir = std::filesystem::path(ATELIER_SHARED_DATA) / "curve-networks";
  if (!std::filesystem::exists(dir / "shell_100.txt")) GTEST_SKIP() << "shared data not found: " << dir;
  const PolylineSet shell = read_curve_network(dir / "shell_100.txt");
  EXPECT_EQ(shell.size(), 60u);  // numbered 0..99 with gaps
  EXPECT_EQ(shell.ids.front(), 0);
  EXPECT_EQ(read_curve_network(dir / "roof_75.txt").size(), 75u);
  EXPECT_EQ(read_curve_network(dir / "kagome_114_regular.txt").size(), 114u);
}
