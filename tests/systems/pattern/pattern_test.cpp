// Pattern pieces (issue 22): seam allowances with mitred corners, notches
// matched by arc length, the sewability check of partner seams, mirrored
// pieces, and the SVG / DXF / PNG files read back (DXF by ezdxf).
#include <atelier/io/png.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/pattern/flatten.h>
#include <atelier/systems/pattern/pattern.h>
#include <atelier/systems/pattern/pattern_files.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/flatten_shapes.h"
#include "tests/support/run_command.h"

namespace atelier {
namespace {

using flatten_shapes::join;
using flatten_shapes::Skirt;

Skirt skirt(double r = 0.2, double h = 0.5, int nu = 16, int nv = 5) {
  return flatten_shapes::skirt(r, r, h, nu, nv);
}

const PatternPiece& piece_named(const PatternSet& set, const std::string& name) {
  for (const PatternPiece& p : set.pieces)
    if (p.name == name) return p;
  throw std::runtime_error("no piece " + name);
}

TEST(Pattern, SkirtSeamsAreSewableAndAllowancesAreMitred) {
  Skirt k = skirt();
  ASSERT_TRUE(validate(k.model)) << validate(k.model).to_string();
  FlattenOptions fo;
  fo.grain = Vec3d(0, 0, 1);  // vertical on the body
  auto flat = flatten_surfaces(k.model, fo);
  ASSERT_TRUE(flat) << flat.status().to_string();
  ASSERT_TRUE(validate(k.model));
  PatternOptions po;
  po.seam_allowance_mm = 10;
  po.hem_allowance_mm = 30;
  po.seam_allowances = {{k.seam_b, 15}};
  po.notch_spacing_mm = 100;
  const std::vector<SurfaceIdx> pieces{k.front, k.back};
  auto set = make_pattern(k.model, pieces, po);
  ASSERT_TRUE(set) << set.status().to_string();
  ASSERT_EQ(set->seams.size(), 2u);
  for (const SeamCheck& c : set->seams) {
    EXPECT_TRUE(c.ok);
    ASSERT_EQ(c.members.size(), 2u);
    for (const SeamMemberLength& ml : c.members) {
      EXPECT_NEAR(ml.length_3d_mm, 1000 * k.h, 1e-9);
      EXPECT_NEAR(ml.length_2d_mm, 1000 * k.h, 1e-6);  // developable: exact
      EXPECT_TRUE(ml.boundary);
    }
  }
  EXPECT_EQ(set->failed_seams(), 0u);
  // The front is a rectangle W x H (grain along +v): seam a on its left,
  // seam b on its right, hems at the bottom and top.
  const PatternPiece& front = piece_named(*set, "front");
  const double r = 0.2;
  const double W = 1000 * k.nu * 2 * r * std::sin(M_PI / (2 * k.nu)), H = 1000 * k.h;
  Eigen::AlignedBox2d sew, cut;
  for (const Vec2d& p : front.sew_line[0]) sew.extend(p);
  for (const Vec2d& p : front.cut_line[0]) cut.extend(p);
  EXPECT_NEAR(sew.min().x(), 0, 1e-6);
  EXPECT_NEAR(sew.min().y(), 0, 1e-6);
  EXPECT_NEAR(sew.max().x(), W, 1e-6);
  EXPECT_NEAR(sew.max().y(), H, 1e-6);
  // Cut line: left -10 (seam a), right +15 (seam b), bottom -30, top +30.
  EXPECT_NEAR(cut.min().x(), -10, 1e-6);
  EXPECT_NEAR(cut.max().x(), W + 15, 1e-6);
  EXPECT_NEAR(cut.min().y(), -30, 1e-6);
  EXPECT_NEAR(cut.max().y(), H + 30, 1e-6);
  // Mitred corners: the four corners of that rectangle are cut-line points,
  // and every cut-line point lies on its sides.
  for (const Vec2d& c : {Vec2d(-10, -30), Vec2d(W + 15, -30), Vec2d(W + 15, H + 30), Vec2d(-10, H + 30)}) {
    double best = 1e9;
    for (const Vec2d& p : front.cut_line[0]) best = std::min(best, (p - c).norm());
    EXPECT_LT(best, 1e-6) << "corner " << c.transpose();
  }
  for (const Vec2d& p : front.cut_line[0]) {
    const double d =
        std::min({std::abs(p.x() + 10), std::abs(p.x() - W - 15), std::abs(p.y() + 30), std::abs(p.y() - H - 30)});
    EXPECT_LT(d, 1e-6) << p.transpose();
  }
  // Outer sew line counter-clockwise; area W x H.
  EXPECT_NEAR(front.area_mm2, W * H, 1e-3);
  // Allowance runs: two seams and two hems with their widths.
  std::map<std::string, double> widths;
  for (const AllowanceRun& r : front.allowances)
    widths[r.seam.valid() ? (r.seam == k.seam_a ? "a" : "b") : "hem" + std::to_string(widths.size())] = r.width_mm;
  EXPECT_EQ(widths.size(), 4u);
  EXPECT_EQ(widths["a"], 10);
  EXPECT_EQ(widths["b"], 15);
  // Grain line vertical.
  EXPECT_NEAR(front.grain_line[0].x(), front.grain_line[1].x(), 1e-9);
  EXPECT_GT(front.grain_line[1].y(), front.grain_line[0].y());
}

TEST(Pattern, NotchesMatchBetweenPartnersByArcLength) {
  Skirt k = skirt(0.2, 0.5, 12, 7);
  // A mark on seam a: an attribute node on the front's seam node j = 3.
  const NodeIdx marked = k.node(k.front, 0, 3);
  (void)k.model.new_attrib_node(k.front, AttribNodeKind::kVertex, marked.value, Vec3d::Zero(),
                                k.model.position(marked));
  FlattenOptions fo;
  fo.grain = Vec3d(0, 0, 1);
  ASSERT_TRUE(flatten_surfaces(k.model, fo));
  PatternOptions po;
  po.notch_spacing_mm = 120;
  const std::vector<SurfaceIdx> pieces{k.front, k.back};
  auto set = make_pattern(k.model, pieces, po);
  ASSERT_TRUE(set) << set.status().to_string();
  // Notch fractions on seam a: ends, the mark (3/7), every 120 mm of 500.
  std::vector<double> want{0, 120 / 500.0, 3 / 7.0, 240 / 500.0, 360 / 500.0, 480 / 500.0, 1};
  for (SurfaceIdx s : pieces) {
    const PatternPiece& p = piece_named(*set, k.model.surfaces.name[s.value]);
    const NodeIdx a0 = k.node(s, s == k.front ? 0 : k.nu, 0), a1 = k.node(s, s == k.front ? 0 : k.nu, k.nv);
    const Vec2d p0 = 1000 * k.model.nodes.uv[a0.value], p1 = 1000 * k.model.nodes.uv[a1.value];
    std::vector<const PatternNotch*> on_a;
    for (const PatternNotch& n : p.notches)
      if (n.seam == k.seam_a) on_a.push_back(&n);
    ASSERT_EQ(on_a.size(), want.size());
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_NEAR(on_a[i]->fraction, want[i], 1e-12);
      // On the seam's straight 2D image, at that fraction of its length.
      EXPECT_LT((on_a[i]->at - (p0 + want[i] * (p1 - p0))).norm(), 1e-6);
      EXPECT_NEAR(on_a[i]->depth, 10, 1e-12);
      // The slit points out of the piece: away from the piece's centroid side.
      EXPECT_GT(on_a[i]->outward.dot(on_a[i]->at - p.label_at), 0);
    }
  }
}

TEST(Pattern, MismatchedSeamsAreReportedPerSeam) {
  Skirt k = skirt();
  ASSERT_TRUE(flatten_surfaces(k.model));
  // The back piece's pattern 1% too large (a pattern from elsewhere).
  for (std::size_t v = 0; v < k.model.nodes.uv.size(); ++v)
    if (k.model.nodes.surface[v] == k.back) k.model.nodes.uv[v] *= 1.01;
  const std::vector<SurfaceIdx> pieces{k.front, k.back};
  auto set = make_pattern(k.model, pieces);
  ASSERT_TRUE(set);
  ASSERT_EQ(set->seams.size(), 2u);
  EXPECT_EQ(set->failed_seams(), 2u);
  for (const SeamCheck& c : set->seams) {
    EXPECT_FALSE(c.ok);
    EXPECT_NEAR(c.max_difference_mm, 0.01 * 1000 * k.h, 1e-6);  // 5 mm > 2 mm
    EXPECT_NEAR(c.max_deviation_3d, 0.01, 1e-9);                // 1% > 0.5%
  }
  // Within the tolerances when they are loosened accordingly.
  PatternOptions loose;
  loose.length_tolerance_mm = 5.001;
  loose.length_tolerance_3d = 0.01001;
  auto ok = make_pattern(k.model, pieces, loose);
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->failed_seams(), 0u);
}

