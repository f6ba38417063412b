#include <atelier/storage/builder.h>

#include <algorithm>
#include <sstream>
#include <vector>

#include <atelier/engine/parallel.h>
#include <atelier/storage/topology.h>

namespace atelier {

namespace {
Status fail(ErrorCode c, const std::string& surface, const std::string& what) {
  return {c, "surface '" + surface + "': " + what};
}
}  // namespace

Expected<Surface> add_polygon_surface(Model& m, std::string name, const PolygonSoupView& a, const ExecContext& ctx) {
  const std::size_t nv = a.positions.size();
  if (a.face_offsets.empty())
    return fail(ErrorCode::kInvalidArgument, name, "face_offsets is empty (needs F+1 entries)");
  const std::size_t nf = a.face_offsets.size() - 1;
  if (a.face_offsets.front() != 0 || a.face_offsets.back() != a.face_nodes.size())
    return fail(ErrorCode::kInvalidArgument, name, "face_offsets must start at 0 and end at face_nodes.size()");
  for (std::size_t v = 0; v < nv; ++v)
    if (!a.positions[v].allFinite()) {
      std::ostringstream s;
      s << "node " << v << " has a non-finite position";
      return fail(ErrorCode::kDegenerate, name, s.str());
    }
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t b = a.face_offsets[f], e = a.face_offsets[f + 1];
    if (e < b + 3) {
      std::ostringstream s;
      s << "face " << f << " has " << (e >= b ? e - b : 0) << " nodes (at least 3 needed)";
      return fail(ErrorCode::kDegenerate, name, s.str());
    }
    for (std::uint32_t k = b; k < e; ++k) {
      if (a.face_nodes[k] >= nv) {
        std::ostringstream s;
        s << "face " << f << " refers to node " << a.face_nodes[k] << " but there are " << nv << " nodes";
        return fail(ErrorCode::kInvalidArgument, name, s.str());
      }
      for (std::uint32_t j = b; j < k; ++j)
        if (a.face_nodes[j] == a.face_nodes[k]) {
          std::ostringstream s;
          s << "face " << f << " uses node " << a.face_nodes[k] << " twice (degenerate face)";
          return fail(ErrorCode::kDegenerate, name, s.str());
        }
    }
  }

