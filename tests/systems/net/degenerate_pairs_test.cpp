// Net Booleans on degenerate but valid pairs, as CAD users make them
// (issue 24, round 17): a shape and its copy shifted by axis steps of
// 1/2^k, turned by quarter turns or by the shape's own symmetry, scaled by
// 2^k, snapped to a grid, touching at a face, an edge or a vertex, inside
// it sharing a face; and chains (A op B) op C on the results, by soups and
// by prepared results. Oracle: CGAL's exact corefinement volume (where
// CGAL declines, V(A u B) + V(A n B) = V(A) + V(B) and the differences
// V(A) - V(A n B) still hold); every result closed, manifold and oriented
// (closed_model) and, by CGAL's exact test, not self-intersecting (results
// with coincident copies of a pinched vertex excepted: CGAL counts those as
// crossings). Exact mode must answer every valid pair; paper mode may
// refuse, but never with an internal error.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/intersections.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/net/boolean.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <map>
#include <numeric>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "../../../systems/net/boolean_detail.h"  // result_check_counts: which results the certificate passed
#include "net_shapes.h"

namespace atelier::degenerate_pairs {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using Kex = CGAL::Exact_predicates_exact_constructions_kernel;
using Kin = CGAL::Exact_predicates_inexact_constructions_kernel;

/// One thread, and two with the sequential threshold lowered so that two
/// threads do run: the pair the same-bits tests compare.
std::pair<ExecContext, ExecContext> one_and_two_threads() {
  ExecContext one, two;
  one.threads = 1;
  two.threads = 2;
  one.sequential_threshold = two.sequential_threshold = 2;
  return {one, two};
}

/// Whether the Booleans split polygon c as the fan from its first corner:
/// exactly planar and strictly convex (docs/glossary.md, "fan split of
/// planar n-gons"). Decided here with CGAL's exact coplanar and
/// coplanar_orientation, apart from the library's own test.
bool split_as_fan(const PolygonSoup& s, std::span<const std::uint32_t> c) {
  std::vector<Kin::Point_3> p;
  for (std::uint32_t v : c) p.emplace_back(s.positions[v].x(), s.positions[v].y(), s.positions[v].z());
  const std::size_t n = p.size();
  if (CGAL::collinear(p[0], p[1], p[2])) return false;
  for (std::size_t i = 3; i < n; ++i)
    if (!CGAL::coplanar(p[0], p[1], p[2], p[i])) return false;
  const auto turn = CGAL::coplanar_orientation(p[0], p[1], p[2]);
  for (std::size_t i = 0; i < n; ++i)
    if (CGAL::coplanar_orientation(p[i], p[(i + 1) % n], p[(i + 2) % n]) != turn) return false;
  for (std::size_t i = 2; i + 1 < n; ++i)
    if (CGAL::coplanar_orientation(p[0], p[i], p[i + 1]) != turn) return false;
  return true;
}

template <class K>
CGAL::Surface_mesh<typename K::Point_3> mesh_of(const PolygonSoup& s) {
  std::vector<typename K::Point_3> pts;
  for (const Vec3d& p : s.positions) pts.emplace_back(p.x(), p.y(), p.z());
  // n-gons split as the Booleans split them (CGAL's own triangulation
  // would pick diagonals of slightly warped quads): planar convex ones as a
  // fan, the others around their centroid.
  std::vector<std::vector<std::size_t>> polys;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const auto c = s.face(f);
    if (c.size() == 3) {
      polys.emplace_back(c.begin(), c.end());
      continue;
    }
    if (split_as_fan(s, c)) {
      for (std::size_t i = 1; i + 1 < c.size(); ++i) polys.push_back({c[0], c[i], c[i + 1]});
      continue;
    }
    Vec3d m = Vec3d::Zero();
    for (std::uint32_t v : c) m += s.positions[v];
    m /= static_cast<double>(c.size());
    pts.emplace_back(m.x(), m.y(), m.z());
    for (std::size_t i = 0; i < c.size(); ++i) polys.push_back({pts.size() - 1, c[i], c[(i + 1) % c.size()]});
  }
  CGAL::Surface_mesh<typename K::Point_3> m;
  PMP::polygon_soup_to_polygon_mesh(pts, polys, m);
  return m;
}

/// A cavity of `s` (a vertex-connected shell of negative volume) whose
/// vertices are all vertices of `t`: it lies on t's surface.
bool has_cavity_on(const PolygonSoup& s, const PolygonSoup& t) {
  std::set<std::array<double, 3>> on;
  for (const Vec3d& p : t.positions) on.insert({p.x(), p.y(), p.z()});
  std::vector<std::uint32_t> up(s.positions.size());
  std::iota(up.begin(), up.end(), 0u);
  auto find = [&](std::uint32_t v) {
    while (up[v] != v) v = up[v] = up[up[v]];
    return v;
  };
  for (std::size_t f = 0; f < s.face_count(); ++f)
    for (std::uint32_t v : s.face(f)) up[find(v)] = find(s.face(f)[0]);
  std::map<std::uint32_t, std::pair<bool, double>> shell;  // root: (all on t, signed volume)
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const auto c = s.face(f);
    auto& [all_on, volume] = shell.emplace(find(c[0]), std::pair{true, 0.0}).first->second;
    for (std::uint32_t v : c) all_on = all_on && on.count({s.positions[v].x(), s.positions[v].y(), s.positions[v].z()});
    for (std::size_t i = 1; i + 1 < c.size(); ++i)
      volume += s.positions[c[0]].dot(s.positions[c[i]].cross(s.positions[c[i + 1]])) / 6.0;
  }
  for (const auto& [root, x] : shell)
    if (x.first && x.second < 0) return true;
  return false;
}

/// CGAL's exact corefinement volume of a op b, or nothing where CGAL
/// declines (a non-manifold output, for one) or cannot be trusted: a cavity
/// of one net lying on the other's surface (seed 2 case 129: X = icosphere
/// minus its half, against the half, C). The cavity meets no intersection
/// curve and every point of it is on C: CGAL answers (X u C, X n C, X - C) =
/// (V(X), -V(C), V(X) + V(C)), its own chain included, against (V(A), 0,
/// V(X)) by hand (the cavity filled, nothing, X); with C scaled by 1/2 +-
/// 2^-10, 3/8 or 5/8 CGAL agrees with ours. The chain's volume identities
/// check ours there.
std::optional<double> corefined_volume(const PolygonSoup& a, const PolygonSoup& b, BooleanOp op) {
  if (has_cavity_on(a, b) || has_cavity_on(b, a)) return std::nullopt;
  auto ma = mesh_of<Kex>(a), mb = mesh_of<Kex>(b);
  CGAL::Surface_mesh<Kex::Point_3> out;
  bool ok = false;
  try {
    switch (op) {
      case BooleanOp::kUnion:
        ok = PMP::corefine_and_compute_union(ma, mb, out);
        break;
      case BooleanOp::kIntersection:
        ok = PMP::corefine_and_compute_intersection(ma, mb, out);
        break;
      case BooleanOp::kAMinusB:
        ok = PMP::corefine_and_compute_difference(ma, mb, out);
        break;
      case BooleanOp::kBMinusA:
        ok = PMP::corefine_and_compute_difference(mb, ma, out);
        break;
    }
  } catch (const std::exception&) {
    ok = false;
  }
  if (!ok) return std::nullopt;
  return CGAL::to_double(PMP::volume(out));
}

