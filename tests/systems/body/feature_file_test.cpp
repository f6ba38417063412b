// Feature curves from a file on a user's body (issue 26, "any reference
// body"): the mannequin written in centimetres and Z-up with its own curves
// as JSON reads back with the same curves and crossings as the engine's,
// members of its family carry them by topology, and bad curves are named.
#include <atelier/storage/validate.h>
#include <atelier/systems/body/body_file.h>
#include <atelier/systems/body/mannequin.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "support/feature_curve_files.h"
#include "support/run_command.h"

using namespace atelier;
namespace fs = std::filesystem;
using atelier::testing::same_frame;
using atelier::testing::to_cm_z_up;

namespace {

struct Files {
  fs::path dir;
  ReferenceBody mannequin;
};

/// The default mannequin as m.obj + m.json (metres, Y up, no units given)
/// and cm.obj + cm.json (centimetres, Z up, declared in the JSON).
const Files& files() {
  static const Files f = [] {
    Files r;
    r.dir = atelier::testing::process_scratch_dir("feature_file_body");
    auto m = make_mannequin();
    if (!m) throw Error(m.status());
    r.mannequin = std::move(*m);
    atelier::testing::write_body_obj(r.mannequin, r.dir / "m.obj", same_frame);
    atelier::testing::write_body_obj(r.mannequin, r.dir / "cm.obj", to_cm_z_up);
    atelier::testing::write_body_curves(r.mannequin, r.dir / "m.json", same_frame, "", "");
    atelier::testing::write_body_curves(r.mannequin, r.dir / "cm.json", to_cm_z_up, "cm", "z");
    return r;
  }();
  return f;
}

double polyline_gap(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  if (a.size() != b.size()) return 1e9;
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
  return worst;
}

}  // namespace

TEST(FeatureFile, CurvesInCentimetresZUpAreTheMannequinsOwnAndCrossWhereItsDo) {
  const Files& f = files();
  auto cm = read_reference_body(f.dir / "cm.obj", {.frame = {0.01, UpAxis::kZ}, .features = f.dir / "cm.json"});
  auto m = read_reference_body(f.dir / "m.obj", {.features = f.dir / "m.json"});
  ASSERT_TRUE(cm) << cm.status().message();
  ASSERT_TRUE(m) << m.status().message();
  for (const ReferenceBody* b : {&*cm, &*m}) {
    EXPECT_TRUE(validate(b->model)) << validate(b->model).message();
    EXPECT_TRUE(validate_features(*b)) << validate_features(*b).message();
    ASSERT_EQ(b->curves.size(), f.mannequin.curves.size());
    for (const FeatureCurve& c : f.mannequin.curves) {
      const FeatureCurve* got = b->find_curve(c.name);
      ASSERT_NE(got, nullptr) << c.name;
      EXPECT_EQ(got->closed, c.closed);
      // Stored by location on the skin's faces, evaluated where the engine's are.
      for (AttribNodeIdx a : b->model.attrib_edges.nodes.row(got->edge.value))
        EXPECT_EQ(b->model.attrib_nodes.kind[a.value], AttribNodeKind::kFace);
      EXPECT_LE(polyline_gap(*feature_curve_polyline(*b, got->id), *feature_curve_polyline(f.mannequin, c.id)), 1e-12)
          << c.name;
    }
    // Every crossing the mannequin declares is found, at its place (both
    // curves pass through the same vertex there).
    for (const FeaturePoint& p : f.mannequin.points) {
      const std::string n1 = f.mannequin.find_curve(p.curve1)->name, n2 = f.mannequin.find_curve(p.curve2)->name;
      const FeaturePoint* got = nullptr;
      for (const FeaturePoint& q : b->points) {
        const std::string a = b->find_curve(q.curve1)->name, c = b->find_curve(q.curve2)->name;
        if ((a == n1 && c == n2) || (a == n2 && c == n1)) got = &q;
      }
      ASSERT_NE(got, nullptr) << p.name;
      EXPECT_LE(
          (b->model.attrib_nodes.position[got->node.value] - f.mannequin.model.attrib_nodes.position[p.node.value])
              .norm(),
          1e-9)
          << p.name;
      // The frame of seed 000 eq. (1) is well defined there.
      auto fr = feature_frame(*b, got->id);
      ASSERT_TRUE(fr) << fr.status().message();
      EXPECT_GT(std::abs(fr->triple()), 0.1) << got->name;
    }
  }
  // The two frames give the engine the same body and curves.
  for (const FeatureCurve& c : m->curves)
    EXPECT_LE(polyline_gap(*feature_curve_polyline(*m, c.id), *feature_curve_polyline(*cm, cm->find_curve(c.name)->id)),
              1e-12);
}

