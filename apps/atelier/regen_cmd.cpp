#include "apps/atelier/regen_cmd.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "engine/parallel.h"
#include "io/atomic_file.h"
#include "io/obj.h"
#include "systems/makehuman_body.h"
#include "systems/mannequin.h"
#include "systems/project_templates.h"
#include "systems/regenerate.h"
#include "systems/template_json.h"

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

/// What a template was encoded on: kind and topology size. Regeneration
/// refuses a body set whose reference differs.
std::string reference_tag(const ReferenceBody& b) {
  return std::to_string(b.model.num_nodes()) + " nodes, " + std::to_string(b.model.num_faces()) + " faces";
}

nlohmann::json quality_json(const RegenQuality& q) {
  // No timings: records must be identical for any thread count.
  return {{"nodes", q.nodes},
          {"faces", q.faces},
          {"inside_nodes", q.inside},
          {"max_depth_m", q.max_depth},
          {"min_distance_m", q.min_distance},
          {"node_clearance_error_m", q.node_clearance_error},
          {"profile_error_m", q.profile_error},
          {"umbrella", q.umbrella},
          {"crack_m", q.crack},
          {"pushed", q.pushed}};
}

}  // namespace

CLI::App* add_encode_subcommand(CLI::App& app, EncodeOptions& opt) {
  auto* c = app.add_subcommand("encode", "encode the project's profile templates on a reference body (JSON files)");
  c->add_option("--template", opt.name, "top, skirt, trousers or all")
      ->check(CLI::IsMember({"top", "skirt", "trousers", "all"}));
  c->add_option("--reference", opt.reference, "reference body: mannequin or makehuman")
      ->check(CLI::IsMember({"mannequin", "makehuman"}));
  c->add_option("--data", opt.data, "the shared data folder (for makehuman)");
  c->add_option("--out", opt.out, "output folder");
  return c;
}

int run_encode(const Common& common, const EncodeOptions& opt, Log& log) {
  ReferenceBody ref;
  if (opt.reference == "mannequin") {
    auto r = make_mannequin();
    if (!r) throw Error(r.status());
    ref = std::move(*r);
  } else {
    const auto lib = makehuman::HumanLibrary::load(opt.data / "makehuman", common.context());
    ref = makehuman::make_reference_body(lib);
  }
  fs::create_directories(opt.out);
  int written = 0;
  for (auto [name, make] : {std::pair{"top", &make_top_template}, std::pair{"skirt", &make_skirt_template},
                            std::pair{"trousers", &make_trousers_template}}) {
    if (opt.name != "all" && opt.name != name) continue;
    auto t = make(ref);
    if (!t) throw Error(Status(t.status().code(), std::string(name) + ": " + t.status().message()));
    t->reference = opt.reference + ": " + reference_tag(ref);
    write_template_json(*t, opt.out / (std::string(name) + ".template.json"));
    write_obj(t->model, opt.out / (std::string(name) + ".obj"));
    std::printf("%s: %zu feature nodes, %zu faces, %zu surfaces, %zu joints, %zu profiles -> %s\n", name,
                t->model.num_nodes(), t->model.num_faces(), t->model.num_surfaces(), t->model.num_joints(),
                t->profiles.size(), (opt.out / (std::string(name) + ".template.json")).string().c_str());
    ++written;
  }
  log.info("encoded " + std::to_string(written) + " template(s) on the " + opt.reference + " reference body");
  return kExitOk;
}

CLI::App* add_regen_subcommand(CLI::App& app, RegenOptions& opt) {
  auto* c = app.add_subcommand("regen", "regenerate encoded templates on every body of a body set");
  c->add_option("--template", opt.templates, "template JSON file (repeatable)")->required();
  c->add_option("--source", opt.bodies.source, "mannequin, makehuman, or a directory of OBJ bodies");
  c->add_option("--count", opt.bodies.count, "bodies to sample (mannequin, makehuman)");
  c->add_option("--data", opt.bodies.data, "the shared data folder (for makehuman)");
  c->add_option("--reference", opt.bodies.reference, "reference body OBJ (directory sources)");
  c->add_option("--scale", opt.bodies.scale, "file units to metres (directory sources)");
  c->add_option("--out", opt.out, "output folder");
  c->add_option("--meshes", opt.meshes, "write OBJ meshes of the first N bodies");
  c->add_option("--chunk", opt.chunk, "bodies per chunk (bounds memory)")->check(CLI::PositiveNumber);
  c->add_option("--levels", opt.levels, "refinement levels (default: each template's)");
  c->add_option("--clearance", opt.clearance, "distance kept from the body in metres (default: each template's)");
  c->add_flag("--no-resume", opt.no_resume, "recompute bodies whose outputs already exist");
  return c;
}

