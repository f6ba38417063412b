// Profile templates (systems/profile/): the readable JSON templates, the
// project's own templates, and their regeneration on bodies (seed 001
// section 4, seed 000 section 4.2) with the meshes it makes.
#include <atelier/engine/parallel.h>
#include <atelier/systems/profile/project_templates.h>
#include <atelier/systems/profile/regenerate.h>
#include <atelier/systems/profile/template_json.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <atomic>
#include <filesystem>
#include <optional>

#include "bind.h"

namespace atelier::python {
/// One body's regenerated profile template: RegenQuality's figures.
struct ProfileQualityRow {
  bool ok;
  std::uint64_t nodes, faces, inside, pushed;
  double max_depth, min_distance, node_clearance_error, profile_error, umbrella, crack;
};
}  // namespace atelier::python

namespace atelier::python {

namespace fs = std::filesystem;

namespace {

struct ProfileRegeneration {
  std::vector<std::string> names;
  py::list meshes;  // per body: a list of Mesh (None where the body failed)
  py::list quality;
  py::array ok;
  py::list errors;
};

/// What a template was encoded on, as `atelier encode` records it: the
/// reference's node and face counts (regeneration refuses another body).
std::string reference_tag(const ReferenceBody& b) {
  return std::to_string(b.model.num_nodes()) + " nodes, " + std::to_string(b.model.num_faces()) + " faces";
}

std::shared_ptr<Template> template_of(ProfileTemplate t) {
  auto out = std::make_shared<Template>();
  out->t = std::make_shared<const ProfileTemplate>(std::move(t));
  return out;
}

std::shared_ptr<Template> load_template(const fs::path& path) {
  if (!fs::exists(path)) {
    PyErr_SetObject(PyExc_FileNotFoundError,
                    py::make_tuple(ENOENT, path.string() + ": no such file", path.string()).ptr());
    throw py::error_already_set();
  }
  py::gil_scoped_release release;
  return template_of(read_template_json(path));
}

std::vector<std::shared_ptr<Template>> templates_arg(py::handle templates) {
  std::vector<std::shared_ptr<Template>> out;
  if (py::isinstance<Template>(templates)) {
    out.push_back(templates.cast<std::shared_ptr<Template>>());
  } else {
    for (py::handle t : templates) {
      if (!py::isinstance<Template>(t)) throw py::type_error("templates: expected ProfileTemplate objects");
      out.push_back(t.cast<std::shared_ptr<Template>>());
    }
  }
  if (out.empty()) value_error("templates: none given");
  return out;
}

ProfileQualityRow row_of(const RegenQuality& q) {
  return {true,
          q.nodes,
          q.faces,
          q.inside,
          q.pushed,
          q.max_depth,
          q.min_distance,
          q.node_clearance_error,
          q.profile_error,
          q.umbrella,
          q.crack};
}

}  // namespace

std::vector<ProfileTemplate> profile_templates_arg(py::handle templates, const Body& reference) {
  std::vector<ProfileTemplate> ts;
  const std::string tag = reference_tag(*reference.reference);
  for (const auto& t : templates_arg(templates)) {
    if (t->t->model.nodes.slots.capacity() != t->t->encodings.nodes.size())
      value_error(t->t->name + ": encodings do not match the template's nodes");
    if (t->t->reference.find(tag) == std::string::npos)
      value_error("template '" + t->t->name + "' was encoded on a reference body with " + t->t->reference +
                  "; this body has " + tag + " (encode it on this body: project_templates(body))");
    ts.push_back(*t->t);
  }
  return ts;
}

Box3d templates_roi(std::span<const ProfileTemplate> templates) {
  Box3d roi;
  for (const auto& t : templates)
    for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v) roi.extend(t.model.nodes.position[v]);
  return roi;
}

