// Painting and penetrated painting (seed 001 section 5, Figs. 9-11) with
// strokes made by projecting known 3D curves.
#include <atelier/storage/validate.h>
#include <atelier/systems/sketch/cut.h>
#include <atelier/systems/sketch/paint.h>
#include <gtest/gtest.h>

#include <cmath>

#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;

namespace {

/// Position of a surface location, computed independently of the painter.
Vec3d position_of(const Model& m, const CurvePoint& p) {
  const SurfaceLocation& l = p.location;
  if (l.kind == AttribNodeKind::kEdge) {
    const HalfedgeIdx h{l.element};
    return (1 - l.param.x()) * m.position(m.tail(h)) + l.param.x() * m.position(m.head(h));
  }
  if (l.kind == AttribNodeKind::kVertex) return m.position(NodeIdx{l.element});
  std::vector<NodeIdx> c;
  m.face_nodes(FaceIdx{l.element}, c);
  return l.param[0] * m.position(c[0]) + l.param[1] * m.position(c[l.corner + 1]) +
         l.param[2] * m.position(c[l.corner + 2]);
}

/// Every point lies in its element, in the plane through the eye and its
/// stroke segment (or on the ray of its stroke point), and projects back
/// onto the stroke.
void expect_on_stroke(const Model& m, const Camera& cam, const std::vector<Vec2d>& stroke, const TracedCurve& c,
                      double scale) {
  for (const CurvePoint& p : c.points) {
    const SurfaceLocation& l = p.location;
    if (l.kind == AttribNodeKind::kEdge) {
      ASSERT_TRUE(m.alive(HalfedgeIdx{l.element}));
      EXPECT_GE(l.param.x(), 0.0);
      EXPECT_LE(l.param.x(), 1.0);
    } else {
      ASSERT_EQ(l.kind, AttribNodeKind::kFace);
      ASSERT_TRUE(m.alive(FaceIdx{l.element}));
      EXPECT_LE(l.corner + 3u, m.face_degree(FaceIdx{l.element}));
      EXPECT_GE(l.param.minCoeff(), 0.0);
      EXPECT_NEAR(l.param.sum(), 1.0, 1e-12);
    }
    EXPECT_LT((position_of(m, p) - p.position).norm(), 1e-12 * scale);
    EXPECT_EQ(m.faces.surface[l.kind == AttribNodeKind::kFace          ? l.element
                              : m.face(HalfedgeIdx{l.element}).valid() ? m.face(HalfedgeIdx{l.element}).value
                                                                       : m.face(twin(HalfedgeIdx{l.element})).value],
              p.surface);
    // The plane through the rays of the segment's ends (through the eye
    // for a perspective camera).
    const auto i = std::min<std::size_t>(static_cast<std::size_t>(std::floor(p.s)), stroke.size() - 2);
    const auto [o0, d0] = cam.ray(stroke[i]);
    const auto [o1, d1] = cam.ray(stroke[i + 1]);
    const Vec3d a = o0, b = o0 + 5 * scale * d0, c1 = o1 + 5 * scale * d1;
    const Vec3d n = (b - a).cross(c1 - a).normalized();
    EXPECT_LT(std::abs(n.dot(p.position - a)), 1e-9 * scale) << "s = " << p.s;
    if (p.s == std::floor(p.s)) {  // a stroke point: on its ray
      const auto [o, d] = cam.ray(stroke[static_cast<std::size_t>(p.s)]);
      EXPECT_LT((p.position - o - (p.position - o).dot(d) * d).norm(), 1e-9 * scale);
    }
    EXPECT_LT(distance_to_polyline(stroke, cam.project(p.position).head<2>()), 1e-6);
  }
}

double max_edge(const Model& m) {
  double h = 0;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e)
    if (m.alive(EdgeIdx{e}))
      h = std::max(
          h, (m.position(m.head(halfedge_of(EdgeIdx{e}, 0))) - m.position(m.tail(halfedge_of(EdgeIdx{e}, 0)))).norm());
  return h;
}

double total_length(const TraceResult& r) {
  double l = 0;
  for (const auto& c : r.curves) l += c.length();
  return l;
}

