// Issue 26, "closer to ground truth": scaled frames (DetailParams::
// scaled_frames) and the MakeHuman helpers as a ground truth.
//
// The helpers (helper-tights, helper-skirt in base.obj) are moved by every
// MakeHuman target together with the skin, so their morphed positions are an
// expectation our code does not make: each helper is encoded on the default
// body as a garment and regenerated on random adults, and compared vertex by
// vertex with MakeHuman's own morphed helper. The figures per stage of the
// pipeline (decode, + edge transfer, + collision pass) are printed, with the
// mean distance to the morphed helper's surface beside them (what remains
// once a vertex sliding along the helper is not counted).
#include <atelier/engine/parallel.h>
#include <atelier/engine/random.h>
#include <atelier/io/checksum.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

#include "support/run_command.h"
#include "support/shapes.h"
#include "systems/garment/sphere_fixture.h"
#include "systems/garment/makehuman_helpers.h"

using namespace atelier;
namespace fs = std::filesystem;

namespace {

using Sphere = garment_test::SphereBody;
using garment_test::shell_points;
using garment_test::sphere_body;

double max_error(std::span<const Vec3d> a, std::span<const Vec3d> b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, (a[i] - b[i]).norm());
  return m;
}

}  // namespace

TEST(ScaledFrames, UniformScalingScalesTheGarmentExactly) {
  // A body scaled by k about any point: with scaled frames every garment
  // vertex is scaled by k about the same point (eqs. 11-12 with every frame
  // axis times k); the paper's unit frames leave the offsets unscaled.
  const Sphere b = sphere_body();
  const auto g = shell_points(800, 5);
  DetailParams scaled;
  scaled.scaled_frames = true;
  auto enc_s = encode_detail(b.poly, b.pos, g, scaled);
  auto enc_r = encode_detail(b.poly, b.pos, g);
  ASSERT_TRUE(enc_s && enc_r);
  EXPECT_TRUE(enc_s->scaled_frames);
  EXPECT_FALSE(enc_r->scaled_frames);
  std::vector<Vec3d> out(g.size());
  ASSERT_TRUE(decode_detail(*enc_s, b.poly, b.pos, out));
  EXPECT_LT(max_error(out, g), 1e-5);  // the source body gives the garment back
  const Vec3d o(0.3, -0.2, 0.1);
  for (const double k : {0.8, 1.25}) {
    std::vector<Vec3d> body(b.pos.size()), want(g.size());
    for (std::size_t v = 0; v < body.size(); ++v) body[v] = o + k * (b.pos[v] - o);
    for (std::size_t v = 0; v < g.size(); ++v) want[v] = o + k * (g[v] - o);
    ASSERT_TRUE(decode_detail(*enc_s, b.poly, body, out));
    EXPECT_LT(max_error(out, want), 2e-5) << k;
    ASSERT_TRUE(decode_detail(*enc_r, b.poly, body, out));
    EXPECT_GT(max_error(out, want), 1e-3) << k;  // unit frames: offsets from the p-polygons keep their length
  }
  // A rigid motion moves the garment rigidly with either frames.
  const Eigen::AngleAxisd rot(0.7, Vec3d(1, 2, 3).normalized());
  std::vector<Vec3d> body(b.pos.size()), want(g.size());
  for (std::size_t v = 0; v < body.size(); ++v) body[v] = rot * b.pos[v] + o;
  for (std::size_t v = 0; v < g.size(); ++v) want[v] = rot * g[v] + o;
  ASSERT_TRUE(decode_detail(*enc_s, b.poly, body, out));
  EXPECT_LT(max_error(out, want), 2e-5);
}

