// `atelier demo`: the main job on the embedded default. Samples mannequin
// bodies and regenerates on each the project's three profile templates (top
// with collar, skirt, trousers: modified variational subdivision with
// collision avoidance) and its detail template (shorts), resolves the four
// as one outfit (demo_outfit.h: shorts, trousers, skirt, top, innermost
// first, by the library's resolve_layers), measures quality, and writes
// meshes, a JSON report, pictures, an HTML report and the bodies'
// measurements to the output folder.
//
// run_demo is the outline; its stages: set_up (the reference mannequin, the
// shorts encoded on it, the profile templates), run_bodies (the bodies in
// chunks: the shorts and the profile templates on each, quality, meshes,
// measurements), write_report (report.json), write_html (report.html and
// its pictures) and print_summary. The algorithms are library calls
// (systems/garment/regenerate_garment.h, systems/profile/regenerate.h).
//
// Why this file is long: the demo is the one command that shows every
// stage at once, and each stage (set-up, bodies, report, pictures,
// patterns) writes its own outputs; they share the reference's structures.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <sstream>

#include <atelier/engine/parallel.h>
#include <atelier/storage/builder.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/obj.h>
#include <atelier/io/png.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/body/measure.h>
#include <atelier/systems/garment/collision_pass.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/pattern/made_to_measure.h>
#include <atelier/systems/profile/project_templates.h>
#include <atelier/systems/profile/regenerate.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/view/render.h>

#include "commands.h"
#include "demo_outfit.h"
#include "html_report.h"
#include "regen_report.h"

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
  std::size_t inside = 0;    // garment vertices inside the body
  double max_depth = 0;      // deepest penetration (m)
  double min_clearance = 0;  // signed distance of the closest vertex (m)
  double mean_clearance = 0;
  double strain_p95 = 0;  // |l/l0 - 1| of garment edges, 95th percentile
  /// RMS over the shorts' vertices of (signed distance on this body - signed
  /// distance on the reference body): issue 7's clearance change
  /// (fit_measure.h), from the same exact distances as the figures above.
  double clearance_change_rms = 0;
  double decode_ms = 0;
  std::size_t pushed = 0;               // garment vertices moved by the collision pass
  std::vector<RegenQuality> templates;  // one per profile template
  /// Garment vertices inside a garment of a lower layer of the outfit
  /// (count_inside_layer, each vertex once): as each garment is fitted alone
  /// (where the shorts poked through the skirt), and after the layering.
  std::size_t layer_inside_unlayered = 0;
  std::size_t layer_inside = 0;
  std::size_t layer_pushed = 0;  // profile-template vertices the layering moved
  std::array<std::size_t, kDemoOutfitOrder.size()> layer_inside_by{};  // after layering, by place in the order
};

// ------------------------------------------------------------------ set-up

/// What every body is regenerated from, made once on the reference
/// mannequin.
struct DemoReference {
  std::shared_ptr<const MannequinTopology> topology;
  std::shared_ptr<const ReferenceBody> body;
  Model garment;  // the shorts on the reference body
  std::shared_ptr<const GarmentFamily> family;
  std::shared_ptr<const GarmentTemplate> shorts;  // the shorts as a detail template
  std::vector<ProfileTemplate> templates;         // the project's profile templates
  Box3d roi;                                      // what the profile templates' collider covers
  SurfaceTriangles body_triangles;                // for the pictures
  std::vector<Triangle> shorts_triangles;         // the shorts fanned (layer counts)
  std::vector<ModelLayer> layers;                 // per profile template: it as a layer of the outfit
  std::vector<int> template_z;                    // per profile template: its place in kDemoOutfitOrder
  int shorts_z = 0;
  double encode_s = 0;                            // wall time of the shorts' encoding
};

int outfit_place(std::string_view name) {
  const auto it = std::find(kDemoOutfitOrder.begin(), kDemoOutfitOrder.end(), name);
  if (it == kDemoOutfitOrder.end())
    throw Error(Status(ErrorCode::kInternal, "demo: garment '" + std::string(name) + "' has no place in the outfit"));
  return static_cast<int>(it - kDemoOutfitOrder.begin());
}

/// The shorts' edges in the model's order, as encode_garment takes them.
std::vector<std::array<std::uint32_t, 2>> edges_of(const Model& garment) {
  std::vector<std::array<std::uint32_t, 2>> edges;
  for (std::uint32_t e = 0; e < garment.edges.slots.capacity(); ++e)
    edges.push_back({garment.tail(halfedge_of(EdgeIdx{e}, 0)).value, garment.tail(halfedge_of(EdgeIdx{e}, 1)).value});
  return edges;
}

