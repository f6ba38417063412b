// Re-triangulation by painted curves (seed 002 section 3.1, Figs. 2-3).
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/sketch/cut.h>
#include <atelier/systems/sketch/paint.h>
#include <atelier/systems/sketch/retriangulate.h>
#include <gtest/gtest.h>

#include <random>

#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;

namespace {

/// Old nodes unmoved, area kept, every chain a connected path of mesh edges
/// whose nodes are the curve's attribute nodes.
void expect_clean(const Model& before, const Model& after, const RetriangulationResult& r,
                  std::span<const AttribEdge> curves) {
  ASSERT_TRUE(validate(after)) << validate(after).to_string();
  for (std::uint32_t v = 0; v < before.nodes.slots.capacity(); ++v)
    if (before.alive(NodeIdx{v})) {
      ASSERT_EQ(before.nodes.position[v], after.nodes.position[v]) << "node " << v;
    }
  const double a0 = fan_area(before), a1 = fan_area(after);
  EXPECT_NEAR(a1, a0, 1e-12 * a0);
  EXPECT_EQ(count_topology(after).implied_holes(), after.complex_holes);
  ASSERT_EQ(r.chains.size(), curves.size());
  for (std::size_t c = 0; c < curves.size(); ++c) {
    const auto& ch = r.chains[c];
    for (std::size_t k = 0; k < ch.size(); ++k) {
      ASSERT_TRUE(ch[k].valid() && after.alive(ch[k]));
      if (k + 1 < ch.size()) {
        EXPECT_EQ(after.head(ch[k]), after.tail(ch[k + 1]));
      }
    }
    for (AttribNodeIdx a : after.attrib_edges.nodes.row(curves[c].idx.value))
      EXPECT_EQ(after.attrib_nodes.kind[a.value], AttribNodeKind::kVertex);
  }
}

}  // namespace

TEST(Retriangulate, CurvesBecomeEdgesOldNodesStayAreaIsKept) {
  struct Case {
    const char* name;
    Model m;
  };
  std::vector<Case> cases;
  cases.push_back({"icosphere", icosphere(3)});
  {
    Model q;  // planar quads
    (void)add_polygon_surface(
        q, "plate", grid(9, 7, [](double u, double v) { return Vec3d(-1 + 2 * u, -1 + 2 * v, 0.2 * u); }).view())
        .value();
    cases.push_back({"quads", std::move(q)});
  }
  {
    Model q;  // non-planar quads (a saddle): the fan triangles' area is kept
    (void)add_polygon_surface(q, "saddle",
                              grid(9, 7,
                                   [](double u, double v) {
                                     const double x = -1 + 2 * u, y = -1 + 2 * v;
                                     return Vec3d(x, y, 0.3 * x * y);
                                   })
                                  .view())
        .value();
    cases.push_back({"saddle", std::move(q)});
  }
  for (Case& c : cases) {
    SCOPED_TRACE(c.name);
    for (const bool persp : {false, true}) {
      Model m = c.m;
      const Camera cam = persp ? front_persp() : front_ortho();
      std::vector<Vec3d> wave;
      for (int k = 0; k <= 30; ++k) wave.push_back(Vec3d(-1.3 + 2.6 * k / 30.0, 0.3 * std::sin(5.0 * k / 30.0), 0));
      auto p = paint_stroke(m, cam, project(cam, wave), {.through = true});
      ASSERT_TRUE(p) << p.status().to_string();
      const auto curves = edges_of(*p);
      // The traced 3D points, to compare with the new nodes.
      std::vector<std::vector<Vec3d>> traced;
      for (const AttribEdge& e : curves) {
        traced.emplace_back();
        for (AttribNodeIdx a : m.attrib_edges.nodes.row(e.idx.value))
          traced.back().push_back(m.attrib_nodes.position[a.value]);
      }
      const Model before = m;
      auto r = retriangulate_curves(m, curves);
      ASSERT_TRUE(r) << r.status().to_string();
      expect_clean(before, m, *r, curves);
      EXPECT_GT(r->faces_added, r->faces_removed);
      // No crossing here: the curve's nodes are the traced points.
      EXPECT_EQ(r->crossings, 0u);
      for (std::size_t c2 = 0; c2 < curves.size(); ++c2) {
        const auto row = m.attrib_edges.nodes.row(curves[c2].idx.value);
        ASSERT_EQ(row.size(), traced[c2].size());
        for (std::size_t k = 0; k < row.size(); ++k)
          EXPECT_LT((m.position(NodeIdx{m.attrib_nodes.element[row[k].value]}) - traced[c2][k]).norm(), 1e-9);
      }
    }
  }
}

