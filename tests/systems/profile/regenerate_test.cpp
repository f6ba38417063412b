// Profile templates: authoring, encoding on a reference body, regeneration
// by the modified variational subdivision with collision avoidance, and the
// quality measures of every result (seed 000 section 4, seed 001 section 4).
#include <atelier/engine/parallel.h>
#include <atelier/storage/edge_flags.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/profile/project_templates.h>
#include <atelier/systems/profile/regenerate.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>

#include "support/fixtures.h"
#include "support/project_templates.h"

using namespace atelier;
namespace fs = std::filesystem;

namespace {

using Fixture = atelier::testing::TemplateFixture;
using atelier::testing::template_fixture;

Box3d bounds(const Model& m) {
  Box3d b;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v})) b.extend(m.position(NodeIdx{v}));
  return b;
}

Box3d bounds(const std::vector<ProfileTemplate>& ts) {
  Box3d b;
  for (const auto& t : ts) {
    const Box3d x = bounds(t.model);
    b.extend(x.lo);
    b.extend(x.hi);
  }
  return b;
}

void print(const ProfileTemplate& t, const RegenQuality& q) {
  std::printf(
      "  %-9s nodes %6zu faces %6zu | inside %zu (max %.1e) min d %.4f | node clearance err %.1e | profile err "
      "%.1e | U2 %.1e | crack %.1e | %.1f ms (split %.1f push %.1f fair %.1f [%llu queries] quality %.1f)\n",
      t.name.c_str(), q.nodes, q.faces, q.inside, q.max_depth, q.min_distance, q.node_clearance_error, q.profile_error,
      q.umbrella, q.crack, q.ms, q.split_ms, q.push_ms, q.fair_ms, static_cast<unsigned long long>(q.fair_queries),
      q.quality_ms);
}

// A template over a hand-built model: every node encoded as an offset from
// the mannequin's first feature point (seed 000 eq. (2)), so it decodes on
// the same body exactly where it was.
ProfileTemplate template_over(const Model& m, const ReferenceBody& body, const Vec3d& shift) {
  ProfileTemplate t;
  t.name = "fixture";
  t.model = m;
  const std::int32_t fp = body.points.front().id;
  for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v) {
    t.model.nodes.position[v] += shift;
    t.encodings.nodes.push_back(encode_on_feature_point(body, fp, t.model.nodes.position[v], true).value());
    t.node_names.push_back("n" + std::to_string(v));
  }
  t.levels = 3;
  return t;
}

}  // namespace

TEST(ProjectTemplates, BuildValidateAndFaceOutwards) {
  const Fixture& f = template_fixture();
  ASSERT_EQ(f.templates.size(), 3u);
  BodyCollider col;
  ASSERT_TRUE(col.build(f.body.model, f.body.skin, skin_positions(f.body), {}, {.use_grid = false}));
  for (const auto& t : f.templates) {
    EXPECT_TRUE(validate_template(t)) << t.name;
    // Every face's normal points away from the body: a step along it goes
    // farther from the skin (faces were listed counter-clockwise from outside).
    std::size_t outward = 0, total = 0;
    std::vector<NodeIdx> ring;
    for (std::uint32_t f2 = 0; f2 < t.model.faces.slots.capacity(); ++f2) {
      t.model.face_nodes(FaceIdx{f2}, ring);
      Vec3d c = Vec3d::Zero(), n = Vec3d::Zero();
      for (std::size_t k = 0; k < ring.size(); ++k) {
        c += t.model.position(ring[k]);
        n += t.model.position(ring[k]).cross(t.model.position(ring[(k + 1) % ring.size()]));
      }
      c /= static_cast<double>(ring.size());
      ++total;
      outward += col.exact(c + 0.003 * n.normalized()).distance > col.exact(c).distance;
    }
    EXPECT_GE(outward, total * 9 / 10) << t.name;  // folds at armholes and the crotch may face sideways
    // Every node has its encoded clearance, and all of them are outside.
    for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v)
      EXPECT_NEAR(t.encoded_clearance[v], col.exact(t.model.position(NodeIdx{v})).distance, 1e-12);
  }
  // Non-manifold structure: the collar on the top's inner yoke line, the
  // trousers' three surfaces meeting at the crotch.
  EXPECT_EQ(f.templates[0].model.num_surfaces(), 2u);
  EXPECT_EQ(f.templates[0].model.num_joints(), 1u);
  EXPECT_EQ(f.templates[2].model.num_surfaces(), 3u);
  EXPECT_EQ(f.templates[2].model.num_joints(), 3u);
  // Profiles: stroke point lists on the top's neckline, Bezier curves on the skirt hem.
  ASSERT_EQ(f.templates[0].profiles.size(), 2u);
  EXPECT_EQ(f.templates[0].profiles[0].kind, ProfileCurve::Kind::kPolyline);
  EXPECT_EQ(f.templates[1].profiles.size(), 8u);
}

