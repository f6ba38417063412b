#include <atelier/engine/cpu_features.h>
#include <atelier/engine/random.h>
#include <atelier/io/checksum.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/garment/detail_template.h>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>

#include "support/shapes.h"
#include "systems/garment/sphere_fixture.h"
#include "tests/support/shared_data.h"

using namespace atelier;
namespace fs = std::filesystem;

namespace {

using Body = garment_test::SphereBody;
using garment_test::shell_points;
using garment_test::sphere_body;

std::vector<Vec3d> centroids_of(const Body& b) {
  PolygonFrames fr;
  compute_frames(b.poly, b.pos, fr);
  std::vector<Vec3d> c;
  for (auto& x : fr.centroid) c.push_back(x.cast<double>());
  return c;
}

fs::path tmp_dir() {
  const char* env = std::getenv("ATELIER_TMP");
  fs::path d = (env ? fs::path(env) : fs::temp_directory_path() / "atelier-tests") / "detail";
  fs::create_directories(d);
  return d;
}

}  // namespace

TEST(PPolygonSearch, EqualsBruteForceOnRandomPoints) {
  SplitMix64 r(3);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<Vec3d> c(3000);
    for (auto& p : c) p = Vec3d(r.uniform(-1, 1), r.uniform(-0.5, 0.5), r.uniform(0, 2));
    // Exact duplicates and lattice points make ties, which must break by index.
    for (int i = 0; i < 200; ++i) c[2000 + i] = c[i];
    for (int i = 0; i < 300; ++i) c[2300 + i] = Vec3d(i % 10, (i / 10) % 5, i / 50) * 0.1;
    std::vector<std::uint8_t> skip(c.size(), 0);
    for (std::size_t i = 0; i < c.size(); i += 17) skip[i] = 1;
    for (std::size_t k : {1u, 7u, 30u, 150u}) {
      CentroidGrid g;
      g.build(c, skip, k);
      std::vector<std::uint32_t> got, want;
      std::vector<std::pair<double, std::uint32_t>> scratch;
      for (int q = 0; q < 300; ++q) {
        // Queries inside, on lattice points, and far outside the box.
        Vec3d p = q % 3 == 0 ? c[2300 + q % 300] : Vec3d(r.uniform(-3, 3), r.uniform(-3, 3), r.uniform(-3, 5));
        g.nearest(p, k, got, scratch);
        nearest_brute_force(c, skip, p, k, want);
        ASSERT_EQ(got, want) << "k=" << k << " query " << q;
        // With a bound on the k-th distance, right or (sometimes) too small.
        const double kth = (c[want.back()] - p).norm();
        const double bound = q % 2 ? kth * 1.5 + 0.01 : kth * r.uniform(0.0, 1.2);
        const double got_kth = g.nearest_bounded(p, k, bound, got, scratch);
        ASSERT_EQ(got, want) << "bounded, k=" << k << " query " << q;
        ASSERT_DOUBLE_EQ(got_kth, kth);
      }
    }
  }
}

TEST(PPolygonSearch, NearestManyEqualsBruteForceWhateverTheThreads) {
  // Centroids on a bumpy closed surface (as a body's), queries as a garment:
  // a coherent walk near the surface, with jumps and far points, so blocks
  // start anywhere and bounds from the previous query are tight or loose.
  SplitMix64 r(11);
  std::vector<Vec3d> c(4000);
  for (auto& p : c) {
    Vec3d d(r.normal(), r.normal(), r.normal());
    d.normalize();
    p = d.cwiseProduct(Vec3d(0.3, 0.2, 0.9)) * (1 + 0.05 * std::sin(9 * d.x()));
  }
  for (int i = 0; i < 100; ++i) c[3000 + i] = c[i];  // exact ties break by index
  std::vector<std::uint8_t> skip(c.size(), 0);
  for (std::size_t i = 0; i < c.size(); i += 13) skip[i] = 1;
  std::vector<Vec3d> q;
  Vec3d walk = c[1] * 1.05;
  for (int i = 0; i < 1500; ++i) {
    if (i % 400 == 399) walk = Vec3d(r.uniform(-2, 2), r.uniform(-2, 2), r.uniform(-2, 2));  // a jump
    walk += 0.01 * Vec3d(r.normal(), r.normal(), r.normal());
    q.push_back(i % 97 == 0 ? c[static_cast<std::size_t>(i) % c.size()] : walk);
  }
  for (std::size_t k : {1u, 9u, 40u, 134u}) {
    CentroidGrid g;
    g.build(c, skip, k);
    std::vector<std::uint32_t> one(q.size() * k), two(q.size() * k, 7), want;
    ExecContext seq = ExecContext::sequential(), par2;
    par2.threads = 2;
    par2.grain = 37;  // many blocks, each starting without a previous query
    par2.sequential_threshold = 1;
    g.nearest_many(q, k, one, seq);
    g.nearest_many(q, k, two, par2);
    ASSERT_EQ(one, two) << "k=" << k;
    for (std::size_t v = 0; v < q.size(); ++v) {
      nearest_brute_force(c, skip, q[v], k, want);
      ASSERT_TRUE(std::equal(want.begin(), want.end(), one.begin() + static_cast<std::ptrdiff_t>(v * k)))
          << "k=" << k << " query " << v;
    }
  }
}

