#include "flatten_cmd.h"

#include <atelier/io/atomic_file.h>
#include <atelier/systems/pattern/pattern_files.h>

#include <cstdio>
#include <nlohmann/json.hpp>

namespace atelier::cli {

namespace {

SurfaceIdx surface_named(const Model& m, const std::string& name, const std::filesystem::path& file) {
  for (std::uint32_t s = 0; s < m.surfaces.slots.capacity(); ++s)
    if (m.alive(SurfaceIdx{s}) && m.surfaces.name[s] == name) return SurfaceIdx{s};
  throw Error(Status(ErrorCode::kInvalidArgument, file.string() + ": no surface named '" + name + "'"));
}

nlohmann::json piece_json(const PieceFlattening& p, const PatternSet& set) {
  const auto& d = p.distortion;
  nlohmann::json j = {
      {"name", p.name},
      {"surface", p.surface.value},
      {"nodes", p.nodes},
      {"triangles", p.triangles},
      {"boundary_loops", p.boundary_loops},
      {"distortion",
       {{"area_error", d.area_error},
        {"length_error", d.length_error},
        {"max_edge_strain", d.max_edge_strain},
        {"min_stretch", d.min_stretch},
        {"max_stretch", d.max_stretch},
        {"flipped", d.flipped},
        {"boundary_crossings", d.boundary_crossings}}},
      {"solver",
       {{"energy_phase1", p.energy_phase1},
        {"energy", p.energy},
        {"closures", p.closures},
        {"iterations", p.iterations},
        {"rejected_steps", p.rejected_steps},
        {"tutte_fallback", p.tutte_fallback},
        {"ms", {{"phase1", p.phase1_ms}, {"factor", p.factor_ms}, {"phase2", p.phase2_ms}, {"total", p.total_ms}}}}}};
  for (const PatternPiece& pc : set.pieces)
    if (pc.surface == p.surface && !pc.mirrored) {
      j["area_mm2"] = pc.area_mm2;
      j["notches"] = pc.notches.size();
    }
  return j;
}

}  // namespace

CLI::App* add_flatten_subcommand(CLI::App& app, FlattenCmdOptions& opt) {
  auto* c = app.add_subcommand("flatten", "flatten a model's pieces into 2D patterns (SVG, DXF, strain maps)");
  c->add_option("--mesh", opt.mesh, "the model (OBJ groups, PLY, OFF or .atm); one piece per surface")->required();
  c->add_option("--out", opt.out, "output folder")->required();
  c->add_option("--seam-allowance", opt.seam_allowance_mm, "seam allowance in mm")->check(CLI::NonNegativeNumber);
  c->add_option("--hem-allowance", opt.hem_allowance_mm, "allowance off seams in mm (default: the seam allowance)")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--notch-spacing", opt.notch_spacing_mm, "notches every this many mm along seams (0: ends and marks)")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--scale", opt.scale, "file units to metres (0.001 for a model in mm)")->check(CLI::PositiveNumber);
  c->add_option("--surface", opt.surfaces, "flatten only this surface (repeatable)");
  c->add_option("--mirror", opt.mirror, "also write this piece mirrored, for a left/right pair (repeatable)");
  c->add_option("--grain", opt.grain, "3D grain direction x y z (default: each pattern's principal axis)")->expected(3);
  c->add_flag("--dxf", opt.dxf, "also write pattern.dxf (ASTM D6673 / AAMA layers)");
  c->add_flag("--allow-holes", opt.allow_holes, "accept pieces with interior holes (more than one boundary loop)");
  c->add_flag("--no-strain-maps", opt.no_strain_maps, "do not write the strain-map PNGs");
  c->add_flag("--free-seams", opt.free_seams,
              "flatten each piece on its own: sewn edges are not held to their 3D length (mismatches are reported)");
  c->add_option("--json", opt.json, "also write the distortion per piece and the seam checks as JSON");
  return c;
}

