#include <atelier/systems/curvenet/corner_mesh.h>

#include <algorithm>
#include <string>

#include <atelier/engine/parallel.h>

namespace atelier {

std::uint32_t CornerMesh::find_edge(std::uint32_t a, std::uint32_t b) const noexcept {
  for (std::uint32_t k = vert_offsets[a]; k < vert_offsets[a + 1]; ++k) {
    const std::uint32_t c = vert_corners[k];
    if (face_verts[next_corner(c)] == b) return corner_edge[c];
    if (face_verts[prev_corner(c)] == b) return corner_edge[prev_corner(c)];
  }
  return kNoCorner;
}

bool CornerMesh::ring(std::uint32_t v, std::vector<std::uint32_t>& out) const {
  out.clear();
  if (vert_offsets[v] == vert_offsets[v + 1]) return false;
  // Walk backwards to a boundary first so an open fan is listed whole.
  std::uint32_t start = vert_corners[vert_offsets[v]];
  const std::size_t n = vert_offsets[v + 1] - vert_offsets[v];
  bool closed = true;
  for (std::size_t guard = 0; guard <= n; ++guard) {
    // The corner before `start` around v: across start's outgoing edge.
    const std::uint32_t e = corner_edge[start];
    const auto& ec = edge_corners[e];
    const std::uint32_t other = ec[0] == start ? ec[1] : ec[0];
    if (other == kNoCorner) {
      closed = false;
      break;
    }
    start = next_corner(other);  // the corner at v in the neighbouring face
    if (start == vert_corners[vert_offsets[v]]) break;
  }
  // Forwards: neighbour across the outgoing edge, then the face across the
  // incoming edge.
  std::uint32_t c = start;
  for (std::size_t guard = 0; guard < n; ++guard) {
    out.push_back(face_verts[next_corner(c)]);
    const std::uint32_t in = corner_edge[prev_corner(c)];
    const auto& ec = edge_corners[in];
    const std::uint32_t p = prev_corner(c);
    const std::uint32_t other = ec[0] == p ? ec[1] : ec[0];
    if (other == kNoCorner) {
      out.push_back(face_verts[p]);  // the last neighbour of an open fan
      return false;
    }
    c = other;  // its face has the edge v -> prev, so `other` is the corner at v
    if (c == start) return closed;
  }
  return closed;
}

Expected<CornerMesh> build_corner_mesh(const PolygonSoupView& soup, std::size_t vertex_count, const ExecContext& ctx) {
  CornerMesh m;
  const std::size_t nf = soup.face_count();
  if (soup.face_offsets.empty() || soup.face_offsets[0] != 0 || soup.face_offsets.back() != soup.face_nodes.size())
    return Status(ErrorCode::kInvalidArgument,
                  "corner mesh: face offsets do not start at 0 and end at the corner count");
  if (vertex_count >= kNoCorner || soup.face_nodes.size() >= kNoCorner)
    return Status(ErrorCode::kInvalidArgument, "corner mesh: more than 2^32 - 2 vertices or corners");
  m.vertex_count = static_cast<std::uint32_t>(vertex_count);
  m.face_offsets.assign(soup.face_offsets.begin(), soup.face_offsets.end());
  m.face_verts.assign(soup.face_nodes.begin(), soup.face_nodes.end());
  const std::size_t nc = m.face_verts.size();
  m.corner_face.resize(nc);
  for (std::uint32_t f = 0; f < nf; ++f) {
    const std::uint32_t b = m.face_offsets[f], e = m.face_offsets[f + 1];
    if (e < b + 3)
      return Status(ErrorCode::kInvalidArgument,
                    "corner mesh: face " + std::to_string(f) + " has fewer than 3 corners");
    for (std::uint32_t c = b; c < e; ++c) {
      if (m.face_verts[c] >= vertex_count)
        return Status(ErrorCode::kInvalidArgument, "corner mesh: face " + std::to_string(f) + " uses vertex " +
                                                       std::to_string(m.face_verts[c]) + " of " +
                                                       std::to_string(vertex_count));
      for (std::uint32_t d = b; d < c; ++d)
        if (m.face_verts[d] == m.face_verts[c])
          return Status(ErrorCode::kInvalidArgument, "corner mesh: face " + std::to_string(f) + " repeats vertex " +
                                                         std::to_string(m.face_verts[c]));
      m.corner_face[c] = f;
    }
  }
  // Vertex -> corners by counting sort (corner order kept: deterministic).
  m.vert_offsets.assign(vertex_count + 1, 0);
  for (std::uint32_t v : m.face_verts) ++m.vert_offsets[v + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) m.vert_offsets[v + 1] += m.vert_offsets[v];
  m.vert_corners.resize(nc);
  {
    std::vector<std::uint32_t> fill(m.vert_offsets.begin(), m.vert_offsets.end() - 1);
    for (std::uint32_t c = 0; c < nc; ++c) m.vert_corners[fill[m.face_verts[c]]++] = c;
  }
  // Twin corners: c runs a -> b; its twin runs b -> a. An edge belongs to
  // the smaller of its two corners.
  std::vector<std::uint32_t> twin(nc, kNoCorner);
  std::vector<std::uint32_t> bad(nc, kNoCorner);
  par::for_each_n(ctx, nc, [&](std::size_t ci) {
    const auto c = static_cast<std::uint32_t>(ci);
    const std::uint32_t a = m.face_verts[c], b = m.face_verts[m.next_corner(c)];
    std::uint32_t found = kNoCorner;
    for (std::uint32_t k = m.vert_offsets[b]; k < m.vert_offsets[b + 1]; ++k) {
      const std::uint32_t d = m.vert_corners[k];
      if (m.face_verts[m.next_corner(d)] == a) {
        if (found != kNoCorner) bad[c] = d;  // three faces on one edge
        found = d;
      }
    }
    for (std::uint32_t k = m.vert_offsets[a]; k < m.vert_offsets[a + 1]; ++k) {
      const std::uint32_t d = m.vert_corners[k];
      if (d != c && m.face_verts[m.next_corner(d)] == b) bad[c] = d;  // same direction twice
    }
    twin[c] = found;
  });
  for (std::uint32_t c = 0; c < nc; ++c)
    if (bad[c] != kNoCorner)
      return Status(ErrorCode::kNonManifold, "corner mesh: faces " + std::to_string(m.face_of(c)) + " and " +
                                                 std::to_string(m.face_of(bad[c])) + " share edge (" +
                                                 std::to_string(m.face_verts[c]) + ", " +
                                                 std::to_string(m.face_verts[m.next_corner(c)]) +
                                                 ") in the same direction or with a third face");
  m.corner_edge.resize(nc);
  for (std::uint32_t c = 0; c < nc; ++c) {
    if (twin[c] != kNoCorner && twin[c] < c) continue;
    const auto e = static_cast<std::uint32_t>(m.edge_verts.size());
    m.edge_verts.push_back({m.face_verts[c], m.face_verts[m.next_corner(c)]});
    m.edge_corners.push_back({c, twin[c]});
    m.corner_edge[c] = e;
    if (twin[c] != kNoCorner) m.corner_edge[twin[c]] = e;
  }
  return m;
}

}  // namespace atelier
