// Garments (systems/garment/regenerate_garment.h): a body family and the
// garments encoded on it (from arrays, a Mesh or an OBJ file; .atd template
// files). Their regeneration on batches of bodies: bind_regenerate.cpp.
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>

#include "bind.h"

namespace atelier::python {

namespace fs = std::filesystem;

std::shared_ptr<Garment> garment_of(GarmentTemplate t, std::shared_ptr<Family> family) {
  auto g = std::make_shared<Garment>();
  double sum = 0;
  for (const float c : t.clearance.clearance) sum += c;
  g->reference_mean_clearance =
      t.clearance.clearance.empty() ? 0.0 : sum / static_cast<double>(t.clearance.clearance.size());
  g->garment = std::make_shared<const GarmentTemplate>(std::move(t));
  g->family = std::move(family);
  return g;
}

void bind_garment(py::module_& m) {
  py::class_<Family, std::shared_ptr<Family>>(m, "GarmentFamily", R"doc(
What every garment of one body family shares: the reference body's
polygons (what garments are encoded on) and its closed skin triangles (the
collision pass). Bodies regenerated on it must have its topology.
)doc")
      .def(py::init([](std::shared_ptr<Body> body) {
             auto f = std::make_shared<Family>();
             f->body = body;
             py::gil_scoped_release release;
             f->family = std::make_shared<const GarmentFamily>(unwrap(GarmentFamily::of(*body->reference)));
             return f;
           }),
           py::arg("body"), "Raises ValueError when the body's skin is not closed and consistently oriented.")
      .def_readonly("body", &Family::body)
      .def_property_readonly("node_count", [](const Family& f) { return f.body->node_count(); });

  py::class_<Garment, std::shared_ptr<Garment>>(m, "GarmentTemplate", R"doc(
A garment encoded on a body family (seed 001 section 6 detail template, the
clearance it keeps, the edge transfer): what ``regenerate`` fits on other
bodies. Made by ``encode_garment`` or ``read_garment_template``; immutable
(array properties are read-only views, zero copy).
)doc")
      .def_property_readonly("name", [](const Garment& g) { return g.garment->name; })
      .def_readonly("family", &Garment::family)
      .def_property_readonly(
          "z_depth", [](const Garment& g) { return g.garment->z_depth; },
          "Layer order in an outfit: smaller is nearer the skin.")
      .def_property_readonly("vertex_count", [](const Garment& g) { return g.garment->mesh.positions.size(); })
      .def_property_readonly(
          "entries", [](const Garment& g) { return g.garment->encoding.entries(); },
          "p-polygon entries of the encoding (about N_q per vertex).")
      .def_property_readonly(
          "vertices",
          [](py::object self) { return points_view(self.cast<const Garment&>().garment->mesh.positions, self); },
          "(m, 3) float64: the garment on the reference body (view).")
      .def_property_readonly(
          "faces",
          [](py::object self) {
            const auto& s = self.cast<const Garment&>().garment->mesh;
            return faces_out(s.face_offsets, s.face_nodes, self);
          },
          "Faces: (F, k) uint32 view, or a list of arrays for mixed polygons.")
      .def_property_readonly(
          "edges",
          [](py::object self) {
            const auto& e = self.cast<const Garment&>().garment->edges;
            return view(e.empty() ? nullptr : e.data()->data(), {static_cast<py::ssize_t>(e.size()), 2}, self);
          },
          "(E, 2) uint32 view: the edges strain is measured on.")
      .def_property_readonly(
          "rest_length",
          [](py::object self) {
            const auto& l = self.cast<const Garment&>().garment->rest_length;
            return view(l.data(), {static_cast<py::ssize_t>(l.size())}, self);
          },
          "(E,) float64 view: edge lengths on the reference body.")
      .def_property_readonly(
          "reference_clearance",
          [](py::object self) {
            const auto& c = self.cast<const Garment&>().garment->clearance.clearance;
            return view(c.data(), {static_cast<py::ssize_t>(c.size())}, self);
          },
          "(m,) float32 view: each vertex's signed distance to the reference body (what the collision pass "
          "restores).")
      .def_property_readonly(
          "mesh",
          [](const Garment& g) {
            auto mesh = std::make_shared<Mesh>();
            mesh->soup = g.garment->mesh;
            return mesh;
          },
          "The garment on the reference body as a Mesh (a copy).")
      .def(
          "with_z_depth",
          [](const Garment& g, int z) {
            GarmentTemplate t = *g.garment;
            t.z_depth = z;
            auto out = garment_of(std::move(t), g.family);
            return out;
          },
          py::arg("z_depth"), "A copy with another layer order.")
      .def(
          "save",
          [](const Garment& g, const fs::path& dir) {
            py::gil_scoped_release release;
            write_garment_template(*g.garment, dir);
          },
          py::arg("dir"), R"doc(
Writes ``<dir>/<name>.obj`` (vertices in float precision) then
``<dir>/<name>.atd``, each atomically: the files ``atelier regen
--template <dir>/<name>.atd`` reads. A template encoded from float32
vertices reads back identical.
)doc")
      .def("__repr__", [](const Garment& g) {
        return "<atelier.GarmentTemplate '" + g.garment->name +
               "': " + std::to_string(g.garment->mesh.positions.size()) + " vertices, z_depth " +
               std::to_string(g.garment->z_depth) + ">";
      });

  m.def(
      "encode_garment",
      [](std::shared_ptr<Family> family, const GarmentSource& garment, const OptFaces& faces,
         std::optional<std::string> name, const OptArray& edges, int z_depth, std::size_t polygons_per_vertex,
         bool scaled_frames, double scale, const std::string& up, int threads, const Progress& progress) {
        PolygonSoup soup;
        std::string default_name = "garment";
        if (py::isinstance<py::str>(garment) || py::hasattr(garment, "__fspath__")) {
          const fs::path path = garment.cast<fs::path>();
          if (path.extension() != ".obj")
            value_error(path.string() + ": garments are read from OBJ files (a MakeHuman .mhclo: MakeHuman.garment())");
          if (!fs::exists(path)) {
            PyErr_SetObject(PyExc_FileNotFoundError,
                            py::make_tuple(ENOENT, path.string() + ": no such file", path.string()).ptr());
            throw py::error_already_set();
          }
          auto axis = parse_up_axis(up);
          if (!axis) value_error("up: " + axis.status().message());
          soup = unwrap(read_garment_mesh(path, BodyFrame{scale, *axis}));
          default_name = path.stem().string();
        } else if (faces.is_none()) {
          const auto mesh = mesh_from(garment, "garment");
          const auto p = mesh->positions();
          soup = mesh->soup;
          soup.positions.assign(p.begin(), p.end());
        } else {
          soup = soup_from(garment, faces, "garment");
        }
        GarmentEncodeOptions options;
        options.detail.polygons_per_vertex = polygons_per_vertex;
        options.detail.scaled_frames = scaled_frames;
        std::vector<std::array<std::uint32_t, 2>> edge_list;
        if (!edges.is_none()) {
          PolygonSoup e;
          const py::array a = py::module_::import("numpy").attr("asarray")(edges);
          if (a.ndim() != 2 || a.shape(1) != 2) value_error("edges: expected an (E, 2) integer array");
          const py::array_t<std::int64_t> ei = py::module_::import("numpy").attr("asarray")(a, "int64");
          if (a.dtype().kind() != 'i' && a.dtype().kind() != 'u') value_error("edges: expected integers");
          for (py::ssize_t i = 0; i < ei.shape(0); ++i) {
            const std::int64_t u = ei.at(i, 0), v = ei.at(i, 1);
            if (u < 0 || v < 0 || static_cast<std::size_t>(u) >= soup.positions.size() ||
                static_cast<std::size_t>(v) >= soup.positions.size())
              value_error("edges: edge " + std::to_string(i) + " uses a vertex out of range");
            edge_list.push_back({static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v)});
          }
          options.edges = edge_list;
        }
        const std::string n = name ? *name : default_name;
        GarmentTemplate t = run_long(progress, threads, [&](const ExecContext& ctx) {
          return unwrap(encode_garment(*family->family, n, std::move(soup), options, ctx));
        });
        t.z_depth = z_depth;
        return garment_of(std::move(t), family);
      },
      py::arg("family"), py::arg("garment"), py::arg("faces") = py::none(), py::kw_only(), py::arg("name") = py::none(),
      py::arg("edges") = py::none(), py::arg("z_depth") = 0, py::arg("polygons_per_vertex") = 0,
      py::arg("scaled_frames") = false, py::arg("scale") = 1.0, py::arg("up") = "y", py::arg("threads") = 0,
      py::arg("progress") = py::none(), R"doc(
Encodes a garment on a body family: its detail template (seed 001 section
6), the clearance it keeps on the reference body and the edge transfer.

garment: the garment on the family's reference body, as
    - vertices (m, 3) with ``faces`` ((F, k) or a list of polygons),
    - a Mesh (e.g. ``MakeHuman.garment(path)``, ``skin_band_garment``), or
    - the path of an OBJ file (every vertex and every face of every group;
      positions times ``scale``, and with ``up="z"`` a Z-up file turned Y-up
      as ``Body.read`` turns its body; the name defaults to the file's stem).
name: the garment's name (files, errors, reports).
edges: (E, 2) edges in the caller's order (the edge transfer's sums follow
    it); default: the faces' edges, sorted.
z_depth: layer order when worn with others (smaller is nearer the skin).
polygons_per_vertex: N_q, the p-polygons per vertex (0: the paper's
    N_H / 100).
scaled_frames: offsets in frames scaled with each body polygon's size
    (``atelier encode --scaled-frames``; DetailParams::scaled_frames): a
    body scaled by s gives the garment scaled by s, clearance included.
    Off by default: issue 7's clearance-change figure counts the scaled
    clearance as error (docs/performance.md, "Closer to ground truth").

Returns a GarmentTemplate. Raises ValueError for bad arrays or a garment
the engine refuses (the message names the garment), FileNotFoundError.
GIL released; Ctrl-C cancels.
)doc");

