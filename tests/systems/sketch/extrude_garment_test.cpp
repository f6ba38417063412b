// Seed 002 Fig. 12 on the project's top (issue 21): a dress grown from the
// top's hem, a sleeve from its right armhole and a ring collar from the
// collar's top edge, on the top regenerated on sampled mannequins, with the
// mannequin as the body the extrusion is kept outside of.
//
// ExtrudeGarment draws each design on every regenerated top (the same
// strokes relative to that body's loop, its extreme points on screen).
// ExtrudeRecipe draws it once, on the top regenerated on the reference body,
// and replays its recipe (systems/sketch/extrude_recipe.h) on the others:
// no strokes; bit for bit the original on the reference body.
#include <atelier/engine/parallel.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/profile/regenerate.h>
#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/sketch/extrude_recipe.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/spatial/collision_body.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <set>
#include <string>

#include "support/project_templates.h"
#include "systems/sketch/sampled_mannequins.h"
#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;

namespace {

enum class Design { kDress, kSleeve, kCollar };

struct DressResult {
  std::string error;
  std::size_t new_nodes = 0, inside = 0, outside_bounds = 0, brute_outside = 0, pushed = 0;
  double deepest = 0;
};

/// The design's strokes on a regenerated top: its loop (the hem: lowest;
/// the right armhole: farthest to +x; the collar's top edge: highest) and
/// strokes relative to the loop's extreme points on screen.
Expected<ExtrudeStrokes> design_strokes(const Model& m, Design design) {
  const std::vector<NodeIdx> loop = best_loop(m, [&](const Vec3d& c) {
    return design == Design::kDress ? c.y() : design == Design::kSleeve ? -c.x() : -c.y();
  });
  if (loop.size() < 8) return Status(ErrorCode::kInvalidArgument, "no boundary loop found");
  // A front view level with the loop's centre; the stroke ends: the loop's
  // extreme points on screen (left/right; for the armhole, top/bottom).
  Vec3d c = Vec3d::Zero(), e0, e1;
  double lo = INFINITY, hi = -INFINITY;
  const int axis = design == Design::kSleeve ? 1 : 0;
  for (NodeIdx v : loop) {
    const Vec3d p = m.position(v);
    c += p;
    if (p[axis] < lo) lo = p[axis], e0 = p;
    if (p[axis] > hi) hi = p[axis], e1 = p;
  }
  c /= static_cast<double>(loop.size());
  const Camera cam =
      Camera::orthographic(Vec3d(c.x(), c.y(), 3), Vec3d(c.x(), c.y(), 0), Vec3d::UnitY(), 0.8, 800, 800);
  ExtrudeStrokes in;
  in.base_camera = in.sweep_camera = cam;
  in.base = project(cam, {e0, e1, e0});
  if (design == Design::kSleeve) {
    // The armhole is not flat enough to be seen edge-on from the front: the
    // base stroke traces it from the side, where it is seen face-on.
    in.base_camera = Camera::orthographic(c + Vec3d(3, 0, 0), c, Vec3d::UnitY(), 0.8, 800, 800);
    std::vector<Vec3d> trace;
    for (NodeIdx v : loop) trace.push_back(m.position(v));
    trace.push_back(trace.front());
    in.base = project(in.base_camera, trace);
  }
  // Dress: down 35 cm, flaring out 8 cm. Sleeve: out along the arm, 30 cm
  // outwards and 25 cm down, narrowing. Collar: up 5 cm, 1 cm inwards.
  Vec3d d0 = Vec3d::Zero(), d1 = Vec3d::Zero();
  if (design == Design::kDress) d0 = Vec3d(-0.08, -0.35, 0), d1 = Vec3d(0.08, -0.35, 0);
  if (design == Design::kSleeve) d0 = Vec3d(0.30, -0.22, 0), d1 = Vec3d(0.28, -0.28, 0);
  if (design == Design::kCollar) d0 = Vec3d(0.01, 0.05, 0), d1 = Vec3d(-0.01, 0.05, 0);
  std::vector<Vec3d> s0, s1;
  for (int k = 0; k <= 14; ++k) {
    const double t = k / 14.0;
    s0.push_back(Vec3d(e0.x(), e0.y(), 0) + t * d0);
    s1.push_back(Vec3d(e1.x(), e1.y(), 0) + t * d1);
  }
  in.sweep = {project(cam, s0), project(cam, s1)};
  return in;
}

/// The body's skin as extrude's CollisionBody and as an oracle (BodyBvh).
struct BodyChecks {
  CollisionBody cb;
  BodyBvh oracle;
  std::string error;
};

std::unique_ptr<BodyChecks> body_checks(const ReferenceBody& body) {
  auto out = std::make_unique<BodyChecks>();
  auto tris = fan_triangulate(body.model, std::vector<SurfaceIdx>{body.skin});
  if (!tris) {
    out->error = tris.status().to_string();
    return out;
  }
  auto topo = CollisionTopology::build(tris->triangles, static_cast<std::uint32_t>(body.model.nodes.slots.capacity()));
  if (!topo) {
    out->error = topo.status().to_string();
    return out;
  }
  if (Status s = out->cb.build(*topo, body.model.nodes.position); !s) {
    out->error = s.to_string();
    return out;
  }
  if (Status s = out->oracle.build(std::span<const Vec3d>(body.model.nodes.position), tris->triangles); !s)
    out->error = s.to_string();
  return out;
}

/// Regenerates the top on `body`, draws the design on its loop, extrudes it
/// outside the body, and checks the new nodes against the body (BodyBvh
/// signed distance, an oracle apart from the CollisionBody extrude uses).
DressResult design_on(const ReferenceBody& body, const ProfileTemplate& top, const ReferenceBody& reference,
                      const Box3d& roi, Design design, int body_smoothing = ExtrudeOptions{}.body_smoothing,
                      int settle_rounds = ExtrudeOptions{}.settle_rounds) {
  DressResult out;
  const ProfileTemplate one[] = {top};
  auto regen =
      regenerate_on_body(one, reference, skin_positions(body), roi, {}, {.use_grid = false}, ExecContext::sequential());
  if (!regen) return {regen.status().to_string()};
  Model m = std::move((*regen)[0].model);
  auto in = design_strokes(m, design);
  if (!in) return {in.status().to_string()};
  const std::size_t loop_size = best_loop(m, [&](const Vec3d& c) {
                                  return design == Design::kDress ? c.y() : design == Design::kSleeve ? -c.x() : -c.y();
                                }).size();
  const auto checks = body_checks(body);
  if (!checks->error.empty()) return {checks->error};
  ExtrudeOptions o;
  o.pick_radius = 30;
  o.body = &checks->cb;
  o.clearance = 0.005;
  o.body_smoothing = body_smoothing;
  o.settle_rounds = settle_rounds;
  const std::size_t cap = m.nodes.slots.capacity();
  auto r = extrude(m, *in, o, ExecContext::sequential());
  if (!r) return {r.status().to_string()};
  if (Status s = validate(m); !s) return {s.to_string()};
  if (r->base.size() != loop_size) return {"B is not the loop"};
  const BodyBvh& oracle = checks->oracle;
  for (std::uint32_t v = static_cast<std::uint32_t>(cap); v < m.nodes.slots.capacity(); ++v) {
    if (!m.alive(NodeIdx{v})) continue;
    ++out.new_nodes;
    const double d = oracle.signed_distance(m.position(NodeIdx{v})).distance;
    out.inside += d < 0;
    out.deepest = std::min(out.deepest, d);
  }
  // Brute force over the model (apart from the report): edges with a new
  // node outside [4/5, 4/3] L, measured after extrude's last push.
  out.outside_bounds = r->after.outside;
  const double L = r->base_mean_edge;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e})) continue;
    const NodeIdx a = m.tail(halfedge_of(EdgeIdx{e}, 0)), b = m.tail(halfedge_of(EdgeIdx{e}, 1));
    if (a.value < cap && b.value < cap) continue;
    const double l = (m.position(a) - m.position(b)).norm();
    out.brute_outside += l < 0.8 * L * (1 - 1e-12) || l > 4.0 / 3.0 * L * (1 + 1e-12);
  }
  out.pushed = r->pushed;
  return out;
}

