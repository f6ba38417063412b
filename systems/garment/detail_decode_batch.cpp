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

// Batched frames: per polygon 12 rows (p_c, X, Y, Z; x, y, z) of kLanes
// bodies, so one entry applies to kLanes bodies with 12 8-wide FMAs.
constexpr std::size_t kLanes = 8;
constexpr std::size_t kFrameFloats = 12 * kLanes;

// One tile of vertices for one group of kLanes bodies: per run (a polygon
// used by several tile vertices) its frames are loaded once and applied to
// every entry of the run. acc: [tile vertex][x, y, z][lane].
__attribute__((target("avx2,fma"))) void decode_tile_avx2(const std::uint32_t* run_polygon,
                                                          const std::uint32_t* run_entry, std::size_t run_begin,
                                                          std::size_t run_end, const std::uint8_t* vertex,
                                                          const float* coef, const float* frames, float* acc) {
  for (std::size_t r = run_begin; r < run_end; ++r) {
    const float* F = frames + static_cast<std::size_t>(run_polygon[r]) * kFrameFloats;
    // The frames of a tile's polygons come from L3 (a pass's frames are
    // megabytes): fetch the next run's six lines while this run computes.
    if (r + 1 < run_end) {
      const char* next =
          reinterpret_cast<const char*>(frames + static_cast<std::size_t>(run_polygon[r + 1]) * kFrameFloats);
      for (int l = 0; l < 6; ++l) _mm_prefetch(next + 64 * l, _MM_HINT_T0);
    }
    __m256 f[12];
    for (int j = 0; j < 12; ++j) f[j] = _mm256_load_ps(F + 8 * j);
    for (std::uint32_t e = run_entry[r]; e < run_entry[r + 1]; ++e) {
      float* o = acc + static_cast<std::size_t>(vertex[e]) * 3 * kLanes;
      const float* c = coef + 4 * static_cast<std::size_t>(e);
      const __m256 a = _mm256_broadcast_ss(c), b = _mm256_broadcast_ss(c + 1), cc = _mm256_broadcast_ss(c + 2),
                   d = _mm256_broadcast_ss(c + 3);
      // A tree, (a p_c + b X) + (c Y + d Z), added to the accumulator last:
      // the products do not wait for the accumulator's load, and the
      // chains are half as deep, so more entries overlap.
      for (int k = 0; k < 3; ++k) {
        const __m256 s = _mm256_fmadd_ps(b, f[3 + k], _mm256_mul_ps(a, f[k]));
        const __m256 t = _mm256_fmadd_ps(d, f[9 + k], _mm256_mul_ps(cc, f[6 + k]));
        _mm256_store_ps(o + 8 * k, _mm256_add_ps(_mm256_load_ps(o + 8 * k), _mm256_add_ps(s, t)));
      }
    }
  }
}

