// The eight extended Euler operators of the non-manifold structure and their
// inverses (seed 000 section 3 and Appendix III, Table A-1; seed 001
// Appendix B). Each operator changes the terms of
//     V - E + F - R = C - H + S
// (nodes, edges, faces, rings, components, complex holes "Chole", closed
// shells) by a fixed amount and keeps `model.complex_holes` (H) in step, so
// validate() holds after every call:
//
//   make/kill_vertex_complex        V+1, C+1
//   make/kill_vertex_edge           V+1, E+1
//   make/kill_edge_Chole            E+1, H+1   (ends already connected)
//   make_edge_kill/kill_edge_make_complex   E+1, C-1
//   make_face_kill/kill_face_make_Chole     F+1, H-1   (or F+1, S+1 when the
//                                   new face closes its face-connected group)
//   make/kill_vertex_ring           V+1, R+1   (stand-alone node in a face)
//   make_edge_kill/kill_edge_make_ring      E+1, R-1
//   split/merge_edge                V+1, E+1
//
// Every operator checks its preconditions and returns a Status naming the
// offending element. Every kill operator returns a record holding exactly
// what the matching make needs to undo it: because the free lists are LIFO
// and node rings are kept sorted, make(kill(x)) puts every element back in
// its old slot and diff_tables() finds no difference (and likewise
// kill(make(x))).
//
// Reads and writes: node, edge, halfedge and face tables, mesh edge chains,
// attribute nodes (edge-nodes and face-nodes of split/merged edges) and
// model.complex_holes. Connectivity tests (same component? does removing the
// edge disconnect its ends?) are BFS over the component, so they cost
// O(component); the high-level operators (systems/edit.h) know their net
// effect on H and use the unchecked primitives instead.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

