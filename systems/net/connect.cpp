// Connecting nets by meshes (seed 004 section 4): the strip rules as one
// dynamic programme over monotone grid paths, and branching.
#include <atelier/systems/net/connect.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "boolean_detail.h"

namespace atelier {

namespace {

using net_detail::fail;

struct Step {
  int di, dj;
  double penalty;  // the rule's cost of a mesh of this kind
};

struct Rule {
  int target = 6;  // regular valence
  bool p_side = true, q_side = true;
  bool count_only = false;  // cost 1 per irregular vertex instead of (v - target)^2
  double valence_weight = 0;
  double length_weight = 1;
  std::vector<Step> steps;
};

Rule rule_of(ConnectRule r) {
  Rule x;
  const std::vector<Step> tri = {{1, 0, 0.0}, {0, 1, 0.0}};
  switch (r) {
    case ConnectRule::kTriShortest:
      x.steps = tri;
      break;
    case ConnectRule::kTriOneSided:
      x.steps = tri, x.q_side = false, x.valence_weight = 1, x.length_weight = 0.1;
      break;
    case ConnectRule::kTriTwoSided:
      x.steps = tri, x.valence_weight = 1, x.length_weight = 1e-4;
      break;
    case ConnectRule::kQuadValence:
      x.target = 4, x.valence_weight = 1, x.length_weight = 1e-4;
      x.steps = {{1, 1, 0.0}, {2, 0, 0.0}, {0, 2, 0.0}, {1, 0, 1.0}, {0, 1, 1.0}};
      break;
    case ConnectRule::kQuadRegularVertices:
      x.target = 4, x.count_only = true, x.valence_weight = 1, x.length_weight = 1e-4;
      x.steps = {{1, 1, 0.0},  {2, 0, 0.0},  {0, 2, 0.0},  {1, 0, 0.25}, {0, 1, 0.25},
                 {3, 0, 0.25}, {0, 3, 0.25}, {2, 1, 0.25}, {1, 2, 0.25}};
      break;
    case ConnectRule::kQuadRegularMeshes:
      x.target = 4, x.count_only = true, x.valence_weight = 0.1, x.length_weight = 1e-4;
      x.steps = {{1, 1, 0.0}, {2, 0, 0.0}, {0, 2, 0.0}, {1, 0, 100.0}, {0, 1, 100.0}};
      break;
  }
  return x;
}

bool quad_rule(ConnectRule r) {
  return r >= ConnectRule::kQuadValence;
}

Status check(std::span<const Vec3d> positions, const BoundaryPolygon& p, const char* name) {
  if (p.vertices.size() < 3)
    return fail(ErrorCode::kInvalidArgument, "connect: polygon ", name, " has fewer than 3 vertices");
  if (!p.valence.empty() && p.valence.size() != p.vertices.size())
    return fail(ErrorCode::kInvalidArgument, "connect: polygon ", name, " has ", p.valence.size(), " valences for ",
                p.vertices.size(), " vertices");
  for (std::size_t i = 0; i < p.vertices.size(); ++i) {
    if (p.vertices[i] >= positions.size())
      return fail(ErrorCode::kInvalidArgument, "connect: polygon ", name, " names vertex ", p.vertices[i], " of ",
                  positions.size());
    if (!is_finite(positions[p.vertices[i]]))
      return fail(ErrorCode::kDegenerate, "connect: vertex ", p.vertices[i], " is not finite");
  }
  return {};
}

}  // namespace

Expected<ConnectRule> parse_connect_rule(std::string_view s) {
  if (s == "a") return ConnectRule::kTriShortest;
  if (s == "b") return ConnectRule::kTriOneSided;
  if (s == "c") return ConnectRule::kTriTwoSided;
  if (s == "i") return ConnectRule::kQuadValence;
  if (s == "ii") return ConnectRule::kQuadRegularVertices;
  if (s == "iii") return ConnectRule::kQuadRegularMeshes;
  return Status(ErrorCode::kInvalidArgument, "unknown connecting rule '" + std::string(s) + "' (a, b, c, i, ii, iii)");
}

Expected<ConnectReport> connect_polygons(std::span<const Vec3d> pos, const BoundaryPolygon& p, const BoundaryPolygon& q,
                                         const ConnectOptions& opt) {
  if (Status s = check(pos, p, "P"); !s) return s;
  if (Status s = check(pos, q, "Q"); !s) return s;
  const Rule rule = rule_of(opt.rule);
  const int m = static_cast<int>(p.vertices.size()), n = static_cast<int>(q.vertices.size());
  const std::uint32_t boundary_valence = quad_rule(opt.rule) ? 3u : 4u;
  // Q runs against P: walk it backwards from the vertex closest to p_0.
  int j0 = 0;
  double best = std::numeric_limits<double>::infinity();
  for (int j = 0; j < n; ++j) {
    const double d = (pos[q.vertices[static_cast<std::size_t>(j)]] - pos[p.vertices[0]]).squaredNorm();
    if (d < best) best = d, j0 = j;
  }
  auto qi = [&](int j) { return static_cast<std::size_t>(((j0 - j) % n + n) % n); };
  auto P = [&](int i) { return p.vertices[static_cast<std::size_t>(i % m)]; };
  auto Q = [&](int j) { return q.vertices[qi(j)]; };
  auto pv = [&](int i) { return p.valence.empty() ? boundary_valence : p.valence[static_cast<std::size_t>(i % m)]; };
  auto qv = [&](int j) { return q.valence.empty() ? boundary_valence : q.valence[qi(j)]; };
  double mean = 0;
  for (int i = 0; i < m; ++i) mean += (pos[P(i + 1)] - pos[P(i)]).norm();
  for (int j = 0; j < n; ++j) mean += (pos[Q(j + 1)] - pos[Q(j)]).norm();
  mean /= m + n;
  if (!(mean > 0)) mean = 1;
  auto vcost = [&](std::uint32_t valence, bool side) {
    if (!side || rule.valence_weight == 0) return 0.0;
    const double d = static_cast<double>(valence) - rule.target;
    return rule.valence_weight * (rule.count_only ? (d != 0 ? 1.0 : 0.0) : d * d);
  };
  auto rowcost = [&](int i, int run) { return vcost(pv(i) + static_cast<std::uint32_t>(run), rule.p_side); };
  auto colcost = [&](int j, int run) { return vcost(qv(j) + static_cast<std::uint32_t>(run), rule.q_side); };
  auto rung = [&](int i, int j) { return (pos[P(i)] - pos[Q(j)]).norm() / mean; };

  // State (i, j, d, r): at node (i, j), the run of the current row (d = 0)
  // or column (d = 1) is r; the other run is 1.
  int K = rule.valence_weight == 0 ? 1 : std::max(1, opt.max_run);
  const std::size_t nodes = static_cast<std::size_t>(m + 1) * static_cast<std::size_t>(n + 1);
  while (K > 2 && nodes * 2 * static_cast<std::size_t>(K + 1) > 60'000'000) --K;
  if (nodes * 2 * static_cast<std::size_t>(K + 1) > 120'000'000)
    return fail(ErrorCode::kInvalidArgument, "connect: polygons of ", m, " and ", n, " vertices are too large");
  const std::size_t per_node = 2 * static_cast<std::size_t>(K + 1);
  auto sid = [&](int i, int j, int d, int r) {
    return (static_cast<std::size_t>(i) * static_cast<std::size_t>(n + 1) + static_cast<std::size_t>(j)) * per_node +
           static_cast<std::size_t>(d) * static_cast<std::size_t>(K + 1) + static_cast<std::size_t>(r);
  };
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> cost(nodes * per_node, inf);
  std::vector<std::uint32_t> from(nodes * per_node, 0xffffffffu);
  std::vector<std::uint8_t> via(nodes * per_node, 0);
  cost[sid(0, 0, 0, 1)] = 0;
  for (int i = 0; i <= m; ++i)
    for (int j = 0; j <= n; ++j)
      for (int d = 0; d < 2; ++d)
        for (int r = 1; r <= K; ++r) {
          const std::size_t s = sid(i, j, d, r);
          if (cost[s] == inf) continue;
          const int row_run = d == 0 ? r : 1, col_run = d == 1 ? r : 1;
          for (std::size_t k = 0; k < rule.steps.size(); ++k) {
            const Step& st = rule.steps[k];
            const int ni = i + st.di, nj = j + st.dj;
            if (ni > m || nj > n || st.di >= m || st.dj >= n) continue;
            double c = cost[s] + st.penalty + rule.length_weight * rung(ni, nj);
            int nd = 0, nr = 1;
            if (st.di > 0) {
              c += rowcost(i, row_run);
              for (int x = i + 1; x < ni; ++x) c += rowcost(x, 0);
            }
            if (st.dj > 0) {
              c += colcost(j, col_run);
              for (int x = j + 1; x < nj; ++x) c += colcost(x, 0);
            }
            if (st.di > 0 && st.dj == 0) nd = 1, nr = std::min(K, col_run + 1);
            if (st.dj > 0 && st.di == 0) nd = 0, nr = std::min(K, row_run + 1);
            const std::size_t t = sid(ni, nj, nd, nr);
            if (c < cost[t]) {
              cost[t] = c;
              from[t] = static_cast<std::uint32_t>(s);
              via[t] = static_cast<std::uint8_t>(k);
            }
          }
        }
  // End at (m, n), the seam edge p_0 q_j0 again: close its row and column.
  double total = inf;
  std::size_t end = 0;
  for (int d = 0; d < 2; ++d)
    for (int r = 1; r <= K; ++r) {
      const std::size_t s = sid(m, n, d, r);
      if (cost[s] == inf) continue;
      const double c = cost[s] + rowcost(m, d == 0 ? r : 1) + colcost(n, d == 1 ? r : 1);
      if (c < total) total = c, end = s;
    }
  if (total == inf)
    return fail(ErrorCode::kInvalidArgument, "connect: no strip of the rule's meshes joins polygons of ", m, " and ", n,
                " vertices");
  std::vector<std::uint8_t> steps;
  for (std::size_t s = end; s != sid(0, 0, 0, 1); s = from[s]) steps.push_back(via[s]);
  std::reverse(steps.begin(), steps.end());

  ConnectReport rep;
  rep.cost = total;
  std::vector<std::array<std::uint32_t, 2>> rungs;
  int i = 0, j = 0;
  rungs.push_back({P(0), Q(0)});
  for (std::uint8_t k : steps) {
    const Step& st = rule.steps[k];
    std::vector<std::uint32_t> face;
    for (int x = 0; x <= st.di; ++x) face.push_back(P(i + x));
    for (int y = st.dj; y >= 0; --y) face.push_back(Q(j + y));
    rep.faces.add_face(face);
    (face.size() == 3 ? rep.triangles : (face.size() == 4 ? rep.quads : rep.other))++;
    i += st.di;
    j += st.dj;
    if (i < m || j < n) rungs.push_back({P(i), Q(j)});
  }
  std::vector<std::uint32_t> extra_p(static_cast<std::size_t>(m), 0), extra_q(static_cast<std::size_t>(n), 0);
  for (const auto& r : rungs) {
    rep.new_edge_length += (pos[r[0]] - pos[r[1]]).norm();
    for (int x = 0; x < m; ++x)
      if (P(x) == r[0]) ++extra_p[static_cast<std::size_t>(x)];
    for (int y = 0; y < n; ++y)
      if (Q(y) == r[1]) ++extra_q[static_cast<std::size_t>(y)];
  }
  const std::uint32_t target = quad_rule(opt.rule) ? 4u : 6u;
  for (int x = 0; x < m; ++x) rep.irregular_vertices += pv(x) + extra_p[static_cast<std::size_t>(x)] != target;
  for (int y = 0; y < n; ++y) rep.irregular_vertices += qv(y) + extra_q[static_cast<std::size_t>(y)] != target;
  return rep;
}

Expected<ConnectReport> connect_branching(std::span<const Vec3d> pos, const BoundaryPolygon& p,
                                          std::span<const BoundaryPolygon> qs, const ConnectOptions& opt) {
  if (Status s = check(pos, p, "P"); !s) return s;
  if (qs.empty()) return fail(ErrorCode::kInvalidArgument, "connect: no polygon to connect to");
  if (qs.size() == 1) return connect_polygons(pos, p, qs[0], opt);
  for (const BoundaryPolygon& q : qs)
    if (Status s = check(pos, q, "Q"); !s) return s;
  const std::size_t m = p.vertices.size(), k = qs.size();
  // Each vertex of P goes to its nearest facing polygon; runs of one owner
  // are the arcs, short runs merged into their neighbours until each
  // polygon owns one arc.
  std::vector<std::size_t> owner(m);
  for (std::size_t i = 0; i < m; ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t l = 0; l < k; ++l)
      for (std::uint32_t v : qs[l].vertices) {
        const double d = (pos[v] - pos[p.vertices[i]]).squaredNorm();
        if (d < best) best = d, owner[i] = l;
      }
  }
  for (int guard = 0; guard < static_cast<int>(m); ++guard) {
    // Runs (start index, length) around the loop.
    std::vector<std::pair<std::size_t, std::size_t>> runs;
    std::size_t start = 0;
    while (start < m && owner[start] == owner[(start + m - 1) % m]) ++start;
    if (start == m) break;  // one owner only
    for (std::size_t c = 0; c < m;) {
      const std::size_t s = (start + c) % m;
      std::size_t len = 1;
      while (c + len < m && owner[(start + c + len) % m] == owner[s]) ++len;
      runs.emplace_back(s, len);
      c += len;
    }
    std::vector<std::size_t> arcs(k, 0);
    for (const auto& r : runs) ++arcs[owner[r.first]];
    if (runs.size() == k && std::all_of(arcs.begin(), arcs.end(), [](std::size_t a) { return a == 1; })) break;
    // Merge the shortest run whose owner has several runs into its predecessor.
    std::size_t victim = runs.size();
    for (std::size_t r = 0; r < runs.size(); ++r)
      if (arcs[owner[runs[r].first]] > 1 && (victim == runs.size() || runs[r].second < runs[victim].second)) victim = r;
    if (victim == runs.size()) break;
    const std::size_t prev_owner = owner[runs[(victim + runs.size() - 1) % runs.size()].first];
    for (std::size_t c = 0; c < runs[victim].second; ++c) owner[(runs[victim].first + c) % m] = prev_owner;
  }
  // Arc boundaries: vertex i starts an arc when its owner differs from i-1's.
  std::vector<std::size_t> starts;
  for (std::size_t i = 0; i < m; ++i)
    if (owner[i] != owner[(i + m - 1) % m]) starts.push_back(i);
  if (starts.size() != k)
    return fail(ErrorCode::kUnsupported, "connect: branching polygon of ", m, " vertices cannot be split into ", k,
                " arcs, one per facing polygon");
  ConnectReport rep;
  for (std::size_t a = 0; a < k; ++a) {
    const std::size_t s = starts[a], e = starts[(a + 1) % k];
    BoundaryPolygon part;
    for (std::size_t i = s;; i = (i + 1) % m) {
      part.vertices.push_back(p.vertices[i]);
      if (!p.valence.empty()) part.valence.push_back(p.valence[i] + ((i == s || i == e) ? 1u : 0u));
      if (i == e) break;
    }
    auto r = connect_polygons(pos, part, qs[owner[s]], opt);
    if (!r) return r.status();
    for (std::size_t f = 0; f < r->faces.face_count(); ++f) rep.faces.add_face(r->faces.face(f));
    rep.triangles += r->triangles, rep.quads += r->quads, rep.other += r->other;
    rep.irregular_vertices += r->irregular_vertices;
    rep.new_edge_length += r->new_edge_length;
    rep.cost += r->cost;
  }
  if (k >= 3) {
    std::vector<std::uint32_t> middle;
    for (std::size_t a = 0; a < k; ++a) middle.push_back(p.vertices[starts[a]]);
    rep.faces.add_face(middle);
    ++(k == 3 ? rep.triangles : (k == 4 ? rep.quads : rep.other));
  }
  return rep;
}

}  // namespace atelier
