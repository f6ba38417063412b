#include <atelier/systems/mesh/subdivide.h>

#include <algorithm>
#include <array>
#include <functional>
#include <limits>
#include <span>
#include <sstream>

#include <atelier/engine/parallel.h>

namespace atelier {

namespace {

// The same expressions in the fast and the naive split, so both produce
// bit-identical positions (and joint partners, whose end nodes coincide,
// get bit-identical midpoints whichever direction they run).
template <class V>
V midpoint(const V& a, const V& b) {
  return (a + b) * 0.5;
}

template <class V, class Get>
V centroid(std::size_t n, Get&& get) {
  V s = get(0);
  for (std::size_t k = 1; k < n; ++k) s += get(k);
  return s / static_cast<double>(n);
}

bool has_free_node_edge_face_slots(const Model& m) {
  return !m.nodes.slots.free_list().empty() || !m.edges.slots.free_list().empty() ||
         !m.faces.slots.free_list().empty();
}

/// Face nodes of polygons (n >= 4) have no exact image in the child quads:
/// their on-surface positions are kept and re-located after the split.
std::vector<std::pair<AttribNodeIdx, Vec3d>> polygon_face_nodes(const Model& m) {
  std::vector<std::pair<AttribNodeIdx, Vec3d>> out;
  const auto& an = m.attrib_nodes;
  for (std::uint32_t i = 0; i < an.slots.capacity(); ++i)
    if (m.alive(AttribNodeIdx{i}) && an.kind[i] == AttribNodeKind::kFace && m.face_degree(FaceIdx{an.element[i]}) != 3)
      out.emplace_back(AttribNodeIdx{i}, m.attrib_position_on_surface(AttribNodeIdx{i}));
  return out;
}

/// Per-face counts and their prefix sums (the layout of all new elements).
struct Layout {
  std::uint32_t V = 0, E = 0, F = 0;
  std::vector<std::uint32_t> degree;      // sides of old face f
  std::vector<std::uint32_t> child_off;   // F+1: extra children (3 for triangles, n-1 for n-gons)
  std::vector<std::uint32_t> centre_off;  // F+1: centre nodes (0 for triangles, 1 for n-gons)
  std::uint32_t children = 0, centres = 0;

