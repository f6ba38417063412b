// Progress and cancellation of the net operations (issues 24 and 25): each
// Boolean, trim and round-off reports its stages in order through
// ExecContext::progress, and a cancel raised at any stage ends the call with
// kCancelled (round-off leaves the model's tables unchanged). A cancel that
// came too late to matter would show as a result instead of kCancelled.
#include <atelier/storage/builder.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/net/boolean.h>
#include <atelier/systems/net/round_off.h>
#include <atelier/systems/net/trim.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "net_shapes.h"

namespace atelier {
namespace {

struct Seen {
  std::vector<std::string> stages;
  std::vector<std::size_t> done;
};

/// A context that records every report and cancels once `cancel_at` reports
/// have been made (never when cancel_at is 0).
ExecContext recording(Seen& seen, std::size_t cancel_at) {
  ExecContext ctx;
  ctx.threads = 2;
  CancelToken token = ctx.cancel;
  ctx.progress = [&seen, token, cancel_at](std::string_view stage, std::size_t done, std::size_t total) {
    seen.stages.emplace_back(stage);
    seen.done.push_back(done);
    EXPECT_LE(done, total);
    if (cancel_at != 0 && seen.stages.size() == cancel_at) token.cancel();
  };
  return ctx;
}

std::vector<Vec3d> circle(int n, double r, double z) {
  std::vector<Vec3d> p;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * (i + 0.5) / n;
    p.emplace_back(r * std::cos(a), r * std::sin(a), z);
  }
  return p;
}

TEST(NetCancel, BooleanReportsEveryStageInOrderAndStopsAtEach) {
  const PolygonSoup a = net_test::icosphere(3, 1.0, {0, 0, 0});
  const PolygonSoup b = net_test::icosphere(3, 0.8, {0.7, 0.1, 0.05});
  BooleanOptions o;
  o.op = BooleanOp::kUnion;
  Seen all;
  auto full = net_boolean(a, b, o, recording(all, 0));
  ASSERT_TRUE(full.has_value()) << full.status().to_string();
  ASSERT_EQ(all.stages.size(), 5u);
  for (std::size_t i = 0; i < all.done.size(); ++i) EXPECT_EQ(all.done[i], i + 1) << all.stages[i];
  for (std::size_t k = 1; k <= all.stages.size(); ++k) {
    Seen seen;
    auto r = net_boolean(a, b, o, recording(seen, k));
    ASSERT_FALSE(r.has_value()) << "a cancel at stage " << k << " still gave a result";
    EXPECT_EQ(r.status().code(), ErrorCode::kCancelled) << r.status().to_string();
    EXPECT_EQ(seen.stages.size(), k) << "work went on after the cancel";
  }
  // A context cancelled before the call does no stage at all.
  Seen none;
  ExecContext pre = recording(none, 0);
  pre.cancel.cancel();
  auto r = net_boolean(a, b, o, pre);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.status().code(), ErrorCode::kCancelled);
  EXPECT_LE(none.stages.size(), 1u);
}

TEST(NetCancel, TrimStopsAtEachStage) {
  const PolygonSoup sphere = net_test::icosphere(3, 1.0, {0, 0, 0});
  const std::vector<Vec3d> curve = circle(24, std::sqrt(1.0 - 0.5 * 0.5), 0.5);
  Seen all;
  auto full = trim_net(sphere, curve, {}, recording(all, 0));
  ASSERT_TRUE(full.has_value()) << full.status().to_string();
  ASSERT_EQ(all.stages.size(), 3u);
  for (std::size_t k = 1; k <= all.stages.size(); ++k) {
    Seen seen;
    auto r = trim_net(sphere, curve, {}, recording(seen, k));
    ASSERT_FALSE(r.has_value()) << k;
    EXPECT_EQ(r.status().code(), ErrorCode::kCancelled);
  }
}

TEST(NetCancel, RoundOffCancelledLeavesTheModelUnchanged) {
  const PolygonSoup a = net_test::box_triangles({-0.8, -0.8, -0.8}, {0.8, 0.8, 0.2});
  const PolygonSoup b = net_test::icosphere(3, 0.7, {0.05, 0.02, 0.3});
  BooleanOptions bo;
  bo.op = BooleanOp::kUnion;
  auto u = net_boolean(a, b, bo);
  ASSERT_TRUE(u.has_value()) << u.status().to_string();
  Model m;
  ASSERT_TRUE(add_polygon_surface(m, "u", u->result).has_value());
  std::vector<NodeIdx> seam;
  for (std::uint32_t v : u->seam) seam.push_back(NodeIdx{v});
  const Model before = m;
  Seen all;
  Model done = m;
  auto full = round_off(done, seam, {}, recording(all, 0));
  ASSERT_TRUE(full.has_value()) << full.status().to_string();
  ASSERT_TRUE(full->moved);
  ASSERT_EQ(all.stages.size(), 3u);
  // The last report comes after the model is written: cancels at the first
  // two stages must leave every table as it was.
  for (std::size_t k = 1; k <= 2; ++k) {
    Seen seen;
    auto r = round_off(m, seam, {}, recording(seen, k));
    ASSERT_FALSE(r.has_value()) << k;
    EXPECT_EQ(r.status().code(), ErrorCode::kCancelled);
    EXPECT_EQ(diff_tables(before, m), "") << k;
    EXPECT_TRUE(validate(m).is_ok());
  }
}

}  // namespace
}  // namespace atelier
