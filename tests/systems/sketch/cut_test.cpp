// Cutting and partitioning (seed 001 section 5, Figs. 12-13 and 15).
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/sketch/cut.h>
#include <atelier/systems/sketch/paint.h>
#include <gtest/gtest.h>

#include <random>

#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;

namespace {

/// Area of the triangles of a triangle mesh clipped to the half-space
/// n.x <= d (Sutherland-Hodgman on each triangle): the independent oracle
/// for a plane cut.
double clipped_area(const Model& m, const Vec3d& n, double d) {
  double a = 0;
  std::vector<NodeIdx> c;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    m.face_nodes(FaceIdx{f}, c);
    std::vector<Vec3d> poly;
    for (std::size_t k = 0; k < c.size(); ++k) {
      const Vec3d p = m.position(c[k]), q = m.position(c[(k + 1) % c.size()]);
      const double sp = n.dot(p) - d, sq = n.dot(q) - d;
      if (sp <= 0) poly.push_back(p);
      if ((sp < 0 && sq > 0) || (sp > 0 && sq < 0)) poly.push_back(p + sp / (sp - sq) * (q - p));
    }
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)
      a += 0.5 * (poly[k] - poly[0]).cross(poly[k + 1] - poly[0]).norm();
  }
  return a;
}

std::vector<Vec2d> ring_stroke(const Camera& cam, const Vec3d& c, double r, int n = 36) {
  std::vector<Vec3d> p;
  for (int k = 0; k <= n; ++k) p.push_back(c + r * Vec3d(std::cos(2 * M_PI * k / n), std::sin(2 * M_PI * k / n), 0));
  auto s = project(cam, p);
  s.back() = s.front();
  return s;
}

}  // namespace

TEST(Cut, APlaneCutOfASphereLeavesAHemisphere) {
  for (const bool persp : {false, true}) {
    SCOPED_TRACE(persp ? "perspective" : "orthographic");
    Model m = icosphere(4);
    const Model original = m;
    const double a0 = fan_area(m);
    const Camera cam = persp ? front_persp(Vec3d(0, 0, 4)) : front_ortho();
    // Through the centre: the sheet is the plane y = 0 (the perspective eye
    // lies in it too).
    auto p = paint_stroke(m, cam, project(cam, {Vec3d(-1.5, 0, 0), Vec3d(1.5, 0, 0)}), {.through = true});
    ASSERT_TRUE(p) << p.status().to_string();
    auto pick = locate_pixel(m, cam, cam.project(Vec3d(0.1, 0.6, 0.8)).head<2>());
    ASSERT_TRUE(pick);
    auto r = cut_along_curves(m, edges_of(*p), {.pick = pick->location});
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_TRUE(validate(m)) << validate(m).to_string();
    ASSERT_EQ(r->pieces.size(), 2u);
    // The upper half went: every node left is at y <= 0, the area left is the
    // original mesh clipped by the plane, and the areas add up.
    for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
      if (m.alive(NodeIdx{v})) {
        EXPECT_LE(m.nodes.position[v].y(), 1e-12);
      }
    EXPECT_NEAR(fan_area(m), clipped_area(original, Vec3d::UnitY(), 0.0), 1e-12 * a0);
    EXPECT_NEAR(r->kept_area, fan_area(m), 1e-12 * a0);
    EXPECT_NEAR(r->removed_area + r->kept_area, a0, 1e-12 * a0);
    EXPECT_NEAR(r->kept_area, 2 * M_PI, 0.01);  // a hemisphere of the unit sphere
    // One boundary loop, on the equator.
    const TopologyCounts t = count_topology(m);
    EXPECT_EQ(t.components, 1);
    EXPECT_EQ(t.shells, 0);
    std::size_t boundary = 0;
    for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e)
      if (m.alive(EdgeIdx{e}) && m.is_boundary(EdgeIdx{e})) {
        ++boundary;
        EXPECT_NEAR(m.position(m.tail(halfedge_of(EdgeIdx{e}, 0))).y(), 0.0, 1e-12);
      }
    EXPECT_GT(boundary, 30u);
  }
}

