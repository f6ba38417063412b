#include <atelier/engine/parallel.h>
#include <atelier/io/atomic_file.h>
#include <atelier/io/makehuman/makehuman.h>
#include <atelier/systems/garment/fit_measure.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <atelier/systems/mesh/fan_triangulation.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>

namespace atelier {

namespace fs = std::filesystem;

namespace {

Status named(const std::string& name, const Status& s) {
  return {s.code(), name + ": " + s.message()};
}

/// The fit figures from each vertex's exact distance at its final position
/// (the pass's own last query of it, or a query when there is no pass).
GarmentQuality quality_of(const GarmentTemplate& g, std::span<const Vec3d> x,
                          std::span<const BodyDistance> final_distance, const CollisionParams& cp) {
  GarmentQuality q;
  const std::size_t n = x.size();
  q.vertices = n;
  q.min_clearance = std::numeric_limits<double>::infinity();
  double sum = 0;
  for (std::size_t v = 0; v < n; ++v) {
    const double sd = final_distance[v].distance;
    if (sd < 0) {
      ++q.inside;
      q.max_depth = std::max(q.max_depth, -sd);
    }
    q.min_clearance = std::min(q.min_clearance, sd);
    sum += sd;
    const double target = std::clamp(static_cast<double>(g.clearance.clearance[v]), cp.min_clearance, cp.max_clearance);
    q.clearance_error = std::max(q.clearance_error, std::abs(sd - target));
  }
  q.mean_clearance = n > 0 ? sum / static_cast<double>(n) : 0.0;
  std::vector<double> strain(g.edges.size());
  for (std::size_t e = 0; e < g.edges.size(); ++e) {
    const double l = (x[g.edges[e][0]] - x[g.edges[e][1]]).norm();
    strain[e] = g.rest_length[e] > 0 ? std::abs(l / g.rest_length[e] - 1.0) : 0.0;
    q.strain_max = std::max(q.strain_max, strain[e]);
  }
  q.strain_p95 = quantile_in_place(strain, 0.95);
  return q;
}

/// Garments in layer order (z_depth, ties in the order given).
std::vector<std::size_t> layer_order(std::span<const GarmentTemplate* const> garments) {
  std::vector<std::size_t> order(garments.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return garments[a]->z_depth < garments[b]->z_depth; });
  return order;
}

/// The BVH of layer k (in layer order) over its garment's fanned faces at
/// its final positions: committed once, when the layer is final, and shared
/// by the lift of every layer above it and by the penetration count (issue
/// 26: each built its own before, twice per lower garment and body).
Status commit_layer_bvh(std::span<const GarmentTemplate* const> garments, std::span<const std::size_t> order,
                        std::span<const std::vector<Vec3d>> positions, std::size_t k, std::vector<BodyBvh>& bvh) {
  if (bvh.size() != order.size()) bvh.resize(order.size());
  if (!bvh[k].empty()) return {};
  const std::size_t j = order[k];
  if (Status s = bvh[k].build(positions[j], fan_triangulate(garments[j]->mesh), {}, ExecContext::sequential()); !s) {
    bvh[k] = BodyBvh();
    return named(garments[j]->name, s);
  }
  return {};
}

/// After resolve_layers: its floor is the inner layers' clearance at their
/// vertices, and in a concave crease (the crotch) an inner garment's faces
/// span the crease farther out than its vertices, so an outer vertex can
/// end under them. Each such vertex (the test of count_inside_layer) is
/// lifted along the body normal to layer_gap above the lower garment's
/// surface, layers inner first, then its body distance is queried again.
/// `lower` receives the BVH of every layer but the outermost (see
/// commit_layer_bvh).
Status lift_layers(std::span<const GarmentTemplate* const> garments, const GarmentRegenOptions& options,
                   std::span<std::vector<Vec3d>> positions, std::span<std::vector<BodyDistance>> fin,
                   const CollisionBody& body, std::vector<BodyBvh>& lower) {
  const std::vector<std::size_t> order = layer_order(garments);
  const double probe = options.layer_penetration.probe, gap = options.collision.layer_gap;
  for (std::size_t l = 1; l < order.size(); ++l) {
    const std::size_t i = order[l];
    // Layer l - 1 is final now: its BVH serves every layer above it.
    if (Status s = commit_layer_bvh(garments, order, positions, l - 1, lower); !s) return s;
    auto lifted = atelier::lift_over_lower_layers(positions[i], fin[i], std::span<const BodyBvh>(lower.data(), l), body,
                                                  probe, gap);
    if (!lifted) return named(garments[i]->name, lifted.status());
  }
  return {};
}

/// Each garment's vertices inside a garment of a lower layer (z_depth
/// order, ties in the order given, as resolve_layers orders them): one BVH
/// over each inner garment's triangles (faces fanned; those the lift
/// committed are reused, the others committed here), rays from the outer
/// vertices' closest body points (count_inside_layer).
Status count_layer_penetration(std::span<const GarmentTemplate* const> garments, const GarmentRegenOptions& options,
                               std::span<const std::vector<Vec3d>> positions, std::vector<GarmentResult>& results,
                               std::span<const std::vector<BodyDistance>> fin, std::vector<BodyBvh>& lower,
                               const ExecContext& ctx) {
  const std::size_t ng = garments.size();
  const std::vector<std::size_t> order = layer_order(garments);
  std::vector<std::vector<std::uint8_t>> flags(ng);
  for (std::size_t k = 0; k < ng; ++k) flags[order[k]].assign(positions[order[k]].size(), 0);
  std::vector<std::uint8_t> inside;
  for (std::size_t k = 0; k + 1 < ng; ++k) {
    if (Status s = commit_layer_bvh(garments, order, positions, k, lower); !s) return s;  // an inner layer
    const BodyBvh& bvh = lower[k];
    for (std::size_t l = k + 1; l < ng; ++l) {  // every layer above it
      const std::size_t i = order[l];
      auto n = count_inside_layer(positions[i], fin[i], bvh, options.layer_penetration, &inside);
      if (!n) return named(garments[i]->name, n.status());
      for (std::size_t v = 0; v < inside.size(); ++v) flags[i][v] |= inside[v];
    }
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "garment regeneration: cancelled");
  }
  for (std::size_t i = 0; i < ng; ++i)
    results[i].quality.layer_inside =
        static_cast<std::size_t>(std::count(flags[i].begin(), flags[i].end(), std::uint8_t{1}));
  return {};
}

