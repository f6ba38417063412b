// Curves that follow the garment (issue 20): curves painted once on the
// reference result, stored in surface coordinates, copied onto the garment
// regenerated on other bodies, and cut or partitioned there: the same pieces
// (face counts) on every body.
//
//  - the project's top (systems/profile/project_templates.h), regenerated
//    (systems/profile/regenerate.h) on 100 mannequins (sample_mannequin);
//  - a MakeHuman garment through the detail-template path (decode, edge
//    transfer, collision pass: systems/garment/regenerate_garment.h).
#include <atelier/engine/parallel.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/garment/makehuman_binding.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <atelier/systems/profile/regenerate.h>
#include <atelier/systems/sketch/cut.h>
#include <atelier/systems/sketch/paint.h>
#include <atelier/systems/sketch/transfer.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <limits>
#include <mutex>

#include "support/project_templates.h"
#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;
namespace fs = std::filesystem;

namespace {

/// Curves painted on the reference result, and where the cut's pick is.
struct PaintedDesign {
  std::vector<AttribEdge> cut, seam;
  std::optional<SurfaceLocation> pick;
};

/// The pieces a design gives: face counts (and removed flags) of the cut's
/// pieces, then of the partition's.
struct Outcome {
  std::vector<std::pair<std::size_t, bool>> cut;
  std::vector<std::size_t> partition;
  std::size_t faces = 0;
  friend bool operator==(const Outcome&, const Outcome&) = default;
};

Expected<Outcome> apply_design(Model& m, const PaintedDesign& d) {
  Outcome o;
  auto c = cut_along_curves(m, d.cut, {.pick = d.pick});
  if (!c) return c.status();
  for (const Piece& p : c->pieces) o.cut.emplace_back(p.faces, p.removed);
  auto p = partition_along_curves(m, d.seam);
  if (!p) return p.status();
  for (const Piece& x : p->pieces) o.partition.push_back(x.faces);
  if (Status s = validate(m); !s) return s;
  o.faces = m.num_faces();
  return o;
}

/// Copies the design's curves from the painted reference onto `m`.
Expected<PaintedDesign> transfer_design(const Model& from, const PaintedDesign& d, Model& m) {
  PaintedDesign out;
  auto c = transfer_curves(from, d.cut, m);
  if (!c) return c.status();
  auto s = transfer_curves(from, d.seam, m);
  if (!s) return s.status();
  out.cut = *c;
  out.seam = *s;
  out.pick = d.pick;
  return out;
}

}  // namespace

