#include <atelier/systems/curvenet/bspline.h>

#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <string>

namespace atelier {

namespace {

/// Uniform cubic basis on a span, u in [0, 1].
std::array<double, 4> cubic_basis(double u) {
  const double u2 = u * u, u3 = u2 * u, v = 1 - u;
  return {v * v * v / 6.0, (3 * u3 - 6 * u2 + 4) / 6.0, (-3 * u3 + 3 * u2 + 3 * u + 1) / 6.0, u3 / 6.0};
}

/// The span and local parameter of t in [0, m].
std::pair<std::size_t, double> span_of(double t, std::size_t m) {
  t = std::clamp(t, 0.0, static_cast<double>(m));
  auto j = static_cast<std::size_t>(std::floor(t));
  if (j >= m) j = m - 1;
  return {j, t - static_cast<double>(j)};
}

/// Weights of the spline at t over P_0 .. P_m (phantoms folded in):
/// (index, weight) pairs.
void weights_at(double t, std::size_t m, std::vector<std::pair<std::size_t, double>>& out) {
  out.clear();
  const auto [j, u] = span_of(t, m);
  const auto b = cubic_basis(u);
  for (int k = 0; k < 4; ++k) {
    const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(j) - 1 + k;  // P_{j-1} .. P_{j+2}
    if (i < 0) {                                                      // P_{-1} = 2 P_0 - P_1
      out.emplace_back(0, 2 * b[static_cast<std::size_t>(k)]);
      out.emplace_back(1, -b[static_cast<std::size_t>(k)]);
    } else if (i > static_cast<std::ptrdiff_t>(m)) {  // P_{m+1} = 2 P_m - P_{m-1}
      out.emplace_back(m, 2 * b[static_cast<std::size_t>(k)]);
      out.emplace_back(m - 1, -b[static_cast<std::size_t>(k)]);
    } else {
      out.emplace_back(static_cast<std::size_t>(i), b[static_cast<std::size_t>(k)]);
    }
  }
}

}  // namespace

Expected<std::vector<Vec3d>> sample_bspline(const BSplineCurve& c, int samples_per_span) {
  const int p = c.degree;
  const std::size_t n = c.control.size();
  if (p < 1) return Status(ErrorCode::kInvalidArgument, "B-spline: degree " + std::to_string(p) + " (at least 1)");
  if (n < static_cast<std::size_t>(p) + 1)
    return Status(ErrorCode::kInvalidArgument, "B-spline: " + std::to_string(n) + " control points for degree " +
                                                   std::to_string(p) + " (at least " + std::to_string(p + 1) + ")");
  if (c.knots.size() != n + static_cast<std::size_t>(p) + 1)
    return Status(ErrorCode::kInvalidArgument, "B-spline: " + std::to_string(c.knots.size()) + " knots for " +
                                                   std::to_string(n) + " control points of degree " +
                                                   std::to_string(p) + " (" + std::to_string(n + p + 1) + " needed)");
  for (std::size_t i = 0; i < c.knots.size(); ++i) {
    if (!std::isfinite(c.knots[i]))
      return Status(ErrorCode::kInvalidArgument, "B-spline: knot " + std::to_string(i) + " is not finite");
    if (i > 0 && c.knots[i] < c.knots[i - 1])
      return Status(ErrorCode::kInvalidArgument, "B-spline: knot " + std::to_string(i) + " decreases");
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!c.control[i].allFinite())
      return Status(ErrorCode::kInvalidArgument, "B-spline: control point " + std::to_string(i) + " is not finite");
  const auto up = static_cast<std::size_t>(p);
  if (!(c.knots[n] > c.knots[up])) return Status(ErrorCode::kInvalidArgument, "B-spline: empty parameter domain");
  samples_per_span = std::max(samples_per_span, 1);
  auto eval = [&](std::size_t span, double t) {  // de Boor on knot span [k_span, k_span+1)
    std::vector<Vec3d> d(up + 1);
    for (std::size_t j = 0; j <= up; ++j) d[j] = c.control[span - up + j];
    for (std::size_t r = 1; r <= up; ++r)
      for (std::size_t j = up; j >= r; --j) {
        const std::size_t i = span - up + j;
        const double den = c.knots[i + up + 1 - r] - c.knots[i];
        const double a = den > 0 ? (t - c.knots[i]) / den : 0.0;
        d[j] = (1 - a) * d[j - 1] + a * d[j];
      }
    return d[up];
  };
  std::vector<Vec3d> out;
  for (std::size_t s = up; s < n; ++s) {
    const double a = c.knots[s], b = c.knots[s + 1];
    if (!(b > a)) continue;
    for (int k = 0; k < samples_per_span; ++k) out.push_back(eval(s, a + (b - a) * k / samples_per_span));
  }
  // The end point: the last non-empty span evaluated at its right end.
  std::size_t last = n - 1;
  while (!(c.knots[last + 1] > c.knots[last])) --last;
  out.push_back(eval(last, c.knots[n]));
  return out;
}

Vec3d crease_spline_point(std::span<const Vec3d> polygon, double t) {
  const std::size_t m = polygon.size() - 1;
  if (m == 0) return polygon[0];
  std::vector<std::pair<std::size_t, double>> w;
  weights_at(t, m, w);
  Vec3d s = Vec3d::Zero();
  for (const auto& [i, x] : w) s += x * polygon[i];
  return s;
}

std::vector<Vec3d> fit_crease_polygon(std::span<const Vec3d> poly, std::size_t count) {
  count = std::max<std::size_t>(count, 2);
  const std::size_t m = count - 1;
  std::vector<Vec3d> P(count);
  P.front() = poly.front();
  P.back() = poly.back();
  if (count == 2) return P;
  // Resample by arc length.
  std::vector<double> arc(poly.size(), 0.0);
  for (std::size_t i = 1; i < poly.size(); ++i) arc[i] = arc[i - 1] + (poly[i] - poly[i - 1]).norm();
  const double L = arc.back();
  if (!(L > 0)) {
    for (std::size_t i = 1; i < m; ++i) P[i] = poly.front();
    return P;
  }
  const std::size_t S = std::max<std::size_t>(8 * m, poly.size()) + 1;
  const std::size_t nu = m - 1;  // unknowns P_1 .. P_{m-1}
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(nu), static_cast<Eigen::Index>(nu));
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(nu), 3);
  std::vector<std::pair<std::size_t, double>> w;
  std::size_t seg = 0;
  for (std::size_t k = 0; k < S; ++k) {
    const double s = L * static_cast<double>(k) / static_cast<double>(S - 1);
    while (seg + 2 < poly.size() && arc[seg + 1] < s) ++seg;
    const double ls = arc[seg + 1] - arc[seg];
    const double f = ls > 0 ? std::clamp((s - arc[seg]) / ls, 0.0, 1.0) : 0.0;
    const Vec3d q = poly[seg] + f * (poly[seg + 1] - poly[seg]);
    weights_at(s / L * static_cast<double>(m), m, w);
    Vec3d known = q;
    for (const auto& [i, x] : w)
      if (i == 0 || i == m) known -= x * P[i];
    for (const auto& [i, x] : w) {
      if (i == 0 || i == m) continue;
      rhs.row(static_cast<Eigen::Index>(i - 1)) += x * known.transpose();
      for (const auto& [j, y] : w)
        if (j != 0 && j != m) A(static_cast<Eigen::Index>(i - 1), static_cast<Eigen::Index>(j - 1)) += x * y;
    }
  }
  // Tiny fairness term sum |P_{i-1} - 2 P_i + P_{i+1}|^2 (well posed for any data).
  const double lambda = 1e-9 * static_cast<double>(S);
  for (std::size_t i = 1; i < m; ++i) {
    const std::size_t idx[3] = {i - 1, i, i + 1};
    const double c[3] = {1, -2, 1};
    for (int a = 0; a < 3; ++a) {
      if (idx[a] == 0 || idx[a] == m) continue;
      for (int b = 0; b < 3; ++b) {
        if (idx[b] == 0 || idx[b] == m) {
          rhs.row(static_cast<Eigen::Index>(idx[a] - 1)) -= lambda * c[a] * c[b] * P[idx[b]].transpose();
          continue;
        }
        A(static_cast<Eigen::Index>(idx[a] - 1), static_cast<Eigen::Index>(idx[b] - 1)) += lambda * c[a] * c[b];
      }
    }
  }
  const Eigen::MatrixXd x = A.ldlt().solve(rhs);
  for (std::size_t i = 1; i < m; ++i) P[i] = x.row(static_cast<Eigen::Index>(i - 1)).transpose();
  return P;
}

double crease_fit_error(std::span<const Vec3d> poly, std::span<const Vec3d> polygon) {
  const std::size_t m = polygon.size() - 1;
  std::vector<double> arc(poly.size(), 0.0);
  for (std::size_t i = 1; i < poly.size(); ++i) arc[i] = arc[i - 1] + (poly[i] - poly[i - 1]).norm();
  const double L = arc.back();
  if (!(L > 0) || m == 0) return 0.0;
  const std::size_t S = std::max<std::size_t>(8 * m, poly.size()) + 1;
  double worst = 0;
  std::size_t seg = 0;
  for (std::size_t k = 0; k < S; ++k) {
    const double s = L * static_cast<double>(k) / static_cast<double>(S - 1);
    while (seg + 2 < poly.size() && arc[seg + 1] < s) ++seg;
    const double ls = arc[seg + 1] - arc[seg];
    const double f = ls > 0 ? std::clamp((s - arc[seg]) / ls, 0.0, 1.0) : 0.0;
    const Vec3d q = poly[seg] + f * (poly[seg + 1] - poly[seg]);
    worst = std::max(worst, (q - crease_spline_point(polygon, s / L * static_cast<double>(m))).norm());
  }
  return worst;
}

}  // namespace atelier
