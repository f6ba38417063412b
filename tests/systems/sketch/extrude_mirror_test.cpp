// Mirrored pairs (issue 21, ExtrudeOptions::mirror): on an icosphere built
// symmetric about x = 0, the result of a closed extrusion drawn off the
// plane is symmetric node for node and face for face (brute force, the
// reflection computed here), with twice the single extrusion's counts, and
// closed, oriented, Euler characteristic 2; an asymmetric sphere and a
// stroke across the plane are refused with the model unchanged; both
// sleeves of the project's top from one armhole stroke, outside the body.
#include <atelier/engine/parallel.h>
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/profile/regenerate.h>
#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/spatial/collision_body.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>

#include "support/project_templates.h"
#include "systems/sketch/sampled_mannequins.h"
#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;

namespace {

Vec3d mirror_x(const Vec3d& p) {
  return Vec3d(-p.x(), p.y(), p.z());
}

/// Index of the live node nearest to p (brute force) and its distance.
std::pair<NodeIdx, double> nearest_node(const Model& m, const Vec3d& p) {
  std::pair<NodeIdx, double> best{NodeIdx{}, INFINITY};
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}))
      if (const double d = (m.position(NodeIdx{v}) - p).norm(); d < best.second) best = {NodeIdx{v}, d};
  return best;
}

/// Every edge with two faces, each face running through one direction.
void expect_one_closed_oriented_shell(const Model& m, std::int64_t chi) {
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e})) continue;
    const HalfedgeIdx h = halfedge_of(EdgeIdx{e}, 0);
    ASSERT_TRUE(m.face(h).valid() && m.face(twin(h)).valid()) << "edge " << e << " is not closed";
    ASSERT_NE(m.face(h), m.face(twin(h)));
  }
  const TopologyCounts t = count_topology(m);
  EXPECT_EQ(t.nodes - t.edges + t.faces, chi);
  EXPECT_EQ(t.shells, 1);
}

/// A ring painted on the sphere around the direction Q z (radius rr, seen
/// from Q (0, 0, 5)) and a semicircular stroke drawn outwards from the side.
ExtrudeStrokes ring_on_sphere(double angle_deg, double rr = 0.3) {
  const Mat3d Q = Eigen::AngleAxisd(angle_deg * M_PI / 180, Vec3d::UnitY()).toRotationMatrix();
  const double z0 = std::sqrt(1 - rr * rr);
  ExtrudeStrokes in;
  in.base_camera = Camera::orthographic(Q * Vec3d(0, 0, 5), Vec3d::Zero(), Vec3d::UnitY(), 1.5, 800, 800);
  std::vector<Vec3d> ring;
  for (int k = 0; k <= 48; ++k)
    ring.push_back(Q * Vec3d(rr * std::cos(2 * M_PI * k / 48), rr * std::sin(2 * M_PI * k / 48), 1));
  in.base = project(in.base_camera, ring);
  in.base.back() = in.base.front();
  in.sweep_camera = Camera::orthographic(Q * Vec3d(5, 0, 0), Vec3d::Zero(), Vec3d::UnitY(), 1.5, 800, 800);
  std::vector<Vec3d> s;
  for (int i = 0; i <= 20; ++i) {
    const double t = M_PI * (1.0 - i / 20.0);
    s.push_back(Q * Vec3d(0, -rr * std::cos(t), z0 + rr * std::sin(t)));
  }
  in.sweep = {project(in.sweep_camera, s)};
  return in;
}

}  // namespace

