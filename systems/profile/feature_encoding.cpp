#include <atelier/systems/profile/feature_encoding.h>

#include <sstream>

#include <atelier/systems/mesh/normals.h>

namespace atelier {

namespace {

Status bad(const std::string& what) {
  return {ErrorCode::kInvalidArgument, what};
}
Status degenerate(const std::string& what) {
  return {ErrorCode::kDegenerate, what};
}

std::string node_msg(std::size_t i, NodeEncodingMode mode, const std::string& what) {
  std::ostringstream s;
  s << "template node " << i << " (" << to_string(mode) << " mode): " << what;
  return s.str();
}

}  // namespace

Expected<ElementFrame> element_frame(const ReferenceBody& body, NodeEncodingMode mode, std::uint32_t element, double t,
                                     std::span<const Vec3d> p) {
  const Model& m = body.model;
  ElementFrame fr;
  switch (mode) {
    case NodeEncodingMode::kVertex: {
      const NodeIdx v{element};
      if (!m.alive(v) || m.is_isolated(v)) return bad("vertex " + std::to_string(element) + " is dead or isolated");
      const Vec3d n = vertex_normal(m, v, p);
      if (!(n.norm() > 0)) return degenerate("vertex " + std::to_string(element) + " has no normal");
      fr.origin = p[element];
      fr.x = n.normalized();
      // Seed 001 eq. (1): Y from the first neighbour (next ones if degenerate).
      bool ok = false;
      m.for_each_outgoing(v, [&](HalfedgeIdx h) {
        if (ok) return;
        const Vec3d d = p[m.head(h).value] - fr.origin;
        const Vec3d y = d.cross(fr.x);
        if (d.norm() > 0 && y.norm() > 1e-9 * d.norm()) {
          fr.y = y.normalized();
          ok = true;
        }
      });
      if (!ok) return degenerate("vertex " + std::to_string(element) + ": every neighbour is along the normal");
      fr.z = fr.x.cross(fr.y);
      return fr;
    }
    case NodeEncodingMode::kEdge: {
      const HalfedgeIdx h{element};
      if (element >= m.halfedges.tail.size() || !m.alive(h))
        return bad("edge halfedge " + std::to_string(element) + " is dead");
      const Vec3d a = p[m.tail(h).value], b = p[m.head(h).value];
      const Vec3d dir = b - a;
      if (!(dir.norm() > 0)) return degenerate("edge " + std::to_string(edge_of(h).value) + " has zero length");
      Vec3d n = Vec3d::Zero();
      for (HalfedgeIdx s : {h, twin(h)})
        if (m.face(s).valid()) n += face_normal(m, m.face(s), p).normalized();
      fr.origin = (1 - t) * a + t * b;
      fr.y = dir.normalized();
      n -= n.dot(fr.y) * fr.y;  // exactly perpendicular to the edge (seed 001 after eq. 2)
      if (!(n.norm() > 1e-12)) return degenerate("edge " + std::to_string(edge_of(h).value) + " has no normal");
      fr.x = n.normalized();
      fr.z = fr.x.cross(fr.y);
      return fr;
    }
    case NodeEncodingMode::kFace: {
      const FaceIdx f{element};
      if (!m.alive(f)) return bad("face " + std::to_string(element) + " is dead");
      Vec3d c = Vec3d::Zero();
      std::size_t k = 0;
      m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
        c += p[m.tail(h).value];
        ++k;
      });
      c /= static_cast<double>(k);
      const Vec3d n = face_normal(m, f, p);
      if (!(n.norm() > 0)) return degenerate("face " + std::to_string(element) + " has zero area");
      fr.origin = c;
      fr.x = n.normalized();
      Vec3d y = p[m.tail(m.faces.halfedge[f.value]).value] - c;
      y -= y.dot(fr.x) * fr.x;
      if (!(y.norm() > 0)) return degenerate("face " + std::to_string(element) + ": first corner at the centroid");
      fr.y = y.normalized();
      fr.z = fr.x.cross(fr.y);
      return fr;
    }
    default:
      return bad("element_frame: mode has no body element");
  }
}

