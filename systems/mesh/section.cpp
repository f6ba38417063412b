#include <atelier/systems/mesh/section.h>

#include <algorithm>
#include <map>

namespace atelier {

std::vector<SectionChain> plane_section(const Model& m, SurfaceIdx s, const Vec3d& n, double d,
                                        std::span<const Vec3d> pos) {
  auto side = [&](NodeIdx v) { return n.dot(pos[v.value]) - d >= 0.0; };
  // Crossing on an edge: keyed by its forward halfedge (even index).
  auto crossing = [&](HalfedgeIdx h) {
    const HalfedgeIdx f = is_forward(h) ? h : twin(h);
    const Vec3d& a = pos[m.tail(f).value];
    const Vec3d& b = pos[m.head(f).value];
    const double da = n.dot(a) - d, db = n.dot(b) - d;
    double u = da / (da - db);
    u = std::clamp(u, 0.0, 1.0);
    SectionPoint p;
    p.where.kind = AttribNodeKind::kEdge;
    p.where.element = f.value;
    p.where.param = Vec3d(u, 0, 0);
    p.p = (1 - u) * a + u * b;
    return p;
  };
  // Segment graph: each crossed face links its crossings pairwise in cycle order.
  std::map<std::uint32_t, std::vector<std::uint32_t>> adj;  // forward halfedge -> neighbours
  std::vector<HalfedgeIdx> cross;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f}) || m.faces.surface[f] != s) continue;
    cross.clear();
    m.for_each_face_halfedge(FaceIdx{f}, [&](HalfedgeIdx h) {
      if (side(m.tail(h)) != side(m.head(h))) cross.push_back(h);
    });
    // Pair crossings in cycle order, starting at one that enters the
    // negative side, so saddle quads (4 crossings) pair consistently.
    if (cross.size() < 2) continue;
    std::size_t start = 0;
    while (start < cross.size() && !(side(m.tail(cross[start])) && !side(m.head(cross[start])))) ++start;
    if (start == cross.size()) start = 0;
    for (std::size_t k = 0; k + 1 < cross.size(); k += 2) {
      const HalfedgeIdx a = cross[(start + k) % cross.size()], b = cross[(start + k + 1) % cross.size()];
      const std::uint32_t ka = (is_forward(a) ? a : twin(a)).value, kb = (is_forward(b) ? b : twin(b)).value;
      adj[ka].push_back(kb);
      adj[kb].push_back(ka);
    }
  }
  std::vector<SectionChain> chains;
  std::map<std::uint32_t, bool> used;
  auto walk = [&](std::uint32_t from) {
    SectionChain c;
    std::uint32_t prev = ~0u, cur = from;
    while (true) {
      used[cur] = true;
      c.points.push_back(crossing(HalfedgeIdx{cur}));
      std::uint32_t nxt = ~0u;
      for (std::uint32_t x : adj[cur])
        if (x != prev && !used[x]) {
          nxt = x;
          break;
        }
      if (nxt == ~0u) {
        for (std::uint32_t x : adj[cur])
          if (x == from && c.points.size() > 2) c.closed = true;
        break;
      }
      prev = cur;
      cur = nxt;
    }
    return c;
  };
  // Open chains first, from their ends (degree-1 crossings), then loops.
  for (auto& [k, nb] : adj)
    if (nb.size() == 1 && !used[k]) chains.push_back(walk(k));
  for (auto& [k, nb] : adj)
    if (!used[k]) chains.push_back(walk(k));
  return chains;
}

}  // namespace atelier
