#include <atelier/systems/profile/project_templates.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/mesh/fan_triangulation.h>

namespace atelier {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Status fail(const std::string& what) { return {ErrorCode::kInvalidArgument, what}; }

// Body-relative placement: feature-curve centroids and heights, rays from
// the body's axis to its skin, all on the reference body as it is.
class BodyProbe {
 public:
  static Expected<BodyProbe> make(const ReferenceBody& body) {
    BodyProbe p(body);
    auto t = fan_triangulate(body.model, std::vector<SurfaceIdx>{body.skin});
    if (!t) return t.status();
    p.tris_ = std::move(*t);
    if (Status s = p.bvh_.build(std::span<const Vec3d>(body.model.nodes.position), p.tris_.triangles); !s) return s;
    return p;
  }

  /// The first curve of `names` the body has (mannequin and MakeHuman names).
  Expected<std::vector<Vec3d>> curve(std::initializer_list<std::string_view> names) const {
    for (auto n : names)
      if (const FeatureCurve* c = body_->find_curve(n)) return feature_curve_polyline(*body_, c->id);
    return fail("reference body has no feature curve '" + std::string(*names.begin()) + "'");
  }
  static Vec3d centroid(const std::vector<Vec3d>& pl) {
    Vec3d c = Vec3d::Zero();
    for (const auto& q : pl) c += q;
    return c / static_cast<double>(pl.size());
  }

  /// The skin point hit by the ray from `origin` along `dir`, moved `ease`
  /// along the outward normal there.
  Expected<Vec3d> hit(const Vec3d& origin, const Vec3d& dir, double ease) const {
    const RayHit h = bvh_.ray_first_hit(origin, dir.normalized());
    if (!h.hit) return fail("ray from the body axis missed the skin");
    const SignedHit s = bvh_.signed_distance(h.point);
    return Vec3d(h.point + ease * s.normal);
  }
  /// Ray in the horizontal plane from `centre` at angle theta (0 front = +z,
  /// 90 = +x, the body's left).
  Expected<Vec3d> around(const Vec3d& centre, double theta_deg, double ease) const {
    return hit(centre, Vec3d(std::sin(theta_deg * kDeg), 0, std::cos(theta_deg * kDeg)), ease);
  }
  const BodyBvh& bvh() const { return bvh_; }

 private:
  explicit BodyProbe(const ReferenceBody& b) : body_(&b) {}
  const ReferenceBody* body_;
  SurfaceTriangles tris_;
  BodyBvh bvh_;
};

#define ATELIER_TRY(expr)              \
  do {                                 \
    if (Status s_ = (expr); !s_) return s_; \
  } while (0)

std::string nm(const char* ring, int k) { return std::string(ring) + "_" + std::to_string(k); }

/// Quads between two rings of the same size (k -> k+1 around), counter-
/// clockwise seen from outside when k runs to the body's left at the front.
void ring_band(std::vector<std::vector<std::string>>& faces, const char* lower, const char* upper, int n,
               std::initializer_list<int> only = {}) {
  auto add = [&](int k) {
    const int k1 = (k + 1) % n;
    faces.push_back({nm(lower, k), nm(lower, k1), nm(upper, k1), nm(upper, k)});
  };
  if (only.size() == 0)
    for (int k = 0; k < n; ++k) add(k);
  else
    for (int k : only) add(k);
}

Vec3d lerp_ab(const Vec3d& a, const Vec3d& b, double t) { return a + t * (b - a); }

}  // namespace