Expected<NodeEncoding> encode_on_feature_point(const ReferenceBody& body, std::int32_t point_id, const Vec3d& p,
                                               bool offset_only) {
  if (!p.allFinite()) return bad("node position is not finite");
  auto fr = feature_frame(body, point_id);
  if (!fr) return fr.status();
  NodeEncoding e;
  e.feature_point = point_id;
  const Vec3d d = p - fr->origin;
  if (offset_only) {  // seed 000 eq. (2)
    e.mode = NodeEncodingMode::kFeatureOffset;
    e.coords = d;
    return e;
  }
  // Seed 000 eq. (1): solve [n t1 t2] (a b g)^T = p - q_j.
  Mat3d A;
  A.col(0) = fr->n;
  A.col(1) = fr->t1;
  A.col(2) = fr->t2;
  if (std::abs(fr->triple()) < 1e-6)
    return degenerate("feature point " + std::to_string(point_id) + ": its curves are tangent, (t1 x t2).n ~ 0");
  e.mode = NodeEncodingMode::kFeaturePoint;
  e.coords = A.fullPivLu().solve(d);
  return e;
}

namespace {
Expected<NodeEncoding> encode_in_frame(const ReferenceBody& body, NodeEncodingMode mode, std::uint32_t element,
                                       double t, const Vec3d& p) {
  if (!p.allFinite()) return bad("node position is not finite");
  const auto pos = skin_positions(body);
  auto fr = element_frame(body, mode, element, t, pos);
  if (!fr) return fr.status();
  NodeEncoding e;
  e.mode = mode;
  e.element = element;
  e.t = t;
  const Vec3d d = p - fr->origin;
  e.coords = Vec3d(d.dot(fr->x), d.dot(fr->y), d.dot(fr->z));
  return e;
}
}  // namespace

Expected<NodeEncoding> encode_on_vertex(const ReferenceBody& body, NodeIdx v, const Vec3d& p) {
  return encode_in_frame(body, NodeEncodingMode::kVertex, v.value, 0, p);
}

Expected<NodeEncoding> encode_on_edge(const ReferenceBody& body, EdgeIdx e, const Vec3d& p) {
  const Model& m = body.model;
  if (!m.alive(e)) return bad("edge " + std::to_string(e.value) + " is dead");
  const HalfedgeIdx h = halfedge_of(e, 0);
  const Vec3d a = m.position(m.tail(h)), b = m.position(m.head(h));
  const double l2 = (b - a).squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(b - a) / l2, 0.0, 1.0) : 0.0;
  return encode_in_frame(body, NodeEncodingMode::kEdge, h.value, t, p);
}

Expected<NodeEncoding> encode_on_face(const ReferenceBody& body, FaceIdx f, const Vec3d& p) {
  return encode_in_frame(body, NodeEncodingMode::kFace, f.value, 0, p);
}

NodeEncoding encode_one_to_one(std::uint32_t other, const Vec3d& other_pos, const Vec3d& p) {
  NodeEncoding e;
  e.mode = NodeEncodingMode::kOneToOne;
  e.element = other;
  e.coords = p - other_pos;
  return e;
}

NodeEncoding encode_n_to_one(NodeEncodings& pool, std::span<const std::uint32_t> others,
                             std::span<const Vec3d> other_pos, const Vec3d& p, double eps) {
  NodeEncoding e;
  e.mode = NodeEncodingMode::kNToOne;
  e.first_ref = static_cast<std::uint32_t>(pool.refs.size());
  e.ref_count = static_cast<std::uint32_t>(others.size());
  for (std::size_t i = 0; i < others.size(); ++i) {
    const Vec3d d = p - other_pos[i];
    pool.refs.push_back({others[i], d, 1.0 / (eps + std::pow(d.norm(), 3))});  // eq. (4)
  }
  return e;
}

