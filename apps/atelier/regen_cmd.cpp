#include "regen_cmd.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "mpi_split.h"
#include <atelier/engine/parallel.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/makehuman/makehuman.h>
#include <atelier/io/makehuman/mhclo.h>
#include <atelier/io/obj.h>
#include <atelier/systems/garment/collision_pass.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/edge_transfer.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/profile/project_templates.h>
#include <atelier/systems/profile/regenerate.h>
#include <atelier/systems/profile/template_json.h>
#include <atelier/systems/mesh/fan_triangulation.h>

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

/// The garment of an OBJ file (read_base_mesh: every `v`, every `f` of every
/// group), positions times `scale`.
PolygonSoup read_garment_obj(const fs::path& file, double scale) {
  const makehuman::BaseMesh m = makehuman::read_base_mesh(file);
  PolygonSoup g;
  for (const Vec3f& p : m.positions) g.positions.push_back(scale * p.cast<double>());
  for (const auto& grp : m.groups)
    for (std::size_t f = 0; f + 1 < grp.face_offsets.size(); ++f) {
      for (std::uint32_t k = grp.face_offsets[f]; k < grp.face_offsets[f + 1]; ++k)
        g.face_nodes.push_back(grp.face_nodes[k]);
      g.face_offsets.push_back(static_cast<std::uint32_t>(g.face_nodes.size()));
    }
  if (g.positions.empty()) throw Error(Status(ErrorCode::kInvalidArgument, file.string() + ": no vertices"));
  if (g.face_nodes.empty()) throw Error(Status(ErrorCode::kInvalidArgument, file.string() + ": no faces"));
  return g;
}

/// Writes the garment with `positions` (float precision: what
/// read_garment_obj gives back, so encoding and regeneration see the same
/// reference garment).
void write_garment_obj(const PolygonSoup& g, std::span<const Vec3d> positions, const fs::path& file) {
  write_atomically(file, [&](AtomicFile& f) {
    char line[128];
    for (const Vec3d& p : positions) {
      const int n =
          std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", static_cast<double>(static_cast<float>(p.x())),
                        static_cast<double>(static_cast<float>(p.y())), static_cast<double>(static_cast<float>(p.z())));
      f.write(line, static_cast<std::size_t>(n));
    }
    std::string face;
    for (std::size_t k = 0; k + 1 < g.face_offsets.size(); ++k) {
      face = "f";
      for (std::uint32_t i = g.face_offsets[k]; i < g.face_offsets[k + 1]; ++i)
        face += " " + std::to_string(g.face_nodes[i] + 1);
      face += "\n";
      f.write(face);
    }
  });
}

/// The collision body of a reference body's skin (shared topology, built once).
std::shared_ptr<const CollisionTopology> collision_topology(const ReferenceBody& ref) {
  auto tris = fan_triangulate(ref.model);
  if (!tris) throw Error(tris.status());
  auto topo = CollisionTopology::build(tris->triangles, static_cast<std::uint32_t>(ref.model.nodes.slots.capacity()));
  if (!topo) throw Error(Status(topo.status().code(), "reference body: " + topo.status().message()));
  return *topo;
}

/// A detail template ready to regenerate: the encoding, the garment on the
/// reference body, and its clearance there (the collision pass's target).
struct DetailJob {
  std::string name;
  DetailEncoding enc;
  PolygonSoup mesh;  // positions: on the reference body
  std::vector<std::array<std::uint32_t, 2>> edges;
  std::vector<double> rest;  // edge lengths on the reference body
  NodeAdjacency adjacency;
  ClearanceEncoding clearance;
  EdgeTransfer transfer;  // the skin's local stretch, applied after decoding
};

}  // namespace