bool has_coincident_vertices(const PolygonSoup& s) {
  std::set<std::array<double, 3>> seen;
  for (const Vec3d& p : s.positions)
    if (!seen.insert({p.x(), p.y(), p.z()}).second) return true;
  return false;
}

/// A result with coincident copies of a pinched vertex (or edge), which
/// does_self_intersect counts as crossing where the copies' faces touch:
/// CGAL's exact self_intersections, each pair's exact intersection
/// ignored when it is a point, or a segment, whose ends are all corners of
/// both faces by position (a pinch: the faces touch at a vertex or along an
/// edge, as the exact result does); any other intersecting pair is a
/// crossing (snap17: repaired results are often pinched, so the campaign
/// checks them too). cross18: the ends were required to be coincident
/// copies; a segment from a corner both faces share by id to coincident
/// copies (two faces on one edge by position, seed 2 case 60) was counted
/// as a crossing, which it is not. Same rule as the Booleans' own
/// pinched_self_crossing (triangles_cross with copies merged).
bool pinched_result_crosses(const PolygonSoup& s) {
  const auto m = mesh_of<Kex>(s);
  using Face = CGAL::Surface_mesh<Kex::Point_3>::Face_index;
  std::vector<std::pair<Face, Face>> pairs;
  PMP::self_intersections(faces(m), m, std::back_inserter(pairs));
  auto tri = [&](Face f) {
    std::vector<Kex::Point_3> c;
    for (auto v : vertices_around_face(halfedge(f, m), m)) c.push_back(m.point(v));
    return Kex::Triangle_3(c[0], c[1], c[2]);
  };
  for (const auto& [f, g] : pairs) {
    const Kex::Triangle_3 tf = tri(f), tg = tri(g);
    const auto hit = CGAL::intersection(tf, tg);
    if (!hit) continue;
    auto corner_of_both = [&](const Kex::Point_3& q) {
      bool in_f = false, in_g = false;
      for (int k = 0; k < 3; ++k) {
        in_f = in_f || tf.vertex(k) == q;
        in_g = in_g || tg.vertex(k) == q;
      }
      return in_f && in_g;
    };
    if (const auto* q = boost::get<Kex::Point_3>(&*hit); q && corner_of_both(*q)) continue;
    if (const auto* e = boost::get<Kex::Segment_3>(&*hit);
        e && corner_of_both(e->source()) && corner_of_both(e->target()))
      continue;
    return true;
  }
  return false;
}

constexpr BooleanOp kOps[] = {BooleanOp::kUnion, BooleanOp::kIntersection, BooleanOp::kAMinusB, BooleanOp::kBMinusA};

struct Tally {
  std::map<std::string, int> cases;  // per family
  int booleans = 0, cgal_declined = 0, pinched = 0, invalid_inputs = 0, chains = 0, paper_ok = 0, paper_refused = 0;
  int fold_refused = 0;      // refused as folded once rounded (the guarantee's error, issue 24 fold15)
  int ok = 0, crossing = 0;  // answered; answered but crossing itself by CGAL's exact test
  // BooleanOptions::check_result of the campaign's Booleans: the default
  // (on since fold16), or ATELIER_CAMPAIGN_CHECK_RESULT=0 / 1.
  bool check_result = std::getenv("ATELIER_CAMPAIGN_CHECK_RESULT")
                          ? std::atoi(std::getenv("ATELIER_CAMPAIGN_CHECK_RESULT")) != 0
                          : BooleanOptions{}.check_result;
  std::vector<std::string> failures, folds;
  // degen19: check_pair runs the union's chain only (CI's sanitizer stage),
  // unless a test needs the difference's chain too.
  bool short_chains = std::getenv("ATELIER_SKIP_LONG_TESTS") != nullptr;
  void fail(const std::string& s) {
    if (failures.size() < 200) failures.push_back(s);
  }
};

PolygonSoup mapped(PolygonSoup s, const auto& f) {
  for (Vec3d& p : s.positions) p = f(p);
  return s;
}

/// One Boolean, checked: answered, closed, not self-intersecting, CGAL's
/// volume. Returns the result (nothing if refused).
std::optional<BooleanReport> checked(const PolygonSoup& a, const PolygonSoup& b, BooleanOp op, const std::string& what,
                                     Tally& t, bool prepare_result = false) {
  BooleanOptions o;
  o.op = op;
  o.prepare_result = prepare_result;
  o.check_result = t.check_result;  // the guarantee under test: never ok with a fold
  o.exact_refinement = std::getenv("ATELIER_CAMPAIGN_EXACT_REFINEMENT") != nullptr;  // the reference path
  ++t.booleans;
  auto r = net_boolean(a, b, o);
  if (!r) {
    // A result that crosses itself once rounded is refused with the faces
    // named (never returned as ok): counted and listed, not a failure.
    if (r.status().code() == ErrorCode::kTopology &&
        r.status().message().find("crosses itself once its new points are rounded") != std::string::npos) {
      ++t.fold_refused;
      if (t.folds.size() < 200) t.folds.push_back(what + ": " + r.status().message());
    } else {
      t.fail(what + ": refused: " + r.status().to_string());
    }
    return std::nullopt;
  }
  ++t.ok;
  const double scale = std::abs(soup_volume(a)) + std::abs(soup_volume(b));
  if (r->result.face_count() > 0) {
    if (auto c = net_test::closed_model(r->result); !c) t.fail(what + ": not a closed model: " + c.message());
    if (has_coincident_vertices(r->result)) {
      ++t.pinched;
      if (pinched_result_crosses(r->result)) {
        ++t.crossing;
        t.fail(what + ": the (pinched) result intersects itself");
      }
    } else if (PMP::does_self_intersect(mesh_of<Kin>(r->result))) {
      ++t.crossing;
      t.fail(what + ": the result intersects itself");
    }
  }
  if (std::abs(r->volume - soup_volume(r->result)) > 1e-12 * scale) t.fail(what + ": reported volume differs");
  if (auto want = corefined_volume(a, b, op)) {
    if (!(std::abs(r->volume - *want) <= 1e-9 * scale))
      t.fail(what + ": volume " + std::to_string(r->volume) + ", CGAL " + std::to_string(*want));
  } else {
    ++t.cgal_declined;
  }
  return std::move(*r);
}

