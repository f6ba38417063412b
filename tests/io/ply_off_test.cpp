#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include <atelier/storage/topology.h>
#include <gtest/gtest.h>

#include <bit>
#include <cstring>

#include "io_test_support.h"

using namespace atelier;
using namespace atelier::test;

namespace {

const std::filesystem::path kGoodDir = std::filesystem::path(ATELIER_TEST_DATA) / "good";

/// Big- or little-endian bytes of a scalar, built without the reader's code.
template <class T>
std::string bytes_of(T v, bool big) {
  std::string s(sizeof(T), '\0');
  std::memcpy(s.data(), &v, sizeof(T));
  if (big == (std::endian::native == std::endian::little)) std::reverse(s.begin(), s.end());
  return s;
}

/// The cube as a binary PLY with distracting properties of every scalar
/// type before, between and after x/y/z, a list property to skip, an extra
/// element, and face indices as ushort with an int count.
std::string exotic_cube_ply(bool big) {
  const Soup c = cube();
  std::string s = "ply\r\nformat ";
  s += big ? "binary_big_endian" : "binary_little_endian";
  s += " 1.0\r\ncomment mixed types\r\nobj_info nothing\r\n"
       "element vertex 8\r\n"
       "property char a\r\nproperty double x\r\nproperty uchar b\r\nproperty float y\r\nproperty short c\r\n"
       "property double z\r\nproperty ushort d\r\nproperty int e\r\nproperty uint f\r\nproperty float64 g\r\n"
       "property list uint8 float32 junk\r\n"
       "element material 2\r\nproperty int16 id\r\n"
       "element face 6\r\nproperty uint32 tag\r\nproperty list int ushort vertex_index\r\nproperty list uchar double "
       "more\r\n"
       "end_header\n";
  for (const Vec3d& p : c.positions) {
    s += bytes_of<std::int8_t>(-3, big) + bytes_of<double>(p.x(), big) + bytes_of<std::uint8_t>(200, big) +
         bytes_of<float>(static_cast<float>(p.y()), big) + bytes_of<std::int16_t>(-300, big) +
         bytes_of<double>(p.z(), big) + bytes_of<std::uint16_t>(60000, big) + bytes_of<std::int32_t>(-7, big) +
         bytes_of<std::uint32_t>(7, big) + bytes_of<double>(1e300, big) + bytes_of<std::uint8_t>(2, big) +
         bytes_of<float>(1.5f, big) + bytes_of<float>(2.5f, big);
  }
  s += bytes_of<std::int16_t>(1, big) + bytes_of<std::int16_t>(2, big);
  for (std::size_t f = 0; f + 1 < c.offsets.size(); ++f) {
    s += bytes_of<std::uint32_t>(99, big);
    s += bytes_of<std::int32_t>(static_cast<std::int32_t>(c.offsets[f + 1] - c.offsets[f]), big);
    for (std::uint32_t k = c.offsets[f]; k < c.offsets[f + 1]; ++k)
      s += bytes_of<std::uint16_t>(static_cast<std::uint16_t>(c.nodes[k]), big);
    s += bytes_of<std::uint8_t>(1, big) + bytes_of<double>(0.25, big);
  }
  return s;
}

void expect_is_cube(const Model& m) {
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_EQ(face_positions(m), face_positions(model_of(cube(), "x")));
  const auto c = count_topology(m);
  EXPECT_EQ(c.nodes - c.edges + c.faces, 2);
  EXPECT_EQ(c.shells, 1);
}

}  // namespace

TEST(Ply, BinaryAndAsciiRoundTripsAreExact) {
  const Soup s = jittered_grid(6, 4, 3);
  const Model m = model_of(s, "grid");  // the reader names the surface after the file stem
  TempDir dir;
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    write_ply(m, dir / "grid.ply", binary);
    const Model back = read_ply(dir / "grid.ply");
    EXPECT_EQ(diff_tables(m, back), "");
    const std::string bytes = slurp(dir / "grid.ply");
    EXPECT_NE(bytes.find(binary ? "binary_little_endian" : "format ascii"), std::string::npos);
  }
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"grid.ply"});
}

