#include "demo_outfit.h"

#include <atelier/storage/mesh_edge_chain.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/spatial/body_bvh.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <string>

namespace atelier::cli {

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

std::uint32_t find(std::vector<std::uint32_t>& parent, std::uint32_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

/// Each garment's vertices inside a garment of a lower layer (z_depth
/// order, ties in the order given), counted once per vertex.
Status count_layers(std::span<OutfitGarment> g, std::span<const std::size_t> order, std::size_t OutfitGarment::*field) {
  std::vector<std::vector<std::uint8_t>> flags(g.size());
  for (std::size_t i = 0; i < g.size(); ++i) flags[i].assign(g[i].positions.size(), 0);
  std::vector<std::uint8_t> inside;
  for (std::size_t k = 0; k + 1 < order.size(); ++k) {
    const OutfitGarment& inner = g[order[k]];
    BodyBvh bvh;
    if (Status s = bvh.build(inner.positions, inner.triangles, {}, ExecContext::sequential()); !s) return s;
    for (std::size_t l = k + 1; l < order.size(); ++l) {
      OutfitGarment& outer = g[order[l]];
      auto n = count_inside_layer(outer.positions, outer.distance, bvh, {}, &inside);
      if (!n) return n.status();
      for (std::size_t v = 0; v < inside.size(); ++v) flags[order[l]][v] |= inside[v];
    }
  }
  for (std::size_t i = 0; i < g.size(); ++i)
    g[i].*field = static_cast<std::size_t>(std::count(flags[i].begin(), flags[i].end(), std::uint8_t{1}));
  return {};
}

/// Collision step 8 (docs/collision.md): after resolve_layers, the
/// library's lift over every lower layer (lift_over_lower_layers, as regen
/// applies it), layers inner first, each lower layer's BVH built once when
/// it is final.
Status lift_layers(std::span<OutfitGarment> g, std::span<const std::size_t> order, const CollisionBody& body,
                   const CollisionParams& params) {
  const LayerPenetrationParams lp;
  std::vector<BodyBvh> lower(order.size());
  for (std::size_t l = 1; l < order.size(); ++l) {
    const OutfitGarment& below = g[order[l - 1]];  // final now: its BVH serves every layer above it
    if (Status s = lower[l - 1].build(below.positions, below.triangles, {}, ExecContext::sequential()); !s) return s;
    OutfitGarment& x = g[order[l]];
    auto lifted = lift_over_lower_layers(x.positions, x.distance, std::span<const BodyBvh>(lower.data(), l), body,
                                         lp.probe, params.layer_gap);
    if (!lifted) return lifted.status();
  }
  return {};
}

}  // namespace

Expected<ModelLayer> ModelLayer::of(const Model& m, const CollisionBody& reference, const ExecContext& ctx) {
  ModelLayer L;
  const auto n = static_cast<std::uint32_t>(m.nodes.slots.capacity());
  // Corresponding nodes of every joint (as joint_crack pairs them) in one set.
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto unite = [&](NodeIdx a, NodeIdx b) {
    const std::uint32_t ra = find(parent, a.value), rb = find(parent, b.value);
    if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
  };
  for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
    if (!m.alive(JointIdx{j})) continue;
    auto members = m.joints.members.row(j);
    if (members.size() < 2) continue;
    const std::size_t len = m.mesh_edges.halfedges.size(members[0].mesh_edge.value);
    for (std::size_t k = 1; k < members.size(); ++k) {
      if (m.mesh_edges.halfedges.size(members[k].mesh_edge.value) != len) continue;
      for (std::size_t t = 0; t < len; ++t) {
        const HalfedgeIdx h0 = joint_member_halfedge(m, members[0], t), hk = joint_member_halfedge(m, members[k], t);
        unite(m.tail(h0), m.tail(hk));
        unite(m.head(h0), m.head(hk));
      }
    }
  }
  L.vertex_of.assign(n, kNone);
  std::vector<std::uint32_t> of_root(n, kNone);
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!m.alive(NodeIdx{v})) continue;
    const std::uint32_t r = find(parent, v);
    if (of_root[r] == kNone) {
      of_root[r] = static_cast<std::uint32_t>(L.first_node.size());
      L.first_node.push_back(v);
    }
    L.vertex_of[v] = of_root[r];
  }
  std::vector<std::array<std::uint32_t, 2>> edges;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e})) continue;
    std::uint32_t a = L.vertex_of[m.tail(halfedge_of(EdgeIdx{e}, 0)).value];
    std::uint32_t b = L.vertex_of[m.tail(halfedge_of(EdgeIdx{e}, 1)).value];
    if (a == b || a == kNone || b == kNone) continue;
    edges.push_back({std::min(a, b), std::max(a, b)});
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  auto adj = adjacency_from_edges(L.first_node.size(), edges);
  if (!adj) return adj.status();
  L.adjacency = std::move(*adj);
  auto tris = fan_triangulate(m);
  if (!tris) return tris.status();
  for (const Triangle& t : tris->triangles)
    L.triangles.push_back({L.vertex_of[t[0]], L.vertex_of[t[1]], L.vertex_of[t[2]]});
  std::vector<Vec3d> p;
  if (Status s = L.positions(m, p); !s) return s;
  auto c = encode_clearance(p, reference, ctx);
  if (!c) return c.status();
  L.clearance = std::move(*c);
  return L;
}

Status ModelLayer::positions(const Model& m, std::vector<Vec3d>& out) const {
  if (m.nodes.slots.capacity() != vertex_of.size())
    return Status(ErrorCode::kMismatch, "outfit layer: the regenerated template has " +
                                            std::to_string(m.nodes.slots.capacity()) + " node slots, the layer " +
                                            std::to_string(vertex_of.size()));
  out.resize(first_node.size());
  for (std::size_t c = 0; c < first_node.size(); ++c) out[c] = m.nodes.position[first_node[c]];
  return {};
}

void ModelLayer::apply(Model& m, std::span<const Vec3d> before, std::span<const Vec3d> after) const {
  for (std::uint32_t v = 0; v < vertex_of.size(); ++v)
    if (vertex_of[v] != kNone) m.nodes.position[v] += after[vertex_of[v]] - before[vertex_of[v]];
}

Status layer_outfit(std::span<OutfitGarment> g, const CollisionBody& body, const CollisionParams& params,
                    const ExecContext& ctx) {
  std::vector<std::size_t> order(g.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return g[a].z_depth < g[b].z_depth; });
  // As fitted alone: each garment's exact distances, then the count.
  for (OutfitGarment& x : g) {
    x.distance.resize(x.positions.size());
    if (Status s = body.query_many(x.positions, x.clearance->triangle, x.distance, ctx); !s) return s;
  }
  if (Status s = count_layers(g, order, &OutfitGarment::layer_inside_before); !s) return s;
  std::vector<GarmentLayer> layers(g.size());
  for (std::size_t i = 0; i < g.size(); ++i)
    layers[i] = {g[i].positions, g[i].adjacency, g[i].clearance, g[i].z_depth, &g[i].distance};
  auto reps = resolve_layers(layers, body, params, ctx);
  if (!reps) return reps.status();
  for (std::size_t i = 0; i < g.size(); ++i) g[i].pushed = (*reps)[i].pushed;
  if (Status s = lift_layers(g, order, body, params); !s) return s;
  return count_layers(g, order, &OutfitGarment::layer_inside);
}

}  // namespace atelier::cli
