// Flattening a model's pieces into 2D patterns (systems/pattern): the
// flattening `atelier flatten` does before it writes its files
// (write_pattern_files calls flatten_surfaces, then makes the pattern and
// writes SVG/DXF/PNG), here as arrays: the planar position of every vertex
// and, per piece, its triangles and distortion figures.
#include <atelier/storage/builder.h>
#include <atelier/systems/pattern/flatten.h>
#include <pybind11/stl.h>

#include <algorithm>
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

}  // namespace

void bind_pattern(py::module_& m) {
  m.def(
      "flatten",
      [](const MeshLike& mesh, const std::optional<std::vector<std::string>>& surfaces, const OptArray& grain,
         bool allow_holes, int threads, const Progress& progress) {
        const std::shared_ptr<const Mesh> in = mesh_from(mesh, "mesh");
        Model model;
        if (in->model)
          model = *in->model;
        else
          (void)unwrap(add_polygon_surface(model, "mesh", in->soup));
        FlattenOptions o;
        o.allow_holes = allow_holes;
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
      py::arg("allow_holes") = false, py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
Flattens a model's pieces into the plane (the flattening of ``atelier flatten``).

mesh: a Mesh (``read_mesh``: one piece per surface, i.e. OBJ group) or a
    (vertices, faces) pair (one piece). Each piece must be a disc (one
    boundary loop) unless allow_holes.
surfaces: flatten only the surfaces of these names (default: all).
grain: 3D grain direction (x, y, z); default each pattern's principal axis.
allow_holes: accept pieces with interior holes.

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
}

}  // namespace atelier::python
