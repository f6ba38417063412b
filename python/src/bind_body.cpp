// Bodies (systems/body/): the parametric mannequin (parameters in, positions
// out), MakeHuman bodies from the shared data, a user's own body arrays, and
// body measurements as dicts or structured arrays.
//
// Why this file is long: it binds the body family's four classes (Body,
// Mannequin, MakeHuman, their parameter dtypes) with their docstrings, which
// are most of its lines; splitting them would scatter one family's Python
// surface over several files.
#include <atelier/engine/parallel.h>
#include <atelier/storage/builder.h>
#include <atelier/systems/body/body_file.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/measure.h>
#include <atelier/systems/garment/makehuman_binding.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdlib>
#include <filesystem>

#include "bind.h"

namespace atelier::python {
/// MakeHuman's macro sliders as a plain row (MacroParams without the
/// measure modifiers), for structured arrays.
struct MacroRow {
  double gender, age, muscle, weight, height, proportions, african, asian, caucasian;
};
}  // namespace atelier::python

namespace atelier::python {

namespace fs = std::filesystem;

namespace {

template <class T>
struct Field {
  const char* name;
  double T::*member;
};

const Field<MannequinParams> kMannequinFields[] = {
    {"height", &MannequinParams::height},
    {"neck_girth", &MannequinParams::neck_girth},
    {"bust_girth", &MannequinParams::bust_girth},
    {"underbust_girth", &MannequinParams::underbust_girth},
    {"waist_girth", &MannequinParams::waist_girth},
    {"hip_girth", &MannequinParams::hip_girth},
    {"thigh_girth", &MannequinParams::thigh_girth},
    {"knee_girth", &MannequinParams::knee_girth},
    {"ankle_girth", &MannequinParams::ankle_girth},
    {"upper_arm_girth", &MannequinParams::upper_arm_girth},
    {"shoulder_width", &MannequinParams::shoulder_width},
    {"back_length", &MannequinParams::back_length},
    {"inseam", &MannequinParams::inseam},
};

using makehuman::MacroParams;
const Field<MacroParams> kMacroFields[] = {
    {"gender", &MacroParams::gender},   {"age", &MacroParams::age},       {"muscle", &MacroParams::muscle},
    {"weight", &MacroParams::weight},   {"height", &MacroParams::height}, {"proportions", &MacroParams::proportions},
    {"african", &MacroParams::african}, {"asian", &MacroParams::asian},   {"caucasian", &MacroParams::caucasian},
};

template <class T, std::size_t N>
std::string field_list(const Field<T> (&fields)[N]) {
  std::string s;
  for (const auto& f : fields) s += (s.empty() ? "" : ", ") + std::string(f.name);
  return s;
}

template <class T, std::size_t N>
double T::*member_of(const Field<T> (&fields)[N], const std::string& name, const char* what) {
  for (const auto& f : fields)
    if (name == f.name) return f.member;
  value_error(std::string(what) + ": unknown field '" + name + "' (fields: " + field_list(fields) + ")");
}

double finite_value(py::handle v, const std::string& where) {
  double x;
  try {
    x = py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>();
  } catch (py::error_already_set&) {
    value_error(where + ": not a number");
  }
  if (!std::isfinite(x)) value_error(where + ": not finite");
  return x;
}

/// Parameters: a dict (one body), a sequence of dicts, a structured array
/// (fields by name, missing ones take the defaults), or None (the
/// defaults). `single` tells whether one body was given as a dict or None.
/// `extra` handles keys that are not double fields (MakeHuman's measures).
template <class T, std::size_t N, class Extra>
std::vector<T> params_from(py::handle obj, const Field<T> (&fields)[N], const char* what, bool& single, Extra&& extra) {
  single = false;
  auto from_dict = [&](py::handle d, std::size_t index) {
    T p{};
    for (auto [k, v] : py::reinterpret_borrow<py::dict>(d)) {
      const std::string key = py::str(k).cast<std::string>();
      const std::string where = std::string(what) + "[" + std::to_string(index) + "]['" + key + "']";
      if (extra(p, key, v, where)) continue;
      p.*member_of(fields, key, what) = finite_value(v, where);
    }
    return p;
  };
  if (obj.is_none()) {
    single = true;
    return {T{}};
  }
  if (py::isinstance<py::dict>(obj)) {
    single = true;
    return {from_dict(obj, 0)};
  }
  if (py::isinstance<py::array>(obj)) {
    const py::array a = py::reinterpret_borrow<py::array>(obj);
    const py::object names = a.dtype().attr("names");
    if (names.is_none())
      value_error(std::string(what) + ": a plain " + py::str(py::object(a.dtype())).cast<std::string>() +
                  " array; expected a structured array with fields named " + field_list(fields) + ", or dicts");
    single = a.ndim() == 0;
    std::vector<T> out(static_cast<std::size_t>(a.size()));
    const py::module_ np = py::module_::import("numpy");
    for (py::handle n : names) {
      const std::string name = n.cast<std::string>();
      double T::*member = member_of(fields, name, what);
      const py::array_t<double> col = np.attr("asarray")(a[n], "float64").attr("ravel")();
      for (std::size_t i = 0; i < out.size(); ++i) {
        const double x = col.at(static_cast<py::ssize_t>(i));
        if (!std::isfinite(x))
          value_error(std::string(what) + "[" + std::to_string(i) + "]['" + name + "']: not finite");
        out[i].*member = x;
      }
    }
    return out;
  }
  if (py::isinstance<py::sequence>(obj) && !py::isinstance<py::str>(obj)) {
    std::vector<T> out;
    std::size_t i = 0;
    for (py::handle d : obj) {
      if (!py::isinstance<py::dict>(d))
        value_error(std::string(what) + "[" + std::to_string(i) + "]: expected a dict of parameters");
      out.push_back(from_dict(d, i++));
    }
    return out;
  }
  value_error(std::string(what) + ": expected a dict, a list of dicts or a structured array");
}

std::vector<MannequinParams> mannequin_params(py::handle obj, bool& single) {
  auto out = params_from(obj, kMannequinFields, "params", single,
                         [](MannequinParams&, const std::string&, py::handle, const std::string&) { return false; });
  for (std::size_t i = 0; i < out.size(); ++i)
    if (Status s = validate_params(out[i]); !s) value_error("params[" + std::to_string(i) + "]: " + s.message());
  return out;
}

std::vector<MacroParams> macro_params(py::handle obj, bool& single) {
  return params_from(obj, kMacroFields, "params", single,
                     [](MacroParams& p, const std::string& key, py::handle v, const std::string& where) {
                       if (key != "measures") return false;
                       for (auto [k, x] : py::dict(py::reinterpret_borrow<py::object>(v))) {
                         const double value = finite_value(x, where + "['" + py::str(k).cast<std::string>() + "']");
                         if (value < -1 || value > 1) value_error(where + ": measure values run from -1 to 1");
                         p.measures.emplace_back(py::str(k).cast<std::string>(), value);
                       }
                       return true;
                     });
}

/// Fills a new (B, n, 3) array (or (n, 3) when single) with body(b, out)
/// for every b, in parallel on the worker thread.
template <class F>
NDArray positions_array(std::size_t count, std::size_t n, bool single, bool f32, int threads, const Progress& progress,
                        F&& body) {
  py::array out =
      f32 ? py::array(
                py::array_t<float>({static_cast<py::ssize_t>(count), static_cast<py::ssize_t>(n), py::ssize_t{3}}))
          : py::array(
                py::array_t<double>({static_cast<py::ssize_t>(count), static_cast<py::ssize_t>(n), py::ssize_t{3}}));
  void* data = out.mutable_data();
  run_long(progress, threads, [&](const ExecContext& ctx) {
    std::vector<Status> status(count);
    ExecContext per_body = ctx;
    per_body.sequential_threshold = 2;
    per_body.grain = 1;
    par::for_each_n(per_body, count, [&](std::size_t b) {
      if (ctx.cancelled()) return;
      std::vector<Vec3d> p;
      status[b] = body(b, p);
      if (!status[b]) return;
      if (f32) {
        float* o = static_cast<float*>(data) + b * n * 3;
        for (std::size_t v = 0; v < n; ++v)
          for (int k = 0; k < 3; ++k) o[3 * v + k] = static_cast<float>(p[v][k]);
      } else {
        double* o = static_cast<double*>(data) + b * n * 3;
        for (std::size_t v = 0; v < n; ++v)
          for (int k = 0; k < 3; ++k) o[3 * v + k] = p[v][k];
      }
    });
    for (std::size_t b = 0; b < count; ++b)
      if (!status[b]) raise(Status(status[b].code(), "body " + std::to_string(b) + ": " + status[b].message()));
  });
  if (single) return NDArray(out[py::int_(0)]);
  return NDArray(out);
}

struct MannequinData {
  std::shared_ptr<const MannequinTopology> topology;
  std::shared_ptr<Body> reference;  // default parameters, made on first use
};

struct MakeHumanData {
  std::shared_ptr<const makehuman::HumanLibrary> lib;
  std::shared_ptr<Body> reference;
};

py::dict measurements_dict(const ReferenceBody& ref, const BodyMeasurements& m) {
  py::dict d;
  const auto cols = measurement_columns(ref);
  const auto row = measurement_row(m);
  for (std::size_t i = 0; i < cols.size() && i < row.size(); ++i) d[py::str(cols[i])] = row[i];
  return d;
}

py::array measure_many(const Body& body, const Array& bodies, int threads, const Progress& progress) {
  const BodyBatch batch(bodies, body.node_count(), "bodies");
  const auto cols = measurement_columns(*body.reference);
  py::list fields;
  for (const auto& c : cols) fields.append(py::make_tuple(c, "f8"));
  const py::module_ np = py::module_::import("numpy");
  py::array out = np.attr("zeros")(batch.size(), np.attr("dtype")(fields));
  auto* data = static_cast<double*>(out.mutable_data());  // every field f8: rows of cols.size() doubles
  run_long(progress, threads, [&](const ExecContext& ctx) {
    check(batch.check(ctx));
    std::vector<Status> status(batch.size());
    ExecContext per_body = ctx;
    per_body.sequential_threshold = 2;
    per_body.grain = 1;
    par::for_each_n(per_body, batch.size(), [&](std::size_t b) {
      if (ctx.cancelled()) return;
      std::vector<Vec3d> p;
      batch.get(b, p);
      auto m = measure_body(*body.reference, p);
      if (!m) {
        status[b] = m.status();
        return;
      }
      const auto row = measurement_row(*m);
      std::copy(row.begin(), row.end(), data + b * cols.size());
    });
    for (std::size_t b = 0; b < batch.size(); ++b)
      if (!status[b]) raise(Status(status[b].code(), "body " + std::to_string(b) + ": " + status[b].message()));
  });
  return out;
}

const FeatureCurve& curve_named(const ReferenceBody& ref, py::handle name) {
  const FeatureCurve* c = py::isinstance<py::int_>(name) ? ref.find_curve(name.cast<std::int32_t>())
                                                         : ref.find_curve(name.cast<std::string>());
  if (!c) {
    std::string names;
    for (const auto& x : ref.curves) names += (names.empty() ? "" : ", ") + x.name;
    value_error("no feature curve " + py::str(name).cast<std::string>() +
                " (curves: " + (names.empty() ? "none" : names) + ")");
  }
  return *c;
}

fs::path default_makehuman_dir() {
  const char* env = std::getenv("ATELIER_SHARED_DATA");
  return fs::path(env && *env ? env : "../shared/data") / "makehuman";
}

}  // namespace

void bind_body(py::module_& m) {
  // Structured numpy dtypes of the rows below (registered at import).
  PYBIND11_NUMPY_DTYPE(MannequinParams, height, neck_girth, bust_girth, underbust_girth, waist_girth, hip_girth,
                       thigh_girth, knee_girth, ankle_girth, upper_arm_girth, shoulder_width, back_length, inseam);
  PYBIND11_NUMPY_DTYPE(MacroRow, gender, age, muscle, weight, height, proportions, african, asian, caucasian);

  // ------------------------------------------------------------ Body
  py::class_<Body, std::shared_ptr<Body>>(m, "Body", R"doc(
A reference body: a closed skin mesh with named feature curves and points
(girths, centre lines and their crossings), the topology that body batches,
garments and templates share.

Made by ``Mannequin.reference()``, ``MakeHuman.reference()``,
``Body.from_arrays`` (a user's own body, without features) or
``body.with_positions`` (another body of the same topology, same features).
Immutable; ``vertices`` and ``faces`` are read-only views (zero copy).
)doc")
      .def_static(
          "from_arrays",
          [](const Array& vertices, const Faces& faces) {
            PolygonSoup soup = soup_from(vertices, faces, "body");
            ReferenceBody rb;
            rb.skin = unwrap(add_polygon_surface(rb.model, "skin", soup)).idx;
            return Body::of(std::make_shared<const ReferenceBody>(std::move(rb)));
          },
          py::arg("vertices"), py::arg("faces"), R"doc(
A body from arrays (a user's own scan or model): vertices (n, 3), faces
(F, k) or a list of polygons. It has no feature curves, so it measures
nothing and profile templates refuse it; garments encode and regenerate on
it when its skin is closed and consistently oriented. One copy. Raises
ValueError for bad arrays or a mesh the engine's model refuses.
)doc")
      .def_static(
          "read",
          [](const fs::path& path, double scale, const std::string& up, std::optional<fs::path> data,
             std::optional<fs::path> features) {
            auto axis = parse_up_axis(up);
            if (!axis) value_error("up: " + axis.status().message());
            if (!fs::exists(path)) {
              PyErr_SetObject(PyExc_FileNotFoundError,
                              py::make_tuple(ENOENT, path.string() + ": no such file", path.string()).ptr());
              throw py::error_already_set();
            }
            if (features && !fs::exists(*features)) {
              PyErr_SetObject(PyExc_FileNotFoundError,
                              py::make_tuple(ENOENT, features->string() + ": no such file", features->string()).ptr());
              throw py::error_already_set();
            }
            BodyFileOptions o{.frame = {scale, *axis},
                              .makehuman_data = data ? *data : fs::path(),
                              .features = features ? *features : fs::path()};
            py::gil_scoped_release release;
            return Body::of(std::make_shared<const ReferenceBody>(unwrap(read_reference_body(path, o))));
          },
          py::arg("path"), py::kw_only(), py::arg("scale") = 1.0, py::arg("up") = "y", py::arg("data") = py::none(),
          py::arg("features") = py::none(),
          R"doc(
A user's reference body from an OBJ file (systems/body/body_file.h,
docs/body-files.md): one closed, consistently oriented, outward-facing
surface in the file's units (``scale``: to metres, 0.01 for centimetres) and
up axis (``up``: "y" or "z"), mapped to metres and Y up. A body with the
mannequin's topology (or MakeHuman's, with the shared ``data`` folder)
takes its feature curves; any other has none: garments encode and
regenerate on it, profile templates refuse it. ``features``: a
feature-curve file (JSON of named polylines, docs/body-files.md; the CLI's
``--features``), in its own "units" and "up" or else ``scale`` and ``up``:
its curves are snapped onto the skin and become the body's only curves, with
a feature point where a closed and an open curve cross, so profile
templates (``project_templates``) apply. Raises FileNotFoundError,
ValueError naming the file and the reason (not closed, not consistently
oriented, facing inward, malformed; for ``features``: the file, line, curve
and point of a malformed file or of a point too far from the skin).
)doc")
      .def_property_readonly(
          "vertices",
          [](py::object self) { return points_view(self.cast<const Body&>().reference->model.nodes.position, self); },
          "(n, 3) float64 read-only view of the skin's node positions (zero copy).")
      .def_property_readonly(
          "faces",
          [](py::object self) {
            const Body& b = self.cast<const Body&>();
            return faces_out(b.skin.face_offsets, b.skin.face_nodes, self);
          },
          "The skin's faces: (F, k) uint32 view when all have k corners, else a list of arrays.")
      .def_property_readonly(
          "triangles",
          [](const Body& b) {
            std::vector<Triangle> t = fan_triangles(b.skin);
            const auto n = static_cast<py::ssize_t>(t.size());
            std::vector<std::uint32_t> flat(3 * t.size());
            for (std::size_t i = 0; i < t.size(); ++i)
              for (int k = 0; k < 3; ++k) flat[3 * i + k] = t[i][k];
            return adopt(std::move(flat), {n, 3});
          },
          "(T, 3) uint32: the skin fan-triangulated (what collision and rendering use).")
      .def_property_readonly("node_count", &Body::node_count, "Vertices per body of this topology.")
      .def_property_readonly(
          "mesh", [](py::object self) { return std::const_pointer_cast<Mesh>(mesh_from(self, "body")); },
          "The skin as a Mesh (shares the body's arrays).")
      .def_property_readonly(
          "curves",
          [](const Body& b) {
            std::vector<std::string> n;
            for (const auto& c : b.reference->curves) n.push_back(c.name);
            return n;
          },
          "Names of the feature curves (e.g. 'waist', 'hip', 'centre_front').")
      .def_property_readonly(
          "points",
          [](const Body& b) {
            std::vector<std::string> n;
            for (const auto& p : b.reference->points) n.push_back(p.name);
            return n;
          },
          "Names of the feature points (crossings of two curves).")
      .def(
          "curve",
          [](const Body& b, const CurveName& name, const OptArray& positions) {
            const FeatureCurve& c = curve_named(*b.reference, name);
            if (positions.is_none()) return adopt_points(unwrap(feature_curve_polyline(*b.reference, c.id)));
            const auto p = b.positions_arg(positions, "positions");
            return adopt_points(unwrap(feature_curve_polyline(*b.reference, c.id, p)));
          },
          py::arg("name"), py::arg("positions") = py::none(), R"doc(
The feature curve ``name`` (or id) as a (k, 3) polyline, on this body or on
another body of its topology given by ``positions`` (n, 3). Closed curves
do not repeat their first point.
)doc")
      .def(
          "measure",
          [](const Body& b, const OptArray& positions) {
            if (positions.is_none()) return measurements_dict(*b.reference, unwrap(measure_body(*b.reference)));
            const auto p = b.positions_arg(positions, "positions");
            return measurements_dict(*b.reference, unwrap(measure_body(*b.reference, p)));
          },
          py::arg("positions") = py::none(), R"doc(
Body measurements as a dict (metres): 'stature', '<curve>_girth' (tape
measure of each closed curve), '<curve>_length', '<point>_height'; of this
body, or of another body of its topology given by ``positions`` (n, 3).
)doc")
      .def("measure_many", &measure_many, py::arg("bodies"), py::kw_only(), py::arg("threads") = 0,
           py::arg("progress") = py::none(), R"doc(
Measurements of a batch of bodies of this topology, (B, n, 3) float32 or
float64, as a structured array (B,) whose fields are the keys of
``measure()``. Parallel over bodies; GIL released.
)doc")
      .def(
          "with_positions",
          [](const Body& b, const Array& positions) {
            const auto p = b.positions_arg(positions, "positions");
            return Body::of(std::make_shared<const ReferenceBody>(unwrap(with_positions(*b.reference, p))));
          },
          py::arg("positions"),
          "Another body of this topology and features at ``positions`` (n, 3); e.g. one body of a batch.")
      .def("__repr__", [](const Body& b) {
        return "<atelier.Body: " + std::to_string(b.node_count()) + " vertices, " +
               std::to_string(b.skin.face_count()) + " faces, " + std::to_string(b.reference->curves.size()) +
               " feature curves>";
      });

  // ------------------------------------------------------------ mannequin
  m.def(
      "sample_mannequins",
      [](std::size_t n, std::uint64_t seed) {
        std::vector<MannequinParams> p = sample_mannequins(n, seed);
        return adopt(std::move(p), {static_cast<py::ssize_t>(n)});
      },
      py::arg("n"), py::arg("seed") = 1, R"doc(
n plausible adult mannequin parameter sets drawn from ``seed``, as a
structured array (n,) with one float64 field per measurement (metres):
height, neck_girth, bust_girth, underbust_girth, waist_girth, hip_girth,
thigh_girth, knee_girth, ankle_girth, upper_arm_girth, shoulder_width,
back_length, inseam. Row i is what ``atelier regen --source mannequin
--seed S`` uses for body i (the vector is moved into the array).
)doc");
  m.def(
      "sample_mannequin",
      [](std::uint64_t seed, std::size_t index) {
        const MannequinParams p = sample_mannequin(seed, index);
        py::dict d;
        for (const auto& f : kMannequinFields) d[f.name] = p.*f.member;
        return d;
      },
      py::arg("seed"), py::arg("index"), "Row ``index`` of sample_mannequins(n, seed) as a dict, drawn on its own.");
  m.def(
      "mannequin_fields",
      [] {
        std::vector<std::string> n;
        for (const auto& f : kMannequinFields) n.push_back(f.name);
        return n;
      },
      "The mannequin's parameter names.");

  py::class_<MannequinData, std::shared_ptr<MannequinData>>(m, "Mannequin", R"doc(
The procedural dress-form mannequin at one resolution: every parameter set
gives the same topology, so bodies of one Mannequin form a batch.
)doc")
      .def(py::init([](std::uint32_t level) {
             if (level < 1 || level > 16) value_error("level: 1 to 16 (6 is the default, about 23k faces)");
             auto d = std::make_shared<MannequinData>();
             d->topology = std::make_shared<const MannequinTopology>(
                 unwrap(make_mannequin_topology(MannequinResolution::from_level(level))));
             return d;
           }),
           py::arg("level") = 6, "level: resolution (6, the default and the CLI's, about 23k faces; 2 about 2.7k).")
      .def_property_readonly("node_count", [](const MannequinData& d) { return std::size_t{d.topology->num_nodes}; })
      .def_property_readonly(
          "faces",
          [](py::object self) {
            const auto& t = *self.cast<const MannequinData&>().topology;
            return faces_out(t.face_offsets, t.face_nodes, self);
          },
          "The faces (view).")
      .def(
          "reference",
          [](MannequinData& d, const Params& params) {
            bool single = false;
            const auto p = mannequin_params(params, single);
            if (!single) value_error("params: one body (a dict or None)");
            if (params.is_none()) {
              if (!d.reference)
                d.reference =
                    Body::of(std::make_shared<const ReferenceBody>(unwrap(make_mannequin(p[0], *d.topology))));
              return d.reference;
            }
            return Body::of(std::make_shared<const ReferenceBody>(unwrap(make_mannequin(p[0], *d.topology))));
          },
          py::arg("params") = py::none(), R"doc(
The mannequin as a Body with its feature curves and points; default
parameters (the CLI's reference body) when ``params`` is None.
)doc")
      .def(
          "positions",
          [](const MannequinData& d, const Params& params, const DType& dtype, int threads, const Progress& progress) {
            bool single = false;
            const auto p = mannequin_params(params, single);
            const auto topo = d.topology;
            return positions_array(p.size(), topo->num_nodes, single, float32_arg(dtype), threads, progress,
                                   [&](std::size_t b, std::vector<Vec3d>& out) {
                                     auto r = mannequin_positions(p[b], *topo);
                                     if (!r) return r.status();
                                     out = std::move(*r);
                                     return Status{};
                                   });
          },
          py::arg("params"), py::kw_only(), py::arg("dtype") = "float64", py::arg("threads") = 0,
          py::arg("progress") = py::none(), R"doc(
Body positions for parameters: a structured array (B,) such as
``sample_mannequins`` returns (missing fields take the defaults), a list of
dicts, or one dict. Returns (B, n, 3) (or (n, 3) for one dict) in metres,
float64 or float32 (``dtype``; bodies in a batch are stored as float32, so
float32 loses nothing there). One copy per body into the new array;
parallel over bodies, GIL released. Raises ValueError naming an unknown
field or a parameter out of range.
)doc");

  // ------------------------------------------------------------ MakeHuman
  py::class_<MakeHumanData, std::shared_ptr<MakeHumanData>>(m, "MakeHuman", R"doc(
MakeHuman bodies: the base mesh mixed with the macro targets (gender, age,
muscle, weight, height, proportions, ethnicity) and measure modifiers, from
the shared data folder (``<data>/makehuman``).
)doc")
      .def(py::init([](std::optional<fs::path> path, int threads, const Progress& progress) {
             const fs::path dir = path ? *path : default_makehuman_dir();
             if (!fs::exists(dir / "base.obj")) {
               const std::string message = dir.string() + ": no MakeHuman data (base.obj) here";
               PyErr_SetObject(PyExc_FileNotFoundError, py::make_tuple(ENOENT, message, dir.string()).ptr());
               throw py::error_already_set();
             }
             auto d = std::make_shared<MakeHumanData>();
             d->lib = std::make_shared<const makehuman::HumanLibrary>(run_long(
                 progress, threads, [&](const ExecContext& ctx) { return makehuman::HumanLibrary::load(dir, ctx); }));
             return d;
           }),
           py::arg("path") = py::none(), py::kw_only(), py::arg("threads") = 0, py::arg("progress") = py::none(),
           R"doc(
Loads the MakeHuman folder (``path``; default $ATELIER_SHARED_DATA/makehuman,
else ../shared/data/makehuman). FileNotFoundError when absent, ValueError
naming the file for bad data. GIL released.
)doc")
      .def_property_readonly(
          "node_count", [](const MakeHumanData& d) { return d.lib->skin_vertex_count(); }, "Skin vertices per body.")
      .def_property_readonly("measure_modifiers", [](const MakeHumanData& d) { return d.lib->measure_modifiers(); })
      .def(
          "reference",
          [](MakeHumanData& d) {
            if (!d.reference)
              d.reference = Body::of(std::make_shared<const ReferenceBody>(makehuman::make_reference_body(*d.lib)));
            return d.reference;
          },
          "The default MakeHuman body (metres) with its girth loops and centre lines as a Body.")
      .def_static(
          "sample",
          [](std::size_t n, std::uint64_t seed) {
            const auto p = makehuman::sample_adults(n, seed);
            std::vector<MacroRow> rows(n);
            for (std::size_t i = 0; i < n; ++i)
              rows[i] = {p[i].gender,      p[i].age,     p[i].muscle, p[i].weight,   p[i].height,
                         p[i].proportions, p[i].african, p[i].asian,  p[i].caucasian};
            return adopt(std::move(rows), {static_cast<py::ssize_t>(n)});
          },
          py::arg("n"), py::arg("seed") = 1, R"doc(
n random adults' sliders with the height slider drawn uniformly (0.2-0.9:
17% of them taller than 2.05 m) as a structured array (n,) of macro slider
values: gender, age, muscle, weight, height, proportions, african, asian,
caucasian. The bodies of ``atelier regen --source makehuman --seed S`` are
``MakeHuman(...).adults(n, S)``: the same sliders with the height slider of
a stature drawn from a survey (docs/body-files.md).
)doc")
      .def(
          "adults",
          [](const MakeHumanData& d, std::size_t n, std::uint64_t seed) {
            std::vector<MacroRow> rows(n);
            std::vector<double> stature(n);
            for (std::size_t i = 0; i < n; ++i) {
              const auto p = makehuman::sample_adult(*d.lib, seed, i, &stature[i]);
              rows[i] = {p.gender, p.age, p.muscle, p.weight, p.height, p.proportions, p.african, p.asian, p.caucasian};
            }
            return py::make_tuple(adopt(std::move(rows), {static_cast<py::ssize_t>(n)}),
                                  adopt(std::move(stature), {static_cast<py::ssize_t>(n)}));
          },
          py::arg("n"), py::arg("seed") = 1, R"doc(
n random adults as ``atelier regen --source makehuman --seed S`` draws
them: (rows, stature) with rows the structured array of ``sample`` (the
height slider chosen to give a stature drawn per sex from NHANES
2015-2018 percentiles, docs/body-files.md) and stature (n,) their
statures in metres (soles on y = 0 to the top of the head).
)doc")
      .def(
          "positions",
          [](const MakeHumanData& d, const Params& params, const DType& dtype, int threads, const Progress& progress) {
            bool single = false;
            const auto p = macro_params(params, single);
            const auto lib = d.lib;
            const std::size_t n = lib->skin_vertex_count();
            return positions_array(p.size(), n, single, float32_arg(dtype), threads, progress,
                                   [&](std::size_t b, std::vector<Vec3d>& out) {
                                     std::vector<Vec3f> full(lib->vertex_count());
                                     try {
                                       lib->build(p[b], full);
                                     } catch (const std::exception& e) {
                                       return Status(ErrorCode::kInvalidArgument, e.what());
                                     }
                                     out.resize(n);
                                     for (std::size_t v = 0; v < n; ++v)
                                       out[v] = makehuman::kMakeHumanToMetres * full[v].cast<double>();
                                     return Status{};
                                   });
          },
          py::arg("params"), py::kw_only(), py::arg("dtype") = "float64", py::arg("threads") = 0,
          py::arg("progress") = py::none(), R"doc(
Skin positions (metres) for macro parameters: a structured array such as
``MakeHuman.sample`` returns, a list of dicts or one dict (a dict may hold
'measures': {'measure-waist-circ': -0.3, ...}, values in [-1, 1]). Returns
(B, n, 3) or (n, 3); parallel, GIL released.
)doc")
      .def(
          "garment",
          [](const MakeHumanData& d, const fs::path& mhclo) {
            if (!fs::exists(mhclo)) {
              PyErr_SetObject(PyExc_FileNotFoundError,
                              py::make_tuple(ENOENT, mhclo.string() + ": no such file", mhclo.string()).ptr());
              throw py::error_already_set();
            }
            PolygonSoup soup;
            {
              py::gil_scoped_release release;
              soup = unwrap(makehuman::fitted_garment(*d.lib, mhclo));
            }
            auto mesh = std::make_shared<Mesh>();
            mesh->soup = std::move(soup);
            return mesh;
          },
          py::arg("mhclo"), R"doc(
A MakeHuman garment (.mhclo and the OBJ beside it) fitted by its binding on
the default body, in metres: the garment on ``reference()``, ready for
``encode_garment``. Returns a Mesh.
)doc");
}

}  // namespace atelier::python