TEST(Ply, KeepsSurfacesAsAFacePropertyAndIsolatedNodes) {
  // Issue 27: a multi-surface model was merged into one surface.
  Model m = model_of(cube(), "a");
  const Soup g = jittered_grid(2, 2, 9);
  ASSERT_TRUE(add_polygon_surface(m, "b with spaces", g.arrays()));
  const NodeIdx iso = m.new_node(SurfaceIdx{0}, Vec3d(5, 6, 7));
  m.complex_holes = count_topology(m).implied_holes();
  ASSERT_TRUE(validate(m));
  TempDir dir;
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    write_ply(m, dir / "two.ply", binary);
    const Model back = read_ply(dir / "two.ply");
    ASSERT_TRUE(validate(back)) << validate(back).to_string();
    ASSERT_EQ(back.num_surfaces(), 2u);
    EXPECT_EQ(back.surfaces.name[0], "a");
    EXPECT_EQ(back.surfaces.name[1], "b with spaces");
    EXPECT_EQ(back.num_nodes(), m.num_nodes());
    EXPECT_EQ(face_positions(back), face_positions(m));
    for (std::uint32_t f = 0; f < back.faces.slots.capacity(); ++f)
      EXPECT_EQ(back.faces.surface[f], m.faces.surface[f]) << "face " << f;
    // The isolated node stays isolated, in the first surface.
    std::size_t found = 0;
    for (std::uint32_t v = 0; v < back.nodes.slots.capacity(); ++v)
      if (back.nodes.position[v] == Vec3d(5, 6, 7)) {
        ++found;
        EXPECT_TRUE(back.is_isolated(NodeIdx{v}));
        EXPECT_EQ(back.nodes.surface[v], SurfaceIdx{0});
      }
    EXPECT_EQ(found, 1u);
    EXPECT_EQ(count_topology(back).faces, count_topology(m).faces);
    EXPECT_EQ(count_topology(back).edges, count_topology(m).edges);
  }
  (void)iso;
  // One surface: no surface property is written (files stay as before).
  write_ply(model_of(cube(), "c"), dir / "one.ply", false);
  EXPECT_EQ(slurp(dir / "one.ply").find("surface"), std::string::npos);
}

TEST(Ply, SurfacePropertyOfAnotherWriterSplitsTheFaces) {
  // Ids need not be dense or sorted; a vertex used by two surfaces becomes a
  // node of each; names default to <stem>_<id>.
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_indices\nproperty uchar surface\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2 7\n3 0 2 3 3\n";
  const Model m = read_ply_from_string(text, "s.ply");
  ASSERT_TRUE(validate(m));
  ASSERT_EQ(m.num_surfaces(), 2u);
  EXPECT_EQ(m.surfaces.name[0], "ply_3");
  EXPECT_EQ(m.surfaces.name[1], "ply_7");
  EXPECT_EQ(m.num_nodes(), 6u);  // vertices 0 and 2 in both surfaces
}

TEST(Ply, SkipsEveryPropertyTypeInBothEndians) {
  for (bool big : {false, true}) {
    SCOPED_TRACE(big ? "big endian" : "little endian");
    expect_is_cube(read_ply_from_string(exotic_cube_ply(big), "exotic.ply"));
  }
  expect_is_cube(read_ply(kGoodDir / "cube_ascii.ply"));
}

TEST(Ply, UvFromVertexProperties) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property float s\nproperty float t\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
      "0 0 0 0.25 0.5\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n";
  const Model m = read_ply_from_string(text, "uv.ply");
  ASSERT_TRUE(validate(m));
  EXPECT_EQ(m.nodes.uv[0], Vec2d(0.25, 0.5));
  EXPECT_EQ(m.nodes.uv[2], Vec2d(0, 1));
}

