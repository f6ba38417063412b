#include <atelier/systems/profile/profile_template.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include <atelier/storage/builder.h>
#include <atelier/storage/edge_flags.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/mesh/fan_triangulation.h>

namespace atelier {

namespace {

Status invalid(const std::string& what) {
  return {ErrorCode::kInvalidArgument, what};
}

}  // namespace

// Named, not anonymous: TemplateBuilder::Impl (declared in the header, so of
// external linkage) holds these as members.
namespace template_builder_detail {

// How a feature node is placed; turned into NodeEncodings once the model's
// node indices are known (build()).
struct FeatureNode {
  Vec3d position = Vec3d::Zero();
  bool relative = false;
  NodeEncoding encoding;            // absolute nodes
  std::vector<std::string> others;  // relative nodes: the feature nodes they follow
};

struct SurfaceInfo {
  SurfaceIdx index;
  std::map<std::string, NodeIdx, std::less<>> nodes;  // feature node -> this surface's copy
};

}  // namespace template_builder_detail

using template_builder_detail::FeatureNode;
using template_builder_detail::SurfaceInfo;

// ------------------------------------------------------------------ template

std::vector<ProfileCurve> ProfileTemplate::decode_profiles(std::span<const Vec3d> p) const {
  std::vector<ProfileCurve> out;
  out.reserve(profiles.size());
  for (const TemplateProfile& tp : profiles) {
    const Vec3d& a = p[model.tail(tp.halfedge).value];
    const Vec3d& b = p[model.head(tp.halfedge).value];
    if (tp.kind == ProfileCurve::Kind::kBezier)
      out.push_back(decode_bezier_profile(tp.bezier, a, b));  // seed 001 eq. (7)
    else
      out.push_back(shift_point_list(tp.points, a, b, tp.shift));  // seed 000 eq. (3)
  }
  return out;
}

// ------------------------------------------------------------------ builder

struct TemplateBuilder::Impl {
  const ReferenceBody& body;
  std::string name;
  double clearance = 0.004;
  int levels = 3;
  std::map<std::string, FeatureNode, std::less<>> features;
  std::map<std::string, SurfaceInfo, std::less<>> surfaces;
  std::map<std::string, NodeIdx, std::less<>> primary;  // first copy of each feature node
  Model model;
  std::vector<std::string> node_names;
  std::vector<TemplateProfile> profiles;
  // Lazily built closest-element search over the skin.
  std::optional<BodyBvh> bvh;
  SurfaceTriangles tris;

  Impl(const ReferenceBody& b, std::string n) : body(b), name(std::move(n)) {}

  Status ensure_bvh() {
    if (bvh) return {};
    auto t = fan_triangulate(body.model, std::vector<SurfaceIdx>{body.skin});
    if (!t) return t.status();
    tris = std::move(*t);
    BodyBvh b;
    if (Status s = b.build(std::span<const Vec3d>(body.model.nodes.position), tris.triangles); !s) return s;
    bvh = std::move(b);
    return {};
  }

