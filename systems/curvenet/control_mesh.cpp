#include <atelier/systems/curvenet/control_mesh.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include <atelier/engine/parallel.h>
#include <atelier/systems/curvenet/bspline.h>

namespace atelier {

namespace {

constexpr std::uint32_t kRoot = 0xfffffffeu;  // the outer cycles, as one face of free parity

/// Knots making every face even (a T-join on the faces' adjacency).
std::vector<std::uint8_t> parity_knots(const CurveGraph& g, const FaceCycles& fc, const std::vector<std::size_t>& count,
                                       std::size_t* odd_before, std::string* error) {
  const std::size_t ns = g.segment_count(), nf = fc.face_count();
  std::vector<std::uint32_t> dart_face(2 * ns, kRoot);
  std::vector<std::uint8_t> odd(nf, 0);
  for (std::uint32_t f = 0; f < nf; ++f) {
    std::size_t edges = 0;
    for (std::uint32_t d : fc.face(f)) {
      dart_face[d] = f;
      edges += count[d >> 1] - 1;
    }
    odd[f] = edges % 2;
  }
  *odd_before = static_cast<std::size_t>(std::count(odd.begin(), odd.end(), 1));
  std::vector<std::uint8_t> knot(ns, 0);
  auto flip = [&](std::uint32_t s) {
    knot[s] ^= 1u;
    for (std::uint32_t d : {2 * s, 2 * s + 1})
      if (dart_face[d] != kRoot) odd[dart_face[d]] ^= 1u;
  };
  // Prefer the segments whose polygon edges are longest.
  std::vector<std::uint32_t> order(ns);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<double> edge_len(ns);
  for (std::uint32_t s = 0; s < ns; ++s) edge_len[s] = g.length(s) / static_cast<double>(count[s] - 1);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return edge_len[a] > edge_len[b]; });
  for (std::uint32_t s : order) {  // two odd faces side by side
    const std::uint32_t a = dart_face[2 * s], b = dart_face[2 * s + 1];
    if (a != kRoot && b != kRoot && a != b && odd[a] && odd[b]) flip(s);
  }
  for (std::uint32_t s : order) {  // an odd face on the outer boundary
    const std::uint32_t a = dart_face[2 * s], b = dart_face[2 * s + 1];
    if ((a == kRoot) != (b == kRoot) && odd[a == kRoot ? b : a]) flip(s);
  }
  // The rest along a breadth-first spanning tree of the faces.
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> adj(nf + 1);  // node nf = root
  auto node = [&](std::uint32_t f) { return f == kRoot ? static_cast<std::uint32_t>(nf) : f; };
  for (std::uint32_t s : order) {
    const std::uint32_t a = node(dart_face[2 * s]), b = node(dart_face[2 * s + 1]);
    if (a == b) continue;
    adj[a].emplace_back(s, b);
    adj[b].emplace_back(s, a);
  }
  std::vector<std::uint32_t> parent_seg(nf + 1, kRoot), parent(nf + 1, kRoot), bfs;
  std::vector<std::uint8_t> seen(nf + 1, 0);
  for (std::uint32_t r = 0; r <= nf; ++r) {
    const std::uint32_t root = r == 0 ? static_cast<std::uint32_t>(nf) : r - 1;  // the outer node first
    if (seen[root]) continue;
    seen[root] = 1;
    bfs.push_back(root);
    for (std::size_t q = bfs.size() - 1; q < bfs.size(); ++q)
      for (const auto& [s, w] : adj[bfs[q]])
        if (!seen[w]) {
          seen[w] = 1;
          parent[w] = bfs[q];
          parent_seg[w] = s;
          bfs.push_back(w);
        }
  }
  for (std::size_t q = bfs.size(); q-- > 0;) {
    const std::uint32_t f = bfs[q];
    if (f == nf || !odd[f] || parent[f] == kRoot) continue;
    flip(parent_seg[f]);
  }
  for (std::uint32_t f = 0; f < nf; ++f)
    if (odd[f]) {
      *error =
          "face cycle " + std::to_string(f) + " keeps an odd number of polygon edges (no segment to insert a knot on)";
      break;
    }
  return knot;
}

}  // namespace

