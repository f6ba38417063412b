// Catmull-Clark with creases (seed 003 step 5): counts, Spot's reference
// tessellation, crease limits against an independent cubic B-spline,
// OpenSubdiv's Far refiner as oracle, thread-count independence, errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <unordered_map>

#include "curvenet_fixtures.h"
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/curvenet/catmull_clark.h>
#include <atelier/systems/curvenet/curve_surface.h>

#if __has_include(<opensubdiv/far/topologyDescriptor.h>)
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#define ATELIER_TEST_OPENSUBDIV 1
#endif

using namespace atelier;
using namespace atelier::curvenet_test;

namespace {

/// A small open mesh with a triangle, quads and a pentagon.
PolygonSoup mixed_mesh() {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0},   {2, 0, 0.2},     {0, 1, 0},  {1, 1, 0.3},
                 {2, 1, 0}, {0.5, 2, 0}, {1.5, 2.2, 0.1}, {3, 0.5, 0}};
  for (const auto& f :
       std::vector<std::vector<std::uint32_t>>{{0, 1, 4, 3}, {1, 2, 5, 4}, {3, 4, 7, 6}, {2, 8, 5}, {4, 5, 7}})
    s.add_face(f);
  return s;
}

/// The unit cube as 6 quads, outward.
PolygonSoup cube() {
  PolygonSoup s;
  for (int c = 0; c < 8; ++c) s.positions.emplace_back(c & 1, (c >> 1) & 1, (c >> 2) & 1);
  for (const auto& f : std::vector<std::vector<std::uint32_t>>{
           {0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}})
    s.add_face(f);
  return s;
}

/// Point-set equality with a bijection found by a hash grid; returns the
/// map from a's indices to b's, or an empty vector (with a failure).
std::vector<std::uint32_t> match_points(std::span<const Vec3d> a, std::span<const Vec3d> b, double tol) {
  EXPECT_EQ(a.size(), b.size());
  if (a.size() != b.size()) return {};
  const double cell = 16 * tol;
  auto key = [&](const Vec3d& p, int dx, int dy, int dz) {
    const auto ix = static_cast<std::int64_t>(std::floor(p.x() / cell)) + dx;
    const auto iy = static_cast<std::int64_t>(std::floor(p.y() / cell)) + dy;
    const auto iz = static_cast<std::int64_t>(std::floor(p.z() / cell)) + dz;
    return (ix * 73856093) ^ (iy * 19349663) ^ (iz * 83492791);
  };
  std::unordered_multimap<std::int64_t, std::uint32_t> grid;
  for (std::uint32_t i = 0; i < b.size(); ++i) grid.emplace(key(b[i], 0, 0, 0), i);
  std::vector<std::uint32_t> m(a.size(), 0xffffffffu);
  std::vector<std::uint8_t> used(b.size(), 0);
  std::size_t misses = 0;
  double worst = 0;
  for (std::uint32_t i = 0; i < a.size(); ++i) {
    double best = tol;
    std::uint32_t found = 0xffffffffu;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto [lo, hi] = grid.equal_range(key(a[i], dx, dy, dz));
          for (auto it = lo; it != hi; ++it) {
            const double d = (a[i] - b[it->second]).norm();
            if (d <= best && !used[it->second]) {
              best = d;
              found = it->second;
            }
          }
        }
    if (found == 0xffffffffu) {
      ++misses;
      continue;
    }
    worst = std::max(worst, best);
    used[found] = 1;
    m[i] = found;
  }
  EXPECT_EQ(misses, 0u) << "points without a partner within " << tol;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", worst);
  ::testing::Test::RecordProperty("worst_match", buf);
  return misses ? std::vector<std::uint32_t>{} : m;
}