int run_regen(const Common& common, const RegenOptions& opt, Log& log) {
  const auto t_start = std::chrono::steady_clock::now();
  const ExecContext ctx = common.context();
  std::vector<ProfileTemplate> templates;
  for (const auto& p : opt.templates) templates.push_back(read_template_json(p));
  const std::unique_ptr<BodySource> src = make_body_source(common, opt.bodies);
  const auto ref = src->reference();
  for (const auto& t : templates) {
    if (t.model.nodes.slots.capacity() != t.encodings.nodes.size())
      throw Error(Status(ErrorCode::kMismatch, t.name + ": encodings do not match the template's nodes"));
    const std::string tag = reference_tag(*ref);
    if (t.reference.find(tag) == std::string::npos)
      throw Error(Status(ErrorCode::kMismatch, "template '" + t.name + "' was encoded on a reference body with " +
                                                   t.reference + "; the body set's reference has " + tag +
                                                   " (encode the template on this reference with `atelier encode`)"));
  }
  const fs::path bodies_dir = opt.out / "bodies";
  fs::create_directories(bodies_dir);
  Box3d roi;
  for (const auto& t : templates)
    for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v) roi.extend(t.model.nodes.position[v]);
  RegenParams rp;
  rp.levels = opt.levels;
  rp.clearance = opt.clearance;

  // Memory: one chunk of bodies (BodySet, float) plus, per worker, one body's
  // collider and one regenerated template at a time.
  BodySet chunk(ref);
  std::vector<BodyFailure> failures;
  std::size_t skipped = 0, done = 0;
  std::vector<double> body_ms;
  const std::size_t n = src->size();
  log.progress("bodies", 0, n);
  for (std::size_t first = 0; first < n; first += opt.chunk) {
    if (ctx.cancelled()) break;
    // Resume: bodies whose record exists are complete.
    std::vector<std::uint8_t> pending(std::min(opt.chunk, n - first), 1);
    bool any = false;
    for (std::size_t i = 0; i < pending.size(); ++i) {
      if (!opt.no_resume && fs::exists(bodies_dir / (src->body_name(first + i) + ".json"))) {
        pending[i] = 0;
        ++skipped;
      }
      any = any || pending[i];
    }
    if (!any) {
      log.progress("bodies", std::min(n, first + opt.chunk), n);
      continue;
    }
    const std::size_t failures_before = failures.size();
    src->generate(first, pending.size(), chunk, failures, ctx);
    for (std::size_t f = failures_before; f < failures.size(); ++f) {  // unreadable bodies: record them too
      nlohmann::json rec = {{"body", failures[f].name}, {"ok", false}, {"reason", failures[f].status.to_string()}};
      write_atomically(bodies_dir / (failures[f].name + ".json"), [&](AtomicFile& file) { file.write(rec.dump(1)); });
    }
    std::vector<std::string> errors(chunk.size());
    std::vector<double> ms(chunk.size(), 0);
    ExecContext per_body = ctx;
    per_body.sequential_threshold = 2;
    per_body.grain = 1;
    par::for_each_n(per_body, chunk.size(), [&](std::size_t b) {
      std::size_t index = first;  // the body's index in the source, by name
      for (std::size_t i = 0; i < pending.size(); ++i)
        if (src->body_name(first + i) == chunk.name(b)) index = first + i;
      if (!pending[index - first]) return;
      const auto t0 = std::chrono::steady_clock::now();
      ExecContext inner = ExecContext::sequential();
      inner.cancel = ctx.cancel;
      const std::vector<Vec3d> body = chunk.positions(b);
      nlohmann::json rec = {{"body", chunk.name(b)}, {"ok", true}};
      try {
        auto regen = regenerate_on_body(templates, *ref, body, roi, rp, {.use_grid = false}, inner);
        if (!regen) throw Error(regen.status());
        nlohmann::json per = nlohmann::json::object();
        for (std::size_t k = 0; k < templates.size(); ++k) {
          const ProfileTemplate& t = templates[k];
          const RegenResult& r = (*regen)[k];
          if (r.quality.inside > 0)
            throw Error(Status(ErrorCode::kDegenerate, t.name + ": " + std::to_string(r.quality.inside) +
                                                           " nodes could not be pushed out of the body"));
          per[t.name] = quality_json(r.quality);
          if (index < opt.meshes) {
            fs::create_directories(bodies_dir / chunk.name(b));
            write_obj(r.model, bodies_dir / chunk.name(b) / (t.name + ".obj"));
          }
        }
        rec["templates"] = per;
      } catch (const Error& e) {
        rec = {{"body", chunk.name(b)}, {"ok", false}, {"reason", e.status().to_string()}};
        errors[b] = e.status().to_string();
      }
      // Written last: its presence means every output of this body is complete.
      write_atomically(bodies_dir / (chunk.name(b) + ".json"), [&](AtomicFile& file) { file.write(rec.dump(1)); });
      ms[b] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    });
    for (std::size_t b = 0; b < chunk.size(); ++b) {
      if (!errors[b].empty()) {
        failures.push_back({first + b, chunk.name(b), Status(ErrorCode::kInternal, errors[b])});
        log.warn(chunk.name(b) + ": " + errors[b]);
      } else if (ms[b] > 0) {
        ++done;
        body_ms.push_back(ms[b]);
      }
    }
    log.progress("bodies", std::min(n, first + opt.chunk), n);
  }
  log.end_progress();

  // Merge the records in body order (the ones from earlier runs included).
  nlohmann::json report;
  report["tool"] = "atelier regen";
  report["seed"] = common.seed;
  report["source"] = opt.bodies.source;
  nlohmann::json names = nlohmann::json::array();
  for (const auto& t : templates) names.push_back(t.name);
  report["templates"] = names;
  nlohmann::json rows = nlohmann::json::array();
  std::size_t ok = 0, failed = 0, inside = 0;
  double crack = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const fs::path rec = bodies_dir / (src->body_name(i) + ".json");
    if (!fs::exists(rec)) continue;  // cancelled before it
    std::ifstream in(rec);
    nlohmann::json r = nlohmann::json::parse(in, nullptr, false);
    if (r.is_discarded()) throw Error(Status(ErrorCode::kParse, rec.string() + ": not valid JSON"));
    if (r.value("ok", false)) {
      ++ok;
      for (auto& [k, q] : r["templates"].items()) {
        inside += q.value("inside_nodes", std::size_t{0});
        crack = std::max(crack, q.value("crack_m", 0.0));
      }
    } else {
      ++failed;
    }
    rows.push_back(std::move(r));
  }
  report["summary"] = {{"bodies", n}, {"completed", ok}, {"failed", failed}, {"inside_nodes_total", inside},
                       {"max_crack_m", crack}};
  report["bodies"] = rows;
  write_atomically(opt.out / "report.json", [&](AtomicFile& f) { f.write(report.dump(1)); });
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  double mean_ms = 0;
  for (double x : body_ms) mean_ms += x;
  mean_ms /= std::max<double>(1, static_cast<double>(body_ms.size()));
  nlohmann::json timing = {{"total_s", total_s}, {"regenerated_now", done}, {"skipped_complete", skipped},
                           {"mean_ms_per_body", mean_ms}, {"threads", common.threads}};
  write_atomically(opt.out / "timing.json", [&](AtomicFile& f) { f.write(timing.dump(1)); });
  std::printf("atelier regen: %zu bodies x %zu templates: %zu complete (%zu now, %zu from an earlier run), %zu failed; "
              "%zu nodes inside, max crack %.1e m; %.1f s\n",
              n, templates.size(), ok, done, skipped, failed, inside, crack, total_s);
  std::printf("  report: %s\n", fs::absolute(opt.out / "report.json").string().c_str());
  return failed == 0 ? kExitOk : kExitPartial;
}

}  // namespace atelier::cli
