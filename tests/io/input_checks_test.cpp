// Issue 27, "nothing wrong": numbers out of range are errors naming the file
// and line (never read as 0), a UTF-8 byte-order mark is skipped (never
// taken for part of the first statement), and text or bytes with no geometry
// are refused (never an empty mesh that convert would write).
#include <gtest/gtest.h>

#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include "io_test_support.h"

using namespace atelier;
using namespace atelier::test;

namespace {
const std::string kBom = "\xEF\xBB\xBF";
const std::string kTri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
}  // namespace

TEST(InputChecks, ObjNumberBeyondADoubleIsAnErrorNamingFileAndLine) {
  // 1e400 was read as 0: std::from_chars leaves the value untouched when the
  // result is out of range.
  expect_error([] { (void)read_obj_from_string("v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n", "big.obj"); },
               ErrorCode::kParse, {"big.obj", "line 2", "'1e400'", "out of range"});
  expect_error([] { (void)read_obj_from_string("v 0 0 0\nv -1e309 0 0\nv 0 1 0\n", "big.obj"); }, ErrorCode::kParse,
               {"line 2", "'-1e309'", "out of range"});
  expect_error([] { (void)read_obj_from_string(kTri + "vt 0 1e999\n", "vt.obj"); }, ErrorCode::kParse,
               {"vt.obj", "line 5", "out of range", "texture coordinate"});
  expect_error([] { (void)read_obj_from_string(kTri + "f 1 2 99999999999999999999\n", "idx.obj"); },
               ErrorCode::kParse, {"idx.obj", "line 5", "out of range"});
  // Underflow is a real number: it reads as strtod rounds it (0 or subnormal).
  const Model m = read_obj_from_string("v 1e-400 4.9e-324 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "tiny.obj");
  EXPECT_EQ(m.nodes.position[0].x(), 0.0);
  EXPECT_EQ(m.nodes.position[0].y(), std::numeric_limits<double>::denorm_min());
}

TEST(InputChecks, PlyAndOffNumbersBeyondTheirTypeAreErrors) {
  const std::string ply_head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  expect_error([&] { (void)read_ply_from_string(ply_head + "0 0 0\n1e400 0 0\n0 1 0\n3 0 1 2\n", "a.ply"); },
               ErrorCode::kParse, {"a.ply", "line 11", "'1e400'", "out of range"});
  // A float property cannot hold 1e300 (it would become inf).
  expect_error([&] { (void)read_ply_from_string(ply_head + "0 0 0\n1e300 0 0\n0 1 0\n3 0 1 2\n", "f.ply"); },
               ErrorCode::kParse, {"f.ply", "line 11", "does not fit the property type"});
  expect_error([] { (void)read_off_from_string("OFF\n3 1 0\n0 0 0\n1e400 0 0\n0 1 0\n3 0 1 2\n", "a.off"); },
               ErrorCode::kParse, {"a.off", "line 4", "'1e400'", "out of range"});
}

TEST(InputChecks, Utf8ByteOrderMarkIsSkipped) {
  // The mark used to glue onto the first "v", dropping the first vertex and
  // shifting every index by one.
  const Model plain = read_obj_from_string(kTri, "plain.obj");
  const Model bom = read_obj_from_string(kBom + kTri, "bom.obj");
  ASSERT_TRUE(validate(bom));
  EXPECT_EQ(bom.num_nodes(), 3u);
  EXPECT_EQ(bom.num_faces(), 1u);
  EXPECT_EQ(diff_tables(plain, bom), "");
  const std::string off = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(diff_tables(read_off_from_string(off, "a.off"), read_off_from_string(kBom + off, "b.off")), "");
  // A mark elsewhere is not skipped: "\xEF\xBB\xBFv" is an unknown statement,
  // which OBJ readers skip, so the second vertex is not read.
  EXPECT_EQ(read_obj_from_string("v 0 0 0\n" + kBom + "v 1 0 0\n", "mid.obj").num_nodes(), 1u);
}

TEST(InputChecks, TextOrBytesWithNoGeometryAreRefused) {
  expect_error([] { (void)read_obj_from_string("", "empty.obj"); }, ErrorCode::kParse, {"empty.obj", "no vertex"});
  expect_error([] { (void)read_obj_from_string("Dear reader,\nthis is a letter.\n\nRegards\n", "letter.obj"); },
               ErrorCode::kParse, {"letter.obj", "no vertex"});
  std::string random(4096, '\0');
  std::uint32_t x = 12345;
  for (char& c : random) {
    x = x * 1664525u + 1013904223u;
    c = static_cast<char>(x >> 24);
    if (c == '\n' || c == 'v' || c == 'f') c = 'x';  // no statement at all
  }
  expect_error([&] { (void)read_obj_from_string(random, "random.obj"); }, ErrorCode::kParse, {"random.obj", "no vertex"});
  expect_error([] { (void)read_off_from_string("OFF\n0 0 0\n", "empty.off"); }, ErrorCode::kParse,
               {"empty.off", "no vertex"});
  expect_error([] {
    (void)read_ply_from_string("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                               "property float z\nend_header\n",
                               "empty.ply");
  }, ErrorCode::kParse, {"empty.ply", "no vertex"});
  // A point cloud (vertices, no face) is still a model of isolated nodes.
  const Model cloud = read_obj_from_string("v 0 0 0\nv 1 2 3\n", "cloud.obj");
  EXPECT_EQ(cloud.num_nodes(), 2u);
  EXPECT_TRUE(validate(cloud));
}

// Found by the ply fuzz harness (a 10^7-execution run): an element with no
// properties and a count of 3.5e15 made the reader loop that many times over
// nothing (a hang). It holds no data whatever its count: the file reads as
// the same file without it, in ASCII and binary alike.
TEST(InputChecks, PlyElementWithoutPropertiesAndAHugeCountIsNotAHang) {
  const std::string vertex = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string face = "element face 1\nproperty list uchar int vertex_indices\n";
  const std::string empty = "element vex 3555555555555555\n";
  const std::string data = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const Model plain = read_ply_from_string("ply\nformat ascii 1.0\n" + vertex + face + "end_header\n" + data, "a.ply");
  for (const std::string& head : {"ply\nformat ascii 1.0\n" + empty + vertex + face,
                                  "ply\nformat ascii 1.0\n" + vertex + empty + face,
                                  "ply\nformat ascii 1.0\n" + vertex + face + empty}) {
    const Model m = read_ply_from_string(head + "end_header\n" + data, "e.ply");
    EXPECT_EQ(m.nodes.position, plain.nodes.position);
    EXPECT_EQ(m.num_faces(), plain.num_faces());
    EXPECT_TRUE(validate(m));
  }
  std::string bin = "ply\nformat binary_little_endian 1.0\n" + empty + vertex + face + "end_header\n";
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) bin.append(reinterpret_cast<const char*>(&v), 4);
  bin.push_back(3);
  for (std::int32_t i : {0, 1, 2}) bin.append(reinterpret_cast<const char*>(&i), 4);
  const Model b = read_ply_from_string(bin, "b.ply");
  EXPECT_EQ(b.nodes.position, plain.nodes.position);
  EXPECT_EQ(b.num_faces(), plain.num_faces());
}
