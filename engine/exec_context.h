// ExecContext: how a system may run (threads, grain, cancellation, progress).
// Passed explicitly to every parallel system; nothing reads global state.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <string_view>

namespace atelier {

/// Shared cancellation flag: set from any thread, polled by long systems.
class CancelToken {
 public:
  CancelToken() : flag_(std::make_shared<std::atomic<bool>>(false)) {}
  void cancel() const noexcept { flag_->store(true, std::memory_order_relaxed); }
  [[nodiscard]] bool cancelled() const noexcept { return flag_->load(std::memory_order_relaxed); }
  void reset() const noexcept { flag_->store(false, std::memory_order_relaxed); }

 private:
  std::shared_ptr<std::atomic<bool>> flag_;
};

struct ExecContext {
  /// Worker threads; 0 means all available, 1 forces the sequential path.
  int threads = 0;
  /// Below this many items a parallel primitive runs sequentially (manifold
  /// uses about 1e4: below it, task overhead exceeds the work).
  std::size_t sequential_threshold = 10'000;
  /// Grain size for the parallel loops (items per task), 0 = automatic.
  std::size_t grain = 0;
  CancelToken cancel;
  /// Progress callback: (stage, done, total). Called from one thread at a time.
  std::function<void(std::string_view, std::size_t, std::size_t)> progress;

  [[nodiscard]] bool cancelled() const noexcept { return cancel.cancelled(); }
  void report(std::string_view stage, std::size_t done, std::size_t total) const {
    if (progress) progress(stage, done, total);
  }
  [[nodiscard]] static ExecContext sequential() {
    ExecContext c;
    c.threads = 1;
    return c;
  }
};

}  // namespace atelier
