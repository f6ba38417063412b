#include <atelier/systems/mesh/triangulate.h>

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <deque>
#include <limits>
#include <sstream>

#include <atelier/storage/mesh_edge_chain.h>

namespace atelier {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K>;
using Fbi = CGAL::Triangulation_face_base_with_info_2<int, K>;
using Fb = CGAL::Constrained_triangulation_face_base_2<K, Fbi>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
// Crossing constraints are refused (they would need constructed points).
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::No_constraint_intersection_tag>;

template <class... A>
Status fail(ErrorCode c, const A&... parts) {
  std::ostringstream s;
  (s << ... << parts);
  return {c, s.str()};
}

/// Areal coordinates of p's projection on the plane of (a, b, c); NaN-free
/// only for non-degenerate triangles (caller checks `ok`).
Vec3d barycentric(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c, bool& ok) {
  const Vec3d e1 = b - a, e2 = c - a, d = p - a;
  const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2);
  const double det = d11 * d22 - d12 * d12;
  ok = det > 1e-24 * d11 * d22 && det > 0;
  if (!ok) return Vec3d::Zero();
  const double r1 = d.dot(e1), r2 = d.dot(e2);
  const double s = (d22 * r1 - d12 * r2) / det, t = (d11 * r2 - d12 * r1) / det;
  return {1 - s - t, s, t};
}

/// Puts face node `a` at position p into the fan triangle (of the candidate
/// faces) holding it best (largest smallest coordinate), clamped to convex.
void relocate_face_node(Model& m, AttribNodeIdx a, const Vec3d& p, std::span<const FaceIdx> candidates) {
  double best = -std::numeric_limits<double>::infinity();
  FaceIdx bf;
  std::uint8_t bc = 0;
  Vec3d bb = Vec3d::Zero();
  std::vector<NodeIdx> c;
  for (FaceIdx f : candidates) {
    m.face_nodes(f, c);
    for (std::size_t k = 0; k + 2 < c.size(); ++k) {
      bool ok = false;
      const Vec3d b = barycentric(p, m.position(c[0]), m.position(c[k + 1]), m.position(c[k + 2]), ok);
      if (ok && b.minCoeff() > best) {
        best = b.minCoeff();
        bf = f;
        bc = static_cast<std::uint8_t>(k);
        bb = b;
      }
    }
  }
  if (!bf.valid()) return;
  bb = bb.cwiseMax(0.0);
  bb /= bb.sum();
  auto& an = m.attrib_nodes;
  an.element[a.value] = bf.value;
  an.corner[a.value] = bc;
  an.param[a.value] = bb;
}

/// Splits halfedge h at node x: h keeps its tail and ends at x; the returned
/// new halfedge runs x -> old head(h). Both faces, the mesh edge chain and
/// the edge flags follow.
HalfedgeIdx split_side(Model& m, HalfedgeIdx h, NodeIdx x) {
  const HalfedgeIdx t = twin(h);
  const NodeIdx b = m.head(h);
  const FaceIdx f1 = m.face(h), f2 = m.face(t);
  const HalfedgeIdx n1 = m.next(h), p2 = m.prev(t);
  const EdgeIdx e = edge_of(h);
  m.set_tail(t, x);
  const EdgeIdx e2 = m.new_edge(x, b);
  const HalfedgeIdx g = halfedge_of(e2, 0), gt = halfedge_of(e2, 1);
  if (f1.valid()) {
    m.halfedges.face[g.value] = f1;
    m.link_face(h, g);
    m.link_face(g, n1);
  }
  if (f2.valid()) {
    m.halfedges.face[gt.value] = f2;
    m.link_face(p2, gt);
    m.link_face(gt, t);
  }
  m.edges.flags[e2.value] = m.edges.flags[e.value];
  chain_split_edge(m, h, g);
  return g;
}

struct Point {
  NodeIdx node;  // existing node, or invalid until created
  Vec3d position;
};

/// Everything decided before the model is touched.
struct Plan {
  FaceIdx face;
  SurfaceIdx surface;
  std::uint8_t flags = 0;
  std::vector<HalfedgeIdx> sides;
  std::vector<Point> points;                         // corners first
  std::vector<std::vector<std::uint32_t>> along;     // per side: new points in order
  std::vector<std::uint32_t> boundary;               // point ids around the polygon
  std::vector<std::pair<AttribNodeIdx, std::uint32_t>> converted;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<FaceIdx> neighbours;                   // faces gaining corners
  /// Joint partners of split sides: partner halfedge (running like the side)
  /// and the points to insert along it, in order.
  std::vector<std::pair<HalfedgeIdx, std::vector<std::uint32_t>>> partner_splits;
  std::vector<std::pair<AttribNodeIdx, Vec3d>> relocate_in_neighbours;
  std::vector<std::pair<AttribNodeIdx, Vec3d>> relocate_in_face;  // non-converting mode
};

