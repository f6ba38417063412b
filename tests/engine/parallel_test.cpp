#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <type_traits>

#include <atelier/engine/handle.h>
#include <atelier/engine/parallel.h>
#include <atelier/engine/status.h>

using namespace atelier;

namespace {
ExecContext with_threads(int t) {
  ExecContext c;
  c.threads = t;
  c.sequential_threshold = 16;  // force the parallel path on small inputs
  return c;
}
}  // namespace

TEST(Handles, KindsDoNotConvert) {
  static_assert(!std::is_convertible_v<NodeIdx, FaceIdx>);
  static_assert(!std::is_convertible_v<Node, Face>);
  static_assert(!std::is_convertible_v<std::uint32_t, NodeIdx>);
  static_assert(sizeof(NodeIdx) == 4 && sizeof(Node) == 8);
  EXPECT_FALSE(NodeIdx{}.valid());
  EXPECT_EQ(twin(HalfedgeIdx{6}).value, 7u);
  EXPECT_EQ(twin(HalfedgeIdx{7}).value, 6u);
  EXPECT_EQ(edge_of(HalfedgeIdx{7}).value, 3u);
  EXPECT_EQ(halfedge_of(EdgeIdx{3}, 1).value, 7u);
}

TEST(Parallel, ForEachVisitsEveryIndexOnce) {
  for (int t : {1, 2}) {
    std::vector<int> hits(100'000, 0);
    par::for_each_n(with_threads(t), hits.size(), [&](std::size_t i) { hits[i] += 1; });
    for (int h : hits) ASSERT_EQ(h, 1);
  }
}

TEST(Parallel, ReductionIsBitIdenticalAcrossThreadCounts) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> d(-1e6, 1e6);
  std::vector<double> v(300'001);
  for (auto& x : v) x = d(rng) * std::pow(10.0, (rng() % 20) - 10.0);
  auto sum = [&](int t) {
    return par::transform_reduce(with_threads(t), v.size(), 0.0, [&](std::size_t i) { return v[i]; },
                                 [](double a, double b) { return a + b; });
  };
  const double s1 = sum(1), s2 = sum(2), s0 = sum(0);
  EXPECT_EQ(std::memcmp(&s1, &s2, sizeof s1), 0);
  EXPECT_EQ(std::memcmp(&s1, &s0, sizeof s1), 0);
  // And it is a sum: compare with a long double reference loosely.
  long double ref = 0;
  for (double x : v) ref += x;
  EXPECT_NEAR(static_cast<double>(ref), s1, 1e-6 * std::abs(static_cast<double>(ref)) + 1e-3);
}

TEST(Parallel, ExclusiveScanMatchesSequential) {
  std::mt19937 rng(3);
  std::vector<std::uint64_t> v(100'003);
  for (auto& x : v) x = rng() % 17;
  std::vector<std::uint64_t> ref(v.size());
  std::uint64_t acc = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    ref[i] = acc;
    acc += v[i];
  }
  auto w = v;
  const auto total = par::exclusive_scan_inplace(with_threads(2), w);
  EXPECT_EQ(total, acc);
  EXPECT_EQ(w, ref);
}

TEST(Parallel, SortGivesTheUniqueOrder) {
  std::mt19937 rng(5);
  std::vector<std::uint32_t> v(50'000);
  for (auto& x : v) x = rng();
  auto a = v, b = v;
  par::sort(with_threads(1), a.begin(), a.end(), std::less<>{});
  par::sort(with_threads(2), b.begin(), b.end(), std::less<>{});
  EXPECT_EQ(a, b);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
}

TEST(Status, ExpectedCarriesValueOrStatus) {
  Expected<int> ok = 5;
  Expected<int> bad = Status(ErrorCode::kParse, "x.obj:3: bad index");
  EXPECT_TRUE(ok.has_value());
  EXPECT_EQ(*ok, 5);
  EXPECT_FALSE(bad.has_value());
  EXPECT_EQ(bad.status().code(), ErrorCode::kParse);
  EXPECT_THROW((void)bad.value(), Error);
  EXPECT_NE(bad.status().to_string().find("x.obj:3"), std::string::npos);
}

TEST(ExecContext, CancelTokenIsShared) {
  ExecContext a;
  ExecContext b = a;  // copies share the flag
  EXPECT_FALSE(b.cancelled());
  a.cancel.cancel();
  EXPECT_TRUE(b.cancelled());
}