  m.def(
      "read_garment_template",
      [](std::shared_ptr<Family> family, const fs::path& atd, int z_depth, int threads, const Progress& progress) {
        if (!fs::exists(atd)) {
          PyErr_SetObject(PyExc_FileNotFoundError,
                          py::make_tuple(ENOENT, atd.string() + ": no such file", atd.string()).ptr());
          throw py::error_already_set();
        }
        GarmentTemplate t = run_long(progress, threads, [&](const ExecContext& ctx) {
          return unwrap(read_garment_template(*family->family, atd, ctx));
        });
        t.z_depth = z_depth;
        return garment_of(std::move(t), family);
      },
      py::arg("family"), py::arg("path"), py::kw_only(), py::arg("z_depth") = 0, py::arg("threads") = 0,
      py::arg("progress") = py::none(), R"doc(
Reads a garment template: ``<stem>.atd`` and the ``<stem>.obj`` beside it,
as ``atelier encode --garment`` and ``GarmentTemplate.save`` write them.
Raises FileNotFoundError, ValueError naming the file (another reference
body, malformed data).
)doc");

  // ------------------------------------------------------------ garments cut from the skin
  m.def(
      "skin_band_garment",
      [](const Body& body, double y_lo, double y_hi, double offset, double max_radius, const std::string& name) {
        return mesh_of(unwrap(skin_band_garment(*body.reference, y_lo, y_hi, offset, max_radius, name)));
      },
      py::arg("body"), py::arg("y_lo"), py::arg("y_hi"), py::arg("offset"), py::arg("max_radius"),
      py::arg("name") = "band", R"doc(
A shell garment cut from the skin: the faces whose vertices all lie in the
height band [y_lo, y_hi] within ``max_radius`` of the body's vertical axis,
pushed ``offset`` metres out along the normals (the demo's shorts are the
band from mid-thigh to 2 cm above the waist, 8 mm out, radius 0.4). Mesh.
)doc");
}

}  // namespace atelier::python
