// Tests of the procedural mannequin: requested girths, identical topology,
// watertightness, no self-intersection (uniform-grid broad phase, exact
// segment/triangle narrow phase), encodable feature frames, determinism of
// the sampler.
#include <gtest/gtest.h>

#include <atelier/engine/parallel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <sstream>
#include <string>

#include <atelier/storage/topology.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/body/measure.h>
#include <atelier/storage/validate.h>

namespace atelier {
namespace {

// ------------------------------------------------ self-intersection check
// Faces are fanned into triangles (c0, ck, ck+1), the same convention as the
// attribute face nodes. Two triangles intersect when an edge of one crosses
// the other; shared corners are excluded (points within a tiny distance of
// a shared node do not count), and edge-adjacent triangles are reported
// only when folded flat onto each other. Coplanar overlaps of non-adjacent
// triangles are not detected (they need exact coplanarity).
struct Tri {
  std::array<std::uint32_t, 3> v;
};

bool segment_hits_triangle(const Vec3d& p, const Vec3d& q, const Vec3d& a, const Vec3d& b, const Vec3d& c, Vec3d& hit) {
  const Vec3d d = q - p, e1 = b - a, e2 = c - a;
  const Vec3d h = d.cross(e2);
  const double det = e1.dot(h);
  const double scale = e1.norm() * e2.norm() * d.norm();
  if (std::abs(det) <= 1e-14 * scale) return false;  // parallel
  const double inv = 1.0 / det;
  const Vec3d s = p - a;
  const double u = s.dot(h) * inv;
  if (u < 0 || u > 1) return false;
  const Vec3d qv = s.cross(e1);
  const double v = d.dot(qv) * inv;
  if (v < 0 || u + v > 1) return false;
  const double t = e2.dot(qv) * inv;
  if (t < 0 || t > 1) return false;
  hit = p + t * d;
  return true;
}

bool triangles_intersect(const std::vector<Vec3d>& P, const Tri& A, const Tri& B) {
  std::array<std::uint32_t, 3> shared{};
  std::size_t nshared = 0;
  for (auto x : A.v)
    for (auto y : B.v)
      if (x == y) shared[nshared++] = x;
  if (nshared >= 3) return true;  // duplicate triangle
  if (nshared == 2) {
    // Edge-adjacent: intersect only when folded onto each other.
    const Vec3d na = (P[A.v[1]] - P[A.v[0]]).cross(P[A.v[2]] - P[A.v[0]]).normalized();
    const Vec3d nb = (P[B.v[1]] - P[B.v[0]]).cross(P[B.v[2]] - P[B.v[0]]).normalized();
    return na.dot(nb) < -0.999999;
  }
  // Early rejection (Moller): when one triangle lies strictly on one side of
  // the other's plane (shared nodes excepted), they meet at most at a shared node.
  auto separated = [&](const Tri& S, const Tri& T) {
    const Vec3d a = P[S.v[0]], n = (P[S.v[1]] - a).cross(P[S.v[2]] - a);
    int pos = 0, neg = 0;
    for (auto v : T.v) {
      if (nshared == 1 && v == shared[0]) continue;
      const double d = n.dot(P[v] - a);
      pos += d > 0;
      neg += d < 0;
    }
    const int others = 3 - static_cast<int>(nshared);
    return pos == others || neg == others;
  };
  if (separated(A, B) || separated(B, A)) return false;
  const double tol = 1e-9;
  auto test = [&](const Tri& S, const Tri& T) {
    for (int k = 0; k < 3; ++k) {
      Vec3d hit;
      if (!segment_hits_triangle(P[S.v[k]], P[S.v[(k + 1) % 3]], P[T.v[0]], P[T.v[1]], P[T.v[2]], hit)) continue;
      if (nshared == 1 && (hit - P[shared[0]]).norm() < tol) continue;
      return true;
    }
    return false;
  };
  return test(A, B) || test(B, A);
}

/// Number of intersecting triangle pairs (0 for an embedded surface).
std::size_t count_self_intersections(const std::vector<Vec3d>& P, std::span<const std::uint32_t> offsets,
                                     std::span<const std::uint32_t> nodes, std::size_t stop_after = 1,
                                     std::string* where = nullptr) {
  std::vector<Tri> tris;
  for (std::size_t f = 0; f + 1 < offsets.size(); ++f)
    for (std::uint32_t k = offsets[f] + 1; k + 1 < offsets[f + 1]; ++k) tris.push_back({{nodes[offsets[f]], nodes[k], nodes[k + 1]}});
  const std::size_t n = tris.size();
  std::vector<Vec3d> lo(n), hi(n);
  Vec3d glo = Vec3d::Constant(1e300), ghi = Vec3d::Constant(-1e300);
  double ext = 0;
  for (std::size_t i = 0; i < n; ++i) {
    lo[i] = P[tris[i].v[0]].cwiseMin(P[tris[i].v[1]]).cwiseMin(P[tris[i].v[2]]);
    hi[i] = P[tris[i].v[0]].cwiseMax(P[tris[i].v[1]]).cwiseMax(P[tris[i].v[2]]);
    glo = glo.cwiseMin(lo[i]);
    ghi = ghi.cwiseMax(hi[i]);
    ext += (hi[i] - lo[i]).maxCoeff();
  }
  // Uniform grid, cells about twice the mean triangle extent.
  const double cell = std::max(2.0 * ext / double(n), 1e-6);
  std::array<long, 3> dim;
  for (int a = 0; a < 3; ++a) dim[a] = std::max(1L, long((ghi[a] - glo[a]) / cell) + 1);
  auto cell_of = [&](const Vec3d& p, int a) { return std::clamp(long((p[a] - glo[a]) / cell), 0L, dim[a] - 1); };
  // (cell, triangle) pairs sorted by cell: a flat grid without per-cell heap lists.
  std::vector<std::pair<long, std::uint32_t>> entries;
  entries.reserve(2 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (long x = cell_of(lo[i], 0); x <= cell_of(hi[i], 0); ++x)
      for (long y = cell_of(lo[i], 1); y <= cell_of(hi[i], 1); ++y)
        for (long z = cell_of(lo[i], 2); z <= cell_of(hi[i], 2); ++z)
          entries.emplace_back((x * dim[1] + y) * dim[2] + z, static_cast<std::uint32_t>(i));
  std::sort(entries.begin(), entries.end());
  std::size_t found = 0;
  for (std::size_t b0 = 0, b1 = 0; b0 < entries.size(); b0 = b1) {
    const long key = entries[b0].first;
    for (b1 = b0; b1 < entries.size() && entries[b1].first == key; ++b1) {
    }
    for (std::size_t i = b0; i < b1; ++i)
      for (std::size_t j = i + 1; j < b1; ++j) {
        const auto a = entries[i].second, b = entries[j].second;
        const Vec3d ilo = lo[a].cwiseMax(lo[b]), ihi = hi[a].cwiseMin(hi[b]);
        if ((ilo.array() > ihi.array()).any()) continue;
        // Test each pair once: in the cell holding the low corner of the overlap.
        if ((cell_of(ilo, 0) * dim[1] + cell_of(ilo, 1)) * dim[2] + cell_of(ilo, 2) != key) continue;
        if (!triangles_intersect(P, tris[a], tris[b])) continue;
        if (where && where->empty()) {
          std::ostringstream o;
          const Vec3d ca = (P[tris[a].v[0]] + P[tris[a].v[1]] + P[tris[a].v[2]]) / 3;
          const Vec3d cb = (P[tris[b].v[0]] + P[tris[b].v[1]] + P[tris[b].v[2]]) / 3;
          o << "triangles " << a << " (nodes " << tris[a].v[0] << "," << tris[a].v[1] << "," << tris[a].v[2] << " near "
            << ca.transpose() << ") and " << b << " (nodes " << tris[b].v[0] << "," << tris[b].v[1] << "," << tris[b].v[2]
            << " near " << cb.transpose() << ")";
          *where = o.str();
        }
        if (++found >= stop_after) return found;
      }
  }
  return found;
}

const MannequinTopology& topology(std::uint32_t level) {
  static std::map<std::uint32_t, MannequinTopology> cache;
  auto it = cache.find(level);
  if (it == cache.end()) it = cache.emplace(level, make_mannequin_topology(MannequinResolution::from_level(level)).value()).first;
  return it->second;
}

// ------------------------------------------------------------------ tests

TEST(MannequinSelfIntersection, CheckerFindsCrossingAndAcceptsSharedCorners) {
  std::vector<Vec3d> P = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, -1}, {0.2, 0.2, 1}, {2, 2, 0}, {3, 0, 0}};
  const std::vector<std::uint32_t> off = {0, 3, 6};
  // Triangle 2 pierces triangle 1.
  EXPECT_EQ(count_self_intersections(P, off, std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}), 1u);
  // Sharing a corner only: no intersection.
  EXPECT_EQ(count_self_intersections(P, off, std::vector<std::uint32_t>{0, 1, 2, 1, 6, 5}), 0u);
  // Sharing a corner, but the other triangle passes through the first one.
  P.push_back({0.3, 0.3, 1});
  EXPECT_EQ(count_self_intersections(P, off, std::vector<std::uint32_t>{0, 1, 2, 1, 3, 7}), 1u);
}

