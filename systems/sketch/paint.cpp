// Why this file is long: the section of the stroke sheet with the mesh is
// one algorithm in four tightly coupled stages (exact screen predicates,
// per-triangle pieces, splicing into chains and layers, the visible-layer
// choice); splitting them would only move shared private types into a
// detail header read by nobody else.
#include <atelier/engine/parallel.h>
#include <atelier/engine/status_format.h>
#include <atelier/systems/mesh/edit.h>
#include <atelier/systems/sketch/paint.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

namespace atelier {

double TracedCurve::length() const noexcept {
  double l = 0;
  for (std::size_t i = 1; i < points.size(); ++i) l += (points[i].position - points[i - 1].position).norm();
  return l;
}

namespace {

using i64 = std::int64_t;
__extension__ typedef __int128 i128;  // exact orientation of 57-bit coordinates

constexpr double kSnap = 65536.0;              // snapped pixel grid: 2^-16 pixel
constexpr double kMaxPixel = 1099511627776.0;  // 2^40 pixels
constexpr std::size_t kChunk = 4096;           // faces per parallel chunk (fixed: results do not depend on threads)
constexpr double kStepTolerance = 1e-12;       // |ds| below this is no step (turn detection)

int sgn(i128 v) noexcept {
  return (v > 0) - (v < 0);
}

struct P2 {
  i64 x = 0, y = 0;
  friend bool operator==(const P2&, const P2&) = default;
};

i128 orient(const P2& a, const P2& b, const P2& c) noexcept {
  return static_cast<i128>(b.x - a.x) * (c.y - a.y) - static_cast<i128>(b.y - a.y) * (c.x - a.x);
}

/// Side of node A of the stroke line p -> q, the stroke translated by
/// (e, e^2): orient(p+d, q+d, A) = orient(p, q, A) + (qy-py) e - (qx-px) e^2.
int node_side(const P2& p, const P2& q, const P2& a) noexcept {
  const int s = sgn(orient(p, q, a));
  if (s) return s;
  if (q.y != p.y) return q.y > p.y ? 1 : -1;
  return p.x > q.x ? 1 : -1;
}

/// Side of stroke point q (translated by (e, e^2)) of the projected edge
/// u -> v: orient(u, v, q) - (vy-uy) e + (vx-ux) e^2. A degenerate edge
/// (u == v) gets +1, which is consistent because callers always pass the
/// canonical (smaller node first) order.
int point_side(const P2& u, const P2& v, const P2& q) noexcept {
  const int s = sgn(orient(u, v, q));
  if (s) return s;
  if (v.y != u.y) return u.y > v.y ? 1 : -1;
  if (v.x != u.x) return v.x > u.x ? 1 : -1;
  return 1;
}

/// The screen image of one node: snapped pixel for the predicates, exact
/// pixel, clip w and the depth key (larger = nearer; affine in screen space
/// along any projected segment) for the geometry.
struct NodeImage {
  P2 snapped;
  Vec2d pixel;
  double w = 0, key = 0;
};

/// The nodes on screen: for every node where its snapped pixel lies against
/// the stroke's box (bits: left of, right of, above, below; 16: not alive,
/// behind the eye or beyond 2^40 pixels), so that a face whose corners'
/// codes share a bit is off the box, found with one byte per corner; and the
/// full image only of the corners of the faces kept (most faces lie away
/// from the stroke; projecting every node into four full columns was a
/// fifth of painting).
struct Screen {
  Mat4d pv;
  bool perspective = false;
  std::vector<std::uint8_t> code;
  static constexpr std::uint8_t kNotOk = 16;
  static constexpr std::uint8_t kImaged = 32;  // the node has an image
  std::vector<std::uint8_t> culled;            // per face slot (culled_faces)
  std::unique_ptr<std::uint32_t[]> slot;       // per imaged node: its image (set only where kImaged)
  std::vector<NodeImage> images;

