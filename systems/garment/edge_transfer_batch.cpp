// apply_edge_transfer_bodies: the edge transfer on several bodies at once,
// one body per SIMD lane (issue 26, branch lanes13).
//
// One body's length iterations are a chain of dependent loads over arrays
// larger than L2 (a Gauss-Seidel sweep in vertex order, a sparse triangular
// solve): colour orders and gathers cost more than they saved (performance.md,
// speed5 and speed7). Bodies of one family share the garment's edges,
// incidences, weights and factor, so the same walk serves kLanes bodies:
// each index is loaded once for all lanes and the lanes' chains run side by
// side. The kernel (edge_transfer_lanes.inc) is compiled three times: 8
// lanes for AVX-512, 4 for AVX2 and 2 for SSE2 (the baseline instruction
// set, the fallback), picked at run time by cpu_features() as
// detail_decode_batch.cpp does (see pick() for why 4, not 8, by default). This file
// and edge_transfer.cpp are compiled with -ffp-contract=off
// (CMakeLists.txt): a product added to a sum stays two roundings in every
// kernel, as in the one-body path, so each lane is that body's bits.
#include <atelier/engine/cpu_features.h>
#include <atelier/systems/garment/edge_transfer.h>
#include <immintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <new>
#include <string>

#include "edge_transfer_detail.h"

// The kernels pass vectors by value only between functions of one
// instruction set (inlined); GCC's note on the ABI of such calls and its
// false alarm on _mm512_sqrt_pd's undefined source are not ours.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
#ifndef __clang__
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

// Every function of a kernel's region compiled for its instruction set:
// GCC's target pragma, clang's attribute pragma (the clang ASan build).
#define ATELIER_PRAGMA(x) _Pragma(#x)
#if defined(__clang__)
#define ATELIER_LANES_TARGET_PUSH(isa) \
  ATELIER_PRAGMA(clang attribute push(__attribute__((target(isa))), apply_to = function))
#define ATELIER_LANES_TARGET_POP ATELIER_PRAGMA(clang attribute pop)
#else
#define ATELIER_LANES_TARGET_PUSH(isa) ATELIER_PRAGMA(GCC push_options) ATELIER_PRAGMA(GCC target(isa))
#define ATELIER_LANES_TARGET_POP ATELIER_PRAGMA(GCC pop_options)
#endif

namespace atelier {
namespace {

// Cache-line aligned storage for the lanes' arrays (the kernels' loads and
// stores of whole lines assume it; std::allocator does not promise it for
// over-aligned vector types across instruction-set regions).
template <class T>
struct LineAllocator {
  using value_type = T;
  LineAllocator() = default;
  template <class U>
  LineAllocator(const LineAllocator<U>&) noexcept {}
  [[nodiscard]] T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(64)));
  }
  void deallocate(T* p, std::size_t) noexcept { ::operator delete(p, std::align_val_t(64)); }
  template <class U>
  bool operator==(const LineAllocator<U>&) const noexcept {
    return true;
  }
};

namespace lanes_avx512 {
ATELIER_LANES_TARGET_PUSH("avx512f")
constexpr int kLanes = 8;
#define ATELIER_LANE_SQRT(a) (V) _mm512_sqrt_pd((__m512d)(a))
#include "edge_transfer_lanes.inc"
#undef ATELIER_LANE_SQRT
ATELIER_LANES_TARGET_POP
}  // namespace lanes_avx512

namespace lanes_avx2 {
ATELIER_LANES_TARGET_PUSH("avx2")
constexpr int kLanes = 4;
#define ATELIER_LANE_SQRT(a) (V) _mm256_sqrt_pd((__m256d)(a))
#include "edge_transfer_lanes.inc"
#undef ATELIER_LANE_SQRT
ATELIER_LANES_TARGET_POP
}  // namespace lanes_avx2

namespace lanes_generic {
constexpr int kLanes = 2;
#define ATELIER_LANE_SQRT(a) (V) _mm_sqrt_pd((__m128d)(a))
#include "edge_transfer_lanes.inc"
#undef ATELIER_LANE_SQRT
}  // namespace lanes_generic

EdgeTransferKernel pick(EdgeTransferKernel k) noexcept {
  const CpuFeatures& cpu = cpu_features();
  // Auto is 4 lanes where AVX2 runs, also on AVX-512 machines: the lanes'
  // arrays grow with the lanes (about 3.5 MB per lane for an 8,426-vertex
  // suit) and the sweeps are bound by the caches, so 8 lanes ran slower
  // than 4 (performance.md, lanes13: 9.7 against 6.3 ms per body; 2 lanes
  // 8.1, one body at a time 9.5).
  if (k == EdgeTransferKernel::kAuto) return cpu.avx2 ? EdgeTransferKernel::kAvx2 : EdgeTransferKernel::kGeneric;
  if (k == EdgeTransferKernel::kAvx512 && !cpu.avx512f) return EdgeTransferKernel::kGeneric;
  if (k == EdgeTransferKernel::kAvx2 && !cpu.avx2) return EdgeTransferKernel::kGeneric;
  return k;
}

