// `atelier regen --report` (regen_report.h).
#include "regen_report.h"

#include <atelier/io/png.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/view/colour_map.h>
#include <atelier/systems/view/render.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "commands.h"
#include "html_report.h"

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

/// One row of the HTML table from a body's record: per template the fit
/// figures in mm and %, named with their unit.
nlohmann::json row_of(const nlohmann::json& rec, const RegenReportInput& in) {
  nlohmann::json row = {{"body", rec.value("body", std::string())}};
  if (!rec.value("ok", false)) return row;
  const nlohmann::json& per = rec["templates"];
  for (const auto& d : in.details) {
    if (!per.contains(d->name)) continue;
    const nlohmann::json& q = per[d->name];
    row[d->name + "_inside"] = q.value("inside_nodes", 0);
    row[d->name + "_in_lower_layer"] = q.value("layer_inside_vertices", 0);
    row[d->name + "_min_clearance_mm"] = 1000 * q.value("min_clearance_m", 0.0);
    row[d->name + "_clearance_error_mm"] = 1000 * q.value("clearance_error_m", 0.0);
    row[d->name + "_strain_p95_pct"] = 100 * q.value("strain_p95", 0.0);
  }
  for (const auto& t : in.templates) {
    if (!per.contains(t.name)) continue;
    const nlohmann::json& q = per[t.name];
    row[t.name + "_inside"] = q.value("inside_nodes", 0);
    row[t.name + "_min_distance_mm"] = 1000 * q.value("min_distance_m", 0.0);
    row[t.name + "_crack_mm"] = 1000 * q.value("crack_m", 0.0);
  }
  return row;
}

/// Front and side pictures of body `index` with its whole outfit
/// regenerated again; nothing when a step fails (logged).
struct Pictured {
  std::vector<Vec3d> body;
  std::vector<std::vector<Vec3d>> details;  // the detail garments' positions
};

std::optional<RgbImage> picture_of(std::size_t index, const RegenReportInput& in,
                                   std::optional<GarmentRegenerator>& regen, ColliderPool& colliders,
                                   const ExecContext& ctx, Log& log, Pictured* pictured = nullptr) {
  const auto ref = in.source->reference();
  BodySet one(ref);
  std::vector<BodyFailure> failed;
  in.source->generate(index, 1, one, failed, ctx);
  if (one.size() != 1) return std::nullopt;
  const std::vector<Vec3d> body = one.positions(0);
  const std::string name = one.name(0);
  std::vector<RegenResult> profiles;
  if (!in.templates.empty()) {
    Box3d roi;
    for (const auto& t : in.templates)
      for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v) roi.extend(t.model.nodes.position[v]);
    auto r = regenerate_on_body(in.templates, *ref, body, roi, in.params, {.use_grid = false}, ctx, colliders);
    if (!r) {
      log.warn("picture of " + name + ": " + r.status().to_string());
      return std::nullopt;
    }
    profiles = std::move(*r);
  }
  std::vector<BodyGarments> fit;
  if (regen) {
    if (Status st = regen->run(one, 0, 1, fit, ctx); !st || !fit[0].status) {
      log.warn("picture of " + name + ": " + (st ? fit[0].status : st).to_string());
      return std::nullopt;
    }
  }
  auto body_tris = fan_triangulate(ref->model);
  if (!body_tris) return std::nullopt;
  std::vector<std::vector<Triangle>> tris;  // kept alive for the scene's spans
  std::vector<RenderTriangles> scene;
  scene.push_back({body, body_tris->triangles, body_colour()});
  for (std::size_t k = 0; k < in.details.size(); ++k) tris.push_back(fan_triangulate(in.details[k]->mesh));
  for (const auto& r : profiles) {
    auto t = fan_triangulate(r.model);
    if (t) tris.push_back(std::move(t->triangles));
  }
  std::size_t colour = 0;
  for (std::size_t k = 0; k < in.details.size(); ++k)
    scene.push_back({fit[0].garments[k].positions, tris[k], garment_colour(colour++)});
  for (std::size_t k = 0; k < profiles.size() && in.details.size() + k < tris.size(); ++k)
    scene.push_back({profiles[k].model.nodes.position, tris[in.details.size() + k], garment_colour(colour++)});
  auto both = render_report_views(scene, ctx);
  if (!both) return std::nullopt;
  if (pictured) {
    pictured->body = body;
    pictured->details.clear();
    for (std::size_t k = 0; k < in.details.size(); ++k) pictured->details.push_back(fit[0].garments[k].positions);
  }
  return std::move(*both);
}

}  // namespace