/// Visible arc of the circle cut from the sphere (centre C, radius R) by the
/// plane through the eye E with unit normal n: points whose outward normal
/// faces the eye, 2 r' acos(-A / B) long.
double visible_arc(const Vec3d& C, double R, const Vec3d& E, const Vec3d& n) {
  const double d = n.dot(E - C);
  const Vec3d cc = C + d * n;
  const double r = std::sqrt(R * R - d * d);
  const Vec3d ec = E - C, in_plane = ec - ec.dot(n) * n;
  const double A = (cc - C).dot(ec) - R * R, B = r * in_plane.norm();
  return 2 * r * std::acos(std::clamp(-A / B, -1.0, 1.0));
}

}  // namespace

TEST(Paint, PointsLieInTheirFacesAndStrokePlanes) {
  for (const bool persp : {false, true}) {
    const Model m = icosphere(3);
    const Camera cam = persp ? front_persp() : front_ortho();
    // A wavy curve drawn on the visible side of the sphere, projected.
    std::vector<Vec3d> curve;
    for (int k = 0; k <= 24; ++k) {
      const double t = -0.8 + 1.6 * k / 24.0;
      curve.push_back(Vec3d(t, 0.3 * std::sin(3 * t), 0));
    }
    const auto stroke = project(cam, curve);
    for (const bool through : {false, true}) {
      auto r = trace_stroke(m, cam, stroke, {.through = through});
      ASSERT_TRUE(r) << r.status().to_string();
      ASSERT_GE(r->curves.size(), through ? 2u : 1u);
      for (const auto& c : r->curves) expect_on_stroke(m, cam, stroke, c, 1.0);
      // Visible painting: the curve runs from the first stroke point to the
      // last (both on the sphere), monotone along the stroke.
      if (!through) {
        const TracedCurve& c = r->curves[0];
        EXPECT_EQ(c.points.front().s, 0.0);
        EXPECT_EQ(c.points.back().s, double(stroke.size() - 1));
        for (std::size_t k = 1; k < c.points.size(); ++k) EXPECT_GE(c.points[k].s, c.points[k - 1].s);
        // Front side: every point faces the eye.
        const Vec3d eye = cam.frame()->eye;
        for (const auto& p : c.points) EXPECT_GT(p.position.dot(eye - p.position), -1e-3);
      }
    }
  }
}

TEST(Paint, StraightStrokeAcrossASphereGivesThePlaneSphereCircle) {
  // Orthographic: the sheet is the plane y = y0; the circle has radius
  // sqrt(1 - y0^2); painting gives its front half, penetrated painting all of it.
  const double y0 = 0.23;
  const double rr = std::sqrt(1 - y0 * y0);
  double last_vis = INFINITY, last_all = INFINITY;
  for (int level = 2; level <= 5; ++level) {
    Model m = icosphere(level);
    const Camera cam = front_ortho();
    const auto stroke = project(cam, {Vec3d(-1.4, y0, 0), Vec3d(1.4, y0, 0)});
    auto vis = trace_stroke(m, cam, stroke);
    auto all = trace_stroke(m, cam, stroke, {.through = true});
    ASSERT_TRUE(vis && all);
    ASSERT_EQ(vis->curves.size(), 1u);
    EXPECT_EQ(all->curves.size(), 2u);  // front and back: layers split where the stroke turns back
    for (const auto* r : {&*vis, &*all})
      for (const auto& c : r->curves)
        for (const auto& p : c.points) {
          EXPECT_NEAR(p.position.y(), y0, 1e-12);     // in the plane
          EXPECT_LE(p.position.norm(), 1.0 + 1e-12);  // on the chords of the sphere
          EXPECT_GT(p.position.norm(), 1.0 - 0.02 / (1 << (level - 2)) / (1 << (level - 2)));
        }
    // The front half, up to the mesh's own silhouette (within an edge of z = 0).
    const double h = max_edge(m);
    for (const auto& p : vis->curves[0].points) EXPECT_GE(p.position.z(), -h);
    const double e_vis = std::abs(vis->curves[0].length() - M_PI * rr) / (M_PI * rr);
    const double e_all = std::abs(total_length(*all) - 2 * M_PI * rr) / (2 * M_PI * rr);
    EXPECT_LT(e_vis, last_vis / 3);  // second order (the silhouettes are symmetric here)
    EXPECT_LT(e_all, last_all / 3);
    last_vis = e_vis;
    last_all = e_all;
  }
  EXPECT_LT(last_vis, 2e-4);
  EXPECT_LT(last_all, 2e-4);
}