void run_bodies(std::size_t n, Design design) {
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  ASSERT_EQ(top.name, "top");
  const Box3d roi = bounds(top.model);
  const std::vector<DressResult> got = sketch_test::on_sampled_mannequins<DressResult>(
      n, [&](const ReferenceBody& body) { return design_on(body, top, fx.body, roi, design); });
  std::size_t pushed = 0, bodies_pushed = 0, off_bounds = 0, brute = 0, worst = 0, worst_brute = 0;
  for (const DressResult& g : got) {
    pushed += g.pushed, bodies_pushed += g.pushed > 0, off_bounds += g.outside_bounds, brute += g.brute_outside;
    worst = std::max(worst, g.outside_bounds), worst_brute = std::max(worst_brute, g.brute_outside);
  }
  ::testing::Test::RecordProperty("design" + std::to_string(static_cast<int>(design)),
                                  "pushed " + std::to_string(pushed) + " nodes on " + std::to_string(bodies_pushed) +
                                      " bodies; edges off bounds " + std::to_string(off_bounds) +
                                      " (after the last push " + std::to_string(brute) + "), per body at most " +
                                      std::to_string(worst) + " (" + std::to_string(worst_brute) + ")");
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_EQ(got[i].error, "") << "design " << static_cast<int>(design) << ", body " << i;
    EXPECT_GT(got[i].new_nodes, 100u) << "body " << i;
    EXPECT_EQ(got[i].inside, 0u) << "body " << i << ": deepest " << got[i].deepest;
    // Edge bounds (issue 21: all new edges within [4/5, 4/3] L), after the
    // last push (with the default settle rounds the optimiser's count is
    // that one). Met on every dress, sleeve and collar of the 100 bodies
    // since sweep12 (the sleeve had up to 31 where the shoulder or the upper
    // arm runs through its first copies, the dress 1 on one body;
    // docs/performance.md).
    EXPECT_EQ(got[i].outside_bounds, 0u) << "body " << i;
    EXPECT_EQ(got[i].outside_bounds, got[i].brute_outside) << "body " << i;
  }
}