// The same for two groups (16 bodies) at once, with the same arithmetic per
// lane (bit-identical to decode_tile_avx2 on each group): an entry's
// coefficients, index and loop overhead are shared by both groups. Group
// 0's X, Y, Z stay in registers; its p_c and group 1's frame are read from
// L1 (the run's 768 bytes). acc: [tile vertex][group][x, y, z][lane].
__attribute__((target("avx2,fma"))) void decode_tile2_avx2(const std::uint32_t* run_polygon,
                                                           const std::uint32_t* run_entry, std::size_t run_begin,
                                                           std::size_t run_end, const std::uint8_t* vertex,
                                                           const float* coef, const float* frames0,
                                                           const float* frames1, float* acc) {
  for (std::size_t r = run_begin; r < run_end; ++r) {
    const float* F = frames0 + static_cast<std::size_t>(run_polygon[r]) * kFrameFloats;
    const float* G = frames1 + static_cast<std::size_t>(run_polygon[r]) * kFrameFloats;
    if (r + 1 < run_end) {
      const std::size_t next = static_cast<std::size_t>(run_polygon[r + 1]) * kFrameFloats;
      for (int l = 0; l < 6; ++l) {
        _mm_prefetch(reinterpret_cast<const char*>(frames0 + next) + 64 * l, _MM_HINT_T0);
        _mm_prefetch(reinterpret_cast<const char*>(frames1 + next) + 64 * l, _MM_HINT_T0);
      }
    }
    __m256 f[9];
    for (int j = 0; j < 9; ++j) f[j] = _mm256_load_ps(F + 8 * (3 + j));
    const std::uint32_t e_end = run_entry[r + 1];
    for (std::uint32_t e = run_entry[r]; e < e_end; ++e) {
      float* o = acc + static_cast<std::size_t>(vertex[e]) * 6 * kLanes;
      const float* c = coef + 4 * static_cast<std::size_t>(e);
      const __m256 a = _mm256_broadcast_ss(c), b = _mm256_broadcast_ss(c + 1), cc = _mm256_broadcast_ss(c + 2),
                   d = _mm256_broadcast_ss(c + 3);
      for (int k = 0; k < 3; ++k) {
        const __m256 s = _mm256_fmadd_ps(b, f[k], _mm256_mul_ps(a, _mm256_load_ps(F + 8 * k)));
        const __m256 t = _mm256_fmadd_ps(d, f[6 + k], _mm256_mul_ps(cc, f[3 + k]));
        _mm256_store_ps(o + 8 * k, _mm256_add_ps(_mm256_load_ps(o + 8 * k), _mm256_add_ps(s, t)));
      }
      for (int k = 0; k < 3; ++k) {
        const __m256 s =
            _mm256_fmadd_ps(b, _mm256_load_ps(G + 8 * (3 + k)), _mm256_mul_ps(a, _mm256_load_ps(G + 8 * k)));
        const __m256 t =
            _mm256_fmadd_ps(d, _mm256_load_ps(G + 8 * (9 + k)), _mm256_mul_ps(cc, _mm256_load_ps(G + 8 * (6 + k))));
        _mm256_store_ps(o + 8 * (3 + k), _mm256_add_ps(_mm256_load_ps(o + 8 * (3 + k)), _mm256_add_ps(s, t)));
      }
    }
  }
}

void decode_tile_scalar(const std::uint32_t* run_polygon, const std::uint32_t* run_entry, std::size_t run_begin,
                        std::size_t run_end, const std::uint8_t* vertex, const float* coef, const float* frames,
                        float* acc) {
  for (std::size_t r = run_begin; r < run_end; ++r) {
    const float* F = frames + static_cast<std::size_t>(run_polygon[r]) * kFrameFloats;
    for (std::uint32_t e = run_entry[r]; e < run_entry[r + 1]; ++e) {
      float* o = acc + static_cast<std::size_t>(vertex[e]) * 3 * kLanes;
      const float* c = coef + 4 * static_cast<std::size_t>(e);
      for (std::size_t k = 0; k < 3; ++k)
        for (std::size_t w = 0; w < kLanes; ++w) {
          const float s = std::fma(c[1], F[(3 + k) * kLanes + w], c[0] * F[k * kLanes + w]);
          const float t = std::fma(c[3], F[(9 + k) * kLanes + w], c[2] * F[(6 + k) * kLanes + w]);
          o[k * kLanes + w] += s + t;
        }
    }
  }
}

// The AVX-512 layout: per polygon 12 rows of kWideLanes = 16 bodies (768
// bytes), one zmm register a row.
constexpr std::size_t kWideLanes = 16;
constexpr std::size_t kWideFrameFloats = 12 * kWideLanes;

// decode_tile2_avx2 with one 16-lane register per frame row: a run's whole
// frame (12 rows for 16 bodies) stays in registers (AVX-512 has 32), so an
// entry costs 4 broadcasts, 3 accumulator loads and 3 stores next to its 12
// FMA-unit operations, where the AVX2 kernel, with 16 registers, also reads
// 15 of its 24 frame vectors from L1 (31 memory operations per entry). The
// arithmetic per lane is the AVX2 kernel's, in the same order, so both give
// the same bits. acc: [tile vertex][x, y, z][16 lanes].
__attribute__((target("avx512f"))) void decode_tile_avx512(const std::uint32_t* run_polygon,
                                                           const std::uint32_t* run_entry, std::size_t run_begin,
                                                           std::size_t run_end, const std::uint8_t* vertex,
                                                           const float* coef, const float* frames, float* acc) {
  for (std::size_t r = run_begin; r < run_end; ++r) {
    const float* F = frames + static_cast<std::size_t>(run_polygon[r]) * kWideFrameFloats;
    if (r + 1 < run_end) {
      const char* next =
          reinterpret_cast<const char*>(frames + static_cast<std::size_t>(run_polygon[r + 1]) * kWideFrameFloats);
      for (int l = 0; l < 12; ++l) _mm_prefetch(next + 64 * l, _MM_HINT_T0);
    }
    __m512 f[12];
    for (int j = 0; j < 12; ++j) f[j] = _mm512_load_ps(F + 16 * j);
    const std::uint32_t e_end = run_entry[r + 1];
    for (std::uint32_t e = run_entry[r]; e < e_end; ++e) {
      float* o = acc + static_cast<std::size_t>(vertex[e]) * 3 * kWideLanes;
      const float* c = coef + 4 * static_cast<std::size_t>(e);
      const __m512 a = _mm512_set1_ps(c[0]), b = _mm512_set1_ps(c[1]), cc = _mm512_set1_ps(c[2]),
                   d = _mm512_set1_ps(c[3]);
      for (int k = 0; k < 3; ++k) {
        const __m512 s = _mm512_fmadd_ps(b, f[3 + k], _mm512_mul_ps(a, f[k]));
        const __m512 t = _mm512_fmadd_ps(d, f[9 + k], _mm512_mul_ps(cc, f[6 + k]));
        _mm512_store_ps(o + 16 * k, _mm512_add_ps(_mm512_load_ps(o + 16 * k), _mm512_add_ps(s, t)));
      }
    }
  }
}