/// Edge transfer, collision pass (with layers) and fit figures of one
/// body's decoded garments; sequential (the caller parallelises over bodies).
BodyGarments finish_body(const GarmentFamily& fam, std::span<const GarmentTemplate* const> garments,
                         const GarmentRegenOptions& options, std::span<const Vec3d> body,
                         std::vector<std::vector<Vec3d>> decoded, const ExecContext& ctx) {
  BodyGarments out;
  const std::size_t ng = garments.size();
  if (options.edge_transfer)
    for (std::size_t i = 0; i < ng; ++i)
      if (Status s = apply_edge_transfer(garments[i]->transfer, body, fam.collision->triangles(), decoded[i], ctx);
          !s) {
        out.status = named(garments[i]->name, s);
        return out;
      }
  CollisionBody cb;
  if (Status s = cb.build(fam.collision, body, {}, ctx); !s) {
    out.status = s;
    return out;
  }
  std::vector<std::vector<BodyDistance>> fin(ng);
  std::vector<CollisionReport> reports(ng);
  std::vector<BodyBvh> lower;  // per layer (layer order), at its final positions; shared by the lift and the count
  if (!options.collision_pass) {
    for (std::size_t i = 0; i < ng; ++i) {
      fin[i].resize(decoded[i].size());
      if (Status s = cb.query_many(decoded[i], garments[i]->clearance.triangle, fin[i], ctx); !s) {
        out.status = named(garments[i]->name, s);
        return out;
      }
    }
  } else if (ng == 1 || !options.layers) {
    for (std::size_t i = 0; i < ng; ++i) {
      const GarmentTemplate& g = *garments[i];
      auto pass = resolve_collisions(decoded[i], g.adjacency, g.clearance, cb, options.collision, fin[i], ctx);
      if (!pass) {
        out.status = named(g.name, pass.status());
        return out;
      }
      reports[i] = *pass;
    }
  } else {
    std::vector<GarmentLayer> layers(ng);
    for (std::size_t i = 0; i < ng; ++i)
      layers[i] = {decoded[i], &garments[i]->adjacency, &garments[i]->clearance, garments[i]->z_depth, &fin[i]};
    auto pass = resolve_layers(layers, cb, options.collision, ctx);
    if (!pass) {
      out.status = pass.status();
      return out;
    }
    reports = std::move(*pass);
    if (Status s = lift_layers(garments, options, decoded, fin, cb, lower); !s) {
      out.status = s;
      return out;
    }
  }
  out.garments.resize(ng);
  for (std::size_t i = 0; i < ng; ++i) {
    for (const Vec3d& p : decoded[i])
      if (!is_finite(p)) {
        out.status = Status(ErrorCode::kDegenerate, garments[i]->name + ": a regenerated vertex is not finite");
        out.garments.clear();
        return out;
      }
    GarmentResult& r = out.garments[i];
    r.quality = quality_of(*garments[i], decoded[i], fin[i], options.collision);
    r.quality.pass = reports[i];
    r.quality.pushed = reports[i].pushed;
  }
  if (options.layers && ng > 1)
    if (Status s = count_layer_penetration(garments, options, decoded, out.garments, fin, lower, ctx); !s) {
      out.status = s;
      out.garments.clear();
      return out;
    }
  for (std::size_t i = 0; i < ng; ++i) out.garments[i].positions = std::move(decoded[i]);
  return out;
}

}  // namespace

