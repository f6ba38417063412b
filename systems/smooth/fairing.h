// Umbrella fairing (seed 000 section 4.2, after Kobbelt's variational
// subdivision): free nodes move to make the 2nd-order umbrella vanish,
//   U(p)  = 1/n sum_j p_j - p,       U2(p) = 1/n sum_j U(p_j) - U(p),
// solved iteratively by p <- p - w U2(p) / nu,  nu = 1 + 1/n sum_j 1/n_j
// (Kobbelt 1998, the diagonal of U2; w = FairParams::relaxation damps it). Jacobi updates over a CSR adjacency,
// so each iteration is a pure function of the previous one: parallel and
// bit-identical for any thread count.
//
// Collision avoidance (seed 000 section 4.2, Fig. 16): with a signed
// distance to the reference body, every move is applied in sub-steps and a
// move that would bring a node closer than the clearance is cut at its last
// admissible sub-step. Because a signed distance is 1-Lipschitz, a node whose
// distance exceeds the clearance by more than its move needs no test at all,
// so the body is queried only near it. Near it, the end point is tested
// first: a move that neither enters nor deepens the forbidden zone and whose
// ends are both farther from the body than half its length (so no point of
// the segment is inside) is taken with one query; only the others are
// walked in sub-steps.
//
// Reads: halfedge connectivity, nodes.position. Writes: nodes.position of
// free nodes, geometry_version.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/adjacency.h>
#include <atelier/storage/model.h>

namespace atelier {

struct FairParams {
  int iterations = 50;
  /// Stop early when the largest move of an iteration is below this.
  double tolerance = 0.0;
  /// Signed distance to the body (negative inside); empty: no collision test.
  std::function<double(const Vec3d&)> signed_distance;
  /// Distance to keep from the body when collision is on.
  double clearance = 0.0;
  /// Optional, one entry per node slot: on entry a lower bound of each node's
  /// signed distance at its current position (-infinity when unknown), on
  /// exit a lower bound at its final position. Lets a caller that already
  /// knows distances (and will need them again) skip body queries.
  std::span<double> distance_bounds;
  /// Damping of the Jacobi step: p <- p - relaxation * U2(p) / nu. Undamped
  /// Jacobi diverges on the highest-frequency modes: the eigenvalues of U2
  /// reach 4 while nu can be as small as 1.5 (regular 1D chain, 2.67 > 2), so
  /// a node's oscillation grows by |1 - lambda / nu| per iteration. With 0.5
  /// the factor stays below 1 for every mode (lambda / nu <= 4).
  double relaxation = 0.5;
  /// Sub-steps of a move near the body (seed 000: "subdivided into several steps").
  int substeps = 4;
  /// Use the AVX2 kernel when the CPU has it (runs without collision only).
  /// It computes the same operations in the same order without FMA, so the
  /// result is bit-identical to the portable SSE2 kernel; false forces the
  /// portable one (tests compare the two).
  bool allow_avx2 = true;
};

struct FairReport {
  int iterations = 0;
  double last_max_move = 0;
  std::uint64_t distance_queries = 0;  // body queries made by the collision test
  std::uint64_t refused_moves = 0;     // moves cut short by the collision test
  bool avx2 = false;                   // the AVX2 kernel ran
};

/// The per-mesh part of a fairing run, like OpenMesh's smoother
/// initialize(): make it once per mesh and fixed set, fair many times.
/// The nodes a run touches are renumbered into a compact local range so the
/// iterations stream through contiguous arrays with no indirection:
/// local [0, active) are the nodes whose umbrella U is needed (the free
/// nodes and their neighbours), in the order of smaller bandwidth among slot
/// order and a Cuthill-McKee order; [active, local.size()) the remaining
/// neighbours of those (positions only). The local CSR keeps ring order, so
/// the sums are those over `adj`. With the bandwidth b (largest |i - j| over
/// the rings of free nodes), U of a node's neighbours is computed at most b
/// places ahead of it, so one pass fuses U and U2 with a small rolling
/// window of U values that stays in cache (see fairing.cpp).
struct FairPlan {
  std::size_t nodes = 0;                // node slots of the adjacency
  std::uint64_t adjacency_version = 0;  // of the adjacency it was made from
  double relaxation = 0.5;
  std::uint32_t active = 0;             // see above
  std::uint32_t free = 0;               // free nodes (among the active ones)
  std::uint32_t bandwidth = 0;          // b above
  std::vector<std::uint32_t> local;     // local index -> node slot
  std::vector<std::uint32_t> offset;    // local CSR over [0, active), size active + 1
  std::vector<std::uint32_t> neighbor;  // local indices
  std::vector<double> inv_degree;       // 1/n by valence n (a table: the same bits as 1.0 / n)
  std::vector<double> inv_nu;           // relaxation / nu (Kobbelt's diagonal) of free nodes, 0 for the others
};
[[nodiscard]] Expected<FairPlan> make_fair_plan(const NodeAdjacency& adj, std::span<const std::uint8_t> fixed,
                                                const FairParams& params, const ExecContext& ctx = {});
/// Runs a plan (params.relaxation must be the plan's).
[[nodiscard]] Expected<FairReport> fair_umbrella(std::span<Vec3d> positions, const NodeAdjacency& adj,
                                                 const FairPlan& plan, const FairParams& params,
                                                 const ExecContext& ctx = {});

/// Fairs the free nodes (fixed[v] == false) of the model in place. `fixed`
/// has one entry per node slot; isolated and dead nodes are ignored.
[[nodiscard]] Expected<FairReport> fair_umbrella(Model& m, std::span<const std::uint8_t> fixed,
                                                 const FairParams& params, const ExecContext& ctx = {});
/// The same on a position array with a prebuilt adjacency (hot path).
[[nodiscard]] Expected<FairReport> fair_umbrella(std::span<Vec3d> positions, const NodeAdjacency& adj,
                                                 std::span<const std::uint8_t> fixed, const FairParams& params,
                                                 const ExecContext& ctx = {});

/// Largest |U2(p)| over free nodes (smoothness measure of a result).
[[nodiscard]] double umbrella2_norm(std::span<const Vec3d> positions, const NodeAdjacency& adj,
                                    std::span<const std::uint8_t> fixed, const ExecContext& ctx = {});

}  // namespace atelier