Status decode_nodes(const NodeEncodings& enc, const ReferenceBody& body, std::span<const Vec3d> bp,
                    std::span<Vec3d> out) {
  const std::size_t n = enc.nodes.size();
  if (out.size() != n) return {ErrorCode::kMismatch, "decode_nodes: output size differs from the node count"};
  if (bp.size() != body.model.nodes.slots.capacity())
    return {ErrorCode::kMismatch, "decode_nodes: body positions do not match the reference body's node count"};
  // 0 = not placed, 1 = being placed (cycle detection), 2 = placed.
  std::vector<std::uint8_t> state(n, 0);
  std::vector<std::uint32_t> stack;
  auto deps = [&](std::uint32_t i, std::vector<std::uint32_t>& d) {
    d.clear();
    const NodeEncoding& e = enc.nodes[i];
    if (e.mode == NodeEncodingMode::kOneToOne) d.push_back(e.element);
    if (e.mode == NodeEncodingMode::kNToOne)
      for (std::uint32_t k = 0; k < e.ref_count; ++k) d.push_back(enc.refs[e.first_ref + k].node);
  };
  std::vector<std::uint32_t> d;
  for (std::uint32_t root = 0; root < n; ++root) {
    if (state[root] == 2) continue;
    stack.assign(1, root);
    while (!stack.empty()) {
      const std::uint32_t i = stack.back();
      const NodeEncoding& e = enc.nodes[i];
      if (state[i] == 0) {
        state[i] = 1;
        deps(i, d);
        bool pushed = false;
        for (std::uint32_t j : d) {
          if (j >= n)
            return {ErrorCode::kInvalidArgument,
                    node_msg(i, e.mode, "refers to node " + std::to_string(j) + " beyond the template")};
          if (state[j] == 1)
            return {ErrorCode::kTopology, node_msg(i, e.mode, "reference cycle through node " + std::to_string(j))};
          if (state[j] == 0) {
            stack.push_back(j);
            pushed = true;
          }
        }
        if (pushed) continue;
      }
      // All dependencies done: place node i.
      stack.pop_back();
      if (state[i] == 2) continue;
      switch (e.mode) {
        case NodeEncodingMode::kFeaturePoint:
        case NodeEncodingMode::kFeatureOffset: {
          auto fr = feature_frame(body, e.feature_point, bp);
          if (!fr) return {fr.status().code(), node_msg(i, e.mode, fr.status().message())};
          if (e.mode == NodeEncodingMode::kFeatureOffset)
            out[i] = fr->origin + e.coords;  // eq. (2)
          else
            out[i] = fr->origin + e.coords.x() * fr->n + e.coords.y() * fr->t1 + e.coords.z() * fr->t2;  // eq. (1)
          break;
        }
        case NodeEncodingMode::kVertex:
        case NodeEncodingMode::kEdge:
        case NodeEncodingMode::kFace: {
          auto fr = element_frame(body, e.mode, e.element, e.t, bp);
          if (!fr) return {fr.status().code(), node_msg(i, e.mode, fr.status().message())};
          out[i] = fr->origin + e.coords.x() * fr->x + e.coords.y() * fr->y + e.coords.z() * fr->z;
          break;
        }
        case NodeEncodingMode::kOneToOne:
          out[i] = out[e.element] + e.coords;
          break;
        case NodeEncodingMode::kNToOne: {  // eq. (5)
          Vec3d s = Vec3d::Zero();
          double w = 0;
          for (std::uint32_t k = 0; k < e.ref_count; ++k) {
            const NodeRef& r = enc.refs[e.first_ref + k];
            s += r.weight * (r.delta + out[r.node]);
            w += r.weight;
          }
          if (!(w > 0)) return {ErrorCode::kDegenerate, node_msg(i, e.mode, "no reference with positive weight")};
          out[i] = s / w;
          break;
        }
      }
      state[i] = 2;
    }
  }
  return {};
}

}  // namespace atelier
