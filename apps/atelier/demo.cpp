// `atelier demo`: the main job on the embedded default. Samples mannequin
// bodies, regenerates the project's garment on each, measures quality, and
// writes meshes, a JSON report and measurements to the output folder.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>

#include "apps/atelier/commands.h"
#include "engine/parallel.h"
#include "io/atomic_file.h"
#include "io/obj.h"
#include "systems/body_bvh.h"
#include "systems/body_set.h"
#include "systems/detail_template.h"
#include "systems/mannequin.h"
#include "systems/mannequin_source.h"
#include "systems/measure.h"

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double curve_height(const ReferenceBody& b, std::int32_t id) {
  auto pl = feature_curve_polyline(b, id);
  if (!pl || pl->empty()) throw Error(Status(ErrorCode::kInternal, "mannequin curve missing"));
  double y = 0;
  for (const auto& p : *pl) y += p.y();
  return y / static_cast<double>(pl->size());
}

struct BodyQuality {
  std::string name;
  std::size_t inside = 0;       // garment vertices inside the body
  double max_depth = 0;         // deepest penetration (m)
  double min_clearance = 0;     // signed distance of the closest vertex (m)
  double mean_clearance = 0;
  double strain_p95 = 0;        // |l/l0 - 1| of garment edges, 95th percentile
  double decode_ms = 0;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace

int run_demo(const Common& common, const DemoOptions& opt, Log& log) {
  const auto t_start = std::chrono::steady_clock::now();
  const ExecContext ctx = common.context();
  fs::create_directories(opt.out / "meshes");

  // The reference body and the project's garment: shorts cut from the skin
  // between the waist and mid-thigh, 8 mm outside it.
  auto topo = make_mannequin_topology();
  if (!topo) throw Error(topo.status());
  auto topology = std::make_shared<const MannequinTopology>(std::move(*topo));
  auto ref_body = make_mannequin(MannequinParams{}, *topology);
  if (!ref_body) throw Error(ref_body.status());
  auto ref = std::make_shared<const ReferenceBody>(std::move(*ref_body));
  const double y_waist = curve_height(*ref, kWaist), y_thigh = curve_height(*ref, kThighLeft);
  const double y_knee = curve_height(*ref, kKneeLeft);
  auto garment = skin_band_garment(*ref, 0.5 * (y_thigh + y_knee), y_waist + 0.02, 0.008, 0.40, "shorts");
  if (!garment) throw Error(garment.status());
  std::vector<Vec3d> g0;
  for (std::uint32_t v = 0; v < garment->nodes.slots.capacity(); ++v) g0.push_back(garment->nodes.position[v]);
  std::vector<std::array<std::uint32_t, 2>> g_edges;
  for (std::uint32_t e = 0; e < garment->edges.slots.capacity(); ++e)
    g_edges.push_back({garment->tail(halfedge_of(EdgeIdx{e}, 0)).value, garment->tail(halfedge_of(EdgeIdx{e}, 1)).value});

  const BodyPolygons poly = BodyPolygons::from_model(ref->model);
  const auto t_enc = std::chrono::steady_clock::now();
  auto enc = encode_detail(poly, skin_positions(*ref), g0, {}, ctx);
  if (!enc) throw Error(enc.status());
  const double encode_s = seconds_since(t_enc);
  write_obj(ref->model, opt.out / "reference_body.obj");
  write_obj(*garment, opt.out / "garment_template.obj");
  write_detail(*enc, opt.out / "garment_template.atd");
  log.info("encoded the shorts (" + std::to_string(g0.size()) + " vertices, " +
           std::to_string(enc->entries() / std::max<std::size_t>(1, g0.size())) + " p-polygons each) on the mannequin");

  // Bodies, streamed in chunks: memory is bounded by the chunk size.
  MannequinSource src(topology, sample_mannequins(opt.bodies, common.seed), ref);
  auto tris = fan_triangulate(ref->model);
  if (!tris) throw Error(tris.status());
  BodySet chunk(ref);
  std::vector<BodyFailure> failures;
  std::vector<BodyQuality> quality;
  std::vector<Vec3f> decoded;
  std::ostringstream csv;
  const std::size_t nv = g0.size();
  log.progress("bodies", 0, src.size());
  for (std::size_t first = 0; first < src.size(); first += opt.chunk) {
    if (ctx.cancelled()) break;
    src.generate(first, opt.chunk, chunk, failures, ctx);
    const auto t0 = std::chrono::steady_clock::now();
    decoded.resize(chunk.size() * nv);
    if (Status s = decode_detail_batch(*enc, poly, chunk, 0, chunk.size(), decoded, ctx); !s) throw Error(s);
    const double per_body_ms = 1000.0 * seconds_since(t0) / static_cast<double>(std::max<std::size_t>(1, chunk.size()));
    // Quality of each body, in parallel over bodies.
    std::vector<BodyQuality> q(chunk.size());
    std::vector<std::string> errors(chunk.size());
    ExecContext per_body = ctx;
    per_body.sequential_threshold = 2;
    per_body.grain = 1;
    par::for_each_n(per_body, chunk.size(), [&](std::size_t b) {
      const std::vector<Vec3d> body = chunk.positions(b);
      BodyBvh bvh;
      ExecContext inner = ExecContext::sequential();
      if (Status s = bvh.build(body, tris->triangles, {}, inner); !s) {
        errors[b] = s.message();
        return;
      }
      std::vector<Vec3d> g(nv);
      for (std::size_t v = 0; v < nv; ++v) g[v] = decoded[b * nv + v].cast<double>();
      std::vector<double> sd(nv);
      if (Status s = bvh.signed_distances(g, sd, inner); !s) {
        errors[b] = s.message();
        return;
      }
      BodyQuality& r = q[b];
      r.name = chunk.name(b);
      r.min_clearance = *std::min_element(sd.begin(), sd.end());
      r.mean_clearance = std::accumulate(sd.begin(), sd.end(), 0.0) / static_cast<double>(nv);
      for (double d : sd)
        if (d < 0) {
          ++r.inside;
          r.max_depth = std::max(r.max_depth, -d);
        }
      std::vector<double> strain;
      for (const auto& e : g_edges) {
        const double l0 = (g0[e[0]] - g0[e[1]]).norm(), l = (g[e[0]] - g[e[1]]).norm();
        strain.push_back(std::abs(l / l0 - 1.0));
      }
      r.strain_p95 = percentile(strain, 0.95);
      r.decode_ms = per_body_ms;
    });
    for (std::size_t b = 0; b < chunk.size(); ++b) {
      if (!errors[b].empty()) {
        failures.push_back({first + b, chunk.name(b), Status(ErrorCode::kInternal, errors[b])});
        continue;
      }
      quality.push_back(q[b]);
      if (quality.size() <= opt.meshes) {
        Model body = ref->model;
        chunk.positions(b, body.nodes.position);
        write_obj(body, opt.out / "meshes" / (chunk.name(b) + "_body.obj"));
        Model gm = *garment;
        for (std::size_t v = 0; v < nv; ++v) gm.nodes.position[v] = decoded[b * nv + v].cast<double>();
        write_obj(gm, opt.out / "meshes" / (chunk.name(b) + "_shorts.obj"));
      }
    }
    Status s = measurements_csv(
        csv, *ref, chunk.size(), [&](std::size_t i) { return chunk.positions(i); }, ctx, first == 0, first);
    if (!s) throw Error(s);
    log.progress("bodies", std::min(src.size(), first + opt.chunk), src.size());
  }
  log.end_progress();
  write_atomically(opt.out / "measurements.csv", [&](AtomicFile& f) { f.write(csv.str()); });

  // Report.
  const double total_s = seconds_since(t_start);
  nlohmann::json rep;
  rep["tool"] = "atelier demo";
  rep["seed"] = common.seed;
  rep["bodies"] = opt.bodies;
  rep["garment"] = {{"name", "shorts"}, {"vertices", nv}, {"faces", garment->num_faces()},
                    {"p_polygons_per_vertex", enc->entries() / std::max<std::size_t>(1, nv)},
                    {"encoding_bytes", enc->bytes()}};
  std::size_t bodies_with_penetration = 0;
  double worst_depth = 0, strain_sum = 0, decode_sum = 0;
  nlohmann::json per = nlohmann::json::array();
  for (const auto& r : quality) {
    bodies_with_penetration += r.inside > 0;
    worst_depth = std::max(worst_depth, r.max_depth);
    strain_sum += r.strain_p95;
    decode_sum += r.decode_ms;
    per.push_back({{"body", r.name},
                   {"inside_vertices", r.inside},
                   {"max_depth_m", r.max_depth},
                   {"min_clearance_m", r.min_clearance},
                   {"mean_clearance_m", r.mean_clearance},
                   {"edge_strain_p95", r.strain_p95},
                   {"decode_ms", r.decode_ms}});
  }
  const double nq = std::max<double>(1, static_cast<double>(quality.size()));
  rep["summary"] = {{"completed", quality.size()},
                    {"failed", failures.size()},
                    {"bodies_with_penetration", bodies_with_penetration},
                    {"worst_penetration_m", worst_depth},
                    {"mean_edge_strain_p95", strain_sum / nq},
                    {"mean_decode_ms_per_body", decode_sum / nq},
                    {"encode_s", encode_s},
                    {"total_s", total_s},
                    {"bodies_per_s", static_cast<double>(quality.size()) / total_s}};
  nlohmann::json fails = nlohmann::json::array();
  for (const auto& f : failures) fails.push_back({{"body", f.name}, {"reason", f.status.to_string()}});
  rep["failures"] = fails;
  rep["bodies_quality"] = per;
  write_atomically(opt.out / "report.json", [&](AtomicFile& f) { f.write(rep.dump(1)); });

  std::printf("atelier demo: %zu bodies regenerated, %zu failed, in %.1f s (%.1f bodies/s)\n", quality.size(),
              failures.size(), total_s, static_cast<double>(quality.size()) / total_s);
  std::printf("  shorts: %zu vertices, decode %.3f ms per body, edge strain p95 %.1f%% (mean over bodies)\n", nv,
              decode_sum / nq, 100.0 * strain_sum / nq);
  std::printf("  penetration: %zu of %zu bodies have garment vertices inside the body (worst %.1f mm)\n",
              bodies_with_penetration, quality.size(), 1000.0 * worst_depth);
  std::printf("  report: %s\n", fs::absolute(opt.out / "report.json").string().c_str());
  return failures.empty() ? kExitOk : kExitPartial;
}

}  // namespace atelier::cli