TEST(DetailTemplate, EncodeDecodeOnTheSameBodyReturnsTheGarment) {
  const Body b = sphere_body();
  const auto g = shell_points(2000, 5);
  for (bool single : {false, true}) {
    DetailParams prm;
    prm.single_polygon = single;
    auto enc = encode_detail(b.poly, b.pos, g, prm);
    ASSERT_TRUE(enc) << enc.status().to_string();
    EXPECT_EQ(enc->entries(), g.size() * (single ? 1 : static_cast<std::size_t>(std::lround(b.poly.size() / 100.0))));
    std::vector<Vec3d> out(g.size());
    ASSERT_TRUE(decode_detail(*enc, b.poly, b.pos, out));
    double worst = 0;
    for (std::size_t v = 0; v < g.size(); ++v) worst = std::max(worst, (out[v] - g[v]).norm());
    EXPECT_LT(worst, 2e-6) << (single ? "single" : "multi");  // float precision at unit scale
  }
}

TEST(DetailTemplate, RigidMotionOfTheBodyMovesTheGarmentRigidly) {
  const Body b = sphere_body();
  const auto g = shell_points(1000, 6);
  auto enc = encode_detail(b.poly, b.pos, g);
  ASSERT_TRUE(enc);
  const Mat3d R = Eigen::AngleAxisd(0.7, Vec3d(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3d t(0.3, -2, 5);
  std::vector<Vec3d> moved(b.pos.size());
  for (std::size_t v = 0; v < moved.size(); ++v) moved[v] = R * b.pos[v] + t;
  std::vector<Vec3d> out(g.size());
  ASSERT_TRUE(decode_detail(*enc, b.poly, moved, out));
  for (std::size_t v = 0; v < g.size(); ++v) ASSERT_LT((out[v] - (R * g[v] + t)).norm(), 1e-5);
}

TEST(DetailTemplate, MultiplePPolygonsKeepSymmetryWhereOneDoesNot) {
  // Seed 001 Fig. 17: a vertex on the symmetry plane of a symmetric body,
  // decoded on a symmetrically deformed body, stays on the plane only when
  // blended over several p-polygons.
  const Body b = sphere_body(50, 24);  // nodes on x = 0, no centroid on it
  std::vector<Vec3d> g;
  for (int i = 0; i < 40; ++i) {
    const double th = 0.3 + 2.5 * i / 40.0;
    g.push_back(1.05 * Vec3d(0, std::sin(th), std::cos(th)));  // on the plane x = 0
  }
  std::vector<Vec3d> bent(b.pos.size());
  for (std::size_t v = 0; v < bent.size(); ++v) {  // mirror-symmetric, non-affine ("legs spread")
    const Vec3d& p = b.pos[v];
    bent[v] = Vec3d(p.x() * (1.0 + 0.6 * std::max(0.0, -p.z())) + 0.2 * p.x() * p.x() * p.x(), p.y(), p.z());
  }
  auto off_plane = [&](bool single) {
    DetailParams prm;
    prm.single_polygon = single;
    prm.polygons_per_vertex = 24;
    auto enc = encode_detail(b.poly, b.pos, g, prm);
    EXPECT_TRUE(enc);
    std::vector<Vec3d> out(g.size());
    EXPECT_TRUE(decode_detail(*enc, b.poly, bent, out));
    double worst = 0;
    for (const auto& q : out) worst = std::max(worst, std::abs(q.x()));
    return worst;
  };
  const double multi = off_plane(false), single = off_plane(true);
  EXPECT_GT(single, 1e-3);
  EXPECT_LT(multi, 1e-5);
  // The paper's frames (Y anchored at each polygon's first corner) depend on
  // vertex numbering and lose the symmetry under this non-affine change.
  DetailParams paper;
  paper.fitted_frames = false;
  paper.tapered_weights = false;
  paper.polygons_per_vertex = 24;
  auto enc = encode_detail(b.poly, b.pos, g, paper);
  ASSERT_TRUE(enc);
  std::vector<Vec3d> out(g.size());
  ASSERT_TRUE(decode_detail(*enc, b.poly, bent, out));
  double paper_off = 0;
  for (const auto& q : out) paper_off = std::max(paper_off, std::abs(q.x()));
  EXPECT_GT(paper_off, 100 * multi);
  std::cout << "off-plane drift: fitted frames " << multi << ", eq. (8) frames " << paper_off << ", single " << single
            << "\n";
}

TEST(DetailTemplate, DegeneratePolygonsAreNeverPPolygons) {
  shapes::Soup s = shapes::uv_sphere(16, 10);
  // Collapse one quad to a segment: move two of its corners onto the others.
  const std::uint32_t f = 40;
  const std::uint32_t* q = s.idx.data() + s.off[f];
  s.p[q[1]] = s.p[q[0]];
  s.p[q[2]] = s.p[q[3]];
  Body b;
  b.ref = shapes::body_from(s);
  b.poly = BodyPolygons::from_model(b.ref->model);
  b.pos = skin_positions(*b.ref);
  PolygonFrames fr;
  compute_frames(b.poly, b.pos, fr);
  std::size_t degenerate = 0;
  for (auto d : fr.degenerate) degenerate += d;
  EXPECT_GE(degenerate, 1u);
  // A garment vertex right at the degenerate polygon's centroid.
  std::vector<Vec3d> g = {fr.centroid[f].cast<double>() * 1.01};
  DetailParams prm;
  prm.polygons_per_vertex = 5;
  auto enc = encode_detail(b.poly, b.pos, g, prm);
  ASSERT_TRUE(enc);
  for (auto p : enc->polygon) EXPECT_FALSE(fr.degenerate[p]) << "degenerate polygon " << p << " used";
}

TEST(DetailTemplate, ABodyWithAnotherTopologyIsRefused) {
  const Body a = sphere_body(40, 24), b = sphere_body(36, 24);
  auto enc = encode_detail(a.poly, a.pos, shell_points(10, 1));
  ASSERT_TRUE(enc);
  std::vector<Vec3d> out(10);
  Status s = decode_detail(*enc, b.poly, b.pos, out);
  EXPECT_EQ(s.code(), ErrorCode::kMismatch);
  EXPECT_NE(s.message().find("topology"), std::string::npos);
  std::vector<Vec3d> g = {Vec3d(0, 0, std::nan(""))};
  auto bad = encode_detail(a.poly, a.pos, g);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.status().message().find("garment vertex 0"), std::string::npos);
}

TEST(DetailTemplate, BatchedDecodingMatchesSingleAndIsDeterministic) {
  const Body b = sphere_body();
  const auto g = shell_points(1500, 8);
  auto enc = encode_detail(b.poly, b.pos, g);
  ASSERT_TRUE(enc);
  BodySet set(b.ref);
  SplitMix64 r(4);
  std::vector<std::vector<Vec3d>> bodies;
  for (int k = 0; k < 21; ++k) {  // not a multiple of the batch width
    std::vector<Vec3d> p(b.pos.size());
    const Vec3d s(r.uniform(0.8, 1.2), r.uniform(0.8, 1.2), r.uniform(0.8, 1.2));
    for (std::size_t v = 0; v < p.size(); ++v)
      p[v] = b.pos[v].cwiseProduct(s) + Vec3d(0, 0, 0.1 * std::sin(3 * b.pos[v].x()));
    ASSERT_TRUE(set.add("b" + std::to_string(k), std::span<const Vec3d>(p)));
    bodies.push_back(set.positions(set.size() - 1));  // what the set stores (float)
  }
  std::vector<Vec3f> batch1(21 * g.size()), batch2(21 * g.size());
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 16;
  ASSERT_TRUE(decode_detail_batch(*enc, b.poly, set, 0, 21, batch1, one));
  ASSERT_TRUE(decode_detail_batch(*enc, b.poly, set, 0, 21, batch2, two));
  EXPECT_EQ(std::memcmp(batch1.data(), batch2.data(), batch1.size() * sizeof(Vec3f)), 0);
  std::vector<Vec3d> single(g.size());
  for (std::size_t k = 0; k < 21; ++k) {
    ASSERT_TRUE(decode_detail(*enc, b.poly, bodies[k], single));
    for (std::size_t v = 0; v < g.size(); ++v)
      ASSERT_LT((batch1[k * g.size() + v].cast<double>() - single[v]).norm(), 1e-5) << k << " " << v;
  }
}

TEST(DetailTemplate, DecodingEqualsEquations11And12InDouble) {
  // The vectorised decoder against eqs. (11)-(12) summed in double from the
  // same float coefficients and frames, on a deformed body.
  const Body b = sphere_body();
  const auto g = shell_points(700, 9);
  DetailParams prm;
  prm.polygons_per_vertex = 23;  // odd: rows end on an unpaired entry
  auto enc = encode_detail(b.poly, b.pos, g, prm);
  ASSERT_TRUE(enc);
  std::vector<Vec3d> bent(b.pos.size());
  for (std::size_t v = 0; v < bent.size(); ++v)
    bent[v] = Vec3d(b.pos[v].x() * 1.3, b.pos[v].y() + 0.2 * b.pos[v].z() * b.pos[v].z(), b.pos[v].z());
  PolygonFrames fr;
  compute_frames(b.poly, bent, fr, {}, enc->reference_corners);
  // Every kernel (rows of 23 entries end on 3 past the last full round of
  // 4 accumulators). AVX-512 and AVX2 sum the same lanes in the same order.
  std::map<DecodeKernel, std::vector<Vec3d>> got;
  for (const DecodeKernel k : {DecodeKernel::kAvx512, DecodeKernel::kAvx2, DecodeKernel::kPortable}) {
    std::vector<Vec3d> o(g.size());
    const DecodeKernel ran = decode_detail(*enc, fr, o, {}, k);
    got.emplace(ran, std::move(o));
  }
  ASSERT_TRUE(got.count(DecodeKernel::kPortable));
  if (atelier::cpu_features().avx512f) {
    EXPECT_TRUE(got.count(DecodeKernel::kAvx512));
  }
  if (got.count(DecodeKernel::kAvx512) && got.count(DecodeKernel::kAvx2)) {
    EXPECT_EQ(got[DecodeKernel::kAvx512], got[DecodeKernel::kAvx2]);
  }
  for (const auto& [kernel, o] : got) {
    double worst = 0;
    for (std::size_t v = 0; v < g.size(); ++v) {
      Vec3d want = Vec3d::Zero();
      for (std::uint32_t e = enc->row[v]; e < enc->row[v + 1]; ++e) {
        const std::uint32_t p = enc->polygon[e];
        want += double{enc->a[e]} * fr.centroid[p].cast<double>() + double{enc->b[e]} * fr.x[p].cast<double>() +
                double{enc->c[e]} * fr.y[p].cast<double>() + double{enc->d[e]} * fr.z[p].cast<double>();
      }
      worst = std::max(worst, (o[v] - want).norm());
    }
    EXPECT_LT(worst, 2e-6) << "kernel " << static_cast<int>(kernel);  // float sums of 23 terms at unit scale
  }
}

TEST(DetailTemplate, DecoderForBatchesIsThreadIndependentAndMatchesSingleBodies) {
  // A garment whose size is not a multiple of the tile, 19 bodies (two
  // passes of 16, the last group partly filled), decoders built and run
  // with 1 and 2 threads.
  const Body b = sphere_body(30, 20);
  const auto g = shell_points(DetailDecoder::kTile * 5 + 17, 12);
  DetailParams prm;
  prm.polygons_per_vertex = 17;
  auto enc = encode_detail(b.poly, b.pos, g, prm);
  ASSERT_TRUE(enc);
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 1;
  const DetailDecoder d1(*enc, one), d2(*enc, two);
  EXPECT_EQ(d1.entries(), enc->entries());
  EXPECT_EQ(d1.runs(), d2.runs());
  BodySet set(b.ref);
  SplitMix64 r(21);
  for (int k = 0; k < 19; ++k) {
    std::vector<Vec3d> p(b.pos.size());
    const double t = r.uniform(-0.3, 0.3);
    const Mat3d R = Eigen::AngleAxisd(r.uniform(0, 3), Vec3d(1, 1, 0).normalized()).toRotationMatrix();
    for (std::size_t v = 0; v < p.size(); ++v)
      p[v] = R * Vec3d(b.pos[v].x() * (1 + t * b.pos[v].z()), b.pos[v].y(), b.pos[v].z() * (1 - t)) + Vec3d(k, 0, 1);
    ASSERT_TRUE(set.add("b" + std::to_string(k), std::span<const Vec3d>(p)));
  }
  const std::size_t nv = g.size();
  std::vector<Vec3f> a(18 * nv), c(18 * nv);
  ASSERT_TRUE(decode_detail_batch(d1, b.poly, set, 1, 18, a, one));
  ASSERT_TRUE(decode_detail_batch(d2, b.poly, set, 1, 18, c, two));
  EXPECT_EQ(std::memcmp(a.data(), c.data(), a.size() * sizeof(Vec3f)), 0);
  std::vector<Vec3d> single(nv);
  double worst = 0;
  for (std::size_t k = 0; k < 18; ++k) {
    ASSERT_TRUE(decode_detail(*enc, b.poly, set.positions(1 + k), single));
    for (std::size_t v = 0; v < nv; ++v) worst = std::max(worst, (a[k * nv + v].cast<double>() - single[v]).norm());
  }
  EXPECT_LT(worst, 2e-5);  // float sums at a scale of up to 19 (translated bodies)
  // A workspace kept between calls of different sizes gives the same bits.
  DecodeWorkspace ws;
  std::vector<Vec3f> w1(5 * nv), w2(18 * nv);
  ASSERT_TRUE(decode_detail_batch(d1, b.poly, set, 1, 5, w1, ws, two));
  ASSERT_TRUE(decode_detail_batch(d1, b.poly, set, 1, 18, w2, ws, one));
  ASSERT_TRUE(decode_detail_batch(d1, b.poly, set, 1, 5, w1, ws, two));
  EXPECT_EQ(std::memcmp(w2.data(), a.data(), a.size() * sizeof(Vec3f)), 0);
  EXPECT_EQ(std::memcmp(w1.data(), a.data(), w1.size() * sizeof(Vec3f)), 0);
  // Errors: another topology, wrong output size, range out of bounds.
  const Body other = sphere_body(31, 20);
  EXPECT_EQ(decode_detail_batch(d1, other.poly, set, 0, 1, std::span<Vec3f>(a.data(), nv)).code(),
            ErrorCode::kMismatch);
  EXPECT_EQ(decode_detail_batch(d1, b.poly, set, 0, 2, std::span<Vec3f>(a.data(), nv)).code(), ErrorCode::kMismatch);
  EXPECT_EQ(decode_detail_batch(d1, b.poly, set, 18, 2, std::span<Vec3f>(a.data(), 2 * nv)).code(),
            ErrorCode::kInvalidArgument);
}

TEST(DetailTemplate, BatchedKernelsAgree) {
  // The AVX-512 kernel (16 bodies a register, frames 16 lanes a row) and
  // the AVX2 one (two groups of 8) do the same arithmetic per lane: same
  // bits. The portable kernel (frames in double) agrees to float rounding.
  // 21 bodies: a full pass and a pass of 5 (lanes 5-15 repeat the last
  // body in the AVX-512 layout). A garment of 3 tiles and a bit.
  const Body b = sphere_body(36, 22);
  const auto g = shell_points(DetailDecoder::kTile * 3 + 41, 17);
  DetailParams prm;
  prm.polygons_per_vertex = 19;
  auto enc = encode_detail(b.poly, b.pos, g, prm);
  ASSERT_TRUE(enc);
  BodySet set(b.ref);
  SplitMix64 r(71);
  for (int k = 0; k < 21; ++k) {
    std::vector<Vec3d> p(b.pos.size());
    const Mat3d R = Eigen::AngleAxisd(r.uniform(0, 3), Vec3d(0, 1, 1).normalized()).toRotationMatrix();
    const Vec3d sc(r.uniform(0.8, 1.2), r.uniform(0.8, 1.2), r.uniform(0.8, 1.2));
    for (std::size_t v = 0; v < p.size(); ++v) p[v] = R * b.pos[v].cwiseProduct(sc) + Vec3d(0.1 * k, 0, 0);
    ASSERT_TRUE(set.add("b" + std::to_string(k), std::span<const Vec3d>(p)));
  }
  ExecContext two;
  two.threads = 2;
  two.sequential_threshold = 1;
  const DetailDecoder dec(*enc, two);
  const std::size_t nv = g.size();
  std::map<DecodeKernel, std::vector<Vec3f>> out;
  for (const DecodeKernel k : {DecodeKernel::kAvx512, DecodeKernel::kAvx2, DecodeKernel::kPortable}) {
    DecodeWorkspace ws;
    ws.allow = k;
    std::vector<Vec3f> o(21 * nv);
    ASSERT_TRUE(decode_detail_batch(dec, b.poly, set, 0, 21, o, ws, two));
    if (out.count(ws.ran) == 0) out[ws.ran] = o;  // narrower than asked where the CPU lacks it
    // A pass of 3 bodies alone gives the same bits as those bodies in the
    // full batch (lanes past the last body never leak).
    std::vector<Vec3f> three(3 * nv);
    ASSERT_TRUE(decode_detail_batch(dec, b.poly, set, 17, 3, three, ws, two));
    EXPECT_EQ(std::memcmp(three.data(), o.data() + 17 * nv, three.size() * sizeof(Vec3f)), 0);
  }
  ASSERT_TRUE(out.count(DecodeKernel::kPortable));
  if (atelier::cpu_features().avx512f) {
    EXPECT_TRUE(out.count(DecodeKernel::kAvx512));
  }
  if (out.count(DecodeKernel::kAvx512) && out.count(DecodeKernel::kAvx2)) {
    const auto& w = out[DecodeKernel::kAvx512];
    EXPECT_EQ(std::memcmp(w.data(), out[DecodeKernel::kAvx2].data(), w.size() * sizeof(Vec3f)), 0);
  }
  std::vector<Vec3d> single(nv);
  for (const auto& [kernel, o] : out) {
    double worst = 0;
    for (std::size_t k = 0; k < 21; ++k) {
      ASSERT_TRUE(decode_detail(*enc, b.poly, set.positions(k), single));
      for (std::size_t v = 0; v < nv; ++v) worst = std::max(worst, (o[k * nv + v].cast<double>() - single[v]).norm());
    }
    EXPECT_LT(worst, 1e-5) << "kernel " << static_cast<int>(kernel);
  }
}

TEST(DetailTemplate, BatchedDecodingOfAPartialGarmentComputesOnlyItsPolygonsFrames) {
  // A cap over the upper sphere uses a fraction of the polygons. The
  // decoder's used polygons are exactly the distinct polygons of the
  // encoding, and a pass that computes only their frames decodes as the
  // single-body path does, also in a workspace whose other frames hold a
  // full-coverage garment's values of other bodies.
  const Body b = sphere_body(40, 24);
  std::vector<Vec3d> cap;
  for (const Vec3d& q : shell_points(6000, 31))
    if (q.z() > 0.6) cap.push_back(q);
  ASSERT_GT(cap.size(), 600u);
  DetailParams prm;
  prm.polygons_per_vertex = 12;
  auto enc = encode_detail(b.poly, b.pos, cap, prm);
  auto full = encode_detail(b.poly, b.pos, shell_points(800, 32), prm);
  ASSERT_TRUE(enc && full);
  ExecContext two;
  two.threads = 2;
  two.sequential_threshold = 1;
  const DetailDecoder dec(*enc, two), dec_full(*full, two);
  std::vector<std::uint32_t> want(enc->polygon.begin(), enc->polygon.end());
  std::sort(want.begin(), want.end());
  want.erase(std::unique(want.begin(), want.end()), want.end());
  EXPECT_TRUE(std::equal(want.begin(), want.end(), dec.used_polygons().begin(), dec.used_polygons().end()));
  EXPECT_LT(dec.used_polygons().size() * 2, b.poly.size());  // a cap of a fifth of the area
  EXPECT_GT(dec_full.used_polygons().size() * 10, b.poly.size() * 9);
  BodySet set(b.ref);
  SplitMix64 r(33);
  for (int k = 0; k < 20; ++k) {
    std::vector<Vec3d> p(b.pos.size());
    const Vec3d sc(r.uniform(0.8, 1.2), r.uniform(0.8, 1.2), r.uniform(0.8, 1.2));
    for (std::size_t v = 0; v < p.size(); ++v) p[v] = b.pos[v].cwiseProduct(sc);
    ASSERT_TRUE(set.add("b" + std::to_string(k), std::span<const Vec3d>(p)));
  }
  DecodeWorkspace ws;
  std::vector<Vec3f> other(16 * full->vertex_count()), out(16 * cap.size());
  ASSERT_TRUE(decode_detail_batch(dec_full, b.poly, set, 4, 16, other, ws, two));
  ASSERT_TRUE(decode_detail_batch(dec, b.poly, set, 0, 16, out, ws, two));
  std::vector<Vec3d> single(cap.size());
  double worst = 0;
  for (std::size_t k = 0; k < 16; ++k) {
    ASSERT_TRUE(decode_detail(*enc, b.poly, set.positions(k), single));
    for (std::size_t v = 0; v < cap.size(); ++v)
      worst = std::max(worst, (out[k * cap.size() + v].cast<double>() - single[v]).norm());
  }
  EXPECT_LT(worst, 1e-5);
}

TEST(DetailTemplate, BatchedFramesHandleLargeAndCollapsedPolygons) {
  // A prism with 20-gon caps (more corners than the vectorised frame code
  // takes: those polygons use the scalar path) and quad sides; on some
  // bodies a cap or a side collapses (degenerate frames on that body only).
  // Batched decoding must match decoding each body on its own.
  constexpr int kSides = 20;
  shapes::Soup s;
  for (int h = 0; h < 2; ++h)
    for (int i = 0; i < kSides; ++i) {
      const double a = 2 * M_PI * i / kSides;
      s.p.emplace_back(0.4 * std::cos(a), 0.3 * std::sin(a), h ? 0.5 : -0.5);
    }
  std::vector<std::uint32_t> bottom, top;
  for (int i = 0; i < kSides; ++i) {
    const auto j = static_cast<std::uint32_t>((i + 1) % kSides), k = static_cast<std::uint32_t>(i);
    s.face({k, j, j + kSides, k + kSides});
    bottom.push_back(static_cast<std::uint32_t>(kSides - 1 - i));
    top.push_back(static_cast<std::uint32_t>(kSides + i));
  }
  s.idx.insert(s.idx.end(), bottom.begin(), bottom.end());
  s.off.push_back(static_cast<std::uint32_t>(s.idx.size()));
  s.idx.insert(s.idx.end(), top.begin(), top.end());
  s.off.push_back(static_cast<std::uint32_t>(s.idx.size()));
  Body b;
  b.ref = shapes::body_from(s);
  b.poly = BodyPolygons::from_model(b.ref->model);
  b.pos = skin_positions(*b.ref);
  std::size_t big = 0;
  for (std::size_t f = 0; f < b.poly.size(); ++f) big += b.poly.face_offsets[f + 1] - b.poly.face_offsets[f] > 16;
  ASSERT_EQ(big, 2u);
  SplitMix64 r(8);
  std::vector<Vec3d> g;
  for (int i = 0; i < 400; ++i) {
    const double a = r.uniform(0, 2 * M_PI), z = r.uniform(-0.6, 0.6);
    g.emplace_back(0.45 * std::cos(a), 0.35 * std::sin(a), z);
  }
  DetailParams prm;
  prm.polygons_per_vertex = 6;
  auto enc = encode_detail(b.poly, b.pos, g, prm);
  ASSERT_TRUE(enc);
  BodySet set(b.ref);
  std::vector<std::size_t> cap_nodes;  // model node indices of the top cap
  for (std::uint32_t k = b.poly.face_offsets[b.poly.size() - 1]; k < b.poly.face_offsets[b.poly.size()]; ++k)
    cap_nodes.push_back(b.poly.face_nodes[k]);
  for (int k = 0; k < 11; ++k) {
    std::vector<Vec3d> p = b.pos;
    for (auto& x : p) x = Vec3d(x.x() * r.uniform(0.9, 1.1), x.y() + 0.05 * x.z() * k, x.z() * (1 + 0.02 * k));
    if (k % 3 == 1)  // the top cap shrinks to a point: zero area
      for (const std::size_t n : cap_nodes) p[n] = Vec3d(0, 0, 0.5);
    if (k % 4 == 2) {  // one side quad folds onto a segment
      const std::uint32_t* q = b.poly.face_nodes.data() + b.poly.face_offsets[3];
      p[q[1]] = p[q[0]];
      p[q[2]] = p[q[3]];
    }
    ASSERT_TRUE(set.add("b" + std::to_string(k), std::span<const Vec3d>(p)));
  }
  const std::size_t nv = g.size();
  std::vector<Vec3f> one_out(11 * nv), two_out(11 * nv);
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 1;
  const DetailDecoder dec(*enc, one);
  // Every kernel: the large caps' frames are written by the double path
  // into each kernel's frame layout.
  for (const DecodeKernel kernel : {DecodeKernel::kAvx512, DecodeKernel::kAvx2, DecodeKernel::kPortable}) {
    DecodeWorkspace w1, w2;
    w1.allow = w2.allow = kernel;
    ASSERT_TRUE(decode_detail_batch(dec, b.poly, set, 0, 11, one_out, w1, one));
    ASSERT_TRUE(decode_detail_batch(dec, b.poly, set, 0, 11, two_out, w2, two));
    EXPECT_EQ(std::memcmp(one_out.data(), two_out.data(), one_out.size() * sizeof(Vec3f)), 0);
    std::vector<Vec3d> single(nv);
    for (std::size_t k = 0; k < 11; ++k) {
      ASSERT_TRUE(decode_detail(*enc, b.poly, set.positions(k), single));
      for (std::size_t v = 0; v < nv; ++v) {
        ASSERT_TRUE(single[v].allFinite()) << k << " " << v;
        ASSERT_LT((one_out[k * nv + v].cast<double>() - single[v]).norm(), 1e-5)
            << "kernel " << static_cast<int>(w1.ran) << " body " << k << " vertex " << v;
      }
    }
  }
}

TEST(PPolygonSearch, NearestManyWithRepeatedQueriesAndLatticeTies) {
  // Centroids on a lattice (many exactly equal distances) and queries that
  // repeat, step by lattice units or sit on centroids: each query's result
  // is built from the previous one, and ties must still break by index.
  std::vector<Vec3d> c;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 10; ++j)
      for (int k = 0; k < 3; ++k) c.emplace_back(0.1 * i, 0.1 * j, 0.1 * k);
  std::vector<std::uint8_t> skip(c.size(), 0);
  for (std::size_t i = 5; i < c.size(); i += 31) skip[i] = 1;
  std::vector<Vec3d> q;
  SplitMix64 r(17);
  for (int i = 0; i < 600; ++i) {
    const int step = i % 5;
    if (step == 0)
      q.push_back(c[static_cast<std::size_t>(r.uniform(0, 359.9))]);
    else if (step == 1)
      q.push_back(q.back());
    else if (step == 2)
      q.push_back(q.back() + Vec3d(0.1, 0, 0));
    else if (step == 3)
      q.push_back(q.back() + Vec3d(0.05, 0.05, 0.05));
    else
      q.push_back(Vec3d(r.uniform(-0.2, 1.3), r.uniform(-0.2, 1.1), r.uniform(-0.2, 0.4)));
  }
  for (std::size_t k : {1u, 6u, 27u, 100u}) {
    CentroidGrid g;
    g.build(c, skip, k);
    std::vector<std::uint32_t> got(q.size() * k), want;
    g.nearest_many(q, k, got, ExecContext::sequential());
    for (std::size_t v = 0; v < q.size(); ++v) {
      nearest_brute_force(c, skip, q[v], k, want);
      ASSERT_TRUE(std::equal(want.begin(), want.end(), got.begin() + static_cast<std::ptrdiff_t>(v * k)))
          << "k=" << k << " query " << v;
    }
  }
}