TEST(Regenerate, OnTheReferenceBodyIsCleanAndKeepsNodes) {
  const Fixture& f = template_fixture();
  const auto pos = skin_positions(f.body);
  for (const auto& t : f.templates) {
    BodyCollider col;
    ASSERT_TRUE(col.build(f.body.model, f.body.skin, pos, bounds(t.model)));
    auto r = regenerate(t, f.body, pos, &col);
    ASSERT_TRUE(r) << r.status().to_string();
    const RegenQuality& q = r->quality;
    print(t, q);
    EXPECT_TRUE(validate(r->model)) << t.name;
    EXPECT_EQ(q.inside, 0u) << t.name;
    EXPECT_GE(q.min_distance, 0.0) << t.name;
    EXPECT_EQ(q.crack, 0.0) << t.name;
    EXPECT_EQ(q.faces, t.model.num_faces() * 64) << t.name;  // 3 levels of 1-to-4 (quads stay quads)
    // Nodes encoded outside the body decode where they were.
    for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v)
      if (t.encoded_clearance[v] > 0) {
        EXPECT_LT((r->model.position(NodeIdx{v}) - t.model.position(NodeIdx{v})).norm(), 1e-9) << t.name << " " << v;
      }
  }
}

TEST(Regenerate, InterpolatesNodesAndProfilesExactly) {
  const Fixture& f = template_fixture();
  const auto pos = skin_positions(f.body);
  for (const auto& t : f.templates) {
    RegenParams p;
    p.collision = false;
    auto r = regenerate(t, f.body, pos, nullptr, p);
    ASSERT_TRUE(r) << r.status().to_string();
    // Without push-outs every refined profile node lies on its curve.
    EXPECT_LT(r->quality.profile_error, 1e-12) << t.name;
    for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v)
      EXPECT_LT((r->model.position(NodeIdx{v}) - t.model.position(NodeIdx{v})).norm(), 1e-12) << t.name;
    EXPECT_EQ(r->quality.crack, 0.0);
  }
  // The profile nodes of the last level, checked independently against the
  // decoded curves: the skirt hem (Bezier) has 8 * 2^3 edges' worth of nodes.
  const ProfileTemplate& skirt = f.templates[1];
  RegenParams p;
  p.collision = false;
  auto r = regenerate(skirt, f.body, pos, nullptr, p).value();
  const auto curves = skirt.decode_profiles(skirt.model.nodes.position);
  std::size_t on_curve = 0;
  for (std::uint32_t v = 0; v < r.model.nodes.slots.capacity(); ++v) {
    double best = INFINITY;
    for (const auto& c : curves) best = std::min(best, c.distance(r.model.position(NodeIdx{v})));
    on_curve += best < 1e-12;
  }
  EXPECT_EQ(on_curve, 8u * 8u);  // 8 curves x (8 segments: 8 nodes each, the ends shared around the loop)
}

TEST(Regenerate, Fig17ConfigurationsRefineWithoutCracks) {
  const Fixture& f = template_fixture();
  const auto pos = skin_positions(f.body);
  const Vec3d far(0, 3.0, 0);  // away from the body: no collision involved
  std::vector<std::pair<std::string, Model>> cases;
  cases.emplace_back("fan of 3", fixtures::fan(3, 4).model);
  cases.emplace_back("fan of 5", fixtures::fan(5, 3).model);
  cases.emplace_back("inner-edge joint", fixtures::inner_edge_joint(4).model);
  for (auto& [name, model] : cases) {
    ProfileTemplate t = template_over(model, f.body, far);
    ASSERT_TRUE(validate(t.model)) << name;
    for (bool smooth : {true, false}) {
      RegenParams p;
      p.collision = false;
      p.smooth_chains = smooth;
      auto r = regenerate(t, f.body, pos, nullptr, p);
      ASSERT_TRUE(r) << name << ": " << r.status().to_string();
      EXPECT_TRUE(validate(r->model)) << name;
      EXPECT_EQ(r->quality.crack, 0.0) << name;
      EXPECT_EQ(joint_crack(r->model), 0.0) << name;
      EXPECT_EQ(r->model.num_joints(), t.model.num_joints());
      // Joint chains were split identically: 2^3 times as many edges each.
      const auto members = r->model.joints.members.row(0);
      EXPECT_EQ(r->model.mesh_edges.halfedges.size(members[0].mesh_edge.value),
                8 * t.model.mesh_edges.halfedges.size(t.model.joints.members.row(0)[0].mesh_edge.value));
    }
  }
}