TEST(Mannequin, DefaultIsWatertightAndValid) {
  auto body = make_mannequin();
  ASSERT_TRUE(body) << body.status().to_string();
  const Model& m = body->model;
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  ASSERT_TRUE(validate_features(*body)) << validate_features(*body).to_string();
  EXPECT_GE(m.num_faces(), 10'000u);
  EXPECT_LE(m.num_faces(), 50'000u);
  // Every edge has a face on both sides.
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e)
    if (m.alive(EdgeIdx{e})) {
      EXPECT_TRUE(m.face(halfedge_of(EdgeIdx{e}, 0)).valid() && m.face(halfedge_of(EdgeIdx{e}, 1)).valid()) << "edge " << e;
    }
  const TopologyCounts t = count_topology(m);
  EXPECT_EQ(t.nodes - t.edges + t.faces, 2);  // a sphere
  EXPECT_EQ(t.shells, 1);
  EXPECT_EQ(t.components, 1);
  // Outward orientation and a plausible volume (a headless, armless adult:
  // a few hundredths of a cubic metre).
  double vol = 0;
  std::vector<NodeIdx> fn;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    m.face_nodes(FaceIdx{f}, fn);
    for (std::size_t k = 1; k + 1 < fn.size(); ++k)
      vol += m.position(fn[0]).dot(m.position(fn[k]).cross(m.position(fn[k + 1]))) / 6.0;
  }
  EXPECT_GT(vol, 0.02);
  EXPECT_LT(vol, 0.12);
}