  [[nodiscard]] const NodeImage& image(NodeIdx v) const { return images[slot[v.value]]; }
  [[nodiscard]] double key_of(const Vec3d& x) const {
    const Vec4d c = pv * Vec4d(x.x(), x.y(), x.z(), 1.0);
    return perspective ? 1.0 / c.w() : -c.z() / c.w();
  }
};

/// The first half of project_point (the same bits): clip coordinates and
/// pixel, false exactly when project_point fails.
bool project_xy(const Mat4d& pv, double W, double H, const Vec3d& x, Vec4d& c, double& px, double& py) {
  c = pv * Vec4d(x.x(), x.y(), x.z(), 1.0);
  if (!(c.w() > 0) || !c.allFinite()) return false;
  px = (c.x() / c.w() + 1.0) * 0.5 * W;
  py = (1.0 - c.y() / c.w()) * 0.5 * H;
  return std::abs(px) < kMaxPixel && std::abs(py) < kMaxPixel;
}

/// Where the snapped pixel llround(p * kSnap) lies against the snapped box
/// [lo, hi] (bits: left of, right of, above, below), each bit set only where
/// it holds whatever the rounding, so no llround is needed: a bit set here
/// is set in the exact code, and a cull by these bits culls nothing the
/// exact code would keep. The margin covers the rounding of llround (1/2)
/// and of the thresholds themselves (below 2^56 in magnitude).
std::uint8_t sure_code(double px, double py, double lox, double hix, double loy, double hiy) {
  auto below = [](double x, double lo) { return x * kSnap < lo - 1.0 - std::abs(lo) * 1e-15; };
  auto above = [](double x, double hi) { return x * kSnap > hi + 1.0 + std::abs(hi) * 1e-15; };
  return static_cast<std::uint8_t>(below(px, lox) | above(px, hix) << 1 | below(py, loy) << 2 | above(py, hiy) << 3);
}

/// Where llround(x) lies against [lo, hi] (integer-valued, below 2^63 in
/// magnitude; bits: 1 below, 2 above), rounding only near the ends: llround
/// is monotonic and keeps integers, so an x inside [lo, hi] snaps inside,
/// and one beyond sure_code's margins snaps outside. The same bits as
/// rounding every x (painting's codes rounded two coordinates of every node,
/// a libm call each).
int snapped_side(double x, double lo, double hi) {
  if (x >= lo && x <= hi) return 0;
  if (x < lo - 1.0 - std::abs(lo) * 1e-15) return 1;
  if (x > hi + 1.0 + std::abs(hi) * 1e-15) return 2;
  const double r = double(std::llround(x));
  return (r < lo) | (r > hi) << 1;
}

/// The screen image of one point (false when behind the eye, not finite or
/// beyond 2^40 pixels). Painting and picking both project through here, so
/// they see the same bits.
bool project_point(const Mat4d& pv, bool perspective, double W, double H, const Vec3d& x, NodeImage& out) {
  Vec4d c;
  double px = 0, py = 0;
  if (!project_xy(pv, W, H, x, c, px, py)) return false;
  out.pixel = Vec2d(px, py);
  out.snapped = {std::llround(px * kSnap), std::llround(py * kSnap)};
  out.w = c.w();
  out.key = perspective ? 1.0 / c.w() : -c.z() / c.w();
  return true;
}

/// Per face slot, 1 when the face is culled: its corners' codes share an
/// outside bit (15) or one is not projectable (`not_ok`). One pass over the
/// halfedge columns in memory order: walking each face's cycle reads them
/// at random, which was most of the time of a cull (the codes and the
/// result are a byte per node and per face and stay in cache). The same
/// halfedges as the face's cycle (halfedge face column), so the same result.
std::vector<std::uint8_t> culled_faces(const Model& m, std::span<const std::uint8_t> code, std::uint8_t not_ok) {
  const std::size_t nf = m.faces.slots.capacity(), ne = m.edges.slots.capacity();
  std::vector<std::uint8_t> all(nf, 0xFF), any(nf, 0);
  const auto& tail = m.halfedges.tail;
  const auto& face = m.halfedges.face;
  for (std::size_t h = 0; h < 2 * ne; ++h) {
    const FaceIdx f = face[h];
    if (!f.valid() || !m.alive(EdgeIdx{static_cast<std::uint32_t>(h >> 1)})) continue;
    const std::uint8_t c = code[tail[h].value];
    all[f.value] &= c;
    any[f.value] |= c;
  }
  for (std::size_t f = 0; f < nf; ++f) all[f] = (any[f] & not_ok) || (all[f] & 15) ? 1 : 0;
  return all;
}

Screen project_nodes(const Model& m, const Camera& cam, const Box3d& box, std::span<const std::uint8_t> surf_mask,
                     const ExecContext& ctx) {
  Screen s;
  s.pv = cam.projection * cam.view;
  s.perspective = cam.perspective();
  const std::size_t n = m.nodes.slots.capacity();
  s.code.assign(n, Screen::kNotOk);
  const double W = cam.width, H = cam.height;
  // The codes: the snapped pixel only (the same bits as project_point's).
  par::for_each_n(ctx, n, [&](std::size_t v) {
    if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)})) return;
    Vec4d c;
    double px = 0, py = 0;
    if (!project_xy(s.pv, W, H, m.nodes.position[v], c, px, py)) return;
    s.code[v] = static_cast<std::uint8_t>(snapped_side(px * kSnap, box.lo.x(), box.hi.x()) |
                                          snapped_side(py * kSnap, box.lo.y(), box.hi.y()) << 2);
  });
  s.culled = culled_faces(m, s.code, Screen::kNotOk);
  // The images of the kept faces' corners, numbered in face order.
  s.slot.reset(new std::uint32_t[n]);
  std::vector<HalfedgeIdx> hs;
  std::vector<NodeIdx> kept_corners;
  for (std::size_t f = 0; f < s.culled.size(); ++f) {
    if (s.culled[f] || !surf_mask[m.faces.surface[f].value]) continue;
    m.face_halfedges(FaceIdx{static_cast<std::uint32_t>(f)}, hs);
    for (HalfedgeIdx h : hs) {
      const NodeIdx v = m.tail(h);
      if (s.code[v.value] & Screen::kImaged) continue;
      s.code[v.value] |= Screen::kImaged;
      s.slot[v.value] = static_cast<std::uint32_t>(kept_corners.size());
      kept_corners.push_back(v);
    }
  }
  s.images.resize(kept_corners.size());
  par::for_each_n(ctx, kept_corners.size(), [&](std::size_t i) {
    // Kept faces' corners are projectable (a face with one that is not is culled).
    (void)project_point(s.pv, s.perspective, W, H, m.position(kept_corners[i]), s.images[i]);
  });
  return s;
}

/// The stroke after removing repeated points (equal once snapped).
struct StrokeData {
  std::vector<Vec2d> px;
  std::vector<P2> snapped;
  std::vector<std::size_t> original;  // index in the caller's stroke
  std::vector<Vec4d> plane;           // per segment: world plane through the eye and the segment
  bool closed = false;
  Box3d box2;  // x, y of the snapped bounding box (z unused)
  [[nodiscard]] std::size_t segments() const noexcept { return px.size() - 1; }
};

Expected<StrokeData> prepare_stroke(const Camera& cam, const Mat4d& pv, std::span<const Vec2d> stroke) {
  StrokeData d;
  for (std::size_t i = 0; i < stroke.size(); ++i) {
    const Vec2d& p = stroke[i];
    if (!p.allFinite() || !(std::abs(p.x()) < kMaxPixel) || !(std::abs(p.y()) < kMaxPixel))
      return status_of(ErrorCode::kInvalidArgument, "stroke point ", i, " is not a finite pixel within 2^40");
    const P2 q{std::llround(p.x() * kSnap), std::llround(p.y() * kSnap)};
    if (!d.snapped.empty() && d.snapped.back() == q) continue;
    d.px.push_back(p);
    d.snapped.push_back(q);
    d.original.push_back(i);
  }
  if (d.px.size() < 2)
    return status_of(ErrorCode::kInvalidArgument, "a stroke needs at least 2 distinct points (got ", stroke.size(),
                     ")");
  d.closed = d.px.size() >= 3 && d.snapped.front() == d.snapped.back();
  const double W = cam.width, H = cam.height;
  for (std::size_t i = 0; i + 1 < d.px.size(); ++i) {
    // w * orient(p, q, pixel(X)) is linear in clip coordinates: a plane.
    const Vec2d p = d.px[i], q = d.px[i + 1];
    const double dx = q.x() - p.x(), dy = q.y() - p.y();
    const Vec4d l(-dy * W / 2, -dx * H / 2, 0.0, dx * (H / 2 - p.y()) - dy * (W / 2 - p.x()));
    d.plane.push_back(pv.transpose() * l);
  }
  for (const P2& q : d.snapped) d.box2.extend(Vec3d(double(q.x), double(q.y), 0));
  return d;
}

