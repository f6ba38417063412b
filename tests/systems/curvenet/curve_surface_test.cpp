// The whole pipeline (issue 23): every shared network becomes a valid
// Catmull-Clark surface whose distance to its curves is reported and
// bounded; the traced mesh closes open networks; curves given as B-splines;
// bad input named; results independent of the thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "curvenet_fixtures.h"
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/curvenet/bspline.h>
#include <atelier/systems/curvenet/curve_surface.h>

using namespace atelier;
using namespace atelier::curvenet_test;

namespace {

/// The report's distance is the true one: brute force over every refined
/// triangle for a sample of the curve points.
double brute_distance(const PolygonSoup& m, const Vec3d& q) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto c = m.face(f);
    for (std::size_t k = 1; k + 1 < c.size(); ++k) {
      const Vec3d &a = m.positions[c[0]], &b = m.positions[c[k]], &d = m.positions[c[k + 1]];
      // Closest point on triangle (a, b, d) by projection and edge clamps.
      const Vec3d n = (b - a).cross(d - a);
      Vec3d p = q - (q - a).dot(n) / n.squaredNorm() * n;
      const double w0 = (b - p).cross(d - p).dot(n), w1 = (d - p).cross(a - p).dot(n), w2 = (a - p).cross(b - p).dot(n);
      if (w0 < 0 || w1 < 0 || w2 < 0) {
        double e = std::numeric_limits<double>::infinity();
        for (const auto& [u, v] : {std::pair{a, b}, std::pair{b, d}, std::pair{d, a}}) {
          const double t = std::clamp((q - u).dot(v - u) / (v - u).squaredNorm(), 0.0, 1.0);
          e = std::min(e, (u + t * (v - u) - q).norm());
        }
        best = std::min(best, e);
      } else {
        best = std::min(best, (p - q).norm());
      }
    }
  }
  return best;
}

void expect_good_surface(const CurveSurface& s, const CurveSurfaceOptions& o, const char* name) {
  const CurveSurfaceReport& r = s.report;
  EXPECT_TRUE(validate(s.model)) << name << ": " << validate(s.model).to_string();
  EXPECT_EQ(s.model.num_faces(), s.refined.mesh.face_count()) << name;
  EXPECT_EQ(r.euler, 1) << name;
  EXPECT_EQ(r.to_curves.samples, s.graph.points.size()) << name;
  // Bounded: the crease limit is each segment's fitted B-spline, which
  // strays at most fit_tolerance x diagonal from the curve (plus the
  // last level's chords).
  EXPECT_LT(r.to_curves.relative_max, 2 * o.control.fit_tolerance) << name;
  EXPECT_LE(r.fairing_energy_after, r.fairing_energy_before) << name;
  for (const auto& f : s.refined.mesh.positions) ASSERT_TRUE(f.allFinite());
  // Counts V' = V + E + F, E' = 2E + sum n_f, F' = sum n_f level by level.
  for (std::size_t l = 0; l + 1 < r.levels.size(); ++l) {
    const std::size_t sum_n = 4 * r.levels[l].faces;  // the control mesh is all quads
    EXPECT_EQ(r.levels[l + 1].vertices, r.levels[l].vertices + r.levels[l].edges + r.levels[l].faces) << name;
    EXPECT_EQ(r.levels[l + 1].faces, sum_n) << name;
    EXPECT_EQ(r.levels[l + 1].edges, 2 * r.levels[l].edges + sum_n) << name;
  }
  const TopologyCounts t = count_topology(s.model);
  EXPECT_EQ(static_cast<std::size_t>(t.edges), r.levels.back().edges) << name;
  // The reported maximum is the true distance (brute force on a sample).
  for (std::size_t i = 0; i < s.graph.points.size(); i += s.graph.points.size() / 7 + 1) {
    const double d = brute_distance(s.refined.mesh, s.graph.points[i]);
    EXPECT_LE(d, r.to_curves.max * (1 + 1e-12) + 1e-15) << name;
  }
}

}  // namespace

TEST(CurveSurface, OpenSharedNetworks) {
  ATELIER_REQUIRE_SHARED_NETWORKS();
  for (const char* name : {"shell_100", "roof_75", "kagome_114_regular", "tent_3_regular_curves"}) {
    CurveSurfaceOptions o;
    o.levels = 1;
    auto s = surface_from_curves(shared_network(name), {}, o);
    ASSERT_TRUE(s) << name << ": " << s.status().to_string();
    expect_good_surface(*s, o, name);
    RecordProperty(std::string(name) + "_relative_max", std::to_string(s->report.to_curves.relative_max));
  }
}