TEST(Mannequin, FaceArraysAreAClosedOrientedSurface) {
  // Independent of the Model: every directed edge once, its twin once.
  for (std::uint32_t level : {1u, 2u, 6u}) {
    const MannequinTopology& t = topology(level);
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
    for (std::size_t f = 0; f + 1 < t.face_offsets.size(); ++f)
      for (std::uint32_t k = t.face_offsets[f]; k < t.face_offsets[f + 1]; ++k) {
        const std::uint32_t a = t.face_nodes[k];
        const std::uint32_t b = k + 1 < t.face_offsets[f + 1] ? t.face_nodes[k + 1] : t.face_nodes[t.face_offsets[f]];
        ++directed[{a, b}];
      }
    std::size_t bad = 0;
    for (const auto& [e, c] : directed)
      if (c != 1 || directed.count({e.second, e.first}) != 1 || directed.at({e.second, e.first}) != 1) ++bad;
    EXPECT_EQ(bad, 0u) << "level " << level;
    std::vector<bool> used(t.num_nodes, false);
    for (auto v : t.face_nodes) used[v] = true;
    EXPECT_TRUE(std::all_of(used.begin(), used.end(), [](bool b) { return b; })) << "isolated node at level " << level;
  }
}

TEST(Mannequin, DefaultGirthsMatchRequest) {
  const MannequinParams p;
  auto body = make_mannequin(p);
  ASSERT_TRUE(body);
  auto ms = measure_body(*body);
  ASSERT_TRUE(ms);
  int checked = 0;
  for (const auto& c : ms->curves) {
    const double want = requested_girth(p, c.id);
    if (std::isnan(want)) continue;
    EXPECT_NEAR(c.girth / want, 1.0, 0.01) << c.name;
    // A convex cross-section: the tape equals the raw curve length.
    EXPECT_LE(c.girth, c.length * (1 + 1e-9)) << c.name;
    ++checked;
  }
  EXPECT_EQ(checked, 13);
  // Heights follow the body: the waist sits back_length below the nape.
  const double nape = ms->points[body->find_point("neck_base_x_centre_back")->id - 1].height;
  const double waist = ms->points[body->find_point("waist_x_centre_back")->id - 1].height;
  EXPECT_NEAR(nape - waist, p.back_length, 1e-9);
  EXPECT_NEAR(body->model.position(NodeIdx{0}).y(), p.inseam, 1e-9);  // torso ring 0 is the crotch
}

