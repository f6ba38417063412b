// Profile templates on a user's body with feature curves from a file (issue
// 26, "any reference body"): the mannequin written by our code in
// centimetres and Z-up, with its own curves written as JSON in that frame,
// encodes the skirt where the mannequin does and regenerates it on family
// members as the same files in metres and Y-up do, up to the transform.
#include <atelier/storage/validate.h>
#include <atelier/systems/body/body_file.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/profile/project_templates.h>
#include <atelier/systems/profile/regenerate.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "support/feature_curve_files.h"
#include "support/run_command.h"

using namespace atelier;
namespace fs = std::filesystem;

namespace {

std::vector<Vec3d> live_positions(const Model& m) {
  std::vector<Vec3d> out;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v})) out.push_back(m.nodes.position[v]);
  return out;
}

double gap(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  if (a.size() != b.size()) return 1e9;
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
  return worst;
}

}  // namespace

TEST(ProfileOnFileCurves, SkirtInCentimetresZUpRegeneratesAsInMetresYUp) {
  const fs::path d = atelier::testing::scratch_dir("profile_feature_file");
  auto topo = make_mannequin_topology();
  ASSERT_TRUE(topo);
  auto mannequin = make_mannequin(MannequinParams{}, *topo);
  ASSERT_TRUE(mannequin);
  // Float coordinates, as bodies written by the engine have: 100 times them
  // is exact, so both frames give the engine the same bits. (With full
  // doubles the frames differ by an ulp, and the skirt's rings, cast by rays
  // that pass exactly through the symmetric mannequin's edges, take another
  // face's normal: 0.75 mm at encoding, mm after regeneration.)
  std::vector<Vec3d> rounded = mannequin->model.nodes.position;
  for (Vec3d& q : rounded) q = round_to_float(q);
  ASSERT_TRUE(set_positions(*mannequin, rounded));
  using atelier::testing::same_frame;
  using atelier::testing::to_cm_z_up;
  atelier::testing::write_body_obj(*mannequin, d / "m.obj", same_frame);
  atelier::testing::write_body_obj(*mannequin, d / "cm.obj", to_cm_z_up);
  atelier::testing::write_body_curves(*mannequin, d / "m.json", same_frame, "m", "y");
  atelier::testing::write_body_curves(*mannequin, d / "cm.json", to_cm_z_up, "", "");  // the body's frame
  auto m = read_reference_body(d / "m.obj", {.features = d / "m.json"});
  auto cm = read_reference_body(d / "cm.obj", {.frame = {0.01, UpAxis::kZ}, .features = d / "cm.json"});
  ASSERT_TRUE(m) << m.status().message();
  ASSERT_TRUE(cm) << cm.status().message();

  auto skirt_m = make_skirt_template(*m);
  auto skirt_cm = make_skirt_template(*cm);
  auto skirt_own = make_skirt_template(*mannequin);
  ASSERT_TRUE(skirt_m) << skirt_m.status().message();
  ASSERT_TRUE(skirt_cm) << skirt_cm.status().message();
  ASSERT_TRUE(skirt_own) << skirt_own.status().message();
  EXPECT_TRUE(validate(skirt_cm->model)) << validate(skirt_cm->model).message();
  // Placed where the mannequin's own curves place it (the nodes are at the
  // same places relative to the same curves), in either frame.
  EXPECT_LE(gap(live_positions(skirt_m->model), live_positions(skirt_own->model)), 1e-9);
  EXPECT_LE(gap(live_positions(skirt_m->model), live_positions(skirt_cm->model)), 1e-9);
  // Its waist nodes at the centre front and back are on feature points the
  // file's crossings made (seed 000 eq. (1)).
  std::size_t on_points = 0;
  for (const auto& e : skirt_cm->encodings.nodes) on_points += e.mode == NodeEncodingMode::kFeaturePoint;
  EXPECT_EQ(on_points, 2u);

  // Family members: other mannequins, the same topology.
  std::vector<MannequinParams> family(3);
  family[0].height = 1.6, family[0].waist_girth = 0.68, family[0].hip_girth = 0.94;
  family[1].height = 1.78, family[1].waist_girth = 0.86, family[1].hip_girth = 1.04;
  family[2].height = 1.9, family[2].waist_girth = 0.96, family[2].hip_girth = 1.12, family[2].thigh_girth = 0.64;
  Box3d roi;
  for (const Vec3d& p : live_positions(skirt_m->model)) roi.extend(p);
  for (const MannequinParams& p : family) {
    auto pos = mannequin_positions(p, *topo);
    ASSERT_TRUE(pos);
    for (Vec3d& q : *pos) q = round_to_float(q);
    // The member in each frame as the files give it to the engine.
    std::vector<Vec3d> pos_cm = *pos;
    const BodyFrame cm_frame{0.01, UpAxis::kZ};
    for (Vec3d& q : pos_cm) q = cm_frame.to_engine(to_cm_z_up(q));
    auto rm = regenerate_on_body(std::span(&*skirt_m, 1), *m, *pos, roi);
    auto rc = regenerate_on_body(std::span(&*skirt_cm, 1), *cm, pos_cm, roi);
    auto ro = regenerate_on_body(std::span(&*skirt_own, 1), *mannequin, *pos, roi);
    ASSERT_TRUE(rm) << rm.status().message();
    ASSERT_TRUE(rc) << rc.status().message();
    ASSERT_TRUE(ro) << ro.status().message();
    const Model& gm = (*rm)[0].model;
    const Model& gc = (*rc)[0].model;
    EXPECT_TRUE(validate(gc)) << validate(gc).message();
    // Up to the transform (which the engine undoes at the door exactly for
    // these coordinates): the same skirt, to 1e-9 m.
    EXPECT_LE(gap(live_positions(gm), live_positions(gc)), 1e-9);
    EXPECT_EQ((*rc)[0].quality.inside, 0u);
    // And the skirt the mannequin's own curves give, to 1 mm: the feature
    // points are at the same places (ids and neighbours may differ).
    EXPECT_LE(gap(live_positions(gm), live_positions((*ro)[0].model)), 1e-3);
    // It followed the member: the template's own nodes (the first ones of
    // the refined model) moved.
    std::vector<Vec3d> first = live_positions(gm), tpl = live_positions(skirt_m->model);
    ASSERT_GE(first.size(), tpl.size());
    first.resize(tpl.size());
    EXPECT_GT(gap(first, tpl), 0.01);
  }
}