Expected<ControlMesh> build_control_mesh(const CurveGraph& g, const FaceCycles& fc, const ControlMeshOptions& opt,
                                         const ExecContext& ctx) {
  if (opt.n0 < 2 || !(opt.C >= 0) || !std::isfinite(opt.C) || opt.max_points < opt.n0)
    return Status(ErrorCode::kInvalidArgument, "control mesh: need n0 >= 2, C >= 0 and max_points >= n0");
  const std::size_t ns = g.segment_count(), nv = g.node_count(), nf = fc.face_count();
  if (ns == 0 || nf == 0) return Status(ErrorCode::kTopology, "control mesh: the network has no face");
  // The cycles must bound a surface: each segment side in at most one face
  // (the paper's search can validate overlapping cycles).
  {
    std::vector<std::uint32_t> use(2 * ns, 0);
    for (std::uint32_t d : fc.darts)
      if (++use[d] > 1 || use[d ^ 1u] > 1)
        return Status(ErrorCode::kTopology,
                      "control mesh: the face cycles overlap: segment " + std::to_string(d >> 1) +
                          " (a piece of the input curve at index " + std::to_string(g.segment_curve[d >> 1]) +
                          ") runs the same way in two of them");
  }
  ControlMesh out;
  // 1. Density, eq. (1).
  std::vector<double> len(ns);
  for (std::size_t s = 0; s < ns; ++s) len[s] = g.length(s);
  const double L0 = *std::min_element(len.begin(), len.end());
  if (!(L0 > 0)) return Status(ErrorCode::kDegenerate, "control mesh: a segment has zero length");
  out.shortest_segment = L0;
  double C = opt.C;
  if (C == 0) {
    std::vector<double> sorted = len;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(ns / 2), sorted.end());
    C = L0 / (2.0 * sorted[ns / 2]);
  }
  out.C = C;
  std::vector<std::size_t> count(ns);
  for (std::size_t s = 0; s < ns; ++s) {
    const double n = std::round(static_cast<double>(opt.n0) * C * len[s] / L0);
    count[s] = std::clamp(static_cast<std::size_t>(std::min(n, 1e9)), opt.n0, opt.max_points);
    // A closed segment needs a polygon of at least 3 edges to bound anything.
    if (g.segment_nodes[s][0] == g.segment_nodes[s][1]) count[s] = std::max<std::size_t>(count[s], 4);
  }
  // Accuracy: more points where eq. (1) cannot follow the curve.
  if (opt.fit_tolerance > 0) {
    Box3d box;
    for (const Vec3d& p : g.points) box.extend(p);
    const double tol = opt.fit_tolerance * (box.hi - box.lo).norm();
    std::vector<std::uint8_t> raised(ns, 0);
    par::for_each_n(ctx, ns, [&](std::size_t s) {
      while (count[s] < opt.max_points &&
             crease_fit_error(g.polyline(s), fit_crease_polygon(g.polyline(s), count[s])) > tol) {
        count[s] = std::min(opt.max_points, count[s] + std::max<std::size_t>(1, count[s] / 2));
        raised[s] = 1;
      }
    });
    out.raised_segments = static_cast<std::size_t>(std::count(raised.begin(), raised.end(), 1));
  }
  // 2. Parity.
  std::string parity_error;
  const auto knot = parity_knots(g, fc, count, &out.odd_faces, &parity_error);
  if (!parity_error.empty()) return Status(ErrorCode::kTopology, "control mesh: " + parity_error);
  for (std::size_t s = 0; s < ns; ++s) {
    count[s] += knot[s];
    out.knots_inserted += knot[s];
  }
  // 3. Control polygons (fitted in parallel; numbering is by segment order).
  std::vector<std::vector<Vec3d>> polygon(ns);
  std::vector<double> fit_error(ns, 0.0);
  par::for_each_n(ctx, ns, [&](std::size_t s) {
    polygon[s] = fit_crease_polygon(g.polyline(s), count[s]);
    fit_error[s] = crease_fit_error(g.polyline(s), polygon[s]);
  });
  out.max_fit_error = *std::max_element(fit_error.begin(), fit_error.end());
  PolygonSoup& mesh = out.mesh;
  mesh.positions = g.nodes;
  for (std::size_t s = 0; s < ns; ++s) {
    out.segment_vertices.push_back(g.segment_nodes[s][0]);
    for (std::size_t i = 1; i + 1 < polygon[s].size(); ++i) {
      out.segment_vertices.push_back(static_cast<std::uint32_t>(mesh.positions.size()));
      mesh.positions.push_back(polygon[s][i]);
    }
    out.segment_vertices.push_back(g.segment_nodes[s][1]);
    out.segment_offsets.push_back(static_cast<std::uint32_t>(out.segment_vertices.size()));
    for (std::uint32_t k = out.segment_offsets[s]; k + 1 < out.segment_offsets[s + 1]; ++k)
      out.creases.push_back({out.segment_vertices[k], out.segment_vertices[k + 1]});
  }
  out.network_vertices = mesh.positions.size();
  {
    std::vector<std::uint32_t> loops_only(nv, 0), degree(nv, 0);
    for (std::size_t s = 0; s < ns; ++s) {
      ++degree[g.segment_nodes[s][0]];
      ++degree[g.segment_nodes[s][1]];
      if (g.segment_nodes[s][0] == g.segment_nodes[s][1]) loops_only[g.segment_nodes[s][0]] += 2;
    }
    for (std::uint32_t v = 0; v < nv; ++v)
      if (!(degree[v] == 2 && loops_only[v] == 2)) out.corners.push_back(v);
  }
  // 4. Quadrangulate every face cycle (in parallel), assemble in face order.
  std::vector<std::vector<std::uint32_t>> loops(nf);
  for (std::size_t f = 0; f < nf; ++f)
    for (std::uint32_t d : fc.face(f)) {
      const std::uint32_t s = d >> 1;
      const std::uint32_t b = out.segment_offsets[s], e = out.segment_offsets[s + 1];
      if ((d & 1u) == 0)
        for (std::uint32_t k = b; k + 1 < e; ++k) loops[f].push_back(out.segment_vertices[k]);
      else
        for (std::uint32_t k = e - 1; k > b; --k) loops[f].push_back(out.segment_vertices[k]);
    }
  // Faces around each network vertex: a chord of face f between two
  // vertices that also bound another face g could be made by g too.
  std::vector<std::vector<std::uint32_t>> faces_at(out.network_vertices);
  for (std::uint32_t f = 0; f < nf; ++f)
    for (std::uint32_t v : loops[f])
      if (faces_at[v].empty() || faces_at[v].back() != f) faces_at[v].push_back(f);
  std::vector<QuadPatch> patches(nf);
  std::vector<Status> errors(nf);
  ExecContext fine = ctx;
  fine.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 64);
  fine.grain = 8;
  par::for_each_n(fine, nf, [&](std::size_t f) {
    std::vector<Vec3d> b;
    b.reserve(loops[f].size());
    for (std::uint32_t v : loops[f]) b.push_back(mesh.positions[v]);
    const ChordFilter shared = [&](std::uint32_t x, std::uint32_t y) {
      for (std::uint32_t g1 : faces_at[loops[f][x]])
        if (g1 != f)
          for (std::uint32_t g2 : faces_at[loops[f][y]])
            if (g1 == g2) return true;
      return false;
    };
    auto p = quadrangulate_cycle(b, opt.quadrangulate, shared);
    if (p)
      patches[f] = std::move(p).value();
    else
      errors[f] = Status(p.status().code(), "face cycle " + std::to_string(f) + ": " + p.status().message());
  });
  for (const Status& s : errors)
    if (!s) return s;
  out.fixed.assign(out.network_vertices, 1);
  for (std::size_t f = 0; f < nf; ++f) {
    const QuadPatch& p = patches[f];
    const auto b = static_cast<std::uint32_t>(loops[f].size());
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), p.interior.begin(), p.interior.end());
    out.fixed.resize(mesh.positions.size(), 0);
    for (const auto& q : p.quads) {
      std::array<std::uint32_t, 4> gq{};
      for (int k = 0; k < 4; ++k)
        gq[static_cast<std::size_t>(k)] = q[static_cast<std::size_t>(k)] < b
                                              ? loops[f][q[static_cast<std::size_t>(k)]]
                                              : base + (q[static_cast<std::size_t>(k)] - b);
      mesh.add_face(gq);
    }
    out.face_quads.push_back(static_cast<std::uint32_t>(mesh.face_count()));
    out.face_boundary.push_back(b);
    out.face_interior.push_back(static_cast<std::uint32_t>(p.interior.size()));
  }
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "control mesh: cancelled");
  // 5. Fairing with the network fixed.
  if (opt.fair) {
    auto r = fair_quad_mesh(mesh.positions, mesh, out.fixed, opt.fairing, ctx);
    if (!r) return Status(r.status().code(), "control mesh: " + r.status().message());
    out.fairing = *r;
    out.fairing_energy_before = r->energy_before;
    out.fairing_energy_after = r->energy_after;
  }
  auto newell = [&](auto&& at, std::size_t n) {
    Vec3d a = Vec3d::Zero();
    for (std::size_t i = 0; i < n; ++i) a += at(i).cross(at((i + 1) % n));
    return a;
  };
  for (std::size_t f = 0; f < nf; ++f) {
    const Vec3d af = newell([&](std::size_t i) { return mesh.positions[loops[f][i]]; }, loops[f].size());
    for (std::uint32_t q = out.face_quads[f]; q < out.face_quads[f + 1]; ++q) {
      const auto c = mesh.face(q);
      if (newell([&](std::size_t i) { return mesh.positions[c[i]]; }, c.size()).dot(af) < 0) ++out.inverted_quads;
    }
  }
  return out;
}

}  // namespace atelier
