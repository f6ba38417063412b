// Edge transfer: a decoded garment takes on the local stretch of the skin
// under it (issue 7's excess strain), keeping the decoded shape at large.
//
// A detail template (seed 001 section 6, eqs. (11)-(12)) blends the frames
// of the N_q polygons nearest to each garment vertex, so it carries the
// body's shape change averaged over a patch of skin several centimetres
// wide: where the skin stretches unevenly (a chest, a hip, a shoulder), the
// garment's edges stretch by the patch average, not by the skin under them.
// This system adds the local part back, in the gradient domain (deformation
// transfer, Sumner & Popovic 2004):
//
//  * encoding (once per garment): each garment edge e = (i, j) stores the
//    source body triangle under its midpoint and its vector in that
//    triangle's basis B = [e1, e2, unit normal]: c_e = B_src^-1 (q_j - q_i);
//  * per body: the edge's target vector is T_e = B_new c_e (the tangential
//    part follows the skin's stretch, the normal part keeps its length: an
//    offset from the skin is not scaled), and the garment solves
//      min  sum_e w_e |x_j - x_i - T_e|^2 + sum_v a_v |x_v - d_v|^2,
//    with d the decoded positions, w_e = 1 / |q_j - q_i|^2 (residuals are
//    relative strains) and a_v = anchor * (mean w_e around v). The anchor
//    keeps the low frequencies of the decode (its placement and clearance);
//    its influence reaches about 1/sqrt(anchor) edges.
//
// The normal equations (D^T W D + A) x = D^T W T + A d have the same matrix
// on every body: it is factored once (sparse LDL^T) at encoding and each
// body costs one right-hand side and one pair of triangular solves (the
// three coordinates together).
//
// Vector targets over-constrain the garment (three equations per edge,
// about two edges per vertex, and the targets of neighbouring edges come
// from different skin triangles), so what is matched next is only each
// edge's length: local-global iterations (as in as-rigid-as-possible
// solvers) turn every target to its edge's current direction and relax the
// same energy again, by Gauss-Seidel sweeps warm-started from the solve.
// On the MakeHuman garments this takes the excess strain p95 from 5.5-6.4%
// (vector targets) to 2.2-2.9% in 30 plain sweeps. The sweeps are a
// fixed-point iteration, accelerated by Anderson's method with an energy
// safeguard (Peng et al. 2018) and stopped by a measured residual: 2.0-2.2%
// in 11-17 sweeps (issue 26, regen8).
//
// On the source body T_e is the source edge and d the source garment, so
// the source comes back exactly; under a rigid motion of the body (and the
// decode, which a detail template moves rigidly with it) the result moves
// rigidly too.
//
// Reads: source and new body positions and triangles, garment edges.
// Writes: garment positions (in place).
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/systems/garment/collision_pass.h>
#include <atelier/systems/spatial/body_bvh.h>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace atelier {

struct EdgeTransferParams {
  /// Weight of the decoded positions against the edge targets (see above).
  double anchor = 0.02;
  /// Length iterations after the first solve (see apply_edge_transfer); with
  /// a tolerance, the most it may take.
  int length_iterations = 30;
  /// Gauss-Seidel sweeps per length iteration, warm-started from the last
  /// solution; 0: an exact solve each time (a solve costs about six sweeps;
  /// on the MakeHuman garments 10 exact iterations reach 2.5-3.0% excess
  /// strain p95 where 30 single sweeps reach 2.2-2.9% for half the time).
  int length_sweeps = 1;
  /// Anderson acceleration of the length iterations (apply_edge_transfer):
  /// the number of previous steps extrapolated from; 0: plain iterations.
  /// It and the tolerance apply with one sweep per iteration (length_sweeps
  /// 1); other sweep counts run length_iterations plain iterations.
  /// On the five MakeHuman garments (12 adults each) a window of 3 with the
  /// tolerance below takes 11-17 sweeps and ends at 2.0-2.2% excess strain
  /// p95 where 30 plain sweeps reach 2.2-2.7% (docs/performance.md, regen8).
  int anderson_window = 3;
  /// Stop once a plain step's moves, each divided by the shortest rest
  /// length at its vertex (the strain a step still changes), have an RMS
  /// over the vertices of at most this; 0: always length_iterations.
  double length_tolerance = 1.2e-3;
};