Expected<ProfileTemplate> make_top_template(const ReferenceBody& body) {
  auto probe = BodyProbe::make(body);
  if (!probe) return probe.status();
  auto neck = probe->curve({"neck_base", "neck"});
  auto bust = probe->curve({"bust"});
  auto waist = probe->curve({"waist"});
  auto hip = probe->curve({"hip"});
  for (auto* c : {&neck, &bust, &waist, &hip})
    if (!*c) return c->status();
  const Vec3d cn = BodyProbe::centroid(*neck), cb = BodyProbe::centroid(*bust), cw = BodyProbe::centroid(*waist),
              ch = BodyProbe::centroid(*hip);
  const Vec3d ca = lerp_ab(cb, cn, 0.3);   // armpit level: armhole bottoms
  const Vec3d cy = lerp_ab(ca, cn, 0.55);  // yoke: collar seam, shoulder tops at the sides
  const Vec3d cnl = lerp_ab(cy, cn, 0.7);  // neckline

  TemplateBuilder b(body, "top");
  b.set_clearance(0.004);
  b.set_levels(3);
  struct Ring {
    const char* name;
    Vec3d centre;
    double ease;
    NodeEncodingMode mode;
  };
  const Ring rings[] = {{"hem", ch, 0.022, NodeEncodingMode::kFace},   {"waist", cw, 0.018, NodeEncodingMode::kFeaturePoint},
                        {"bust", cb, 0.014, NodeEncodingMode::kEdge},  {"armpit", ca, 0.014, NodeEncodingMode::kVertex},
                        {"yoke", cy, 0.010, NodeEncodingMode::kFace}, {"neck", cnl, 0.016, NodeEncodingMode::kFace}};
  for (const Ring& r : rings) {
    for (int k = 0; k < 8; ++k) {
      auto p = probe->around(r.centre, 45.0 * k, r.ease);
      if (!p) return Status(p.status().code(), std::string("top, ring ") + r.name + ": " + p.status().message());
      NodeEncodingMode mode = r.mode;
      // Only the centre lines carry feature points on every reference body.
      if (mode == NodeEncodingMode::kFeaturePoint && k % 4 != 0) mode = NodeEncodingMode::kFace;
      if (std::string_view(r.name) == "neck" && k == 0) continue;  // follows its neighbours, below
      ATELIER_TRY(b.node_at(nm(r.name, k), *p, mode));
    }
  }
  {  // The centre-front neckline node follows its two neighbours (seed 001 eqs. (4)-(5)).
    auto p = probe->around(cnl, 0.0, 0.016);
    if (!p) return p.status();
    const std::string others[] = {"neck_7", "neck_1"};
    ATELIER_TRY(b.node_relative("neck_0", others, *p));
  }
  // Collar ring: above the neckline, standing off the neck.
  const Vec3d cc = lerp_ab(cn, cn + (cn - cb), 0.12);
  for (int k = 0; k < 8; ++k) {
    auto p = probe->around(cc, 45.0 * k, 0.03);
    if (!p) return p.status();
    ATELIER_TRY(b.node_at(nm("collar", k), *p, NodeEncodingMode::kFace));
  }
  std::vector<std::vector<std::string>> top;
  ring_band(top, "hem", "waist", 8);
  ring_band(top, "waist", "bust", 8);
  ring_band(top, "bust", "armpit", 8);
  ring_band(top, "armpit", "yoke", 8, {7, 0, 3, 4});  // front and back panels; armholes at 90 and 270
  ring_band(top, "yoke", "neck", 8);                  // over the shoulders
  ATELIER_TRY(b.surface("top", top));
  std::vector<std::vector<std::string>> collar;
  ring_band(collar, "yoke", "collar", 8);
  ATELIER_TRY(b.surface("collar", collar));
  // The collar stands on the yoke line: inner edges of the top at the front
  // and back, boundary edges over the shoulders.
  std::vector<std::string> yoke_loop;
  for (int k = 0; k <= 8; ++k) yoke_loop.push_back(nm("yoke", k % 8));
  const TemplateBuilder::JointChain members[] = {{"top", yoke_loop}, {"collar", yoke_loop}};
  ATELIER_TRY(b.joint(members));
  // Seams the pattern cuts along (systems/pattern/seams.h): side seams from
  // the hem to the armhole bottoms, shoulder seams from the armhole tops to
  // the neckline, and the yoke line at the front and back, where the collar
  // is sewn; the top's pattern is a front and a back body and a front and a
  // back yoke, the collar sewn onto their boundaries.
  for (int k : {2, 6}) {
    ATELIER_TRY(b.seam("top", std::vector<std::string>{nm("hem", k), nm("waist", k), nm("bust", k), nm("armpit", k)}));
    ATELIER_TRY(b.seam("top", std::vector<std::string>{nm("yoke", k), nm("neck", k)}));
  }
  ATELIER_TRY(b.seam("top", std::vector<std::string>{"yoke_7", "yoke_0", "yoke_1"}));
  ATELIER_TRY(b.seam("top", std::vector<std::string>{"yoke_3", "yoke_4", "yoke_5"}));

  // Scoop neckline: two strokes in a front orthographic view, each dipping
  // between the centre-front node and its neighbours (seed 000 Fig. 13).
  const int W = 800, H = 800;
  const double half = 0.25;
  const Camera cam = Camera::orthographic(cn + Vec3d(0, 0, 1.0), cn, Vec3d::UnitY(), half, W, H);
  for (int side : {1, 7}) {
    const Vec3d a = cam.project(*b.position("neck_0")), c = cam.project(*b.position(nm("neck", side)));
    const double dip_px = 0.010 * H / (2 * half);
    std::vector<Vec2d> stroke;
    for (int i = 0; i <= 24; ++i) {
      const double s = i / 24.0;
      const Vec2d q = Vec2d(a.x(), a.y()) + s * Vec2d(c.x() - a.x(), c.y() - a.y());
      stroke.push_back(q + Vec2d(0, dip_px * std::sin(std::numbers::pi * s) * (1.0 - 0.5 * s)));
    }
    auto added = b.stroke_profile("top", cam, stroke, 3.0);
    if (!added) return added.status();
    if (*added == 0) return Status(ErrorCode::kInternal, "top: the neckline stroke selected no edge");
  }
  return b.build();
}

