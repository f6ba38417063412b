// Why this file is long: cutting and partitioning share the pieces, the
// bookkeeping of attribute nodes, mesh edges and joints on removed or moved
// faces, and the snapshot that makes both transactional.
#include <atelier/engine/math.h>
#include <atelier/engine/parallel.h>
#include <atelier/engine/status_format.h>
#include <atelier/storage/bulk_remove.h>
#include <atelier/storage/topology.h>
#include <atelier/storage/union_find.h>
#include <atelier/systems/sketch/cut.h>

#include <algorithm>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <set>

namespace atelier {

namespace {

struct PieceData {
  SurfaceIdx surface;
  std::vector<FaceIdx> faces;  // increasing
  double area = 0;
  std::uint32_t comp = 0;
};

struct Pieces {
  std::vector<std::uint32_t> piece_of;   // per face slot
  std::vector<std::uint8_t> curve_edge;  // per edge slot
  std::vector<PieceData> data;           // ordered by smallest face
  std::vector<std::uint8_t> crossed_comp;
};

/// Union-find over face slots (storage/union_find.h).
using FaceSets = UnionFind;

/// Area of face f from its fan triangles (c0, c_k+1, c_k+2), summed in
/// halfedge order.
double fan_area(const Model& m, std::size_t f) {
  const HalfedgeIdx h0 = m.faces.halfedge[f];
  const Vec3d& p0 = m.position(m.tail(h0));
  HalfedgeIdx h = m.next(h0);
  double a = 0;
  for (HalfedgeIdx n = m.next(h); n != h0; h = n, n = m.next(n))
    a += 0.5 * (m.position(m.tail(h)) - p0).cross(m.position(m.tail(n)) - p0).norm();
  return a;
}

/// Pieces of the surfaces the curve edges lie in: one pass over the edges
/// (union-find), one over the faces.
Pieces find_pieces(const Model& m, const RetriangulationResult& r, const ExecContext& ctx) {
  Pieces P;
  P.curve_edge.assign(m.edges.slots.capacity(), 0);
  std::vector<std::uint8_t> touched(m.surfaces.slots.capacity(), 0);
  for (const auto& ch : r.chains)
    for (HalfedgeIdx h : ch) {
      P.curve_edge[edge_of(h).value] = 1;
      touched[m.surface_of(edge_of(h)).value] = 1;
    }
  const std::size_t nf = m.faces.slots.capacity();
  FaceSets pieces(nf), comps(nf);
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e})) continue;
    const FaceIdx f0 = m.halfedges.face[2 * e], f1 = m.halfedges.face[2 * e + 1];
    if (!f0.valid() || !f1.valid() || !touched[m.faces.surface[f0.value].value]) continue;
    comps.unite(f0.value, f1.value);
    if (!P.curve_edge[e]) pieces.unite(f0.value, f1.value);
  }
  // Face areas (fan triangles) in parallel; sums below run in face order.
  std::vector<double> area(nf, 0.0);
  par::for_each_n(ctx, nf, [&](std::size_t f) {
    if (!m.alive(FaceIdx{static_cast<std::uint32_t>(f)}) || !touched[m.faces.surface[f].value]) return;
    area[f] = fan_area(m, f);
  });
  P.piece_of.assign(nf, kNone);
  std::vector<std::uint32_t> comp_id(nf, kNone);
  std::uint32_t ncomp = 0;
  for (std::uint32_t f = 0; f < nf; ++f) {
    const FaceIdx fi{f};
    if (!m.alive(fi) || !touched[m.faces.surface[f].value]) continue;
    const std::uint32_t rp = pieces.find(f), rc = comps.find(f);
    if (rc == f) comp_id[f] = ncomp++;
    if (rp == f) {
      P.piece_of[f] = static_cast<std::uint32_t>(P.data.size());
      PieceData d;
      d.surface = m.faces.surface[f];
      d.comp = comp_id[rc];
      P.data.push_back(std::move(d));
    } else {
      P.piece_of[f] = P.piece_of[rp];
    }
    PieceData& d = P.data[P.piece_of[f]];
    d.faces.push_back(fi);  // increasing: faces are visited in index order
    d.area += area[f];
  }
  P.crossed_comp.assign(ncomp, 0);
  for (std::uint32_t e = 0; e < P.curve_edge.size(); ++e)
    if (P.curve_edge[e])
      for (unsigned s = 0; s < 2; ++s)
        if (const FaceIdx f = m.face(halfedge_of(EdgeIdx{e}, s)); f.valid())
          P.crossed_comp[P.data[P.piece_of[f.value]].comp] = 1;
  return P;
}

/// Removes attribute nodes from their attribute edges' rows and deletes
/// them; attribute edges left empty are deleted.
void delete_attrib_nodes(Model& m, const std::vector<AttribNodeIdx>& dead) {
  std::vector<std::uint8_t> is_dead(m.attrib_nodes.slots.capacity(), 0);
  std::set<AttribEdgeIdx> owners;
  for (AttribNodeIdx a : dead) {
    is_dead[a.value] = 1;
    if (m.attrib_nodes.owner[a.value].valid()) owners.insert(m.attrib_nodes.owner[a.value]);
  }
  for (AttribEdgeIdx e : owners) {
    const auto row = m.attrib_edges.nodes.row(e.value);
    std::vector<AttribNodeIdx> keep;
    for (AttribNodeIdx a : row)
      if (!is_dead[a.value]) keep.push_back(a);
    if (keep.empty()) {
      m.delete_attrib_edge(e);
    } else {
      m.attrib_edges.nodes.assign(e.value, keep);
    }
  }
  for (AttribNodeIdx a : dead) {
    m.attrib_nodes.owner[a.value] = {};
    m.delete_attrib_node(a);
  }
}