struct FaceAttribs {
  std::vector<AttribNodeIdx> face_nodes, edge_nodes, vertex_nodes;
};

/// Attribute nodes touching face f (one scan of the attribute table).
FaceAttribs gather_attribs(const Model& m, FaceIdx f, const std::vector<HalfedgeIdx>& sides) {
  FaceAttribs r;
  const auto& an = m.attrib_nodes;
  auto on_side = [&](std::uint32_t e) {
    for (HalfedgeIdx h : sides)
      if (edge_of(h).value == e) return true;
    return false;
  };
  auto is_corner = [&](std::uint32_t v) {
    for (HalfedgeIdx h : sides)
      if (m.tail(h).value == v) return true;
    return false;
  };
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i) {
    if (!m.alive(AttribNodeIdx{i})) continue;
    switch (an.kind[i]) {
      case AttribNodeKind::kFace:
        if (an.element[i] == f.value) r.face_nodes.push_back(AttribNodeIdx{i});
        break;
      case AttribNodeKind::kEdge:
        if (on_side(an.element[i] >> 1)) r.edge_nodes.push_back(AttribNodeIdx{i});
        break;
      case AttribNodeKind::kVertex:
        if (is_corner(an.element[i])) r.vertex_nodes.push_back(AttribNodeIdx{i});
        break;
    }
  }
  return r;
}