// ------------------------------------------------------------ family, templates

Expected<GarmentFamily> GarmentFamily::of(const ReferenceBody& reference) {
  GarmentFamily f;
  f.polygons = BodyPolygons::from_model(reference.model);
  auto tris = fan_triangulate(reference.model);
  if (!tris) return tris.status();
  auto topo =
      CollisionTopology::build(tris->triangles, static_cast<std::uint32_t>(reference.model.nodes.slots.capacity()));
  if (!topo) return Status(topo.status().code(), "reference body: " + topo.status().message());
  f.collision = std::move(*topo);
  f.reference_positions = skin_positions(reference);
  return f;
}

Expected<GarmentTemplate> encode_garment(const GarmentFamily& family, std::string name, PolygonSoup mesh,
                                         DetailEncoding encoding, const GarmentEncodeOptions& options,
                                         const ExecContext& ctx) {
  if (mesh.positions.empty()) return Status(ErrorCode::kInvalidArgument, name + ": the garment has no vertices");
  if (mesh.face_count() == 0) return Status(ErrorCode::kInvalidArgument, name + ": the garment has no faces");
  if (Status s = mesh.check(); !s) return named(name, s);
  if (Status s = check_topology(encoding, family.polygons); !s)
    return Status(ErrorCode::kMismatch, name + ": encoded on another reference body (" + s.message() + ")");
  if (encoding.vertex_count() != mesh.positions.size())
    return Status(ErrorCode::kMismatch, name + ": the encoding has " + std::to_string(encoding.vertex_count()) +
                                            " vertices, the garment " + std::to_string(mesh.positions.size()));
  GarmentTemplate g;
  g.name = std::move(name);
  g.encoding = std::move(encoding);
  if (options.edges.empty())
    g.edges = mesh.edges();
  else
    g.edges.assign(options.edges.begin(), options.edges.end());
  g.rest_length.reserve(g.edges.size());
  for (const auto& e : g.edges) {
    if (e[0] >= mesh.positions.size() || e[1] >= mesh.positions.size())
      return Status(ErrorCode::kInvalidArgument, g.name + ": an edge uses a vertex out of range");
    g.rest_length.push_back((mesh.positions[e[0]] - mesh.positions[e[1]]).norm());
  }
  auto adj = adjacency_from_edges(mesh.positions.size(), g.edges);
  if (!adj) return named(g.name, adj.status());
  g.adjacency = std::move(*adj);
  // Where the garment sits on the reference body: what the collision pass
  // restores on every other body.
  CollisionBody reference;
  if (Status s = reference.build(family.collision, family.reference_positions, {}, ctx); !s) return named(g.name, s);
  auto clear = encode_clearance(mesh.positions, reference, ctx);
  if (!clear) return named(g.name, clear.status());
  g.clearance = std::move(*clear);
  auto transfer = encode_edge_transfer(mesh.positions, g.edges, reference, options.transfer, ctx);
  if (!transfer) return named(g.name, transfer.status());
  g.transfer = std::move(*transfer);
  g.mesh = std::move(mesh);
  return g;
}