/// Replaces mesh edge `me`'s chain by the runs of its halfedges that pass
/// `keep` (one mesh edge per contiguous run, the first keeping the index);
/// the loop holding it, if any, is deleted (it no longer closes).
void trim_mesh_edge(Model& m, MeshEdgeIdx me, const std::vector<std::uint8_t>& edge_dies) {
  const auto row = m.mesh_edges.halfedges.row(me.value);
  std::vector<std::vector<HalfedgeIdx>> runs(1);
  for (HalfedgeIdx h : row) {
    if (edge_dies[edge_of(h).value]) {
      if (!runs.back().empty()) runs.emplace_back();
    } else {
      runs.back().push_back(h);
    }
  }
  if (runs.back().empty()) runs.pop_back();
  const SurfaceIdx s = m.mesh_edges.surface[me.value];
  if (const MeshLoopIdx l = m.mesh_edges.loop[me.value]; l.valid()) m.delete_mesh_loop(l);
  m.delete_mesh_edge(me);
  for (const auto& r : runs) (void)m.new_mesh_edge(s, r);
}

/// What remove_faces removed (for the Euler bookkeeping of the cut).
struct Removal {
  std::size_t faces = 0, edges = 0, nodes = 0;
  std::vector<NodeIdx> survivors;  // corners of removed faces that live on, in index order
  bool rings = false;              // the model holds ring nodes (the local count does not cover them)
};

/// Removes faces, then the edges and nodes left without faces.
Status remove_faces(Model& m, const std::vector<FaceIdx>& rm, Removal& out) {
  std::vector<std::uint8_t> gone(m.faces.slots.capacity(), 0);
  for (FaceIdx f : rm) gone[f.value] = 1;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
    const FaceIdx f = m.nodes.in_face[v];
    if (!f.valid() || !m.alive(NodeIdx{v})) continue;
    out.rings = true;
    if (gone[f.value])
      return status_of(ErrorCode::kUnsupported, "cut: face ", f.value, " to remove holds ring node ", v);
  }
  // Which edges die (both sides faceless once the faces are gone, one of
  // them a removed face), which nodes are corners of removed faces and which
  // keep an edge: one pass over the halfedge columns in memory order. (A
  // walk round each removed face read them at random: most of the removal's
  // own time on half a mesh.) The lists come out in index order.
  const std::size_t ne = m.edges.slots.capacity(), nn = m.nodes.slots.capacity();
  std::vector<std::uint8_t> edge_dies(ne, 0), corner(nn, 0), keeps(nn, 0);
  std::vector<EdgeIdx> dying;
  {
    const auto& hf = m.halfedges.face;
    const auto& tail = m.halfedges.tail;
    for (std::uint32_t e = 0; e < ne; ++e) {
      if (!m.alive(EdgeIdx{e})) continue;
      const FaceIdx f0 = hf[2 * e], f1 = hf[2 * e + 1];
      const bool g0 = f0.valid() && gone[f0.value], g1 = f1.valid() && gone[f1.value];
      const NodeIdx t0 = tail[2 * e], t1 = tail[2 * e + 1];
      if (g0) corner[t0.value] = 1;
      if (g1) corner[t1.value] = 1;
      if ((g0 || g1) && (g0 || !f0.valid()) && (g1 || !f1.valid())) {
        edge_dies[e] = 1;
        dying.push_back(EdgeIdx{e});
      } else {
        keeps[t0.value] = keeps[t1.value] = 1;
      }
    }
  }
  std::set<MeshEdgeIdx> trimmed;
  for (EdgeIdx e : dying) {
    const MeshEdgeIdx me = m.edges.mesh_edge[e.value];
    if (!me.valid()) continue;
    if (const JointIdx j = m.mesh_edges.joint[me.value]; j.valid())
      return status_of(ErrorCode::kJointRefused, "cut: the removed side holds edge ", e.value, " of mesh edge ",
                       me.value, " in joint ", j.value, " (a seam to another surface); cut elsewhere or partition");
    trimmed.insert(me);
  }
  // A corner dies when all its edges die.
  std::vector<NodeIdx> dying_nodes;
  std::vector<std::uint8_t> node_dies(nn, 0);
  for (std::uint32_t v = 0; v < nn; ++v) {
    if (!corner[v]) continue;
    if (keeps[v]) {
      out.survivors.push_back(NodeIdx{v});
    } else {
      dying_nodes.push_back(NodeIdx{v});
      node_dies[v] = 1;
    }
  }
  std::vector<AttribNodeIdx> dead_attribs;
  const auto& an = m.attrib_nodes;
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i) {
    if (!m.alive(AttribNodeIdx{i})) continue;
    const std::uint32_t el = an.element[i];
    const bool d = an.kind[i] == AttribNodeKind::kFace   ? gone[el] != 0
                   : an.kind[i] == AttribNodeKind::kEdge ? edge_dies[el >> 1] != 0
                                                         : node_dies[el] != 0;
    if (d) dead_attribs.push_back(AttribNodeIdx{i});
  }
  // Apply: mesh edges and attribute nodes first (they do not depend on the
  // faces), then faces, edges and nodes in one bulk pass.
  for (MeshEdgeIdx me : trimmed) trim_mesh_edge(m, me, edge_dies);
  delete_attrib_nodes(m, dead_attribs);
  remove_faces_bulk(m, rm, dying, dying_nodes);
  out.faces = rm.size();
  out.edges = dying.size();
  out.nodes = dying_nodes.size();
  return {};
}

/// Number of node components (over live edges) holding the given nodes:
/// one breadth-first flood from all of them at once that stops as soon as
/// they are all in one set. Cutting one piece off leaves its surviving
/// corners joined along the curve, so the flood meets within a few rings of
/// the curve; only a cut that really splits the rest explores all of it.
std::size_t components_holding(const Model& m, const std::vector<NodeIdx>& seeds) {
  if (seeds.size() <= 1) return seeds.size();
  std::vector<std::uint32_t> label(m.nodes.slots.capacity(), kNone);
  UnionFind sets(seeds.size());
  std::size_t count = seeds.size();
  std::vector<NodeIdx> queue(seeds.begin(), seeds.end());
  for (std::uint32_t i = 0; i < seeds.size(); ++i) label[seeds[i].value] = i;
  for (std::size_t q = 0; q < queue.size() && count > 1; ++q) {
    const NodeIdx v = queue[q];
    m.for_each_outgoing(v, [&](HalfedgeIdx h) {
      const NodeIdx w = m.head(h);
      std::uint32_t& lw = label[w.value];
      if (lw == kNone) {
        lw = label[v.value];
        queue.push_back(w);
      } else if (const std::uint32_t a = sets.find(lw), b = sets.find(label[v.value]); a != b) {
        sets.unite(a, b);
        --count;
      }
    });
  }
  return count;
}

