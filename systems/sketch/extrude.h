// Sketch extrusion (seed 002, Wang and Yuen, "Freeform extrusion by sketched
// input"): a base curve B on the mesh and one or two extruding strokes drawn
// from a second camera grow a surface out of (or, drawn into the object, a
// cavity into) the mesh.
//
//  1. Base curve (section 3.1). A closed base stroke (last point = first) is
//     painted on the surface (systems/sketch/paint.h), re-triangulated and
//     the faces inside it removed (cut_along_curves without a pick: every
//     piece but the largest, i.e. the side the stroke encloses): B is the new
//     boundary ring. An open base stroke selects boundary edges: the
//     boundary node nearest on screen to each of its ends (within
//     pick_radius pixels) and the boundary arc between them that stays
//     within pick_radius of the stroke (the result stays manifold). A closed
//     stroke along a whole boundary loop selects the loop (a sleeve from an
//     armhole).
//  2. Projection plane (eq. 1): through P1* and P2*, the points of B nearest
//     on screen to the strokes' ends, parallel to n_B, the normal of B's
//     least-squares plane; its normal n_p = (P2* - P1*) x n_B, turned towards
//     the camera. Every stroke pixel's ray is cut with it.
//  3. Sweep (Figs. 5-6, eq. 2): a left and a right point advance along the
//     projected stroke(s); each step takes, of "left", "right" and "both",
//     the case with the shortest new segment P1'P2' (goodness 1/l; ties to
//     the lower case), and places a copy of B by the similarity mapping
//     P1*P2* onto P1'P2' (frames [n_p, e, n_p x e], scale |P1'P2'|/|P1*P2*|).
//     One stroke (a closed extrusion, B a ring): the points start at its two
//     ends and walk towards each other; the last copy is a single vertex.
//     Two strokes (an open extrusion): each point walks along its stroke.
//  4. Sewing (contour stitching, Figs. 7-8): two triangles per segment of B
//     between neighbouring copies, strip after strip from B outwards (rule
//     1), each oriented so that the strip's edge on the previous copy is
//     negative in it where it was positive in the previous strip (rule 2).
//  5. Mesh optimisation (Fig. 9; the paper's [1]) of the new faces only:
//     optimise_region (systems/sketch/optimise_region.h) towards L, the mean
//     edge length of B, B fixed: split, collapse, swap with the edit
//     operators, tangential relaxation projected onto the swept triangles,
//     then a local repair until every new edge is within [4/5 L, 4/3 L].
//
// Counts before optimisation, K copies (report.copies): a ring of n nodes
// with a closed extrusion adds n(K-1) + 1 nodes and n(2K-1) triangles; a
// chain of n edges with an open extrusion (n+1)K nodes and 2nK triangles;
// a ring of n nodes with an open extrusion nK nodes and 2nK triangles.
//
// Reads: the model, the strokes and cameras. Writes: nodes, edges, faces of
// B's surface (appended; the base cut removes faces), the painted base curve
// (kept as an attribute edge along B), model.complex_holes (recounted),
// topology_version. B's nodes keep their indices and positions bit for bit.
//
// With options.body: new nodes pushed out of the body (see ExtrudeOptions).
// With options.as_surface: the extruded part in its own surface, joined to
// B's surface along B by MESHJOINTs (B's nodes stay with the base; where B
// runs along a mesh edge a joint already holds, the part joins that joint,
// a seam of three or more surfaces, seed 000 Fig. 4).
//
// Transactional: on any error the model is unchanged (diff_tables == "").
// Errors: kInvalidArgument (fewer than 2 distinct or non-finite stroke
// points, a bad camera, a base stroke that selects no boundary arc, an
// extruding stroke that does not start within pick_radius of B, one stroke
// with an open B, more than 2 strokes, a negative or non-finite
// clearance), kDegenerate (B's least-squares fit has
// no area, P1*P2* parallel to n_B, a plane seen edge-on, strokes that cross
// so that a copy collapses to a point), kNonManifold (a boundary node with
// several boundary arcs), those of paint_stroke and cut_along_curves, and
// kCancelled; with options.as_surface also kJointRefused (B runs along one
// mesh edge in several stretches) and kUnsupported (attribute nodes on the
// part); with options.mirror also kInvalidArgument (a bad plane or
// tolerance, strokes or parts that cross the plane: "drawn side: ...") and
// kDegenerate (no mirror base curve: "mirror side: ... the mesh is not
// symmetric there"). The single-threaded result is the result: every step runs in a
// fixed order (ExecContext threads do not change a bit).
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/sketch/optimise_region.h>
#include <atelier/systems/sketch/retriangulate.h>
#include <atelier/systems/spatial/collision_body.h>
#include <atelier/systems/view/camera.h>
#include <atelier/systems/view/strokes.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace atelier {

