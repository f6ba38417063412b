// Model: the papers' BODY. All topology lives in structure-of-arrays tables
// addressed by typed indices; there are no pointer trees.
//
// Within a surface (MESHSURFACE / PMESH) connectivity is half-edge columns:
// edge e owns halfedges 2e and 2e+1 (twin = h ^ 1), each halfedge has its
// tail node, the face on its left (invalid when none: boundary or wire), and
// next/prev within that face. Around a node, the outgoing halfedges form a
// circular doubly-linked list kept sorted by halfedge index, so the state of
// the tables depends only on which elements exist, never on the order in
// which operators linked them (this is what makes inverse operators restore
// bit-identical tables). Non-manifold assembly across surfaces goes through
// joints (MESHJOINT), which order mesh edges (MESHEDGE) of several surfaces.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <atelier/engine/handle.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/property.h>
#include <atelier/storage/ragged.h>
#include <atelier/storage/slot_table.h>

namespace atelier {

/// Kind of an attribute node (ATTRIB_NODE and its derived kinds).
enum class AttribNodeKind : std::uint8_t {
  kVertex = 0,  // ATTRIB_NODE sitting on a mesh node
  kEdge = 1,    // ATTRIB_EDGENODE: parameter u along a halfedge's edge
  kFace = 2,    // ATTRIB_FACENODE: areal coordinates (u,v,w) in a face
};

/// One mesh edge inside a joint with its direction flag (positive when it
/// runs along the joint's direction).
struct JointMember {
  MeshEdgeIdx mesh_edge;
  bool positive = true;
  friend bool operator==(const JointMember&, const JointMember&) = default;
};

struct NodeTable {
  SlotTable<NodeTag> slots;
  std::vector<Vec3d> position;         // p_3d
  std::vector<Vec3d> position_backup;  // p_3d_backup
  std::vector<Vec2d> uv;               // p_2d (planar position, for patterns)
  std::vector<HalfedgeIdx> out;        // smallest outgoing halfedge, invalid when isolated
  std::vector<SurfaceIdx> surface;
  std::vector<FaceIdx> in_face;        // set for ring nodes (stand-alone vertex on a face)
  PropertyRegistry<NodeTag> props;
};

struct EdgeTable {
  SlotTable<EdgeTag> slots;
  std::vector<std::uint8_t> flags;
  std::vector<MeshEdgeIdx> mesh_edge;  // the MESHEDGE holding this edge, if any
  PropertyRegistry<EdgeTag> props;
};

/// Halfedge columns: sized 2 * edge capacity, alive exactly when their edge is.
/// A halfedge with a face is one corner of that face (its tail node in that
/// face), so `props` holds per-face-corner attributes: "corner_uv" (Vec2d,
/// texture coordinates with their seams) and "source_texcoord" (int32, the
/// OBJ `vt` index it came from) written by the readers (docs/glossary.md).
struct HalfedgeTable {
  std::vector<NodeIdx> tail;
  std::vector<FaceIdx> face;
  std::vector<HalfedgeIdx> next;   // next in face (invalid when faceless)
  std::vector<HalfedgeIdx> prev;   // prev in face (invalid when faceless)
  std::vector<HalfedgeIdx> vnext;  // next outgoing halfedge around tail (sorted ring)
  std::vector<HalfedgeIdx> vprev;  // previous outgoing halfedge around tail
  PropertyRegistry<HalfedgeTag> props;
};

struct FaceTable {
  SlotTable<FaceTag> slots;
  std::vector<HalfedgeIdx> halfedge;  // first halfedge of the face cycle
  std::vector<SurfaceIdx> surface;
  std::vector<std::uint8_t> flags;
  PropertyRegistry<FaceTag> props;
};

struct SurfaceTable {
  SlotTable<SurfaceTag> slots;
  std::vector<std::string> name;
  std::vector<std::uint8_t> flags;
  PropertyRegistry<SurfaceTag> props;
};

struct MeshEdgeTable {
  SlotTable<MeshEdgeTag> slots;
  std::vector<SurfaceIdx> surface;
  std::vector<MeshLoopIdx> loop;
  std::vector<JointIdx> joint;
  RaggedColumn<HalfedgeIdx> halfedges;  // ordered; the halfedge carries the direction flag
};

struct MeshLoopTable {
  SlotTable<MeshLoopTag> slots;
  std::vector<SurfaceIdx> surface;
  RaggedColumn<MeshEdgeIdx> mesh_edges;  // ordered around the loop
};

struct JointTable {
  SlotTable<JointTag> slots;
  RaggedColumn<JointMember> members;  // clockwise by the right-hand rule about the joint direction
};

struct AttribNodeTable {
  SlotTable<AttribNodeTag> slots;
  std::vector<AttribNodeKind> kind;
  std::vector<std::uint32_t> element;  // node, halfedge or face index, by kind
  std::vector<std::uint8_t> corner;    // face nodes: fan triangle k = (c0, c_{k+1}, c_{k+2})
  std::vector<Vec3d> param;            // edge: (u,0,0); face: (u,v,w) areal coordinates
  std::vector<Vec3d> position;         // p_3d (profile points may lie off their edge)
  std::vector<AttribEdgeIdx> owner;    // ATTRIB_EDGE holding it, if any
  std::vector<SurfaceIdx> surface;
};

struct AttribEdgeTable {
  SlotTable<AttribEdgeTag> slots;
  std::vector<SurfaceIdx> surface;
  std::vector<std::int32_t> feature_id;
  RaggedColumn<AttribNodeIdx> nodes;  // ordered
  PropertyRegistry<AttribEdgeTag> props;
};

/// Old->new index tables returned by Model::compact(); invalid for dead slots.
struct CompactRemap {
  std::vector<NodeIdx> nodes;
  std::vector<EdgeIdx> edges;
  std::vector<FaceIdx> faces;
  std::vector<SurfaceIdx> surfaces;
  std::vector<MeshEdgeIdx> mesh_edges;
  std::vector<MeshLoopIdx> mesh_loops;
  std::vector<JointIdx> joints;
  std::vector<AttribNodeIdx> attrib_nodes;
  std::vector<AttribEdgeIdx> attrib_edges;
  [[nodiscard]] HalfedgeIdx halfedge(HalfedgeIdx h) const noexcept {
    const EdgeIdx e = edges[edge_of(h).value];
    return e.valid() ? halfedge_of(e, h.value & 1u) : HalfedgeIdx{};
  }
};

class Model {
 public:
  // ---------------------------------------------------------------- tables
  // Systems read and write columns directly; topology changes go through the
  // primitives below (or the Euler operators built on them), which keep the
  // incidence columns symmetric.
  NodeTable nodes;
  EdgeTable edges;
  HalfedgeTable halfedges;
  FaceTable faces;
  SurfaceTable surfaces;
  MeshEdgeTable mesh_edges;
  MeshLoopTable mesh_loops;
  JointTable joints;
  AttribNodeTable attrib_nodes;
  AttribEdgeTable attrib_edges;

