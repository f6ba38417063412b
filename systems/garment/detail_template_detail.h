// Internals shared by the sources of the detail template (seed 001 section
// 6), manifold style: one private header whose sections name the source
// implementing them, so the unit splits without touching the public header
// (systems/garment/detail_template.h).
//
//   detail_frames.cpp        body polygons, polygon frames (eq. 8)
//   detail_encode.cpp        encoding (eqs. 9-10)
//   detail_decode.cpp        single-body decoding kernels (eqs. 11-12)
//   detail_decode_batch.cpp  the batched decoder and its kernels
//   detail_file.cpp          the .atd file
//   systems/spatial/centroid_grid.cpp  the p-polygon search
#pragma once

#include <cstdint>
#include <span>

#include <atelier/engine/cpu_features.h>
#include <atelier/engine/math.h>
#include <atelier/systems/garment/detail_template.h>

namespace atelier::detail_internal {

// ---------------------------------------------------------- detail_frames.cpp

/// FNV-1a, the topology hash of BodyPolygons (and the checksum of version-1 .atd files).
inline std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

struct FrameD {
  Vec3d c, x, y, z;
  bool degenerate;
};

// Eq. (8). The normal is Newell's (exact for planar polygons, a robust
// average otherwise). Y is p_1 - p_c with its normal component removed, so
// the frame is orthonormal even for non-planar quads and encoding then
// decoding on the same body returns q exactly.
//
// With `ref` (fitted frames), Y is then turned by the best-fit rotation of
// the polygon's corners onto their reference shape (2D Procrustes: the angle
// maximising sum r_k . R d_k, whose cosine and sine are (sdot, scross)
// normalised). Scalar code over a local copy of the corners: this runs for
// every polygon of every decoded body.
//
// `p.get(node, xyz)` gives a node's position (from a span of doubles, or a
// body set's float columns read in place).
//
// With `scaled` (and `ref`), the axes are then multiplied by the corners'
// best-fit similarity scale r / sum |r_k|^2 (DetailParams::scaled_frames).
template <class Pos>
FrameD polygon_frame(const BodyPolygons& b, const Pos& p, std::size_t f, std::span<const Eigen::Vector2f> ref = {},
                     bool scaled = false) {
  const std::uint32_t s = b.face_offsets[f], e = b.face_offsets[f + 1];
  const std::size_t n = e - s;
  constexpr std::size_t kLocal = 16;
  double local[3 * kLocal];
  std::vector<double> big;
  double* P = local;
  if (n > kLocal) {
    big.resize(3 * n);
    P = big.data();
  }
  for (std::size_t k = 0; k < n; ++k) p.get(b.face_nodes[s + k], P + 3 * k);
  double c[3] = {0, 0, 0}, nr[3] = {0, 0, 0}, scale = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double* A = P + 3 * k;
    const double* Q = P + 3 * (k + 1 < n ? k + 1 : 0);
    c[0] += A[0];
    c[1] += A[1];
    c[2] += A[2];
    nr[0] += A[1] * Q[2] - A[2] * Q[1];
    nr[1] += A[2] * Q[0] - A[0] * Q[2];
    nr[2] += A[0] * Q[1] - A[1] * Q[0];
    const double d0 = Q[0] - A[0], d1 = Q[1] - A[1], d2 = Q[2] - A[2];
    scale = std::max(scale, d0 * d0 + d1 * d1 + d2 * d2);
  }
  const double inv_n = 1.0 / static_cast<double>(n);
  c[0] *= inv_n;
  c[1] *= inv_n;
  c[2] *= inv_n;
  FrameD fr;  // every field is set below (a zeroing constructor costs more than the arithmetic)
  fr.c = Vec3d(c[0], c[1], c[2]);
  fr.x = fr.y = fr.z = Vec3d::Zero();
  const double nn = std::sqrt(nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2]);
  if (!(nn > 1e-12 * scale) || !(scale > 0)) {
    fr.degenerate = true;
    return fr;
  }
  const double inv_nn = 1.0 / nn;
  const double x[3] = {nr[0] * inv_nn, nr[1] * inv_nn, nr[2] * inv_nn};
  double y[3] = {P[0] - c[0], P[1] - c[1], P[2] - c[2]};
  const double yx = y[0] * x[0] + y[1] * x[1] + y[2] * x[2];
  y[0] -= yx * x[0];
  y[1] -= yx * x[1];
  y[2] -= yx * x[2];
  const double yn = std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
  fr.x = Vec3d(x[0], x[1], x[2]);
  if (!(yn > 1e-9 * std::sqrt(scale))) {
    fr.degenerate = true;
    return fr;
  }
  const double inv_yn = 1.0 / yn;
  y[0] *= inv_yn;
  y[1] *= inv_yn;
  y[2] *= inv_yn;
  double z[3] = {x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
  double sim = 1;  // similarity scale (scaled frames)
  if (!ref.empty()) {
    double sdot = 0, scross = 0, rr = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const double q[3] = {P[3 * k] - c[0], P[3 * k + 1] - c[1], P[3 * k + 2] - c[2]};
      const double d1 = q[0] * y[0] + q[1] * y[1] + q[2] * y[2];
      const double d2 = q[0] * z[0] + q[1] * z[1] + q[2] * z[2];
      const double r1 = ref[s + k].x(), r2 = ref[s + k].y();
      sdot += r1 * d1 + r2 * d2;
      scross += r1 * d2 - r2 * d1;
      rr += r1 * r1 + r2 * r2;
    }
    const double r = std::sqrt(sdot * sdot + scross * scross);  // sums of squared lengths: no overflow to fear
    if (r > 0) {                                                // else no preferred angle (atan2(0, 0) = 0)
      const double inv_r = 1.0 / r, cs = sdot * inv_r, sn = scross * inv_r;
      for (int i = 0; i < 3; ++i) y[i] = cs * y[i] + sn * z[i];
      z[0] = x[1] * y[2] - x[2] * y[1];
      z[1] = x[2] * y[0] - x[0] * y[2];
      z[2] = x[0] * y[1] - x[1] * y[0];
    }
    if (scaled && r > 0 && rr > 0) sim = r / rr;
  }
  fr.x *= sim;
  fr.y = sim * Vec3d(y[0], y[1], y[2]);
  fr.z = sim * Vec3d(z[0], z[1], z[2]);
  fr.degenerate = false;
  return fr;
}

struct SpanPos {
  std::span<const Vec3d> p;
  void get(std::uint32_t n, double* out) const noexcept {
    out[0] = p[n].x();
    out[1] = p[n].y();
    out[2] = p[n].z();
  }
};


// --------------------------------------------------------- detail_decode.cpp

inline bool have_avx2_fma() noexcept { return cpu_features().avx2 && cpu_features().fma; }

inline bool have_avx512f() noexcept { return cpu_features().avx512f; }

// The widest kernel both the CPU and the caller allow.
inline DecodeKernel pick_kernel(DecodeKernel allow) noexcept {
  DecodeKernel k = have_avx512f()    ? DecodeKernel::kAvx512
                   : have_avx2_fma() ? DecodeKernel::kAvx2
                                     : DecodeKernel::kPortable;
  return allow != DecodeKernel::kAuto && allow > k ? allow : k;
}

// --------------------------------------------------- detail_decode_batch.cpp

// A body's node positions read in place from a body set's float columns
// (the same doubles BodySet::positions gives).
struct SetPos {
  const float *x, *y, *z;
  void get(std::uint32_t n, double* out) const noexcept {
    out[0] = x[n];
    out[1] = y[n];
    out[2] = z[n];
  }
};


}  // namespace atelier::detail_internal
