// `atelier encode` and `atelier regen` (regen_cmd.h).
//
// Why this file is long: the two subcommands share the reference tags and
// quality records that tie a template to the body set it regenerates on;
// `regen` itself is one rank's set-up, its share of bodies, the streamed
// merge of the records and the MPI verdict, each short.
#include "regen_cmd.h"

#include <atelier/engine/parallel.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/makehuman/makehuman.h>
#include <atelier/io/obj.h>
#include <atelier/systems/body/body_file.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/makehuman_binding.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/pattern/made_to_measure_templates.h>
#include <atelier/systems/profile/project_templates.h>
#include <atelier/systems/profile/regenerate.h>
#include <atelier/systems/profile/template_json.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>

#include "mpi_split.h"
#include "regen_job.h"
#include "regen_report.h"

namespace atelier::cli {

namespace fs = std::filesystem;

namespace {

/// What a template was encoded on: kind and topology size. Regeneration
/// refuses a body set whose reference differs.
std::string reference_tag(const ReferenceBody& b) {
  return std::to_string(b.model.num_nodes()) + " nodes, " + std::to_string(b.model.num_faces()) + " faces";
}

/// Feature curves from a file (--features): a template encoded on them
/// names their feature points by id, so it must be regenerated on the same
/// curves. A digest (FNV-1a) of the curve and point tables: names, ids and
/// locations on the skin.
std::string features_tag(const ReferenceBody& b) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](const void* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ull;
  };
  const Model& m = b.model;
  auto node = [&](AttribNodeIdx a) {
    mix(&m.attrib_nodes.kind[a.value], sizeof m.attrib_nodes.kind[a.value]);
    mix(&m.attrib_nodes.element[a.value], sizeof m.attrib_nodes.element[a.value]);
    mix(m.attrib_nodes.param[a.value].data(), 3 * sizeof(double));
  };
  for (const FeatureCurve& c : b.curves) {
    mix(&c.id, sizeof c.id);
    mix(c.name.data(), c.name.size());
    for (AttribNodeIdx a : m.attrib_edges.nodes.row(c.edge.value)) node(a);
  }
  for (const FeaturePoint& p : b.points) {
    mix(&p.id, sizeof p.id);
    mix(p.name.data(), p.name.size());
    node(p.node);
  }
  char buf[40];
  std::snprintf(buf, sizeof buf, ", feature curves %016llx", static_cast<unsigned long long>(h));
  return buf;
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
  auto* c = app.add_subcommand("encode",
                               "encode the project's profile templates (JSON files) or a garment mesh (--garment, a "
                               "detail template .atd) on a reference body");
  c->add_option("--template", opt.name, "top, skirt, trousers or all (default: all, none with --garment)")
      ->check(CLI::IsMember({"top", "skirt", "trousers", "all"}));
  c->add_option("--garment", opt.garment, "a garment on the reference body: .obj, or .mhclo (--reference makehuman)");
  c->add_option("--scale", opt.scale, "garment (and reference body file) units to metres, e.g. 0.01 for cm")
      ->check(CLI::PositiveNumber);
  c->add_option("--up", opt.up, "garment (and reference body file) up axis: y or z")->check(CLI::IsMember({"y", "z"}));
  c->add_option("--reference", opt.reference,
                "reference body: mannequin, makehuman, or a closed body OBJ file (garments only unless it has the "
                "topology of one of those)")
      ->check([](const std::string& r) -> std::string {
        // A missing .obj is bad input (exit 3, named by read_reference_body), not a usage error.
        if (r == "mannequin" || r == "makehuman" || fs::path(r).extension() == ".obj" || fs::is_regular_file(r))
          return {};
        return "'" + r + "': neither mannequin, makehuman nor a body OBJ file";
      });
  c->add_option("--features", opt.features,
                "feature curves of a body OBJ file (JSON of named polylines, docs/body-files.md): profile templates "
                "encode on it");
  c->add_option("--data", opt.data, "the shared data folder (for makehuman)");
  c->add_option("--z-depth", opt.z_depth,
                "the garment's layer order in an outfit, stored in the .atd (smaller is nearer the skin; a .mhclo's "
                "z_depth by default): regen with several templates that all have one layers them by it");
  c->add_flag("--scaled-frames", opt.scaled_frames,
              "--garment: frames that scale with the skin (offsets grow with the local girth; closer to MakeHuman's "
              "helpers, more clearance change: docs/performance.md), stored in the .atd");
  c->add_option("--out", opt.out, "output folder");
  return c;
}