Expected<Plan> make_plan(const Model& m, FaceIdx f, bool convert, const TriangulateOptions& opt,
                         const std::vector<AttribNodeIdx>* face_nodes_hint) {
  Plan P;
  P.face = f;
  P.surface = m.faces.surface[f.value];
  P.flags = m.faces.flags[f.value];
  m.face_halfedges(f, P.sides);
  const std::size_t n = P.sides.size();
  for (HalfedgeIdx h : P.sides) P.points.push_back({m.tail(h), m.position(m.tail(h))});
  double diam = 0;
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t j = k + 1; j < n; ++j) diam = std::max(diam, (P.points[k].position - P.points[j].position).norm());
  const double tol = opt.merge_tolerance * diam;
  P.along.resize(n);

  FaceAttribs fa;
  if (convert) {
    fa = gather_attribs(m, f, P.sides);
  } else if (face_nodes_hint) {
    fa.face_nodes = *face_nodes_hint;
  } else {
    fa.face_nodes = gather_attribs(m, f, P.sides).face_nodes;
  }
  std::vector<std::pair<AttribNodeIdx, std::uint32_t>>& pid = P.converted;  // attribute -> point
  auto find_near = [&](const Vec3d& p) -> std::int64_t {
    for (std::size_t i = 0; i < P.points.size(); ++i)
      if ((P.points[i].position - p).norm() <= tol) return static_cast<std::int64_t>(i);
    return -1;
  };

  if (convert) {
    // Edge nodes: sorted along their side, merged with corners and each other.
    for (std::size_t k = 0; k < n; ++k) {
      std::vector<std::pair<double, AttribNodeIdx>> on;
      for (AttribNodeIdx a : fa.edge_nodes) {
        const HalfedgeIdx h{m.attrib_nodes.element[a.value]};
        if (edge_of(h) != edge_of(P.sides[k])) continue;
        const double u = m.attrib_nodes.param[a.value].x();
        on.emplace_back(h == P.sides[k] ? u : 1 - u, a);
      }
      if (on.empty()) continue;
      std::sort(on.begin(), on.end(), [](const auto& x, const auto& y) {
        return x.first != y.first ? x.first < y.first : x.second < y.second;
      });
      for (const auto& [u, a] : on) {
        const Vec3d p = m.attrib_position_on_surface(a);
        std::int64_t id = find_near(p);
        if (id < 0) {
          id = static_cast<std::int64_t>(P.points.size());
          P.points.push_back({NodeIdx{}, p});
          P.along[k].push_back(static_cast<std::uint32_t>(id));
        }
        pid.emplace_back(a, static_cast<std::uint32_t>(id));
      }
      auto add_neighbour = [&](FaceIdx g) {
        if (g.valid() && g != f && std::find(P.neighbours.begin(), P.neighbours.end(), g) == P.neighbours.end())
          P.neighbours.push_back(g);
      };
      if (P.along[k].empty()) continue;
      add_neighbour(m.face(twin(P.sides[k])));
      // Joint: every member gets the same split (seed 000 section 3, "face
      // split": the corresponding TRGLEDGEs of the MESHJOINT get the same
      // stand-alone vertices), so lengths stay equal and nodes coincide.
      const EdgeIdx e = edge_of(P.sides[k]);
      const MeshEdgeIdx me = m.edges.mesh_edge[e.value];
      const JointIdx j = me.valid() ? m.mesh_edges.joint[me.value] : JointIdx{};
      if (!j.valid()) continue;
      const auto members = m.joints.members.row(j.value);
      const auto chain = m.mesh_edges.halfedges.row(me.value);
      const std::size_t len = chain.size();
      std::size_t i = 0;
      while (edge_of(chain[i]) != e) ++i;
      bool pa = true;
      for (const JointMember& jm : members)
        if (jm.mesh_edge == me) pa = jm.positive;
      const bool along_joint = (chain[i] == P.sides[k]) == pa;
      const std::size_t t = pa ? i : len - 1 - i;
      for (const JointMember& jm : members) {
        if (jm.mesh_edge == me) continue;
        const auto pc = m.mesh_edges.halfedges.row(jm.mesh_edge.value);
        const HalfedgeIdx d = pc[jm.positive ? t : len - 1 - t];
        const HalfedgeIdx jd = jm.positive ? d : twin(d);
        const HalfedgeIdx hp = along_joint ? jd : twin(jd);
        for (std::uint32_t x = 0; x < m.attrib_nodes.slots.capacity(); ++x)
          if (m.alive(AttribNodeIdx{x}) && m.attrib_nodes.kind[x] == AttribNodeKind::kEdge &&
              edge_of(HalfedgeIdx{m.attrib_nodes.element[x]}) == edge_of(hp))
            return fail(ErrorCode::kJointRefused, "face ", f.value, ": joint ", j.value, " partner edge ",
                        edge_of(hp).value, " carries attribute edge-nodes of its own; triangulate its face first");
        P.partner_splits.emplace_back(hp, P.along[k]);
        add_neighbour(m.face(hp));
        add_neighbour(m.face(twin(hp)));
      }
    }
    for (AttribNodeIdx a : fa.vertex_nodes)
      for (std::uint32_t k = 0; k < n; ++k)
        if (P.points[k].node.value == m.attrib_nodes.element[a.value]) pid.emplace_back(a, k);
  }
  for (std::size_t k = 0; k < n; ++k) {
    P.boundary.push_back(static_cast<std::uint32_t>(k));
    P.boundary.insert(P.boundary.end(), P.along[k].begin(), P.along[k].end());
  }
  const std::size_t B = P.boundary.size();
  if (convert) {
    for (AttribNodeIdx a : fa.face_nodes) {
      const Vec3d p = m.attrib_position_on_surface(a);
      std::int64_t id = find_near(p);
      if (id < 0) {
        id = static_cast<std::int64_t>(P.points.size());
        P.points.push_back({NodeIdx{}, p});
      }
      pid.emplace_back(a, static_cast<std::uint32_t>(id));
    }
  } else {
    for (AttribNodeIdx a : fa.face_nodes) P.relocate_in_face.emplace_back(a, m.attrib_position_on_surface(a));
  }
  for (FaceIdx g : P.neighbours)
    for (std::uint32_t i = 0; i < m.attrib_nodes.slots.capacity(); ++i)
      if (m.alive(AttribNodeIdx{i}) && m.attrib_nodes.kind[i] == AttribNodeKind::kFace && m.attrib_nodes.element[i] == g.value)
        P.relocate_in_neighbours.emplace_back(AttribNodeIdx{i}, m.attrib_position_on_surface(AttribNodeIdx{i}));

  // Constraint segments: consecutive nodes of an attribute edge, both in the face.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> constraints;
  std::sort(pid.begin(), pid.end());
  auto point_of = [&](AttribNodeIdx a) -> std::int64_t {
    auto it = std::lower_bound(pid.begin(), pid.end(), std::make_pair(a, std::uint32_t{0}));
    return it != pid.end() && it->first == a ? static_cast<std::int64_t>(it->second) : -1;
  };
  for (const auto& [a, p] : pid) {
    const AttribEdgeIdx o = m.attrib_nodes.owner[a.value];
    if (!o.valid()) continue;
    auto row = m.attrib_edges.nodes.row(o.value);
    for (std::size_t j = 0; j + 1 < row.size(); ++j) {
      if (row[j] != a) continue;
      const std::int64_t q = point_of(row[j + 1]);
      if (q >= 0 && q != p) constraints.emplace_back(std::min<std::uint32_t>(p, q), std::max<std::uint32_t>(p, q));
    }
  }
  std::sort(constraints.begin(), constraints.end());
  constraints.erase(std::unique(constraints.begin(), constraints.end()), constraints.end());

  // Least-squares plane of the boundary, oriented by the Newell normal.
  Vec3d c = Vec3d::Zero(), newell = Vec3d::Zero();
  for (std::uint32_t b : P.boundary) c += P.points[b].position;
  c /= static_cast<double>(B);
  Mat3d cov = Mat3d::Zero();
  for (std::size_t k = 0; k < B; ++k) {
    const Vec3d d = P.points[P.boundary[k]].position - c;
    cov += d * d.transpose();
    newell += P.points[P.boundary[k]].position.cross(P.points[P.boundary[(k + 1) % B]].position);
  }
  if (!(newell.norm() > 0) || !newell.allFinite())
    return fail(ErrorCode::kDegenerate, "face ", f.value, " has no area (no plane to triangulate in)");
  Eigen::SelfAdjointEigenSolver<Mat3d> eig(cov);
  Vec3d nrm = eig.eigenvectors().col(0);
  if (nrm.dot(newell) < 0) nrm = -nrm;
  const Vec3d axis = std::abs(nrm.x()) < 0.6 ? Vec3d::UnitX() : Vec3d::UnitY();
  const Vec3d ux = nrm.cross(axis).normalized(), uy = nrm.cross(ux);  // ux x uy = nrm: CCW kept

  Cdt cdt;
  std::vector<Cdt::Vertex_handle> vh(P.points.size());
  for (std::size_t i = 0; i < P.points.size(); ++i) {
    const Vec3d d = P.points[i].position - c;
    const std::size_t before = cdt.number_of_vertices();
    vh[i] = cdt.insert(K::Point_2(d.dot(ux), d.dot(uy)));
    if (cdt.number_of_vertices() == before)
      return fail(ErrorCode::kDegenerate, "face ", f.value, ": two points project onto the same place in its plane");
    vh[i]->info() = static_cast<std::uint32_t>(i);
  }
  std::vector<std::int64_t> bpos(P.points.size(), -1);
  for (std::size_t k = 0; k < B; ++k) bpos[P.boundary[k]] = static_cast<std::int64_t>(k);
  try {
    for (std::size_t k = 0; k < B; ++k) cdt.insert_constraint(vh[P.boundary[k]], vh[P.boundary[(k + 1) % B]]);
    for (const auto& [a, b] : constraints) cdt.insert_constraint(vh[a], vh[b]);
  } catch (const std::exception&) {
    return fail(ErrorCode::kDegenerate, "face ", f.value,
                ": constraints cross (self-intersecting boundary in its plane, or crossing attribute edges)");
  }
  auto is_side = [&](std::uint32_t a, std::uint32_t b) {
    const std::int64_t pa = bpos[a], pb = bpos[b];
    if (pa < 0 || pb < 0) return false;
    return (pa + 1) % static_cast<std::int64_t>(B) == pb || (pb + 1) % static_cast<std::int64_t>(B) == pa;
  };
  // Outside = reachable from the infinite face without crossing a side.
  for (auto fh = cdt.all_faces_begin(); fh != cdt.all_faces_end(); ++fh) fh->info() = 1;
  std::deque<Cdt::Face_handle> queue{cdt.infinite_face()};
  cdt.infinite_face()->info() = 0;
  while (!queue.empty()) {
    const Cdt::Face_handle fh = queue.front();
    queue.pop_front();
    for (int i = 0; i < 3; ++i) {
      const Cdt::Face_handle g = fh->neighbor(i);
      if (g->info() == 0) continue;
      const bool crosses_side = !cdt.is_infinite(fh->vertex(Cdt::cw(i))) && !cdt.is_infinite(fh->vertex(Cdt::ccw(i))) &&
                                is_side(fh->vertex(Cdt::cw(i))->info(), fh->vertex(Cdt::ccw(i))->info());
      if (crosses_side) continue;
      g->info() = 0;
      queue.push_back(g);
    }
  }
  for (auto fh = cdt.finite_faces_begin(); fh != cdt.finite_faces_end(); ++fh) {
    if (fh->info() != 1) continue;
    std::array<std::uint32_t, 3> t = {fh->vertex(0)->info(), fh->vertex(1)->info(), fh->vertex(2)->info()};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    P.triangles.push_back(t);
  }
  std::sort(P.triangles.begin(), P.triangles.end());
  const std::size_t interior = P.points.size() - B;
  if (P.triangles.size() != B - 2 + 2 * interior)
    return fail(ErrorCode::kDegenerate, "face ", f.value, ": ", P.triangles.size(), " triangles inside instead of ",
                B - 2 + 2 * interior, " (a point lies outside the face or on its boundary)");
  for (const auto& t : P.triangles) {
    const Vec3d& a = P.points[t[0]].position;
    const Vec3d tn = (P.points[t[1]].position - a).cross(P.points[t[2]].position - a);
    if (!(tn.dot(nrm) > 0))
      return fail(ErrorCode::kDegenerate, "face ", f.value, ": a triangle would be flipped against the face normal");
    // A diagonal between two existing nodes must not duplicate an edge outside the face.
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t x = t[k], y = t[(k + 1) % 3];
      if (x < n && y < n && !is_side(x, y) && m.find_halfedge(P.points[x].node, P.points[y].node).valid())
        return fail(ErrorCode::kTopology, "face ", f.value, ": diagonal ", P.points[x].node.value, "-",
                    P.points[y].node.value, " would duplicate an existing edge");
    }
  }
  return P;
}

