#include <atelier/engine/memory.h>

#include <climits>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace atelier {

bool apply_memory_policy(const MemoryPolicy& policy) noexcept {
#if defined(__GLIBC__)
  const auto clamp = [](std::size_t v) { return static_cast<int>(v > INT_MAX ? INT_MAX : v); };
  // Setting either value also turns off glibc's dynamic threshold, which
  // would otherwise move them back after the first large free.
  const bool a = mallopt(M_MMAP_THRESHOLD, clamp(policy.mmap_threshold)) == 1;
  const bool b = mallopt(M_TRIM_THRESHOLD, clamp(policy.trim_threshold)) == 1;
  return a && b;
#else
  (void)policy;
  return false;
#endif
}

}  // namespace atelier
