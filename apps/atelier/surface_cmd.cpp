#include "surface_cmd.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>

#include <atelier/io/atomic_file.h>
#include <atelier/io/curve_network.h>
#include <atelier/io/obj.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/curvenet/curve_surface.h>

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

bool is_obj(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e == ".obj";
}

nlohmann::json distance_json(const CurveDistance& d) {
  return {{"samples", d.samples}, {"max", d.max}, {"mean", d.mean}, {"rms", d.rms}, {"relative_max", d.relative_max}};
}

}  // namespace

CLI::App* add_surface_subcommand(CLI::App& app, SurfaceOptions& opt) {
  auto* c = app.add_subcommand("surface", "a network of curves to a Catmull-Clark surface through them (seed 003)");
  c->add_option("--curves", opt.curves, "the curves: `CURVE i` text, or OBJ `l` polylines")->required();
  c->add_option("--mesh", opt.mesh, "the mesh the curves were traced on (orients faces, closes open networks)");
  c->add_option("--levels", opt.levels, "Catmull-Clark levels (0 writes the control mesh itself)")
      ->required()
      ->check(CLI::Range(0, 6));
  c->add_option("--out", opt.out, "the subdivided surface (.obj)")->required();
  c->add_option("--control", opt.control, "also write the quad control mesh (.obj)");
  c->add_option("--json", opt.json, "also write the report as JSON");
  c->add_option("--cycles", opt.cycles, "face cycles: angular (default) or paper (the paper's search)")
      ->check(CLI::IsMember({"angular", "paper"}));
  c->add_option("--n0", opt.n0, "control points of the shortest curve piece (eq. 1)")->check(CLI::Range(2, 64));
  c->add_option("--density", opt.density_c, "the constant C of eq. (1); 0 = automatic")->check(CLI::NonNegativeNumber);
  c->add_option("--tolerance", opt.tolerance, "intersection tolerance, relative to the network's size")
      ->check(CLI::NonNegativeNumber);
  c->add_flag("--no-fairing", opt.no_fairing, "keep the eq. (3) positions (no eqs. 4-7)");
  return c;
}