/// The faces of a, mapped through m, equal those of b as cyclic sequences.
void expect_same_faces(const PolygonSoupView& a, const PolygonSoupView& b, const std::vector<std::uint32_t>& m) {
  ASSERT_EQ(a.face_count(), b.face_count());
  auto canon = [](std::vector<std::uint32_t> f) {
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    return f;
  };
  std::map<std::vector<std::uint32_t>, int> fb;
  for (std::size_t f = 0; f < b.face_count(); ++f)
    ++fb[canon({b.face_nodes.begin() + b.face_offsets[f], b.face_nodes.begin() + b.face_offsets[f + 1]})];
  std::size_t missing = 0;
  for (std::size_t f = 0; f < a.face_count(); ++f) {
    std::vector<std::uint32_t> q;
    for (std::uint32_t k = a.face_offsets[f]; k < a.face_offsets[f + 1]; ++k) q.push_back(m[a.face_nodes[k]]);
    auto it = fb.find(canon(q));
    if (it == fb.end() || it->second == 0)
      ++missing;
    else
      --it->second;
  }
  EXPECT_EQ(missing, 0u);
}

/// Uniform cubic B-spline of P_0..P_m with P_{-1} = 2P_0 - P_1, P_{m+1} =
/// 2P_m - P_{m-1}, at t in [0, m] (written from the basis functions).
Vec3d bspline(const std::vector<Vec3d>& P, double t) {
  const auto m = static_cast<int>(P.size()) - 1;
  auto at = [&](int i) -> Vec3d {
    if (i < 0) return 2 * P[0] - P[1];
    if (i > m) return 2 * P[static_cast<std::size_t>(m)] - P[static_cast<std::size_t>(m - 1)];
    return P[static_cast<std::size_t>(i)];
  };
  int j = std::min(static_cast<int>(std::floor(t)), m - 1);
  const double u = t - j;
  const double b0 = (1 - u) * (1 - u) * (1 - u) / 6, b1 = (3 * u * u * u - 6 * u * u + 4) / 6,
               b2 = (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6, b3 = u * u * u / 6;
  return b0 * at(j - 1) + b1 * at(j) + b2 * at(j + 1) + b3 * at(j + 2);
}

}  // namespace

TEST(CatmullClark, CountsFollowTheFormulas) {
  for (const PolygonSoup& s : {mixed_mesh(), cube()}) {
    CatmullClarkOptions o;
    o.levels = 3;
    o.full_topology_in_last_level = true;
    auto r = CatmullClarkRefiner::create(s, s.positions.size(), {}, {}, o);
    ASSERT_TRUE(r) << r.status().to_string();
    for (int l = 0; l < 3; ++l) {
      const CornerMesh& p = r->level(l);
      const CornerMesh& c = r->level(l + 1);
      const std::size_t sum_n = p.corner_count();
      EXPECT_EQ(c.vertex_count, p.vertex_count + p.edge_count() + p.face_count()) << "level " << l + 1;
      EXPECT_EQ(c.edge_count(), 2 * p.edge_count() + sum_n) << "level " << l + 1;
      EXPECT_EQ(c.face_count(), sum_n) << "level " << l + 1;
      // The analytic child topology equals the one built from its faces.
      auto rebuilt = build_corner_mesh(PolygonSoupView({}, c.face_offsets, c.face_verts), c.vertex_count);
      ASSERT_TRUE(rebuilt);
      EXPECT_EQ(rebuilt->edge_count(), c.edge_count());
      for (std::uint32_t v = 0; v < c.vertex_count; ++v)
        EXPECT_EQ(rebuilt->vert_offsets[v + 1] - rebuilt->vert_offsets[v], c.vert_offsets[v + 1] - c.vert_offsets[v]);
      for (std::size_t e = 0; e < c.edge_count(); ++e) {
        const auto [a, b] = c.edge_verts[e];
        EXPECT_NE(rebuilt->find_edge(a, b), kNoCorner);
        for (std::uint32_t k : c.edge_corners[e])
          if (k != kNoCorner) {
            EXPECT_EQ(c.corner_edge[k], e);
          }
      }
    }
    // The refined surface is a valid oriented manifold.
    auto out = subdivide_catmull_clark(s, {}, {}, o);
    ASSERT_TRUE(out);
    Model m;
    ASSERT_TRUE(add_polygon_surface(m, "cc", out->mesh));
    EXPECT_TRUE(validate(m)) << validate(m).to_string();
  }
}