namespace {

/// `encode --garment`: the detail template of a garment on `ref` (seed 001
/// section 6), written as <stem>.atd with the garment as <stem>.obj.
void encode_garment_files(const Common& common, const EncodeOptions& opt, const ReferenceBody& ref,
                          const makehuman::HumanLibrary* lib, Log& log) {
  const ExecContext ctx = common.context();
  const fs::path& file = opt.garment;
  if (!fs::exists(file)) throw Error(Status(ErrorCode::kIo, file.string() + ": no such file"));
  const std::string ext = file.extension().string();
  Expected<PolygonSoup> g = Status(ErrorCode::kInvalidArgument,
                                   file.string() + ": unknown garment format (use .obj or .mhclo)");
  if (ext != ".obj" && ext != ".mhclo") throw Error(g.status());
  if (ext == ".mhclo") {
    if (!lib)
      throw Error(Status(ErrorCode::kInvalidArgument,
                         file.string() + ": a .mhclo garment is bound to the MakeHuman base mesh: use --reference "
                                         "makehuman (or give the garment as an OBJ on the mannequin)"));
    g = makehuman::fitted_garment(*lib, file);
  }
  std::optional<int> z_depth = opt.z_depth;
  if (ext == ".mhclo" && !z_depth) {
    const makehuman::GarmentBinding b = makehuman::read_mhclo(file, lib->vertex_count());  // read again: cheap
    if (b.has_z_depth) z_depth = b.z_depth;
  }
  Expected<GarmentTemplate> t = Status(ErrorCode::kInternal, "not encoded");
  GarmentEncodeOptions encode;
  encode.detail.scaled_frames = opt.scaled_frames;
  if (ext == ".obj") {
    // One library call: read, mapped to metres and Y up, encoded.
    t = encode_garment_file(ref, file, {.frame = body_frame(opt.scale, opt.up), .encode = encode}, ctx);
  } else {
    if (!g) throw Error(g.status());
    for (Vec3d& p : g->positions) p = round_to_float(p);  // float, as the .obj beside the template stores it
    auto family = GarmentFamily::of(ref);
    if (!family) throw Error(family.status());
    t = encode_garment(*family, file.stem().string(), std::move(*g), encode, ctx);
    if (!t) t = Status(t.status().code(), file.string() + ": " + t.status().message());
  }
  if (!t) throw Error(t.status());
  if (z_depth) {
    t->encoding.z_depth = *z_depth;  // written in the .atd
    t->z_depth = *z_depth;
  }
  std::size_t inside = 0;
  double min_c = std::numeric_limits<double>::infinity();
  for (float c : t->clearance.clearance) {
    inside += c < 0;
    min_c = std::min(min_c, static_cast<double>(c));
  }
  write_garment_template(*t, opt.out);
  const std::string& name = t->name;
  std::printf(
      "%s: %zu vertices, %zu faces, %zu p-polygons per vertex, clearance on the reference %.1f mm (min), "
      "%zu vertices inside -> %s\n",
      name.c_str(), t->mesh.positions.size(), t->mesh.face_count(),
      t->encoding.entries() / std::max<std::size_t>(1, t->mesh.positions.size()), 1000 * min_c, inside,
      (opt.out / (name + ".atd")).string().c_str());
  if (inside > 0)
    log.warn(name + ": " + std::to_string(inside) +
             " vertices are inside the reference body; regeneration pushes them out to the minimum clearance");
}

}  // namespace

int run_encode(const Common& common, const EncodeOptions& opt, Log& log) {
  ReferenceBody ref;
  std::optional<makehuman::HumanLibrary> lib;
  const bool user_body = opt.reference != "mannequin" && opt.reference != "makehuman";
  if (!opt.features.empty() && !user_body)
    throw Error(Status(ErrorCode::kInvalidArgument, "--features is for a body OBJ file; the " + opt.reference +
                                                        " has its own feature curves"));
  if (opt.reference == "mannequin") {
    auto r = make_mannequin();
    if (!r) throw Error(r.status());
    ref = std::move(*r);
  } else if (opt.reference == "makehuman") {
    lib.emplace(makehuman::HumanLibrary::load(opt.data / "makehuman", common.context()));
    ref = makehuman::make_reference_body(*lib);
  } else {
    // A user's body: in the file's units and axes, mapped at the door.
    auto r = read_reference_body(
        opt.reference,
        {.frame = body_frame(opt.scale, opt.up), .makehuman_data = opt.data, .features = opt.features},
        common.context());
    if (!r) throw Error(r.status());
    ref = std::move(*r);
  }
  const std::string which = opt.name.empty() ? (opt.garment.empty() ? "all" : "") : opt.name;
  const bool no_curves = user_body && !which.empty() && ref.curves.empty();
  int written = 0;
  if (no_curves && opt.garment.empty()) written = -1;  // refused below, before anything is written
  if (written == 0) make_output_dir(opt.out);
  if (!opt.garment.empty()) {
    encode_garment_files(common, opt, ref, lib ? &*lib : nullptr, log);
    ++written;
  }
  if (no_curves) {
    // Profile templates are built from feature curves an OBJ file has not.
    const std::string why = opt.reference +
                            ": the body has no feature curves, so only detail templates apply: encode a garment with "
                            "--garment, or give the body's feature curves with --features CURVES.json for profile "
                            "templates (docs/body-files.md)";
    if (written <= 0) throw Error(Status(ErrorCode::kInvalidArgument, why));
    log.warn(why + "; the garment was encoded, no profile template");
    return kExitPartial;
  }
  for (auto [name, make] : {std::pair{"top", &make_top_template}, std::pair{"skirt", &make_skirt_template},
                            std::pair{"trousers", &make_trousers_template}}) {
    if (which != "all" && which != name) continue;
    auto t = make(ref);
    if (!t) throw Error(Status(t.status().code(), std::string(name) + ": " + t.status().message()));
    t->reference = opt.reference + ": " + reference_tag(ref) + (opt.features.empty() ? "" : features_tag(ref));
    write_template_json(*t, opt.out / (std::string(name) + ".template.json"));
    write_obj(t->model, opt.out / (std::string(name) + ".obj"));
    std::printf("%s: %zu feature nodes, %zu faces, %zu surfaces, %zu joints, %zu profiles -> %s\n", name,
                t->model.num_nodes(), t->model.num_faces(), t->model.num_surfaces(), t->model.num_joints(),
                t->profiles.size(), (opt.out / (std::string(name) + ".template.json")).string().c_str());
    ++written;
  }
  log.info("encoded " + std::to_string(written) + " template(s) on the " + opt.reference + " reference body");
  if (user_body && written > 0)
    log.info(
        "the template pair is in metres and Y up (the engine's frame); `atelier regen` with the same --scale "
        "and --up writes its results back in the body files' units and axes");
  return kExitOk;
}