/// The reference mannequin; the shorts cut from its skin between the waist
/// and mid-thigh, 8 mm outside it, encoded as a detail template (seed 001
/// section 6) with the clearance and edge transfer of the garment pipeline
/// (systems/garment/regenerate_garment.h); the profile templates authored
/// on it (systems/profile/project_templates.h). Writes the reference body,
/// the shorts (.obj, .atd) and the templates' meshes to the output folder.
DemoReference set_up(const DemoOptions& opt, const ExecContext& ctx, Log& log) {
  DemoReference r;
  auto topo = make_mannequin_topology();
  if (!topo) throw Error(topo.status());
  r.topology = std::make_shared<const MannequinTopology>(std::move(*topo));
  auto ref_body = make_mannequin(MannequinParams{}, *r.topology);
  if (!ref_body) throw Error(ref_body.status());
  r.body = std::make_shared<const ReferenceBody>(std::move(*ref_body));
  const ReferenceBody& ref = *r.body;
  const double y_waist = curve_height(ref, kWaist), y_thigh = curve_height(ref, kThighLeft);
  const double y_knee = curve_height(ref, kKneeLeft);
  auto garment = skin_band_garment(ref, 0.5 * (y_thigh + y_knee), y_waist + 0.02, 0.008, 0.40, "shorts");
  if (!garment) throw Error(garment.status());
  r.garment = std::move(*garment);

  const std::vector<std::array<std::uint32_t, 2>> edges = edges_of(r.garment);
  GarmentEncodeOptions geo;
  geo.edges = edges;  // a view: `edges` outlives the encoding
  PolygonSoup shorts_soup = polygon_soup(r.garment);
  auto family = GarmentFamily::of(ref);
  if (!family) throw Error(family.status());
  r.family = std::make_shared<const GarmentFamily>(std::move(*family));
  const auto t_enc = std::chrono::steady_clock::now();
  auto shorts = encode_garment(*r.family, "shorts", std::move(shorts_soup), geo, ctx);
  if (!shorts) throw Error(shorts.status());
  r.encode_s = seconds_since(t_enc);
  r.shorts = std::make_shared<const GarmentTemplate>(std::move(*shorts));
  const DetailEncoding& enc = r.shorts->encoding;
  const std::vector<Vec3d>& g0 = r.shorts->mesh.positions;
  auto body_tris = fan_triangulate(ref.model);
  if (!body_tris) throw Error(body_tris.status());
  r.body_triangles = std::move(*body_tris);
  auto shorts_tris = fan_triangulate(r.garment);
  if (!shorts_tris) throw Error(shorts_tris.status());
  r.shorts_triangles = std::move(shorts_tris->triangles);
  write_obj(ref.model, opt.out / "reference_body.obj");
  write_obj(r.garment, opt.out / "garment_template.obj");
  write_detail(enc, opt.out / "garment_template.atd");
  log.info("encoded the shorts (" + std::to_string(g0.size()) + " vertices, " +
           std::to_string(enc.entries() / std::max<std::size_t>(1, g0.size())) + " p-polygons each) on the mannequin");

  auto made = make_project_templates(ref);
  if (!made) throw Error(made.status());
  r.templates = std::move(*made);
  make_output_dir(opt.out / "templates");
  for (const auto& t : r.templates) {
    write_obj(t.model, opt.out / "templates" / (t.name + ".obj"));
    for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v) r.roi.extend(t.model.nodes.position[v]);
    log.info("profile template '" + t.name + "': " + std::to_string(t.model.num_faces()) + " faces, " +
             std::to_string(t.model.num_surfaces()) + " surfaces, " + std::to_string(t.model.num_joints()) +
             " joints, " + std::to_string(t.profiles.size()) + " profiles");
  }
  for (const auto& g : g0) r.roi.extend(g);
  // The outfit: each profile template regenerated on the reference itself
  // (the topology every body's regeneration has) as a layer, its clearance
  // encoded on the reference skin.
  auto on_ref = regenerate_on_body(r.templates, ref, r.family->reference_positions, r.roi, {}, {.use_grid = false}, ctx);
  if (!on_ref) throw Error(on_ref.status());
  CollisionBody ref_cb;
  if (Status s = ref_cb.build(r.family->collision, r.family->reference_positions, {}, ctx); !s) throw Error(s);
  for (std::size_t k = 0; k < r.templates.size(); ++k) {
    auto layer = ModelLayer::of((*on_ref)[k].model, ref_cb, ctx);
    if (!layer) throw Error(Status(layer.status().code(), r.templates[k].name + ": " + layer.status().message()));
    r.layers.push_back(std::move(*layer));
    r.template_z.push_back(outfit_place(r.templates[k].name));
  }
  r.shorts_z = outfit_place("shorts");
  return r;
}