struct ExtrudeStrokes {
  /// The base stroke (pixels through base_camera): closed (last point =
  /// first) paints and cuts a ring; open selects boundary edges.
  Camera base_camera;
  std::vector<Vec2d> base;
  /// The extruding strokes (pixels through sweep_camera): one for a closed
  /// extrusion (starts and ends near B), two for an open one (each starts
  /// near B).
  Camera sweep_camera;
  std::vector<std::vector<Vec2d>> sweep;
};

/// A symmetry plane through `point` with normal `normal` (any length > 0).
/// The default is the body's sagittal plane x = 0 of the Y-up garment frame
/// (the mannequins' left and right mirror across it).
struct SymmetryPlane {
  Vec3d point = Vec3d::Zero();
  Vec3d normal = Vec3d::UnitX();
};

struct ExtrudeOptions {
  /// Surfaces the base stroke paints on / selects boundary edges of (empty: all).
  std::vector<SurfaceIdx> surfaces;
  /// Screen distance (pixels) within which stroke ends must lie from B, and
  /// an open base stroke from the boundary it selects.
  double pick_radius = 12.0;
  /// Mesh optimisation of the new region (step 5, optimise_region.h):
  /// optimisation.target is set to L, B's mean edge length; B is fixed.
  bool optimise = true;
  RegionOptimiseOptions optimisation;
  /// Beyond the paper (which lists collision as future work): a body the
  /// extruded part is kept outside of, e.g. a sleeve grown from a garment on
  /// a mannequin. Not owned; it must outlive the call. Every new node closer
  /// than `clearance` to it (or inside) moves to its closest body point plus
  /// `clearance` along the outward normal (the push of the garment family's
  /// collision pass, systems/garment/collision_pass.h step 3, on the same
  /// CollisionBody queries), before the optimisation (whose projection then
  /// keeps the pushed surface) and again after it, up to push_rounds times.
  const CollisionBody* body = nullptr;
  double clearance = 0.002;
  int push_rounds = 4;
  /// With a body and the optimisation (systems/sketch/extrude_body.cpp):
  /// before it, `body_smoothing` umbrella steps on the pushed nodes and two
  /// rings around them, each followed by the push, so that the surface the
  /// optimisation keeps to is not folded where the push moved nodes onto
  /// the body; after the last push, up to `settle_rounds` times, the faces
  /// around the edges then outside the bounds optimised again (B fixed)
  /// and pushed. On by default (8 and 8): on the project top's sleeve over
  /// 100 mannequins they bring the edges out of bounds after the last push
  /// from 0 / 8 / 60 (min / median / max per body; 1188 in all) to 0 / 0 / 31
  /// (160; 90 bodies at 0), with the open end's chamfers collapsing in
  /// optimise_region (docs/performance.md, "issue 21, sweep11"); 0 turns
  /// either off.
  int body_smoothing = 8;
  int settle_rounds = 8;
  /// Beyond the paper: the extruded part becomes its own MESHSURFACE joined
  /// to the base along B by MESHJOINTs (systems/sketch/extrude_surface.cpp:
  /// B's nodes and edges duplicated on the part's side, one mesh edge per
  /// side and stretch of B), instead of being merged into B's surface. A
  /// stretch of B on a mesh edge that is already in a joint (a seam to
  /// another surface) adds the part's mesh edge to that joint, placed
  /// clockwise about the joint direction (the joint cut at the stretch's
  /// ends first when it runs beyond them); the rest of B gets a joint of
  /// its own.
  bool as_surface = false;
  RetriangulateOptions retriangulate;
  /// Beyond the paper (issue 21, "mirrored pairs"): with a plane, the strokes
  /// make two extrusions, the drawn one and its mirror image across the
  /// plane (both sleeves from one stroke). Off by default. The mirror base
  /// curve B' is found on the mesh: the drawn strokes seen through the
  /// reflected cameras (each camera's view composed with the reflection and
  /// its picture flipped left-right, so a pixel (x, y) becomes (width - x,
  /// y)) select the reflected boundary arc, or paint and cut the reflected
  /// ring; every node of B' must lie within mirror_tolerance * L of the
  /// reflection of its node of B (else: the mesh is not symmetric there).
  /// The drawn part is swept, sewn and optimised once; the mirror part is
  /// its exact reflection (nodes reflected, faces reversed so that normals
  /// stay outward), sewn onto B': the optimisation is not reflection
  /// symmetric (edge order, ties), so it runs on one region only. With a
  /// body, the mirror part's nodes get the same push (a no-op for a body
  /// symmetric about the plane). With as_surface, each part is its own
  /// surface with its own joint along its base.
  std::optional<SymmetryPlane> mirror;
  double mirror_tolerance = 1e-6;
};

