// Profile curves on template edges: the 3D shape an edge of a profile
// template must take after regeneration.
//
// Two representations:
//   * attached point lists (seed 000 section 4.1.4): ATTRIB_EDGENODEs on the
//     edge, each a 3D point with a chord-length parameter u, created from a
//     2D stroke and a camera (Fig. 13) and shifted with the edge's ends by
//     eq. (3) (Fig. 14);
//   * Bezier curves (seed 001 section 4, "4th order" = cubic) encoded against
//     the edge's chord, ep(u) = C(u) - E(u) (eq. 6), decoded on new ends by
//     C*(u) = ep(u) + E*(u) (eq. 7).
// Both become a ProfileCurve from the edge's start node to its end node,
// which the modified variational subdivision evaluates at u = 1/2 and splits
// (seed 000 section 4.2, seed 001 "profile template decoding").
//
// Reads: Model nodes/edges/halfedges/faces (positions may be passed in
// separately) and ATTRIB_EDGENODEs. Writes: only attach_point_list /
// clear_point_list / attach_stroke_profiles, which add or remove unowned
// ATTRIB_EDGENODEs (nodes held by an ATTRIB_EDGE, e.g. feature curves, are
// never touched or read as profile points).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include <atelier/engine/handle.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/systems/view/camera.h>

namespace atelier {

/// A profile curve in world coordinates on one template edge, from the edge's
/// start node (u = 0) to its end node (u = 1).
struct ProfileCurve {
  enum class Kind : std::uint8_t { kBezier, kPolyline };
  Kind kind = Kind::kBezier;
  /// kBezier: control points (degree = size - 1 >= 1; "4th order" = cubic, 4 points);
  /// kPolyline: the points in order, both ends included.
  std::vector<Vec3d> points;
  /// kPolyline only: parameter of each point, non-decreasing from 0 to 1 (by
  /// chord length when built from points, seed 000 ref. [42]).
  std::vector<double> u;

  /// De Casteljau; polyline: piecewise linear in u. u is clamped to [0, 1].
  [[nodiscard]] Vec3d eval(double u) const;
  [[nodiscard]] Vec3d start() const { return points.front(); }
  [[nodiscard]] Vec3d end() const { return points.back(); }
  /// The two halves [0, 1/2] and [1/2, 1], each reparametrised to [0, 1]
  /// (Bezier: exact de Casteljau subdivision; polyline: cut at u = 1/2,
  /// inserting the point eval(1/2) unless a point already sits there).
  /// first.end() == second.start() == eval(0.5) exactly.
  [[nodiscard]] std::pair<ProfileCurve, ProfileCurve> split_half() const;
  /// The same curve run from end to start (C'(u) = C(1 - u)).
  [[nodiscard]] ProfileCurve reversed() const;
  /// Euclidean distance from p to the curve (polyline exact; Bezier: dense
  /// sampling, then golden-section and Newton refinement of every sampled
  /// local minimum, accurate to 1e-9 relative).
  [[nodiscard]] double distance(const Vec3d& p) const;
  /// Structure check: enough points, sizes agree, finite, u from 0 to 1 non-decreasing.
  [[nodiscard]] Status check() const;

  /// A polyline with chord-length u (uniform u if all points coincide).
  [[nodiscard]] static ProfileCurve polyline(std::span<const Vec3d> pts);
  [[nodiscard]] static ProfileCurve bezier(std::span<const Vec3d> control_points);
};

// ------------------------------------------------------ Bezier profiles (seed 001)

/// seed 001 eq. (6): ep(u) = C(u) - E(u) with E(u) = (1-u) a + u b. For a Bezier C
/// of degree n, ep is the Bezier whose control points are P_i - E(i/n)
/// (the degree-elevated chord), stored as offsets.
struct BezierProfileEncoding {
  std::vector<Vec3d> offsets;
};
/// Encodes against the curve's own ends (a = c.start(), b = c.end(), so the
/// first and last offsets are zero). kBezier only.
[[nodiscard]] Expected<BezierProfileEncoding> encode_bezier_profile(const ProfileCurve& c);
/// Encodes against explicit edge ends a, b (eq. 6 as written: if C's ends do
/// not coincide with a, b the end offsets keep the difference).
[[nodiscard]] Expected<BezierProfileEncoding> encode_bezier_profile(const ProfileCurve& c, const Vec3d& a,
                                                                    const Vec3d& b);
/// seed 001 eq. (7): C*(u) = ep(u) + E*(u) for the new edge ends a*, b*.
[[nodiscard]] ProfileCurve decode_bezier_profile(const BezierProfileEncoding& e, const Vec3d& a, const Vec3d& b);

// -------------------------------------------------- point-list profiles (seed 000)

/// seed 000: attached point list: interior points Q_i with parameters u_i, stored
/// with the edge's ends at encoding time.
struct PointListProfile {
  Vec3d a = Vec3d::Zero(), b = Vec3d::Zero();
  std::vector<double> u;
  std::vector<Vec3d> points;