// Frames of one polygon on 8 bodies at once (AVX2 floats, one body per
// lane): polygon_frame's steps with the branches as lane masks. Batched
// decoding computes polygons x bodies frames per pass; in doubles they cost
// a fifth of the whole decode. Floats keep the frames' precision because
// every product is taken on corners relative to the polygon's first corner
// (exact differences of nearby floats): the cross-product sum is invariant
// under that shift for a closed polygon, so no product of two metre-sized
// coordinates loses the centimetre-sized area to cancellation. Frames then
// differ from polygon_frame's by float rounding (a few 1e-7 relative).
//
// pos: node positions of the pass's bodies, node-major ([node][x, y, z]
// [lanes] floats), read at lanes lane .. lane + 7. out: rows (p_c, X, Y,
// Z; x, y, z) of 8 floats, row_stride floats apart (kLanes in the AVX2
// layout, kWideLanes in the AVX-512 one). Polygons of at most kMaxCorners.
constexpr std::size_t kMaxCorners = 16;
__attribute__((target("avx2,fma"), always_inline)) inline __m256 dot_x8(__m256 a0, __m256 a1, __m256 a2, __m256 b0,
                                                                        __m256 b1, __m256 b2) {
  return _mm256_fmadd_ps(a2, b2, _mm256_fmadd_ps(a1, b1, _mm256_mul_ps(a0, b0)));
}
// Without FMA: a x a is then exactly zero, so a polygon folded onto a
// segment (repeated corners) has an exactly zero normal, as in doubles.
__attribute__((target("avx2"), always_inline)) inline void cross_x8(__m256 a0, __m256 a1, __m256 a2, __m256 b0,
                                                                    __m256 b1, __m256 b2, __m256* out) {
  out[0] = _mm256_sub_ps(_mm256_mul_ps(a1, b2), _mm256_mul_ps(a2, b1));
  out[1] = _mm256_sub_ps(_mm256_mul_ps(a2, b0), _mm256_mul_ps(a0, b2));
  out[2] = _mm256_sub_ps(_mm256_mul_ps(a0, b1), _mm256_mul_ps(a1, b0));
}