/// All four operations of a and b (exact mode), the volumes adding up,
/// paper mode's union and difference, and chains against c.
void check_pair(const PolygonSoup& a, const PolygonSoup& b, const PolygonSoup& c, const std::string& family,
                const std::string& what, Tally& t) {
  for (const PolygonSoup* s : {&a, &b, &c})
    if (auto p = PreparedNet::prepare(*s); !p) {
      // Only a net CGAL also finds self-intersecting may be refused here
      // (snapping can fold a net); anything else is a wrong refusal.
      if (!PMP::does_self_intersect(mesh_of<Kex>(*s)) && p.status().message().find("degenerate") == std::string::npos &&
          p.status().message().find("duplicate") == std::string::npos)
        t.fail(what + ": a valid input refused: " + p.status().to_string());
      ++t.invalid_inputs;
      return;
    }
  ++t.cases[family];
  double v[4] = {};
  bool all = true;
  for (BooleanOp op : kOps) {
    auto r = checked(a, b, op, what + " op " + std::to_string(static_cast<int>(op)), t);
    if (r)
      v[static_cast<int>(op)] = r->volume;
    else
      all = false;
  }
  const double va = soup_volume(a), vb = soup_volume(b), scale = std::abs(va) + std::abs(vb);
  if (all && (std::abs(v[0] + v[1] - va - vb) > 1e-12 * scale || std::abs(v[2] - (va - v[1])) > 1e-12 * scale ||
              std::abs(v[3] - (vb - v[1])) > 1e-12 * scale))
    t.fail(what + ": volumes do not add up");
  for (BooleanOp op : {BooleanOp::kUnion, BooleanOp::kAMinusB}) {
    BooleanOptions o;
    o.op = op;
    o.mode = BooleanMode::kPaper;
    auto r = net_boolean(a, b, o);
    if (r)
      ++t.paper_ok;
    else if (r.status().code() == ErrorCode::kInternal)
      t.fail(what + " paper op " + std::to_string(static_cast<int>(op)) + ": " + r.status().to_string());
    else
      ++t.paper_refused;
  }
  // Chains: (A op B) op2 C by soups, and by the prepared result against a
  // prepared C (the same volume). Under ATELIER_SKIP_LONG_TESTS (CI's
  // sanitizer stage) the union's chain only (degen19: half of a case's
  // degenerate Booleans are chains; the difference's chains still run in
  // every Release `make test` and in the broad campaign).
  for (BooleanOp op : {BooleanOp::kUnion, BooleanOp::kAMinusB}) {
    if (t.short_chains && op != BooleanOp::kUnion) continue;
    const std::string w1 = what + " chain op " + std::to_string(static_cast<int>(op));
    auto r = checked(a, b, op, w1, t, true);
    if (!r || r->result.face_count() == 0 || r->prepared.empty()) continue;
    auto pc = PreparedNet::prepare(c, PrepareOptions{"B", true});
    if (!pc) continue;
    std::optional<double> chain_volume[3];  // op2: union, intersection, difference
    for (BooleanOp op2 : {BooleanOp::kUnion, BooleanOp::kIntersection, BooleanOp::kAMinusB}) {
      ++t.chains;
      const std::string w2 = w1 + " then op " + std::to_string(static_cast<int>(op2));
      auto s = checked(r->result, c, op2, w2, t);
      if (s) chain_volume[static_cast<int>(op2)] = s->volume;
      BooleanOptions o;
      o.op = op2;
      o.check_self_intersection = true;
      o.check_result = t.check_result;
      auto p = net_boolean(r->prepared, *pc, o);
      if (!p && p.status().code() == ErrorCode::kTopology &&
          p.status().message().find("crosses itself once its new points are rounded") != std::string::npos)
        ++t.fold_refused;
      else if (!p)
        t.fail(w2 + " (prepared): refused: " + p.status().to_string());
      else if (s && p->volume != s->volume)
        t.fail(w2 + " (prepared): volume " + std::to_string(p->volume) + " against " + std::to_string(s->volume));
    }
    // The volume identities of the chain (where CGAL declines, the only check).
    const double vx = r->volume, vc = soup_volume(c), scale = std::abs(vx) + std::abs(vc);
    if (chain_volume[0] && chain_volume[1] && chain_volume[2] &&
        (std::abs(*chain_volume[0] + *chain_volume[1] - vx - vc) > 1e-12 * scale ||
         std::abs(*chain_volume[2] - (vx - *chain_volume[1])) > 1e-12 * scale))
      t.fail(w1 + ": the chain's volumes do not add up");
  }
}

// ---- the families -------------------------------------------------------

/// A base shape: icospheres (levels 1-3), boxes (quads or triangles),
/// prisms over n-gons, UV spheres (quads and fans). Sizes are powers of two
/// or simple, centres on a coarse grid.
PolygonSoup base_shape(std::mt19937& rng, std::string& name, int& symmetry) {
  std::uniform_int_distribution<int> kind(0, 4), level(1, 3), ngon(0, 5);
  const int sides[] = {3, 4, 5, 6, 8, 12};
  switch (kind(rng)) {
    case 0:
    case 1: {
      const int l = level(rng);
      name = "icosphere" + std::to_string(l);
      symmetry = 5;
      return net_test::icosphere(l, 1.0, {0, 0, 0});
    }
    case 2:
      name = "box";
      symmetry = 4;
      return rng() % 2 ? net_test::box({0, 0, 0}, {1, 1, 1}) : net_test::box_triangles({0, 0, 0}, {1, 1, 1});
    case 3: {
      const int n = sides[ngon(rng)];
      name = "prism" + std::to_string(n);
      symmetry = n;
      return net_test::prism(n, 1.0, {0, 0, 0}, -0.5, 0.5);
    }
    default: {
      const int n = 4 * (2 + static_cast<int>(rng() % 3));
      name = "uvsphere" + std::to_string(n);
      symmetry = n;
      return net_test::from_shapes(shapes::uv_sphere(n, n / 2, 1.0));
    }
  }
}

Vec3d axis_step(std::mt19937& rng, int max_k) {
  Vec3d d = Vec3d::Zero();
  const int axes = 1 + static_cast<int>(rng() % 2);
  for (int i = 0; i < axes; ++i) {
    const int k = static_cast<int>(rng() % (max_k + 1));
    const int j = 1 + static_cast<int>(rng() % 3);
    d[rng() % 3] = (rng() % 2 ? 1 : -1) * std::ldexp(double(j), -k);
  }
  return d;
}

/// A quarter turn about an axis, exact: coordinates permuted and negated.
Vec3d quarter_turn(const Vec3d& p, int axis, int turns) {
  Vec3d q = p;
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  for (int k = 0; k < turns % 4; ++k) {
    const double a = q[i], b = q[j];
    q[i] = -b;
    q[j] = a;
  }
  return q;
}

struct Bounds {
  Vec3d lo, hi;
};
Bounds bounds(const PolygonSoup& s) {
  Bounds b{Vec3d::Constant(HUGE_VAL), Vec3d::Constant(-HUGE_VAL)};
  for (const Vec3d& p : s.positions) {
    b.lo = b.lo.cwiseMin(p);
    b.hi = b.hi.cwiseMax(p);
  }
  return b;
}

const char* const kFamilies[] = {"shift", "quarter-turn", "symmetry-turn", "scale", "snap", "touch", "inside"};