TEST(CatmullClark, SpotTwoLevelsEqualsItsQuadrangulation) {
  const auto dir = std::filesystem::path(ATELIER_SHARED_DATA) / "meshes";
  if (!std::filesystem::exists(dir / "spot_control_mesh.obj")) GTEST_SKIP() << "shared meshes not found";
  const PolygonSoup control = read_soup(dir / "spot_control_mesh.obj");
  const PolygonSoup reference = read_soup(dir / "spot_quadrangulated.obj");
  ASSERT_EQ(control.positions.size(), 188u);
  CatmullClarkOptions o;
  o.levels = 2;
  auto out = subdivide_catmull_clark(control, {}, {}, o);
  ASSERT_TRUE(out) << out.status().to_string();
  // 188 + 366 + 180 = 734 vertices, then 734 + 1464 + 732 = 2930: the file's count.
  EXPECT_EQ(out->mesh.positions.size(), reference.positions.size());
  EXPECT_EQ(out->mesh.face_count(), reference.face_count());
  // The file keeps 6 significant digits: 1e-5 covers its rounding.
  const auto m = match_points(out->mesh.positions, reference.positions, 1e-5);
  ASSERT_FALSE(m.empty());
  expect_same_faces(out->mesh, reference, m);
  // The control vertices keep their numbers (vertex points first).
  for (std::uint32_t v = 0; v < 188; ++v) EXPECT_EQ(m[v], v);
}

TEST(CatmullClark, CreaseLimitIsTheCubicBSplineOfItsPolygon) {
  // A wavy crease polygon P_0..P_6 along y = 0 with corners at both ends,
  // inside a 6 x 2 quad strip on each side.
  const int m = 6;
  std::vector<Vec3d> P;
  for (int i = 0; i <= m; ++i)
    P.emplace_back(i + 0.2 * std::sin(1.3 * i), 0.1 * std::cos(2.1 * i), 0.3 * std::sin(0.9 * i));
  PolygonSoup s;
  for (int j = -2; j <= 2; ++j)
    for (int i = 0; i <= m; ++i)
      s.positions.push_back(j == 0 ? P[static_cast<std::size_t>(i)] : Vec3d(i, 0.7 * j, 0.2 * std::cos(i + j)));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>((j + 2) * (m + 1) + i); };
  for (int j = -2; j < 2; ++j)
    for (int i = 0; i < m; ++i) {
      const std::uint32_t f[] = {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      s.add_face(f);
    }
  std::vector<std::array<std::uint32_t, 2>> creases;
  for (int i = 0; i < m; ++i) creases.push_back({id(i, 0), id(i + 1, 0)});
  const std::uint32_t corners[] = {id(0, 0), id(m, 0)};
  const int L = 4;
  CatmullClarkOptions o;
  o.levels = L;
  auto out = subdivide_catmull_clark(s, creases, corners, o);
  ASSERT_TRUE(out) << out.status().to_string();
  ASSERT_EQ(out->creases.size(), static_cast<std::size_t>(m << L));
  const auto limit = crease_limit_positions(out->mesh.positions, out->creases, out->corners);
  // Walk the refined crease from P_0 and compare every vertex with the spline.
  std::vector<std::vector<std::uint32_t>> nb(out->mesh.positions.size());
  for (const auto& e : out->creases) {
    nb[e[0]].push_back(e[1]);
    nb[e[1]].push_back(e[0]);
  }
  std::uint32_t prev = 0xffffffffu, v = id(0, 0);
  double worst = 0;
  for (int k = 0; k <= (m << L); ++k) {
    const Vec3d expected = bspline(P, static_cast<double>(k) / (1 << L));
    worst = std::max(worst, (limit[v] - expected).norm());
    if (k == (m << L)) break;
    const std::uint32_t next = nb[v][0] == prev ? nb[v][1] : nb[v][0];
    prev = v;
    v = next;
  }
  EXPECT_EQ(v, id(m, 0));
  EXPECT_LT(worst, 1e-12);
}