TEST(CurveSurface, TracedMeshClosesTheNetwork) {
  ATELIER_REQUIRE_SHARED_NETWORKS();
  // hill_3 and shell_3 are three curves crossing pairwise with their ends on
  // the traced mesh's boundary: alone they bound no face.
  for (const auto& [name, mesh] : {std::pair{"hill_3", "hill"}, std::pair{"shell_3", "shell"}}) {
    auto alone = surface_from_curves(shared_network(name), {}, {});
    ASSERT_FALSE(alone);
    EXPECT_EQ(alone.status().code(), ErrorCode::kTopology);
    const PolygonSoup traced = read_soup(shared_networks() / (std::string(mesh) + ".obj"));
    CurveSurfaceOptions o;
    o.levels = 2;
    auto s = surface_from_curves(shared_network(name), traced, o);
    ASSERT_TRUE(s) << name << ": " << s.status().to_string();
    EXPECT_EQ(s->report.boundary_curves, 1u) << name;
    EXPECT_EQ(s->report.faces, 6u) << name;  // 3 curves, 2 crossings, 6 ends on one boundary loop
    expect_good_surface(*s, o, name);
    EXPECT_TRUE(s->report.has_traced);
    EXPECT_GT(s->report.to_traced.samples, 0u);
    EXPECT_TRUE(std::isfinite(s->report.to_traced.max));
  }
  // tent_3's curves meet end to end: its mesh adds nothing.
  const PolygonSoup tent = read_soup(shared_networks() / "tent.obj");
  auto s = surface_from_curves(shared_network("tent_3_regular_curves"), tent, {});
  ASSERT_TRUE(s);
  EXPECT_EQ(s->report.boundary_curves, 0u);
  EXPECT_EQ(s->report.faces, 1u);
}

TEST(CurveSurface, ClosedNetworksGiveClosedSurfaces) {
  for (const auto& [net, genus] : {std::pair{cube_wireframe(), 0}, std::pair{torus_grid(8, 4), 1}}) {
    CurveSurfaceOptions o;
    o.levels = 2;
    auto s = surface_from_curves(net, {}, o);
    ASSERT_TRUE(s) << s.status().to_string();
    EXPECT_TRUE(validate(s->model)) << validate(s->model).to_string();
    const TopologyCounts t = count_topology(s->model);
    EXPECT_EQ(t.shells, 1);
    EXPECT_EQ(t.nodes - t.edges + t.faces, 2 - 2 * genus);
    EXPECT_EQ(s->report.outer_cycles, 0u);
    EXPECT_LT(s->report.to_curves.relative_max, 2e-3);
  }
}

TEST(CurveSurface, BSplineCurvesAsInput) {
  // A clamped cubic B-spline with Bezier knots is the cubic Bezier curve.
  BSplineCurve b;
  b.control = {{0, 0, 0}, {1, 2, 0}, {3, 2, 1}, {4, 0, 0}};
  b.knots = {0, 0, 0, 0, 1, 1, 1, 1};
  auto pts = sample_bspline(b, 16);
  ASSERT_TRUE(pts);
  ASSERT_EQ(pts->size(), 17u);
  for (std::size_t i = 0; i < pts->size(); ++i) {
    const double t = i / 16.0, u = 1 - t;
    const Vec3d bez = u * u * u * b.control[0] + 3 * u * u * t * b.control[1] + 3 * u * t * t * b.control[2] +
                      t * t * t * b.control[3];
    EXPECT_LT(((*pts)[i] - bez).norm(), 1e-14);
  }
  // The cube's edges as degree-2 B-splines (straight, with an inner knot).
  PolylineSet net;
  const PolylineSet cube = cube_wireframe();
  for (std::size_t c = 0; c < cube.size(); ++c) {
    BSplineCurve e;
    e.degree = 2;
    const Vec3d p = cube.curve(c).front(), q = cube.curve(c).back();
    e.control = {p, 0.75 * p + 0.25 * q, 0.25 * p + 0.75 * q, q};
    e.knots = {0, 0, 0, 0.5, 1, 1, 1};
    auto s = sample_bspline(e, 4);
    ASSERT_TRUE(s);
    EXPECT_EQ(s->front(), p);
    EXPECT_LT((s->back() - q).norm(), 1e-15);
    s->back() = q;
    net.add(static_cast<std::int64_t>(c), *s);
  }
  auto surf = surface_from_curves(net, {}, {});
  ASSERT_TRUE(surf) << surf.status().to_string();
  EXPECT_EQ(surf->report.faces, 6u);
  // Bad B-splines are refused.
  BSplineCurve bad = b;
  bad.knots.pop_back();
  EXPECT_FALSE(sample_bspline(bad));
  bad = b;
  bad.knots[5] = 0.5;
  EXPECT_FALSE(sample_bspline(bad));
  bad = b;
  bad.control[2].y() = std::nan("");
  EXPECT_FALSE(sample_bspline(bad));
}