__attribute__((target("avx2,fma"))) void polygon_frame_x8(const BodyPolygons& b, const float* pos, std::size_t lanes,
                                                          std::size_t lane, std::size_t f,
                                                          std::span<const Eigen::Vector2f> ref, bool scaled,
                                                          float* out, std::size_t row_stride) {
  const std::uint32_t s = b.face_offsets[f], e = b.face_offsets[f + 1];
  const std::size_t n = e - s;
  __m256 O[3];
  __m256 P[3 * kMaxCorners];  // corners relative to corner 0
  {
    const float* node = pos + std::size_t{b.face_nodes[s]} * 3 * lanes + lane;
    for (std::size_t d = 0; d < 3; ++d) O[d] = _mm256_loadu_ps(node + d * lanes);
  }
  P[0] = P[1] = P[2] = _mm256_setzero_ps();
  for (std::size_t k = 1; k < n; ++k) {
    const float* node = pos + std::size_t{b.face_nodes[s + k]} * 3 * lanes + lane;
    for (std::size_t d = 0; d < 3; ++d) P[3 * k + d] = _mm256_sub_ps(_mm256_loadu_ps(node + d * lanes), O[d]);
  }
  const __m256 zero = _mm256_setzero_ps();
  __m256 c0 = zero, c1 = zero, c2 = zero, nr0 = zero, nr1 = zero, nr2 = zero, scale = zero;
  for (std::size_t k = 0; k < n; ++k) {
    const __m256* A = P + 3 * k;
    const __m256* Q = P + 3 * (k + 1 < n ? k + 1 : 0);
    c0 = _mm256_add_ps(c0, A[0]);
    c1 = _mm256_add_ps(c1, A[1]);
    c2 = _mm256_add_ps(c2, A[2]);
    __m256 x[3];
    cross_x8(A[0], A[1], A[2], Q[0], Q[1], Q[2], x);
    nr0 = _mm256_add_ps(nr0, x[0]);
    nr1 = _mm256_add_ps(nr1, x[1]);
    nr2 = _mm256_add_ps(nr2, x[2]);
    const __m256 d0 = _mm256_sub_ps(Q[0], A[0]), d1 = _mm256_sub_ps(Q[1], A[1]), d2 = _mm256_sub_ps(Q[2], A[2]);
    scale = _mm256_max_ps(scale, dot_x8(d0, d1, d2, d0, d1, d2));
  }
  const __m256 inv_n = _mm256_set1_ps(1.0f / static_cast<float>(n));
  c0 = _mm256_mul_ps(c0, inv_n);  // the centroid relative to corner 0
  c1 = _mm256_mul_ps(c1, inv_n);
  c2 = _mm256_mul_ps(c2, inv_n);
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 nn = _mm256_sqrt_ps(dot_x8(nr0, nr1, nr2, nr0, nr1, nr2));
  // polygon_frame's degeneracy tests, with bounds raised from double's
  // rounding level (1e-12, 1e-9) to float's: a polygon with collinear
  // corners has a normal of float noise, about 1e-7 of its squared size.
  // Only slivers with aspect ratios between 1e6 and 1e12 are judged
  // differently from polygon_frame.
  const __m256 ok1 = _mm256_and_ps(_mm256_cmp_ps(nn, _mm256_mul_ps(_mm256_set1_ps(1e-6f), scale), _CMP_GT_OQ),
                                   _mm256_cmp_ps(scale, zero, _CMP_GT_OQ));
  const __m256 inv_nn = _mm256_div_ps(one, nn);
  const __m256 x0 = _mm256_mul_ps(nr0, inv_nn), x1 = _mm256_mul_ps(nr1, inv_nn), x2 = _mm256_mul_ps(nr2, inv_nn);
  // Y: corner 0 minus the centroid, made orthogonal to X.
  __m256 y0 = _mm256_sub_ps(zero, c0), y1 = _mm256_sub_ps(zero, c1), y2 = _mm256_sub_ps(zero, c2);
  const __m256 yx = dot_x8(y0, y1, y2, x0, x1, x2);
  y0 = _mm256_fnmadd_ps(yx, x0, y0);
  y1 = _mm256_fnmadd_ps(yx, x1, y1);
  y2 = _mm256_fnmadd_ps(yx, x2, y2);
  const __m256 yn = _mm256_sqrt_ps(dot_x8(y0, y1, y2, y0, y1, y2));
  const __m256 ok2 =
      _mm256_and_ps(ok1, _mm256_cmp_ps(yn, _mm256_mul_ps(_mm256_set1_ps(1e-6f), _mm256_sqrt_ps(scale)), _CMP_GT_OQ));
  const __m256 inv_yn = _mm256_div_ps(one, yn);
  y0 = _mm256_mul_ps(y0, inv_yn);
  y1 = _mm256_mul_ps(y1, inv_yn);
  y2 = _mm256_mul_ps(y2, inv_yn);
  __m256 z[3];
  cross_x8(x0, x1, x2, y0, y1, y2, z);
  __m256 sim = one;  // the similarity scale (scaled frames), else 1
  if (!ref.empty()) {
    __m256 sdot = zero, scross = zero;
    float rr = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const __m256 q0 = _mm256_sub_ps(P[3 * k], c0), q1 = _mm256_sub_ps(P[3 * k + 1], c1),
                   q2 = _mm256_sub_ps(P[3 * k + 2], c2);
      const __m256 d1 = dot_x8(q0, q1, q2, y0, y1, y2), d2 = dot_x8(q0, q1, q2, z[0], z[1], z[2]);
      const __m256 r1 = _mm256_set1_ps(ref[s + k].x()), r2 = _mm256_set1_ps(ref[s + k].y());
      sdot = _mm256_fmadd_ps(r2, d2, _mm256_fmadd_ps(r1, d1, sdot));
      scross = _mm256_fnmadd_ps(r2, d1, _mm256_fmadd_ps(r1, d2, scross));
      rr += ref[s + k].squaredNorm();
    }
    const __m256 r = _mm256_sqrt_ps(_mm256_fmadd_ps(scross, scross, _mm256_mul_ps(sdot, sdot)));
    const __m256 turn = _mm256_cmp_ps(r, zero, _CMP_GT_OQ);
    const __m256 inv_r = _mm256_div_ps(one, r), cs = _mm256_mul_ps(sdot, inv_r), sn = _mm256_mul_ps(scross, inv_r);
    const __m256 t0 = _mm256_fmadd_ps(sn, z[0], _mm256_mul_ps(cs, y0));
    const __m256 t1 = _mm256_fmadd_ps(sn, z[1], _mm256_mul_ps(cs, y1));
    const __m256 t2 = _mm256_fmadd_ps(sn, z[2], _mm256_mul_ps(cs, y2));
    __m256 tz[3];
    cross_x8(x0, x1, x2, t0, t1, t2, tz);
    y0 = _mm256_blendv_ps(y0, t0, turn);
    y1 = _mm256_blendv_ps(y1, t1, turn);
    y2 = _mm256_blendv_ps(y2, t2, turn);
    for (int i = 0; i < 3; ++i) z[i] = _mm256_blendv_ps(z[i], tz[i], turn);
    if (scaled && rr > 0) sim = _mm256_blendv_ps(one, _mm256_mul_ps(r, _mm256_set1_ps(1.0f / rr)), turn);
  }
  // Times 1 without scaled frames: the same bits as before.
  const __m256 sx0 = _mm256_mul_ps(x0, sim), sx1 = _mm256_mul_ps(x1, sim), sx2 = _mm256_mul_ps(x2, sim);
  y0 = _mm256_mul_ps(y0, sim);
  y1 = _mm256_mul_ps(y1, sim);
  y2 = _mm256_mul_ps(y2, sim);
  for (int i = 0; i < 3; ++i) z[i] = _mm256_mul_ps(z[i], sim);
  const __m256 rows[12] = {_mm256_add_ps(O[0], c0),  _mm256_add_ps(O[1], c1),  _mm256_add_ps(O[2], c2),
                           _mm256_and_ps(sx0, ok1),  _mm256_and_ps(sx1, ok1),  _mm256_and_ps(sx2, ok1),
                           _mm256_and_ps(y0, ok2),   _mm256_and_ps(y1, ok2),   _mm256_and_ps(y2, ok2),
                           _mm256_and_ps(z[0], ok2), _mm256_and_ps(z[1], ok2), _mm256_and_ps(z[2], ok2)};
  for (std::size_t j = 0; j < 12; ++j) _mm256_store_ps(out + j * row_stride, rows[j]);
}

}  // namespace