TEST(Mannequin, SampledGirthsMatchRequestAndFramesEncode) {
  const auto params = sample_mannequins(50, 7);
  const MannequinTopology& t = topology(6);
  for (std::size_t i = 0; i < params.size(); ++i) {
    auto body = make_mannequin(params[i], t);
    ASSERT_TRUE(body) << i << ": " << body.status().to_string();
    auto ms = measure_body(*body);
    ASSERT_TRUE(ms);
    for (const auto& c : ms->curves) {
      const double want = requested_girth(params[i], c.id);
      if (!std::isnan(want)) {
        EXPECT_NEAR(c.girth / want, 1.0, 0.01) << "body " << i << " " << c.name;
      }
    }
    EXPECT_GT(body->points.size(), 20u);
    for (const auto& fp : body->points) {
      auto f = feature_frame(*body, fp.id);
      ASSERT_TRUE(f) << f.status().to_string();
      EXPECT_NEAR(f->n.norm(), 1.0, 1e-9);
      EXPECT_GT(std::abs(f->triple()), 0.3) << "body " << i << " point " << fp.name;
      // The normal points away from the body's vertical axis (outward skin).
      EXPECT_GT(f->n.dot(Vec3d(f->origin.x(), 0, f->origin.z())), -0.2) << fp.name;
    }
  }
}

TEST(Mannequin, SameTopologyForEveryParameterSet) {
  const auto params = sample_mannequins(5, 99);
  auto a = make_mannequin(params[0], topology(2));
  ASSERT_TRUE(a);
  for (std::size_t i = 1; i < params.size(); ++i) {
    auto b = make_mannequin(params[i], topology(2));
    ASSERT_TRUE(b);
    ASSERT_EQ(a->model.num_faces(), b->model.num_faces());
    std::vector<NodeIdx> fa, fb;
    for (std::uint32_t f = 0; f < a->model.faces.slots.capacity(); ++f) {
      a->model.face_nodes(FaceIdx{f}, fa);
      b->model.face_nodes(FaceIdx{f}, fb);
      ASSERT_EQ(fa, fb) << "face " << f;
    }
    // With the positions swapped in, every table is bit-identical.
    ASSERT_TRUE(set_positions(*b, a->model.nodes.position));
    EXPECT_EQ(diff_tables(a->model, b->model), "");
  }
}

TEST(Mannequin, NoSelfIntersectionAtDefaultResolution) {
  const MannequinTopology& t = topology(6);
  std::vector<MannequinParams> params = {MannequinParams{}};
  for (const auto& p : sample_mannequins(8, 2024)) params.push_back(p);
  for (std::size_t i = 0; i < params.size(); ++i) {
    auto pos = mannequin_positions(params[i], t);
    ASSERT_TRUE(pos);
    std::string where;
    EXPECT_EQ(count_self_intersections(*pos, t.face_offsets, t.face_nodes, 1, &where), 0u) << "body " << i << ": " << where;
  }
}

TEST(Mannequin, AThousandSampledBodiesAreEmbeddedFittedAndEncodable) {
  const MannequinTopology& t = topology(2);
  const auto params = sample_mannequins(1000, 1);
  // One model carries the features; each body is evaluated from its positions.
  auto features = make_mannequin(MannequinParams{}, t);
  ASSERT_TRUE(features);
  std::size_t bad = 0;
  for (std::size_t i = 0; i < params.size(); ++i) {
    auto pos = mannequin_positions(params[i], t);
    ASSERT_TRUE(pos) << pos.status().to_string();
    auto ms = measure_body(*features, *pos);
    ASSERT_TRUE(ms);
    for (const auto& c : ms->curves) {
      const double want = requested_girth(params[i], c.id);
      if (!std::isnan(want)) {
        ASSERT_NEAR(c.girth / want, 1.0, 0.01) << "body " << i << " " << c.name;
      }
    }
    for (const auto& fp : features->points) {
      auto f = feature_frame(*features, fp.id, *pos);
      ASSERT_TRUE(f);
      ASSERT_GT(std::abs(f->triple()), 0.3) << "body " << i << " point " << fp.name;
    }
    // Non-degenerate faces as well.
    for (std::size_t f = 0; f + 1 < t.face_offsets.size(); ++f) {
      const auto* v = &t.face_nodes[t.face_offsets[f]];
      const double area = ((*pos)[v[1]] - (*pos)[v[0]]).cross((*pos)[v[2]] - (*pos)[v[0]]).norm();
      ASSERT_GT(area, 1e-8) << "body " << i << " face " << f;
    }
    std::string where;
    if (count_self_intersections(*pos, t.face_offsets, t.face_nodes, 1, &where) != 0) {
      ++bad;
      ADD_FAILURE() << "body " << i << " self-intersects: " << where;
    }
  }
  EXPECT_EQ(bad, 0u);
}