/// An extrusion relative to its base curve B (systems/sketch/extrude_recipe.h:
/// B's frame, P_i* as points of B's segments, the copies' similarities in
/// that frame), filled by extrude() and replayed by replay_extrusion().
struct ExtrusionRecipe {
  std::vector<std::uint32_t> base;               // B's node indices in order
  bool ring = false;                             // B is a boundary loop
  bool capped = false;                           // the last copy is one vertex (closed extrusion)
  std::uint32_t p1_segment = 0, p2_segment = 0;  // P_i* = B[s] + t (B[s+1] - B[s])
  double p1_t = 0, p2_t = 0;
  double normal_sign = 1;  // n_p = normal_sign * unit(e x n_B)
  /// Copy k in B's frame: x_loc' = translations[k] + scales[k] * rotations[k] * x_loc.
  std::vector<double> scales;
  std::vector<Mat3d> rotations;
  std::vector<Vec3d> translations;
};

struct ExtrudeReport {
  bool base_ring = false;                        // B is a closed ring
  bool capped = false;                           // closed extrusion: the last copy is one vertex
  std::vector<NodeIdx> base;                     // B's nodes in order (along its faceless halfedges)
  double base_mean_edge = 0;                     // L, the optimisation target
  Vec3d base_normal = Vec3d::Zero();             // n_B (least squares)
  Vec3d plane_normal = Vec3d::Zero();            // n_p (eq. 1), towards the camera
  Vec3d p1 = Vec3d::Zero(), p2 = Vec3d::Zero();  // P1*, P2*
  std::size_t copies = 0;                        // K
  /// The similarity of each copy k = 1..K: x' = translation + scale * rotation * x.
  std::vector<double> scales;
  std::vector<Mat3d> rotations;
  std::vector<Vec3d> translations;
  /// The same extrusion relative to B (replay_extrusion; usable on another
  /// model when B was a boundary, faces_removed == 0).
  ExtrusionRecipe recipe;
  std::size_t faces_removed = 0;                 // by the base cut
  std::size_t swept_nodes = 0, swept_faces = 0;  // added by sweep and sewing
  std::size_t splits = 0, collapses = 0, swaps = 0;
  std::size_t settle_ops = 0;  // operations of the settle rounds after the last push
  /// Of the new region, around the optimisation; with a body and settle
  /// rounds, `after` is of every edge with a new node after the last push.
  EdgeLengthStats before, after;
  double max_deviation = 0;                      // of the optimised nodes from the swept surface
  std::size_t nodes_added = 0, faces_added = 0;  // net, after optimisation
  double volume_change = 0;                      // signed volume (of B's surface) after minus before
  /// With a body: new nodes pushed (counting each once) and new nodes still
  /// inside it (signed distance < 0) at the end; the smallest signed
  /// distance of a new node to it at the end.
  std::size_t pushed = 0, inside_after = 0;
  double min_body_distance = 0;
  /// With as_surface: the extruded part's surface and the joint(s) along B.
  SurfaceIdx part_surface;
  std::vector<Joint> joints;
  /// With options.mirror: B' (mirror_base[i] is the node at the reflection
  /// of base[i]), the largest distance between them and the reflections,
  /// the mirror part's nodes and faces (already counted in nodes_added and
  /// faces_added, which then hold both parts), its surface and joint(s).
  bool mirrored = false;
  std::vector<NodeIdx> mirror_base;
  double mirror_base_error = 0;
  std::size_t mirror_nodes = 0, mirror_faces = 0;
  SurfaceIdx mirror_part_surface;
  std::vector<Joint> mirror_joints;
};

/// The extrusion held by the run of "extrude" strokes starting at stroke
/// `first` of a stroke file (docs/strokes.md): the base stroke, then one or
/// two extruding strokes, each through its own camera or the file's. Reads
/// the file only. kInvalidArgument when no such run starts there.
[[nodiscard]] Expected<ExtrudeStrokes> extrusion_from_file(const StrokeFile& file, std::size_t first = 0);

/// The body an extrusion is kept outside of (ExtrudeOptions::body), from a
/// closed mesh: its faces fanned into triangles, the collision topology and
/// the committed BVH (the garment family's CollisionBody). Reads `body`;
/// writes `out` only on success. kInvalidArgument naming the cause (no
/// faces, a degenerate or out-of-range face).
[[nodiscard]] Status collision_body_of(const Model& body, CollisionBody& out);

/// Extrudes (see above).
[[nodiscard]] Expected<ExtrudeReport> extrude(Model& model, const ExtrudeStrokes& strokes,
                                              const ExtrudeOptions& options = {}, const ExecContext& ctx = {});

}  // namespace atelier
