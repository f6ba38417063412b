// Mirrored pairs (issue 21, beyond seed 002): one base stroke and its
// extruding stroke(s) make the drawn extrusion and its mirror image across
// a symmetry plane (see ExtrudeOptions::mirror in extrude.h).
//
// Order: (1) B' first, on the untouched mesh (the reflected cameras' rays
// must not meet the drawn part); (2) the drawn extrusion, complete (sweep,
// sewing, optimisation, body push); (3) the checks: both sides of the plane
// strictly, B' node for node at the reflections of B; (4) the mirror part:
// the drawn part's nodes reflected, its faces reversed (a reflection turns
// an outward-oriented face inwards; reversing restores it), sewn onto B';
// (5) the body push, the parts as surfaces, validate.
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/sketch/extrude.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "extrude_detail.h"

namespace atelier::extrude_detail {

namespace {

struct Reflection {
  Vec3d q, n;  // a point of the plane, its unit normal
  [[nodiscard]] double side(const Vec3d& p) const { return (p - q).dot(n); }
  [[nodiscard]] Vec3d operator()(const Vec3d& p) const { return p - 2.0 * side(p) * n; }
};

/// The camera that sees the reflected world as `c` sees the world, with its
/// picture flipped left-right (so that it is not a mirrored camera: screen
/// orientation tests keep their sign): project'(x) = flip(project(R x)).
Camera reflected(const Camera& c, const Reflection& r) {
  Mat4d R = Mat4d::Identity();
  R.topLeftCorner<3, 3>() -= 2.0 * r.n * r.n.transpose();
  R.topRightCorner<3, 1>() = 2.0 * r.q.dot(r.n) * r.n;
  Mat4d flip = Mat4d::Identity();
  flip(0, 0) = -1;
  Camera out = c;
  out.view = c.view * R;
  out.projection = flip * c.projection;
  return out;
}

std::vector<Vec2d> flipped(const std::vector<Vec2d>& s, int width) {
  std::vector<Vec2d> out;
  out.reserve(s.size());
  for (const Vec2d& p : s) out.push_back(Vec2d(width - p.x(), p.y()));
  return out;
}

std::string str(const Vec3d& p) {
  std::ostringstream o;
  o << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return o.str();
}

Status mirror_fail(ErrorCode c, const std::string& what) {
  return fail(c, "mirror side: " + what);
}

}  // namespace

Expected<ExtrudeReport> run_mirrored(Model& m, const ExtrudeStrokes& in, const ExtrudeOptions& opt,
                                     const ExecContext& ctx) {
  const SymmetryPlane& pl = *opt.mirror;
  if (!pl.point.allFinite() || !pl.normal.allFinite() || !(pl.normal.norm() > 0))
    return fail(ErrorCode::kInvalidArgument, "the symmetry plane needs a finite point and a non-zero finite normal");
  if (!(opt.mirror_tolerance > 0) || !std::isfinite(opt.mirror_tolerance))
    return fail(ErrorCode::kInvalidArgument, "mirror_tolerance must be positive and finite");
  const Reflection refl{pl.point, pl.normal.normalized()};
  for (const Camera* c : {&in.base_camera, &in.sweep_camera})
    if (Status s = c->check(); !s) return fail(ErrorCode::kInvalidArgument, s.message());

  const double volume_before = signed_volume(m);
  // (1) B' through the reflected cameras, before the drawn part exists.
  ExtrudeStrokes min;
  min.base_camera = reflected(in.base_camera, refl);
  min.sweep_camera = reflected(in.sweep_camera, refl);
  min.base = flipped(in.base, in.base_camera.width);
  for (const auto& s : in.sweep) min.sweep.push_back(flipped(s, in.sweep_camera.width));
  ExtrudeOptions single = opt;
  single.mirror.reset();
  single.as_surface = false;
  // Which side B is on: step 1 alone on a copy (an open base changes
  // nothing; a painted one is cut on the copy only). An open B' is then
  // looked for on the other side only: seen through the reflected camera,
  // B itself lies right behind B' on screen.
  double side = 0;
  {
    Model probe = m;
    auto pb = run(probe, in, single, ctx, Stop::kAfterBase, nullptr);
    if (!pb) return fail(pb.status().code(), "drawn side: " + pb.status().message());
    for (NodeIdx v : pb->base) side += refl.side(probe.position(v));
  }
  const BaseSide other{refl.q, refl.n, side >= 0 ? -1.0 : 1.0};
  auto mb = run(m, min, single, ctx, Stop::kAfterBase, nullptr, &other);
  if (!mb) return mirror_fail(mb.status().code(), "no mirror base curve: " + mb.status().message());
  const std::vector<NodeIdx> Bm = mb->base;

  // (2) The drawn extrusion.
  RunOut ro;
  auto r = run(m, in, single, ctx, Stop::kNever, &ro);
  if (!r) {
    std::string msg = r.status().message();
    if (msg.rfind("extrude: ", 0) == 0) msg = msg.substr(9);
    return fail(r.status().code(), "drawn side: " + msg);
  }
  ExtrudeReport rep = std::move(*r);
  const std::vector<NodeIdx>& B = rep.base;
  const std::size_t n = B.size();
  const double L = rep.base_mean_edge, tol = opt.mirror_tolerance * L;

  // (3) The drawn side: B and the part strictly on one side of the plane.
  const std::vector<NodeIdx> part = new_nodes(m, ro.old_node);
  const double sgn = refl.side(m.position(B[0])) >= 0 ? 1.0 : -1.0;
  auto off_side = [&](NodeIdx v) { return !(sgn * refl.side(m.position(v)) > tol); };
  for (const std::vector<NodeIdx>* set : {&B, &part})
    for (NodeIdx v : *set)
      if (off_side(v))
        return fail(ErrorCode::kInvalidArgument,
                    "drawn side: the extrusion crosses the symmetry plane (" + std::string(set == &B ? "base" : "new") +
                        " node " + std::to_string(v.value) + " at " + str(m.position(v)) + ", signed distance " +
                        std::to_string(refl.side(m.position(v))) + ")");
  // B', node for node at the reflections of B (brute force: B is short).
  if (Bm.size() != n || mb->base_ring != rep.base_ring)
    return mirror_fail(ErrorCode::kDegenerate, "no mirror base curve: the reflected strokes select a " +
                                                   std::string(mb->base_ring ? "ring" : "chain") + " of " +
                                                   std::to_string(Bm.size()) + " nodes, B is a " +
                                                   (rep.base_ring ? "ring" : "chain") + " of " + std::to_string(n) +
                                                   " (the mesh is not symmetric there)");
  std::vector<NodeIdx> map(n);
  std::vector<char> used(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d t = refl(m.position(B[i]));
    double best = std::numeric_limits<double>::infinity();
    std::size_t bj = 0;
    for (std::size_t j = 0; j < n; ++j)
      if (const double d = (m.position(Bm[j]) - t).norm(); d < best) best = d, bj = j;
    if (!(best <= tol) || used[bj])
      return mirror_fail(ErrorCode::kDegenerate, "no mirror base curve: node " + std::to_string(i) +
                                                     " of B reflected to " + str(t) + " is " + std::to_string(best) +
                                                     " from the nearest node of B' (tolerance " + std::to_string(tol) +
                                                     "): the mesh is not symmetric there");
    used[bj] = 1;
    map[i] = Bm[bj];
    rep.mirror_base_error = std::max(rep.mirror_base_error, best);
  }
  const std::size_t segs = rep.base_ring ? n : n - 1;
  for (std::size_t i = 0; i < segs; ++i) {
    const HalfedgeIdx h = m.find_halfedge(map[(i + 1) % n], map[i]);
    if (!h.valid() || m.face(h).valid())
      return mirror_fail(ErrorCode::kDegenerate, "no mirror base curve: the nodes of B' at the reflections of B " +
                                                     std::to_string(i) + ", " + std::to_string((i + 1) % n) +
                                                     " are not joined by a free boundary edge");
  }
  if (ctx.cancelled()) return fail(ErrorCode::kCancelled, "cancelled");

  // (4) The mirror part: reflected nodes, reversed faces, sewn onto B'.
  std::vector<NodeIdx> to(m.nodes.slots.capacity());
  std::vector<char> mapped(m.nodes.slots.capacity(), 0);
  for (std::size_t i = 0; i < n; ++i) to[B[i].value] = map[i], mapped[B[i].value] = 1;
  const SurfaceIdx ms = m.nodes.surface[map[0].value];
  std::vector<char> old_mirror(m.nodes.slots.capacity(), 1);  // every node now but the mirror part's
  for (NodeIdx v : part) {
    const NodeIdx w = m.new_node(ms, refl(m.position(v)));
    if (w.value >= old_mirror.size()) old_mirror.resize(w.value + 1, 1);
    old_mirror[w.value] = 0;
    to[v.value] = w, mapped[v.value] = 1;
  }
  std::vector<FaceIdx> faces;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f)
    if (m.alive(FaceIdx{f}) && !(f < ro.old_face.size() && ro.old_face[f])) faces.push_back(FaceIdx{f});
  std::vector<NodeIdx> fn;
  std::vector<HalfedgeIdx> cyc;
  for (FaceIdx f : faces) {
    m.face_nodes(f, fn);
    std::reverse(fn.begin(), fn.end());
    cyc.clear();
    for (std::size_t k = 0; k < fn.size(); ++k) {
      const NodeIdx a = fn[k], b = fn[(k + 1) % fn.size()];
      if (!mapped[a.value] || !mapped[b.value])
        return fail(ErrorCode::kInternal, "a face of the drawn part uses node " +
                                              std::to_string((mapped[a.value] ? b : a).value) +
                                              ", neither new nor on B");
      auto h = halfedge_for(m, to[a.value], to[b.value]);
      if (!h) return mirror_fail(h.status().code(), h.status().message());
      cyc.push_back(*h);
    }
    (void)m.new_face(ms, cyc);
  }
  rep.mirrored = true;
  rep.mirror_base = map;
  rep.mirror_nodes = part.size();
  rep.mirror_faces = faces.size();
  rep.nodes_added += part.size();
  rep.faces_added += faces.size();
  m.complex_holes = count_topology(m).implied_holes();