TEST(Cut, AreasAddUpAndThePickChoosesTheSide) {
  Model m0 = icosphere(3);
  const Camera cam = front_persp();
  const auto stroke = project(cam, {Vec3d(-1.5, 0.3, 0), Vec3d(0, 0.1, 0), Vec3d(1.5, 0.35, 0)});
  double kept[2];
  for (int side = 0; side < 2; ++side) {
    Model m = m0;
    const double a0 = fan_area(m);
    auto p = paint_stroke(m, cam, stroke, {.through = true});
    ASSERT_TRUE(p);
    auto pick = locate_pixel(m, cam, cam.project(Vec3d(0, side ? -0.5 : 0.7, 0.5)).head<2>());
    ASSERT_TRUE(pick);
    auto r = cut_along_curves(m, edges_of(*p), {.pick = pick->location});
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_TRUE(validate(m)) << validate(m).to_string();
    EXPECT_NEAR(r->removed_area + r->kept_area, a0, 1e-12 * a0);
    EXPECT_NEAR(fan_area(m), r->kept_area, 1e-12 * a0);
    kept[side] = r->kept_area;
  }
  EXPECT_NEAR(kept[0] + kept[1], fan_area(m0), 1e-12 * fan_area(m0));  // the two sides complement
  // Without a pick the smaller side goes.
  Model m = m0;
  auto p = paint_stroke(m, cam, stroke, {.through = true});
  auto r = cut_along_curves(m, edges_of(*p));
  ASSERT_TRUE(r);
  EXPECT_NEAR(r->kept_area, std::max(kept[0], kept[1]), 1e-12);
}

TEST(Cut, ACurveThatSeparatesNothingIsRefused) {
  // Visible painting on a closed sphere ends at the silhouette: it does not
  // separate; nothing changes (not even the painted curve's re-triangulation).
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  auto p = paint_stroke(m, cam, project(cam, {Vec3d(-1.5, 0.2, 0), Vec3d(1.5, 0.2, 0)}));
  ASSERT_TRUE(p);
  const Model before = m;
  auto pick = locate_pixel(m, cam, cam.project(Vec3d(0, 0.7, 0)).head<2>());
  auto r = cut_along_curves(m, edges_of(*p), {.pick = pick->location});
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("does not separate"), std::string::npos) << r.status().message();
  EXPECT_EQ(diff_tables(before, m), "");
  auto r2 = cut_along_curves(m, edges_of(*p));
  ASSERT_FALSE(r2);
  EXPECT_EQ(diff_tables(before, m), "");
}