TEST(Regenerate, CollisionAvoidanceRemovesPenetration) {
  // The same template regenerated without collision handling penetrates the
  // body (chord midpoints and fairing cut into convex parts of the skin);
  // with it no node is inside.
  const Fixture& f = template_fixture();
  const auto pos = skin_positions(f.body);
  const ProfileTemplate& top = f.templates[0];
  BodyCollider col;
  ASSERT_TRUE(col.build(f.body.model, f.body.skin, pos, bounds(top.model)));
  RegenParams off;
  off.collision = false;
  off.clearance = 0.0;
  auto a = regenerate(top, f.body, pos, nullptr, off).value();
  std::size_t inside = 0;
  for (std::uint32_t v = 0; v < a.model.nodes.slots.capacity(); ++v)
    inside += col.exact(a.model.position(NodeIdx{v})).distance < 0;
  EXPECT_GT(inside, 10u);
  auto b = regenerate(top, f.body, pos, &col).value();
  EXPECT_EQ(b.quality.inside, 0u);
  EXPECT_GT(b.quality.pushed + b.quality.refused_moves, 0u);
  std::printf("  top without collision: %zu nodes inside; with: %zu\n", inside, b.quality.inside);
}

TEST(Regenerate, TwoHundredMannequins) {
  // Minutes under the sanitizers: `make asan` sets ATELIER_SKIP_LONG_TESTS; `make test` runs it.
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "ATELIER_SKIP_LONG_TESTS is set";
  const Fixture& f = template_fixture();
  const auto params = sample_mannequins(200, 2026);
  struct Worst {
    std::size_t inside = 0;
    double crack = 0, depth = 0, clearance = 0;
  };
  std::vector<Worst> per(params.size());
  std::vector<std::string> errors(params.size());
  ExecContext seq = ExecContext::sequential();
  const Box3d roi = bounds(f.templates);
  ColliderPool pool;
  par::for_each_n(ExecContext{.sequential_threshold = 1, .grain = 1}, params.size(), [&](std::size_t i) {
    auto p = mannequin_positions(params[i], f.topo);
    if (!p) {
      errors[i] = p.status().to_string();
      return;
    }
    // Through a collider pool, as the batch job runs (refits after the first body of each worker).
    auto regen = regenerate_on_body(f.templates, f.body, *p, roi, {}, {.use_grid = false}, seq, pool);
    if (!regen) {
      errors[i] = regen.status().to_string();
      return;
    }
    for (std::size_t k = 0; k < f.templates.size(); ++k) {
      const auto& t = f.templates[k];
      const RegenResult* r = &(*regen)[k];
      per[i].inside += r->quality.inside;
      per[i].crack = std::max(per[i].crack, r->quality.crack);
      per[i].depth = std::max(per[i].depth, r->quality.max_depth);
      if (r->quality.inside)
        std::printf("  body %zu %s: %zu inside, depth %.4f\n", i, t.name.c_str(), r->quality.inside,
                    r->quality.max_depth);
    }
  });
  std::size_t inside = 0;
  double crack = 0;
  for (std::size_t i = 0; i < params.size(); ++i) {
    EXPECT_TRUE(errors[i].empty()) << "body " << i << ": " << errors[i];
    inside += per[i].inside;
    crack = std::max(crack, per[i].crack);
  }
  std::printf("  200 mannequins x 3 templates: %zu nodes inside, max crack %.1e\n", inside, crack);
  EXPECT_EQ(inside, 0u);
  EXPECT_EQ(crack, 0.0);
}