TEST(CurveSurface, BadInputNamesTheCurve) {
  PolylineSet net = cube_wireframe();
  const Vec3d lone[] = {{5, 5, 5}};
  net.add(42, lone);
  auto s = surface_from_curves(net, {}, {});
  ASSERT_FALSE(s);
  EXPECT_NE(s.status().message().find("CURVE 42"), std::string::npos) << s.status().message();
  CurveSurfaceOptions o;
  o.levels = 7;
  EXPECT_EQ(surface_from_curves(cube_wireframe(), {}, o).status().code(), ErrorCode::kInvalidArgument);
  PolygonSoup traced;
  traced.positions = {{0, 0, 0}, {1, 0, 0}};
  const std::uint32_t f[] = {0, 1, 7};
  traced.add_face(f);
  EXPECT_EQ(surface_from_curves(cube_wireframe(), traced, {}).status().code(), ErrorCode::kInvalidArgument);
}

TEST(CurveSurface, ThreadCountDoesNotChangeABit) {
  ATELIER_REQUIRE_SHARED_NETWORKS();
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 1;
  two.grain = 64;
  CurveSurfaceOptions o;
  o.levels = 1;
  o.build_model = false;
  const PolylineSet net = shared_network("shell_100");
  auto a = surface_from_curves(net, {}, o, one), b = surface_from_curves(net, {}, o, two);
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->control.mesh.positions.size(), b->control.mesh.positions.size());
  EXPECT_EQ(0, std::memcmp(a->control.mesh.positions.data(), b->control.mesh.positions.data(),
                           a->control.mesh.positions.size() * sizeof(Vec3d)));
  ASSERT_EQ(a->refined.mesh.positions.size(), b->refined.mesh.positions.size());
  EXPECT_EQ(0, std::memcmp(a->refined.mesh.positions.data(), b->refined.mesh.positions.data(),
                           a->refined.mesh.positions.size() * sizeof(Vec3d)));
  EXPECT_EQ(a->report.to_curves.max, b->report.to_curves.max);
}

TEST(CurveSurface, PaperSearchOptionEndToEnd) {
  // On the closed cube the paper's search finds the six faces and meets
  // its stop rule: a valid closed surface.
  CurveSurfaceOptions o;
  o.cycles = FaceCycleMethod::kPaperSearch;
  o.levels = 1;
  auto cube = surface_from_curves(cube_wireframe(), {}, o);
  ASSERT_TRUE(cube) << cube.status().to_string();
  EXPECT_EQ(cube->report.faces, 6u);
  EXPECT_TRUE(cube->report.stop_rule_met);
  EXPECT_TRUE(validate(cube->model));
  // On an open grid its boundary segments never reach two cycles, so it
  // goes on validating larger cycles through them, which overlap the
  // faces: refused with the reason (as on roof_75).
  auto grid = surface_from_curves(grid_network(4, 3, 1.0, 0.3, 0.4), {}, o);
  ASSERT_FALSE(grid);
  EXPECT_EQ(grid.status().code(), ErrorCode::kTopology);
  EXPECT_NE(grid.status().message().find("overlap"), std::string::npos) << grid.status().message();
  ATELIER_REQUIRE_SHARED_NETWORKS();
  auto roof = surface_from_curves(shared_network("roof_75"), {}, o);
  ASSERT_FALSE(roof);
  EXPECT_NE(roof.status().message().find("overlap"), std::string::npos) << roof.status().message();
}