Expected<Model> regenerate_top(const ReferenceBody& body, const ProfileTemplate& top, const ReferenceBody& reference,
                               const Box3d& roi) {
  const ProfileTemplate one[] = {top};
  auto regen =
      regenerate_on_body(one, reference, skin_positions(body), roi, {}, {.use_grid = false}, ExecContext::sequential());
  if (!regen) return regen.status();
  return std::move((*regen)[0].model);
}

ExtrudeOptions garment_options(const BodyChecks& checks) {
  ExtrudeOptions o;
  o.pick_radius = 30;
  o.body = &checks.cb;
  o.clearance = 0.005;
  return o;
}

/// A design drawn once, on the top regenerated on the reference body.
struct Recorded {
  Model before, after;
  ExtrudeReport report;
  ExtrusionRecipe recipe;
};

Recorded record(Design d) {
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  Recorded out;
  out.before = regenerate_top(fx.body, top, fx.body, bounds(top.model)).value();
  out.after = out.before;
  const auto checks = body_checks(fx.body);
  EXPECT_EQ(checks->error, "");
  auto in = design_strokes(out.before, d);
  EXPECT_TRUE(in) << in.status().to_string();
  auto r = extrude(out.after, *in, garment_options(*checks), ExecContext::sequential());
  EXPECT_TRUE(r) << r.status().to_string();
  out.report = *r;
  auto rc = extrusion_recipe(out.after, *r);
  EXPECT_TRUE(rc) << rc.status().to_string();
  out.recipe = *rc;
  return out;
}