  // (5) Body, surfaces, checks.
  if (opt.body) {
    std::vector<char> pushed;
    push_out(m, old_mirror, *opt.body, opt.clearance, opt.push_rounds, pushed);
    for (NodeIdx v : new_nodes(m, old_mirror)) {
      rep.pushed += v.value < pushed.size() && pushed[v.value];
      const double d = opt.body->query(m.position(v)).distance;
      rep.min_body_distance = std::min(rep.min_body_distance, d);
      rep.inside_after += d < 0;
    }
  }
  rep.volume_change = signed_volume(m) - volume_before;
  if (opt.as_surface) {
    if (Status s = split_off(m, B, rep.base_ring, rep, ctx); !s) return fail(s.code(), "drawn side: " + s.message());
    // split_off takes the part on the side of base[0] -> base[1]: B' runs
    // the other way round.
    std::vector<NodeIdx> back(map.rbegin(), map.rend());
    ExtrudeReport mr;
    if (Status s = split_off(m, back, rep.base_ring, mr, ctx); !s) return mirror_fail(s.code(), s.message());
    rep.mirror_part_surface = mr.part_surface;
    rep.mirror_joints = mr.joints;
  }
  if (Status s = validate(m); !s)
    return fail(ErrorCode::kInternal, "the mirrored result does not validate: " + s.message());
  return rep;
}

}  // namespace atelier::extrude_detail
