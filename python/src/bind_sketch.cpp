// Sketch tools (systems/sketch, seed 001 section 5): the call of
// `atelier sketch`, over the same one library call (apply_strokes), and of
// `atelier extrude` (extrude, seed 002): a mesh
// painted, cut and partitioned by the strokes of a stroke file (a path, or
// the same JSON as a dict; docs/strokes.md).
#include <atelier/storage/builder.h>
#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/sketch/extrude_recipe.h>
#include <atelier/systems/sketch/sketch.h>
#include <atelier/systems/view/strokes.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cerrno>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "bind.h"

namespace atelier::python {

namespace {

namespace fs = std::filesystem;

StrokeFile strokes_arg(py::handle strokes) {
  if (py::isinstance<py::str>(strokes) || py::hasattr(strokes, "__fspath__")) {
    const fs::path p = strokes.cast<fs::path>();
    Expected<StrokeFile> f = [&] {
      py::gil_scoped_release release;
      return read_strokes(p);
    }();
    return unwrap(std::move(f));
  }
  if (!py::isinstance<py::dict>(strokes))
    throw py::type_error("strokes: expected a stroke file path or a dict of its JSON (docs/strokes.md)");
  // The dict as the JSON of a stroke file (json.dumps writes NaN for a
  // non-finite number: parse_strokes refuses it by name).
  const std::string text = py::module_::import("json").attr("dumps")(strokes).cast<std::string>();
  return unwrap(parse_strokes(text, "strokes"));
}

py::dict report_dict(const Model& m, const SketchReport& r) {
  py::list tools;
  for (const StrokeReport& t : r.tools) {
    py::dict j;
    j["stroke"] = t.stroke;
    j["strokes"] = t.strokes;
    j["tool"] = to_string(t.tool);
    j["through"] = t.through;
    j["ok"] = t.status.is_ok();
    if (!t.name.empty()) j["name"] = t.name;
    if (!t.status) {
      j["error"] = t.status.message();
      tools.append(j);
      continue;
    }
    py::list curves;
    for (std::size_t c = 0; c < t.curve_lengths.size(); ++c)
      curves.append(
          py::dict(py::arg("length") = t.curve_lengths[c], py::arg("closed") = static_cast<bool>(t.curve_closed[c])));
    j["curves"] = curves;
    if (t.tool == StrokeTool::kPaint || t.tool == StrokeTool::kPaintThrough) {
      py::list lines;
      for (const AttribEdge& e : t.curves) {
        if (!m.alive(e)) continue;
        std::vector<Vec3d> pts;
        for (AttribNodeIdx a : m.attrib_edges.nodes.row(e.idx.value)) pts.push_back(m.attrib_position_on_surface(a));
        lines.append(py::dict(py::arg("surface") = m.surfaces.name[m.attrib_edges.surface[e.idx.value].value],
                              py::arg("points") = adopt_points(std::move(pts))));
      }
      j["polylines"] = lines;
    }
    j["faces_added"] = t.faces_added;
    j["nodes_added"] = t.nodes_added;
    j["faces_removed"] = t.faces_removed;
    j["crossings"] = t.crossings;
    py::list pieces;
    for (const Piece& p : t.pieces) {
      py::dict pj(py::arg("faces") = p.faces, py::arg("area") = p.area, py::arg("removed") = p.removed);
      if (!p.removed && m.alive(p.surface)) pj["surface"] = m.surfaces.name[p.surface.idx.value];
      pieces.append(pj);
    }
    j["pieces"] = pieces;
    if (t.tool == StrokeTool::kCut) j["removed_area"] = t.removed_area;
    tools.append(j);
  }
  py::dict root;
  root["failed"] = r.failed;
  root["tools"] = tools;
  return root;
}

void def_extrude(py::module_& m);
void def_replay_extrusion(py::module_& m);

}  // namespace

void bind_sketch(py::module_& m) {
  m.def(
      "sketch",
      [](const MeshLike& mesh, const Strokes& strokes, const std::optional<std::vector<std::string>>& surfaces,
         bool keep_going, int threads, const Progress& progress) {
        Model model = model_from(mesh, "mesh");
        const StrokeFile file = strokes_arg(strokes);
        atelier::SketchOptions so;
        so.keep_going = keep_going;
        if (surfaces)
          for (const std::string& name : *surfaces) {
            SurfaceIdx found;
            for (std::uint32_t s = 0; s < model.surfaces.slots.capacity(); ++s)
              if (model.alive(SurfaceIdx{s}) && model.surfaces.name[s] == name) found = SurfaceIdx{s};
            if (!found.valid()) value_error("surfaces: the mesh has no surface named '" + name + "'");
            so.surfaces.push_back(found);
          }
        const SketchReport r = unwrap(
            run_long(progress, threads, [&](const ExecContext& ctx) { return apply_strokes(model, file, so, ctx); }));
        py::dict rep = report_dict(model, r);
        (void)model.compact();  // the live nodes and faces in order, as the writers number them
        rep["result"] = py::dict(py::arg("surfaces") = model.num_surfaces(), py::arg("nodes") = model.num_nodes(),
                                 py::arg("faces") = model.num_faces(), py::arg("joints") = model.num_joints());
        return py::make_tuple(mesh_of(std::move(model)), rep);
      },
      py::arg("mesh"), py::arg("strokes"), py::kw_only(), py::arg("surfaces") = py::none(),
      py::arg("keep_going") = false, py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
Paints, cuts and partitions a mesh with the strokes of a stroke file (``atelier sketch``; seed 001 section 5).

mesh: a Mesh (``read_mesh``) or a (vertices, faces) pair.
strokes: a stroke file path, or a dict of the same JSON (camera and
    strokes, docs/strokes.md).
surfaces: paint only on the surfaces of these names (default: all).
keep_going: skip strokes that fail (report["failed"] counts them) instead
    of raising.

Returns (mesh, report): the result as a Mesh (pieces of a partition are its
``surfaces``, ``face_surface`` says each face's; ``write_mesh`` gives the
CLI's file) and a dict: ``failed`` and ``tools``, one dict per tool as the
CLI's --json writes it (``tool``, ``ok``, ``curves`` with lengths,
``polylines`` of painted curves as (k, 3) arrays, ``faces_added``,
``pieces`` with areas, ``removed_area``...), and ``result`` (counts).
Long call (GIL released, Ctrl-C cancels). Raises ValueError with the
engine's message (naming the file and JSON location for bad stroke files,
the stroke for a failed tool), FileNotFoundError for a missing file.
)doc");
  def_extrude(m);
  def_replay_extrusion(m);
}

