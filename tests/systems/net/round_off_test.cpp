// Rounding-off (seed 004 section 6): E never rises, fixed vertices keep
// their bits, the result is the minimiser (no perturbation lowers E).
#include <atelier/systems/net/boolean.h>
#include <atelier/systems/net/round_off.h>
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "net_shapes.h"

namespace atelier {
namespace {

struct Seamed {
  Model model;
  std::vector<NodeIdx> seam;
};

/// The union of a box and a sphere: a sharp seam to round off.
Seamed union_with_seam() {
  const PolygonSoup a = net_test::box_triangles({-0.8, -0.8, -0.8}, {0.8, 0.8, 0.2});
  const PolygonSoup b = net_test::icosphere(3, 0.7, {0.05, 0.02, 0.3});
  BooleanOptions o;
  o.op = BooleanOp::kUnion;
  auto r = net_boolean(a, b, o);
  EXPECT_TRUE(r.has_value());
  Seamed s;
  EXPECT_TRUE(add_polygon_surface(s.model, "u", r->result).has_value());
  for (std::uint32_t v : r->seam) s.seam.push_back(NodeIdx{v});
  return s;
}

TEST(NetRoundOff, LowersEnergyAndKeepsFixedVertices) {
  Seamed s = union_with_seam();
  ASSERT_FALSE(s.seam.empty());
  const Model before = s.model;
  RoundOptions o;
  o.rings = 1;
  auto r = round_off(s.model, s.seam, o);
  ASSERT_TRUE(r.has_value()) << r.status().to_string();
  EXPECT_TRUE(r->moved);
  EXPECT_LT(r->energy_after, r->energy_before);
  EXPECT_TRUE(validate(s.model).is_ok());
  // Which nodes were free: the seam and its first ring.
  std::vector<std::uint8_t> free(s.model.nodes.position.size(), 0);
  for (NodeIdx v : s.seam) free[v.value] = 1;
  std::vector<std::uint8_t> grown = free;
  for (std::uint32_t e = 0; e < s.model.edges.slots.capacity(); ++e) {
    if (!s.model.alive(EdgeIdx{e})) continue;
    const NodeIdx a = s.model.halfedges.tail[2 * e], b = s.model.halfedges.tail[2 * e + 1];
    if (free[a.value]) grown[b.value] = 1;
    if (free[b.value]) grown[a.value] = 1;
  }
  std::size_t moved = 0;
  for (std::size_t v = 0; v < grown.size(); ++v) {
    const bool same =
        std::memcmp(before.nodes.position[v].data(), s.model.nodes.position[v].data(), sizeof(Vec3d)) == 0;
    if (!grown[v]) {
      EXPECT_TRUE(same) << v;
    }
    moved += !same;
  }
  EXPECT_GT(moved, s.seam.size() / 2);
  // The reported energies are E of the free set, computed independently.
  EXPECT_NEAR(*umbrella_energy(before, grown, o), r->energy_before, 1e-12 * r->energy_before);
  EXPECT_NEAR(*umbrella_energy(s.model, grown, o), r->energy_after, 1e-9 * r->energy_before);
  // A minimiser: random perturbations of the free nodes never lower E.
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1e-3);
  for (int trial = 0; trial < 20; ++trial) {
    Model p = s.model;
    for (std::size_t v = 0; v < grown.size(); ++v)
      if (grown[v]) p.nodes.position[v] += Vec3d(g(rng), g(rng), g(rng));
    EXPECT_GE(*umbrella_energy(p, grown, o), r->energy_after * (1 - 1e-12));
  }
}

TEST(NetRoundOff, NeverRaisesEnergyOnASecondRun) {
  Seamed s = union_with_seam();
  auto first = round_off(s.model, s.seam, {});
  ASSERT_TRUE(first.has_value());
  const Model once = s.model;
  auto second = round_off(s.model, s.seam, {});
  ASSERT_TRUE(second.has_value());
  EXPECT_LE(second->energy_after, second->energy_before);
  EXPECT_NEAR(second->energy_before, first->energy_after, 1e-9 * first->energy_before);
}

TEST(NetRoundOff, RefusesBadArguments) {
  Seamed s = union_with_seam();
  const Model before = s.model;
  RoundOptions bad;
  bad.mu = -1;
  EXPECT_FALSE(round_off(s.model, s.seam, bad).has_value());
  std::vector<NodeIdx> nowhere{NodeIdx{999999}};
  EXPECT_FALSE(round_off(s.model, nowhere, {}).has_value());
  EXPECT_TRUE(diff_tables(before, s.model).empty());
  EXPECT_EQ(parse_seam("# seam\n1 2 3\n4\n", "s.txt").size(), 4u);
  EXPECT_THROW((void)parse_seam("1 2 -3\n", "s.txt"), Error);
  EXPECT_THROW((void)parse_seam("1 x\n", "s.txt"), Error);
}

}  // namespace
}  // namespace atelier