/// The two library pipelines the demo runs on a body: the garment pipeline
/// for the shorts, and the profile regeneration of the templates with one
/// collider per worker, refitted to each body (systems/profile/regenerate.h).
class Regenerators {
 public:
  Regenerators(const DemoReference& ref, const ExecContext& ctx) : ref_(ref) {
    // The shorts' collision pass is the outfit's first layer (dress).
    GarmentRegenOptions o;
    o.collision_pass = false;
    auto made = GarmentRegenerator::create(ref.family, {ref.shorts}, o, ctx);
    if (!made) throw Error(made.status());
    shorts_ = std::move(*made);
  }
  [[nodiscard]] GarmentRegenerator& shorts() noexcept { return shorts_; }
  /// The profile templates on one body; safe to call from several workers.
  Status profiles(std::span<const Vec3d> body, const ExecContext& c, std::vector<RegenResult>& out) {
    auto r = regenerate_on_body(ref_.templates, *ref_.body, body, ref_.roi, {}, {.use_grid = false}, c, colliders_);
    if (!r) return r.status();
    out = std::move(*r);
    return {};
  }

 private:
  const DemoReference& ref_;
  GarmentRegenerator shorts_;
  ColliderPool colliders_;
};

// ------------------------------------------------------------------ bodies

/// The shorts' fit on one body after the outfit's layering.
struct ShortsFit {
  std::size_t inside = 0, pushed = 0;
  double max_depth = 0, min_clearance = 0, mean_clearance = 0, strain_p95 = 0, clearance_change_rms = 0;
};

/// Dresses one body: the shorts (decoded, edge-transferred) and the profile
/// templates (regenerated) resolved as one outfit (layer_outfit, in
/// kDemoOutfitOrder), in place; the shorts' fit measured after it, the
/// profile templates' penetration and cracks measured again.
Status dress(const DemoReference& ref, std::span<const Vec3d> body, std::vector<Vec3d>& shorts,
             std::vector<RegenResult>& profiles, BodyQuality* q, ShortsFit* fit, const ExecContext& ctx) {
  CollisionBody cb;
  if (Status s = cb.build(ref.family->collision, body, {}, ctx); !s) return s;
  const std::size_t k_n = profiles.size();
  std::vector<OutfitGarment> g(1 + k_n);
  g[0].positions = shorts;
  g[0].adjacency = &ref.shorts->adjacency;
  g[0].clearance = &ref.shorts->clearance;
  g[0].triangles = ref.shorts_triangles;
  g[0].z_depth = ref.shorts_z;
  std::vector<std::vector<Vec3d>> before(k_n);
  for (std::size_t k = 0; k < k_n; ++k) {
    if (Status s = ref.layers[k].positions(profiles[k].model, before[k]); !s) return s;
    g[1 + k].positions = before[k];
    g[1 + k].adjacency = &ref.layers[k].adjacency;
    g[1 + k].clearance = &ref.layers[k].clearance;
    g[1 + k].triangles = ref.layers[k].triangles;
    g[1 + k].z_depth = ref.template_z[k];
  }
  if (Status s = layer_outfit(g, cb, CollisionParams{}, ctx); !s) return s;
  shorts = g[0].positions;
  for (std::size_t k = 0; k < k_n; ++k) {
    ref.layers[k].apply(profiles[k].model, before[k], g[1 + k].positions);
    RegenQuality& rq = profiles[k].quality;
    rq.crack = joint_crack(profiles[k].model);  // the layering moves joint nodes together
    rq.inside = 0;
    rq.min_distance = std::numeric_limits<double>::infinity();
    for (const BodyDistance& d : g[1 + k].distance) {
      rq.inside += d.distance < 0;
      rq.min_distance = std::min(rq.min_distance, d.distance);
    }
  }
  if (q) {
    for (const OutfitGarment& x : g) {
      q->layer_inside_unlayered += x.layer_inside_before;
      q->layer_inside += x.layer_inside;
      q->layer_inside_by[static_cast<std::size_t>(x.z_depth)] += x.layer_inside;
    }
    for (std::size_t k = 0; k < k_n; ++k) q->layer_pushed += g[1 + k].pushed;
  }
  if (fit) {
    *fit = {};
    fit->pushed = g[0].pushed;
    fit->min_clearance = std::numeric_limits<double>::infinity();
    double sum = 0, change2 = 0;
    const std::vector<float>& designed = ref.shorts->clearance.clearance;
    for (std::size_t i = 0; i < g[0].distance.size(); ++i) {
      const BodyDistance& d = g[0].distance[i];
      if (i < designed.size()) change2 += (d.distance - designed[i]) * (d.distance - designed[i]);
      fit->inside += d.distance < 0;
      fit->max_depth = std::max(fit->max_depth, -d.distance);
      fit->min_clearance = std::min(fit->min_clearance, d.distance);
      sum += d.distance;
    }
    fit->mean_clearance = sum / static_cast<double>(std::max<std::size_t>(1, g[0].distance.size()));
    fit->clearance_change_rms = std::sqrt(change2 / static_cast<double>(std::max<std::size_t>(1, designed.size())));
    std::vector<double> strain;
    for (std::size_t e = 0; e < ref.shorts->edges.size(); ++e) {
      const auto [a, b] = ref.shorts->edges[e];
      if (ref.shorts->rest_length[e] > 0)
        strain.push_back(std::abs((shorts[a] - shorts[b]).norm() / ref.shorts->rest_length[e] - 1));
    }
    if (!strain.empty()) {
      auto at = strain.begin() + static_cast<std::ptrdiff_t>(0.95 * static_cast<double>(strain.size() - 1));
      std::nth_element(strain.begin(), at, strain.end());
      fit->strain_p95 = *at;
    }
  }
  return {};
}