  [[nodiscard]] std::uint32_t interior_base(std::size_t f) const noexcept {
    // n-gons have n = (n-1) + 1 interior edges, triangles 3 = 3 + 0.
    return 2 * E + child_off[f] + centre_off[f];
  }
  [[nodiscard]] HalfedgeIdx first_half(HalfedgeIdx h) const noexcept {
    return (h.value & 1u) ? HalfedgeIdx{2u * (E + (h.value >> 1)) + 1u} : h;
  }
  [[nodiscard]] HalfedgeIdx second_half(HalfedgeIdx h) const noexcept {
    return (h.value & 1u) ? h : HalfedgeIdx{2u * (E + (h.value >> 1))};
  }
  [[nodiscard]] FaceIdx child(std::size_t f, std::uint32_t k) const noexcept {
    return k == 0 ? FaceIdx{static_cast<std::uint32_t>(f)} : FaceIdx{F + child_off[f] + k - 1};
  }
};

Layout make_layout(const Model& m, const ExecContext& ctx) {
  Layout L;
  L.V = static_cast<std::uint32_t>(m.nodes.slots.capacity());
  L.E = static_cast<std::uint32_t>(m.edges.slots.capacity());
  L.F = static_cast<std::uint32_t>(m.faces.slots.capacity());
  L.degree.resize(L.F);
  L.child_off.resize(L.F + 1);
  L.centre_off.resize(L.F + 1);
  par::for_each_n(ctx, L.F, [&](std::size_t f) {
    const auto n = static_cast<std::uint32_t>(m.face_degree(FaceIdx{static_cast<std::uint32_t>(f)}));
    L.degree[f] = n;
    L.child_off[f] = n == 3 ? 3u : n - 1;
    L.centre_off[f] = n == 3 ? 0u : 1u;
  });
  L.child_off[L.F] = L.centre_off[L.F] = 0;
  L.children = par::exclusive_scan_inplace(ctx, L.child_off);
  L.centres = par::exclusive_scan_inplace(ctx, L.centre_off);
  return L;
}

void fill_map(SubdivisionMap& map, const Layout& L, const ExecContext& ctx) {
  map.old_nodes = L.V;
  map.old_edges = L.E;
  map.old_faces = L.F;
  map.edge_midpoint.resize(L.E);
  map.face_centre.resize(L.F);
  map.face_child_begin.resize(L.F + 1);
  par::for_each_n(ctx, L.E, [&](std::size_t e) { map.edge_midpoint[e] = NodeIdx{L.V + static_cast<std::uint32_t>(e)}; });
  par::for_each_n(ctx, L.F + 1, [&](std::size_t f) {
    map.face_child_begin[f] = FaceIdx{L.F + L.child_off[f]};
    if (f < L.F)
      map.face_centre[f] = L.degree[f] == 3 ? NodeIdx{} : NodeIdx{L.V + L.E + L.centre_off[f]};
  });
}

/// Edge nodes move to the half holding them, face nodes to the child triangle
/// holding them; both exactly (u' = 2u or 2u - 1, see split_triangle_barycentric).
void remap_attributes(Model& m, const Layout& L, const ExecContext& ctx) {
  auto& an = m.attrib_nodes;
  par::for_each_n(ctx, an.slots.capacity(), [&](std::size_t i) {
    if (!m.alive(AttribNodeIdx{static_cast<std::uint32_t>(i)})) return;
    if (an.kind[i] == AttribNodeKind::kEdge) {
      const HalfedgeIdx h{an.element[i]};
      const double u = an.param[i].x();
      if (u <= 0.5) {
        an.element[i] = L.first_half(h).value;
        an.param[i].x() = 2.0 * u;
      } else {
        an.element[i] = L.second_half(h).value;
        an.param[i].x() = 2.0 * u - 1.0;
      }
    } else if (an.kind[i] == AttribNodeKind::kFace && L.degree[an.element[i]] == 3) {
      const std::size_t f = an.element[i];
      const ChildBarycentric cb = split_triangle_barycentric(an.param[i]);
      an.element[i] = L.child(f, cb.child).value;
      an.param[i] = cb.param;
      an.corner[i] = 0;
    }
  });
}

/// Face nodes of an old polygon go to the fan triangle of its child quads
/// that holds their old position best (largest smallest areal coordinate),
/// clamped to a convex combination: exact up to rounding for planar faces,
/// the projection onto the nearest child triangle for warped ones.
void relocate_polygon_face_nodes(Model& m, const Layout& L, std::span<const std::pair<AttribNodeIdx, Vec3d>> nodes) {
  auto& an = m.attrib_nodes;
  std::vector<NodeIdx> c;
  for (const auto& [a, p] : nodes) {
    const std::uint32_t f = an.element[a.value];
    double best = -std::numeric_limits<double>::infinity();
    FaceIdx bf;
    std::uint8_t bc = 0;
    Vec3d bb = Vec3d::Zero();
    for (std::uint32_t k = 0; k < L.degree[f]; ++k) {
      const FaceIdx child = L.child(f, k);
      m.face_nodes(child, c);
      for (std::size_t t = 0; t + 2 < c.size(); ++t) {
        const Vec3d o = m.position(c[0]), e1 = m.position(c[t + 1]) - o, e2 = m.position(c[t + 2]) - o, d = p - o;
        const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2), det = d11 * d22 - d12 * d12;
        if (!(det > 1e-24 * d11 * d22)) continue;
        const double r1 = d.dot(e1), r2 = d.dot(e2);
        const double u = (d22 * r1 - d12 * r2) / det, v = (d11 * r2 - d12 * r1) / det;
        const Vec3d b(1 - u - v, u, v);
        if (b.minCoeff() > best) {
          best = b.minCoeff();
          bf = child;
          bc = static_cast<std::uint8_t>(t);
          bb = b;
        }
      }
    }
    if (!bf.valid()) {  // every child degenerate: pin it to child 0's first corner
      bf = L.child(f, 0);
      bb = Vec3d(1, 0, 0);
    }
    bb = bb.cwiseMax(0.0);
    an.element[a.value] = bf.value;
    an.corner[a.value] = bc;
    an.param[a.value] = bb / bb.sum();
  }
}

/// Each halfedge of a mesh edge chain becomes its two halves, in order.
void remap_mesh_edges(Model& m, const Layout& L) {
  auto& me = m.mesh_edges;
  RaggedColumn<HalfedgeIdx> fresh;
  fresh.resize_rows(me.slots.capacity());
  std::vector<HalfedgeIdx> chain;
  for (std::uint32_t i = 0; i < me.slots.capacity(); ++i) {
    if (!m.alive(MeshEdgeIdx{i})) continue;
    chain.clear();
    for (HalfedgeIdx h : me.halfedges.row(i)) {
      chain.push_back(L.first_half(h));
      chain.push_back(L.second_half(h));
    }
    fresh.assign(i, chain);
  }
  me.halfedges = std::move(fresh);
}

/// Small per-call buffer: node rings and faces are short, rarely long.
template <class T, std::size_t N>
class SmallBuf {
 public:
  void clear() noexcept { n_ = 0, heap_.clear(); }
  void push_back(T v) {
    if (n_ < N) {
      inline_[n_++] = v;
    } else {
      if (heap_.empty()) heap_.assign(inline_.begin(), inline_.end());
      heap_.push_back(v);
      ++n_;
    }
  }
  [[nodiscard]] std::size_t size() const noexcept { return n_; }
  T operator[](std::size_t i) const noexcept { return n_ <= N ? inline_[i] : heap_[i]; }