TEST(Mannequin, NoSelfIntersectionForAThousandBodiesAtDefaultResolution) {
  // About 1.5 CPU-minutes, spread over the cores. Sanitizer builds (10x
  // slower) skip it with ATELIER_SKIP_LONG_TESTS=1; `make test` runs it.
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) GTEST_SKIP() << "ATELIER_SKIP_LONG_TESTS is set";
  const MannequinTopology& t = topology(6);
  const auto params = sample_mannequins(1000, 1);
  std::vector<std::string> where(params.size());
  std::vector<std::size_t> hits(params.size(), 0);
  ExecContext ctx;
  ctx.sequential_threshold = 2;
  ctx.grain = 1;
  par::for_each_n(ctx, params.size(), [&](std::size_t i) {
    auto pos = mannequin_positions(params[i], t);
    if (!pos) {
      where[i] = pos.status().to_string();
      hits[i] = 1;
      return;
    }
    hits[i] = count_self_intersections(*pos, t.face_offsets, t.face_nodes, 1, &where[i]);
  });
  std::size_t bad = 0;
  for (std::size_t i = 0; i < params.size(); ++i)
    if (hits[i]) {
      ++bad;
      ADD_FAILURE() << "body " << i << " self-intersects: " << where[i];
    }
  EXPECT_EQ(bad, 0u);
}

