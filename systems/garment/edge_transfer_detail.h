// Internals shared by the one-body edge transfer (edge_transfer.cpp) and its
// lanes of bodies (edge_transfer_batch.cpp): the factor's arrays, the
// per-body set-up and the small least-squares solve of Anderson's method.
// Both files call the same compiled code for these, so a lane's result can
// be the same bits as the body's alone.
#pragma once

#include <atelier/systems/garment/edge_transfer.h>

#include <Eigen/Dense>

namespace atelier {

// P A P^T = L D L^T (sparse LDL^T with a fill-reducing ordering, Eigen's
// SimplicialLDLT), kept as plain arrays so that a solve runs the three
// coordinates together: one pass over L per direction instead of one per
// coordinate (Eigen's solve with a three-column right-hand side makes six).
class EdgeTransferSolver {
 public:
  std::vector<int> col_start, row;  // strictly lower L, compressed columns
  std::vector<double> value;
  std::vector<double> inv_d;
  std::vector<int> perm;  // y = P b: y[perm[i]] = b[i]

  void solve(std::span<const Vec3d> b, std::span<Vec3d> x, std::vector<Vec3d>& y) const;
};

namespace edge_transfer_detail {

/// apply_edge_transfer's checks (naming the element) and its set-up on one
/// body: the edge targets T_e = B_new c_e and the right-hand side
/// D^T W T + A d of the first solve (d = `garment`, the decoded positions).
[[nodiscard]] Status targets_and_rhs(const EdgeTransfer& t, std::span<const Vec3d> body_points,
                                     std::span<const Triangle> body_triangles, std::span<const Vec3d> garment,
                                     std::vector<Vec3d>& target, std::vector<Vec3d>& rhs, const ExecContext& ctx);

/// Anderson's coefficients gamma from the Gram matrix of the difference
/// columns (its top-left k x k) and the right-hand side; false when they
/// are not finite.
[[nodiscard]] bool anderson_gamma(const Eigen::MatrixXd& gram, const Eigen::VectorXd& rhs, Eigen::VectorXd& gamma);

}  // namespace edge_transfer_detail
}  // namespace atelier
