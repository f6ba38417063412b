// Pattern pieces from flattened surfaces: sew and cut lines, allowances,
// notches, grain lines, mirrored pieces, and the seams' sewability check
// (pattern.h).
#include <atelier/systems/pattern/pattern.h>

#include <algorithm>
#include <cmath>
#include <map>

#include <atelier/storage/mesh_edge_chain.h>

#include "flatten_detail.h"

namespace atelier {

using pattern_detail::PieceTopology;

std::size_t PatternSet::failed_seams() const noexcept {
  return static_cast<std::size_t>(std::count_if(seams.begin(), seams.end(), [](const SeamCheck& c) { return !c.ok; }));
}

namespace {

[[nodiscard]] inline Vec2d left_normal(const Vec2d& d) noexcept {
  return Vec2d(-d.y(), d.x());
}

[[nodiscard]] double signed_area(const std::vector<Vec2d>& p) {
  double a = 0;
  for (std::size_t i = 0; i < p.size(); ++i) a += cross2(p[i], p[(i + 1) % p.size()]);
  return 0.5 * a;
}

/// The crossing point of segments ab and cd when they cross properly.
[[nodiscard]] bool crossing(const Vec2d& a, const Vec2d& b, const Vec2d& c, const Vec2d& d, Vec2d& x) {
  const Vec2d r = b - a, s = d - c;
  const double den = cross2(r, s);
  if (den == 0) return false;
  const double t = cross2(c - a, s) / den, u = cross2(c - a, r) / den;
  if (t <= 0 || t >= 1 || u <= 0 || u >= 1) return false;
  x = a + t * r;
  return true;
}

/// Cuts out the small loops an offset makes on curves tighter than the
/// offset: where segment i crosses a later segment j within `window`
/// segments, the points between them give way to the crossing point.
void remove_local_loops(std::vector<Vec2d>& p, bool closed, std::size_t window = 256) {
  if (p.size() < 4) return;
  if (closed) {
    // Start at the point farthest from the centroid (on the convex hull, so
    // outside every loop) and close the polyline explicitly.
    Vec2d c = Vec2d::Zero();
    for (const Vec2d& q : p) c += q;
    c /= static_cast<double>(p.size());
    std::size_t far = 0;
    for (std::size_t i = 1; i < p.size(); ++i)
      if ((p[i] - c).squaredNorm() > (p[far] - c).squaredNorm()) far = i;
    std::rotate(p.begin(), p.begin() + static_cast<std::ptrdiff_t>(far), p.end());
    p.push_back(p.front());
  }
  std::vector<Vec2d> out;
  out.reserve(p.size());
  for (std::size_t i = 0; i + 1 < p.size(); ++i) {
    out.push_back(p[i]);
    Vec2d x;
    const std::size_t last = std::min(p.size() - 1, i + window);
    for (std::size_t j = last; j >= i + 2; --j) {  // the farthest crossing removes the whole loop
      if (j + 1 >= p.size()) continue;
      if (crossing(p[i], p[i + 1], p[j], p[j + 1], x)) {
        out.push_back(x);
        i = j;  // continue from segment j (its start replaced by x)
        p[j] = x;
        break;
      }
    }
  }
  if (!closed) out.push_back(p.back());
  p = std::move(out);
}

/// Nodes of a joint member in the joint's direction, t = 0..len.
[[nodiscard]] NodeIdx member_node(const Model& m, const JointMember& mem, std::size_t t) {
  auto chain = m.mesh_edges.halfedges.row(mem.mesh_edge.value);
  const std::size_t len = chain.size();
  if (mem.positive) return t < len ? m.tail(chain[t]) : m.head(chain[len - 1]);
  return t < len ? m.head(chain[len - 1 - t]) : m.tail(chain[0]);
}

struct PieceBuild {
  PatternPiece piece;
  std::size_t index = 0;
};

}  // namespace

Expected<PatternSet> make_pattern(const Model& m, std::span<const SurfaceIdx> pieces, const PatternOptions& opt) {
  if (!(opt.units_to_mm > 0) || !std::isfinite(opt.units_to_mm) || !(opt.seam_allowance_mm >= 0) ||
      !std::isfinite(opt.seam_allowance_mm) || !std::isfinite(opt.hem_allowance_mm) || !(opt.mitre_limit >= 1) ||
      !(opt.notch_spacing_mm >= 0) || !(opt.length_tolerance_mm >= 0) || !(opt.length_tolerance_3d >= 0))
    return Status(ErrorCode::kInvalidArgument, "make_pattern: an option is out of range");
  const double k = opt.units_to_mm;
  const double hem = opt.hem_allowance_mm < 0 ? opt.seam_allowance_mm : opt.hem_allowance_mm;
  std::map<std::uint32_t, double> override_mm;
  for (const SeamAllowance& a : opt.seam_allowances) {
    if (!a.seam.valid() || !m.alive(a.seam))
      return Status(ErrorCode::kInvalidArgument, "make_pattern: a seam allowance names joint " +
                                                     std::to_string(a.seam.value) + ", not a live joint");
    if (!(a.mm >= 0) || !std::isfinite(a.mm))
      return Status(ErrorCode::kInvalidArgument,
                    "make_pattern: the allowance of seam " + std::to_string(a.seam.value) + " is out of range");
    override_mm[a.seam.value] = a.mm;
  }
  auto joint_of = [&](HalfedgeIdx h) {
    const MeshEdgeIdx me = m.edges.mesh_edge[edge_of(h).value];
    return me.valid() && m.alive(me) ? m.mesh_edges.joint[me.value] : JointIdx{};
  };
  auto allowance_of = [&](HalfedgeIdx h) {
    const JointIdx j = joint_of(h);
    if (!j.valid()) return hem;
    const auto it = override_mm.find(j.value);
    return it != override_mm.end() ? it->second : opt.seam_allowance_mm;
  };
  auto uv_mm = [&](NodeIdx v) { return Vec2d(k * m.nodes.uv[v.value]); };

  PatternSet set;
  std::vector<std::uint8_t> is_piece(m.surfaces.slots.capacity(), 0);
  for (SurfaceIdx s : pieces) {
    if (!s.valid() || !m.alive(s))
      return Status(ErrorCode::kStaleHandle, "make_pattern: surface " + std::to_string(s.value) + " is not alive");
    is_piece[s.value] = 1;
  }
  for (SurfaceIdx s : pieces) {
    auto topo = pattern_detail::build_topology(m, s, true, false);
    if (!topo) return topo.status();
    PatternPiece pc;
    pc.surface = s;
    pc.name = m.surfaces.name[s.value];
    for (NodeIdx v : topo->node)
      if (!m.nodes.uv[v.value].allFinite())
        return Status(ErrorCode::kDegenerate, "make_pattern: surface '" + pc.name + "' has a non-finite uv at node " +
                                                  std::to_string(v.value) + " (flatten it first)");
    // Boundary loops as faceless halfedge chains: the piece lies to their
    // right, so the outward normal of each edge is its left normal.
    for (const auto& hs : topo->loop_halfedges) {
      const std::size_t n = hs.size();
      std::vector<Vec2d> P(n), N(n);
      std::vector<double> w(n);
      for (std::size_t i = 0; i < n; ++i) P[i] = uv_mm(m.tail(hs[i]));
      for (std::size_t i = 0; i < n; ++i) {
        const Vec2d d = P[(i + 1) % n] - P[i];
        N[i] = d.norm() > 0 ? Vec2d(left_normal(d).normalized()) : Vec2d::Zero();
        w[i] = allowance_of(hs[i]);
      }
      // corner[i]: the cut-line point(s) at P[i], between edges i-1 and i.
      std::vector<std::vector<Vec2d>> corner(n);
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t a = (i + n - 1) % n;
        const Vec2d A = P[i] + w[a] * N[a], B = P[i] + w[i] * N[i];
        const double det = cross2(N[a], N[i]);
        if (std::abs(det) < 1e-12) {
          corner[i] = (A - B).norm() < 1e-12 ? std::vector<Vec2d>{A} : std::vector<Vec2d>{A, B};
          continue;
        }
        // Mitre: n_a . X = n_a . P + w_a and n_i . X = n_i . P + w_i.
        Eigen::Matrix2d M;
        M << N[a].x(), N[a].y(), N[i].x(), N[i].y();
        const Vec2d X = M.inverse() * Vec2d(N[a].dot(P[i]) + w[a], N[i].dot(P[i]) + w[i]);
        if ((X - P[i]).norm() > opt.mitre_limit * std::max(w[a], w[i]) + 1e-12)
          corner[i] = {A, B};  // bevel
        else
          corner[i] = {X};
      }
      std::vector<Vec2d> cut;
      for (const auto& c : corner) cut.insert(cut.end(), c.begin(), c.end());
      // Runs of one allowance owner (a seam member's mesh edge, or a hem).
      auto owner = [&](std::size_t i) { return m.edges.mesh_edge[edge_of(hs[i]).value].value; };
      std::size_t start = 0;
      while (start < n && owner(start) == owner((start + n - 1) % n)) ++start;
      const bool single = start == n;
      if (single) start = 0;
      for (std::size_t done = 0; done < n;) {
        std::size_t len = 1;
        while (len < n && owner((start + len) % n) == owner(start) && !(single && len == n)) ++len;
        AllowanceRun run;
        run.seam = joint_of(hs[start]);
        run.loop = pc.sew_line.size();
        run.width_mm = w[start];
        run.edge.push_back(corner[start].back());
        for (std::size_t q = 1; q < len; ++q)
          for (const Vec2d& c : corner[(start + q) % n]) run.edge.push_back(c);
        run.edge.push_back(corner[(start + len) % n].front());
        remove_local_loops(run.edge, false);
        pc.allowances.push_back(std::move(run));
        done += len;
        start = (start + len) % n;
      }
      remove_local_loops(cut, true);
      pc.sew_line.push_back(std::move(P));
      pc.cut_line.push_back(std::move(cut));
    }
    // Outer loop first, every loop reversed so the outer one runs CCW.
    std::size_t outer = 0;
    for (std::size_t l = 1; l < pc.sew_line.size(); ++l)
      if (std::abs(signed_area(pc.sew_line[l])) > std::abs(signed_area(pc.sew_line[outer]))) outer = l;
    if (outer != 0) {
      std::swap(pc.sew_line[0], pc.sew_line[outer]);
      std::swap(pc.cut_line[0], pc.cut_line[outer]);
      for (AllowanceRun& r : pc.allowances) r.loop = r.loop == 0 ? outer : r.loop == outer ? 0 : r.loop;
    }
    for (auto& l : pc.sew_line) std::reverse(l.begin(), l.end());
    for (auto& l : pc.cut_line) std::reverse(l.begin(), l.end());
    for (AllowanceRun& r : pc.allowances) std::reverse(r.edge.begin(), r.edge.end());
    // Area centroid of the outer sew line, grain line and label.
    const auto& O = pc.sew_line[0];
    double A = 0;
    Vec2d C = Vec2d::Zero();
    for (std::size_t i = 0; i < O.size(); ++i) {
      const Vec2d &p = O[i], &q = O[(i + 1) % O.size()];
      const double c = cross2(p, q);
      A += c;
      C += c * (p + q);
    }
    A *= 0.5;
    C /= 6 * A;
    pc.area_mm2 = A;
    for (std::size_t l = 1; l < pc.sew_line.size(); ++l) pc.area_mm2 += signed_area(pc.sew_line[l]);
    double lo = O[0].y(), hi = O[0].y();
    for (const Vec2d& p : O) lo = std::min(lo, p.y()), hi = std::max(hi, p.y());
    pc.grain_line = {Vec2d(C.x(), lo + 0.15 * (hi - lo)), Vec2d(C.x(), hi - 0.15 * (hi - lo))};
    pc.label_at = C;
    set.pieces.push_back(std::move(pc));
  }
  std::vector<std::size_t> piece_of(m.surfaces.slots.capacity(), SIZE_MAX);
  for (std::size_t i = 0; i < set.pieces.size(); ++i) piece_of[set.pieces[i].surface.value] = i;