struct DemoRun {
  std::vector<BodyFailure> failures;
  std::vector<BodyQuality> quality;  // per completed body, in body order
};

/// The bodies, streamed in chunks (memory is bounded by the chunk size): on
/// each chunk the shorts decoded in batches with the edge transfer, the
/// collision pass and the fit figures, then the profile templates and the
/// quality of each body in parallel over bodies. Writes the first bodies'
/// meshes and measurements.csv.
DemoRun run_bodies(const DemoOptions& opt, const DemoReference& ref, const MannequinSource& src, Regenerators& regen,
                   const ExecContext& ctx, Log& log) {
  DemoRun run;
  BodySet chunk(ref.body);
  std::vector<BodyGarments> fitted;
  std::ostringstream csv;
  const std::size_t nv = ref.shorts->mesh.positions.size();
  log.progress("bodies", 0, src.size());
  for (std::size_t first = 0; first < src.size(); first += opt.chunk) {
    if (ctx.cancelled()) break;
    src.generate(first, opt.chunk, chunk, run.failures, ctx);
    if (Status s = regen.shorts().run(chunk, 0, chunk.size(), fitted, ctx); !s) throw Error(s);
    const double per_body_ms = regen.shorts().last_decode_ms_per_body();
    std::vector<BodyQuality> q(chunk.size());
    std::vector<std::string> errors(chunk.size());
    ExecContext per_body = ctx;
    per_body.sequential_threshold = 2;
    per_body.grain = 1;
    par::for_each_n(per_body, chunk.size(), [&](std::size_t b) {
      const std::vector<Vec3d> body = chunk.positions(b);
      ExecContext inner = ExecContext::sequential();
      inner.cancel = ctx.cancel;
      std::vector<RegenResult> profiles;
      if (Status s = regen.profiles(body, inner, profiles); !s) {
        errors[b] = s.message();
        return;
      }
      if (!fitted[b].status) {
        errors[b] = fitted[b].status.message();
        return;
      }
      BodyQuality& r = q[b];
      ShortsFit fit;
      if (Status s = dress(ref, body, fitted[b].garments[0].positions, profiles, &r, &fit, inner); !s) {
        errors[b] = "outfit: " + s.message();
        return;
      }
      if (first + b < opt.meshes) {
        for (std::size_t k = 0; k < profiles.size(); ++k)
          write_obj(profiles[k].model, opt.out / "meshes" / (chunk.name(b) + "_" + ref.templates[k].name + ".obj"));
      }
      r.name = chunk.name(b);
      r.pushed = fit.pushed;
      r.min_clearance = fit.min_clearance;
      r.mean_clearance = fit.mean_clearance;
      r.inside = fit.inside;
      r.max_depth = fit.max_depth;
      r.strain_p95 = fit.strain_p95;
      r.clearance_change_rms = fit.clearance_change_rms;
      r.decode_ms = per_body_ms;
      for (const auto& x : profiles) r.templates.push_back(x.quality);
    });
    for (std::size_t b = 0; b < chunk.size(); ++b) {
      if (!errors[b].empty()) {
        run.failures.push_back({first + b, chunk.name(b), Status(ErrorCode::kInternal, errors[b])});
        continue;
      }
      run.quality.push_back(q[b]);
      if (run.quality.size() <= opt.meshes) {
        Model body = ref.body->model;
        chunk.positions(b, body.nodes.position);
        write_obj(body, opt.out / "meshes" / (chunk.name(b) + "_body.obj"));
        Model gm = ref.garment;
        // Written in float precision, as the decoded garment is kept.
        const std::vector<Vec3d>& fit = fitted[b].garments[0].positions;
        for (std::size_t v = 0; v < nv; ++v) gm.nodes.position[v] = round_to_float(fit[v]);
        write_obj(gm, opt.out / "meshes" / (chunk.name(b) + "_shorts.obj"));
      }
    }
    Status s = measurements_csv(
        csv, *ref.body, chunk.size(), [&](std::size_t i) { return chunk.positions(i); }, ctx, first == 0, first);
    if (!s) throw Error(s);
    log.progress("bodies", std::min(src.size(), first + opt.chunk), src.size());
  }
  log.end_progress();
  write_atomically(opt.out / "measurements.csv", [&](AtomicFile& f) { f.write(csv.str()); });
  return run;
}

// ------------------------------------------------------------------ report

