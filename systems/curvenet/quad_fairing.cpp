#include <atelier/systems/curvenet/quad_fairing.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <cmath>
#include <string>

#include <atelier/systems/curvenet/corner_mesh.h>

namespace atelier {

namespace {


/// One row of eq. (4): sum_j w_j p_j over (vertex, weight) pairs.
struct Row {
  std::vector<std::pair<std::uint32_t, double>> w;
};

/// The rows of every vertex with a closed ring.
std::vector<Row> energy_rows(const CornerMesh& m, FairingEquations eq, std::size_t* terms) {
  std::vector<Row> rows;
  std::vector<std::uint32_t> ring;
  std::size_t t = 0;
  for (std::uint32_t v = 0; v < m.vertex_count; ++v) {
    if (!m.ring(v, ring)) continue;
    const RingWeights rw = fairing_weights(ring.size(), eq);
    ++t;
    Row a, b, g;
    for (std::size_t j = 0; j < ring.size(); ++j) {
      if (rw.alpha[j] != 0) a.w.emplace_back(ring[j], rw.alpha[j]);
      if (rw.beta[j] != 0) b.w.emplace_back(ring[j], rw.beta[j]);
      if (rw.gamma[j] != 0) g.w.emplace_back(ring[j], rw.gamma[j]);
    }
    if (rw.gamma_self != 0) g.w.emplace_back(v, rw.gamma_self);
    for (Row* r : {&a, &b, &g})
      if (!r->w.empty()) rows.push_back(std::move(*r));
  }
  if (terms) *terms = t;
  return rows;
}

double energy_of(const std::vector<Row>& rows, std::span<const Vec3d> p) {
  double e = 0;
  for (const Row& r : rows) {
    Vec3d s = Vec3d::Zero();
    for (const auto& [v, w] : r.w) s += w * p[v];
    e += s.squaredNorm();
  }
  return e;
}

}  // namespace

RingWeights fairing_weights(std::size_t k, FairingEquations eq) {
  RingWeights w;
  w.alpha.assign(k, 0.0);
  w.beta.assign(k, 0.0);
  w.gamma.assign(k, k ? 1.0 / static_cast<double>(k) : 0.0);
  w.gamma_self = -1.0;  // eq. (7)
  if (k == 4) {
    for (std::size_t j = 0; j < 4; ++j)
      w.alpha[j] = (j % 2 == 0 ? 0.25 : -0.25);                    // eq. (6): 1/4 cos(pi j); sin(pi j) = 0
    if (eq == FairingEquations::kPrinted) w.gamma.assign(4, 0.0);  // eq. (6) as printed has no gamma
    return w;
  }
  if (k < 4 && eq == FairingEquations::kFixed) return w;  // no second harmonic on a ring of 3 or fewer
  const double kd = static_cast<double>(k);
  for (std::size_t j = 0; j < k; ++j) {
    const double a = 4.0 * kPi * static_cast<double>(j) / kd;  // eq. (5)
    w.alpha[j] = 2.0 / kd * std::cos(a);
    w.beta[j] = 2.0 / kd * std::sin(a);
  }
  return w;
}

Expected<double> fairing_energy(std::span<const Vec3d> positions, const PolygonSoupView& faces,
                                const QuadFairingOptions& opt) {
  auto m = build_corner_mesh(faces, positions.size());
  if (!m) return m.status();
  return energy_of(energy_rows(*m, opt.equations, nullptr), positions);
}

Expected<QuadFairingReport> fair_quad_mesh(std::span<Vec3d> positions, const PolygonSoupView& faces,
                                           std::span<const std::uint8_t> fixed, const QuadFairingOptions& opt,
                                           const ExecContext& ctx) {
  if (fixed.size() != positions.size())
    return Status(ErrorCode::kMismatch, "fairing: " + std::to_string(fixed.size()) + " fixed flags for " +
                                            std::to_string(positions.size()) + " vertices");
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (!positions[v].allFinite())
      return Status(ErrorCode::kInvalidArgument, "fairing: vertex " + std::to_string(v) + " is not finite");
  auto mesh = build_corner_mesh(faces, positions.size(), ctx);
  if (!mesh) return mesh.status();
  const CornerMesh& m = *mesh;
  QuadFairingReport rep;
  const std::vector<Row> rows = energy_rows(m, opt.equations, &rep.terms);
  rep.energy_before = energy_of(rows, positions);

  // Free vertices numbered densely; each must reach a fixed one through edges.
  const std::size_t nv = positions.size();
  std::vector<std::int64_t> local(nv, -1);
  std::vector<std::uint32_t> free_list;
  for (std::uint32_t v = 0; v < nv; ++v)
    if (!fixed[v]) {
      local[v] = static_cast<std::int64_t>(free_list.size());
      free_list.push_back(v);
    }
  rep.free_vertices = free_list.size();
  if (free_list.empty()) {
    rep.energy_after = rep.energy_before;
    return rep;
  }
  {
    std::vector<std::uint8_t> reached(nv, 0);
    std::vector<std::uint32_t> queue;
    for (std::uint32_t v = 0; v < nv; ++v)
      if (fixed[v]) {
        reached[v] = 1;
        queue.push_back(v);
      }
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::uint32_t v = queue[q];
      for (std::uint32_t k = m.vert_offsets[v]; k < m.vert_offsets[v + 1]; ++k) {
        const std::uint32_t c = m.vert_corners[k];
        for (std::uint32_t w : {m.face_verts[m.next_corner(c)], m.face_verts[m.prev_corner(c)]})
          if (!reached[w]) {
            reached[w] = 1;
            queue.push_back(w);
          }
      }
    }
    for (std::uint32_t v : free_list)
      if (!reached[v] && m.vert_offsets[v] != m.vert_offsets[v + 1])
        return Status(ErrorCode::kInvalidArgument,
                      "fairing: free vertex " + std::to_string(v) + " is connected to no fixed vertex");
  }
  // Normal equations of the rows restricted to free vertices. A free vertex
  // in no row (an isolated or open-fan-only vertex) keeps its position: a
  // unit diagonal entry with its own position as right-hand side.
  const auto nf = static_cast<Eigen::Index>(free_list.size());
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nf, 3);
  std::vector<std::uint8_t> in_row(free_list.size(), 0);
  std::vector<std::pair<Eigen::Index, double>> fr;
  for (const Row& r : rows) {
    fr.clear();
    Vec3d fixed_sum = Vec3d::Zero();
    for (const auto& [v, w] : r.w) {
      if (local[v] >= 0)
        fr.emplace_back(local[v], w);
      else
        fixed_sum += w * Vec3d(positions[v]);
    }
    for (const auto& [a, wa] : fr) {
      in_row[static_cast<std::size_t>(a)] = 1;
      for (const auto& [b, wb] : fr) trip.emplace_back(a, b, wa * wb);
      rhs.row(a) -= wa * fixed_sum.transpose();
    }
  }
  for (std::size_t i = 0; i < free_list.size(); ++i)
    if (!in_row[i]) {
      trip.emplace_back(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i), 1.0);
      rhs.row(static_cast<Eigen::Index>(i)) = positions[free_list[i]].transpose();
    }
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "fairing: cancelled");
  Eigen::SparseMatrix<double> A(nf, nf);
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  solver.compute(A);
  if (solver.info() != Eigen::Success)
    return Status(ErrorCode::kDegenerate, "fairing: the system of eq. (4) could not be factorised");
  const Eigen::MatrixXd x = solver.solve(rhs);
  if (solver.info() != Eigen::Success || !x.allFinite())
    return Status(ErrorCode::kDegenerate, "fairing: the solve of eq. (4) failed or gave non-finite positions");
  std::vector<Vec3d> next(positions.begin(), positions.end());
  for (std::size_t i = 0; i < free_list.size(); ++i) {
    const Vec3d p = x.row(static_cast<Eigen::Index>(i)).transpose();
    rep.max_move = std::max(rep.max_move, (p - next[free_list[i]]).norm());
    next[free_list[i]] = p;
  }
  rep.energy_after = energy_of(rows, next);
  for (std::uint32_t v : free_list) positions[v] = next[v];
  return rep;
}

}  // namespace atelier