Expected<ProfileTemplate> make_skirt_template(const ReferenceBody& body) {
  auto probe = BodyProbe::make(body);
  if (!probe) return probe.status();
  auto waist = probe->curve({"waist"});
  auto hip = probe->curve({"hip"});
  auto knee_l = probe->curve({"knee_left", "left_knee"});
  for (auto* c : {&waist, &hip, &knee_l})
    if (!*c) return c->status();
  const Vec3d cw = BodyProbe::centroid(*waist), ch = BodyProbe::centroid(*hip);
  const double y_knee = BodyProbe::centroid(*knee_l).y();

  TemplateBuilder b(body, "skirt");
  b.set_clearance(0.004);
  b.set_levels(3);
  std::array<Vec3d, 8> hip_pts;
  for (int k = 0; k < 8; ++k) {
    auto pw = probe->around(cw, 45.0 * k, 0.012);
    auto ph = probe->around(ch, 45.0 * k, 0.02);
    if (!pw || !ph) return fail("skirt: a ray missed the body");
    hip_pts[k] = *ph;
    ATELIER_TRY(b.node_at(nm("waist", k), *pw, k % 4 == 0 ? NodeEncodingMode::kFeaturePoint : NodeEncodingMode::kVertex));
    ATELIER_TRY(b.node_at(nm("hip", k), *ph, NodeEncodingMode::kFace));
  }
  // Below the hips the skirt hangs free: rings scaled out from the hip ring,
  // encoded on the nearest face (the thighs) or edge.
  const double y_mid = ch.y() + 0.45 * (y_knee - ch.y());
  const double y_hem = y_knee - 0.04;
  for (int k = 0; k < 8; ++k) {
    Vec3d m = ch + 1.10 * (hip_pts[k] - ch);
    m.y() = y_mid;
    Vec3d h = ch + 1.32 * (hip_pts[k] - ch);
    h.y() = y_hem;
    ATELIER_TRY(b.node_at(nm("mid", k), m, NodeEncodingMode::kFace));
    ATELIER_TRY(b.node_at(nm("hemline", k), h, NodeEncodingMode::kEdge));
  }
  std::vector<std::vector<std::string>> faces;
  ring_band(faces, "hip", "waist", 8);
  ring_band(faces, "mid", "hip", 8);
  ring_band(faces, "hemline", "mid", 8);
  ATELIER_TRY(b.surface("skirt", faces));
  // Scalloped hem: each hem edge a cubic Bezier dipping 2.5 cm.
  for (int k = 0; k < 8; ++k) {
    const Vec3d a = *b.position(nm("hemline", k)), c = *b.position(nm("hemline", (k + 1) % 8));
    const Vec3d down(0, -0.025, 0);
    const Vec3d out = (0.5 * (a + c) - Vec3d(ch.x(), 0.5 * (a + c).y(), ch.z())).normalized() * 0.01;
    const Vec3d ctrl[] = {lerp_ab(a, c, 1.0 / 3) + down + out, lerp_ab(a, c, 2.0 / 3) + down + out};
    ATELIER_TRY(b.bezier_profile("skirt", nm("hemline", k), nm("hemline", (k + 1) % 8), ctrl));
  }
  return b.build();
}