Expected<GarmentVertexFigures> garment_vertex_figures(const BodyBvh& body, const GarmentTemplate& garment,
                                                      std::span<const Vec3d> positions) {
  const std::size_t n = garment.mesh.positions.size();
  if (positions.size() != n || garment.clearance.clearance.size() != n ||
      garment.rest_length.size() != garment.edges.size())
    return Status(ErrorCode::kInvalidArgument, "vertex figures of " + garment.name + ": " +
                                                   std::to_string(positions.size()) + " positions for " +
                                                   std::to_string(n) + " vertices");
  GarmentVertexFigures f;
  f.clearance_change_mm.resize(n);
  f.strain_pct.assign(n, 0.0);
  for (std::size_t v = 0; v < n; ++v)
    f.clearance_change_mm[v] =
        1000.0 * (body.signed_distance(positions[v]).distance - static_cast<double>(garment.clearance.clearance[v]));
  for (std::size_t e = 0; e < garment.edges.size(); ++e) {
    const auto [a, b] = garment.edges[e];
    if (a >= n || b >= n || !(garment.rest_length[e] > 0)) continue;
    const double s = 100.0 * std::abs((positions[a] - positions[b]).norm() / garment.rest_length[e] - 1.0);
    f.strain_pct[a] = std::max(f.strain_pct[a], s);
    f.strain_pct[b] = std::max(f.strain_pct[b], s);
  }
  for (std::size_t v = 0; v < n; ++v)
    if (!std::isfinite(f.clearance_change_mm[v]) || !std::isfinite(f.strain_pct[v]))
      return Status(ErrorCode::kInvalidArgument,
                    "vertex figures of " + garment.name + ": vertex " + std::to_string(v) + " is not finite");
  return f;
}

nlohmann::json fit_colour_pictures(const FitPictureInput& in, const fs::path& out, const ExecContext& ctx) {
  if (in.garments.empty() || in.garments.size() != in.positions.size())
    throw Error(Status(ErrorCode::kInvalidArgument, "fit pictures: one position array per garment"));
  BodyBvh bvh;
  if (Status s = bvh.build(in.body, in.body_triangles, {}, ctx); !s) throw Error(s);
  std::vector<GarmentVertexFigures> figures;
  double change = 0, strain = 0;
  for (std::size_t k = 0; k < in.garments.size(); ++k) {
    auto f = garment_vertex_figures(bvh, *in.garments[k], in.positions[k]);
    if (!f) throw Error(f.status());
    for (double c : f->clearance_change_mm) change = std::max(change, std::abs(c));
    for (double s : f->strain_pct) strain = std::max(strain, s);
    figures.push_back(std::move(*f));
  }
  // A zero range still shows (every vertex at the map's middle or low end).
  if (!(change > 0)) change = 1;
  if (!(strain > 0)) strain = 1;
  std::vector<std::vector<Triangle>> tris;
  for (const GarmentTemplate* g : in.garments) tris.push_back(fan_triangulate(g->mesh));
  nlohmann::json pictures = nlohmann::json::array();
  make_output_dir(out / "pictures");
  std::string names;
  for (const GarmentTemplate* g : in.garments) names += (names.empty() ? "" : ", ") + g->name;
  struct Map {
    const char* file;
    const char* label;
    ColourMap map;
    double lo, hi;
  };
  for (const Map& m : {Map{"clearance_change", "clearance change", ColourMap::kDiverging, -change, change},
                       Map{"strain", "edge strain (largest at the vertex)", ColourMap::kViridis, 0.0, strain}}) {
    std::vector<std::vector<Vec3d>> colours;
    for (const GarmentVertexFigures& f : figures) {
      auto c = map_values(m.map == ColourMap::kDiverging ? f.clearance_change_mm : f.strain_pct, m.lo, m.hi, m.map);
      if (!c) throw Error(c.status());
      colours.push_back(std::move(*c));
    }
    std::vector<RenderTriangles> scene;
    scene.push_back({in.body, in.body_triangles, body_colour()});
    for (std::size_t k = 0; k < in.garments.size(); ++k) {
      RenderTriangles g{in.positions[k], tris[k], garment_colour(k)};
      g.vertex_colours = colours[k];
      g.shading = 0.3;  // mostly the map's colour (read against the bar), a little light for the shape
      scene.push_back(g);
    }
    auto both = render_report_views(scene, ctx);
    if (!both) throw Error(both.status());
    const std::string file = "pictures/" + in.body_name + "_" + m.file + ".png";
    write_png(*both, out / file);
    const std::string unit = m.map == ColourMap::kDiverging ? "mm" : "%";
    pictures.push_back(
        {{"title", in.body_name + ": " + m.label + (in.why.empty() ? "" : " (" + in.why + ")")},
         {"path", file},
         {"caption",
          "front and side: " + names + " coloured by " + m.label + " (" + unit + ")" +
              (m.map == ColourMap::kDiverging ? "; blue: closer to the body than on the reference, red: farther" : "")},
         {"colour_bar",
          {{"map", std::string(colour_map_name(m.map))},
           {"min", m.lo},
           {"max", m.hi},
           {"label", m.label},
           {"unit", unit}}}});
  }
  return pictures;
}