/// Uniform grid over the stroke's bounding box listing the segments whose
/// boxes overlap each cell.
class SegmentGrid {
 public:
  explicit SegmentGrid(const StrokeData& s) {
    lo_x_ = s.box2.lo.x();
    lo_y_ = s.box2.lo.y();
    const double ext = std::max({s.box2.hi.x() - lo_x_, s.box2.hi.y() - lo_y_, 1.0});
    n_ = std::clamp<int>(static_cast<int>(std::sqrt(double(s.segments())) * 2), 1, 256);
    cell_ = ext / n_ * (1 + 1e-9);
    cells_.resize(std::size_t(n_) * n_);
    seg_box_.reserve(s.segments());
    for (std::size_t i = 0; i < s.segments(); ++i) {
      const P2 a = s.snapped[i], b = s.snapped[i + 1];
      seg_box_.push_back({P2{std::min(a.x, b.x), std::min(a.y, b.y)}, P2{std::max(a.x, b.x), std::max(a.y, b.y)}});
      const int x0 = cx(double(std::min(a.x, b.x))), x1 = cx(double(std::max(a.x, b.x)));
      const int y0 = cy(double(std::min(a.y, b.y))), y1 = cy(double(std::max(a.y, b.y)));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) cells_[std::size_t(y) * n_ + x].push_back(static_cast<std::uint32_t>(i));
    }
    box_ = s.box2;
  }
  /// Segments whose cells overlap the box [lo, hi] of snapped pixels and
  /// whose own boxes are not strictly apart from it (sorted, unique) into
  /// out. A segment strictly apart (a gap of at least one snapped unit on
  /// one axis) cannot meet a triangle inside the box, even translated by the
  /// infinitesimal (e, e^2) of node_side and point_side: its line crossings
  /// would fall outside the segment and no end would pierce, so cut_triangle
  /// would make nothing of it. Most cells' candidates end here, before the
  /// exact side tests (a stroke spanning the mesh has wide cells).
  void query(const P2& lo, const P2& hi, std::vector<std::uint32_t>& out) const {
    out.clear();
    const double lox = double(lo.x), loy = double(lo.y), hix = double(hi.x), hiy = double(hi.y);
    if (hix < box_.lo.x() || lox > box_.hi.x() || hiy < box_.lo.y() || loy > box_.hi.y()) return;
    const int x0 = cx(lox), x1 = cx(hix), y0 = cy(loy), y1 = cy(hiy);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        for (std::uint32_t i : cells_[std::size_t(y) * n_ + x]) {
          const auto& b = seg_box_[i];
          if (b[1].x < lo.x || b[0].x > hi.x || b[1].y < lo.y || b[0].y > hi.y) continue;
          out.push_back(i);
        }
    // One cell's list is already increasing (segments are added in order).
    if (x0 == x1 && y0 == y1) return;
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

 private:
  int cx(double x) const { return std::clamp(static_cast<int>((x - lo_x_) / cell_), 0, n_ - 1); }
  int cy(double y) const { return std::clamp(static_cast<int>((y - lo_y_) / cell_), 0, n_ - 1); }
  double lo_x_ = 0, lo_y_ = 0, cell_ = 1;
  int n_ = 1;
  Box3d box_;
  std::vector<std::vector<std::uint32_t>> cells_;
  std::vector<std::array<P2, 2>> seg_box_;  // per segment: snapped lo, hi
};

// ------------------------------------------------------------ the section

enum class VKind : std::uint8_t { kEdge = 0, kDiagonal = 1, kPierce = 2 };

/// A vertex of the section: an edge or diagonal crossing in a sector, or a
/// stroke point's ray piercing a fan triangle.
struct VKey {
  VKind kind = VKind::kEdge;
  std::uint32_t a = 0;  // edge, or face
  std::uint32_t b = 0;  // 0, diagonal index d (c0 - c_d), or fan index
  std::uint32_t c = 0;  // sector, or stroke point
  friend auto operator<=>(const VKey&, const VKey&) = default;
};

struct Vertex {
  VKey key;
  CurvePoint point;
  double depth = 0;  // larger = nearer
};

struct SectionPiece {
  FaceIdx face;
  std::uint32_t sector = 0;
  VKey end[2];
};

struct Section {
  std::vector<Vertex> vertices;  // sorted by key, unique
  std::vector<SectionPiece> pieces;
  std::size_t triangles = 0;
  [[nodiscard]] std::uint32_t find(const VKey& k) const {
    auto it =
        std::lower_bound(vertices.begin(), vertices.end(), k, [](const Vertex& v, const VKey& x) { return v.key < x; });
    return it != vertices.end() && it->key == k ? static_cast<std::uint32_t>(it - vertices.begin())
                                                : std::numeric_limits<std::uint32_t>::max();
  }
};

/// A fan triangle (c0, c_j+1, c_j+2) of a face and its three sides.
struct FanTri {
  FaceIdx face;
  std::uint32_t fan = 0, degree = 0;
  NodeIdx n[3];
  HalfedgeIdx real[3];                // the face halfedge along side k, or invalid for a fan diagonal
  std::uint32_t diag[3] = {0, 0, 0};  // for diagonals: d with the diagonal c0 - c_d
};

/// Areal coordinates of pixel q in the projected triangle, corrected for
/// perspective (divided by w) so that they weigh the 3D corners.
Vec3d pierce_weights(const Vec2d& a, const Vec2d& b, const Vec2d& c, const double (&w)[3], const Vec2d& q) {
  const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  Vec3d beta;
  if (std::abs(area) > 1e-300 && std::isfinite(area)) {
    const double wb = ((q - a).x() * (c - a).y() - (q - a).y() * (c - a).x()) / area;
    const double wc = ((b - a).x() * (q - a).y() - (b - a).y() * (q - a).x()) / area;
    beta = Vec3d(1 - wb - wc, wb, wc);
  } else {
    beta = Vec3d(1.0 / 3, 1.0 / 3, 1.0 / 3);
  }
  Vec3d l(beta[0] / w[0], beta[1] / w[1], beta[2] / w[2]);
  l = l.cwiseMax(0.0);
  const double sum = l.sum();
  if (!(sum > 0) || !std::isfinite(sum)) return Vec3d(1.0 / 3, 1.0 / 3, 1.0 / 3);
  return l / sum;
}
Vec3d pierce_weights(const Screen& s, const FanTri& t, const Vec2d& q) {
  const NodeImage &a = s.image(t.n[0]), &b = s.image(t.n[1]), &c = s.image(t.n[2]);
  const double w[3] = {a.w, b.w, c.w};
  return pierce_weights(a.pixel, b.pixel, c.pixel, w, q);
}

struct ChunkOut {
  std::vector<Vertex> vertices;
  std::vector<SectionPiece> pieces;
  std::size_t triangles = 0;
  Status status;
};