void apply_plan(Model& m, Plan& P, TriangulationResult& out) {
  for (Point& p : P.points)
    if (!p.node.valid()) {
      p.node = m.new_node(P.surface, p.position);
      out.new_nodes.push_back(p.node);
    }
  for (std::size_t k = 0; k < P.sides.size(); ++k) {
    HalfedgeIdx h = P.sides[k];
    for (std::uint32_t id : P.along[k]) h = split_side(m, h, P.points[id].node);
  }
  for (const auto& [hp, ids] : P.partner_splits) {
    const SurfaceIdx ps = m.surface_of(edge_of(hp));
    HalfedgeIdx h = hp;
    for (std::uint32_t id : ids) {
      const NodeIdx x = m.new_node(ps, P.points[id].position);
      out.new_nodes.push_back(x);
      h = split_side(m, h, x);
    }
  }
  m.delete_face(P.face);
  std::vector<FaceIdx> made;
  for (const auto& t : P.triangles) {
    std::array<HalfedgeIdx, 3> cyc;
    for (int k = 0; k < 3; ++k) {
      const NodeIdx a = P.points[t[k]].node, b = P.points[t[(k + 1) % 3]].node;
      HalfedgeIdx h = m.find_halfedge(a, b);
      if (!h.valid()) h = halfedge_of(m.new_edge(a, b), 0);
      cyc[k] = h;
    }
    const FaceIdx nf = m.new_face(P.surface, cyc);
    m.faces.flags[nf.value] = P.flags;
    made.push_back(nf);
  }
  auto& an = m.attrib_nodes;
  for (const auto& [a, id] : P.converted) {
    an.kind[a.value] = AttribNodeKind::kVertex;
    an.element[a.value] = P.points[id].node.value;
    an.param[a.value] = Vec3d::Zero();
    an.corner[a.value] = 0;
  }
  for (const auto& [a, p] : P.relocate_in_face) relocate_face_node(m, a, p, made);
  for (const auto& [a, p] : P.relocate_in_neighbours) {
    const FaceIdx g{an.element[a.value]};
    relocate_face_node(m, a, p, std::span<const FaceIdx>(&g, 1));
  }
  out.faces.insert(out.faces.end(), made.begin(), made.end());
  for (FaceIdx g : P.neighbours)
    if (std::find(out.grown_faces.begin(), out.grown_faces.end(), g) == out.grown_faces.end())
      out.grown_faces.push_back(g);
}