TEST(ExtrudeMirror, ClosedExtrusionOnASphereIsTheExactReflection) {
  const Model sphere = icosphere(3);
  // Precondition: the icosphere is symmetric about x = 0 bit for bit.
  for (std::uint32_t v = 0; v < sphere.nodes.slots.capacity(); ++v)
    ASSERT_EQ(nearest_node(sphere, mirror_x(sphere.position(NodeIdx{v}))).second, 0.0);
  const ExtrudeStrokes in = ring_on_sphere(40);
  Model single = sphere;
  auto r1 = extrude(single, in);
  ASSERT_TRUE(r1) << r1.status().to_string();
  Model m = sphere;
  ExtrudeOptions opt;
  opt.mirror = SymmetryPlane{};  // x = 0
  auto r = extrude(m, in, opt);
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  EXPECT_TRUE(r->mirrored);
  EXPECT_LT(r->mirror_base_error, 1e-12);
  // Twice the single extrusion's changes, closed, oriented, chi = 2 (a
  // capped extrusion keeps the sphere's topology; two of them too).
  EXPECT_EQ(m.num_nodes() - sphere.num_nodes(), 2 * (single.num_nodes() - sphere.num_nodes()));
  EXPECT_EQ(m.num_faces() - sphere.num_faces(), 2 * (single.num_faces() - sphere.num_faces()));
  EXPECT_EQ(r->mirror_nodes, r1->nodes_added);
  expect_one_closed_oriented_shell(m, 2);
  // Outward: each part adds volume, the pair twice one part.
  const double dv1 = signed_volume(single) - signed_volume(sphere), dv = signed_volume(m) - signed_volume(sphere);
  EXPECT_GT(dv1, 0);
  EXPECT_NEAR(dv, 2 * dv1, 1e-3 * dv1);
  EXPECT_NEAR(r->volume_change, dv, 1e-12);
  // The whole result is symmetric: every node has a node at its reflection
  // to 1e-12, every face (a, b, c) a face (c', b', a') on the reflections.
  std::map<std::uint32_t, std::uint32_t> twin_of;
  std::size_t off_plane = 0;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
    if (!m.alive(NodeIdx{v})) continue;
    const auto [w, d] = nearest_node(m, mirror_x(m.position(NodeIdx{v})));
    EXPECT_LE(d, 1e-12) << "node " << v << " at " << m.position(NodeIdx{v}).transpose();
    twin_of[v] = w.value;
    off_plane += std::abs(m.position(NodeIdx{v}).x()) > 0.1;
  }
  EXPECT_GT(off_plane, 200u);
  std::vector<NodeIdx> f;
  std::size_t faces_checked = 0;
  for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i) {
    if (!m.alive(FaceIdx{i})) continue;
    m.face_nodes(FaceIdx{i}, f);
    ASSERT_EQ(f.size(), 3u);
    // The reflected face, reversed so that it stays outward.
    const HalfedgeIdx h = m.find_halfedge(NodeIdx{twin_of[f[2].value]}, NodeIdx{twin_of[f[1].value]});
    ASSERT_TRUE(h.valid() && m.face(h).valid()) << "face " << i;
    std::vector<NodeIdx> g;
    m.face_nodes(m.face(h), g);
    EXPECT_NE(std::find(g.begin(), g.end(), NodeIdx{twin_of[f[0].value]}), g.end()) << "face " << i;
    ++faces_checked;
  }
  EXPECT_EQ(faces_checked, m.num_faces());
}

