// The demo's outfit (issue 26): the shorts (a detail template) and the
// profile templates (top, skirt, trousers) of one body resolved together
// as layers by the library's layering (resolve_layers,
// systems/garment/collision_pass.h), and the vertices of each garment
// inside a garment of a lower layer counted before and after
// (count_inside_layer, systems/garment/fit_measure.h).
//
// The order, innermost first: shorts, trousers, skirt, top. The shorts sit
// 8 mm off the skin like cycling shorts and go under the trousers; the
// skirt is worn over the trousers; the top, untucked, is outermost over the
// skirt's waistband. No garment is dropped: every pair can be worn in this
// order.
//
// A profile template is a Model whose surfaces meet at joints through
// corresponding nodes: they are merged into one layer vertex, so that the
// layering moves them together and opens no crack (each node keeps its own
// offset from the merged vertex). Private to the demo.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/adjacency.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/garment/collision_pass.h>
#include <atelier/systems/garment/fit_measure.h>
#include <atelier/systems/spatial/collision_body.h>

namespace atelier::cli {

/// Layer order of the demo's garments, innermost first.
inline constexpr std::array<std::string_view, 4> kDemoOutfitOrder = {"shorts", "trousers", "skirt", "top"};

/// A profile template's regenerated Model as a layer: its live nodes merged
/// across joints.
struct ModelLayer {
  std::vector<std::uint32_t> vertex_of;  // per node slot: its layer vertex (UINT32_MAX: dead node)
  std::vector<std::uint32_t> first_node;  // per layer vertex: the node whose position it carries
  NodeAdjacency adjacency;               // of the layer vertices
  std::vector<Triangle> triangles;       // faces fanned, on layer vertices
  ClearanceEncoding clearance;           // on the reference body

  /// From the template regenerated on the reference body; `reference` is a
  /// CollisionBody built on the reference skin. Errors: a model that cannot
  /// be triangulated, those of encode_clearance.
  [[nodiscard]] static Expected<ModelLayer> of(const Model& on_reference, const CollisionBody& reference,
                                               const ExecContext& ctx);
  /// The layer vertices' positions in `m` (a regeneration of the same
  /// template: same node slots). Errors: another node count.
  [[nodiscard]] Status positions(const Model& m, std::vector<Vec3d>& out) const;
  /// Moves every node of `m` by its layer vertex's displacement from `before` to `after`.
  void apply(Model& m, std::span<const Vec3d> before, std::span<const Vec3d> after) const;
};

/// One garment of the outfit on one body.
struct OutfitGarment {
  std::vector<Vec3d> positions;  // in place
  const NodeAdjacency* adjacency = nullptr;
  const ClearanceEncoding* clearance = nullptr;
  std::span<const Triangle> triangles;
  int z_depth = 0;
  std::vector<BodyDistance> distance;  // on exit: each vertex's exact body distance
  std::size_t layer_inside_before = 0;  // vertices inside a lower layer as fitted alone
  std::size_t layer_inside = 0;         // the same after the layering
  std::size_t pushed = 0;               // vertices the layered pass moved
};

/// Counts, resolves the layers (resolve_layers), lifts what a lower layer
/// still covers (collision step 8, as regen does), counts again. Sequential
/// unless ctx says otherwise. Errors: those of the library calls.
[[nodiscard]] Status layer_outfit(std::span<OutfitGarment> garments, const CollisionBody& body,
                                  const CollisionParams& params, const ExecContext& ctx);

}  // namespace atelier::cli