bool has_ring_nodes(const Model& m, FaceIdx f) {
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}) && m.nodes.in_face[v] == f) return true;
  return false;
}

Status triangulate_one(Model& m, FaceIdx f, const TriangulateOptions& opt, TriangulationResult& out) {
  if (has_ring_nodes(m, f))
    return fail(ErrorCode::kUnsupported, "face ", f.value, " holds ring nodes; remove them before triangulating it");
  auto plan = make_plan(m, f, true, opt, nullptr);
  if (!plan) return plan.status();
  apply_plan(m, *plan, out);
  return {};
}

Expected<TriangulationResult> run(Model& m, std::span<const Face> faces, const TriangulateOptions& opt) {
  TriangulationResult out;
  std::vector<Face> pending(faces.begin(), faces.end());
  for (const Face& fh : pending) {
    auto f = m.resolve(fh);
    if (!f) return f.status();
    if (Status s = triangulate_one(m, *f, opt, out); !s) return s;
  }
  if (opt.triangulate_grown) {
    std::deque<Face> queue;
    for (FaceIdx g : out.grown_faces) queue.push_back(m.handle(g));
    out.grown_faces.clear();
    while (!queue.empty()) {
      const Face g = queue.front();
      queue.pop_front();
      if (!m.alive(g) || m.face_degree(g.idx) <= 3) continue;
      TriangulationResult sub;
      if (Status s = triangulate_one(m, g.idx, opt, sub); !s) return s;
      out.faces.insert(out.faces.end(), sub.faces.begin(), sub.faces.end());
      out.new_nodes.insert(out.new_nodes.end(), sub.new_nodes.begin(), sub.new_nodes.end());
      for (FaceIdx x : sub.grown_faces) queue.push_back(m.handle(x));
    }
  }
  // Faces made by one step may have been replaced by a later one.
  std::erase_if(out.faces, [&](FaceIdx x) { return !m.alive(x) || m.face_degree(x) != 3; });
  std::sort(out.faces.begin(), out.faces.end());
  out.faces.erase(std::unique(out.faces.begin(), out.faces.end()), out.faces.end());
  std::erase_if(out.grown_faces, [&](FaceIdx x) { return !m.alive(x) || m.face_degree(x) <= 3; });
  return out;
}

}  // namespace