Expected<GarmentTemplate> encode_garment(const GarmentFamily& family, std::string name, PolygonSoup mesh,
                                         const GarmentEncodeOptions& options, const ExecContext& ctx) {
  auto enc = encode_detail(family.polygons, family.reference_positions, mesh.positions, options.detail, ctx);
  if (!enc) return named(name, enc.status());
  return encode_garment(family, std::move(name), std::move(mesh), std::move(*enc), options, ctx);
}

Expected<PolygonSoup> read_garment_mesh(const fs::path& file, double scale) {
  if (!(scale > 0) || !std::isfinite(scale))
    return Status(ErrorCode::kInvalidArgument, file.string() + ": the scale must be a positive number");
  makehuman::BaseMesh m;
  try {
    m = makehuman::read_base_mesh(file);
  } catch (const Error& e) {
    return e.status();
  }
  PolygonSoup g;
  g.positions.reserve(m.positions.size());
  for (const Vec3f& p : m.positions) g.positions.push_back(scale * p.cast<double>());
  for (const auto& grp : m.groups) {
    for (std::size_t f = 0; f < grp.face_count(); ++f) g.add_face(grp.face(f));
    g.corner_uv.insert(g.corner_uv.end(), grp.corner_uv.begin(), grp.corner_uv.end());  // all or none (read_base_mesh)
  }
  if (g.positions.empty()) return Status(ErrorCode::kInvalidArgument, file.string() + ": no vertices");
  if (g.face_nodes.empty()) return Status(ErrorCode::kInvalidArgument, file.string() + ": no faces");
  return g;
}

void write_garment_mesh(const PolygonSoup& g, std::span<const Vec3d> positions, const fs::path& file) {
  // Texture coordinates per corner (seams kept), written once per distinct
  // value in first-use order: the uv map does not move with the body.
  const bool has_uv = !g.corner_uv.empty() && g.corner_uv.size() == g.face_nodes.size();
  std::vector<std::uint32_t> vt_of(has_uv ? g.corner_uv.size() : 0);
  std::vector<Vec2d> vt;
  if (has_uv) {
    std::map<std::pair<double, double>, std::uint32_t> index;
    for (std::size_t k = 0; k < g.corner_uv.size(); ++k) {
      const auto [it, inserted] =
          index.try_emplace({g.corner_uv[k].x(), g.corner_uv[k].y()}, static_cast<std::uint32_t>(vt.size()));
      if (inserted) vt.push_back(g.corner_uv[k]);
      vt_of[k] = it->second;
    }
  }
  write_atomically(file, [&](AtomicFile& f) {
    char line[128];
    for (const Vec3d& p : positions) {
      const int n =
          std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", static_cast<double>(static_cast<float>(p.x())),
                        static_cast<double>(static_cast<float>(p.y())), static_cast<double>(static_cast<float>(p.z())));
      f.write(line, static_cast<std::size_t>(n));
    }
    for (const Vec2d& t : vt) {
      const int n = std::snprintf(line, sizeof line, "vt %.9g %.9g\n", static_cast<double>(static_cast<float>(t.x())),
                                  static_cast<double>(static_cast<float>(t.y())));
      f.write(line, static_cast<std::size_t>(n));
    }
    std::string face;
    for (std::size_t k = 0; k < g.face_count(); ++k) {
      face = "f";
      for (std::uint32_t c = g.face_offsets[k]; c < g.face_offsets[k + 1]; ++c) {
        face += " " + std::to_string(g.face_nodes[c] + 1);
        if (has_uv) face += "/" + std::to_string(vt_of[c] + 1);
      }
      face += "\n";
      f.write(face);
    }
  });
}