/// Cuts one fan triangle with the candidate sectors.
void cut_triangle(const Model& m, const Screen& sc, const StrokeData& sd, const FanTri& t,
                  std::span<const std::uint32_t> sectors, ChunkOut& out) {
  const P2 c[3] = {sc.image(t.n[0]).snapped, sc.image(t.n[1]).snapped, sc.image(t.n[2]).snapped};
  // Canonical side orientation: smaller node index first.
  auto side_sign = [&](int k, const P2& q) {
    const int a = k, b = (k + 1) % 3;
    const bool fwd = t.n[a] < t.n[b];
    const int s = fwd ? point_side(c[a], c[b], q) : point_side(c[b], c[a], q);
    return fwd ? s : -s;
  };
  std::map<std::uint32_t, bool> inside_memo;
  auto inside = [&](std::uint32_t j) {
    auto it = inside_memo.find(j);
    if (it != inside_memo.end()) return it->second;
    const P2& q = sd.snapped[j];
    const int s0 = side_sign(0, q), s1 = side_sign(1, q), s2 = side_sign(2, q);
    const bool in = s0 == s1 && s1 == s2;
    inside_memo.emplace(j, in);
    return in;
  };
  const SurfaceIdx surf = m.faces.surface[t.face.value];
  auto add_pierce = [&](std::uint32_t j) {
    Vertex v;
    v.key = {VKind::kPierce, t.face.value, t.fan, j};
    const Vec3d l = pierce_weights(sc, t, sd.px[j]);
    v.point.location = {AttribNodeKind::kFace, t.face.value, l, static_cast<std::uint8_t>(t.fan)};
    v.point.surface = surf;
    v.point.position = l[0] * m.position(t.n[0]) + l[1] * m.position(t.n[1]) + l[2] * m.position(t.n[2]);
    v.point.s = double(j);
    v.depth = sc.key_of(v.point.position);
    out.vertices.push_back(v);
    return v.key;
  };
  bool any = false;
  for (std::uint32_t i : sectors) {
    const P2 &p = sd.snapped[i], &q = sd.snapped[i + 1];
    const int s[3] = {node_side(p, q, c[0]), node_side(p, q, c[1]), node_side(p, q, c[2])};
    if (s[0] == s[1] && s[1] == s[2]) continue;
    VKey ends[4];
    int ne = 0;
    for (int k = 0; k < 3; ++k) {
      const int a = k, b = (k + 1) % 3;
      if (s[a] == s[b]) continue;
      const int ia = t.n[a] < t.n[b] ? a : b, ib = ia == a ? b : a;  // canonical order
      const P2 &U = c[ia], &V = c[ib];
      const int sp = point_side(U, V, p), sq = point_side(U, V, q);
      if (sp == sq) continue;  // the line crosses this side outside the segment
      Vertex v;
      const NodeIdx nu = t.n[ia], nv = t.n[ib];
      if (t.real[k].valid()) {
        v.key = {VKind::kEdge, edge_of(t.real[k]).value, 0, i};
      } else {
        v.key = {VKind::kDiagonal, t.face.value, t.diag[k], i};
      }
      // 3D crossing on the segment's plane (canonical order, so both faces
      // of the edge compute the same bits).
      const Vec3d &xu = m.position(nu), &xv = m.position(nv);
      const Vec4d& pl = sd.plane[i];
      const double du = pl.head<3>().dot(xu) + pl.w(), dv = pl.head<3>().dot(xv) + pl.w();
      double u;
      if (du != dv && std::isfinite(du) && std::isfinite(dv) && (du <= 0) != (dv <= 0)) {
        u = du / (du - dv);
      } else {
        // Rounding disagrees with the exact side test: the 2D parameter,
        // corrected for perspective.
        const double ou = double(orient(p, q, U)), ov = double(orient(p, q, V));
        const double sg = ou != ov ? ou / (ou - ov) : 0.5;
        const double a1 = (1 - sg) / sc.image(nu).w, a2 = sg / sc.image(nv).w;
        u = a2 / (a1 + a2);
      }
      u = std::clamp(u, 0.0, 1.0);
      v.point.position = (1 - u) * xu + u * xv;
      v.point.surface = surf;
      if (t.real[k].valid()) {
        const HalfedgeIdx h0 = halfedge_of(edge_of(t.real[k]), 0);
        const double uh = m.tail(h0) == nu ? u : 1 - u;
        v.point.location = {AttribNodeKind::kEdge, h0.value, Vec3d(uh, 0, 0), 0};
      } else {
        // Diagonal c0 - c_d: side 2 of fan d-2, areal (1-w, 0, w) from c0.
        const NodeIdx c0 = t.n[0];
        const double wd = nu == c0 ? u : 1 - u;
        v.point.location = {AttribNodeKind::kFace, t.face.value, Vec3d(1 - wd, 0, wd),
                            static_cast<std::uint8_t>(t.diag[k] - 2)};
      }
      const double op = double(orient(U, V, p)), oq = double(orient(U, V, q));
      const double tt = op != oq ? std::clamp(op / (op - oq), 0.0, 1.0) : 0.5;
      v.point.s = double(i) + tt;
      v.depth = sc.key_of(v.point.position);
      if (ne < 4) ends[ne] = v.key;
      ++ne;
      out.vertices.push_back(v);
    }
    for (std::uint32_t j : {i, i + 1})
      if (inside(j)) {
        const VKey k = add_pierce(j);
        if (ne < 4) ends[ne] = k;
        ++ne;
      }
    if (ne == 0) continue;
    if (ne != 2) {
      out.status = status_of(ErrorCode::kInternal, "painting: the section of face ", t.face.value, " fan ", t.fan,
                             " with stroke segment ", i, " has ", ne, " ends");
      return;
    }
    out.pieces.push_back({t.face, i, {ends[0], ends[1]}});
    any = true;
  }
  out.triangles += any;
}

Expected<std::vector<std::uint8_t>> surface_mask(const Model& m, std::span<const SurfaceIdx> surfaces) {
  std::vector<std::uint8_t> mask(m.surfaces.slots.capacity(), surfaces.empty() ? 1 : 0);
  for (SurfaceIdx s : surfaces) {
    if (!s.valid() || s.value >= mask.size() || !m.alive(s))
      return status_of(ErrorCode::kInvalidArgument, "painting: surface ", s.value, " is not a live surface");
    mask[s.value] = 1;
  }
  return mask;
}

/// Fan triangles of face f in `tris` (sides classified).
void fan_triangles(const Model& m, FaceIdx f, std::vector<HalfedgeIdx>& hs, std::vector<FanTri>& tris) {
  m.face_halfedges(f, hs);
  const auto k = static_cast<std::uint32_t>(hs.size());
  tris.clear();
  for (std::uint32_t j = 0; j + 2 < k; ++j) {
    FanTri t;
    t.face = f;
    t.fan = j;
    t.degree = k;
    t.n[0] = m.tail(hs[0]);
    t.n[1] = m.tail(hs[j + 1]);
    t.n[2] = m.tail(hs[j + 2]);
    t.real[0] = j == 0 ? hs[0] : HalfedgeIdx{};
    t.diag[0] = j + 1;
    t.real[1] = hs[j + 1];
    t.real[2] = j + 3 == k ? hs[k - 1] : HalfedgeIdx{};
    t.diag[2] = j + 2;
    tris.push_back(t);
  }
}