// The cut keeps the complex-hole count H by Euler bookkeeping of the removed
// piece (components among its surviving corners, whether its face group was
// a closed shell) instead of recounting the model. Oracle: a full recount
// (count_topology) after every cut of random sequences, on a closed sphere,
// a sphere next to an open sheet (boundary elsewhere in the model: the
// closed-shell test floods), and a band cut that leaves two components.
TEST(Cut, IncrementalEulerCountEqualsARecount) {
  auto sheet = [](Model& m, double y0) {
    (void)add_polygon_surface(
        m, "sheet", grid(6, 4, [&](double u, double v) { return Vec3d(-1 + 2 * u, y0 + v, 0.1 * u * v); }).view())
        .value();
  };
  auto check = [](const Model& m, const char* what) {
    SCOPED_TRACE(what);
    ASSERT_TRUE(validate(m)) << validate(m).to_string();
    EXPECT_EQ(m.complex_holes, count_topology(m).implied_holes());
  };
  const Camera cam = front_ortho();
  std::mt19937 rng(20);
  std::uniform_real_distribution<double> U(-1, 1);
  int cuts = 0;
  for (int model = 0; model < 3; ++model) {
    SCOPED_TRACE(model);
    Model m = icosphere(3);
    if (model == 1) sheet(m, 2.0);  // open, out of the strokes' way
    if (model == 2) {
      // Two strokes and the band between them: the rest falls in two.
      Model b = m;
      std::vector<AttribEdge> both;
      for (double y : {0.3, -0.25}) {
        auto p = paint_stroke(b, cam, project(cam, {Vec3d(-1.5, y, 0), Vec3d(1.5, y + 0.05, 0)}), {.through = true});
        ASSERT_TRUE(p) << p.status().to_string();
        const auto e = edges_of(*p);
        both.insert(both.end(), e.begin(), e.end());
      }
      auto pick = locate_pixel(b, cam, cam.project(Vec3d(0.1, 0.0, 0.9)).head<2>());
      ASSERT_TRUE(pick);
      auto r = cut_along_curves(b, both, {.pick = pick->location});
      ASSERT_TRUE(r) << r.status().to_string();
      check(b, "band");
      EXPECT_EQ(count_topology(b).components, 2);
      ++cuts;
    }
    // Successive random cuts: the first of a closed shell, the next ones of
    // what is left (open).
    for (int k = 0; k < 8; ++k) {
      const double y = 0.5 * U(rng), tilt = 0.2 * U(rng);
      const Model before = m;
      auto p = paint_stroke(
          m, cam, project(cam, {Vec3d(-1.5, y - tilt, 0), Vec3d(0, y + 0.1 * U(rng), 0), Vec3d(1.5, y + tilt, 0)}),
          {.through = true});
      if (!p) continue;  // the stroke missed what is left
      const double side = U(rng) < 0 ? -0.9 : 0.9;
      auto pick = locate_pixel(m, cam, cam.project(Vec3d(0.05, side, 0.3)).head<2>());
      if (!pick) continue;
      auto r = cut_along_curves(m, edges_of(*p), {.pick = pick->location});
      if (!r) {
        // Refused (nothing to separate on that side): nothing changed but the painted curve.
        m = before;
        continue;
      }
      check(m, "random cut");
      ++cuts;
    }
  }
  EXPECT_GE(cuts, 6);
}

TEST(Cut, OpenSurfacesAndAttributesOnTheRemovedSide) {
  // A visible stroke across an open saddle of quads separates it.
  Model m;
  (void)add_polygon_surface(m, "saddle",
                            grid(12, 10,
                                 [](double u, double v) {
                                   const double x = -1 + 2 * u, y = -1 + 2 * v;
                                   return Vec3d(x, y, 0.2 * x * y);
                                 })
                                .view())
      .value();
  const Camera cam = front_persp();
  auto feature = paint_stroke(m, cam, project(cam, {Vec3d(0.1, -1.3, 0), Vec3d(0.15, 1.3, 0)}));  // crosses the cut
  ASSERT_TRUE(feature);
  auto p = paint_stroke(m, cam, project(cam, {Vec3d(-1.3, 0.2, 0), Vec3d(1.3, -0.1, 0)}));
  ASSERT_TRUE(p);
  const double a0 = fan_area(m);
  auto pick = locate_pixel(m, cam, cam.project(Vec3d(0.3, 0.8, 0)).head<2>());
  auto r = cut_along_curves(m, edges_of(*p), {.pick = pick->location});
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_NEAR(r->removed_area + r->kept_area, a0, 1e-12 * a0);
  // The crossing curve lost its nodes on the removed side, kept the others.
  const AttribEdge fe = edges_of(*feature)[0];
  ASSERT_TRUE(m.alive(fe));
  for (AttribNodeIdx a : m.attrib_edges.nodes.row(fe.idx.value)) EXPECT_LT(m.attrib_position_on_surface(a).y(), 0.3);
  // The cut curve stays, on the new boundary.
  for (const AttribEdge& e : edges_of(*p)) EXPECT_TRUE(m.alive(e));
}