void write_regen_html(const RegenReportInput& in, const ExecContext& ctx, Log& log) {
  std::ifstream f(in.out / "report.json");
  const nlohmann::json rep = nlohmann::json::parse(f, nullptr, false);
  if (rep.is_discarded())
    throw Error(Status(ErrorCode::kParse, (in.out / "report.json").string() + ": not valid JSON"));
  nlohmann::json html;
  const std::size_t n = rep["bodies"].size();
  html["title"] = "atelier regen: " + std::to_string(n) + " bodies";
  html["row_noun"] = "bodies";
  const nlohmann::json& s = rep["summary"];
  // The record's keys: html_report labels them with their units (describe_figure).
  html["summary"] = {{"bodies", s.value("bodies", 0)},
                     {"completed", s.value("completed", 0)},
                     {"failed", s.value("failed", 0)},
                     {"inside_nodes_total", s.value("inside_nodes_total", 0)},
                     {"layer_inside_vertices_total", s.value("layer_inside_vertices_total", 0)},
                     {"max_crack_m", s.value("max_crack_m", 0.0)}};
  nlohmann::json rows = nlohmann::json::array();
  std::vector<std::string> names;  // body names by row
  for (const auto& rec : rep["bodies"]) {
    rows.push_back(row_of(rec, in));
    names.push_back(rec.value("body", std::string()));
  }
  html["rows"] = rows;
  // Which bodies to picture: a sample, then the worst by each figure (quality
  // only, never a timing: the same run pictures the same bodies).
  std::vector<std::pair<std::size_t, std::string>> picks;
  for (std::size_t i = 0; i < std::min(in.samples, rows.size()); ++i) picks.emplace_back(i, "sample");
  auto worst = [&](const std::string& column, bool largest) {
    auto w = worst_rows(html, column, 1, largest);
    if (!w.empty())
      picks.emplace_back(w[0], std::string(largest ? "highest " : "lowest ") + describe_figure(column).label);
  };
  for (const auto& d : in.details) {
    worst(d->name + "_min_clearance_mm", false);
    worst(d->name + "_strain_p95_pct", true);
    worst(d->name + "_in_lower_layer", true);
  }
  for (const auto& t : in.templates) worst(t.name + "_min_distance_mm", false);
  std::optional<GarmentRegenerator> regen;
  if (!in.details.empty()) {
    auto r = GarmentRegenerator::create(
        in.family, std::vector<std::shared_ptr<const GarmentTemplate>>(in.details.begin(), in.details.end()), {}, ctx);
    if (!r) throw Error(r.status());
    regen = std::move(*r);
  }
  ColliderPool colliders;
  nlohmann::json pictures = nlohmann::json::array();
  make_output_dir(in.out / "pictures");
  std::vector<std::size_t> done;
  std::optional<std::size_t> colour_row;  // the body pictured coloured by its fit
  if (!in.details.empty())
    if (const auto w = worst_rows(html, in.details[0]->name + "_strain_p95_pct", 1, true); !w.empty())
      colour_row = w[0];
  Pictured fitted;
  std::string outfit = "body";
  for (const auto& d : in.details) outfit += ", " + d->name;
  for (const auto& t : in.templates) outfit += ", " + t.name;
  for (const auto& [row, why] : picks) {
    if (std::find(done.begin(), done.end(), row) != done.end()) continue;
    done.push_back(row);
    std::size_t index = in.source->size();
    for (std::size_t i = 0; i < in.source->size(); ++i)
      if (in.source->body_name(i) == names[row]) {
        index = i;
        break;
      }
    if (index == in.source->size()) continue;
    const std::optional<RgbImage> picture =
        picture_of(index, in, regen, colliders, ctx, log, colour_row && row == *colour_row ? &fitted : nullptr);
    if (!picture) continue;
    const std::string file = "pictures/" + names[row] + ".png";
    write_png(*picture, in.out / file);
    pictures.push_back(
        {{"title", names[row] + " (" + why + ")"}, {"path", file}, {"caption", "front and side: " + outfit}});
  }
  // The detail garments coloured by clearance change and by strain on the
  // body with the highest strain of the first one (a quality figure: the
  // same run pictures the same body; it is among the picks above).
  if (colour_row && !fitted.body.empty()) {
    const auto body_tris = fan_triangulate(in.source->reference()->model);
    if (!body_tris) throw Error(body_tris.status());
    FitPictureInput fi;
    fi.body_name = names[*colour_row];
    fi.body = fitted.body;
    fi.body_triangles = body_tris->triangles;
    for (std::size_t k = 0; k < in.details.size(); ++k) {
      fi.garments.push_back(in.details[k].get());
      fi.positions.push_back(fitted.details[k]);
    }
    fi.why = "highest " + describe_figure(in.details[0]->name + "_strain_p95_pct").label;
    for (auto& p : fit_colour_pictures(fi, in.out, ctx)) pictures.push_back(std::move(p));
  }
  html["pictures"] = pictures;
  HtmlReportOptions ho;
  ho.picture_dir = in.out;
  write_html_report(html, in.out / "report.html", ho);
}

}  // namespace atelier::cli