 private:
  std::array<T, N> inline_{};
  std::vector<T> heap_;
  std::size_t n_ = 0;
};

}  // namespace

ChildBarycentric split_triangle_barycentric(const Vec3d& b) noexcept {
  // p = a v0 + b v1 + c v2 with v1 = 2 m0 - v0 etc. (m_k midpoint of v_k v_{k+1}).
  const double a = b.x(), bb = b.y(), c = b.z();
  if (a >= 0.5) return {0, Vec3d(2 * a - 1, 2 * bb, 2 * c)};  // (v0, m0, m2)
  if (bb >= 0.5) return {1, Vec3d(2 * bb - 1, 2 * c, 2 * a)};  // (v1, m1, m0)
  if (c >= 0.5) return {2, Vec3d(2 * c - 1, 2 * a, 2 * bb)};  // (v2, m2, m1)
  return {3, Vec3d(1 - 2 * c, 1 - 2 * a, 1 - 2 * bb)};          // (m0, m1, m2)
}

// ------------------------------------------------------------------ fast

Expected<SubdivisionMap> subdivide_uniform(Model& m, const ExecContext& ctx) {
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "subdivide_uniform cancelled");
  SubdivisionMap map;
  // Index arithmetic needs dense tables.
  if (has_free_node_edge_face_slots(m)) {
    map.compaction = m.compact();
    map.compacted = true;
  }
  const auto poly_nodes = polygon_face_nodes(m);
  const Layout L = make_layout(m, ctx);
  const std::uint32_t V = L.V, E = L.E, F = L.F;

  // Grow every column once. Most of the split's time is the kernel
  // zero-filling the new pages, so the columns are grown concurrently (one
  // task per column, largest first); sync_*_columns then only grows the
  // property columns.
  m.nodes.slots.append_bulk(E + L.centres);
  m.edges.slots.append_bulk(E + L.children + L.centres);
  m.faces.slots.append_bulk(L.children);
  std::vector<HalfedgeIdx> mid_out;
  {
    const std::size_t nn = m.nodes.slots.capacity(), ne = m.edges.slots.capacity(), nf = m.faces.slots.capacity();
    auto& H = m.halfedges;
    auto& N = m.nodes;
    const std::array<std::function<void()>, 18> grow = {
        [&] { N.position.resize(nn, Vec3d::Zero()); },
        [&] { N.position_backup.resize(nn, Vec3d::Zero()); },
        [&] { N.uv.resize(nn, Vec2d::Zero()); },
        [&] { H.tail.resize(2 * ne); },
        [&] { H.face.resize(2 * ne); },
        [&] { H.next.resize(2 * ne); },
        [&] { H.prev.resize(2 * ne); },
        [&] { H.vnext.resize(2 * ne); },
        [&] { H.vprev.resize(2 * ne); },
        [&] { mid_out.resize(4 * std::size_t{E}); },
        [&] { m.edges.mesh_edge.resize(ne); },
        [&] { m.faces.halfedge.resize(nf); },
        [&] { m.faces.surface.resize(nf); },
        [&] { N.out.resize(nn); },
        [&] { N.surface.resize(nn); },
        [&] { N.in_face.resize(nn); },
        [&] { m.edges.flags.resize(ne, 0); },
        [&] { m.faces.flags.resize(nf, 0); },
    };
    ExecContext jobs = ctx;
    jobs.sequential_threshold = 2;
    jobs.grain = 1;
    par::for_each_n(jobs, grow.size(), [&](std::size_t i) { grow[i](); });
  }
  m.sync_node_columns();
  m.sync_edge_columns();
  m.sync_face_columns();

  auto& H = m.halfedges;
  auto& N = m.nodes;
  auto link_ring = [&](auto&& ring, std::size_t n) {
    for (std::size_t k = 0; k < n; ++k) {
      const HalfedgeIdx a = ring[k], b = ring[k + 1 < n ? k + 1 : 0];
      H.vnext[a.value] = b;
      H.vprev[b.value] = a;
    }
  };

  // 1. Rings of old nodes. Outgoing halfedge h becomes first_half(h): even
  // ones keep their index, odd ones move past 2E in the same order, so the
  // sorted ring is the old ring with its even members first. A node reads
  // and writes only its own ring, so nodes run in parallel.
  par::for_each_n(ctx, V, [&](std::size_t v) {
    const HalfedgeIdx start = N.out[v];
    if (!start.valid()) return;
    SmallBuf<HalfedgeIdx, 32> ring, odd;
    HalfedgeIdx h = start;
    do {
      if (h.value & 1u)
        odd.push_back(L.first_half(h));
      else
        ring.push_back(h);
      h = H.vnext[h.value];
    } while (h != start);
    for (std::size_t k = 0; k < odd.size(); ++k) ring.push_back(odd[k]);
    link_ring(ring, ring.size());
    N.out[v] = ring[0];
  });

  // 2. Faces. Interior halfedges leaving each new midpoint are noted in
  // mid_out (two per old halfedge) for the midpoint rings of step 3.
  auto& FT = m.faces;
  par::for_each_n(ctx, F, [&](std::size_t f) {
    const std::uint32_t n = L.degree[f];
    const std::uint32_t I = L.interior_base(f);  // first interior edge
    const SurfaceIdx s = FT.surface[f];
    const std::uint8_t flags = FT.flags[f];
    auto set_face = [&](FaceIdx c, HalfedgeIdx a, HalfedgeIdx b, HalfedgeIdx d, HalfedgeIdx e) {
      // Cycle a -> b -> d (-> e when valid).
      const HalfedgeIdx last = e.valid() ? e : d;
      H.face[a.value] = H.face[b.value] = H.face[d.value] = c;
      H.next[a.value] = b, H.prev[b.value] = a;
      H.next[b.value] = d, H.prev[d.value] = b;
      if (e.valid()) {
        H.face[e.value] = c;
        H.next[d.value] = e, H.prev[e.value] = d;
      }
      H.next[last.value] = a, H.prev[a.value] = last;
      FT.halfedge[c.value] = a;
      FT.surface[c.value] = s;
      FT.flags[c.value] = flags;
    };
    if (n == 3) {
      // Interior edge I+k joins m_k and m_{k-1}: A_k = m_k -> m_{k-1} (corner
      // triangle k), B_k = m_{k-1} -> m_k (centre triangle).
      const HalfedgeIdx h[3] = {FT.halfedge[f], H.next[FT.halfedge[f].value],
                                H.next[H.next[FT.halfedge[f].value].value]};
      NodeIdx mid[3];
      HalfedgeIdx A[3], B[3];
      for (unsigned k = 0; k < 3; ++k) {
        mid[k] = NodeIdx{V + (h[k].value >> 1)};
        A[k] = HalfedgeIdx{2 * (I + k)};
        B[k] = HalfedgeIdx{2 * (I + k) + 1};
      }
      for (unsigned k = 0; k < 3; ++k) {
        const unsigned km = (k + 2) % 3, kp = (k + 1) % 3;
        H.tail[A[k].value] = mid[k];
        H.tail[B[k].value] = mid[km];
        mid_out[2 * h[k].value] = A[k];
        mid_out[2 * h[k].value + 1] = B[kp];
      }
      for (unsigned k = 0; k < 3; ++k)
        set_face(L.child(f, k), L.first_half(h[k]), A[k], L.second_half(h[(k + 2) % 3]), HalfedgeIdx{});
      set_face(L.child(f, 3), B[1], B[2], B[0], HalfedgeIdx{});
      return;
    }
    // n-gon: edge I+k joins m_k and the centre c: P_k = m_k -> c, Q_k = c -> m_k.
    const NodeIdx c{V + E + L.centre_off[f]};
    const HalfedgeIdx h0 = FT.halfedge[f];
    {
      SmallBuf<NodeIdx, 16> corners;
      HalfedgeIdx h = h0;
      for (std::uint32_t k = 0; k < n; ++k, h = H.next[h.value]) corners.push_back(H.tail[h.value]);
      N.position[c.value] = centroid<Vec3d>(n, [&](std::size_t k) { return N.position[corners[k].value]; });
      N.position_backup[c.value] =
          centroid<Vec3d>(n, [&](std::size_t k) { return N.position_backup[corners[k].value]; });
      N.uv[c.value] = centroid<Vec2d>(n, [&](std::size_t k) { return N.uv[corners[k].value]; });
      N.surface[c.value] = s;
      N.in_face[c.value] = FaceIdx{};
    }
    HalfedgeIdx hprev = H.prev[h0.value];
    HalfedgeIdx h = h0;
    for (std::uint32_t k = 0; k < n; ++k) {
      const HalfedgeIdx hn = H.next[h.value];  // read before this face's writes reach it
      const HalfedgeIdx P{2 * (I + k)}, Q{2 * (I + k) + 1};
      const HalfedgeIdx Qm{2 * (I + (k + n - 1) % n) + 1};
      H.tail[P.value] = NodeIdx{V + (h.value >> 1)};
      H.tail[Q.value] = c;
      mid_out[2 * h.value] = P;
      set_face(L.child(f, k), L.first_half(h), P, Qm, L.second_half(hprev));
      hprev = h;
      h = hn;
    }
    // Centre ring: Q_0 < Q_1 < ... already sorted.
    for (std::uint32_t k = 0; k < n; ++k) {
      const HalfedgeIdx a{2 * (I + k) + 1}, b{2 * (I + (k + 1) % n) + 1};
      H.vnext[a.value] = b;
      H.vprev[b.value] = a;
    }
    N.out[c.value] = HalfedgeIdx{2 * I + 1};
  });

  // 3. Edges: tails of the two halves, the midpoint node and its ring
  // {2e+1, 2(E+e), interior ones} (already in increasing order but the
  // interior ones of the two sides, sorted by insertion).
  auto& ET = m.edges;
  par::for_each_n(ctx, E, [&](std::size_t e) {
    const auto ei = static_cast<std::uint32_t>(e);
    const NodeIdx a = H.tail[2 * ei], b = H.tail[2 * ei + 1];
    const NodeIdx mn{V + ei};
    const std::uint32_t he = 2 * (E + ei);
    H.tail[2 * ei + 1] = mn;
    H.tail[he] = mn;
    H.tail[he + 1] = b;
    N.position[mn.value] = midpoint(N.position[a.value], N.position[b.value]);
    N.position_backup[mn.value] = midpoint(N.position_backup[a.value], N.position_backup[b.value]);
    N.uv[mn.value] = midpoint(N.uv[a.value], N.uv[b.value]);
    N.surface[mn.value] = N.surface[a.value];
    // A wire edge between ring nodes stays inside their face.
    N.in_face[mn.value] = N.in_face[a.value].valid() && N.in_face[a.value] == N.in_face[b.value] ? N.in_face[a.value]
                                                                                                  : FaceIdx{};
    ET.flags[E + ei] = ET.flags[ei];
    ET.mesh_edge[E + ei] = ET.mesh_edge[ei];
    std::array<HalfedgeIdx, 6> ring;
    std::size_t n = 0;
    ring[n++] = HalfedgeIdx{2 * ei + 1};
    ring[n++] = HalfedgeIdx{he};
    for (std::size_t k = 4 * e; k < 4 * e + 4; ++k)
      if (mid_out[k].valid()) {
        std::size_t j = n++;
        while (j > 2 && ring[j - 1] > mid_out[k]) {
          ring[j] = ring[j - 1];
          --j;
        }
        ring[j] = mid_out[k];
      }
    link_ring(ring, n);
    N.out[mn.value] = ring[0];
  });

  remap_attributes(m, L, ctx);
  relocate_polygon_face_nodes(m, L, poly_nodes);
  remap_mesh_edges(m, L);
  fill_map(map, L, ctx);
  ++m.topology_version;
  ++m.geometry_version;
  return map;
}

