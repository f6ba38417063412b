#include <atelier/systems/curvenet/curve_network.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <tuple>

#include <atelier/storage/union_find.h>

namespace atelier {

double CurveGraph::length(std::size_t s) const noexcept {
  const auto p = polyline(s);
  double l = 0;
  for (std::size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
  return l;
}

void CurveGraph::add_segment(std::uint32_t from, std::uint32_t to, std::span<const Vec3d> polyline,
                             std::uint32_t curve) {
  segment_nodes.push_back({from, to});
  points.insert(points.end(), polyline.begin(), polyline.end());
  offsets.push_back(static_cast<std::uint32_t>(points.size()));
  segment_curve.push_back(curve);
}

std::vector<std::uint32_t> CurveGraph::degrees() const {
  std::vector<std::uint32_t> d(nodes.size(), 0);
  for (const auto& sn : segment_nodes) {
    ++d[sn[0]];
    ++d[sn[1]];
  }
  return d;
}

namespace {

/// Closest points of segments [a0,a1] and [b0,b1] (Ericson, Real-Time
/// Collision Detection 5.1.9), parameters s, t in [0, 1].
struct SegmentPair {
  double dist = 0, s = 0, t = 0;
  Vec3d p, q;
};

SegmentPair closest_segments(const Vec3d& a0, const Vec3d& a1, const Vec3d& b0, const Vec3d& b1) {
  const Vec3d d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) {
    s = t = 0;
  } else if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), den = a * e - b * b;
      s = den > 0 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  SegmentPair out;
  out.s = s;
  out.t = t;
  out.p = a0 + s * d1;
  out.q = b0 + t * d2;
  out.dist = (out.p - out.q).norm();
  return out;
}

double point_segment_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

/// A curve after cleaning, with the cumulative arc length at each point.
struct Curve {
  std::vector<Vec3d> p;
  std::vector<double> arc;
  [[nodiscard]] double arc_at(double t) const {  // t = segment index + fraction
    const auto i = std::min(static_cast<std::size_t>(t), p.size() - 2);
    return arc[i] + (t - static_cast<double>(i)) * (arc[i + 1] - arc[i]);
  }
};

struct Hit {
  std::uint32_t ca, cb;
  double ta, tb;  // segment index + fraction
  double dist;
  Vec3d point;
};

/// A place where a curve is cut: parameter and node candidate.
struct Cut {
  double t;
  std::uint32_t node;
};

std::string at(const Vec3d& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", p.x(), p.y(), p.z());
  return buf;
}

/// Unit tangent leaving a polyline's first point, and the curvature there,
/// from the points at arc length h and 2h (Menger curvature of the three).
struct EndShape {
  Vec3d tangent = Vec3d::Zero();
  double curvature = 0;
};

Vec3d point_at_arc(std::span<const Vec3d> p, double s) {
  double acc = 0;
  for (std::size_t i = 1; i < p.size(); ++i) {
    const double l = (p[i] - p[i - 1]).norm();
    if (acc + l >= s && l > 0) return p[i - 1] + (s - acc) / l * (p[i] - p[i - 1]);
    acc += l;
  }
  return p.back();
}

EndShape end_shape(std::span<const Vec3d> p, double h) {
  EndShape e;
  const Vec3d a = p.front(), b = point_at_arc(p, h), c = point_at_arc(p, 2 * h);
  const Vec3d ab = b - a;
  if (ab.norm() > 0) e.tangent = ab.normalized();
  const double la = (b - a).norm(), lb = (c - b).norm(), lc = (c - a).norm();
  const double area2 = (b - a).cross(c - a).norm();
  if (la > 0 && lb > 0 && lc > 0) e.curvature = 2 * area2 / (la * lb * lc);
  return e;
}

/// Finite curves without repeated consecutive points, with arc lengths;
/// errors name the curve.
Status clean_curves(const PolylineSet& in, std::vector<Curve>& curves, Box3d& box) {
  curves.assign(in.size(), {});
  for (std::size_t c = 0; c < in.size(); ++c) {
    for (const Vec3d& p : in.curve(c)) {
      if (!p.allFinite())
        return Status(ErrorCode::kInvalidArgument, in.describe(c) + " has a non-finite point " + at(p));
      if (curves[c].p.empty() || curves[c].p.back() != p) curves[c].p.push_back(p);
      box.extend(p);
    }
    if (curves[c].p.size() < 2)
      return Status(ErrorCode::kInvalidArgument, in.describe(c) + " has fewer than 2 distinct points");
    auto& cu = curves[c];
    cu.arc.assign(cu.p.size(), 0.0);
    for (std::size_t i = 1; i < cu.p.size(); ++i) cu.arc[i] = cu.arc[i - 1] + (cu.p[i] - cu.p[i - 1]).norm();
  }
  return {};
}

/// Closest approaches within tol between pieces of different curves (or
/// far-apart pieces of one), by sort-and-sweep over boxes inflated by tol;
/// two curves lying along each other are refused as duplicates.
Expected<std::vector<Hit>> find_hits(const PolylineSet& in, const std::vector<Curve>& curves, double tol,
                                     double cluster) {
  struct Seg {
    std::uint32_t c, i;
    Box3d b;
  };
  std::vector<Seg> segs;
  for (std::uint32_t c = 0; c < curves.size(); ++c)
    for (std::uint32_t i = 0; i + 1 < curves[c].p.size(); ++i) {
      Seg s{c, i, {}};
      s.b.extend(curves[c].p[i]);
      s.b.extend(curves[c].p[i + 1]);
      s.b.lo.array() -= tol;
      s.b.hi.array() += tol;
      segs.push_back(s);
    }
  std::sort(segs.begin(), segs.end(),
            [](const Seg& a, const Seg& b) { return std::tie(a.b.lo.x(), a.c, a.i) < std::tie(b.b.lo.x(), b.c, b.i); });
  std::vector<Hit> hits;
  std::vector<std::uint32_t> active;
  for (std::uint32_t k = 0; k < segs.size(); ++k) {
    const Seg& s = segs[k];
    std::erase_if(active, [&](std::uint32_t a) { return segs[a].b.hi.x() < s.b.lo.x(); });
    for (std::uint32_t a : active) {
      const Seg& o = segs[a];
      if (o.b.hi.y() < s.b.lo.y() || s.b.hi.y() < o.b.lo.y() || o.b.hi.z() < s.b.lo.z() || s.b.hi.z() < o.b.lo.z())
        continue;
      const Seg *x = &o, *y = &s;
      if (std::tie(y->c, y->i) < std::tie(x->c, x->i)) std::swap(x, y);
      if (x->c == y->c && y->i <= x->i + 1) continue;  // same or adjacent piece of one curve
      const Curve &cx = curves[x->c], &cy = curves[y->c];
      const SegmentPair sp = closest_segments(cx.p[x->i], cx.p[x->i + 1], cy.p[y->i], cy.p[y->i + 1]);
      if (sp.dist > tol) continue;
      const double ta = x->i + sp.s, tb = y->i + sp.t;
      // A curve passing close to itself counts only when the two places are
      // far apart along it (tiny zigzags of a polyline are not crossings).
      if (x->c == y->c && cx.arc_at(tb) - cx.arc_at(ta) <= std::max(10 * tol, cluster)) continue;
      // Two pieces lying along each other over more than the cluster length
      // are two copies of one curve.
      {
        const Vec3d ends[4] = {cx.p[x->i], cx.p[x->i + 1], cy.p[y->i], cy.p[y->i + 1]};
        std::vector<Vec3d> along;
        if (point_segment_distance(ends[0], ends[2], ends[3]) <= tol) along.push_back(ends[0]);
        if (point_segment_distance(ends[1], ends[2], ends[3]) <= tol) along.push_back(ends[1]);
        if (point_segment_distance(ends[2], ends[0], ends[1]) <= tol) along.push_back(ends[2]);
        if (point_segment_distance(ends[3], ends[0], ends[1]) <= tol) along.push_back(ends[3]);
        for (std::size_t u = 0; u < along.size(); ++u)
          for (std::size_t v = u + 1; v < along.size(); ++v)
            if ((along[u] - along[v]).norm() > 100 * cluster)
              return Status(ErrorCode::kInvalidArgument, in.describe(x->c) + " and " + in.describe(y->c) +
                                                             " run on top of each other near " + at(sp.p) +
                                                             " (duplicate curves)");
      }
      hits.push_back({x->c, y->c, ta, tb, sp.dist, 0.5 * (sp.p + sp.q)});
    }
    active.push_back(k);
  }
  std::sort(hits.begin(), hits.end(), [](const Hit& a, const Hit& b) {
    return std::tie(a.ca, a.cb, a.ta, a.tb, a.dist) < std::tie(b.ca, b.cb, b.ta, b.tb, b.dist);
  });

  return hits;
}

/// Nodes (a cluster of hits is one crossing; curve ends; candidates within
/// tol of each other are one node) and the pieces of every curve between
/// its nodes (section 4.1: the pieces end on the node, bit for bit).
CurveGraph split_at_nodes(const std::vector<Curve>& curves, const std::vector<Hit>& hits, double tol, double cluster,
                          CurveTreatmentReport& rep) {
  // ---- node candidates: one per cluster of hits (a crossing at a polyline
  // vertex is found by up to four segment pairs), one per curve end.
  std::vector<Vec3d> cand;
  std::vector<std::uint8_t> cand_is_end;
  std::vector<std::vector<Cut>> cuts(curves.size());
  for (std::size_t h = 0; h < hits.size();) {
    std::size_t e = h + 1;
    std::size_t best = h;
    while (e < hits.size() && hits[e].ca == hits[h].ca && hits[e].cb == hits[h].cb &&
           curves[hits[h].ca].arc_at(hits[e].ta) - curves[hits[h].ca].arc_at(hits[e - 1].ta) <= cluster &&
           std::abs(curves[hits[h].cb].arc_at(hits[e].tb) - curves[hits[h].cb].arc_at(hits[e - 1].tb)) <= cluster) {
      if (hits[e].dist < hits[best].dist) best = e;
      ++e;
    }
    const Hit& b = hits[best];
    const auto id = static_cast<std::uint32_t>(cand.size());
    cand.push_back(b.point);
    cand_is_end.push_back(0);
    cuts[b.ca].push_back({b.ta, id});
    cuts[b.cb].push_back({b.tb, id});
    rep.max_intersection_gap = std::max(rep.max_intersection_gap, b.dist);
    ++rep.intersections;
    h = e;
  }
  for (std::uint32_t c = 0; c < curves.size(); ++c) {
    const auto n = static_cast<double>(curves[c].p.size() - 1);
    cuts[c].push_back({0.0, static_cast<std::uint32_t>(cand.size())});
    cand.push_back(curves[c].p.front());
    cand_is_end.push_back(1);
    cuts[c].push_back({n, static_cast<std::uint32_t>(cand.size())});
    cand.push_back(curves[c].p.back());
    cand_is_end.push_back(1);
  }

  // ---- candidates within tol of each other are one node (sweep on x).
  UnionFind uf(cand.size());
  {
    std::vector<std::uint32_t> order(cand.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(),
              [&](std::uint32_t a, std::uint32_t b) { return std::tie(cand[a].x(), a) < std::tie(cand[b].x(), b); });
    for (std::size_t i = 0; i < order.size(); ++i)
      for (std::size_t j = i + 1; j < order.size() && cand[order[j]].x() - cand[order[i]].x() <= tol; ++j)
        if ((cand[order[i]] - cand[order[j]]).norm() <= tol) uf.unite(order[i], order[j]);
  }
  // Node position: the mean of the group's crossing points, or of its curve
  // ends when it has no crossing (summed in candidate order: deterministic).
  std::vector<std::uint32_t> node_of(cand.size(), kNoCurveNode);
  std::vector<Vec3d> node_pos;
  {
    std::vector<Vec3d> sum_x(cand.size(), Vec3d::Zero()), sum_e(cand.size(), Vec3d::Zero());
    std::vector<std::uint32_t> n_x(cand.size(), 0), n_e(cand.size(), 0);
    for (std::uint32_t i = 0; i < cand.size(); ++i) {
      const std::uint32_t r = uf.find(i);
      if (cand_is_end[i]) {
        sum_e[r] += cand[i];
        ++n_e[r];
      } else {
        sum_x[r] += cand[i];
        ++n_x[r];
      }
    }
    for (std::uint32_t i = 0; i < cand.size(); ++i) {
      const std::uint32_t r = uf.find(i);
      if (node_of[r] == kNoCurveNode) {
        node_of[r] = static_cast<std::uint32_t>(node_pos.size());
        node_pos.push_back(n_x[r] ? Vec3d(sum_x[r] / n_x[r]) : Vec3d(sum_e[r] / n_e[r]));
      }
      node_of[i] = node_of[r];
    }
  }

  // ---- pieces: each curve cut at its sorted cuts.
  CurveGraph g;
  g.nodes = node_pos;
  std::vector<Vec3d> poly;
  for (std::uint32_t c = 0; c < curves.size(); ++c) {
    auto& cs = cuts[c];
    for (Cut& x : cs) x.node = node_of[x.node];
    std::sort(cs.begin(), cs.end(),
              [](const Cut& a, const Cut& b) { return std::tie(a.t, a.node) < std::tie(b.t, b.node); });
    const Curve& cu = curves[c];
    // Repeated cuts at one node close together along the curve are one.
    std::vector<Cut> kept;
    for (const Cut& x : cs)
      if (kept.empty() || x.node != kept.back().node || cu.arc_at(x.t) - cu.arc_at(kept.back().t) > cluster)
        kept.push_back(x);
    std::size_t pieces = 0;
    for (std::size_t k = 0; k + 1 < kept.size(); ++k) {
      const Cut &a = kept[k], &b = kept[k + 1];
      if (a.node == b.node && cu.arc_at(b.t) - cu.arc_at(a.t) <= cluster) continue;
      const Vec3d& pa = g.nodes[a.node];
      const Vec3d& pb = g.nodes[b.node];
      poly.clear();
      poly.push_back(pa);
      const auto first = static_cast<std::size_t>(std::floor(a.t)) + 1;
      const auto last = static_cast<std::size_t>(std::ceil(b.t)) - 1;  // inclusive
      for (std::size_t i = first; i <= last && i < cu.p.size(); ++i) {
        const double ti = static_cast<double>(i);
        if (ti <= a.t || ti >= b.t) continue;
        if ((cu.p[i] - pa).norm() <= tol || (cu.p[i] - pb).norm() <= tol) continue;
        poly.push_back(cu.p[i]);
      }
      poly.push_back(pb);
      g.add_segment(a.node, b.node, poly, c);
      ++pieces;
    }
    rep.splits += pieces > 1 ? pieces - 1 : 0;
  }

  return g;
}

/// Merge threshold 1 (with 2 and 3): free ends close to each other that
/// continue each other are joined into one node.
void join_free_ends(CurveGraph& g, const CurveTreatmentOptions& opt, double diag, CurveTreatmentReport& rep) {
  // ---- merge threshold 1: free ends close to each other are joined.
  if (!opt.merge || !(opt.merge_distance > 0)) return;
  {
    const auto deg = g.degrees();
    const double reach = opt.merge_distance * diag;
    std::vector<std::uint32_t> free_nodes, free_segment(g.node_count(), kNoCurveNode);
    for (std::uint32_t v = 0; v < g.node_count(); ++v)
      if (deg[v] == 1) free_nodes.push_back(v);
    for (std::uint32_t s = 0; s < g.segment_count(); ++s)
      for (int e = 0; e < 2; ++e) free_segment[g.segment_nodes[s][e]] = s;
    // The piece ending at free node v, oriented away from v.
    auto away_from = [&](std::uint32_t v) {
      const std::uint32_t s = free_segment[v];
      std::vector<Vec3d> p(g.polyline(s).begin(), g.polyline(s).end());
      if (g.segment_nodes[s][0] != v) std::reverse(p.begin(), p.end());
      return p;
    };
    const double cos_max = std::cos(opt.merge_angle_degrees * 3.14159265358979323846 / 180.0);
    struct Pair {
      double d;
      std::uint32_t a, b;
    };
    std::vector<Pair> pairs;
    for (std::size_t i = 0; i < free_nodes.size(); ++i)
      for (std::size_t j = i + 1; j < free_nodes.size(); ++j) {
        const double d = (g.nodes[free_nodes[i]] - g.nodes[free_nodes[j]]).norm();
        if (d > reach) continue;
        // Thresholds 2 and 3 as well: the two ends must continue each other
        // (else they are two dangling ends that happen to be close).
        const auto pa = away_from(free_nodes[i]), pb = away_from(free_nodes[j]);
        const double step =
            0.1 * std::min(g.length(free_segment[free_nodes[i]]), g.length(free_segment[free_nodes[j]]));
        const EndShape ea = end_shape(pa, step), eb = end_shape(pb, step);
        const double kmax = std::max({ea.curvature, eb.curvature, 1.0 / diag});
        if (-ea.tangent.dot(eb.tangent) < cos_max || std::abs(ea.curvature - eb.curvature) > opt.merge_curvature * kmax)
          continue;
        pairs.push_back({d, free_nodes[i], free_nodes[j]});
      }
    std::sort(pairs.begin(), pairs.end(),
              [](const Pair& x, const Pair& y) { return std::tie(x.d, x.a, x.b) < std::tie(y.d, y.a, y.b); });
    std::vector<std::uint32_t> joined_to(g.node_count(), kNoCurveNode);
    for (const Pair& p : pairs) {
      if (joined_to[p.a] != kNoCurveNode || joined_to[p.b] != kNoCurveNode) continue;
      joined_to[p.a] = p.a;
      joined_to[p.b] = p.a;
      g.nodes[p.a] = 0.5 * (g.nodes[p.a] + g.nodes[p.b]);
      ++rep.joined_ends;
    }
    for (std::size_t s = 0; s < g.segment_count(); ++s)
      for (int e = 0; e < 2; ++e) {
        const std::uint32_t v = g.segment_nodes[s][e];
        if (joined_to[v] == kNoCurveNode) continue;
        g.segment_nodes[s][e] = joined_to[v];
        g.points[e == 0 ? g.offsets[s] : g.offsets[s + 1] - 1] = g.nodes[joined_to[v]];
      }
  }
}

/// Dangling ends removed repeatedly (with a warning naming their curves),
/// then the live segments and their nodes renumbered in order.
CurveGraph prune_dangling(const CurveGraph& g, const PolylineSet& in, bool prune, CurveTreatmentReport& rep) {
  // ---- prune dangling ends.
  std::vector<std::uint8_t> dead(g.segment_count(), 0);
  if (prune) {
    auto deg = g.degrees();
    std::vector<std::vector<std::uint32_t>> incident(g.node_count());
    for (std::uint32_t s = 0; s < g.segment_count(); ++s) {
      incident[g.segment_nodes[s][0]].push_back(s);
      incident[g.segment_nodes[s][1]].push_back(s);
    }
    std::vector<std::uint32_t> stack;
    for (std::uint32_t v = 0; v < g.node_count(); ++v)
      if (deg[v] == 1) stack.push_back(v);
    std::reverse(stack.begin(), stack.end());
    while (!stack.empty()) {
      const std::uint32_t v = stack.back();
      stack.pop_back();
      if (deg[v] != 1) continue;
      for (std::uint32_t s : incident[v]) {
        if (dead[s]) continue;
        dead[s] = 1;
        ++rep.pruned_segments;
        rep.pruned_length += g.length(s);
        rep.pruned_curve_ids.push_back(in.ids.empty() ? g.segment_curve[s] : in.ids[g.segment_curve[s]]);
        for (int e = 0; e < 2; ++e) {
          const std::uint32_t w = g.segment_nodes[s][e];
          --deg[w];
          if (w != v && deg[w] == 1) stack.push_back(w);
        }
        break;
      }
    }
    std::sort(rep.pruned_curve_ids.begin(), rep.pruned_curve_ids.end());
    rep.pruned_curve_ids.erase(std::unique(rep.pruned_curve_ids.begin(), rep.pruned_curve_ids.end()),
                               rep.pruned_curve_ids.end());
    if (rep.pruned_segments > 0) {
      std::string names;
      for (std::size_t i = 0; i < rep.pruned_curve_ids.size() && i < 12; ++i)
        names += (i ? ", " : "") + std::to_string(rep.pruned_curve_ids[i]);
      if (rep.pruned_curve_ids.size() > 12) names += ", ...";
      rep.warnings.push_back("pruned " + std::to_string(rep.pruned_segments) + " dangling curve end" +
                             (rep.pruned_segments == 1 ? "" : "s") + " (total length " +
                             std::to_string(rep.pruned_length) + ") of curve" +
                             (rep.pruned_curve_ids.size() == 1 ? " " : "s ") + names);
    }
  }

  // ---- compact: live segments, nodes they use (both in order).
  CurveGraph h;
  {
    std::vector<std::uint32_t> remap(g.node_count(), kNoCurveNode);
    for (std::uint32_t s = 0; s < g.segment_count(); ++s) {
      if (dead[s]) continue;
      std::array<std::uint32_t, 2> ends{};
      for (int e = 0; e < 2; ++e) {
        const std::uint32_t v = g.segment_nodes[s][e];
        if (remap[v] == kNoCurveNode) {
          remap[v] = static_cast<std::uint32_t>(h.nodes.size());
          h.nodes.push_back(g.nodes[v]);
        }
        ends[e] = remap[v];
      }
      h.add_segment(ends[0], ends[1], g.polyline(s), g.segment_curve[s]);
    }
  }
  return h;
}

/// Merge thresholds 2 and 3 at degree-2 nodes (section 4.2, knot removal):
/// the two pieces become one when their tangents and curvatures agree.
void merge_continuations(CurveGraph& h, const CurveTreatmentOptions& opt, double diag, CurveTreatmentReport& rep) {
  // ---- merge threshold 2 and 3 at degree-2 nodes: knot removal.
  if (!opt.merge) return;
  {
    const double cos_max = std::cos(opt.merge_angle_degrees * 3.14159265358979323846 / 180.0);
    for (bool changed = true; changed;) {
      changed = false;
      const auto d = h.degrees();
      std::vector<std::array<std::uint32_t, 2>> at_node(h.node_count(), {kNoCurveNode, kNoCurveNode});
      for (std::uint32_t s = 0; s < h.segment_count(); ++s)
        for (int e = 0; e < 2; ++e) {
          auto& slot = at_node[h.segment_nodes[s][e]];
          (slot[0] == kNoCurveNode ? slot[0] : slot[1]) = s;
        }
      std::vector<std::uint8_t> removed_node(h.node_count(), 0), merged_seg(h.segment_count(), 0);
      CurveGraph next;
      std::vector<std::uint32_t> next_curve;
      for (std::uint32_t v = 0; v < h.node_count(); ++v) {
        if (d[v] != 2) continue;
        const std::uint32_t s0 = at_node[v][0], s1 = at_node[v][1];
        if (s0 == s1 || merged_seg[s0] || merged_seg[s1]) continue;  // closed loop, or already merged this round
        // The two pieces oriented away from v.
        auto away = [&](std::uint32_t s) {
          std::vector<Vec3d> p(h.polyline(s).begin(), h.polyline(s).end());
          if (h.segment_nodes[s][0] != v) std::reverse(p.begin(), p.end());
          return p;
        };
        const std::vector<Vec3d> a = away(s0), b = away(s1);
        const double la = h.length(s0), lb = h.length(s1);
        const double step = 0.1 * std::min(la, lb);
        const EndShape ea = end_shape(a, step), eb = end_shape(b, step);
        const bool tangent_ok = -ea.tangent.dot(eb.tangent) >= cos_max;
        const double kmax = std::max({ea.curvature, eb.curvature, 1.0 / diag});
        const bool curvature_ok = std::abs(ea.curvature - eb.curvature) <= opt.merge_curvature * kmax;
        if (!(tangent_ok && curvature_ok)) continue;
        // Merge: b reversed (from its far end to v), then a (from v on).
        std::vector<Vec3d> m(b.rbegin(), b.rend());
        m.insert(m.end(), a.begin() + 1, a.end());
        const std::uint32_t from = h.segment_nodes[s1][h.segment_nodes[s1][0] == v ? 1 : 0];
        const std::uint32_t to = h.segment_nodes[s0][h.segment_nodes[s0][0] == v ? 1 : 0];
        merged_seg[s0] = merged_seg[s1] = 1;
        removed_node[v] = 1;
        next.add_segment(from, to, m, std::min(h.segment_curve[s0], h.segment_curve[s1]));
        ++rep.merges;
        changed = true;
      }
      if (!changed) break;
      for (std::uint32_t s = 0; s < h.segment_count(); ++s)
        if (!merged_seg[s])
          next.add_segment(h.segment_nodes[s][0], h.segment_nodes[s][1], h.polyline(s), h.segment_curve[s]);
      // Renumber nodes (drop removed ones), segments sorted by source curve
      // then first point so the order does not depend on the merge rounds.
      std::vector<std::uint32_t> remap(h.node_count(), kNoCurveNode);
      CurveGraph r;
      for (std::uint32_t v = 0; v < h.node_count(); ++v)
        if (!removed_node[v]) {
          remap[v] = static_cast<std::uint32_t>(r.nodes.size());
          r.nodes.push_back(h.nodes[v]);
        }
      for (std::uint32_t s = 0; s < next.segment_count(); ++s)
        r.add_segment(remap[next.segment_nodes[s][0]], remap[next.segment_nodes[s][1]], next.polyline(s),
                      next.segment_curve[s]);
      h = std::move(r);
    }
    const auto d = h.degrees();
    for (std::uint32_t v = 0; v < h.node_count(); ++v) rep.kinks += d[v] == 2;
  }
}

/// Canonical segment order: by source curve, then by where they start.
void canonical_order(CurveGraph& h) {
  {
    std::vector<std::uint32_t> order(h.segment_count());
    std::iota(order.begin(), order.end(), 0u);
    auto key = [&](std::uint32_t s) {
      const Vec3d& p = h.points[h.offsets[s]];
      const Vec3d& q = h.points[h.offsets[s] + 1];
      return std::make_tuple(h.segment_curve[s], p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), s);
    };
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
    CurveGraph r;
    r.nodes = h.nodes;
    for (std::uint32_t s : order)
      r.add_segment(h.segment_nodes[s][0], h.segment_nodes[s][1], h.polyline(s), h.segment_curve[s]);
    h = std::move(r);
  }
}

}  // namespace

