#include <atelier/systems/garment/detail_template.h>

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include <atelier/engine/cpu_features.h>
#include <atelier/engine/parallel.h>
#include <atelier/systems/body/body_set.h>
#include "detail_template_detail.h"

namespace atelier {

using namespace detail_internal;

namespace {


// Frames of one body packed per polygon as 16 floats on a 64-byte line,
// transposed: (p_c.x, X.x, Y.x, Z.x, p_c.y, X.y, Y.y, Z.y, p_c.z, X.z, Y.z,
// Z.z, 0, 0, 0, 0). An entry's (a, b, c, d), broadcast to the four
// quarters, times the line gives the 12 products of eq. (12) in one
// 16-wide FMA; each quarter's sum is one coordinate.
struct PackedFrames {
  std::vector<float> storage;
  float* data = nullptr;
  void pack(const PolygonFrames& fr, const ExecContext& ctx) {
    const std::size_t n = fr.centroid.size();
    storage.assign(n * 16 + 16, 0.0f);
    const auto addr = reinterpret_cast<std::uintptr_t>(storage.data());
    data = storage.data() + ((64 - addr % 64) % 64) / sizeof(float);
    par::for_each_n(ctx, n, [&](std::size_t p) {
      float* f = data + p * 16;
      const Vec3f* v[4] = {&fr.centroid[p], &fr.x[p], &fr.y[p], &fr.z[p]};
      for (int j = 0; j < 4; ++j)
        for (int k = 0; k < 3; ++k) f[4 * k + j] = (*v[j])[k];
    });
  }
};

// A row's entries go round-robin into 4 accumulators (FMA latency 4, so 4
// entries are in flight); the accumulators are added (0 + 1) + (2 + 3) and
// each quarter summed as (l0 + l1) + (l2 + l3). The AVX-512 and AVX2
// kernels do exactly this per lane (the AVX2 one on two 8-lane halves of the
// same 16 lanes), so they give the same bits. An entry's (a, b, c, d) come
// from the encoding's four columns, four entries at a time, transposed in
// registers.
constexpr int kRowChains = 4;

__attribute__((target("avx2,fma"))) inline __m128 quarter_sums(__m128 x, __m128 y, __m128 z) {
  __m128 w = _mm_setzero_ps();
  _MM_TRANSPOSE4_PS(x, y, z, w);  // now x = lane 0 of each quarter, ...
  return _mm_add_ps(_mm_add_ps(x, y), _mm_add_ps(z, w));
}

// Entries e .. e+3 as (a, b, c, d) rows; past the row's end, zeros.
__attribute__((target("avx2,fma"), always_inline)) inline void coefficients4(const DetailEncoding& enc, std::uint32_t e,
                                                                             std::uint32_t e1, __m128* k) {
  if (e + 4 <= e1) {
    k[0] = _mm_loadu_ps(enc.a.data() + e);
    k[1] = _mm_loadu_ps(enc.b.data() + e);
    k[2] = _mm_loadu_ps(enc.c.data() + e);
    k[3] = _mm_loadu_ps(enc.d.data() + e);
  } else {
    alignas(16) float t[4][4] = {};
    for (std::uint32_t i = e; i < e1; ++i) {
      t[0][i - e] = enc.a[i];
      t[1][i - e] = enc.b[i];
      t[2][i - e] = enc.c[i];
      t[3][i - e] = enc.d[i];
    }
    for (int j = 0; j < 4; ++j) k[j] = _mm_load_ps(t[j]);
  }
  _MM_TRANSPOSE4_PS(k[0], k[1], k[2], k[3]);
}

// (The masked broadcasts and extracts with an all-ones mask are the plain
// instructions; their unmasked intrinsics pass GCC 12 an undefined source
// that -Wmaybe-uninitialized reports.)
// Eqs. (11)-(12), one body, AVX-512: per entry one 64-byte frame line times
// its (a, b, c, d) in every quarter, one FMA.
__attribute__((target("avx512f,avx2,fma"))) void decode_rows_avx512(const DetailEncoding& enc, const float* frames,
                                                                    std::size_t begin, std::size_t end, Vec3d* out) {
  const std::uint32_t* poly = enc.polygon.data();
  for (std::size_t v = begin; v < end; ++v) {
    __m512 s[kRowChains];
    for (auto& x : s) x = _mm512_setzero_ps();
    const std::uint32_t e1 = enc.row[v + 1];
    for (std::uint32_t e = enc.row[v]; e < e1; e += kRowChains) {
      __m128 k[4];
      coefficients4(enc, e, e1, k);
      for (std::uint32_t j = 0; j < kRowChains && e + j < e1; ++j)
        s[j] = _mm512_fmadd_ps(_mm512_mask_broadcast_f32x4(_mm512_setzero_ps(), 0xFFFF, k[j]),
                               _mm512_load_ps(frames + std::size_t{poly[e + j]} * 16), s[j]);
    }
    const __m512 t = _mm512_add_ps(_mm512_add_ps(s[0], s[1]), _mm512_add_ps(s[2], s[3]));
    alignas(16) float r[4];
    _mm_store_ps(r, quarter_sums(_mm512_mask_extractf32x4_ps(_mm_setzero_ps(), 0xF, t, 0),
                                 _mm512_mask_extractf32x4_ps(_mm_setzero_ps(), 0xF, t, 1),
                                 _mm512_mask_extractf32x4_ps(_mm_setzero_ps(), 0xF, t, 2)));
    out[v] = Vec3d(r[0], r[1], r[2]);
  }
}

// The same with AVX2: the line's two halves, two FMAs per entry.
__attribute__((target("avx2,fma"))) void decode_rows_avx2(const DetailEncoding& enc, const float* frames,
                                                          std::size_t begin, std::size_t end, Vec3d* out) {
  const std::uint32_t* poly = enc.polygon.data();
  for (std::size_t v = begin; v < end; ++v) {
    __m256 lo[kRowChains], hi[kRowChains];
    for (int j = 0; j < kRowChains; ++j) lo[j] = hi[j] = _mm256_setzero_ps();
    const std::uint32_t e1 = enc.row[v + 1];
    for (std::uint32_t e = enc.row[v]; e < e1; e += kRowChains) {
      __m128 k[4];
      coefficients4(enc, e, e1, k);
      for (std::uint32_t j = 0; j < kRowChains && e + j < e1; ++j) {
        const __m256 kk = _mm256_set_m128(k[j], k[j]);
        const float* f = frames + std::size_t{poly[e + j]} * 16;
        lo[j] = _mm256_fmadd_ps(kk, _mm256_load_ps(f), lo[j]);
        hi[j] = _mm256_fmadd_ps(kk, _mm256_load_ps(f + 8), hi[j]);
      }
    }
    const __m256 l = _mm256_add_ps(_mm256_add_ps(lo[0], lo[1]), _mm256_add_ps(lo[2], lo[3]));
    const __m256 h = _mm256_add_ps(_mm256_add_ps(hi[0], hi[1]), _mm256_add_ps(hi[2], hi[3]));
    alignas(16) float r[4];
    _mm_store_ps(r, quarter_sums(_mm256_castps256_ps128(l), _mm256_extractf128_ps(l, 1), _mm256_castps256_ps128(h)));
    out[v] = Vec3d(r[0], r[1], r[2]);
  }
}

void decode_rows_scalar(const DetailEncoding& enc, const float* frames, std::size_t begin, std::size_t end,
                        Vec3d* out) {
  for (std::size_t v = begin; v < end; ++v) {
    float s[3] = {0, 0, 0};
    for (std::uint32_t e = enc.row[v]; e < enc.row[v + 1]; ++e) {
      const float* f = frames + static_cast<std::size_t>(enc.polygon[e]) * 16;
      for (int k = 0; k < 3; ++k)
        s[k] += enc.a[e] * f[4 * k] + enc.b[e] * f[4 * k + 1] + enc.c[e] * f[4 * k + 2] + enc.d[e] * f[4 * k + 3];
    }
    out[v] = Vec3d(s[0], s[1], s[2]);
  }
}

}  // namespace

DecodeKernel decode_detail(const DetailEncoding& enc, const PolygonFrames& frames, std::span<Vec3d> out,
                           const ExecContext& ctx, DecodeKernel allow) {
  PackedFrames packed;
  packed.pack(frames, ctx);
  ExecContext c = ctx;
  c.grain = ctx.grain ? ctx.grain : 256;
  const DecodeKernel kernel = pick_kernel(allow);
  par::for_each_block(c, enc.vertex_count(), [&](std::size_t b, std::size_t e) {
    if (kernel == DecodeKernel::kAvx512)
      decode_rows_avx512(enc, packed.data, b, e, out.data());
    else if (kernel == DecodeKernel::kAvx2)
      decode_rows_avx2(enc, packed.data, b, e, out.data());
    else
      decode_rows_scalar(enc, packed.data, b, e, out.data());
  });
  return kernel;
}

Status decode_detail(const DetailEncoding& enc, const BodyPolygons& body, std::span<const Vec3d> bp,
                     std::span<Vec3d> out, const ExecContext& ctx) {
  if (Status s = check_topology(enc, body); !s) return s;
  if (bp.size() != body.node_count || out.size() != enc.vertex_count())
    return {ErrorCode::kMismatch, "decode_detail: position or output array has the wrong size"};
  PolygonFrames fr;
  compute_frames(body, bp, fr, ctx, enc.reference_corners, enc.scaled_frames);
  decode_detail(enc, fr, out, ctx);
  return {};
}

}  // namespace atelier