namespace atelier {

/// Everything a node slot holds (so a killed node comes back bit-identical).
struct NodeRecord {
  SurfaceIdx surface;
  Vec3d position = Vec3d::Zero();
  Vec3d position_backup = Vec3d::Zero();
  Vec2d uv = Vec2d::Zero();
  FaceIdx in_face;  // set for ring nodes
};

/// A wire edge: halfedge 2e runs tail -> head.
struct EdgeRecord {
  NodeIdx tail;
  NodeIdx head;
  std::uint8_t flags = 0;
};

/// A face: its halfedge cycle starting at faces.halfedge[f].
struct FaceRecord {
  SurfaceIdx surface;
  std::vector<HalfedgeIdx> cycle;
  std::uint8_t flags = 0;
  bool closed_shell = false;  // the face closed (or belonged to) a closed shell: S changed instead of H
};

/// make_vertex_edge's input / kill_vertex_edge's record.
struct VertexEdgeRecord {
  NodeIdx anchor;             // the existing node
  NodeRecord node;            // the new (killed) node
  bool from_anchor = true;    // halfedge 2e runs anchor -> node
  std::uint8_t flags = 0;
};

struct VertexEdge {
  Node node;
  Edge edge;
};

/// Old state of an attribute node changed by split/merge (restored by the inverse).
struct AttribChange {
  AttribNodeIdx node;
  AttribNodeKind kind = AttribNodeKind::kVertex;
  std::uint32_t element = 0;
  std::uint8_t corner = 0;
  Vec3d param = Vec3d::Zero();
};

struct SplitEdgeResult {
  Node node;      // the new node m
  Edge new_edge;  // m -> old head of the split halfedge
  std::vector<AttribChange> attribs;  // pre-split state of the edge/face attribute nodes it moved
};

/// merge_edge's record: what split_edge needs to rebuild the exact tables.
struct MergeEdgeRecord {
  HalfedgeIdx kept;            // halfedge of the kept edge whose tail is not the merged node
  NodeRecord node;             // the merged node
  bool removed_forward = true; // the removed edge's halfedge 2r ran node -> far end
  std::uint8_t removed_flags = 0;
  bool face_start_on_removed[2] = {false, false};  // faces.halfedge pointed at the removed edge (sides of `kept`, twin)
  std::vector<AttribChange> attribs;  // pre-merge state of the attribute nodes it moved
};

// ------------------------------------------------------------- vertices

/// New isolated node in surface s (V+1, C+1).
[[nodiscard]] Expected<Node> make_vertex_complex(Model& m, Surface s, const Vec3d& position);
[[nodiscard]] Expected<Node> make_vertex_complex(Model& m, const NodeRecord& r);
/// Kills an isolated, non-ring node carrying no attribute node (V-1, C-1).
[[nodiscard]] Expected<NodeRecord> kill_vertex_complex(Model& m, Node v);

/// New node joined to `anchor` by a new wire edge anchor -> node (V+1, E+1).
/// When the anchor is a ring node the new node joins its ring (same face).
[[nodiscard]] Expected<VertexEdge> make_vertex_edge(Model& m, Node anchor, const Vec3d& position);
[[nodiscard]] Expected<VertexEdge> make_vertex_edge(Model& m, const VertexEdgeRecord& r);
/// Kills a degree-1 node and its wire edge (V-1, E-1).
[[nodiscard]] Expected<VertexEdgeRecord> kill_vertex_edge(Model& m, Node v);

// ---------------------------------------------------------------- edges

/// Wire edge a -> b between two nodes of one component (E+1, H+1). Ring
/// nodes must lie in the same ring.
[[nodiscard]] Expected<Edge> make_edge_Chole(Model& m, Node a, Node b);
[[nodiscard]] Expected<Edge> make_edge_Chole(Model& m, const EdgeRecord& r);
/// Kills a wire edge whose ends stay connected without it (E-1, H-1).
[[nodiscard]] Expected<EdgeRecord> kill_edge_Chole(Model& m, Edge e);

/// Wire edge a -> b joining two components (E+1, C-1). No ring nodes.
[[nodiscard]] Expected<Edge> make_edge_kill_complex(Model& m, Node a, Node b);
[[nodiscard]] Expected<Edge> make_edge_kill_complex(Model& m, const EdgeRecord& r);
/// Kills a bridge wire edge between non-ring nodes (E-1, C+1).
[[nodiscard]] Expected<EdgeRecord> kill_edge_make_complex(Model& m, Edge e);

/// Wire edge a -> b joining two different rings of one face (E+1, R-1).
[[nodiscard]] Expected<Edge> make_edge_kill_ring(Model& m, Node a, Node b);
[[nodiscard]] Expected<Edge> make_edge_kill_ring(Model& m, const EdgeRecord& r);
/// Kills a bridge wire edge between ring nodes (E-1, R+1).
[[nodiscard]] Expected<EdgeRecord> kill_edge_make_ring(Model& m, Edge e);

// ---------------------------------------------------------------- faces

/// Face on a closed chain of faceless halfedges (each one's head is the next
/// one's tail; at least 3, distinct non-ring nodes of one surface).
/// F+1, H-1; or F+1, S+1 when the face-connected group it joins becomes
/// closed. faces.halfedge[f] = cycle[0].
[[nodiscard]] Expected<Face> make_face_kill_Chole(Model& m, std::span<const HalfedgeIdx> cycle);
[[nodiscard]] Expected<Face> make_face_kill_Chole(Model& m, const FaceRecord& r);
/// Kills a face holding no ring node and no attribute face-node (F-1, H+1; or
/// F-1, S-1 when its group was a closed shell).
[[nodiscard]] Expected<FaceRecord> kill_face_make_Chole(Model& m, Face f);

// ---------------------------------------------------------------- rings

/// Stand-alone node lying in face f (V+1, R+1).
[[nodiscard]] Expected<Node> make_vertex_ring(Model& m, Face f, const Vec3d& position);
[[nodiscard]] Expected<Node> make_vertex_ring(Model& m, const NodeRecord& r);
/// Kills an isolated ring node (V-1, R-1).
[[nodiscard]] Expected<NodeRecord> kill_vertex_ring(Model& m, Node v);

// ------------------------------------------------------------ split/merge

/// Splits edge e at `position` (V+1, E+1): e keeps halfedge 2e's tail and now
/// ends at the new node m; a new edge runs m -> old head. Faces on both sides
/// gain the corner m (their first corner is kept); a mesh edge holding e gets
/// the new edge next to e, in chain order; ATTRIB_EDGENODEs on e move to the
/// half containing them with reparametrised u, face-nodes of the two faces
/// are re-expressed in the new fan. Refused (kJointRefused) on a joint edge:
/// use edge_split() (systems/edit.h), which splits every joint member.
[[nodiscard]] Expected<SplitEdgeResult> split_edge(Model& m, Edge e, const Vec3d& position);
/// Same, keeping the tail of halfedge h.
[[nodiscard]] Expected<SplitEdgeResult> split_edge(Model& m, Halfedge h, const Vec3d& position);
/// Exact inverse of merge_edge.
[[nodiscard]] Expected<SplitEdgeResult> split_edge(Model& m, const MergeEdgeRecord& r);

/// Merges the two edges of a degree-2, non-ring node v into `keep` (V-1,
/// E-1): keep then runs to the far end of the other edge, which is removed.
/// Both edges must be in the same mesh edge or none, and not in a joint.
/// `restore` (from split_edge) puts moved attribute nodes back bit-exactly.
[[nodiscard]] Expected<MergeEdgeRecord> merge_edge(Model& m, Node v, Edge keep,
                                                   std::span<const AttribChange> restore = {});

// ----------------------------------------------- queries used by the checks

/// True when a and b are joined by a path of edges (BFS, O(component)).
[[nodiscard]] bool edge_connected(const Model& m, NodeIdx a, NodeIdx b, EdgeIdx skip = EdgeIdx{});
/// True when the face-connected group of f has no faceless twin (BFS).
[[nodiscard]] bool face_group_closed(const Model& m, FaceIdx f);

namespace euler_detail {
// Unchecked building blocks shared with systems/edit.cpp. Preconditions are
// the caller's; they keep incidence symmetric but do not touch complex_holes.

/// Splits the edge of h at p: tail(h) is kept, the new edge g runs m -> old
/// head(h) with halfedge 2g in h's direction when `new_forward`. Returns m and
/// the new edge; appends the old state of moved attribute nodes to `changes`.
struct RawSplit {
  NodeIdx node;
  EdgeIdx edge;
};
RawSplit split_edge_raw(Model& m, HalfedgeIdx h, const Vec3d& p, bool new_forward,
                        std::vector<AttribChange>* changes);
/// Puts attribute nodes back to a recorded state.
void restore_attribs(Model& m, std::span<const AttribChange> changes);
/// Re-attaches face-nodes whose 3D surface position is `where` to the fan
/// triangle of `candidates` that contains it best (largest minimum areal
/// coordinate), clamping the coordinates to a convex combination.
void relocate_face_node(Model& m, AttribNodeIdx a, const Vec3d& where, std::span<const FaceIdx> candidates);
}  // namespace euler_detail

}  // namespace atelier