TEST(Paint, PerspectiveStrokeGivesTheVisibleArc) {
  // The plane through the eye and the stroke cuts the sphere in a circle;
  // the painted curve is the part facing the eye. Penetrated painting's
  // whole circle converges at second order; the visible arc ends at the
  // mesh's silhouette, within an edge of the sphere's.
  const Vec3d eye(0.3, 0.2, 4);
  const Camera cam = front_persp(eye);
  const Vec3d p1(-2, 0.3, 0), p2(2, 0.1, 0);
  const Vec3d n = (p1 - eye).cross(p2 - eye).normalized();
  const double arc = visible_arc(Vec3d::Zero(), 1.0, eye, n);
  const double d = n.dot(eye), circle = 2 * M_PI * std::sqrt(1 - d * d);
  double last = INFINITY;
  for (int level = 2; level <= 6; ++level) {
    Model m = icosphere(level);
    const auto stroke = project(cam, {p1, p2});
    auto vis = trace_stroke(m, cam, stroke);
    auto all = trace_stroke(m, cam, stroke, {.through = true});
    ASSERT_TRUE(vis && all) << vis.status().to_string();
    for (const auto* r : {&*vis, &*all})
      for (const auto& c : r->curves)
        for (const auto& p : c.points) EXPECT_LT(std::abs(n.dot(p.position - eye)), 1e-12);
    EXPECT_LT(std::abs(vis->curves[0].length() - arc), 2 * max_edge(m)) << "level " << level;
    const double e = std::abs(total_length(*all) - circle) / circle;
    EXPECT_LT(e, last / 3) << "level " << level;  // second order: ~4x per level
    last = e;
  }
  EXPECT_LT(last, 1e-4);
}

TEST(Paint, AFoldMakesPaintingFailWhilePenetratedPaintingKeepsEveryLayer) {
  Model m = z_fold();
  ASSERT_TRUE(validate(m));
  const Camera cam = front_ortho();
  const auto stroke = project(cam, {Vec3d(-1.2, 0.1, 0), Vec3d(0, 0.12, 0), Vec3d(1.2, 0.1, 0)});
  const Model before = m;
  auto r = paint_stroke(m, cam, stroke);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), ErrorCode::kDegenerate);
  EXPECT_NE(r.status().message().find("fold"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("stroke point"), std::string::npos);
  EXPECT_EQ(diff_tables(before, m), "");
  auto t = paint_stroke(m, cam, stroke, {.through = true});
  ASSERT_TRUE(t) << t.status().to_string();
  EXPECT_EQ(t->curves.size(), 3u);  // panel A, the folded-back panel B, panel C
  EXPECT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_EQ(m.num_attrib_edges(), 3u);
  // The three layers cover x in [-1, 0.5], [-0.5, 0.5] and [-0.5, 1].
  double sum = 0;
  for (const auto& c : t->curves) sum += c.length;
  EXPECT_NEAR(sum, 1.5 + std::hypot(1.0, 0.5) + std::hypot(1.5, 0.5), 0.05);
}

TEST(Paint, AnOccludingPartMakesPaintingFail) {
  // A sphere with a thin strap in front of it (another surface); the stroke
  // points all lie on the sphere, the strap passes between two of them.
  Model m = icosphere(3);
  (void)add_polygon_surface(
      m, "strap", grid(2, 10, [](double u, double v) { return Vec3d(0.45 + 0.1 * u, -1.2 + 2.4 * v, 1.5); }).view())
      .value();
  const Camera cam = front_ortho();
  const auto stroke = project(cam, {Vec3d(-0.8, 0.1, 0), Vec3d(0.2, 0.1, 0), Vec3d(0.8, 0.1, 0)});
  auto r = trace_stroke(m, cam, stroke);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("behind another part"), std::string::npos) << r.status().message();
  // Painting only on the sphere, the strap does not count.
  auto s = trace_stroke(m, cam, stroke, {.surfaces = {SurfaceIdx{0}}});
  ASSERT_TRUE(s) << s.status().to_string();
  // A stroke that leaves the sphere and comes back onto the strap: a gap.
  const auto gap = project(cam, {Vec3d(-0.8, 0.1, 0), Vec3d(0.2, 0.1, 0), Vec3d(0.8, 1.15, 0)});
  auto g = trace_stroke(m, cam, gap);
  ASSERT_FALSE(g);
}