TEST(Partition, KDisjointClosedCurvesGiveKPlusOnePieces) {
  for (int k = 1; k <= 3; ++k) {
    SCOPED_TRACE(k);
    Model m = icosphere(4);
    const double a0 = fan_area(m);
    const Camera cam = front_persp();
    std::vector<AttribEdge> curves;
    const Vec3d centres[3] = {Vec3d(-0.45, 0.3, 0), Vec3d(0.4, 0.35, 0), Vec3d(0.0, -0.45, 0)};
    for (int i = 0; i < k; ++i) {
      auto p = paint_stroke(m, cam, ring_stroke(cam, centres[i], 0.25));
      ASSERT_TRUE(p) << p.status().to_string();
      ASSERT_TRUE(p->curves[0].closed);
      for (auto e : edges_of(*p)) curves.push_back(e);
    }
    auto r = partition_along_curves(m, curves);
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_TRUE(validate(m)) << validate(m).to_string();
    EXPECT_EQ(r->pieces.size(), static_cast<std::size_t>(k + 1));
    EXPECT_EQ(m.num_surfaces(), static_cast<std::size_t>(k + 1));
    EXPECT_EQ(m.num_joints(), static_cast<std::size_t>(k));
    EXPECT_EQ(r->new_surfaces.size(), static_cast<std::size_t>(k));
    double sum = 0;
    for (const Piece& pc : r->pieces) {
      sum += pc.area;
      EXPECT_NEAR(fan_area(m, pc.surface.idx), pc.area, 1e-12 * a0);
      EXPECT_EQ(count_topology(m, pc.surface.idx).components, 1);
    }
    EXPECT_NEAR(sum, a0, 1e-12 * a0);
    // Every joint: two members with equal edge counts, opposite directions,
    // coincident nodes (checked here directly, not only by validate()).
    for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
      if (!m.alive(JointIdx{j})) continue;
      const auto mem = m.joints.members.row(j);
      ASSERT_EQ(mem.size(), 2u);
      const auto c0 = m.mesh_edges.halfedges.row(mem[0].mesh_edge.value);
      const auto c1 = m.mesh_edges.halfedges.row(mem[1].mesh_edge.value);
      ASSERT_EQ(c0.size(), c1.size());
      EXPECT_NE(mem[0].positive, mem[1].positive);
      EXPECT_NE(m.mesh_edges.surface[mem[0].mesh_edge.value], m.mesh_edges.surface[mem[1].mesh_edge.value]);
      for (std::size_t t = 0; t < c0.size(); ++t) {
        EXPECT_EQ(m.position(m.tail(c0[t])), m.position(m.head(c1[c1.size() - 1 - t])));
        EXPECT_EQ(m.position(m.head(c0[t])), m.position(m.tail(c1[c1.size() - 1 - t])));
        EXPECT_TRUE(m.is_boundary(edge_of(c0[t])) && m.is_boundary(edge_of(c1[t])));
      }
      // A closed seam.
      EXPECT_EQ(m.tail(c0.front()), m.head(c0.back()));
    }
  }
}

TEST(Partition, CrossingCurvesGiveFourPiecesAroundOneNode) {
  Model m = icosphere(4);
  const double a0 = fan_area(m);
  const Camera cam = front_ortho();
  auto a = paint_stroke(m, cam, project(cam, {Vec3d(-1.5, 0.05, 0), Vec3d(1.5, 0.1, 0)}), {.through = true});
  auto b = paint_stroke(m, cam, project(cam, {Vec3d(0.1, -1.5, 0), Vec3d(0.05, 1.5, 0)}), {.through = true});
  ASSERT_TRUE(a && b);
  std::vector<AttribEdge> curves = edges_of(*a);
  for (auto e : edges_of(*b)) curves.push_back(e);
  auto r = partition_along_curves(m, curves);
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_EQ(r->pieces.size(), 4u);
  EXPECT_EQ(r->crossings, 2u);  // front and back
  double sum = 0;
  for (const Piece& pc : r->pieces) sum += pc.area;
  EXPECT_NEAR(sum, a0, 1e-12 * a0);
  // One seam per pair of neighbouring quarters, from one crossing to the
  // other: 4 open joints whose 8 ends meet 4 by 4 at the two crossings.
  ASSERT_EQ(m.num_joints(), 4u);
  std::vector<Vec3d> ends;
  for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
    if (!m.alive(JointIdx{j})) continue;
    const auto c = m.mesh_edges.halfedges.row(m.joints.members.row(j)[0].mesh_edge.value);
    EXPECT_NE(m.tail(c.front()), m.head(c.back()));
    ends.push_back(m.position(m.tail(c.front())));
    ends.push_back(m.position(m.head(c.back())));
  }
  for (const Vec3d& e : ends) {
    int same = 0;
    for (const Vec3d& f : ends) same += (e - f).norm() < 1e-12;
    EXPECT_EQ(same, 4);
  }
}