/// The copy B of A for family f (and the third net C of the chains: the
/// same family drawn again).
PolygonSoup transformed(const PolygonSoup& a, int symmetry, int f, std::mt19937& rng) {
  switch (f) {
    case 0: {
      const Vec3d d = axis_step(rng, 4);
      return mapped(a, [&](const Vec3d& p) { return Vec3d(p + d); });
    }
    case 1: {
      const int axis = static_cast<int>(rng() % 3), turns = 1 + static_cast<int>(rng() % 3);
      const Vec3d d = rng() % 3 ? axis_step(rng, 3) : Vec3d::Zero();
      return mapped(a, [&](const Vec3d& p) { return Vec3d(quarter_turn(p, axis, turns) + d); });
    }
    case 2: {
      // The shape's own symmetry (an n-gon's turn about z; the
      // icosahedron's fifth turn about a vertex axis; a box's quarter turn
      // about its centre's axis), inexact: near-copies.
      Vec3d axis = Vec3d::UnitZ(), centre = bounds(a).lo / 2 + bounds(a).hi / 2;
      if (symmetry == 5) axis = Vec3d(0, 1, (1.0 + std::sqrt(5.0)) / 2).normalized();
      const double turn = 2.0 * M_PI * (1 + rng() % 2) / symmetry;
      const Eigen::AngleAxisd q(turn, axis);
      const Vec3d d = rng() % 2 ? axis_step(rng, 3) : Vec3d::Zero();
      return mapped(a, [&](const Vec3d& p) { return Vec3d(centre + q * (p - centre) + d); });
    }
    case 3: {
      const double s = std::ldexp(1.0, static_cast<int>(rng() % 5) - 2);
      const Vec3d d = rng() % 2 ? axis_step(rng, 2) : Vec3d::Zero();
      return mapped(a, [&](const Vec3d& p) { return Vec3d(s * p + d); });
    }
    case 4: {
      const double h = std::ldexp(1.0, -2 - static_cast<int>(rng() % 3));
      const Vec3d d = axis_step(rng, 3);
      return mapped(a, [&](const Vec3d& p) { return Vec3d(((p + d) / h).array().round().matrix() * h); });
    }
    case 5: {
      // Touching at a face, an edge or a vertex: B's low sides on A's high
      // sides along 1, 2 or 3 axes (exact on symmetric shapes: lo = -hi).
      const Bounds ba = bounds(a);
      const int axes = 1 + static_cast<int>(rng() % 3);
      Vec3d d = Vec3d::Zero();
      const int first = static_cast<int>(rng() % 3);
      for (int k = 0; k < axes; ++k) d[(first + k) % 3] = ba.hi[(first + k) % 3] - ba.lo[(first + k) % 3];
      return mapped(a, [&](const Vec3d& p) { return Vec3d(p + d); });
    }
    default: {
      // Inside A, sharing (part of) A's lowest face: halved towards the
      // point below the centre on A's lowest z.
      const Bounds ba = bounds(a);
      const int axis = static_cast<int>(rng() % 3);
      Vec3d o = ba.lo / 2 + ba.hi / 2;
      o[axis] = ba.lo[axis];
      return mapped(a, [&](const Vec3d& p) {
        Vec3d q = o + (p - o) / 2;
        q[axis] = p[axis] == ba.lo[axis] ? ba.lo[axis] : q[axis];
        return q;
      });
    }
  }
}