TEST(Mannequin, ExtremeSampledMeasurementsStayEmbedded) {
  // Each measurement pushed to the smallest and largest value of 20,000
  // draws, the others kept at a typical body's: still valid and embedded.
  const auto draws = sample_mannequins(20'000, 3);
  const MannequinTopology& t = topology(6);
  double MannequinParams::*fields[] = {&MannequinParams::neck_girth,     &MannequinParams::bust_girth,
                                       &MannequinParams::underbust_girth, &MannequinParams::waist_girth,
                                       &MannequinParams::hip_girth,       &MannequinParams::thigh_girth,
                                       &MannequinParams::knee_girth,      &MannequinParams::ankle_girth,
                                       &MannequinParams::upper_arm_girth, &MannequinParams::shoulder_width,
                                       &MannequinParams::back_length};
  int tried = 0;
  for (auto f : fields) {
    const auto [lo, hi] = std::minmax_element(draws.begin(), draws.end(), [f](const auto& a, const auto& b) { return a.*f < b.*f; });
    for (const MannequinParams* src : {&*lo, &*hi}) {
      MannequinParams p = *src;  // the extreme body itself (consistent by construction)
      auto pos = mannequin_positions(p, t);
      ASSERT_TRUE(pos) << pos.status().to_string();
      std::string where;
      EXPECT_EQ(count_self_intersections(*pos, t.face_offsets, t.face_nodes, 1, &where), 0u) << where;
      ++tried;
    }
  }
  EXPECT_EQ(tried, 22);
}

TEST(Mannequin, CheckerSeesLegsPushedIntoEachOther) {
  // The check above can fail: shifting the left leg onto the right one is caught.
  const MannequinTopology& t = topology(2);
  auto pos = mannequin_positions(MannequinParams{}, t);
  ASSERT_TRUE(pos);
  for (std::uint32_t v = t.left_leg_base; v < t.right_leg_base; ++v)
    if ((*pos)[v].y() < 0.6) (*pos)[v].x() -= 0.12;
  EXPECT_GT(count_self_intersections(*pos, t.face_offsets, t.face_nodes), 0u);
}

TEST(Mannequin, FeaturesMoveWithTheMesh) {
  auto body = make_mannequin(MannequinParams{}, MannequinResolution::from_level(3));
  ASSERT_TRUE(body);
  std::vector<Vec3d> scaled = body->model.nodes.position;
  for (auto& p : scaled) p *= 1.1;
  auto big = with_positions(*body, scaled);
  ASSERT_TRUE(big);
  ASSERT_TRUE(validate(big->model));
  for (const auto& fp : body->points) {
    const Vec3d a = attrib_position(body->model, fp.node, body->model.nodes.position);
    const Vec3d b = big->model.attrib_nodes.position[fp.node.value];
    EXPECT_LT((b - 1.1 * a).norm(), 1e-12) << fp.name;
    auto fa = feature_frame(*body, fp.id), fb = feature_frame(*big, fp.id);
    ASSERT_TRUE(fa && fb);
    EXPECT_LT((fb->origin - 1.1 * fa->origin).norm(), 1e-12);
    EXPECT_LT((fb->t1 - fa->t1).norm(), 1e-9);  // directions are scale-invariant
    EXPECT_LT((fb->n - fa->n).norm(), 1e-9);
  }
  auto ma = measure_body(*body), mb = measure_body(*big);
  ASSERT_TRUE(ma && mb);
  for (std::size_t c = 0; c < ma->curves.size(); ++c)
    EXPECT_NEAR(mb->curves[c].length, 1.1 * ma->curves[c].length, 1e-9);
}

TEST(Mannequin, SamplerIsDeterministicAndPlausible) {
  const auto a = sample_mannequins(1000, 42), b = sample_mannequins(1000, 42), c = sample_mannequins(1000, 43);
  EXPECT_EQ(a, b);
  std::size_t same = 0;
  for (std::size_t i = 0; i < a.size(); ++i) same += a[i] == c[i];
  EXPECT_EQ(same, 0u);
  // Every draw is a valid body; measures correlate as they do in people.
  double sh = 0, si = 0, shh = 0, sii = 0, shi = 0, sw = 0, sp = 0, sww = 0, spp = 0, swp = 0;
  for (const auto& p : a) {
    ASSERT_TRUE(validate_params(p)) << validate_params(p).to_string();
    sh += p.height, si += p.inseam, shh += p.height * p.height, sii += p.inseam * p.inseam, shi += p.height * p.inseam;
    sw += p.waist_girth, sp += p.hip_girth, sww += p.waist_girth * p.waist_girth, spp += p.hip_girth * p.hip_girth,
        swp += p.waist_girth * p.hip_girth;
  }
  const double n = double(a.size());
  auto corr = [n](double sx, double sy, double sxx, double syy, double sxy) {
    return (sxy - sx * sy / n) / std::sqrt((sxx - sx * sx / n) * (syy - sy * sy / n));
  };
  EXPECT_GT(corr(sh, si, shh, sii, shi), 0.6);
  EXPECT_GT(corr(sw, sp, sww, spp, swp), 0.4);
  EXPECT_GT(sh / n, 1.62);
  EXPECT_LT(sh / n, 1.78);
  // First draw of a fixed seed (guards the portability of the stream).
  const auto one = sample_mannequins(1, 42);
  EXPECT_EQ(one[0], a[0]);
}

TEST(Mannequin, SampledSourceDrawsEachBodyOnItsOwn) {
  // Body i of a sampled source is sample_mannequins(n, seed)[i] whatever n,
  // drawn when its chunk is generated: the same bodies as a source holding
  // every parameter set, with no per-body state.
  const auto all = sample_mannequins(40, 9);
  for (const std::size_t i : {0u, 1u, 17u, 39u}) EXPECT_EQ(sample_mannequin(9, i), all[i]) << i;
  EXPECT_EQ(sample_mannequins(18, 9)[17], all[17]);
  auto topo = make_mannequin_topology();
  ASSERT_TRUE(topo);
  auto t = std::make_shared<const MannequinTopology>(std::move(*topo));
  auto ref = make_mannequin(MannequinParams{}, *t);
  ASSERT_TRUE(ref);
  auto r = std::make_shared<const ReferenceBody>(std::move(*ref));
  const MannequinSource held(t, all, r), sampled(t, 40, 9, r);
  ASSERT_EQ(sampled.size(), 40u);
  BodySet a(r), b(r);
  std::vector<BodyFailure> fa, fb;
  held.generate(21, 4, a, fa, {});
  sampled.generate(21, 4, b, fb, {});
  ASSERT_EQ(a.size(), 4u);
  ASSERT_EQ(b.size(), 4u);
  EXPECT_TRUE(fa.empty() && fb.empty());
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(a.name(k), b.name(k));
    EXPECT_EQ(a.positions(k), b.positions(k)) << k;
  }
  sampled.generate(38, 10, b, fb, {});  // clipped at the end
  EXPECT_EQ(b.size(), 2u);
}