TEST(Partition, RefusalsChangeNothing) {
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  auto p = paint_stroke(m, cam, project(cam, {Vec3d(-1.5, 0.2, 0), Vec3d(1.5, 0.2, 0)}));
  ASSERT_TRUE(p);
  const Model before = m;
  auto r = partition_along_curves(m, edges_of(*p));
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("do not separate"), std::string::npos);
  EXPECT_EQ(diff_tables(before, m), "");
}

TEST(Cut, AJointOnTheRemovedSideIsRefused) {
  // Partition a cap off, then cut away the half holding part of its seam.
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  auto ring = paint_stroke(m, cam, ring_stroke(cam, Vec3d(0, 0.3, 0), 0.3));
  ASSERT_TRUE(ring);
  ASSERT_TRUE(partition_along_curves(m, edges_of(*ring)));
  auto p = paint_stroke(m, cam, project(cam, {Vec3d(-1.5, 0.25, 0), Vec3d(1.5, 0.3, 0)}), {.through = true}, {});
  ASSERT_TRUE(p) << p.status().to_string();
  const Model before = m;
  auto pick = locate_pixel(m, cam, cam.project(Vec3d(0.8, 0.45, 0)).head<2>(), std::vector<SurfaceIdx>{SurfaceIdx{0}});
  ASSERT_TRUE(pick);
  auto r = cut_along_curves(m, edges_of(*p), {.pick = pick->location});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), ErrorCode::kJointRefused) << r.status().to_string();
  EXPECT_EQ(diff_tables(before, m), "");
}

TEST(Partition, OtherCurvesAcrossASeamAreSplitPerSurface) {
  Model m = icosphere(4);
  const Camera cam = front_ortho();
  auto feature = paint_stroke(m, cam, project(cam, {Vec3d(-0.9, 0.05, 0), Vec3d(0.9, 0.1, 0)}), {.feature_id = 11});
  ASSERT_TRUE(feature);
  std::vector<Vec3d> before_pts;
  for (AttribNodeIdx a : m.attrib_edges.nodes.row(edges_of(*feature)[0].idx.value))
    before_pts.push_back(m.attrib_position_on_surface(a));
  auto ring = paint_stroke(m, cam, ring_stroke(cam, Vec3d(0.05, 0.0, 0), 0.4));
  ASSERT_TRUE(ring);
  auto r = partition_along_curves(m, edges_of(*ring));
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  // The feature curve now lies on two surfaces: one attribute edge per run.
  std::vector<AttribEdgeIdx> runs;
  for (std::uint32_t e = 0; e < m.attrib_edges.slots.capacity(); ++e)
    if (m.alive(AttribEdgeIdx{e}) && m.attrib_edges.feature_id[e] == 11) runs.push_back(AttribEdgeIdx{e});
  EXPECT_EQ(runs.size(), 3u);  // outside, inside the ring, outside
  std::size_t nodes = 0;
  for (AttribEdgeIdx e : runs) {
    nodes += m.attrib_edges.nodes.size(e.value);
    for (AttribNodeIdx a : m.attrib_edges.nodes.row(e.value)) {
      const Vec3d p = m.attrib_position_on_surface(a);
      double best = INFINITY;
      for (const Vec3d& q : before_pts) best = std::min(best, (p - q).norm());
      EXPECT_LT(best, 1e-12);  // every node still where the curve was
    }
  }
  EXPECT_GE(nodes, before_pts.size());
}
