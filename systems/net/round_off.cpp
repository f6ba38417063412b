// Rounding-off (seed 004 section 6): the umbrella energy of moments as a
// least-squares problem over the freed vertices.
#include <atelier/io/mesh_arrays.h>
#include <atelier/storage/adjacency.h>
#include <atelier/systems/net/round_off.h>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "boolean_detail.h"

namespace atelier {

namespace {

using net_detail::fail;
using net_detail::stage_done;

using SpMat = Eigen::SparseMatrix<double, Eigen::RowMajor>;
using Trip = Eigen::Triplet<double>;

/// The residual rows of E over all nodes: R X gives, per row, one term whose
/// square is summed (one column of X per coordinate). Rows for each p in the
/// term set: sqrt(mu) Delta p, and sqrt(nu / n) (Delta p - Delta q_i).
struct Residuals {
  SpMat r;
  std::size_t terms = 0;
};

Residuals residuals(const NodeAdjacency& adj, std::span<const std::uint8_t> term, std::size_t nodes,
                    const RoundOptions& o) {
  // Delta as rows over node slots.
  auto delta = [&](std::uint32_t p, double w, std::vector<Trip>& t, std::size_t row) {
    const std::uint32_t n = adj.degree(p);
    if (n == 0) return;
    t.emplace_back(static_cast<int>(row), static_cast<int>(p), w);
    for (std::uint32_t k = adj.offset[p]; k < adj.offset[p + 1]; ++k)
      t.emplace_back(static_cast<int>(row), static_cast<int>(adj.neighbor[k]), -w / n);
  };
  std::vector<Trip> t;
  std::size_t row = 0, terms = 0;
  for (std::uint32_t p = 0; p < nodes; ++p) {
    if (!term[p] || adj.degree(p) == 0) continue;
    ++terms;
    delta(p, std::sqrt(o.mu), t, row++);
    const double w = std::sqrt(o.nu / adj.degree(p));
    for (std::uint32_t k = adj.offset[p]; k < adj.offset[p + 1]; ++k) {
      delta(p, w, t, row);
      delta(adj.neighbor[k], -w, t, row);
      ++row;
    }
  }
  Residuals r;
  r.r.resize(static_cast<int>(row), static_cast<int>(nodes));
  r.r.setFromTriplets(t.begin(), t.end());
  r.terms = terms;
  return r;
}

/// Terms: every vertex whose Delta or torsion involves a free vertex (within
/// two rings of one).
std::vector<std::uint8_t> term_set(const NodeAdjacency& adj, std::span<const std::uint8_t> free_mask,
                                   std::size_t nodes) {
  std::vector<std::uint8_t> t(free_mask.begin(), free_mask.end());
  for (int ring = 0; ring < 2; ++ring) {
    std::vector<std::uint8_t> next = t;
    for (std::uint32_t p = 0; p < nodes; ++p)
      if (t[p])
        for (std::uint32_t k = adj.offset[p]; k < adj.offset[p + 1]; ++k) next[adj.neighbor[k]] = 1;
    t = std::move(next);
  }
  return t;
}

double energy_of(const SpMat& r, const Eigen::MatrixX3d& x) {
  return (r * x).squaredNorm();
}

Eigen::MatrixX3d positions(const Model& m) {
  Eigen::MatrixX3d x(static_cast<int>(m.nodes.position.size()), 3);
  for (std::size_t v = 0; v < m.nodes.position.size(); ++v)
    x.row(static_cast<int>(v)) = m.alive(NodeIdx{static_cast<std::uint32_t>(v)})
                                     ? Eigen::RowVector3d(m.nodes.position[v].transpose())
                                     : Eigen::RowVector3d::Zero();
  return x;
}

Status check_weights(const RoundOptions& o) {
  if (!(std::isfinite(o.mu) && std::isfinite(o.nu) && o.mu >= 0 && o.nu >= 0 && o.mu + o.nu > 0))
    return fail(ErrorCode::kInvalidArgument, "round: mu and nu must be finite, >= 0 and not both 0");
  if (o.rings < 0) return fail(ErrorCode::kInvalidArgument, "round: rings must be >= 0");
  return {};
}

}  // namespace

Expected<double> umbrella_energy(const Model& m, std::span<const std::uint8_t> free_mask, const RoundOptions& opt) {
  if (Status s = check_weights(opt); !s) return s;
  const std::size_t nodes = m.nodes.position.size();
  if (free_mask.size() != nodes)
    return fail(ErrorCode::kInvalidArgument, "round: the free mask needs one entry per node slot");
  const NodeAdjacency adj = build_adjacency(m);
  const auto term = term_set(adj, free_mask, nodes);
  return energy_of(residuals(adj, term, nodes, opt).r, positions(m));
}

Expected<RoundReport> round_off(Model& m, std::span<const NodeIdx> seam, const RoundOptions& opt,
                                const ExecContext& ctx) {
  if (Status s = check_weights(opt); !s) return s;
  const std::size_t nodes = m.nodes.position.size();
  if (seam.empty()) return fail(ErrorCode::kInvalidArgument, "round: the seam is empty");
  for (NodeIdx v : seam)
    if (v.value >= nodes || !m.alive(v))
      return fail(ErrorCode::kInvalidArgument, "round: seam node ", v.value, " does not exist");
  const NodeAdjacency adj = build_adjacency(m);
  std::vector<std::uint8_t> free_mask(nodes, 0);
  for (NodeIdx v : seam) free_mask[v.value] = 1;
  for (int r = 0; r < opt.rings; ++r) {
    std::vector<std::uint8_t> next = free_mask;
    for (std::uint32_t p = 0; p < nodes; ++p)
      if (free_mask[p])
        for (std::uint32_t k = adj.offset[p]; k < adj.offset[p + 1]; ++k) next[adj.neighbor[k]] = 1;
    free_mask = std::move(next);
  }
  std::vector<int> col(nodes, -1);
  std::vector<std::uint32_t> free_nodes;
  for (std::uint32_t p = 0; p < nodes; ++p)
    if (free_mask[p] && adj.degree(p) > 0) {
      col[p] = static_cast<int>(free_nodes.size());
      free_nodes.push_back(p);
    }
  RoundReport rep;
  rep.free_nodes = free_nodes.size();
  const auto term = term_set(adj, free_mask, nodes);
  const Residuals res = residuals(adj, term, nodes, opt);
  rep.terms = res.terms;
  const Eigen::MatrixX3d x0 = positions(m);
  rep.energy_before = energy_of(res.r, x0);
  // r = R X = M x_free + c, with c = R X restricted to fixed columns.
  Eigen::MatrixX3d fixed_x = x0;
  for (std::uint32_t p : free_nodes) fixed_x.row(static_cast<int>(p)).setZero();
  const Eigen::MatrixX3d c = res.r * fixed_x;
  std::vector<Trip> mt;
  for (int row = 0; row < res.r.outerSize(); ++row)
    for (SpMat::InnerIterator it(res.r, row); it; ++it)
      if (col[static_cast<std::size_t>(it.col())] >= 0)
        mt.emplace_back(row, col[static_cast<std::size_t>(it.col())], it.value());
  Eigen::SparseMatrix<double> M(res.r.rows(), static_cast<int>(free_nodes.size()));
  M.setFromTriplets(mt.begin(), mt.end());
  if (Status s = stage_done(ctx, "round: system", 1, 3); !s) return s;
  const Eigen::SparseMatrix<double> A = M.transpose() * M;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
  if (solver.info() != Eigen::Success ||
      (solver.vectorD().array() <= 1e-14 * solver.vectorD().cwiseAbs().maxCoeff()).any())
    return fail(ErrorCode::kDegenerate,
                "round: the freed region has no unique minimiser (does it touch fixed vertices?)");
  const Eigen::MatrixX3d rhs = -(M.transpose() * c);
  const Eigen::MatrixX3d xf = solver.solve(rhs);
  if (!xf.allFinite()) return fail(ErrorCode::kDegenerate, "round: the minimiser is not finite");
  // The last chance to cancel: after it the model is written.
  if (Status s = stage_done(ctx, "round: solve", 2, 3); !s) return s;
  Eigen::MatrixX3d x1 = x0;
  for (std::size_t k = 0; k < free_nodes.size(); ++k)
    x1.row(static_cast<int>(free_nodes[k])) = xf.row(static_cast<int>(k));
  const double e1 = energy_of(res.r, x1);
  if (!(e1 <= rep.energy_before)) {
    rep.energy_after = rep.energy_before;
    return rep;
  }
  rep.energy_after = e1;
  rep.moved = true;
  for (std::uint32_t p : free_nodes) m.nodes.position[p] = x1.row(static_cast<int>(p)).transpose();
  ++m.geometry_version;
  ctx.report("round: result", 3, 3);
  return rep;
}

std::vector<std::uint32_t> parse_seam(std::string_view text, std::string_view name) {
  std::vector<std::uint32_t> out;
  std::vector<std::string_view> tok;
  std::size_t line_no = 0;
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    const std::string_view line = text.substr(0, nl);
    text = nl == std::string_view::npos ? std::string_view() : text.substr(nl + 1);
    ++line_no;
    io_detail::split_blanks(line, tok);
    if (tok.empty() || tok[0][0] == '#') continue;
    for (std::string_view t : tok) {
      const auto v = io_detail::parse_int(t);
      if (!v || *v < 0 || *v > 0xfffffffe)
        throw io_detail::parse_error_at_line(name, line_no, "not a vertex index: '" + std::string(t) + "'");
      out.push_back(static_cast<std::uint32_t>(*v));
    }
  }
  return out;
}

std::vector<std::uint32_t> read_seam(const std::filesystem::path& path) {
  return parse_seam(io_detail::read_file_bytes(path), path.string());
}

}  // namespace atelier