  /// Complex holes (the papers' "Chole") tracked by the Euler operators; see
  /// docs/glossary.md for the Euler-Poincare formula that validate() checks.
  std::int64_t complex_holes = 0;

  /// Bumped on every topology change (derived data such as BVHs, frames and
  /// CSR adjacency compare it to know they are stale).
  std::uint64_t topology_version = 0;
  /// Bumped by systems that move nodes.
  std::uint64_t geometry_version = 0;

  // ------------------------------------------------------------- handles
  [[nodiscard]] Node handle(NodeIdx i) const noexcept { return nodes.slots.handle(i); }
  [[nodiscard]] Edge handle(EdgeIdx i) const noexcept { return edges.slots.handle(i); }
  [[nodiscard]] Face handle(FaceIdx i) const noexcept { return faces.slots.handle(i); }
  [[nodiscard]] Surface handle(SurfaceIdx i) const noexcept { return surfaces.slots.handle(i); }
  [[nodiscard]] MeshEdge handle(MeshEdgeIdx i) const noexcept { return mesh_edges.slots.handle(i); }
  [[nodiscard]] MeshLoop handle(MeshLoopIdx i) const noexcept { return mesh_loops.slots.handle(i); }
  [[nodiscard]] Joint handle(JointIdx i) const noexcept { return joints.slots.handle(i); }
  [[nodiscard]] AttribNode handle(AttribNodeIdx i) const noexcept { return attrib_nodes.slots.handle(i); }
  [[nodiscard]] AttribEdge handle(AttribEdgeIdx i) const noexcept { return attrib_edges.slots.handle(i); }
  [[nodiscard]] Halfedge handle(HalfedgeIdx h) const noexcept {
    return {h, edges.slots.generation(edge_of(h))};
  }