  // Seams: joints with at least two members on the pieces.
  for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
    if (!m.alive(JointIdx{j})) continue;
    auto members = m.joints.members.row(j);
    std::vector<JointMember> on;
    for (const JointMember& mem : members)
      if (is_piece[m.mesh_edges.surface[mem.mesh_edge.value].value]) on.push_back(mem);
    if (on.size() < 2) continue;
    SeamCheck chk;
    chk.joint = JointIdx{j};
    struct Walk {
      std::vector<double> a2, a3;  // cumulative 2D (mm) and 3D (mm) arc length, t = 0..len
    };
    std::vector<Walk> walks(on.size());
    std::vector<double> fractions{0.0, 1.0};
    for (std::size_t q = 0; q < on.size(); ++q) {
      const JointMember& mem = on[q];
      const std::size_t len = m.mesh_edges.halfedges.size(mem.mesh_edge.value);
      Walk& wk = walks[q];
      wk.a2.assign(1, 0.0);
      wk.a3.assign(1, 0.0);
      bool boundary = true;
      for (std::size_t t = 0; t < len; ++t) {
        const NodeIdx a = member_node(m, mem, t), b = member_node(m, mem, t + 1);
        wk.a2.push_back(wk.a2.back() + (uv_mm(b) - uv_mm(a)).norm());
        wk.a3.push_back(wk.a3.back() + k * (m.position(b) - m.position(a)).norm());
        const HalfedgeIdx h = joint_member_halfedge(m, mem, t);
        boundary = boundary && (!m.face(h).valid() || !m.face(twin(h)).valid());
      }
      SeamMemberLength ml;
      ml.surface = m.mesh_edges.surface[mem.mesh_edge.value];
      ml.mesh_edge = mem.mesh_edge;
      ml.boundary = boundary;
      ml.length_2d_mm = wk.a2.back();
      ml.length_3d_mm = wk.a3.back();
      chk.members.push_back(ml);
      // Marks: attribute nodes on this member's nodes or edges.
      const double L3 = wk.a3.back();
      if (!(L3 > 0)) continue;
      std::map<std::uint32_t, std::size_t> node_t, half_t;  // member node / halfedge -> t
      for (std::size_t t = 0; t <= len; ++t) node_t[member_node(m, mem, t).value] = t;
      for (std::size_t t = 0; t < len; ++t) half_t[edge_of(joint_member_halfedge(m, mem, t)).value] = t;
      for (std::uint32_t an = 0; an < m.attrib_nodes.slots.capacity(); ++an) {
        // A mark stands alone: points of an attribute edge (profiles) are not marks.
        if (!m.alive(AttribNodeIdx{an}) || m.attrib_nodes.owner[an].valid()) continue;
        const std::uint32_t el = m.attrib_nodes.element[an];
        if (m.attrib_nodes.kind[an] == AttribNodeKind::kVertex) {
          if (auto it = node_t.find(el); it != node_t.end()) fractions.push_back(wk.a3[it->second] / L3);
        } else if (m.attrib_nodes.kind[an] == AttribNodeKind::kEdge) {
          if (auto it = half_t.find(el >> 1); it != half_t.end()) {
            const std::size_t t = it->second;
            const double u = m.attrib_nodes.param[an].x();
            const double along = el == joint_member_halfedge(m, mem, t).value ? u : 1 - u;
            fractions.push_back((wk.a3[t] + along * (wk.a3[t + 1] - wk.a3[t])) / L3);
          }
        }
      }
    }
    for (std::size_t a = 0; a < chk.members.size(); ++a) {
      const SeamMemberLength& x = chk.members[a];
      if (x.length_3d_mm > 0)
        chk.max_deviation_3d =
            std::max(chk.max_deviation_3d, std::abs(x.length_2d_mm - x.length_3d_mm) / x.length_3d_mm);
      for (std::size_t b = a + 1; b < chk.members.size(); ++b)
        chk.max_difference_mm = std::max(chk.max_difference_mm, std::abs(x.length_2d_mm - chk.members[b].length_2d_mm));
    }
    chk.ok = chk.max_difference_mm <= opt.length_tolerance_mm && chk.max_deviation_3d <= opt.length_tolerance_3d;
    // Notch fractions: ends, marks, spacing; sorted, without near-duplicates.
    const double L3 = walks[0].a3.back();
    if (opt.notch_spacing_mm > 0 && L3 > 0)
      for (double s = opt.notch_spacing_mm; s < L3 - 1e-9; s += opt.notch_spacing_mm) fractions.push_back(s / L3);
    std::sort(fractions.begin(), fractions.end());
    fractions.erase(
        std::unique(fractions.begin(), fractions.end(), [](double x, double y) { return std::abs(x - y) < 1e-9; }),
        fractions.end());
    for (std::size_t q = 0; q < on.size(); ++q) {
      if (!chk.members[q].boundary) continue;
      const JointMember& mem = on[q];
      PatternPiece& pc = set.pieces[piece_of[chk.members[q].surface.value]];
      const Walk& wk = walks[q];
      const std::size_t len = wk.a2.size() - 1;
      const double L2 = wk.a2.back();
      for (double f : fractions) {
        const double s = std::clamp(f, 0.0, 1.0) * L2;
        std::size_t t = static_cast<std::size_t>(std::upper_bound(wk.a2.begin(), wk.a2.end(), s) - wk.a2.begin());
        t = std::clamp<std::size_t>(t, 1, len) - 1;
        const Vec2d pa = uv_mm(member_node(m, mem, t)), pb = uv_mm(member_node(m, mem, t + 1));
        const double seg = wk.a2[t + 1] - wk.a2[t];
        const double u = seg > 0 ? std::clamp((s - wk.a2[t]) / seg, 0.0, 1.0) : 0.0;
        const HalfedgeIdx h = joint_member_halfedge(m, mem, t);
        const HalfedgeIdx open = m.face(h).valid() ? twin(h) : h;
        const Vec2d d = uv_mm(m.head(open)) - uv_mm(m.tail(open));
        PatternNotch nt;
        nt.at = pa + u * (pb - pa);
        nt.outward = d.norm() > 0 ? Vec2d(left_normal(d).normalized()) : Vec2d::Zero();
        nt.depth = allowance_of(open);
        nt.seam = JointIdx{j};
        nt.fraction = f;
        pc.notches.push_back(nt);
      }
    }
    set.seams.push_back(std::move(chk));
  }

  // Mirrored copies: u -> -u, back to u >= 0; loops reversed to keep their
  // orientation.
  for (SurfaceIdx s : opt.mirror) {
    if (!s.valid() || s.value >= piece_of.size() || piece_of[s.value] == SIZE_MAX) continue;
    PatternPiece mp = set.pieces[piece_of[s.value]];
    mp.mirrored = true;
    mp.name += " (mirrored)";
    double lo = std::numeric_limits<double>::infinity();
    for (const Vec2d& p : mp.sew_line[0]) lo = std::min(lo, -p.x());
    auto flip = [&](Vec2d& p) { p.x() = -p.x() - lo; };
    for (auto* loops : {&mp.sew_line, &mp.cut_line})
      for (auto& l : *loops) {
        for (Vec2d& p : l) flip(p);
        std::reverse(l.begin(), l.end());
      }
    for (AllowanceRun& r : mp.allowances) {
      for (Vec2d& p : r.edge) flip(p);
      std::reverse(r.edge.begin(), r.edge.end());
    }
    for (PatternNotch& nt : mp.notches) {
      flip(nt.at);
      nt.outward.x() = -nt.outward.x();
    }
    for (Vec2d& p : mp.grain_line) flip(p);
    flip(mp.label_at);
    set.pieces.push_back(std::move(mp));
  }
  return set;
}

}  // namespace atelier
