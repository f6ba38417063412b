#include "net_cmd.h"

#include <atelier/io/atomic_file.h>
#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include <atelier/storage/builder.h>
#include <atelier/systems/net/boolean.h>
#include <atelier/systems/net/round_off.h>
#include <atelier/systems/net/trim.h>

#include <algorithm>
#include <cctype>
#include <nlohmann/json.hpp>

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

template <class T>
T need(Expected<T> e) {
  if (!e) throw Error(e.status());
  return std::move(*e);
}

/// Checks the output's format before any work, then writes atomically.
Model to_model(const PolygonSoup& s, const std::string& name) {
  Model m;
  if (s.face_count() > 0) (void)need(add_polygon_surface(m, name, s));
  return m;
}

void write_json(const fs::path& p, const nlohmann::json& j) {
  write_atomically(p, [&](AtomicFile& f) { f.write(j.dump(2) + "\n"); });
}

/// A net read from a file; errors name the file.
PolygonSoup read_net(const fs::path& p) {
  const Model m = read_mesh_file(p);
  return net_polygons(m);
}

template <class T>
T named(Expected<T> e, const fs::path& a, const fs::path& b) {
  if (e) return std::move(*e);
  std::string msg = e.status().message();
  // "net A ..." / "net B ...": say which file.
  if (msg.rfind("net A", 0) == 0) msg = a.string() + ": " + msg;
  if (msg.rfind("net B", 0) == 0) msg = b.string() + ": " + msg;
  throw Error(Status(e.status().code(), msg));
}

}  // namespace

CLI::App* add_boolean_subcommand(CLI::App& app, NetBooleanOptions& opt) {
  auto* c = app.add_subcommand("boolean", "union, intersection or difference of two closed nets (seed 004)");
  c->add_option("--op", opt.op, "union, intersection, difference (A minus B) or b-a");
  c->add_option("a", opt.a, "net A (OBJ, PLY, OFF or .atm)")->required();
  c->add_option("b", opt.b, "net B; several: A op B op B2 ... (each result used as the next A)")->required();
  c->add_option("--out", opt.out, "result file (.obj, .ply, .off, .atm)")->required();
  c->add_option("--mode", opt.mode, "exact (watertight, default) or paper (merged midpoints, Fig. 2)");
  c->add_option("--correspondence", opt.correspondence, "paper mode: visual, topological, window2 or window4");
  c->add_option("--join", opt.join, "cut (section 3, default) or meshes (connecting meshes, section 4)");
  c->add_option("--rule", opt.rule, "with --join meshes: a, b, c (triangles) or i, ii, iii (quads)");
  c->add_option("--json", opt.json, "report: volumes, areas, intersection polygons, valences");
  c->add_option("--seam-out", opt.seam_out, "write the result's vertex indices on the intersection polygons");
  c->add_flag("--no-self-check", opt.no_self_check, "skip the self-intersection test of the inputs");
  c->add_flag("--exact-refinement", opt.exact_refinement,
              "re-triangulate every cut triangle exactly (no certified double fast path)");
  c->add_flag("--check-result", opt.check_result,
              "exact mode: repair and check the result after rounding; refuse one that crosses itself (the default)");
  c->add_flag("--no-check-result", opt.no_check_result,
              "exact mode: return the rounded result unchecked (it may cross itself on degenerate pairs)");
  return c;
}