namespace {

ProfileRegeneration regenerate_profiles(const Templates& templates, const Body& reference, const Array& bodies,
                                        int levels, double clearance, int threads, const Progress& progress) {
  const std::vector<ProfileTemplate> ts = profile_templates_arg(templates, reference);
  // One body (n, 3) or a batch (B, n, 3).
  const py::array a = py::module_::import("numpy").attr("asarray")(bodies);
  const bool single = a.ndim() == 2;
  const BodyBatch batch(single ? py::object(a[py::make_tuple(py::none(), py::ellipsis())]) : py::object(a),
                        reference.node_count(), "bodies");
  const std::size_t nb = batch.size(), nt = ts.size();
  RegenParams rp;
  rp.levels = levels;
  rp.clearance = clearance;
  const Box3d roi = templates_roi(ts);
  std::vector<std::vector<std::optional<Model>>> models(nb, std::vector<std::optional<Model>>(nt));
  std::vector<std::vector<ProfileQualityRow>> rows(nt, std::vector<ProfileQualityRow>(nb));
  std::vector<std::string> errors(nb);
  run_long(progress, threads, [&](const ExecContext& ctx) {
    check(batch.check(ctx));
    ColliderPool pool;
    ExecContext per_body = ctx;
    per_body.sequential_threshold = 2;
    per_body.grain = 1;
    std::atomic<std::size_t> done{0};
    ctx.report("bodies", 0, nb);
    par::for_each_n(per_body, nb, [&](std::size_t b) {
      ExecContext inner = ExecContext::sequential();
      inner.cancel = ctx.cancel;
      if (ctx.cancelled()) return;
      std::vector<Vec3d> p;
      batch.get(b, p);
      auto r = regenerate_on_body(ts, *reference.reference, p, roi, rp, {.use_grid = false}, inner, pool);
      if (!r) {
        errors[b] = r.status().to_string();
        for (std::size_t t = 0; t < nt; ++t) rows[t][b] = {false, 0, 0, 0, 0, NAN, NAN, NAN, NAN, NAN, NAN};
      } else {
        for (std::size_t t = 0; t < nt; ++t) {
          rows[t][b] = row_of((*r)[t].quality);
          models[b][t] = std::move((*r)[t].model);
        }
      }
      ctx.report("bodies", ++done, nb);
    });
    if (ctx.cancelled()) raise(Status(ErrorCode::kCancelled, "profile regeneration cancelled"));
  });
  ProfileRegeneration out;
  for (const auto& t : ts) out.names.push_back(t.name);
  for (std::size_t b = 0; b < nb; ++b) {
    py::list per;
    for (std::size_t t = 0; t < nt; ++t)
      per.append(models[b][t] ? py::cast(mesh_of(std::move(*models[b][t]))) : py::object(py::none()));
    out.meshes.append(per);
    out.errors.append(errors[b].empty() ? py::object(py::none()) : py::str(errors[b]));
  }
  py::array_t<bool> ok(static_cast<py::ssize_t>(nb));
  for (std::size_t b = 0; b < nb; ++b) ok.mutable_at(static_cast<py::ssize_t>(b)) = errors[b].empty();
  out.ok = ok;
  for (std::size_t t = 0; t < nt; ++t) {
    const auto n = static_cast<py::ssize_t>(nb);
    out.quality.append(adopt(std::move(rows[t]), {n}));
  }
  return out;
}

}  // namespace