int run_flatten(const Common& common, const FlattenCmdOptions& opt, Log& log) {
  Model m = read_mesh_file(opt.mesh);
  PatternFileOptions po;
  po.dxf = opt.dxf;
  po.strain_maps = !opt.no_strain_maps;
  po.flatten.allow_holes = opt.allow_holes;
  po.flatten.seam_lengths = !opt.free_seams;
  if (opt.grain.size() == 3) po.flatten.grain = Vec3d(opt.grain[0], opt.grain[1], opt.grain[2]);
  for (const std::string& s : opt.surfaces) po.flatten.surfaces.push_back(surface_named(m, s, opt.mesh));
  for (const std::string& s : opt.mirror) po.pattern.mirror.push_back(surface_named(m, s, opt.mesh));
  po.pattern.units_to_mm = 1000 * opt.scale;
  po.pattern.seam_allowance_mm = opt.seam_allowance_mm;
  po.pattern.hem_allowance_mm = opt.hem_allowance_mm;
  po.pattern.notch_spacing_mm = opt.notch_spacing_mm;
  auto rep = write_pattern_files(m, po, opt.out, common.context());
  if (!rep) throw Error(Status(rep.status().code(), opt.mesh.string() + ": " + rep.status().message()));

  bool partial = false;
  for (const PieceFlattening& p : rep->flattening.pieces) {
    const auto& d = p.distortion;
    std::printf("%-20s %7zu nodes  E_L %.5f  E_A %.5f  max strain %.4f  stretch [%.4f, %.4f]  flipped %zu%s\n",
                p.name.c_str(), p.nodes, d.length_error, d.area_error, d.max_edge_strain, d.min_stretch, d.max_stretch,
                d.flipped, d.boundary_crossings ? "  BOUNDARY CROSSES ITSELF" : "");
    if (d.flipped || d.boundary_crossings) {
      log.warn(p.name + ": " + std::to_string(d.flipped) + " flipped triangles, " +
               std::to_string(d.boundary_crossings) + " boundary crossings");
      partial = true;
    }
  }
  for (const SeamCheck& c : rep->pattern.seams) {
    std::string who;
    for (const SeamMemberLength& ml : c.members)
      who += (who.empty() ? "" : " / ") + m.surfaces.name[ml.surface.value] + " " +
             std::to_string(ml.length_2d_mm).substr(0, 7) + " mm";
    std::printf("seam %-4u %s: %s (3D %.1f mm, partners differ by %.2f mm, %.3f%% off 3D)\n", c.joint.value,
                c.ok ? "ok     " : "MISMATCH", who.c_str(), c.members[0].length_3d_mm, c.max_difference_mm,
                100 * c.max_deviation_3d);
    if (!c.ok) partial = true;
  }
  for (const auto& f : rep->files) log.info("wrote " + f.string());
  if (!opt.json.empty()) {
    nlohmann::json j = {{"mesh", opt.mesh.string()}, {"out", opt.out.string()}};
    j["pieces"] = nlohmann::json::array();
    for (const PieceFlattening& p : rep->flattening.pieces) j["pieces"].push_back(piece_json(p, rep->pattern));
    j["seams"] = nlohmann::json::array();
    for (const SeamCheck& c : rep->pattern.seams) {
      nlohmann::json s = {{"joint", c.joint.value},
                          {"ok", c.ok},
                          {"max_difference_mm", c.max_difference_mm},
                          {"max_deviation_3d", c.max_deviation_3d}};
      for (const SeamMemberLength& ml : c.members)
        s["members"].push_back({{"surface", m.surfaces.name[ml.surface.value]},
                                {"boundary", ml.boundary},
                                {"length_2d_mm", ml.length_2d_mm},
                                {"length_3d_mm", ml.length_3d_mm}});
      j["seams"].push_back(s);
    }
    j["files"] = nlohmann::json::array();
    for (const auto& f : rep->files) j["files"].push_back(f.string());
    write_atomically(opt.json, [&](AtomicFile& f) { f.write(j.dump(1)); });
    log.info("wrote " + opt.json.string());
  }
  return partial ? kExitPartial : kExitOk;
}

}  // namespace atelier::cli