/// Whether the face group (faces connected across edges) holding `piece`
/// had no boundary halfedge before the cut (a closed shell, the S of the
/// Euler-Poincare formula). `piece_open`: the piece itself has one. Cheap
/// cases first: an open piece, or no boundary edge in the whole model
/// (`known_boundary`, from the triangle rows, else one pass over a column);
/// otherwise the rest of the group is flooded from the piece's neighbours
/// until a boundary halfedge shows up.
bool group_closed(const Model& m, const std::vector<std::uint8_t>& in_piece, const std::vector<FaceIdx>& piece,
                  bool piece_open, std::optional<bool> known_boundary) {
  if (piece_open) return false;
  bool any_boundary = known_boundary.value_or(false);
  const auto& hf = m.halfedges.face;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity() && !any_boundary && !known_boundary; ++e)
    any_boundary = m.alive(EdgeIdx{e}) && (hf[2 * e].valid() != hf[2 * e + 1].valid());
  if (!any_boundary) return true;
  std::vector<std::uint8_t> seen(m.faces.slots.capacity(), 0);
  std::vector<FaceIdx> stack;
  for (FaceIdx f : piece)
    m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
      const FaceIdx o = m.face(twin(h));
      if (o.valid() && !in_piece[o.value] && !seen[o.value]) {
        seen[o.value] = 1;
        stack.push_back(o);
      }
    });
  while (!stack.empty()) {
    const FaceIdx f = stack.back();
    stack.pop_back();
    bool open = false;
    m.for_each_face_halfedge(f, [&](HalfedgeIdx h) {
      const FaceIdx o = m.face(twin(h));
      if (!o.valid()) {
        open = true;
      } else if (!in_piece[o.value] && !seen[o.value]) {
        seen[o.value] = 1;
        stack.push_back(o);
      }
    });
    if (open) return false;
  }
  return true;
}

void recount_holes(Model& m) {
  m.complex_holes = count_topology(m).implied_holes();
}

/// Restores the snapshot on every error path. The caller's tables move into
/// the snapshot (no copy) and the model is copied back into columns with
/// headroom for the re-triangulation, so that the snapshot and the growth of
/// the columns cost one copy of the tables instead of two.
struct Rollback {
  Model& m;
  Model backup;
  bool armed = true;
  explicit Rollback(Model& model) : m(model), backup(std::move(model)) {
    m = Model{};
    auto room = [](std::size_t n) { return n + n / 8 + 1024; };
    m.reserve(room(backup.nodes.slots.capacity()), room(backup.edges.slots.capacity()),
              room(backup.faces.slots.capacity()));
    m = backup;  // std::vector's copy assignment keeps the reserved capacity
  }
  ~Rollback() {
    if (armed) m = std::move(backup);
  }
};

// ------------------------------------------------------------ partition

/// Splits attribute edges whose nodes lie in several surfaces into one
/// attribute edge per run.
void split_attrib_edges_by_surface(Model& m) {
  const std::size_t n = m.attrib_edges.slots.capacity();
  for (std::uint32_t e = 0; e < n; ++e) {
    const AttribEdgeIdx ei{e};
    if (!m.alive(ei)) continue;
    const auto row = m.attrib_edges.nodes.row(e);
    const std::vector<AttribNodeIdx> nodes(row.begin(), row.end());
    std::vector<std::vector<AttribNodeIdx>> runs;
    for (AttribNodeIdx a : nodes) {
      if (runs.empty() || m.attrib_nodes.surface[runs.back().back().value] != m.attrib_nodes.surface[a.value])
        runs.emplace_back();
      runs.back().push_back(a);
    }
    if (runs.size() <= 1) {
      if (!runs.empty()) m.attrib_edges.surface[e] = m.attrib_nodes.surface[runs[0][0].value];
      continue;
    }
    // A node repeated in the row (a closed curve) cannot belong to two edges: copy it.
    std::set<AttribNodeIdx> seen;
    const std::int32_t fid = m.attrib_edges.feature_id[e];
    for (std::size_t r = 0; r < runs.size(); ++r) {
      for (AttribNodeIdx& a : runs[r])
        if (!seen.insert(a).second) {
          const auto& an = m.attrib_nodes;
          a = m.new_attrib_node(an.surface[a.value], an.kind[a.value], an.element[a.value], an.param[a.value],
                                an.position[a.value], an.corner[a.value]);
        }
      const SurfaceIdx s = m.attrib_nodes.surface[runs[r][0].value];
      if (r == 0) {
        m.attrib_edges.nodes.assign(e, runs[0]);
        m.attrib_edges.surface[e] = s;
        for (AttribNodeIdx a : runs[0]) m.attrib_nodes.owner[a.value] = ei;
      } else {
        (void)m.new_attrib_edge(s, fid, runs[r]);
      }
    }
  }
}

struct SeamSide {
  HalfedgeIdx h;  // old halfedge on the side of piece a (the smaller piece id)
  std::uint32_t a = 0, b = 0;
};

/// Triangle faces as flat rows, built by one pass over the halfedge columns
/// in memory order: per face slot f, its three neighbours across its sides
/// (kBlocked across a curve edge, kOpen across a boundary) and its three
/// corners. The picked side's flood and the area sums then read one short
/// row per face instead of chasing next pointers and twins through the
/// halfedge columns at random (most of their time on half a mesh). `ok` is
/// false when a face of the model is not a triangle (the walks are used).
/// A face's neighbours and corners share one row (the pass writes a face's
/// three halfedges at different times: one cache line to come back to, not
/// two), and the rows are not cleared first: every live face writes all of
/// its row, and only live faces' rows are read.
struct TriRows {
  static constexpr std::uint32_t kBlocked = kNone - 1, kOpen = kNone;
  struct Row {
    std::uint32_t adj[3], corner[3];
  };
  bool ok = false;
  bool boundary = false;        // some face side has no face across (when ok)
  std::unique_ptr<Row[]> rows;  // per face slot
};
TriRows tri_rows(const Model& m, const std::vector<std::uint8_t>& curve_edge) {
  TriRows t;
  const std::size_t nf = m.faces.slots.capacity(), nh = 2 * m.edges.slots.capacity();
  std::vector<std::uint8_t> count(nf, 0);
  t.rows = std::make_unique_for_overwrite<TriRows::Row[]>(nf);
  const auto& hf = m.halfedges.face;
  const auto& tail = m.halfedges.tail;
  for (std::size_t h = 0; h < nh; ++h) {
    const FaceIdx f = hf[h];
    if (!f.valid()) continue;
    const std::uint8_t k = count[f.value]++;
    if (k >= 3) return t;  // a polygon
    const FaceIdx o = hf[h ^ 1];
    t.boundary |= !o.valid();
    TriRows::Row& r = t.rows[f.value];
    r.adj[k] = !o.valid() ? TriRows::kOpen : curve_edge[h >> 1] ? TriRows::kBlocked : o.value;
    r.corner[k] = tail[h].value;
  }
  t.ok = true;
  return t;
}