struct ReplayResult {
  std::string error;
  std::size_t new_nodes = 0, inside = 0, unsewn = 0, b_moved = 0;
  double along = 0;  // mean of the new nodes minus B's centroid, along the design's direction
};

/// Regenerates the top on `body` and replays the recipe on it (no strokes).
ReplayResult replay_on(const ReferenceBody& body, const Recorded& rec, Design d) {
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  auto m = regenerate_top(body, top, fx.body, bounds(top.model));
  if (!m) return {m.status().to_string()};
  const Model before = *m;
  const auto checks = body_checks(body);
  if (!checks->error.empty()) return {checks->error};
  const std::size_t cap = m->nodes.slots.capacity();
  auto r = replay_extrusion(*m, rec.recipe, garment_options(*checks), ExecContext::sequential());
  if (!r) return {r.status().to_string()};
  if (Status s = validate(*m); !s) return {s.to_string()};
  ReplayResult out;
  // Attached along B: B's nodes where they were, every edge of B (a
  // boundary before) now with a face on both sides.
  Vec3d cb = Vec3d::Zero(), cn = Vec3d::Zero();
  const std::size_t n = rec.recipe.base.size();
  for (std::size_t i = 0; i < n; ++i) {
    const NodeIdx v{rec.recipe.base[i]};
    out.b_moved += m->position(v) != before.position(v);
    cb += m->position(v);
    if (!rec.recipe.ring && i + 1 == n) continue;
    const HalfedgeIdx h = m->find_halfedge(v, NodeIdx{rec.recipe.base[(i + 1) % n]});
    out.unsewn += !h.valid() || !m->face(h).valid() || !m->face(twin(h)).valid();
  }
  cb /= static_cast<double>(n);
  for (std::uint32_t v = static_cast<std::uint32_t>(cap); v < m->nodes.slots.capacity(); ++v) {
    if (!m->alive(NodeIdx{v})) continue;
    ++out.new_nodes;
    cn += m->position(NodeIdx{v});
    out.inside += checks->oracle.signed_distance(m->position(NodeIdx{v})).distance < 0;
  }
  if (out.new_nodes) cn /= static_cast<double>(out.new_nodes);
  const Vec3d dir = d == Design::kDress ? Vec3d(0, -1, 0) : d == Design::kSleeve ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
  out.along = (cn - cb).dot(dir);
  return out;
}

void replay_bodies(std::size_t n) {
  for (Design d : {Design::kDress, Design::kSleeve, Design::kCollar}) {
    const Recorded rec = record(d);
    const std::vector<ReplayResult> got = sketch_test::on_sampled_mannequins<ReplayResult>(
        n, [&](const ReferenceBody& body) { return replay_on(body, rec, d); });
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_EQ(got[i].error, "") << "design " << static_cast<int>(d) << ", body " << i;
      EXPECT_GT(got[i].new_nodes, 100u) << "body " << i;
      EXPECT_EQ(got[i].inside, 0u) << "body " << i;
      EXPECT_EQ(got[i].unsewn, 0u) << "body " << i;
      EXPECT_EQ(got[i].b_moved, 0u) << "body " << i;
      // The part grows the designed way from B: dress down, sleeve out,
      // collar up (by at least a third of the stroke's reach, measured on
      // the reference: 0.35, 0.30, 0.05 m).
      const double reach = d == Design::kDress ? 0.35 : d == Design::kSleeve ? 0.30 : 0.05;
      EXPECT_GT(got[i].along, reach / 6) << "design " << static_cast<int>(d) << ", body " << i;
    }
  }
}

}  // namespace

TEST(ExtrudeGarment, DressSleeveAndCollarOnTheTopOutsideTheBodyOnAFewMannequins) {
  for (Design d : {Design::kDress, Design::kSleeve, Design::kCollar}) run_bodies(2, d);
}