TEST(CatmullClark, NetworkCreasesLimitToTheirSegmentsSplines) {
  ATELIER_REQUIRE_SHARED_NETWORKS();
  CurveSurfaceOptions o;
  o.levels = 3;
  o.build_model = false;
  auto r = surface_from_curves(shared_network("roof_75"), {}, o);
  ASSERT_TRUE(r) << r.status().to_string();
  const ControlMesh& cm = r->control;
  const SubdividedMesh& sm = r->refined;
  const auto limit = crease_limit_positions(sm.mesh.positions, sm.creases, sm.corners);
  std::vector<std::vector<std::uint32_t>> nb(sm.mesh.positions.size());
  for (const auto& e : sm.creases) {
    nb[e[0]].push_back(e[1]);
    nb[e[1]].push_back(e[0]);
  }
  // Refined vertex indices along a segment: walk from its first node through
  // the child of its first polygon edge (control vertex indices are kept).
  double worst = 0;
  std::size_t checked = 0;
  for (std::size_t s = 0; s < r->graph.segment_count(); ++s) {
    std::vector<Vec3d> P;
    for (std::uint32_t k = cm.segment_offsets[s]; k < cm.segment_offsets[s + 1]; ++k)
      P.push_back(cm.mesh.positions[cm.segment_vertices[k]]);
    const auto mm = static_cast<int>(P.size()) - 1;
    const std::uint32_t a = cm.segment_vertices[cm.segment_offsets[s]];
    const std::uint32_t b = cm.segment_vertices[cm.segment_offsets[s + 1] - 1];
    if (a == b) continue;  // a closed segment: its walk may start either way
    // The first step: the refined neighbour of a closest to the spline at t = 1/8.
    const Vec3d first = bspline(P, 1.0 / 8);
    std::uint32_t v = a, prev = 0xffffffffu, next = nb[a][0];
    for (std::uint32_t w : nb[a])
      if ((limit[w] - first).norm() < (limit[next] - first).norm()) next = w;
    for (int k = 0; k <= mm * 8; ++k) {
      worst = std::max(worst, (limit[v] - bspline(P, k / 8.0)).norm());
      ++checked;
      if (k == mm * 8) break;
      if (k > 0) {
        ASSERT_EQ(nb[v].size(), 2u);
        next = nb[v][0] == prev ? nb[v][1] : nb[v][0];
      }
      prev = v;
      v = next;
    }
    EXPECT_EQ(v, b);
  }
  EXPECT_GT(checked, 10000u);
  EXPECT_LT(worst, 1e-12 * (1 + r->report.treatment.diagonal));
}

TEST(CatmullClark, ThreadCountDoesNotChangeABit) {
  ATELIER_REQUIRE_SHARED_NETWORKS();
  CurveSurfaceOptions o;
  o.levels = 0;
  o.build_model = false;
  auto r = surface_from_curves(shared_network("shell_100"), {}, o);
  ASSERT_TRUE(r);
  const ControlMesh& cm = r->control;
  ExecContext one = ExecContext::sequential(), two;
  two.threads = 2;
  two.sequential_threshold = 1;
  two.grain = 64;
  CatmullClarkOptions co;
  co.levels = 3;
  auto a = subdivide_catmull_clark(cm.mesh, cm.creases, cm.corners, co, one);
  auto b = subdivide_catmull_clark(cm.mesh, cm.creases, cm.corners, co, two);
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->mesh.positions.size(), b->mesh.positions.size());
  EXPECT_EQ(0,
            std::memcmp(a->mesh.positions.data(), b->mesh.positions.data(), a->mesh.positions.size() * sizeof(Vec3d)));
  EXPECT_EQ(a->mesh.face_nodes, b->mesh.face_nodes);
  EXPECT_EQ(a->creases, b->creases);
}

