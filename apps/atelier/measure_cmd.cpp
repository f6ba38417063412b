#include "measure_cmd.h"

#include <cstdio>
#include <nlohmann/json.hpp>

#include <atelier/io/atomic_file.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/garment/fit_measure.h>
#include <atelier/systems/mesh/fan_triangulation.h>

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

struct Mesh {
  std::vector<Vec3d> points;  // node slots, scaled to metres
  std::vector<Triangle> triangles;
  std::vector<std::array<std::uint32_t, 2>> edges;
};

Mesh load(const fs::path& p, double scale, bool need_faces) {
  const Model m = read_mesh_file(p);
  Mesh out;
  out.points.reserve(m.nodes.position.size());
  for (const Vec3d& x : m.nodes.position) out.points.push_back(scale * x);
  if (need_faces) {
    auto tri = fan_triangulate(m);
    if (!tri) throw Error(Status(ErrorCode::kInvalidArgument, p.string() + ": " + tri.status().message()));
    if (tri->triangles.empty())
      throw Error(Status(ErrorCode::kInvalidArgument, p.string() + ": the body has no faces"));
    out.triangles = std::move(tri->triangles);
  }
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e)
    if (m.alive(EdgeIdx{e})) out.edges.push_back({m.halfedges.tail[2 * e].value, m.halfedges.tail[2 * e + 1].value});
  return out;
}

}  // namespace

CLI::App* add_measure_subcommand(CLI::App& app, MeasureOptions& opt) {
  auto* c = app.add_subcommand("measure", "measure the fit of a garment on a body: penetration, clearance, strain");
  c->add_option("--body", opt.body, "the body (closed mesh: OBJ, PLY, OFF or .atm)")->required();
  c->add_option("--garment", opt.garment, "the garment on that body")->required();
  c->add_option("--source-garment", opt.source_garment, "the garment as designed (same vertices): strain");
  c->add_option("--source-body", opt.source_body,
                "the body it was designed on (same topology as --body): clearance change, excess strain");
  c->add_option("--scale", opt.scale, "file units to metres (0.1 for MakeHuman)")->check(CLI::PositiveNumber);
  c->add_option("--tolerance", opt.tolerance, "depth in metres beyond which a vertex counts as penetrating")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--json", opt.json, "also write the figures as JSON to this file");
  return c;
}

int run_measure(const Common& common, const MeasureOptions& opt, Log& log) {
  if (!opt.source_body.empty() && opt.source_garment.empty())
    throw Error(Status(ErrorCode::kInvalidArgument, "--source-body needs --source-garment (the design on it)"));
  const Mesh body = load(opt.body, opt.scale, true);
  const Mesh garment = load(opt.garment, opt.scale, false);
  Mesh src_garment, src_body;
  if (!opt.source_garment.empty()) src_garment = load(opt.source_garment, opt.scale, false);
  if (!opt.source_body.empty()) src_body = load(opt.source_body, opt.scale, true);
  if (!opt.source_garment.empty() && src_garment.edges != garment.edges)
    throw Error(Status(ErrorCode::kMismatch, opt.source_garment.string() + " and " + opt.garment.string() +
                                                 " do not have the same vertices and edges"));
  if (!opt.source_body.empty() && src_body.triangles != body.triangles)
    throw Error(Status(ErrorCode::kMismatch,
                       opt.source_body.string() + " and " + opt.body.string() + " do not share one topology"));
  FitInput in{body.points, body.triangles, garment.points, garment.edges, src_garment.points, src_body.points};
  auto m = measure_fit(in, {.inside_tolerance = opt.tolerance}, common.context());
  if (!m)
    throw Error(
        Status(m.status().code(), opt.garment.string() + " on " + opt.body.string() + ": " + m.status().message()));

  std::printf("%s on %s: %zu vertices, %zu edges\n", opt.garment.string().c_str(), opt.body.string().c_str(),
              m->vertices, m->edges);
  std::printf("  inside the body:   %zu vertices (%zu deeper than %.1f mm), max depth %.2f mm\n", m->inside,
              m->inside_tolerance, 1e3 * opt.tolerance, 1e3 * m->max_depth);
  std::printf("  clearance:         min %.2f mm, mean %.2f mm, p50 %.2f mm, p95 %.2f mm\n", 1e3 * m->clearance_min,
              1e3 * m->clearance_mean, 1e3 * m->clearance_p50, 1e3 * m->clearance_p95);
  if (m->has_source) std::printf("  edge strain p95:   %.2f %%\n", 100 * m->edge_strain_p95);
  if (m->has_source_body) {
    std::printf("  clearance change:  %.2f mm RMS\n", 1e3 * m->clearance_change_rms);
    std::printf("  excess strain p95: %.2f %%\n", 100 * m->excess_strain_p95);
  }
  if (!opt.json.empty()) {
    nlohmann::json j = {{"body", opt.body.string()},
                        {"garment", opt.garment.string()},
                        {"vertices", m->vertices},
                        {"edges", m->edges},
                        {"inside", m->inside},
                        {"inside_beyond_tolerance", m->inside_tolerance},
                        {"tolerance_m", opt.tolerance},
                        {"max_depth_m", m->max_depth},
                        {"clearance_m",
                         {{"min", m->clearance_min},
                          {"mean", m->clearance_mean},
                          {"p50", m->clearance_p50},
                          {"p95", m->clearance_p95}}}};
    if (m->has_source) j["edge_strain_p95"] = m->edge_strain_p95;
    if (m->has_source_body) {
      j["clearance_change_rms_m"] = m->clearance_change_rms;
      j["excess_edge_strain_p95"] = m->excess_strain_p95;
    }
    write_atomically(opt.json, [&](AtomicFile& f) { f.write(j.dump(1)); });
    log.info("wrote " + opt.json.string());
  }
  if (m->inside_tolerance > 0) {
    log.warn(std::to_string(m->inside_tolerance) + " garment vertices are more than " +
             std::to_string(1e3 * opt.tolerance) + " mm inside the body");
    return kExitPartial;
  }
  return kExitOk;
}

}  // namespace atelier::cli