Expected<TreatedCurves> treat_curves(const PolylineSet& in, const CurveTreatmentOptions& opt, const ExecContext& ctx) {
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "treat_curves: cancelled");
  if (in.size() == 0) return Status(ErrorCode::kInvalidArgument, "the curve network has no curve");
  if (!(opt.intersection_tolerance >= 0) || !(opt.merge_distance >= 0) || !(opt.cluster_length > 0))
    return Status(ErrorCode::kInvalidArgument, "treat_curves: tolerances must be non-negative");
  TreatedCurves out;
  CurveTreatmentReport& rep = out.report;
  rep.input_curves = in.size();
  rep.input_points = in.points.size();
  std::vector<Curve> curves;
  Box3d box;
  if (Status st = clean_curves(in, curves, box); !st) return st;
  const double diag = (box.hi - box.lo).norm();
  if (!(diag > 0) || !std::isfinite(diag))
    return Status(ErrorCode::kInvalidArgument, "the curve network is degenerate (all points coincide)");
  rep.diagonal = diag;
  const double tol = opt.intersection_tolerance * diag;
  const double cluster = opt.cluster_length * diag;
  rep.tolerance = tol;
  auto hits = find_hits(in, curves, tol, cluster);
  if (!hits) return hits.status();
  CurveGraph g = split_at_nodes(curves, *hits, tol, cluster, rep);
  join_free_ends(g, opt, diag, rep);
  CurveGraph h = prune_dangling(g, in, opt.prune_dangling, rep);
  if (h.segment_count() == 0)
    return Status(ErrorCode::kTopology, "the curve network has no cycle: every curve is a dangling end (" +
                                            std::to_string(rep.pruned_segments) + " pieces pruned)");
  merge_continuations(h, opt, diag, rep);
  canonical_order(h);
  out.graph = std::move(h);
  return out;
}

}  // namespace atelier