double tri_area(const Model& m, const std::uint32_t* c) {
  const Vec3d& p0 = m.nodes.position[c[0]];
  return 0.5 * (m.nodes.position[c[1]] - p0).cross(m.nodes.position[c[2]] - p0).norm();
}

/// Area of face f: its fan triangles (c0, c_k+1, c_k+2).
double face_area(const Model& m, const TriRows& t, std::size_t f) {
  if (t.ok) return tri_area(m, t.rows[f].corner);
  return fan_area(m, f);
}

/// The piece holding face `start`: faces connected to it across edges that
/// are not on a curve (in face order), and its area.
struct OnePiece {
  std::vector<FaceIdx> faces;
  std::vector<std::uint8_t> in;  // per face slot
  double area = 0;
  bool open = false;  // a face of the piece has a boundary halfedge
};
OnePiece piece_from(const Model& m, FaceIdx start, const std::vector<std::uint8_t>& curve_edge, const TriRows& t) {
  OnePiece p;
  const std::size_t nf = m.faces.slots.capacity();
  p.in.assign(nf, 0);
  std::vector<FaceIdx> stack{start};
  p.in[start.value] = 1;
  std::size_t count = 0;
  while (!stack.empty()) {
    const FaceIdx f = stack.back();
    stack.pop_back();
    ++count;
    if (t.ok) {
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t o = t.rows[f.value].adj[k];
        if (o == TriRows::kOpen) {
          p.open = true;
        } else if (o != TriRows::kBlocked && !p.in[o]) {
          p.in[o] = 1;
          stack.push_back(FaceIdx{o});
        }
      }
      continue;
    }
    const HalfedgeIdx h0 = m.faces.halfedge[f.value];
    HalfedgeIdx h = h0;
    do {
      const FaceIdx o = m.face(twin(h));
      p.open |= !o.valid();
      if (!curve_edge[edge_of(h).value] && o.valid() && !p.in[o.value]) {
        p.in[o.value] = 1;
        stack.push_back(o);
      }
      h = m.next(h);
    } while (h != h0);
  }
  // Face order (the removal order decides the free lists): read off the
  // marks, which costs a byte per face slot instead of a sort. The area is
  // summed here, in face order, rather than in the flood's order: the
  // corners are then read nearly in memory order.
  p.faces.reserve(count);
  for (std::uint32_t f = 0; f < nf; ++f) {
    if (!p.in[f]) continue;
    p.faces.push_back(FaceIdx{f});
    p.area += face_area(m, t, f);
  }
  return p;
}

/// Area and face count of the live faces of the given surfaces outside
/// `skip` (the removed piece, already measured: its faces' cycles are not
/// read again), parallel, summed in a fixed order.
std::pair<double, std::size_t> surface_totals(const Model& m, const std::vector<std::uint8_t>& touched,
                                              const std::vector<std::uint8_t>& skip, const TriRows& t,
                                              const ExecContext& ctx) {
  using Acc = std::pair<double, std::size_t>;
  return par::transform_reduce(
      ctx, m.faces.slots.capacity(), Acc{0.0, 0},
      [&](std::size_t f) -> Acc {
        if (skip[f] || !m.alive(FaceIdx{static_cast<std::uint32_t>(f)}) || !touched[m.faces.surface[f].value])
          return {0.0, 0};
        return {face_area(m, t, f), 1};
      },
      [](const Acc& x, const Acc& y) {
        return Acc{x.first + y.first, x.second + y.second};
      });
}

}  // namespace