TEST(Pattern, CurvedSeamLengthsAreMeasuredAsStated) {
  // A spherical cap cut along a diameter into two halves joined by one seam.
  flatten_shapes::SplitCap sc = flatten_shapes::split_cap(10, M_PI / 4, 0.15);
  Model& m = sc.model;
  const std::vector<SurfaceIdx> halves{sc.upper, sc.lower};
  const JointIdx seam = sc.seam;
  const std::vector<NodeIdx>&a = sc.upper_chain, &b = sc.lower_chain;
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  auto flat = flatten_surfaces(m);
  ASSERT_TRUE(flat) << flat.status().to_string();
  auto set = make_pattern(m, halves);
  ASSERT_TRUE(set);
  ASSERT_EQ(set->seams.size(), 1u);
  const SeamCheck& c = set->seams[0];
  EXPECT_EQ(c.joint, seam);
  // Lengths measured independently along the chains.
  double l3 = 0, l2[2] = {0, 0};
  for (std::size_t i = 0; i + 1 < a.size(); ++i) {
    l3 += 1000 * (m.position(a[i + 1]) - m.position(a[i])).norm();
    l2[0] += 1000 * (m.nodes.uv[a[i + 1].value] - m.nodes.uv[a[i].value]).norm();
    l2[1] += 1000 * (m.nodes.uv[b[i + 1].value] - m.nodes.uv[b[i].value]).norm();
  }
  ASSERT_EQ(c.members.size(), 2u);
  EXPECT_NEAR(c.members[0].length_3d_mm, l3, 1e-9);
  EXPECT_NEAR(c.members[0].length_2d_mm, l2[0], 1e-9);
  EXPECT_NEAR(c.members[1].length_2d_mm, l2[1], 1e-9);
  EXPECT_NEAR(c.max_difference_mm, std::abs(l2[0] - l2[1]), 1e-9);
  const double dev = std::max(std::abs(l2[0] - l3), std::abs(l2[1] - l3)) / l3;
  EXPECT_NEAR(c.max_deviation_3d, dev, 1e-12);
  EXPECT_EQ(c.ok, std::abs(l2[0] - l2[1]) <= 2 && dev <= 0.005);
  // The two halves are mirror images: their seams agree to well under 2 mm.
  EXPECT_LT(c.max_difference_mm, 0.05);
  RecordProperty("seam_deviation_3d", std::to_string(dev));
}