TEST(ExtrudeGarment, TheSleevesSweepDoesNotFoldBack) {
  // The sleeve's strokes on the first two mannequins: eq. 2's greedy path
  // took one-sided steps there that turned the copy about the stationary
  // end, moving up to 24 of the armhole's 48 points back by 0.46-0.74 L
  // (sleeve8's probe; docs/performance.md, sweep10). The sweep now takes a
  // path without such steps: from the report's similarities applied to B
  // (an independent placement of the copies), no point of B moves against
  // the motion of the pair's midpoint by more than 0.1 L between
  // consecutive copies, and the counts are those of K copies.
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  struct Folds {
    std::string error;
    std::size_t copies = 0, back = 0, counts_off = 0;
    double worst = 0;
  };
  const auto got = sketch_test::on_sampled_mannequins<Folds>(2, [&](const ReferenceBody& body) {
    Folds out;
    auto m = regenerate_top(body, top, fx.body, bounds(top.model));
    if (!m) return Folds{m.status().to_string()};
    auto in = design_strokes(*m, Design::kSleeve);
    if (!in) return Folds{in.status().to_string()};
    ExtrudeOptions o;
    o.pick_radius = 30;
    o.optimise = false;
    auto r = extrude(*m, *in, o, ExecContext::sequential());
    if (!r) return Folds{r.status().to_string()};
    if (Status s = validate(*m); !s) return Folds{s.to_string()};
    std::vector<Vec3d> B;
    for (NodeIdx v : r->base) B.push_back(m->position(v));
    auto at = [&](std::size_t k, const Vec3d& p) -> Vec3d {
      return k == 0 ? p : Vec3d(r->translations[k - 1] + r->scales[k - 1] * (r->rotations[k - 1] * p));
    };
    out.copies = r->copies;
    out.counts_off = (r->swept_nodes != B.size() * r->copies) + (r->swept_faces != 2 * B.size() * r->copies);
    for (std::size_t k = 1; k <= r->copies; ++k) {
      const Vec3d d = (0.5 * (at(k, r->p1) + at(k, r->p2)) - 0.5 * (at(k - 1, r->p1) + at(k - 1, r->p2))).normalized();
      for (const Vec3d& p : B) {
        const double a = (at(k, p) - at(k - 1, p)).dot(d) / r->base_mean_edge;
        out.back += a < -0.1;
        out.worst = std::min(out.worst, a);
      }
    }
    return out;
  });
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got[i].error, "") << "body " << i;
    EXPECT_GE(got[i].copies, 10u) << "body " << i;
    EXPECT_EQ(got[i].counts_off, 0u) << "body " << i;
    EXPECT_EQ(got[i].back, 0u) << "body " << i << ": worst " << got[i].worst << " L";
  }
}

TEST(ExtrudeGarment, BodySmoothingAndSettleRoundsCutTheSleevesEdgesOutOfBounds) {
  // The passes around the body push (ExtrudeOptions::body_smoothing,
  // settle_rounds; on by default): on the first two mannequins the sleeve ends with fewer
  // edges out of [4/5, 4/3] L after the last push with 4 settle rounds than
  // without them (3 -> 0 and 2 -> 1, sweep10; 3 -> 0 and 2 -> 0 since
  // sweep12), and with the smoothing too (the defaults, 8 and 8 rounds)
  // with no more than without either (with smoothing 8 and 4 settle rounds
  // body 1 keeps 3 since sweep12, 0 with 8); the report's count is the final
  // one, and no node is inside the body.
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  const Box3d roi = bounds(top.model);
  struct Runs {
    std::string error;
    DressResult plain, settle, both;
  };
  const auto got = sketch_test::on_sampled_mannequins<Runs>(2, [&](const ReferenceBody& body) {
    return Runs{"", design_on(body, top, fx.body, roi, Design::kSleeve, 0, 0),
                design_on(body, top, fx.body, roi, Design::kSleeve, 0, 4),
                design_on(body, top, fx.body, roi, Design::kSleeve, 8, 8)};
  });
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got[i].error, "");
    for (const DressResult* r : {&got[i].plain, &got[i].settle, &got[i].both}) ASSERT_EQ(r->error, "");
    for (const DressResult* r : {&got[i].settle, &got[i].both}) {
      EXPECT_EQ(r->inside, 0u) << "body " << i;
      EXPECT_EQ(r->outside_bounds, r->brute_outside) << "body " << i;
    }
    EXPECT_LT(got[i].settle.brute_outside, got[i].plain.brute_outside) << "body " << i;
    EXPECT_LE(got[i].both.brute_outside, got[i].plain.brute_outside) << "body " << i;
    RecordProperty("body" + std::to_string(i), std::to_string(got[i].plain.brute_outside) + " -> " +
                                                   std::to_string(got[i].settle.brute_outside) + ", " +
                                                   std::to_string(got[i].both.brute_outside));
  }
}