class EdgeTransferSolver;  // the factored normal matrix (shared, immutable)

struct EdgeTransfer {
  std::size_t vertices = 0;
  std::vector<std::array<std::uint32_t, 2>> edges;
  std::vector<std::uint32_t> triangle;  // per edge: source triangle under its midpoint (kNoTriangle: no target)
  std::vector<Vec3d> coefficient;       // per edge: its vector in that triangle's basis
  std::vector<double> weight;           // per edge: w_e (0: zero-length or degenerate, no target)
  std::vector<double> anchor;           // per vertex: a_v
  std::shared_ptr<const EdgeTransferSolver> solver;
  int length_iterations = 0;
  int length_sweeps = 0;
  int anderson_window = 0;
  double length_tolerance = 0;
  std::vector<double> residual_scale;  // per vertex: 1 / its shortest rest length with a target (0: none)
  std::vector<std::uint32_t> vertex_edge_offset, vertex_edge;  // vertex -> incident edges (CSR)
  std::vector<double> inv_diagonal;                            // per vertex: 1 / (a_v + sum of w_e)
};

/// Encodes a garment (`source`, its `edges`) on its source body (`body`,
/// the CollisionBody over the source body's triangles). Errors: empty
/// garment, edge index out of range or an edge from a vertex to itself,
/// non-finite vertex (naming it), bad parameters, a matrix that does not
/// factor.
[[nodiscard]] Expected<EdgeTransfer> encode_edge_transfer(std::span<const Vec3d> source,
                                                          std::span<const std::array<std::uint32_t, 2>> edges,
                                                          const CollisionBody& body,
                                                          const EdgeTransferParams& params = {},
                                                          const ExecContext& ctx = {});

/// Applies the transfer on a new body of the source body's topology:
/// `garment` holds the decoded positions on entry and the result on exit.
/// Errors: sizes that do not match, a non-finite vertex.
[[nodiscard]] Status apply_edge_transfer(const EdgeTransfer& transfer, std::span<const Vec3d> body_points,
                                         std::span<const Triangle> body_triangles, std::span<Vec3d> garment,
                                         const ExecContext& ctx = {});

/// The lane kernel of apply_edge_transfer_bodies: kAuto picks AVX2 (4 lanes)
/// where the CPU runs it (cpu_features()), else kGeneric (SSE2, 2 lanes);
/// kAvx512 (8 lanes) is for tests and benchmarks (slower: see
/// edge_transfer_batch.cpp). A kernel the CPU lacks falls back to kGeneric.
enum class EdgeTransferKernel : std::uint8_t { kAuto, kAvx512, kAvx2, kGeneric };

/// Lanes of a kernel (AVX-512 8, AVX2 4, generic 2); kAuto: the one it picks.
[[nodiscard]] std::size_t edge_transfer_lanes(EdgeTransferKernel kernel = EdgeTransferKernel::kAuto) noexcept;

/// apply_edge_transfer on several bodies of one family at once, one body per
/// SIMD lane (edge_transfer_batch.cpp): the bodies share the garment's edges,
/// weights and factor, so a Gauss-Seidel sweep or a triangular solve loads
/// each index once for all lanes and runs the lanes' dependency chains side
/// by side; a lane whose body stops takes the next one, so lanes do not wait
/// for the slowest body. Every lane does the one-body path's operations in its order
/// (no contraction into FMA; sqrt and division are correctly rounded), with
/// its own Anderson history and stop: each garment is the same bits as
/// apply_edge_transfer gives it alone. `bodies[b]` and `garments[b]` are
/// body b's points and garment (decoded on entry, the result on exit);
/// `status[b]` gets its own errors (those of apply_edge_transfer) and a body
/// that fails keeps its garment. Errors of the call: sizes that differ, a
/// transfer not encoded.
[[nodiscard]] Status apply_edge_transfer_bodies(const EdgeTransfer& transfer,
                                                std::span<const std::span<const Vec3d>> bodies,
                                                std::span<const Triangle> body_triangles,
                                                std::span<const std::span<Vec3d>> garments, std::span<Status> status,
                                                EdgeTransferKernel kernel = EdgeTransferKernel::kAuto);

}  // namespace atelier