Expected<ProfileTemplate> make_trousers_template(const ReferenceBody& body) {
  auto probe = BodyProbe::make(body);
  if (!probe) return probe.status();
  auto waist = probe->curve({"waist"});
  auto hip = probe->curve({"hip"});
  auto thigh_l = probe->curve({"thigh_left", "left_thigh"});
  auto thigh_r = probe->curve({"thigh_right", "right_thigh"});
  auto knee_l = probe->curve({"knee_left", "left_knee"});
  auto knee_r = probe->curve({"knee_right", "right_knee"});
  auto ankle_l = probe->curve({"ankle_left", "left_ankle"});
  auto ankle_r = probe->curve({"ankle_right", "right_ankle"});
  for (auto* c : {&waist, &hip, &thigh_l, &thigh_r, &knee_l, &knee_r, &ankle_l, &ankle_r})
    if (!*c) return c->status();
  const Vec3d cw = BodyProbe::centroid(*waist), ch = BodyProbe::centroid(*hip);

  TemplateBuilder b(body, "trousers");
  b.set_clearance(0.004);
  b.set_levels(3);
  for (int k = 0; k < 8; ++k) {
    auto pw = probe->around(cw, 45.0 * k, 0.012);
    auto ph = probe->around(ch, 45.0 * k, 0.018);
    if (!pw || !ph) return fail("trousers: a ray missed the body");
    ATELIER_TRY(b.node_at(nm("waist", k), *pw, k % 4 == 0 ? NodeEncodingMode::kFeaturePoint : NodeEncodingMode::kFace));
    ATELIER_TRY(b.node_at(nm("hip", k), *ph, NodeEncodingMode::kFace));
  }
  // Crotch: the skin point straight above the middle between the knees.
  const Vec3d knees = 0.5 * (BodyProbe::centroid(*knee_l) + BodyProbe::centroid(*knee_r));
  auto crotch = probe->hit(Vec3d(ch.x(), knees.y(), ch.z()), Vec3d::UnitY(), 0.02);
  if (!crotch) return Status(crotch.status().code(), "trousers: crotch: " + crotch.status().message());
  ATELIER_TRY(b.node_at("crotch", *crotch, NodeEncodingMode::kFace));

  // Leg rings: 6 nodes matching the leg's top chain (hip_0, hip_45, hip_90,
  // hip_135, hip_180, crotch for the left leg; mirrored for the right).
  const double phi_left[6] = {-25, 45, 90, 135, 205, 270};
  struct Leg {
    const char* side;
    const std::vector<Vec3d>* thigh;
    const std::vector<Vec3d>* knee;
    const std::vector<Vec3d>* ankle;
    double sign;
    std::array<int, 5> hip;
  };
  const Leg legs[] = {{"l", &*thigh_l, &*knee_l, &*ankle_l, 1.0, {0, 1, 2, 3, 4}},
                      {"r", &*thigh_r, &*knee_r, &*ankle_r, -1.0, {0, 7, 6, 5, 4}}};
  for (const Leg& L : legs) {
    struct R {
      const char* name;
      Vec3d centre;
      double ease;
      NodeEncodingMode mode;
    };
    const Vec3d ct = BodyProbe::centroid(*L.thigh), ck = BodyProbe::centroid(*L.knee),
                ca = BodyProbe::centroid(*L.ankle);
    const R rings[] = {{"thigh", ct, 0.022, NodeEncodingMode::kFace},
                       {"knee", ck, 0.03, NodeEncodingMode::kEdge},
                       {"cuff", lerp_ab(ca, ck, 0.15), 0.04, NodeEncodingMode::kFace}};
    for (const R& r : rings)
      for (int k = 0; k < 6; ++k) {
        auto p = probe->around(r.centre, L.sign * phi_left[k], r.ease);
        if (!p) return fail(std::string("trousers: leg ring ") + r.name + ": a ray missed the body");
        ATELIER_TRY(b.node_at(std::string(L.side) + "_" + nm(r.name, k), *p, r.mode));
      }
    std::vector<std::string> top;
    for (int h : L.hip) top.push_back(nm("hip", h));
    top.push_back("crotch");
    auto ring = [&](const char* r, int k) { return std::string(L.side) + "_" + nm(r, k); };
    std::vector<std::vector<std::string>> faces;
    const char* order[] = {"cuff", "knee", "thigh"};
    for (int level = 0; level < 3; ++level)
      for (int k = 0; k < 6; ++k) {
        const int k1 = (k + 1) % 6;
        const std::string lo0 = ring(order[level], k), lo1 = ring(order[level], k1);
        const std::string up0 = level < 2 ? ring(order[level + 1], k) : top[k];
        const std::string up1 = level < 2 ? ring(order[level + 1], k1) : top[k1];
        // The left leg's ring runs to the body's left at the front (counter-
        // clockwise from outside); the mirrored right leg's the other way.
        if (L.sign > 0)
          faces.push_back({lo0, lo1, up1, up0});
        else
          faces.push_back({lo1, lo0, up0, up1});
      }
    ATELIER_TRY(b.surface(L.sign > 0 ? "left_leg" : "right_leg", faces));
  }
  std::vector<std::vector<std::string>> band;
  ring_band(band, "hip", "waist", 8);
  ATELIER_TRY(b.surface("waistband", band));
  const std::vector<std::string> left_chain = {"hip_0", "hip_1", "hip_2", "hip_3", "hip_4"};
  const std::vector<std::string> right_chain = {"hip_4", "hip_5", "hip_6", "hip_7", "hip_0"};
  const std::vector<std::string> crotch_chain = {"hip_0", "crotch", "hip_4"};
  const TemplateBuilder::JointChain j1[] = {{"waistband", left_chain}, {"left_leg", left_chain}};
  const TemplateBuilder::JointChain j2[] = {{"waistband", right_chain}, {"right_leg", right_chain}};
  const TemplateBuilder::JointChain j3[] = {{"left_leg", crotch_chain}, {"right_leg", crotch_chain}};
  ATELIER_TRY(b.joint(j1));
  ATELIER_TRY(b.joint(j2));
  ATELIER_TRY(b.joint(j3));
  return b.build();
}

Expected<std::vector<ProfileTemplate>> make_project_templates(const ReferenceBody& body) {
  std::vector<ProfileTemplate> out;
  for (auto* make : {&make_top_template, &make_skirt_template, &make_trousers_template}) {
    auto t = make(body);
    if (!t) return t.status();
    out.push_back(std::move(*t));
  }
  return out;
}

}  // namespace atelier