Expected<GarmentTemplate> read_garment_template(const GarmentFamily& family, const fs::path& atd,
                                                const ExecContext& ctx) {
  if (!fs::exists(atd)) return Status(ErrorCode::kIo, atd.string() + ": no such file");
  DetailEncoding enc;
  try {
    enc = read_detail(atd);
  } catch (const Error& e) {
    return e.status();
  }
  if (Status s = check_topology(enc, family.polygons); !s)
    return Status(ErrorCode::kMismatch, atd.string() + ": encoded on another reference body (" + s.message() +
                                            "); encode the garment on this reference with `atelier encode --garment`");
  fs::path mesh_file = atd;
  mesh_file.replace_extension(".obj");
  if (!fs::exists(mesh_file))
    return Status(ErrorCode::kIo, atd.string() + ": its garment mesh " + mesh_file.string() +
                                      " is missing (`atelier encode --garment` writes both)");
  auto mesh = read_garment_mesh(mesh_file);
  if (!mesh) return mesh.status();
  if (mesh->positions.size() != enc.vertex_count())
    return Status(ErrorCode::kMismatch, mesh_file.string() + " has " + std::to_string(mesh->positions.size()) +
                                            " vertices, " + atd.string() + " encodes " +
                                            std::to_string(enc.vertex_count()));
  auto g = encode_garment(family, atd.stem().string(), std::move(*mesh), std::move(enc), {}, ctx);
  if (!g) return Status(g.status().code(), mesh_file.string() + ": " + g.status().message());
  g->z_depth = g->encoding.z_depth.value_or(0);  // the .atd's layer order when it has one
  return g;
}

Expected<PolygonSoup> read_garment_mesh(const fs::path& file, const BodyFrame& frame) {
  if (Status s = frame.check(); !s) return Status(s.code(), file.string() + ": " + s.message());
  auto mesh = read_garment_mesh(file);
  if (!mesh) return mesh;
  // At the door: file units and axes to metres and Y up.
  for (std::size_t v = 0; v < mesh->positions.size(); ++v) {
    mesh->positions[v] = frame.to_engine(mesh->positions[v]);
    if (!mesh->positions[v].allFinite())
      return Status(ErrorCode::kDegenerate,
                    file.string() + ": vertex " + std::to_string(v + 1) + " is not finite in metres");
  }
  return mesh;
}

Expected<GarmentTemplate> encode_garment_file(const ReferenceBody& reference, const fs::path& garment,
                                              const GarmentFileOptions& options, const ExecContext& ctx) {
  const std::string file = garment.string();
  if (Status s = options.frame.check(); !s) return Status(s.code(), file + ": " + s.message());
  std::error_code ec;
  if (!fs::is_regular_file(garment, ec)) return Status(ErrorCode::kIo, file + ": no such file");
  auto mesh = read_garment_mesh(garment, options.frame);
  if (!mesh) return mesh.status();
  // Float, as the template's .obj keeps it.
  for (Vec3d& p : mesh->positions) p = round_to_float(p);
  auto family = GarmentFamily::of(reference);
  if (!family) return Status(family.status().code(), file + ": " + family.status().message());
  auto t = encode_garment(*family, garment.stem().string(), std::move(*mesh), options.encode, ctx);
  if (!t) return Status(t.status().code(), file + ": " + t.status().message());
  return t;
}

