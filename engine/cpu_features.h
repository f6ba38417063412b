// The CPU-feature probe: which instruction-set kernels this machine runs.
// Every kernel choice in the engine asks here (one probe, read once), so a
// test or a benchmark can see what was picked and why.
#pragma once

namespace atelier {

struct CpuFeatures {
  bool avx2 = false;
  bool fma = false;
  bool avx512f = false;
};

/// The features of the running CPU (probed once, thread-safe).
[[nodiscard]] const CpuFeatures& cpu_features() noexcept;

}  // namespace atelier
