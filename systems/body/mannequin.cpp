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

namespace atelier {

namespace {

constexpr double kPi = std::numbers::pi;

// ---------------------------------------------------------------- layout
// Torso key levels (ring index of each is fixed by the resolution).
enum TorsoKey { kTCrotch, kTHip, kTWaist, kTUnderbust, kTBust, kTArmpit, kTShoulder, kTNeckBase, kTNeckTop, kTKeys };
enum LegKey { kLCrotch, kLThigh, kLKnee, kLAnkle, kLKeys };
// Nominal segment lengths (m) at the default body; ring counts follow them
// so that rings are about 6/L cm apart. The shoulder segment is counted by
// its slanted length, not its rise.
constexpr std::array<double, kTKeys - 1> kTorsoSeg = {0.10, 0.17, 0.10, 0.09, 0.035, 0.15, 0.09, 0.06};
constexpr std::array<std::uint32_t, kTKeys - 1> kTorsoMin = {2, 2, 2, 2, 1, 2, 2, 1};
constexpr std::array<double, kLKeys - 1> kLegSeg = {0.04, 0.26, 0.39};
constexpr std::array<std::uint32_t, kLKeys - 1> kLegMin = {2, 3, 3};
constexpr double kArmSeg = 0.12;

std::uint32_t seg_count(double len, std::uint32_t level, std::uint32_t min) {
  const double h = 0.06 / level;
  return std::max<std::uint32_t>(min, static_cast<std::uint32_t>(std::lround(len / h)));
}

// ------------------------------------------------------------ 2D helpers
struct P2 {
  double x, z;
};

double cross2(const P2& o, const P2& a, const P2& b) { return (a.x - o.x) * (b.z - o.z) - (a.z - o.z) * (b.x - o.x); }

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
double torso_angle(std::uint32_t j, std::uint32_t n) { return kPi / 2 - 2 * kPi * j / n; }

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
      {"height", p.height, 1.40, 2.10},          {"neck_girth", p.neck_girth, 0.27, 0.56},
      {"bust_girth", p.bust_girth, 0.68, 1.55},  {"underbust_girth", p.underbust_girth, 0.58, 1.45},
      {"waist_girth", p.waist_girth, 0.50, 1.55}, {"hip_girth", p.hip_girth, 0.72, 1.60},
      {"thigh_girth", p.thigh_girth, 0.38, 0.90}, {"knee_girth", p.knee_girth, 0.26, 0.58},
      {"ankle_girth", p.ankle_girth, 0.16, 0.36}, {"upper_arm_girth", p.upper_arm_girth, 0.18, 0.52},
      {"shoulder_width", p.shoulder_width, 0.30, 0.56}, {"back_length", p.back_length, 0.30, 0.58},
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
  if (waist < p.inseam + 0.12) return inconsistent("back_length + inseam too long: the waist must be 12 cm above the crotch");
  return {};
}

double requested_girth(const MannequinParams& p, std::int32_t id) noexcept {
  switch (id) {
    case kNeckBase: return p.neck_girth;
    case kBust: return p.bust_girth;
    case kUnderbust: return p.underbust_girth;
    case kWaist: return p.waist_girth;
    case kHip: return p.hip_girth;
    case kThighLeft:
    case kThighRight: return p.thigh_girth;
    case kKneeLeft:
    case kKneeRight: return p.knee_girth;
    case kAnkleLeft:
    case kAnkleRight: return p.ankle_girth;
    case kUpperArmLeft:
    case kUpperArmRight: return p.upper_arm_girth;
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}

// -------------------------------------------------------------- topology

Expected<MannequinTopology> make_mannequin_topology(const MannequinResolution& res) {
  if (res.around < 16 || res.around % 16 != 0)
    return Status(ErrorCode::kInvalidArgument, "mannequin resolution: around must be a positive multiple of 16");
  if (res.level < 1 || res.level > 64)
    return Status(ErrorCode::kInvalidArgument, "mannequin resolution: level must be in [1, 64]");
  MannequinTopology t;
  t.res = res;
  const std::uint32_t N = res.around, L = res.level;
  t.key_torso.assign(kTKeys, 0);
  for (int k = 0; k + 1 < kTKeys; ++k) t.key_torso[k + 1] = t.key_torso[k] + seg_count(kTorsoSeg[k], L, kTorsoMin[k]);
  t.key_leg.assign(kLKeys, 0);
  for (int k = 0; k + 1 < kLKeys; ++k) t.key_leg[k + 1] = t.key_leg[k] + seg_count(kLegSeg[k], L, kLegMin[k]);
  t.torso_rings = t.key_torso[kTNeckTop] + 1;
  t.leg_rings = t.key_leg[kLAnkle] + 1;
  const std::uint32_t K = seg_count(kArmSeg, L, 3);
  t.arm_rings = K + 1;
  t.key_arm = {0, static_cast<std::uint32_t>(std::lround(0.75 * K)), K};

  const std::uint32_t iap = t.key_torso[kTArmpit], ish = t.key_torso[kTShoulder];
  const std::uint32_t w = N / 16;
  const std::uint32_t lc0 = N / 4 - w, lc1 = N / 4 + w, rc0 = 3 * N / 4 - w, rc1 = 3 * N / 4 + w;
  auto in_hole = [&](std::uint32_t i, std::uint32_t j) {  // node removed (inside an armhole)
    return i > iap && i < ish && ((j > lc0 && j < lc1) || (j > rc0 && j < rc1));
  };
  auto quad_in_hole = [&](std::uint32_t i, std::uint32_t j) {  // band quad (i,j) removed
    return i >= iap && i < ish && ((j >= lc0 && j < lc1) || (j >= rc0 && j < rc1));
  };

  // Nodes: torso, bridge, legs, arms, apexes.
  std::uint32_t next = 0;
  t.torso_node.assign(std::size_t{t.torso_rings} * N, -1);
  for (std::uint32_t i = 0; i < t.torso_rings; ++i)
    for (std::uint32_t j = 0; j < N; ++j)
      if (!in_hole(i, j)) t.torso_node[std::size_t{i} * N + j] = static_cast<std::int32_t>(next++);
  auto T = [&](std::uint32_t i, std::uint32_t j) { return static_cast<std::uint32_t>(t.torso_node[std::size_t{i} * N + j % N]); };
  const std::uint32_t nbridge = N / 2 - 1;
  t.bridge_base = next;
  next += nbridge;
  t.left_leg_base = next;
  next += (t.leg_rings - 1) * N;
  t.right_leg_base = next;
  next += (t.leg_rings - 1) * N;
  // Armhole loops: bottom row forward, up the back column, top row back,
  // down the front column (left); the right loop is its mirror image.
  for (std::uint32_t j = lc0; j < lc1; ++j) t.left_loop.push_back(T(iap, j));
  for (std::uint32_t i = iap; i < ish; ++i) t.left_loop.push_back(T(i, lc1));
  for (std::uint32_t j = lc1; j > lc0; --j) t.left_loop.push_back(T(ish, j));
  for (std::uint32_t i = ish; i > iap; --i) t.left_loop.push_back(T(i, lc0));
  for (std::uint32_t v : t.left_loop) {
    // mirror (i, j) -> (i, N - j)
    const auto it = std::find(t.torso_node.begin(), t.torso_node.end(), static_cast<std::int32_t>(v));
    const std::size_t idx = static_cast<std::size_t>(it - t.torso_node.begin());
    t.right_loop.push_back(T(static_cast<std::uint32_t>(idx / N), N - static_cast<std::uint32_t>(idx % N)));
  }
  const std::uint32_t M = static_cast<std::uint32_t>(t.left_loop.size());
  t.arm_around = M;
  t.left_arm_base = next;
  next += K * M;
  t.right_arm_base = next;
  next += K * M;
  t.neck_apex = next++;
  t.left_foot_apex = next++;
  t.right_foot_apex = next++;
  t.left_hand_apex = next++;
  t.right_hand_apex = next++;
  t.num_nodes = next;

  auto leg = [&](bool left, std::uint32_t r, std::uint32_t m) -> std::uint32_t {
    m %= N;
    if (r == 0) {
      if (m <= N / 2) return left ? T(0, m) : T(0, (N - m) % N);
      return t.bridge_base + (m - N / 2 - 1);  // back to front
    }
    return (left ? t.left_leg_base : t.right_leg_base) + (r - 1) * N + m;
  };
  auto arm = [&](bool left, std::uint32_t k, std::uint32_t m) -> std::uint32_t {
    m %= M;
    if (k == 0) return left ? t.left_loop[m] : t.right_loop[m];
    return (left ? t.left_arm_base : t.right_arm_base) + (k - 1) * M + m;
  };

  // Faces, counter-clockwise seen from outside (checked by the tests through
  // the signed volume).
  t.face_offsets.assign(1, 0);
  auto face = [&](std::initializer_list<std::uint32_t> f) {
    t.face_nodes.insert(t.face_nodes.end(), f);
    t.face_offsets.push_back(static_cast<std::uint32_t>(t.face_nodes.size()));
  };
  for (std::uint32_t i = 0; i + 1 < t.torso_rings; ++i)
    for (std::uint32_t j = 0; j < N; ++j)
      if (!quad_in_hole(i, j)) face({T(i, j), T(i, j + 1), T(i + 1, j + 1), T(i + 1, j)});
  for (std::uint32_t j = 0; j < N; ++j) face({T(t.torso_rings - 1, j), T(t.torso_rings - 1, j + 1), t.neck_apex});
  for (bool left : {true, false}) {
    for (std::uint32_t r = 0; r + 1 < t.leg_rings; ++r)
      for (std::uint32_t m = 0; m < N; ++m) {
        if (left)
          face({leg(true, r + 1, m), leg(true, r + 1, m + 1), leg(true, r, m + 1), leg(true, r, m)});
        else
          face({leg(false, r + 1, m), leg(false, r, m), leg(false, r, m + 1), leg(false, r + 1, m + 1)});
      }
    const std::uint32_t last = t.leg_rings - 1;
    const std::uint32_t apex = left ? t.left_foot_apex : t.right_foot_apex;
    for (std::uint32_t m = 0; m < N; ++m) {
      if (left)
        face({leg(true, last, m + 1), leg(true, last, m), apex});
      else
        face({leg(false, last, m), leg(false, last, m + 1), apex});
    }
  }
  for (bool left : {true, false}) {
    for (std::uint32_t k = 0; k < K; ++k)
      for (std::uint32_t m = 0; m < M; ++m) {
        if (left)
          face({arm(true, k, m), arm(true, k, m + 1), arm(true, k + 1, m + 1), arm(true, k + 1, m)});
        else
          face({arm(false, k, m), arm(false, k + 1, m), arm(false, k + 1, m + 1), arm(false, k, m + 1)});
      }
    const std::uint32_t apex = left ? t.left_hand_apex : t.right_hand_apex;
    for (std::uint32_t m = 0; m < M; ++m) {
      if (left)
        face({arm(true, K, m), arm(true, K, m + 1), apex});
      else
        face({arm(false, K, m + 1), arm(false, K, m), apex});
    }
  }

  // Feature curves (node lists) and points.
  auto ring = [&](std::uint32_t i) {
    std::vector<std::uint32_t> v;
    for (std::uint32_t j = 0; j < N; ++j) v.push_back(T(i, j));
    return v;
  };
  auto leg_ring = [&](bool left, std::uint32_t r) {
    std::vector<std::uint32_t> v;
    for (std::uint32_t m = 0; m < N; ++m) v.push_back(leg(left, r, m));
    return v;
  };
  auto arm_ring = [&](bool left, std::uint32_t k) {
    std::vector<std::uint32_t> v;
    for (std::uint32_t m = 0; m < M; ++m) v.push_back(arm(left, k, m));
    return v;
  };
  auto column = [&](std::uint32_t j, std::uint32_t from, std::uint32_t to) {  // from > to: downwards
    std::vector<std::uint32_t> v;
    for (std::uint32_t i = from + 1; i-- > to;) v.push_back(T(i, j));
    return v;
  };
  const std::uint32_t inb = t.key_torso[kTNeckBase];
  auto add = [&](std::int32_t id, const char* name, bool closed, std::vector<std::uint32_t> nodes) {
    t.curves.push_back({id, name, closed, std::move(nodes)});
  };
  add(kNeckBase, "neck_base", true, ring(inb));
  add(kShoulderLeft, "shoulder_left", false, column(N / 4, inb, ish));
  add(kShoulderRight, "shoulder_right", false, column(3 * N / 4, inb, ish));
  add(kArmholeLeft, "armhole_left", true, t.left_loop);
  add(kArmholeRight, "armhole_right", true, t.right_loop);
  add(kBust, "bust", true, ring(t.key_torso[kTBust]));
  add(kUnderbust, "underbust", true, ring(t.key_torso[kTUnderbust]));
  add(kWaist, "waist", true, ring(t.key_torso[kTWaist]));
  add(kHip, "hip", true, ring(t.key_torso[kTHip]));
  add(kThighLeft, "thigh_left", true, leg_ring(true, t.key_leg[kLThigh]));
  add(kThighRight, "thigh_right", true, leg_ring(false, t.key_leg[kLThigh]));
  add(kKneeLeft, "knee_left", true, leg_ring(true, t.key_leg[kLKnee]));
  add(kKneeRight, "knee_right", true, leg_ring(false, t.key_leg[kLKnee]));
  add(kAnkleLeft, "ankle_left", true, leg_ring(true, t.key_leg[kLAnkle]));
  add(kAnkleRight, "ankle_right", true, leg_ring(false, t.key_leg[kLAnkle]));
  add(kCentreFront, "centre_front", false, column(0, inb, 0));
  add(kCentreBack, "centre_back", false, column(N / 2, inb, 0));
  for (bool left : {true, false}) {
    std::vector<std::uint32_t> side = column(left ? N / 4 : 3 * N / 4, iap, 0);
    for (std::uint32_t r = 1; r < t.leg_rings; ++r) side.push_back(leg(left, r, N / 4));
    add(left ? kSideLeft : kSideRight, left ? "side_left" : "side_right", false, std::move(side));
  }
  add(kUpperArmLeft, "upper_arm_left", true, arm_ring(true, t.key_arm[1]));
  add(kUpperArmRight, "upper_arm_right", true, arm_ring(false, t.key_arm[1]));

  std::int32_t pid = 1;
  auto name_of = [&](std::int32_t c) -> std::string {
    for (const auto& c2 : t.curves)
      if (c2.id == c) return c2.name;
    return "?";
  };
  auto point = [&](std::int32_t c1, std::int32_t c2, std::uint32_t node) {
    t.points.push_back({pid++, name_of(c1) + "_x_" + name_of(c2), node, c1, c2});
  };
  point(kNeckBase, kCentreFront, T(inb, 0));
  point(kNeckBase, kCentreBack, T(inb, N / 2));
  point(kNeckBase, kShoulderLeft, T(inb, N / 4));
  point(kNeckBase, kShoulderRight, T(inb, 3 * N / 4));
  point(kShoulderLeft, kArmholeLeft, T(ish, N / 4));
  point(kShoulderRight, kArmholeRight, T(ish, 3 * N / 4));
  point(kArmholeLeft, kSideLeft, T(iap, N / 4));
  point(kArmholeRight, kSideRight, T(iap, 3 * N / 4));
  const std::pair<std::int32_t, TorsoKey> girths[] = {
      {kBust, kTBust}, {kUnderbust, kTUnderbust}, {kWaist, kTWaist}, {kHip, kTHip}};
  for (const auto& [c, key] : girths) {
    const std::uint32_t i = t.key_torso[key];
    point(c, kCentreFront, T(i, 0));
    point(c, kCentreBack, T(i, N / 2));
    point(c, kSideLeft, T(i, N / 4));
    point(c, kSideRight, T(i, 3 * N / 4));
  }
  const std::tuple<std::int32_t, std::int32_t, LegKey> legs[] = {
      {kThighLeft, kThighRight, kLThigh}, {kKneeLeft, kKneeRight, kLKnee}, {kAnkleLeft, kAnkleRight, kLAnkle}};
  for (const auto& [cl, cr, key] : legs) {
    point(cl, kSideLeft, leg(true, t.key_leg[key], N / 4));
    point(cr, kSideRight, leg(false, t.key_leg[key], N / 4));
  }
  return t;
}

// ------------------------------------------------------------- geometry

Expected<std::vector<Vec3d>> mannequin_positions(const MannequinParams& p, const MannequinTopology& t) {
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
    pos[t.bridge_base + b - 1].x() = 0;  // exactly on the symmetry line: the
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
    if (Status st = add_feature_point(body, q.id, q.name, {AttribNodeKind::kVertex, q.node, Vec3d::Zero(), 0}, q.c1, q.c2);
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
    if (Status s = validate_params(params[i]); !s) return Status(s.code(), "body " + std::to_string(i) + ": " + s.message());
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

// -------------------------------------------------------------- sampling

namespace {

// xoshiro256** (Blackman & Vigna) seeded by splitmix64: fixed integer
// arithmetic, so the stream is the same on every platform.
class Xoshiro256 {
 public:
  explicit Xoshiro256(std::uint64_t seed) noexcept {
    for (auto& x : s_) {
      seed += 0x9e3779b97f4a7c15ull;
      std::uint64_t z = seed;
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
      x = z ^ (z >> 31);
    }
  }
  std::uint64_t next() noexcept {
    const std::uint64_t r = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return r;
  }
  double uniform() noexcept { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Marsaglia polar method: only sqrt (correctly rounded) and log.
  double normal() noexcept {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = 2 * uniform() - 1;
      v = 2 * uniform() - 1;
      s = u * u + v * v;
    } while (s >= 1 || s == 0);
    const double f = std::sqrt(-2 * std::log(s) / s);
    spare_ = v * f;
    has_spare_ = true;
    return u * f;
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) noexcept { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4];
  double spare_ = 0;
  bool has_spare_ = false;
};

double clampz(double z) { return std::clamp(z, -2.5, 2.5); }

}  // namespace

MannequinParams sample_mannequin(std::uint64_t seed, std::size_t index) {
  // Body `index` has its own stream, its seed a splitmix64 finalisation of
  // (seed, index): any body is drawn without the ones before it, so a body
  // source holds no per-body state.
  std::uint64_t z = seed + (static_cast<std::uint64_t>(index) + 1) * 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  Xoshiro256 rng(z ^ (z >> 31));
  {
    const bool female = rng.uniform() < 0.5;
    // Latent factors: stature and size (adiposity/build). Girths grow weakly
    // with stature and strongly with size; each measure adds its own noise.
    const double zh = clampz(rng.normal()), zs = clampz(rng.normal()), zb = clampz(rng.normal());
    MannequinParams p;
    p.height = female ? 1.640 + 0.065 * zh : 1.760 + 0.070 * zh;
    const double hs = p.height / (female ? 1.64 : 1.76);
    const double gh = std::pow(hs, 0.5);  // girth vs stature
    auto girth = [&](double base, double ks, double noise) {
      return base * gh * std::exp(ks * zs + noise * clampz(rng.normal()));
    };
    if (female) {
      p.neck_girth = girth(0.345, 0.05, 0.03);
      p.bust_girth = girth(0.93, 0.09, 0.03);
      p.underbust_girth = p.bust_girth * std::clamp(0.84 + 0.03 * zb, 0.76, 0.92);
      p.waist_girth = girth(0.76, 0.13, 0.04);
      p.hip_girth = girth(1.00, 0.08, 0.03);
      p.thigh_girth = girth(0.58, 0.10, 0.04);
      p.knee_girth = girth(0.37, 0.06, 0.03);
      p.ankle_girth = girth(0.225, 0.04, 0.03);
      p.upper_arm_girth = girth(0.28, 0.11, 0.04);
      p.shoulder_width = 0.385 * hs * std::exp(0.02 * zs + 0.03 * clampz(rng.normal()));
      p.back_length = 0.405 * hs * std::exp(0.03 * clampz(rng.normal()));
      p.inseam = p.height * std::clamp(0.455 + 0.012 * rng.normal(), 0.40, 0.50);
    } else {
      p.neck_girth = girth(0.39, 0.05, 0.03);
      p.bust_girth = girth(1.00, 0.08, 0.03);
      p.underbust_girth = p.bust_girth * std::clamp(0.91 + 0.02 * zb, 0.84, 0.97);
      p.waist_girth = girth(0.88, 0.12, 0.04);
      p.hip_girth = girth(1.00, 0.07, 0.03);
      p.thigh_girth = girth(0.56, 0.09, 0.04);
      p.knee_girth = girth(0.385, 0.05, 0.03);
      p.ankle_girth = girth(0.235, 0.04, 0.03);
      p.upper_arm_girth = girth(0.31, 0.09, 0.04);
      p.shoulder_width = 0.44 * hs * std::exp(0.02 * zs + 0.03 * clampz(rng.normal()));
      p.back_length = 0.44 * hs * std::exp(0.03 * clampz(rng.normal()));
      p.inseam = p.height * std::clamp(0.46 + 0.012 * rng.normal(), 0.40, 0.50);
    }
    // Clamps that keep the set inside validate_params' ranges and order.
    p.height = std::clamp(p.height, 1.45, 2.05);
    p.inseam = std::clamp(p.inseam, 0.39 * p.height, 0.51 * p.height);
    auto cl = [](double& v, double lo, double hi) { v = std::clamp(v, lo, hi); };
    cl(p.neck_girth, 0.28, 0.54);
    cl(p.bust_girth, 0.70, 1.50);
    cl(p.underbust_girth, 0.60, p.bust_girth);
    cl(p.waist_girth, 0.52, 1.50);
    cl(p.hip_girth, 0.74, 1.55);
    cl(p.thigh_girth, 0.40, 0.74 * p.hip_girth);
    cl(p.knee_girth, 0.28, 0.88 * p.thigh_girth);
    cl(p.ankle_girth, 0.17, 0.84 * p.knee_girth);
    cl(p.upper_arm_girth, 0.19, 0.44 * p.bust_girth);
    p.neck_girth = std::min(p.neck_girth, 0.49 * p.bust_girth);
    cl(p.shoulder_width, std::max(0.31, 0.42 * p.neck_girth + 0.11), 0.55);
    const double nape = 0.848 * p.height, armpit = nape - 0.118 * p.height;
    // waist between (crotch + 0.13) and (armpit - 0.09)
    p.back_length = std::clamp(p.back_length, std::max(0.31, nape - (armpit - 0.09)),
                               std::min(0.57, 0.463 * p.height - 0.135));
    if (nape - p.back_length < p.inseam + 0.13) p.inseam = nape - p.back_length - 0.13;
    p.inseam = std::max(p.inseam, 0.385 * p.height);
    return p;
  }
}

std::vector<MannequinParams> sample_mannequins(std::size_t n, std::uint64_t seed) {
  std::vector<MannequinParams> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) out.push_back(sample_mannequin(seed, i));
  return out;
}

}  // namespace atelier
