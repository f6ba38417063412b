#include "systems/edge_transfer.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cmath>
#include <string>

#include "engine/parallel.h"

namespace atelier {

class EdgeTransferSolver {
 public:
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
};

namespace {

// Columns: the triangle's two edges from corner 0 and its unit normal.
bool triangle_basis(std::span<const Vec3d> p, const Triangle& t, Mat3d& m) {
  const Vec3d e1 = p[t[1]] - p[t[0]], e2 = p[t[2]] - p[t[0]];
  const Vec3d n = e1.cross(e2);
  const double l = n.norm();
  if (!(l > 0)) return false;
  m << e1, e2, n / l;
  return true;
}

}  // namespace

Expected<EdgeTransfer> encode_edge_transfer(std::span<const Vec3d> source,
                                            std::span<const std::array<std::uint32_t, 2>> edges,
                                            const CollisionBody& body, const EdgeTransferParams& params,
                                            const ExecContext& ctx) {
  const std::size_t n = source.size();
  if (n == 0) return Status(ErrorCode::kInvalidArgument, "edge transfer: empty garment");
  if (body.empty()) return Status(ErrorCode::kInvalidArgument, "edge transfer: source body not built");
  if (!(params.anchor > 0) || !std::isfinite(params.anchor))
    return Status(ErrorCode::kInvalidArgument, "edge transfer: anchor must be positive");
  for (std::size_t v = 0; v < n; ++v)
    if (!is_finite(source[v]))
      return Status(ErrorCode::kDegenerate, "edge transfer: garment vertex " + std::to_string(v) + " is not finite");
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges[e][0] >= n || edges[e][1] >= n || edges[e][0] == edges[e][1])
      return Status(ErrorCode::kInvalidArgument, "edge transfer: edge " + std::to_string(e) + " (" +
                                                     std::to_string(edges[e][0]) + ", " + std::to_string(edges[e][1]) +
                                                     ") is not an edge of " + std::to_string(n) + " vertices");
  EdgeTransfer t;
  t.vertices = n;
  t.edges.assign(edges.begin(), edges.end());
  const std::size_t ne = edges.size();
  t.triangle.assign(ne, kNoTriangle);
  t.coefficient.assign(ne, Vec3d::Zero());
  t.weight.assign(ne, 0.0);
  const auto tris = body.topology().triangles();
  const auto pos = body.positions();
  par::for_each_n(ctx, ne, [&](std::size_t e) {
    const Vec3d& a = source[edges[e][0]];
    const Vec3d& b = source[edges[e][1]];
    const double l2 = (b - a).squaredNorm();
    if (!(l2 > 0)) return;
    const std::uint32_t tri = body.query(0.5 * (a + b)).triangle;
    Mat3d m;
    if (tri == kNoTriangle || !triangle_basis(pos, tris[tri], m)) return;
    const Eigen::FullPivLU<Mat3d> lu(m);
    if (!lu.isInvertible()) return;
    t.triangle[e] = tri;
    t.coefficient[e] = lu.solve(b - a);
    t.weight[e] = 1.0 / l2;
  });
  // a_v = anchor * mean weight of v's edges (1 for a vertex without any:
  // it keeps its decoded position).
  std::vector<double> wsum(n, 0.0);
  std::vector<std::uint32_t> deg(n, 0);
  for (std::size_t e = 0; e < ne; ++e)
    for (std::uint32_t v : edges[e]) {
      wsum[v] += t.weight[e];
      deg[v] += t.weight[e] > 0;
    }
  t.anchor.resize(n);
  for (std::size_t v = 0; v < n; ++v) t.anchor[v] = deg[v] > 0 ? params.anchor * wsum[v] / deg[v] : 1.0;
  // Normal matrix D^T W D + A.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(4 * ne + n);
  for (std::size_t e = 0; e < ne; ++e) {
    const double w = t.weight[e];
    if (w == 0) continue;
    const auto [i, j] = edges[e];
    trip.emplace_back(i, i, w);
    trip.emplace_back(j, j, w);
    trip.emplace_back(i, j, -w);
    trip.emplace_back(j, i, -w);
  }
  for (std::size_t v = 0; v < n; ++v) trip.emplace_back(v, v, t.anchor[v]);
  Eigen::SparseMatrix<double> a(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  a.setFromTriplets(trip.begin(), trip.end());
  auto solver = std::make_shared<EdgeTransferSolver>();
  solver->ldlt.compute(a);
  if (solver->ldlt.info() != Eigen::Success)
    return Status(ErrorCode::kDegenerate, "edge transfer: the normal matrix does not factor");
  t.solver = std::move(solver);
  return t;
}

Status apply_edge_transfer(const EdgeTransfer& t, std::span<const Vec3d> body_points,
                           std::span<const Triangle> body_triangles, std::span<Vec3d> garment, const ExecContext& ctx) {
  const std::size_t n = t.vertices;
  if (!t.solver) return Status(ErrorCode::kInvalidArgument, "edge transfer: not encoded");
  if (garment.size() != n)
    return Status(ErrorCode::kMismatch, "edge transfer: " + std::to_string(garment.size()) +
                                            " garment vertices for an encoding of " + std::to_string(n));
  for (std::size_t e = 0; e < t.edges.size(); ++e) {
    if (t.triangle[e] == kNoTriangle) continue;
    if (t.triangle[e] >= body_triangles.size())
      return Status(ErrorCode::kMismatch, "edge transfer: the body has " + std::to_string(body_triangles.size()) +
                                              " triangles; the encoding uses triangle " +
                                              std::to_string(t.triangle[e]));
    for (std::uint32_t c : body_triangles[t.triangle[e]])
      if (c >= body_points.size())
        return Status(ErrorCode::kMismatch, "edge transfer: triangle " + std::to_string(t.triangle[e]) +
                                                " uses point " + std::to_string(c) + " of " +
                                                std::to_string(body_points.size()));
  }
  for (std::size_t v = 0; v < n; ++v)
    if (!is_finite(garment[v]))
      return Status(ErrorCode::kDegenerate, "edge transfer: garment vertex " + std::to_string(v) + " is not finite");
  // Edge targets T_e = B_new c_e, then the right-hand side D^T W T + A d,
  // gathered per vertex in a fixed order (deterministic).
  std::vector<Vec3d> target(t.edges.size(), Vec3d::Zero());
  par::for_each_n(ctx, t.edges.size(), [&](std::size_t e) {
    if (t.weight[e] == 0) return;
    Mat3d m;
    // A triangle collapsed on this body gives no stretch: the edge keeps
    // its decoded vector.
    target[e] = triangle_basis(body_points, body_triangles[t.triangle[e]], m)
                    ? Vec3d(m * t.coefficient[e])
                    : Vec3d(garment[t.edges[e][1]] - garment[t.edges[e][0]]);
  });
  Eigen::MatrixX3d rhs(static_cast<Eigen::Index>(n), 3);
  for (std::size_t v = 0; v < n; ++v) rhs.row(static_cast<Eigen::Index>(v)) = t.anchor[v] * garment[v].transpose();
  for (std::size_t e = 0; e < t.edges.size(); ++e) {
    if (t.weight[e] == 0) continue;
    const Vec3d f = t.weight[e] * target[e];
    rhs.row(t.edges[e][1]) += f.transpose();
    rhs.row(t.edges[e][0]) -= f.transpose();
  }
  const Eigen::MatrixX3d x = t.solver->ldlt.solve(rhs);
  for (std::size_t v = 0; v < n; ++v) garment[v] = x.row(static_cast<Eigen::Index>(v)).transpose();
  return Status::ok();
}

}  // namespace atelier