Expected<Section> build_section(const Model& m, const Screen& sc, const StrokeData& sd,
                                std::span<const std::uint8_t> surf_mask, const ExecContext& ctx) {
  const SegmentGrid grid(sd);
  const std::size_t nf = m.faces.slots.capacity();
  // Faces culled by their screen boxes (most faces lie away from the stroke).
  const std::vector<std::uint8_t>& culled = sc.culled;
  const std::size_t chunks = (nf + kChunk - 1) / kChunk;
  std::vector<ChunkOut> outs(chunks);
  ExecContext c = ctx;
  c.sequential_threshold = std::max<std::size_t>(1, ctx.sequential_threshold / kChunk);
  c.grain = 1;
  par::for_each_n(c, chunks, [&](std::size_t ch) {
    ChunkOut& out = outs[ch];
    std::vector<HalfedgeIdx> hs;
    std::vector<FanTri> tris;
    std::vector<std::uint32_t> sectors;
    const std::size_t end = std::min(nf, (ch + 1) * kChunk);
    for (std::size_t fi = ch * kChunk; fi < end && out.status; ++fi) {
      const FaceIdx f{static_cast<std::uint32_t>(fi)};
      if (!m.alive(f) || culled[fi] || !surf_mask[m.faces.surface[fi].value]) continue;
      fan_triangles(m, f, hs, tris);
      if (hs.size() > 257) {
        out.status =
            status_of(ErrorCode::kInvalidArgument, "painting: face ", fi, " has ", hs.size(), " corners (at most 257)");
        return;
      }
      for (const FanTri& t : tris) {
        P2 lo = sc.image(t.n[0]).snapped, hi = lo;
        for (int k = 1; k < 3; ++k) {
          const P2& q = sc.image(t.n[k]).snapped;
          lo = {std::min(lo.x, q.x), std::min(lo.y, q.y)};
          hi = {std::max(hi.x, q.x), std::max(hi.y, q.y)};
        }
        grid.query(lo, hi, sectors);
        if (!sectors.empty()) cut_triangle(m, sc, sd, t, sectors, out);
        if (!out.status) return;
      }
    }
  });
  Section s;
  for (ChunkOut& o : outs) {
    if (!o.status) return o.status;
    s.vertices.insert(s.vertices.end(), o.vertices.begin(), o.vertices.end());
    s.pieces.insert(s.pieces.end(), o.pieces.begin(), o.pieces.end());
    s.triangles += o.triangles;
  }
  // Edge crossings are computed by both faces of the edge, bit-identically.
  std::stable_sort(s.vertices.begin(), s.vertices.end(),
                   [](const Vertex& a, const Vertex& b) { return a.key < b.key; });
  s.vertices.erase(std::unique(s.vertices.begin(), s.vertices.end(),
                               [](const Vertex& a, const Vertex& b) { return a.key == b.key; }),
                   s.vertices.end());
  return s;
}

// ------------------------------------------------------- chains and layers

/// The section as a graph: vertices, and arcs that are pieces or links
/// (joint partners, the closure of a closed stroke).
struct Graph {
  struct Arc {
    std::uint32_t a = 0, b = 0;
    std::int64_t piece = -1;  // index into Section::pieces, -1 for a link
  };
  std::vector<Arc> arcs;
  std::vector<std::uint32_t> first;  // CSR over vertices
  std::vector<std::uint32_t> list;   // arc ids
  [[nodiscard]] std::size_t degree(std::uint32_t v) const { return first[v + 1] - first[v]; }
};

Graph build_graph(const Model& m, const Section& s, const StrokeData& sd) {
  Graph g;
  for (std::size_t i = 0; i < s.pieces.size(); ++i)
    g.arcs.push_back({s.find(s.pieces[i].end[0]), s.find(s.pieces[i].end[1]), static_cast<std::int64_t>(i)});
  // Joint links: an edge crossing on a joint edge continues on every
  // partner's corresponding edge (same sector).
  for (std::uint32_t v = 0; v < s.vertices.size(); ++v) {
    const VKey& k = s.vertices[v].key;
    if (k.kind != VKind::kEdge) continue;
    const EdgeIdx e{k.a};
    const MeshEdgeIdx me = m.edges.mesh_edge[e.value];
    if (!me.valid() || !m.mesh_edges.joint[me.value].valid()) continue;
    for (HalfedgeIdx h : joint_corresponding_halfedges(m, halfedge_of(e, 0))) {
      const EdgeIdx e2 = edge_of(h);
      if (e2.value <= e.value) continue;  // each pair once
      const std::uint32_t w = s.find({VKind::kEdge, e2.value, 0, k.c});
      if (w != std::numeric_limits<std::uint32_t>::max()) g.arcs.push_back({v, w, -1});
    }
  }
  if (sd.closed) {
    const auto last = static_cast<std::uint32_t>(sd.px.size() - 1);
    for (std::uint32_t v = 0; v < s.vertices.size(); ++v) {
      const VKey& k = s.vertices[v].key;
      if (k.kind != VKind::kPierce || k.c != 0) continue;
      const std::uint32_t w = s.find({VKind::kPierce, k.a, k.b, last});
      if (w != std::numeric_limits<std::uint32_t>::max()) g.arcs.push_back({w, v, -1});
    }
  }
  const std::size_t nv = s.vertices.size();
  g.first.assign(nv + 1, 0);
  for (const auto& a : g.arcs) {
    ++g.first[a.a + 1];
    ++g.first[a.b + 1];
  }
  for (std::size_t v = 0; v < nv; ++v) g.first[v + 1] += g.first[v];
  g.list.resize(g.first[nv]);
  std::vector<std::uint32_t> fill(g.first.begin(), g.first.end() - 1);
  for (std::uint32_t i = 0; i < g.arcs.size(); ++i) {
    g.list[fill[g.arcs[i].a]++] = i;
    g.list[fill[g.arcs[i].b]++] = i;
  }
  return g;
}

struct Chain {
  std::vector<std::uint32_t> v;     // vertices in order
  std::vector<std::int64_t> piece;  // piece between v[k] and v[k+1] (-1: link)
  bool cycle = false;
};