TEST(Pattern, MirroredPieceIsTheReflection) {
  Skirt k = skirt();
  FlattenOptions fo;
  fo.grain = Vec3d(0, 0, 1);
  ASSERT_TRUE(flatten_surfaces(k.model, fo));
  PatternOptions po;
  po.mirror = {k.front};
  const std::vector<SurfaceIdx> pieces{k.front, k.back};
  auto set = make_pattern(k.model, pieces, po);
  ASSERT_TRUE(set);
  ASSERT_EQ(set->pieces.size(), 3u);
  const PatternPiece& f = piece_named(*set, "front");
  const PatternPiece& mf = piece_named(*set, "front (mirrored)");
  EXPECT_TRUE(mf.mirrored);
  double W = 0;
  for (const Vec2d& p : f.sew_line[0]) W = std::max(W, p.x());
  // Same points reflected about u = W / 2, same orientation (CCW), same area.
  ASSERT_EQ(mf.sew_line[0].size(), f.sew_line[0].size());
  for (const Vec2d& p : f.sew_line[0]) {
    const Vec2d q(W - p.x(), p.y());
    double best = 1e9;
    for (const Vec2d& x : mf.sew_line[0]) best = std::min(best, (x - q).norm());
    EXPECT_LT(best, 1e-9);
  }
  EXPECT_NEAR(mf.area_mm2, f.area_mm2, 1e-6);
  EXPECT_GT(mf.area_mm2, 0);
  ASSERT_EQ(mf.notches.size(), f.notches.size());
  for (std::size_t i = 0; i < f.notches.size(); ++i) {
    EXPECT_LT((mf.notches[i].at - Vec2d(W - f.notches[i].at.x(), f.notches[i].at.y())).norm(), 1e-9);
    EXPECT_NEAR(mf.notches[i].outward.x(), -f.notches[i].outward.x(), 1e-12);
  }
}