int run_boolean(const Common& common, const NetBooleanOptions& opt, Log& log) {
  BooleanOptions o;
  o.op = need(parse_boolean_op(opt.op));
  o.mode = need(parse_boolean_mode(opt.mode));
  o.correspondence = need(parse_correspondence(opt.correspondence));
  o.join = need(parse_boolean_join(opt.join));
  o.rule = need(parse_connect_rule(opt.rule));
  o.check_self_intersection = !opt.no_self_check;
  o.exact_refinement = opt.exact_refinement;
  if (opt.check_result && opt.no_check_result)
    throw Error(Status(ErrorCode::kInvalidArgument, "--check-result and --no-check-result contradict each other"));
  o.check_result = !opt.no_check_result;
  check_mesh_output(opt.out);
  PolygonSoup a = read_net(opt.a);
  std::vector<PolygonSoup> bs;
  for (const fs::path& p : opt.b) bs.push_back(read_net(p));
  const ExecContext ctx = common.context();
  BooleanReport r;
  nlohmann::json steps = nlohmann::json::array();
  if (bs.size() == 1) {
    r = named(net_boolean(a, bs[0], o, ctx), opt.a, opt.b[0]);
  } else {
    // A chain: every net prepared (converted, checked, its hierarchy built)
    // once, each result prepared (with prepare()'s checks) for the next step.
    PrepareOptions pa, pb;
    pa.check_self_intersection = pb.check_self_intersection = o.check_self_intersection;
    pb.name = "B";
    PreparedNet acc = named(PreparedNet::prepare(std::move(a), pa, ctx), opt.a, opt.b[0]);
    for (std::size_t i = 0; i < bs.size(); ++i) {
      const fs::path a_label = i == 0 ? opt.a : fs::path("the result of step " + std::to_string(i));
      const PreparedNet b = named(PreparedNet::prepare(std::move(bs[i]), pb, ctx), a_label, opt.b[i]);
      o.prepare_result = i + 1 < bs.size();
      r = named(net_boolean(acc, b, o, ctx), a_label, opt.b[i]);
      steps.push_back({{"b", opt.b[i].string()},
                       {"volume", r.volume},
                       {"area", r.area},
                       {"intersection_polygons", r.intersection_polygons}});
      if (!o.prepare_result) break;
      if (!r.prepared_status)
        throw Error(Status(r.prepared_status.code(),
                           "the result of step " + std::to_string(i + 1) + " (with " + opt.b[i].string() +
                               ") cannot be the next operand: " + r.prepared_status.message()));
      acc = std::move(r.prepared);
    }
  }
  const Model m = to_model(r.result, "result");
  write_mesh_file(m, opt.out, log);
  if (!opt.seam_out.empty())
    write_atomically(opt.seam_out, [&](AtomicFile& f) {
      std::string s = "# vertices of " + opt.out.filename().string() + " on the intersection polygons (0-based)\n";
      for (std::uint32_t v : r.seam) s += std::to_string(v) + "\n";
      f.write(s);
    });
  if (!opt.json.empty()) {
    nlohmann::json j;
    j["op"] = opt.op;
    j["mode"] = opt.mode;
    j["volume"] = {{"a", r.volume_a}, {"b", r.volume_b}, {"result", r.volume}};
    j["area"] = {{"a", r.area_a}, {"b", r.area_b}, {"result", r.area}};
    j["intersection_polygons"] = r.intersection_polygons;
    j["candidate_pairs"] = r.candidate_pairs;
    j["intersecting_pairs"] = r.intersecting_pairs;
    j["intersection_points"] = r.intersection_points;
    j["cut_triangles"] = r.cut_triangles;
    j["refined_exact"] = r.refined_exact;
    if (!steps.empty()) j["steps"] = steps;  // a chain: volume, area above are the last step's
    j["faces"] = r.result.face_count();
    j["vertices"] = r.result.positions.size();
    if (o.mode == BooleanMode::kPaper) {
      j["correspondence"] = opt.correspondence;
      j["merged_pairs"] = r.merged_pairs;
      j["valence"] = {{"vertices", r.valence.vertices},
                      {"irregular", r.valence.irregular},
                      {"min", r.valence.min},
                      {"max", r.valence.max},
                      {"mean", r.valence.mean}};
    }
    if (o.join == BooleanJoin::kMeshes) {
      j["join"] = opt.join;
      j["rule"] = opt.rule;
      j["connecting"] = {{"triangles", r.connecting.triangles},
                         {"quads", r.connecting.quads},
                         {"other", r.connecting.other},
                         {"irregular_vertices", r.connecting.irregular_vertices}};
    }
    write_json(opt.json, j);
  }
  log.info("wrote " + opt.out.string() + " (volume " + std::to_string(r.volume) + ", " +
           std::to_string(r.intersection_polygons) + " intersection polygons)");
  return kExitOk;
}