nlohmann::json by_garment(const BodyQuality& r) {
  nlohmann::json j;
  for (std::size_t k = 0; k < kDemoOutfitOrder.size(); ++k) j[std::string(kDemoOutfitOrder[k])] = r.layer_inside_by[k];
  return j;
}

/// Totals over the completed bodies, for report.json and the summary.
struct DemoTotals {
  std::size_t bodies_with_penetration = 0;
  double worst_depth = 0, strain_sum = 0, change_sum = 0, decode_sum = 0;
  double nq = 1;                                       // completed bodies (at least 1, a divisor)
  nlohmann::json templates = nlohmann::json::array();  // per profile template
  std::size_t template_inside = 0;                     // profile template nodes inside, over all bodies
  double template_crack = 0;                           // largest crack of any profile template
};

/// report.json: the run, the shorts, the summary, the failures, the quality
/// of each body and the per-template totals over all bodies. Returns the
/// report and the totals.
std::pair<nlohmann::json, DemoTotals> write_report(const Common& common, const DemoOptions& opt,
                                                   const DemoReference& ref, const DemoRun& run, double total_s) {
  const std::vector<BodyQuality>& quality = run.quality;
  const DetailEncoding& enc = ref.shorts->encoding;
  const std::size_t nv = ref.shorts->mesh.positions.size();
  DemoTotals tot;
  nlohmann::json rep;
  rep["tool"] = "atelier demo";
  rep["seed"] = common.seed;
  rep["bodies"] = opt.bodies;
  rep["garment"] = {{"name", "shorts"},
                    {"vertices", nv},
                    {"faces", ref.garment.num_faces()},
                    {"p_polygons_per_vertex", enc.entries() / std::max<std::size_t>(1, nv)},
                    {"encoding_bytes", enc.bytes()}};
  nlohmann::json per = nlohmann::json::array();
  for (const auto& r : quality) {
    tot.bodies_with_penetration += r.inside > 0;
    tot.worst_depth = std::max(tot.worst_depth, r.max_depth);
    tot.strain_sum += r.strain_p95;
    tot.change_sum += r.clearance_change_rms;
    tot.decode_sum += r.decode_ms;
    per.push_back({{"body", r.name},
                   {"inside_vertices", r.inside},
                   {"max_depth_m", r.max_depth},
                   {"min_clearance_m", r.min_clearance},
                   {"mean_clearance_m", r.mean_clearance},
                   {"edge_strain_p95", r.strain_p95},
                   {"clearance_change_rms_m", r.clearance_change_rms},
                   {"collision_pushed", r.pushed},
                   {"layer_inside_vertices", r.layer_inside},
                   {"layer_inside_vertices_unlayered", r.layer_inside_unlayered},
                   {"layer_inside_by_garment", by_garment(r)},
                   {"layer_pushed", r.layer_pushed},
                   {"decode_ms", r.decode_ms}});
  }
  std::size_t layered = 0, unlayered = 0;
  for (const auto& r : quality) layered += r.layer_inside, unlayered += r.layer_inside_unlayered;
  nlohmann::json order = nlohmann::json::array();
  for (std::string_view g : kDemoOutfitOrder) order.push_back(std::string(g));
  rep["outfit_order"] = order;  // innermost first
  tot.nq = std::max<double>(1, static_cast<double>(quality.size()));
  rep["summary"] = {{"completed", quality.size()},
                    {"failed", run.failures.size()},
                    {"bodies_with_penetration", tot.bodies_with_penetration},
                    {"worst_penetration_m", tot.worst_depth},
                    {"layer_inside_vertices_total", layered},
                    {"layer_inside_vertices_unlayered_total", unlayered},
                    {"mean_edge_strain_p95", tot.strain_sum / tot.nq},
                    {"mean_clearance_change_rms_m", tot.change_sum / tot.nq},
                    {"mean_decode_ms_per_body", tot.decode_sum / tot.nq},
                    {"encode_s", ref.encode_s},
                    {"total_s", total_s},
                    {"bodies_per_s", static_cast<double>(quality.size()) / total_s}};
  nlohmann::json fails = nlohmann::json::array();
  for (const auto& f : run.failures) fails.push_back({{"body", f.name}, {"reason", f.status.to_string()}});
  rep["failures"] = fails;
  rep["bodies_quality"] = per;
  // Profile templates: per template totals over all bodies.
  for (std::size_t k = 0; k < ref.templates.size(); ++k) {
    std::size_t inside = 0, nodes = 0;
    double crack = 0, prof = 0, clr = 0, ms = 0, u2 = 0, min_d = INFINITY;
    for (const auto& r : quality) {
      if (r.templates.size() <= k) continue;
      const RegenQuality& q = r.templates[k];
      inside += q.inside;
      nodes = q.nodes;
      crack = std::max(crack, q.crack);
      prof = std::max(prof, q.profile_error);
      clr = std::max(clr, q.node_clearance_error);
      u2 = std::max(u2, q.umbrella);
      min_d = std::min(min_d, q.min_distance);
      ms += q.ms;
    }
    tot.template_inside += inside;
    tot.template_crack = std::max(tot.template_crack, crack);
    tot.templates.push_back({{"template", ref.templates[k].name},
                             {"nodes", nodes},
                             {"inside_nodes_total", inside},
                             {"min_distance_m", std::isfinite(min_d) ? min_d : 0.0},
                             {"max_crack_m", crack},
                             {"max_profile_error_m", prof},
                             {"max_node_clearance_error_m", clr},
                             {"max_umbrella", u2},
                             {"mean_ms", ms / tot.nq}});
  }
  rep["profile_templates"] = tot.templates;
  write_atomically(opt.out / "report.json", [&](AtomicFile& f) { f.write(rep.dump(1)); });
  return {std::move(rep), std::move(tot)};
}

