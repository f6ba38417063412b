// The mannequin's topology (systems/body/mannequin.h): rings of nodes over
// the torso, the legs and the short arms, their faces, the feature curves
// and points. The positions are in mannequin.cpp.
#include <atelier/systems/body/mannequin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "mannequin_detail.h"

namespace atelier {

namespace {

// Nominal segment lengths (m) at the default body; ring counts follow them
// so that rings are about 6/L cm apart. The shoulder segment is counted by
// its slanted length, not its rise.
constexpr std::array<double, mannequin_detail::kTKeys - 1> kTorsoSeg = {0.10,  0.17, 0.10, 0.09,
                                                                        0.035, 0.15, 0.09, 0.06};
constexpr std::array<std::uint32_t, mannequin_detail::kTKeys - 1> kTorsoMin = {2, 2, 2, 2, 1, 2, 2, 1};
constexpr std::array<double, mannequin_detail::kLKeys - 1> kLegSeg = {0.04, 0.26, 0.39};
constexpr std::array<std::uint32_t, mannequin_detail::kLKeys - 1> kLegMin = {2, 3, 3};
constexpr double kArmSeg = 0.12;

std::uint32_t seg_count(double len, std::uint32_t level, std::uint32_t min) {
  const double h = 0.06 / level;
  return std::max<std::uint32_t>(min, static_cast<std::uint32_t>(std::lround(len / h)));
}

}  // namespace

Expected<MannequinTopology> make_mannequin_topology(const MannequinResolution& res) {
  using namespace mannequin_detail;  // NOLINT(google-build-using-namespace): the layout's key levels
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
  auto T = [&](std::uint32_t i, std::uint32_t j) {
    return static_cast<std::uint32_t>(t.torso_node[std::size_t{i} * N + j % N]);
  };
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

}  // namespace atelier
