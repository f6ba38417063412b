// Flattening a model's pieces into 2D patterns (systems/pattern): the
// flattening `atelier flatten` does before it writes its files
// (write_pattern_files calls flatten_surfaces, then makes the pattern and
// writes SVG/DXF/PNG), here as arrays: the planar position of every vertex
// and, per piece, its triangles and distortion figures.
#include <atelier/storage/builder.h>
#include <atelier/systems/pattern/flatten.h>
#include <atelier/systems/pattern/made_to_measure_templates.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bind.h"

namespace atelier::python {

namespace {

SurfaceIdx surface_named(const Model& m, const std::string& name) {
  for (std::uint32_t s = 0; s < m.surfaces.slots.capacity(); ++s)
    if (m.alive(SurfaceIdx{s}) && m.surfaces.name[s] == name) return SurfaceIdx{s};
  std::string names;
  for (std::uint32_t s = 0; s < m.surfaces.slots.capacity(); ++s)
    if (m.alive(SurfaceIdx{s})) names += (names.empty() ? "" : ", ") + m.surfaces.name[s];
  value_error("surfaces: no surface named '" + name + "' (surfaces: " + names + ")");
}

/// The made-to-measure options the Python calls take (the rest default).
MadeToMeasureOptions mtm_options(const std::optional<std::vector<std::pair<std::string, double>>>& lines, bool svg,
                                 bool dxf, bool csv, bool marked_seams) {
  MadeToMeasureOptions o;
  o.files.svg = svg;
  o.files.dxf = dxf;
  o.csv = csv;
  o.seams.marked = marked_seams;
  if (lines) {
    o.lines.clear();
    for (const auto& [name, f] : *lines) o.lines.push_back({name, f});
  }
  return o;
}

/// A made-to-measure report as the dict made_to_measure_pattern returns.
py::dict mtm_report(const MadeToMeasureReport& rep, const MadeToMeasureOptions& o) {
  py::list pieces;
  for (std::size_t i = 0; i < rep.files.pattern.pieces.size(); ++i) {
    const PatternPiece& p = rep.files.pattern.pieces[i];
    const PieceMeasurements& pm = rep.measurements[i];
    py::dict widths;
    for (std::size_t k = 0; k < o.lines.size(); ++k) widths[py::str(o.lines[k].name)] = pm.widths_mm[k];
    pieces.append(py::dict(py::arg("name") = p.name, py::arg("mirrored") = p.mirrored, py::arg("area_mm2") = p.area_mm2,
                           py::arg("height_mm") = pm.height_mm, py::arg("widths_mm") = widths));
  }
  py::list seams;
  for (const SeamCheck& c : rep.files.pattern.seams) {
    py::list lengths;
    for (const SeamMemberLength& ml : c.members) lengths.append(py::make_tuple(ml.length_2d_mm, ml.length_3d_mm));
    seams.append(py::dict(py::arg("joint") = c.joint.value, py::arg("lengths_mm") = lengths,
                          py::arg("max_difference_mm") = c.max_difference_mm, py::arg("ok") = c.ok));
  }
  py::list files;
  for (const auto& f : rep.files.files) files.append(f.string());
  std::size_t warm = 0;
  for (const PieceFlattening& p : rep.files.flattening.pieces) warm += p.warm_started;
  return py::dict(py::arg("seams_opened") = rep.seams_opened, py::arg("flipped") = rep.flipped,
                  py::arg("failed_seams") = rep.failed_seams,
                  py::arg("max_seam_difference_mm") = rep.max_seam_difference_mm,
                  py::arg("max_length_error") = rep.max_length_error, py::arg("warm_started_pieces") = warm,
                  py::arg("pieces") = pieces, py::arg("seams") = seams, py::arg("files") = files);
}

/// atelier.MadeToMeasurePatterns: one template's patterns for many bodies
/// (the batch form when prepared, else the one-shot form), and the options
/// its reports are read with.
struct PreparedPatterns {
  TemplatePatterns patterns;
};

using Lines = std::optional<std::vector<std::pair<std::string, double>>>;

}  // namespace

void bind_pattern(py::module_& m) {
  m.def(
      "flatten",
      [](const MeshLike& mesh, const std::optional<std::vector<std::string>>& surfaces, const OptArray& grain,
         bool allow_holes, bool free_seams, int threads, const Progress& progress) {
        Model model = model_from(mesh, "mesh");
        FlattenOptions o;
        o.allow_holes = allow_holes;
        o.seam_lengths = !free_seams;
        if (surfaces)
          for (const std::string& s : *surfaces) o.surfaces.push_back(surface_named(model, s));
        if (!grain.is_none()) {
          const std::vector<Vec3d> g =
              points_from(py::module_::import("numpy").attr("reshape")(grain, py::make_tuple(-1, 3)), "grain");
          if (g.size() != 1 || g[0].norm() == 0) value_error("grain: expected one nonzero direction (x, y, z)");
          o.grain = g[0];
        }
        FlattenReport rep = unwrap(
            run_long(progress, threads, [&](const ExecContext& ctx) { return flatten_surfaces(model, o, ctx); }));
        std::vector<double> uv(2 * model.nodes.slots.capacity(), 0.0);
        for (std::size_t v = 0; v < model.nodes.slots.capacity() && v < model.nodes.uv.size(); ++v) {
          uv[2 * v] = model.nodes.uv[v].x();
          uv[2 * v + 1] = model.nodes.uv[v].y();
        }
        const auto n = static_cast<py::ssize_t>(model.nodes.slots.capacity());
        py::list pieces;
        for (const PieceFlattening& p : rep.pieces) {
          std::vector<std::uint32_t> tri;
          tri.reserve(3 * p.triangle_nodes.size());
          for (const auto& t : p.triangle_nodes)
            for (NodeIdx v : t) tri.push_back(v.value);
          std::vector<std::uint32_t> verts(tri);
          std::sort(verts.begin(), verts.end());
          verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
          const auto t_count = static_cast<py::ssize_t>(p.triangle_nodes.size());
          const auto v_count = static_cast<py::ssize_t>(verts.size());
          const PatternDistortion& d = p.distortion;
          py::dict pd;
          pd["name"] = p.name;
          pd["surface"] = p.surface.value;
          pd["vertices"] = adopt(std::move(verts), {v_count});
          pd["triangles"] = adopt(std::move(tri), {t_count, 3});
          pd["boundary_loops"] = p.boundary_loops;
          pd["distortion"] =
              py::dict(py::arg("area_error") = d.area_error, py::arg("length_error") = d.length_error,
                       py::arg("max_edge_strain") = d.max_edge_strain, py::arg("min_stretch") = d.min_stretch,
                       py::arg("max_stretch") = d.max_stretch, py::arg("flipped") = d.flipped,
                       py::arg("boundary_crossings") = d.boundary_crossings);
          pd["solver"] =
              py::dict(py::arg("energy_phase1") = p.energy_phase1, py::arg("energy") = p.energy,
                       py::arg("closures") = p.closures, py::arg("iterations") = p.iterations,
                       py::arg("rejected_steps") = p.rejected_steps, py::arg("tutte_fallback") = p.tutte_fallback);
          pieces.append(pd);
        }
        return py::make_tuple(adopt(std::move(uv), {n, 2}), pieces);
      },
      py::arg("mesh"), py::kw_only(), py::arg("surfaces") = py::none(), py::arg("grain") = py::none(),
      py::arg("allow_holes") = false, py::arg("free_seams") = false, py::arg("threads") = 0,
      py::arg("progress") = py::none(), R"doc(
Flattens a model's pieces into the plane (the flattening of ``atelier flatten``).

mesh: a Mesh (``read_mesh``: one piece per surface, i.e. OBJ group) or a
    (vertices, faces) pair (one piece). Each piece must be a disc (one
    boundary loop) unless allow_holes.
surfaces: flatten only the surfaces of these names (default: all).
grain: 3D grain direction (x, y, z); default each pattern's principal axis.
allow_holes: accept pieces with interior holes.
free_seams: flatten each piece on its own; by default every sewn edge of a
    piece's boundary is held to its 3D length so that seams sew
    (``atelier flatten --free-seams``).

Returns (uv, pieces): uv is an (n, 2) float64 array, the planar position of
every mesh vertex (zeros for vertices of pieces not flattened; one copy of
the engine's column), and pieces a list of dicts, one per piece: ``name``,
``surface``, ``vertices`` (uint32, the piece's vertex indices),
``triangles`` ((T, 3) uint32 mesh vertex indices), ``boundary_loops``,
``distortion`` (``area_error`` E_A, ``length_error`` E_L,
``max_edge_strain``, ``min_stretch``, ``max_stretch``, ``flipped``,
``boundary_crossings``: the same figures as the CLI's --json) and
``solver``. Long call (GIL released, Ctrl-C cancels). Raises ValueError
with the engine's message (a piece with holes, an unknown surface, ...).
)doc");

  m.def(
      "made_to_measure_pattern",
      [](const MeshLike& mesh, const std::string& out,
         const std::optional<std::vector<std::pair<std::string, double>>>& lines, bool svg, bool dxf, bool csv,
         bool marked_seams, int threads, const Progress& progress) {
        Model model = model_from(mesh, "mesh");
        const MadeToMeasureOptions o = mtm_options(lines, svg, dxf, csv, marked_seams);
        MadeToMeasureReport rep = unwrap(run_long(progress, threads, [&](const ExecContext& ctx) {
          return write_made_to_measure_pattern(model, o, std::filesystem::path(out), ctx);
        }));
        return mtm_report(rep, o);
      },
      py::arg("mesh"), py::arg("out"), py::kw_only(), py::arg("lines") = py::none(), py::arg("svg") = true,
      py::arg("dxf") = true, py::arg("csv") = true, py::arg("marked_seams") = true, py::arg("threads") = 0,
      py::arg("progress") = py::none(), R"doc(
The made-to-measure pattern set of one garment (what ``atelier regen
--patterns`` writes per body and template; systems/pattern/made_to_measure.h).

mesh: a Mesh (e.g. a regenerated template read with ``read_mesh``; one piece
    per surface) or a (vertices, faces) pair. Edges marked as seams (a
    template's seam marks, carried by regeneration and the .atm format) are
    cut first, a surface they separate becoming several pieces ("top",
    "top.1", ...); tubes and pieces with several boundary loops left are
    opened along seams chosen from the topology.
out: the folder to write (created): one SVG per piece, pattern.dxf,
    measurements.csv.
lines: named lines as (name, fraction of the piece's height along the
    grain, +y); default hem 0.02, low 0.25, middle 0.5, high 0.75, top 0.98.
marked_seams: cut along the marked seams (default); False ignores the marks.

Returns a dict: ``seams_opened``, ``flipped``, ``failed_seams``,
``max_seam_difference_mm``, ``max_length_error``, ``warm_started_pieces``
(0 here; see MadeToMeasurePatterns), ``pieces`` (``name``,
``mirrored``, ``area_mm2``, ``height_mm``, ``widths_mm`` per named line),
``seams`` (``joint``, ``lengths_mm`` (pattern, body) per member,
``max_difference_mm``, ``ok``) and ``files``. Long call (GIL released).
Raises ValueError with the engine's message.
)doc");

  py::class_<PreparedPatterns, std::shared_ptr<PreparedPatterns>>(m, "MadeToMeasurePatterns", R"doc(
Made-to-measure patterns of one garment topology for many bodies: the batch
form of ``made_to_measure_pattern`` (systems/pattern/made_to_measure.h,
MadeToMeasurePatterns), prepared once on the garment on a reference body,
then ``write()`` per body. Each body is flattened warm from the reference's
pattern (its seams already opened, its flattening built): on the project
templates about 1.5x less CPU per body than ``made_to_measure_pattern``
(the top's body pieces 2x; the trouser legs fall back to a cold start).
The preparation costs about two bodies' worth: worth it from a few bodies.
A body's result depends on the reference and the body only (the same bits
for any thread count or order); ``write()`` may run from several Python
threads at once.
)doc")
      .def(py::init([](const MeshLike& reference,
                       const std::optional<std::vector<std::pair<std::string, double>>>& lines, bool svg, bool dxf,
                       bool csv, bool marked_seams, bool warm_start, int threads, const Progress& progress) {
             Model model = model_from(reference, "mesh");  // pieces named as made_to_measure_pattern names them
             auto p = std::make_shared<PreparedPatterns>();
             TemplatePatterns& t = p->patterns;
             t.options = mtm_options(lines, svg, dxf, csv, marked_seams);
             t.options.warm_start = warm_start;
             check(run_long(progress, threads,
                            [&](const ExecContext& ctx) { return t.batch.prepare(model, t.options, ctx); }));
             return p;
           }),
           py::arg("reference"), py::kw_only(), py::arg("lines") = py::none(), py::arg("svg") = true,
           py::arg("dxf") = true, py::arg("csv") = true, py::arg("marked_seams") = true, py::arg("warm_start") = true,
           py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
reference: the garment on the reference body, as ``made_to_measure_pattern``'s
    mesh (a Mesh or a (vertices, faces) pair); every garment given to
    write() must have its topology (the same template regenerated).
lines, svg, dxf, csv, marked_seams: as made_to_measure_pattern's.
warm_start: flatten each body warm from the reference (default); False
    flattens cold, as made_to_measure_pattern does.
Long call (GIL released): the seams opened and the reference flattened.
Raises ValueError with the engine's message.
)doc")
      .def(
          "write",
          [](const PreparedPatterns& p, const MeshLike& garment, const std::string& out, int threads,
             const Progress& progress) {
            Model model = model_from(garment, "mesh");
            MadeToMeasureReport rep = unwrap(run_long(progress, threads, [&](const ExecContext& ctx) {
              return write_template_patterns(p.patterns, model, std::filesystem::path(out), ctx);
            }));
            return mtm_report(rep, p.patterns.options);
          },
          py::arg("garment"), py::arg("out"), py::kw_only(), py::arg("threads") = 0, py::arg("progress") = py::none(),
          R"doc(
The pattern set of one garment (the reference's topology, this body's
positions) in the folder ``out``: the files and the dict of
``made_to_measure_pattern``; ``warm_started_pieces`` counts the pieces
flattened warm. Unprepared (``prepare_made_to_measure_patterns`` could not
prepare it), the one-shot ``made_to_measure_pattern`` with its options.
Long call (GIL released). Raises ValueError for a garment of another
topology and with the engine's message.
)doc")
      .def_property_readonly(
          "prepared", [](const PreparedPatterns& p) { return p.patterns.batch.prepared(); },
          "True when write() takes the batch form (always for an object made by the constructor).")
      .def_property_readonly(
          "reason",
          [](const PreparedPatterns& p) {
            return p.patterns.reason ? py::object(py::none()) : py::object(py::str(p.patterns.reason.to_string()));
          },
          "Why it is not prepared (the engine's message), or None.");

  m.def(
      "prepare_made_to_measure_patterns",
      [](const Templates& templates, const Body& reference, int levels, double clearance, const Lines& lines, bool svg,
         bool dxf, bool csv, bool marked_seams, bool warm_start, int threads, const Progress& progress) {
        const std::vector<ProfileTemplate> ts = profile_templates_arg(templates, reference);
        MadeToMeasureOptions o = mtm_options(lines, svg, dxf, csv, marked_seams);
        o.warm_start = warm_start;
        RegenParams rp;
        rp.levels = levels;
        rp.clearance = clearance;
        std::vector<TemplatePatterns> prepared = unwrap(run_long(progress, threads, [&](const ExecContext& ctx) {
          return prepare_made_to_measure_patterns(ts, *reference.reference, templates_roi(ts), rp, o, ctx);
        }));
        py::list out;
        for (TemplatePatterns& t : prepared) {
          auto p = std::make_shared<PreparedPatterns>();
          p->patterns = std::move(t);
          out.append(py::cast(p));
        }
        return out;
      },
      py::arg("templates"), py::arg("reference"), py::kw_only(), py::arg("levels") = -1, py::arg("clearance") = -1.0,
      py::arg("lines") = py::none(), py::arg("svg") = true, py::arg("dxf") = true, py::arg("csv") = true,
      py::arg("marked_seams") = true, py::arg("warm_start") = true, py::arg("threads") = 0,
      py::arg("progress") = py::none(), R"doc(
The made-to-measure patterns of profile templates for many bodies, as
``atelier regen --patterns`` prepares them in a job of 8 bodies or more
(systems/pattern/made_to_measure_templates.h): the templates regenerated
on ``reference`` (a Body) with ``levels`` and ``clearance`` (give the same
as to ``regenerate_profiles`` for the bodies, so the garments have one
topology), and per template the batch form prepared on its garment.

Returns one MadeToMeasurePatterns per template, in order: ``prepared``, or
not, with ``reason`` (the reference garment could not be flattened, e.g. a
closed surface); write() of an unprepared one makes the one-shot pattern
set. lines, svg, dxf, csv, marked_seams, warm_start: as
MadeToMeasurePatterns'. Long call (GIL released). Raises ValueError for a
bad named line, a template encoded on another body, or templates that
cannot be regenerated on the reference (naming the template).
)doc");
}

}  // namespace atelier::python
