// Feature-node encoding of profile templates: how each node of a template
// is tied to a reference body, so the template can be decoded (relocated) on
// any body with the same topology and features.
//
// Modes (each stores the reference element and local coordinates):
//   kFeaturePoint   seed 000 eq. (1): p = q_j + a n + b t1 + g t2 at feature
//                   point j with the surface normal and the two curve tangents
//                   (not orthogonal; (t1 x t2).n != 0 is required);
//   kFeatureOffset  seed 000 eq. (2): p = q_j + d (for comparison: it does
//                   not follow the body's orientation, Fig. 11);
//   kVertex         seed 001 eq. (1): frame at a body vertex V_b: X = n,
//                   Y = unit((V_b^1 - V_b) x n), Z = X x Y, V_b^1 its first
//                   neighbour (next ones if degenerate);
//   kEdge           seed 001 eq. (2): frame at the point of edge E_b nearest
//                   the node (parameter t): X = mean of the two face normals,
//                   Y = unit edge direction, Z = X x Y;
//   kFace           seed 001 eq. (3): frame at the face centroid: X = normal,
//                   Y = unit(V^1 - centroid) made orthogonal to X, Z = X x Y;
//   kOneToOne       seed 001: p = delta + p(other node);
//   kNToOne         seed 001 eqs. (4)-(5): blend of delta_i + p(node_i) with
//                   weights 1 / (eps + |delta_i|^3).
// Template nodes encoded on other nodes are decoded after them (the order is
// resolved once; cycles are refused).
//
// Reads: the reference body (model connectivity, feature tables) and a
// position array of the body to decode on.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/systems/body/reference_body.h>

namespace atelier {

enum class NodeEncodingMode : std::uint8_t {
  kFeaturePoint = 0,
  kFeatureOffset = 1,
  kVertex = 2,
  kEdge = 3,
  kFace = 4,
  kOneToOne = 5,
  kNToOne = 6,
};

/// The mode's name in template files (inline: readers need it without the encoders).
[[nodiscard]] inline const char* to_string(NodeEncodingMode m) noexcept {
  switch (m) {
    case NodeEncodingMode::kFeaturePoint:
      return "feature_point";
    case NodeEncodingMode::kFeatureOffset:
      return "feature_offset";
    case NodeEncodingMode::kVertex:
      return "vertex";
    case NodeEncodingMode::kEdge:
      return "edge";
    case NodeEncodingMode::kFace:
      return "face";
    case NodeEncodingMode::kOneToOne:
      return "one_to_one";
    case NodeEncodingMode::kNToOne:
      return "n_to_one";
  }
  return "?";
}

/// One node's encoding. For kNToOne the references are the range
/// [first_ref, first_ref + ref_count) of NodeEncodings::refs.
struct NodeEncoding {
  NodeEncodingMode mode = NodeEncodingMode::kVertex;
  std::int32_t feature_point = -1;  // kFeaturePoint / kFeatureOffset: feature point id
  std::uint32_t element = 0;        // kVertex: node; kEdge: halfedge (t from its tail); kFace: face; kOneToOne: template node
  double t = 0;                     // kEdge: parameter of the foot point
  Vec3d coords = Vec3d::Zero();     // (a, b, g), d, (u, v, w) or delta, by mode
  std::uint32_t first_ref = 0, ref_count = 0;
};

/// A reference of an n-to-one node: template node, delta and weight (eq. 4).
struct NodeRef {
  std::uint32_t node = 0;
  Vec3d delta = Vec3d::Zero();
  double weight = 0;
};

/// The encodings of all nodes of a template (indexed like its node table).
struct NodeEncodings {
  std::vector<NodeEncoding> nodes;
  std::vector<NodeRef> refs;  // pool for n-to-one nodes
};

// ------------------------------------------------------------ encoding one node
[[nodiscard]] Expected<NodeEncoding> encode_on_feature_point(const ReferenceBody& body, std::int32_t point_id,
                                                             const Vec3d& p, bool offset_only = false);
[[nodiscard]] Expected<NodeEncoding> encode_on_vertex(const ReferenceBody& body, NodeIdx vertex, const Vec3d& p);
/// The foot point on the edge is the point nearest p (t clamped to [0, 1]).
[[nodiscard]] Expected<NodeEncoding> encode_on_edge(const ReferenceBody& body, EdgeIdx edge, const Vec3d& p);
[[nodiscard]] Expected<NodeEncoding> encode_on_face(const ReferenceBody& body, FaceIdx face, const Vec3d& p);
/// Relative to already placed template nodes (their positions given).
[[nodiscard]] NodeEncoding encode_one_to_one(std::uint32_t other, const Vec3d& other_pos, const Vec3d& p);
[[nodiscard]] NodeEncoding encode_n_to_one(NodeEncodings& pool, std::span<const std::uint32_t> others,
                                           std::span<const Vec3d> other_pos, const Vec3d& p, double eps = 1e-8);

/// Decodes every template node on a body with the reference body's topology
/// and features and the given node positions (out.size() == nodes). Errors
/// name the node: a dead element, a degenerate frame, a reference cycle.
[[nodiscard]] Status decode_nodes(const NodeEncodings& enc, const ReferenceBody& body,
                                  std::span<const Vec3d> body_positions, std::span<Vec3d> out);

/// The local frame of a body element used by the vertex / edge / face modes
/// (origin, X, Y, Z), for inspection and tests.
struct ElementFrame {
  Vec3d origin = Vec3d::Zero(), x = Vec3d::Zero(), y = Vec3d::Zero(), z = Vec3d::Zero();
};
[[nodiscard]] Expected<ElementFrame> element_frame(const ReferenceBody& body, NodeEncodingMode mode,
                                                   std::uint32_t element, double t,
                                                   std::span<const Vec3d> positions);

}  // namespace atelier
