#include <gtest/gtest.h>

#include <random>

#include <atelier/storage/property.h>
#include <atelier/storage/ragged.h>
#include <atelier/storage/slot_table.h>

using namespace atelier;

TEST(SlotTable, StaleHandlesAreDetectedAndSlotsReusedLifo) {
  SlotTable<NodeTag> t;
  bool app = false;
  auto a = t.allocate(app);
  EXPECT_TRUE(app);
  auto b = t.allocate(app);
  auto c = t.allocate(app);
  const Node ha = t.handle(a), hb = t.handle(b);
  t.release(b);
  t.release(a);
  EXPECT_FALSE(t.alive(ha));
  EXPECT_FALSE(t.alive(hb));
  EXPECT_EQ(t.size(), 1u);
  // LIFO: a was freed last, so it comes back first.
  auto a2 = t.allocate(app);
  EXPECT_FALSE(app);
  EXPECT_EQ(a2, a);
  EXPECT_TRUE(t.alive(t.handle(a2)));
  EXPECT_FALSE(t.alive(ha));  // the old handle stays stale after reuse
  auto b2 = t.allocate(app);
  EXPECT_EQ(b2, b);
  (void)c;
}

TEST(SlotTable, CompactRemapsLiveSlotsInOrder) {
  SlotTable<FaceTag> t;
  bool app;
  std::vector<FaceIdx> ids;
  for (int i = 0; i < 10; ++i) ids.push_back(t.allocate(app));
  for (int i : {0, 3, 4, 9}) t.release(ids[i]);
  auto remap = t.compact();
  ASSERT_EQ(remap.size(), 10u);
  std::uint32_t next = 0;
  for (int i = 0; i < 10; ++i) {
    if (i == 0 || i == 3 || i == 4 || i == 9)
      EXPECT_FALSE(remap[i].valid());
    else
      EXPECT_EQ(remap[i].value, next++);
  }
  EXPECT_EQ(t.capacity(), 6u);
  EXPECT_EQ(t.size(), 6u);
}

TEST(RaggedColumn, MatchesVectorOfVectorsUnderRandomEdits) {
  std::mt19937 rng(11);
  RaggedColumn<int> r;
  std::vector<std::vector<int>> ref(50);
  r.resize_rows(50);
  for (int step = 0; step < 20'000; ++step) {
    const std::size_t row = rng() % 50;
    const int op = static_cast<int>(rng() % 4);
    if (op == 0 || ref[row].empty()) {
      const std::size_t pos = rng() % (ref[row].size() + 1);
      const int v = static_cast<int>(rng() % 1000);
      r.insert(row, pos, v);
      ref[row].insert(ref[row].begin() + static_cast<std::ptrdiff_t>(pos), v);
    } else if (op == 1) {
      const std::size_t pos = rng() % ref[row].size();
      r.erase(row, pos);
      ref[row].erase(ref[row].begin() + static_cast<std::ptrdiff_t>(pos));
    } else if (op == 2) {
      const int v = static_cast<int>(rng() % 1000);
      r.push_back(row, v);
      ref[row].push_back(v);
    } else if (rng() % 50 == 0) {
      r.clear_row(row);
      ref[row].clear();
    }
  }
  for (std::size_t i = 0; i < 50; ++i) {
    auto s = r.row(i);
    ASSERT_EQ(std::vector<int>(s.begin(), s.end()), ref[i]) << "row " << i;
  }
  // Compaction drops rows and repacks the pool tightly.
  std::vector<Idx<FaceTag>> remap(50);
  std::uint32_t n = 0;
  std::size_t kept_total = 0;
  for (std::size_t i = 0; i < 50; ++i)
    if (i % 3 != 0) {
      remap[i] = Idx<FaceTag>{n++};
      kept_total += ref[i].size();
    }
  r.compact(remap, n);
  EXPECT_EQ(r.pool_size(), kept_total);
  for (std::size_t i = 0; i < 50; ++i) {
    if (!remap[i].valid()) continue;
    auto s = r.row(remap[i].value);
    ASSERT_EQ(std::vector<int>(s.begin(), s.end()), ref[i]);
  }
}

TEST(PropertyRegistry, TypedColumnsFollowTheTable) {
  PropertyRegistry<NodeTag> reg;
  reg.resize(3);
  auto w = reg.add<double>("weight", 1.5);
  w[NodeIdx{2}] = 7.0;
  EXPECT_EQ(w[NodeIdx{0}], 1.5);
  EXPECT_TRUE(reg.find<double>("weight").valid());
  EXPECT_FALSE(reg.find<int>("weight").valid());   // wrong type is not found
  EXPECT_THROW(reg.add<int>("weight"), std::invalid_argument);
  reg.resize(5);
  EXPECT_EQ(w[NodeIdx{4}], 1.5);
  std::vector<NodeIdx> remap = {NodeIdx{}, NodeIdx{0}, NodeIdx{1}, NodeIdx{}, NodeIdx{2}};
  reg.compact(remap, 3);
  EXPECT_EQ(w.vector().size(), 3u);
  EXPECT_EQ(w[NodeIdx{1}], 7.0);
  PropertyRegistry<NodeTag> copy = reg;  // deep copy
  copy.find<double>("weight")[NodeIdx{1}] = 0;
  EXPECT_EQ(w[NodeIdx{1}], 7.0);
  EXPECT_TRUE(reg.remove("weight"));
  EXPECT_FALSE(reg.contains("weight"));
}
