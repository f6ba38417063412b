#include <atelier/storage/adjacency.h>

#include <algorithm>
#include <numeric>
#include <string>

#include <atelier/engine/parallel.h>

namespace atelier {

NodeAdjacency build_adjacency(const Model& m, SurfaceIdx only, const ExecContext& ctx) {
  NodeAdjacency a;
  const std::size_t n = m.nodes.slots.capacity();
  a.offset.assign(n + 1, 0);
  a.topology_version = m.topology_version;
  auto use = [&](std::size_t v) {
    return m.alive(NodeIdx{static_cast<std::uint32_t>(v)}) && (!only.valid() || m.nodes.surface[v] == only);
  };
  par::for_each_n(ctx, n, [&](std::size_t v) {
    if (use(v)) a.offset[v + 1] = static_cast<std::uint32_t>(m.degree(NodeIdx{static_cast<std::uint32_t>(v)}));
  });
  for (std::size_t v = 0; v < n; ++v) a.offset[v + 1] += a.offset[v];
  a.neighbor.resize(a.offset[n]);
  par::for_each_n(ctx, n, [&](std::size_t v) {
    if (!use(v)) return;
    std::uint32_t k = a.offset[v];
    m.for_each_outgoing(NodeIdx{static_cast<std::uint32_t>(v)}, [&](HalfedgeIdx h) { a.neighbor[k++] = m.head(h).value; });
  });
  return a;
}

Expected<NodeAdjacency> adjacency_from_edges(std::size_t vertex_count,
                                             std::span<const std::array<std::uint32_t, 2>> edges) {
  NodeAdjacency adj;
  adj.offset.assign(vertex_count + 1, 0);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto [a, b] = edges[e];
    if (a >= vertex_count || b >= vertex_count)
      return Status(ErrorCode::kInvalidArgument,
                    "adjacency_from_edges: edge " + std::to_string(e) + " uses a vertex out of range");
    if (a == b) continue;
    ++adj.offset[a + 1];
    ++adj.offset[b + 1];
  }
  std::partial_sum(adj.offset.begin(), adj.offset.end(), adj.offset.begin());
  adj.neighbor.resize(adj.offset.back());
  std::vector<std::uint32_t> fill(adj.offset.begin(), adj.offset.end() - 1);
  for (const auto& [a, b] : edges) {
    if (a == b) continue;
    adj.neighbor[fill[a]++] = b;
    adj.neighbor[fill[b]++] = a;
  }
  // Duplicate edges would weigh a neighbour twice in the umbrella.
  for (std::size_t v = 0; v < vertex_count; ++v) {
    auto* b = adj.neighbor.data() + adj.offset[v];
    auto* e = adj.neighbor.data() + adj.offset[v + 1];
    std::sort(b, e);
    if (std::adjacent_find(b, e) != e)
      return Status(ErrorCode::kInvalidArgument, "adjacency_from_edges: duplicate edge at vertex " + std::to_string(v));
  }
  return adj;
}

}  // namespace atelier
