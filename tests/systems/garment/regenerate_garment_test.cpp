// The garment-regeneration pipeline (systems/garment/regenerate_garment.h):
// batched and single-body paths agree, results do not depend on the thread
// count, errors are returned per body, layers keep garments apart, and a
// garment template survives its files.
#include <atelier/systems/garment/regenerate_garment.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>

#include <atelier/storage/builder.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/mesh/fan_triangulation.h>

namespace atelier {
namespace {

namespace fs = std::filesystem;

struct Scene {
  std::shared_ptr<const MannequinTopology> topo;
  std::shared_ptr<const ReferenceBody> ref;
  std::shared_ptr<const GarmentFamily> family;
  std::shared_ptr<const GarmentTemplate> shorts, shell;
};

const Scene& scene() {
  static const Scene s = [] {
    Scene r;
    r.topo = std::make_shared<const MannequinTopology>(make_mannequin_topology(MannequinResolution::from_level(3)).value());
    r.ref = std::make_shared<const ReferenceBody>(make_mannequin(MannequinParams{}, *r.topo).value());
    r.family = std::make_shared<const GarmentFamily>(GarmentFamily::of(*r.ref).value());
    const Model inner = skin_band_garment(*r.ref, 0.70, 1.10, 0.004, 0.40, "inner").value();
    const Model outer = skin_band_garment(*r.ref, 0.75, 1.05, 0.006, 0.40, "outer").value();
    r.shorts = std::make_shared<const GarmentTemplate>(encode_garment(*r.family, "inner", polygon_soup(inner)).value());
    GarmentTemplate shell = encode_garment(*r.family, "outer", polygon_soup(outer)).value();
    shell.z_depth = 1;
    r.shell = std::make_shared<const GarmentTemplate>(std::move(shell));
    return r;
  }();
  return s;
}

BodySet bodies(std::size_t n, std::uint64_t seed) {
  const Scene& s = scene();
  MannequinSource src(s.topo, n, seed, s.ref);
  BodySet set(s.ref);
  std::vector<BodyFailure> failures;
  src.generate(0, n, set, failures, {});
  EXPECT_TRUE(failures.empty());
  return set;
}

TEST(GarmentPipeline, BatchedRunMatchesSingleBodyCallsAndIsOutsideTheBody) {
  const Scene& s = scene();
  const BodySet set = bodies(5, 11);
  auto regen = GarmentRegenerator::create(s.family, {s.shorts});
  ASSERT_TRUE(regen) << regen.status().to_string();
  std::vector<BodyGarments> out;
  ASSERT_TRUE(regen->run(set, 0, set.size(), out));
  ASSERT_EQ(out.size(), set.size());
  auto tris = fan_triangulate(s.ref->model).value();
  for (std::size_t b = 0; b < set.size(); ++b) {
    ASSERT_TRUE(out[b].status) << out[b].status.to_string();
    const std::vector<Vec3d> body = set.positions(b);
    auto one = regenerate_garment(*s.family, *s.shorts, body);
    ASSERT_TRUE(one) << one.status().to_string();
    const GarmentResult& r = out[b].garments[0];
    // Batched decoding keeps frames in float: the same garment to float rounding.
    double mx = 0;
    for (std::size_t v = 0; v < r.positions.size(); ++v) mx = std::max(mx, (r.positions[v] - one->positions[v]).norm());
    EXPECT_LT(mx, 1e-5) << "body " << b;
    // The figures are those of an independent exact query of the result.
    BodyBvh bvh;
    ASSERT_TRUE(bvh.build(body, tris.triangles));
    std::size_t inside = 0;
    double min_d = 1e300;
    for (const Vec3d& p : r.positions) {
      const double d = bvh.signed_distance(p).distance;
      inside += d < 0;
      min_d = std::min(min_d, d);
    }
    EXPECT_EQ(inside, 0u);
    EXPECT_EQ(r.quality.inside, 0u);
    EXPECT_NEAR(r.quality.min_clearance, min_d, 1e-12);
    EXPECT_GE(r.quality.min_clearance, CollisionParams{}.min_clearance - CollisionParams{}.tolerance);
    EXPECT_GT(r.quality.strain_p95, 0.0);
    EXPECT_LE(r.quality.strain_p95, r.quality.strain_max);
  }
}

// 35 bodies: three tiles of run()'s edge transfer, shared by the threads.
TEST(GarmentPipeline, SameBitsForOneAndTwoThreads) {
  const Scene& s = scene();
  const BodySet set = bodies(35, 5);
  std::vector<std::vector<BodyGarments>> runs;
  for (int threads : {1, 2}) {
    ExecContext ctx;
    ctx.threads = threads;
    auto regen = GarmentRegenerator::create(s.family, {s.shorts, s.shell}, {}, ctx);
    ASSERT_TRUE(regen);
    runs.emplace_back();
    ASSERT_TRUE(regen->run(set, 0, set.size(), runs.back(), ctx));
  }
  for (std::size_t b = 0; b < set.size(); ++b)
    for (std::size_t g = 0; g < 2; ++g) {
      const auto& a = runs[0][b].garments[g].positions;
      const auto& c = runs[1][b].garments[g].positions;
      ASSERT_EQ(a.size(), c.size());
      EXPECT_EQ(0, std::memcmp(a.data(), c.data(), a.size() * sizeof(Vec3d))) << "body " << b << " garment " << g;
      // The body's record: every figure the same bits.
      const GarmentQuality& qa = runs[0][b].garments[g].quality;
      const GarmentQuality& qc = runs[1][b].garments[g].quality;
      for (const auto& [x, y] : {std::pair{qa.min_clearance, qc.min_clearance}, {qa.mean_clearance, qc.mean_clearance},
                                 {qa.clearance_error, qc.clearance_error}, {qa.strain_max, qc.strain_max},
                                 {qa.strain_p95, qc.strain_p95}, {qa.max_depth, qc.max_depth}})
        EXPECT_EQ(0, std::memcmp(&x, &y, sizeof(double))) << "body " << b << " garment " << g;
      EXPECT_EQ(qa.inside, qc.inside);
      EXPECT_EQ(qa.pushed, qc.pushed);
      EXPECT_EQ(qa.layer_inside, qc.layer_inside);
    }
}

// run() transfers a tile of bodies as SIMD lanes: each garment is the bits
// the one-body apply_edge_transfer gives it from the same decode (run()
// without the transfer), for 19 bodies (a tile of 16 and one not full),
// two garments, on 1 and 2 threads.
TEST(GarmentPipeline, TiledTransferGivesTheOneBodyTransfersBits) {
  const Scene& s = scene();
  const BodySet set = bodies(19, 8);
  GarmentRegenOptions decode_only;
  decode_only.edge_transfer = false;
  decode_only.collision_pass = false;
  auto plain = GarmentRegenerator::create(s.family, {s.shorts, s.shell}, decode_only);
  ASSERT_TRUE(plain);
  std::vector<BodyGarments> decoded;
  ASSERT_TRUE(plain->run(set, 0, set.size(), decoded));
  GarmentRegenOptions transfer_only = decode_only;
  transfer_only.edge_transfer = true;
  for (int threads : {1, 2}) {
    ExecContext ctx;
    ctx.threads = threads;
    auto regen = GarmentRegenerator::create(s.family, {s.shorts, s.shell}, transfer_only, ctx);
    ASSERT_TRUE(regen);
    std::vector<BodyGarments> out;
    ASSERT_TRUE(regen->run(set, 0, set.size(), out, ctx));
    for (std::size_t b = 0; b < set.size(); ++b) {
      ASSERT_TRUE(out[b].status) << out[b].status.to_string();
      const std::vector<Vec3d> body = set.positions(b);
      for (std::size_t g = 0; g < 2; ++g) {
        std::vector<Vec3d> want = decoded[b].garments[g].positions;
        ASSERT_TRUE(apply_edge_transfer(regen->garment(g).transfer, body, s.family->collision->triangles(), want));
        const auto& got = out[b].garments[g].positions;
        ASSERT_EQ(got.size(), want.size());
        EXPECT_EQ(0, std::memcmp(got.data(), want.data(), got.size() * sizeof(Vec3d)))
            << threads << " threads, body " << b << " garment " << g;
        EXPECT_NE(0, std::memcmp(got.data(), decoded[b].garments[g].positions.data(), got.size() * sizeof(Vec3d)));
      }
    }
  }
}

TEST(GarmentPipeline, LayersKeepTheOuterGarmentOutsideTheInnerOne) {
  const Scene& s = scene();
  const BodySet set = bodies(4, 21);
  auto regen = GarmentRegenerator::create(s.family, {s.shell, s.shorts});  // given outer first: z_depth orders them
  ASSERT_TRUE(regen);
  std::vector<BodyGarments> out;
  ASSERT_TRUE(regen->run(set, 0, set.size(), out));
  for (std::size_t b = 0; b < set.size(); ++b) {
    ASSERT_TRUE(out[b].status);
    const GarmentQuality& outer = out[b].garments[0].quality;
    const GarmentQuality& inner = out[b].garments[1].quality;
    EXPECT_EQ(outer.inside, 0u);
    EXPECT_EQ(inner.inside, 0u);
    // The outer layer keeps at least the layer gap over the inner one's
    // clearance under it, so its closest approach is the farther one.
    EXPECT_GT(outer.min_clearance, inner.min_clearance);
  }
}

TEST(GarmentPipeline, ABadBodyIsReportedAndOthersComplete) {
  const Scene& s = scene();
  auto regen = GarmentRegenerator::create(s.family, {s.shorts});
  ASSERT_TRUE(regen);
  std::vector<Vec3d> body = skin_positions(*s.ref);
  body[body.size() / 2] = Vec3d(std::nan(""), 0, 0);
  const BodyGarments bad = regen->run_one(body);
  EXPECT_FALSE(bad.status);
  EXPECT_TRUE(bad.garments.empty());
  const BodyGarments good = regen->run_one(skin_positions(*s.ref));
  EXPECT_TRUE(good.status) << good.status.to_string();
  // Wrong sizes and ranges are errors of the call, not crashes.
  std::vector<BodyGarments> out;
  const BodySet set = bodies(2, 3);
  EXPECT_FALSE(regen->run(set, 1, 5, out));
  EXPECT_FALSE(regenerate_garment(*s.family, *s.shorts, std::vector<Vec3d>(3)).has_value());
}

TEST(GarmentPipeline, EncodingErrorsNameTheGarment) {
  const Scene& s = scene();
  PolygonSoup bad;
  bad.positions = {{0, 1, 0.2}, {0.1, 1, 0.2}, {0, 1.1, 0.2}};
  bad.add_face(std::vector<std::uint32_t>{0, 1, 7});
  auto r = encode_garment(*s.family, "scarf", bad);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("scarf"), std::string::npos) << r.status().message();
  bad.face_nodes.back() = 2;
  bad.positions[1].x() = std::nan("");
  EXPECT_FALSE(encode_garment(*s.family, "scarf", bad).has_value());
  EXPECT_FALSE(encode_garment(*s.family, "empty", PolygonSoup{}).has_value());
}

TEST(GarmentPipeline, TemplateFilesRoundTrip) {
  const Scene& s = scene();
  const char* env = std::getenv("ATELIER_TMP");
  const fs::path dir = (env ? fs::path(env) : fs::temp_directory_path()) / "garment-template-rt";
  fs::remove_all(dir);
  // Float precision, as the file stores it.
  GarmentTemplate t = *s.shorts;
  for (Vec3d& p : t.mesh.positions) p = round_to_float(p);
  auto exact = encode_garment(*s.family, "inner", t.mesh);
  ASSERT_TRUE(exact);
  write_garment_template(*exact, dir);
  auto back = read_garment_template(*s.family, dir / "inner.atd");
  ASSERT_TRUE(back) << back.status().to_string();
  EXPECT_EQ(back->mesh.positions, exact->mesh.positions);
  EXPECT_EQ(back->mesh.face_nodes, exact->mesh.face_nodes);
  EXPECT_EQ(back->encoding.polygon, exact->encoding.polygon);
  EXPECT_EQ(back->encoding.a, exact->encoding.a);
  EXPECT_EQ(back->clearance.clearance, exact->clearance.clearance);
  const std::vector<Vec3d> body = bodies(1, 9).positions(0);
  EXPECT_EQ(regenerate_garment(*s.family, *back, body)->positions,
            regenerate_garment(*s.family, *exact, body)->positions);
  // A missing mesh beside the .atd is named.
  fs::remove(dir / "inner.obj");
  auto missing = read_garment_template(*s.family, dir / "inner.atd");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.status().message().find("inner.obj"), std::string::npos);
  fs::remove_all(dir);
}