TEST(DetailTemplate, FileRoundTripAndCorruption) {
  const Body b = sphere_body();
  auto enc = encode_detail(b.poly, b.pos, shell_points(300, 2));
  ASSERT_TRUE(enc);
  const fs::path p = tmp_dir() / "garment.atd";
  write_detail(*enc, p);
  const DetailEncoding back = read_detail(p);
  EXPECT_EQ(back.polygon, enc->polygon);
  EXPECT_EQ(back.a, enc->a);
  EXPECT_EQ(back.b, enc->b);
  EXPECT_EQ(back.c, enc->c);
  EXPECT_EQ(back.d, enc->d);
  EXPECT_EQ(back.topology_hash, enc->topology_hash);
  EXPECT_EQ(back.reference_corners, enc->reference_corners);
  EXPECT_FALSE(back.z_depth.has_value());
  // Header (magic, version, sizes, topology hash), the matrix, the layer
  // order (flag and int32), a CRC-32.
  EXPECT_EQ(fs::file_size(p), enc->bytes() + 8 + 4 + 4 + 4 + 8 + 8 + 8 + 8 + 5 + 4);
  std::string bytes;
  {
    std::ifstream in(p, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  // On disk the coefficients are four blocks (all a, then b, c, d) after
  // the 52-byte header, the row offsets and the polygons.
  {
    const std::size_t ne = enc->entries(), at = 52 + 4 * (enc->vertex_count() + 1) + 4 * ne;
    for (const std::size_t e : {std::size_t{0}, ne / 2, ne - 1})
      for (std::size_t j = 0; j < 4; ++j) {
        float x;
        std::memcpy(&x, bytes.data() + at + 4 * (j * ne + e), 4);
        const std::vector<float>* col[4] = {&enc->a, &enc->b, &enc->c, &enc->d};
        EXPECT_EQ(x, (*col[j])[e]) << "entry " << e << " coefficient " << j;
      }
  }
  auto expect_error = [&](const std::string& content, const std::string& fragment) {
    const fs::path bad = tmp_dir() / "bad.atd";
    std::ofstream(bad, std::ios::binary) << content;
    try {
      (void)read_detail(bad);
      FAIL() << "no error for " << fragment;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.atd"), std::string::npos);
    }
  };
  expect_error(bytes.substr(0, bytes.size() / 2), "truncated");
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x40;
  expect_error(flipped, "checksum");
  expect_error("hello world, not a template", "bad magic");
  expect_error(bytes + "x", "1 bytes after the checksum");
  expect_error(flipped, "byte offset");
  // Version 1 files (no layer order, an FNV-1a checksum of 8 bytes) are still read.
  {
    std::string v1 = bytes.substr(0, bytes.size() - 4 - 5);
    const std::uint32_t one = 1;
    std::memcpy(v1.data() + 8, &one, 4);
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (const unsigned char c : v1) h = (h ^ c) * 0x100000001b3ull;
    v1.append(reinterpret_cast<const char*>(&h), 8);
    const fs::path old = tmp_dir() / "v1.atd";
    std::ofstream(old, std::ios::binary) << v1;
    EXPECT_EQ(read_detail(old).a, enc->a);
  }
  // Version 2 files (no layer order, a CRC-32) are still read, without a z_depth.
  {
    std::string v2 = bytes.substr(0, bytes.size() - 4 - 5);
    const std::uint32_t two = 2;
    std::memcpy(v2.data() + 8, &two, 4);
    const std::uint32_t sum = crc32(v2);
    v2.append(reinterpret_cast<const char*>(&sum), 4);
    const fs::path old = tmp_dir() / "v2.atd";
    std::ofstream(old, std::ios::binary) << v2;
    const DetailEncoding o = read_detail(old);
    EXPECT_EQ(o.a, enc->a);
    EXPECT_EQ(o.reference_corners, enc->reference_corners);
    EXPECT_FALSE(o.z_depth.has_value());
  }
  // Issue 26: the layer order round-trips (negative and zero included: a
  // z_depth of 0 is not "none"), and a flag other than 0 or 1 is named.
  for (const std::int32_t z : {0, -3, 50}) {
    DetailEncoding with = *enc;
    with.z_depth = z;
    const fs::path pz = tmp_dir() / "layered.atd";
    write_detail(with, pz);
    const DetailEncoding got = read_detail(pz);
    ASSERT_TRUE(got.z_depth.has_value());
    EXPECT_EQ(*got.z_depth, z);
    EXPECT_EQ(got.a, enc->a);
  }
  {
    std::string bad_flag = bytes.substr(0, bytes.size() - 4);
    bad_flag[bad_flag.size() - 5] = 7;
    const std::uint32_t sum = crc32(bad_flag);
    bad_flag.append(reinterpret_cast<const char*>(&sum), 4);
    expect_error(bad_flag, "layer-order flag");
  }
  // Writing into a missing folder fails cleanly and leaves nothing behind.
  EXPECT_THROW(write_detail(*enc, tmp_dir() / "no" / "such" / "dir" / "x.atd"), Error);
}

TEST(DetailTemplate, FileErrorsNameTheByteOffsetOfTheBadValue) {
  // Issue 27: values that pass the checksum but break the format are named
  // by the byte offset of the value, not of the end of the file.
  DetailEncoding d;
  d.polygon_count = 2;
  d.body_node_count = 4;
  d.row = {0, 1, 3, 4};
  d.polygon = {0, 1, 0, 1};
  d.a = {0.1f, 0.2f, 0.3f, 0.4f};
  d.b = d.c = d.d = d.a;
  const std::size_t header = 52, polygons_at = header + 4 * d.row.size(), coeff_at = polygons_at + 4 * 4;
  auto error_of = [](const DetailEncoding& e, const std::string& name) -> std::string {
    const fs::path p = tmp_dir() / name;
    write_detail(e, p);
    try {
      (void)read_detail(p);
    } catch (const Error& err) {
      return err.what();
    }
    return "accepted";
  };
  DetailEncoding bad_polygon = d;
  bad_polygon.polygon[2] = 2;
  EXPECT_NE(error_of(bad_polygon, "p.atd")
                .find("byte offset " + std::to_string(polygons_at + 8) + ": entry 2 names a polygon"),
            std::string::npos)
      << error_of(bad_polygon, "p.atd");
  DetailEncoding bad_coeff = d;
  bad_coeff.c[3] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(
      error_of(bad_coeff, "c.atd").find("byte offset " + std::to_string(coeff_at + 4 * (2 * 4 + 3)) + ": entry 3"),
      std::string::npos)
      << error_of(bad_coeff, "c.atd");
  DetailEncoding bad_row = d;
  bad_row.row[2] = 0;  // decreasing at vertex 1
  EXPECT_NE(error_of(bad_row, "r.atd").find("byte offset " + std::to_string(header + 8) + ": row offsets decrease"),
            std::string::npos)
      << error_of(bad_row, "r.atd");
  // Found by fuzzing: a file with no entries and no reference corners
  // memcpy'd into the null data() of empty vectors (undefined behaviour,
  // reported by UBSan in the sanitizer run). It reads as the empty matrix.
  DetailEncoding empty;
  empty.row = {0};
  write_detail(empty, tmp_dir() / "empty.atd");
  const DetailEncoding back = read_detail(tmp_dir() / "empty.atd");
  EXPECT_EQ(back.vertex_count(), 0u);
  EXPECT_EQ(back.entries(), 0u);
  EXPECT_TRUE(back.reference_corners.empty());
}

namespace {
using atelier::testing::makehuman_dir;
}  // namespace

TEST(DetailTemplate, RealSkinPPolygonsEqualBruteForceAndHelpersRegenerate) {
  if (!fs::exists(makehuman_dir() / "base.obj")) GTEST_SKIP() << "MakeHuman data not found at " << makehuman_dir();
  auto lib = std::make_shared<const makehuman::HumanLibrary>(makehuman::HumanLibrary::load(makehuman_dir()));
  const ReferenceBody ref = makehuman::make_reference_body(*lib);
  Body b;
  b.poly = BodyPolygons::from_model(ref.model);
  b.pos = skin_positions(ref);
  EXPECT_EQ(b.poly.size(), 13378u);
  // The tights helper as a garment on the default body.
  std::vector<Vec3f> full(lib->vertex_count());
  lib->build(makehuman::MacroParams{}, full);
  const auto* tights = lib->base().group("helper-tights");
  ASSERT_NE(tights, nullptr);
  std::vector<std::uint32_t> verts(tights->face_nodes.begin(), tights->face_nodes.end());
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  std::vector<Vec3d> g;
  for (auto v : verts) g.push_back(makehuman::kMakeHumanToMetres * full[v].cast<double>());
  // p-polygon sets on the real skin equal brute force (a sample of vertices).
  {
    const auto c = centroids_of(b);
    PolygonFrames fr;
    compute_frames(b.poly, b.pos, fr);
    CentroidGrid grid;
    grid.build(c, fr.degenerate, 134);
    std::vector<std::uint32_t> got, want;
    std::vector<std::pair<double, std::uint32_t>> scratch;
    for (std::size_t v = 0; v < g.size(); v += 37) {
      grid.nearest(g[v], 134, got, scratch);
      nearest_brute_force(c, fr.degenerate, g[v], 134, want);
      ASSERT_EQ(got, want) << "vertex " << v;
    }
  }
  auto enc = encode_detail(b.poly, b.pos, g);
  ASSERT_TRUE(enc);
  EXPECT_EQ(enc->entries() / g.size(), 134u);  // N_q = round(13378 / 100)
  // On morphed bodies, the regenerated tights stay close to MakeHuman's own
  // morphed helper (a ground truth: every target moves the helpers too).
  auto params = makehuman::sample_adults(5, 11);
  double worst_mean = 0;
  for (const auto& p : params) {
    lib->build(p, full);
    std::vector<Vec3d> body(b.pos.size()), out(g.size());
    for (std::size_t v = 0; v < body.size(); ++v) body[v] = makehuman::kMakeHumanToMetres * full[v].cast<double>();
    ASSERT_TRUE(decode_detail(*enc, b.poly, body, out));
    double sum = 0;
    for (std::size_t i = 0; i < verts.size(); ++i)
      sum += (out[i] - makehuman::kMakeHumanToMetres * full[verts[i]].cast<double>()).norm();
    worst_mean = std::max(worst_mean, sum / verts.size());
  }
  EXPECT_LT(worst_mean, 0.01);  // mean error under 1 cm on every body
  RecordProperty("tights_worst_mean_error_m", std::to_string(worst_mean));
  std::cout << "tights regeneration: worst mean error over 5 bodies = " << worst_mean * 1000 << " mm\n";
}