std::vector<Chain> chains_of(const Graph& g, std::size_t nv) {
  std::vector<Chain> out;
  std::vector<std::uint8_t> used(g.arcs.size(), 0);
  auto walk = [&](std::uint32_t start, std::uint32_t arc0) {
    Chain c;
    c.v.push_back(start);
    std::uint32_t v = start, arc = arc0;
    while (true) {
      used[arc] = 1;
      const auto& a = g.arcs[arc];
      const std::uint32_t w = a.a == v ? a.b : a.a;
      c.piece.push_back(a.piece);
      c.v.push_back(w);
      v = w;
      if (g.degree(v) != 2) break;
      std::uint32_t nxt = std::numeric_limits<std::uint32_t>::max();
      for (std::uint32_t k = g.first[v]; k < g.first[v + 1]; ++k)
        if (!used[g.list[k]]) nxt = g.list[k];
      if (nxt == std::numeric_limits<std::uint32_t>::max()) {
        c.cycle = v == start;
        break;
      }
      arc = nxt;
    }
    out.push_back(std::move(c));
  };
  for (std::uint32_t v = 0; v < nv; ++v)
    if (g.degree(v) != 2)
      for (std::uint32_t k = g.first[v]; k < g.first[v + 1]; ++k)
        if (!used[g.list[k]]) walk(v, g.list[k]);
  for (std::uint32_t v = 0; v < nv; ++v)
    for (std::uint32_t k = g.first[v]; k < g.first[v + 1]; ++k)
      if (!used[g.list[k]]) walk(v, g.list[k]);
  return out;
}

/// A layer: part of a chain along which s is monotone.
struct Run {
  std::vector<std::uint32_t> v;
  std::vector<std::int64_t> piece;
  bool closed = false;
};

std::vector<Run> runs_of(const Section& s, std::vector<Chain> chains) {
  std::vector<Run> out;
  auto step = [&](const Chain& c, std::size_t k) {
    if (c.piece[k] < 0) return 0;  // links do not move along the stroke
    const double d = s.vertices[c.v[k + 1]].point.s - s.vertices[c.v[k]].point.s;
    return d > kStepTolerance ? 1 : d < -kStepTolerance ? -1 : 0;
  };
  for (Chain& c : chains) {
    const std::size_t n = c.piece.size();
    if (c.cycle) {
      // Start the cycle at a turn (a vertex where s changes direction), when it has one.
      std::vector<int> d(n);
      int prev = 0;
      for (std::size_t k = 0; k < n; ++k) {
        d[k] = step(c, k);
        if (d[k] != 0) prev = d[k];  // the last direction before index 0, cyclically
      }
      std::size_t start = n;
      for (std::size_t k = 0; k < n && start == n; ++k) {
        if (d[k] == 0) continue;
        if (prev != 0 && d[k] != prev) start = k;
        prev = d[k];
      }
      if (start == n) {
        out.push_back({c.v, c.piece, true});  // c.v repeats its first vertex at the end
        continue;
      }
      Chain r;
      for (std::size_t k = 0; k < n; ++k) {
        r.v.push_back(c.v[(start + k) % n]);
        r.piece.push_back(c.piece[(start + k) % n]);
      }
      r.v.push_back(c.v[start]);
      c = std::move(r);
    }
    Run cur;
    cur.v.push_back(c.v[0]);
    int dir = 0;
    for (std::size_t k = 0; k < c.piece.size(); ++k) {
      const int d = step(c, k);
      if (d != 0 && dir != 0 && d != dir) {
        out.push_back(cur);
        cur = Run{};
        cur.v.push_back(c.v[k]);
        dir = 0;
      }
      if (d != 0) dir = d;
      cur.v.push_back(c.v[k + 1]);
      cur.piece.push_back(c.piece[k]);
    }
    out.push_back(std::move(cur));
  }
  // Orient every layer along the stroke.
  for (Run& r : out) {
    double ds = 0;
    for (std::size_t k = 0; k < r.piece.size(); ++k)
      if (r.piece[k] >= 0) ds += s.vertices[r.v[k + 1]].point.s - s.vertices[r.v[k]].point.s;
    if (ds < 0) {
      std::reverse(r.v.begin(), r.v.end());
      std::reverse(r.piece.begin(), r.piece.end());
    }
  }
  return out;
}

/// Orders runs by first stroke parameter, then nearest first, then key.
void sort_runs(const Section& s, std::vector<Run>& runs) {
  auto first_s = [&](const Run& r) {
    double lo = INFINITY;
    for (std::uint32_t v : r.v) lo = std::min(lo, s.vertices[v].point.s);
    return lo;
  };
  std::stable_sort(runs.begin(), runs.end(), [&](const Run& a, const Run& b) {
    const double sa = first_s(a), sb = first_s(b);
    if (sa != sb) return sa < sb;
    const double da = s.vertices[a.v.front()].depth, db = s.vertices[b.v.front()].depth;
    if (da != db) return da > db;
    return s.vertices[a.v.front()].key < s.vertices[b.v.front()].key;
  });
}

std::string pixel_text(const StrokeData& sd, std::size_t j) {
  std::ostringstream o;
  o << "stroke point " << sd.original[j] << " (" << sd.px[j].x() << ", " << sd.px[j].y() << ")";
  return o.str();
}

/// s-range and depth keys of a piece at its ends (ordered by s).
struct PieceSpan {
  double s0 = 0, k0 = 0, s1 = 0, k1 = 0;
  [[nodiscard]] double key_at(double x) const {
    return s1 > s0 ? k0 + (k1 - k0) * (x - s0) / (s1 - s0) : std::max(k0, k1);
  }
};

PieceSpan span_of(const Section& s, std::uint32_t p) {
  const Vertex& a = s.vertices[s.find(s.pieces[p].end[0])];
  const Vertex& b = s.vertices[s.find(s.pieces[p].end[1])];
  PieceSpan r{a.point.s, a.depth, b.point.s, b.depth};
  if (r.s0 > r.s1) {
    std::swap(r.s0, r.s1);
    std::swap(r.k0, r.k1);
  }
  return r;
}