// Fan triangles crossed by one chord are split without a CDT; the oracle
// is CGAL's CDT itself: the same curves re-triangulated with every fan
// through the CDT must give the same tables, on triangles (a sphere, two
// crossing strokes, perspective and orthographic) and on non-planar quads
// (chords across fan diagonals).
TEST(Retriangulate, ChordsWithoutACdtGiveTheCdtsTriangles) {
  std::vector<std::pair<const char*, Model>> cases;
  cases.emplace_back("icosphere", icosphere(4));
  {
    Model q;
    (void)add_polygon_surface(q, "saddle",
                              grid(13, 11,
                                   [](double u, double v) {
                                     const double x = -1 + 2 * u, y = -1 + 2 * v;
                                     return Vec3d(x, y, 0.3 * x * y);
                                   })
                                  .view())
        .value();
    cases.emplace_back("saddle", std::move(q));
  }
  for (auto& [name, model] : cases) {
    SCOPED_TRACE(name);
    for (const bool persp : {false, true}) {
      Model m = model;
      const Camera cam = persp ? front_persp() : front_ortho();
      std::vector<Vec3d> wave, slant;
      for (int k = 0; k <= 40; ++k) {
        const double t = k / 40.0;
        wave.push_back(Vec3d(-1.3 + 2.6 * t, 0.3 * std::sin(7.0 * t), 0));
        slant.push_back(Vec3d(-0.8 + 1.5 * t, -1.2 + 2.5 * t + 0.05 * std::cos(9.0 * t), 0));
      }
      std::vector<AttribEdge> curves;
      for (const auto& line : {wave, slant}) {
        auto p = paint_stroke(m, cam, project(cam, line), {.through = true});
        ASSERT_TRUE(p) << p.status().to_string();
        const auto e = edges_of(*p);
        curves.insert(curves.end(), e.begin(), e.end());
      }
      Model direct = m, cdt = m;
      auto a = retriangulate_curves(direct, curves);
      auto b = retriangulate_curves(cdt, curves, {.chords_without_cdt = false});
      ASSERT_TRUE(a) << a.status().to_string();
      ASSERT_TRUE(b) << b.status().to_string();
      EXPECT_GT(a->fans_without_cdt, 0u);
      EXPECT_EQ(b->fans_without_cdt, 0u);
      EXPECT_GT(a->crossings, 0u);
      EXPECT_EQ(a->faces_added, b->faces_added);
      EXPECT_EQ(a->chains, b->chains);
      EXPECT_EQ(diff_tables(direct, cdt), "");
      expect_clean(m, direct, *a, curves);
    }
  }
}