CLI::App* add_regen_subcommand(CLI::App& app, RegenOptions& opt) {
  auto* c = app.add_subcommand("regen", mpi::built_with_mpi()
                                            ? "regenerate encoded templates on every body of a body set (under "
                                              "mpirun: the bodies are split across the ranks)"
                                            : "regenerate encoded templates on every body of a body set");
  c->add_option("--template", opt.templates, "template file (repeatable): profile .template.json or detail .atd")
      ->required();
  c->add_option("--source", opt.bodies.source, "mannequin, makehuman, or a directory of OBJ bodies");
  c->add_option("--count", opt.bodies.count, "bodies to sample (mannequin, makehuman)")->check(body_count_check());
  c->add_option("--data", opt.bodies.data, "the shared data folder (for makehuman)");
  c->add_option("--reference", opt.bodies.reference, "reference body OBJ (directory sources)");
  c->add_option("--features", opt.bodies.features,
                "feature curves of the reference body OBJ (JSON, docs/body-files.md): for profile templates");
  c->add_option("--scale", opt.bodies.scale,
                "file units to metres (directory sources); outputs are written back in them");
  c->add_option("--up", opt.bodies.up, "the files' up axis, y or z (directory sources); outputs are written back in it")
      ->check(CLI::IsMember({"y", "z"}));
  c->add_option("--out", opt.out, "output folder");
  c->add_option("--meshes", opt.meshes, "write OBJ meshes of the first N bodies: body.obj beside their garments");
  c->add_option("--chunk", opt.chunk, "bodies per chunk (bounds memory)")->check(CLI::PositiveNumber);
  c->add_option("--levels", opt.levels, "refinement levels (default: each template's)")
      ->check(CLI::Range(0, kMaxTemplateLevels));
  c->add_option("--clearance", opt.clearance, "distance kept from the body in metres (default: each template's)")
      ->check(clearance_check());
  c->add_flag("--no-resume", opt.no_resume, "recompute bodies whose outputs already exist");
  c->add_flag("--report", opt.report,
              "also write report.html: summary, a row per body, pictures of sample and worst bodies with their outfit");
  c->add_flag("--patterns", opt.patterns,
              "also write made-to-measure pattern sets (SVG, DXF, measurements CSV) of the profile templates");
  c->add_flag("--no-marked-seams", opt.no_marked_seams,
              "with --patterns: ignore the seams the templates mark (pieces are cut along them by default)");
  return c;
}

