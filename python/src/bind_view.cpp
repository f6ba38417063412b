// Pictures (systems/view/render.h, io/png.h): a ray-cast picture of a body
// and its garments, as an RGB array and optionally a PNG file.
#include <atelier/io/png.h>
#include <atelier/systems/view/render.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>

#include "bind.h"

namespace atelier::python {

namespace fs = std::filesystem;

namespace {

View view_arg(const std::string& v) {
  if (v == "front") return View::kFront;
  if (v == "side") return View::kSide;
  if (v == "back") return View::kBack;
  value_error("view: 'front', 'side', 'back' or 'both', got '" + v + "'");
}

Vec3d colour_arg(py::handle c, const char* what) {
  const auto v = py::module_::import("numpy").attr("asarray")(c, "float64").cast<py::array_t<double>>();
  if (v.ndim() != 1 || v.shape(0) != 3) value_error(std::string(what) + ": expected an (r, g, b) triple in [0, 1]");
  Vec3d out(v.at(0), v.at(1), v.at(2));
  if (!out.allFinite() || out.minCoeff() < 0 || out.maxCoeff() > 1)
    value_error(std::string(what) + ": components run from 0 to 1");
  return out;
}

}  // namespace

void bind_view(py::module_& m) {
  m.def(
      "render",
      [](const OptMeshLike& body, const MeshList& garments, std::uint32_t width, std::uint32_t height,
         const std::string& view, const std::string& projection, const Colours& colours, int supersample, bool outlines,
         const Colour& background, std::optional<fs::path> path, int threads, const Progress& progress) {
        std::vector<std::shared_ptr<const Mesh>> meshes;
        if (!body.is_none()) meshes.push_back(mesh_from(body, "body"));
        if (!garments.is_none()) {
          // One garment (a Mesh or a (vertices, faces) pair) or a list of them.
          const bool one = py::isinstance<Mesh>(garments) || py::isinstance<Body>(garments) ||
                           (py::isinstance<py::tuple>(garments) && py::len(garments) == 2 &&
                            py::isinstance<py::array>(garments[py::int_(0)]));
          if (one) {
            meshes.push_back(mesh_from(garments, "garment"));
          } else {
            std::size_t i = 0;
            for (py::handle g : garments)
              meshes.push_back(mesh_from(g, ("garments[" + std::to_string(i++) + "]").c_str()));
          }
        }
        if (meshes.empty()) value_error("render: nothing to draw (no body, no garments)");
        if (width == 0 || height == 0 || width > 16384 || height > 16384)
          value_error("width, height: 1 to 16384 pixels");
        if (supersample < 1 || supersample > 8) value_error("supersample: 1 to 8");
        std::vector<Vec3d> colour;
        if (!colours.is_none()) {
          for (py::handle c : colours) colour.push_back(colour_arg(c, "colours"));
          if (colour.size() != meshes.size())
            value_error("colours: " + std::to_string(colour.size()) + " given for " + std::to_string(meshes.size()) +
                        " meshes");
        } else {
          for (std::size_t i = 0; i < meshes.size(); ++i)
            colour.push_back(i == 0 && !body.is_none() ? body_colour() : garment_colour(body.is_none() ? i : i - 1));
        }
        RenderParams params;
        params.width = width;
        params.height = height;
        if (projection == "orthographic")
          params.projection = Projection::kOrthographic;
        else if (projection == "perspective")
          params.projection = Projection::kPerspective;
        else
          value_error("projection: 'orthographic' or 'perspective', got '" + projection + "'");
        params.supersample = supersample;
        params.outlines = outlines;
        if (!background.is_none()) params.background = colour_arg(background, "background");
        std::vector<View> views;
        if (view == "both")
          views = {View::kFront, View::kSide};
        else
          views = {view_arg(view)};
        std::vector<std::vector<Triangle>> tris(meshes.size());
        for (std::size_t i = 0; i < meshes.size(); ++i) tris[i] = fan_triangles(meshes[i]->soup);
        RgbImage image = run_long(progress, threads, [&](const ExecContext& ctx) {
          std::vector<RenderTriangles> scene;
          for (std::size_t i = 0; i < meshes.size(); ++i) scene.push_back({meshes[i]->positions(), tris[i], colour[i]});
          std::vector<RgbImage> pictures;
          for (const View v : views) {
            RenderParams p = params;
            p.view = v;
            pictures.push_back(unwrap(render_scene(scene, p, ctx)).image);
          }
          RgbImage out =
              pictures.size() == 1 ? std::move(pictures[0]) : unwrap(side_by_side(pictures, 8, params.background));
          if (ctx.cancelled()) raise(Status(ErrorCode::kCancelled, "render cancelled"));
          if (path) write_png(out, *path);  // atomically: a cancelled call leaves no file
          return out;
        });
        const auto h = static_cast<py::ssize_t>(image.height), w = static_cast<py::ssize_t>(image.width);
        return adopt(std::move(image.pixels), {h, w, 3});
      },
      py::arg("body"), py::arg("garments") = py::none(), py::kw_only(), py::arg("width") = 480, py::arg("height") = 640,
      py::arg("view") = "front", py::arg("projection") = "orthographic", py::arg("colours") = py::none(),
      py::arg("supersample") = 1, py::arg("outlines") = false, py::arg("background") = py::none(),
      py::arg("path") = py::none(), py::arg("threads") = 0, py::arg("progress") = py::none(), R"doc(
Ray-casts a picture of a body and its garments (systems/view/render.h):
two-sided Lambert shading, framed on the meshes' bounds.

body: a Body, a Mesh or a (vertices, faces) pair (None: garments only).
garments: one or a list of Mesh / (vertices, faces), e.g.
    ``(result.positions[0][b], garment.faces)``.
view: 'front', 'side', 'back', or 'both' (front and side side by side).
colours: one (r, g, b) in [0, 1] per mesh (default: skin, then a palette).
path: also write a PNG there, atomically (a cancelled or failed call
    leaves no file).

Returns the (H, W, 3) uint8 picture (the engine's pixel buffer, moved: no
copy). Rows render in parallel (same pixels for any thread count);
progress reports ("render", rows done, rows); Ctrl-C cancels.
)doc");
}

}  // namespace atelier::python
