// Files (io/): meshes in OBJ, PLY, OFF and the native .atm to and from numpy
// arrays, PNG pictures; and the Mesh class the other families return.
#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include <atelier/io/png.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "bind.h"

namespace atelier::python {

namespace fs = std::filesystem;

namespace {

std::string lower_ext(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

[[noreturn]] void no_such_file(const fs::path& p) {
  // FileNotFoundError(errno, message, filename), as open() raises it.
  const std::string message = p.string() + ": no such file";
  PyErr_SetObject(PyExc_FileNotFoundError, py::make_tuple(ENOENT, message, p.string()).ptr());
  throw py::error_already_set();
}

[[noreturn]] void unknown_format(const fs::path& p) {
  value_error(p.string() + ": unknown mesh format '" + p.extension().string() + "' (use .obj, .ply, .off or .atm)");
}

Model read_any(const fs::path& p) {
  const std::string e = lower_ext(p);
  if (e != ".obj" && e != ".ply" && e != ".off" && e != ".atm") unknown_format(p);
  if (!fs::exists(p)) no_such_file(p);
  py::gil_scoped_release release;
  if (e == ".obj") return read_obj(p);
  if (e == ".ply") return read_ply(p);
  if (e == ".off") return read_off(p);
  return read_model(p);
}

/// The Model a mesh is written from: its own, or one surface built from the
/// arrays (the builder's errors: non-manifold edges, inconsistent faces).
std::shared_ptr<const Model> model_of(const Mesh& mesh) {
  if (mesh.model) return mesh.model;
  auto m = std::make_shared<Model>();
  check(add_polygon_surface(*m, "mesh", mesh.soup).status());
  return m;
}

py::array face_surfaces(const Mesh& mesh) {
  std::vector<std::int32_t> s;
  s.reserve(mesh.soup.face_count());
  if (mesh.model) {
    for (std::uint32_t f = 0; f < mesh.model->faces.slots.capacity(); ++f)
      if (mesh.model->alive(FaceIdx{f})) s.push_back(static_cast<std::int32_t>(mesh.model->faces.surface[f].value));
  } else {
    s.assign(mesh.soup.face_count(), 0);
  }
  const auto n = static_cast<py::ssize_t>(s.size());
  return adopt(std::move(s), {n});
}

py::list surface_names(const Mesh& mesh) {
  py::list names;
  if (!mesh.model) {
    names.append("mesh");
    return names;
  }
  for (std::uint32_t i = 0; i < mesh.model->surfaces.slots.capacity(); ++i)
    names.append(mesh.model->alive(SurfaceIdx{i}) ? py::str(mesh.model->surfaces.name[i]) : py::str(""));
  return names;
}

}  // namespace

void bind_io(py::module_& m) {
  py::class_<Mesh, std::shared_ptr<Mesh>>(m, "Mesh", R"doc(
A polygon mesh: vertices (n, 3) and polygon faces.

Made by ``read_mesh``, by the engine (regenerated profile templates, garment
templates, MakeHuman garments), or from arrays: ``Mesh(vertices, faces)``.
Immutable. ``vertices``, ``faces``, ``face_offsets`` and ``face_indices`` are
read-only numpy views onto the engine's columns (zero copy; they keep the
mesh alive). Unpacks as ``vertices, faces = mesh``.
)doc")
      .def(py::init([](const Array& vertices, const Faces& faces) {
             auto mesh = std::make_shared<Mesh>();
             mesh->soup = soup_from(vertices, faces, "mesh");
             return mesh;
           }),
           py::arg("vertices"), py::arg("faces"), R"doc(
A mesh from arrays (one copy, checked).

vertices: (n, 3) float32 or float64, finite.
faces: (F, k) integer array, k >= 3, or a list of polygons of any sizes;
    every index in [0, n).
Raises ValueError naming the bad element.
)doc")
      .def_property_readonly(
          "vertices", [](py::object self) { return points_view(self.cast<const Mesh&>().positions(), self); },
          "(n, 3) float64, read-only view (zero copy).")
      .def_property_readonly(
          "faces",
          [](py::object self) {
            const Mesh& mesh = self.cast<const Mesh&>();
            return faces_out(mesh.soup.face_offsets, mesh.soup.face_nodes, self);
          },
          "(F, k) uint32 read-only view when every face has k corners (zero copy); otherwise a list of 1-D arrays "
          "(copies).")
      .def_property_readonly(
          "face_offsets",
          [](py::object self) {
            const auto& o = self.cast<const Mesh&>().soup.face_offsets;
            return view(o.data(), {static_cast<py::ssize_t>(o.size())}, self);
          },
          "(F + 1,) uint32: face f has corners face_indices[face_offsets[f]:face_offsets[f + 1]] (view).")
      .def_property_readonly(
          "face_indices",
          [](py::object self) {
            const auto& n = self.cast<const Mesh&>().soup.face_nodes;
            return view(n.data(), {static_cast<py::ssize_t>(n.size())}, self);
          },
          "The faces' corners, concatenated (uint32 view).")
      .def_property_readonly(
          "triangles",
          [](const Mesh& mesh) {
            std::vector<Triangle> t = fan_triangles(mesh.soup);
            const auto n = static_cast<py::ssize_t>(t.size());
            auto* owned = new std::vector<Triangle>(std::move(t));
            py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<Triangle>*>(p); });
            return py::array(py::dtype::of<std::uint32_t>(), {n, py::ssize_t{3}}, {},
                             owned->empty() ? nullptr : owned->data()->data(), owner);
          },
          "(T, 3) uint32: the faces fan-triangulated (c0, c[j+1], c[j+2]), computed per call.")
      .def_property_readonly("vertex_count", [](const Mesh& mesh) { return mesh.positions().size(); })
      .def_property_readonly("face_count", [](const Mesh& mesh) { return mesh.soup.face_count(); })
      .def_property_readonly("surfaces", &surface_names,
                             "Surface names (OBJ groups); ['mesh'] for a mesh made from arrays.")
      .def_property_readonly("face_surface", &face_surfaces, "(F,) int32: each face's surface index.")
      .def(
          "validate",
          [](const Mesh& mesh) {
            const auto model = model_of(mesh);
            check(validate(*model));
          },
          "Checks every invariant of the engine's model (raises ValueError naming the first violation).")
      .def("__iter__",
           [](py::object self) { return py::iter(py::make_tuple(self.attr("vertices"), self.attr("faces"))); })
      .def("__repr__", [](const Mesh& mesh) {
        return "<atelier.Mesh: " + std::to_string(mesh.positions().size()) + " vertices, " +
               std::to_string(mesh.soup.face_count()) + " faces>";
      });

  m.def(
      "read_mesh", [](const fs::path& path) { return mesh_of(read_any(path)); }, py::arg("path"), R"doc(
Reads a mesh file: OBJ, PLY (ASCII or binary), OFF, or the native .atm.

Returns a Mesh; ``vertices, faces = atelier.read_mesh(path)`` unpacks it
into an (n, 3) float64 array and an (F, k) uint32 array (views onto the
engine's columns, zero copy). OBJ groups become surfaces (``face_surface``).

Raises FileNotFoundError (an OSError) for a missing file, ValueError for an
unknown extension or a malformed file, with the engine's message naming the
file, the line (or byte offset) and the problem.
)doc");

  m.def(
      "write_mesh",
      [](const fs::path& path, const MeshOrArray& mesh_or_vertices, const OptFaces& faces, bool binary) {
        const std::string e = lower_ext(path);
        if (e != ".obj" && e != ".ply" && e != ".off" && e != ".atm") unknown_format(path);
        std::shared_ptr<const Mesh> mesh = faces.is_none() ? mesh_from(mesh_or_vertices, "mesh")
                                                           : mesh_from(py::make_tuple(mesh_or_vertices, faces), "mesh");
        const auto model = model_of(*mesh);
        py::gil_scoped_release release;
        if (e == ".obj") write_obj(*model, path);
        if (e == ".ply") write_ply(*model, path, binary);
        if (e == ".off") write_off(*model, path);
        if (e == ".atm") write_model(*model, path);
      },
      py::arg("path"), py::arg("mesh"), py::arg("faces") = py::none(), py::arg("binary") = true, R"doc(
Writes a mesh by extension: .obj, .ply (binary double, or ASCII with
binary=False), .off or .atm, atomically (a temporary file renamed into
place: an error leaves no half-written file).

mesh: a Mesh or a Body, or the vertices (n, 3) with ``faces`` given.
Text formats write the shortest decimal that reads back to the same double:
every format round-trips bit for bit.

Raises ValueError for bad arrays or a mesh the engine's model refuses
(an edge shared by more than two faces, inconsistent orientation), OSError
when the file cannot be written.
)doc");

  m.def(
      "read_png",
      [](const fs::path& path) {
        if (!fs::exists(path)) no_such_file(path);
        RgbImage img;
        {
          py::gil_scoped_release release;
          img = read_png(path);
        }
        const auto h = static_cast<py::ssize_t>(img.height), w = static_cast<py::ssize_t>(img.width);
        return adopt(std::move(img.pixels), {h, w, 3});
      },
      py::arg("path"), R"doc(
Reads a PNG as an (H, W, 3) uint8 RGB array (alpha composed on black; the
pixel buffer is moved into the array, no copy). FileNotFoundError,
ValueError for damaged data.
)doc");

  m.def(
      "write_png",
      [](const fs::path& path, const Array& image, int level) {
        const py::array a = py::module_::import("numpy").attr("asarray")(image);
        if (a.dtype().kind() != 'u' || a.itemsize() != 1)
          value_error("image: dtype " + py::str(py::object(a.dtype())).cast<std::string>() + "; expected uint8");
        if (a.ndim() != 3 || a.shape(2) != 3 || a.shape(0) == 0 || a.shape(1) == 0)
          value_error("image: expected an (H, W, 3) RGB array");
        if (level < 0 || level > 9) value_error("level: zlib levels run from 0 to 9");
        RgbImage img(static_cast<std::uint32_t>(a.shape(1)), static_cast<std::uint32_t>(a.shape(0)));
        const auto* base = static_cast<const char*>(a.data());
        for (py::ssize_t y = 0; y < a.shape(0); ++y)
          for (py::ssize_t x = 0; x < a.shape(1); ++x)
            for (py::ssize_t c = 0; c < 3; ++c)
              img.at(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y))[c] =
                  *reinterpret_cast<const std::uint8_t*>(base + y * a.strides(0) + x * a.strides(1) + c * a.strides(2));
        py::gil_scoped_release release;
        write_png(img, path, level);
      },
      py::arg("path"), py::arg("image"), py::arg("level") = 6, R"doc(
Writes an (H, W, 3) uint8 RGB array as a PNG, atomically (one copy into
the engine's image).
)doc");
}

}  // namespace atelier::python
