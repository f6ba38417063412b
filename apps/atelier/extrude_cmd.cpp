#include "extrude_cmd.h"

#include <atelier/io/atomic_file.h>
#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/sketch/extrude_recipe.h>
#include <atelier/systems/spatial/collision_body.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace atelier::cli {

namespace {

nlohmann::json stats_json(const EdgeLengthStats& s) {
  return {{"edges", s.edges}, {"mean", s.mean},     {"min", s.min},
          {"max", s.max},     {"within", s.within}, {"outside", s.outside}};
}

nlohmann::json report_json(const ExtrudeCmdOptions& opt, const ExtrudeReport* r, const Status& st) {
  nlohmann::json j = {{"mesh", opt.mesh.string()}, {"strokes", opt.strokes.string()}, {"ok", st.is_ok()}};
  if (!st) {
    j["error"] = st.message();
    return j;
  }
  auto v3 = [](const Vec3d& p) { return nlohmann::json::array({p.x(), p.y(), p.z()}); };
  j["base_ring"] = r->base_ring;
  j["capped"] = r->capped;
  j["base_nodes"] = r->base.size();
  j["base_mean_edge"] = r->base_mean_edge;
  j["base_normal"] = v3(r->base_normal);
  j["plane_normal"] = v3(r->plane_normal);
  j["p1"] = v3(r->p1);
  j["p2"] = v3(r->p2);
  j["copies"] = r->copies;
  j["scales"] = r->scales;
  j["faces_removed"] = r->faces_removed;
  j["swept_nodes"] = r->swept_nodes;
  j["swept_faces"] = r->swept_faces;
  j["splits"] = r->splits;
  j["collapses"] = r->collapses;
  j["swaps"] = r->swaps;
  j["before"] = stats_json(r->before);
  j["after"] = stats_json(r->after);
  j["nodes_added"] = r->nodes_added;
  j["faces_added"] = r->faces_added;
  j["volume_change"] = r->volume_change;
  j["max_deviation"] = r->max_deviation;
  if (!opt.body.empty()) {
    j["pushed"] = r->pushed;
    j["inside_after"] = r->inside_after;
    j["min_body_distance"] = r->min_body_distance;
  }
  if (r->mirrored) {
    j["mirrored"] = true;
    j["mirror_base_nodes"] = r->mirror_base.size();
    j["mirror_base_error"] = r->mirror_base_error;
    j["mirror_nodes"] = r->mirror_nodes;
    j["mirror_faces"] = r->mirror_faces;
    if (opt.as_surface) j["mirror_part_surface"] = r->mirror_part_surface.value;
  }
  if (opt.as_surface) {
    j["part_surface"] = r->part_surface.value;
    j["joints"] = r->joints.size();
  }
  return j;
}

/// "px,py,pz,nx,ny,nz": six finite numbers, the normal non-zero.
bool parse_plane(const std::string& text, std::vector<double>& v) {
  v.clear();
  std::stringstream ss(text);
  for (std::string tok; std::getline(ss, tok, ',');) {
    char* end = nullptr;
    const double d = std::strtod(tok.c_str(), &end);
    if (tok.empty() || *end != '\0' || !std::isfinite(d)) return false;
    v.push_back(d);
  }
  return v.size() == 6 && (v[3] != 0 || v[4] != 0 || v[5] != 0);
}

}  // namespace

CLI::App* add_extrude_subcommand(CLI::App& app, ExtrudeCmdOptions& opt) {
  auto* c = app.add_subcommand("extrude", "extrude a surface or a cavity from a mesh by sketched strokes (seed 002)");
  c->add_option("--mesh", opt.mesh, "input mesh: OBJ, PLY, OFF or .atm")->required();
  auto* input = c->add_option_group("input", "the strokes or a recipe (exactly one)");
  input->add_option("--strokes", opt.strokes, "stroke file with a run of extrude strokes (docs/strokes.md)");
  input->add_option("--replay", opt.replay, "extrusion recipe (from --recipe-out) to replay instead of strokes");
  input->require_option(1);
  c->add_option("--recipe-out", opt.recipe_out, "write the extrusion's recipe (JSON) for --replay on other meshes");
  c->add_option("--out", opt.out, "output mesh: OBJ, PLY, OFF or .atm")->required();
  c->add_option("--json", opt.json, "write the extrusion report as JSON");
  c->add_option("--first", opt.first, "index of the base stroke of the extrusion (default 0)");
  c->add_option("--pick-radius", opt.pick_radius, "pixels within which strokes must start near the base curve")
      ->check(CLI::PositiveNumber);
  c->add_flag("--no-optimise", opt.no_optimise, "skip the mesh optimisation of the new region");
  c->add_flag("--as-surface", opt.as_surface, "make the extruded part its own surface joined along B (write .atm)");
  c->add_option("--body", opt.body, "closed body mesh (OBJ, PLY, OFF or .atm) the extruded part is kept outside of");
  c->add_option("--clearance", opt.clearance, "with --body: distance kept from the body (model units)")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--body-smoothing", opt.body_smoothing,
                "with --body: umbrella steps on the pushed nodes before the optimisation (default 8; 0: off)")
      ->check(CLI::Range(0, 100));
  c->add_option("--settle-rounds", opt.settle_rounds,
                "with --body: rounds re-optimising around edges out of bounds after the last push (default 8; 0: off)")
      ->check(CLI::Range(0, 100));
  auto* mx = c->add_option("--mirror", opt.mirror,
                           "also extrude the mirror image across the plane through the origin normal to this axis "
                           "(x: the body's sagittal plane)")
                 ->check(CLI::IsMember({"x", "y", "z"}));
  c->add_option("--mirror-plane", opt.mirror_plane, "also extrude the mirror image across the plane px,py,pz,nx,ny,nz")
      ->excludes(mx)
      ->check(CLI::Validator(
          [](std::string& s) {
            std::vector<double> v;
            return parse_plane(s, v) ? std::string() : "needs six finite numbers px,py,pz,nx,ny,nz (normal non-zero)";
          },
          "PX,PY,PZ,NX,NY,NZ"));
  return c;
}