  /// The profile as it stands (no shift): polyline a, Q_1..Q_k, b with u = 0, u_1..u_k, 1.
  [[nodiscard]] ProfileCurve curve() const;
};

enum class ShiftMode : std::uint8_t {
  kScale,        // seed 000 eq. (3) as written: offsets from the chord scaled by |a*b*| / |ab|
  kScaleRotate,  // eq. (3) plus the minimal rotation taking (b - a) to (b* - a*) (our default: follows the body's
                 // orientation)
};

/// eq. (3): the shifted profile as a kPolyline ProfileCurve from a* to b* (ends included).
/// A degenerate old edge (a == b) keeps the offsets unscaled and unrotated.
[[nodiscard]] ProfileCurve shift_point_list(const PointListProfile& p, const Vec3d& a_new, const Vec3d& b_new,
                                            ShiftMode mode = ShiftMode::kScaleRotate);

/// Attached points in the Model: ATTRIB_EDGENODEs on halfedge h (element = h,
/// param = (u,0,0), position = the 3D point, which may lie off the edge).
/// Replaces any profile already attached to edge_of(h) (unowned edge nodes on
/// either halfedge). Errors: dead halfedge, surface s not the edge's, size
/// mismatch, u outside [0, 1], non-finite points.
[[nodiscard]] Status attach_point_list(Model& m, SurfaceIdx s, HalfedgeIdx h, std::span<const double> u,
                                       std::span<const Vec3d> pts);
/// Removes the profile points attached to edge e; returns how many.
std::size_t clear_point_list(Model& m, EdgeIdx e);
/// The ATTRIB_EDGENODEs on edge_of(h), sorted by u as seen from tail(h) (u of the twin side = 1-u).
/// a, b are the current positions of tail(h), head(h).
[[nodiscard]] PointListProfile read_point_list(const Model& m, HalfedgeIdx h);
/// Every edge carrying profile points, in increasing edge order, each read from
/// halfedge_of(e, 0), in one pass over the attribute table.
struct EdgePointList {
  EdgeIdx edge;
  PointListProfile profile;
};
[[nodiscard]] std::vector<EdgePointList> read_all_point_lists(const Model& m);

// ------------------------------------------------------------ strokes (seed 000 Fig. 13)

/// seed 000 4.1.4: edges whose both projected ends lie within tol_px of the
/// stroke polyline and that are visible: the optional predicate must hold at
/// both ends and the midpoint (e.g. a BodyBvh ray test). positions are node
/// positions indexed by node index (empty: the model's own positions; fewer
/// than the node capacity selects nothing). Increasing edge order.
[[nodiscard]] std::vector<EdgeIdx> select_edges_by_stroke(const Model& m, std::span<const Vec3d> positions,
                                                          const Camera& cam, std::span<const Vec2d> stroke,
                                                          double tol_px,
                                                          const std::function<bool(const Vec3d&)>& visible = {});

/// Projects the stroke onto the least-squares plane of the selected edges'
/// end points (one edge: the plane containing it that bisects the dihedral
/// angle of its two faces; a boundary edge, or collinear edges: the plane
/// through it facing the camera most), by intersecting each stroke pixel's
/// camera ray with it; then cuts it per selected edge: for edge v_i v_m the
/// stroke points strictly between the point of the 3D stroke closest to v_i
/// and the one closest to v_m become its attached list (u by chord length
/// along v_i, list, v_m; ends snapped to v_i, v_m). The halfedge reported
/// runs in the stroke's direction. plane_normal is unit and faces the camera.
struct StrokeProfiles {
  std::vector<HalfedgeIdx> edges;
  std::vector<PointListProfile> profiles;
  Vec3d plane_point = Vec3d::Zero(), plane_normal = Vec3d::Zero();
  std::vector<Vec3d> stroke_points;  // the stroke on the plane (pixels whose ray misses it are dropped)
};
[[nodiscard]] Expected<StrokeProfiles> profiles_from_stroke(const Model& m, std::span<const Vec3d> positions,
                                                            const Camera& cam, std::span<const Vec2d> stroke,
                                                            double tol_px,
                                                            const std::function<bool(const Vec3d&)>& visible = {});
/// Attaches every profile of a stroke (attach_point_list on each halfedge).
[[nodiscard]] Status attach_stroke_profiles(Model& m, const StrokeProfiles& sp);

}  // namespace atelier