TEST(ScaledFrames, NeedFittedFrames) {
  const Sphere b = sphere_body(12, 8);
  DetailParams p;
  p.scaled_frames = true;
  p.fitted_frames = false;
  auto e = encode_detail(b.poly, b.pos, shell_points(10, 1), p);
  ASSERT_FALSE(e);
  EXPECT_EQ(e.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(e.status().message().find("scaled frames need fitted frames"), std::string::npos);
}

TEST(ScaledFrames, BatchedDecodingMatchesSingle) {
  // The batched decoder computes frames in its own (AVX2) kernel: same
  // scaled frames as compute_frames, to float rounding, on bodies stretched
  // unevenly (each polygon its own scale).
  const Sphere b = sphere_body();
  const auto g = shell_points(1200, 8);
  DetailParams scaled;
  scaled.scaled_frames = true;
  auto enc = encode_detail(b.poly, b.pos, g, scaled);
  ASSERT_TRUE(enc);
  BodySet set(b.ref);
  SplitMix64 r(4);
  std::vector<std::vector<Vec3d>> bodies;
  for (int k = 0; k < 19; ++k) {
    std::vector<Vec3d> p(b.pos.size());
    const Vec3d s(r.uniform(0.7, 1.3), r.uniform(0.7, 1.3), r.uniform(0.7, 1.3));
    for (std::size_t v = 0; v < p.size(); ++v)
      p[v] = b.pos[v].cwiseProduct(s) + Vec3d(0, 0, 0.1 * std::sin(3 * b.pos[v].x()));
    ASSERT_TRUE(set.add("b" + std::to_string(k), std::span<const Vec3d>(p)));
    bodies.push_back(set.positions(set.size() - 1));
  }
  std::vector<Vec3f> batch1(19 * g.size()), batch2(19 * g.size());
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 16;
  ASSERT_TRUE(decode_detail_batch(*enc, b.poly, set, 0, 19, batch1, one));
  ASSERT_TRUE(decode_detail_batch(*enc, b.poly, set, 0, 19, batch2, two));
  EXPECT_EQ(std::memcmp(batch1.data(), batch2.data(), batch1.size() * sizeof(Vec3f)), 0);
  std::vector<Vec3d> single(g.size());
  double moved = 0;
  for (std::size_t k = 0; k < 19; ++k) {
    ASSERT_TRUE(decode_detail(*enc, b.poly, bodies[k], single));
    for (std::size_t v = 0; v < g.size(); ++v) {
      ASSERT_LT((batch1[k * g.size() + v].cast<double>() - single[v]).norm(), 1e-5) << k << " " << v;
      moved = std::max(moved, (single[v] - g[v]).norm());
    }
  }
  EXPECT_GT(moved, 0.05);  // the bodies did deform the garment
}

TEST(ScaledFrames, FileKeepsTheFlag) {
  const Sphere b = sphere_body(16, 10);
  const auto g = shell_points(50, 2);
  DetailParams scaled;
  scaled.scaled_frames = true;
  auto enc_s = encode_detail(b.poly, b.pos, g, scaled);
  auto enc_r = encode_detail(b.poly, b.pos, g);
  ASSERT_TRUE(enc_s && enc_r);
  const fs::path d = atelier::testing::scratch_dir("helper_truth");
  write_detail(*enc_s, d / "s.atd");
  write_detail(*enc_r, d / "r.atd");
  auto version = [](const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    char h[12];
    f.read(h, 12);
    std::uint32_t v;
    std::memcpy(&v, h + 8, 4);
    return v;
  };
  EXPECT_EQ(version(d / "s.atd"), 4u);
  EXPECT_EQ(version(d / "r.atd"), 3u);  // unchanged for encodings without scaled frames
  const DetailEncoding s = read_detail(d / "s.atd"), r = read_detail(d / "r.atd");
  EXPECT_TRUE(s.scaled_frames);
  EXPECT_FALSE(r.scaled_frames);
  // Same decode as the encoding written.
  std::vector<Vec3d> body(b.pos.size()), x(g.size()), y(g.size());
  for (std::size_t v = 0; v < body.size(); ++v) body[v] = 1.3 * b.pos[v];
  ASSERT_TRUE(decode_detail(*enc_s, b.poly, body, x));
  ASSERT_TRUE(decode_detail(s, b.poly, body, y));
  EXPECT_EQ(max_error(x, y), 0.0);
  // A bad flag byte (checksum made right) is named with its offset.
  std::ifstream f(d / "s.atd", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const std::size_t flag_at = bytes.size() - 5;
  bytes[flag_at] = 2;
  const std::uint32_t sum = crc32(bytes.data(), flag_at + 1);
  std::memcpy(bytes.data() + flag_at + 1, &sum, 4);
  try {
    (void)read_detail_from_bytes(bytes, "bad.atd");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.atd: byte offset " + std::to_string(flag_at)), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("frame flags"), std::string::npos) << e.what();
  }
}

// ------------------------------------------------------------ the helpers

namespace {

struct HelperCase {
  std::string name;
  std::vector<std::uint32_t> verts;  // base.obj vertex of each helper vertex
  std::vector<Triangle> triangles;   // over helper vertices
  GarmentTemplate unit, scaled;      // encoded with the paper's and with scaled frames
};

// Per helper and body: mean vertex error per (frames, stage), and the mean
// distance to the morphed helper's surface per (frames, stage).
struct HelperFigures {
  std::array<std::array<double, 3>, 2> vertex{}, surface{};
  std::array<std::array<double, 3>, 2> max_vertex{};
};

// Encodes both helpers and regenerates them on `n` adults (seed 2024, the
// garment test's), sequentially per body, bodies in parallel.
void run_helpers(std::size_t n, std::vector<HelperCase>& helpers, std::vector<std::vector<HelperFigures>>& per_body) {
  using namespace makehuman;
  const fs::path dir = fs::path(ATELIER_SHARED_DATA) / "makehuman";
  const HumanLibrary lib = HumanLibrary::load(dir);
  const ReferenceBody ref = make_reference_body(lib);
  auto family = GarmentFamily::of(ref);
  ASSERT_TRUE(family) << family.status().to_string();
  std::vector<Vec3f> H0(lib.vertex_count());
  lib.build(MacroParams{}, H0);
  for (const char* hname : {"helper-tights", "helper-skirt"}) {
    HelperCase h;
    h.name = hname;
    const auto* grp = lib.base().group(hname);
    ASSERT_NE(grp, nullptr);
    h.verts = garment_test::group_vertices(*grp);
    PolygonSoup soup;
    for (auto v : h.verts) soup.positions.push_back(kMakeHumanToMetres * H0[v].cast<double>());
    std::vector<std::uint32_t> f;
    for (std::size_t k = 0; k < grp->face_count(); ++k) {
      f.clear();
      for (auto v : grp->face(k))
        f.push_back(static_cast<std::uint32_t>(std::lower_bound(h.verts.begin(), h.verts.end(), v) - h.verts.begin()));
      soup.add_face(f);
    }
    h.triangles = fan_triangulate(soup);
    auto unit = encode_garment(*family, h.name, soup);
    ASSERT_TRUE(unit) << unit.status().to_string();
    GarmentEncodeOptions o;
    o.detail.scaled_frames = true;
    auto scaled = encode_garment(*family, h.name, soup, o);
    ASSERT_TRUE(scaled) << scaled.status().to_string();
    h.unit = std::move(*unit);
    h.scaled = std::move(*scaled);
    helpers.push_back(std::move(h));
  }
  const auto params = sample_adults(n, 2024);
  per_body.assign(n, std::vector<HelperFigures>(helpers.size()));
  std::vector<std::string> errors(n);
  ExecContext ctx;
  ctx.sequential_threshold = 2;
  ctx.grain = 1;
  par::for_each_n(ctx, n, [&](std::size_t b) {
    const ExecContext seq = ExecContext::sequential();
    std::vector<Vec3f> H(lib.vertex_count());
    lib.build(params[b], H);
    std::vector<Vec3d> skin(family->reference_positions.size());
    for (std::size_t v = 0; v < skin.size(); ++v) skin[v] = kMakeHumanToMetres * H[v].cast<double>();
    for (std::size_t hi = 0; hi < helpers.size(); ++hi) {
      const HelperCase& h = helpers[hi];
      std::vector<Vec3d> truth(h.verts.size());
      for (std::size_t i = 0; i < truth.size(); ++i) truth[i] = kMakeHumanToMetres * H[h.verts[i]].cast<double>();
      BodyBvh surface;
      if (Status s = surface.build(truth, h.triangles, {}, seq); !s) {
        errors[b] = s.to_string();
        return;
      }
      for (int frames = 0; frames < 2; ++frames)
        for (int stage = 0; stage < 3; ++stage) {
          GarmentRegenOptions o;
          o.edge_transfer = stage >= 1;
          o.collision_pass = stage >= 2;
          auto r = regenerate_garment(*family, frames ? h.scaled : h.unit, skin, o, seq);
          if (!r) {
            errors[b] = h.name + ": " + r.status().to_string();
            return;
          }
          double sum = 0, sum_surface = 0, mx = 0;
          for (std::size_t i = 0; i < truth.size(); ++i) {
            const double d = (r->positions[i] - truth[i]).norm();
            sum += d;
            mx = std::max(mx, d);
            sum_surface += surface.closest_point(r->positions[i]).distance;
          }
          HelperFigures& fig = per_body[b][hi];
          fig.vertex[frames][stage] = sum / truth.size();
          fig.surface[frames][stage] = sum_surface / truth.size();
          fig.max_vertex[frames][stage] = mx;
        }
    }
  });
  for (const auto& e : errors) ASSERT_TRUE(e.empty()) << e;
}

// Mean over bodies of a figure.
template <class F>
double over_bodies(const std::vector<std::vector<HelperFigures>>& per, std::size_t h, F f) {
  double s = 0;
  for (const auto& b : per) s += f(b[h]);
  return s / static_cast<double>(per.size());
}

void report(const std::vector<HelperCase>& helpers, const std::vector<std::vector<HelperFigures>>& per) {
  static const char* kStage[] = {"decode", "+ edge transfer", "+ collision pass"};
  std::printf(
      "\n%zu adults (sample_adults(n, 2024)): mean over bodies of the mean vertex error to MakeHuman's "
      "morphed helper (mm); in brackets the mean distance to its surface\n",
      per.size());
  std::printf("%-14s %-17s %-18s %-18s\n", "helper", "stage", "unit frames", "scaled frames");
  for (std::size_t h = 0; h < helpers.size(); ++h)
    for (int s = 0; s < 3; ++s) {
      double v[2], d[2], worst[2] = {0, 0};
      for (int f = 0; f < 2; ++f) {
        v[f] = over_bodies(per, h, [&](const HelperFigures& x) { return x.vertex[f][s]; });
        d[f] = over_bodies(per, h, [&](const HelperFigures& x) { return x.surface[f][s]; });
        for (const auto& b : per) worst[f] = std::max(worst[f], b[h].vertex[f][s]);
      }
      std::printf("%-14s %-17s %6.2f (%5.2f) w%5.2f  %6.2f (%5.2f) w%5.2f\n", helpers[h].name.c_str(), kStage[s],
                  1000 * v[0], 1000 * d[0], 1000 * worst[0], 1000 * v[1], 1000 * d[1], 1000 * worst[1]);
    }
}

}  // namespace

TEST(HelperTruth, MakeHumanHelpersOnAdults) {
  // Always on: 8 adults (about 1 s); 100 adults unless long tests are off.
  if (!fs::exists(fs::path(ATELIER_SHARED_DATA) / "makehuman" / "base.obj")) GTEST_SKIP() << "MakeHuman data not found";
  const std::size_t n = std::getenv("ATELIER_SKIP_LONG_TESTS") ? 8 : 100;
  std::vector<HelperCase> helpers;
  std::vector<std::vector<HelperFigures>> per;
  run_helpers(n, helpers, per);
  if (HasFatalFailure()) return;
  report(helpers, per);
  ASSERT_EQ(helpers.size(), 2u);
  for (std::size_t h = 0; h < 2; ++h) {
    const bool tights = helpers[h].name == "helper-tights";
    auto v = [&](int f, int s) { return over_bodies(per, h, [&](const HelperFigures& x) { return x.vertex[f][s]; }); };
    auto d = [&](int f, int s) { return over_bodies(per, h, [&](const HelperFigures& x) { return x.surface[f][s]; }); };
    RecordProperty(helpers[h].name + "_unit_decode_mm", std::to_string(1000 * v(0, 0)));
    RecordProperty(helpers[h].name + "_scaled_decode_mm", std::to_string(1000 * v(1, 0)));
    // Scaled frames follow the helpers at least as closely as unit frames,
    // to 0.05 mm (measured, 100 adults: tights 3.98 -> 3.93 mm, skirt
    // 10.62 -> 9.93 mm; 8 adults: 3.72 -> 3.72, 11.77 -> 10.51).
    EXPECT_LE(v(1, 0), v(0, 0) + 5e-5) << helpers[h].name;
    if (!tights) {  // the skirt gains over 0.3 mm
      EXPECT_LT(v(1, 0), v(0, 0) - 3e-4) << helpers[h].name;
    }
    // Levels reached (issue 26 asks 2 and 5 mm: not reached, see
    // docs/performance.md; a regression past these fails).
    EXPECT_LT(v(1, 0), tights ? 0.0045 : 0.0115) << helpers[h].name;
    // Most of the vertex error is sliding along the helper: its surface
    // is followed several times more closely than its vertices.
    EXPECT_LT(d(1, 0), 0.5 * v(1, 0)) << helpers[h].name;
    // The later stages change a helper's error by under 2 mm on average
    // (they restore edge lengths and clearance, not the targets' sliding;
    // measured +0.2 mm on the tights, +0.2 to +0.8 mm on the skirt, 100
    // adults; up to +1.3 mm on the skirt for 8).
    for (int f = 0; f < 2; ++f)
      for (int s = 1; s < 3; ++s) EXPECT_LT(std::abs(v(f, s) - v(f, 0)), 0.002) << helpers[h].name << " " << s;
  }
}

TEST(HelperTruth, NearbySkinDoesNotDetermineTheHelpers) {
  // What following the nearby skin can reach. A helper vertex moved by a
  // fixed linear combination of the displacements of its K nearest skin
  // vertices (detail templates, .mhclo and closest-point bindings all are,
  // to first order in the displacement), with the least-squares weights:
  //  * across targets: weights fitted on MakeHuman's even targets (each at
  //    weight 1 on the default body), tested on the odd ones. No such law
  //    follows an unseen target within 2 mm (tights) or 5 mm (skirt): the
  //    targets slide the helpers along themselves, each its own way
  //    (docs/performance.md, issue 26);
  //  * across adults: weights fitted on 200 adults (sample_adults(200, 7)),
  //    tested on the 100 of the test above (seed 2024). With K = 64 this
  //    regression reaches 0.8 / 1.4 mm: adults are a family of a few
  //    sliders, so the helpers are predictable from the body once fitted to
  //    MakeHuman's own helpers, which a garment never has.
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "long test (about 5 s)";
  using namespace makehuman;
  const fs::path dir = fs::path(ATELIER_SHARED_DATA) / "makehuman";
  if (!fs::exists(dir / "base.obj")) GTEST_SKIP() << "MakeHuman data not found";
  const HumanLibrary lib = HumanLibrary::load(dir);
  const std::uint32_t nv = lib.vertex_count(), nskin = lib.skin_vertex_count();
  std::vector<Vec3f> H0(nv);
  lib.build(MacroParams{}, H0);
  // Displacements from the default body, body-major (nb x nv).
  auto of_adults = [&](const std::vector<MacroParams>& ps) {
    std::vector<Vec3f> d(ps.size() * nv);
    par::for_each_n({}, ps.size(), [&](std::size_t b) {
      std::span<Vec3f> out(d.data() + b * nv, nv);
      lib.build(ps[b], out);
      for (std::uint32_t v = 0; v < nv; ++v) out[v] = kMakeHumanToMetres * (out[v] - H0[v]);
    });
    return d;
  };
  auto of_targets = [&](int parity) {
    std::vector<const Target*> all;
    for (const auto& t : lib.macro_targets()) all.push_back(&t);
    for (const auto& t : lib.measure_targets()) all.push_back(&t);
    std::vector<const Target*> half;
    for (std::size_t t = static_cast<std::size_t>(parity); t < all.size(); t += 2) half.push_back(all[t]);
    std::vector<Vec3f> d(half.size() * nv, Vec3f::Zero());
    for (std::size_t t = 0; t < half.size(); ++t)
      for (std::size_t k = 0; k < half[t]->index.size(); ++k)
        d[t * nv + half[t]->index[k]] = kMakeHumanToMetres * half[t]->delta[k];
    return d;
  };
  struct Split {
    const char* name;
    std::vector<Vec3f> train, test;
    std::vector<std::size_t> ks;
  };
  Split splits[] = {{"targets", of_targets(0), of_targets(1), {3, 8, 24}},
                    {"adults", of_adults(sample_adults(200, 7)), of_adults(sample_adults(100, 2024)), {8, 64}}};
  for (const Split& sp : splits) {
    const std::size_t ntr = sp.train.size() / nv, nte = sp.test.size() / nv;
    for (const char* hname : {"helper-tights", "helper-skirt"}) {
      const bool tights = std::string(hname) == "helper-tights";
      const auto* grp = lib.base().group(hname);
      ASSERT_NE(grp, nullptr);
      std::vector<std::uint32_t> verts(grp->face_nodes.begin(), grp->face_nodes.end());
      std::sort(verts.begin(), verts.end());
      verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
      for (const std::size_t K : sp.ks) {
        double e_train = 0, e_test = 0;
        std::size_t counted = 0;
        for (std::size_t i = 0; i < verts.size(); i += 3, ++counted) {
          std::vector<std::pair<float, std::uint32_t>> near;
          for (std::uint32_t v = 0; v < nskin; ++v) near.push_back({(H0[v] - H0[verts[i]]).squaredNorm(), v});
          std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(K), near.end());
          auto rows = [&](const std::vector<Vec3f>& D, std::size_t nb, Eigen::MatrixXd& A, Eigen::VectorXd& y) {
            A.resize(3 * nb, K);
            y.resize(3 * nb);
            for (std::size_t b = 0; b < nb; ++b)
              for (int ax = 0; ax < 3; ++ax) {
                for (std::size_t j = 0; j < K; ++j) A(3 * b + ax, j) = D[b * nv + near[j].second][ax];
                y(3 * b + ax) = D[b * nv + verts[i]][ax];
              }
          };
          Eigen::MatrixXd A, At;
          Eigen::VectorXd y, yt;
          rows(sp.train, ntr, A, y);
          rows(sp.test, nte, At, yt);
          const Eigen::VectorXd w = A.colPivHouseholderQr().solve(y);
          auto mean_norm = [](const Eigen::VectorXd& r) {
            double s = 0;
            for (Eigen::Index b = 0; b < r.size() / 3; ++b) s += r.segment<3>(3 * b).norm();
            return s / static_cast<double>(r.size() / 3);
          };
          e_train += mean_norm(A * w - y);
          e_test += mean_norm(At * w - yt);
        }
        e_train /= static_cast<double>(counted);
        e_test /= static_cast<double>(counted);
        std::printf("%s, fitted across %s (%zu, tested on %zu), K = %zu: mean error %.2f mm fitted, %.2f mm tested\n",
                    hname, sp.name, ntr, nte, K, 1000 * e_train, 1000 * e_test);
        RecordProperty(std::string(hname) + "_" + sp.name + "_K" + std::to_string(K) + "_test_mm",
                       std::to_string(1000 * e_test));
        if (std::string(sp.name) == "targets")
          EXPECT_GT(e_test, tights ? 0.002 : 0.005) << hname << " K " << K;
        else if (K == 64)  // a regression on the family beats every regeneration of the helpers
          EXPECT_LT(e_test, tights ? 0.0015 : 0.003) << hname;
      }
    }
  }
}