Expected<TriangulationResult> triangulate_face(Model& m, Face face, const TriangulateOptions& opt) {
  return run(m, std::span<const Face>(&face, 1), opt);
}

Expected<TriangulationResult> triangulate_faces(Model& m, std::span<const Face> faces, const TriangulateOptions& opt) {
  return run(m, faces, opt);
}

Expected<std::size_t> triangulate_polygons(Model& m, const ExecContext& ctx) {
  // One pass over nodes and attributes, then the polygons one by one.
  std::vector<Face> polys;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f)
    if (m.alive(FaceIdx{f}) && m.face_degree(FaceIdx{f}) > 3) polys.push_back(m.handle(FaceIdx{f}));
  std::vector<std::uint8_t> ring(m.faces.slots.capacity(), 0);
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}) && m.nodes.in_face[v].valid()) ring[m.nodes.in_face[v].value] = 1;
  std::vector<std::pair<std::uint32_t, AttribNodeIdx>> fnodes;
  for (std::uint32_t i = 0; i < m.attrib_nodes.slots.capacity(); ++i)
    if (m.alive(AttribNodeIdx{i}) && m.attrib_nodes.kind[i] == AttribNodeKind::kFace)
      fnodes.emplace_back(m.attrib_nodes.element[i], AttribNodeIdx{i});
  std::sort(fnodes.begin(), fnodes.end());
  // Planned and applied one by one: a plan checks diagonals against the
  // model as the earlier polygons left it.
  const TriangulateOptions opt;
  TriangulationResult out;
  std::size_t done = 0;
  for (const Face& fh : polys) {
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "triangulate_polygons cancelled");
    const FaceIdx f = fh.idx;
    if (ring[f.value])
      return fail(ErrorCode::kUnsupported, "face ", f.value, " holds ring nodes; remove them before triangulating it");
    std::vector<AttribNodeIdx> mine;
    for (auto it = std::lower_bound(fnodes.begin(), fnodes.end(), std::make_pair(f.value, AttribNodeIdx{0}));
         it != fnodes.end() && it->first == f.value; ++it)
      mine.push_back(it->second);
    auto plan = make_plan(m, f, false, opt, &mine);
    if (!plan) return plan.status();
    apply_plan(m, *plan, out);
    ++done;
  }
  return done;
}

}  // namespace atelier
