// Outfits (issue 26): several garments of one body resolved together in
// layer order. Checked independently of the engine's counters: the body
// side by the spatial family's BVH signed distance (not the collision
// body the pass and its counters use) and, on a few bodies, by the brute
// force generalized winding number; the garment side by a brute-force ray
// against every triangle of the inner garment (Moller-Trumbore in double).
#include <atelier/storage/builder.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/garment/fit_measure.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>

namespace atelier {
namespace {

struct Outfit {
  std::shared_ptr<const MannequinTopology> topo;
  std::shared_ptr<const ReferenceBody> ref;
  std::shared_ptr<const GarmentFamily> family;
  std::vector<std::shared_ptr<const GarmentTemplate>> layers;  // given outer first: z_depth must order them
};

// Three bands that overlap on the reference body in the wrong order: the
// innermost (tights, z 0) is the loosest, the outermost (skirt, z 2) lies
// between the two others. Fitted one by one, each keeps its own clearance
// and they cross; as an outfit they must not. `crotch`: the bands go down
// the thighs across the crotch, a concave crease (see CrotchCrease below);
// otherwise they cover the waist and hips above it.
const Outfit& outfit(bool crotch = false) {
  auto make = [](bool c) {
    Outfit r;
    r.topo =
        std::make_shared<const MannequinTopology>(make_mannequin_topology(MannequinResolution::from_level(3)).value());
    r.ref = std::make_shared<const ReferenceBody>(make_mannequin(MannequinParams{}, *r.topo).value());
    r.family = std::make_shared<const GarmentFamily>(GarmentFamily::of(*r.ref).value());
    struct Band {
      const char* name;
      double lo, hi, offset;
      int z;
    };
    const double d = c ? 0.0 : 0.20;  // the reference's crotch is near y = 0.80
    for (const Band& b : {Band{"skirt", 0.66 + d, 1.02, 0.006, 2}, Band{"shorts", 0.72 + d, 1.06, 0.003, 1},
                          Band{"tights", 0.60 + d, 1.10, 0.009, 0}}) {
      const Model m = skin_band_garment(*r.ref, b.lo, b.hi, b.offset, 0.40, b.name).value();
      GarmentTemplate t = encode_garment(*r.family, b.name, polygon_soup(m)).value();
      t.z_depth = b.z;
      r.layers.push_back(std::make_shared<const GarmentTemplate>(std::move(t)));
    }
    return r;
  };
  static const Outfit hips = make(false), legs = make(true);
  return crotch ? legs : hips;
}

BodySet outfit_bodies(std::size_t n, std::uint64_t seed) {
  const Outfit& o = outfit();  // the topology and reference are the same for both
  MannequinSource src(o.topo, n, seed, o.ref);
  BodySet set(o.ref);
  std::vector<BodyFailure> failures;
  src.generate(0, n, set, failures, {});
  EXPECT_TRUE(failures.empty());
  return set;
}

/// The outfit's garments each fitted on its own (no layers): they cross.
std::vector<BodyGarments> fitted_apart(const Outfit& o, const BodySet& set) {
  GarmentRegenOptions apart;
  apart.layers = false;
  auto alone = GarmentRegenerator::create(o.family, o.layers, apart);
  std::vector<BodyGarments> out;
  if (!alone || !alone->run(set, 0, set.size(), out)) out.clear();
  return out;
}

/// Brute force: the first t in (0, tmax] where origin + t dir meets one of
/// the triangles (Moller-Trumbore), or infinity.
double first_hit(const Vec3d& o, const Vec3d& d, std::span<const Vec3d> p, std::span<const Triangle> tris,
                 double tmax) {
  double best = std::numeric_limits<double>::infinity();
  for (const Triangle& t : tris) {
    const Vec3d a = p[t[0]], e1 = p[t[1]] - a, e2 = p[t[2]] - a;
    const Vec3d h = d.cross(e2);
    const double det = e1.dot(h);
    if (std::abs(det) < 1e-18) continue;
    const Vec3d s = o - a;
    const double u = s.dot(h) / det;
    if (u < 0 || u > 1) continue;
    const Vec3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const double tt = e2.dot(q) / det;
    if (tt > 0 && tt <= tmax) best = std::min(best, tt);
  }
  return best;
}

/// Per garment, the vertices inside a lower layer by the definition of
/// count_inside_layer, computed by brute force; body distances from the
/// spatial family's BVH.
std::vector<std::size_t> independent_layer_count(const Outfit& o, const BodyBvh& bvh, const BodyGarments& g,
                                                 std::size_t& inside_body) {
  const double probe = LayerPenetrationParams{}.probe, tolerance = LayerPenetrationParams{}.tolerance;
  std::vector<std::size_t> count(o.layers.size(), 0);
  std::vector<std::vector<Triangle>> tris;
  for (const auto& l : o.layers) tris.push_back(fan_triangulate(l->mesh));
  for (std::size_t i = 0; i < o.layers.size(); ++i) {
    for (const Vec3d& p : g.garments[i].positions) {
      const SignedHit h = bvh.signed_distance(p);
      if (h.distance < 0) ++inside_body;
      if (!(h.distance > 0)) continue;
      const Vec3d x = h.closest.point, dir = (p - x) / h.distance;
      bool inside = false;
      for (std::size_t j = 0; j < o.layers.size() && !inside; ++j) {
        if (o.layers[j]->z_depth >= o.layers[i]->z_depth) continue;
        const double t = first_hit(x, dir, g.garments[j].positions, tris[j], h.distance + probe);
        inside = t > h.distance + tolerance && std::isfinite(t);
      }
      count[i] += inside;
    }
  }
  return count;
}

void check_outfit(std::size_t n, std::uint64_t seed) {
  const Outfit& o = outfit();
  const BodySet set = outfit_bodies(n, seed);
  auto layered = GarmentRegenerator::create(o.family, o.layers);
  GarmentRegenOptions apart;
  apart.layers = false;
  auto alone = GarmentRegenerator::create(o.family, o.layers, apart);
  ASSERT_TRUE(layered && alone);
  std::vector<BodyGarments> out, out_alone;
  ASSERT_TRUE(layered->run(set, 0, set.size(), out));
  ASSERT_TRUE(alone->run(set, 0, set.size(), out_alone));
  const auto tris = fan_triangulate(o.ref->model).value();
  std::size_t crossed_alone = 0;
  for (std::size_t b = 0; b < set.size(); ++b) {
    ASSERT_TRUE(out[b].status) << out[b].status.to_string();
    ASSERT_TRUE(out_alone[b].status);
    const std::vector<Vec3d> body = set.positions(b);
    BodyBvh bvh;
    ASSERT_TRUE(bvh.build(body, tris.triangles));
    std::size_t inside_body = 0;
    const auto count = independent_layer_count(o, bvh, out[b], inside_body);
    EXPECT_EQ(inside_body, 0u) << "body " << b;
    for (std::size_t i = 0; i < o.layers.size(); ++i) {
      EXPECT_EQ(count[i], 0u) << "body " << b << ": " << o.layers[i]->name << " inside a lower layer";
      EXPECT_EQ(out[b].garments[i].quality.layer_inside, count[i]) << "body " << b << " " << o.layers[i]->name;
      EXPECT_EQ(out[b].garments[i].quality.inside, 0u);
    }
    // Fitted one by one the same garments cross: the check above can fail.
    std::size_t ignored = 0;
    const auto crossed = independent_layer_count(o, bvh, out_alone[b], ignored);
    for (std::size_t c : crossed) crossed_alone += c;
  }
  EXPECT_GT(crossed_alone, 10 * n) << "the unlayered garments should cross on every body";
}

TEST(Outfit, ThreeLayersOnTenBodiesStayOutsideTheBodyAndEachOther) {
  check_outfit(10, 5);
}

TEST(Outfit, ThreeLayersOnAHundredBodiesStayOutsideTheBodyAndEachOther) {
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "long: 100 bodies with brute-force checks";
  check_outfit(100, 26);
}

// The known limit: across the crotch, a concave crease, a few outer
// vertices on the crease's medial axis stay 1-3 mm under a lower layer
// (the closest body point, and with it the push and the ray, jumps from
// one thigh to the other). Bounded here so that a regression shows.
TEST(Outfit, AcrossTheCrotchCreaseOnlyAFewMedialVerticesStayUnderALowerLayer) {
  const Outfit& o = outfit(true);
  const BodySet set = outfit_bodies(10, 5);
  auto layered = GarmentRegenerator::create(o.family, o.layers);
  ASSERT_TRUE(layered);
  std::vector<BodyGarments> out;
  ASSERT_TRUE(layered->run(set, 0, set.size(), out));
  const auto tris = fan_triangulate(o.ref->model).value();
  std::size_t under = 0, outer_vertices = 0;
  for (std::size_t b = 0; b < set.size(); ++b) {
    ASSERT_TRUE(out[b].status) << out[b].status.to_string();
    BodyBvh bvh;
    ASSERT_TRUE(bvh.build(set.positions(b), tris.triangles));
    std::size_t inside_body = 0;
    const auto count = independent_layer_count(o, bvh, out[b], inside_body);
    EXPECT_EQ(inside_body, 0u) << "body " << b;
    for (std::size_t i = 0; i < o.layers.size(); ++i) {
      under += count[i];
      if (o.layers[i]->z_depth > 0) outer_vertices += out[b].garments[i].positions.size();
    }
  }
  RecordProperty("outer_vertices_under_a_lower_layer", static_cast<int>(under));
  RecordProperty("outer_vertices", static_cast<int>(outer_vertices));
  EXPECT_LE(static_cast<double>(under), 0.002 * static_cast<double>(outer_vertices))
      << under << " of " << outer_vertices << " outer vertices under a lower layer";
}

TEST(Outfit, TheLayerCounterAgreesWithBruteForceOnCrossingGarments) {
  // The engine's counter (count_inside_layer) on garments that do cross.
  const Outfit& o = outfit();
  const BodySet set = outfit_bodies(3, 7);
  const std::vector<BodyGarments> out = fitted_apart(o, set);
  ASSERT_EQ(out.size(), set.size());
  const auto tris = fan_triangulate(o.ref->model).value();
  for (std::size_t b = 0; b < set.size(); ++b) {
    const std::vector<Vec3d> body = set.positions(b);
    BodyBvh bvh;
    ASSERT_TRUE(bvh.build(body, tris.triangles));
    std::size_t ignored = 0;
    const auto expected = independent_layer_count(o, bvh, out[b], ignored);
    CollisionBody cb;
    ASSERT_TRUE(cb.build(o.family->collision, body));
    // shorts (z 1) under tights (z 0): one inner layer, so counts compare directly.
    const std::size_t shorts = 1, tights = 2;
    std::vector<BodyDistance> d(out[b].garments[shorts].positions.size());
    ASSERT_TRUE(cb.query_many(out[b].garments[shorts].positions, {}, d));
    BodyBvh inner;
    ASSERT_TRUE(inner.build(out[b].garments[tights].positions, fan_triangulate(o.layers[tights]->mesh)));
    auto n = count_inside_layer(out[b].garments[shorts].positions, d, inner);
    ASSERT_TRUE(n);
    EXPECT_GT(*n, 0u);
    // Float rays against double brute force: a vertex on the boundary may differ.
    EXPECT_NEAR(static_cast<double>(*n), static_cast<double>(expected[shorts]), 2 + 0.01 * expected[shorts]);
  }
  // Bad input is an error, not a crash.
  BodyBvh empty;
  std::vector<Vec3d> p(2, Vec3d::Zero());
  std::vector<BodyDistance> d(1);
  EXPECT_FALSE(count_inside_layer(p, d, empty).has_value());
}

TEST(Outfit, TheLiftMovesCoveredOuterVerticesOutwardAboveTheLowerLayer) {
  // lift_over_lower_layers on garments that do cross (fitted apart): the
  // shorts (z 1) lifted over the tights (z 0). Every vertex it moves goes
  // outward along the body normal, the others keep their bits, the body
  // distances it returns are those of a fresh query, and afterwards the
  // counter (shown equal to brute force above) finds almost none covered.
  const Outfit& o = outfit();
  const BodySet set = outfit_bodies(2, 11);
  const std::vector<BodyGarments> out = fitted_apart(o, set);
  ASSERT_EQ(out.size(), set.size());
  const std::size_t shorts = 1, tights = 2;
  for (std::size_t b = 0; b < set.size(); ++b) {
    const std::vector<Vec3d> body = set.positions(b);  // the collision body reads it in place
    CollisionBody cb;
    ASSERT_TRUE(cb.build(o.family->collision, body));
    std::vector<Vec3d> p = out[b].garments[shorts].positions;
    const std::vector<Vec3d> p0 = p;
    std::vector<BodyDistance> d(p.size());
    ASSERT_TRUE(cb.query_many(p, {}, d));
    const std::vector<BodyDistance> d0 = d;
    BodyBvh inner;
    ASSERT_TRUE(inner.build(out[b].garments[tights].positions, fan_triangulate(o.layers[tights]->mesh)));
    const auto before = count_inside_layer(p, d, inner);
    ASSERT_TRUE(before);
    ASSERT_GT(*before, 0u);
    const double gap = 0.001;
    auto lifted = lift_over_lower_layers(p, d, std::span<const BodyBvh>(&inner, 1), cb, 0.01, gap);
    ASSERT_TRUE(lifted) << lifted.status().message();
    EXPECT_GE(*lifted, *before);
    std::vector<BodyDistance> fresh(p.size());
    ASSERT_TRUE(cb.query_many(p, {}, fresh));
    std::size_t moved = 0;
    for (std::size_t v = 0; v < p.size(); ++v) {
      EXPECT_NEAR(d[v].distance, fresh[v].distance, 1e-9) << "vertex " << v;
      if (p[v] == p0[v]) continue;
      ++moved;
      EXPECT_GT(d[v].distance, d0[v].distance + 0.5 * gap) << "vertex " << v << " was not moved outward";
    }
    EXPECT_GE(moved, *before);
    const auto after = count_inside_layer(p, d, inner);
    ASSERT_TRUE(after);
    EXPECT_LE(static_cast<double>(*after), 0.05 * static_cast<double>(*before) + 2)
        << *after << " of " << *before << " still covered";
  }
  // Bad input is an error and leaves the positions as they were.
  std::vector<Vec3d> p(2, Vec3d::Ones());
  std::vector<BodyDistance> d(1);
  const std::vector<Vec3d> body = set.positions(0);
  CollisionBody cb;
  ASSERT_TRUE(cb.build(o.family->collision, body));
  BodyBvh empty;
  EXPECT_FALSE(lift_over_lower_layers(p, d, {}, cb, 0.01, 0.001).has_value());
  d.resize(2);
  EXPECT_FALSE(lift_over_lower_layers(p, d, std::span<const BodyBvh>(&empty, 1), cb, 0.01, 0.001).has_value());
  EXPECT_FALSE(lift_over_lower_layers(p, d, {}, cb, 0.01, 0.0).has_value());
  EXPECT_EQ(p, std::vector<Vec3d>(2, Vec3d::Ones()));
}

}  // namespace
}  // namespace atelier