namespace {

/// The dict the CLI's --json writes for an extrusion.
py::dict extrude_report(const ExtrudeReport& r, bool as_surface, bool with_body) {
  auto stats = [](const EdgeLengthStats& s) {
    return py::dict(py::arg("edges") = s.edges, py::arg("mean") = s.mean, py::arg("min") = s.min,
                    py::arg("max") = s.max, py::arg("within") = s.within, py::arg("outside") = s.outside);
  };
  py::dict rep;
  rep["base_ring"] = r.base_ring;
  rep["capped"] = r.capped;
  rep["base_nodes"] = r.base.size();
  rep["base_mean_edge"] = r.base_mean_edge;
  rep["copies"] = r.copies;
  rep["scales"] = r.scales;
  rep["faces_removed"] = r.faces_removed;
  rep["swept_nodes"] = r.swept_nodes;
  rep["swept_faces"] = r.swept_faces;
  rep["splits"] = r.splits;
  rep["collapses"] = r.collapses;
  rep["swaps"] = r.swaps;
  rep["before"] = stats(r.before);
  rep["after"] = stats(r.after);
  rep["nodes_added"] = r.nodes_added;
  rep["faces_added"] = r.faces_added;
  rep["volume_change"] = r.volume_change;
  rep["max_deviation"] = r.max_deviation;
  if (as_surface) rep["joints"] = r.joints.size();
  if (with_body) {
    rep["pushed"] = r.pushed;
    rep["inside_after"] = r.inside_after;
    rep["min_body_distance"] = r.min_body_distance;
  }
  if (r.mirrored) {
    rep["mirrored"] = true;
    rep["mirror_base_nodes"] = r.mirror_base.size();
    rep["mirror_base_error"] = r.mirror_base_error;
    rep["mirror_nodes"] = r.mirror_nodes;
    rep["mirror_faces"] = r.mirror_faces;
  }
  return rep;
}

/// body, clearance, body_smoothing, settle_rounds: ExtrudeOptions' body
/// fields, as the CLI's --body, --clearance, --body-smoothing and
/// --settle-rounds. `body_model` and `body` must outlive the extrusion.
void set_body(const OptMeshLike& body_arg, double clearance, int body_smoothing, int settle_rounds,
              Model& body_model, CollisionBody& body, ExtrudeOptions& eo) {
  if (!(clearance >= 0) || !std::isfinite(clearance)) value_error("clearance: a finite number >= 0");
  if (body_smoothing < 0 || settle_rounds < 0) value_error("body_smoothing, settle_rounds: counts >= 0");
  eo.clearance = clearance;
  eo.body_smoothing = body_smoothing;
  eo.settle_rounds = settle_rounds;
  if (body_arg.is_none()) return;
  body_model = model_from(body_arg, "body");
  if (Status st = collision_body_of(body_model, body); !st) value_error("body: " + st.message());
  eo.body = &body;
}

void def_extrude(py::module_& m) {
  m.def(
      "extrude",
      [](const MeshLike& mesh, const Strokes& strokes, std::size_t first, double pick_radius, bool optimise,
         bool as_surface, const py::object& mirror, const OptMeshLike& body_arg, double clearance, int body_smoothing,
         int settle_rounds, int threads, const Progress& progress) {
        Model model = model_from(mesh, "mesh");
        const StrokeFile file = strokes_arg(strokes);
        const ExtrudeStrokes es = unwrap(extrusion_from_file(file, first));
        ExtrudeOptions eo;
        eo.pick_radius = pick_radius;
        eo.optimise = optimise;
        eo.as_surface = as_surface;
        Model body_model;
        CollisionBody body;
        set_body(body_arg, clearance, body_smoothing, settle_rounds, body_model, body, eo);
        // mirror: None, "x" / "y" / "z" (the plane through the origin normal
        // to that axis), or (px, py, pz, nx, ny, nz), as the CLI's --mirror
        // and --mirror-plane.
        if (!mirror.is_none()) {
          SymmetryPlane p;
          if (py::isinstance<py::str>(mirror)) {
            const std::string a = mirror.cast<std::string>();
            if (a != "x" && a != "y" && a != "z")
              value_error("mirror: expected 'x', 'y', 'z' or 6 numbers, got '" + a + "'");
            p.normal = Vec3d::Unit(a == "x" ? 0 : a == "y" ? 1 : 2);
          } else {
            const std::vector<double> v = mirror.cast<std::vector<double>>();
            if (v.size() != 6) value_error("mirror: expected 6 numbers (px, py, pz, nx, ny, nz)");
            p.point = Vec3d(v[0], v[1], v[2]);
            p.normal = Vec3d(v[3], v[4], v[5]);
          }
          eo.mirror = p;
        }
        const ExtrudeReport r =
            unwrap(run_long(progress, threads, [&](const ExecContext& ctx) { return extrude(model, es, eo, ctx); }));
        py::dict rep = extrude_report(r, as_surface, eo.body != nullptr);
        // The recipe (extrude_recipe.h) of an open extrusion, to grow the
        // same part on another mesh of this topology (replay_extrusion);
        // None for a painted and cut base or a mirrored pair, which have none.
        const Expected<ExtrusionRecipe> recipe = extrusion_recipe(model, r);
        rep["recipe"] = recipe ? py::module_::import("json").attr("loads")(extrusion_recipe_json(*recipe))
                               : py::object(py::none());
        (void)model.compact();
        return py::make_tuple(mesh_of(std::move(model)), rep);
      },
      py::arg("mesh"), py::arg("strokes"), py::kw_only(), py::arg("first") = 0, py::arg("pick_radius") = 12.0,
      py::arg("optimise") = true, py::arg("as_surface") = false, py::arg("mirror") = py::none(),
      py::arg("body") = py::none(), py::arg("clearance") = 0.002,
      py::arg("body_smoothing") = ExtrudeOptions{}.body_smoothing,
      py::arg("settle_rounds") = ExtrudeOptions{}.settle_rounds,
      py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
Extrudes a surface or a cavity from a mesh by sketched strokes (``atelier extrude``; seed 002).

mesh: a Mesh (``read_mesh``) or a (vertices, faces) pair.
strokes: a stroke file path, or a dict of the same JSON, holding a run of
    "extrude" strokes from index ``first``: the base stroke (closed: painted
    and cut; open: selects boundary edges), then one (closed extrusion) or
    two (open extrusion) extruding strokes, each with its own "camera" or
    the file's (docs/strokes.md).
pick_radius: pixels within which the strokes must start near the base curve.
optimise: run the mesh optimisation of the new region (towards B's mean
    edge length, B fixed; every new edge within [4/5, 4/3] of it).
as_surface: the extruded part as its own surface joined to the base along
    B by a joint (``face_surface`` of the Mesh tells them apart).
mirror: None (default), "x" (the body's sagittal plane x = 0), "y", "z", or
    (px, py, pz, nx, ny, nz): also extrude the mirror image across that
    plane (both sleeves from one stroke; ``--mirror`` / ``--mirror-plane``).
    The mirror part is the exact reflection of the drawn one; raises
    ValueError ("mirror side: ... not symmetric there", "drawn side: ...
    crosses the symmetry plane") with the mesh unchanged.
body: None, or a closed body (Mesh, Body or (vertices, faces)) the
    extruded part is kept outside of, ``clearance`` (model units) from it
    (``--body``, ``--clearance``): a sleeve grown from a garment on a
    mannequin. The report then has ``pushed``, ``inside_after`` and
    ``min_body_distance``.
body_smoothing, settle_rounds: with a body, the two passes around the push
    (``--body-smoothing``, ``--settle-rounds``; ExtrudeOptions): umbrella
    steps on the pushed nodes before the optimisation, and rounds that
    optimise again around edges out of bounds after the last push. By
    default body_smoothing 8 and settle_rounds 8 (ExtrudeOptions; 0: off).

Returns (mesh, report): the result as a Mesh and the dict the CLI's --json
writes (``copies``, ``swept_nodes``, ``swept_faces``, ``splits``,
``collapses``, ``swaps``, edge-length ``before``/``after``,
``volume_change``...) and ``recipe``: the extrusion relative to its base
curve (a dict of the JSON ``--recipe-out`` writes) for ``replay_extrusion``
on another mesh of the same topology, or None (a painted and cut base, a
mirrored pair: their base nodes exist on no other mesh). Long call (GIL released, Ctrl-C cancels). Raises
ValueError with the engine's message (a stroke not starting near the base,
NaN, a degenerate plane), FileNotFoundError for a missing file.
)doc");
}

void def_replay_extrusion(py::module_& m) {
  m.def(
      "replay_extrusion",
      [](const MeshLike& mesh, const py::object& recipe, bool optimise, bool as_surface, const OptMeshLike& body_arg,
         double clearance, int body_smoothing, int settle_rounds, int threads, const Progress& progress) {
        Model model = model_from(mesh, "mesh");
        // The recipe: the report's dict (the JSON of --recipe-out) or a path to that file.
        ExtrusionRecipe rec;
        if (py::isinstance<py::dict>(recipe)) {
          const std::string text = py::module_::import("json").attr("dumps")(recipe).cast<std::string>();
          rec = unwrap(parse_extrusion_recipe(text, "recipe"));
        } else if (py::isinstance<py::str>(recipe) || py::hasattr(recipe, "__fspath__")) {
          const fs::path p = recipe.cast<fs::path>();
          std::ifstream f(p, std::ios::binary);
          if (!f) {
            PyErr_SetObject(PyExc_FileNotFoundError,
                            py::make_tuple(ENOENT, p.string() + ": cannot be read", p.string()).ptr());
            throw py::error_already_set();
          }
          const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
          rec = unwrap(parse_extrusion_recipe(text, p.string()));
        } else {
          throw py::type_error("recipe: expected the dict of extrude()'s report['recipe'] or a recipe file path");
        }
        ExtrudeOptions eo;
        eo.optimise = optimise;
        eo.as_surface = as_surface;
        Model body_model;
        CollisionBody body;
        set_body(body_arg, clearance, body_smoothing, settle_rounds, body_model, body, eo);
        const ExtrudeReport r = unwrap(
            run_long(progress, threads, [&](const ExecContext& ctx) { return replay_extrusion(model, rec, eo, ctx); }));
        py::dict rep = extrude_report(r, as_surface, eo.body != nullptr);
        (void)model.compact();
        return py::make_tuple(mesh_of(std::move(model)), rep);
      },
      py::arg("mesh"), py::arg("recipe"), py::kw_only(), py::arg("optimise") = true, py::arg("as_surface") = false,
      py::arg("body") = py::none(), py::arg("clearance") = 0.002,
      py::arg("body_smoothing") = ExtrudeOptions{}.body_smoothing,
      py::arg("settle_rounds") = ExtrudeOptions{}.settle_rounds,
      py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
Grows a recorded extrusion again on another mesh (``atelier extrude
--replay``; systems/sketch/extrude_recipe.h): the part drawn once (a sleeve
from an armhole, a dress from a hem) on each body's garment without
redrawing strokes.

mesh: a Mesh or a (vertices, faces) pair with the topology of the mesh the
    recipe was recorded on (the same base nodes, joined by boundary edges).
recipe: ``report["recipe"]`` of ``extrude`` (a dict), or the path of a file
    written by ``atelier extrude --recipe-out``.
optimise, as_surface, body, clearance, body_smoothing, settle_rounds: as for
    ``extrude`` (a sleeve replayed on another mannequin kept outside it).

The copies of B follow B's position, orientation and size on this mesh (a
similarity of the drawn part; on the recorded mesh, the drawn part itself
to rounding). Returns (mesh, report) as ``extrude`` does (no ``recipe``).
Long call (GIL released, Ctrl-C cancels). Raises ValueError naming the
field of a bad recipe, or the base node that this mesh lacks, with the mesh
unchanged; FileNotFoundError for a missing file.
)doc");
}

}  // namespace

}  // namespace atelier::python