/// Front and side pictures of one body (by its index in the source) with
/// the profile templates and the shorts regenerated on it again; nothing
/// when a step fails (a failed shorts fit is logged).
std::optional<RgbImage> picture_of(std::size_t index, const std::string& name, const DemoReference& ref,
                                   const MannequinSource& src, Regenerators& regen, const ExecContext& ctx, Log& log) {
  BodySet one(ref.body);
  std::vector<BodyFailure> f1;
  src.generate(index, 1, one, f1, ctx);
  if (one.size() != 1) return std::nullopt;
  const std::vector<Vec3d> body = one.positions(0);
  std::vector<RegenResult> profiles;
  if (!regen.profiles(body, ctx, profiles)) return std::nullopt;
  std::vector<BodyGarments> one_fit;
  if (Status st = regen.shorts().run(one, 0, 1, one_fit, ctx); !st || !one_fit[0].status) {
    log.warn("picture of " + name + ": " + (st ? one_fit[0].status : st).to_string());
    return std::nullopt;
  }
  std::vector<Vec3d>& shorts_d = one_fit[0].garments[0].positions;
  if (Status st = dress(ref, body, shorts_d, profiles, nullptr, nullptr, ctx); !st) {
    log.warn("picture of " + name + ": outfit: " + st.to_string());
    return std::nullopt;
  }
  auto shorts_tris = fan_triangulate(ref.garment);
  std::vector<SurfaceTriangles> gt;
  for (const auto& r : profiles) gt.push_back(fan_triangulate(r.model).value());
  std::vector<RenderTriangles> scene;
  scene.push_back({body, ref.body_triangles.triangles, body_colour()});
  for (std::size_t k = 0; k < profiles.size(); ++k)
    scene.push_back({profiles[k].model.nodes.position, gt[k].triangles, garment_colour(k)});
  if (shorts_tris) scene.push_back({shorts_d, shorts_tris->triangles, garment_colour(profiles.size())});
  auto both = render_report_views(scene, ctx);
  if (!both) return std::nullopt;
  return std::move(*both);
}

/// Made-to-measure patterns of the profile templates regenerated on one
/// body (systems/pattern/made_to_measure.h: the top's body and collar, the
/// skirt, the trousers' three surfaces) in patterns/<body>/<template>/, with
/// a strain map per piece as the report's pictures. Summary figures go to
/// `summary`; a failing template is logged and left out.
nlohmann::json pattern_pictures(const DemoOptions& opt, const DemoReference& ref, const std::string& name,
                                std::span<const Vec3d> body, Regenerators& regen, const ExecContext& ctx, nlohmann::json& summary, Log& log) {
  nlohmann::json pictures = nlohmann::json::array();
  std::vector<RegenResult> profiles;
  if (!regen.profiles(body, ctx, profiles)) return pictures;
  MadeToMeasureOptions mo;
  mo.files.strain_maps = true;
  mo.files.strain_map_px_per_mm = 0.5;
  std::size_t flipped = 0, pieces = 0;
  double seam_mm = 0;
  for (const RegenResult& r : profiles) {
    const std::size_t k = static_cast<std::size_t>(&r - profiles.data());
    const std::string& tname = ref.templates[k].name;
    const fs::path rel = fs::path("patterns") / name / tname;
    auto rep = write_made_to_measure_pattern(r.model, mo, opt.out / rel, ctx);
    if (!rep) {
      log.warn("patterns of " + tname + " on " + name + ": " + rep.status().to_string());
      continue;
    }
    flipped += rep->flipped;
    pieces += rep->files.flattening.pieces.size();
    seam_mm = std::max(seam_mm, rep->max_seam_difference_mm);
    for (const fs::path& f : rep->files.files) {
      const std::string fn = f.filename().string();
      if (fn.size() < 11 || fn.substr(fn.size() - 11) != "_strain.png") continue;
      const std::string piece = fn.substr(0, fn.size() - 11);
      pictures.push_back({{"title", name + ": " + tname + " pattern, piece " + piece},
                          {"path", (rel / fn).string()},
                          {"caption", "made-to-measure pattern (SVG and DXF beside it): principal stretch, blue "
                                      "compression to red stretch at +-5%, sew line in black"}});
    }
  }
  summary["pattern_pieces"] = pieces;
  summary["pattern_flipped_triangles"] = flipped;
  summary["pattern_max_seam_difference_mm"] = seam_mm;
  return pictures;
}