CLI::App* add_trim_subcommand(CLI::App& app, NetTrimOptions& opt) {
  auto* c = app.add_subcommand("trim", "trim a net by a closed curve on it (seed 004 section 6)");
  c->add_option("--mesh", opt.mesh, "the net (OBJ, PLY, OFF or .atm; open or closed)")->required();
  c->add_option("--curve", opt.curve, "the curve: one 'x y z' point per line, closed")->required();
  c->add_option("--out", opt.out, "the trimmed net")->required();
  c->add_option("--height", opt.height, "half height of the extruded band (0: twice the mean edge)")
      ->check(CLI::NonNegativeNumber);
  c->add_flag("--keep-enclosed", opt.keep_enclosed, "keep the part the curve encloses instead");
  c->add_option("--band-out", opt.band_out, "also write the extruded band");
  c->add_option("--json", opt.json, "report: areas, cut points, parts");
  return c;
}

int run_trim(const Common& common, const NetTrimOptions& opt, Log& log) {
  check_mesh_output(opt.out);
  if (!opt.band_out.empty()) check_mesh_output(opt.band_out);
  const PolygonSoup net = read_net(opt.mesh);
  const std::vector<Vec3d> curve = read_curve(opt.curve);
  TrimOptions o;
  o.height = opt.height;
  o.keep_enclosed = opt.keep_enclosed;
  auto r = trim_net(net, curve, o, common.context());
  if (!r)
    throw Error(Status(r.status().code(), opt.mesh.string() + ", " + opt.curve.string() + ": " + r.status().message()));
  write_mesh_file(to_model(r->result, "trimmed"), opt.out, log);
  if (!opt.band_out.empty()) write_mesh_file(to_model(r->band, "band"), opt.band_out, log);
  if (!opt.json.empty())
    write_json(opt.json, {{"area", {{"before", r->area_before}, {"after", r->area_after}}},
                          {"cut_points", r->cut_points},
                          {"parts", r->parts}});
  log.info("wrote " + opt.out.string() + " (area " + std::to_string(r->area_before) + " -> " +
           std::to_string(r->area_after) + ")");
  return kExitOk;
}

CLI::App* add_round_subcommand(CLI::App& app, NetRoundOptions& opt) {
  auto* c = app.add_subcommand("round", "round off a seam by the umbrella energy (seed 004 section 6)");
  c->add_option("--mesh", opt.mesh, "the net")->required();
  c->add_option("--seam", opt.seam, "vertex indices of the seam (0-based; as written by boolean --seam-out)")
      ->required();
  c->add_option("--out", opt.out, "the rounded net")->required();
  c->add_option("--mu", opt.mu, "weight of curvature")->check(CLI::NonNegativeNumber);
  c->add_option("--nu", opt.nu, "weight of torsion")->check(CLI::NonNegativeNumber);
  c->add_option("--rings", opt.rings, "free the vertices within this many edges of the seam")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--json", opt.json, "report: energies, freed vertices");
  return c;
}

int run_round(const Common& common, const NetRoundOptions& opt, Log& log) {
  check_mesh_output(opt.out);
  Model m = read_mesh_file(opt.mesh);
  const std::vector<std::uint32_t> seam_ids = read_seam(opt.seam);
  // Seam indices are file vertex indices: map through the reader's source_vertex.
  const auto source = m.nodes.props.find<std::int32_t>("source_vertex");
  std::vector<NodeIdx> seam;
  for (std::uint32_t id : seam_ids) {
    NodeIdx found;
    for (std::uint32_t v = 0; v < m.nodes.slots.capacity() && !found.valid(); ++v)
      if (m.alive(NodeIdx{v}) && (source.valid() ? source[NodeIdx{v}] == static_cast<std::int32_t>(id) : v == id))
        found = NodeIdx{v};
    if (!found.valid())
      throw Error(Status(ErrorCode::kInvalidArgument, opt.seam.string() + ": vertex " + std::to_string(id) +
                                                          " is not a vertex of " + opt.mesh.string()));
    seam.push_back(found);
  }
  RoundOptions o;
  o.mu = opt.mu;
  o.nu = opt.nu;
  o.rings = opt.rings;
  const RoundReport r = need(round_off(m, seam, o, common.context()));
  write_mesh_file(m, opt.out, log);
  if (!opt.json.empty())
    write_json(opt.json, {{"energy", {{"before", r.energy_before}, {"after", r.energy_after}}},
                          {"free_vertices", r.free_nodes},
                          {"terms", r.terms},
                          {"moved", r.moved}});
  log.info("wrote " + opt.out.string() + " (E " + std::to_string(r.energy_before) + " -> " +
           std::to_string(r.energy_after) + ")");
  return kExitOk;
}

}  // namespace atelier::cli