// The fans split without CGAL's CDT (one stroke point with its spokes, or
// chords between side points, then Lawson's flips) on random triangles:
// one or two random curves per triangle, made of points on its sides, one
// inside it and its corners (two curves may cross, which adds an inner
// point with four spokes). The oracle is CGAL's CDT of the same fans
// (`chords_without_cdt = false`): same tables (random points: no four are
// cocircular, so the CDT is unique), or the same refusal with the model
// unchanged; and independently of it, a valid model, the area kept to
// 1e-12 and every new face turned as the old one (no fold).
TEST(Retriangulate, DirectSplitsAreTheCdtOnRandomFaces) {
  std::mt19937 rng(20);
  std::uniform_real_distribution<double> unit(0.0, 1.0), coord(-1.0, 1.0);
  std::size_t direct = 0, succeeded = 0;
  for (int trial = 0; trial < 600; ++trial) {
    SCOPED_TRACE(trial);
    Model m;
    const std::vector<Vec3d> corners = {Vec3d(coord(rng), coord(rng), coord(rng)),
                                        Vec3d(coord(rng), coord(rng), coord(rng)),
                                        Vec3d(coord(rng), coord(rng), coord(rng))};
    const Vec3d normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    if (normal.norm() < 0.05) continue;
    const std::vector<std::uint32_t> off{0, 3}, idx{0, 1, 2};
    const Surface surface = add_polygon_surface(m, "t", PolygonSoupView{corners, off, idx}).value();
    const SurfaceIdx s = m.resolve(surface).value();
    FaceIdx f;
    for (std::uint32_t x = 0; x < m.faces.slots.capacity(); ++x)
      if (m.alive(FaceIdx{x})) f = FaceIdx{x};
    std::vector<HalfedgeIdx> hs;
    m.face_halfedges(f, hs);
    auto on_side = [&](int side) {  // side i runs from corner i to corner i + 1
      const double u = 0.05 + 0.9 * unit(rng);
      const HalfedgeIdx h = hs[side % 3];
      const Vec3d x = (1 - u) * m.position(m.tail(h)) + u * m.position(m.head(h));
      return m.new_attrib_node(s, AttribNodeKind::kEdge, h.value, Vec3d(u, 0, 0), x);
    };
    auto inside = [&] {
      Vec3d b(0.05 + unit(rng), 0.05 + unit(rng), 0.05 + unit(rng));
      b /= b.sum();
      Vec3d x = Vec3d::Zero();
      for (int i = 0; i < 3; ++i) x += b[i] * m.position(m.tail(hs[i]));
      return m.new_attrib_node(s, AttribNodeKind::kFace, f.value, b, x);
    };
    auto corner = [&](int i) {
      const NodeIdx v = m.tail(hs[i % 3]);
      return m.new_attrib_node(s, AttribNodeKind::kVertex, v.value, Vec3d::Zero(), m.position(v));
    };
    std::vector<AttribEdge> curves;
    const int count = 1 + (trial % 3 == 2);
    for (int c = 0; c < count; ++c) {
      const int i = static_cast<int>(rng() % 3), j = static_cast<int>(rng() % 3);
      std::vector<AttribNodeIdx> row;
      switch (rng() % 5) {
        case 0:  // across, through a stroke point (both ends may be on one side)
          row = {on_side(i), inside(), on_side(j)};
          break;
        case 1:  // a chord from side to side
          row = {on_side(i), on_side(i + 1 + j % 2)};
          break;
        case 2:  // from a corner to the opposite side
          row = {corner(i), on_side(i + 1)};
          break;
        case 3:  // ending at a stroke point
          row = {on_side(i), inside()};
          break;
        default:  // from a stroke point to a corner
          row = {inside(), corner(i)};
          break;
      }
      curves.push_back(m.handle(m.new_attrib_edge(s, -1, row)));
    }
    Model a = m, b = m;
    auto ra = retriangulate_curves(a, curves);
    auto rb = retriangulate_curves(b, curves, {.chords_without_cdt = false});
    ASSERT_EQ(ra.has_value(), rb.has_value()) << (ra ? rb.status() : ra.status()).to_string();
    if (!ra) {
      EXPECT_EQ(ra.status().code(), rb.status().code());
      EXPECT_EQ(diff_tables(a, m), "");
      continue;
    }
    ++succeeded;
    // One curve: one stroke point with its spokes, or one chord: always direct.
    if (count == 1) {
      EXPECT_EQ(ra->fans_without_cdt, 1u);
    }
    direct += ra->fans_without_cdt;
    EXPECT_EQ(rb->fans_without_cdt, 0u);
    ASSERT_TRUE(validate(a)) << validate(a).to_string();
    const double a0 = fan_area(m), a1 = fan_area(a);
    EXPECT_NEAR(a1, a0, 1e-12 * a0);
    std::vector<NodeIdx> c;
    for (std::uint32_t x = 0; x < a.faces.slots.capacity(); ++x) {
      if (!a.alive(FaceIdx{x})) continue;
      a.face_nodes(FaceIdx{x}, c);
      ASSERT_EQ(c.size(), 3u);
      EXPECT_GT((a.position(c[1]) - a.position(c[0])).cross(a.position(c[2]) - a.position(c[0])).dot(normal), 0.0)
          << "face " << x << " is folded";
    }
    EXPECT_EQ(diff_tables(a, b), "");
  }
  // Most random configurations succeed; two curves (two stroke points, or a
  // chord beside a stroke point, in one triangle) may still take the CDT.
  EXPECT_GT(succeeded, 400u);
  EXPECT_GT(direct, succeeded / 2);
}

