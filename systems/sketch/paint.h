// Mesh painting and penetrated painting (seed 001 section 5, Figs. 9-11):
// a 2D stroke drawn through a camera becomes curves on the surface, stored
// in surface coordinates as ATTRIB_EDGEs of ATTRIB_EDGENODEs (where the
// curve crosses a mesh edge: halfedge and parameter u) and ATTRIB_FACENODEs
// (stroke points inside faces, and crossings of the fan diagonals of
// polygon faces: face, fan triangle and areal coordinates).
//
// The section. Each stroke segment [p_i, p_i+1] and the eye span a plane
// (the "bounding plane" of Fig. 9); the stroke sweeps the sheet of points
// that project onto the stroke polyline. The sheet is cut with the fan
// triangles (c0, c_k+1, c_k+2) of every face (the surface the attribute
// nodes are defined on): crossings of mesh edges and fan diagonals with the
// planes, and the points where the stroke points' rays pierce triangles. The
// pieces are spliced through the connectivity (edge crossings shared by the
// two faces of an edge, piercings shared by consecutive segments; joint
// partners across surfaces) into chains, and every chain is cut where the
// stroke parameter turns back (a silhouette) into "layers": curves along
// which the stroke parameter is monotone.
//
// Robustness. Every combinatorial decision (which side of a stroke line a
// node projects to, which side of a projected edge a stroke point lies on)
// is an exact orientation test on pixel coordinates snapped to 2^-16 pixel,
// with the stroke symbolically translated by (e, e^2) to break ties, so the
// pieces always splice (no gaps, no double crossings), strokes through
// vertices or along edges included. 3D positions are computed in double:
// edge crossings on the segment's plane, piercings on the stroke point's ray.
//
// Painting keeps the one layer the stroke sees: the nearest piercing of
// every stroke point's ray must lie on one layer, and nothing may lie in
// front of that layer anywhere along it (depth compared on the sheet in
// each segment's plane). The curve runs on to where the stroke leaves the
// surface (a silhouette, a boundary) or ends. A stroke across a fold (Fig.
// 10), an occluding part or a gap fails with kDegenerate naming the stroke
// point; nothing is written. Penetrated painting keeps every layer.
//
// Visibility comes from the section itself (which piercing of a ray is
// nearest), not from an Embree BVH: the same exact pieces decide both, so a
// ray grazing an edge can never see a triangle the section did not cut, and
// no BVH is built per stroke (docs/glossary.md, departures).
//
// Cameras: any projection * view that Camera::check() accepts (perspective
// or orthographic); faces with a corner on or behind the eye plane, or
// projecting farther than 2^40 pixels, are not painted. Near and far planes
// do not clip.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/surface_location.h>
#include <atelier/systems/view/camera.h>

#include <cstdint>
#include <span>
#include <vector>

namespace atelier {

struct PaintOptions {
  /// Penetrated painting (Fig. 11b): every layer the rays cross.
  bool through = false;
  /// Surfaces to paint on (empty: every live surface). Other surfaces
  /// neither receive curves nor hide anything.
  std::vector<SurfaceIdx> surfaces;
  /// Stored in attrib_edges.feature_id of the painted curves.
  std::int32_t feature_id = -1;
};

/// One point of a traced curve.
struct CurvePoint {
  SurfaceLocation location;  // kEdge: halfedge 2e and u from its tail; kFace: face, fan corner, areal coordinates
  SurfaceIdx surface;
  Vec3d position = Vec3d::Zero();
  double s = 0;  // stroke parameter: segment index + fraction (stroke point i is at s = i)
};

/// One layer of the section: a polyline on the surface, monotone in s.
struct TracedCurve {
  std::vector<CurvePoint> points;
  /// A closed stroke (last point = first) traced all the way round: the last
  /// point repeats the first.
  bool closed = false;
  [[nodiscard]] double length() const noexcept;
};

struct TraceResult {
  std::vector<TracedCurve> curves;    // painting: one; penetrated painting: every layer, ordered by first s then depth
  std::size_t triangles_crossed = 0;  // fan triangles cut by the sheet (all layers)
  std::size_t stroke_points = 0;      // after removing repeated points
};

/// Traces the stroke (pixels) on the model through `camera` (seed 001
/// section 5, "mesh painting"). Reads: nodes, faces, halfedges, joints.
/// Writes nothing. Errors: kInvalidArgument (bad camera, fewer than 2
/// distinct or non-finite stroke points, a dead surface in options, a face
/// with more than 257 corners, a stroke that crosses no face), kDegenerate
/// for painting across a fold, an occluding part or a gap (the message
/// names the stroke point), kCancelled.
[[nodiscard]] Expected<TraceResult> trace_stroke(const Model& model, const Camera& camera,
                                                 std::span<const Vec2d> stroke, const PaintOptions& options = {},
                                                 const ExecContext& ctx = {});

struct PaintedCurve {
  /// One ATTRIB_EDGE per surface the curve crosses, in curve order. A
  /// closed curve's attribute edge repeats its first node at the end.
  std::vector<AttribEdge> edges;
  double length = 0;
  bool closed = false;
  std::size_t nodes = 0;
};

struct PaintResult {
  std::vector<PaintedCurve> curves;
  std::size_t triangles_crossed = 0;
};

/// trace_stroke, then stores every traced curve as attribute nodes (p_3d =
/// the traced position) and attribute edges. Reads as trace_stroke; writes
/// attrib_nodes, attrib_edges (appended). Transactional: on any error the
/// model is unchanged.
[[nodiscard]] Expected<PaintResult> paint_stroke(Model& model, const Camera& camera, std::span<const Vec2d> stroke,
                                                 const PaintOptions& options = {}, const ExecContext& ctx = {});

/// The nearest surface point under a pixel (the "pick" of a cut), with the
/// same exact tests as painting. Errors: kInvalidArgument when no face of
/// the surfaces lies under it (or a bad camera / pixel).
[[nodiscard]] Expected<CurvePoint> locate_pixel(const Model& model, const Camera& camera, const Vec2d& pixel,
                                                std::span<const SurfaceIdx> surfaces = {}, const ExecContext& ctx = {});

}  // namespace atelier
