// Extrusion recipes: see extrude_recipe.h. The frame is computed the same
// way when recording and replaying, so that on the recording model the
// round trip F (F^T R F) F^T is R to rounding.
#include <atelier/systems/sketch/extrude_recipe.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "extrude_detail.h"

namespace atelier {

namespace {

using extrude_detail::fail;

struct Frame {
  Vec3d p1, p2;
  double chord = 0;
  Mat3d f;  // columns n_p, e, n_p x e
  Vec3d n_b;
  double mean_edge = 0;
};

Vec3d at(const std::vector<Vec3d>& b, bool ring, std::uint32_t s, double t) {
  const Vec3d& a = b[s];
  const Vec3d& c = b[ring ? (s + 1) % b.size() : s + 1];
  return a + t * (c - a);
}

/// n_B: the least-squares normal (as extrude's step 2), turned to agree
/// with B's Newell normal. P1*, P2* from their segments. kDegenerate as
/// extrude's.
Expected<Frame> frame(const std::vector<Vec3d>& b, bool ring, std::uint32_t s1, double t1, std::uint32_t s2,
                      double t2) {
  Frame fr;
  const std::size_t n = b.size();
  Vec3d centroid = Vec3d::Zero();
  for (const Vec3d& p : b) centroid += p;
  centroid /= static_cast<double>(n);
  Mat3d cov = Mat3d::Zero();
  for (const Vec3d& p : b) cov += (p - centroid) * (p - centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Mat3d> eig(cov);
  const Vec3d ev = eig.eigenvalues();
  if (!(ev[2] > 0) || !(ev[1] > 1e-12 * ev[2]))
    return fail(ErrorCode::kDegenerate, "the base curve's least-squares plane has no area (B is straight)");
  fr.n_b = eig.eigenvectors().col(0).normalized();
  Vec3d newell = Vec3d::Zero();
  for (std::size_t i = 0; i < n; ++i) newell += (b[i] - centroid).cross(b[(i + 1) % n] - centroid);
  if (newell.dot(fr.n_b) < 0) fr.n_b = -fr.n_b;
  double sum = 0;
  const std::size_t segs = ring ? n : n - 1;
  for (std::size_t i = 0; i < segs; ++i) sum += (b[(i + 1) % n] - b[i]).norm();
  fr.mean_edge = sum / static_cast<double>(segs);
  fr.p1 = at(b, ring, s1, t1);
  fr.p2 = at(b, ring, s2, t2);
  const Vec3d e = fr.p2 - fr.p1;
  fr.chord = e.norm();
  if (!(fr.chord > 1e-12 * (1 + centroid.norm())))
    return fail(ErrorCode::kDegenerate, "P1* and P2* coincide on this base curve");
  Vec3d np = e.cross(fr.n_b);
  if (!(np.norm() > 1e-6 * fr.chord)) return fail(ErrorCode::kDegenerate, "P1*P2* is parallel to the normal of B");
  np.normalize();
  const Vec3d u = e / fr.chord;
  fr.f << np, u, np.cross(u);
  return fr;
}

Mat3d signed_frame(const Frame& fr, double sign) {
  Mat3d F = fr.f;
  F.col(0) *= sign;
  F.col(2) = F.col(0).cross(F.col(1));
  return F;
}

std::vector<Vec3d> positions(const Model& m, std::span<const std::uint32_t> base) {
  std::vector<Vec3d> b;
  for (std::uint32_t v : base) b.push_back(m.position(NodeIdx{v}));
  return b;
}

}  // namespace

namespace extrude_detail {

Status localise(const Model& m, ExtrusionRecipe& rc, const ExtrudeReport& rep) {
  const std::vector<Vec3d> b = positions(m, rc.base);
  auto fr = frame(b, rc.ring, rc.p1_segment, rc.p1_t, rc.p2_segment, rc.p2_t);
  if (!fr) return fr.status();
  // The sign that makes the frame's n_p the one extrude used (towards its camera).
  rc.normal_sign = fr->f.col(0).dot(rep.plane_normal) < 0 ? -1.0 : 1.0;
  const Mat3d F = signed_frame(*fr, rc.normal_sign);
  rc.scales.clear(), rc.rotations.clear(), rc.translations.clear();
  for (std::size_t k = 0; k < rep.scales.size(); ++k) {
    const double s = rep.scales[k];
    const Mat3d& R = rep.rotations[k];
    rc.scales.push_back(s);
    rc.rotations.push_back(F.transpose() * R * F);
    rc.translations.push_back(F.transpose() * (rep.translations[k] + s * (R * fr->p1) - fr->p1) / fr->chord);
  }
  return {};
}

Status place_copies(const Model& m, const ExtrusionRecipe& rc, ExtrudeReport& rep,
                    std::vector<std::vector<Vec3d>>& copies) {
  const std::vector<Vec3d> b = positions(m, rc.base);
  auto fr = frame(b, rc.ring, rc.p1_segment, rc.p1_t, rc.p2_segment, rc.p2_t);
  if (!fr) return fr.status();
  const Mat3d F = signed_frame(*fr, rc.normal_sign);
  rep.base_mean_edge = fr->mean_edge;
  rep.plane_normal = F.col(0);
  rep.p1 = fr->p1;
  rep.p2 = fr->p2;
  rep.scales.clear(), rep.rotations.clear(), rep.translations.clear();
  copies.clear();
  const std::size_t k_count = rc.scales.size();
  for (std::size_t k = 0; k < k_count; ++k) {
    const double s = rc.scales[k];
    const Mat3d R = F * rc.rotations[k] * F.transpose();
    const Vec3d t = fr->p1 + fr->chord * (F * rc.translations[k]) - s * (R * fr->p1);
    rep.scales.push_back(s);
    rep.rotations.push_back(R);
    rep.translations.push_back(t);
    std::vector<Vec3d> row;
    if (rc.capped && k + 1 == k_count) {
      row.push_back(t);
    } else {
      for (const Vec3d& p : b) row.push_back(t + s * (R * p));
    }
    for (const Vec3d& p : row)
      if (!p.allFinite()) return fail(ErrorCode::kDegenerate, "a copy of B is not finite");
    copies.push_back(std::move(row));
  }
  rep.copies = copies.size();
  return {};
}

}  // namespace extrude_detail

Expected<ExtrusionRecipe> extrusion_recipe(const Model& m, const ExtrudeReport& r) {
  if (r.mirrored)
    return fail(ErrorCode::kUnsupported, "recipe: a mirrored pair (record the single extrusion and replay it twice)");
  if (r.faces_removed > 0)
    return fail(ErrorCode::kUnsupported,
                "recipe: the base curve was painted and cut; its nodes exist on no other model (record an "
                "extrusion from a boundary: a hem, an armhole, a neckline)");
  const ExtrusionRecipe& rc = r.recipe;
  if (rc.base.size() < 2 || rc.scales.empty() || rc.scales.size() != r.copies)
    return fail(ErrorCode::kInvalidArgument, "recipe: the report holds no base curve or no copies");
  for (std::uint32_t v : rc.base)
    if (v >= m.nodes.slots.capacity() || !m.alive(NodeIdx{v}))
      return fail(ErrorCode::kInvalidArgument, "recipe: base node " + std::to_string(v) + " is dead");
  return rc;
}

Expected<ExtrudeReport> replay_extrusion(Model& model, const ExtrusionRecipe& rc, const ExtrudeOptions& opt,
                                         const ExecContext& ctx) {
  Model& m = model;
  if (opt.mirror) return fail(ErrorCode::kInvalidArgument, "replay: options.mirror is not supported");
  const std::size_t n = rc.base.size(), k_count = rc.scales.size();
  if (n < (rc.ring ? 3u : 2u)) return fail(ErrorCode::kInvalidArgument, "replay: the base curve has too few nodes");
  if (k_count == 0 || rc.rotations.size() != k_count || rc.translations.size() != k_count)
    return fail(ErrorCode::kInvalidArgument, "replay: no copies, or copy tables of different sizes");
  const std::size_t segs = rc.ring ? n : n - 1;
  if (rc.p1_segment >= segs || rc.p2_segment >= segs || !(rc.p1_t >= 0 && rc.p1_t <= 1) ||
      !(rc.p2_t >= 0 && rc.p2_t <= 1) || !(std::abs(rc.normal_sign) == 1))
    return fail(ErrorCode::kInvalidArgument, "replay: P1*, P2* or the normal's sign out of range");
  for (std::size_t k = 0; k < k_count; ++k)
    if (!std::isfinite(rc.scales[k]) || rc.scales[k] < 0 || !rc.rotations[k].allFinite() ||
        !rc.translations[k].allFinite())
      return fail(ErrorCode::kInvalidArgument, "replay: copy " + std::to_string(k + 1) + " is not finite");
  if (opt.body && (!(opt.clearance >= 0) || !std::isfinite(opt.clearance) || opt.push_rounds < 1))
    return fail(ErrorCode::kInvalidArgument, "the clearance must be finite and >= 0, push_rounds >= 1");
  if (opt.body && opt.body->empty()) return fail(ErrorCode::kInvalidArgument, "the body is empty");
  ExtrudeReport rep;
  for (std::size_t i = 0; i < n; ++i) {
    const NodeIdx v{rc.base[i]};
    if (v.value >= m.nodes.slots.capacity() || !m.alive(v))
      return fail(ErrorCode::kInvalidArgument,
                  "replay: base node " + std::to_string(i) + " (" + std::to_string(v.value) + ") is not a live node");
    rep.base.push_back(v);
  }
  for (std::size_t i = 0; i < segs; ++i) {
    const HalfedgeIdx h = m.find_halfedge(rep.base[i], rep.base[(i + 1) % n]);
    if (!h.valid() || m.face(h).valid())
      return fail(ErrorCode::kInvalidArgument, "replay: base nodes " + std::to_string(rc.base[i]) + " and " +
                                                   std::to_string(rc.base[(i + 1) % n]) +
                                                   " are not joined by a boundary edge of this model");
  }
  rep.base_ring = rc.ring;
  rep.capped = rc.capped;
  rep.recipe = rc;
  std::vector<std::vector<Vec3d>> copies;
  if (Status s = extrude_detail::place_copies(m, rc, rep, copies); !s) return s;
  {
    const std::vector<Vec3d> b = positions(m, rc.base);
    if (auto fr = frame(b, rc.ring, rc.p1_segment, rc.p1_t, rc.p2_segment, rc.p2_t)) rep.base_normal = fr->n_b;
  }
  Model backup = m;  // transactional
  auto r = extrude_detail::finish(m, std::move(rep), rc.ring, copies, opt, ctx, nullptr,
                                  extrude_detail::signed_volume(m));
  if (!r) m = std::move(backup);
  return r;
}

std::string extrusion_recipe_json(const ExtrusionRecipe& r) {
  nlohmann::json j;
  j["format"] = "atelier extrusion recipe";
  j["version"] = 1;
  j["base"] = r.base;
  j["ring"] = r.ring;
  j["capped"] = r.capped;
  j["p1"] = {r.p1_segment, r.p1_t};
  j["p2"] = {r.p2_segment, r.p2_t};
  j["normal_sign"] = r.normal_sign;
  nlohmann::json copies = nlohmann::json::array();
  for (std::size_t k = 0; k < r.scales.size(); ++k) {
    nlohmann::json c;
    c["scale"] = r.scales[k];
    c["rotation"] = std::vector<double>(r.rotations[k].data(), r.rotations[k].data() + 9);  // column-major
    c["translation"] = {r.translations[k].x(), r.translations[k].y(), r.translations[k].z()};
    copies.push_back(std::move(c));
  }
  j["copies"] = std::move(copies);
  return j.dump(1) + "\n";
}

Expected<ExtrusionRecipe> parse_extrusion_recipe(std::string_view text, const std::string& source) {
  auto bad = [&](const std::string& what) {
    return Status(ErrorCode::kInvalidArgument, source + ": extrusion recipe: " + what);
  };
  const nlohmann::json j = nlohmann::json::parse(text.begin(), text.end(), nullptr, false);
  if (j.is_discarded() || !j.is_object()) return bad("not a JSON object");
  if (j.value("format", std::string()) != "atelier extrusion recipe") return bad("\"format\" is not \"atelier extrusion recipe\"");
  ExtrusionRecipe r;
  try {
    r.base = j.at("base").get<std::vector<std::uint32_t>>();
    r.ring = j.at("ring").get<bool>();
    r.capped = j.at("capped").get<bool>();
    const auto& p1 = j.at("p1");
    const auto& p2 = j.at("p2");
    if (!p1.is_array() || p1.size() != 2 || !p2.is_array() || p2.size() != 2)
      return bad("\"p1\" and \"p2\" must be [segment, t]");
    r.p1_segment = p1[0].get<std::uint32_t>(), r.p1_t = p1[1].get<double>();
    r.p2_segment = p2[0].get<std::uint32_t>(), r.p2_t = p2[1].get<double>();
    r.normal_sign = j.at("normal_sign").get<double>();
    const auto& copies = j.at("copies");
    if (!copies.is_array()) return bad("\"copies\" must be an array");
    for (std::size_t k = 0; k < copies.size(); ++k) {
      const auto rot = copies[k].at("rotation").get<std::vector<double>>();
      const auto tr = copies[k].at("translation").get<std::vector<double>>();
      if (rot.size() != 9 || tr.size() != 3)
        return bad("copy " + std::to_string(k) + ": a rotation of 9 numbers and a translation of 3 needed");
      r.scales.push_back(copies[k].at("scale").get<double>());
      r.rotations.push_back(Eigen::Map<const Mat3d>(rot.data()));
      r.translations.push_back(Vec3d(tr[0], tr[1], tr[2]));
    }
  } catch (const nlohmann::json::exception& e) {
    return bad(e.what());
  }
  if (!std::isfinite(r.p1_t) || !std::isfinite(r.p2_t) || !std::isfinite(r.normal_sign)) return bad("a number is not finite");
  for (std::size_t k = 0; k < r.scales.size(); ++k)
    if (!std::isfinite(r.scales[k]) || !r.rotations[k].allFinite() || !r.translations[k].allFinite())
      return bad("copy " + std::to_string(k) + " is not finite");
  return r;
}

}  // namespace atelier
