// Quadrangulation of face cycles (seed 003 section 6.1): every result is a
// quad disk with F = I + b/2 - 1 whose boundary is the input loop, checked
// on regular and irregular polygons, and on every face of the shared
// networks inside the pipeline, where the network's vertices must come out
// bit-identical to their fitted control polygons.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "curvenet_fixtures.h"
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/curvenet/bspline.h>
#include <atelier/systems/curvenet/curve_surface.h>
#include <atelier/systems/curvenet/quadrangulate.h>

using namespace atelier;
using namespace atelier::curvenet_test;

namespace {

/// Checks that the patch is a quad disk bounded by 0 -> 1 -> ... -> b-1.
void expect_quad_disk(std::span<const Vec3d> boundary, const QuadPatch& p) {
  const auto b = static_cast<std::uint32_t>(boundary.size());
  EXPECT_EQ(p.quads.size(), p.interior.size() + b / 2 - 1) << "F = I + b/2 - 1, b = " << b;
  PolygonSoup s;
  s.positions.assign(boundary.begin(), boundary.end());
  s.positions.insert(s.positions.end(), p.interior.begin(), p.interior.end());
  for (const auto& q : p.quads) s.add_face(q);
  Model m;
  auto surf = add_polygon_surface(m, "patch", s);
  ASSERT_TRUE(surf) << surf.status().to_string();
  EXPECT_TRUE(validate(m)) << validate(m).to_string();
  // Boundary edges (used once) are exactly the loop's, in its direction.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> use;
  for (const auto& q : p.quads)
    for (int k = 0; k < 4; ++k) ++use[{q[static_cast<std::size_t>(k)], q[static_cast<std::size_t>((k + 1) % 4)]}];
  std::size_t boundary_edges = 0;
  for (const auto& [e, n] : use)
    if (!use.count({e.second, e.first})) {
      ++boundary_edges;
      EXPECT_LT(e.first, b);
      EXPECT_EQ(e.second, (e.first + 1) % b) << "boundary edge " << e.first << " -> " << e.second;
    }
  EXPECT_EQ(boundary_edges, b);
  for (const Vec3d& x : p.interior) EXPECT_TRUE(x.allFinite());
}

std::vector<Vec3d> polygon(const std::vector<Vec3d>& corners, const std::vector<int>& edges_per_side) {
  std::vector<Vec3d> p;
  for (std::size_t c = 0; c < corners.size(); ++c) {
    const Vec3d &a = corners[c], &b = corners[(c + 1) % corners.size()];
    for (int k = 0; k < edges_per_side[c]; ++k) p.push_back(a + (b - a) * (static_cast<double>(k) / edges_per_side[c]));
  }
  return p;
}

}  // namespace

TEST(Quadrangulate, RectanglesBecomeRegularGrids) {
  for (int m = 1; m <= 6; ++m)
    for (int n = 1; n <= 7; ++n) {
      const auto b = polygon({{0, 0, 0}, {2.0 * n, 0, 0}, {2.0 * n, 2.0 * m, 0}, {0, 2.0 * m, 0}}, {n, m, n, m});
      auto p = quadrangulate_cycle(b);
      ASSERT_TRUE(p) << p.status().to_string();
      expect_quad_disk(b, *p);
      EXPECT_EQ(p->quads.size(), static_cast<std::size_t>(m * n)) << m << " x " << n;
      EXPECT_EQ(p->interior.size(), static_cast<std::size_t>((m - 1) * (n - 1)));
      // Eq. (3) interpolates the side vectors: on a rectangle the new
      // vertices land on the grid points.
      for (const Vec3d& x : p->interior) {
        EXPECT_NEAR(x.x() / 2, std::round(x.x() / 2), 1e-12);
        EXPECT_NEAR(x.y() / 2, std::round(x.y() / 2), 1e-12);
      }
    }
}

TEST(Quadrangulate, PolygonsWithTwoEdgesPerSideGetACentre) {
  for (int sides = 3; sides <= 7; ++sides) {  // corners below the 135-degree threshold
    std::vector<Vec3d> corners;
    for (int k = 0; k < sides; ++k)
      corners.emplace_back(std::cos(2 * kPi * k / sides), std::sin(2 * kPi * k / sides), 0);
    const auto b = polygon(corners, std::vector<int>(static_cast<std::size_t>(sides), 2));
    auto p = quadrangulate_cycle(b);
    ASSERT_TRUE(p);
    expect_quad_disk(b, *p);
    EXPECT_EQ(p->quads.size(), static_cast<std::size_t>(sides));  // one quad per corner
    ASSERT_EQ(p->interior.size(), 1u);
    EXPECT_LT(p->interior[0].norm(), 1e-12);
  }
}