TEST(Paint, StrokesThroughVerticesAndAlongEdges) {
  // A planar grid whose nodes project exactly onto pixel centres; strokes
  // along a grid line and through grid nodes diagonally.
  Model m;
  (void)add_polygon_surface(m, "plate",
                            grid(
                                8, 8, [](double u, double v) { return Vec3d(-1 + 2 * u, -1 + 2 * v, 0); }, true)
                                .view())
      .value();
  const Camera cam = Camera::orthographic(Vec3d(0, 0, 5), Vec3d::Zero(), Vec3d::UnitY(), 2.0, 800, 800);
  for (const auto& pts : {std::vector<Vec3d>{Vec3d(-1.5, 0, 0), Vec3d(1.5, 0, 0)},            // along edges
                          std::vector<Vec3d>{Vec3d(-1.5, -1.5, 0), Vec3d(1.5, 1.5, 0)},       // through nodes
                          std::vector<Vec3d>{Vec3d(-0.5, -0.5, 0), Vec3d(0.25, 0.75, 0)}}) {  // from node to node
    const auto stroke = project(cam, pts);
    for (const bool through : {false, true}) {
      auto r = trace_stroke(m, cam, stroke, {.through = through});
      ASSERT_TRUE(r) << r.status().to_string();
      ASSERT_EQ(r->curves.size(), 1u);
      const auto& c = r->curves[0];
      expect_on_stroke(m, cam, stroke, c, 1.0);
      // The whole visible part of the straight stroke: from its start or
      // the plate's boundary to its end or the boundary.
      const Vec3d a = c.points.front().position, b = c.points.back().position;
      EXPECT_NEAR(c.length(), (b - a).norm(), 1e-12);
      EXPECT_TRUE(std::abs(a.x()) >= 1 - 1e-12 || std::abs(a.y()) >= 1 - 1e-12 || (a - pts[0]).norm() < 1e-12);
    }
  }
}

TEST(Paint, ClosedStrokesGiveClosedCurvesAndStoreThem) {
  Model m = icosphere(3);
  const Camera cam = front_persp();
  std::vector<Vec3d> ring;
  for (int k = 0; k <= 30; ++k)
    ring.push_back(Vec3d(0.3 * std::cos(2 * M_PI * k / 30), 0.3 * std::sin(2 * M_PI * k / 30), 0.9));
  auto stroke = project(cam, ring);
  stroke.back() = stroke.front();
  auto r = paint_stroke(m, cam, stroke, {.feature_id = 7});
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_EQ(r->curves.size(), 1u);
  EXPECT_TRUE(r->curves[0].closed);
  ASSERT_EQ(r->curves[0].edges.size(), 1u);
  const AttribEdge e = r->curves[0].edges[0];
  const auto row = m.attrib_edges.nodes.row(e.idx.value);
  EXPECT_EQ(row.front(), row.back());  // a closed ATTRIB_EDGE repeats its first node
  EXPECT_EQ(m.attrib_edges.feature_id[e.idx.value], 7);
  EXPECT_TRUE(validate(m)) << validate(m).to_string();
  for (AttribNodeIdx a : row)
    EXPECT_LT((m.attrib_position_on_surface(a) - m.attrib_nodes.position[a.value]).norm(), 1e-12);
  // Penetrated: the front ring and the back ring.
  auto t = trace_stroke(m, cam, stroke, {.through = true});
  ASSERT_TRUE(t);
  ASSERT_EQ(t->curves.size(), 2u);
  EXPECT_TRUE(t->curves[0].closed && t->curves[1].closed);
}

TEST(Paint, BadInputIsRefusedAndChangesNothing) {
  Model m = icosphere(2);
  const Model before = m;
  const Camera cam = front_ortho();
  auto miss = paint_stroke(m, cam, project(cam, {Vec3d(-1.4, 1.3, 0), Vec3d(1.4, 1.3, 0)}));
  ASSERT_FALSE(miss);
  EXPECT_NE(miss.status().message().find("crosses no face"), std::string::npos);
  auto one = paint_stroke(m, cam, std::vector<Vec2d>{{3, 4}, {3, 4}});
  ASSERT_FALSE(one);
  EXPECT_EQ(one.status().code(), ErrorCode::kInvalidArgument);
  auto nan = paint_stroke(m, cam, std::vector<Vec2d>{{3, 4}, {NAN, 4}});
  ASSERT_FALSE(nan);
  Camera bad = cam;
  bad.projection.setZero();
  auto sing = paint_stroke(m, bad, std::vector<Vec2d>{{3, 4}, {5, 4}});
  ASSERT_FALSE(sing);
  EXPECT_NE(sing.status().message().find("singular"), std::string::npos);
  auto dead = paint_stroke(m, cam, std::vector<Vec2d>{{3, 4}, {500, 400}}, {.surfaces = {SurfaceIdx{5}}});
  ASSERT_FALSE(dead);
  EXPECT_EQ(diff_tables(before, m), "");
  // A mesh partly behind a perspective eye is painted where it is in front.
  const Camera inside = Camera::look_at(Vec3d(0, 0, 0.5), Vec3d(0, 0, -1), Vec3d::UnitY(), 90, 400, 400);
  auto in = trace_stroke(m, inside, std::vector<Vec2d>{{10, 200}, {390, 200}});
  ASSERT_TRUE(in) << in.status().to_string();
  for (const auto& p : in->curves[0].points) EXPECT_LT(p.position.z(), 0.5);
}

