// All parallel primitives of Atelier, in one place (manifold style).
//
// Each primitive has a sequential path used below ExecContext::sequential_threshold
// or when ExecContext::threads == 1. Results never depend on scheduling:
// reductions combine fixed-size blocks in index order, scans are two-pass
// with fixed blocks, sorts are by total order.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

#include "engine/exec_context.h"

#if defined(__SANITIZE_THREAD__)
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#endif

namespace atelier::par {

/// ThreadSanitizer's view of a parallel loop's fork and join. TBB as
/// packaged is not instrumented, so TSan cannot see that the caller's
/// writes happen before the workers run, nor that the workers' writes
/// happen before the loop returns, and reports every hand-over as a race.
/// These edges say it; outside TSan builds the type is empty and free.
struct ForkJoin {
#if defined(__SANITIZE_THREAD__)
  char fork_ = 0, join_ = 0;
  ForkJoin() noexcept {
    __tsan_release(&fork_);
  }
  ~ForkJoin() {
    __tsan_acquire(&join_);
  }
  ForkJoin(const ForkJoin&) = delete;
  ForkJoin& operator=(const ForkJoin&) = delete;
  void enter() noexcept {
    __tsan_acquire(&fork_);
  }  // at the start of a worker's block
  void leave() noexcept {
    __tsan_release(&join_);
  }  // at its end
#else
  void enter() const noexcept {}
  void leave() const noexcept {}
#endif
};

[[nodiscard]] inline bool run_sequential(const ExecContext& ctx, std::size_t n) noexcept {
  return ctx.threads == 1 || n < ctx.sequential_threshold;
}

/// Runs f inside an arena limited to ctx.threads (no-op limit when 0, or
/// when the calling arena is no larger: making an arena costs tens of
/// microseconds, which small loops called many times per body would pay
/// on every call).
template <class F>
void in_arena(const ExecContext& ctx, F&& f) {
  if (ctx.threads > 0 && ctx.threads < tbb::this_task_arena::max_concurrency()) {
    tbb::task_arena arena(ctx.threads);
    arena.execute(std::forward<F>(f));
  } else {
    f();
  }
}

/// Calls f(i) for i in [0, n). f must only write to locations owned by i.
template <class F>
void for_each_n(const ExecContext& ctx, std::size_t n, F&& f) {
  if (run_sequential(ctx, n)) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  const std::size_t grain = ctx.grain ? ctx.grain : 1024;
  ForkJoin fj;
  in_arena(ctx, [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain), [&](const tbb::blocked_range<std::size_t>& r) {
      fj.enter();
      for (std::size_t i = r.begin(); i < r.end(); ++i) f(i);
      fj.leave();
    });
  });
}

/// Calls f(begin, end) over blocks of [0, n).
template <class F>
void for_each_block(const ExecContext& ctx, std::size_t n, F&& f) {
  if (run_sequential(ctx, n)) {
    if (n) f(std::size_t{0}, n);
    return;
  }
  const std::size_t grain = ctx.grain ? ctx.grain : 1024;
  ForkJoin fj;
  in_arena(ctx, [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain), [&](const tbb::blocked_range<std::size_t>& r) {
      fj.enter();
      f(r.begin(), r.end());
      fj.leave();
    });
  });
}

/// Deterministic reduction: [0,n) is cut into fixed blocks whose size does
/// not depend on the thread count; block results are combined in index order,
/// so floating-point sums are bit-identical for any number of threads.
template <class T, class Map, class Combine>
[[nodiscard]] T transform_reduce(const ExecContext& ctx, std::size_t n, T init, Map&& map, Combine&& combine) {
  constexpr std::size_t kBlock = 4096;
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<T> partial(blocks, init);
  auto body = [&](std::size_t b) {
    T acc = init;
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    for (std::size_t i = b * kBlock; i < end; ++i) acc = combine(acc, map(i));
    partial[b] = acc;
  };
  ExecContext c = ctx;
  c.sequential_threshold = std::max<std::size_t>(1, ctx.sequential_threshold / kBlock);
  c.grain = 1;
  for_each_n(c, blocks, body);
  T acc = init;
  for (const T& p : partial) acc = combine(acc, p);
  return acc;
}

/// Exclusive prefix sum in place; returns the total. Deterministic (integers).
template <class T>
T exclusive_scan_inplace(const ExecContext& ctx, std::vector<T>& v) {
  const std::size_t n = v.size();
  if (run_sequential(ctx, n)) {
    T acc{};
    for (auto& x : v) {
      T t = x;
      x = acc;
      acc += t;
    }
    return acc;
  }
  constexpr std::size_t kBlock = 1 << 14;
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<T> sums(blocks + 1, T{});
  ExecContext c = ctx;
  c.sequential_threshold = 2;
  c.grain = 1;
  for_each_n(c, blocks, [&](std::size_t b) {
    T acc{};
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    for (std::size_t i = b * kBlock; i < end; ++i) acc += v[i];
    sums[b + 1] = acc;
  });
  for (std::size_t b = 0; b < blocks; ++b) sums[b + 1] += sums[b];
  for_each_n(c, blocks, [&](std::size_t b) {
    T acc = sums[b];
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    for (std::size_t i = b * kBlock; i < end; ++i) {
      T t = v[i];
      v[i] = acc;
      acc += t;
    }
  });
  return sums[blocks];
}

/// Sort by a strict total order (so the result is unique, whatever the
/// scheduling). `less` must not leave equal-but-distinct elements.
template <class It, class Less>
void sort(const ExecContext& ctx, It first, It last, Less less) {
  const auto n = static_cast<std::size_t>(last - first);
  if (run_sequential(ctx, n)) {
    std::sort(first, last, less);
    return;
  }
#if defined(__SANITIZE_THREAD__)
  // TBB's sort moves elements in tasks TSan cannot see forked (see
  // ForkJoin); the order is total, so the sequential sort gives the same
  // result and keeps TSan's reports to our own code.
  std::sort(first, last, less);
#else
  in_arena(ctx, [&] { tbb::parallel_sort(first, last, less); });
#endif
}

}  // namespace atelier::par
