#include <atelier/systems/body/measure.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <atelier/engine/parallel.h>

namespace atelier {

double polyline_length(std::span<const Vec3d> pts, bool closed) noexcept {
  double l = 0;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) l += (pts[i + 1] - pts[i]).norm();
  if (closed && pts.size() > 2) l += (pts.front() - pts.back()).norm();
  return l;
}

double tape_girth(std::span<const Vec3d> c) {
  const std::size_t n = c.size();
  if (n < 3) return 0;
  Vec3d mean = Vec3d::Zero();
  for (const auto& p : c) mean += p;
  mean /= double(n);
  Mat3d cov = Mat3d::Zero();
  for (const auto& p : c) cov += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Mat3d> es(cov);
  // Eigenvalues ascending: column 0 is the plane normal, 1 and 2 span it.
  const Vec3d u = es.eigenvectors().col(2), v = es.eigenvectors().col(1);
  std::vector<Vec2d> q(n);
  for (std::size_t i = 0; i < n; ++i) q[i] = {(c[i] - mean).dot(u), (c[i] - mean).dot(v)};
  std::sort(q.begin(), q.end(), [](const Vec2d& a, const Vec2d& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  auto cross = [](const Vec2d& o, const Vec2d& a, const Vec2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Vec2d> h(2 * n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], q[i]) <= 0) --k;
    h[k++] = q[i];
  }
  for (std::size_t i = n - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], q[i - 1]) <= 0) --k;
    h[k++] = q[i - 1];
  }
  h.resize(k - 1);
  double per = 0;
  for (std::size_t i = 0; i < h.size(); ++i) per += (h[(i + 1) % h.size()] - h[i]).norm();
  return per;
}

Expected<BodyMeasurements> measure_body(const ReferenceBody& body) { return measure_body(body, body.model.nodes.position); }

Expected<BodyMeasurements> measure_body(const ReferenceBody& b, std::span<const Vec3d> pos) {
  const Model& m = b.model;
  if (pos.size() < m.nodes.slots.capacity())
    return Status(ErrorCode::kMismatch, "position array is smaller than the node table");
  BodyMeasurements out;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::uint32_t i = 0; i < m.nodes.slots.capacity(); ++i)
    if (m.alive(NodeIdx{i}) && m.nodes.surface[i] == b.skin) {
      lo = std::min(lo, pos[i].y());
      hi = std::max(hi, pos[i].y());
    }
  if (!(hi >= lo)) return Status(ErrorCode::kDegenerate, "body has no skin nodes");
  out.stature = hi - lo;
  for (const auto& c : b.curves) {
    auto poly = feature_curve_polyline(b, c.id, pos);
    if (!poly) return poly.status();
    CurveMeasure cm{c.id, c.name, c.closed, std::numeric_limits<double>::quiet_NaN(), polyline_length(*poly, c.closed)};
    if (c.closed) cm.girth = tape_girth(*poly);
    out.curves.push_back(std::move(cm));
  }
  for (const auto& p : b.points)
    out.points.push_back({p.id, p.name, attrib_position(m, p.node, pos).y() - lo});
  return out;
}

std::vector<std::string> measurement_columns(const ReferenceBody& b) {
  std::vector<std::string> cols{"stature"};
  for (const auto& c : b.curves)
    if (c.closed) cols.push_back(c.name + "_girth");
  for (const auto& c : b.curves) cols.push_back(c.name + "_length");
  for (const auto& p : b.points) cols.push_back(p.name + "_height");
  return cols;
}

std::vector<double> measurement_row(const BodyMeasurements& m) {
  std::vector<double> row{m.stature};
  for (const auto& c : m.curves)
    if (c.closed) row.push_back(c.girth);
  for (const auto& c : m.curves) row.push_back(c.length);
  for (const auto& p : m.points) row.push_back(p.height);
  return row;
}

Status measurements_csv(std::ostream& out, const ReferenceBody& features, std::size_t count,
                        const std::function<std::vector<Vec3d>(std::size_t)>& positions, const ExecContext& ctx,
                        bool header, std::size_t first_index) {
  if (header) {
    out << "body";
    for (const auto& c : measurement_columns(features)) out << ',' << c;
    out << '\n';
  }
  std::vector<std::string> rows(count);
  std::vector<Status> status(count);
  ExecContext c = ctx;
  c.sequential_threshold = 2;
  c.grain = 1;
  par::for_each_n(c, count, [&](std::size_t i) {
    const std::vector<Vec3d> pos = positions(i);
    auto m = measure_body(features, pos);
    if (!m) {
      status[i] = m.status();
      return;
    }
    std::string s = std::to_string(first_index + i);
    char buf[32];
    for (double v : measurement_row(*m)) {
      std::snprintf(buf, sizeof buf, ",%.6f", v);  // micrometres: far below any tape
      s += buf;
    }
    rows[i] = std::move(s);
  });
  for (std::size_t i = 0; i < count; ++i) {
    if (!status[i]) return Status(status[i].code(), "body " + std::to_string(first_index + i) + ": " + status[i].message());
    out << rows[i] << '\n';
  }
  if (!out) return Status(ErrorCode::kIo, "writing the measurements CSV failed");
  return {};
}

Status measurements_csv(std::ostream& out, std::span<const ReferenceBody> bodies, const ExecContext& ctx) {
  if (bodies.empty()) return Status(ErrorCode::kInvalidArgument, "no bodies to measure");
  const auto cols = measurement_columns(bodies[0]);
  for (std::size_t i = 1; i < bodies.size(); ++i)
    if (measurement_columns(bodies[i]) != cols ||
        bodies[i].model.nodes.slots.capacity() != bodies[0].model.nodes.slots.capacity())
      return Status(ErrorCode::kMismatch, "body " + std::to_string(i) + " has other features or topology than body 0");
  return measurements_csv(
      out, bodies[0], bodies.size(), [&](std::size_t i) { return bodies[i].model.nodes.position; }, ctx);
}

}  // namespace atelier