/// Painting: the one layer the stroke sees (see paint.h). The layer seen
/// at the middle of the stroke's shadow on the surface must span the whole
/// shadow and have nothing in front of it; then it is the upper envelope of
/// the section, i.e. exactly what the stroke covers on screen.
Expected<Run> visible_run(const Section& s, const StrokeData& sd, const std::vector<Run>& runs) {
  const std::size_t n = sd.px.size();
  if (s.pieces.empty())
    return Status(ErrorCode::kInvalidArgument, "painting: the stroke crosses no face of the surfaces");
  std::vector<PieceSpan> spans(s.pieces.size());
  for (std::uint32_t p = 0; p < s.pieces.size(); ++p) spans[p] = span_of(s, p);
  auto near_point = [&](double x) {
    return std::min<std::size_t>(static_cast<std::size_t>(std::max(0.0, x + 0.5)), n - 1);
  };
  // The stroke's shadow: the union of the pieces' s-ranges, one interval.
  std::vector<std::pair<double, double>> ranges;
  for (const PieceSpan& sp : spans) ranges.emplace_back(sp.s0, sp.s1);
  std::sort(ranges.begin(), ranges.end());
  double lo = ranges[0].first, hi = ranges[0].second;
  for (const auto& [a, b] : ranges) {
    if (a > hi + kStepTolerance)
      return status_of(ErrorCode::kDegenerate, "painting fails near ", pixel_text(sd, near_point(hi)),
                       ": the stroke leaves the surface and comes back near ", pixel_text(sd, near_point(a)),
                       " (a gap), so the pieces cannot be spliced into one curve; penetrated painting keeps every "
                       "layer");
    hi = std::max(hi, b);
  }
  // The layer seen at the middle of the shadow.
  const double mid = 0.5 * (lo + hi);
  std::int64_t best = -1;
  double best_key = -INFINITY;
  for (std::uint32_t p = 0; p < s.pieces.size(); ++p) {
    const PieceSpan& sp = spans[p];
    if (mid < sp.s0 || mid > sp.s1) continue;
    const double k = sp.key_at(mid);
    if (k > best_key) {
      best_key = k;
      best = p;
    }
  }
  std::int64_t run = -1;
  for (std::size_t r = 0; r < runs.size() && run < 0; ++r)
    for (std::int64_t p : runs[r].piece)
      if (p == best) run = static_cast<std::int64_t>(r);
  if (run < 0) return status_of(ErrorCode::kInternal, "painting: piece ", best, " belongs to no layer");
  const Run& R = runs[run];
  double rlo = INFINITY, rhi = -INFINITY;
  for (std::uint32_t v : R.v) {
    rlo = std::min(rlo, s.vertices[v].point.s);
    rhi = std::max(rhi, s.vertices[v].point.s);
  }
  if (rlo > lo + kStepTolerance || rhi < hi - kStepTolerance) {
    const double at = rlo > lo + kStepTolerance ? rlo : rhi;
    return status_of(ErrorCode::kDegenerate, "painting fails near ", pixel_text(sd, near_point(at)),
                     ": the visible surface jumps to another layer (a fold, seed 001 Fig. 10, or an occluding "
                     "part), so the pieces cannot be spliced into one curve; penetrated painting keeps every layer");
  }
  // Nothing may lie in front of the layer (depth is affine in s on a piece).
  std::vector<std::vector<std::uint32_t>> by_sector(sd.segments());
  for (std::uint32_t p = 0; p < s.pieces.size(); ++p) by_sector[s.pieces[p].sector].push_back(p);
  double kscale = 0;
  for (const Vertex& v : s.vertices) kscale = std::max(kscale, std::abs(v.depth));
  const double tol = 1e-9 * std::max(kscale, 1e-300);
  for (std::int64_t p : R.piece) {
    if (p < 0) continue;
    const PieceSpan& a = spans[p];
    if (a.s1 - a.s0 <= kStepTolerance) continue;
    for (std::uint32_t q : by_sector[s.pieces[p].sector]) {
      if (q == p) continue;
      const PieceSpan& b = spans[q];
      if (b.s1 - b.s0 <= kStepTolerance) continue;
      const double x0 = std::max(a.s0, b.s0), x1 = std::min(a.s1, b.s1);
      if (!(x1 - x0 > kStepTolerance)) continue;
      for (double x : {x0, x1})
        if (b.key_at(x) > a.key_at(x) + tol)
          return status_of(ErrorCode::kDegenerate, "painting fails near ", pixel_text(sd, near_point(x)),
                           ": the curve passes behind another part of the surface (a fold, seed 001 Fig. 10, or an "
                           "occluding part); penetrated painting keeps every layer");
    }
  }
  return R;
}

TracedCurve to_curve(const Section& s, const StrokeData& sd, const Run& r) {
  TracedCurve c;
  c.closed = r.closed;
  if (!r.closed) {
    for (std::uint32_t v : r.v) c.points.push_back(s.vertices[v].point);
    return c;
  }
  // A closed layer of a closed stroke starts where the stroke starts: drop
  // the last stroke point's piercing (it coincides with the first's) and
  // repeat the first point at the end.
  const std::size_t n = r.piece.size();  // r.v has n + 1 entries, the first repeated
  const auto last = static_cast<std::uint32_t>(sd.px.size() - 1);
  std::size_t start = 0;
  bool linked = false;
  for (std::size_t k = 0; k < n; ++k) {
    const VKey &a = s.vertices[r.v[k]].key, &b = s.vertices[r.v[k + 1]].key;
    if (r.piece[k] < 0 && a.kind == VKind::kPierce && b.kind == VKind::kPierce &&
        ((a.c == last && b.c == 0) || (a.c == 0 && b.c == last))) {
      start = a.c == 0 ? k : k + 1;  // index of the first stroke point's piercing
      linked = true;
    }
  }
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t v = r.v[(start + k) % n];
    if (linked && s.vertices[v].key.kind == VKind::kPierce && s.vertices[v].key.c == last) continue;
    c.points.push_back(s.vertices[v].point);
  }
  c.points.push_back(c.points.front());
  return c;
}

}  // namespace

Expected<TraceResult> trace_stroke(const Model& m, const Camera& camera, std::span<const Vec2d> stroke,
                                   const PaintOptions& opt, const ExecContext& ctx) {
  auto mask = surface_mask(m, opt.surfaces);
  if (!mask) return mask.status();
  if (Status st = camera.check(); !st) return Status(ErrorCode::kInvalidArgument, "painting: " + st.message());
  auto sd = prepare_stroke(camera, camera.projection * camera.view, stroke);
  if (!sd) return sd.status();
  const Screen sc = project_nodes(m, camera, sd->box2, *mask, ctx);
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "painting cancelled");
  auto sec = build_section(m, sc, *sd, *mask, ctx);
  if (!sec) return sec.status();
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "painting cancelled");
  const Graph g = build_graph(m, *sec, *sd);
  std::vector<Run> runs = runs_of(*sec, chains_of(g, sec->vertices.size()));
  sort_runs(*sec, runs);
  TraceResult out;
  out.triangles_crossed = sec->triangles;
  out.stroke_points = sd->px.size();
  if (opt.through) {
    if (runs.empty())
      return Status(ErrorCode::kInvalidArgument, "penetrated painting: the stroke crosses no face of the surfaces");
    for (const Run& r : runs) out.curves.push_back(to_curve(*sec, *sd, r));
  } else {
    auto r = visible_run(*sec, *sd, runs);
    if (!r) return r.status();
    out.curves.push_back(to_curve(*sec, *sd, *r));
  }
  return out;
}

