// Private to systems/pattern: a piece's topology in local numbering and the
// two phases of the energy-based flattening (Wang, Smith, Yuen 2002) that
// run on it. Shared by flatten.cpp (the Model side: checks, API, distortion),
// flatten_phase1.cpp, flatten_solver.cpp (phase 2) and pattern.cpp.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <array>
#include <chrono>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

namespace atelier::pattern_detail {

using Clock = std::chrono::steady_clock;
[[nodiscard]] inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// Twice the signed area of (a, b, c): positive when counter-clockwise.
[[nodiscard]] inline double signed_area2(const Vec2d& a, const Vec2d& b, const Vec2d& c) noexcept {
  return cross2(b - a, c - a);
}

/// d(2D area)/d(corner q) of a triangle (q, a, b) in CCW order: half the
/// opposite edge turned, 1/2 (a_y - b_y, b_x - a_x).
[[nodiscard]] inline Vec2d area_gradient(const Vec2d& a, const Vec2d& b) noexcept {
  return 0.5 * Vec2d(a.y() - b.y(), b.x() - a.x());
}

/// One piece (a surface) in dense local numbering. Polygons are fanned from
/// their first corner into triangles (CCW seen from the front, as the faces);
/// every triangle side is a spring, fan diagonals included.
struct PieceTopology {
  std::vector<NodeIdx> node;                             // local vertex -> model node (increasing)
  std::vector<std::array<std::uint32_t, 3>> tri;         // local vertices, CCW
  std::vector<FaceIdx> tri_face;                         // the face each triangle fans
  std::vector<std::array<std::uint32_t, 3>> tri_adj;     // triangle across side k = (tri[k], tri[k+1]), or kNone
  std::vector<std::array<std::uint32_t, 3>> tri_spring;  // spring of side k
  std::vector<std::array<std::uint32_t, 2>> spring;      // (a, b), a < b
  std::vector<std::uint8_t> spring_is_edge;              // a model edge (not a fan diagonal)
  // Vertex -> springs (and the other end), vertex -> triangles, in CSR form.
  std::vector<std::uint32_t> vs_off, vs_spring, vs_other;
  std::vector<std::uint32_t> vt_off, vt_tri;
  /// Boundary loops as local vertex sequences (faceless halfedges in chain
  /// order: the front of the piece lies to their right).
  std::vector<std::vector<std::uint32_t>> loops;
  std::vector<std::vector<HalfedgeIdx>> loop_halfedges;  // the model's faceless halfedges, same order