  [[nodiscard]] bool alive(NodeIdx i) const noexcept { return nodes.slots.alive(i); }
  [[nodiscard]] bool alive(EdgeIdx i) const noexcept { return edges.slots.alive(i); }
  [[nodiscard]] bool alive(HalfedgeIdx h) const noexcept { return edges.slots.alive(edge_of(h)); }
  [[nodiscard]] bool alive(FaceIdx i) const noexcept { return faces.slots.alive(i); }
  [[nodiscard]] bool alive(SurfaceIdx i) const noexcept { return surfaces.slots.alive(i); }
  [[nodiscard]] bool alive(MeshEdgeIdx i) const noexcept { return mesh_edges.slots.alive(i); }
  [[nodiscard]] bool alive(MeshLoopIdx i) const noexcept { return mesh_loops.slots.alive(i); }
  [[nodiscard]] bool alive(JointIdx i) const noexcept { return joints.slots.alive(i); }
  [[nodiscard]] bool alive(AttribNodeIdx i) const noexcept { return attrib_nodes.slots.alive(i); }
  [[nodiscard]] bool alive(AttribEdgeIdx i) const noexcept { return attrib_edges.slots.alive(i); }
  [[nodiscard]] bool alive(Node h) const noexcept { return nodes.slots.alive(h); }
  [[nodiscard]] bool alive(Edge h) const noexcept { return edges.slots.alive(h); }
  [[nodiscard]] bool alive(Halfedge h) const noexcept {
    return edges.slots.alive(Edge{edge_of(h.idx), h.generation});
  }
  [[nodiscard]] bool alive(Face h) const noexcept { return faces.slots.alive(h); }
  [[nodiscard]] bool alive(Surface h) const noexcept { return surfaces.slots.alive(h); }
  [[nodiscard]] bool alive(MeshEdge h) const noexcept { return mesh_edges.slots.alive(h); }
  [[nodiscard]] bool alive(MeshLoop h) const noexcept { return mesh_loops.slots.alive(h); }
  [[nodiscard]] bool alive(Joint h) const noexcept { return joints.slots.alive(h); }
  [[nodiscard]] bool alive(AttribNode h) const noexcept { return attrib_nodes.slots.alive(h); }
  [[nodiscard]] bool alive(AttribEdge h) const noexcept { return attrib_edges.slots.alive(h); }

  /// Handle -> index, or a kStaleHandle status naming the element.
  template <class Tag>
  [[nodiscard]] Expected<Idx<Tag>> resolve(Handle<Tag> h) const {
    if (!alive(h)) return Status(ErrorCode::kStaleHandle, stale_message(kind_name(Tag{}), h.idx.value, h.generation));
    return h.idx;
  }

