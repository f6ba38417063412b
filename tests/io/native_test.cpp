#include <gtest/gtest.h>

#include <cstring>

#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include "io_test_support.h"
#include <atelier/storage/topology.h>

using namespace atelier;
using namespace atelier::test;

namespace {

/// A model with every kind of element: two surfaces joined along a mesh
/// edge pair (joint with coincident nodes), a closed mesh loop, a wire edge,
/// an isolated node, a ring node, attribute nodes of each kind, attribute
/// edges, flags, uv and backup positions, property columns, and tombstones.
Model every_kind_model() {
  Model m;
  Soup a;
  a.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 0}};
  a.face({0, 1, 4, 3});
  a.face({1, 2, 5, 4});
  Soup b;
  b.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 0, -1}, {1, 0, -1}, {2, 0, -1}};
  b.face({0, 3, 4, 1});
  b.face({1, 4, 5, 2});
  const SurfaceIdx sa = add_polygon_surface(m, "sheet A", a.arrays()).value().idx;
  const SurfaceIdx sb = add_polygon_surface(m, "flap B", b.arrays()).value().idx;
  auto h = [&](std::uint32_t x, std::uint32_t y) {
    const HalfedgeIdx r = m.find_halfedge(NodeIdx{x}, NodeIdx{y});
    if (!r.valid()) throw std::logic_error("no halfedge");
    return r;
  };
  // Tombstones first, so compact() has work to do.
  const NodeIdx dead0 = m.new_node(sa, Vec3d(9, 9, 9));
  const NodeIdx dead1 = m.new_node(sa, Vec3d(8, 9, 9));
  const EdgeIdx dead_e = m.new_edge(dead0, dead1);

  const std::vector<HalfedgeIdx> c0 = {h(0, 1), h(1, 2)};
  const std::vector<HalfedgeIdx> c1 = {h(2, 5), h(5, 4), h(4, 3), h(3, 0)};
  // B's chain runs the other way: a negative joint member.
  const std::vector<HalfedgeIdx> c2 = {h(8, 7), h(7, 6)};
  const MeshEdgeIdx me0 = m.new_mesh_edge(sa, c0);
  const MeshEdgeIdx me1 = m.new_mesh_edge(sa, c1);
  const MeshEdgeIdx me2 = m.new_mesh_edge(sb, c2);
  const std::vector<MeshEdgeIdx> loop = {me0, me1};
  (void)m.new_mesh_loop(sa, loop);
  const std::vector<JointMember> joint = {{me0, true}, {me2, false}};
  (void)m.new_joint(joint);

  const NodeIdx w0 = m.new_node(sa, Vec3d(3, 0, 0)), w1 = m.new_node(sa, Vec3d(3, 1, 0));
  const EdgeIdx wire = m.new_edge(w0, w1);
  m.edges.flags[wire.value] = 3;
  (void)m.new_node(sb, Vec3d(5, 5, 5));  // isolated
  const NodeIdx ring = m.new_node(sa, Vec3d(0.5, 0.5, 0));
  m.nodes.in_face[ring.value] = FaceIdx{0};

  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
    if (!m.alive(NodeIdx{v})) continue;
    m.nodes.uv[v] = Vec2d(0.1 * v, 1.0 / (v + 3));
    m.nodes.position_backup[v] = m.nodes.position[v] + Vec3d(0, 0, 1e-3 * v);
  }
  m.faces.flags[1] = 5;
  m.surfaces.flags[sb.value] = 2;

  const AttribNodeIdx an0 = m.new_attrib_node(sa, AttribNodeKind::kVertex, 4, Vec3d::Zero(), m.position(NodeIdx{4}));
  const AttribNodeIdx an1 = m.new_attrib_node(sa, AttribNodeKind::kEdge, h(0, 1).value, Vec3d(0.25, 0, 0), Vec3d::Zero());
  const AttribNodeIdx an2 = m.new_attrib_node(sa, AttribNodeKind::kFace, 0, Vec3d(0.2, 0.3, 0.5), Vec3d::Zero(), 1);
  const AttribNodeIdx an3 = m.new_attrib_node(sb, AttribNodeKind::kFace, 3, Vec3d(0.6, 0.2, 0.2), Vec3d::Zero(), 0);
  for (AttribNodeIdx x : {an1, an2, an3}) m.attrib_nodes.position[x.value] = m.attrib_position_on_surface(x);
  (void)an0;
  (void)m.new_attrib_edge(sa, 7, std::vector<AttribNodeIdx>{an1, an2});
  (void)m.new_attrib_edge(sb, -3, std::vector<AttribNodeIdx>{an3});

  auto src = m.nodes.props.add<std::int32_t>("source_vertex", -1);
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) src[NodeIdx{v}] = static_cast<std::int32_t>(100 + v);
  auto area = m.faces.props.add<double>("area");
  area[FaceIdx{1}] = 0.1;
  auto dir = m.edges.props.add<Vec3d>("dir");
  dir[EdgeIdx{0}] = Vec3d(1, 2, 3);
  m.surfaces.props.add<std::uint8_t>("kind")[SurfaceIdx{1}] = 9;
  m.attrib_edges.props.add<float>("weight")[AttribEdgeIdx{0}] = 0.5f;
  m.nodes.props.add<std::string>("note");  // a type the format does not store

  m.delete_edge(dead_e);
  m.delete_node(dead1);
  m.delete_node(dead0);

  m.complex_holes = count_topology(m).implied_holes();
  return m;
}