TEST(ExtrudeGarment, TheSettleRoundsKeepTheirPlacesOutsideTheBody) {
  // Mannequins 5 and 93 (seed 42): the shoulder or the upper arm runs
  // through the sleeve's first copies, so triangles between pushed nodes
  // cross the limb. When the settle rounds optimised like step 5 (relaxing
  // onto those triangles, splitting their edges at midpoints inside the
  // limb) the push took nodes out again by up to 2 L and 31 and 28 edges
  // ended outside [4/5, 4/3] L (sweep11's default). Their optimisation now
  // keeps its places outside the body (extrude_detail::optimise_outside):
  // none left, none inside, the report's count the brute force's.
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  const Box3d roi = bounds(top.model);
  const auto topo = make_mannequin_topology().value();
  for (std::size_t i : {5u, 93u}) {
    auto body = make_mannequin(sample_mannequin(42, i), topo);
    ASSERT_TRUE(body) << body.status().to_string();
    const DressResult r = design_on(*body, top, fx.body, roi, Design::kSleeve);
    ASSERT_EQ(r.error, "") << "body " << i;
    EXPECT_GT(r.pushed, 20u) << "body " << i;  // the limb is there
    EXPECT_EQ(r.inside, 0u) << "body " << i << ": deepest " << r.deepest;
    EXPECT_EQ(r.brute_outside, 0u) << "body " << i;
    EXPECT_EQ(r.outside_bounds, r.brute_outside) << "body " << i;
  }
}

TEST(ExtrudeGarment, TheSettleRoundsMoveANodeAcrossItsTangentPlane) {
  // Mannequin 67 (seed 42): the dress kept one 0.67 L edge from a node of
  // B; no node is pushed there. Its free end has three of B's nodes in its
  // ring: moving it along the edge, or by springs, stretched the edge to
  // the farther one past 4/3 L, so every settle round left it. The settle
  // rounds' repair now also tries places around the node in its tangent
  // plane (extrude_detail::optimise_outside): no edge out.
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  const auto topo = make_mannequin_topology().value();
  auto body = make_mannequin(sample_mannequin(42, 67), topo);
  ASSERT_TRUE(body) << body.status().to_string();
  const DressResult r = design_on(*body, top, fx.body, bounds(top.model), Design::kDress);
  ASSERT_EQ(r.error, "");
  EXPECT_EQ(r.inside, 0u) << "deepest " << r.deepest;
  EXPECT_EQ(r.brute_outside, 0u);
  EXPECT_EQ(r.outside_bounds, r.brute_outside);
}

TEST(ExtrudeGarment, DressSleeveAndCollarOnTheTopOutsideTheBodyOn100Mannequins) {
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "300 regenerations (long under sanitizers)";
  for (Design d : {Design::kDress, Design::kSleeve, Design::kCollar}) run_bodies(100, d);
}