TEST(FollowGarment, TopNecklineAndSeamOn100Mannequins) {
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "100 regenerations (long under sanitizers)";
  const auto& fx = atelier::testing::template_fixture();
  const ProfileTemplate& top = fx.templates[0];
  ASSERT_EQ(top.name, "top");
  const Box3d roi = bounds(top.model);
  RegenParams rp;
  ColliderPool pool;
  auto regen = [&](const ReferenceBody& body) -> Expected<Model> {
    const ProfileTemplate one[] = {top};
    auto r = regenerate_on_body(one, fx.body, skin_positions(body), roi, rp, {.use_grid = false},
                                ExecContext::sequential(), pool);
    if (!r) return r.status();
    return std::move((*r)[0].model);
  };
  // The reference result: the top on the reference mannequin.
  auto ref = regen(fx.body);
  ASSERT_TRUE(ref) << ref.status().to_string();
  Model m0 = std::move(*ref);
  const Model unpainted = m0;
  // A front view from a little below (the back of the neck band hides behind
  // the front); painting only on the top itself (the collar stands in front
  // of its neck band and is not cut).
  const Camera cam = Camera::orthographic(Vec3d(0, 0.6, 2), Vec3d(0, 1.2, 0), Vec3d::UnitY(), 0.45, 800, 800);
  const std::vector<SurfaceIdx> top_only{SurfaceIdx{0}};
  ASSERT_EQ(m0.surfaces.name[0], "top");
  // Neckline: a scoop from the neck edge down to just above the yoke line
  // and back up (the cut removes the front of the neck band above it).
  std::vector<Vec3d> scoop;
  for (int k = 0; k <= 40; ++k) {
    const double x = -0.075 + 0.15 * k / 40.0;
    scoop.push_back(Vec3d(x, 1.395 + 0.08 * std::pow(std::abs(x) / 0.075, 2.0), 0.09));
  }
  auto neck = paint_stroke(m0, cam, project(cam, scoop), {.surfaces = top_only});
  ASSERT_TRUE(neck) << neck.status().to_string();
  // Seam: all the way round at the waist (penetrated painting: front and back).
  auto seam = paint_stroke(m0, cam, project(cam, {Vec3d(-0.4, 1.08, 0), Vec3d(0.4, 1.1, 0)}),
                           {.through = true, .surfaces = top_only});
  ASSERT_TRUE(seam) << seam.status().to_string();
  ASSERT_EQ(seam->curves.size(), 2u);
  auto pick = locate_pixel(m0, cam, cam.project(Vec3d(0, 1.42, 0.09)).head<2>(), top_only);
  ASSERT_TRUE(pick);
  const PaintedDesign design{edges_of(*neck), edges_of(*seam), pick->location};
  EXPECT_TRUE(validate(m0));
  Model ref_cut = m0;
  auto expect = apply_design(ref_cut, design);
  ASSERT_TRUE(expect) << expect.status().to_string();
  ASSERT_EQ(expect->cut.size(), 2u);
  ASSERT_EQ(expect->partition.size(), 2u);
  // The neckline piece is small, the waist seam splits the rest in two.
  EXPECT_LT(std::min(expect->cut[0].first, expect->cut[1].first), 200u);

  // 100 sampled mannequins.
  const auto topo = make_mannequin_topology().value();
  constexpr std::size_t kBodies = 100;
  std::vector<std::string> errors(kBodies);
  std::vector<Outcome> got(kBodies);
  ExecContext ctx;
  ctx.sequential_threshold = 2;
  ctx.grain = 1;
  par::for_each_n(ctx, kBodies, [&](std::size_t i) {
    auto body = make_mannequin(sample_mannequin(42, i), topo);
    if (!body) {
      errors[i] = body.status().to_string();
      return;
    }
    auto m = regen(*body);
    if (!m) {
      errors[i] = m.status().to_string();
      return;
    }
    if (Status s = check_same_topology(unpainted, *m); !s) {
      errors[i] = s.to_string();
      return;
    }
    auto d = transfer_design(m0, design, *m);
    if (!d) {
      errors[i] = d.status().to_string();
      return;
    }
    // The curves moved with the garment: on this body's surface, not the reference's.
    const AttribNodeIdx a = m->attrib_edges.nodes.row(d->seam[0].idx.value)[3];
    if ((m->attrib_nodes.position[a.value] - m->attrib_position_on_surface(a)).norm() > 1e-12) {
      errors[i] = "transferred curve node not on the surface";
      return;
    }
    auto o = apply_design(*m, *d);
    if (!o) {
      errors[i] = o.status().to_string();
      return;
    }
    got[i] = *o;
  });
  std::size_t moved = 0;
  for (std::size_t i = 0; i < kBodies; ++i) {
    ASSERT_EQ(errors[i], "") << "body " << i;
    EXPECT_EQ(got[i], *expect) << "body " << i;
  }
  (void)moved;
}