TEST(GarmentPipeline, TextureCoordinatesAndSeamsSurviveEncodingAndRegeneration) {
  // Issue 27: regenerated garments had no `vt`. The uv map belongs to the
  // topology: encoding keeps it beside the .atd, regeneration writes it
  // unchanged with the new positions. Corner uv of the shorts: a seam on
  // every face (each face its own copy of the unit square's corners).
  const Scene& s = scene();
  const char* env = std::getenv("ATELIER_TMP");
  const fs::path dir = (env ? fs::path(env) : fs::temp_directory_path()) / "garment-uv";
  fs::remove_all(dir);
  GarmentTemplate t = *s.shorts;
  for (Vec3d& p : t.mesh.positions) p = round_to_float(p);
  t.mesh.corner_uv.clear();
  for (std::size_t f = 0; f < t.mesh.face_count(); ++f)
    for (std::size_t k = 0; k < t.mesh.face(f).size(); ++k)
      t.mesh.corner_uv.emplace_back(0.125 * static_cast<double>(f % 7), 0.25 * static_cast<double>(k));
  ASSERT_TRUE(t.mesh.check());
  auto enc = encode_garment(*s.family, "uvshorts", t.mesh);
  ASSERT_TRUE(enc);
  write_garment_template(*enc, dir);
  auto back = read_garment_template(*s.family, dir / "uvshorts.atd");
  ASSERT_TRUE(back) << back.status().to_string();
  EXPECT_EQ(back->mesh.corner_uv, t.mesh.corner_uv);
  // A regenerated body's garment file: new positions, the same corner uv.
  const std::vector<Vec3d> body = bodies(1, 9).positions(0);
  auto r = regenerate_garment(*s.family, *back, body);
  ASSERT_TRUE(r);
  write_garment_mesh(back->mesh, r->positions, dir / "regenerated.obj");
  auto again = read_garment_mesh(dir / "regenerated.obj");
  ASSERT_TRUE(again) << again.status().to_string();
  EXPECT_EQ(again->corner_uv, t.mesh.corner_uv);
  EXPECT_EQ(again->face_nodes, t.mesh.face_nodes);
  EXPECT_NE(again->positions, back->mesh.positions);  // it did move
  fs::remove_all(dir);
}