TEST(FeatureFile, FamilyMembersCarryTheCurvesByTopology) {
  const Files& f = files();
  auto ref = read_reference_body(f.dir / "cm.obj", {.frame = {0.01, UpAxis::kZ}, .features = f.dir / "cm.json"});
  ASSERT_TRUE(ref) << ref.status().message();
  auto topo = make_mannequin_topology();
  ASSERT_TRUE(topo);
  MannequinParams p;
  p.height = 1.82;
  p.waist_girth = 0.9;
  p.hip_girth = 1.06;
  p.bust_girth = 1.0;
  auto member = make_mannequin(p, *topo);  // the engine's own curves on another body
  ASSERT_TRUE(member);
  auto moved = with_positions(*ref, member->model.nodes.position);
  ASSERT_TRUE(moved) << moved.status().message();
  for (const FeatureCurve& c : member->curves) {
    const FeatureCurve* got = moved->find_curve(c.name);
    ASSERT_NE(got, nullptr);
    const auto a = *feature_curve_polyline(*moved, got->id), b = *feature_curve_polyline(*member, c.id);
    EXPECT_LE(polyline_gap(a, b), 1e-9) << c.name;
    // Not trivially: the member's curve is elsewhere than the reference's.
    if (c.name == "waist") {
      EXPECT_GT(polyline_gap(a, *feature_curve_polyline(*ref, got->id)), 0.01);
    }
  }
}

TEST(FeatureFile, FarPointsUnknownNamesAndMissingFilesAreNamedAndLeaveTheBodyAsItWas) {
  const Files& f = files();
  // waist (written first: line 4, after units and up), point 3 (line 8) moved 3 cm out from the body's axis.
  auto file = read_feature_curves(f.dir / "cm.json");
  ASSERT_TRUE(file);
  ASSERT_EQ(file->curves[0].name, "waist");
  Vec3d centre = Vec3d::Zero();
  for (const Vec3d& p : file->curves[0].points) centre += p / static_cast<double>(file->curves[0].points.size());
  Vec3d& q = file->curves[0].points[3];
  Vec3d out = q - centre;
  out.z() = 0;  // horizontal in the file's Z-up frame
  q += 3.0 * out.normalized();
  atelier::testing::write_curves_json(*file, f.dir / "far.json");
  auto far = read_reference_body(f.dir / "cm.obj", {.frame = {0.01, UpAxis::kZ}, .features = f.dir / "far.json"});
  ASSERT_FALSE(far);
  const std::string msg = far.status().message();
  EXPECT_NE(msg.find("far.json:8: curve 'waist', point 3 is "), std::string::npos) << msg;
  EXPECT_NE(msg.find(" mm from the body's surface (at most 10.0 mm)"), std::string::npos) << msg;
  // A larger tolerance takes it (snapped onto the surface).
  auto loose = read_reference_body(
      f.dir / "cm.obj", {.frame = {0.01, UpAxis::kZ}, .features = f.dir / "far.json", .snap = {.tolerance = 0.05}});
  ASSERT_TRUE(loose) << loose.status().message();

  // The body's own units instead of the file's declared ones: every point is
  // 100 times too far (the message suggests the units).
  {
    std::ofstream o(f.dir / "nounits.json");
    o << "{\"curves\": [{\"name\": \"waist\", \"closed\": true, \"points\": [[0, 0, 100], [10, 0, 100], [0, 10, "
         "100]]}]}";
  }
  auto wrong = read_reference_body(f.dir / "m.obj", {.features = f.dir / "nounits.json"});
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.status().message().find("units"), std::string::npos) << wrong.status().message();

  // Unknown names and missing files name the file.
  {
    std::ofstream o(f.dir / "unknown.json");
    o << "{\"curves\": [\n{\"name\": \"belly\", \"closed\": true, \"points\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]}]}";
  }
  auto unknown = read_reference_body(f.dir / "m.obj", {.features = f.dir / "unknown.json"});
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.status().message().find("unknown.json:2: curve 0: unknown curve name \"belly\""), std::string::npos)
      << unknown.status().message();
  auto none = read_reference_body(f.dir / "m.obj", {.features = f.dir / "none.json"});
  ASSERT_FALSE(none);
  EXPECT_NE(none.status().message().find("none.json: no such file"), std::string::npos);

  // The operator is transactional: a good curve before a bad one is not added.
  auto bare = read_reference_body(f.dir / "m.obj");  // mannequin topology: its own curves
  ASSERT_TRUE(bare);
  ReferenceBody body = f.mannequin;
  body.curves.clear();
  body.points.clear();
  const std::size_t attrib_nodes = body.model.attrib_nodes.slots.size();
  const auto hip = *feature_curve_polyline(f.mannequin, f.mannequin.find_curve("hip")->id);
  std::vector<Vec3d> off = *feature_curve_polyline(f.mannequin, f.mannequin.find_curve("bust")->id);
  off[5] += Vec3d(0, 0, 0.5);
  const FeaturePolyline lines[] = {{"hip", true, hip, {}}, {"bust", true, off, {}}};
  auto r = add_snapped_feature_curves(body, lines);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("curve 'bust', point 5"), std::string::npos) << r.status().message();
  EXPECT_TRUE(body.curves.empty());
  EXPECT_EQ(body.model.attrib_nodes.slots.size(), attrib_nodes);
  // A name the body has already.
  const FeaturePolyline again[] = {{"waist", true, hip, {}}};
  auto dup = add_snapped_feature_curves(*bare, again);
  ASSERT_FALSE(dup);
  EXPECT_NE(dup.status().message().find("already has a curve"), std::string::npos);
}