Expected<PaintResult> paint_stroke(Model& m, const Camera& camera, std::span<const Vec2d> stroke,
                                   const PaintOptions& opt, const ExecContext& ctx) {
  auto tr = trace_stroke(m, camera, stroke, opt, ctx);
  if (!tr) return tr.status();
  // Everything is checked; from here on the model only grows.
  PaintResult out;
  out.triangles_crossed = tr->triangles_crossed;
  for (const TracedCurve& c : tr->curves) {
    PaintedCurve pc;
    pc.length = c.length();
    pc.closed = c.closed;
    const std::size_t n = c.closed ? c.points.size() - 1 : c.points.size();
    std::vector<AttribNodeIdx> nodes;
    SurfaceIdx cur;
    AttribNodeIdx first;
    auto flush = [&] {
      if (nodes.empty()) return;
      const AttribEdgeIdx e = m.new_attrib_edge(cur, opt.feature_id, nodes);
      pc.edges.push_back(m.handle(e));
      nodes.clear();
    };
    for (std::size_t k = 0; k < n; ++k) {
      const CurvePoint& p = c.points[k];
      if (p.surface != cur) {
        flush();
        cur = p.surface;
      }
      const AttribNodeIdx a = m.new_attrib_node(p.surface, p.location.kind, p.location.element, p.location.param,
                                                p.position, p.location.corner);
      if (k == 0) first = a;
      nodes.push_back(a);
      ++pc.nodes;
    }
    if (c.closed && first.valid() && m.attrib_nodes.surface[first.value] == cur) nodes.push_back(first);
    flush();
    out.curves.push_back(std::move(pc));
  }
  return out;
}

Expected<CurvePoint> locate_pixel(const Model& m, const Camera& camera, const Vec2d& pixel,
                                  std::span<const SurfaceIdx> surfaces, const ExecContext& ctx) {
  auto mask = surface_mask(m, surfaces);
  if (!mask) return mask.status();
  if (!pixel.allFinite() || !(std::abs(pixel.x()) < kMaxPixel) || !(std::abs(pixel.y()) < kMaxPixel))
    return Status(ErrorCode::kInvalidArgument, "pick: the pixel is not finite");
  if (Status st = camera.check(); !st) return Status(ErrorCode::kInvalidArgument, "painting: " + st.message());
  const Mat4d pv = camera.projection * camera.view;
  const bool persp = camera.perspective();
  const double W = camera.width, H = camera.height;
  const P2 q{std::llround(pixel.x() * kSnap), std::llround(pixel.y() * kSnap)};
  // One byte per node instead of the painting's full screen image: on which
  // sides of the pixel the node projects (bits: left, right, above, below;
  // 16: not projectable). A face whose corners all lie on one side of it
  // (the AND of their codes) cannot hold the pixel; the few faces left are
  // projected again, corner by corner, through the same project_point.
  constexpr std::uint8_t kNotOk = 16;
  const std::size_t nn = m.nodes.slots.capacity();
  std::vector<std::uint8_t> code(nn, kNotOk);
  // The codes are the sure bits of sure_code (no rounding): a face is
  // culled only when the exact codes would cull it too.
  const double qx = double(q.x), qy = double(q.y);
  par::for_each_n(ctx, nn, [&](std::size_t v) {
    Vec4d cl;
    double px = 0, py = 0;
    if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)}) || !project_xy(pv, W, H, m.nodes.position[v], cl, px, py))
      return;
    code[v] = sure_code(px, py, qx, qx, qy, qy);
  });
  const std::size_t nf = m.faces.slots.capacity();
  const std::vector<std::uint8_t> culled = culled_faces(m, code, kNotOk);
  const std::size_t chunks = (nf + kChunk - 1) / kChunk;
  std::vector<std::pair<double, CurvePoint>> best(chunks, {-INFINITY, CurvePoint{}});
  ExecContext c = ctx;
  c.sequential_threshold = std::max<std::size_t>(1, ctx.sequential_threshold / kChunk);
  c.grain = 1;
  par::for_each_n(c, chunks, [&](std::size_t ch) {
    std::vector<HalfedgeIdx> hs;
    std::vector<FanTri> tris;
    const std::size_t end = std::min(nf, (ch + 1) * kChunk);
    for (std::size_t fi = ch * kChunk; fi < end; ++fi) {
      const FaceIdx f{static_cast<std::uint32_t>(fi)};
      if (!m.alive(f) || culled[fi] || !(*mask)[m.faces.surface[fi].value]) continue;
      fan_triangles(m, f, hs, tris);
      if (hs.size() > 257) continue;
      for (const FanTri& t : tris) {
        NodeImage im[3];
        for (int k = 0; k < 3; ++k) (void)project_point(pv, persp, W, H, m.position(t.n[k]), im[k]);
        const P2 cc[3] = {im[0].snapped, im[1].snapped, im[2].snapped};
        if (std::max({cc[0].x, cc[1].x, cc[2].x}) < q.x || std::min({cc[0].x, cc[1].x, cc[2].x}) > q.x ||
            std::max({cc[0].y, cc[1].y, cc[2].y}) < q.y || std::min({cc[0].y, cc[1].y, cc[2].y}) > q.y)
          continue;  // the pixel is outside the triangle's box (the perturbed point too)
        int sg[3];
        for (int k = 0; k < 3; ++k) {
          const int a = k, b = (k + 1) % 3;
          const bool fwd = t.n[a] < t.n[b];
          const int s = fwd ? point_side(cc[a], cc[b], q) : point_side(cc[b], cc[a], q);
          sg[k] = fwd ? s : -s;
        }
        if (!(sg[0] == sg[1] && sg[1] == sg[2])) continue;
        const double w[3] = {im[0].w, im[1].w, im[2].w};
        const Vec3d l = pierce_weights(im[0].pixel, im[1].pixel, im[2].pixel, w, pixel);
        CurvePoint p;
        p.location = {AttribNodeKind::kFace, f.value, l, static_cast<std::uint8_t>(t.fan)};
        p.surface = m.faces.surface[fi];
        p.position = l[0] * m.position(t.n[0]) + l[1] * m.position(t.n[1]) + l[2] * m.position(t.n[2]);
        const Vec4d cp = pv * Vec4d(p.position.x(), p.position.y(), p.position.z(), 1.0);
        const double k = persp ? 1.0 / cp.w() : -cp.z() / cp.w();
        if (k > best[ch].first) best[ch] = {k, p};
      }
    }
  });
  std::pair<double, CurvePoint> b{-INFINITY, CurvePoint{}};
  for (const auto& x : best)
    if (x.first > b.first) b = x;
  if (!(b.first > -INFINITY))
    return status_of(ErrorCode::kInvalidArgument, "pick: no face lies under pixel (", pixel.x(), ", ", pixel.y(), ")");
  return b.second;
}

}  // namespace atelier