CLI::App* add_encode_subcommand(CLI::App& app, EncodeOptions& opt) {
  auto* c = app.add_subcommand("encode",
                               "encode the project's profile templates (JSON files) or a garment mesh (--garment, a "
                               "detail template .atd) on a reference body");
  c->add_option("--template", opt.name, "top, skirt, trousers or all (default: all, none with --garment)")
      ->check(CLI::IsMember({"top", "skirt", "trousers", "all"}));
  c->add_option("--garment", opt.garment, "a garment on the reference body: .obj, or .mhclo (--reference makehuman)");
  c->add_option("--scale", opt.scale, "garment OBJ units to metres")->check(CLI::PositiveNumber);
  c->add_option("--reference", opt.reference, "reference body: mannequin or makehuman")
      ->check(CLI::IsMember({"mannequin", "makehuman"}));
  c->add_option("--data", opt.data, "the shared data folder (for makehuman)");
  c->add_option("--out", opt.out, "output folder");
  return c;
}

namespace {

/// `encode --garment`: the detail template of a garment on `ref` (seed 001
/// section 6), written as <stem>.atd with the garment as <stem>.obj.
void encode_garment(const Common& common, const EncodeOptions& opt, const ReferenceBody& ref,
                    const makehuman::HumanLibrary* lib, Log& log) {
  const ExecContext ctx = common.context();
  const fs::path& file = opt.garment;
  if (!fs::exists(file)) throw Error(Status(ErrorCode::kIo, file.string() + ": no such file"));
  PolygonSoup g;
  const std::string ext = file.extension().string();
  if (ext == ".mhclo") {
    if (!lib)
      throw Error(Status(ErrorCode::kInvalidArgument,
                         file.string() + ": a .mhclo garment is bound to the MakeHuman base mesh: use --reference "
                                         "makehuman (or give the garment as an OBJ on the mannequin)"));
    const auto binding = makehuman::read_mhclo(file, lib->vertex_count());
    g = read_garment_obj(file.parent_path() / binding.obj_file, 1.0);
    if (g.positions.size() != binding.refs.size())
      throw Error(Status(ErrorCode::kMismatch, file.string() + ": " + std::to_string(binding.refs.size()) +
                                                   " bound vertices but " + binding.obj_file + " has " +
                                                   std::to_string(g.positions.size())));
    // The binding's fit on the default body, the reference body's shape.
    std::vector<Vec3f> H(lib->vertex_count());
    lib->build(makehuman::MacroParams{}, H);
    g.positions = makehuman::fit_binding(binding, H);
    for (Vec3d& p : g.positions) p *= makehuman::kMakeHumanToMetres;
  } else if (ext == ".obj") {
    g = read_garment_obj(file, opt.scale);
  } else {
    throw Error(Status(ErrorCode::kInvalidArgument, file.string() + ": unknown garment format (use .obj or .mhclo)"));
  }
  // Float precision, as the .obj beside the template stores it.
  for (Vec3d& p : g.positions) p = p.cast<float>().cast<double>();
  const std::string name = file.stem().string();
  const std::vector<Vec3d> skin = skin_positions(ref);
  const BodyPolygons poly = BodyPolygons::from_model(ref.model);
  auto enc = encode_detail(poly, skin, g.positions, {}, ctx);
  if (!enc) throw Error(Status(enc.status().code(), file.string() + ": " + enc.status().message()));
  // Where the garment sits on the reference body: what the collision pass
  // restores on every other body (systems/collision_pass.h).
  CollisionBody cb;
  if (Status s = cb.build(collision_topology(ref), skin, {}, ctx); !s) throw Error(s);
  auto clear = encode_clearance(g.positions, cb, ctx);
  if (!clear) throw Error(Status(clear.status().code(), file.string() + ": " + clear.status().message()));
  std::size_t inside = 0;
  double min_c = std::numeric_limits<double>::infinity();
  for (float c : clear->clearance) {
    inside += c < 0;
    min_c = std::min(min_c, static_cast<double>(c));
  }
  fs::create_directories(opt.out);
  write_garment_obj(g, g.positions, opt.out / (name + ".obj"));
  write_detail(*enc, opt.out / (name + ".atd"));  // last: the template is complete with its mesh
  std::printf(
      "%s: %zu vertices, %zu faces, %zu p-polygons per vertex, clearance on the reference %.1f mm (min), "
      "%zu vertices inside -> %s\n",
      name.c_str(), g.positions.size(), g.face_offsets.size() - 1,
      enc->entries() / std::max<std::size_t>(1, g.positions.size()), 1000 * min_c, inside,
      (opt.out / (name + ".atd")).string().c_str());
  if (inside > 0)
    log.warn(name + ": " + std::to_string(inside) +
             " vertices are inside the reference body; regeneration pushes them out to the minimum clearance");
}

}  // namespace