void bind_profile(py::module_& m) {
  // Structured numpy dtypes of the rows below (registered at import).
  PYBIND11_NUMPY_DTYPE(ProfileQualityRow, ok, nodes, faces, inside, pushed, max_depth, min_distance,
                       node_clearance_error, profile_error, umbrella, crack);

  py::class_<Template, std::shared_ptr<Template>>(m, "ProfileTemplate", R"doc(
A profile template (seed 000 section 4.1, seed 001 section 4): a coarse
mesh of feature nodes encoded on a reference body, with profile curves on
some edges; regenerated and refined on other bodies of that body's
topology. Read from its JSON (docs/template-format.md) or made by
``project_templates``. Immutable.
)doc")
      .def_static("load", &load_template, py::arg("path"),
                  "Reads a .template.json (ValueError naming the file, the JSON location and the problem).")
      .def_static(
          "from_json",
          [](const std::string& text, const std::string& name) {
            return template_of(template_from_json_string(text, name));
          },
          py::arg("text"), py::arg("name") = "<memory>", "The same from a string.")
      .def(
          "to_json", [](const Template& t) { return template_to_json_string(*t.t); }, "The JSON document.")
      .def(
          "save",
          [](const Template& t, const fs::path& path) {
            py::gil_scoped_release release;
            write_template_json(*t.t, path);
          },
          py::arg("path"), "Writes the JSON atomically.")
      .def_property_readonly("name", [](const Template& t) { return t.t->name; })
      .def_property_readonly(
          "reference", [](const Template& t) { return t.t->reference; },
          "The reference body it was encoded on (node and face counts).")
      .def_property_readonly("levels", [](const Template& t) { return t.t->levels; })
      .def_property_readonly("clearance", [](const Template& t) { return t.t->clearance; })
      .def_property_readonly("node_names", [](const Template& t) { return t.t->node_names; })
      .def_property_readonly("profile_count", [](const Template& t) { return t.t->profiles.size(); })
      .def_property_readonly(
          "mesh", [](const Template& t) { return mesh_of(t.t->model); },
          "The coarse template on its reference body as a Mesh (a copy of the model; surfaces as groups).")
      .def("__repr__", [](const Template& t) {
        return "<atelier.ProfileTemplate '" + t.t->name + "': " + std::to_string(t.t->model.num_faces()) + " faces, " +
               std::to_string(t.t->profiles.size()) + " profiles>";
      });

  m.def("read_profile_template", &load_template, py::arg("path"), "ProfileTemplate.load(path).");

  m.def(
      "project_templates",
      [](const Body& body) {
        std::vector<ProfileTemplate> ts;
        {
          py::gil_scoped_release release;
          ts = unwrap(make_project_templates(*body.reference));
        }
        py::list out;
        for (auto& t : ts) {
          t.reference = "python: " + reference_tag(*body.reference);
          out.append(py::cast(template_of(std::move(t))));
        }
        return out;
      },
      py::arg("body"), R"doc(
The project's profile templates encoded on ``body`` (a mannequin or
MakeHuman Body with feature curves): [top, skirt, trousers], as
``atelier encode --template all`` makes them.
)doc");

  py::class_<ProfileRegeneration>(m, "ProfileRegeneration", "The result of regenerate_profiles().")
      .def_readonly("names", &ProfileRegeneration::names)
      .def_readonly("meshes", &ProfileRegeneration::meshes, "Per body: one Mesh per template (None if it failed).")
      .def_readonly("quality", &ProfileRegeneration::quality, "Per template: structured array (B,).")
      .def_readonly("ok", &ProfileRegeneration::ok)
      .def_readonly("errors", &ProfileRegeneration::errors)
      .def("__len__", [](const ProfileRegeneration& r) { return py::len(r.ok); });

  m.def("regenerate_profiles", &regenerate_profiles, py::arg("templates"), py::arg("reference"), py::arg("bodies"),
        py::kw_only(), py::arg("levels") = -1, py::arg("clearance") = -1.0, py::arg("threads") = 0,
        py::arg("progress") = py::none(), R"doc(
Regenerates profile templates on bodies (seed 001 section 4: decode the
feature nodes and profiles; seed 000 section 4.2: the modified variational
subdivision with collision avoidance), as ``atelier regen`` does for
.template.json files.

templates: a ProfileTemplate or a list, encoded on ``reference`` (a Body).
bodies: (n, 3) or (B, n, 3) positions of bodies with the reference's
    topology.
levels, clearance: refinement levels and the distance kept from the body
    (m); negative: each template's own.

Returns a ProfileRegeneration: ``meshes[b][t]`` the regenerated Mesh
(surfaces and joints as groups), ``quality[t]`` a structured array (B,):
ok, nodes, faces, inside, pushed, max_depth, min_distance,
node_clearance_error, profile_error, umbrella, crack. Parallel over bodies,
GIL released, progress per body, Ctrl-C cancels.
)doc");
}

}  // namespace atelier::python