namespace {

/// One rank's part of a regen run, from its set-up to its share of bodies.
struct RegenJob {
  std::vector<ProfileTemplate> templates;
  std::vector<std::shared_ptr<const GarmentTemplate>> details;
  std::shared_ptr<const GarmentFamily> family;  // details: the reference's polygons and skin
  std::unique_ptr<BodySource> src;
  fs::path bodies_dir;
  // This rank's work, for timing.json.
  std::size_t done = 0, skipped = 0;
  double body_ms_sum = 0;  // over the bodies regenerated now (no per-body list: memory stays bounded)
};

/// Reads the templates and the body set and checks they fit (throws Error).
RegenJob prepare_regen(const Common& common, const RegenOptions& opt) {
  RegenJob job;
  std::vector<fs::path> detail_files, profile_files;
  for (const auto& p : opt.templates) {
    if (p.extension() == ".atd") {
      detail_files.push_back(p);
    } else {
      job.templates.push_back(read_template_json(p));
      profile_files.push_back(p);
    }
  }
  job.src = make_body_source(common, opt.bodies);
  const auto ref = job.src->reference();
  // A user's body without feature curves: profile templates cannot be placed on it.
  const std::string no_curves =
      ref->curves.empty() ? "; the reference body " + opt.bodies.reference.string() +
                                " has no feature curves, so only detail templates (.atd) apply to it unless they are "
                                "given with --features CURVES.json (docs/body-files.md)"
                          : std::string();
  if (!detail_files.empty()) {
    const ExecContext ctx = common.context();
    auto family = GarmentFamily::of(*ref);
    if (!family) throw Error(family.status());
    job.family = std::make_shared<const GarmentFamily>(std::move(*family));
    std::vector<GarmentTemplate> read;
    for (const fs::path& f : detail_files) {
      auto d = read_garment_template(*job.family, f, ctx);
      if (!d) throw Error(d.status());
      read.push_back(std::move(*d));
    }
    // An outfit: the garments are layers by the z_depth stored in their .atd
    // files when every one has one (MakeHuman's order; ties in the order of
    // the --template options), else in the order of the --template options,
    // the first nearest the skin. The effective order follows from the
    // templates' contents and order, both part of job.json.
    const bool by_z = std::all_of(read.begin(), read.end(), [](const GarmentTemplate& g) { return g.encoding.z_depth; });
    for (std::size_t i = 0; i < read.size(); ++i) {
      read[i].z_depth = by_z ? *read[i].encoding.z_depth : static_cast<int>(i);
      job.details.push_back(std::make_shared<const GarmentTemplate>(std::move(read[i])));
    }
  }
  // Outputs are named after the templates: two of one name would overwrite
  // each other's meshes and records.
  std::map<std::string, fs::path> named;
  named.emplace("body", "(the body's own mesh, --meshes)");  // <body>/body.obj
  auto claim = [&](const std::string& name, const fs::path& file) {
    const auto [it, fresh] = named.emplace(name, file);
    if (!fresh)
      throw Error(Status(ErrorCode::kInvalidArgument, "templates " + it->second.string() + " and " + file.string() +
                                                          " are both named '" + name +
                                                          "': their outputs would overwrite each other"));
  };
  for (std::size_t i = 0; i < job.templates.size(); ++i) claim(job.templates[i].name, profile_files[i]);
  for (std::size_t i = 0; i < job.details.size(); ++i) claim(job.details[i]->name, detail_files[i]);
  for (const auto& t : job.templates) {
    if (t.model.nodes.slots.capacity() != t.encodings.nodes.size())
      throw Error(Status(ErrorCode::kMismatch, t.name + ": encodings do not match the template's nodes"));
    const std::string tag = reference_tag(*ref);
    if (t.reference.find(tag) == std::string::npos)
      throw Error(Status(ErrorCode::kMismatch, "template '" + t.name + "' was encoded on a reference body with " +
                                                   t.reference + "; the body set's reference has " + tag +
                                                   " (encode the template on this reference with `atelier encode`)" +
                                                   no_curves));
    if (!no_curves.empty())
      throw Error(Status(ErrorCode::kInvalidArgument, "profile template '" + t.name + "'" + no_curves));
    // Curves from a file: the template's feature points are the file's, by id.
    const bool t_file = t.reference.find(", feature curves ") != std::string::npos;
    const std::string ftag = opt.bodies.features.empty() ? std::string() : features_tag(*ref);
    if (t_file != !ftag.empty() || (t_file && t.reference.find(ftag) == std::string::npos))
      throw Error(Status(ErrorCode::kMismatch,
                         "template '" + t.name + "' was encoded on " +
                             (t_file ? "feature curves from a file (" + t.reference + ")" : "the body's own feature curves") +
                             (ftag.empty() ? "; this job's reference has its own (give the same --features file)"
                                           : "; this job's --features " + opt.bodies.features.string() +
                                                 " gives other curves (" + ftag.substr(2) + ")") +
                             ": its feature points would be others"));
  }
  job.bodies_dir = opt.out / "bodies";
  make_output_dir(job.bodies_dir);
  return job;
}

/// --patterns: the options of every pattern set (the defaults; the top cut
/// along its template's marked seams unless --no-marked-seams).
MadeToMeasureOptions pattern_options(bool marked_seams) {
  MadeToMeasureOptions o;
  o.seams.marked = marked_seams;
  return o;
}

/// --patterns: the fewest bodies in a job (all ranks, done or not: the
/// choice is the job's, the same on a rerun) for which the pattern sets are
/// made by the batch form. Its prepare() (the templates regenerated and
/// flattened on the reference body, the reference with 3 times the
/// iteration cap) costs about 2 bodies' worth of CPU on the project
/// templates, more than it saves below ~6 bodies (docs/performance.md,
/// mtm13: 4 bodies 7.1 s against 6.0 s one-shot, 16 bodies 20.0 s against
/// 24.4 s). A body's pattern set is the same bits for any thread count,
/// rank count, chunk size or resume; which of the two forms made it depends
/// on the job's body count only.
constexpr std::size_t kBatchPatternBodies = 8;

/// --patterns: per template, the made-to-measure patterns of the job's
/// bodies (systems/pattern/made_to_measure_templates.h): in a job of
/// kBatchPatternBodies or more, the batch form prepared on the template
/// regenerated on the reference body (same parameters, same roi as the
/// bodies), so every body's pattern set is flattened warm from the
/// reference's (per body, the top 1.6-2.2x less CPU than one-shot, the skirt
/// 1.2x, the trousers about the same: their legs start again cold;
/// docs/performance.md, flat11, mtm13); else, and for a template whose
/// reference garment cannot be prepared (with a warning), the one-shot form.
std::vector<TemplatePatterns> template_patterns(std::span<const ProfileTemplate> templates, const ReferenceBody& ref,
                                                const Box3d& roi, const RegenParams& rp, bool batch, bool marked_seams,
                                                const ExecContext& ctx, Log& log) {
  if (batch) {
    auto prepared = prepare_made_to_measure_patterns(templates, ref, roi, rp, pattern_options(marked_seams), ctx);
    if (prepared) {
      for (std::size_t k = 0; k < templates.size(); ++k)
        if (!(*prepared)[k].reason)
          log.warn("patterns of " + templates[k].name + ": the reference garment could not be flattened (" +
                   (*prepared)[k].reason.to_string() + "); its bodies' patterns are made alone");
      return std::move(*prepared);
    }
    log.warn("patterns: the templates could not be regenerated on the reference body (" +
             prepared.status().to_string() + "); every body's patterns are made alone");
  }
  std::vector<TemplatePatterns> one_shot(templates.size());
  for (TemplatePatterns& t : one_shot) t.options = pattern_options(marked_seams);
  return one_shot;
}

/// A body's record marks it complete; with --patterns, only a record that
/// lists its pattern sets (or a failure) does.
/// The made-to-measure pattern set of one regenerated template, and its
/// figures for the body's record.
nlohmann::json write_patterns(const TemplatePatterns& patterns, const Model& garment, const fs::path& dir,
                              const ExecContext& ctx) {
  auto rep = write_template_patterns(patterns, garment, dir, ctx);
  if (!rep) throw Error(Status(rep.status().code(), "patterns: " + rep.status().message()));
  double e_l = 0;
  std::size_t warm = 0;  // pieces flattened warm from the reference (batch form)
  for (const auto& p : rep->files.flattening.pieces) {
    e_l = std::max(e_l, p.distortion.length_error);
    warm += p.warm_started;
  }
  return {{"pieces", rep->files.pattern.pieces.size()},
          {"seams_opened", rep->seams_opened},
          {"flipped", rep->flipped},
          {"failed_seams", rep->failed_seams},
          {"max_seam_difference_mm", rep->max_seam_difference_mm},
          {"max_length_error", e_l},
          {"warm_started_pieces", warm}};
}

nlohmann::json garment_quality_json(const GarmentQuality& q) {
  return {{"vertices", q.vertices},         {"inside_nodes", q.inside},          {"max_depth_m", q.max_depth},
          {"min_clearance_m", q.min_clearance}, {"clearance_error_m", q.clearance_error}, {"strain_max", q.strain_max},
          {"strain_p95", q.strain_p95},     {"pushed", q.pushed}, {"layer_inside_vertices", q.layer_inside}};
}

/// Regenerates the bodies of this rank's chunks (mpi::regen_share) that have
/// no record yet; writes each body's outputs and record (last, atomically).
void regen_share(const Common& common, const RegenOptions& opt, const mpi::ProcessGroup& group, RegenJob& job,
                 Log& log) {
  const ExecContext ctx = common.context();
  const auto& templates = job.templates;
  const BodySource& src = *job.src;
  const fs::path& bodies_dir = job.bodies_dir;
  const auto ref = src.reference();
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
  // One collider per worker, refit per body instead of rebuilt (results are
  // identical to fresh builds: Regenerate.PooledCollidersGiveTheSameResults...).
  ColliderPool colliders;
  // Detail garments: decoded in batches over the chunk, then the edge
  // transfer, the collision pass with layers and the fit figures
  // (systems/garment/regenerate_garment.h).
  std::optional<GarmentRegenerator> regenerator;
  if (!job.details.empty()) {
    auto r = GarmentRegenerator::create(job.family, job.details, {}, ctx);
    if (!r) throw Error(r.status());
    regenerator = std::move(*r);
  }
  std::vector<BodyGarments> garments;
  const std::size_t n = src.size();
  // --patterns: the batch form for a job of kBatchPatternBodies or more
  // bodies (prepared at the first chunk with a body to do), else one-shot.
  std::vector<TemplatePatterns> patterns;
  bool prepare = opt.patterns && !templates.empty();
  // Progress counts this rank's share; only rank 0 draws it (one bar).
  const bool show = group.rank() == 0;
  std::size_t share = 0, share_seen = 0;
  for (std::size_t first = 0, c = 0; first < n; first += opt.chunk, ++c)
    if (mpi::regen_share(c, group.rank(), group.size())) share += std::min(opt.chunk, n - first);
  if (show) log.progress("bodies", 0, share);
  for (std::size_t first = 0, c = 0; first < n; first += opt.chunk, ++c) {
    if (ctx.cancelled()) break;
    if (!mpi::regen_share(c, group.rank(), group.size())) continue;
    const std::size_t count = std::min(opt.chunk, n - first);
    share_seen += count;
    // Resume: bodies whose record says ok are complete; failed ones are retried.
    // Bodies read from files are also checked against the contents their
    // record was made from: an edited body file is computed again.
    std::vector<std::uint8_t> pending(count, 1);
    std::vector<nlohmann::json> inputs(count);
    bool any = false;
    for (std::size_t i = 0; i < pending.size(); ++i) {
      inputs[i] = body_input_identity(src.body_file(first + i));
      if (!opt.no_resume &&
          body_record_complete(bodies_dir / (src.body_name(first + i) + ".json"), opt.patterns, inputs[i])) {
        pending[i] = 0;
        ++job.skipped;
      }
      any = any || pending[i];
    }
    if (!any) {
      if (show) log.progress("bodies", share_seen, share);
      continue;
    }
    const std::size_t failures_before = failures.size();
    src.generate(first, pending.size(), chunk, failures, ctx);
    for (std::size_t f = failures_before; f < failures.size(); ++f) {  // unreadable bodies: record them too
      nlohmann::json rec = {{"body", failures[f].name}, {"ok", false}, {"reason", failures[f].status.to_string()}};
      log.warn(failures[f].name + ": " + failures[f].status.message());  // e.g. a member of another topology
      write_atomically(bodies_dir / (failures[f].name + ".json"), [&](AtomicFile& file) { file.write(rec.dump(1)); });
    }
    if (prepare) {
      patterns = template_patterns(templates, *ref, roi, rp, n >= kBatchPatternBodies, !opt.no_marked_seams, ctx, log);
      prepare = false;
    }
    double garment_ms_per_body = 0;
    if (regenerator) {
      const auto tg = std::chrono::steady_clock::now();
      if (Status st = regenerator->run(chunk, 0, chunk.size(), garments, ctx); !st) throw Error(st);
      garment_ms_per_body = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tg).count() /
                            static_cast<double>(std::max<std::size_t>(1, chunk.size()));
    }
    std::vector<std::string> errors(chunk.size());
    std::vector<double> ms(chunk.size(), 0);
    ExecContext per_body = ctx;
    per_body.sequential_threshold = 2;
    per_body.grain = 1;
    par::for_each_n(per_body, chunk.size(), [&](std::size_t b) {
      std::size_t index = first;  // the body's index in the source, by name
      for (std::size_t i = 0; i < pending.size(); ++i)
        if (src.body_name(first + i) == chunk.name(b)) index = first + i;
      if (!pending[index - first]) return;
      const auto t0 = std::chrono::steady_clock::now();
      ExecContext inner = ExecContext::sequential();
      inner.cancel = ctx.cancel;
      const std::vector<Vec3d> body = chunk.positions(b);
      nlohmann::json rec = {{"body", chunk.name(b)}, {"ok", true}};
      if (!inputs[index - first].is_null()) rec["input"] = inputs[index - first];
      try {
        std::vector<RegenResult> regen;
        if (!templates.empty()) {
          auto r = regenerate_on_body(templates, *ref, body, roi, rp, {.use_grid = false}, inner, colliders);
          if (!r) throw Error(r.status());
          regen = std::move(*r);
        }
        nlohmann::json per = nlohmann::json::object();
        for (std::size_t k = 0; k < job.details.size(); ++k) {
          const GarmentTemplate& d = *job.details[k];
          if (!garments[b].status) throw Error(garments[b].status);
          const GarmentResult& g = garments[b].garments[k];
          if (g.quality.inside > 0)
            throw Error(Status(ErrorCode::kDegenerate, d.name + ": " + std::to_string(g.quality.inside) +
                                                           " vertices could not be pushed out of the body"));
          const GarmentQuality& gq = g.quality;
          require_finite(d.name, g.positions,
                         {{"max_depth_m", gq.max_depth},
                          {"min_clearance_m", gq.min_clearance},
                          {"mean_clearance_m", gq.mean_clearance},
                          {"clearance_error_m", gq.clearance_error},
                          {"strain_max", gq.strain_max},
                          {"strain_p95", gq.strain_p95}});
          per[d.name] = garment_quality_json(g.quality);
          if (index < opt.meshes) {
            make_output_dir(bodies_dir / chunk.name(b));
            std::vector<Vec3d> p = g.positions;
            src.frame().to_file(p);  // back in the body files' units and axes
            write_garment_mesh(d.mesh, p, bodies_dir / chunk.name(b) / (d.name + ".obj"));
          }
        }
        for (std::size_t k = 0; k < templates.size(); ++k) {
          const ProfileTemplate& t = templates[k];
          const RegenResult& r = regen[k];
          if (r.quality.inside > 0)
            throw Error(Status(ErrorCode::kDegenerate, t.name + ": " + std::to_string(r.quality.inside) +
                                                           " nodes could not be pushed out of the body"));
          const RegenQuality& q = r.quality;
          require_finite(t.name, r.model.nodes.position,
                         {{"max_depth_m", q.max_depth},
                          {"min_distance_m", q.min_distance},
                          {"node_clearance_error_m", q.node_clearance_error},
                          {"profile_error_m", q.profile_error},
                          {"umbrella", q.umbrella},
                          {"crack_m", q.crack}},
                         &r.model);
          per[t.name] = quality_json(r.quality);
          if (index < opt.meshes) {
            make_output_dir(bodies_dir / chunk.name(b));
            if (src.frame().identity()) {
              write_obj(r.model, bodies_dir / chunk.name(b) / (t.name + ".obj"));
            } else {
              Model m = r.model;
              src.frame().to_file(m.nodes.position);  // back in the body files' units and axes
              write_obj(m, bodies_dir / chunk.name(b) / (t.name + ".obj"));
            }
          }
        }
        if (index < opt.meshes) {  // the body beside its garments, in the body files' units and axes
          make_output_dir(bodies_dir / chunk.name(b));
          Model bm = ref->model;
          chunk.positions(b, bm.nodes.position);
          if (!src.frame().identity()) src.frame().to_file(bm.nodes.position);
          write_obj(bm, bodies_dir / chunk.name(b) / "body.obj");
        }
        rec["templates"] = per;
        if (opt.patterns) {
          nlohmann::json pats = nlohmann::json::object();
          for (std::size_t k = 0; k < templates.size(); ++k)
            pats[templates[k].name] = write_patterns(
                patterns[k], regen[k].model, bodies_dir / chunk.name(b) / "patterns" / templates[k].name, inner);
          rec["patterns"] = pats;
        }
      } catch (const Error& e) {
        rec = {{"body", chunk.name(b)}, {"ok", false}, {"reason", e.status().to_string()}};
        errors[b] = e.status().to_string();
      }
      // Written last: its presence means every output of this body is complete.
      write_atomically(bodies_dir / (chunk.name(b) + ".json"), [&](AtomicFile& file) { file.write(rec.dump(1)); });
      ms[b] = garment_ms_per_body +
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    });
    for (std::size_t b = 0; b < chunk.size(); ++b) {
      if (!errors[b].empty()) {
        failures.push_back({first + b, chunk.name(b), Status(ErrorCode::kInternal, errors[b])});
        log.warn(chunk.name(b) + ": " + errors[b]);
      } else if (ms[b] > 0) {
        ++job.done;
        job.body_ms_sum += ms[b];
      }
    }
    if (show) log.progress("bodies", share_seen, share);
  }
  if (show) log.end_progress();
}

