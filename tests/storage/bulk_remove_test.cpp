// remove_faces_bulk against the primitives it replaces: the same live rows,
// the same free lists and generations (so later allocations and handles
// agree too), on random face sets of a triangle grid and a closed cube.
#include <atelier/storage/builder.h>
#include <atelier/storage/bulk_remove.h>
#include <atelier/storage/validate.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

using namespace atelier;

namespace {

Model tri_grid(int n) {
  std::vector<Vec3d> p;
  std::vector<std::uint32_t> off{0}, idx;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) p.emplace_back(i, j, 0.01 * i * j);
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      for (auto t : {std::array{id(i, j), id(i + 1, j), id(i + 1, j + 1)},
                     std::array{id(i, j), id(i + 1, j + 1), id(i, j + 1)}}) {
        idx.insert(idx.end(), t.begin(), t.end());
        off.push_back(static_cast<std::uint32_t>(idx.size()));
      }
    }
  Model m;
  (void)add_polygon_surface(m, "grid", PolygonSoupView{p, off, idx}).value();
  return m;
}

Model cube_model() {
  const std::vector<Vec3d> p = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const std::vector<std::uint32_t> idx = {0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6, 3, 0, 4, 7};
  const std::vector<std::uint32_t> off = {0, 4, 8, 12, 16, 20, 24};
  Model m;
  (void)add_polygon_surface(m, "cube", PolygonSoupView{p, off, idx}).value();
  return m;
}

/// The edges and nodes the faces leave behind, as the sketch cut finds them.
void leftovers(const Model& m, const std::vector<FaceIdx>& faces, std::vector<EdgeIdx>& edges,
               std::vector<NodeIdx>& nodes) {
  std::vector<std::uint8_t> gone(m.faces.slots.capacity(), 0), edie(m.edges.slots.capacity(), 0),
      seen(m.nodes.slots.capacity(), 0);
  for (FaceIdx f : faces) gone[f.value] = 1;
  auto faceless = [&](HalfedgeIdx h) { return !m.face(h).valid() || gone[m.face(h).value]; };
  std::vector<NodeIdx> corners;
  for (FaceIdx f : faces)
    m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
      corners.push_back(m.tail(h));
      if (!edie[edge_of(h).value] && faceless(h) && faceless(twin(h))) {
        edie[edge_of(h).value] = 1;
        edges.push_back(edge_of(h));
      }
    });
  for (NodeIdx v : corners) {
    if (seen[v.value]) continue;
    seen[v.value] = 1;
    bool all = true;
    m.for_each_outgoing(v, [&](HalfedgeIdx h) { all &= edie[edge_of(h).value] != 0; });
    if (all) nodes.push_back(v);
  }
}

template <class Tag>
void expect_same_slots(const SlotTable<Tag>& a, const SlotTable<Tag>& b) {
  EXPECT_TRUE(std::ranges::equal(a.free_list(), b.free_list()));
  EXPECT_TRUE(std::ranges::equal(a.generations(), b.generations()));
  EXPECT_TRUE(std::ranges::equal(a.alive_column(), b.alive_column()));
}

void check(const Model& m0, const std::vector<FaceIdx>& faces) {
  std::vector<EdgeIdx> edges;
  std::vector<NodeIdx> nodes;
  leftovers(m0, faces, edges, nodes);
  Model a = m0, b = m0;
  for (FaceIdx f : faces) a.delete_face(f);
  for (EdgeIdx e : edges) a.delete_edge(e);
  for (NodeIdx v : nodes) a.delete_node(v);
  remove_faces_bulk(b, faces, edges, nodes);
  EXPECT_EQ(diff_tables(a, b), "");
  expect_same_slots(a.nodes.slots, b.nodes.slots);
  expect_same_slots(a.edges.slots, b.edges.slots);
  expect_same_slots(a.faces.slots, b.faces.slots);
  ValidateOptions vo;
  vo.check_euler = false;  // the complex holes are the caller's bookkeeping
  EXPECT_TRUE(validate(b, vo)) << validate(b, vo).to_string();
  // Both models keep working alike: the next allocations take the same slots.
  const SurfaceIdx s{0};
  EXPECT_EQ(a.new_node(s, Vec3d(9, 9, 9)), b.new_node(s, Vec3d(9, 9, 9)));
}

}  // namespace

TEST(BulkRemove, SameTablesAsThePrimitivesOnRandomFaceSets) {
  const Model g = tri_grid(12);
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    SCOPED_TRACE(trial);
    std::vector<FaceIdx> faces;
    std::bernoulli_distribution pick(0.1 + 0.04 * trial);
    for (std::uint32_t f = 0; f < g.faces.slots.capacity(); ++f)
      if (pick(rng)) faces.push_back(FaceIdx{f});
    if (trial % 2) std::shuffle(faces.begin(), faces.end(), rng);  // any order, as long as both sides use it
    check(g, faces);
  }
  // Small sets (under a sixteenth of the faces) are walked face by face
  // instead of found by a pass over the halfedge columns: the same tables.
  for (int trial = 0; trial < 6; ++trial) {
    SCOPED_TRACE(100 + trial);
    std::vector<FaceIdx> faces;
    std::uniform_int_distribution<std::uint32_t> any(0, static_cast<std::uint32_t>(g.faces.slots.capacity() - 1));
    for (int k = 0; k < 1 + 3 * trial; ++k) faces.push_back(FaceIdx{any(rng)});
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    ASSERT_LT(faces.size() * 16, g.faces.slots.capacity());
    check(g, faces);
  }
  // All of it, and all of a closed cube but one face.
  std::vector<FaceIdx> all;
  for (std::uint32_t f = 0; f < g.faces.slots.capacity(); ++f) all.push_back(FaceIdx{f});
  check(g, all);
  const Model c = cube_model();
  check(c, {FaceIdx{0}, FaceIdx{1}, FaceIdx{2}, FaceIdx{3}, FaceIdx{4}});
}