void write_garment_template(const GarmentTemplate& garment, const fs::path& dir) {
  fs::create_directories(dir);
  write_garment_mesh(garment.mesh, garment.mesh.positions, dir / (garment.name + ".obj"));
  write_detail(garment.encoding, dir / (garment.name + ".atd"));  // last: the template is complete with its mesh
}

// ------------------------------------------------------------ the pipeline

Expected<GarmentRegenerator> GarmentRegenerator::create(std::shared_ptr<const GarmentFamily> family,
                                                        std::vector<std::shared_ptr<const GarmentTemplate>> garments,
                                                        const GarmentRegenOptions& options, const ExecContext& ctx) {
  if (!family) return Status(ErrorCode::kInvalidArgument, "garment regeneration: no body family");
  if (garments.empty()) return Status(ErrorCode::kInvalidArgument, "garment regeneration: no garments");
  GarmentRegenerator r;
  for (const auto& g : garments) {
    if (!g) return Status(ErrorCode::kInvalidArgument, "garment regeneration: a null garment");
    if (Status s = check_topology(g->encoding, family->polygons); !s) return named(g->name, s);
    r.decoders_.push_back(std::make_shared<const DetailDecoder>(g->encoding, ctx));
  }
  r.family_ = std::move(family);
  r.garments_ = std::move(garments);
  r.options_ = options;
  r.workspace_.resize(r.garments_.size());
  for (auto& ws : r.workspace_) ws.allow = options.kernel;
  return r;
}

Status GarmentRegenerator::run(const BodySet& bodies, std::size_t first, std::size_t count,
                               std::vector<BodyGarments>& out, const ExecContext& ctx) {
  if (!family_) return Status(ErrorCode::kInvalidArgument, "garment regeneration: not created");
  if (first > bodies.size() || count > bodies.size() - first)
    return Status(ErrorCode::kInvalidArgument, "garment regeneration: bodies [" + std::to_string(first) + ", " +
                                                   std::to_string(first + count) + ") of a set of " +
                                                   std::to_string(bodies.size()));
  out.assign(count, {});
  if (count == 0) return {};
  // 1. Decoding, 16 bodies per pass over each garment's matrix.
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::size_t> offset(garments_.size() + 1, 0);
  for (std::size_t i = 0; i < garments_.size(); ++i)
    offset[i + 1] = offset[i] + count * garments_[i]->mesh.positions.size();
  decoded_.resize(offset.back());
  for (std::size_t i = 0; i < garments_.size(); ++i) {
    const std::span<Vec3f> dst(decoded_.data() + offset[i], offset[i + 1] - offset[i]);
    if (Status s = decode_detail_batch(*decoders_[i], family_->polygons, bodies, first, count, dst, workspace_[i], ctx);
        !s)
      return named(garments_[i]->name, s);
  }
  decode_ms_per_body_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
                        static_cast<double>(count);
  // 2-4. Tiles of kTransferTile bodies in parallel: the tile's edge
  // transfer with bodies as SIMD lanes (each body the bits it has alone),
  // then per body the collision pass and the figures. Sequential within a
  // tile, and tiles do not depend on the thread count: the same bits for
  // any thread count.
  constexpr std::size_t kTransferTile = 16;
  const std::size_t ng = garments_.size();
  const std::vector<const GarmentTemplate*> raw = raw_garments();
  GarmentRegenOptions after = options_;
  const bool lanes = options_.edge_transfer;
  if (lanes) after.edge_transfer = false;  // done for the tile
  ExecContext per_tile = ctx;
  per_tile.sequential_threshold = 2;
  per_tile.grain = 1;
  par::for_each_n(per_tile, (count + kTransferTile - 1) / kTransferTile, [&](std::size_t tile) {
    ExecContext inner = ExecContext::sequential();
    inner.cancel = ctx.cancel;
    const std::size_t b0 = tile * kTransferTile, nb = std::min(kTransferTile, count - b0);
    if (ctx.cancelled()) {
      for (std::size_t b = b0; b < b0 + nb; ++b)
        out[b].status = Status(ErrorCode::kCancelled, "garment regeneration cancelled");
      return;
    }
    std::vector<std::vector<Vec3d>> body(nb);
    std::vector<std::vector<std::vector<Vec3d>>> g(nb, std::vector<std::vector<Vec3d>>(ng));
    for (std::size_t k = 0; k < nb; ++k) {
      body[k] = bodies.positions(first + b0 + k);
      for (std::size_t i = 0; i < ng; ++i) {
        const std::size_t nv = garments_[i]->mesh.positions.size();
        g[k][i].resize(nv);
        const Vec3f* src = decoded_.data() + offset[i] + (b0 + k) * nv;
        for (std::size_t v = 0; v < nv; ++v) g[k][i][v] = src[v].cast<double>();
      }
    }
    std::vector<Status> transferred(nb);  // per body: the first error of its garments' transfers, else ok
    if (lanes) {
      std::vector<std::span<const Vec3d>> bs(body.begin(), body.end());
      std::vector<std::span<Vec3d>> gs(nb);
      std::vector<Status> st(nb);
      for (std::size_t i = 0; i < ng; ++i) {
        for (std::size_t k = 0; k < nb; ++k) gs[k] = g[k][i];
        const Status call = apply_edge_transfer_bodies(garments_[i]->transfer, bs, family_->collision->triangles(), gs,
                                                       st, EdgeTransferKernel::kAuto);
        for (std::size_t k = 0; k < nb; ++k)
          if (transferred[k] && !(call && st[k])) transferred[k] = named(garments_[i]->name, call ? st[k] : call);
      }
    }
    for (std::size_t k = 0; k < nb; ++k) {
      if (!transferred[k]) {
        out[b0 + k].status = transferred[k];
        continue;
      }
      out[b0 + k] = finish_body(*family_, raw, after, body[k], std::move(g[k]), inner);
    }
  });
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "garment regeneration cancelled");
  return {};
}