TEST(GarmentPipeline, MakeHumanGarmentKeepsItsUvMapThroughAWriteAndRead) {
  const fs::path obj = fs::path(ATELIER_SHARED_DATA) / "makehuman" / "clothes" / "female_sportsuit01.obj";
  if (!fs::exists(obj)) GTEST_SKIP() << "shared data absent: " << obj;
  auto g = read_garment_mesh(obj);
  ASSERT_TRUE(g) << g.status().to_string();
  ASSERT_EQ(g->corner_uv.size(), g->face_nodes.size());
  ASSERT_TRUE(g->check());
  // Seams: some vertex has two different uv in two of its faces.
  std::map<std::uint32_t, Vec2d> first;
  std::size_t seam_corners = 0;
  for (std::size_t k = 0; k < g->face_nodes.size(); ++k) {
    const auto [it, inserted] = first.try_emplace(g->face_nodes[k], g->corner_uv[k]);
    seam_corners += !inserted && it->second != g->corner_uv[k];
  }
  EXPECT_GT(seam_corners, 0u);
  const char* env = std::getenv("ATELIER_TMP");
  const fs::path out = (env ? fs::path(env) : fs::temp_directory_path()) / "sportsuit-uv.obj";
  write_garment_mesh(*g, g->positions, out);
  auto back = read_garment_mesh(out);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->corner_uv, g->corner_uv);
  fs::remove(out);
}

}  // namespace
}  // namespace atelier
