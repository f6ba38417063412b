// ReferenceBody: a closed skin surface with semantic feature curves and
// feature points (seed 000 section 4.1.1, seed 001 section 4).
//
// Feature curves are ATTRIB_EDGEs: ordered attribute nodes (vertex, edge or
// face kind) stored by their element and parameters, never by position, so
// when the skin's node positions change (another body with the same
// topology) the curves move with the mesh. Feature points are crossings of
// two feature curves, each stored as an owner-less ATTRIB_NODE plus the pair
// of curve ids. At a feature point, feature_frame() gives the local frame of
// seed 000 eq. (1): surface normal n and unit tangents t(f1), t(f2).
//
// Reads/writes: the body's Model (nodes.position, attrib_nodes, attrib_edges)
// and the two small name tables below.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/surface_location.h>

namespace atelier {

/// One row of the feature-curve table: feature id -> name.
struct FeatureCurve {
  std::int32_t id = -1;      // the ATTRIB_EDGE's feature_id
  std::string name;          // e.g. "waist", "centre_front"
  AttribEdgeIdx edge;        // the ATTRIB_EDGE holding the ordered nodes
  bool closed = false;       // girths and armholes are closed loops
};

/// One feature point: the crossing of curves curve1 and curve2.
struct FeaturePoint {
  std::int32_t id = -1;
  std::string name;          // e.g. "waist_x_centre_front"
  AttribNodeIdx node;        // owner-less ATTRIB_NODE at the crossing
  std::int32_t curve1 = -1;  // feature ids of the two curves
  std::int32_t curve2 = -1;
};

struct ReferenceBody {
  Model model;
  SurfaceIdx skin;
  std::vector<FeatureCurve> curves;  // ids are unique (not necessarily dense)
  std::vector<FeaturePoint> points;