TEST(ExtrudeGarment, TheDressCollarAndSleeveAsTheirOwnSurfacesTheSleeveOnAThreeSurfaceSeam) {
  // `--as-surface` on the project's top (issue 21): the dress (from the hem),
  // the ring collar (from the collar's top edge) and the sleeve (from the
  // right armhole) become surfaces of their own, joined along B. The
  // armhole runs 16 edges along the seam (a joint) between the top and its
  // collar piece: there the sleeve joins that joint, a seam of three
  // surfaces (seed 000's MESHJOINT, Fig. 4), the rest of B a joint of two.
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "six extrusions on the top (5 s in Release)";
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  const Model before = regenerate_top(fx.body, top, fx.body, bounds(top.model)).value();
  const auto checks = body_checks(fx.body);
  ASSERT_EQ(checks->error, "");
  for (Design d : {Design::kDress, Design::kCollar, Design::kSleeve}) {
    SCOPED_TRACE(static_cast<int>(d));
    auto in = design_strokes(before, d);
    ASSERT_TRUE(in) << in.status().to_string();
    ExtrudeOptions o = garment_options(*checks);
    Model plain = before;
    auto rp = extrude(plain, *in, o, ExecContext::sequential());
    ASSERT_TRUE(rp) << rp.status().to_string();
    o.as_surface = true;
    Model m = before;
    auto r = extrude(m, *in, o, ExecContext::sequential());
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_TRUE(validate(m)) << validate(m).to_string();
    // The same part as without as_surface, in a surface of its own: B's
    // nodes once more on the part's side, the part's faces all there.
    expect_part_in_its_own_surface(m, plain, before, *r);
    // The joints along B: each holds B's surface and the part's, every
    // member with the same number of edges and the same node positions;
    // together they hold each of B's edges once. The sleeve's include the
    // collar seam (three surfaces, 16 edges).
    const SurfaceIdx base = m.nodes.surface[r->base[0].value];
    std::size_t along = 0, on_seam = 0;
    ASSERT_EQ(r->joints.size(), d == Design::kSleeve ? 2u : 1u);
    for (const Joint& joint : r->joints) {
      const JointIdx j = m.resolve(joint).value();
      const auto members = m.joints.members.row(j.value);
      ASSERT_GE(members.size(), 2u);
      std::vector<std::vector<Vec3d>> sides;
      std::set<SurfaceIdx> surfaces;
      const std::size_t len = m.mesh_edges.halfedges.size(members[0].mesh_edge.value);
      for (const JointMember& jm : members) {
        const auto hs = m.mesh_edges.halfedges.row(jm.mesh_edge.value);
        EXPECT_EQ(hs.size(), len);
        surfaces.insert(m.mesh_edges.surface[jm.mesh_edge.value]);
        std::vector<Vec3d> p;
        for (HalfedgeIdx h : hs) p.push_back(m.position(m.tail(h))), p.push_back(m.position(m.head(h)));
        std::sort(p.begin(), p.end(), [](const Vec3d& a, const Vec3d& b) {
          return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
        });
        p.erase(std::unique(p.begin(), p.end()), p.end());
        sides.push_back(std::move(p));
      }
      EXPECT_EQ(surfaces.size(), members.size());
      EXPECT_TRUE(surfaces.count(base) && surfaces.count(r->part_surface));
      for (std::size_t k = 1; k < sides.size(); ++k) EXPECT_EQ(sides[k], sides[0]);
      along += len;
      if (members.size() == 3) on_seam += len;
      EXPECT_LE(members.size(), d == Design::kSleeve ? 3u : 2u);
    }
    EXPECT_EQ(along, r->base.size() - (r->base_ring ? 0 : 1));
    EXPECT_EQ(on_seam, d == Design::kSleeve ? 16u : 0u);
  }
}