  // --------------------------------------------------------------- counts
  [[nodiscard]] std::size_t num_nodes() const noexcept { return nodes.slots.size(); }
  [[nodiscard]] std::size_t num_edges() const noexcept { return edges.slots.size(); }
  [[nodiscard]] std::size_t num_faces() const noexcept { return faces.slots.size(); }
  [[nodiscard]] std::size_t num_surfaces() const noexcept { return surfaces.slots.size(); }
  [[nodiscard]] std::size_t num_mesh_edges() const noexcept { return mesh_edges.slots.size(); }
  [[nodiscard]] std::size_t num_mesh_loops() const noexcept { return mesh_loops.slots.size(); }
  [[nodiscard]] std::size_t num_joints() const noexcept { return joints.slots.size(); }
  [[nodiscard]] std::size_t num_attrib_nodes() const noexcept { return attrib_nodes.slots.size(); }
  [[nodiscard]] std::size_t num_attrib_edges() const noexcept { return attrib_edges.slots.size(); }

  // ---------------------------------------------------- connectivity queries
  [[nodiscard]] NodeIdx tail(HalfedgeIdx h) const noexcept { return halfedges.tail[h.value]; }
  [[nodiscard]] NodeIdx head(HalfedgeIdx h) const noexcept { return halfedges.tail[twin(h).value]; }
  [[nodiscard]] FaceIdx face(HalfedgeIdx h) const noexcept { return halfedges.face[h.value]; }
  [[nodiscard]] HalfedgeIdx next(HalfedgeIdx h) const noexcept { return halfedges.next[h.value]; }
  [[nodiscard]] HalfedgeIdx prev(HalfedgeIdx h) const noexcept { return halfedges.prev[h.value]; }
  [[nodiscard]] bool is_boundary(HalfedgeIdx h) const noexcept { return !face(h).valid(); }
  /// An edge with no face on either side (wireframe edge).
  [[nodiscard]] bool is_wire(EdgeIdx e) const noexcept {
    return !face(halfedge_of(e, 0)).valid() && !face(halfedge_of(e, 1)).valid();
  }
  [[nodiscard]] bool is_boundary(EdgeIdx e) const noexcept {
    return face(halfedge_of(e, 0)).valid() != face(halfedge_of(e, 1)).valid();
  }
  [[nodiscard]] bool is_isolated(NodeIdx v) const noexcept { return !nodes.out[v.value].valid(); }
  [[nodiscard]] SurfaceIdx surface_of(EdgeIdx e) const noexcept { return nodes.surface[tail(halfedge_of(e, 0)).value]; }
  [[nodiscard]] const Vec3d& position(NodeIdx v) const noexcept { return nodes.position[v.value]; }
  /// Number of outgoing halfedges (= incident edges) of a node.
  [[nodiscard]] std::size_t degree(NodeIdx v) const noexcept;
  /// Number of sides of a face.
  [[nodiscard]] std::size_t face_degree(FaceIdx f) const noexcept;
  /// The halfedge a->b, or invalid.
  [[nodiscard]] HalfedgeIdx find_halfedge(NodeIdx a, NodeIdx b) const noexcept;
  /// Face corner nodes in cycle order starting at faces.halfedge[f].
  void face_nodes(FaceIdx f, std::vector<NodeIdx>& out) const;
  void face_halfedges(FaceIdx f, std::vector<HalfedgeIdx>& out) const;
  void outgoing(NodeIdx v, std::vector<HalfedgeIdx>& out) const;
  /// Position of an attribute node computed from its element and parameters
  /// (vertex/edge/face kinds), independent of the stored p_3d.
  [[nodiscard]] Vec3d attrib_position_on_surface(AttribNodeIdx a) const;

