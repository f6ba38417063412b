#include <atelier/systems/body/reference_body.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_set>

#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/mesh/normals.h>
#include <atelier/systems/spatial/body_bvh.h>

namespace atelier {

namespace {

std::string str(std::int32_t v) {
  return std::to_string(v);
}

Status check_location(const Model& m, SurfaceIdx skin, const SurfaceLocation& l) {
  switch (l.kind) {
    case AttribNodeKind::kVertex:
      if (!m.alive(NodeIdx{l.element}) || m.nodes.surface[l.element] != skin)
        return {ErrorCode::kInvalidArgument, "location on node " + std::to_string(l.element) + " is not a skin node"};
      return {};
    case AttribNodeKind::kEdge:
      if (l.element >= m.halfedges.tail.size() || !m.alive(HalfedgeIdx{l.element}) ||
          m.surface_of(edge_of(HalfedgeIdx{l.element})) != skin)
        return {ErrorCode::kInvalidArgument,
                "location on halfedge " + std::to_string(l.element) + " is not on the skin"};
      if (!(l.param.x() >= 0.0 && l.param.x() <= 1.0))
        return {ErrorCode::kInvalidArgument, "edge parameter outside [0,1]"};
      return {};
    case AttribNodeKind::kFace:
      if (!m.alive(FaceIdx{l.element}) || m.faces.surface[l.element] != skin)
        return {ErrorCode::kInvalidArgument, "location in face " + std::to_string(l.element) + " is not on the skin"};
      if (std::abs(l.param.sum() - 1.0) > 1e-9 || l.param.minCoeff() < 0.0)
        return {ErrorCode::kInvalidArgument, "face location is not a convex combination"};
      if (l.corner + 3u > m.face_degree(FaceIdx{l.element}))
        return {ErrorCode::kInvalidArgument, "face location names a fan triangle beyond its face"};
      return {};
  }
  return {ErrorCode::kInvalidArgument, "unknown location kind"};
}

Vec3d location_normal(const Model& m, AttribNodeIdx a, std::span<const Vec3d> pos) {
  const auto el = m.attrib_nodes.element[a.value];
  switch (m.attrib_nodes.kind[a.value]) {
    case AttribNodeKind::kVertex:
      return vertex_normal(m, NodeIdx{el}, pos).normalized();
    case AttribNodeKind::kEdge: {
      const HalfedgeIdx h{el};
      Vec3d n = Vec3d::Zero();
      for (HalfedgeIdx g : {h, twin(h)})
        if (m.face(g).valid()) n += face_normal(m, m.face(g), pos).normalized();
      return n.normalized();
    }
    case AttribNodeKind::kFace:
      return face_normal(m, FaceIdx{el}, pos).normalized();
  }
  return Vec3d::Zero();
}

// Point at arc length s along a polyline with cumulative lengths `cum`
// (cum.size() == pts.size() + closed); s is wrapped (closed) or clamped.
Vec3d point_at(std::span<const Vec3d> pts, const std::vector<double>& cum, bool closed, double s) {
  const double total = cum.back();
  if (closed) {
    s = std::fmod(s, total);
    if (s < 0) s += total;
  } else {
    s = std::clamp(s, 0.0, total);
  }
  const std::size_t seg = std::min<std::size_t>(
      static_cast<std::size_t>(std::upper_bound(cum.begin(), cum.end(), s) - cum.begin()), cum.size() - 1);
  const std::size_t i = seg == 0 ? 0 : seg - 1;
  const std::size_t j = (i + 1) % pts.size();
  const double len = cum[i + 1] - cum[i];
  const double t = len > 0 ? (s - cum[i]) / len : 0.0;
  return (1 - t) * pts[i] + t * pts[j];
}

// Unit tangent of a polyline at the point nearest to p, by a centred chord.
Vec3d polyline_tangent(std::span<const Vec3d> pts, bool closed, const Vec3d& p) {
  const std::size_t n = pts.size();
  const std::size_t segs = closed ? n : n - 1;
  std::vector<double> cum(segs + 1, 0.0);
  for (std::size_t i = 0; i < segs; ++i) cum[i + 1] = cum[i] + (pts[(i + 1) % n] - pts[i]).norm();
  double best = std::numeric_limits<double>::infinity(), s0 = 0;
  for (std::size_t i = 0; i < segs; ++i) {
    const Vec3d a = pts[i], d = pts[(i + 1) % n] - a;
    const double l2 = d.squaredNorm();
    const double t = l2 > 0 ? std::clamp((p - a).dot(d) / l2, 0.0, 1.0) : 0.0;
    const double dist = (a + t * d - p).squaredNorm();
    if (dist < best) {
      best = dist;
      s0 = cum[i] + t * (cum[i + 1] - cum[i]);
    }
  }
  // Window of two mean segments each side: long enough to average out the
  // zig-zag of a curve crossing faces, short enough to stay local.
  const double h = 2.0 * cum.back() / static_cast<double>(segs);
  return point_at(pts, cum, closed, s0 + h) - point_at(pts, cum, closed, s0 - h);
}

}  // namespace

const FeatureCurve* ReferenceBody::find_curve(std::int32_t id) const noexcept {
  for (const auto& c : curves)
    if (c.id == id) return &c;
  return nullptr;
}
const FeatureCurve* ReferenceBody::find_curve(std::string_view name) const noexcept {
  for (const auto& c : curves)
    if (c.name == name) return &c;
  return nullptr;
}
const FeaturePoint* ReferenceBody::find_point(std::int32_t id) const noexcept {
  for (const auto& p : points)
    if (p.id == id) return &p;
  return nullptr;
}
const FeaturePoint* ReferenceBody::find_point(std::string_view name) const noexcept {
  for (const auto& p : points)
    if (p.name == name) return &p;
  return nullptr;
}

Vec3d attrib_position(const Model& m, AttribNodeIdx a, std::span<const Vec3d> pos) {
  const auto i = a.value;
  const Vec3d& prm = m.attrib_nodes.param[i];
  switch (m.attrib_nodes.kind[i]) {
    case AttribNodeKind::kVertex:
      return pos[m.attrib_nodes.element[i]];
    case AttribNodeKind::kEdge: {
      const HalfedgeIdx h{m.attrib_nodes.element[i]};
      return (1.0 - prm.x()) * pos[m.tail(h).value] + prm.x() * pos[m.head(h).value];
    }
    case AttribNodeKind::kFace: {
      // Same fan convention as Model::attrib_position_on_surface.
      const FaceIdx f{m.attrib_nodes.element[i]};
      const HalfedgeIdx h0 = m.faces.halfedge[f.value];
      HalfedgeIdx h1 = m.next(h0);
      for (unsigned k = 0; k < m.attrib_nodes.corner[i]; ++k) h1 = m.next(h1);
      const HalfedgeIdx h2 = m.next(h1);
      return prm.x() * pos[m.tail(h0).value] + prm.y() * pos[m.tail(h1).value] + prm.z() * pos[m.tail(h2).value];
    }
  }
  return Vec3d::Zero();
}

Status add_feature_curve(ReferenceBody& body, std::int32_t id, std::string name, std::span<const SurfaceLocation> path,
                         bool closed) {
  if (body.find_curve(id)) return {ErrorCode::kInvalidArgument, "feature curve id " + str(id) + " already used"};
  if (body.find_curve(name)) return {ErrorCode::kInvalidArgument, "feature curve name '" + name + "' already used"};
  if (path.size() < (closed ? 3u : 2u))
    return {ErrorCode::kInvalidArgument,
            "feature curve '" + name + "' needs at least " + (closed ? "3" : "2") + " points"};
  Model& m = body.model;
  for (const auto& l : path)
    if (Status s = check_location(m, body.skin, l); !s)
      return {s.code(), "feature curve '" + name + "': " + s.message()};
  std::vector<AttribNodeIdx> nodes;
  nodes.reserve(path.size());
  for (const auto& l : path) {
    const AttribNodeIdx a = m.new_attrib_node(body.skin, l.kind, l.element, l.param, Vec3d::Zero(), l.corner);
    m.attrib_nodes.position[a.value] = m.attrib_position_on_surface(a);
    nodes.push_back(a);
  }
  const AttribEdgeIdx e = m.new_attrib_edge(body.skin, id, nodes);
  body.curves.push_back({id, std::move(name), e, closed});
  return {};
}

Status add_feature_point(ReferenceBody& body, std::int32_t id, std::string name, const SurfaceLocation& where,
                         std::int32_t c1, std::int32_t c2) {
  if (body.find_point(id)) return {ErrorCode::kInvalidArgument, "feature point id " + str(id) + " already used"};
  if (!body.find_curve(c1) || !body.find_curve(c2) || c1 == c2)
    return {ErrorCode::kInvalidArgument, "feature point '" + name + "' needs two distinct existing curves"};
  Model& m = body.model;
  if (Status s = check_location(m, body.skin, where); !s)
    return {s.code(), "feature point '" + name + "': " + s.message()};
  const AttribNodeIdx a =
      m.new_attrib_node(body.skin, where.kind, where.element, where.param, Vec3d::Zero(), where.corner);
  m.attrib_nodes.position[a.value] = m.attrib_position_on_surface(a);
  body.points.push_back({id, std::move(name), a, c1, c2});
  return {};
}

Expected<std::vector<Vec3d>> feature_curve_polyline(const ReferenceBody& body, std::int32_t id) {
  return feature_curve_polyline(body, id, body.model.nodes.position);
}

Expected<std::vector<Vec3d>> feature_curve_polyline(const ReferenceBody& body, std::int32_t id,
                                                    std::span<const Vec3d> positions) {
  const FeatureCurve* c = body.find_curve(id);
  if (!c) return Status(ErrorCode::kInvalidArgument, "no feature curve with id " + str(id));
  const Model& m = body.model;
  if (positions.size() < m.nodes.slots.capacity())
    return Status(ErrorCode::kMismatch, "position array is smaller than the node table");
  const auto row = m.attrib_edges.nodes.row(c->edge.value);
  std::vector<Vec3d> out;
  out.reserve(row.size());
  for (AttribNodeIdx a : row) out.push_back(attrib_position(m, a, positions));
  return out;
}

Expected<FeatureFrame> feature_frame(const ReferenceBody& body, std::int32_t point_id) {
  return feature_frame(body, point_id, body.model.nodes.position);
}

Expected<FeatureFrame> feature_frame(const ReferenceBody& body, std::int32_t point_id,
                                     std::span<const Vec3d> positions) {
  const FeaturePoint* p = body.find_point(point_id);
  if (!p) return Status(ErrorCode::kInvalidArgument, "no feature point with id " + str(point_id));
  const Model& m = body.model;
  if (positions.size() < m.nodes.slots.capacity())
    return Status(ErrorCode::kMismatch, "position array is smaller than the node table");
  FeatureFrame f;
  f.origin = attrib_position(m, p->node, positions);
  f.n = location_normal(m, p->node, positions);
  if (!f.n.allFinite() || f.n.norm() < 0.5)
    return Status(ErrorCode::kDegenerate, "feature point '" + p->name + "' has no well-defined normal");
  Vec3d* ts[2] = {&f.t1, &f.t2};
  const std::int32_t ids[2] = {p->curve1, p->curve2};
  for (int k = 0; k < 2; ++k) {
    auto poly = feature_curve_polyline(body, ids[k], positions);
    if (!poly) return poly.status();
    const FeatureCurve* c = body.find_curve(ids[k]);
    Vec3d t = polyline_tangent(*poly, c->closed, f.origin);
    t -= t.dot(f.n) * f.n;  // the curve lies on the surface: its tangent is in the tangent plane
    const double l = t.norm();
    if (!(l > 0)) return Status(ErrorCode::kDegenerate, "curve '" + c->name + "' has no tangent at '" + p->name + "'");
    *ts[k] = t / l;
  }
  return f;
}

std::vector<Vec3d> skin_positions(const ReferenceBody& body) {
  return body.model.nodes.position;
}

Status set_positions(ReferenceBody& body, std::span<const Vec3d> positions) {
  Model& m = body.model;
  if (positions.size() != m.nodes.slots.capacity())
    return {ErrorCode::kMismatch, "got " + std::to_string(positions.size()) + " positions for a node table of " +
                                      std::to_string(m.nodes.slots.capacity())};
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (m.alive(NodeIdx{static_cast<std::uint32_t>(i)}) && !positions[i].allFinite())
      return {ErrorCode::kDegenerate, "position of node " + std::to_string(i) + " is not finite"};
  std::copy(positions.begin(), positions.end(), m.nodes.position.begin());
  for (std::uint32_t a = 0; a < m.attrib_nodes.slots.capacity(); ++a)
    if (m.alive(AttribNodeIdx{a})) m.attrib_nodes.position[a] = m.attrib_position_on_surface(AttribNodeIdx{a});
  ++m.geometry_version;
  return {};
}

Expected<ReferenceBody> with_positions(const ReferenceBody& body, std::span<const Vec3d> positions) {
  ReferenceBody out = body;
  if (Status s = set_positions(out, positions); !s) return s;
  return out;
}

Status validate_features(const ReferenceBody& body) {
  const Model& m = body.model;
  std::unordered_set<std::int32_t> ids;
  std::unordered_set<std::string> names;
  for (const auto& c : body.curves) {
    if (!ids.insert(c.id).second) return {ErrorCode::kInternal, "feature curve id " + str(c.id) + " repeated"};
    if (!names.insert(c.name).second) return {ErrorCode::kInternal, "feature curve name '" + c.name + "' repeated"};
    if (!m.alive(c.edge)) return {ErrorCode::kInternal, "feature curve '" + c.name + "' has a dead attribute edge"};
    if (m.attrib_edges.feature_id[c.edge.value] != c.id)
      return {ErrorCode::kInternal, "feature curve '" + c.name + "' attribute edge carries another feature id"};
    if (m.attrib_edges.surface[c.edge.value] != body.skin)
      return {ErrorCode::kInternal, "feature curve '" + c.name + "' is not on the skin"};
    if (m.attrib_edges.nodes.size(c.edge.value) < (c.closed ? 3u : 2u))
      return {ErrorCode::kInternal, "feature curve '" + c.name + "' has too few nodes"};
  }
  ids.clear();
  names.clear();
  for (const auto& p : body.points) {
    if (!ids.insert(p.id).second) return {ErrorCode::kInternal, "feature point id " + str(p.id) + " repeated"};
    if (!names.insert(p.name).second) return {ErrorCode::kInternal, "feature point name '" + p.name + "' repeated"};
    if (!m.alive(p.node)) return {ErrorCode::kInternal, "feature point '" + p.name + "' has a dead attribute node"};
    if (!body.find_curve(p.curve1) || !body.find_curve(p.curve2))
      return {ErrorCode::kInternal, "feature point '" + p.name + "' names a missing curve"};
  }
  return {};
}


namespace {

std::string mm(double metres) {
  std::ostringstream s;
  s.precision(1);
  s << std::fixed << 1000.0 * metres << " mm";
  return s.str();
}

/// Closest points of segments [p0, p1] and [q0, q1] (Ericson, Real-Time
/// Collision Detection, 5.1.9); returns the squared distance.
double segment_closest(const Vec3d& p0, const Vec3d& p1, const Vec3d& q0, const Vec3d& q1, Vec3d& a, Vec3d& b) {
  const Vec3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double aa = d1.squaredNorm(), ee = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (aa <= 0 && ee <= 0) {
    s = t = 0;
  } else if (aa <= 0) {
    t = std::clamp(f / ee, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (ee <= 0) {
      s = std::clamp(-c / aa, 0.0, 1.0);
    } else {
      const double bb = d1.dot(d2), den = aa * ee - bb * bb;
      s = den > 0 ? std::clamp((bb * f - c * ee) / den, 0.0, 1.0) : 0.0;
      t = (bb * s + f) / ee;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / aa, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((bb - c) / aa, 0.0, 1.0);
      }
    }
  }
  a = p0 + s * d1;
  b = q0 + t * d2;
  return (a - b).squaredNorm();
}

}  // namespace

Expected<FeatureSnapReport> add_snapped_feature_curves(ReferenceBody& body, std::span<const FeaturePolyline> curves,
                                                       const FeatureSnapOptions& options) {
  const std::string src = options.source.empty() ? std::string("feature curves") : options.source;
  auto where = [&](const FeaturePolyline& c, std::size_t k) {
    const std::string line = k < c.lines.size() ? ":" + std::to_string(c.lines[k]) : std::string();
    return src + line + ": curve '" + c.name + "'";
  };
  if (!(options.tolerance > 0) || !std::isfinite(options.tolerance) || !(options.crossing_tolerance >= 0) ||
      !std::isfinite(options.crossing_tolerance))
    return Status(ErrorCode::kInvalidArgument, src + ": snap tolerances must be finite and positive");
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const FeaturePolyline& c = curves[i];
    if (body.find_curve(c.name))
      return Status(ErrorCode::kInvalidArgument, where(c, 0) + ": the body already has a curve of that name");
    for (std::size_t j = 0; j < i; ++j)
      if (curves[j].name == c.name) return Status(ErrorCode::kInvalidArgument, where(c, 0) + " is given twice");
    if (c.points.size() < (c.closed ? 3u : 2u))
      return Status(ErrorCode::kInvalidArgument,
                    where(c, 0) + ": a" + (c.closed ? " closed curve needs 3 points" : "n open curve needs 2 points"));
  }
  auto tris = fan_triangulate(body.model, std::vector<SurfaceIdx>{body.skin});
  if (!tris) return tris.status();
  if (tris->triangles.empty()) return Status(ErrorCode::kDegenerate, src + ": the body has no faces");
  // Fan triangle k of a face is (c0, c_{k+1}, c_{k+2}): the corner of a face
  // location (storage/surface_location.h), and the hit's barycentrics are
  // its areal coordinates in that order.
  std::vector<std::uint8_t> corner(tris->triangles.size(), 0);
  for (std::size_t t = 1; t < corner.size(); ++t)
    if (tris->face[t] == tris->face[t - 1]) corner[t] = static_cast<std::uint8_t>(std::min(255, corner[t - 1] + 1));
  BodyBvh bvh;
  if (Status s = bvh.build(std::span<const Vec3d>(body.model.nodes.position), tris->triangles); !s) return s;
  auto locate = [&](const ClosestHit& h) {
    Vec3d w = h.barycentric.cwiseMax(0.0);
    w /= w.sum();
    return SurfaceLocation{AttribNodeKind::kFace, tris->face[h.triangle].value, w, corner[h.triangle]};
  };

