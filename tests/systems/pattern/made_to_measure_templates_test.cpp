// Made-to-measure patterns of profile templates for a job of bodies (issue
// 26, systems/pattern/made_to_measure_templates.h): the batch form prepared
// per template on the reference body gives, cold, the one-shot's bits for a
// body; warm, the bits of the same pipeline assembled by hand
// (regenerate_on_body on the reference, then MadeToMeasurePatterns), for
// 1 or 2 threads; a template whose reference garment cannot be flattened
// comes back unprepared with its reason, and its bodies take the one-shot
// form. (Helpers are prefixed mtt_: unity builds put this file beside
// made_to_measure_test.cpp.)
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/pattern/made_to_measure_templates.h>
#include <atelier/systems/profile/profile_template.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/support/made_to_measure_options.h"
#include "tests/support/project_templates.h"

namespace atelier {
namespace {

namespace fs = std::filesystem;

/// The roi `atelier regen` regenerates a job's bodies with: every node slot
/// of its templates.
Box3d mtt_roi(std::span<const ProfileTemplate> ts) {
  Box3d b;
  for (const auto& t : ts)
    for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v) b.extend(t.model.nodes.position[v]);
  return b;
}

/// Copies of the project templates of these names, in this order.
std::vector<ProfileTemplate> mtt_templates(std::initializer_list<std::string> names) {
  std::vector<ProfileTemplate> out;
  for (const std::string& n : names)
    for (const ProfileTemplate& t : testing::template_fixture().templates)
      if (t.name == n) out.push_back(t);
  return out;
}

/// Every piece's sew line, in piece order, as one list.
std::vector<Vec2d> mtt_sew_lines(const MadeToMeasureReport& r) {
  std::vector<Vec2d> out;
  for (const PatternPiece& p : r.files.pattern.pieces)
    for (const auto& loop : p.sew_line) out.insert(out.end(), loop.begin(), loop.end());
  return out;
}

bool mtt_same_bits(const std::vector<Vec2d>& a, const std::vector<Vec2d>& b) {
  return !a.empty() && a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec2d)) == 0;
}

/// The templates regenerated on sampled body `index` (seed 2026) or, for
/// index < 0, on the reference itself, as regen does.
std::vector<RegenResult> mtt_regen(std::span<const ProfileTemplate> ts, int index) {
  const auto& f = testing::template_fixture();
  const std::vector<Vec3d> body =
      index < 0 ? f.body.model.nodes.position
                : mannequin_positions(sample_mannequin(2026, static_cast<std::size_t>(index)), f.topo).value();
  auto r = regenerate_on_body(ts, f.body, body, mtt_roi(ts), {}, {.use_grid = false}, ExecContext::sequential());
  if (!r) throw Error(r.status());
  return std::move(*r);
}