  Expected<FeatureNode> place(const Vec3d& p, NodeEncodingMode mode) {
    FeatureNode f;
    f.position = p;
    const Model& bm = body.model;
    switch (mode) {
      case NodeEncodingMode::kFeaturePoint:
      case NodeEncodingMode::kFeatureOffset: {
        const FeaturePoint* best = nullptr;
        double bd = std::numeric_limits<double>::infinity();
        for (const FeaturePoint& fp : body.points) {
          const double d = (bm.attrib_nodes.position[fp.node.value] - p).squaredNorm();
          if (d < bd) bd = d, best = &fp;
        }
        if (!best)
          return invalid(
              "reference body has no feature points (crossings of its feature curves: a body with curves from a "
              "file needs centre_front and centre_back crossing its girths, docs/body-files.md)");
        auto e = encode_on_feature_point(body, best->id, p, mode == NodeEncodingMode::kFeatureOffset);
        if (!e) return e.status();
        f.encoding = *e;
        return f;
      }
      case NodeEncodingMode::kVertex:
      case NodeEncodingMode::kEdge:
      case NodeEncodingMode::kFace: {
        if (Status s = ensure_bvh(); !s) return s;
        const ClosestHit hit = bvh->closest_point(p);
        if (hit.triangle == kNoTriangle) return invalid("reference body has no faces");
        const Triangle& t = tris.triangles[hit.triangle];
        Expected<NodeEncoding> e = Status{};
        if (mode == NodeEncodingMode::kFace) {
          e = encode_on_face(body, tris.face[hit.triangle], p);
        } else if (mode == NodeEncodingMode::kVertex) {
          std::uint32_t v = t[0];
          for (std::uint32_t c : t)
            if ((bm.position(NodeIdx{c}) - p).squaredNorm() < (bm.position(NodeIdx{v}) - p).squaredNorm()) v = c;
          e = encode_on_vertex(body, NodeIdx{v}, p);
        } else {
          // The nearest of the triangle's sides that is a model edge (a fan
          // diagonal of a polygon is not).
          EdgeIdx best;
          double bd = std::numeric_limits<double>::infinity();
          for (int k = 0; k < 3; ++k) {
            const NodeIdx a{t[k]}, b{t[(k + 1) % 3]};
            const HalfedgeIdx h = bm.find_halfedge(a, b);
            if (!h.valid()) continue;
            const Vec3d pa = bm.position(a), ab = bm.position(b) - pa;
            const double s = std::clamp((p - pa).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
            const double d = (pa + s * ab - p).squaredNorm();
            if (d < bd) bd = d, best = edge_of(h);
          }
          if (!best.valid()) return invalid("no model edge on the closest triangle");
          e = encode_on_edge(body, best, p);
        }
        if (!e) return e.status();
        f.encoding = *e;
        return f;
      }
      default:
        return invalid(std::string("node_at: mode ") + to_string(mode) + " needs other nodes (use node_relative)");
    }
  }

  Status add_feature(const std::string& n, FeatureNode f) {
    if (n.empty()) return invalid("feature node names must not be empty");
    if (features.count(n)) return invalid("feature node '" + n + "' is defined twice");
    if (!f.position.allFinite()) return invalid("feature node '" + n + "' has a non-finite position");
    features.emplace(n, std::move(f));
    return {};
  }

  Expected<NodeIdx> node_of(std::string_view surface, std::string_view feature) const {
    auto s = surfaces.find(surface);
    if (s == surfaces.end()) return invalid("no surface '" + std::string(surface) + "'");
    auto v = s->second.nodes.find(feature);
    if (v == s->second.nodes.end())
      return invalid("surface '" + std::string(surface) + "' has no node '" + std::string(feature) + "'");
    return v->second;
  }

  Expected<HalfedgeIdx> halfedge_of(std::string_view surface, std::string_view from, std::string_view to) const {
    auto a = node_of(surface, from);
    if (!a) return a.status();
    auto b = node_of(surface, to);
    if (!b) return b.status();
    const HalfedgeIdx h = model.find_halfedge(*a, *b);
    if (!h.valid())
      return invalid("surface '" + std::string(surface) + "' has no edge " + std::string(from) + " - " +
                     std::string(to));
    return h;
  }

  Status add_profile(TemplateProfile tp) {
    for (const auto& q : profiles)
      if (edge_of(q.halfedge) == edge_of(tp.halfedge))
        return invalid("edge " + std::to_string(edge_of(tp.halfedge).value) + " already has a profile");
    profiles.push_back(std::move(tp));
    return {};
  }
};

TemplateBuilder::TemplateBuilder(const ReferenceBody& body, std::string name)
    : impl_(std::make_unique<Impl>(body, std::move(name))) {}
TemplateBuilder::~TemplateBuilder() = default;

void TemplateBuilder::set_clearance(double c) noexcept {
  impl_->clearance = c;
}
void TemplateBuilder::set_levels(int levels) noexcept {
  impl_->levels = levels;
}

Status TemplateBuilder::node_on_feature_point(const std::string& name, std::string_view point, const Vec3d& abg) {
  const FeaturePoint* fp = impl_->body.find_point(point);
  if (!fp) return invalid("reference body has no feature point '" + std::string(point) + "'");
  auto fr = feature_frame(impl_->body, fp->id);
  if (!fr) return fr.status();
  FeatureNode f;
  f.position = fr->origin + abg.x() * fr->n + abg.y() * fr->t1 + abg.z() * fr->t2;  // seed 000 eq. (1)
  auto e = encode_on_feature_point(impl_->body, fp->id, f.position);
  if (!e) return e.status();
  f.encoding = *e;
  return impl_->add_feature(name, std::move(f));
}

Status TemplateBuilder::node_at(const std::string& name, const Vec3d& p, NodeEncodingMode mode) {
  auto f = impl_->place(p, mode);
  if (!f) return Status(f.status().code(), "feature node '" + name + "': " + f.status().message());
  return impl_->add_feature(name, std::move(*f));
}

Status TemplateBuilder::node_relative(const std::string& name, std::span<const std::string> others, const Vec3d& p) {
  if (others.empty()) return invalid("feature node '" + name + "': node_relative needs at least one other node");
  for (const auto& o : others)
    if (!impl_->features.count(o)) return invalid("feature node '" + name + "' refers to unknown node '" + o + "'");
  FeatureNode f;
  f.position = p;
  f.relative = true;
  f.others.assign(others.begin(), others.end());
  return impl_->add_feature(name, std::move(f));
}

Expected<Vec3d> TemplateBuilder::position(std::string_view name) const {
  auto it = impl_->features.find(name);
  if (it == impl_->features.end()) return invalid("no feature node '" + std::string(name) + "'");
  return it->second.position;
}

bool TemplateBuilder::has_node(std::string_view name) const {
  return impl_->features.count(name) > 0;
}

Status TemplateBuilder::surface(const std::string& name, std::span<const std::vector<std::string>> faces) {
  Impl& I = *impl_;
  if (I.surfaces.count(name)) return invalid("surface '" + name + "' is defined twice");
  if (faces.empty()) return invalid("surface '" + name + "' has no faces");
  std::vector<std::string> order;  // feature nodes in first-use order
  std::map<std::string, std::uint32_t, std::less<>> local;
  std::vector<std::uint32_t> offsets{0}, ids;
  std::vector<Vec3d> pos;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    for (const auto& n : faces[f]) {
      auto it = I.features.find(n);
      if (it == I.features.end())
        return invalid("surface '" + name + "', face " + std::to_string(f) + ": unknown feature node '" + n + "'");
      auto [l, fresh] = local.emplace(n, static_cast<std::uint32_t>(order.size()));
      if (fresh) {
        order.push_back(n);
        pos.push_back(it->second.position);
      }
      ids.push_back(l->second);
    }
    offsets.push_back(static_cast<std::uint32_t>(ids.size()));
  }
  // Nodes are appended at the end of a dense table, in array order.
  const auto base = static_cast<std::uint32_t>(I.model.nodes.slots.capacity());
  if (I.model.nodes.slots.size() != base) return Status(ErrorCode::kInternal, "template model has node tombstones");
  auto s = add_polygon_surface(I.model, name, PolygonSoupView{pos, offsets, ids});
  if (!s) return Status(s.status().code(), "surface '" + name + "': " + s.status().message());
  SurfaceInfo info;
  info.index = s->idx;
  for (std::uint32_t k = 0; k < order.size(); ++k) {
    const NodeIdx v{base + k};
    if (I.model.position(v) != pos[k]) return Status(ErrorCode::kInternal, "unexpected node order in surface");
    info.nodes.emplace(order[k], v);
    I.primary.emplace(order[k], v);  // keeps the first copy
  }
  I.node_names.resize(I.model.nodes.slots.capacity());
  for (std::uint32_t k = 0; k < order.size(); ++k) I.node_names[base + k] = order[k];
  I.surfaces.emplace(name, std::move(info));
  return {};
}

Status TemplateBuilder::seam(std::string_view surface, std::span<const std::string> nodes) {
  Impl& I = *impl_;
  if (nodes.size() < 2) return invalid("a seam chain needs at least two nodes");
  std::vector<EdgeIdx> edges;  // all found before any is marked: nothing changes on error
  for (std::size_t i = 0; i + 1 < nodes.size(); ++i) {
    auto h = I.halfedge_of(surface, nodes[i], nodes[i + 1]);
    if (!h) return h.status();
    edges.push_back(edge_of(*h));
  }
  for (EdgeIdx e : edges) I.model.edges.flags[e.value] |= kEdgeSeam;
  return {};
}

Status TemplateBuilder::joint(std::span<const JointChain> members) {
  Impl& I = *impl_;
  if (members.size() < 2) return invalid("a joint needs at least two members");
  const auto& ref = members[0].nodes;
  if (ref.size() < 2) return invalid("a joint chain needs at least two nodes");
  struct Member {
    MeshEdgeIdx mesh_edge;
    bool positive;
    double angle;
  };
  std::vector<Member> made;
  const Vec3d a0 = I.features.at(ref.front()).position;
  Vec3d dir = I.features.at(ref.back()).position - a0;
  if (ref.front() == ref.back() || dir.norm() < 1e-12)  // closed chain: the first edge's direction
    dir = I.features.at(ref[1]).position - a0;
  dir.normalize();
  const Vec3d e1 = dir.unitOrthogonal(), e2 = dir.cross(e1);
  for (std::size_t k = 0; k < members.size(); ++k) {
    const JointChain& mc = members[k];
    if (mc.nodes != ref)
      return invalid("joint member " + std::to_string(k) + " (surface '" + mc.surface +
                     "') does not name the same node chain as member 0");
    auto si = I.surfaces.find(mc.surface);
    if (si == I.surfaces.end())
      return invalid("joint member " + std::to_string(k) + ": no surface '" + mc.surface + "'");
    std::vector<HalfedgeIdx> chain;
    bool any_face_side_forward = true;
    for (std::size_t i = 0; i + 1 < mc.nodes.size(); ++i) {
      auto h = I.halfedge_of(mc.surface, mc.nodes[i], mc.nodes[i + 1]);
      if (!h) return Status(h.status().code(), "joint member " + std::to_string(k) + ": " + h.status().message());
      chain.push_back(*h);
      if (i == 0) any_face_side_forward = !I.model.is_boundary(*h);
    }
    // Mesh edges follow their surface's orientation: a boundary chain runs
    // along its faces (negative flag when that is against the joint).
    bool positive = true;
    if (!any_face_side_forward) {
      std::vector<HalfedgeIdx> rev;
      for (auto it = chain.rbegin(); it != chain.rend(); ++it) rev.push_back(twin(*it));
      chain = std::move(rev);
      positive = false;
    }
    for (HalfedgeIdx h : chain)
      if (I.model.edges.mesh_edge[edge_of(h).value].valid())
        return invalid("joint member " + std::to_string(k) + ": edge " + std::to_string(edge_of(h).value) +
                       " already belongs to a mesh edge");
    const MeshEdgeIdx me = I.model.new_mesh_edge(si->second.index, chain);
    // Angle of the member's sheet about the joint direction, from the first
    // edge's midpoint towards the centroid of a face on it.
    const HalfedgeIdx h0 = chain.front();
    const HalfedgeIdx hf = I.model.is_boundary(h0) ? twin(h0) : h0;
    Vec3d c = Vec3d::Zero();
    int n = 0;
    I.model.for_each_face_halfedge(I.model.face(hf), [&](HalfedgeIdx h) {
      c += I.model.position(I.model.tail(h));
      ++n;
    });
    const Vec3d mid = 0.5 * (I.model.position(I.model.tail(h0)) + I.model.position(I.model.head(h0)));
    const Vec3d w = c / n - mid;
    made.push_back({me, positive, std::atan2(w.dot(e2), w.dot(e1))});
  }
  // Clockwise about dir by the right-hand rule: decreasing angle.
  std::stable_sort(made.begin(), made.end(), [](const Member& x, const Member& y) { return x.angle > y.angle; });
  std::vector<JointMember> jm;
  for (const Member& m : made) jm.push_back({m.mesh_edge, m.positive});
  (void)I.model.new_joint(jm);
  return {};
}

Status TemplateBuilder::bezier_profile(std::string_view surface, std::string_view from, std::string_view to,
                                       std::span<const Vec3d> interior) {
  Impl& I = *impl_;
  auto h = I.halfedge_of(surface, from, to);
  if (!h) return h.status();
  ProfileCurve c;
  c.kind = ProfileCurve::Kind::kBezier;
  c.points.push_back(I.model.position(I.model.tail(*h)));
  for (const Vec3d& p : interior) {
    if (!p.allFinite())
      return invalid("Bezier profile " + std::string(from) + " - " + std::string(to) + ": non-finite control point");
    c.points.push_back(p);
  }
  c.points.push_back(I.model.position(I.model.head(*h)));
  auto e = encode_bezier_profile(c);  // seed 001 eq. (6)
  if (!e) return e.status();
  TemplateProfile tp;
  tp.halfedge = *h;
  tp.kind = ProfileCurve::Kind::kBezier;
  tp.bezier = std::move(*e);
  return I.add_profile(std::move(tp));
}

Status TemplateBuilder::point_list_profile(std::string_view surface, std::string_view from, std::string_view to,
                                           std::span<const double> u, std::span<const Vec3d> points) {
  Impl& I = *impl_;
  auto h = I.halfedge_of(surface, from, to);
  if (!h) return h.status();
  if (u.size() != points.size() || u.empty())
    return invalid("point list profile: u and points must have the same, non-zero size");
  for (std::size_t i = 0; i < u.size(); ++i) {
    if (!(u[i] > 0 && u[i] < 1) || (i && !(u[i] > u[i - 1])))
      return invalid("point list profile: parameters must increase inside (0, 1)");
    if (!points[i].allFinite()) return invalid("point list profile: non-finite point");
  }
  TemplateProfile tp;
  tp.halfedge = *h;
  tp.kind = ProfileCurve::Kind::kPolyline;
  tp.points.a = I.model.position(I.model.tail(*h));
  tp.points.b = I.model.position(I.model.head(*h));
  tp.points.u.assign(u.begin(), u.end());
  tp.points.points.assign(points.begin(), points.end());
  if (Status s = I.add_profile(tp); !s) return s;
  return attach_point_list(I.model, I.surfaces.find(surface)->second.index, *h, u, points);
}

Expected<std::size_t> TemplateBuilder::stroke_profile(std::string_view surface, const Camera& camera,
                                                      std::span<const Vec2d> stroke, double tol_px) {
  Impl& I = *impl_;
  auto si = I.surfaces.find(surface);
  if (si == I.surfaces.end()) return invalid("no surface '" + std::string(surface) + "'");
  // Seed 000 4.1.4: only visible edges are selected; the reference body
  // occludes (a point is visible when the camera ray reaches it first).
  if (Status s = I.ensure_bvh(); !s) return s;
  auto visible = [&](const Vec3d& p) {
    const Vec3d px = camera.project(p);
    if (!px.allFinite()) return false;
    const auto [o, d] = camera.ray(Vec2d(px.x(), px.y()));
    const double tp = (p - o).dot(d);
    return !I.bvh->ray_first_hit(o, d, std::max(0.0, tp - 1e-6)).hit;
  };
  auto sp = profiles_from_stroke(I.model, I.model.nodes.position, camera, stroke, tol_px, visible);
  if (!sp) return sp.status();
  std::size_t added = 0;
  for (std::size_t i = 0; i < sp->edges.size(); ++i) {
    const HalfedgeIdx h = sp->edges[i];
    if (I.model.nodes.surface[I.model.tail(h).value] != si->second.index) continue;
    PointListProfile pl;  // interior points only
    pl.a = sp->profiles[i].a;
    pl.b = sp->profiles[i].b;
    for (std::size_t k = 0; k < sp->profiles[i].u.size(); ++k) {
      const double u = sp->profiles[i].u[k];
      if (u > 1e-9 && u < 1 - 1e-9 && (pl.u.empty() || u > pl.u.back())) {
        pl.u.push_back(u);
        pl.points.push_back(sp->profiles[i].points[k]);
      }
    }
    if (pl.u.empty()) continue;
    TemplateProfile tp;
    tp.halfedge = h;
    tp.kind = ProfileCurve::Kind::kPolyline;
    tp.points = pl;
    if (Status s = I.add_profile(tp); !s) return s;
    if (Status s = attach_point_list(I.model, si->second.index, h, pl.u, pl.points); !s) return s;
    ++added;
  }
  return added;
}

Expected<ProfileTemplate> TemplateBuilder::build() {
  Impl& I = *impl_;
  ProfileTemplate t;
  t.name = I.name;
  t.reference = "reference body";
  t.clearance = I.clearance;
  t.levels = I.levels;
  const std::size_t n = I.model.nodes.slots.capacity();
  I.node_names.resize(n);
  t.encodings.nodes.resize(n);
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!I.model.alive(NodeIdx{v})) continue;
    const std::string& fname = I.node_names[v];
    const FeatureNode& f = I.features.at(fname);
    const NodeIdx prim = I.primary.at(fname);
    if (prim.value != v) {  // a copy in another surface: follows its first copy exactly
      t.encodings.nodes[v] = encode_one_to_one(prim.value, f.position, f.position);
      continue;
    }
    if (!f.relative) {
      t.encodings.nodes[v] = f.encoding;
      continue;
    }
    std::vector<std::uint32_t> refs;
    std::vector<Vec3d> ref_pos;
    for (const auto& o : f.others) {
      auto it = I.primary.find(o);
      if (it == I.primary.end())
        return invalid("feature node '" + fname + "' follows '" + o + "', which no surface uses");
      refs.push_back(it->second.value);
      ref_pos.push_back(I.features.at(o).position);
    }
    t.encodings.nodes[v] = refs.size() == 1 ? encode_one_to_one(refs[0], ref_pos[0], f.position)
                                            : encode_n_to_one(t.encodings, refs, ref_pos, f.position);
  }
  if (Status s = I.ensure_bvh(); !s) return s;
  if (!I.bvh->closed()) return Status(ErrorCode::kTopology, "reference body skin is not closed");
  t.encoded_clearance.assign(n, 0.0);
  for (std::uint32_t v = 0; v < n; ++v)
    if (I.model.alive(NodeIdx{v}))
      t.encoded_clearance[v] = I.bvh->signed_distance(I.model.position(NodeIdx{v})).distance;
  t.model = std::move(I.model);
  t.node_names = std::move(I.node_names);
  t.profiles = std::move(I.profiles);
  I.model = Model{};
  I.surfaces.clear();
  I.primary.clear();
  if (Status s = validate_template(t); !s) return s;
  return t;
}

}  // namespace atelier