DetailDecoder::DetailDecoder(const DetailEncoding& enc, const ExecContext& ctx)
    : polygon_count_(enc.polygon_count),
      body_node_count_(enc.body_node_count),
      topology_hash_(enc.topology_hash),
      vertex_count_(static_cast<std::uint32_t>(enc.vertex_count())),
      reference_corners_(enc.reference_corners),
      scaled_frames_(enc.scaled_frames) {
  const std::size_t nv = enc.vertex_count(), ne = enc.entries(), np = enc.polygon_count;
  const std::size_t tiles = (nv + kTile - 1) / kTile;
  vertex_.resize(ne);
  coef_.resize(4 * ne);
  // Per tile, a counting sort of its entries by polygon; within a run the
  // tile's vertices stay in increasing order, so every vertex still sums
  // its entries in row order.
  std::vector<std::vector<std::uint32_t>> polys(tiles), ends(tiles);
  ExecContext c = ctx;
  c.grain = 4;
  c.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 8);
  par::for_each_block(c, tiles, [&](std::size_t t0, std::size_t t1) {
    std::vector<std::uint32_t> slot(np, 0);
    std::vector<std::uint32_t> touched;
    for (std::size_t t = t0; t < t1; ++t) {
      const std::size_t v0 = t * kTile, v1 = std::min(nv, v0 + kTile);
      const std::uint32_t base = enc.row[v0];
      touched.clear();
      for (std::uint32_t e = base; e < enc.row[v1]; ++e)
        if (slot[enc.polygon[e]]++ == 0) touched.push_back(enc.polygon[e]);
      std::sort(touched.begin(), touched.end());
      std::uint32_t at = base;
      for (const std::uint32_t p : touched) {
        const std::uint32_t n = slot[p];
        slot[p] = at;  // count -> next free position of the run
        at += n;
        ends[t].push_back(at);
      }
      polys[t] = touched;
      for (std::size_t v = v0; v < v1; ++v)
        for (std::uint32_t e = enc.row[v]; e < enc.row[v + 1]; ++e) {
          const std::uint32_t pos = slot[enc.polygon[e]]++;
          vertex_[pos] = static_cast<std::uint8_t>(v - v0);
          coef_[4 * std::size_t{pos}] = enc.a[e];
          coef_[4 * std::size_t{pos} + 1] = enc.b[e];
          coef_[4 * std::size_t{pos} + 2] = enc.c[e];
          coef_[4 * std::size_t{pos} + 3] = enc.d[e];
        }
      for (const std::uint32_t p : touched) slot[p] = 0;
    }
  });
  tile_run_.assign(tiles + 1, 0);
  for (std::size_t t = 0; t < tiles; ++t) tile_run_[t + 1] = tile_run_[t] + static_cast<std::uint32_t>(polys[t].size());
  run_polygon_.resize(tile_run_.back());
  run_entry_.resize(tile_run_.back() + 1);
  run_entry_[0] = 0;
  for (std::size_t t = 0; t < tiles; ++t) {
    std::copy(polys[t].begin(), polys[t].end(), run_polygon_.begin() + tile_run_[t]);
    std::copy(ends[t].begin(), ends[t].end(), run_entry_.begin() + tile_run_[t] + 1);
  }
  // A garment rarely covers the whole body (a skirt uses a fifth of the
  // skin's polygons): frames are computed for these polygons only.
  std::vector<std::uint8_t> used(np, 0);
  for (const std::uint32_t p : run_polygon_) used[p] = 1;
  for (std::size_t p = 0; p < np; ++p)
    if (used[p]) used_polygons_.push_back(static_cast<std::uint32_t>(p));
}

