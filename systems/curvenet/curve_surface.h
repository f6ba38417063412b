// From a network of curves to a subdivision surface through them (seed 003,
// Li & Lou 2014, the whole method; issue 23): curve treatment
// (curve_network.h), face cycles (face_cycles.h), the quad control mesh with
// eq. (1) density, parity knots, eq. (3) quadrangulation and eqs. (4)-(7)
// fairing (control_mesh.h), then Catmull-Clark with the network's polygon
// edges as infinitely sharp creases and its nodes as corners
// (catmull_clark.h), so the limit surface runs through the curves' B-spline
// approximations. The result is also a Model surface (storage/builder.h),
// for validate() and the OBJ writer.
//
// The traced mesh (optional: the surface the curves were drawn on) is used
// two ways: its normals orient the nodes' tangent planes for face tracing
// (the planes themselves come from the curves' tangents); its boundary
// loops close an open network whose free curve ends reach them (the parts
// of a loop that run along an input curve are left out, the rest are added
// as curves). Distances from the subdivided surface to the
// input curves (their points on the kept segments) and to the traced mesh
// (from every subdivided vertex) are reported.
//
// Reads: the curves, the traced mesh. Writes: nothing outside the result.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/io/curve_network.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/curvenet/catmull_clark.h>
#include <atelier/systems/curvenet/control_mesh.h>
#include <atelier/systems/curvenet/curve_network.h>
#include <atelier/systems/curvenet/face_cycles.h>

namespace atelier {

struct CurveSurfaceOptions {
  CurveTreatmentOptions treatment;
  FaceCycleMethod cycles = FaceCycleMethod::kAngular;
  std::size_t max_cycle_length = 8;  // kPaperSearch only
  ControlMeshOptions control;
  int levels = 2;  // Catmull-Clark levels, chosen by the caller
  /// A boundary edge of the traced mesh whose two ends lie within this
  /// distance (x the network's diagonal) of an input curve runs along that
  /// curve and is not added.
  double boundary_cover = 1e-3;
  /// Build the Model surface (and validate it).
  bool build_model = true;
};

struct CurveDistance {
  std::size_t samples = 0;
  double max = 0, mean = 0, rms = 0;
  double relative_max = 0;  // max / network diagonal
};

struct CurveSurfaceReport {
  CurveTreatmentReport treatment;
  std::size_t boundary_curves = 0;  // pieces of the traced mesh's boundary added
  std::size_t nodes = 0, segments = 0;
  std::size_t faces = 0, outer_cycles = 0;
  std::int64_t euler = 0;
  std::map<std::size_t, std::size_t> faces_by_size;
  bool stop_rule_met = true;
  std::size_t control_vertices = 0, network_vertices = 0, control_quads = 0, knots_inserted = 0, odd_faces = 0;
  double shortest_segment = 0;
  double density_C = 0;  // the constant of eq. (1) used
  std::size_t raised_segments = 0;
  double max_fit_error = 0;  // largest distance between a curve and its control polygon's B-spline (parametric)
  double fairing_energy_before = 0, fairing_energy_after = 0;
  std::size_t inverted_quads = 0;  // control quads folded against their face cycle
  struct Level {
    std::size_t vertices = 0, edges = 0, faces = 0;
  };
  std::vector<Level> levels;  // control mesh, then each subdivision level (edges unknown for the last: 0)
  CurveDistance to_curves;
  bool has_traced = false;
  CurveDistance to_traced;
  std::map<std::string, double> seconds;  // per stage
  std::vector<std::string> warnings;
};

struct CurveSurface {
  CurveGraph graph;
  FaceCycles cycles;
  ControlMesh control;
  SubdividedMesh refined;
  Model model;  // one surface "curve_surface" holding `refined` (empty when build_model is off)
  CurveSurfaceReport report;
};

/// The whole pipeline. `traced` may be empty (no faces). Errors: those of
/// each step (naming the curve for bad curves, kTopology when the network
/// has no cycle), a traced mesh with non-finite points or bad faces
/// (kInvalidArgument), a non-finite result (kDegenerate), kCancelled.
[[nodiscard]] Expected<CurveSurface> surface_from_curves(const PolylineSet& curves, const PolygonSoupView& traced,
                                                         const CurveSurfaceOptions& opt = {},
                                                         const ExecContext& ctx = {});

}  // namespace atelier