/// report.html: the summary, a row per body, and pictures of a sample of
/// bodies and of the worst body by each measure (written to pictures/).
void write_html(const DemoOptions& opt, const DemoReference& ref, const MannequinSource& src, Regenerators& regen,
                const DemoRun& run, const nlohmann::json& rep, const DemoTotals& tot, const ExecContext& ctx,
                Log& log) {
  const std::vector<BodyQuality>& quality = run.quality;
  nlohmann::json html;
  html["title"] = "atelier demo: " + std::to_string(quality.size()) + " mannequin bodies";
  html["row_noun"] = "bodies";
  html["summary"] = rep["summary"];
  html["summary"]["profile_template_nodes_inside"] = tot.template_inside;
  html["summary"]["profile_template_max_crack_m"] = tot.template_crack;
  std::vector<std::string> columns = {"body",
                                      "shorts_inside",
                                      "shorts_min_clearance_mm",
                                      "shorts_clearance_change_mm",
                                      "shorts_strain_p95",
                                      "layer_inside_vertices"};
  for (const auto& t : ref.templates)
    for (const char* c : {"_inside", "_min_distance_mm", "_profile_error_mm", "_crack_mm", "_ms"})
      columns.push_back(t.name + c);
  html["columns"] = columns;
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& r : quality) {
    nlohmann::json row = {{"body", r.name},
                          {"shorts_inside", r.inside},
                          {"shorts_min_clearance_mm", 1000 * r.min_clearance},
                          {"shorts_clearance_change_mm", 1000 * r.clearance_change_rms},
                          {"shorts_strain_p95", r.strain_p95},
                          {"layer_inside_vertices", r.layer_inside}};
    for (std::size_t k = 0; k < r.templates.size() && k < ref.templates.size(); ++k) {
      const RegenQuality& q = r.templates[k];
      const std::string& n = ref.templates[k].name;
      row[n + "_inside"] = q.inside;
      row[n + "_min_distance_mm"] = 1000 * q.min_distance;
      row[n + "_profile_error_mm"] = 1000 * q.profile_error;
      row[n + "_crack_mm"] = 1000 * q.crack;
      row[n + "_ms"] = q.ms;
    }
    rows.push_back(row);
  }
  html["rows"] = rows;
  std::vector<std::pair<std::size_t, std::string>> picks;  // (row, why)
  for (std::size_t i = 0; i < std::min<std::size_t>(2, quality.size()); ++i) picks.emplace_back(i, "sample");
  for (const char* c : {"shorts_min_clearance_mm", "top_min_distance_mm", "trousers_min_distance_mm"}) {
    // worst_rows ranks by the largest value: the closest approach is the smallest, so rank its negation.
    std::size_t best = 0;
    for (std::size_t i = 0; i < rows.size(); ++i)
      if (rows[i].contains(c) && rows[i][c].get<double>() < rows[best][c].get<double>()) best = i;
    if (!rows.empty()) picks.emplace_back(best, std::string("lowest ") + describe_figure(c).label);
  }
  // Quality figures only, never a timing (the "_ms" columns): the same run
  // picks the same pictures (issue 27).
  for (const char* c : {"shorts_strain_p95", "top_profile_error_mm"}) {
    auto w = worst_rows(html, c, 1);
    if (!w.empty()) picks.emplace_back(w[0], std::string("highest ") + describe_figure(c).label);
  }
  nlohmann::json pictures = nlohmann::json::array();
  make_output_dir(opt.out / "pictures");
  std::vector<std::size_t> done_rows;
  for (const auto& [row, why] : picks) {
    if (std::find(done_rows.begin(), done_rows.end(), row) != done_rows.end()) continue;
    done_rows.push_back(row);
    // The body's index in the source, from its name's position in the run.
    const std::string& name = quality[row].name;
    std::size_t index = src.size();
    for (std::size_t i = 0; i < src.size(); ++i)
      if (src.body_name(i) == name) {
        index = i;
        break;
      }
    if (index == src.size()) continue;
    const std::optional<RgbImage> picture = picture_of(index, name, ref, src, regen, ctx, log);
    if (!picture) continue;
    const std::string file = "pictures/" + name + ".png";
    write_png(*picture, opt.out / file);
    pictures.push_back({{"title", name + " (" + why + ")"},
                        {"path", file},
                        {"caption", "front and side: body, top with collar, skirt, trousers, shorts"}});
  }
  // The shorts coloured by clearance change and by strain on the body with
  // the highest shorts strain (regen_report.h, shared with `regen --report`).
  if (const auto w = worst_rows(html, "shorts_strain_p95", 1); !w.empty()) {
    BodySet one(ref.body);
    std::vector<BodyFailure> f1;
    for (std::size_t i = 0; i < src.size(); ++i)
      if (src.body_name(i) == quality[w[0]].name) src.generate(i, 1, one, f1, ctx);
    std::vector<BodyGarments> fit;
    if (one.size() == 1 && regen.shorts().run(one, 0, 1, fit, ctx) && fit[0].status) {
      const std::vector<Vec3d> body = one.positions(0);
      const GarmentTemplate& shorts = regen.shorts().garment(0);
      for (auto& p : fit_colour_pictures({.body_name = quality[w[0]].name,
                                          .body = body,
                                          .body_triangles = ref.body_triangles.triangles,
                                          .garments = {&shorts},
                                          .positions = {fit[0].garments[0].positions},
                                          .why = "highest shorts strain"},
                                         opt.out, ctx))
        pictures.push_back(std::move(p));
    }
  }
  // Made-to-measure patterns of the first body.
  if (!quality.empty()) {
    BodySet one(ref.body);
    std::vector<BodyFailure> f1;
    for (std::size_t i = 0; i < src.size(); ++i)
      if (src.body_name(i) == quality[0].name) src.generate(i, 1, one, f1, ctx);
    if (one.size() == 1)
      for (auto& p : pattern_pictures(opt, ref, quality[0].name, one.positions(0), regen, ctx, html["summary"], log))
        pictures.push_back(std::move(p));
  }
  html["pictures"] = pictures;
  HtmlReportOptions ho;
  ho.picture_dir = opt.out;
  write_html_report(html, opt.out / "report.html", ho);
}