TEST(Retriangulate, TwoCrossingCurvesShareOneNode) {
  Model m = icosphere(3);
  const Camera cam = front_persp();
  auto a = paint_stroke(m, cam, project(cam, {Vec3d(-1.3, 0.1, 0), Vec3d(1.3, -0.05, 0)}));
  auto b = paint_stroke(m, cam, project(cam, {Vec3d(0.15, -1.3, 0), Vec3d(-0.1, 1.3, 0)}));
  ASSERT_TRUE(a && b);
  std::vector<AttribEdge> curves = edges_of(*a);
  for (auto e : edges_of(*b)) curves.push_back(e);
  ASSERT_EQ(curves.size(), 2u);
  const Model before = m;
  auto r = retriangulate_curves(m, curves);
  ASSERT_TRUE(r) << r.status().to_string();
  expect_clean(before, m, *r, curves);
  EXPECT_EQ(r->crossings, 1u);
  std::vector<NodeIdx> na = r->nodes[0], nb = r->nodes[1];
  std::sort(na.begin(), na.end());
  std::sort(nb.begin(), nb.end());
  std::vector<NodeIdx> common;
  std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
  ASSERT_EQ(common.size(), 1u);
  EXPECT_EQ(m.degree(common[0]), 4u);  // both curves pass through it
  // Both attribute edges hold a node on it.
  for (const AttribEdge& e : curves) {
    bool has = false;
    for (AttribNodeIdx x : m.attrib_edges.nodes.row(e.idx.value))
      has |= m.attrib_nodes.element[x.value] == common[0].value;
    EXPECT_TRUE(has);
  }
  // The crossing lies on both strokes' planes: it projects onto both.
  const Vec2d px = cam.project(m.position(common[0])).head<2>();
  EXPECT_LT(distance_to_polyline(project(cam, {Vec3d(-1.3, 0.1, 0), Vec3d(1.3, -0.05, 0)}), px), 1e-6);
  EXPECT_LT(distance_to_polyline(project(cam, {Vec3d(0.15, -1.3, 0), Vec3d(-0.1, 1.3, 0)}), px), 1e-6);
}