Expected<CutResult> cut_along_curves(Model& m, std::span<const AttribEdge> curves, const CutOptions& opt,
                                     const ExecContext& ctx) {
  Rollback rb(m);
  RetriangulateOptions ro = opt.retriangulate;
  if (opt.pick) ro.probes.push_back(*opt.pick);
  auto rt = retriangulate_curves(m, curves, ro, ctx);
  if (!rt) return rt.status();
  CutResult out;
  out.faces_added = rt->faces_added;
  out.nodes_added = rt->nodes_added;
  out.crossings = rt->crossings;
  std::vector<FaceIdx> rm;
  std::optional<bool> shell_closed;  // with a pick: whether the picked side's face group was a closed shell
  if (opt.pick) {
    // The picked side only: the piece holding the pick, grown across edges
    // that are not on a curve; it must meet a face of another piece across
    // a curve edge (else the curve separates nothing).
    const SurfaceLocation& l = rt->probes.back();
    FaceIdx f;
    if (l.kind == AttribNodeKind::kFace) f = FaceIdx{l.element};
    if (!f.valid())
      return Status(ErrorCode::kInvalidArgument,
                    "cut: the pick is not inside a face; pick inside a face of the "
                    "side to remove");
    std::vector<std::uint8_t> curve_edge(m.edges.slots.capacity(), 0), touched(m.surfaces.slots.capacity(), 0);
    for (const auto& ch : rt->chains)
      for (HalfedgeIdx h : ch) {
        curve_edge[edge_of(h).value] = 1;
        touched[m.surface_of(edge_of(h)).value] = 1;
      }
    if (!touched[m.faces.surface[f.value].value])
      return Status(ErrorCode::kInvalidArgument, "cut: the pick is on a surface the curves do not cross");
    if (rt->probe_margin.back() <= 0) {
      // On a side of its face: ambiguous only when that side is on a curve.
      std::vector<HalfedgeIdx> hs;
      m.face_halfedges(f, hs);
      const std::size_t n = hs.size();
      const std::size_t c[3] = {0, l.corner + 1u, l.corner + 2u};
      for (int i = 0; i < 3; ++i) {
        if (l.param[i] > 0) continue;
        const NodeIdx a = m.tail(hs[c[(i + 1) % 3] % n]), b = m.tail(hs[c[(i + 2) % 3] % n]);
        const HalfedgeIdx h = m.find_halfedge(a, b);
        if (h.valid() && curve_edge[edge_of(h).value])
          return Status(ErrorCode::kInvalidArgument,
                        "cut: the pick lies on the cut curve; pick inside the side to "
                        "remove");
      }
    }
    const TriRows rows = tri_rows(m, curve_edge);
    const OnePiece pc = piece_from(m, f, curve_edge, rows);
    bool separates = false;
    for (const auto& ch : rt->chains)
      for (HalfedgeIdx h : ch) {
        const FaceIdx a = m.face(h), b = m.face(twin(h));
        separates |= a.valid() && b.valid() && pc.in[a.value] != pc.in[b.value];
      }
    if (!separates)
      return Status(ErrorCode::kInvalidArgument,
                    "cut: the curve does not separate the surface (the picked side is all of it); a cut all the "
                    "way round a closed body or a tube needs penetrated painting (\"through\": true)");
    Piece removed;
    removed.surface = m.handle(m.faces.surface[f.value]);
    removed.faces = pc.faces.size();
    removed.area = pc.area;
    removed.removed = true;
    out.pieces = {removed};
    out.removed_area = removed.area;
    if (opt.kept_totals) {
      // The one pass over every face of the cut: on request only.
      const auto [kept_area, kept_faces] = surface_totals(m, touched, pc.in, rows, ctx);
      Piece kept;  // everything else of the surfaces the curves cross
      kept.surface = removed.surface;
      kept.faces = kept_faces;
      kept.area = kept_area;
      out.pieces.push_back(kept);
      out.kept_area = kept.area;
    }
    shell_closed =
        group_closed(m, pc.in, pc.faces, pc.open, rows.ok ? std::optional<bool>(rows.boundary) : std::nullopt);
    rm = pc.faces;
  } else {
    const Pieces P = find_pieces(m, *rt, ctx);
    std::vector<std::uint8_t> remove(P.data.size(), 0);
    bool any = false;
    for (std::uint32_t comp = 0; comp < P.crossed_comp.size(); ++comp) {
      if (!P.crossed_comp[comp]) continue;
      std::int64_t largest = -1;
      std::size_t count = 0;
      for (std::uint32_t q = 0; q < P.data.size(); ++q)
        if (P.data[q].comp == comp) {
          ++count;
          if (largest < 0 || P.data[q].area > P.data[largest].area) largest = q;
        }
      if (count < 2) continue;
      any = true;
      for (std::uint32_t q = 0; q < P.data.size(); ++q)
        if (P.data[q].comp == comp && static_cast<std::int64_t>(q) != largest) remove[q] = 1;
    }
    if (!any)
      return Status(ErrorCode::kInvalidArgument,
                    "cut: the curves do not separate the surface; a cut all the way round a closed body or a tube "
                    "needs penetrated painting (\"through\": true)");
    for (std::uint32_t q = 0; q < P.data.size(); ++q) {
      if (!P.crossed_comp[P.data[q].comp]) continue;
      Piece pc;
      pc.surface = m.handle(P.data[q].surface);
      pc.faces = P.data[q].faces.size();
      pc.area = P.data[q].area;
      pc.removed = remove[q] != 0;
      (pc.removed ? out.removed_area : out.kept_area) += pc.area;
      out.pieces.push_back(pc);
      if (remove[q]) rm.insert(rm.end(), P.data[q].faces.begin(), P.data[q].faces.end());
    }
    std::sort(rm.begin(), rm.end());
  }
  out.faces_removed = rm.size();
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "cut cancelled");
  Removal rem;
  if (Status s = remove_faces(m, rm, rem); !s) return s;
  out.nodes_removed = rem.nodes;
  if (shell_closed && !rem.rings) {
    // Euler bookkeeping of the removed piece instead of a recount of the
    // model: H = C - (V - E + F - R) + S (docs/glossary.md). R is
    // unchanged (no ring node in the model). The piece was one face-connected
    // set, so its corners were in one component; the survivors among them
    // tell how many components that one became. The face groups left all
    // border the curve, so they are open: S drops by one if the group was a
    // closed shell.
    const auto d_chi = -static_cast<std::int64_t>(rem.nodes) + static_cast<std::int64_t>(rem.edges) -
                       static_cast<std::int64_t>(rem.faces);
    const auto d_c = static_cast<std::int64_t>(components_holding(m, rem.survivors)) - 1;
    const std::int64_t d_s = *shell_closed ? -1 : 0;
    m.complex_holes += d_c - d_chi + d_s;
  } else {
    recount_holes(m);
  }
  rb.armed = false;
  return out;
}