// Independent CRC-32 (bit by bit, no table) to re-seal patched sections.
std::uint32_t crc32_bitwise(std::string_view s) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (char ch : s) {
    c ^= static_cast<std::uint8_t>(ch);
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

template <class T>
T get_le(const std::string& b, std::size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof(T));
  return v;
}
template <class T>
void put_le(std::string& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof(T));
}

struct SectionAt {
  std::size_t header = 0, payload = 0;
  std::uint64_t size = 0;
};

/// Finds a section by its four-letter tag by walking the documented layout.
SectionAt find_section(const std::string& b, const char* tag) {
  std::size_t pos = 16;
  while (pos + 16 <= b.size()) {
    const std::uint64_t size = get_le<std::uint64_t>(b, pos + 4);
    if (std::memcmp(b.data() + pos, tag, 4) == 0) return {pos, pos + 16, size};
    pos += 16 + size;
  }
  throw std::logic_error("no section");
}

void reseal(std::string& b, const SectionAt& s) {
  put_le<std::uint32_t>(b, s.header + 12, crc32_bitwise(std::string_view(b).substr(s.payload, s.size)));
}

}  // namespace

TEST(Native, RoundTripOfEveryKindOfElement) {
  const Model m = every_kind_model();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  ASSERT_GT(m.nodes.slots.capacity(), m.nodes.slots.size());  // there are tombstones
  EXPECT_EQ(m.num_joints(), 1u);
  EXPECT_EQ(m.num_mesh_loops(), 1u);
  EXPECT_EQ(count_topology(m).rings, 1);

  Model expected = m;
  (void)expected.compact();
  ASSERT_TRUE(validate(expected));

  TempDir dir;
  write_model(m, dir / "all.atm");
  const Model back = read_model(dir / "all.atm");
  EXPECT_TRUE(validate(back));
  EXPECT_EQ(diff_tables(expected, back), "");
  EXPECT_EQ(back.complex_holes, m.complex_holes);
  EXPECT_EQ(back.surfaces.name, expected.surfaces.name);
  EXPECT_EQ(back.surfaces.flags, expected.surfaces.flags);
  // Joint direction flags and attribute feature ids survive.
  EXPECT_FALSE(back.joints.members.row(0)[1].positive);
  EXPECT_TRUE(back.joints.members.row(0)[0].positive);
  EXPECT_EQ(back.attrib_edges.feature_id, expected.attrib_edges.feature_id);
  // Property columns of storable types survive; others are left out.
  EXPECT_EQ(back.nodes.props.find<std::int32_t>("source_vertex").vector(),
            expected.nodes.props.find<std::int32_t>("source_vertex").vector());
  EXPECT_EQ(back.faces.props.find<double>("area").vector(), expected.faces.props.find<double>("area").vector());
  EXPECT_EQ(back.edges.props.find<Vec3d>("dir").vector(), expected.edges.props.find<Vec3d>("dir").vector());
  EXPECT_EQ(back.surfaces.props.find<std::uint8_t>("kind").vector(),
            expected.surfaces.props.find<std::uint8_t>("kind").vector());
  EXPECT_EQ(back.attrib_edges.props.find<float>("weight").vector(),
            expected.attrib_edges.props.find<float>("weight").vector());
  EXPECT_FALSE(back.nodes.props.contains("note"));
  // The bytes are a function of the tables alone.
  EXPECT_EQ(serialize_model(back), serialize_model(m));
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"all.atm"});
}