struct MergeCounts {
  std::size_t ok = 0, failed = 0, inside = 0;
  std::size_t layer_inside = 0;  // garment vertices inside a lower layer of the outfit
  double crack = 0;
};

/// Merges every body's record, in body order, into report.json (the records
/// of earlier runs and of other ranks included). Rank 0 only.
///
/// Streamed: each record is read, counted and written out before the next
/// is read, so the merge holds one record and the summary's counters
/// whatever the number of bodies. The output is what nlohmann's dump(1) of
/// the whole report would be: the keys in its (sorted) order, "bodies" first,
/// so the summary, known only at the end, comes after the rows.
MergeCounts merge_report(const Common& common, const RegenOptions& opt, const RegenJob& job) {
  const std::size_t n = job.src->size();
  MergeCounts m;
  write_atomically(opt.out / "report.json", [&](AtomicFile& f) {
    f.write("{\n \"bodies\": [");
    bool first = true;
    std::string text;
    for (std::size_t i = 0; i < n; ++i) {
      const fs::path rec = job.bodies_dir / (job.src->body_name(i) + ".json");
      if (!fs::exists(rec)) continue;  // cancelled before it
      std::ifstream in(rec);
      const nlohmann::json r = nlohmann::json::parse(in, nullptr, false);
      if (r.is_discarded()) throw Error(Status(ErrorCode::kParse, rec.string() + ": not valid JSON"));
      if (r.value("ok", false)) {
        ++m.ok;
        for (const auto& [k, q] : r["templates"].items()) {
          m.inside += q.value("inside_nodes", std::size_t{0});
          m.layer_inside += q.value("layer_inside_vertices", std::size_t{0});
          m.crack = std::max(m.crack, q.value("crack_m", 0.0));
        }
      } else {
        ++m.failed;
      }
      // The row at depth 2 of the report: its own dump(1), indented by 2.
      text = first ? "\n  " : ",\n  ";
      first = false;
      for (const char c : r.dump(1)) {
        text += c;
        if (c == '\n') text += "  ";
      }
      f.write(text);
    }
    f.write(first ? "]" : "\n ]");
    nlohmann::json rest;
    rest["tool"] = "atelier regen";
    rest["seed"] = common.seed;
    rest["source"] = opt.bodies.source;
    nlohmann::json names = nlohmann::json::array();
    for (const auto& t : job.templates) names.push_back(t.name);
    for (const auto& d : job.details) names.push_back(d->name);
    rest["templates"] = names;
    if (job.details.size() > 1) {
      // The outfit's effective layer order, innermost first (stable by z_depth).
      std::vector<std::size_t> order(job.details.size());
      std::iota(order.begin(), order.end(), std::size_t{0});
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t a, std::size_t b) { return job.details[a]->z_depth < job.details[b]->z_depth; });
      nlohmann::json layers = nlohmann::json::array();
      for (std::size_t i : order) layers.push_back({{"garment", job.details[i]->name}, {"z_depth", job.details[i]->z_depth}});
      rest["layer_order"] = layers;
    }
    rest["summary"] = {{"bodies", n},
                       {"completed", m.ok},
                       {"failed", m.failed},
                       {"inside_nodes_total", m.inside},
                       {"layer_inside_vertices_total", m.layer_inside},
                       {"max_crack_m", m.crack}};
    // rest's dump(1) without its braces: the remaining members, in order.
    const std::string tail = rest.dump(1);
    f.write(",");
    f.write(tail.substr(1));
  });
  return m;
}