Status DetailDecoder::check_topology(const BodyPolygons& body) const {
  if (polygon_count_ != body.size() || body_node_count_ != body.node_count || topology_hash_ != body.topology_hash) {
    std::ostringstream s;
    s << "the body's topology (" << body.node_count << " nodes, " << body.size()
      << " polygons) differs from the one the detail template was encoded on (" << body_node_count_ << " nodes, "
      << polygon_count_ << " polygons)";
    return {ErrorCode::kMismatch, s.str()};
  }
  return {};
}

Status decode_detail_batch(const DetailDecoder& dec, const BodyPolygons& body, const BodySet& bodies, std::size_t first,
                           std::size_t count, std::span<Vec3f> out, const ExecContext& ctx) {
  DecodeWorkspace ws;
  return decode_detail_batch(dec, body, bodies, first, count, out, ws, ctx);
}

Status decode_detail_batch(const DetailDecoder& dec, const BodyPolygons& body, const BodySet& bodies, std::size_t first,
                           std::size_t count, std::span<Vec3f> out, DecodeWorkspace& ws, const ExecContext& ctx) {
  if (Status s = dec.check_topology(body); !s) return s;
  if (bodies.node_count() != body.node_count)
    return {ErrorCode::kMismatch, "decode_detail_batch: the body set has another node count than the template's body"};
  if (first + count > bodies.size())
    return {ErrorCode::kInvalidArgument, "decode_detail_batch: body range out of bounds"};
  const std::size_t nv = dec.vertex_count();
  if (out.size() != count * nv) return {ErrorCode::kMismatch, "decode_detail_batch: output has the wrong size"};
  if (count == 0 || nv == 0) return {};
  const std::size_t np = body.size();
  const DecodeKernel kernel = pick_kernel(ws.allow);
  ws.ran = kernel;
  const bool fast = kernel != DecodeKernel::kPortable, wide = kernel == DecodeKernel::kAvx512;
  // Groups of kLanes bodies; kGroups groups share one pass over the matrix
  // (a tile's entries stay in L2 while each group's frames stream through).
  // The AVX-512 kernel takes both groups in one register (its frames are
  // laid out 16 lanes a row), so its passes always hold 16 lanes.
  constexpr std::size_t kGroups = 2;
  static_assert(kGroups * kLanes == kWideLanes);
  const std::size_t pass_groups = wide ? kGroups : std::min(kGroups, (count + kLanes - 1) / kLanes);
  // Frame of polygon p for group g: rows of `row` floats.
  const std::size_t row = wide ? kWideLanes : kLanes;
  auto frame_of = [&](float* base, std::size_t g, std::size_t p) {
    return wide ? base + p * kWideFrameFloats + g * kLanes : base + (g * np + p) * kFrameFloats;
  };
  // Every lane of every frame the decoder reads (its used polygons') is
  // written below before it is read.
  if (ws.frames.size() < pass_groups * np * kFrameFloats + 16) ws.frames.resize(pass_groups * np * kFrameFloats + 16);
  const auto addr = reinterpret_cast<std::uintptr_t>(ws.frames.data());
  float* frames = ws.frames.data() + ((64 - addr % 64) % 64) / sizeof(float);
  if (fast && ws.positions.size() < std::size_t{body.node_count} * 3 * pass_groups * kLanes)
    ws.positions.resize(std::size_t{body.node_count} * 3 * pass_groups * kLanes);
  float* tpos = ws.positions.data();
  // The nodes whose positions the frames read: the used polygons' corners.
  std::vector<std::uint32_t> nodes;
  if (fast) {
    std::vector<std::uint8_t> used(body.node_count, 0);
    for (const std::uint32_t p : dec.used_polygons_)
      for (std::uint32_t k = body.face_offsets[p]; k < body.face_offsets[p + 1]; ++k) used[body.face_nodes[k]] = 1;
    for (std::uint32_t n = 0; n < body.node_count; ++n)
      if (used[n]) nodes.push_back(n);
  }
  const std::size_t tiles = (nv + DetailDecoder::kTile - 1) / DetailDecoder::kTile;
  for (std::size_t g0 = 0; g0 < count; g0 += pass_groups * kLanes) {
    const std::size_t nb = std::min(pass_groups * kLanes, count - g0);
    const std::size_t groups = wide ? kGroups : (nb + kLanes - 1) / kLanes;
    // Frames of every body of the pass, written straight into the lanes,
    // 8 bodies per vector. Lanes past the last body repeat it (never output).
    const float* col[kGroups * kLanes];
    for (std::size_t i = 0; i < groups * kLanes; ++i) col[i] = bodies.x(first + g0 + std::min(i, nb - 1)).data();
    const std::size_t stride = bodies.node_count(), lanes = groups * kLanes;
    if (fast) {
      // The bodies' columns transposed node-major, so a polygon corner's
      // coordinate for 8 bodies is one load (a body set is body-major: 48
      // columns read at once would defeat the hardware prefetchers). Only
      // the used nodes (not a body's helper geometry or the skin a garment
      // does not reach), in sub-blocks of 128 whose 24 KB of transposed
      // rows stay in L1 while the columns are read into them.
      ExecContext tc = ctx;
      tc.grain = 2048;
      par::for_each_block(tc, nodes.size(), [&](std::size_t b0, std::size_t b1) {
        for (std::size_t j0 = b0; j0 < b1; j0 += 128) {
          const std::size_t j1 = std::min(b1, j0 + 128);
          for (std::size_t i = 0; i < lanes; ++i)
            for (std::size_t d = 0; d < 3; ++d) {
              const float* src = col[i] + d * stride;
              for (std::size_t j = j0; j < j1; ++j) tpos[(nodes[j] * std::size_t{3} + d) * lanes + i] = src[nodes[j]];
            }
        }
      });
    }
    ExecContext fc = ctx;
    fc.grain = 256;  // 13k polygons: enough blocks to balance 2 threads
    par::for_each_n(fc, dec.used_polygons_.size(), [&](std::size_t u) {
      const std::size_t p = dec.used_polygons_[u];
      const bool small = body.face_offsets[p + 1] - body.face_offsets[p] <= kMaxCorners;
      for (std::size_t g = 0; g < groups; ++g) {
        float* f = frame_of(frames, g, p);
        if (fast && small) {
          polygon_frame_x8(body, tpos, lanes, g * kLanes, p, dec.reference_corners_, dec.scaled_frames_, f, row);
          continue;
        }
        for (std::size_t l = 0; l < kLanes; ++l) {
          const float* cl = col[g * kLanes + l];
          const SetPos pos{cl, cl + stride, cl + 2 * stride};
          const FrameD fr = polygon_frame(body, pos, p, dec.reference_corners_, dec.scaled_frames_);
          const Vec3d* v[4] = {&fr.c, &fr.x, &fr.y, &fr.z};
          for (std::size_t j = 0; j < 4; ++j)
            for (std::size_t k = 0; k < 3; ++k)
              f[(3 * j + k) * row + l] = static_cast<float>((*v[j])[static_cast<int>(k)]);
        }
      }
    });
    ExecContext c = ctx;
    c.grain = 2;
    c.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 4);
    par::for_each_block(c, tiles, [&](std::size_t t0, std::size_t t1) {
      alignas(64) float acc[DetailDecoder::kTile * 3 * kGroups * kLanes];
      for (std::size_t t = t0; t < t1; ++t) {
        const std::size_t v0 = t * DetailDecoder::kTile, v1 = std::min(nv, v0 + DetailDecoder::kTile);
        if (wide || (fast && groups == 2)) {
          // Both groups in one pass: acc is [vertex][x, y, z][16 lanes]
          // (AVX-512) or [vertex][group][x, y, z][8 lanes] (AVX2).
          std::fill(acc, acc + (v1 - v0) * 6 * kLanes, 0.0f);
          if (wide)
            decode_tile_avx512(dec.run_polygon_.data(), dec.run_entry_.data(), dec.tile_run_[t], dec.tile_run_[t + 1],
                               dec.vertex_.data(), dec.coef_.data(), frames, acc);
          else
            decode_tile2_avx2(dec.run_polygon_.data(), dec.run_entry_.data(), dec.tile_run_[t], dec.tile_run_[t + 1],
                              dec.vertex_.data(), dec.coef_.data(), frames, frames + np * kFrameFloats, acc);
          for (std::size_t g = 0; g * kLanes < nb; ++g) {
            const std::size_t lanes = std::min(kLanes, nb - g * kLanes);
            for (std::size_t v = v0; v < v1; ++v) {
              const float* r =
                  wide ? acc + (v - v0) * 3 * kWideLanes + g * kLanes : acc + ((v - v0) * 2 + g) * 3 * kLanes;
              for (std::size_t w = 0; w < lanes; ++w)
                out[(g0 + g * kLanes + w) * nv + v] = Vec3f(r[w], r[row + w], r[2 * row + w]);
            }
          }
          continue;
        }
        for (std::size_t g = 0; g < groups; ++g) {
          std::fill(acc, acc + (v1 - v0) * 3 * kLanes, 0.0f);
          const float* fg = frames + g * np * kFrameFloats;
          if (fast)
            decode_tile_avx2(dec.run_polygon_.data(), dec.run_entry_.data(), dec.tile_run_[t], dec.tile_run_[t + 1],
                             dec.vertex_.data(), dec.coef_.data(), fg, acc);
          else
            decode_tile_scalar(dec.run_polygon_.data(), dec.run_entry_.data(), dec.tile_run_[t], dec.tile_run_[t + 1],
                               dec.vertex_.data(), dec.coef_.data(), fg, acc);
          const std::size_t lanes = std::min(kLanes, nb - g * kLanes);
          for (std::size_t v = v0; v < v1; ++v) {
            const float* r = acc + (v - v0) * 3 * kLanes;
            for (std::size_t w = 0; w < lanes; ++w)
              out[(g0 + g * kLanes + w) * nv + v] = Vec3f(r[w], r[kLanes + w], r[2 * kLanes + w]);
          }
        }
      }
    });
    if (ctx.cancelled()) return {ErrorCode::kCancelled, "decode_detail_batch cancelled"};
  }
  return {};
}

Status decode_detail_batch(const DetailEncoding& enc, const BodyPolygons& body, const BodySet& bodies,
                           std::size_t first, std::size_t count, std::span<Vec3f> out, const ExecContext& ctx) {
  if (Status s = check_topology(enc, body); !s) return s;
  return decode_detail_batch(DetailDecoder(enc, ctx), body, bodies, first, count, out, ctx);
}

}  // namespace atelier
