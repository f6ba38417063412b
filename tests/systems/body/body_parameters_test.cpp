// Honest bodies (issue 26): a body source says what each body was made
// from, and the mannequin stands on the documented floor (y = 0, Y up:
// the person's soles; the headless form itself ends at 0.03 H).
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace atelier {
namespace {

TEST(BodyParameters, SampledMannequinsStandOnTheFloorAndReportTheirPerson) {
  auto topo =
      std::make_shared<const MannequinTopology>(make_mannequin_topology(MannequinResolution::from_level(2)).value());
  auto ref = std::make_shared<const ReferenceBody>(make_mannequin(MannequinParams{}, *topo).value());
  const MannequinSource src(topo, 60, 31, ref);
  EXPECT_FALSE(src.whole_person());  // headless: its extent is not a stature
  BodySet set(ref);
  std::vector<BodyFailure> failures;
  src.generate(0, src.size(), set, failures, {});
  ASSERT_TRUE(failures.empty());
  std::size_t female = 0;
  double female_height = 0, male_height = 0;
  for (std::size_t b = 0; b < set.size(); ++b) {
    const std::vector<Vec3d> p = set.positions(b);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3d& x : p) {
      lo = std::min(lo, x.y());
      hi = std::max(hi, x.y());
    }
    const auto params = src.parameters(b);
    ASSERT_GE(params.size(), 3u);
    EXPECT_EQ(params[0].first, "sampled_sex");
    EXPECT_EQ(params[1].first, "sampled_stature_m");
    const MannequinParams mp = src.params(b);
    // The floor the person stands on is y = 0 (mannequin.h): the form ends
    // in caps below the ankles whose lowest point is 0.03 H above it.
    EXPECT_NEAR(lo, 0.03 * mp.height, 0.002) << "body " << b;
    EXPECT_NEAR(std::stod(params[1].second), mp.height, 1e-4);  // printed to 0.1 mm
    // The form is headless: well short of the person's stature.
    EXPECT_LT(hi, 0.92 * mp.height) << "body " << b;
    const bool is_female = params[0].second == "female";
    EXPECT_EQ(is_female, sample_mannequin_female(31, b));
    EXPECT_TRUE(is_female || params[0].second == "male");
    female += is_female;
    (is_female ? female_height : male_height) += mp.height;
  }
  ASSERT_GT(female, 10u);
  ASSERT_LT(female, 50u);
  // The sex is the one the body was drawn for: mean statures 1.64 and 1.76 m.
  EXPECT_NEAR(female_height / static_cast<double>(female), 1.64, 0.04);
  EXPECT_NEAR(male_height / static_cast<double>(set.size() - female), 1.76, 0.04);
}

}  // namespace
}  // namespace atelier
