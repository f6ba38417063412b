// The mannequin's measurements and positions (systems/body/mannequin.h):
// parameter checks, the cross sections fitted to the girths, the positions
// of the rings, and the reference body with its feature curves and points.
// The topology is in mannequin_topology.cpp, the sampling in
// mannequin_sampling.cpp.
#include <atelier/systems/body/mannequin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <tuple>

#include <atelier/engine/parallel.h>
#include <atelier/storage/builder.h>

#include "mannequin_detail.h"

namespace atelier {

namespace {


// ------------------------------------------------------------ 2D helpers
struct P2 {
  double x, z;
};

double cross2(const P2& o, const P2& a, const P2& b) {
  return (a.x - o.x) * (b.z - o.z) - (a.z - o.z) * (b.x - o.x);
}

// Perimeter of the convex hull (Andrew's monotone chain): a tape measure
// bridges the concave parts of a cross section.
double hull_perimeter(std::vector<P2> p) {
  std::sort(p.begin(), p.end(), [](const P2& a, const P2& b) { return a.x < b.x || (a.x == b.x && a.z < b.z); });
  const std::size_t n = p.size();
  if (n < 3) return 0;
  std::vector<P2> h(2 * n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (k >= 2 && cross2(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = n - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross2(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k - 1);
  double per = 0;
  for (std::size_t i = 0; i < h.size(); ++i) {
    const P2& a = h[i];
    const P2& b = h[(i + 1) % h.size()];
    per += std::hypot(b.x - a.x, b.z - a.z);
  }
  return per;
}

// A two-sided super-ellipse cross section: half-width a (x), front depth bf
// (z > 0), back depth bb, exponent p (2 = ellipse, larger = squarer), centre
// (cx, cz).
struct Section {
  double a = 1, bf = 1, bb = 1, p = 2, cx = 0, cz = 0;
};

// Radius of the section along polar angle t (star-shaped about its centre).
double section_radius(const Section& s, double t) {
  const double c = std::abs(std::cos(t)), sn = std::abs(std::sin(t));
  const double b = std::sin(t) >= 0 ? s.bf : s.bb;
  const double v = std::pow(c / s.a, s.p) + std::pow(sn / b, s.p);
  return std::pow(v, -1.0 / s.p);
}

P2 section_point(const Section& s, double t) {
  const double r = section_radius(s, t);
  return {s.cx + r * std::cos(t), s.cz + r * std::sin(t)};
}

// Torso column angles: j = 0 is the centre front (+z), j = N/4 the left side (+x).
double torso_angle(std::uint32_t j, std::uint32_t n) {
  return kPi / 2 - 2 * kPi * j / n;
}

// Hull perimeter of the N-gon of section s sampled at the given angles.
double section_girth(const Section& s, std::span<const double> angles) {
  std::vector<P2> pts;
  pts.reserve(angles.size());
  for (double t : angles) pts.push_back(section_point(s, t));
  return hull_perimeter(std::move(pts));
}

// Scales the section's size (not its centre) so its sampled hull perimeter
// equals g. The hull of a scaled polygon scales exactly, so one step is exact.
Section fit_girth(Section s, double g, std::span<const double> angles) {
  const double cur = section_girth(s, angles);
  const double k = g / cur;
  s.a *= k;
  s.bf *= k;
  s.bb *= k;
  return s;
}

// Monotone piecewise cubic (Fritsch-Carlson): smooth silhouettes without
// overshoot between measured levels.
double pchip(std::span<const double> x, std::span<const double> y, double t) {
  const std::size_t n = x.size();
  if (t <= x[0]) return y[0];
  if (t >= x[n - 1]) return y[n - 1];
  std::size_t k = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), t) - x.begin()) - 1;
  auto slope = [&](std::size_t i) { return (y[i + 1] - y[i]) / (x[i + 1] - x[i]); };
  auto tangent = [&](std::size_t i) {
    if (i == 0) return slope(0);
    if (i == n - 1) return slope(n - 2);
    const double d0 = slope(i - 1), d1 = slope(i);
    if (d0 * d1 <= 0) return 0.0;
    const double w0 = 2 * (x[i + 1] - x[i]) + (x[i] - x[i - 1]);
    const double w1 = (x[i + 1] - x[i]) + 2 * (x[i] - x[i - 1]);
    return (w0 + w1) / (w0 / d0 + w1 / d1);
  };
  const double h = x[k + 1] - x[k];
  const double s = (t - x[k]) / h;
  const double m0 = tangent(k) * h, m1 = tangent(k + 1) * h;
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * y[k] + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * y[k + 1] + (s3 - s2) * m1;
}

double smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Ring index within segments [key[k], key[k+1]] -> height by linear steps.
double ring_height(std::uint32_t i, std::span<const std::uint32_t> key, std::span<const double> y) {
  for (std::size_t k = 0; k + 1 < key.size(); ++k)
    if (i <= key[k + 1]) {
      const double t = double(i - key[k]) / double(key[k + 1] - key[k]);
      return y[k] + t * (y[k + 1] - y[k]);
    }
  return y.back();
}

}  // namespace

// ------------------------------------------------------------ parameters

Status validate_params(const MannequinParams& p) {
  auto bad = [](const char* what, double v, double lo, double hi) {
    std::ostringstream s;
    s << "mannequin " << what << " = " << v << " m is outside [" << lo << ", " << hi << "]";
    return Status(ErrorCode::kInvalidArgument, s.str());
  };
  struct Range {
    const char* name;
    double v, lo, hi;
  };
  const double H = p.height;
  const Range ranges[] = {
      {"height", p.height, 1.40, 2.10},
      {"neck_girth", p.neck_girth, 0.27, 0.56},
      {"bust_girth", p.bust_girth, 0.68, 1.55},
      {"underbust_girth", p.underbust_girth, 0.58, 1.45},
      {"waist_girth", p.waist_girth, 0.50, 1.55},
      {"hip_girth", p.hip_girth, 0.72, 1.60},
      {"thigh_girth", p.thigh_girth, 0.38, 0.90},
      {"knee_girth", p.knee_girth, 0.26, 0.58},
      {"ankle_girth", p.ankle_girth, 0.16, 0.36},
      {"upper_arm_girth", p.upper_arm_girth, 0.18, 0.52},
      {"shoulder_width", p.shoulder_width, 0.30, 0.56},
      {"back_length", p.back_length, 0.30, 0.58},
  };
  for (const auto& r : ranges)
    if (!(r.v >= r.lo && r.v <= r.hi)) return bad(r.name, r.v, r.lo, r.hi);
  if (!(p.inseam >= 0.38 * H && p.inseam <= 0.52 * H)) return bad("inseam", p.inseam, 0.38 * H, 0.52 * H);
  auto inconsistent = [](const std::string& m) { return Status(ErrorCode::kInvalidArgument, "mannequin: " + m); };
  if (p.underbust_girth > p.bust_girth) return inconsistent("underbust_girth exceeds bust_girth");
  if (p.thigh_girth > 0.75 * p.hip_girth) return inconsistent("thigh_girth exceeds 0.75 * hip_girth");
  if (p.knee_girth > 0.9 * p.thigh_girth) return inconsistent("knee_girth exceeds 0.9 * thigh_girth");
  if (p.ankle_girth > 0.85 * p.knee_girth) return inconsistent("ankle_girth exceeds 0.85 * knee_girth");
  if (p.upper_arm_girth > 0.45 * p.bust_girth) return inconsistent("upper_arm_girth exceeds 0.45 * bust_girth");
  if (p.neck_girth > 0.5 * p.bust_girth) return inconsistent("neck_girth exceeds 0.5 * bust_girth");
  if (p.shoulder_width < 0.42 * p.neck_girth + 0.10)
    return inconsistent("shoulder_width too small for the neck (needs >= 0.42 * neck_girth + 0.10)");
  // Vertical order of the levels (see mannequin_positions): armpit 0.118 H
  // below the nape, waist back_length below it, crotch at the inseam.
  const double nape = 0.848 * H, armpit = nape - 0.118 * H, waist = nape - p.back_length;
  if (waist > armpit - 0.08) return inconsistent("back_length too short: the waist must be 8 cm below the armpit");
  if (waist < p.inseam + 0.12)
    return inconsistent("back_length + inseam too long: the waist must be 12 cm above the crotch");
  return {};
}

double requested_girth(const MannequinParams& p, std::int32_t id) noexcept {
  switch (id) {
    case kNeckBase:
      return p.neck_girth;
    case kBust:
      return p.bust_girth;
    case kUnderbust:
      return p.underbust_girth;
    case kWaist:
      return p.waist_girth;
    case kHip:
      return p.hip_girth;
    case kThighLeft:
    case kThighRight:
      return p.thigh_girth;
    case kKneeLeft:
    case kKneeRight:
      return p.knee_girth;
    case kAnkleLeft:
    case kAnkleRight:
      return p.ankle_girth;
    case kUpperArmLeft:
    case kUpperArmRight:
      return p.upper_arm_girth;
    default:
      return std::numeric_limits<double>::quiet_NaN();
  }
}

// ------------------------------------------------------------- geometry

Expected<std::vector<Vec3d>> mannequin_positions(const MannequinParams& p, const MannequinTopology& t) {
  using namespace mannequin_detail;  // NOLINT(google-build-using-namespace): the layout's key levels
  if (Status s = validate_params(p); !s) return s;
  const std::uint32_t N = t.res.around;
  const double H = p.height;
  std::vector<Vec3d> pos(t.num_nodes, Vec3d::Zero());

  // Key heights (fractions of the stature from anthropometric tables).
  const double y_nb = 0.848 * H, y_ap = y_nb - 0.118 * H, y_w = y_nb - p.back_length, y_c = p.inseam;
  std::array<double, kTKeys> ty{};
  ty[kTCrotch] = y_c;
  ty[kTHip] = y_c + 0.42 * (y_w - y_c);
  ty[kTWaist] = y_w;
  ty[kTUnderbust] = y_w + 0.45 * (y_ap - y_w);
  ty[kTBust] = y_w + 0.85 * (y_ap - y_w);
  ty[kTArmpit] = y_ap;
  ty[kTShoulder] = y_nb - 0.030 * H;
  ty[kTNeckBase] = y_nb;
  ty[kTNeckTop] = y_nb + 0.035 * H;

  std::vector<double> angles(N);
  for (std::uint32_t j = 0; j < N; ++j) angles[j] = torso_angle(j, N);

  // Key sections. Shapes (depth/width ratios, squareness) are fixed; sizes
  // come from the measurements. Girth levels are fitted exactly.
  std::array<Section, kTKeys> ks;
  ks[kTHip] = fit_girth({1, 0.66, 0.80, 2.3, 0, 0}, p.hip_girth, angles);
  ks[kTCrotch] = fit_girth({1, 0.64, 0.78, 2.3, 0, 0}, 0.95 * p.hip_girth, angles);
  ks[kTWaist] = fit_girth({1, 0.72, 0.72, 2.2, 0, 0}, p.waist_girth, angles);
  ks[kTUnderbust] = fit_girth({1, 0.68, 0.70, 2.3, 0, 0}, p.underbust_girth, angles);
  // Bust prominence grows with the bust - underbust difference.
  const double prom = 1.5 * (p.bust_girth - p.underbust_girth) / p.bust_girth;
  ks[kTBust] = fit_girth({1, 0.62 + prom, 0.64, 2.3, 0, 0}, p.bust_girth, angles);
  {
    // Chest at the armpit: at least as wide as the levels below, so the
    // sides do not bulge out under the short arms.
    Section s = ks[kTBust];
    s.a = std::max({ks[kTBust].a, ks[kTUnderbust].a, ks[kTWaist].a * 1.02});
    s.bf = 0.8 * ks[kTBust].bf;
    s.bb = ks[kTBust].bb;
    s.p = 2.4;
    ks[kTArmpit] = s;
  }
  ks[kTShoulder] = {0.5 * p.shoulder_width, 0.75 * ks[kTArmpit].bf, 0.85 * ks[kTArmpit].bb, 2.6, 0, 0};
  ks[kTNeckBase] = fit_girth({1, 0.95, 0.95, 2.0, 0, -0.007 * H}, p.neck_girth, angles);
  ks[kTNeckTop] = fit_girth({1, 0.95, 0.95, 2.0, 0, -0.004 * H}, 0.94 * p.neck_girth, angles);

  auto column_of = [&](auto get) {
    std::array<double, kTKeys> v{};
    for (int k = 0; k < kTKeys; ++k) v[k] = get(ks[k]);
    return v;
  };
  const auto va = column_of([](const Section& s) { return s.a; });
  const auto vbf = column_of([](const Section& s) { return s.bf; });
  const auto vbb = column_of([](const Section& s) { return s.bb; });
  const auto vp = column_of([](const Section& s) { return s.p; });
  const auto vcz = column_of([](const Section& s) { return s.cz; });

  std::vector<Section> torso(t.torso_rings);
  std::vector<double> torso_y(t.torso_rings);
  for (std::uint32_t i = 0; i < t.torso_rings; ++i) {
    const double y = ring_height(i, t.key_torso, ty);
    torso_y[i] = y;
    const auto key = std::find(t.key_torso.begin(), t.key_torso.end(), i);
    if (key != t.key_torso.end()) {
      torso[i] = ks[key - t.key_torso.begin()];  // exact at measured levels
    } else {
      torso[i] = {pchip(ty, va, y), pchip(ty, vbf, y), pchip(ty, vbb, y), pchip(ty, vp, y), 0, pchip(ty, vcz, y)};
    }
    for (std::uint32_t j = 0; j < N; ++j) {
      const std::int32_t v = t.torso_node[std::size_t{i} * N + j];
      if (v < 0) continue;
      const P2 q = section_point(torso[i], angles[j]);
      pos[v] = {q.x, y, q.z};
    }
  }

  // Crotch bridge: straight line from the back to the front crotch point.
  const std::uint32_t nb = N / 2 - 1;
  const Vec3d front = pos[t.torso_node[0]], back = pos[t.torso_node[N / 2]];
  for (std::uint32_t b = 1; b <= nb; ++b) {
    const double s = double(b) / double(nb + 1);
    pos[t.bridge_base + b - 1] = (1 - s) * back + s * front;
    pos[t.bridge_base + b - 1].x() = 0;    // exactly on the symmetry line: the
    pos[t.bridge_base + b - 1].y() = y_c;  // two legs' first bands meet only there
  }

  // ---- legs (left computed, right mirrored)
  std::vector<Vec3d> d_ring(N);  // ring 0 of the left leg: half crotch ring + bridge
  for (std::uint32_t m = 0; m < N; ++m)
    d_ring[m] = m <= N / 2 ? pos[t.torso_node[m]] : pos[t.bridge_base + (m - N / 2 - 1)];
  const double cx0 = 0.5 * ks[kTCrotch].a, cz0 = 0.5 * (ks[kTCrotch].bf - ks[kTCrotch].bb);
  std::vector<double> leg_angles(N);
  for (std::uint32_t m = 0; m < N; ++m) leg_angles[m] = torso_angle(m, N);
  std::array<double, kLKeys> ly{};
  ly[kLCrotch] = y_c;
  ly[kLThigh] = y_c - 0.025 * H;
  ly[kLKnee] = 0.285 * H;
  ly[kLAnkle] = 0.055 * H;
  std::array<Section, kLKeys> ls;
  constexpr double gap = 0.012;  // half the clearance between the legs
  ls[kLThigh] = fit_girth({0.92, 1.08, 1.0, 2.1, 0, 0}, p.thigh_girth, leg_angles);
  ls[kLKnee] = fit_girth({0.95, 1.0, 1.05, 2.0, 0, 0}, p.knee_girth, leg_angles);
  ls[kLAnkle] = fit_girth({0.85, 1.1, 1.1, 2.0, 0, 0}, p.ankle_girth, leg_angles);
  ls[kLThigh].cx = std::max(cx0, ls[kLThigh].a + gap);
  ls[kLThigh].cz = 0.3 * cz0;
  ls[kLAnkle].cx = std::max(0.05 * H, ls[kLAnkle].a + gap);
  ls[kLAnkle].cz = -0.01 * H;
  ls[kLKnee].cx = std::max(0.5 * (ls[kLThigh].cx + ls[kLAnkle].cx), ls[kLKnee].a + gap);
  ls[kLKnee].cz = 0;
  ls[kLCrotch] = ls[kLThigh];
  // Leg interpolation tables over height (increasing order for pchip).
  std::array<double, 3> lyk = {ly[kLAnkle], ly[kLKnee], ly[kLThigh]};
  auto leg_col = [&](auto get) { return std::array<double, 3>{get(ls[kLAnkle]), get(ls[kLKnee]), get(ls[kLThigh])}; };
  const auto la = leg_col([](const Section& s) { return s.a; });
  const auto lbf = leg_col([](const Section& s) { return s.bf; });
  const auto lbb = leg_col([](const Section& s) { return s.bb; });
  const auto lp = leg_col([](const Section& s) { return s.p; });
  const auto lcx = leg_col([](const Section& s) { return s.cx; });
  const auto lcz = leg_col([](const Section& s) { return s.cz; });

  // Ring r = lerp(ring 0 (D shape), section ring, w(r)), then scaled about
  // its centre by s(r); s is fitted at the thigh so its girth is exact and
  // interpolated linearly in between (1 at the crotch, where the ring is
  // shared with the torso, and from the knee down where w = 1).
  auto leg_ring_raw = [&](std::uint32_t r, double& wout, Vec3d& centre) {
    const double y = ring_height(r, t.key_leg, ly);
    const double w = smoothstep((y_c - y) / (y_c - ly[kLKnee]));
    const Section s{pchip(lyk, la, y), pchip(lyk, lbf, y), pchip(lyk, lbb, y),
                    pchip(lyk, lp, y), pchip(lyk, lcx, y), pchip(lyk, lcz, y)};
    std::vector<Vec3d> ring(N);
    for (std::uint32_t m = 0; m < N; ++m) {
      const P2 q = section_point(s, leg_angles[m]);
      ring[m] = (1 - w) * Vec3d(d_ring[m].x(), y, d_ring[m].z()) + w * Vec3d(q.x, y, q.z);
    }
    centre = Vec3d((1 - w) * cx0 + w * s.cx, y, (1 - w) * cz0 + w * s.cz);
    wout = w;
    return ring;
  };
  auto ring_girth = [](const std::vector<Vec3d>& ring) {
    std::vector<P2> q;
    q.reserve(ring.size());
    for (const auto& v : ring) q.push_back({v.x(), v.z()});
    return hull_perimeter(std::move(q));
  };
  const std::uint32_t r_th = t.key_leg[kLThigh], r_kn = t.key_leg[kLKnee];
  double w_th;
  Vec3d c_th;
  const double s_th = p.thigh_girth / ring_girth(leg_ring_raw(r_th, w_th, c_th));
  for (std::uint32_t r = 1; r < t.leg_rings; ++r) {
    double w;
    Vec3d c;
    std::vector<Vec3d> ring = leg_ring_raw(r, w, c);
    double s = 1;
    if (r <= r_th)
      s = 1 + (s_th - 1) * double(r) / double(r_th);
    else if (r < r_kn)
      s = s_th + (1 - s_th) * double(r - r_th) / double(r_kn - r_th);
    for (std::uint32_t m = 0; m < N; ++m) {
      Vec3d v = c + s * (ring[m] - c);
      v.y() = c.y();
      pos[t.left_leg_base + (r - 1) * N + m] = v;
      pos[t.right_leg_base + (r - 1) * N + m] = {-v.x(), v.y(), v.z()};
    }
  }
  {
    const Section& a = ls[kLAnkle];
    const Vec3d apex(a.cx, ly[kLAnkle] - 0.025 * H, a.cz);
    pos[t.left_foot_apex] = apex;
    pos[t.right_foot_apex] = {-apex.x(), apex.y(), apex.z()};
  }

  // ---- short arms (left computed, right mirrored)
  {
    const std::uint32_t M = t.arm_around, K = t.arm_rings - 1, kua = t.key_arm[1];
    std::vector<Vec3d> loop(M);
    Vec3d c0 = Vec3d::Zero();
    for (std::uint32_t m = 0; m < M; ++m) c0 += (loop[m] = pos[t.left_loop[m]]);
    c0 /= double(M);
    std::vector<double> psi(M);  // angle about the outward axis, in the (z, y) plane
    for (std::uint32_t m = 0; m < M; ++m) psi[m] = std::atan2(loop[m].y() - c0.y(), loop[m].z() - c0.z());
    // Upper arm: a circle-like section sampled at the loop's angles, fitted.
    Section ua{1.0, 1.0, 1.0, 2.0, 0, 0};
    ua = fit_girth(ua, p.upper_arm_girth, psi);
    const double len = 0.07 * H;  // arm length along its axis
    const double tilt = 20.0 * kPi / 180.0;
    Vec3d c = c0;
    for (std::uint32_t k = 1; k <= K; ++k) {
      const double alpha = tilt * smoothstep(double(k) / double(K));
      const Vec3d axis(std::cos(alpha), -std::sin(alpha), 0.0);
      const Vec3d up(std::sin(alpha), std::cos(alpha), 0.0), fwd(0, 0, 1);
      c += (len / K) * axis;
      const double w = smoothstep(double(k) / double(kua));
      for (std::uint32_t m = 0; m < M; ++m) {
        const P2 q = section_point(ua, psi[m]);  // x: along fwd (z), z: along up (y)
        const Vec3d target = c + q.x * fwd + q.z * up;
        const Vec3d carried = loop[m] + (c - c0);
        const Vec3d v = (1 - w) * carried + w * target;
        pos[t.left_arm_base + (k - 1) * M + m] = v;
        pos[t.right_arm_base + (k - 1) * M + m] = {-v.x(), v.y(), v.z()};
      }
      if (k == K) {
        const Vec3d apex = c + 0.6 * ua.a * axis;
        pos[t.left_hand_apex] = apex;
        pos[t.right_hand_apex] = {-apex.x(), apex.y(), apex.z()};
      }
    }
  }
  {
    const Section& s = ks[kTNeckTop];
    pos[t.neck_apex] = {0, ty[kTNeckTop] + 0.3 * s.a, s.cz};
  }
  return pos;
}

Expected<ReferenceBody> make_mannequin(const MannequinParams& p, const MannequinTopology& t) {
  auto pos = mannequin_positions(p, t);
  if (!pos) return pos.status();
  ReferenceBody body;
  PolygonSoupView arrays{*pos, t.face_offsets, t.face_nodes};
  auto s = add_polygon_surface(body.model, "skin", arrays, ExecContext::sequential());
  if (!s) return s.status();
  body.skin = s->idx;
  for (const auto& c : t.curves) {
    std::vector<SurfaceLocation> path;
    path.reserve(c.nodes.size());
    for (std::uint32_t v : c.nodes) path.push_back({AttribNodeKind::kVertex, v, Vec3d::Zero(), 0});
    if (Status st = add_feature_curve(body, c.id, c.name, path, c.closed); !st) return st;
  }
  for (const auto& q : t.points)
    if (Status st =
            add_feature_point(body, q.id, q.name, {AttribNodeKind::kVertex, q.node, Vec3d::Zero(), 0}, q.c1, q.c2);
        !st)
      return st;
  return body;
}

Expected<ReferenceBody> make_mannequin(const MannequinParams& p, const MannequinResolution& res) {
  auto t = make_mannequin_topology(res);
  if (!t) return t.status();
  return make_mannequin(p, *t);
}

Expected<std::vector<ReferenceBody>> make_mannequins(std::span<const MannequinParams> params,
                                                     const MannequinTopology& t, const ExecContext& ctx) {
  for (std::size_t i = 0; i < params.size(); ++i)
    if (Status s = validate_params(params[i]); !s)
      return Status(s.code(), "body " + std::to_string(i) + ": " + s.message());
  std::vector<ReferenceBody> out(params.size());
  std::vector<Status> status(params.size());
  ExecContext c = ctx;
  c.sequential_threshold = 2;  // each item is a whole body
  c.grain = 1;
  par::for_each_n(c, params.size(), [&](std::size_t i) {
    auto b = make_mannequin(params[i], t);
    if (b)
      out[i] = std::move(*b);
    else
      status[i] = b.status();
  });
  for (std::size_t i = 0; i < status.size(); ++i)
    if (!status[i]) return Status(status[i].code(), "body " + std::to_string(i) + ": " + status[i].message());
  return out;
}

}  // namespace atelier