TEST(Native, RoundTripOfARealMesh) {
  const std::filesystem::path p = std::filesystem::path(ATELIER_SHARED_DATA) / "meshes" / "spot_control_mesh.obj";
  if (!std::filesystem::exists(p)) GTEST_SKIP() << "shared data absent: " << p;
  const Model m = read_obj(p);
  const Model back = deserialize_model(serialize_model(m), "spot.atm");
  EXPECT_EQ(diff_tables(m, back), "");
}

TEST(Native, EveryTruncationIsDetected) {
  const std::string good = serialize_model(every_kind_model());
  for (std::size_t n = 0; n < good.size(); ++n) {
    try {
      (void)deserialize_model(std::string_view(good).substr(0, n), "cut.atm");
      ADD_FAILURE() << "prefix of " << n << " bytes read without error";
    } catch (const Error& e) {
      EXPECT_EQ(e.status().code(), ErrorCode::kParse);
      const std::string w = e.what();
      EXPECT_NE(w.find("cut.atm"), std::string::npos);
      EXPECT_TRUE(w.find("truncated") != std::string::npos || w.find("bad magic") != std::string::npos) << w;
    }
  }
}

TEST(Native, EveryFlippedBitIsDetected) {
  const std::string good = serialize_model(every_kind_model());
  for (std::size_t i = 0; i < good.size(); ++i)
    for (int bit : {0, 5}) {
      std::string bad = good;
      bad[i] = static_cast<char>(bad[i] ^ (1 << bit));
      try {
        (void)deserialize_model(bad, "flip.atm");
        ADD_FAILURE() << "flipping bit " << bit << " of byte " << i << " went unnoticed";
      } catch (const Error& e) {
        EXPECT_EQ(e.status().code(), ErrorCode::kParse) << e.what();
      }
    }
  // A flip inside a payload names the section and calls it corruption.
  const SectionAt s = find_section(good, "FACE");
  std::string bad = good;
  bad[s.payload + 2] ^= 1;
  expect_error([&] { (void)deserialize_model(bad, "f.atm"); }, ErrorCode::kParse,
               {"f.atm", "checksum mismatch in section 'FACE'", "byte offset " + std::to_string(s.payload)});
}

