// RaggedColumn: one ordered list per row, all lists in one pool (no
// per-element heap objects). Rows grow by moving to the end of the pool with
// doubled capacity; compact() repacks.
#pragma once

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/handle.h>

namespace atelier {

template <class T>
class RaggedColumn {
 public:
  struct Row {
    std::uint32_t offset = 0;
    std::uint32_t size = 0;
    std::uint32_t capacity = 0;
    friend bool operator==(const Row&, const Row&) = default;
  };

  [[nodiscard]] std::size_t rows() const noexcept { return rows_.size(); }
  void resize_rows(std::size_t n) { rows_.resize(n); }

  [[nodiscard]] std::span<const T> row(std::size_t r) const noexcept {
    const Row& x = rows_[r];
    return {pool_.data() + x.offset, x.size};
  }
  [[nodiscard]] std::span<T> row_mut(std::size_t r) noexcept {
    const Row& x = rows_[r];
    return {pool_.data() + x.offset, x.size};
  }
  [[nodiscard]] std::size_t size(std::size_t r) const noexcept { return rows_[r].size; }

  void clear_row(std::size_t r) noexcept { rows_[r].size = 0; }

  void assign(std::size_t r, std::span<const T> values) {
    reserve(r, values.size());
    std::copy(values.begin(), values.end(), pool_.begin() + rows_[r].offset);
    rows_[r].size = static_cast<std::uint32_t>(values.size());
  }

  void push_back(std::size_t r, const T& v) { insert(r, rows_[r].size, v); }

  void insert(std::size_t r, std::size_t pos, const T& v) {
    assert(pos <= rows_[r].size);
    reserve(r, rows_[r].size + 1);
    Row& x = rows_[r];
    auto base = pool_.begin() + x.offset;
    std::move_backward(base + pos, base + x.size, base + x.size + 1);
    base[pos] = v;
    ++x.size;
  }

  void erase(std::size_t r, std::size_t pos) {
    Row& x = rows_[r];
    assert(pos < x.size);
    auto base = pool_.begin() + x.offset;
    std::move(base + pos + 1, base + x.size, base + pos);
    --x.size;
  }

  /// Keeps rows whose remap entry is valid, moved to their new index; the
  /// pool is rebuilt tightly in new row order.
  template <class Tag>
  void compact(const std::vector<Idx<Tag>>& remap, std::size_t new_rows) {
    std::vector<Row> rows(new_rows);
    std::vector<T> pool;
    std::size_t total = 0;
    for (std::size_t i = 0; i < remap.size(); ++i)
      if (remap[i].valid()) total += rows_[i].size;
    pool.reserve(total);
    // Fill in new order: remap is monotone, so iterating old rows is new order.
    for (std::size_t i = 0; i < remap.size(); ++i) {
      if (!remap[i].valid()) continue;
      Row& n = rows[remap[i].value];
      n.offset = static_cast<std::uint32_t>(pool.size());
      n.size = n.capacity = rows_[i].size;
      auto src = row(i);
      pool.insert(pool.end(), src.begin(), src.end());
    }
    rows_ = std::move(rows);
    pool_ = std::move(pool);
  }

  /// Element-wise remap of stored values (e.g. after compacting the kind
  /// they refer to). `f` maps a value to its new value.
  template <class F>
  void transform_values(F&& f) {
    for (auto& r : rows_)
      for (std::uint32_t k = 0; k < r.size; ++k) pool_[r.offset + k] = f(pool_[r.offset + k]);
  }

  [[nodiscard]] std::size_t pool_size() const noexcept { return pool_.size(); }

  void clear() {
    rows_.clear();
    pool_.clear();
  }

 private:
  void reserve(std::size_t r, std::size_t need) {
    Row& x = rows_[r];
    if (need <= x.capacity) return;
    const std::uint32_t cap = static_cast<std::uint32_t>(std::max<std::size_t>(need, 2 * x.capacity + 2));
    // Rows at the end of the pool grow in place.
    if (x.offset + x.capacity == pool_.size() && x.capacity > 0) {
      pool_.resize(x.offset + cap);
      x.capacity = cap;
      return;
    }
    const auto off = static_cast<std::uint32_t>(pool_.size());
    pool_.resize(pool_.size() + cap);
    std::copy(pool_.begin() + x.offset, pool_.begin() + x.offset + x.size, pool_.begin() + off);
    x.offset = off;
    x.capacity = cap;
  }

  std::vector<Row> rows_;
  std::vector<T> pool_;
};

}  // namespace atelier