// Runs one kernel on the bodies listed in `ok` (those whose set-up passed).
// A body with an edge of zero length on the way (where the one-body path
// keeps an edge's previous target) is left to apply_edge_transfer.
template <class Tile, class Bodies, auto Run>
void run_kernel(const EdgeTransfer& t, std::span<const std::size_t> ok, std::span<const std::vector<Vec3d>> target,
                std::span<std::vector<Vec3d>> rhs, std::span<const std::span<const Vec3d>> bodies,
                std::span<const Triangle> body_triangles, std::span<const std::span<Vec3d>> garments,
                std::span<Status> status) {
  Tile w;
  std::vector<const std::vector<Vec3d>*> tg;
  std::vector<std::vector<Vec3d>*> solved;
  std::vector<Vec3d*> out;
  for (const std::size_t b : ok) {
    tg.push_back(&target[b]);
    solved.push_back(&rhs[b]);
    out.push_back(garments[b].data());
  }
  std::vector<std::uint8_t> alone(ok.size(), 0);
  Run(t, Bodies{tg, solved, out, alone}, w);
  const ExecContext seq = ExecContext::sequential();
  for (std::size_t k = 0; k < ok.size(); ++k)
    if (alone[k]) status[ok[k]] = apply_edge_transfer(t, bodies[ok[k]], body_triangles, garments[ok[k]], seq);
}

}  // namespace

std::size_t edge_transfer_lanes(EdgeTransferKernel kernel) noexcept {
  const EdgeTransferKernel k = pick(kernel);
  return k == EdgeTransferKernel::kAvx512 ? 8 : k == EdgeTransferKernel::kAvx2 ? 4 : 2;
}

Status apply_edge_transfer_bodies(const EdgeTransfer& t, std::span<const std::span<const Vec3d>> bodies,
                                  std::span<const Triangle> body_triangles, std::span<const std::span<Vec3d>> garments,
                                  std::span<Status> status, EdgeTransferKernel kernel) {
  if (!t.solver) return Status(ErrorCode::kInvalidArgument, "edge transfer: not encoded");
  if (garments.size() != bodies.size() || status.size() != bodies.size())
    return Status(ErrorCode::kMismatch, "edge transfer: " + std::to_string(bodies.size()) + " bodies, " +
                                            std::to_string(garments.size()) + " garments and " +
                                            std::to_string(status.size()) + " statuses");
  // The lane kernels run the accelerated iterations with at most 8 columns
  // (the default window is 3); other settings take the one-body path.
  const bool lanes_fit =
      (t.anderson_window > 0 || t.length_tolerance > 0) && t.length_sweeps == 1 && t.anderson_window <= 8;
  if (!lanes_fit || bodies.size() == 1) {
    const ExecContext seq = ExecContext::sequential();
    for (std::size_t b = 0; b < bodies.size(); ++b)
      status[b] = apply_edge_transfer(t, bodies[b], body_triangles, garments[b], seq);
    return {};
  }
  const ExecContext seq = ExecContext::sequential();
  std::vector<std::vector<Vec3d>> target(bodies.size()), rhs(bodies.size());
  std::vector<std::size_t> ok;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    status[b] =
        edge_transfer_detail::targets_and_rhs(t, bodies[b], body_triangles, garments[b], target[b], rhs[b], seq);
    if (status[b]) ok.push_back(b);
  }
  switch (pick(kernel)) {
    case EdgeTransferKernel::kAvx512:
      run_kernel<lanes_avx512::Tile, lanes_avx512::Bodies, lanes_avx512::run_bodies>(t, ok, target, rhs, bodies,
                                                                                     body_triangles, garments, status);
      break;
    case EdgeTransferKernel::kAvx2:
      run_kernel<lanes_avx2::Tile, lanes_avx2::Bodies, lanes_avx2::run_bodies>(t, ok, target, rhs, bodies,
                                                                               body_triangles, garments, status);
      break;
    default:
      run_kernel<lanes_generic::Tile, lanes_generic::Bodies, lanes_generic::run_bodies>(
          t, ok, target, rhs, bodies, body_triangles, garments, status);
  }
  return {};
}

}  // namespace atelier

#pragma GCC diagnostic pop
