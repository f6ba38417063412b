#include "sketch_cmd.h"

#include <atelier/io/atomic_file.h>
#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include <atelier/systems/sketch/sketch.h>

#include <cstdio>
#include <nlohmann/json.hpp>

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

nlohmann::json report_json(const Model& m, const atelier::SketchReport& r, const fs::path& mesh,
                           const fs::path& strokes, const Status& overall) {
  nlohmann::json tools = nlohmann::json::array();
  for (const StrokeReport& t : r.tools) {
    nlohmann::json j = {{"stroke", t.stroke},
                        {"strokes", t.strokes},
                        {"tool", to_string(t.tool)},
                        {"through", t.through},
                        {"ok", t.status.is_ok()}};
    if (!t.name.empty()) j["name"] = t.name;
    if (!t.status) {
      j["error"] = t.status.message();
      tools.push_back(j);
      continue;
    }
    nlohmann::json curves = nlohmann::json::array();
    for (std::size_t c = 0; c < t.curve_lengths.size(); ++c)
      curves.push_back({{"length", t.curve_lengths[c]}, {"closed", static_cast<bool>(t.curve_closed[c])}});
    j["curves"] = curves;
    // The painted curves still in the model, as polylines (painting keeps them).
    if (t.tool == StrokeTool::kPaint || t.tool == StrokeTool::kPaintThrough) {
      nlohmann::json lines = nlohmann::json::array();
      for (const AttribEdge& e : t.curves) {
        if (!m.alive(e)) continue;
        nlohmann::json pts = nlohmann::json::array();
        for (AttribNodeIdx a : m.attrib_edges.nodes.row(e.idx.value)) {
          const Vec3d p = m.attrib_position_on_surface(a);
          pts.push_back({p.x(), p.y(), p.z()});
        }
        lines.push_back({{"surface", m.surfaces.name[m.attrib_edges.surface[e.idx.value].value]}, {"points", pts}});
      }
      j["polylines"] = lines;
    }
    j["faces_added"] = t.faces_added;
    j["nodes_added"] = t.nodes_added;
    j["faces_removed"] = t.faces_removed;
    j["crossings"] = t.crossings;
    nlohmann::json pieces = nlohmann::json::array();
    for (const Piece& p : t.pieces) {
      nlohmann::json pj = {{"faces", p.faces}, {"area", p.area}, {"removed", p.removed}};
      if (!p.removed && m.alive(p.surface)) pj["surface"] = m.surfaces.name[p.surface.idx.value];
      pieces.push_back(pj);
    }
    j["pieces"] = pieces;
    if (t.tool == StrokeTool::kCut) j["removed_area"] = t.removed_area;
    tools.push_back(j);
  }
  nlohmann::json root = {{"mesh", mesh.string()},
                         {"strokes", strokes.string()},
                         {"ok", overall.is_ok()},
                         {"failed", r.failed},
                         {"tools", tools}};
  if (!overall) root["error"] = overall.message();
  root["result"] = {
      {"surfaces", m.num_surfaces()}, {"nodes", m.num_nodes()}, {"faces", m.num_faces()}, {"joints", m.num_joints()}};
  return root;
}

}  // namespace

CLI::App* add_sketch_subcommand(CLI::App& app, SketchOptions& opt) {
  auto* c = app.add_subcommand("sketch", "paint, cut and partition a mesh with the strokes of a stroke file");
  c->add_option("--mesh", opt.mesh, "input mesh: OBJ, PLY, OFF or .atm")->required();
  c->add_option("--strokes", opt.strokes, "stroke file (JSON: camera and strokes, docs/strokes.md)")->required();
  c->add_option("--out", opt.out, "output mesh: OBJ (pieces as groups), PLY, OFF or .atm (keeps painted curves)")
      ->required();
  c->add_option("--json", opt.json, "write what each tool did as JSON (curve lengths, faces added, pieces, areas)");
  c->add_option("--surface", opt.surfaces, "paint only on the surface (OBJ group) of this name; repeatable");
  c->add_flag("--keep-going", opt.keep_going, "skip strokes that fail (exit code 1) instead of stopping");
  return c;
}

int run_sketch(const Common& common, const SketchOptions& opt, Log& log) {
  check_mesh_output(opt.out);
  Model m = read_mesh_file(opt.mesh);
  auto file = read_strokes(opt.strokes);
  if (!file) throw Error(file.status());
  atelier::SketchOptions so;
  so.keep_going = opt.keep_going;
  for (const std::string& name : opt.surfaces) {
    SurfaceIdx found;
    for (std::uint32_t s = 0; s < m.surfaces.slots.capacity(); ++s)
      if (m.alive(SurfaceIdx{s}) && m.surfaces.name[s] == name) found = SurfaceIdx{s};
    if (!found.valid())
      throw Error(Status(ErrorCode::kInvalidArgument, opt.mesh.string() + ": no surface named '" + name + "'"));
    so.surfaces.push_back(found);
  }
  auto r = apply_strokes(m, *file, so, common.context());
  const Status overall = r ? Status{} : r.status();
  const atelier::SketchReport empty;
  if (!opt.json.empty()) {
    const std::string text = report_json(m, r ? *r : empty, opt.mesh, opt.strokes, overall).dump(1) + "\n";
    write_atomically(opt.json, [&](AtomicFile& f) { f.write(text); });
  }
  if (!r) throw Error(Status(r.status().code(), opt.strokes.string() + ": " + r.status().message()));
  for (const StrokeReport& t : r->tools) {
    if (!t.status) {
      log.warn(t.status.message());
      continue;
    }
    double len = 0;
    for (double l : t.curve_lengths) len += l;
    std::printf("stroke %zu %s%s: %zu curve(s), length %.6g", t.stroke, to_string(t.tool),
                t.through && t.tool != StrokeTool::kPaintThrough ? " (through)" : "", t.curve_lengths.size(), len);
    if (t.tool == StrokeTool::kCut || t.tool == StrokeTool::kPartition)
      std::printf(", %zu pieces, %zu faces added, %zu removed", t.pieces.size(), t.faces_added, t.faces_removed);
    std::printf("\n");
  }
  write_mesh_file(m, opt.out, log);
  std::printf("%s: %zu surfaces, %zu faces, %zu joints\n", opt.out.string().c_str(), m.num_surfaces(), m.num_faces(),
              m.num_joints());
  return r->failed ? kExitPartial : kExitOk;
}

}  // namespace atelier::cli