TEST(Native, IndicesAreCheckedBeforeBuilding) {
  const Model m = every_kind_model();
  const std::string good = serialize_model(m);
  Model c = m;
  (void)c.compact();
  const std::size_t ne = c.edges.slots.capacity();
  const SectionAt edge = find_section(good, "EDGE");
  const std::size_t tail0 = edge.payload + ne * 1 + ne * 4;  // flags u8, mesh_edge u32, then tails
  {
    std::string bad = good;
    put_le<std::uint32_t>(bad, tail0, 99999);
    reseal(bad, edge);
    expect_error([&] { (void)deserialize_model(bad, "idx.atm"); }, ErrorCode::kParse,
                 {"idx.atm", "section 'EDGE'", "bad index", "tail of halfedge 0 refers to 99999"});
  }
  {
    std::string bad = good;
    put_le<std::uint32_t>(bad, tail0, 0xFFFFFFFFu);
    reseal(bad, edge);
    expect_error([&] { (void)deserialize_model(bad, "idx.atm"); }, ErrorCode::kParse,
                 {"bad index", "tail of halfedge 0 refers to nothing"});
  }
  {
    // In range but wrong: validate() must reject the result.
    std::string bad = good;
    put_le<std::uint32_t>(bad, tail0, get_le<std::uint32_t>(bad, tail0) + 5);
    reseal(bad, edge);
    expect_error([&] { (void)deserialize_model(bad, "topo.atm"); }, ErrorCode::kParse, {"topo.atm", "not valid"});
  }
  {
    // Every u32 of every section set to a large value, re-sealed: never a
    // crash, always a clean error or a valid model.
    for (const char* tag : {"NODE", "EDGE", "FACE", "MEDG", "LOOP", "JOIN", "ATND", "ATED"}) {
      const SectionAt s = find_section(good, tag);
      for (std::size_t off = 0; off + 4 <= s.size; off += 4)
        for (std::uint32_t v : {0x7FFFFFFFu, 3u}) {
          std::string bad = good;
          put_le<std::uint32_t>(bad, s.payload + off, v);
          reseal(bad, s);
          try {
            const Model r = deserialize_model(bad, "poke.atm");
            EXPECT_TRUE(validate(r));
          } catch (const Error& e) {
            EXPECT_EQ(e.status().code(), ErrorCode::kParse) << e.what();
          }
        }
    }
  }
  {
    // A huge table size in the header must not allocate: it does not fit.
    std::string bad = good;
    const SectionAt head = find_section(good, "HEAD");
    put_le<std::uint64_t>(bad, head.payload + 8, 1'000'000'000ull);
    reseal(bad, head);
    expect_error([&] { (void)deserialize_model(bad, "big.atm"); }, ErrorCode::kParse,
                 {"section 'NODE'", "element count mismatch"});
  }
}

TEST(Native, VersionOneFilesWithoutHalfedgePropertiesStillRead) {
  // Version 2 appends the halfedge (face-corner) property columns to PROP,
  // the last section. A version 1 file is the same without them.
  const Model m = every_kind_model();
  ASSERT_TRUE(m.halfedges.props.names().empty());
  std::string v1 = serialize_model(m);
  std::size_t pos = 16;
  for (int k = 0; k < 10; ++k) {
    std::uint64_t size = 0;
    std::memcpy(&size, v1.data() + pos + 4, 8);
    pos += 16 + size;
  }
  std::uint64_t size = 0;
  std::memcpy(&size, v1.data() + pos + 4, 8);
  ASSERT_EQ(pos + 16 + size, v1.size());
  v1.resize(v1.size() - 4);  // the halfedge registry's property count (0)
  put_le<std::uint64_t>(v1, pos + 4, size - 4);
  put_le<std::uint32_t>(v1, pos + 12, crc32_bitwise(std::string_view(v1).substr(pos + 16, size - 4)));
  put_le<std::uint32_t>(v1, 8, 1);
  Model expected = m;  // files hold the compacted tables
  (void)expected.compact();
  EXPECT_EQ(diff_tables(deserialize_model(v1, "v1.atm"), expected), "");
}

TEST(Native, VersionAndMagicAreChecked) {
  std::string b = serialize_model(every_kind_model());
  std::string v3 = b;
  put_le<std::uint32_t>(v3, 8, 3);
  expect_error([&] { (void)deserialize_model(v3, "v.atm"); }, ErrorCode::kParse, {"v.atm", "unsupported version 3"});
  b[0] = 'X';
  expect_error([&] { (void)deserialize_model(b, "m.atm"); }, ErrorCode::kParse, {"m.atm", "bad magic"});
  TempDir dir;
  expect_error([&] { (void)read_model(dir / "absent.atm"); }, ErrorCode::kIo, {"absent.atm"});
}