TEST(CatmullClark, BadInputIsRefused) {
  const PolygonSoup s = mixed_mesh();
  const std::array<std::uint32_t, 2> not_edge[] = {{0, 5}};
  EXPECT_NE(subdivide_catmull_clark(s, not_edge, {}).status().message().find("not an edge"), std::string::npos);
  const std::uint32_t far_corner[] = {99};
  EXPECT_EQ(subdivide_catmull_clark(s, {}, far_corner).status().code(), ErrorCode::kInvalidArgument);
  CatmullClarkOptions o;
  o.levels = 9;
  EXPECT_EQ(subdivide_catmull_clark(s, {}, {}, o).status().code(), ErrorCode::kInvalidArgument);
  // Three faces on one edge, and two faces running an edge the same way.
  PolygonSoup fin;
  fin.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  for (const auto& f : std::vector<std::vector<std::uint32_t>>{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}) fin.add_face(f);
  EXPECT_EQ(subdivide_catmull_clark(fin, {}, {}).status().code(), ErrorCode::kNonManifold);
  PolygonSoup flipped;
  flipped.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  for (const auto& f : std::vector<std::vector<std::uint32_t>>{{0, 1, 2}, {0, 1, 3}}) flipped.add_face(f);
  EXPECT_EQ(subdivide_catmull_clark(flipped, {}, {}).status().code(), ErrorCode::kNonManifold);
  auto r = CatmullClarkRefiner::create(s, s.positions.size(), {}, {});
  ASSERT_TRUE(r);
  std::vector<Vec3d> out;
  EXPECT_EQ(r->refine(std::span<const Vec3d>(s.positions).first(3), out).code(), ErrorCode::kMismatch);
  std::vector<Vec3d> nan = s.positions;
  nan[2].x() = std::nan("");
  EXPECT_EQ(r->refine(nan, out).code(), ErrorCode::kInvalidArgument);
}

#ifdef ATELIER_TEST_OPENSUBDIV
namespace {

struct OsdPoint {
  double x = 0, y = 0, z = 0;
  void Clear(void* = nullptr) { x = y = z = 0; }
  void AddWithWeight(const OsdPoint& s, double w) {
    x += w * s.x;
    y += w * s.y;
    z += w * s.z;
  }
};

/// The last level of OpenSubdiv's Far uniform refinement (Catmark, boundary
/// edges sharp, infinitely sharp creases and corners), double precision.
PolygonSoup opensubdiv_refine(const PolygonSoupView& s, std::span<const std::array<std::uint32_t, 2>> creases,
                              std::span<const std::uint32_t> corners, int levels) {
  using namespace OpenSubdiv;
  using Descriptor = Far::TopologyDescriptor;
  std::vector<int> nverts, idx(s.face_nodes.begin(), s.face_nodes.end()), crease_idx,
      corner_idx(corners.begin(), corners.end());
  for (std::size_t f = 0; f < s.face_count(); ++f)
    nverts.push_back(static_cast<int>(s.face_offsets[f + 1] - s.face_offsets[f]));
  for (const auto& c : creases) {
    crease_idx.push_back(static_cast<int>(c[0]));
    crease_idx.push_back(static_cast<int>(c[1]));
  }
  std::vector<float> crease_w(creases.size(), Sdc::Crease::SHARPNESS_INFINITE);
  std::vector<float> corner_w(corners.size(), Sdc::Crease::SHARPNESS_INFINITE);
  Descriptor d;
  d.numVertices = static_cast<int>(s.positions.size());
  d.numFaces = static_cast<int>(s.face_count());
  d.numVertsPerFace = nverts.data();
  d.vertIndicesPerFace = idx.data();
  d.numCreases = static_cast<int>(creases.size());
  d.creaseVertexIndexPairs = crease_idx.data();
  d.creaseWeights = crease_w.data();
  d.numCorners = static_cast<int>(corners.size());
  d.cornerVertexIndices = corner_idx.data();
  d.cornerWeights = corner_w.data();
  Sdc::Options options;
  options.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
  std::unique_ptr<Far::TopologyRefiner> refiner(Far::TopologyRefinerFactory<Descriptor>::Create(
      d, Far::TopologyRefinerFactory<Descriptor>::Options(Sdc::SCHEME_CATMARK, options)));
  refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(levels));
  std::vector<OsdPoint> buf(static_cast<std::size_t>(refiner->GetNumVerticesTotal()));
  for (std::size_t v = 0; v < s.positions.size(); ++v)
    buf[v] = {s.positions[v].x(), s.positions[v].y(), s.positions[v].z()};
  Far::PrimvarRefinerReal<double> primvar(*refiner);
  OsdPoint* src = buf.data();
  for (int l = 1; l <= levels; ++l) {
    OsdPoint* dst = src + refiner->GetLevel(l - 1).GetNumVertices();
    primvar.Interpolate(l, src, dst);
    src = dst;
  }
  const Far::TopologyLevel& last = refiner->GetLevel(levels);
  PolygonSoup out;
  for (int v = 0; v < last.GetNumVertices(); ++v) out.positions.emplace_back(src[v].x, src[v].y, src[v].z);
  for (int f = 0; f < last.GetNumFaces(); ++f) {
    const Far::ConstIndexArray fv = last.GetFaceVertices(f);
    std::vector<std::uint32_t> q;
    for (int k = 0; k < fv.size(); ++k) q.push_back(static_cast<std::uint32_t>(fv[k]));
    out.add_face(q);
  }
  return out;
}

}  // namespace