/// Exit code of an exception at this entry point, as main() maps them.
int exit_code_of(const Error& e) {
  const auto c = e.status().code();
  return c == ErrorCode::kInternal || c == ErrorCode::kStaleHandle ? kExitInternal : kExitInput;
}

}  // namespace

int run_regen(const Common& common, const RegenOptions& opt, Log& log) {
  const auto t_start = std::chrono::steady_clock::now();
  const mpi::ProcessGroup group;
  if (group.launched_without_mpi())
    throw Error(Status(ErrorCode::kInvalidArgument,
                       "started by an MPI launcher as one of several ranks, but this atelier was built without MPI "
                       "(install libopenmpi-dev and reconfigure with -DATELIER_WITH_MPI=ON)"));
  const std::string who =
      group.distributed() ? "rank " + std::to_string(group.rank()) + " of " + std::to_string(group.size()) + ": " : "";
  // Every rank must reach the collectives below, so on several ranks an
  // error is caught, logged and reduced instead of leaving the others
  // waiting; one process keeps the plain exception path of main().
  std::optional<RegenJob> job;
  nlohmann::json definition;
  int code = kExitOk;
  auto guarded = [&](auto&& work) {
    try {
      work();
    } catch (const Error& e) {
      if (!group.distributed()) throw;
      log.error(who + e.what());
      code = exit_code_of(e);
    } catch (const std::exception& e) {
      if (!group.distributed()) throw;
      log.error(who + "internal error: " + e.what());
      code = kExitInternal;
    }
  };
  bool claimed = false;
  guarded([&] {
    job.emplace(prepare_regen(common, opt));
    definition = describe_regen_job(common, opt);  // job.json: a rerun resumes only its own job
    if (const std::string refused = claim_regen_folder(opt.out, definition, opt.no_resume, group.rank() == 0);
        refused.empty()) {
      claimed = true;
    } else {
      log.error(who + refused);
      code = kExitUsage;
    }
  });
  // No rank writes a body record before every rank has checked the folder:
  // a fast rank's first record would look like another job's to a slow one.
  if (group.distributed()) group.barrier();
  if (claimed) guarded([&] { regen_share(common, opt, group, *job, log); });
  if (group.distributed())
    log.info(who + "regenerated " + std::to_string(job ? job->done : 0) + " bodies, skipped " +
             std::to_string(job ? job->skipped : 0) + " complete ones");

  // Per-rank work for timing.json: gathered on every rank (one collective,
  // which is also the barrier before the merge: all records are written).
  double mean_ms = 0;
  if (job) mean_ms = job->body_ms_sum / std::max<double>(1, static_cast<double>(job->done));
  const std::array<double, 4> mine = {static_cast<double>(code), job ? static_cast<double>(job->done) : 0.0,
                                      job ? static_cast<double>(job->skipped) : 0.0, mean_ms};
  const std::vector<double> all = group.all_gather(mine);
  for (int r = 0; r < group.size(); ++r) code = std::max(code, static_cast<int>(all[4 * r]));

  if (group.rank() == 0 && code < kExitUsage) {
    try {
      // Every rank is done writing: temporaries of killed runs can go.
      remove_stale_output_temporaries(opt.out);
      record_regen_job(opt.out, definition);
      const MergeCounts m = merge_report(common, opt, *job);
      const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      std::size_t done = 0, skipped = 0;
      double weighted_ms = 0;
      nlohmann::json ranks = nlohmann::json::array();
      for (int r = 0; r < group.size(); ++r) {
        const auto d = static_cast<std::size_t>(all[4 * r + 1]);
        const auto s = static_cast<std::size_t>(all[4 * r + 2]);
        done += d;
        skipped += s;
        weighted_ms += all[4 * r + 3] * static_cast<double>(d);
        ranks.push_back(
            {{"rank", r}, {"regenerated_now", d}, {"skipped_complete", s}, {"mean_ms_per_body", all[4 * r + 3]}});
      }
      nlohmann::json timing = {{"total_s", total_s},
                               {"regenerated_now", done},
                               {"skipped_complete", skipped},
                               {"mean_ms_per_body", weighted_ms / std::max<double>(1, static_cast<double>(done))},
                               {"threads", common.threads},
                               {"ranks", ranks}};
      write_atomically(opt.out / "timing.json", [&](AtomicFile& f) { f.write(timing.dump(1)); });
      if (opt.report) {
        RegenParams rp;
        rp.levels = opt.levels;
        rp.clearance = opt.clearance;
        write_regen_html({.templates = job->templates,
                          .details = job->details,
                          .family = job->family,
                          .source = job->src.get(),
                          .params = rp,
                          .out = opt.out},
                         common.context(), log);
      }
      const std::size_t n = job->src->size();
      std::printf(
          "atelier regen: %zu bodies x %zu templates: %zu complete (%zu now, %zu from an earlier run), %zu "
          "failed; %zu nodes inside, %zu inside a lower layer, max crack %.1e m; %.1f s",
          n, job->templates.size() + job->details.size(), m.ok, done, skipped, m.failed, m.inside, m.layer_inside,
          m.crack, total_s);
      if (group.distributed()) std::printf(" on %d ranks", group.size());
      std::printf("\n  report: %s\n", fs::absolute(opt.out / (opt.report ? "report.html" : "report.json")).string().c_str());
      std::fflush(stdout);
      code = std::max(code, m.failed == 0 ? int{kExitOk} : int{kExitPartial});
    } catch (const Error& e) {
      if (!group.distributed()) throw;
      log.error(who + e.what());
      code = exit_code_of(e);
    }
  }
  // Rank 0's verdict on the merge, to every rank: each exits with the same code.
  return group.max_all(code);
}

}  // namespace atelier::cli
