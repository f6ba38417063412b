// Process memory policy for batch work.
//
// Refinement grows every column about 4x per level and a batch job frees
// and re-allocates the same sizes for every body. With glibc's default
// policy, freed blocks of a few MB go back to the kernel (mmap threshold and
// heap trimming), so each body faults in and zero-fills its ~100 MB again:
// a 200k -> 800k uniform split spends 60% of its time in page faults
// (docs/performance.md). Keeping freed memory mapped turns that into reuse.
//
// This is a process-wide allocator setting, so the engine never applies it
// by itself: the application opts in (the CLI and the benchmark do at
// start-up; an embedding program decides for itself).
#pragma once

#include <cstddef>

namespace atelier {

struct MemoryPolicy {
  /// Blocks below this size come from the heap instead of fresh mmaps
  /// (glibc caps it at 32 MiB on 64-bit systems).
  std::size_t mmap_threshold = std::size_t{32} << 20;
  /// Free memory at the top of a heap is returned to the kernel only beyond
  /// this size.
  std::size_t trim_threshold = std::size_t{1} << 30;
};

/// Applies the policy (glibc mallopt). Returns false when the allocator does
/// not support it (other C libraries), in which case nothing changed.
bool apply_memory_policy(const MemoryPolicy& policy = {}) noexcept;

}  // namespace atelier