TEST(Regenerate, FiftyMakeHumanBodies) {
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "ATELIER_SKIP_LONG_TESTS is set";
  const fs::path dir = fs::path(ATELIER_SHARED_DATA) / "makehuman";
  if (!fs::exists(dir / "base.obj"))
    GTEST_SKIP() << "MakeHuman data not found at " << dir << " (../shared/data absent)";
  auto lib = std::make_shared<const makehuman::HumanLibrary>(makehuman::HumanLibrary::load(dir));
  auto ref = std::make_shared<const ReferenceBody>(makehuman::make_reference_body(*lib));
  // MakeHuman units are decimetres: the reference body is in metres.
  auto templates = make_project_templates(*ref);
  ASSERT_TRUE(templates) << templates.status().to_string();
  makehuman::MakeHumanSource src(lib, makehuman::sample_adults(50, 404), ref);
  std::vector<std::size_t> inside(src.size(), 0);
  std::vector<double> crack(src.size(), 0);
  std::vector<std::string> errors(src.size());
  ExecContext seq = ExecContext::sequential();
  par::for_each_n(ExecContext{.sequential_threshold = 1, .grain = 1}, src.size(), [&](std::size_t i) {
    const auto p = src.skin_positions(i);
    BodyCollider col;
    if (Status s = col.build(ref->model, ref->skin, p, bounds(*templates), {.use_grid = false}, seq); !s) {
      errors[i] = s.to_string();
      return;
    }
    for (const auto& t : *templates) {
      auto r = regenerate(t, *ref, p, &col, {}, seq);
      if (!r) {
        errors[i] = r.status().to_string();
        return;
      }
      inside[i] += r->quality.inside;
      crack[i] = std::max(crack[i], r->quality.crack);
    }
  });
  std::size_t total = 0;
  double worst = 0;
  for (std::size_t i = 0; i < src.size(); ++i) {
    EXPECT_TRUE(errors[i].empty()) << "body " << i << ": " << errors[i];
    total += inside[i];
    worst = std::max(worst, crack[i]);
  }
  std::printf("  50 MakeHuman bodies x 3 templates: %zu nodes inside, max crack %.1e\n", total, worst);
  EXPECT_EQ(total, 0u);
  EXPECT_EQ(worst, 0.0);
}

TEST(Regenerate, DeterministicAcrossThreadCounts) {
  const Fixture& f = template_fixture();
  const auto params = sample_mannequins(1, 77);
  const auto p = mannequin_positions(params[0], f.topo).value();
  BodyCollider col;
  ASSERT_TRUE(col.build(f.body.model, f.body.skin, p, bounds(f.templates)));
  for (const auto& t : f.templates) {
    ExecContext one = ExecContext::sequential(), two;
    two.threads = 2;
    two.sequential_threshold = 16;
    auto a = regenerate(t, f.body, p, &col, {}, one).value();
    auto b = regenerate(t, f.body, p, &col, {}, two).value();
    EXPECT_TRUE(diff_tables(a.model, b.model).empty()) << t.name;
  }
}

TEST(Regenerate, PooledCollidersGiveTheSameResultsAsFreshOnes) {
  // A pooled collider is refitted to each new body instead of built; the
  // queries are exact, so every result must be identical to a fresh build.
  const Fixture& f = template_fixture();
  const auto params = sample_mannequins(3, 4242);
  const Box3d roi = bounds(f.templates);
  ColliderPool pool;
  for (std::size_t i = 0; i < params.size(); ++i) {
    const auto p = mannequin_positions(params[i], f.topo).value();
    auto fresh = regenerate_on_body(f.templates, f.body, p, roi, {}, {.use_grid = false}, {});
    auto pooled = regenerate_on_body(f.templates, f.body, p, roi, {}, {.use_grid = false}, {}, pool);
    ASSERT_TRUE(fresh && pooled);
    for (std::size_t k = 0; k < f.templates.size(); ++k) {
      EXPECT_TRUE(diff_tables((*fresh)[k].model, (*pooled)[k].model).empty()) << "body " << i << " " << k;
      EXPECT_EQ((*fresh)[k].quality.min_distance, (*pooled)[k].quality.min_distance);
    }
  }
  // The pool kept one collider, built: the next body is a refit.
  auto c = pool.acquire();
  EXPECT_TRUE(c->built());
  EXPECT_TRUE(c->reusable_for(f.body.model, f.body.skin, roi, {.use_grid = false}));
  EXPECT_FALSE(c->reusable_for(f.body.model, f.body.skin, Box3d{}, {.use_grid = false}));
  std::vector<Vec3d> few(10, Vec3d::Zero());
  EXPECT_EQ(c->update(few).code(), ErrorCode::kMismatch);
  auto p = skin_positions(f.body);
  p[f.topo.num_nodes / 2].x() = std::nan("");
  EXPECT_FALSE(c->update(p));
  BodyCollider never_built;
  EXPECT_FALSE(never_built.update(skin_positions(f.body)));
}