TEST(Pattern, SharpCornersAreBevelledAndTightCurvesLoseTheirLoops) {
  // A flat piece (mm / 1000): a 100 x 60 rectangle with a 23-degree tip on
  // its left and a semicircular bite of radius 5 (tighter than the 10 mm
  // allowance) in its top edge, fanned from (50, 20).
  PolygonSoup s;
  std::vector<Vec2d> loop{{0, 0}, {100, 0}, {100, 60}};
  for (int i = 0; i <= 16; ++i) loop.emplace_back(50 + 5 * std::cos(-M_PI * i / 16), 60 + 5 * std::sin(-M_PI * i / 16));
  loop.emplace_back(0, 60);
  loop.emplace_back(-150, 30);
  s.positions.emplace_back(0.050, 0.020, 0);
  for (const Vec2d& q : loop) s.positions.emplace_back(q.x() / 1000, q.y() / 1000, 0);
  const auto n = static_cast<std::uint32_t>(loop.size());
  for (std::uint32_t i = 0; i < n; ++i) flatten_shapes::tri(s, 0, 1 + i, 1 + (i + 1) % n);
  Model m;
  ASSERT_TRUE(add_polygon_surface(m, "tip", s));
  ASSERT_TRUE(flatten_surfaces(m));
  PatternOptions po;
  po.seam_allowance_mm = 10;
  const std::vector<SurfaceIdx> pieces{SurfaceIdx{0}};
  auto set = make_pattern(m, pieces, po);
  ASSERT_TRUE(set);
  const PatternPiece& p = set->pieces[0];
  // Every cut-line point is at least the allowance from the sew line (no
  // loop left inside) and no farther than the mitre limit allows.
  auto dist_to_sew = [&](const Vec2d& x) {
    double d = 1e9;
    const auto& L = p.sew_line[0];
    for (std::size_t i = 0; i < L.size(); ++i) {
      const Vec2d a = L[i], b = L[(i + 1) % L.size()];
      const double t = std::clamp((x - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      d = std::min(d, (a + t * (b - a) - x).norm());
    }
    return d;
  };
  for (const Vec2d& x : p.cut_line[0]) {
    EXPECT_GT(dist_to_sew(x), 10 - 1e-6) << x.transpose();
    EXPECT_LT(dist_to_sew(x), 4 * 10 + 1e-6) << x.transpose();
  }
  // The tip (22.6 degrees) would mitre to 10 / sin(11.3) = 51 mm > 40 mm: bevelled.
  // Bevel: two cut-line points, each one allowance from the tip.
  Vec2d tip = p.sew_line[0][0];  // the sew-line point farthest from the centroid
  for (const Vec2d& q : p.sew_line[0])
    if ((q - p.label_at).norm() > (tip - p.label_at).norm()) tip = q;
  EXPECT_EQ(std::count_if(p.cut_line[0].begin(), p.cut_line[0].end(),
                          [&](const Vec2d& x) { return std::abs((x - tip).norm() - 10) < 1e-6; }),
            2);
  // The bite's 17 arc points leave a single crossing point on the cut line:
  // four mitred corners, one crossing, two bevel points.
  EXPECT_EQ(p.sew_line[0].size(), 22u);
  EXPECT_EQ(p.cut_line[0].size(), 7u);
}

}  // namespace
}  // namespace atelier