TEST(ExtrudeMirror, AsymmetricMeshOrStrokeAcrossThePlaneIsRefusedUnchanged) {
  ExtrudeOptions opt;
  opt.mirror = SymmetryPlane{};
  {
    // A sphere with its -x side bumped out by 3 %: no B' at the reflections.
    Model m = icosphere(3);
    for (auto& p : m.nodes.position)
      if (p.x() < 0) p *= 1.03;
    const Model before = m;
    auto r = extrude(m, ring_on_sphere(40), opt);
    ASSERT_FALSE(r);
    EXPECT_NE(r.status().message().find("mirror side"), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find("not symmetric"), std::string::npos) << r.status().message();
    EXPECT_EQ(diff_tables(m, before), "");
    // The same strokes without the mirror work on it.
    EXPECT_TRUE(extrude(m, ring_on_sphere(40)));
  }
  {
    // The ring straddles x = 0 (centre at 10 degrees, radius 0.3).
    Model m = icosphere(3);
    const Model before = m;
    auto r = extrude(m, ring_on_sphere(10), opt);
    ASSERT_FALSE(r);
    EXPECT_NE(r.status().message().find("drawn side"), std::string::npos) << r.status().message();
    EXPECT_EQ(diff_tables(m, before), "");
  }
  {
    Model m = icosphere(2);
    const Model before = m;
    opt.mirror->normal = Vec3d::Zero();
    EXPECT_EQ(extrude(m, ring_on_sphere(40), opt).status().code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(diff_tables(m, before), "");
  }
}

namespace {

struct SleevesResult {
  std::string error;
  std::size_t right = 0, left = 0, inside = 0, inside_after = 0, base = 0, loop = 0, mirror_base = 0,
              mirror_in_left = 0;
  std::int64_t d_nodes = 0, d_faces = 0, d_chi = 0, single_nodes = 0, single_faces = 0, single_chi = 0;
  std::size_t shells = 0, shells0 = 0;
  double mirror_base_error = 0;
  double asymmetry = 0, tolerance = 0;  // of the armholes, in B's mean edge
  bool refused = false;                 // cleanly, the armholes too asymmetric
};

/// The top regenerated on `body`, both sleeves from one armhole stroke (the
/// right armhole traced from the side, the sleeve strokes drawn from the
/// front, as in ExtrudeGarment), outside the body, against the single
/// sleeve for the counts.
SleevesResult both_sleeves_on(const ReferenceBody& body) {
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  if (top.name != "top") return {"no top"};
  Box3d roi;
  for (std::uint32_t v = 0; v < top.model.nodes.slots.capacity(); ++v)
    if (top.model.alive(NodeIdx{v})) roi.extend(top.model.position(NodeIdx{v}));
  const ProfileTemplate one[] = {top};
  auto regen =
      regenerate_on_body(one, fx.body, skin_positions(body), roi, {}, {.use_grid = false}, ExecContext::sequential());
  if (!regen) return {regen.status().to_string()};
  Model m = std::move((*regen)[0].model);
  const std::vector<NodeIdx> loop = best_loop(m, [&](const Vec3d& c) { return -c.x(); });
  const std::vector<NodeIdx> left = best_loop(m, [&](const Vec3d& c) { return c.x(); });
  if (loop.size() < 8) return {"no armhole"};
  Vec3d c = Vec3d::Zero(), e0, e1;
  double lo = INFINITY, hi = -INFINITY;
  for (NodeIdx v : loop) {
    const Vec3d p = m.position(v);
    c += p;
    if (p.y() < lo) lo = p.y(), e0 = p;
    if (p.y() > hi) hi = p.y(), e1 = p;
  }
  c /= static_cast<double>(loop.size());
  if (!(c.x() > 0.05)) return {"the right armhole is not on the right"};
  const Camera cam =
      Camera::orthographic(Vec3d(c.x(), c.y(), 3), Vec3d(c.x(), c.y(), 0), Vec3d::UnitY(), 0.8, 800, 800);
  ExtrudeStrokes in;
  in.sweep_camera = cam;
  in.base_camera = Camera::orthographic(c + Vec3d(3, 0, 0), c, Vec3d::UnitY(), 0.8, 800, 800);
  std::vector<Vec3d> trace;
  for (NodeIdx v : loop) trace.push_back(m.position(v));
  trace.push_back(trace.front());
  in.base = project(in.base_camera, trace);
  std::vector<Vec3d> s0, s1;
  for (int k = 0; k <= 14; ++k) {
    const double t = k / 14.0;
    s0.push_back(Vec3d(e0.x(), e0.y(), 0) + t * Vec3d(0.30, -0.22, 0));
    s1.push_back(Vec3d(e1.x(), e1.y(), 0) + t * Vec3d(0.28, -0.28, 0));
  }
  in.sweep = {project(cam, s0), project(cam, s1)};
  auto tris = fan_triangulate(body.model, std::vector<SurfaceIdx>{body.skin});
  if (!tris) return {tris.status().to_string()};
  auto topo = CollisionTopology::build(tris->triangles, static_cast<std::uint32_t>(body.model.nodes.slots.capacity()));
  if (!topo) return {topo.status().to_string()};
  CollisionBody cb;
  if (Status s = cb.build(*topo, body.model.nodes.position); !s) return {s.to_string()};
  ExtrudeOptions o;
  o.pick_radius = 30;
  o.body = &cb;
  o.clearance = 0.005;
  o.mirror = SymmetryPlane{};
  // The regenerated top is symmetric only to ~1.6 % of its armhole's mean
  // edge on the default mannequin (its left armhole lies 3.6e-4 from the
  // reflection of the right one), not bit for bit: a tolerance of 5 % of L.
  // On a sampled mannequin it can be less symmetric than that (mannequin 37
  // of 100: over 13 %); extrude must then refuse cleanly (kDegenerate, the
  // model unchanged), which is checked against the asymmetry measured here.
  o.mirror_tolerance = 0.05;
  const std::size_t cap = m.nodes.slots.capacity();
  const Model m0 = m;
  Model m1 = m;
  ExtrudeOptions o1 = o;
  o1.mirror.reset();
  if (auto r1 = extrude(m1, in, o1, ExecContext::sequential()); !r1) return {"single: " + r1.status().to_string()};
  auto chi = [](const Model& x) {
    const TopologyCounts t = count_topology(x);
    return static_cast<std::int64_t>(t.nodes) - static_cast<std::int64_t>(t.edges) + static_cast<std::int64_t>(t.faces);
  };
  SleevesResult out;
  {  // The armholes' asymmetry, brute force: each right armhole node
     // reflected, to the nearest left armhole node, over B's mean edge.
    double L = 0;
    for (std::size_t i = 0; i < loop.size(); ++i)
      L += (m.position(loop[(i + 1) % loop.size()]) - m.position(loop[i])).norm();
    L /= static_cast<double>(loop.size());
    for (NodeIdx v : loop) {
      double best = INFINITY;
      for (NodeIdx w : left) best = std::min(best, (mirror_x(m.position(v)) - m.position(w)).norm());
      out.asymmetry = std::max(out.asymmetry, best / L);
    }
  }
  out.tolerance = o.mirror_tolerance;
  auto r = extrude(m, in, o, ExecContext::sequential());
  if (!r) {
    out.refused = r.status().code() == ErrorCode::kDegenerate && diff_tables(m, m0).empty();
    if (out.refused && out.asymmetry > o.mirror_tolerance) return out;
    return {r.status().to_string()};
  }
  if (Status s = validate(m); !s) return {s.to_string()};
  out.mirror_base_error = r->mirror_base_error / r->base_mean_edge;
  out.base = r->base.size();
  out.loop = loop.size();
  out.mirror_base = r->mirror_base.size();
  for (NodeIdx v : r->mirror_base) out.mirror_in_left += std::find(left.begin(), left.end(), v) != left.end();
  // BodyBvh signed distance: an oracle apart from extrude's CollisionBody.
  BodyBvh oracle;
  if (Status s = oracle.build(std::span<const Vec3d>(body.model.nodes.position), tris->triangles); !s)
    return {s.to_string()};
  for (std::uint32_t v = static_cast<std::uint32_t>(cap); v < m.nodes.slots.capacity(); ++v) {
    if (!m.alive(NodeIdx{v})) continue;
    const Vec3d p = m.position(NodeIdx{v});
    out.right += p.x() > c.x() + 0.02;
    out.left += p.x() < -c.x() - 0.02;
    out.inside += oracle.signed_distance(p).distance < 0;
  }
  out.inside_after = r->inside_after;
  out.d_nodes = static_cast<std::int64_t>(m.num_nodes()) - static_cast<std::int64_t>(m0.num_nodes());
  out.d_faces = static_cast<std::int64_t>(m.num_faces()) - static_cast<std::int64_t>(m0.num_faces());
  out.single_nodes = static_cast<std::int64_t>(m1.num_nodes()) - static_cast<std::int64_t>(m0.num_nodes());
  out.single_faces = static_cast<std::int64_t>(m1.num_faces()) - static_cast<std::int64_t>(m0.num_faces());
  out.d_chi = chi(m) - chi(m0);
  out.single_chi = chi(m1) - chi(m0);
  out.shells = count_topology(m).shells;
  out.shells0 = count_topology(m0).shells;
  return out;
}

void expect_both_sleeves(const SleevesResult& g, const std::string& where) {
  ASSERT_EQ(g.error, "") << where;
  if (g.refused) {  // only when the armholes are measured too asymmetric
    EXPECT_GT(g.asymmetry, g.tolerance) << where;
    return;
  }
  // B is the right armhole, B' the left one (the other loop farthest out).
  EXPECT_EQ(g.base, g.loop) << where;
  EXPECT_EQ(g.mirror_in_left, g.mirror_base) << where;
  EXPECT_GT(g.mirror_base, 8u) << where;
  // Two sleeves, outside the body, each with the single sleeve's counts.
  EXPECT_GT(g.right, 100u) << where;
  EXPECT_EQ(g.left, g.right) << where;
  EXPECT_EQ(g.inside, 0u) << where;
  EXPECT_EQ(g.inside_after, 0u) << where;
  EXPECT_EQ(g.d_nodes, 2 * g.single_nodes) << where;
  EXPECT_EQ(g.d_faces, 2 * g.single_faces) << where;
  EXPECT_EQ(g.d_chi, 2 * g.single_chi) << where;
  EXPECT_EQ(g.shells, g.shells0) << where;
}

void sleeves_on_mannequins(std::size_t n) {
  const std::vector<SleevesResult> got = sketch_test::on_sampled_mannequins<SleevesResult>(
      n, [&](const ReferenceBody& body) { return both_sleeves_on(body); });
  double worst = 0;
  std::size_t refused = 0;
  for (std::size_t i = 0; i < n; ++i) {
    expect_both_sleeves(got[i], "body " + std::to_string(i));
    worst = std::max(worst, got[i].mirror_base_error);
    refused += got[i].refused;
  }
  // Nearly every body's top is symmetric enough (measured: 1 refused of 100).
  EXPECT_LE(refused, std::max<std::size_t>(1, n / 50));
  ::testing::Test::RecordProperty("worst_mirror_base_error_over_L", std::to_string(worst));
  ::testing::Test::RecordProperty("refused_as_asymmetric", std::to_string(refused));
}

}  // namespace

TEST(ExtrudeMirror, BothSleevesOfTheTopFromOneArmholeStrokeOutsideTheBody) {
  // On the reference body. Not as_surface: see ExtrudeMirror.AsSurface* and
  // ExtrudeGarment.TheDressCollarAndSleeveAsTheirOwnSurfaces* (the top's
  // armhole runs along the collar seam).
  const SleevesResult g = both_sleeves_on(atelier::testing::template_fixture().body);
  EXPECT_FALSE(g.refused);  // symmetric to ~1.6 % of L here
  expect_both_sleeves(g, "reference body");
  RecordProperty("mirror_base_error", std::to_string(g.mirror_base_error));
}

TEST(ExtrudeMirror, BothSleevesOnTwoSampledMannequins) {
  sleeves_on_mannequins(2);
}

TEST(ExtrudeMirror, BothSleevesOn100SampledMannequins) {
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "100 regenerations (long under sanitizers)";
  sleeves_on_mannequins(100);
}

TEST(ExtrudeMirror, AsSurfaceGivesEachPartItsOwnSurfaceAndJoint) {
  Model m = icosphere(3);
  const std::size_t surfaces0 = m.num_surfaces();
  ExtrudeOptions opt;
  opt.mirror = SymmetryPlane{};
  opt.as_surface = true;
  auto r = extrude(m, ring_on_sphere(40), opt);
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  ASSERT_TRUE(r->part_surface.valid() && r->mirror_part_surface.valid());
  EXPECT_NE(r->part_surface, r->mirror_part_surface);
  EXPECT_EQ(m.num_surfaces(), surfaces0 + 2);
  EXPECT_FALSE(r->joints.empty());
  EXPECT_FALSE(r->mirror_joints.empty());
  // Each part's faces lie on its own side of x = 0, every one of them.
  std::vector<NodeIdx> f;
  std::size_t drawn = 0, mirror = 0;
  for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i) {
    if (!m.alive(FaceIdx{i})) continue;
    const SurfaceIdx s = m.faces.surface[i];
    if (s != r->part_surface && s != r->mirror_part_surface) continue;
    m.face_nodes(FaceIdx{i}, f);
    for (NodeIdx v : f) EXPECT_GT((s == r->part_surface ? 1 : -1) * m.position(v).x(), 0) << "face " << i;
    (s == r->part_surface ? drawn : mirror)++;
  }
  EXPECT_GT(drawn, 50u);
  EXPECT_EQ(drawn, mirror);
}
