// SlotTable: liveness, generations and the free list of one element kind.
// The columns of the kind live next to it as plain std::vectors (SoA); the
// owner resizes them whenever capacity() changes.
#pragma once

#include <cassert>
#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/handle.h>

namespace atelier {

/// Deletion policy: tombstones with a LIFO free list. A deleted slot keeps
/// its index (so other columns stay put), its generation is bumped (so stale
/// handles are detected), and it is reused first by the next allocation. This
/// LIFO order is what lets an inverse operator put an element back into the
/// very slot it came from. compact() removes tombstones and returns a remap.
template <class Tag>
class SlotTable {
 public:
  using IdxT = Idx<Tag>;
  using HandleT = Handle<Tag>;

  [[nodiscard]] std::size_t capacity() const noexcept { return alive_.size(); }
  [[nodiscard]] std::size_t size() const noexcept { return live_; }
  [[nodiscard]] bool empty() const noexcept { return live_ == 0; }

  [[nodiscard]] bool alive(IdxT i) const noexcept { return i.value < alive_.size() && alive_[i.value]; }
  [[nodiscard]] bool alive(HandleT h) const noexcept {
    return alive(h.idx) && generation_[h.idx.value] == h.generation;
  }
  [[nodiscard]] HandleT handle(IdxT i) const noexcept {
    assert(i.value < generation_.size());
    return {i, generation_[i.value]};
  }
  [[nodiscard]] std::uint32_t generation(IdxT i) const noexcept { return generation_[i.value]; }

  /// Returns the slot to use; `appended` tells the caller to grow its columns.
  [[nodiscard]] IdxT allocate(bool& appended) {
    ++live_;
    if (!free_.empty()) {
      const auto i = free_.back();
      free_.pop_back();
      alive_[i] = 1;
      appended = false;
      return IdxT{i};
    }
    alive_.push_back(1);
    generation_.push_back(0);
    appended = true;
    return IdxT{static_cast<std::uint32_t>(alive_.size() - 1)};
  }

  void release(IdxT i) {
    assert(alive(i));
    alive_[i.value] = 0;
    ++generation_[i.value];
    free_.push_back(i.value);
    --live_;
  }

  /// Appends n live slots at once (bulk construction); returns the first.
  IdxT append_bulk(std::size_t n) {
    const auto first = static_cast<std::uint32_t>(alive_.size());
    alive_.resize(alive_.size() + n, 1);
    generation_.resize(generation_.size() + n, 0);
    live_ += n;
    return IdxT{first};
  }

  /// Builds old->new remap (invalid for dead slots) and resets the table to
  /// its live slots, in their old order. Generations restart at 0: compaction
  /// invalidates every handle, callers go through the remap.
  [[nodiscard]] std::vector<IdxT> compact() {
    std::vector<IdxT> remap(alive_.size());
    std::uint32_t next = 0;
    for (std::size_t i = 0; i < alive_.size(); ++i)
      remap[i] = alive_[i] ? IdxT{next++} : IdxT{};
    alive_.assign(next, 1);
    generation_.assign(next, 0);
    free_.clear();
    live_ = next;
    return remap;
  }

  void clear() {
    alive_.clear();
    generation_.clear();
    free_.clear();
    live_ = 0;
  }

  [[nodiscard]] std::span<const std::uint8_t> alive_column() const noexcept { return alive_; }
  [[nodiscard]] std::span<const std::uint32_t> free_list() const noexcept { return free_; }
  [[nodiscard]] std::span<const std::uint32_t> generations() const noexcept { return generation_; }

 private:
  std::vector<std::uint8_t> alive_;
  std::vector<std::uint32_t> generation_;
  std::vector<std::uint32_t> free_;
  std::size_t live_ = 0;
};

/// Applies an old->new remap to a column: moves live entries down in place.
template <class T, class Tag>
void compact_column(std::vector<T>& col, const std::vector<Idx<Tag>>& remap, std::size_t new_size) {
  for (std::size_t i = 0; i < remap.size() && i < col.size(); ++i)
    if (remap[i].valid() && remap[i].value != i) col[remap[i].value] = std::move(col[i]);
  col.resize(new_size);
}

}  // namespace atelier
