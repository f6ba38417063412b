// The quad control mesh of a curve network (seed 003 sections 4.3 and 6):
//
//  1. density, eq. (1): segment s gets n_s = n0 C L_s / L_0 control points
//     (L_0 the shortest segment's length), rounded, at least n0 (so the
//     shortest gets n0) and at most max_points. The paper leaves C open;
//     Atelier's default is C = L_0 / (2 L_m), L_m the median length, so the
//     density does not hang on the one shortest piece (docs/glossary.md);
//  2. parity: a cycle with an odd number of polygon edges cannot be all
//     quads; one knot (one more control point) is inserted on segments
//     chosen so that every face becomes even: segments shared by two odd
//     faces first, then outer-boundary segments of odd faces, then paths
//     of a spanning tree of the faces (a T-join: each knot flips the parity
//     of the two faces beside its segment);
//     Before that, a segment whose fit strays beyond fit_tolerance gets more
//     points (our addition, see ControlMeshOptions::fit_tolerance);
//  3. each segment's control polygon is fitted to its curve
//     (fit_crease_polygon): the crease limit of the subdivision is then the
//     curve's B-spline approximation, through the nodes exactly;
//  4. every face cycle is quadrangulated (quadrangulate_cycle, eq. 3);
//  5. the interior vertices are faired (fair_quad_mesh, eqs. 4-7) with the
//     network's vertices fixed.
//
// Vertex numbering: the graph's nodes [0, V), then each segment's interior
// control points in segment order, then each face's new vertices in face
// order. The creases are the control polygons' edges; the corners are the
// nodes (except a node closing a loop on its own, which is smooth).
//
// Reads: the graph and its face cycles. Writes: nothing outside the result.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/curvenet/curve_network.h>
#include <atelier/systems/curvenet/face_cycles.h>
#include <atelier/systems/curvenet/quad_fairing.h>
#include <atelier/systems/curvenet/quadrangulate.h>

namespace atelier {

struct ControlMeshOptions {
  std::size_t n0 = 3;  // control points of the shortest segment (eq. 1), >= 2
  /// The model constant of eq. (1); 0 (the default) means L_0 / (2 L_m),
  /// L_m the median segment length: segments up to twice the median get n0
  /// points, longer ones proportionally more, whatever the shortest is.
  double C = 0;
  std::size_t max_points = 64;  // per segment
  /// Not in the paper (its section 7 asks for curvature to count): a
  /// segment whose fitted spline strays farther than this (x the network's
  /// diagonal) from its curve gets more points (x 1.5 until it fits or
  /// reaches max_points). 0 turns it off (eq. 1 alone).
  double fit_tolerance = 1e-3;
  QuadrangulateOptions quadrangulate;
  bool fair = true;
  QuadFairingOptions fairing;
};

struct ControlMesh {
  PolygonSoup mesh;                                   // positions and quads (counter-clockwise about the normals)
  std::vector<std::array<std::uint32_t, 2>> creases;  // every control-polygon edge of the network
  std::vector<std::uint32_t> corners;                 // vertices the subdivision keeps fixed
  std::vector<std::uint8_t> fixed;                    // per vertex: lies on the network
  /// Segment s's control polygon: vertices segment_vertices[segment_offsets[s] .. [s+1]), from its first node.
  std::vector<std::uint32_t> segment_offsets{0};
  std::vector<std::uint32_t> segment_vertices;
  /// Face f's quads are mesh faces [face_quads[f], face_quads[f+1]); its
  /// boundary has face_boundary[f] vertices, its interior face_interior[f].
  std::vector<std::uint32_t> face_quads{0};
  std::vector<std::uint32_t> face_boundary, face_interior;

  // Report.
  double shortest_segment = 0;
  double C = 0;                      // the constant of eq. (1) used
  std::size_t network_vertices = 0;  // nodes + segment interior control points
  std::size_t knots_inserted = 0;
  std::size_t raised_segments = 0;  // segments given more points than eq. (1) by fit_tolerance
  double max_fit_error = 0;         // largest crease_fit_error over the segments
  std::size_t odd_faces = 0;        // before the knots
  /// Quads whose normal points against their face cycle's (Newell) normal:
  /// folds, which the linear fairing cannot undo in strongly concave
  /// cycles (cusps).
  std::size_t inverted_quads = 0;
  QuadFairingReport fairing;
  double fairing_energy_before = 0, fairing_energy_after = 0;
};

/// Builds the control mesh. Errors: bad options (kInvalidArgument); cycles
/// that overlap (a segment side in two faces: kTopology); a face
/// that stays odd (only when it has no segment to put a knot on: a closed
/// network with an odd number of odd faces cannot occur), the errors of
/// quadrangulate_cycle and fair_quad_mesh.
[[nodiscard]] Expected<ControlMesh> build_control_mesh(const CurveGraph& g, const FaceCycles& cycles,
                                                       const ControlMeshOptions& opt = {}, const ExecContext& ctx = {});

}  // namespace atelier