TEST(Quadrangulate, IrregularAndNonPlanarCyclesAreQuadDisks) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::size_t total = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int sides = 3 + trial % 6;
    std::vector<Vec3d> corners;
    std::vector<int> per_side;
    int sum = 0;
    for (int k = 0; k < sides; ++k) {
      // Star-shaped, some sides concave, lifted out of the plane.
      const double r = 1 + 0.45 * u(rng), a = 2 * kPi * (k + 0.3 * u(rng)) / sides;
      corners.emplace_back(r * std::cos(a), r * std::sin(a), 0.4 * u(rng));
      per_side.push_back(1 + static_cast<int>(rng() % 7));
      sum += per_side.back();
    }
    if (sum % 2) ++per_side[0];
    const auto b = polygon(corners, per_side);
    if (b.size() < 4) continue;
    auto p = quadrangulate_cycle(b);
    ASSERT_TRUE(p) << p.status().to_string();
    expect_quad_disk(b, *p);
    total += p->quads.size();
  }
  EXPECT_GT(total, 1000u);
}

TEST(Quadrangulate, ForbiddenChordsAreNotMade) {
  // A hexagon with one edge per side: without a filter its front is cut by
  // chords; forbidding every chord leaves the centre fan (no chord at all).
  std::vector<Vec3d> b;
  for (int k = 0; k < 6; ++k) b.emplace_back(std::cos(kPi * k / 3), std::sin(kPi * k / 3), 0);
  auto p = quadrangulate_cycle(b, {}, [](std::uint32_t, std::uint32_t) { return true; });
  ASSERT_TRUE(p);
  expect_quad_disk(b, *p);
  for (const auto& q : p->quads) {
    int boundary_corners = 0;
    for (std::uint32_t v : q) boundary_corners += v < 6;
    EXPECT_EQ(boundary_corners, 3);  // (centre, three consecutive boundary vertices)
  }
}

TEST(Quadrangulate, OddOrTinyOrNonFiniteCyclesAreRefused) {
  const std::vector<Vec3d> five = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0.5, 1.5, 0}, {0, 1, 0}};
  EXPECT_EQ(quadrangulate_cycle(five).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_FALSE(quadrangulate_cycle(std::span<const Vec3d>(five).first(2)));
  std::vector<Vec3d> bad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, std::nan(""), 0}};
  EXPECT_FALSE(quadrangulate_cycle(bad));
}

TEST(Quadrangulate, EveryFaceOfTheSharedNetworks) {
  ATELIER_REQUIRE_SHARED_NETWORKS();
  for (const char* name : {"shell_100", "roof_75", "kagome_114_regular"}) {
    CurveSurfaceOptions o;
    o.levels = 0;
    o.build_model = false;
    auto r = surface_from_curves(shared_network(name), {}, o);
    ASSERT_TRUE(r) << name << ": " << r.status().to_string();
    const ControlMesh& cm = r->control;
    ASSERT_EQ(cm.face_boundary.size(), r->cycles.face_count());
    for (std::size_t f = 0; f < cm.face_boundary.size(); ++f) {
      const std::size_t quads = cm.face_quads[f + 1] - cm.face_quads[f];
      ASSERT_EQ(quads, cm.face_interior[f] + cm.face_boundary[f] / 2 - 1) << name << " face " << f;
      for (std::uint32_t q = cm.face_quads[f]; q < cm.face_quads[f + 1]; ++q) ASSERT_EQ(cm.mesh.face(q).size(), 4u);
    }
    // The network's vertices are the nodes and the fitted control polygons,
    // bit for bit, after quadrangulation and fairing.
    std::size_t compared = 0;
    for (std::size_t s = 0; s < r->graph.segment_count(); ++s) {
      const std::uint32_t b = cm.segment_offsets[s], e = cm.segment_offsets[s + 1];
      const auto fitted = fit_crease_polygon(r->graph.polyline(s), e - b);
      for (std::uint32_t k = b; k < e; ++k) {
        const Vec3d& x = cm.mesh.positions[cm.segment_vertices[k]];
        ASSERT_EQ(0, std::memcmp(x.data(), fitted[k - b].data(), sizeof(Vec3d))) << name << " segment " << s;
        ++compared;
      }
    }
    for (std::size_t v = 0; v < r->graph.node_count(); ++v) ASSERT_EQ(cm.mesh.positions[v], r->graph.nodes[v]);
    EXPECT_GT(compared, 1000u);
  }
}