TEST(Regenerate, BadInputIsRefused) {
  const Fixture& f = template_fixture();
  const auto pos = skin_positions(f.body);
  const ProfileTemplate& t = f.templates[1];
  std::vector<Vec3d> short_pos(pos.begin(), pos.begin() + 10);
  auto a = regenerate(t, f.body, short_pos, nullptr, {.collision = false});
  ASSERT_FALSE(a);
  EXPECT_EQ(a.status().code(), ErrorCode::kMismatch);
  auto b = regenerate(t, f.body, pos, nullptr);  // collision without a collider
  ASSERT_FALSE(b);
  EXPECT_EQ(b.status().code(), ErrorCode::kInvalidArgument);
  // An open body cannot answer inside tests.
  Model open = fixtures::grid_patch(3, 3).model;
  BodyCollider col;
  const Status s = col.build(open, SurfaceIdx{0}, open.nodes.position, {});
  EXPECT_FALSE(s);
  // A NaN body position is named.
  auto nan_pos = pos;
  nan_pos[0] = Vec3d(NAN, 0, 0);
  BodyCollider col2;
  EXPECT_FALSE(col2.build(f.body.model, f.body.skin, nan_pos, {}));
}

namespace {

std::size_t seam_edges(const Model& m) {
  std::size_t n = 0;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e)
    n += m.alive(EdgeIdx{e}) && (m.edges.flags[e] & kEdgeSeam);
  return n;
}

}  // namespace

TEST(Template, SeamMarksAreSetOnTheirEdgesOnlyAndBadChainsMarkNothing) {
  // The top marks its side seams (3 edges each), shoulder seams (1 each)
  // and the yoke line at the front and back (2 each): 12 template edges;
  // the skirt and trousers mark none.
  const Fixture& f = template_fixture();
  EXPECT_EQ(seam_edges(f.templates[0].model), 12u);
  EXPECT_EQ(seam_edges(f.templates[1].model), 0u);
  EXPECT_EQ(seam_edges(f.templates[2].model), 0u);
  // A small template: one triangle on three body vertices.
  TemplateBuilder b(f.body, "patch");
  const char* names[] = {"a", "b", "c"};
  for (int k = 0; k < 3; ++k)
    ASSERT_TRUE(
        b.node_at(names[k], f.body.model.nodes.position[100u * static_cast<unsigned>(k)], NodeEncodingMode::kVertex));
  const std::vector<std::vector<std::string>> faces = {{"a", "b", "c"}};
  ASSERT_TRUE(b.surface("patch", faces));
  const Status unknown = b.seam("patch", std::vector<std::string>{"a", "b", "x"});
  EXPECT_EQ(unknown.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(unknown.message().find("'x'"), std::string::npos) << unknown.message();
  EXPECT_FALSE(b.seam("patch", std::vector<std::string>{"a"}));
  EXPECT_FALSE(b.seam("cape", std::vector<std::string>{"a", "b"}));
  ASSERT_TRUE(b.seam("patch", std::vector<std::string>{"b", "c"}));
  auto t = b.build();
  ASSERT_TRUE(t) << t.status().to_string();
  ASSERT_EQ(seam_edges(t->model), 1u);  // b - c only: the refused chains marked nothing
  for (std::uint32_t e = 0; e < t->model.edges.slots.capacity(); ++e)
    if (t->model.edges.flags[e] & kEdgeSeam) {
      const HalfedgeIdx h = halfedge_of(EdgeIdx{e}, 0);
      const std::string ends[2] = {t->node_names[t->model.tail(h).value], t->node_names[t->model.head(h).value]};
      EXPECT_TRUE((ends[0] == "b" && ends[1] == "c") || (ends[0] == "c" && ends[1] == "b"));
    }
}
