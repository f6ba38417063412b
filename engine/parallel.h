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

#include <atelier/engine/exec_context.h>

#if defined(__SANITIZE_THREAD__)
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#endif

namespace atelier::par {

/// Happens-before edges for ThreadSanitizer around our callbacks that
/// Embree and OpenVDB call on their own (uninstrumented) TBB threads: the
/// callback releases, the caller acquires once the library returns. No-ops
/// outside TSan builds.
inline void tsan_release(const void* addr) noexcept {
#if defined(__SANITIZE_THREAD__)
  __tsan_release(const_cast<void*>(addr));
#else
  (void)addr;
#endif
}
inline void tsan_acquire(const void* addr) noexcept {
#if defined(__SANITIZE_THREAD__)
  __tsan_acquire(const_cast<void*>(addr));
#else
  (void)addr;
#endif
}

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

#if defined(__SANITIZE_THREAD__)
namespace detail {
inline thread_local bool in_parallel_block = false;

/// The loops' parallel path under ThreadSanitizer: blocks of [0, n) taken
/// from an atomic counter by std::threads that TSan sees created and
/// joined. TBB as packaged is not instrumented, so TSan cannot see it hand
/// a loop body's copy from the thread that split the range to the thread
/// that runs it, and reports every such hand-over as a race in our code.
/// Blocks of `grain` elements (TBB cuts them between grain / 2 and grain;
/// no result depends on it); loops nested in a block run sequentially.
template <class Body>
void run_blocks(const ExecContext& ctx, std::size_t n, std::size_t grain, Body&& body) {
  const std::size_t blocks = (n + grain - 1) / grain;
  std::size_t want = ctx.threads > 0 ? static_cast<std::size_t>(ctx.threads)
                                     : std::max<std::size_t>(1, std::thread::hardware_concurrency());
  if (in_parallel_block) want = 1;
  const std::size_t workers = std::min(want, blocks);
  std::atomic<std::size_t> next{0};
  std::mutex error_mutex;
  std::exception_ptr error;
  auto work = [&] {
    const bool outer = in_parallel_block;
    in_parallel_block = true;
    try {
      for (std::size_t b; (b = next.fetch_add(1)) < blocks;) body(b * grain, std::min(n, (b + 1) * grain));
    } catch (...) {
      const std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = blocks;
    }
    in_parallel_block = outer;
  };
  std::vector<std::thread> pool;
  for (std::size_t k = 1; k < workers; ++k) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}
}  // namespace detail
#endif

/// Calls f(i) for i in [0, n). f must only write to locations owned by i.
template <class F>
void for_each_n(const ExecContext& ctx, std::size_t n, F&& f) {
  if (run_sequential(ctx, n)) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  const std::size_t grain = ctx.grain ? ctx.grain : 1024;
#if defined(__SANITIZE_THREAD__)
  detail::run_blocks(ctx, n, grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) f(i);
  });
#else
  in_arena(ctx, [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) f(i);
    });
  });
#endif
}

/// Calls f(begin, end) over blocks of [0, n).
template <class F>
void for_each_block(const ExecContext& ctx, std::size_t n, F&& f) {
  if (run_sequential(ctx, n)) {
    if (n) f(std::size_t{0}, n);
    return;
  }
  const std::size_t grain = ctx.grain ? ctx.grain : 1024;
#if defined(__SANITIZE_THREAD__)
  detail::run_blocks(ctx, n, grain, f);
#else
  in_arena(ctx, [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                      [&](const tbb::blocked_range<std::size_t>& r) { f(r.begin(), r.end()); });
  });
#endif
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
  // TBB's sort moves elements in tasks TSan cannot see handed over (see
  // detail::run_blocks); the order is total, so the sequential sort gives the same
  // result and keeps TSan's reports to our own code.
  std::sort(first, last, less);
#else
  in_arena(ctx, [&] { tbb::parallel_sort(first, last, less); });
#endif
}

}  // namespace atelier::par