TEST(Retriangulate, OtherAttributesStayWhereTheyWere) {
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  // A feature-like curve painted first, then the curve to re-triangulate
  // across it: the first one's nodes (face and edge nodes) keep their 3D places.
  auto feat = paint_stroke(m, cam, project(cam, {Vec3d(0.05, -1.3, 0), Vec3d(0.02, 1.3, 0)}));
  auto cut = paint_stroke(m, cam, project(cam, {Vec3d(-1.3, 0.1, 0), Vec3d(1.3, 0.12, 0)}));
  ASSERT_TRUE(feat && cut);
  std::vector<std::pair<AttribNodeIdx, Vec3d>> where;
  for (auto e : edges_of(*feat))
    for (AttribNodeIdx a : m.attrib_edges.nodes.row(e.idx.value))
      where.emplace_back(a, m.attrib_position_on_surface(a));
  const SurfaceLocation probe{AttribNodeKind::kFace, where[where.size() / 2].first.value, Vec3d(0.2, 0.3, 0.5), 0};
  RetriangulateOptions opt;
  // A probe in a face of the first curve: followed into the new faces.
  std::vector<NodeIdx> fc;
  const FaceIdx pf{m.attrib_nodes.kind[where[1].first.value] == AttribNodeKind::kFace
                       ? m.attrib_nodes.element[where[1].first.value]
                       : 0};
  m.face_nodes(pf, fc);
  const Vec3d probe_at = 0.2 * m.position(fc[0]) + 0.3 * m.position(fc[1]) + 0.5 * m.position(fc[2]);
  opt.probes.push_back({AttribNodeKind::kFace, pf.value, Vec3d(0.2, 0.3, 0.5), 0});
  (void)probe;
  const Model before = m;
  auto r = retriangulate_curves(m, edges_of(*cut), opt);
  ASSERT_TRUE(r) << r.status().to_string();
  expect_clean(before, m, *r, edges_of(*cut));
  for (const auto& [a, p] : where) EXPECT_LT((m.attrib_position_on_surface(a) - p).norm(), 1e-12);
  ASSERT_EQ(r->probes.size(), 1u);
  const SurfaceLocation& l = r->probes[0];
  ASSERT_EQ(l.kind, AttribNodeKind::kFace);
  m.face_nodes(FaceIdx{l.element}, fc);
  EXPECT_LT(
      (l.param[0] * m.position(fc[0]) + l.param[1] * m.position(fc[1]) + l.param[2] * m.position(fc[2]) - probe_at)
          .norm(),
      1e-12);
}

TEST(Retriangulate, JointsStayCrackFree) {
  // Partition first (a joint along a ring), then re-triangulate a curve that
  // crosses the joint: the partner edges are split at the same places.
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  std::vector<Vec3d> ring;
  for (int k = 0; k <= 32; ++k)
    ring.push_back(Vec3d(0.45 * std::cos(2 * M_PI * k / 32), 0.45 * std::sin(2 * M_PI * k / 32), 0));
  auto rs = project(cam, ring);
  rs.back() = rs.front();
  auto p = paint_stroke(m, cam, rs);
  ASSERT_TRUE(p);
  ASSERT_TRUE(partition_along_curves(m, edges_of(*p)));
  ASSERT_EQ(m.num_joints(), 1u);
  auto q = paint_stroke(m, cam, project(cam, {Vec3d(-0.9, 0.07, 0), Vec3d(0.9, 0.03, 0)}));
  ASSERT_TRUE(q);
  const auto joint_len = [&] { return m.mesh_edges.halfedges.size(m.joints.members.row(0)[0].mesh_edge.value); };
  const std::size_t len0 = joint_len();
  const Model before = m;
  auto r = retriangulate_curves(m, edges_of(*q));
  ASSERT_TRUE(r) << r.status().to_string();
  expect_clean(before, m, *r, edges_of(*q));  // validate() checks equal counts and coincident nodes
  EXPECT_EQ(joint_len(), len0 + 2);           // crossed twice
}