Expected<PartitionResult> partition_along_curves(Model& m, std::span<const AttribEdge> curves,
                                                 const PartitionOptions& opt, const ExecContext& ctx) {
  Rollback rb(m);
  std::vector<AttribEdgeIdx> cur;
  for (const AttribEdge& c : curves)
    if (auto r = m.resolve(c); r) cur.push_back(*r);
  auto rt = retriangulate_curves(m, curves, opt.retriangulate, ctx);
  if (!rt) return rt.status();
  const Pieces P = find_pieces(m, *rt, ctx);
  PartitionResult out;
  out.faces_added = rt->faces_added;
  out.nodes_added = rt->nodes_added;
  out.crossings = rt->crossings;
  // Which pieces move: in each surface, the piece with the smallest face
  // stays; every other piece of a crossed component gets its own surface.
  std::map<std::uint32_t, std::uint32_t> staying;  // surface -> piece
  for (std::uint32_t q = 0; q < P.data.size(); ++q)
    if (!staying.count(P.data[q].surface.value)) staying[P.data[q].surface.value] = q;
  std::vector<std::uint8_t> moves(P.data.size(), 0);
  bool any = false;
  for (std::uint32_t q = 0; q < P.data.size(); ++q) {
    if (!P.crossed_comp[P.data[q].comp] || staying[P.data[q].surface.value] == q) continue;
    moves[q] = 1;
    any = true;
  }
  if (!any) return Status(ErrorCode::kInvalidArgument, "partition: the curves do not separate the surface into pieces");
  // Seam edges: curve edges with different pieces on their two sides.
  std::vector<SeamSide> seams;
  for (std::uint32_t e = 0; e < P.curve_edge.size(); ++e) {
    if (!P.curve_edge[e]) continue;
    const HalfedgeIdx h0 = halfedge_of(EdgeIdx{e}, 0);
    const FaceIdx f0 = m.face(h0), f1 = m.face(twin(h0));
    if (!f0.valid() || !f1.valid()) continue;
    const std::uint32_t p0 = P.piece_of[f0.value], p1 = P.piece_of[f1.value];
    if (p0 == p1) continue;
    if (const MeshEdgeIdx me = m.edges.mesh_edge[e]; me.valid())
      return status_of(ErrorCode::kJointRefused, "partition: a curve runs along edge ", e, " of mesh edge ", me.value,
                       "; seams must not follow existing mesh edges");
    seams.push_back(p0 < p1 ? SeamSide{h0, p0, p1} : SeamSide{twin(h0), p1, p0});
  }
  // Mesh edges: inside one piece they move with it; across pieces they are
  // cut into runs (refused on a joint).
  std::set<MeshEdgeIdx> split_me;
  for (std::uint32_t i = 0; i < m.mesh_edges.slots.capacity(); ++i) {
    const MeshEdgeIdx me{i};
    if (!m.alive(me)) continue;
    std::set<std::uint32_t> ps;
    for (HalfedgeIdx h : m.mesh_edges.halfedges.row(i))
      for (HalfedgeIdx x : {h, twin(h)})
        if (const FaceIdx f = m.face(x); f.valid() && P.piece_of[f.value] != kNone) ps.insert(P.piece_of[f.value]);
    if (ps.size() <= 1) continue;
    if (const JointIdx j = m.mesh_edges.joint[i]; j.valid())
      return status_of(ErrorCode::kJointRefused, "partition: the pieces would split mesh edge ", i, " of joint ",
                       j.value, " (a seam to another surface)");
    split_me.insert(me);
  }
  // Ring nodes in moving faces.
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
    const FaceIdx f = m.nodes.in_face[v];
    if (f.valid() && m.alive(NodeIdx{v}) && P.piece_of[f.value] != kNone && moves[P.piece_of[f.value]])
      return status_of(ErrorCode::kUnsupported, "partition: face ", f.value, " holds ring node ", v);
  }
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "partition cancelled");

  // Mesh edges across pieces: cut at piece changes (by the piece of the
  // face on either side of each halfedge).
  for (MeshEdgeIdx me : split_me) {
    const auto row = m.mesh_edges.halfedges.row(me.value);
    std::vector<std::vector<HalfedgeIdx>> runs;
    std::uint32_t last = kNone;
    for (HalfedgeIdx h : row) {
      std::uint32_t p = kNone;
      for (HalfedgeIdx x : {h, twin(h)})
        if (const FaceIdx f = m.face(x); f.valid() && P.piece_of[f.value] != kNone) p = P.piece_of[f.value];
      if (runs.empty() || p != last) runs.emplace_back();
      runs.back().push_back(h);
      last = p;
    }
    const SurfaceIdx s = m.mesh_edges.surface[me.value];
    if (const MeshLoopIdx l = m.mesh_edges.loop[me.value]; l.valid()) m.delete_mesh_loop(l);
    m.delete_mesh_edge(me);
    for (const auto& r : runs) (void)m.new_mesh_edge(s, r);
  }
  // Which piece lies left of each curve node (for the curves' own nodes,
  // which sit on seam nodes that the move duplicates).
  std::vector<std::map<NodeIdx, std::uint32_t>> curve_left(rt->chains.size());
  for (std::size_t c = 0; c < rt->chains.size(); ++c)
    for (HalfedgeIdx h : rt->chains[c]) {
      const FaceIdx f = m.face(h).valid() ? m.face(h) : m.face(twin(h));
      if (!f.valid()) continue;
      curve_left[c].emplace(m.tail(h), P.piece_of[f.value]);
      curve_left[c].emplace(m.head(h), P.piece_of[f.value]);
    }
  // Move the pieces, recording old halfedge -> new halfedge and the copies
  // of their nodes.
  // Old halfedge of a moved face -> its new halfedge (indexed by the old
  // halfedge; only halfedges that exist now are keys).
  std::vector<HalfedgeIdx> hmap(2 * m.edges.slots.capacity());
  auto hmapped = [&](HalfedgeIdx h) { return h.value < hmap.size() && hmap[h.value].valid(); };
  std::vector<NodeIdx> nmap(m.nodes.slots.capacity());  // per piece: old node -> its copy
  std::set<NodeIdx> seam_nodes;
  std::map<std::pair<NodeIdx, std::uint32_t>, NodeIdx> copy_of;  // (old node, piece) -> its copy
  std::vector<SurfaceIdx> piece_surface(P.data.size());
  for (std::uint32_t q = 0; q < P.data.size(); ++q) piece_surface[q] = P.data[q].surface;
  std::set<std::string> used_names;
  for (std::uint32_t s = 0; s < m.surfaces.slots.capacity(); ++s)
    if (m.alive(SurfaceIdx{s})) used_names.insert(m.surfaces.name[s]);
  std::map<std::uint32_t, int> suffix;
  std::map<FaceIdx, std::pair<FaceIdx, SurfaceIdx>> face_moved;
  for (std::uint32_t q = 0; q < P.data.size(); ++q) {
    if (!moves[q]) continue;
    const PieceData& pd = P.data[q];
    struct OldFace {
      FaceIdx f;
      std::vector<HalfedgeIdx> hs;
      std::uint8_t flags;
    };
    std::vector<OldFace> old;
    std::vector<NodeIdx> nodes;
    std::vector<EdgeIdx> edges;
    for (FaceIdx f : pd.faces) {
      OldFace o{f, {}, m.faces.flags[f.value]};
      m.face_halfedges(f, o.hs);
      for (HalfedgeIdx h : o.hs) {
        nodes.push_back(m.tail(h));
        edges.push_back(edge_of(h));
      }
      old.push_back(std::move(o));
    }
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    // Mesh edges of the piece (entirely in it: those across pieces were cut
    // above) move with it, keeping their place in their joint.
    struct OldMeshEdge {
      std::vector<HalfedgeIdx> chain;
      JointIdx joint;
      std::size_t member = 0;
      MeshEdgeIdx idx;
    };
    std::vector<OldMeshEdge> old_me;
    {
      std::set<MeshEdgeIdx> mes;
      for (EdgeIdx e : edges)
        if (const MeshEdgeIdx me = m.edges.mesh_edge[e.value]; me.valid()) mes.insert(me);
      for (MeshEdgeIdx me : mes) {
        const auto row = m.mesh_edges.halfedges.row(me.value);
        OldMeshEdge o{{row.begin(), row.end()}, m.mesh_edges.joint[me.value], 0, me};
        if (o.joint.valid()) {
          const auto mem = m.joints.members.row(o.joint.value);
          for (std::size_t i = 0; i < mem.size(); ++i)
            if (mem[i].mesh_edge == me) o.member = i;
        }
        old_me.push_back(std::move(o));
      }
    }
    const std::string base = m.surfaces.name[pd.surface.value];
    std::string name;
    do {
      name = base + "." + std::to_string(++suffix[pd.surface.value]);
    } while (used_names.count(name));
    used_names.insert(name);
    const Surface ns = m.add_surface(name);
    m.surfaces.flags[ns.idx.value] = m.surfaces.flags[pd.surface.value];
    piece_surface[q] = ns.idx;
    out.new_surfaces.push_back(ns);
    for (const OldFace& o : old) m.delete_face(o.f);
    for (const OldMeshEdge& o : old_me) {
      if (const MeshLoopIdx l = m.mesh_edges.loop[o.idx.value]; l.valid()) m.delete_mesh_loop(l);
      m.mesh_edges.joint[o.idx.value] = {};  // re-pointed below, by member position
      m.delete_mesh_edge(o.idx);
    }
    for (NodeIdx v : nodes) {
      const NodeIdx nv = m.new_node(ns.idx, m.position(v));
      m.nodes.uv[nv.value] = m.nodes.uv[v.value];
      m.nodes.position_backup[nv.value] = m.nodes.position_backup[v.value];
      nmap[v.value] = nv;
    }
    for (const OldFace& o : old) {
      std::vector<HalfedgeIdx> cyc;
      for (HalfedgeIdx h : o.hs) {
        const NodeIdx a = nmap[m.tail(h).value], b = nmap[m.head(h).value];
        HalfedgeIdx x = m.find_halfedge(a, b);
        if (!x.valid()) {
          const EdgeIdx e = m.new_edge(a, b);
          m.edges.flags[e.value] = m.edges.flags[edge_of(h).value];
          x = halfedge_of(e, 0);
        }
        cyc.push_back(x);
        hmap[h.value] = x;
        // The twin moves too unless another piece's face holds it (a seam),
        // or a piece moved before already took it.
        if (!m.face(twin(h)).valid() && !hmap[twin(h).value].valid()) hmap[twin(h).value] = twin(x);
      }
      const FaceIdx nf = m.new_face(ns.idx, cyc);
      m.faces.flags[nf.value] = o.flags;
      face_moved[o.f] = {nf, ns.idx};
    }
    // Edges left without faces go (the piece's own); seam edges stay with
    // the other side.
    std::vector<std::uint8_t> edge_dies(m.edges.slots.capacity(), 0);
    for (EdgeIdx e : edges)
      if (m.is_wire(e)) edge_dies[e.value] = 1;
    for (std::uint32_t i = 0; i < m.attrib_nodes.slots.capacity(); ++i) {
      if (!m.alive(AttribNodeIdx{i})) continue;
      auto& an = m.attrib_nodes;
      if (an.kind[i] == AttribNodeKind::kEdge) {
        const HalfedgeIdx h{an.element[i]};
        if (!std::binary_search(edges.begin(), edges.end(), edge_of(h)) || !hmapped(h)) continue;
        // On the moved side: the edge goes, or this side lost its face.
        if (edge_dies[edge_of(h).value] || !m.face(h).valid()) {
          an.element[i] = hmap[h.value].value;
          an.surface[i] = ns.idx;
        }
      } else if (an.kind[i] == AttribNodeKind::kVertex) {
        const NodeIdx v{an.element[i]};
        if (!std::binary_search(nodes.begin(), nodes.end(), v)) continue;
        bool interior = true;
        m.for_each_outgoing(v, [&](HalfedgeIdx h) { interior &= edge_dies[edge_of(h).value] != 0; });
        if (interior) {
          an.element[i] = nmap[v.value].value;
          an.surface[i] = ns.idx;
        }
      }
    }
    for (const OldMeshEdge& o : old_me) {
      std::vector<HalfedgeIdx> chain;
      for (HalfedgeIdx h : o.chain) chain.push_back(hmap[h.value]);
      const MeshEdgeIdx nm = m.new_mesh_edge(ns.idx, chain);
      if (o.joint.valid()) {
        const auto row = m.joints.members.row(o.joint.value);
        std::vector<JointMember> mem(row.begin(), row.end());
        mem[o.member].mesh_edge = nm;
        m.joints.members.assign(o.joint.value, mem);
        m.mesh_edges.joint[nm.value] = o.joint;
      }
    }
    for (EdgeIdx e : edges)
      if (edge_dies[e.value]) m.delete_edge(e);
    for (NodeIdx v : nodes) {
      // A seam node (shared with a piece not moved yet, or with one moved
      // before): remember its copy in this piece.
      if (m.is_isolated(v) && !m.nodes.in_face[v.value].valid()) {
        m.delete_node(v);
        if (seam_nodes.count(v)) copy_of[{v, q}] = nmap[v.value];
      } else {
        ++out.seam_nodes;
        seam_nodes.insert(v);
        copy_of[{v, q}] = nmap[v.value];
      }
    }
  }
  // Face-nodes follow their faces.
  for (std::uint32_t i = 0; i < m.attrib_nodes.slots.capacity(); ++i) {
    if (!m.alive(AttribNodeIdx{i}) || m.attrib_nodes.kind[i] != AttribNodeKind::kFace) continue;
    auto it = face_moved.find(FaceIdx{m.attrib_nodes.element[i]});
    if (it == face_moved.end()) continue;
    m.attrib_nodes.element[i] = it->second.first.value;
    m.attrib_nodes.surface[i] = it->second.second;
  }
  // Vertex-nodes on seam nodes (which now exist once per side): a curve's
  // own nodes go to the piece left of the curve, other attribute edges'
  // nodes to the surface of their nearest neighbour in the row.
  auto node_in = [&](NodeIdx v, SurfaceIdx s) -> NodeIdx {
    if (m.alive(v) && m.nodes.surface[v.value] == s) return v;
    for (std::uint32_t q = 0; q < P.data.size(); ++q)
      if (piece_surface[q] == s)
        if (auto it = copy_of.find({v, q}); it != copy_of.end()) return it->second;
    return {};
  };
  std::set<NodeIdx> copied;
  for (const auto& [key, nv] : copy_of) copied.insert(key.first);
  std::map<AttribEdgeIdx, std::size_t> curve_index;
  for (std::size_t c = 0; c < cur.size(); ++c) curve_index[cur[c]] = c;
  for (std::uint32_t e = 0; e < m.attrib_edges.slots.capacity(); ++e) {
    if (!m.alive(AttribEdgeIdx{e})) continue;
    const auto row = m.attrib_edges.nodes.row(e);
    const std::vector<AttribNodeIdx> nodes(row.begin(), row.end());
    auto& an = m.attrib_nodes;
    const auto ci = curve_index.find(AttribEdgeIdx{e});
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const AttribNodeIdx a = nodes[k];
      if (an.kind[a.value] != AttribNodeKind::kVertex) continue;
      const NodeIdx v{an.element[a.value]};
      if (!copied.count(v)) continue;
      SurfaceIdx want;
      if (ci != curve_index.end()) {
        if (auto it = curve_left[ci->second].find(v); it != curve_left[ci->second].end())
          want = piece_surface[it->second];
      }
      for (std::size_t d = 1; d < nodes.size() && !want.valid(); ++d)
        for (std::int64_t kk :
             {static_cast<std::int64_t>(k) - static_cast<std::int64_t>(d), static_cast<std::int64_t>(k + d)}) {
          if (kk < 0 || kk >= static_cast<std::int64_t>(nodes.size()) || want.valid()) continue;
          const AttribNodeIdx b = nodes[kk];
          const bool b_seam = an.kind[b.value] == AttribNodeKind::kVertex && copied.count(NodeIdx{an.element[b.value]});
          if (!b_seam && node_in(v, an.surface[b.value]).valid()) want = an.surface[b.value];
        }
      if (!want.valid() && m.alive(v)) continue;  // stays where it is
      if (!want.valid())
        for (std::uint32_t q = 0; q < P.data.size() && !want.valid(); ++q)
          if (copy_of.count({v, q})) want = piece_surface[q];
      const NodeIdx t = node_in(v, want);
      if (!t.valid()) continue;
      an.element[a.value] = t.value;
      an.surface[a.value] = want;
      an.position[a.value] = m.position(t);
    }
  }
  // Joints along the seams: per pair of pieces, chains of seam halfedges on
  // the side of the smaller piece (one surface), their twins on the other.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<SeamSide>> by_pair;
  for (const SeamSide& s : seams) by_pair[{s.a, s.b}].push_back(s);
  auto mapped = [&](HalfedgeIdx h) { return hmapped(h) ? hmap[h.value] : h; };
  for (auto& [pair, list] : by_pair) {
    std::sort(list.begin(), list.end(), [](const SeamSide& x, const SeamSide& y) { return x.h < y.h; });
    std::vector<HalfedgeIdx> ha, hb;
    for (const SeamSide& s : list) {
      ha.push_back(mapped(s.h));
      hb.push_back(mapped(twin(s.h)));
    }
    std::map<NodeIdx, std::size_t> by_tail;
    std::map<NodeIdx, int> indeg, outdeg;
    for (std::size_t i = 0; i < ha.size(); ++i) {
      by_tail[m.tail(ha[i])] = i;
      ++outdeg[m.tail(ha[i])];
      ++indeg[m.head(ha[i])];
    }
    std::vector<std::uint8_t> used(ha.size(), 0);
    auto plain = [&](NodeIdx v) { return indeg[v] == 1 && outdeg[v] == 1; };
    auto make_joint = [&](const std::vector<std::size_t>& chain) {
      std::vector<HalfedgeIdx> ca, cb;
      for (std::size_t i : chain) ca.push_back(ha[i]);
      for (auto it = chain.rbegin(); it != chain.rend(); ++it) cb.push_back(hb[*it]);
      const MeshEdgeIdx ma = m.new_mesh_edge(m.surface_of(edge_of(ca[0])), ca);
      const MeshEdgeIdx mb = m.new_mesh_edge(m.surface_of(edge_of(cb[0])), cb);
      const JointMember mem[2] = {{ma, true}, {mb, false}};
      out.joints.push_back(m.handle(m.new_joint(mem)));
    };
    auto follow = [&](std::size_t i, bool open) {
      std::vector<std::size_t> chain{i};
      used[i] = 1;
      NodeIdx hd = m.head(ha[i]);
      while (!open || plain(hd)) {
        auto it = by_tail.find(hd);
        if (it == by_tail.end() || used[it->second]) break;
        used[it->second] = 1;
        chain.push_back(it->second);
        hd = m.head(ha[it->second]);
      }
      make_joint(chain);
    };
    for (std::size_t i = 0; i < ha.size(); ++i)
      if (!used[i] && !plain(m.tail(ha[i]))) follow(i, true);
    for (std::size_t i = 0; i < ha.size(); ++i)
      if (!used[i]) follow(i, false);
  }
  split_attrib_edges_by_surface(m);
  recount_holes(m);
  std::vector<NodeIdx> c;
  for (std::uint32_t q = 0; q < P.data.size(); ++q) {
    Piece pc;
    pc.surface = m.handle(piece_surface[q]);
    pc.faces = P.data[q].faces.size();
    pc.area = P.data[q].area;
    out.pieces.push_back(pc);
  }
  rb.armed = false;
  return out;
}

}  // namespace atelier