  // Corners grouped by their smaller end node (counting sort): each group is
  // tiny, so matching the two sides of an edge is a short scan.
  const std::size_t nc = a.face_nodes.size();
  std::vector<std::uint32_t> corner_face(nc);
  for (std::size_t f = 0; f < nf; ++f)
    for (std::uint32_t k = a.face_offsets[f]; k < a.face_offsets[f + 1]; ++k)
      corner_face[k] = static_cast<std::uint32_t>(f);
  auto corner_next = [&](std::size_t k) -> std::uint32_t {
    const std::uint32_t f = corner_face[k];
    return k + 1 < a.face_offsets[f + 1] ? a.face_nodes[k + 1] : a.face_nodes[a.face_offsets[f]];
  };
  std::vector<std::uint32_t> bucket_start(nv + 1, 0);
  for (std::size_t k = 0; k < nc; ++k) ++bucket_start[std::min(a.face_nodes[k], corner_next(k)) + 1];
  for (std::size_t v = 0; v < nv; ++v) bucket_start[v + 1] += bucket_start[v];
  std::vector<std::uint32_t> bucket(nc);
  {
    std::vector<std::uint32_t> fill(bucket_start.begin(), bucket_start.end() - 1);
    for (std::size_t k = 0; k < nc; ++k)
      bucket[fill[std::min(a.face_nodes[k], corner_next(k))]++] = static_cast<std::uint32_t>(k);
  }
  // Within a bucket, order corners by their larger end (then corner index),
  // so edge numbering is a pure function of the input.
  std::vector<std::uint32_t> corner_half(nc);  // corner -> local halfedge id 2*edge+side
  // The first corner of each edge writes both of its halfedges' tails (the
  // other corner, if any, would write the same values: a data race).
  std::vector<std::uint8_t> writes_tails(nc, 0);
  std::uint32_t n_edges = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    auto* first = bucket.data() + bucket_start[v];
    auto* last = bucket.data() + bucket_start[v + 1];
    std::sort(first, last, [&](std::uint32_t x, std::uint32_t y) {
      const auto mx = std::max(a.face_nodes[x], corner_next(x)), my = std::max(a.face_nodes[y], corner_next(y));
      return mx != my ? mx < my : x < y;
    });
    for (auto* it = first; it != last;) {
      const auto hi = std::max(a.face_nodes[*it], corner_next(*it));
      auto* run = it;
      while (run != last && std::max(a.face_nodes[*run], corner_next(*run)) == hi) ++run;
      const std::size_t count = static_cast<std::size_t>(run - it);
      if (count > 2) {
        std::ostringstream s;
        s << "edge (" << v << "," << hi << ") is shared by " << count << " faces (";
        for (auto* q = it; q != run; ++q) s << (q == it ? "" : ", ") << corner_face[*q];
        s << "); a surface allows two: put the extra faces in another surface and join them by a joint";
        return fail(ErrorCode::kNonManifold, name, s.str());
      }
      const bool fwd0 = a.face_nodes[*it] == v;
      if (count == 2 && fwd0 == (a.face_nodes[it[1]] == v)) {
        std::ostringstream s;
        s << "faces " << corner_face[it[0]] << " and " << corner_face[it[1]] << " traverse edge (" << v << "," << hi
          << ") in the same direction (inconsistent orientation)";
        return fail(ErrorCode::kNonManifold, name, s.str());
      }
      for (auto* q = it; q != run; ++q) corner_half[*q] = 2 * n_edges + (a.face_nodes[*q] == v ? 0u : 1u);
      writes_tails[*it] = 1;
      ++n_edges;
      it = run;
    }
  }

  // Allocate everything at once.
  Surface surf = m.add_surface(std::move(name));
  const SurfaceIdx s = surf.idx;
  const std::uint32_t v0 = m.nodes.slots.append_bulk(nv).value;
  m.sync_node_columns();
  const std::uint32_t e0 = m.edges.slots.append_bulk(n_edges).value;
  m.sync_edge_columns();
  const std::uint32_t f0 = m.faces.slots.append_bulk(nf).value;
  m.sync_face_columns();
  const std::uint32_t h0 = 2 * e0;

  par::for_each_n(ctx, nv, [&](std::size_t v) {
    m.nodes.position[v0 + v] = a.positions[v];
    m.nodes.surface[v0 + v] = s;
  });
  // Halfedge tails: forward side of local edge starts at its smaller node.
  par::for_each_n(ctx, nc, [&](std::size_t k) {
    const std::uint32_t lh = corner_half[k];
    const std::uint32_t va = a.face_nodes[k], vb = corner_next(k);
    const std::uint32_t lo = std::min(va, vb), hi = std::max(va, vb);
    if (writes_tails[k]) {
      const std::uint32_t he = lh & ~1u;
      m.halfedges.tail[h0 + he] = NodeIdx{v0 + lo};
      m.halfedges.tail[h0 + he + 1] = NodeIdx{v0 + hi};
    }
    const std::uint32_t f = corner_face[k];
    m.halfedges.face[h0 + lh] = FaceIdx{f0 + f};
    const std::uint32_t b = a.face_offsets[f], e = a.face_offsets[f + 1];
    const std::size_t kn = k + 1 < e ? k + 1 : b;
    const std::size_t kp = k > b ? k - 1 : e - 1;
    m.halfedges.next[h0 + lh] = HalfedgeIdx{h0 + corner_half[kn]};
    m.halfedges.prev[h0 + lh] = HalfedgeIdx{h0 + corner_half[kp]};
  });
  par::for_each_n(ctx, nf, [&](std::size_t f) {
    m.faces.halfedge[f0 + f] = HalfedgeIdx{h0 + corner_half[a.face_offsets[f]]};
    m.faces.surface[f0 + f] = s;
  });
  // Node rings: outgoing halfedges in increasing index order (counting sort
  // by tail keeps index order within each node).
  {
    const std::size_t nh = 2 * std::size_t{n_edges};
    std::vector<std::uint32_t> start(nv + 1, 0);
    for (std::size_t h = 0; h < nh; ++h) ++start[m.halfedges.tail[h0 + h].value - v0 + 1];
    for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<std::uint32_t> order(nh);
    {
      std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
      for (std::size_t h = 0; h < nh; ++h)
        order[fill[m.halfedges.tail[h0 + h].value - v0]++] = h0 + static_cast<std::uint32_t>(h);
    }
    par::for_each_n(ctx, nv, [&](std::size_t v) {
      const std::uint32_t b = start[v], e = start[v + 1];
      if (b == e) return;
      m.nodes.out[v0 + v] = HalfedgeIdx{order[b]};
      for (std::uint32_t k = b; k < e; ++k) {
        const std::uint32_t nxt = k + 1 < e ? k + 1 : b;
        m.halfedges.vnext[order[k]] = HalfedgeIdx{order[nxt]};
        m.halfedges.vprev[order[nxt]] = HalfedgeIdx{order[k]};
      }
    });
  }
  ++m.topology_version;
  const TopologyCounts c = count_topology(m, s);
  m.complex_holes += c.implied_holes();
  return surf;
}

PolygonSoup polygon_soup(const Model& m, SurfaceIdx only) {
  PolygonSoup s;
  s.positions.assign(m.nodes.position.begin(), m.nodes.position.begin() + m.nodes.slots.capacity());
  const auto uv = m.halfedges.props.find<Vec2d>("corner_uv");
  std::vector<HalfedgeIdx> fh;
  std::vector<std::uint32_t> ids;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f}) || (only.valid() && m.faces.surface[f] != only)) continue;
    m.face_halfedges(FaceIdx{f}, fh);
    ids.clear();
    for (HalfedgeIdx h : fh) {
      ids.push_back(m.tail(h).value);
      if (uv.valid()) s.corner_uv.push_back(uv[h]);
    }
    s.add_face(ids);
  }
  return s;
}

}  // namespace atelier