  FeatureSnapReport rep;
  std::vector<std::vector<SurfaceLocation>> paths(curves.size());
  std::vector<std::vector<Vec3d>> snapped(curves.size());
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const FeaturePolyline& c = curves[i];
    for (std::size_t k = 0; k < c.points.size(); ++k) {
      if (!c.points[k].allFinite())
        return Status(ErrorCode::kInvalidArgument, where(c, k) + ", point " + std::to_string(k) + " is not finite");
      const ClosestHit h = bvh.closest_point(c.points[k]);
      if (h.triangle == kNoTriangle || !(h.distance <= options.tolerance))
        return Status(ErrorCode::kInvalidArgument,
                      where(c, k) + ", point " + std::to_string(k) + " is " + mm(h.distance) +
                          " from the body's surface (at most " + mm(options.tolerance) +
                          "): drawn on another body, or in other units or axes (\"units\", \"up\", --scale, --up)?");
      rep.max_distance = std::max(rep.max_distance, h.distance);
      paths[i].push_back(locate(h));
      snapped[i].push_back(h.point);
    }
  }
  // Crossings, found on the snapped polylines before anything is written.
  struct Crossing {
    std::size_t closed, open;
    SurfaceLocation at;
  };
  std::vector<Crossing> crossings;
  const double tol2 = options.crossing_tolerance * options.crossing_tolerance;
  for (std::size_t i = 0; i < curves.size(); ++i) {
    if (!curves[i].closed) continue;
    for (std::size_t j = 0; j < curves.size(); ++j) {
      if (curves[j].closed) continue;
      const auto& P = snapped[i];
      const auto& Q = snapped[j];
      double best = std::numeric_limits<double>::infinity();
      Vec3d mid = Vec3d::Zero();
      for (std::size_t a = 0; a < P.size(); ++a)
        for (std::size_t b = 0; b + 1 < Q.size(); ++b) {
          Vec3d x, y;
          const double d2 = segment_closest(P[a], P[(a + 1) % P.size()], Q[b], Q[b + 1], x, y);
          if (d2 < best) best = d2, mid = 0.5 * (x + y);
        }
      if (best <= tol2) crossings.push_back({i, j, locate(bvh.closest_point(mid))});
    }
  }

  // Everything is checked: write, into a copy so that a failure (none is
  // expected: names and sizes were checked, locations come from the skin's
  // faces) leaves the body as it was.
  ReferenceBody out = body;
  std::int32_t next_curve = 1, next_point = 1;
  for (const auto& c : out.curves) next_curve = std::max(next_curve, c.id + 1);
  for (const auto& p : out.points) next_point = std::max(next_point, p.id + 1);
  std::vector<std::int32_t> ids(curves.size());
  for (std::size_t i = 0; i < curves.size(); ++i) {
    ids[i] = next_curve++;
    if (Status s = add_feature_curve(out, ids[i], curves[i].name, paths[i], curves[i].closed); !s)
      return Status(s.code(), src + ": " + s.message());
    ++rep.curves;
  }
  for (const Crossing& x : crossings) {
    if (Status s = add_feature_point(out, next_point++, curves[x.closed].name + "_x_" + curves[x.open].name, x.at,
                                     ids[x.closed], ids[x.open]);
        !s)
      return Status(s.code(), src + ": " + s.message());
    ++rep.points;
  }
  body = std::move(out);
  return rep;
}

}  // namespace atelier