int run_encode(const Common& common, const EncodeOptions& opt, Log& log) {
  ReferenceBody ref;
  std::optional<makehuman::HumanLibrary> lib;
  if (opt.reference == "mannequin") {
    auto r = make_mannequin();
    if (!r) throw Error(r.status());
    ref = std::move(*r);
  } else {
    lib.emplace(makehuman::HumanLibrary::load(opt.data / "makehuman", common.context()));
    ref = makehuman::make_reference_body(*lib);
  }
  fs::create_directories(opt.out);
  int written = 0;
  if (!opt.garment.empty()) {
    encode_garment(common, opt, ref, lib ? &*lib : nullptr, log);
    ++written;
  }
  const std::string which = opt.name.empty() ? (opt.garment.empty() ? "all" : "") : opt.name;
  for (auto [name, make] : {std::pair{"top", &make_top_template}, std::pair{"skirt", &make_skirt_template},
                            std::pair{"trousers", &make_trousers_template}}) {
    if (which != "all" && which != name) continue;
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
  auto* c = app.add_subcommand("regen", mpi::built_with_mpi()
                                            ? "regenerate encoded templates on every body of a body set (under "
                                              "mpirun: the bodies are split across the ranks)"
                                            : "regenerate encoded templates on every body of a body set");
  c->add_option("--template", opt.templates, "template file (repeatable): profile .template.json or detail .atd")
      ->required();
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

namespace {

/// One rank's part of a regen run, from its set-up to its share of bodies.
struct RegenJob {
  std::vector<ProfileTemplate> templates;
  std::vector<DetailJob> details;
  BodyPolygons poly;                                 // details: the reference's polygons
  std::shared_ptr<const CollisionTopology> collide;  // details: the reference's skin
  std::unique_ptr<BodySource> src;
  fs::path bodies_dir;
  // This rank's work, for timing.json.
  std::size_t done = 0, skipped = 0;
  double body_ms_sum = 0;  // over the bodies regenerated now (no per-body list: memory stays bounded)
};

/// Reads the templates and the body set and checks they fit (throws Error).
RegenJob prepare_regen(const Common& common, const RegenOptions& opt) {
  RegenJob job;
  std::vector<fs::path> detail_files;
  for (const auto& p : opt.templates) {
    if (p.extension() == ".atd")
      detail_files.push_back(p);
    else
      job.templates.push_back(read_template_json(p));
  }
  job.src = make_body_source(common, opt.bodies);
  const auto ref = job.src->reference();
  if (!detail_files.empty()) {
    const ExecContext ctx = common.context();
    job.poly = BodyPolygons::from_model(ref->model);
    job.collide = collision_topology(*ref);
    const std::vector<Vec3d> skin = skin_positions(*ref);
    CollisionBody cb;
    if (Status s = cb.build(job.collide, skin, {}, ctx); !s) throw Error(s);
    for (const fs::path& f : detail_files) {
      DetailJob d;
      d.name = f.stem().string();
      if (!fs::exists(f)) throw Error(Status(ErrorCode::kIo, f.string() + ": no such file"));
      d.enc = read_detail(f);
      if (Status s = check_topology(d.enc, job.poly); !s)
        throw Error(Status(ErrorCode::kMismatch, f.string() + ": encoded on another reference body (" + s.message() +
                                                     "); encode the garment on this reference with `atelier encode "
                                                     "--garment`"));
      fs::path mesh_file = f;
      mesh_file.replace_extension(".obj");
      if (!fs::exists(mesh_file))
        throw Error(Status(ErrorCode::kIo, f.string() + ": its garment mesh " + mesh_file.string() +
                                               " is missing (`atelier encode --garment` writes both)"));
      d.mesh = read_garment_obj(mesh_file, 1.0);
      if (d.mesh.positions.size() != d.enc.vertex_count())
        throw Error(Status(ErrorCode::kMismatch, mesh_file.string() + " has " +
                                                     std::to_string(d.mesh.positions.size()) + " vertices, " +
                                                     f.string() + " encodes " + std::to_string(d.enc.vertex_count())));
      d.edges = d.mesh.edges();
      for (const auto& e : d.edges) d.rest.push_back((d.mesh.positions[e[0]] - d.mesh.positions[e[1]]).norm());
      auto adj = adjacency_from_edges(d.mesh.positions.size(), d.edges);
      if (!adj) throw Error(Status(adj.status().code(), mesh_file.string() + ": " + adj.status().message()));
      d.adjacency = std::move(*adj);
      auto clear = encode_clearance(d.mesh.positions, cb, ctx);
      if (!clear) throw Error(Status(clear.status().code(), mesh_file.string() + ": " + clear.status().message()));
      d.clearance = std::move(*clear);
      auto transfer = encode_edge_transfer(d.mesh.positions, d.edges, cb, {}, ctx);
      if (!transfer)
        throw Error(Status(transfer.status().code(), mesh_file.string() + ": " + transfer.status().message()));
      d.transfer = std::move(*transfer);
      job.details.push_back(std::move(d));
    }
  }
  for (const auto& t : job.templates) {
    if (t.model.nodes.slots.capacity() != t.encodings.nodes.size())
      throw Error(Status(ErrorCode::kMismatch, t.name + ": encodings do not match the template's nodes"));
    const std::string tag = reference_tag(*ref);
    if (t.reference.find(tag) == std::string::npos)
      throw Error(Status(ErrorCode::kMismatch, "template '" + t.name + "' was encoded on a reference body with " +
                                                   t.reference + "; the body set's reference has " + tag +
                                                   " (encode the template on this reference with `atelier encode`)"));
  }
  job.bodies_dir = opt.out / "bodies";
  fs::create_directories(job.bodies_dir);
  return job;
}

/// A detail template on one body: decode (seed 001 eqs. 11-12), the edge
/// transfer (the skin's local stretch, systems/edge_transfer.h), then the
/// collision pass back to the clearance it had on the reference body.
/// Returns the garment positions and fills the quality record.
std::vector<Vec3d> regen_detail(const RegenJob& job, const DetailJob& d, std::span<const Vec3d> body,
                                nlohmann::json& quality, const ExecContext& ctx) {
  std::vector<Vec3d> g(d.mesh.positions.size());
  if (Status s = decode_detail(d.enc, job.poly, body, g, ctx); !s) throw Error(s);
  if (Status s = apply_edge_transfer(d.transfer, body, job.collide->triangles(), g, ctx); !s) throw Error(s);
  CollisionBody cb;
  if (Status s = cb.build(job.collide, body, {}, ctx); !s) throw Error(s);
  const CollisionParams cp;
  std::vector<BodyDistance> fin;
  auto pass = resolve_collisions(g, d.adjacency, d.clearance, cb, cp, fin, ctx);
  if (!pass) throw Error(pass.status());
  // From each vertex's exact distance at its final position (the pass's
  // last query of it; tests check these against BodyBvh), not from the
  // pass's counters.
  std::size_t inside = 0;
  double depth = 0, min_c = std::numeric_limits<double>::infinity(), clear_err = 0;
  for (std::size_t v = 0; v < g.size(); ++v) {
    const double sd = fin[v].distance;
    if (sd < 0) {
      ++inside;
      depth = std::max(depth, -sd);
    }
    min_c = std::min(min_c, sd);
    const double target = std::clamp(static_cast<double>(d.clearance.clearance[v]), cp.min_clearance, cp.max_clearance);
    clear_err = std::max(clear_err, std::abs(sd - target));
  }
  std::vector<double> strain(d.edges.size());
  double strain_max = 0;
  for (std::size_t e = 0; e < d.edges.size(); ++e) {
    strain[e] = d.rest[e] > 0 ? std::abs((g[d.edges[e][0]] - g[d.edges[e][1]]).norm() / d.rest[e] - 1.0) : 0.0;
    strain_max = std::max(strain_max, strain[e]);
  }
  double p95 = 0;
  if (!strain.empty()) {
    const std::size_t k = std::min(strain.size() - 1, strain.size() * 95 / 100);
    std::nth_element(strain.begin(), strain.begin() + static_cast<std::ptrdiff_t>(k), strain.end());
    p95 = strain[k];
  }
  quality = {{"vertices", g.size()},     {"inside_nodes", inside},         {"max_depth_m", depth},
             {"min_clearance_m", min_c}, {"clearance_error_m", clear_err}, {"strain_max", strain_max},
             {"strain_p95", p95},        {"pushed", pass->pushed}};
  return g;
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
  const std::size_t n = src.size();
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
    // Resume: bodies whose record exists are complete.
    std::vector<std::uint8_t> pending(count, 1);
    bool any = false;
    for (std::size_t i = 0; i < pending.size(); ++i) {
      if (!opt.no_resume && fs::exists(bodies_dir / (src.body_name(first + i) + ".json"))) {
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
        if (src.body_name(first + i) == chunk.name(b)) index = first + i;
      if (!pending[index - first]) return;
      const auto t0 = std::chrono::steady_clock::now();
      ExecContext inner = ExecContext::sequential();
      inner.cancel = ctx.cancel;
      const std::vector<Vec3d> body = chunk.positions(b);
      nlohmann::json rec = {{"body", chunk.name(b)}, {"ok", true}};
      try {
        std::vector<RegenResult> regen;
        if (!templates.empty()) {
          auto r = regenerate_on_body(templates, *ref, body, roi, rp, {.use_grid = false}, inner, colliders);
          if (!r) throw Error(r.status());
          regen = std::move(*r);
        }
        nlohmann::json per = nlohmann::json::object();
        for (const DetailJob& d : job.details) {
          nlohmann::json q;
          const std::vector<Vec3d> g = regen_detail(job, d, body, q, inner);
          if (q["inside_nodes"].get<std::size_t>() > 0)
            throw Error(Status(ErrorCode::kDegenerate, d.name + ": " + q["inside_nodes"].dump() +
                                                           " vertices could not be pushed out of the body"));
          per[d.name] = std::move(q);
          if (index < opt.meshes) {
            fs::create_directories(bodies_dir / chunk.name(b));
            write_garment_obj(d.mesh, g, bodies_dir / chunk.name(b) / (d.name + ".obj"));
          }
        }
        for (std::size_t k = 0; k < templates.size(); ++k) {
          const ProfileTemplate& t = templates[k];
          const RegenResult& r = regen[k];
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
    for (const auto& d : job.details) names.push_back(d.name);
    rest["templates"] = names;
    rest["summary"] = {{"bodies", n},
                       {"completed", m.ok},
                       {"failed", m.failed},
                       {"inside_nodes_total", m.inside},
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
  int code = kExitOk;
  try {
    job.emplace(prepare_regen(common, opt));
    regen_share(common, opt, group, *job, log);
  } catch (const Error& e) {
    if (!group.distributed()) throw;
    log.error(who + e.what());
    code = exit_code_of(e);
  } catch (const std::exception& e) {
    if (!group.distributed()) throw;
    log.error(who + "internal error: " + e.what());
    code = kExitInternal;
  }
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
      const std::size_t n = job->src->size();
      std::printf(
          "atelier regen: %zu bodies x %zu templates: %zu complete (%zu now, %zu from an earlier run), %zu "
          "failed; %zu nodes inside, max crack %.1e m; %.1f s",
          n, job->templates.size() + job->details.size(), m.ok, done, skipped, m.failed, m.inside, m.crack, total_s);
      if (group.distributed()) std::printf(" on %d ranks", group.size());
      std::printf("\n  report: %s\n", fs::absolute(opt.out / "report.json").string().c_str());
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