  [[nodiscard]] const FeatureCurve* find_curve(std::int32_t id) const noexcept;
  [[nodiscard]] const FeatureCurve* find_curve(std::string_view name) const noexcept;
  [[nodiscard]] const FeaturePoint* find_point(std::int32_t id) const noexcept;
  [[nodiscard]] const FeaturePoint* find_point(std::string_view name) const noexcept;
};


/// Adds a feature curve through the given locations (in order). Writes new
/// attribute nodes and one ATTRIB_EDGE with feature_id = id.
[[nodiscard]] Status add_feature_curve(ReferenceBody& body, std::int32_t id, std::string name,
                                       std::span<const SurfaceLocation> path, bool closed);

/// Adds a feature point at `where`, the crossing of curves c1 and c2.
[[nodiscard]] Status add_feature_point(ReferenceBody& body, std::int32_t id, std::string name,
                                       const SurfaceLocation& where, std::int32_t c1, std::int32_t c2);

/// One polyline to snap onto the skin (engine frame: metres, Y up).
struct FeaturePolyline {
  std::string name;
  bool closed = false;
  std::span<const Vec3d> points;
  std::span<const std::uint32_t> lines;  // optional: 1-based file line of each point, for messages
};

struct FeatureSnapOptions {
  /// A point farther than this from the skin (metres) is refused: it was
  /// drawn on another body, in other units or axes (docs/body-files.md).
  double tolerance = 0.01;
  /// An open curve whose snapped polyline passes within this distance
  /// (metres) of a closed curve's crosses it there: a feature point.
  double crossing_tolerance = 0.005;
  std::string source;  // the file named in messages ("" in memory)
};

struct FeatureSnapReport {
  std::size_t curves = 0, points = 0;  // added
  double max_distance = 0;             // largest point-to-skin distance snapped over (metres)
};

/// Snaps named polylines onto the skin and adds them as feature curves (issue
/// 26: a user's body with feature curves from a file): each point becomes the
/// face location (fan triangle and areal coordinates) of its closest skin
/// point, found with the Embree BVH (systems/spatial/body_bvh.h), so the curve
/// follows the mesh onto every body of the same topology (with_positions,
/// feature_curve_polyline with other positions). Curve ids are 1 + the
/// largest existing id, in order. Then every pair of a closed and an open
/// curve that come within options.crossing_tolerance gets a feature point
/// "<closed>_x_<open>" (the mannequin's naming) at the skin point closest to
/// the middle of their closest approach; profile templates anchor nodes
/// there (seed 000 eq. (1)).
///
/// Reads: the skin's faces and positions. Writes: attribute nodes and edges,
/// body.curves and body.points; on failure nothing (all points are snapped
/// and checked before anything is added).
/// Errors (naming options.source, the line, the curve and the point): a point
/// farther than options.tolerance from the skin, a name the body already has,
/// too few points, a bad tolerance, a body without faces.
[[nodiscard]] Expected<FeatureSnapReport> add_snapped_feature_curves(ReferenceBody& body,
                                                                     std::span<const FeaturePolyline> curves,
                                                                     const FeatureSnapOptions& options = {});

/// Position of an attribute node evaluated from `positions` (indexed by node
/// index) instead of the model's own column; lets one topology be evaluated
/// for many bodies without copying the model.
[[nodiscard]] Vec3d attrib_position(const Model& m, AttribNodeIdx a, std::span<const Vec3d> positions);

/// The curve as a polyline computed from current node positions (closed
/// curves do not repeat their first point).
[[nodiscard]] Expected<std::vector<Vec3d>> feature_curve_polyline(const ReferenceBody& body, std::int32_t id);
[[nodiscard]] Expected<std::vector<Vec3d>> feature_curve_polyline(const ReferenceBody& body, std::int32_t id,
                                                                   std::span<const Vec3d> positions);

/// Local frame of seed 000 eq. (1) at a feature point.
struct FeatureFrame {
  Vec3d origin = Vec3d::Zero();  // p(q_j)
  Vec3d n = Vec3d::Zero();       // unit surface normal (outward)
  Vec3d t1 = Vec3d::Zero();      // unit tangent of curve1 (in the tangent plane)
  Vec3d t2 = Vec3d::Zero();      // unit tangent of curve2
  /// (t1 x t2) . n: must stay away from 0 for eq. (1) to be invertible.
  [[nodiscard]] double triple() const noexcept { return t1.cross(t2).dot(n); }
};

/// The frame at feature point `point_id`: n is the angle-weighted normal at a
/// vertex, the mean of the two face normals on an edge, the face normal
/// inside a face; each tangent is the chord of its curve over a window of
/// about two mean segment lengths each side of the crossing (one-sided at
/// an open curve's end), projected into the tangent plane. The tangents are
/// not forced orthogonal: eq. (1) only needs (t1 x t2) . n != 0.
[[nodiscard]] Expected<FeatureFrame> feature_frame(const ReferenceBody& body, std::int32_t point_id);
[[nodiscard]] Expected<FeatureFrame> feature_frame(const ReferenceBody& body, std::int32_t point_id,
                                                   std::span<const Vec3d> positions);

/// Current skin node positions (indexed by node index; dead slots zero).
[[nodiscard]] std::vector<Vec3d> skin_positions(const ReferenceBody& body);

/// Replaces node positions (same topology, indexed by node index) and
/// refreshes the stored p_3d of every attribute node. Bumps geometry_version.
[[nodiscard]] Status set_positions(ReferenceBody& body, std::span<const Vec3d> positions);

/// A copy of `body` with other node positions: another body with the same
/// topology and features.
[[nodiscard]] Expected<ReferenceBody> with_positions(const ReferenceBody& body, std::span<const Vec3d> positions);

/// Checks the feature tables against the model: every curve's ATTRIB_EDGE is
/// alive, on the skin and carries its id; every point's node is alive and its
/// curves exist; ids and names are unique.
[[nodiscard]] Status validate_features(const ReferenceBody& body);

}  // namespace atelier