TEST(ExtrudeRecipe, OnTheReferenceBodyTheReplayIsTheOriginal) {
  for (Design d : {Design::kDress, Design::kSleeve, Design::kCollar}) {
    const Recorded rec = record(d);
    ASSERT_FALSE(rec.recipe.base.empty());
    const auto& fx = atelier::testing::template_fixture();
    const auto checks = body_checks(fx.body);
    Model m = rec.before;
    auto r = replay_extrusion(m, rec.recipe, garment_options(*checks), ExecContext::sequential());
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_TRUE(validate(m)) << validate(m).to_string();
    // The copies of B to rounding, then the same sewing and optimisation:
    // the same model, node for node and face for face.
    ASSERT_EQ(r->copies, rec.report.copies);
    for (std::size_t k = 0; k < r->copies; ++k) {
      EXPECT_NEAR((r->rotations[k] - rec.report.rotations[k]).norm(), 0, 1e-12);
      EXPECT_NEAR((r->translations[k] - rec.report.translations[k]).norm(), 0, 1e-12);
      EXPECT_EQ(r->scales[k], rec.report.scales[k]);
    }
    ASSERT_EQ(m.nodes.slots.capacity(), rec.after.nodes.slots.capacity());
    ASSERT_EQ(m.faces.slots.capacity(), rec.after.faces.slots.capacity());
    double worst = 0;
    for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
      ASSERT_EQ(m.alive(NodeIdx{v}), rec.after.alive(NodeIdx{v}));
      if (m.alive(NodeIdx{v}))
        worst = std::max(worst, (m.position(NodeIdx{v}) - rec.after.position(NodeIdx{v})).norm());
    }
    std::vector<NodeIdx> f0, f1;
    for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
      ASSERT_EQ(m.alive(FaceIdx{f}), rec.after.alive(FaceIdx{f}));
      if (!m.alive(FaceIdx{f})) continue;
      m.face_nodes(FaceIdx{f}, f0);
      rec.after.face_nodes(FaceIdx{f}, f1);
      ASSERT_EQ(f0, f1) << "face " << f;
    }
    EXPECT_LT(worst, 1e-9) << "design " << static_cast<int>(d);
    RecordProperty("design" + std::to_string(static_cast<int>(d)) + "_max_node_difference", std::to_string(worst));
  }
}

TEST(ExtrudeRecipe, RefusesAPaintedBaseAndABaseThatIsNotABoundary) {
  const Recorded rec = record(Design::kCollar);
  // Replayed on the model that already has the part: B is no longer a
  // boundary; the model is unchanged.
  Model m = rec.after;
  const Model before = m;
  auto r = replay_extrusion(m, rec.recipe);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(diff_tables(before, m), "");
  ExtrusionRecipe bad = rec.recipe;
  bad.base[0] = static_cast<std::uint32_t>(m.nodes.slots.capacity() + 5);
  Model m2 = rec.before;
  EXPECT_EQ(replay_extrusion(m2, bad).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(diff_tables(rec.before, m2), "");
  // The JSON text round trips bit for bit; bad text is refused by name.
  auto back = parse_extrusion_recipe(extrusion_recipe_json(rec.recipe), "r.json");
  ASSERT_TRUE(back) << back.status().to_string();
  EXPECT_EQ(back->base, rec.recipe.base);
  EXPECT_EQ(back->p1_t, rec.recipe.p1_t);
  ASSERT_EQ(back->scales.size(), rec.recipe.scales.size());
  for (std::size_t k = 0; k < back->scales.size(); ++k) {
    EXPECT_EQ(back->scales[k], rec.recipe.scales[k]);
    EXPECT_EQ(back->rotations[k], rec.recipe.rotations[k]);
    EXPECT_EQ(back->translations[k], rec.recipe.translations[k]);
  }
  for (const char* text : {"[1,2]", "{\"format\": \"atelier extrusion recipe\"}", "not json"}) {
    auto r2 = parse_extrusion_recipe(text, "r.json");
    ASSERT_FALSE(r2) << text;
    EXPECT_NE(r2.status().message().find("r.json"), std::string::npos);
  }
  ExtrudeReport painted = rec.report;
  painted.faces_removed = 3;
  EXPECT_EQ(extrusion_recipe(rec.after, painted).status().code(), ErrorCode::kUnsupported);
}

TEST(ExtrudeRecipe, DressSleeveAndCollarReplayOnAFewMannequinsWithoutStrokes) {
  replay_bodies(2);
}

TEST(ExtrudeRecipe, DressSleeveAndCollarReplayOn100MannequinsWithoutStrokes) {
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "300 regenerations (long under sanitizers)";
  replay_bodies(100);
}