int run_extrude(const Common& common, const ExtrudeCmdOptions& opt, Log& log) {
  check_mesh_output(opt.out);
  Model m = read_mesh_file(opt.mesh);
  Expected<ExtrudeStrokes> in = Status(ErrorCode::kInvalidArgument, "no strokes");
  Expected<ExtrusionRecipe> recipe = Status(ErrorCode::kInvalidArgument, "no recipe");
  if (!opt.strokes.empty()) {
    auto file = read_strokes(opt.strokes);
    if (!file) throw Error(file.status());
    in = extrusion_from_file(*file, opt.first);
  } else {
    std::ifstream f(opt.replay, std::ios::binary);
    if (!f) throw Error(Status(ErrorCode::kInvalidArgument, opt.replay.string() + ": cannot be read"));
    const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    recipe = parse_extrusion_recipe(text, opt.replay.string());
    if (!recipe) throw Error(recipe.status());
  }
  ExtrudeOptions eo;
  eo.pick_radius = opt.pick_radius;
  eo.optimise = !opt.no_optimise;
  eo.as_surface = opt.as_surface;
  eo.clearance = opt.clearance;
  eo.body_smoothing = opt.body_smoothing;
  eo.settle_rounds = opt.settle_rounds;
  if (!opt.mirror.empty()) {
    SymmetryPlane p;
    p.normal = Vec3d::Unit(opt.mirror == "x" ? 0 : opt.mirror == "y" ? 1 : 2);
    eo.mirror = p;
  }
  if (!opt.mirror_plane.empty()) {
    std::vector<double> v;
    (void)parse_plane(opt.mirror_plane, v);  // checked when parsing (exit 2)
    eo.mirror = SymmetryPlane{Vec3d(v[0], v[1], v[2]), Vec3d(v[3], v[4], v[5])};
  }
  // The body: its triangles as a collision body (the garment family's query).
  Model body_model;
  CollisionBody body;
  if (!opt.body.empty()) {
    body_model = read_mesh_file(opt.body);
    if (Status s = collision_body_of(body_model, body); !s)
      throw Error(Status(ErrorCode::kInvalidArgument, opt.body.string() + ": " + s.message()));
    eo.body = &body;
  }
  Expected<ExtrudeReport> r = !opt.replay.empty() ? replay_extrusion(m, *recipe, eo, common.context())
                              : in                 ? extrude(m, *in, eo, common.context())
                                                   : Expected<ExtrudeReport>(in.status());
  Expected<ExtrusionRecipe> out_recipe = ExtrusionRecipe{};
  if (r && !opt.recipe_out.empty()) out_recipe = extrusion_recipe(m, *r);
  const Status st = r ? Status{} : r.status();
  if (!opt.json.empty()) {
    const std::string text = report_json(opt, r ? &*r : nullptr, st).dump(1) + "\n";
    write_atomically(opt.json, [&](AtomicFile& f) { f.write(text); });
  }
  const std::string source = (opt.replay.empty() ? opt.strokes : opt.replay).string();
  if (!r) throw Error(Status(st.code(), source + ": " + st.message()));
  if (!out_recipe) throw Error(Status(out_recipe.status().code(), source + ": " + out_recipe.status().message()));
  std::printf(
      "extrude: %zu copies of a %s of %zu nodes, %zu nodes and %zu faces added (%zu splits, %zu collapses, "
      "%zu swaps), volume change %.6g\n",
      r->copies, r->base_ring ? "ring" : "chain", r->base.size(), r->nodes_added, r->faces_added, r->splits,
      r->collapses, r->swaps, r->volume_change);
  write_mesh_file(m, opt.out, log);
  if (!opt.recipe_out.empty()) {
    const std::string text = extrusion_recipe_json(*out_recipe);
    write_atomically(opt.recipe_out, [&](AtomicFile& f) { f.write(text); });
  }
  if (eo.body && r->inside_after > 0) {
    std::printf("extrude: %zu new nodes are still inside the body %s (deepest %.6g)\n", r->inside_after,
                opt.body.string().c_str(), -r->min_body_distance);
    return kExitPartial;
  }
  return kExitOk;
}

}  // namespace atelier::cli
