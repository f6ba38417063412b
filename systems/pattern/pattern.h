// Pattern pieces a cutting room can use (issue 22), from flattened pieces
// (flatten.h: the pattern in nodes.uv): sew lines, seam allowances with
// mitred corners, notches matched between partner seams, grain lines,
// labels, mirrored left/right pieces, and the sewability check of the seams.
//
// Seams: a MESHJOINT whose members are mesh edges of flattened pieces; its
// members are the partner seams (boundary chains of the pieces sewn
// together; a member along a piece's inside is measured too, but gets no
// notches). Lengths are measured node to node along each member: in 2D on
// the pattern (mm) and in 3D on the model. A seam passes the sewability
// check when its members' 2D lengths agree within `length_tolerance_mm` and
// each member's 2D length is within `length_tolerance_3d` (relative) of its
// 3D length.
//
// Geometry of a piece, in millimetres (model units times `units_to_mm`),
// pattern coordinates (u right, v up, grain along +v):
//  * sew line: the flattened boundary loops (the outer loop first, then
//    holes), counter-clockwise for the outer loop;
//  * cut line: each boundary edge moved outwards by its allowance (its
//    seam's, or the hem allowance off seams); consecutive offset edges meet
//    at mitred corners (the intersection of the two offset lines), bevelled
//    where the mitre would reach beyond `mitre_limit` times the allowance;
//    loops that the offset makes on tight concave curves are cut out;
//  * seam allowance: per run of boundary edges with one allowance (a seam
//    member or a hem), the offset polyline of that run;
//  * notches: at both ends of every seam member (where seams meet), at the
//    marks on a seam (attribute nodes on its nodes or edges that belong to
//    no attribute edge: profile points are not marks) and, with
//    `notch_spacing_mm`, every that much 3D arc length. A notch at 3D arc
//    length s of a seam of 3D length L sits on each partner at 2D arc length
//    (s / L) * (that partner's 2D length) from the seam's start (in the
//    joint's direction), so partner notches meet when the seam is sewn. A
//    notch is a slit across the allowance: from the sew-line point, along the
//    outward normal, to the cut line;
//  * grain line: vertical through the piece's area centroid, over 70% of its
//    height; label: the piece's name at the centroid.
// Mirrored pieces (the other side of a left/right pair): u -> -u, then moved
// to start at u = 0 again; loops keep their orientation.
//
// Reads: the pieces' faces, boundary, nodes.position and nodes.uv, mesh
// edges, joints, attribute nodes. Writes: nothing but the result.
#pragma once

#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace atelier {

struct SeamAllowance {
  JointIdx seam;
  double mm = 10;
};

struct PatternOptions {
  /// Model units to millimetres (models are in metres).
  double units_to_mm = 1000;
  /// Allowance of every seam, of boundary edges on no seam (hems; negative:
  /// the seam allowance), and overrides per seam.
  double seam_allowance_mm = 10;
  double hem_allowance_mm = -1;
  std::vector<SeamAllowance> seam_allowances;
  /// Mitred corners longer than this many allowances are bevelled.
  double mitre_limit = 4;
  /// Notches every this much 3D arc length along seams, besides the ends and
  /// marks (0: none).
  double notch_spacing_mm = 0;
  /// Pieces that also appear mirrored (left/right pairs).
  std::vector<SurfaceIdx> mirror;
  /// Sewability: partners' 2D lengths within this (mm), and each within this
  /// fraction of its 3D length.
  double length_tolerance_mm = 2;
  double length_tolerance_3d = 0.005;
};

struct PatternNotch {
  Vec2d at;          // on the sew line (mm)
  Vec2d outward;     // unit normal of the sew line there, towards the cut line
  double depth = 0;  // slit length: the allowance there
  JointIdx seam;
  double fraction = 0;  // position along the seam (3D arc length / 3D length)
};

/// One run of boundary edges with one allowance: a seam member or a hem.
struct AllowanceRun {
  JointIdx seam;         // invalid for a hem
  std::size_t loop = 0;  // index into sew_line
  double width_mm = 0;
  std::vector<Vec2d> edge;  // the run's offset polyline (on the cut line)
};

struct PatternPiece {
  SurfaceIdx surface;
  std::string name;
  bool mirrored = false;
  std::vector<std::vector<Vec2d>> sew_line;  // closed loops, outer first (CCW)
  std::vector<std::vector<Vec2d>> cut_line;  // closed loops, same order
  std::vector<AllowanceRun> allowances;
  std::vector<PatternNotch> notches;
  std::array<Vec2d, 2> grain_line{Vec2d::Zero(), Vec2d::Zero()};  // from, to (+v)
  Vec2d label_at = Vec2d::Zero();
  double area_mm2 = 0;  // inside the sew line
};

struct SeamMemberLength {
  SurfaceIdx surface;
  MeshEdgeIdx mesh_edge;
  bool boundary = true;  // a boundary chain of its piece
  double length_2d_mm = 0;
  double length_3d_mm = 0;
};

struct SeamCheck {
  JointIdx joint;
  std::vector<SeamMemberLength> members;
  double max_difference_mm = 0;  // largest |L2d_a - L2d_b| over partners
  double max_deviation_3d = 0;   // largest |L2d - L3d| / L3d over partners
  bool ok = true;
};

struct PatternSet {
  std::vector<PatternPiece> pieces;
  std::vector<SeamCheck> seams;
  [[nodiscard]] std::size_t failed_seams() const noexcept;
};

/// Pattern pieces for the given flattened surfaces (their nodes.uv) and the
/// seams among them (joints with at least two members on these surfaces).
/// Errors: kStaleHandle (a dead surface), kInvalidArgument (options out of
/// range, a joint override naming no seam), kDegenerate (non-finite uv).
[[nodiscard]] Expected<PatternSet> make_pattern(const Model& m, std::span<const SurfaceIdx> pieces,
                                                const PatternOptions& opt = {});

}  // namespace atelier
