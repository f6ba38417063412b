// Typed, generational handles: one type per element kind, never interchangeable.
#pragma once

#include <compare>
#include <cstdint>
#include <functional>
#include <limits>

namespace atelier {

/// A typed 32-bit index into a column (no generation). Used inside
/// connectivity columns, where the extra 4 bytes of a generation would double
/// the memory traffic of every traversal.
template <class Tag>
struct Idx {
  using value_type = std::uint32_t;
  static constexpr value_type kInvalid = std::numeric_limits<value_type>::max();

  value_type value = kInvalid;

  constexpr Idx() noexcept = default;
  constexpr explicit Idx(value_type v) noexcept : value(v) {}

  [[nodiscard]] constexpr bool valid() const noexcept { return value != kInvalid; }
  [[nodiscard]] constexpr value_type operator*() const noexcept { return value; }
  friend constexpr auto operator<=>(Idx, Idx) noexcept = default;
  friend constexpr bool operator==(Idx, Idx) noexcept = default;
};

/// A typed handle: index plus generation. Deleting an element bumps the
/// generation of its slot, so a handle kept across the deletion is detected
/// as stale (EnTT style).
template <class Tag>
struct Handle {
  Idx<Tag> idx;
  std::uint32_t generation = 0;

  constexpr Handle() noexcept = default;
  constexpr Handle(Idx<Tag> i, std::uint32_t g) noexcept : idx(i), generation(g) {}

  [[nodiscard]] constexpr bool valid() const noexcept { return idx.valid(); }
  [[nodiscard]] constexpr std::uint32_t index() const noexcept { return idx.value; }
  friend constexpr auto operator<=>(Handle, Handle) noexcept = default;
  friend constexpr bool operator==(Handle, Handle) noexcept = default;
};

// Element kinds. The papers' names are in docs/glossary.md.
struct NodeTag {};        // TRGLNODE / PNODE
struct HalfedgeTag {};    // a TRGLEDGE with its direction flag
struct EdgeTag {};        // TRGLEDGE / PEDGE
struct FaceTag {};        // TRGLFACE / PFACE
struct SurfaceTag {};     // MESHSURFACE / PMESH
struct MeshLoopTag {};    // MESHLOOP
struct MeshEdgeTag {};    // MESHEDGE
struct JointTag {};       // MESHJOINT
struct AttribNodeTag {};  // ATTRIB_NODE (vertex, edge or face node)
struct AttribEdgeTag {};  // ATTRIB_EDGE

// Names for messages ("node 12 is stale").
constexpr const char* kind_name(NodeTag) noexcept { return "node"; }
constexpr const char* kind_name(HalfedgeTag) noexcept { return "halfedge"; }
constexpr const char* kind_name(EdgeTag) noexcept { return "edge"; }
constexpr const char* kind_name(FaceTag) noexcept { return "face"; }
constexpr const char* kind_name(SurfaceTag) noexcept { return "surface"; }
constexpr const char* kind_name(MeshLoopTag) noexcept { return "mesh loop"; }
constexpr const char* kind_name(MeshEdgeTag) noexcept { return "mesh edge"; }
constexpr const char* kind_name(JointTag) noexcept { return "joint"; }
constexpr const char* kind_name(AttribNodeTag) noexcept { return "attribute node"; }
constexpr const char* kind_name(AttribEdgeTag) noexcept { return "attribute edge"; }

using NodeIdx = Idx<NodeTag>;
using HalfedgeIdx = Idx<HalfedgeTag>;
using EdgeIdx = Idx<EdgeTag>;
using FaceIdx = Idx<FaceTag>;
using SurfaceIdx = Idx<SurfaceTag>;
using MeshLoopIdx = Idx<MeshLoopTag>;
using MeshEdgeIdx = Idx<MeshEdgeTag>;
using JointIdx = Idx<JointTag>;
using AttribNodeIdx = Idx<AttribNodeTag>;
using AttribEdgeIdx = Idx<AttribEdgeTag>;

using Node = Handle<NodeTag>;
using Halfedge = Handle<HalfedgeTag>;
using Edge = Handle<EdgeTag>;
using Face = Handle<FaceTag>;
using Surface = Handle<SurfaceTag>;
using MeshLoop = Handle<MeshLoopTag>;
using MeshEdge = Handle<MeshEdgeTag>;
using Joint = Handle<JointTag>;
using AttribNode = Handle<AttribNodeTag>;
using AttribEdge = Handle<AttribEdgeTag>;

// Halfedges are not allocated on their own: edge e owns halfedges 2e and
// 2e+1, so twin(h) = h ^ 1 and a halfedge is alive exactly when its edge is.
[[nodiscard]] constexpr HalfedgeIdx halfedge_of(EdgeIdx e, unsigned side) noexcept {
  return HalfedgeIdx{2u * e.value + side};
}
[[nodiscard]] constexpr EdgeIdx edge_of(HalfedgeIdx h) noexcept { return EdgeIdx{h.value >> 1}; }
[[nodiscard]] constexpr HalfedgeIdx twin(HalfedgeIdx h) noexcept { return HalfedgeIdx{h.value ^ 1u}; }
[[nodiscard]] constexpr bool is_forward(HalfedgeIdx h) noexcept { return (h.value & 1u) == 0; }

}  // namespace atelier

template <class Tag>
struct std::hash<atelier::Idx<Tag>> {
  std::size_t operator()(atelier::Idx<Tag> i) const noexcept { return std::hash<std::uint32_t>{}(i.value); }
};
template <class Tag>
struct std::hash<atelier::Handle<Tag>> {
  std::size_t operator()(atelier::Handle<Tag> h) const noexcept {
    return std::hash<std::uint64_t>{}((std::uint64_t{h.generation} << 32) | h.idx.value);
  }
};
