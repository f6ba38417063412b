// Curve networks to surfaces (systems/curvenet, seed 003): the call of
// `atelier surface`, over the same one library call (surface_from_curves),
// with the curves given as a list of (k, 3) arrays or read from a file by
// the CLI's reader (read_curve_network: `CURVE i` text or OBJ `l` lines).
#include <atelier/io/curve_network.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/curvenet/curve_surface.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "bind.h"

namespace atelier::python {

namespace {

namespace fs = std::filesystem;

bool is_path(py::handle h) {
  return py::isinstance<py::str>(h) || py::hasattr(h, "__fspath__");
}

PolylineSet curves_arg(py::handle curves) {
  if (is_path(curves)) {
    const fs::path p = curves.cast<fs::path>();
    py::gil_scoped_release release;
    return read_curve_network(p);
  }
  if (py::isinstance<py::array>(curves))
    value_error("curves: expected a list of (k, 3) arrays (one per curve) or a file path, got one array");
  PolylineSet set;
  std::int64_t i = 0;
  for (py::handle c : curves) {
    const std::string what = "curves[" + std::to_string(i) + "]";
    const std::vector<Vec3d> pts = points_from(c, what.c_str());
    if (pts.size() < 2) value_error(what + ": a curve needs at least 2 points, got " + std::to_string(pts.size()));
    set.add(i++, pts);
  }
  if (set.size() == 0) value_error("curves: no curves");
  return set;
}

py::dict distance_dict(const CurveDistance& d) {
  return py::dict(py::arg("samples") = d.samples, py::arg("max") = d.max, py::arg("mean") = d.mean,
                  py::arg("rms") = d.rms, py::arg("relative_max") = d.relative_max);
}

}  // namespace

void bind_curvenet(py::module_& m) {
  m.def(
      "surface_from_curves",
      [](const Curves& curves, int levels, const OptMeshLike& mesh, const std::string& cycles, std::size_t n0,
         double density, double tolerance, bool fairing, int threads, const Progress& progress) {
        if (levels < 0 || levels > 6) value_error("levels: 0 to 6, got " + std::to_string(levels));
        if (cycles != "angular" && cycles != "paper") value_error("cycles: 'angular' or 'paper', got '" + cycles + "'");
        if (n0 < 2 || n0 > 64) value_error("n0: 2 to 64, got " + std::to_string(n0));
        if (!(density >= 0) || !std::isfinite(density)) value_error("density: a finite number >= 0");
        if (!(tolerance >= 0) || !std::isfinite(tolerance)) value_error("tolerance: a finite number >= 0");
        const PolylineSet set = curves_arg(curves);
        PolygonSoup traced;
        if (!mesh.is_none()) {
          const std::shared_ptr<const Mesh> t = mesh_from(mesh, "mesh");
          const auto p = t->positions();
          traced.positions.assign(p.begin(), p.end());
          traced.face_offsets = t->soup.face_offsets;
          traced.face_nodes = t->soup.face_nodes;
          if (traced.face_count() == 0) value_error("mesh: the traced mesh has no faces");
        }
        CurveSurfaceOptions so;
        so.levels = levels;
        so.cycles = cycles == "paper" ? FaceCycleMethod::kPaperSearch : FaceCycleMethod::kAngular;
        so.control.n0 = n0;
        so.control.C = density;
        so.control.fair = fairing;
        so.treatment.intersection_tolerance = tolerance;
        CurveSurface r = unwrap(run_long(
            progress, threads, [&](const ExecContext& ctx) { return surface_from_curves(set, traced, so, ctx); }));
        if (const Status s = validate(r.model); !s)
          raise(Status(ErrorCode::kInternal, "surface_from_curves: the result fails validate(): " + s.message()));
        const CurveSurfaceReport& rep = r.report;
        const CurveTreatmentReport& t = rep.treatment;
        py::dict d;
        d["curves"] = py::dict(
            py::arg("input") = t.input_curves, py::arg("points") = t.input_points, py::arg("diagonal") = t.diagonal,
            py::arg("intersections") = t.intersections, py::arg("max_intersection_gap") = t.max_intersection_gap,
            py::arg("splits") = t.splits, py::arg("joined_ends") = t.joined_ends, py::arg("merges") = t.merges,
            py::arg("kinks") = t.kinks, py::arg("pruned_ends") = t.pruned_segments,
            py::arg("pruned_length") = t.pruned_length, py::arg("boundary_curves_added") = rep.boundary_curves);
        d["network"] = py::dict(py::arg("nodes") = rep.nodes, py::arg("segments") = rep.segments);
        py::dict by_size;
        for (const auto& [n, count] : rep.faces_by_size) by_size[py::int_(n)] = count;
        d["cycles"] = py::dict(py::arg("faces") = rep.faces, py::arg("by_size") = by_size,
                               py::arg("outer") = rep.outer_cycles, py::arg("euler") = rep.euler);
        d["stop_rule_met"] = rep.stop_rule_met;
        d["control_mesh"] =
            py::dict(py::arg("vertices") = rep.control_vertices, py::arg("quads") = rep.control_quads,
                     py::arg("knots_inserted") = rep.knots_inserted, py::arg("odd_faces") = rep.odd_faces,
                     py::arg("C") = rep.density_C, py::arg("max_fit_error") = rep.max_fit_error,
                     py::arg("inverted_quads") = rep.inverted_quads);
        d["fairing"] = py::dict(py::arg("energy_before") = rep.fairing_energy_before,
                                py::arg("energy_after") = rep.fairing_energy_after);
        py::list levels_out;
        for (const auto& l : rep.levels)
          levels_out.append(
              py::dict(py::arg("vertices") = l.vertices, py::arg("edges") = l.edges, py::arg("faces") = l.faces));
        d["levels"] = levels_out;
        d["distance_to_curves"] = distance_dict(rep.to_curves);
        if (rep.has_traced) d["distance_to_traced"] = distance_dict(rep.to_traced);
        d["warnings"] = rep.warnings;
        auto cage = std::make_shared<Mesh>();
        cage->soup = std::move(r.control.mesh);
        py::object cage_obj = py::cast(cage);
        d["control"] = py::make_tuple(cage_obj.attr("vertices"), cage_obj.attr("faces"));
        py::object out = py::cast(mesh_of(std::move(r.model)));
        return py::make_tuple(out.attr("vertices"), out.attr("faces"), d);
      },
      py::arg("curves"), py::kw_only(), py::arg("levels") = 2, py::arg("mesh") = py::none(),
      py::arg("cycles") = "angular", py::arg("n0") = 3, py::arg("density") = 0.0, py::arg("tolerance") = 1e-6,
      py::arg("fairing") = true, py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
A network of curves to a Catmull-Clark surface through them (``atelier surface``; seed 003).

curves: a list of (k, 3) float arrays (one polyline per curve, k >= 2), or
    a file path (``CURVE i`` text or OBJ ``l`` polylines, read as the CLI
    reads it).
levels: Catmull-Clark levels, 0 to 6 (0 returns the control mesh itself).
mesh: the mesh the curves were traced on (a Mesh or a (vertices, faces)
    pair; orients the faces and closes open networks), or None.
cycles: face cycles, "angular" (default) or "paper" (the paper's search).
n0: control points of the shortest curve piece (eq. 1), 2 to 64.
density: the constant C of eq. (1); 0 = automatic.
tolerance: intersection tolerance, relative to the network's size.
fairing: solve eqs. (4-7) (False keeps the eq. (3) positions).

Returns (vertices, faces, report): the subdivided surface ((n, 3) float64
and (F, 4) uint32 views; the same bits as the CLI's OBJ) and a dict:
``curves`` (treatment: intersections, merges, pruned ends...),
``network``, ``cycles`` (faces, by_size, outer, euler = V - E + F),
``stop_rule_met`` (False where the CLI exits 1), ``control_mesh``,
``fairing``, ``levels``, ``distance_to_curves`` (and
``distance_to_traced``), ``warnings`` and ``control`` (the quad control
mesh as (vertices, faces)). Long call (GIL released, Ctrl-C cancels).
Raises ValueError with the engine's message (naming the curve) for bad
curves, FileNotFoundError or ValueError for a missing or malformed file.
)doc");
}

}  // namespace atelier::python
