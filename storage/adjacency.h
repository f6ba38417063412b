// Node adjacency in CSR form: the neighbours of every node through its
// edges. Built from a Model (in ring order) or from a list of undirected
// edges (for polygon soups that a Model would refuse, such as inconsistently
// oriented garments). Read by fairing, the collision pass and the edge
// transfer.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

namespace atelier {

/// Node adjacency in CSR form (neighbours through edges, in ring order).
struct NodeAdjacency {
  std::vector<std::uint32_t> offset;    // size N+1 (N = node capacity)
  std::vector<std::uint32_t> neighbor;  // node indices
  std::uint64_t topology_version = 0;   // of the model it was built from
  [[nodiscard]] std::uint32_t degree(std::size_t v) const noexcept { return offset[v + 1] - offset[v]; }
};

/// Adjacency of all live nodes (optionally of one surface only).
[[nodiscard]] NodeAdjacency build_adjacency(const Model& m, SurfaceIdx only = {}, const ExecContext& ctx = {});

/// Adjacency of `vertex_count` vertices from undirected edges (neighbours
/// sorted by index). Errors: an index out of range, a duplicate edge (it
/// would weigh a neighbour twice in an umbrella). Edges from a vertex to
/// itself are ignored.
[[nodiscard]] Expected<NodeAdjacency> adjacency_from_edges(std::size_t vertex_count,
                                                           std::span<const std::array<std::uint32_t, 2>> edges);

}  // namespace atelier