void dump_obj(const PolygonSoup& s, const char* file) {
  std::FILE* f = std::fopen(file, "w");
  for (const Vec3d& p : s.positions) std::fprintf(f, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
  for (std::size_t k = 0; k < s.face_count(); ++k) {
    std::fprintf(f, "f");
    for (std::uint32_t v : s.face(k)) std::fprintf(f, " %u", v + 1);
    std::fprintf(f, "\n");
  }
  std::fclose(f);
}

/// Cases 0 .. cases-1 of the campaign drawn from `seed` (family n % 7),
/// or only case `only` of them (the draws before it still made): each as
/// f(a, b, c, family, what).
template <class F>
void for_each_case(std::uint32_t seed, int cases, int only, F&& f) {
  std::mt19937 rng(seed);
  for (int n = 0; n < cases; ++n) {
    std::string name;
    int symmetry = 4;
    PolygonSoup a = base_shape(rng, name, symmetry);
    const int fam = n % 7;
    PolygonSoup b = transformed(a, symmetry, fam, rng);
    PolygonSoup c = transformed(a, symmetry, fam, rng);
    if (fam == 4) a = mapped(a, [&](const Vec3d& p) { return Vec3d((p * 8).array().round().matrix() / 8); });
    const std::string what = std::string(kFamilies[fam]) + " " + name + " case " + std::to_string(n);
    if (only >= 0 && only != n) continue;
    if (const char* dump = std::getenv("ATELIER_CAMPAIGN_DUMP"); dump && std::atoi(dump) == n) {
      dump_obj(a, "/tmp/bool17_a.obj");
      dump_obj(b, "/tmp/bool17_b.obj");
      dump_obj(c, "/tmp/bool17_c.obj");
    }
    f(a, b, c, kFamilies[fam], what);
  }
}

/// The campaign's cases checked by check_pair.
void run_campaign(std::uint32_t seed, int cases, Tally& t, int only = -1) {
  for_each_case(seed, cases, only,
                [&](const PolygonSoup& a, const PolygonSoup& b, const PolygonSoup& c, const char* family,
                    const std::string& what) { check_pair(a, b, c, family, what, t); });
}

void report(const Tally& t) {
  std::cout << "booleans " << t.booleans << ", chains " << t.chains << ", CGAL declined " << t.cgal_declined
            << ", pinched results " << t.pinched << ", invalid inputs " << t.invalid_inputs << ", paper ok "
            << t.paper_ok << ", paper refused " << t.paper_refused << ", refused as folded " << t.fold_refused
            << ", ok " << t.ok << ", ok but crossing (CGAL) " << t.crossing << ", check_result " << t.check_result
            << "\n";
  for (const std::string& s : t.folds) std::cout << "FOLD " << s << "\n";
  for (const auto& [k, v] : t.cases) std::cout << "  " << k << ": " << v << " pairs\n";
  for (const std::string& s : t.failures) std::cout << "FAIL " << s << "\n";
}

TEST(NetDegeneratePairs, DISABLED_BroadCampaign) {
  const char* env = std::getenv("ATELIER_CAMPAIGN_CASES");
  const int cases = env ? std::atoi(env) : 700;
  const char* seed = std::getenv("ATELIER_CAMPAIGN_SEED");
  const char* only = std::getenv("ATELIER_CAMPAIGN_ONLY");
  Tally t;
  run_campaign(seed ? static_cast<std::uint32_t>(std::atoi(seed)) : 1u, cases, t, only ? std::atoi(only) : -1);
  report(t);
  EXPECT_TRUE(t.failures.empty()) << t.failures.size() << " failures";
}

/// The compact campaign: the first nine cases of seed 1 (every family once,
/// shifts and quarter turns twice; case 9, the broad campaign's first
/// failure on main, is its own test below). A few seconds.
TEST(NetDegeneratePairs, CompactCampaignAgreesWithCgal) {
  Tally t;
  run_campaign(1u, 9, t);
  if (!t.failures.empty()) report(t);
  EXPECT_TRUE(t.failures.empty()) << t.failures.size() << " failures";
  for (const char* f : kFamilies) EXPECT_GE(t.cases[f], 1) << f;
  EXPECT_EQ(t.invalid_inputs, 0);
  EXPECT_GE(t.booleans, 9 * 6);
  EXPECT_GE(t.chains, 9);
}

/// The failures the broad campaign found (seed 1, 70 cases), not yet fixed
/// (issue 24, round 17): each runs its one case; enable once fixed.
/// One case of the campaign, reported and expected free of failures.
Tally one_case(int n, std::uint32_t seed = 1u) {
  Tally t;
  run_campaign(seed, n + 1, t, n);
  report(t);
  EXPECT_TRUE(t.failures.empty()) << "case " << n << ": " << t.failures.size() << " failures";
  return t;
}
void known_case(int n, std::uint32_t seed = 1u) {
  (void)one_case(n, seed);
}

// Exact inputs: an icosphere (level 1) and two quarter-turned copies (case
// 15), and two UV spheres (8) shifted (case 49). snap17's repair_folds
// answered every Boolean of both, but a repaired (A u B) - C of case 15
// and B - A of case 49 cross themselves by CGAL's exact pairs
// (pinched_result_crosses): both have coincident vertices (two ids rounded
// to one position), where the fold check merges corners and misses the
// crossing. A result the repair moved is therefore returned only when it
// passes the operands' whole self-intersection test (prepare_result,
// boolean.cpp): no crossing is returned, and those Booleans are refused as
// folded, as before the repair. Fails without that rule (a crossing in
// each case).
// cross18: case 15's moved results with coincident copies now pass
// pinched_self_crossing (copies merged: no two faces cross) and are
// returned, none crossing by CGAL's pinched oracle; case 49 op 3 is still
// refused.
TEST(NetDegeneratePairs, RepairedResultsPassTheWholeSelfTestOrAreRefused) {
  for (const int n : {15, 49}) {
    const Tally t = one_case(n);
    EXPECT_EQ(t.crossing, 0) << "case " << n;
    if (n == 49) EXPECT_GE(t.fold_refused, 1) << "case " << n << " is no longer refused: pick another case";
    EXPECT_GE(t.ok, 6) << "case " << n;
  }
}
// A UV sphere (16 x 8) and its half, scaled about a point on the line of an
// equator edge (the faces there coplanar and overlapping): every operation's
// result intersects itself (by CGAL, and by the Boolean's own check when it
// is used as an operand). With the check on by default (fold16) three of
// its Booleans were refused as folded; snap17's repair_folds answers all
// twelve (the chains after them now run too), each closed, CGAL's volume and
// unpinched, so CGAL's exact test checks every one (the test fails without
// the repair: fold_refused 3).
TEST(NetDegeneratePairs, HalfSizeUvSphereInsideSharingFacesIsRepairedNotRefused) {
  const Tally t = one_case(20);
  EXPECT_EQ(t.fold_refused, 0);
  // 4 operations, and 2 chains of 4 Booleans (the union's only under
  // ATELIER_SKIP_LONG_TESTS, check_pair).
  EXPECT_GE(t.ok, std::getenv("ATELIER_SKIP_LONG_TESTS") ? 8 : 12);
}
// A box and its copy turned a quarter turn about its centre's z axis by
// Eigen's AngleAxis (inexact: a near-copy): results intersected themselves
// (issue 24, round 17). The boxes' quads are planar and convex: split as
// fans now, without centroids off their planes (issue 24, fold15), the
// results pass check_pair (CGAL's volume, closed_model, CGAL's
// self-intersection test) with no fold refused.
// BooleanOptions::check_result is what keeps a folded result from being
// returned: the half-size UV sphere inside sharing faces (case 20) gives
// results that cross themselves by CGAL's exact test without it, and with
// it (the default since fold16) none is returned crossing: fold15 and
// fold16 refused them as folded, snap17's repair_folds repairs them (no
// refusal, every result free of crossings by CGAL's test).
TEST(NetDegeneratePairs, CheckResultNeverReturnsWhatRoundingFolds) {
  Tally off;
  off.check_result = false;
  run_campaign(1u, 21, off, 20);
  const auto crossing = std::count_if(off.failures.begin(), off.failures.end(), [](const std::string& f) {
    return f.find("the result intersects itself") != std::string::npos;
  });
  EXPECT_GE(crossing, 1) << "case 20 no longer folds without the check: pick another case";
  EXPECT_EQ(off.fold_refused, 0);
  Tally on;
  on.check_result = BooleanOptions{}.check_result;  // the default, whatever the environment says
  run_campaign(1u, 21, on, 20);
  report(on);
  EXPECT_TRUE(on.failures.empty()) << on.failures.size() << " failures";
  EXPECT_EQ(on.crossing, 0);
  EXPECT_EQ(on.fold_refused, 0);
}
TEST(NetDegeneratePairs, NearCopyOfABoxDoesNotFold) {
  const Tally t = one_case(9);
  EXPECT_EQ(t.fold_refused, 0);
  EXPECT_GE(t.booleans, 6);
}
// An icosphere (level 1) turned a fifth turn about the axis through its
// vertex 0 (a near-copy sharing the fan about vertex 0): A - B had an edge
// (0, 71) of four faces (issue 24, round 18). The rounded constructed
// points there leave slivers whose faces about the edge do not alternate in
// orientation, so no angular pairing exists; unpinch re-pairs the edge
// until its ends' fans split it. Checked by check_pair as above.
TEST(NetDegeneratePairs, FifthTurnOfAnIcosphereStaysManifold) {
  known_case(44);
}
// A prism over a 12-gon and its copy shifted by 1/8 along its axis (side
// quads coplanar and overlapping, caps split around their centroids): the
// pair of seed 2's case 56 below, here with the volumes by hand (the prisms
// overlap over 7/8 of their height).
TEST(NetDegeneratePairs, APrismShiftedAlongItsAxisHasTheVolumesByHand) {
  const PolygonSoup a = net_test::prism(12, 1.0, {0, 0, 0}, -0.5, 0.5);
  const PolygonSoup b = mapped(a, [](const Vec3d& p) { return Vec3d(p + Vec3d(0, 0, -0.125)); });
  const double v = soup_volume(a);
  const double want[4] = {v * 9 / 8, v * 7 / 8, v / 8, v / 8};
  for (BooleanOp op : kOps) {
    BooleanOptions o;
    o.op = op;
    const auto r = net_boolean(a, b, o);
    ASSERT_TRUE(r.has_value()) << r.status().to_string();
    EXPECT_TRUE(net_test::closed_model(r->result));
    EXPECT_NEAR(r->volume, want[static_cast<int>(op)], 1e-12 * v);
  }
}
// Seed 2's case 56 (issue 24, round 18): that prism and its copies shifted
// by 1/8 and 3/16 along the axis. The union's intersection points, rounded
// to doubles, fold a sliver of A's cap over a side triangle (the exact
// union does not cross itself: the sliver is the cap poking 1e-17 out of
// B's side quads, split about their rounded centroids). The prepared result
// skipped the self-intersection test, so the prepared chain (A u B) op C
// crashed in CGAL's constrained triangulation (a segfault on main). Now a
// result is prepared exactly when CGAL finds it free of crossings and of
// coincident vertex copies; otherwise prepared_status names the faces, as
// the soup chain's error does. Prepared chains agree with the soup chains
// and with CGAL's volume.
TEST(NetDegeneratePairs, ShiftedPrismsChainRefusesAFoldedResultClearly) {
  const PolygonSoup a = net_test::prism(12, 1.0, {0, 0, 0}, -0.5, 0.5);
  const PolygonSoup b = mapped(a, [](const Vec3d& p) { return Vec3d(p + Vec3d(0, 0, -0.125)); });
  const PolygonSoup c = mapped(a, [](const Vec3d& p) { return Vec3d(p + Vec3d(0, 0, -0.1875)); });
  const auto pc = PreparedNet::prepare(c, PrepareOptions{"B", true});
  ASSERT_TRUE(pc.has_value()) << pc.status().to_string();
  const double scale = 2 * soup_volume(a);
  int refused_crossing = 0;
  for (BooleanOp op : {BooleanOp::kUnion, BooleanOp::kAMinusB}) {
    BooleanOptions o;
    o.op = op;
    o.prepare_result = true;
    const auto r = net_boolean(a, b, o);
    ASSERT_TRUE(r.has_value()) << r.status().to_string();
    EXPECT_TRUE(net_test::closed_model(r->result));
    const auto want = corefined_volume(a, b, op);
    ASSERT_TRUE(want.has_value());
    EXPECT_NEAR(r->volume, *want, 1e-9 * scale);
    const bool coincident = has_coincident_vertices(r->result);
    const bool crosses = !coincident && PMP::does_self_intersect(mesh_of<Kin>(r->result));
    EXPECT_EQ(r->prepared.empty(), coincident || crosses)
        << "op " << static_cast<int>(op) << ": " << r->prepared_status.to_string();
    if (crosses) {
      // The same refusal as the soup chain's, naming the two faces.
      ++refused_crossing;
      EXPECT_EQ(r->prepared_status.code(), ErrorCode::kTopology);
      EXPECT_NE(r->prepared_status.message().find("intersects itself: faces "), std::string::npos);
      BooleanOptions o2;
      const auto s = net_boolean(r->result, c, o2);
      ASSERT_FALSE(s.has_value());
      EXPECT_EQ(s.status().message(), r->prepared_status.message());
    }
    if (r->prepared.empty()) continue;
    for (BooleanOp op2 : {BooleanOp::kUnion, BooleanOp::kIntersection, BooleanOp::kAMinusB}) {
      BooleanOptions o2;
      o2.op = op2;
      o2.check_self_intersection = true;
      const auto p = net_boolean(r->prepared, *pc, o2);
      const auto s = net_boolean(r->result, c, o2);
      ASSERT_EQ(p.has_value(), s.has_value());
      if (!p) {
        EXPECT_EQ(p.status().message(), s.status().message());
        continue;
      }
      EXPECT_EQ(p->volume, s->volume);
      EXPECT_TRUE(net_test::closed_model(p->result));
      if (const auto w = corefined_volume(r->result, c, op2)) {
        EXPECT_NEAR(p->volume, *w, 1e-9 * scale);
      }
    }
  }
  // The union folded on main (its side quads split about centroids off
  // their planes); split as fans (issue 24, fold15) neither result crosses
  // itself, so both are prepared.
  EXPECT_EQ(refused_crossing, 0);
}
// UV spheres turned by their own symmetry (inexact): B - A (case 30) and
// A - B (37) had an edge of four faces (issue 24, round 18): unpinch paired
// them net by net, so both ends stayed one fan. Now paired by the faces'
// exact order about the edge (pair_about_edge); checked against CGAL's
// volume, closed_model and CGAL's self-intersection test by check_pair.
// Under the sanitizers (ATELIER_SKIP_LONG_TESTS) case 30 alone: the two
// cases cost about 120 s of CI's ASan stage, mostly the repair's exact
// predicates and CGAL's oracle; case 37 runs in every Release `make test`.
TEST(NetDegeneratePairs, SymmetryTurnsOfUvSpheresStayManifold) {
  known_case(30);
  if (std::getenv("ATELIER_SKIP_LONG_TESTS") == nullptr) known_case(37);
}

// Seed 2 case 129: A an icosphere, B = C = A scaled by 1/2 (exact). X = A - B
// has two shells, its cavity exactly C's surface reversed, so by hand
// X u C = A (the cavity filled), X n C is empty and X - C = X. CGAL answered
// V(X), -V(C), V(A) (a cavity on the other net's surface, classified by a
// point on it); the oracle now declines that pair, and CGAL agrees with ours
// where C is a little smaller or larger (the answers then differ from the
// ones by hand by about C's change of volume: continuity).
TEST(NetDegeneratePairs, AChainIntoTheCavityItFillsHasTheVolumesByHand) {
  const PolygonSoup a = net_test::icosphere(2, 1.0, {0, 0, 0});
  auto scaled = [&](double s) { return mapped(a, [s](const Vec3d& p) { return Vec3d(s * p); }); };
  const PolygonSoup b = scaled(0.5);
  const double va = soup_volume(a), vb = soup_volume(b), tol = 1e-12 * va;
  BooleanOptions o;
  o.op = BooleanOp::kAMinusB;
  o.prepare_result = true;
  const auto x = net_boolean(a, b, o);
  ASSERT_TRUE(x.has_value()) << x.status().to_string();
  ASSERT_FALSE(x->prepared.empty()) << x->prepared_status.to_string();
  EXPECT_NEAR(x->volume, va - vb, tol);
  EXPECT_EQ(x->result.face_count(), a.face_count() + b.face_count());
  auto pc = PreparedNet::prepare(b, PrepareOptions{"B", true});
  ASSERT_TRUE(pc.has_value());
  const double by_hand[3] = {va, 0.0, va - vb};  // union, intersection, difference
  const std::size_t faces[3] = {a.face_count(), 0, x->result.face_count()};
  for (BooleanOp op : {BooleanOp::kUnion, BooleanOp::kIntersection, BooleanOp::kAMinusB}) {
    const int i = static_cast<int>(op);
    BooleanOptions q;
    q.op = op;
    const auto r = net_boolean(x->result, b, q);
    ASSERT_TRUE(r.has_value()) << i << ": " << r.status().to_string();
    EXPECT_NEAR(r->volume, by_hand[i], tol) << i;
    EXPECT_EQ(r->result.face_count(), faces[i]) << i;
    if (faces[i] > 0) {
      EXPECT_TRUE(net_test::closed_model(r->result)) << i;
    }
    const auto p = net_boolean(x->prepared, *pc, q);
    ASSERT_TRUE(p.has_value()) << i << ": " << p.status().to_string();
    EXPECT_EQ(p->volume, r->volume) << i;
    EXPECT_FALSE(corefined_volume(x->result, b, op).has_value()) << i << ": the oracle trusts CGAL here";
    // Continuity: C a little smaller and larger, where CGAL classifies.
    for (double s : {0.5 - 0x1p-10, 0.5 + 0x1p-10}) {
      const PolygonSoup c = scaled(s);
      const auto rc = net_boolean(x->result, c, q);
      ASSERT_TRUE(rc.has_value()) << i << " " << s << ": " << rc.status().to_string();
      const auto want = corefined_volume(x->result, c, op);
      ASSERT_TRUE(want.has_value()) << i << " " << s;
      EXPECT_NEAR(rc->volume, *want, 1e-9 * va) << i << " " << s;
      EXPECT_LE(std::abs(rc->volume - by_hand[i]), 1.01 * std::abs(soup_volume(c) - vb)) << i << " " << s;
    }
  }
}

// The rounded result's certificate (issue 24, fold16) against CGAL's exact
// self-intersection test, brute force over the campaign's results: every
// Boolean of seed 1's cases 0-21 (the compact campaign's nine, the near-copy
// box of case 9, the quarter-turn chain of case 15, the half-size UV sphere
// of case 20) with the check on (the default) and off. Where the
// certificate decides alone, the result is the unchecked one byte for byte
// and CGAL finds it free of crossings (pinched results, which CGAL counts
// as crossings, only compared byte for byte); every unchecked result CGAL
// finds crossing must have gone to the full check.
TEST(NetDegeneratePairs, CertificateNeverPassesAResultThatCrosses) {
  auto& counts = net_detail::result_check_counts();
  int certified = 0, full = 0, crossing_off = 0, certified_checked_by_cgal = 0, no_result_stage = 0;
  for_each_case(
      1u, 22, -1,
      [&](const PolygonSoup& a, const PolygonSoup& b, const PolygonSoup&, const char*, const std::string& what) {
        if (!PreparedNet::prepare(a) || !PreparedNet::prepare(b)) return;
        for (BooleanOp op : kOps) {
          BooleanOptions off;
          off.op = op;
          off.check_result = false;
          BooleanOptions on = off;
          on.check_result = true;
          const auto r_off = net_boolean(a, b, off);
          const std::size_t c0 = counts.certified, f0 = counts.full;
          const auto r_on = net_boolean(a, b, on);
          const bool passed = counts.certified - c0 == 1, sent = counts.full - f0 == 1;
          if (!r_off) {
            EXPECT_FALSE(r_on.has_value()) << what;
            continue;
          }
          const bool pinched = has_coincident_vertices(r_off->result);
          const bool crosses =
              r_off->result.face_count() > 0 && !pinched && PMP::does_self_intersect(mesh_of<Kin>(r_off->result));
          crossing_off += crosses;
          ASSERT_FALSE(passed && sent) << what << ": one verdict per Boolean";
          if (!passed && !sent) {
            ++no_result_stage;  // answered before the result's assembly (no cut)
            continue;
          }
          if (passed) {
            ++certified;
            EXPECT_FALSE(crosses) << what << " op " << static_cast<int>(op)
                                  << ": certified, but CGAL finds the result crossing itself";
            ASSERT_TRUE(r_on.has_value()) << what;
            EXPECT_EQ(r_on->result.positions, r_off->result.positions) << what;
            EXPECT_EQ(r_on->result.face_nodes, r_off->result.face_nodes) << what;
            certified_checked_by_cgal += !pinched;
          } else {
            ++full;
          }
        }
      });
  std::cout << "certified " << certified << " (CGAL-checked " << certified_checked_by_cgal << "), full check " << full
            << ", crossing without the check " << crossing_off << ", no result check " << no_result_stage << "\n";
  EXPECT_GE(crossing_off, 1) << "no crossing result left to test the certificate against: pick other cases";
  EXPECT_GE(certified_checked_by_cgal, 20);
  EXPECT_GE(full, crossing_off);
}

// The default check gives the same bits on one and two threads, where the
// certificate passes (a generic pair of icospheres) and where it sends the
// result to the full check (case 20: refused or repaired alike), with the
// sequential threshold lowered so that two threads do run; case 20's
// Booleans are repaired by snap17's repair_folds.
TEST(NetDegeneratePairs, DefaultCheckGivesTheSameBitsForOneAndTwoThreads) {
  std::vector<std::array<PolygonSoup, 2>> pairs;
  pairs.push_back({net_test::icosphere(3, 1.0, {0, 0, 0}), net_test::icosphere(3, 0.9, {0.31, 0.17, 0.05})});
  for_each_case(1u, 21, 20,
                [&](const PolygonSoup& a, const PolygonSoup& b, const PolygonSoup&, const char*, const std::string&) {
                  pairs.push_back({a, b});
                });
  ASSERT_EQ(pairs.size(), 2u);
  auto& counts = net_detail::result_check_counts();
  std::size_t full0 = counts.full, certified0 = counts.certified, repaired0 = net_detail::fold_repair_count();
  for (const auto& [a, b] : pairs)
    for (BooleanOp op : kOps) {
      BooleanOptions o;
      o.op = op;
      const auto threads = one_and_two_threads();
      const ExecContext &one = threads.first, &two = threads.second;
      const auto r1 = net_boolean(a, b, o, one);
      const auto r2 = net_boolean(a, b, o, two);
      ASSERT_EQ(r1.has_value(), r2.has_value());
      if (!r1) {
        EXPECT_EQ(r1.status().to_string(), r2.status().to_string());
        continue;
      }
      EXPECT_EQ(r1->result.positions, r2->result.positions);
      EXPECT_EQ(r1->result.face_nodes, r2->result.face_nodes);
      EXPECT_EQ(r1->result.face_offsets, r2->result.face_offsets);
    }
  EXPECT_GE(counts.full - full0, 2u) << "case 20 no longer needs the full check";
  EXPECT_GE(counts.certified - certified0, 2u) << "the icospheres are no longer certified";
  // snap17: case 20's folded results go through repair_folds (on one and
  // on two threads): its moves must give the same bits too.
  EXPECT_GE(net_detail::fold_repair_count() - repaired0, 4u) << "case 20 is no longer repaired by repair_folds";
}

// cross18: seed 2 case 60 (a UV sphere (8) snapped to a grid of 1/8): B -
// A and its chain are pinched results in which CGAL's exact pairs meet two
// faces along the segment from (3/4, 1/2, 0), a corner both share by id, to
// (7/8, 3/8, 0), where each has its own copy of a pinched vertex: the two
// faces lie on one edge by position (one above z = 0, one below), a touch
// as in the exact result, not a crossing. The oracle required both ends to
// be coincident copies and counted it (the two "crossings" of seed 2); it
// now ignores a point or segment whose ends are corners of both faces, the
// rule of the Booleans' own triangles_cross with the copies merged. Fails
// with the old oracle (2 failures: "the (pinched) result intersects
// itself").
TEST(NetDegeneratePairs, TwoFacesOnOneEdgeThroughAPinchAreATouchNotACrossing) {
  // Both chains always (0.06 s): the second pinched result is a chain.
  Tally t;
  t.short_chains = false;
  run_campaign(2u, 61, t, 60);
  report(t);
  EXPECT_TRUE(t.failures.empty()) << t.failures.size() << " failures";
  EXPECT_GE(t.pinched, 2) << "case 60 is no longer pinched: pick another case";
  EXPECT_EQ(t.crossing, 0);
  EXPECT_EQ(t.fold_refused, 0);
}

// Seed 1 case 43 (a prism over an octagon and two quarter-turned copies):
// the chain (A u B) u C had a triangle whose two corners (two ids) lie at
// one position, a zero-length edge fold15's collapse could not remove under
// the link condition (cross18; CGAL's exact pairs counted the face as
// crossing itself). flat19: the Booleans merge such an edge's two ids after
// unpinch where the result stays a 2-manifold (merge_flat_edges, no
// position moves), and refuse a flat face left in any result. The chain is
// answered through the merge (flat_merge_count moves): closed and
// validate() clean, no face with two corners at one position, the whole
// self-test with flat faces refused finds nothing, CGAL's exact test (its
// pinched oracle where copies remain) finds no crossing, and the volume is
// CGAL's corefinement's. Before flat19 it failed the corner and CGAL checks.
TEST(NetDegeneratePairs, APinchedResultsFlatFaceIsMergedAway) {
  std::vector<std::array<PolygonSoup, 3>> nets;
  for_each_case(1u, 44, 43,
                [&](const PolygonSoup& a, const PolygonSoup& b, const PolygonSoup& c, const char*, const std::string&) {
                  nets.push_back({a, b, c});
                });
  ASSERT_EQ(nets.size(), 1u);
  const auto& [a, b, c] = nets[0];
  const auto ab = net_boolean(a, b, BooleanOptions{});
  ASSERT_TRUE(ab.has_value()) << ab.status().to_string();
  const std::size_t merged = net_detail::flat_merge_count().load();
  const auto abc = net_boolean(ab->result, c, BooleanOptions{});
  ASSERT_TRUE(abc.has_value()) << abc.status().to_string();
  EXPECT_GT(net_detail::flat_merge_count().load(), merged) << "no edge merged: the case changed";
  const PolygonSoup& r = abc->result;
  EXPECT_TRUE(net_test::closed_model(r));
  int coincident = 0;
  for (std::size_t f = 0; f < r.face_count(); ++f) {
    const auto c3 = r.face(f);
    for (std::size_t k = 0; k < c3.size(); ++k)
      coincident += c3[k] != c3[(k + 1) % c3.size()] && r.positions[c3[k]] == r.positions[c3[(k + 1) % c3.size()]];
  }
  EXPECT_EQ(coincident, 0) << "a face has two corners at one position";
  EXPECT_EQ(net_detail::pinched_self_crossing(r, ExecContext{}, true)[0], net_detail::kNil);
  if (has_coincident_vertices(r)) {
    EXPECT_FALSE(pinched_result_crosses(r));
  } else {
    EXPECT_FALSE(PMP::does_self_intersect(mesh_of<Kex>(r)));
  }
  const double scale = std::abs(soup_volume(ab->result)) + std::abs(soup_volume(c));
  if (const auto want = corefined_volume(ab->result, c, BooleanOp::kUnion)) {
    EXPECT_LE(std::abs(abc->volume - *want), 1e-9 * scale);
  }
}

// snap17: what fold15's repair left folded is repaired, not refused. Seed
// 1's cases 6 (a half-size UV sphere inside sharing faces), 16 and 23
// (symmetry turns of icospheres) and 20 (case 20 above): every Boolean of
// the four operations on default options; where repair_folds ran (its
// count moved), the result must be there, closed, manifold and oriented
// (closed_model), validate() clean as a model, CGAL's volume, and free of
// crossings by CGAL's exact test (pinched ones by pinched_result_crosses:
// CGAL's exact pairs, touches at coincident copies only). Before snap17 these
// Booleans were refused as folded (the campaign's FOLD lines), so the test
// fails without the repair: the count does not move.
TEST(NetDegeneratePairs, FoldedResultsAreRepairedNotRefused) {
  auto& repaired = net_detail::fold_repair_count();
  int ran = 0, refused = 0, pinched = 0;
  // degen19: case 23's A - B and B - A are refused after the repair's whole
  // budget (1.7-1.8 s of CPU each in Release, about 3/4 of this test):
  // under ATELIER_SKIP_LONG_TESTS (CI's sanitizer stage) they are left out.
  // Refused Booleans only count towards `refused` (at most 4), so `ran` is
  // the same either way.
  const bool short_run = std::getenv("ATELIER_SKIP_LONG_TESTS") != nullptr;
  for (const int n : {6, 16, 20, 23})
    for_each_case(
        1u, n + 1, n,
        [&](const PolygonSoup& a, const PolygonSoup& b, const PolygonSoup&, const char*, const std::string& what) {
          for (BooleanOp op : kOps) {
            if (short_run && n == 23 && (op == BooleanOp::kAMinusB || op == BooleanOp::kBMinusA)) continue;
            BooleanOptions o;
            o.op = op;
            const std::size_t r0 = repaired;
            const auto r = net_boolean(a, b, o);
            const std::string w = what + " op " + std::to_string(static_cast<int>(op));
            if (!r) {
              refused += r.status().message().find("crosses itself once") != std::string::npos;
              continue;
            }
            if (repaired == r0) continue;
            ++ran;
            EXPECT_TRUE(net_test::closed_model(r->result)) << w;
            Model m;
            ASSERT_TRUE(add_polygon_surface(m, "r", r->result).has_value()) << w;
            EXPECT_TRUE(validate(m).is_ok()) << w;
            const double scale = std::abs(soup_volume(a)) + std::abs(soup_volume(b));
            if (auto want = corefined_volume(a, b, op)) {
              EXPECT_LE(std::abs(r->volume - *want), 1e-9 * scale) << w;
            }
            if (has_coincident_vertices(r->result)) {
              ++pinched;
              EXPECT_FALSE(pinched_result_crosses(r->result)) << w;
            } else {
              EXPECT_FALSE(PMP::does_self_intersect(mesh_of<Kin>(r->result))) << w;
            }
          }
        });
  std::cout << "repaired " << ran << " (pinched " << pinched << "), refused as folded " << refused << "\n";
  // fold16: 0 (10 of these 16 Booleans refused as folded); snap17: 7 and
  // 3; one repaired result fails the whole self-test (prepare_result) and
  // is refused since the lead's merge.
  EXPECT_GE(ran, 6);
  EXPECT_LE(refused, 4);
}

// degen19: repair_folds' lean search (a candidate's crossings counted only
// up to the best so far, ulp steps once per step, reused boxes and scratch
// meshes) against snap17's whole counts (fold_repair_lean() false): every
// Boolean of the four operations on campaign cases whose results the
// repair moves must give the same verdict, the same error text and the
// same bytes, and the lean search the same on one and on two threads.
// Seed 1's cases 6, 16, 20 (FoldedResultsAreRepairedNotRefused), 44 (the
// fifth turn: A - B refused after 1.1-1.5 s of rounds) and 49 (B - A
// refused); under ATELIER_SKIP_LONG_TESTS cases 20 and 49 only. Case 23
// (3.6 s of rounds on snap17's search alone) is left out for the time.
TEST(NetDegeneratePairs, LeanFoldRepairKeepsVerdictsAndBytes) {
  auto& lean = net_detail::fold_repair_lean();
  const bool was = lean;
  std::vector<int> cases = {6, 16, 20, 44, 49};
  if (std::getenv("ATELIER_SKIP_LONG_TESTS") != nullptr) cases = {20, 49};
  auto& repaired = net_detail::fold_repair_count();
  std::size_t repairs = 0;
  int refused = 0, compared = 0;
  auto same = [&](const Expected<BooleanReport>& x, const Expected<BooleanReport>& y, const std::string& w) {
    ASSERT_EQ(x.has_value(), y.has_value()) << w;
    ++compared;
    if (!x) {
      EXPECT_EQ(x.status().to_string(), y.status().to_string()) << w;
      return;
    }
    EXPECT_EQ(x->result.positions, y->result.positions) << w;
    EXPECT_EQ(x->result.face_nodes, y->result.face_nodes) << w;
    EXPECT_EQ(x->result.face_offsets, y->result.face_offsets) << w;
    EXPECT_EQ(x->volume, y->volume) << w;
  };
  for (const int n : cases)
    for_each_case(1u, n + 1, n,
                  [&](const PolygonSoup& a, const PolygonSoup& b, const PolygonSoup&, const char*,
                      const std::string& what) {
                    for (BooleanOp op : kOps) {
                      BooleanOptions o;
                      o.op = op;
                      const auto threads = one_and_two_threads();
      const ExecContext &one = threads.first, &two = threads.second;
                      const std::string w = what + " op " + std::to_string(static_cast<int>(op));
                      // Thread CPU time of each one-thread Boolean (the
                      // figures of docs/performance.md, degen19).
                      auto cpu_ms = [] {
                        timespec ts{};
                        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
                        return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
                      };
                      lean = false;
                      const double t0 = cpu_ms();
                      const auto old_one = net_boolean(a, b, o, one);
                      lean = true;
                      const double t1 = cpu_ms();
                      const std::size_t r0 = repaired;
                      const auto lean_one = net_boolean(a, b, o, one);
                      const double t2 = cpu_ms();
                      repairs += repaired - r0;
                      std::cout << w << ": snap17's search " << t1 - t0 << " ms, lean " << t2 - t1 << " ms ("
                                << (lean_one ? "ok" : "refused") << ")\n";
                      const auto lean_two = net_boolean(a, b, o, two);
                      same(old_one, lean_one, w + " (lean against snap17's search)");
                      same(lean_one, lean_two, w + " (lean, 1 against 2 threads)");
                      refused += !lean_one && lean_one.status().message().find("crosses itself once") !=
                                                  std::string::npos;
                    }
                  });
  lean = was;
  std::cout << "compared " << compared << ", repaired " << repairs << ", refused as folded " << refused << "\n";
  // The comparison means something only where the search ran: results it
  // repaired and Booleans refused after its rounds.
  EXPECT_GE(repairs, 2u) << "no result was repaired: pick other cases";
  EXPECT_GE(refused, 1) << "no Boolean was refused after the repair's rounds: pick other cases";
}

}  // namespace
}  // namespace atelier::degenerate_pairs
