// Garment regeneration (systems/garment/regenerate_garment.h): the one
// pipeline, on batches of bodies given as (B, n, 3) arrays: batched
// decoding, the edge transfer, the collision pass with layers and the fit
// figures, as `atelier regen` runs them, bit for bit; and measure_fit
// (systems/garment/fit_measure.h).
#include <atelier/engine/parallel.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/garment/fit_measure.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "bind.h"

namespace atelier::python {
/// One body's fit of one garment: the pipeline's figures (GarmentQuality)
/// and, with fit=True, those of measure_fit against the garment on the
/// reference body (NaN otherwise).
struct QualityRow {
  bool ok;
  std::uint64_t vertices, inside, pushed;
  std::uint64_t layer_inside;  // vertices inside a garment of a lower layer (count_inside_layer)
  double max_depth, min_clearance, mean_clearance, clearance_error, clearance_change, strain_p95, strain_max;
  double clearance_change_rms, excess_strain_p95, clearance_p50, clearance_p95;
};
}  // namespace atelier::python

namespace atelier::python {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Regenerator {
  GarmentRegenerator regenerator;
  std::shared_ptr<Family> family;
  std::vector<std::shared_ptr<Garment>> garments;
  std::mutex busy;  // GarmentRegenerator: one caller at a time
};

struct Regeneration {
  std::vector<std::string> names;
  py::list positions;
  py::list quality;
  py::array ok;
  py::list errors;
};

QualityRow failed_row() {
  QualityRow r{};
  r.ok = false;
  r.max_depth = r.min_clearance = r.mean_clearance = r.clearance_error = r.clearance_change = r.strain_p95 =
      r.strain_max = kNaN;
  r.clearance_change_rms = r.excess_strain_p95 = r.clearance_p50 = r.clearance_p95 = kNaN;
  return r;
}

QualityRow row_of(const GarmentQuality& q, double reference_mean_clearance) {
  QualityRow r = failed_row();
  r.ok = true;
  r.vertices = q.vertices;
  r.inside = q.inside;
  r.pushed = q.pushed;
  r.layer_inside = q.layer_inside;
  r.max_depth = q.max_depth;
  r.min_clearance = q.min_clearance;
  r.mean_clearance = q.mean_clearance;
  r.clearance_error = q.clearance_error;
  r.clearance_change = q.mean_clearance - reference_mean_clearance;
  r.strain_p95 = q.strain_p95;
  r.strain_max = q.strain_max;
  return r;
}

py::dict quality_dict(const QualityRow& r) {
  py::dict d;
  const py::array_t<QualityRow> one(1, &r);
  const py::object names = one.dtype().attr("names");
  for (py::handle n : names) d[n] = one[n].attr("item")(0);
  return d;
}

GarmentRegenOptions regen_options(bool layers, bool edge_transfer, bool collision_pass, const std::string& kernel) {
  GarmentRegenOptions o;
  o.layers = layers;
  o.edge_transfer = edge_transfer;
  o.collision_pass = collision_pass;
  if (kernel == "auto")
    o.kernel = DecodeKernel::kAuto;
  else if (kernel == "avx512")
    o.kernel = DecodeKernel::kAvx512;
  else if (kernel == "avx2")
    o.kernel = DecodeKernel::kAvx2;
  else if (kernel == "portable")
    o.kernel = DecodeKernel::kPortable;
  else
    value_error("kernel: 'auto', 'avx512', 'avx2' or 'portable', got '" + kernel + "'");
  return o;
}

std::vector<std::shared_ptr<Garment>> garments_arg(py::handle garments) {
  std::vector<std::shared_ptr<Garment>> out;
  if (py::isinstance<Garment>(garments)) {
    out.push_back(garments.cast<std::shared_ptr<Garment>>());
  } else {
    for (py::handle g : garments) {
      if (!py::isinstance<Garment>(g)) throw py::type_error("garments: expected GarmentTemplate objects");
      out.push_back(g.cast<std::shared_ptr<Garment>>());
    }
  }
  if (out.empty()) value_error("garments: none given");
  for (const auto& g : out)
    if (g->family->family != out[0]->family->family)
      value_error("garments: '" + g->garment->name + "' and '" + out[0]->garment->name +
                  "' were encoded on different GarmentFamily objects (layers share one body family)");
  return out;
}

std::shared_ptr<Regenerator> make_regenerator(const Garments& garments, bool layers, bool edge_transfer,
                                              bool collision_pass, const std::string& kernel) {
  auto r = std::make_shared<Regenerator>();
  r->garments = garments_arg(garments);
  r->family = r->garments[0]->family;
  std::vector<std::shared_ptr<const GarmentTemplate>> t;
  for (const auto& g : r->garments) t.push_back(g->garment);
  const GarmentRegenOptions options = regen_options(layers, edge_transfer, collision_pass, kernel);
  py::gil_scoped_release release;
  r->regenerator = unwrap(GarmentRegenerator::create(r->family->family, std::move(t), options));
  return r;
}

/// The batch: bodies (B, n, 3) in chunks through GarmentRegenerator::run,
/// each chunk's results copied into the output arrays (one copy: the
/// engine gives one vector per body and garment).
Regeneration run_batch(Regenerator& r, const Array& bodies, int threads, const Progress& progress, std::size_t chunk,
                       const DType& dtype, bool fit) {
  const BodyBatch batch(bodies, r.family->body->node_count(), "bodies");
  if (chunk == 0) value_error("chunk: at least 1 body");
  const bool f32 = float32_arg(dtype);
  const std::size_t nb = batch.size(), ng = r.garments.size();
  Regeneration out;
  std::vector<void*> pos(ng);
  std::vector<QualityRow*> qual(ng);
  std::vector<std::size_t> nv(ng);
  for (std::size_t g = 0; g < ng; ++g) {
    const GarmentTemplate& t = *r.garments[g]->garment;
    nv[g] = t.mesh.positions.size();
    out.names.push_back(t.name);
    const std::vector<py::ssize_t> shape = {static_cast<py::ssize_t>(nb), static_cast<py::ssize_t>(nv[g]), 3};
    py::array a = f32 ? py::array(py::array_t<float>(shape)) : py::array(py::array_t<double>(shape));
    pos[g] = a.mutable_data();
    out.positions.append(a);
    py::array_t<QualityRow> q(static_cast<py::ssize_t>(nb));
    qual[g] = q.mutable_data();
    out.quality.append(q);
  }
  py::array_t<bool> ok(static_cast<py::ssize_t>(nb));
  bool* ok_data = ok.mutable_data();
  std::vector<std::string> errors(nb);

  std::unique_lock<std::mutex> lock(r.busy, std::try_to_lock);
  if (!lock.owns_lock())
    throw py::value_error("this Regenerator is running in another thread: make one Regenerator per thread");
  run_long(progress, threads, [&](const ExecContext& ctx) {
    check(batch.check(ctx));
    const GarmentFamily& family = *r.family->family;
    BodySet set(r.family->body->reference);
    set.reserve(std::min(chunk, nb));
    std::vector<BodyGarments> result;
    std::vector<Vec3f> scratch;
    ExecContext per_body = ctx;
    per_body.sequential_threshold = 2;
    per_body.grain = 1;
    ctx.report("bodies", 0, nb);
    for (std::size_t first = 0; first < nb; first += chunk) {
      if (ctx.cancelled()) raise(Status(ErrorCode::kCancelled, "garment regeneration cancelled"));
      const std::size_t count = std::min(chunk, nb - first);
      set.clear();
      for (std::size_t b = first; b < first + count; ++b) {
        const std::string name = "body " + std::to_string(b);
        if (auto f = batch.floats(b); !f.empty()) {
          check(set.add(name, f));
        } else if (auto d = batch.doubles(b); !d.empty()) {
          check(set.add(name, d));
        } else {
          batch.get(b, scratch);
          check(set.add(name, std::span<const Vec3f>(scratch)));
        }
      }
      check(r.regenerator.run(set, 0, count, result, ctx));
      par::for_each_n(per_body, count, [&](std::size_t k) {
        const std::size_t b = first + k;
        BodyGarments& body = result[k];
        ok_data[b] = body.status.is_ok();
        if (!body.status) errors[b] = body.status.to_string();
        std::vector<Vec3d> body_points;
        if (fit && body.status) body_points = set.positions(k);
        for (std::size_t g = 0; g < ng; ++g) {
          const std::size_t n3 = 3 * nv[g];
          if (!body.status) {
            qual[g][b] = failed_row();
            if (f32)
              std::fill_n(static_cast<float*>(pos[g]) + b * n3, n3, std::numeric_limits<float>::quiet_NaN());
            else
              std::fill_n(static_cast<double*>(pos[g]) + b * n3, n3, kNaN);
            continue;
          }
          const GarmentResult& res = body.garments[g];
          QualityRow row = row_of(res.quality, r.garments[g]->reference_mean_clearance);
          if (fit) {
            const GarmentTemplate& t = *r.garments[g]->garment;
            FitInput in;
            in.body_points = body_points;
            in.body_triangles = family.collision->triangles();
            in.garment = res.positions;
            in.garment_edges = t.edges;
            in.source_garment = t.mesh.positions;
            in.source_body_points = family.reference_positions;
            ExecContext inner = ExecContext::sequential();
            inner.cancel = ctx.cancel;
            if (auto f = measure_fit(in, {}, inner); f) {
              row.clearance_change_rms = f->clearance_change_rms;
              row.excess_strain_p95 = f->excess_strain_p95;
              row.clearance_p50 = f->clearance_p50;
              row.clearance_p95 = f->clearance_p95;
            }
          }
          qual[g][b] = row;
          if (f32) {
            float* o = static_cast<float*>(pos[g]) + b * n3;
            for (std::size_t v = 0; v < nv[g]; ++v)
              for (int c = 0; c < 3; ++c) o[3 * v + c] = static_cast<float>(res.positions[v][c]);
          } else {
            std::copy_n(res.positions.data()->data(), n3, static_cast<double*>(pos[g]) + b * n3);
          }
        }
        body = {};  // frees the body's vectors as soon as they are copied
      });
      ctx.report("bodies", first + count, nb);
    }
  });
  out.ok = ok;
  for (std::size_t b = 0; b < nb; ++b)
    out.errors.append(errors[b].empty() ? py::object(py::none()) : py::str(errors[b]));
  return out;
}

const char* kRegenerateDoc = R"doc(
Regenerates garments on a batch of bodies: the engine's garment pipeline
(systems/garment/regenerate_garment.h), as ``atelier regen`` runs it, bit
for bit.

garments: a GarmentTemplate, or a list of them encoded on the same
    GarmentFamily: several garments are one outfit, resolved as layers in
    z_depth order (outer garments kept outside inner ones) unless
    layers=False.
bodies: (B, n, 3) float32 or float64 array of B bodies with the family's
    topology (n = family.node_count), in metres; read in place (any
    strides) and copied once per chunk into the engine's float body set.
threads: worker threads, 0 = all cores; results are the same bits for any
    count.
progress: optional callable(stage, done, total), called on this thread
    after each chunk ("bodies", bodies done, B); raise from it to cancel.
chunk: bodies per engine call (memory: one chunk of decoded garments).
dtype: float64 (the engine's precision) or float32 for the positions.
fit: also run measure_fit on every body against the garment on the
    reference body (clearance_change_rms, excess_strain_p95,
    clearance_p50/p95; slower: two BVH builds per body).

Returns a Regeneration: ``positions[g]`` is a (B, m_g, 3) array per garment
(one copy from the engine's per-body vectors), ``quality[g]`` a structured
array (B,) of fit figures: ok, vertices, inside (vertices inside the
body), pushed, layer_inside (vertices inside a garment of a lower layer
of the outfit: count_inside_layer, systems/garment/fit_measure.h; 0 for the
innermost layer and with layers=False), max_depth, min_clearance,
mean_clearance, clearance_error
(max |distance - target clearance|), clearance_change (mean clearance
minus the mean on the reference body), strain_p95, strain_max
(|l / l_reference - 1| over edges), and the fit=True fields. A body that
fails has ok False, NaN positions and its reason in ``errors[b]``; the
others complete.

Raises ValueError for a bad array (shape, dtype, NaN: naming the body and
vertex); KeyboardInterrupt on Ctrl-C (the engine is cancelled, nothing is
returned). The GIL is released while the engine runs.
)doc";

}  // namespace

void bind_regenerate(py::module_& m) {
  // The structured numpy dtype of the fit figures (registered at import).
  PYBIND11_NUMPY_DTYPE(QualityRow, ok, vertices, inside, pushed, layer_inside, max_depth, min_clearance, mean_clearance,
                       clearance_error, clearance_change, strain_p95, strain_max, clearance_change_rms,
                       excess_strain_p95, clearance_p50, clearance_p95);

  py::class_<Regeneration>(m, "Regeneration", "The result of regenerate() / Regenerator.run() (see regenerate).")
      .def_readonly("names", &Regeneration::names, "Garment names, in the order given.")
      .def_readonly("positions", &Regeneration::positions, "Per garment: (B, m, 3) positions.")
      .def_readonly("quality", &Regeneration::quality, "Per garment: structured array (B,) of fit figures.")
      .def_readonly("ok", &Regeneration::ok, "(B,) bool: the body completed.")
      .def_readonly("errors", &Regeneration::errors, "Per body: None, or why it failed.")
      .def("__len__", [](const Regeneration& r) { return py::len(r.ok); })
      .def("__repr__", [](const Regeneration& r) {
        std::string names;
        for (const auto& n : r.names) names += (names.empty() ? "" : ", ") + n;
        return "<atelier.Regeneration: " + std::to_string(py::len(r.ok)) + " bodies x [" + names + "]>";
      });

  py::class_<Regenerator, std::shared_ptr<Regenerator>>(m, "Regenerator", R"doc(
The reusable garment pipeline: decoders built once per garment, buffers
kept across calls (GarmentRegenerator). One object per concurrent caller.
)doc")
      .def(py::init(&make_regenerator), py::arg("garments"), py::kw_only(), py::arg("layers") = true,
           py::arg("edge_transfer") = true, py::arg("collision_pass") = true, py::arg("kernel") = "auto", R"doc(
garments: a GarmentTemplate or a list of them (one outfit, layered).
layers: resolve several garments as layers (z_depth order).
edge_transfer, collision_pass: the pipeline's stages after decoding.
kernel: decoding kernel: 'auto' (widest this CPU runs), 'avx512', 'avx2',
    'portable'.
)doc")
      .def_property_readonly("garments",
                             [](const Regenerator& r) {
                               py::list l;
                               for (const auto& g : r.garments) l.append(py::cast(g));
                               return l;
                             })
      .def("run", &run_batch, py::arg("bodies"), py::kw_only(), py::arg("threads") = 0,
           py::arg("progress") = py::none(), py::arg("chunk") = 256, py::arg("dtype") = "float64",
           py::arg("fit") = false, kRegenerateDoc)
      .def(
          "run_one",
          [](const Regenerator& r, const Array& body) {
            const std::vector<Vec3d> p = r.family->body->positions_arg(body, "body");
            BodyGarments b;
            {
              py::gil_scoped_release release;
              b = r.regenerator.run_one(p);
            }
            check(b.status);
            py::list out;
            for (std::size_t g = 0; g < b.garments.size(); ++g) {
              const QualityRow row = row_of(b.garments[g].quality, r.garments[g]->reference_mean_clearance);
              out.append(py::make_tuple(adopt_points(std::move(b.garments[g].positions)), quality_dict(row)));
            }
            return out;
          },
          py::arg("body"), R"doc(
One body (n, 3), decoded on its own: a list with one (positions, quality)
per garment. The positions array owns the engine's vector (moved, no copy);
quality is a dict of the fields of ``regenerate``'s quality. Raises
ValueError when the body fails.
)doc");

  m.def(
      "regenerate",
      [](const Garments& garments, const Array& bodies, bool layers, bool edge_transfer, bool collision_pass,
         int threads, const Progress& progress, std::size_t chunk, const DType& dtype, bool fit) {
        auto r = make_regenerator(garments, layers, edge_transfer, collision_pass, "auto");
        return run_batch(*r, bodies, threads, progress, chunk, dtype, fit);
      },
      py::arg("garments"), py::arg("bodies"), py::kw_only(), py::arg("layers") = true, py::arg("edge_transfer") = true,
      py::arg("collision_pass") = true, py::arg("threads") = 0, py::arg("progress") = py::none(),
      py::arg("chunk") = 256, py::arg("dtype") = "float64", py::arg("fit") = false, kRegenerateDoc);

  m.def(
      "measure_fit",
      [](const MeshLike& body, const MeshLike& garment, const OptArray& source_garment, const OptArray& source_body,
         double inside_tolerance, int threads) {
        const auto b = mesh_from(body, "body");
        const auto g = mesh_from(garment, "garment");
        const std::vector<Triangle> tris = fan_triangles(b->soup);
        const auto edges = g->soup.edges();
        std::vector<Vec3d> sg, sb;
        FitInput in;
        in.body_points = b->positions();
        in.body_triangles = tris;
        in.garment = g->positions();
        in.garment_edges = edges;
        if (!source_garment.is_none()) {
          sg = points_from(source_garment, "source_garment");
          in.source_garment = sg;
        }
        if (!source_body.is_none()) {
          sb = points_from(source_body, "source_body");
          in.source_body_points = sb;
        }
        FitMeasureParams params;
        params.inside_tolerance = inside_tolerance;
        const FitMeasure f =
            run_long(py::none(), threads, [&](const ExecContext& ctx) { return unwrap(measure_fit(in, params, ctx)); });
        py::dict d;
        d["vertices"] = f.vertices;
        d["edges"] = f.edges;
        d["inside"] = f.inside;
        d["inside_tolerance"] = f.inside_tolerance;
        d["max_depth"] = f.max_depth;
        d["clearance_min"] = f.clearance_min;
        d["clearance_mean"] = f.clearance_mean;
        d["clearance_p50"] = f.clearance_p50;
        d["clearance_p95"] = f.clearance_p95;
        if (f.has_source) d["edge_strain_p95"] = f.edge_strain_p95;
        if (f.has_source_body) {
          d["clearance_change_rms"] = f.clearance_change_rms;
          d["excess_strain_p95"] = f.excess_strain_p95;
        }
        return d;
      },
      py::arg("body"), py::arg("garment"), py::kw_only(), py::arg("source_garment") = py::none(),
      py::arg("source_body") = py::none(), py::arg("inside_tolerance") = 0.001, py::arg("threads") = 0, R"doc(
The fit of a garment on a body, as ``atelier measure`` reports it
(systems/garment/fit_measure.h), from exact signed distances.

body, garment: Mesh, Body or (vertices, faces). source_garment: the same
garment as designed, (m, 3); source_body: the body it was designed on,
(n, 3), same topology as ``body``. Returns a dict: vertices, edges, inside,
inside_tolerance, max_depth, clearance_min/mean/p50/p95, and with the
sources edge_strain_p95, clearance_change_rms (RMS over vertices of the
change of signed distance) and excess_strain_p95.
)doc");
}

}  // namespace atelier::python