TEST(Ply, EveryPrefixOfABinaryFileFailsCleanly) {
  TempDir dir;
  write_ply(model_of(jittered_grid(3, 2, 5), "g"), dir / "g.ply", true);
  const std::string good = slurp(dir / "g.ply");
  for (std::size_t n = 0; n < good.size(); ++n) {
    try {
      (void)read_ply_from_string(std::string_view(good).substr(0, n), "cut.ply");
      ADD_FAILURE() << "prefix of " << n << " bytes read without error";
    } catch (const Error& e) {
      EXPECT_EQ(e.status().code(), ErrorCode::kParse) << e.what();
      EXPECT_NE(std::string(e.what()).find("cut.ply"), std::string::npos);
    }
  }
  EXPECT_NO_THROW((void)read_ply_from_string(good, "full.ply"));
  // Also every prefix of the exotic big-endian file.
  const std::string exotic = exotic_cube_ply(true);
  for (std::size_t n = 0; n < exotic.size(); ++n)
    EXPECT_THROW((void)read_ply_from_string(std::string_view(exotic).substr(0, n), "cut.ply"), Error) << n;
}

TEST(Ply, CorruptedBytesNeverCrash) {
  TempDir dir;
  write_ply(model_of(jittered_grid(2, 2, 5), "g"), dir / "g.ply", true);
  const std::string good = slurp(dir / "g.ply");
  std::size_t failed = 0;
  for (std::size_t i = 0; i < good.size(); ++i)
    for (unsigned char v : {0x00, 0xff, 0x7f, 0x80}) {
      std::string bad = good;
      bad[i] = static_cast<char>(v);
      try {
        const Model m = read_ply_from_string(bad, "bad.ply");
        EXPECT_TRUE(validate(m));
      } catch (const Error& e) {
        EXPECT_EQ(e.status().code(), ErrorCode::kParse) << e.what();
        ++failed;
      }
    }
  EXPECT_GT(failed, 0u);
}

TEST(Ply, EveryPrefixOfAnAsciiFileReadsOrFailsCleanly) {
  const std::string good = slurp(kGoodDir / "cube_ascii.ply");
  for (std::size_t n = 0; n <= good.size(); ++n) {
    try {
      expect_is_cube(read_ply_from_string(std::string_view(good).substr(0, n), "cut.ply"));
    } catch (const Error& e) {
      EXPECT_EQ(e.status().code(), ErrorCode::kParse) << e.what();
    }
  }
}

TEST(Off, RoundTripIsExactAndVariantsRead) {
  const Model m = model_of(jittered_grid(5, 3, 11), "grid");
  TempDir dir;
  write_off(m, dir / "grid.off");
  EXPECT_EQ(diff_tables(m, read_off(dir / "grid.off")), "");
  expect_is_cube(read_off(kGoodDir / "cube.off"));
  expect_is_cube(read_off(kGoodDir / "cube_colored.off"));
  // NOFF with normals, counts on the header line, comments between.
  const std::string noff =
      "NOFF 4 2 5 # header with counts\n"
      "0 0 0  0 0 1\n1 0 0 0 0 1\n# comment\n1 1 0 0 0 1\n0 1 0 0 0 1\n"
      "3 0 1 2\n\n3 0 2 3 255 0 0\n";
  const Model q = read_off_from_string(noff, "q.off");
  ASSERT_TRUE(validate(q));
  EXPECT_EQ(q.num_faces(), 2u);
  EXPECT_EQ(q.num_edges(), 5u);
  EXPECT_EQ(q.nodes.position[2], Vec3d(1, 1, 0));
}

TEST(Off, EveryPrefixReadsOrFailsCleanly) {
  const std::string good = slurp(kGoodDir / "cube_colored.off");
  std::size_t failed = 0;
  for (std::size_t n = 0; n <= good.size(); ++n) {
    try {
      expect_is_cube(read_off_from_string(std::string_view(good).substr(0, n), "cut.off"));
    } catch (const Error& e) {
      EXPECT_EQ(e.status().code(), ErrorCode::kParse) << e.what();
      EXPECT_NE(std::string(e.what()).find("cut.off"), std::string::npos);
      ++failed;
    }
  }
  EXPECT_GT(failed, 0u);
}