TEST(Mannequin, RejectsBadParameters) {
  MannequinParams p;
  p.underbust_girth = 1.0;
  auto b = make_mannequin(p);
  ASSERT_FALSE(b);
  EXPECT_NE(b.status().message().find("underbust"), std::string::npos);
  p = {};
  p.height = 3.0;
  EXPECT_NE(validate_params(p).message().find("height"), std::string::npos);
  EXPECT_FALSE(make_mannequin_topology({20, 2}));
}

TEST(Mannequin, ParallelGenerationMatchesSequential) {
  const auto params = sample_mannequins(6, 5);
  const MannequinTopology& t = topology(2);
  ExecContext two;
  two.threads = 2;
  auto a = make_mannequins(params, t, ExecContext::sequential());
  auto b = make_mannequins(params, t, two);
  ASSERT_TRUE(a && b);
  for (std::size_t i = 0; i < params.size(); ++i) EXPECT_EQ(diff_tables((*a)[i].model, (*b)[i].model), "");
}

TEST(Mannequin, MeasurementsCsv) {
  const auto params = sample_mannequins(3, 11);
  auto bodies = make_mannequins(params, topology(2));
  ASSERT_TRUE(bodies);
  std::ostringstream csv;
  ASSERT_TRUE(measurements_csv(csv, *bodies));
  std::istringstream in(csv.str());
  std::string line;
  std::vector<std::string> lines;
  while (std::getline(in, line)) lines.push_back(line);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0].rfind("body,stature,neck_base_girth,", 0), 0u);
  const auto cols = std::count(lines[0].begin(), lines[0].end(), ',');
  for (std::size_t i = 1; i < lines.size(); ++i) EXPECT_EQ(std::count(lines[i].begin(), lines[i].end(), ','), cols);
  // The waist column holds the requested waist (to the CSV's 6 decimals, within 1%).
  std::vector<std::string> head;
  std::stringstream hs(lines[0]);
  while (std::getline(hs, line, ',')) head.push_back(line);
  const auto wcol = std::find(head.begin(), head.end(), "waist_girth") - head.begin();
  for (std::size_t i = 1; i < lines.size(); ++i) {
    std::stringstream rs(lines[i]);
    std::vector<std::string> cells;
    while (std::getline(rs, line, ',')) cells.push_back(line);
    EXPECT_NEAR(std::stod(cells[wcol]) / params[i - 1].waist_girth, 1.0, 0.01);
  }
}

}  // namespace
}  // namespace atelier

// Issue 26: every body source uses one floor, y = 0, Y up
// (docs/body-files.md). The mannequin is footless and headless: y = 0 is
// the floor its person stands on, and its lowest point is the cap under the
// ankles, 0.03 of the person's stature above it (ankle 0.055 H, cap 0.025 H
// below it); MakeHuman bodies, which have feet, touch y = 0
// (MakeHumanStature tests).
namespace atelier {
TEST(Mannequin, SampledBodiesStandOnTheFloorYZero) {
  auto topo = make_mannequin_topology();
  ASSERT_TRUE(topo);
  auto t = std::make_shared<const MannequinTopology>(std::move(*topo));
  auto ref = make_mannequin(MannequinParams{}, *t);
  ASSERT_TRUE(ref);
  auto r = std::make_shared<const ReferenceBody>(std::move(*ref));
  const MannequinSource src(t, 12, 26, r);
  BodySet set(r);
  std::vector<BodyFailure> fails;
  src.generate(0, 12, set, fails, {});
  ASSERT_TRUE(fails.empty());
  for (std::size_t b = 0; b < set.size(); ++b) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3d& q : set.positions(b)) lo = std::min(lo, q.y()), hi = std::max(hi, q.y());
    const double stature = src.params(b).height;
    EXPECT_NEAR(lo, 0.03 * stature, 1e-8) << b;  // a BodySet keeps float positions (ulp 4e-9 m here)
    EXPECT_LT(hi, stature) << b;  // headless: below the crown, Y up
    EXPECT_GT(hi, 0.8 * stature) << b;
  }
}
}  // namespace atelier