TEST(Paint, PickFindsTheNearestSurface) {
  Model m = icosphere(3);
  const Camera cam = front_persp();
  auto p = locate_pixel(m, cam, cam.project(Vec3d(0.2, 0.3, 0.5)).head<2>());
  ASSERT_TRUE(p);
  EXPECT_GT(p->position.z(), 0.8);  // the front of the sphere, not the back
  EXPECT_NEAR(p->position.norm(), 1.0, 0.02);
  auto off = locate_pixel(m, cam, Vec2d(1, 1));
  ASSERT_FALSE(off);
}

TEST(Paint, SameBitsForOneAndTwoThreads) {
  const Model m = icosphere(5);  // 20480 faces: several parallel chunks
  const Camera cam = front_persp();
  std::vector<Vec3d> curve;
  for (int k = 0; k <= 200; ++k) {
    const double t = -1.3 + 2.6 * k / 200.0;
    curve.push_back(Vec3d(t, 0.4 * std::sin(4 * t), 0));
  }
  const auto stroke = project(cam, curve);
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 1;
  for (const bool through : {false, true}) {
    auto a = trace_stroke(m, cam, stroke, {.through = through}, one);
    auto b = trace_stroke(m, cam, stroke, {.through = through}, two);
    ASSERT_TRUE(a && b);
    ASSERT_EQ(a->curves.size(), b->curves.size());
    for (std::size_t c = 0; c < a->curves.size(); ++c) {
      ASSERT_EQ(a->curves[c].points.size(), b->curves[c].points.size());
      for (std::size_t k = 0; k < a->curves[c].points.size(); ++k) {
        EXPECT_EQ(a->curves[c].points[k].position, b->curves[c].points[k].position);
        EXPECT_EQ(a->curves[c].points[k].location.element, b->curves[c].points[k].location.element);
      }
    }
  }
}

TEST(Paint, CurvesCrossJointsBetweenSurfaces) {
  // Partition a sphere along a closed curve, then paint across the seam:
  // the curve continues on the other surface (one attribute edge per surface).
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  std::vector<Vec3d> ring;
  for (int k = 0; k <= 32; ++k)
    ring.push_back(Vec3d(0.4 * std::cos(2 * M_PI * k / 32), 0.4 * std::sin(2 * M_PI * k / 32), 0));
  auto rs = project(cam, ring);
  rs.back() = rs.front();
  auto p = paint_stroke(m, cam, rs);
  ASSERT_TRUE(p);
  ASSERT_TRUE(partition_along_curves(m, p->curves[0].edges));
  ASSERT_EQ(m.num_surfaces(), 2u);
  auto across = paint_stroke(m, cam, project(cam, {Vec3d(-0.8, 0.05, 0), Vec3d(0.8, 0.07, 0)}));
  ASSERT_TRUE(across) << across.status().to_string();
  ASSERT_EQ(across->curves.size(), 1u);
  const auto& e = across->curves[0].edges;
  ASSERT_EQ(e.size(), 3u);  // outside, inside the ring, outside again
  for (std::size_t k = 0; k + 1 < e.size(); ++k) {
    const auto a = m.attrib_edges.nodes.row(e[k].idx.value), b = m.attrib_edges.nodes.row(e[k + 1].idx.value);
    EXPECT_NE(m.attrib_edges.surface[e[k].idx.value], m.attrib_edges.surface[e[k + 1].idx.value]);
    EXPECT_LT((m.attrib_position_on_surface(a.back()) - m.attrib_position_on_surface(b.front())).norm(), 1e-12);
  }
  EXPECT_TRUE(validate(m)) << validate(m).to_string();
}