TEST(Retriangulate, FailuresChangeNothing) {
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  const auto stroke = project(cam, {Vec3d(-1.3, 0.1, 0), Vec3d(1.3, 0.12, 0)});
  auto a = paint_stroke(m, cam, stroke);
  auto b = paint_stroke(m, cam, stroke);  // the same curve again: they overlap
  ASSERT_TRUE(a && b);
  std::vector<AttribEdge> both = edges_of(*a);
  for (auto e : edges_of(*b)) both.push_back(e);
  const Model before = m;
  auto r = retriangulate_curves(m, both);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), ErrorCode::kDegenerate);
  EXPECT_NE(r.status().message().find("overlap"), std::string::npos) << r.status().message();
  EXPECT_EQ(diff_tables(before, m), "");
  // A stale curve.
  Model m2 = before;
  m2.delete_attrib_edge(edges_of(*a)[0].idx);
  auto s = retriangulate_curves(m2, edges_of(*a));
  ASSERT_FALSE(s);
  EXPECT_EQ(s.status().code(), ErrorCode::kStaleHandle);
  // A probe off the model.
  RetriangulateOptions opt;
  opt.probes.push_back({AttribNodeKind::kFace, 999999, Vec3d(1, 0, 0), 0});
  auto t = retriangulate_curves(m, edges_of(*a), opt);
  ASSERT_FALSE(t);
  EXPECT_EQ(diff_tables(before, m), "");
}

TEST(Retriangulate, CurvesAlongEdgesAndThroughVertices) {
  // A grid whose lines the strokes follow exactly: curve points on nodes and
  // curve segments along edges (no new faces needed there).
  Model m;
  (void)add_polygon_surface(m, "plate",
                            grid(
                                8, 8, [](double u, double v) { return Vec3d(-1 + 2 * u, -1 + 2 * v, 0); }, true)
                                .view())
      .value();
  const Camera cam = Camera::orthographic(Vec3d(0, 0, 5), Vec3d::Zero(), Vec3d::UnitY(), 2.0, 800, 800);
  auto a = paint_stroke(m, cam, project(cam, {Vec3d(-1.5, 0, 0), Vec3d(1.5, 0, 0)}));
  auto b = paint_stroke(m, cam, project(cam, {Vec3d(-1.5, -1.5, 0), Vec3d(1.5, 1.5, 0)}));
  ASSERT_TRUE(a && b);
  std::vector<AttribEdge> curves = edges_of(*a);
  for (auto e : edges_of(*b)) curves.push_back(e);
  const Model before = m;
  auto r = retriangulate_curves(m, curves);
  ASSERT_TRUE(r) << r.status().to_string();
  expect_clean(before, m, *r, curves);
  EXPECT_EQ(r->nodes_added, 0u);  // every curve point is a grid node
  EXPECT_EQ(r->chains[0].size(), 8u);
  EXPECT_EQ(r->chains[1].size(), 8u);
}

TEST(Retriangulate, DegenerateFacesAreRefusedCleanly) {
  // A strip of triangles with one of zero area (three collinear nodes) in
  // the stroke's way: painting goes through, re-triangulating refuses it.
  Soup s;
  s.p = {Vec3d(-1, -1, 0), Vec3d(0, -1, 0), Vec3d(1, -1, 0), Vec3d(-1, 1, 0),
         Vec3d(0, 1, 0),   Vec3d(1, 1, 0),  Vec3d(0, 0, 0)};
  s.face({0, 1, 4});
  s.face({0, 4, 3});
  s.face({1, 2, 5});
  s.face({1, 5, 4});
  // Node 6 lies on edge 1-4 only geometrically: the face (1, 6, 4) has no area.
  Model m;
  (void)add_polygon_surface(m, "strip", s.view()).value();
  (void)add_polygon_surface(m, "sliver",
                            PolygonSoupView{s.p, std::vector<std::uint32_t>{0, 3}, std::vector<std::uint32_t>{1, 6, 4}})
      .value();
  const Camera cam = Camera::orthographic(Vec3d(0, 0, 5), Vec3d::Zero(), Vec3d::UnitY(), 2.0, 400, 400);
  auto p = paint_stroke(m, cam, project(cam, {Vec3d(-1.5, 0.1, 0), Vec3d(1.5, 0.12, 0)}), {.through = true});
  ASSERT_TRUE(p) << p.status().to_string();
  const Model before = m;
  auto r = retriangulate_curves(m, edges_of(*p));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), ErrorCode::kDegenerate);
  EXPECT_NE(r.status().message().find("no area"), std::string::npos) << r.status().message();
  EXPECT_EQ(diff_tables(before, m), "");
}