// ----------------------------------------------------------------- naive

Expected<SubdivisionMap> subdivide_uniform_naive(Model& m) {
  SubdivisionMap map;
  if (has_free_node_edge_face_slots(m)) {
    map.compaction = m.compact();
    map.compacted = true;
  }
  const auto poly_nodes = polygon_face_nodes(m);
  const ExecContext seq = ExecContext::sequential();
  const Layout L = make_layout(m, seq);
  const std::uint32_t V = L.V, E = L.E, F = L.F;

  // Snapshot the faces, then remove them (in reverse, so the LIFO free list
  // hands slot f back to face f's first child).
  struct Snap {
    SurfaceIdx surface;
    std::uint8_t flags;
    std::vector<HalfedgeIdx> h;
    std::vector<NodeIdx> v;
  };
  std::vector<Snap> snap(F);
  for (std::uint32_t f = 0; f < F; ++f) {
    snap[f].surface = m.faces.surface[f];
    snap[f].flags = m.faces.flags[f];
    m.face_halfedges(FaceIdx{f}, snap[f].h);
    m.face_nodes(FaceIdx{f}, snap[f].v);
  }
  for (std::uint32_t f = F; f-- > 0;) m.delete_face(FaceIdx{f});

  // Split every edge: a -> b becomes a -> mid (edge e) and mid -> b (new edge).
  for (std::uint32_t e = 0; e < E; ++e) {
    const NodeIdx a = m.tail(HalfedgeIdx{2 * e}), b = m.tail(HalfedgeIdx{2 * e + 1});
    const NodeIdx mid = m.new_node(m.nodes.surface[a.value], midpoint(m.position(a), m.position(b)));
    m.nodes.position_backup[mid.value] = midpoint(m.nodes.position_backup[a.value], m.nodes.position_backup[b.value]);
    m.nodes.uv[mid.value] = midpoint(m.nodes.uv[a.value], m.nodes.uv[b.value]);
    const FaceIdx ra = m.nodes.in_face[a.value];
    m.nodes.in_face[mid.value] = ra.valid() && ra == m.nodes.in_face[b.value] ? ra : FaceIdx{};
    m.set_tail(HalfedgeIdx{2 * e + 1}, mid);
    const EdgeIdx e2 = m.new_edge(mid, b);
    if (e2.value != E + e || mid.value != V + e) return Status(ErrorCode::kInternal, "naive split: unexpected slot");
    m.edges.flags[e2.value] = m.edges.flags[e];
    m.edges.mesh_edge[e2.value] = m.edges.mesh_edge[e];
  }

  auto make_face = [&](const Snap& s, std::initializer_list<NodeIdx> cyc) {
    std::vector<HalfedgeIdx> cycle;
    const NodeIdx* p = cyc.begin();
    for (std::size_t k = 0; k < cyc.size(); ++k) cycle.push_back(m.find_halfedge(p[k], p[(k + 1) % cyc.size()]));
    const FaceIdx c = m.new_face(s.surface, cycle);
    m.faces.flags[c.value] = s.flags;
    return c;
  };
  auto mids = [&](const Snap& s) {
    std::vector<NodeIdx> mid(s.h.size());
    for (std::size_t k = 0; k < s.h.size(); ++k) mid[k] = NodeIdx{V + (s.h[k].value >> 1)};
    return mid;
  };
  // First children (interior edges, centre nodes, child 0) face by face, then
  // the other children, so the slots match the fast split's layout.
  std::vector<NodeIdx> centre(F);
  for (std::uint32_t f = 0; f < F; ++f) {
    const Snap& s = snap[f];
    const std::size_t n = s.v.size();
    const std::vector<NodeIdx> mid = mids(s);
    if (n == 3) {
      for (unsigned k = 0; k < 3; ++k) (void)m.new_edge(mid[k], mid[(k + 2) % 3]);
      make_face(s, {s.v[0], mid[0], mid[2]});
      continue;
    }
    const NodeIdx c =
        m.new_node(s.surface, centroid<Vec3d>(n, [&](std::size_t k) { return m.position(s.v[k]); }));
    m.nodes.position_backup[c.value] =
        centroid<Vec3d>(n, [&](std::size_t k) { return m.nodes.position_backup[s.v[k].value]; });
    m.nodes.uv[c.value] = centroid<Vec2d>(n, [&](std::size_t k) { return m.nodes.uv[s.v[k].value]; });
    centre[f] = c;
    for (std::size_t k = 0; k < n; ++k) (void)m.new_edge(mid[k], c);
    make_face(s, {s.v[0], mid[0], c, mid[n - 1]});
  }
  for (std::uint32_t f = 0; f < F; ++f) {
    const Snap& s = snap[f];
    const std::size_t n = s.v.size();
    const std::vector<NodeIdx> mid = mids(s);
    if (n == 3) {
      make_face(s, {s.v[1], mid[1], mid[0]});
      make_face(s, {s.v[2], mid[2], mid[1]});
      make_face(s, {mid[0], mid[1], mid[2]});
      continue;
    }
    for (std::size_t k = 1; k < n; ++k) make_face(s, {s.v[k], mid[k], centre[f], mid[k - 1]});
  }

  remap_attributes(m, L, seq);
  relocate_polygon_face_nodes(m, L, poly_nodes);
  remap_mesh_edges(m, L);
  fill_map(map, L, seq);
  ++m.geometry_version;
  return map;
}

}  // namespace atelier