  /// Calls f(h) for each halfedge of face f, in cycle order.
  template <class F>
  void for_each_face_halfedge(FaceIdx f, F&& fn) const {
    const HalfedgeIdx start = faces.halfedge[f.value];
    HalfedgeIdx h = start;
    do {
      fn(h);
      h = halfedges.next[h.value];
    } while (h != start);
  }
  /// Calls f(h) for each outgoing halfedge of v, in increasing index order.
  template <class F>
  void for_each_outgoing(NodeIdx v, F&& fn) const {
    const HalfedgeIdx start = nodes.out[v.value];
    if (!start.valid()) return;
    HalfedgeIdx h = start;
    do {
      fn(h);
      h = halfedges.vnext[h.value];
    } while (h != start);
  }

  // ------------------------------------------------- topology primitives
  // Low-level: they keep incidence symmetric but not the Euler-Poincare
  // bookkeeping. Use the Euler operators (systems/euler.h) for that.
  Surface add_surface(std::string name);
  /// Kills a surface with no live node/face left in it.
  void remove_surface(SurfaceIdx s);
  NodeIdx new_node(SurfaceIdx s, const Vec3d& p);
  /// Kills an isolated node.
  void delete_node(NodeIdx v);
  /// New wire edge a->b (halfedge 2e runs a->b), linked into both node rings.
  EdgeIdx new_edge(NodeIdx a, NodeIdx b);
  /// Kills a wire edge (both sides faceless) not held by a mesh edge.
  void delete_edge(EdgeIdx e);
  /// Makes a face on a closed chain of faceless halfedges (each one's head is
  /// the next one's tail). faces.halfedge[f] = cycle[0].
  FaceIdx new_face(SurfaceIdx s, std::span<const HalfedgeIdx> cycle);
  /// Kills a face, leaving its halfedges faceless. No ring node may sit in it.
  void delete_face(FaceIdx f);
  /// Re-points the tail of h to node v (updates both rings). Used by split/collapse.
  void set_tail(HalfedgeIdx h, NodeIdx v);
  /// Rewires next/prev: h -> n within the same face.
  void link_face(HalfedgeIdx h, HalfedgeIdx n) noexcept {
    halfedges.next[h.value] = n;
    halfedges.prev[n.value] = h;
  }

  MeshEdgeIdx new_mesh_edge(SurfaceIdx s, std::span<const HalfedgeIdx> chain);
  void delete_mesh_edge(MeshEdgeIdx m);
  MeshLoopIdx new_mesh_loop(SurfaceIdx s, std::span<const MeshEdgeIdx> mesh_edges);
  void delete_mesh_loop(MeshLoopIdx l);
  /// A joint over mesh edges (clockwise about the joint direction).
  JointIdx new_joint(std::span<const JointMember> members);
  void delete_joint(JointIdx j);

  AttribNodeIdx new_attrib_node(SurfaceIdx s, AttribNodeKind kind, std::uint32_t element, const Vec3d& param,
                                const Vec3d& position, std::uint8_t corner = 0);
  void delete_attrib_node(AttribNodeIdx a);
  AttribEdgeIdx new_attrib_edge(SurfaceIdx s, std::int32_t feature_id, std::span<const AttribNodeIdx> nodes);
  void delete_attrib_edge(AttribEdgeIdx a);

  /// Removes tombstones from every table; all handles are invalidated and
  /// every stored index is rewritten. Returns the remap tables.
  CompactRemap compact();

  /// Reserves column capacity (bulk builders).
  void reserve(std::size_t nodes, std::size_t edges, std::size_t faces);
  /// Grows node/edge/face columns after bulk slot appends.
  void sync_node_columns();
  void sync_edge_columns();
  void sync_face_columns();

 private:
  void link_out(HalfedgeIdx h);
  void unlink_out(HalfedgeIdx h);
  [[nodiscard]] static std::string stale_message(const char* kind, std::uint32_t index, std::uint32_t generation);
};

/// Compares two models table by table. Live slots must hold bit-identical
/// columns at the same indices; dead slots are ignored (they may differ in
/// generation or stay as tombstones). Returns an empty string when equal,
/// else a description of the first difference.
[[nodiscard]] std::string diff_tables(const Model& a, const Model& b);

}  // namespace atelier