std::vector<const GarmentTemplate*> GarmentRegenerator::raw_garments() const {
  std::vector<const GarmentTemplate*> g;
  for (const auto& p : garments_) g.push_back(p.get());
  return g;
}

BodyGarments GarmentRegenerator::run_one(std::span<const Vec3d> body, const ExecContext& ctx) const {
  BodyGarments out;
  if (!family_) {
    out.status = Status(ErrorCode::kInvalidArgument, "garment regeneration: not created");
    return out;
  }
  std::vector<std::vector<Vec3d>> g(garments_.size());
  for (std::size_t i = 0; i < garments_.size(); ++i) {
    g[i].resize(garments_[i]->mesh.positions.size());
    if (Status s = decode_detail(garments_[i]->encoding, family_->polygons, body, g[i], ctx); !s) {
      out.status = named(garments_[i]->name, s);
      return out;
    }
  }
  return finish_body(*family_, raw_garments(), options_, body, std::move(g), ctx);
}

Expected<GarmentResult> regenerate_garment(const GarmentFamily& family, const GarmentTemplate& garment,
                                           std::span<const Vec3d> body, const GarmentRegenOptions& options,
                                           const ExecContext& ctx) {
  if (Status s = check_topology(garment.encoding, family.polygons); !s) return named(garment.name, s);
  std::vector<std::vector<Vec3d>> g(1, std::vector<Vec3d>(garment.mesh.positions.size()));
  if (Status s = decode_detail(garment.encoding, family.polygons, body, g[0], ctx); !s) return named(garment.name, s);
  const GarmentTemplate* one[] = {&garment};
  BodyGarments b = finish_body(family, one, options, body, std::move(g), ctx);
  if (!b.status) return b.status;
  return std::move(b.garments.front());
}

}  // namespace atelier
