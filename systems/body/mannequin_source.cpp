#include <atelier/systems/body/mannequin_source.h>

#include <cstdio>
#include <iomanip>
#include <map>
#include <sstream>

#include <atelier/engine/parallel.h>
#include <atelier/storage/builder.h>

namespace atelier {

MannequinSource::MannequinSource(std::shared_ptr<const MannequinTopology> topology, std::vector<MannequinParams> params,
                                 std::shared_ptr<const ReferenceBody> reference)
    : topology_(std::move(topology)), params_(std::move(params)), reference_(std::move(reference)) {}

MannequinSource::MannequinSource(std::shared_ptr<const MannequinTopology> topology, std::size_t count,
                                 std::uint64_t seed, std::shared_ptr<const ReferenceBody> reference)
    : topology_(std::move(topology)), sampled_(true), count_(count), seed_(seed), reference_(std::move(reference)) {}

std::string MannequinSource::body_name(std::size_t i) const {
  std::ostringstream s;
  s << "mannequin-" << std::setw(5) << std::setfill('0') << i;
  return s.str();
}

std::vector<std::pair<std::string, std::string>> MannequinSource::parameters(std::size_t i) const {
  const MannequinParams p = params(i);
  auto m = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4f", v);  // 0.1 mm
    return std::string(b);
  };
  std::vector<std::pair<std::string, std::string>> out;
  out.emplace_back("sampled_sex",
                   sampled_ ? (sample_mannequin_female(seed_, i) ? std::string("female") : std::string("male"))
                            : std::string());
  out.emplace_back("sampled_stature_m", m(p.height));
  for (const auto& [name, v] : {std::pair{"neck_girth", p.neck_girth}, std::pair{"bust_girth", p.bust_girth},
                                std::pair{"underbust_girth", p.underbust_girth}, std::pair{"waist_girth", p.waist_girth},
                                std::pair{"hip_girth", p.hip_girth}, std::pair{"thigh_girth", p.thigh_girth},
                                std::pair{"knee_girth", p.knee_girth}, std::pair{"ankle_girth", p.ankle_girth},
                                std::pair{"upper_arm_girth", p.upper_arm_girth},
                                std::pair{"shoulder_width", p.shoulder_width}, std::pair{"back_length", p.back_length},
                                std::pair{"inseam", p.inseam}})
    out.emplace_back(std::string("sampled_") + name + "_m", m(v));
  return out;
}

void MannequinSource::generate(std::size_t first, std::size_t count, BodySet& out, std::vector<BodyFailure>& failures,
                               const ExecContext& ctx) const {
  out.clear();
  const std::size_t end = std::min(size(), first + count);
  if (first >= end) return;
  std::vector<Expected<std::vector<Vec3d>>> bodies(end - first, Status(ErrorCode::kInternal, "not generated"));
  ExecContext c = ctx;
  c.sequential_threshold = 2;
  c.grain = 1;
  par::for_each_n(c, end - first, [&](std::size_t k) { bodies[k] = mannequin_positions(params(first + k), *topology_); });
  out.reserve(end - first);
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const std::size_t i = first + k;
    Status s = bodies[k] ? out.add(body_name(i), std::span<const Vec3d>(*bodies[k])) : bodies[k].status();
    if (!s) failures.push_back({i, body_name(i), s});
  }
}

Expected<Model> skin_band_garment(const ReferenceBody& body, double y_lo, double y_hi, double offset,
                                  double max_radius, const std::string& name) {
  const Model& m = body.model;
  std::vector<NodeIdx> fn;
  std::vector<std::uint32_t> faces;
  // Vertical axis through the centroid of the band.
  Vec3d axis = Vec3d::Zero();
  std::size_t na = 0;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}) && m.nodes.position[v].y() >= y_lo && m.nodes.position[v].y() <= y_hi) {
      axis += m.nodes.position[v];
      ++na;
    }
  if (na == 0) return Status(ErrorCode::kInvalidArgument, "skin_band_garment: no skin in the height band");
  axis /= static_cast<double>(na);
  auto ok = [&](NodeIdx v) {
    const Vec3d& p = m.position(v);
    return p.y() >= y_lo && p.y() <= y_hi && std::hypot(p.x() - axis.x(), p.z() - axis.z()) <= max_radius;
  };
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f}) || m.faces.surface[f] != body.skin) continue;
    m.face_nodes(FaceIdx{f}, fn);
    if (std::all_of(fn.begin(), fn.end(), ok)) faces.push_back(f);
  }
  if (faces.empty()) return Status(ErrorCode::kInvalidArgument, "skin_band_garment: no face in the band");
  // Area-weighted normals of the selected nodes (over all their skin faces).
  std::vector<Vec3d> normal(m.nodes.slots.capacity(), Vec3d::Zero());
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f}) || m.faces.surface[f] != body.skin) continue;
    m.face_nodes(FaceIdx{f}, fn);
    Vec3d n = Vec3d::Zero();
    for (std::size_t k = 0; k < fn.size(); ++k) n += m.position(fn[k]).cross(m.position(fn[(k + 1) % fn.size()]));
    for (NodeIdx v : fn) normal[v.value] += n;  // |n| = 2 area
  }
  std::map<std::uint32_t, std::uint32_t> local;
  std::vector<Vec3d> pos;
  std::vector<std::uint32_t> off{0}, idx;
  for (std::uint32_t f : faces) {
    m.face_nodes(FaceIdx{f}, fn);
    for (NodeIdx v : fn) {
      auto [it, inserted] = local.emplace(v.value, static_cast<std::uint32_t>(pos.size()));
      if (inserted) pos.push_back(m.position(v) + offset * normal[v.value].normalized());
      idx.push_back(it->second);
    }
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  }
  Model g;
  auto s = add_polygon_surface(g, name, {pos, off, idx});
  if (!s) return s.status();
  return g;
}

}  // namespace atelier