int run_surface(const Common& common, const SurfaceOptions& opt, Log& log) {
  for (const fs::path* p : {&opt.out, &opt.control})
    if (!p->empty() && !is_obj(*p)) {
      log.error("surface: " + p->string() + ": the surface and the control mesh are written as .obj");
      return kExitUsage;
    }
  const PolylineSet curves = read_curve_network(opt.curves);
  Model traced;
  PolygonSoup soup;
  if (!opt.mesh.empty()) {
    traced = read_mesh_file(opt.mesh);
    soup.positions = traced.nodes.position;
    std::vector<NodeIdx> corners;
    std::vector<std::uint32_t> f;
    for (std::uint32_t k = 0; k < traced.faces.slots.capacity(); ++k) {
      if (!traced.alive(FaceIdx{k})) continue;
      traced.face_nodes(FaceIdx{k}, corners);
      f.clear();
      for (NodeIdx v : corners) f.push_back(v.value);
      soup.add_face(f);
    }
    if (soup.face_count() == 0)
      throw Error(Status(ErrorCode::kInvalidArgument, opt.mesh.string() + ": the traced mesh has no faces"));
  }
  CurveSurfaceOptions so;
  so.levels = opt.levels;
  so.cycles = opt.cycles == "paper" ? FaceCycleMethod::kPaperSearch : FaceCycleMethod::kAngular;
  so.control.n0 = opt.n0;
  so.control.C = opt.density_c;
  so.control.fair = !opt.no_fairing;
  so.treatment.intersection_tolerance = opt.tolerance;
  auto r = surface_from_curves(curves, soup, so, common.context());
  if (!r) {
    const std::string where = opt.curves.string() + (opt.mesh.empty() ? "" : " (traced on " + opt.mesh.string() + ")");
    throw Error(Status(r.status().code(), where + ": " + r.status().message()));
  }
  const CurveSurfaceReport& rep = r->report;
  for (const std::string& w : rep.warnings) log.warn(w);
  if (Status s = validate(r->model); !s)
    throw Error(Status(ErrorCode::kInternal, "surface: the result fails validate(): " + s.message()));
  write_obj(r->model, opt.out);
  log.info("wrote " + opt.out.string());
  if (!opt.control.empty()) {
    Model cage;
    auto s = add_polygon_surface(cage, "control_mesh", r->control.mesh);
    if (!s) throw Error(Status(ErrorCode::kInternal, "surface: the control mesh was refused: " + s.status().message()));
    write_obj(cage, opt.control);
    log.info("wrote " + opt.control.string());
  }
  std::printf("%s: %zu curves, %zu intersections, %zu merges, %zu pruned ends; %zu faces (V - E + F = %lld)\n",
              opt.curves.string().c_str(), rep.treatment.input_curves, rep.treatment.intersections,
              rep.treatment.merges, rep.treatment.pruned_segments, rep.faces, static_cast<long long>(rep.euler));
  std::printf("  control mesh: %zu vertices, %zu quads, %zu knots inserted; fairing energy %.6g -> %.6g\n",
              rep.control_vertices, rep.control_quads, rep.knots_inserted, rep.fairing_energy_before,
              rep.fairing_energy_after);
  std::printf(
      "  surface: %zu levels, %zu vertices, %zu quads; distance to the curves max %.4g (%.2e of the size), mean %.4g\n",
      rep.levels.size() - 1, rep.levels.back().vertices, rep.levels.back().faces, rep.to_curves.max,
      rep.to_curves.relative_max, rep.to_curves.mean);
  if (rep.has_traced)
    std::printf("  distance to the traced mesh: max %.4g, mean %.4g\n", rep.to_traced.max, rep.to_traced.mean);
  if (!opt.json.empty()) {
    nlohmann::json by_size = nlohmann::json::object();
    for (const auto& [n, count] : rep.faces_by_size) by_size[std::to_string(n)] = count;
    nlohmann::json levels = nlohmann::json::array();
    for (const auto& l : rep.levels)
      levels.push_back({{"vertices", l.vertices}, {"edges", l.edges}, {"faces", l.faces}});
    const CurveTreatmentReport& t = rep.treatment;
    nlohmann::json j = {
        {"curves_file", opt.curves.string()},
        {"curves",
         {{"input", t.input_curves},
          {"points", t.input_points},
          {"diagonal", t.diagonal},
          {"intersection_tolerance", t.tolerance},
          {"intersections", t.intersections},
          {"max_intersection_gap", t.max_intersection_gap},
          {"splits", t.splits},
          {"joined_ends", t.joined_ends},
          {"merges", t.merges},
          {"kinks", t.kinks},
          {"pruned_ends", t.pruned_segments},
          {"pruned_length", t.pruned_length},
          {"pruned_curve_ids", t.pruned_curve_ids},
          {"boundary_curves_added", rep.boundary_curves}}},
        {"network", {{"nodes", rep.nodes}, {"segments", rep.segments}}},
        {"cycles",
         {{"method", opt.cycles},
          {"faces", rep.faces},
          {"by_size", by_size},
          {"outer", rep.outer_cycles},
          {"euler", rep.euler},
          {"stop_rule_met", rep.stop_rule_met}}},
        {"control_mesh",
         {{"vertices", rep.control_vertices},
          {"network_vertices", rep.network_vertices},
          {"quads", rep.control_quads},
          {"knots_inserted", rep.knots_inserted},
          {"odd_faces", rep.odd_faces},
          {"n0", opt.n0},
          {"C", rep.density_C},
          {"shortest_segment", rep.shortest_segment},
          {"raised_segments", rep.raised_segments},
          {"max_fit_error", rep.max_fit_error},
          {"inverted_quads", rep.inverted_quads}}},
        {"fairing", {{"energy_before", rep.fairing_energy_before}, {"energy_after", rep.fairing_energy_after}}},
        {"subdivision", {{"levels", opt.levels}, {"per_level", levels}}},
        {"distance_to_curves", distance_json(rep.to_curves)},
        {"seconds", rep.seconds},
        {"warnings", rep.warnings}};
    if (rep.has_traced) {
      j["traced_mesh"] = opt.mesh.string();
      j["distance_to_traced"] = distance_json(rep.to_traced);
    }
    write_atomically(opt.json, [&](AtomicFile& f) { f.write(j.dump(1)); });
    log.info("wrote " + opt.json.string());
  }
  if (!rep.stop_rule_met) return kExitPartial;
  return kExitOk;
}

}  // namespace atelier::cli