  [[nodiscard]] std::size_t vertex_count() const noexcept { return node.size(); }
};

/// The piece's triangles, springs, adjacency and boundary loops; with
/// `check`, also the conditions of a flattenable piece (flatten.h), as
/// errors naming the surface. Implemented in flatten.cpp.
[[nodiscard]] Expected<PieceTopology> build_topology(const Model& m, SurfaceIdx s, bool allow_holes, bool check);

/// Rest state of the spring-mass system for one set of 3D positions.
struct RestState {
  std::vector<double> length;     // l_ij per spring (3D)
  std::vector<double> stiffness;  // C_ij per spring
  std::vector<double> area;       // 3D area per triangle
};

/// Seam-length constraints of a piece (FlattenOptions::seam_lengths): the
/// 2D length of each chain, the sum of |Q_a - Q_b| over its sides, held at
/// its target (the mean 3D length of its joint's members).
struct SeamLengths {
  std::vector<std::vector<std::array<std::uint32_t, 2>>> sides;  // per constraint: local vertex pairs
  std::vector<double> target;                                    // per constraint (set per body)
  std::vector<double> lambda;  // Lagrange multipliers, kept for the next body (warm start)
  [[nodiscard]] std::size_t size() const noexcept { return sides.size(); }
};

/// The seam-length constraints of one piece and where their targets come
/// from: every member of a joint that lies on the piece is a constraint; its
/// target is the mean 3D length of all the joint's members (they lie at one
/// place in 3D, so the mean is each one's length up to the joint's
/// tolerance). Implemented in flatten_seams.cpp.
struct PieceSeams {
  SeamLengths lengths;
  std::vector<std::uint32_t> joint;                                       // per constraint: index into members
  std::vector<JointIdx> joint_id;                                         // per joint: the model's joint
  std::vector<std::vector<std::vector<std::array<NodeIdx, 2>>>> members;  // per joint, per member: its sides
};

/// The constraints of surface s, piece t: its members that run along its
/// boundary (sew lines). A member inside the piece (an inner-edge joint, a
/// collar stitched on a line of the piece) is not constrained: the piece's
/// own strain decides its length.
[[nodiscard]] PieceSeams collect_seams(const Model& m, SurfaceIdx s, const PieceTopology& t);

/// Sets the targets for `positions`. Errors: kDegenerate (a joint of
/// non-finite or zero length), naming the joint.
[[nodiscard]] Status set_seam_targets(PieceSeams& ps, std::span<const Vec3d> positions, const std::string& label);

struct SolverParams {
  int relax_rings = 1;
  int relax_sweeps = 1;
  int max_iterations = 400;
  double tolerance = 1e-7;  // relative energy decrease that ends phase 2
  int memory = 8;           // L-BFGS pairs
  /// Warm starts only (0: off): phase 2 gives up (SolverStats::stalled)
  /// when each of its first `stall_window` iterations had its step cut by
  /// the flip guard: a start that keeps pressing triangles into a flip.
  int stall_window = 0;
};

struct SolverStats {
  std::size_t closures = 0;     // phase 1: triangles that closed a loop
  double energy_phase1 = 0;     // E after phase 1 (or of the warm start)
  double energy = 0;            // E after phase 2
  int iterations = 0;           // phase 2 iterations
  int rejected_steps = 0;       // line-search halvings refused by the flip / overlap guard
  bool tutte_fallback = false;  // phase 1 left flips: phase 2 started from a Tutte embedding
  bool reused_factor = false;   // phase 2 kept the previous body's factor
  bool stalled = false;         // gave up after SolverParams::stall_window limited steps (uv unchanged)
  int seam_rounds = 0;          // augmented-Lagrangian rounds (seam lengths)
  int seam_projections = 0;     // projection steps onto the seam lengths
  double seam_residual = 0;     // largest |L_2d - target| after phase 2
  double phase1_ms = 0, phase2_ms = 0, factor_ms = 0;
};

/// Phase 1 (triangle flattening): BFS from `seed`, circle
/// intersections, local relaxation where loops close. Writes uv (local).
void run_phase1(const PieceTopology& t, const RestState& rest, std::uint32_t seed, const SolverParams& prm,
                std::vector<Vec2d>& uv, SolverStats& stats);

/// Tutte's barycentric embedding with the boundary loop on a circle (arc
/// length spacing): flip-free by Tutte's theorem. The fallback start of
/// phase 2 when phase 1 leaves flipped triangles.
void tutte_embedding(const PieceTopology& t, const RestState& rest, std::vector<Vec2d>& uv);

/// A warm start (another body's pattern of the same piece) fitted to this
/// body's rest lengths: the symmetric 2x2 map A minimising the spring
/// energy sum 1/2 C (|A d_ij| - l_ij)^2 (Gauss-Newton from the best uniform
/// scale), applied about the centroid. det A > 0, so the start keeps its
/// orientation and a boundary that does not cross itself. Implemented in
/// flatten_warm.cpp.
void fit_warm_start(const PieceTopology& t, const RestState& rest, std::vector<Vec2d>& uv);

/// Signed areas of the 2D triangles (positive when CCW).
[[nodiscard]] std::size_t count_flipped(const PieceTopology& t, std::span<const Vec2d> uv, const ExecContext& ctx);

/// Pairs of non-adjacent boundary segments that intersect (uniform grid).
[[nodiscard]] std::size_t count_boundary_crossings(const PieceTopology& t, std::span<const Vec2d> uv);

/// Phase 2 (planar mesh deformation): L-BFGS on E = sum 1/2 C (|Q_i Q_j| - l)^2
/// with the spring Laplacian as initial Hessian; owns the factorization so
/// a Flattener keeps its symbolic analysis across bodies.
class Phase2Solver {
 public:
  /// Symbolic analysis of the Laplacian's pattern (once per topology).
  void analyze(const PieceTopology& t);
  /// Minimises from uv (flip-free) in place. With `reuse`, the previous
  /// factor stays when the stiffnesses are within 25% of its own. With
  /// seam-length constraints (`seams` not null and not empty), E is
  /// minimised subject to them (augmented Lagrangian, then a projection;
  /// flatten_solver.cpp); their multipliers are updated in place. False when
  /// the factorization fails.
  [[nodiscard]] bool run(const PieceTopology& t, const RestState& rest, const SolverParams& prm, std::vector<Vec2d>& uv,
                         SolverStats& stats, const ExecContext& ctx, bool reuse = false, SeamLengths* seams = nullptr);

  /// The numeric factor of H0 (immutable once made, so solvers of one
  /// topology can share it across threads).
  struct Factor {
    std::vector<int> outer, inner, perm;   // L's columns (the diagonal leads each) and P
    std::vector<float> values;             // L's values as floats, for the solves
    std::vector<double> inverse_diagonal;  // 1 / L_jj
    std::vector<double> stiffness;         // the C_ij it was made with
  };
  [[nodiscard]] const std::shared_ptr<const Factor>& factor() const noexcept { return factor_; }
  /// The factor the next `reuse` run starts from (one of a solver built on
  /// the same topology).
  void set_factor(std::shared_ptr<const Factor> f) noexcept { factor_ = std::move(f); }

 private:
  using SpMat = Eigen::SparseMatrix<double>;
  SpMat laplacian_;
  std::vector<std::uint32_t> value_of_spring_[2];  // nonzero slots of each spring's (a,b) and (b,a) entries
  std::vector<std::uint32_t> value_of_diag_;
  Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> llt_;
  mutable std::vector<Vec2d> work_;
  std::shared_ptr<const Factor> factor_;
  bool analyzed_ = false;
  /// x = H0^-1 b for the u and v columns at once.
  void solve(std::span<const Vec2d> b, std::span<Vec2d> x) const;
};

/// The flip barrier of phase 2 (flatten_solver.cpp); adds its gradient to
/// `gradient` when not empty. Infinite when a triangle is flipped.
[[nodiscard]] double barrier_energy(const PieceTopology& t, const RestState& rest, std::span<const Vec2d> uv,
                                    std::span<Vec2d> gradient, std::vector<Vec2d>& scratch, const ExecContext& ctx);

/// The largest s > 0 for which uv + s dir still has every triangle CCW
/// (infinity when no triangle ever flips along dir); exact when below
/// `cap`, else some value at least `cap`.
[[nodiscard]] double max_feasible_step(const PieceTopology& t, std::span<const Vec2d> uv, std::span<const Vec2d> dir,
                                       const ExecContext& ctx, double cap = std::numeric_limits<double>::infinity());

/// Spring energy and, when `gradient` is not empty, dE/dQ per vertex.
[[nodiscard]] double spring_energy(const PieceTopology& t, const RestState& rest, std::span<const Vec2d> uv,
                                   std::span<Vec2d> gradient, std::vector<Vec2d>& scratch, const ExecContext& ctx);

}  // namespace atelier::pattern_detail