TEST(FollowGarment, MakeHumanGarmentThroughTheDetailTemplate) {
  const fs::path dir = fs::path(ATELIER_SHARED_DATA) / "makehuman";
  if (!fs::exists(dir / "base.obj")) GTEST_SKIP() << "MakeHuman data not found at " << dir;
  using namespace atelier::makehuman;
  const HumanLibrary lib = HumanLibrary::load(dir);
  const ReferenceBody ref = make_reference_body(lib);
  auto family = GarmentFamily::of(ref);
  ASSERT_TRUE(family) << family.status().to_string();
  // The garment fitted on the reference body by its binding (metres); the
  // model over the same vertices (node i = vertex i).
  auto soup = fitted_garment(lib, dir / "clothes" / "female_casualsuit01.mhclo");
  ASSERT_TRUE(soup) << soup.status().to_string();
  Model m0;
  ASSERT_TRUE(add_polygon_surface(m0, "suit", *soup));
  ASSERT_EQ(m0.nodes.slots.capacity(), soup->positions.size());
  std::vector<std::array<std::uint32_t, 2>> edges;
  for (std::uint32_t e = 0; e < m0.edges.slots.capacity(); ++e)
    edges.push_back({m0.tail(halfedge_of(EdgeIdx{e}, 0)).value, m0.head(halfedge_of(EdgeIdx{e}, 0)).value});
  auto garment = encode_garment(*family, "suit", *soup, {.edges = edges});
  ASSERT_TRUE(garment) << garment.status().to_string();
  const Model unpainted = m0;

  // Paint once on the garment on the reference body: shorten the legs below
  // the knee (through both legs; without a pick the small pieces go) and a
  // seam all the way round at the waist.
  const Box3d box = bounds(m0);
  const Vec3d c = 0.5 * (box.lo + box.hi);
  const Camera cam = Camera::orthographic(c + Vec3d(0, 0, 3), c, Vec3d::UnitY(), 0.8, 800, 800);
  // Heights were chosen in base.obj's frame (centred mid-body); bodies
  // now stand on y = 0 (issue 26), so the strokes move up by base.obj's
  // sole height.
  float sole = std::numeric_limits<float>::infinity();
  for (std::uint32_t v = 0; v < lib.skin_vertex_count(); ++v) sole = std::min(sole, lib.base().positions[v].y());
  const double up = -kMakeHumanToMetres * sole;
  auto knee =
      paint_stroke(m0, cam, project(cam, {Vec3d(-0.6, -0.35 + up, 0), Vec3d(0.6, -0.33 + up, 0)}), {.through = true});
  ASSERT_TRUE(knee) << knee.status().to_string();
  auto waist =
      paint_stroke(m0, cam, project(cam, {Vec3d(-0.6, 0.02 + up, 0), Vec3d(0.6, 0.0 + up, 0)}), {.through = true});
  ASSERT_TRUE(waist) << waist.status().to_string();
  const PaintedDesign design{edges_of(*knee), edges_of(*waist), std::nullopt};
  Model ref_cut = m0;
  auto expect = apply_design(ref_cut, design);
  ASSERT_TRUE(expect) << expect.status().to_string();
  std::size_t removed = 0;
  for (const auto& [faces, gone] : expect->cut) removed += gone;
  EXPECT_EQ(removed, 2u);  // both lower legs
  EXPECT_GE(expect->partition.size(), 2u);

  // Sampled adult bodies through the garment pipeline (decode, edge
  // transfer, collision pass: regenerate_garment), then the same curves cut
  // and partition the regenerated garment.
  const auto params = sample_adults(8, 77);
  for (std::size_t b = 0; b < params.size(); ++b) {
    std::vector<Vec3f> H(lib.vertex_count());
    lib.build(params[b], H);
    std::vector<Vec3d> skin(family->reference_positions.size());
    for (std::size_t v = 0; v < skin.size(); ++v) skin[v] = kMakeHumanToMetres * H[v].cast<double>();
    auto fit = regenerate_garment(*family, *garment, skin);
    ASSERT_TRUE(fit) << "body " << b << ": " << fit.status().to_string();
    Model m = unpainted;
    m.nodes.position = fit->positions;
    double moved = 0;
    for (std::size_t v = 0; v < fit->positions.size(); ++v)
      moved = std::max(moved, (fit->positions[v] - soup->positions[v]).norm());
    EXPECT_GT(moved, 0.01) << "body " << b;  // another body, another garment shape
    auto d = transfer_design(m0, design, m);
    ASSERT_TRUE(d) << d.status().to_string();
    auto o = apply_design(m, *d);
    ASSERT_TRUE(o) << "body " << b << ": " << o.status().to_string();
    EXPECT_EQ(*o, *expect) << "body " << b;
  }
}

TEST(FollowGarment, AnotherTopologyIsRefused) {
  Model a = icosphere(2), b = icosphere(3);
  const Camera cam = front_ortho();
  auto p = paint_stroke(a, cam, project(cam, {Vec3d(-1.4, 0.1, 0), Vec3d(1.4, 0.1, 0)}));
  ASSERT_TRUE(p);
  const Model before = b;
  auto t = transfer_curves(a, edges_of(*p), b);
  ASSERT_FALSE(t);
  EXPECT_EQ(t.status().code(), ErrorCode::kMismatch);
  EXPECT_NE(t.status().message().find("level"), std::string::npos) << t.status().message();
  EXPECT_EQ(diff_tables(before, b), "");
  // The same topology, other positions: the curve follows.
  Model c = a;
  for (auto& q : c.nodes.position) q *= 2.0;
  auto u = transfer_curves(a, edges_of(*p), c);
  ASSERT_TRUE(u);
  const auto ra = a.attrib_edges.nodes.row(edges_of(*p)[0].idx.value);
  const auto rc = c.attrib_edges.nodes.row((*u)[0].idx.value);
  ASSERT_EQ(ra.size(), rc.size());
  for (std::size_t k = 0; k < ra.size(); ++k)
    EXPECT_LT((c.attrib_position_on_surface(rc[k]) - 2.0 * a.attrib_position_on_surface(ra[k])).norm(), 1e-12);
  EXPECT_TRUE(validate(c));
}