void print_summary(const DemoOptions& opt, const DemoReference& ref, const DemoRun& run, const DemoTotals& tot,
                   double total_s) {
  const std::size_t completed = run.quality.size();
  std::printf("atelier demo: %zu bodies regenerated, %zu failed, in %.1f s (%.1f bodies/s)\n", completed,
              run.failures.size(), total_s, static_cast<double>(completed) / total_s);
  std::printf("  shorts: %zu vertices, decode %.3f ms per body, edge strain p95 %.1f%% (mean over bodies)\n",
              ref.shorts->mesh.positions.size(), tot.decode_sum / tot.nq, 100.0 * tot.strain_sum / tot.nq);
  std::printf("  penetration: %zu of %zu bodies have garment vertices inside the body (worst %.1f mm)\n",
              tot.bodies_with_penetration, completed, 1000.0 * tot.worst_depth);
  std::size_t layered = 0, unlayered = 0;
  for (const auto& r : run.quality) layered += r.layer_inside, unlayered += r.layer_inside_unlayered;
  std::printf(
      "  outfit (shorts, trousers, skirt, top, innermost first): %zu garment vertices inside a lower layer over all "
      "bodies (%zu as fitted apart)\n",
      layered, unlayered);
  for (const auto& t : tot.templates)
    std::printf(
        "  %-9s %6zu nodes, %zu nodes inside over all bodies, max crack %.1e m, max profile error %.2f mm, %.1f ms per "
        "body\n",
        t["template"].get<std::string>().c_str(), t["nodes"].get<std::size_t>(),
        t["inside_nodes_total"].get<std::size_t>(), t["max_crack_m"].get<double>(),
        1000 * t["max_profile_error_m"].get<double>(), t["mean_ms"].get<double>());
  std::printf("  report: %s\n", fs::absolute(opt.out / "report.html").string().c_str());
  std::printf("  data:   %s\n", fs::absolute(opt.out / "report.json").string().c_str());
}

}  // namespace

int run_demo(const Common& common, const DemoOptions& opt, Log& log) {
  const auto t_start = std::chrono::steady_clock::now();
  const ExecContext ctx = common.context();
  make_output_dir(opt.out / "meshes");

  // The reference mannequin, the shorts encoded on it, the profile templates.
  const DemoReference ref = set_up(opt, ctx, log);
  Regenerators regen(ref, ctx);

  // Every body: the shorts and the profile templates regenerated, quality.
  const MannequinSource src(ref.topology, opt.bodies, common.seed, ref.body);
  const DemoRun run = run_bodies(opt, ref, src, regen, ctx, log);

  // The reports and the pictures.
  const double total_s = seconds_since(t_start);
  const auto [rep, totals] = write_report(common, opt, ref, run, total_s);
  write_html(opt, ref, src, regen, run, rep, totals, ctx, log);
  remove_stale_output_temporaries(opt.out);  // a killed earlier run's
  print_summary(opt, ref, run, totals, total_s);
  return run.failures.empty() ? kExitOk : kExitPartial;
}

}  // namespace atelier::cli