fs::path mtt_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("atelier_mtt_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

/// A closed octahedron 5 cm across, 10 cm in front of the reference body:
/// it regenerates, but a closed surface has no boundary for a seam to start
/// from, so open_seams refuses it (kTopology) and it cannot be flattened.
ProfileTemplate mtt_pouch() {
  const auto& f = testing::template_fixture();
  Box3d b;
  for (const Vec3d& p : f.body.model.nodes.position) b.extend(p);
  const Vec3d c(0.5 * (b.lo.x() + b.hi.x()), 0.5 * (b.lo.y() + b.hi.y()), b.hi.z() + 0.1);
  TemplateBuilder tb(f.body, "pouch");
  tb.set_levels(1);
  const char* names[] = {"px", "nx", "py", "ny", "pz", "nz"};
  const Vec3d dir[] = {Vec3d::UnitX(),  -Vec3d::UnitX(), Vec3d::UnitY(),
                       -Vec3d::UnitY(), Vec3d::UnitZ(),  -Vec3d::UnitZ()};
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(tb.node_at(names[k], c + 0.025 * dir[k], NodeEncodingMode::kFace));
  // Counter-clockwise seen from outside.
  const std::vector<std::vector<std::string>> faces = {{"px", "py", "pz"}, {"py", "nx", "pz"}, {"nx", "ny", "pz"},
                                                       {"ny", "px", "pz"}, {"py", "px", "nz"}, {"nx", "py", "nz"},
                                                       {"ny", "nx", "nz"}, {"px", "ny", "nz"}};
  EXPECT_TRUE(tb.surface("pouch", faces));
  auto t = tb.build();
  if (!t) throw Error(t.status());
  return std::move(*t);
}

TEST(MadeToMeasureTemplates, PreparedGivesTheOneShotBitsColdAndTheHandAssembledBitsWarmForAnyThreadCount) {
  const auto& f = testing::template_fixture();
  const std::vector<ProfileTemplate> ts = mtt_templates({"top", "skirt"});
  ASSERT_EQ(ts.size(), 2u);
  const Box3d roi = mtt_roi(ts);
  const std::vector<RegenResult> body = mtt_regen(ts, 1);
  const fs::path dir = mtt_dir("bits");
  // Cold: per template, the one-shot call's bits on every piece.
  const MadeToMeasureOptions cold_options = testing::pattern_set_only(false);
  auto cold = prepare_made_to_measure_patterns(ts, f.body, roi, {}, cold_options, ExecContext::sequential());
  ASSERT_TRUE(cold) << cold.status().to_string();
  ASSERT_EQ(cold->size(), 2u);
  for (std::size_t k = 0; k < ts.size(); ++k) {
    SCOPED_TRACE(ts[k].name);
    EXPECT_TRUE((*cold)[k].batch.prepared());
    EXPECT_TRUE((*cold)[k].reason) << (*cold)[k].reason.to_string();
    auto prepared = write_template_patterns((*cold)[k], body[k].model, dir);
    ASSERT_TRUE(prepared) << prepared.status().to_string();
    auto one_shot = write_made_to_measure_pattern(body[k].model, cold_options, dir);
    ASSERT_TRUE(one_shot) << one_shot.status().to_string();
    EXPECT_EQ(prepared->flipped, 0u);
    EXPECT_EQ(prepared->files.pattern.pieces.size(), one_shot->files.pattern.pieces.size());
    EXPECT_TRUE(mtt_same_bits(mtt_sew_lines(*prepared), mtt_sew_lines(*one_shot)));
    for (std::size_t i = 0; i < prepared->files.flattening.pieces.size(); ++i) {
      EXPECT_FALSE(prepared->files.flattening.pieces[i].warm_started);
      EXPECT_EQ(prepared->files.flattening.pieces[i].iterations, one_shot->files.flattening.pieces[i].iterations);
    }
  }
  // Warm (the default): prepared with 1 and with 2 threads, and the
  // pipeline assembled by hand: the same bits for the body.
  const MadeToMeasureOptions warm_options = testing::pattern_set_only(true);
  ExecContext two;
  two.threads = 2;
  two.sequential_threshold = 1;
  two.grain = 1;
  auto one_thread = prepare_made_to_measure_patterns(ts, f.body, roi, {}, warm_options, ExecContext::sequential());
  auto two_threads = prepare_made_to_measure_patterns(ts, f.body, roi, {}, warm_options, two);
  ASSERT_TRUE(one_thread && two_threads);
  const std::vector<RegenResult> reference = mtt_regen(ts, -1);
  std::size_t warm = 0;
  for (std::size_t k = 0; k < ts.size(); ++k) {
    SCOPED_TRACE(ts[k].name);
    MadeToMeasurePatterns by_hand;
    ASSERT_TRUE(by_hand.prepare(reference[k].model, warm_options));
    auto expected = by_hand.write(body[k].model, dir, ExecContext::sequential());
    ASSERT_TRUE(expected) << expected.status().to_string();
    for (const auto* p : {&*one_thread, &*two_threads}) {
      ASSERT_TRUE((*p)[k].batch.prepared());
      auto r = write_template_patterns((*p)[k], body[k].model, dir, two);
      ASSERT_TRUE(r) << r.status().to_string();
      EXPECT_TRUE(mtt_same_bits(mtt_sew_lines(*r), mtt_sew_lines(*expected)));
      for (const PieceFlattening& piece : r->files.flattening.pieces) warm += piece.warm_started;
    }
  }
  EXPECT_GT(warm, 0u);  // the warm path was taken (the top's body pieces)
  fs::remove_all(dir);
}

TEST(MadeToMeasureTemplates, ATemplateThatCannotBeFlattenedComesBackUnpreparedWithItsReason) {
  const auto& f = testing::template_fixture();
  std::vector<ProfileTemplate> ts = mtt_templates({"skirt"});
  ts.push_back(mtt_pouch());
  const Box3d roi = mtt_roi(ts);
  const MadeToMeasureOptions o = testing::pattern_set_only(false);
  auto r = prepare_made_to_measure_patterns(ts, f.body, roi, {}, o, ExecContext::sequential());
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_EQ(r->size(), 2u);
  EXPECT_TRUE((*r)[0].batch.prepared());
  EXPECT_TRUE((*r)[0].reason);
  const TemplatePatterns& pouch = (*r)[1];
  EXPECT_FALSE(pouch.batch.prepared());
  EXPECT_EQ(pouch.reason.code(), ErrorCode::kTopology);
  EXPECT_NE(pouch.reason.message().find("'pouch' is closed"), std::string::npos) << pouch.reason.message();
  // Its bodies take the one-shot form: the one-shot call's answer (here
  // the same refusal); the skirt's unprepared form gives the one-shot bits.
  const std::vector<RegenResult> body = mtt_regen(ts, 1);
  const fs::path dir = mtt_dir("unprepared");
  auto fallback = write_template_patterns(pouch, body[1].model, dir);
  auto one_shot = write_made_to_measure_pattern(body[1].model, o, dir);
  ASSERT_FALSE(fallback);
  ASSERT_FALSE(one_shot);
  EXPECT_EQ(fallback.status().code(), one_shot.status().code());
  EXPECT_EQ(fallback.status().message(), one_shot.status().message());
  TemplatePatterns skirt_alone;
  skirt_alone.options = o;
  auto a = write_template_patterns(skirt_alone, body[0].model, dir);
  auto b = write_made_to_measure_pattern(body[0].model, o, dir);
  ASSERT_TRUE(a && b);
  EXPECT_TRUE(mtt_same_bits(mtt_sew_lines(*a), mtt_sew_lines(*b)));
  fs::remove_all(dir);
}

TEST(MadeToMeasureTemplates, BadOptionsAndACancelledJobAreRefused) {
  const auto& f = testing::template_fixture();
  const std::vector<ProfileTemplate> ts = mtt_templates({"skirt"});
  MadeToMeasureOptions o = testing::pattern_set_only(true);
  o.lines.push_back({"knee", 1.5});
  auto bad = prepare_made_to_measure_patterns(ts, f.body, mtt_roi(ts), {}, o, ExecContext::sequential());
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("'knee'"), std::string::npos) << bad.status().message();
  ExecContext cancelled = ExecContext::sequential();
  cancelled.cancel.cancel();
  auto none = prepare_made_to_measure_patterns(ts, f.body, mtt_roi(ts), {}, testing::pattern_set_only(true), cancelled);
  ASSERT_FALSE(none);
  EXPECT_EQ(none.status().code(), ErrorCode::kCancelled);
}

}  // namespace
}  // namespace atelier