TEST(CatmullClark, OpenSubdivFarGivesTheSamePoints) {
  // 1. A mixed open mesh with an interior crease path, a dart, corners.
  {
    const PolygonSoup s = mixed_mesh();
    const std::array<std::uint32_t, 2> creases[] = {{1, 4}, {4, 5}, {4, 7}};
    const std::uint32_t corners[] = {0, 6};
    CatmullClarkOptions o;
    o.levels = 3;
    auto ours = subdivide_catmull_clark(s, creases, corners, o);
    ASSERT_TRUE(ours);
    const PolygonSoup osd = opensubdiv_refine(s, creases, corners, 3);
    const auto m = match_points(ours->mesh.positions, osd.positions, 1e-9);
    ASSERT_FALSE(m.empty());
    expect_same_faces(ours->mesh, osd, m);
  }
  // 2. A curve network's control mesh: its polygons as creases, its nodes as corners.
  ATELIER_REQUIRE_SHARED_NETWORKS();
  CurveSurfaceOptions co;
  co.levels = 0;
  co.build_model = false;
  auto r = surface_from_curves(shared_network("roof_75"), {}, co);
  ASSERT_TRUE(r);
  const ControlMesh& cm = r->control;
  CatmullClarkOptions o;
  o.levels = 2;
  auto ours = subdivide_catmull_clark(cm.mesh, cm.creases, cm.corners, o);
  ASSERT_TRUE(ours);
  const PolygonSoup osd = opensubdiv_refine(cm.mesh, cm.creases, cm.corners, 2);
  const auto m = match_points(ours->mesh.positions, osd.positions, 1e-9);
  ASSERT_FALSE(m.empty());
  expect_same_faces(ours->mesh, osd, m);
  // 3. Spot, smooth (no crease): the closed case with triangles and pentagons.
  const auto dir = std::filesystem::path(ATELIER_SHARED_DATA) / "meshes";
  if (std::filesystem::exists(dir / "spot_control_mesh.obj")) {
    const PolygonSoup spot = read_soup(dir / "spot_control_mesh.obj");
    o.levels = 3;
    auto a = subdivide_catmull_clark(spot, {}, {}, o);
    ASSERT_TRUE(a);
    const PolygonSoup b = opensubdiv_refine(spot, {}, {}, 3);
    const auto ms = match_points(a->mesh.positions, b.positions, 1e-9);
    ASSERT_FALSE(ms.empty());
    expect_same_faces(a->mesh, b, ms);
  }
}
#else
TEST(CatmullClark, OpenSubdivFarGivesTheSamePoints) {
  GTEST_SKIP() << "OpenSubdiv (libosd-dev) not installed";
}
#endif
