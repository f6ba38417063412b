// SdfGrid implementation: the only file of Atelier that includes OpenVDB.
// Why this file is long: OpenVDB's headers stay inside one source
// (docs/architecture.md, third-party table); the grid's build (narrow band,
// sign flood, tiles) and its samplers all touch OpenVDB types, so splitting
// would mean a second OpenVDB source or an internal header exposing them.
#include <atelier/systems/spatial/sdf_grid.h>

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <string>

#include <atelier/engine/parallel.h>

namespace atelier {

namespace vdb = openvdb;

namespace {

/// OpenVDB interrupter wired to the CancelToken. It is passed to OpenVDB as
/// its base class, util::NullInterrupter (virtual calls), so that
/// meshToVolume is the instantiation libopenvdb already holds (declared
/// `extern template` by MeshToVolume.h) for QuadAndTriangleDataAdapter<
/// Vec3s, Vec3I>: instantiating it here with our own adapter and
/// interrupter types cost 70 s of this file's 95 s compile, most of a
/// fresh `make demo`'s critical path.
struct CancelInterrupter final : vdb::util::NullInterrupter {
  explicit CancelInterrupter(const ExecContext* c) : ctx(c) {}
  const ExecContext* ctx = nullptr;
  bool wasInterrupted(int = -1) override {
    const bool stop = ctx->cancelled();
    par::tsan_release(this);  // called on OpenVDB's threads; acquired after meshToVolume
    return stop;
  }
};

Box3d grow(const Box3d& b, double r) {
  Box3d g = b;
  g.lo.array() -= r;
  g.hi.array() += r;
  return g;
}

/// Runs fn(leaf) on every leaf of the grid in parallel (leaves are
/// independent), a few leaves per task. False when cancelled.
template <class Fn>
[[nodiscard]] bool for_each_leaf(vdb::FloatGrid& grid, const ExecContext& ctx, Fn&& fn) {
  using LeafT = vdb::FloatTree::LeafNodeType;
  std::vector<LeafT*> leaves;
  leaves.reserve(grid.tree().leafCount());
  grid.tree().getNodes(leaves);
  std::atomic<bool> stopped{false};
  ExecContext c = ctx;
  c.sequential_threshold = std::max<std::size_t>(1, ctx.sequential_threshold / 64);
  c.grain = ctx.grain ? ctx.grain : 8;
  par::for_each_n(c, leaves.size(), [&](std::size_t li) {
    if (ctx.cancelled()) {
      stopped.store(true, std::memory_order_relaxed);
      return;
    }
    fn(*leaves[li]);
  });
  return !stopped.load();
}

/// Runs fn(at, blk, accessor) on every cell of a dim[0] x dim[1] x dim[2]
/// table of 8^3-voxel blocks (at = row-major index, blk = its 3D index), in
/// parallel, each task with its own read accessor. False when cancelled.
template <class Fn>
[[nodiscard]] bool for_each_block_cell(const vdb::FloatGrid& grid, const std::array<int, 3>& dim,
                                       const ExecContext& ctx, std::size_t default_grain, Fn&& fn) {
  const std::size_t count =
      static_cast<std::size_t>(dim[0]) * static_cast<std::size_t>(dim[1]) * static_cast<std::size_t>(dim[2]);
  const std::size_t nz = static_cast<std::size_t>(dim[2]), nyz = static_cast<std::size_t>(dim[1]) * nz;
  std::atomic<bool> stopped{false};
  ExecContext c = ctx;
  c.grain = ctx.grain ? ctx.grain : default_grain;
  par::for_each_block(c, count, [&](std::size_t begin, std::size_t end) {
    if (ctx.cancelled()) {
      stopped.store(true, std::memory_order_relaxed);
      return;
    }
    auto acc = grid.getConstUnsafeAccessor();
    for (std::size_t at = begin; at < end; ++at) {
      const int blk[3] = {static_cast<int>(at / nyz), static_cast<int>((at / nz) % static_cast<std::size_t>(dim[1])),
                          static_cast<int>(at % nz)};
      fn(at, blk, acc);
    }
  });
  return !stopped.load();
}

}  // namespace

struct SdfGrid::Impl {
  vdb::FloatGrid::Ptr grid;
  const BodyBvh* body = nullptr;
  SdfParams params;
  SdfStats stats;
  bool roi = false;
  double h = 1.0, inv_h = 1.0;
  double exact_world = 0.0;       // exact band in world units
  double band_world = 0.0;        // half width in world units
  std::vector<Box3d> walk_boxes;  // ROI boxes grown by 2h: where the band is complete

  /// ROI grids: the sign of every 8^3 block without a leaf (a tile, no band
  /// voxel) that meets a walk box, found once at build by walk_sign, so a
  /// query off the band reads it instead of walking. Within a walk box the
  /// band is complete, so the block's voxels there (a box of lattice points,
  /// each at least w h >= 2 h from the surface, neighbours h apart) are all
  /// on one side. 0: the block has a leaf, or the walk did not decide.
  struct BlockSigns {
    std::array<int, 3> vlo{}, vhi{};  // voxel index range of the walk box
    std::array<int, 3> blo{}, dim{};  // its blocks: [blo, blo + dim)
    std::vector<std::int8_t> sign;
  };
  std::vector<BlockSigns> block_signs;  // one per walk box

  [[nodiscard]] int block_sign(std::size_t box, const vdb::Coord& c0) const noexcept {
    if (box >= block_signs.size()) return 0;
    const BlockSigns& t = block_signs[box];
    if (t.sign.empty()) return 0;
    std::size_t at = 0;
    for (int a = 0; a < 3; ++a) {
      if (c0[a] < t.vlo[a] || c0[a] > t.vhi[a]) return 0;
      at = at * static_cast<std::size_t>(t.dim[a]) + static_cast<std::size_t>((c0[a] >> 3) - t.blo[a]);
    }
    return t.sign[at];
  }

  [[nodiscard]] bool covers(const Vec3d& p) const noexcept {
    if (!roi) return true;
    for (const Box3d& b : params.roi) {
      if ((p.array() >= b.lo.array()).all() && (p.array() <= b.hi.array()).all()) return true;
    }
    return false;
  }

  /// Flat table of the 8^3 blocks over the band's bounding box (grown by
  /// two blocks): each entry is the block's leaf, or its tile value and
  /// state. A query reads its block in one array access instead of walking
  /// the tree (root map, two internal nodes), whose nodes are cache misses
  /// for scattered queries: the tree is the cost of an inside test far more
  /// than the arithmetic. Outside the box (or for boxes of more than 2^22
  /// blocks, where the table is not made) queries use the accessor.
  /// The entry holds the leaf's value array itself, so a query's loads do
  /// not wait on the leaf node first (the leaf is in table_leaf, for its
  /// value mask, read only when needed: see value_mask_needed).
  struct BlockRef {
    const float* values = nullptr;  // the leaf's 512 voxels, or null: a tile
    float tile = 0.0f;
    bool tile_on = false;
  };
  std::vector<BlockRef> table;
  std::vector<const vdb::FloatTree::LeafNodeType*> table_leaf;
  std::array<int, 3> table_lo{}, table_dim{};
  /// False when every inactive voxel of a full grid holds |value| >= the
  /// exact band (checked at build; OpenVDB sets them to +-background): then
  /// a corner is an exact band voxel iff |value| < exact band, and nothing
  /// else needs the active state, so queries skip the value masks.
  bool value_mask_needed = true;

  /// The entry of block (bx, by, bz), or null outside the table.
  [[nodiscard]] const BlockRef* block_ref(int bx, int by, int bz) const noexcept {
    const auto x = static_cast<unsigned>(bx - table_lo[0]), y = static_cast<unsigned>(by - table_lo[1]),
               z = static_cast<unsigned>(bz - table_lo[2]);
    if (x >= static_cast<unsigned>(table_dim[0]) || y >= static_cast<unsigned>(table_dim[1]) ||
        z >= static_cast<unsigned>(table_dim[2]))
      return nullptr;
    return &table[(static_cast<std::size_t>(x) * static_cast<std::size_t>(table_dim[1]) + y) *
                      static_cast<std::size_t>(table_dim[2]) +
                  z];
  }

  struct Probe {
    double d = 0.0;
    bool valid = false;             // p maps to representable voxel coordinates
    bool all_active = false;        // every corner is a band voxel
    unsigned active = 0;            // bit n: corner n is a band voxel
    float v[8] = {};                // corner values, corner n at offset ((n >> 2) & 1, (n >> 1) & 1, n & 1)
    double tx = 0, ty = 0, tz = 0;  // p in its cell, in [0, 1)
  };

  /// Trilinear interpolation of the 8 voxel values around p.
  template <class Accessor>
  [[nodiscard]] Probe trilinear(Accessor& acc, const Vec3d& p) const {
    Probe r;
    const double x = p.x() * inv_h, y = p.y() * inv_h, z = p.z() * inv_h;
    constexpr double kLimit = 1 << 30;
    if (!(std::abs(x) < kLimit && std::abs(y) < kLimit && std::abs(z) < kLimit)) return r;
    const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    const int i = static_cast<int>(fx), j = static_cast<int>(fy), k = static_cast<int>(fz);
    r.tx = x - fx;
    r.ty = y - fy;
    r.tz = z - fz;
    using LeafT = vdb::FloatTree::LeafNodeType;
    // Corner n sits at offset ((n >> 2) & 1, (n >> 1) & 1, n & 1); along an
    // axis whose index is 7 mod 8 the cell crosses into the next 8^3 block.
    const unsigned sx = (i & 7) == 7, sy = (j & 7) == 7, sz = (k & 7) == 7;
    constexpr vdb::Index kOff[8] = {0, 1, 8, 9, 64, 65, 72, 73};
    if (!table.empty()) {
      // Through the block table when the cell's blocks are in it (the
      // table is a box: the first and last corner's blocks suffice).
      const BlockRef* b0 = block_ref(i >> 3, j >> 3, k >> 3);
      if (b0 && block_ref((i + 1) >> 3, (j + 1) >> 3, (k + 1) >> 3)) {
        unsigned on = 0;
        if (!(sx | sy | sz)) {
          if (const float* values = b0->values) {
            const vdb::Index o = static_cast<vdb::Index>(((i & 7) << 6) | ((j & 7) << 3) | (k & 7));
            for (int n = 0; n < 8; ++n) r.v[n] = values[o + kOff[n]];
            if (value_mask_needed) {
              const auto& mask = table_leaf[static_cast<std::size_t>(b0 - table.data())]->getValueMask();
              for (int n = 0; n < 8; ++n) on |= static_cast<unsigned>(mask.isOn(o + kOff[n])) << n;
            } else {
              on = 0xffu;
            }
          } else {
            std::fill(std::begin(r.v), std::end(r.v), b0->tile);
            on = b0->tile_on ? 0xffu : 0u;
          }
          return finish(r, on);
        }
        for (unsigned n = 0; n < 8; ++n) {
          const int ci = i + static_cast<int>((n >> 2) & 1), cj = j + static_cast<int>((n >> 1) & 1),
                    ck = k + static_cast<int>(n & 1);
          const BlockRef* b = block_ref(ci >> 3, cj >> 3, ck >> 3);
          if (b->values) {
            const vdb::Index o = static_cast<vdb::Index>(((ci & 7) << 6) | ((cj & 7) << 3) | (ck & 7));
            r.v[n] = b->values[o];
            on |=
                (value_mask_needed ? static_cast<unsigned>(
                                         table_leaf[static_cast<std::size_t>(b - table.data())]->getValueMask().isOn(o))
                                   : 1u)
                << n;
          } else {
            r.v[n] = b->tile;
            on |= static_cast<unsigned>(b->tile_on) << n;
          }
        }
        return finish(r, on);
      }
    }
    if (!(sx | sy | sz)) {
      // The 8 corners in one block (7/8 of the cells per axis): one leaf...
      if (const LeafT* leaf = acc.probeConstLeaf(vdb::Coord(i, j, k))) {
        const vdb::Index o = static_cast<vdb::Index>(((i & 7) << 6) | ((j & 7) << 3) | (k & 7));
        const auto& mask = leaf->getValueMask();
        unsigned on = 0;
        for (int n = 0; n < 8; ++n) {
          r.v[n] = leaf->getValue(o + kOff[n]);
          on |= static_cast<unsigned>(mask.isOn(o + kOff[n])) << n;
        }
        return finish(r, on);
      }
      // ...or no leaf: the whole block is one tile (most queries away from
      // the surface), whose value and state every corner shares. One lookup
      // instead of eight.
      float v = 0.0f;
      const bool on = acc.probeValue(vdb::Coord(i, j, k), v);
      std::fill(std::begin(r.v), std::end(r.v), v);
      return finish(r, on ? 0xffu : 0u);
    }
    // The cell spans 2, 4 or 8 blocks: one leaf or tile lookup per block.
    // Block bn of corner n keeps the bits of n along the crossing axes; it is
    // first met at corner bn (bn <= n), so one pass fills both.
    const LeafT* leaf[8] = {};
    float tile[8] = {};
    bool tile_on[8] = {};
    unsigned on = 0;
    for (unsigned n = 0; n < 8; ++n) {
      const vdb::Coord c(i + static_cast<int>((n >> 2) & 1), j + static_cast<int>((n >> 1) & 1),
                         k + static_cast<int>(n & 1));
      const unsigned bn = (n & (sx << 2)) | (n & (sy << 1)) | (n & sz);
      if (bn == n) {
        leaf[n] = acc.probeConstLeaf(c);
        if (!leaf[n]) tile_on[n] = acc.probeValue(c, tile[n]);
      }
      if (const LeafT* l = leaf[bn]) {
        const vdb::Index o = LeafT::coordToOffset(c);
        r.v[n] = l->getValue(o);
        on |= static_cast<unsigned>(l->isValueOn(o)) << n;
      } else {
        r.v[n] = tile[bn];
        on |= static_cast<unsigned>(tile_on[bn]) << n;
      }
    }
    return finish(r, on);
  }

  [[nodiscard]] static Probe finish(Probe& r, unsigned on) noexcept {
    const float* v = r.v;
    const double tx = r.tx, ty = r.ty, tz = r.tz;
    const double a00 = v[0] + tz * (v[1] - v[0]), a01 = v[2] + tz * (v[3] - v[2]);
    const double a10 = v[4] + tz * (v[5] - v[4]), a11 = v[6] + tz * (v[7] - v[6]);
    const double b0 = a00 + ty * (a01 - a00), b1 = a10 + ty * (a11 - a10);
    r.d = b0 + tx * (b1 - b0);
    r.valid = true;
    r.active = on;
    r.all_active = on == 0xffu;
    return r;
  }

  /// Certified sign from an exact corner (see exact_world): a band voxel
  /// whose stored |value| is below the exact band holds the exact signed
  /// distance D(c) (recomputed at build), and a signed distance is
  /// 1-Lipschitz, so |D(c)| > |p - c| puts p strictly on c's side of the
  /// surface. Returns -1 inside, +1 outside, 0 when no corner decides; then
  /// `bound` is lowered to min |D(c)| + |p - c| over the exact corners, an
  /// upper bound on p's distance (the same Lipschitz bound the other way),
  /// which keeps the BVH's first search radius within a voxel.
  [[nodiscard]] int corner_sign(const Probe& r, double& bound) const noexcept {
    for (int n = 0; n < 8; ++n) {
      if (!((r.active >> n) & 1u)) continue;
      const double a = std::abs(double(r.v[n]));
      if (!(a < exact_world)) continue;
      const double dx = r.tx - ((n >> 2) & 1), dy = r.ty - ((n >> 1) & 1), dz = r.tz - (n & 1);
      const double dist2 = (dx * dx + dy * dy + dz * dz) * h * h;
      // Float storage rounds by 2^-24 relative; keep a margin well above it.
      const double m = a * (1.0 - 1e-6) - 1e-9 * h;
      if (m > 0.0 && m * m > dist2) return r.v[n] < 0.0f ? -1 : 1;
      bound = std::min(bound, a * (1.0 + 1e-6) + 1e-9 * h + std::sqrt(dist2) * (1.0 + 1e-12));
    }
    return 0;
  }

  template <class Accessor>
  [[nodiscard]] double sample(Accessor& acc, const Vec3d& p) const {
    const Probe r = trilinear(acc, p);
    return r.valid ? r.d : band_world;
  }

  /// ROI grids, p outside the band: the sign of the first band voxel met
  /// walking along a grid line from p's nearest voxel. Inside a ROI box
  /// grown by 2h the band is complete (every voxel within w h of the body is
  /// active, w >= 2), so a run of inactive voxels never crosses the surface:
  /// a crossing between two neighbours would put both within h of it.
  /// Returns -1 inside, +1 outside, 0 when undecided (walked out of the box).
  template <class Accessor>
  [[nodiscard]] int walk_sign(Accessor& acc, const Vec3d& p, const Box3d& box) const {
    const vdb::Coord c0(static_cast<int>(std::lround(p.x() * inv_h)), static_cast<int>(std::lround(p.y() * inv_h)),
                        static_cast<int>(std::lround(p.z() * inv_h)));
    float v = 0.0f;
    if (acc.probeValue(c0, v)) {
      // |p - c0| <= (sqrt(3) / 2) h: no surface between them if |v| exceeds it.
      if (std::abs(double(v)) > 0.87 * h) return v < 0.0f ? -1 : 1;
      return 0;
    }
    const std::array<int, 3> lo_idx = {static_cast<int>(std::ceil(box.lo.x() * inv_h)),
                                       static_cast<int>(std::ceil(box.lo.y() * inv_h)),
                                       static_cast<int>(std::ceil(box.lo.z() * inv_h))};
    const std::array<int, 3> hi_idx = {static_cast<int>(std::floor(box.hi.x() * inv_h)),
                                       static_cast<int>(std::floor(box.hi.y() * inv_h)),
                                       static_cast<int>(std::floor(box.hi.z() * inv_h))};
    for (int axis = 0; axis < 3; ++axis) {
      for (int dir : {1, -1}) {
        vdb::Coord c = c0;
        for (;;) {
          // Skip whole inactive tiles (8, 128 or 4096 voxels wide).
          const int depth = acc.getValueDepth(c);
          int step = 1;
          if (depth < 3) step = depth == 2 ? 8 : depth == 1 ? 128 : 4096;
          if (step > 1) {
            const int x = c[axis];
            const int base = (x >= 0 ? x / step : -((-x + step - 1) / step)) * step;  // floor to a multiple
            c[axis] = dir > 0 ? base + step : base - 1;
          } else {
            c[axis] += dir;
          }
          if (c[axis] < lo_idx[axis] || c[axis] > hi_idx[axis]) break;
          if (acc.probeValue(c, v)) return v < 0.0f ? -1 : 1;
        }
      }
    }
    return 0;
  }

  template <class Accessor>
  [[nodiscard]] bool inside(Accessor& acc, const Vec3d& p, InsideStats& st) const {
    double bound = std::numeric_limits<double>::infinity();
    if (covers(p)) {
      const Probe r = trilinear(acc, p);
      // Full grids: outside the band the flood-filled tiles carry the sign.
      // ROI grids have no valid flood fill (open sub-mesh): inside the band
      // the trilinear value, outside it a walk to the band.
      if (r.valid && (!roi || r.all_active) && std::abs(r.d) >= exact_world) {
        ++st.from_grid;
        return r.d < 0.0;
      }
      double corner_bound = std::numeric_limits<double>::infinity();
      if (r.valid) {
        if (const int s = corner_sign(r, corner_bound); s != 0) {
          ++st.from_grid;
          return s < 0;
        }
      }
      if (r.valid && roi && !r.all_active) {
        for (std::size_t bi = 0; bi < walk_boxes.size(); ++bi) {
          const Box3d& b = walk_boxes[bi];
          if ((p.array() >= b.lo.array()).all() && (p.array() <= b.hi.array()).all()) {
            const vdb::Coord c0(static_cast<int>(std::lround(p.x() * inv_h)),
                                static_cast<int>(std::lround(p.y() * inv_h)),
                                static_cast<int>(std::lround(p.z() * inv_h)));
            if (const int s = block_sign(bi, c0); s != 0) {  // what walk_sign(p) would find
              ++st.from_grid;
              return s < 0;
            }
            const int s = walk_sign(acc, p, b);
            if (s != 0) {
              ++st.from_grid;
              return s < 0;
            }
            break;
          }
        }
      }
      // |d - distance| <= sqrt(3) h + value error: a tight first radius
      // for the exact query (the answer does not depend on it).
      if (r.valid && (!roi || r.all_active)) bound = std::abs(r.d) + 2.5 * h;
      bound = std::min(bound, corner_bound);
    }
    ++st.exact;
    return body->signed_distance(p, bound).distance < 0.0;
  }
};

struct SdfGrid::Sampler::Impl {
  const SdfGrid::Impl* g;
  vdb::FloatGrid::ConstUnsafeAccessor acc;
  InsideStats stats;
};

SdfGrid::SdfGrid() = default;
SdfGrid::~SdfGrid() = default;
SdfGrid::SdfGrid(SdfGrid&&) noexcept = default;
SdfGrid& SdfGrid::operator=(SdfGrid&&) noexcept = default;

Status SdfGrid::build(const BodyBvh& body, const SdfParams& params, const ExecContext& ctx) {
  impl_.reset();
  if (body.empty()) return {ErrorCode::kInvalidArgument, "SdfGrid: the BodyBvh is not built"};
  if (Status s = body.require_closed(); !s) return {s.code(), "SdfGrid: " + s.message()};
  if (!(params.voxel_size > 0.0) || !std::isfinite(params.voxel_size)) {
    return {ErrorCode::kInvalidArgument,
            "SdfGrid: voxel size must be positive, got " + std::to_string(params.voxel_size)};
  }
  if (!(params.half_width >= 2.0) || !std::isfinite(params.half_width)) {
    return {ErrorCode::kInvalidArgument,
            "SdfGrid: half width must be at least 2 voxels, got " + std::to_string(params.half_width)};
  }
  if (!(params.exact_band >= 0.0) || !std::isfinite(params.exact_band)) {
    return {ErrorCode::kInvalidArgument, "SdfGrid: exact band must be >= 0 voxels"};
  }
  for (std::size_t i = 0; i < params.roi.size(); ++i) {
    const Box3d& b = params.roi[i];
    if (b.empty() || !b.lo.allFinite() || !b.hi.allFinite()) {
      return {ErrorCode::kInvalidArgument, "SdfGrid: ROI box " + std::to_string(i) + " is empty or not finite"};
    }
  }
  auto im = std::make_unique<Impl>();
  im->body = &body;
  im->params = params;
  im->roi = !params.roi.empty();
  im->h = params.voxel_size;
  im->inv_h = 1.0 / params.voxel_size;
  im->exact_world = params.exact_band * params.voxel_size;
  im->band_world = params.half_width * params.voxel_size;

  const Box3d bounds = grow(body.bounds(), (params.half_width + 2.0) * params.voxel_size);
  const double extent = std::max(bounds.lo.cwiseAbs().maxCoeff(), bounds.hi.cwiseAbs().maxCoeff());
  if (extent * im->inv_h >= double(1 << 30)) {
    return {ErrorCode::kInvalidArgument, "SdfGrid: voxel size " + std::to_string(params.voxel_size) +
                                             " too small for a body reaching " + std::to_string(extent)};
  }

  const std::span<const Vec3d> pos = body.positions();
  const std::span<const Triangle> tris = body.triangles();

  // ROI: the triangles whose box meets a ROI box grown by (w + 3) h. A query
  // in the ROI reads voxels within sqrt(3) h of it whose band distance is at
  // most w h, so their closest triangle meets the grown box.
  const double grow_by = (params.half_width + 3.0) * params.voxel_size;
  std::vector<Box3d> grown;
  std::vector<std::uint32_t> sel;
  if (im->roi) {
    for (const Box3d& b : params.roi) {
      grown.push_back(grow(b, grow_by));
      im->walk_boxes.push_back(grow(b, 2.0 * params.voxel_size));
    }
    std::vector<std::uint8_t> keep(tris.size(), 0);
    par::for_each_n(ctx, tris.size(), [&](std::size_t t) {
      Box3d tb;
      for (std::uint32_t v : tris[t]) tb.extend(pos[v]);
      for (const Box3d& g : grown) {
        if ((tb.lo.array() <= g.hi.array()).all() && (tb.hi.array() >= g.lo.array()).all()) {
          keep[t] = 1;
          break;
        }
      }
    });
    for (std::size_t t = 0; t < tris.size(); ++t) {
      if (keep[t]) sel.push_back(static_cast<std::uint32_t>(t));
    }
  }

  // OpenVDB's adapter takes float index-space points: rounding moves them by
  // at most 2^-24 of the body's extent in voxels (about 1e-4 h), far inside
  // the slacks below that treat OpenVDB's values as distance bounds.
  const std::size_t num_polygons = im->roi ? sel.size() : tris.size();
  std::vector<vdb::Vec3s> index_points(pos.size());
  std::vector<vdb::Vec3I> index_tris(num_polygons);
  par::for_each_n(ctx, pos.size(), [&](std::size_t v) {
    const Vec3d p = pos[v] * im->inv_h;
    index_points[v] = vdb::Vec3s(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  });
  for (std::size_t n = 0; n < num_polygons; ++n) {
    const Triangle& t = tris[im->roi ? sel[n] : n];
    index_tris[n] = vdb::Vec3I(t[0], t[1], t[2]);
  }
  const vdb::tools::QuadAndTriangleDataAdapter<vdb::Vec3s, vdb::Vec3I> mesh(index_points, index_tris);
  im->stats.source_triangles = num_polygons;
  const vdb::math::Transform::Ptr xform = vdb::math::Transform::createLinearTransform(params.voxel_size);
  CancelInterrupter cancel(&ctx);
  vdb::util::NullInterrupter& interrupter = cancel;
  const auto w = static_cast<float>(params.half_width);
  vdb::Int32Grid::Ptr index_grid;
  if (im->roi) index_grid = vdb::Int32Grid::create();

  par::in_arena(ctx, [&] {
    if (num_polygons == 0) {
      im->grid = vdb::FloatGrid::create(static_cast<float>(im->band_world));
      im->grid->setTransform(xform);
      return;
    }
    if (!im->roi) {
      // Signed conversion with OpenVDB's interior classification and flood
      // fill (meshToLevelSet with renormalisation off: exact distances).
      im->grid = vdb::tools::meshToVolume<vdb::FloatGrid>(
          interrupter, mesh, *xform, w, w, vdb::tools::DISABLE_RENORMALIZATION, static_cast<vdb::Int32Grid*>(nullptr));
    } else {
      im->grid = vdb::tools::meshToVolume<vdb::FloatGrid>(
          interrupter, mesh, *xform, w, w, vdb::tools::UNSIGNED_DISTANCE_FIELD | vdb::tools::DISABLE_RENORMALIZATION,
          index_grid.get());
    }
  });
  par::tsan_acquire(&cancel);
  if (ctx.cancelled()) return {ErrorCode::kCancelled, "SdfGrid: cancelled"};
  if (!im->grid) return {ErrorCode::kInternal, "SdfGrid: OpenVDB returned no grid"};

  if (im->roi && num_polygons > 0) {
    // Sign each band voxel with the pseudo-normal of its closest triangle
    // (exact when the voxel's distance ball lies in a grown box, so every
    // triangle that could be closer was voxelised); drop the others.
    using LeafT = vdb::FloatTree::LeafNodeType;
    const vdb::Int32Tree& itree = index_grid->tree();
    const float off_value = static_cast<float>(im->band_world);
    const double h = params.voxel_size;
    const double slack = 1e-3 * h;  // OpenVDB's values, from float points, may be short by ~1e-4 h
    const double bound_slack = 1e-3 * h;
    const bool done = for_each_leaf(*im->grid, ctx, [&](LeafT& leaf) {
      const vdb::Int32Tree::LeafNodeType* ileaf = itree.probeConstLeaf(leaf.origin());
      for (vdb::Index off = 0; off < LeafT::SIZE; ++off) {
        if (!leaf.isValueOn(off)) continue;
        const vdb::Coord ijk = leaf.offsetToGlobalCoord(off);
        const Vec3d q(ijk.x() * h, ijk.y() * h, ijk.z() * h);
        const float v = std::abs(leaf.getValue(off));
        const std::int32_t sub = ileaf ? ileaf->getValue(off) : -1;
        bool certified = false;
        if (sub >= 0 && static_cast<std::size_t>(sub) < sel.size()) {
          const double r = double(v) + slack;
          for (const Box3d& g : grown) {
            if (((q.array() - g.lo.array()) >= r).all() && ((g.hi.array() - q.array()) >= r).all()) {
              certified = true;
              break;
            }
          }
        }
        if (!certified) {
          leaf.setValueOff(off, off_value);
          continue;
        }
        if (double(v) < im->exact_world) {  // exact corner (see below)
          leaf.setValueOnly(off, static_cast<float>(body.signed_distance(q, double(v) + bound_slack).distance));
          continue;
        }
        const double s = body.signed_distance_to(q, sel[static_cast<std::size_t>(sub)]).distance;
        leaf.setValueOnly(off, s < 0.0 ? -v : v);
      }
    });
    if (!done) return {ErrorCode::kCancelled, "SdfGrid: cancelled"};
    par::in_arena(ctx, [&] { vdb::tools::pruneInactive(im->grid->tree(), ctx.threads != 1); });

    // Block signs (see BlockSigns), from a voxel of each leafless block
    // inside the walk box. Skipped for boxes of more than 2^24 blocks.
    for (const Box3d& b : im->walk_boxes) {
      Impl::BlockSigns& t = im->block_signs.emplace_back();
      std::size_t count = 1;
      for (int a = 0; a < 3; ++a) {
        t.vlo[a] = static_cast<int>(std::ceil(b.lo[a] * im->inv_h));
        t.vhi[a] = static_cast<int>(std::floor(b.hi[a] * im->inv_h));
        t.blo[a] = t.vlo[a] >> 3;  // floor division (arithmetic shift)
        t.dim[a] = std::max(0, (t.vhi[a] >> 3) - t.blo[a] + 1);
        count *= static_cast<std::size_t>(t.dim[a]);
      }
      if (count == 0 || count > (std::size_t{1} << 24)) continue;
      t.sign.assign(count, 0);
      const bool done =
          for_each_block_cell(*im->grid, t.dim, ctx, 64, [&](std::size_t at, const int(&blk)[3], auto& acc) {
            vdb::Coord v;
            for (int a = 0; a < 3; ++a) v[a] = std::max(t.vlo[a], (t.blo[a] + blk[a]) * 8);  // in the block and the box
            if (acc.probeConstLeaf(v)) return;
            t.sign[at] = static_cast<std::int8_t>(im->walk_sign(acc, Vec3d(v.x() * h, v.y() * h, v.z() * h), b));
          });
      if (!done) return {ErrorCode::kCancelled, "SdfGrid: cancelled"};
    }
  }

  if (!im->roi && num_polygons > 0 && im->exact_world > 0.0) {
    // Exact corners: every band voxel whose value is below the exact band
    // gets the exact signed distance of the BVH (OpenVDB's value is the
    // distance to some triangle, an upper bound: a tight first radius). Then
    // a stored |value| below the band is exact, which inside() uses to
    // certify signs by the 1-Lipschitz bound instead of asking the BVH.
    using LeafT = vdb::FloatTree::LeafNodeType;
    const double h = params.voxel_size;
    const double bound_slack = 1e-3 * h;
    const bool done = for_each_leaf(*im->grid, ctx, [&](LeafT& leaf) {
      for (auto it = leaf.beginValueOn(); it; ++it) {
        const double v = std::abs(double(*it));
        if (!(v < im->exact_world)) continue;
        const vdb::Coord ijk = it.getCoord();
        const Vec3d q(ijk.x() * h, ijk.y() * h, ijk.z() * h);
        it.setValue(static_cast<float>(body.signed_distance(q, v + bound_slack).distance));
      }
    });
    if (!done) return {ErrorCode::kCancelled, "SdfGrid: cancelled"};
  }

  // The block table (see BlockRef) over the leaves' bounding box grown by
  // two blocks, so cells next to the band and the flood-filled tiles around
  // it are read from it too.
  if (vdb::CoordBBox leaf_box; im->grid->tree().evalLeafBoundingBox(leaf_box)) {
    std::size_t count = 1;
    for (int a = 0; a < 3; ++a) {
      im->table_lo[a] = (leaf_box.min()[a] >> 3) - 2;
      im->table_dim[a] = (leaf_box.max()[a] >> 3) + 2 - im->table_lo[a] + 1;
      count *= static_cast<std::size_t>(im->table_dim[a]);
    }
    if (count <= (std::size_t{1} << 22)) {
      im->table.resize(count);
      im->table_leaf.assign(count, nullptr);
      const bool done =
          for_each_block_cell(*im->grid, im->table_dim, ctx, 256, [&](std::size_t at, const int(&blk)[3], auto& acc) {
            const vdb::Coord origin((im->table_lo[0] + blk[0]) * 8, (im->table_lo[1] + blk[1]) * 8,
                                    (im->table_lo[2] + blk[2]) * 8);
            Impl::BlockRef& r = im->table[at];
            const auto* leaf = acc.probeConstLeaf(origin);
            im->table_leaf[at] = leaf;
            if (leaf)
              r.values = leaf->buffer().data();
            else
              r.tile_on = acc.probeValue(origin, r.tile);
          });
      if (!done) return {ErrorCode::kCancelled, "SdfGrid: cancelled"};
    }
  }
  if (!im->roi) {
    // Full grids: can the value masks be skipped (see value_mask_needed)?
    using LeafT = vdb::FloatTree::LeafNodeType;
    std::vector<const LeafT*> leaves;
    leaves.reserve(im->grid->tree().leafCount());
    im->grid->tree().getNodes(leaves);
    std::atomic<bool> low{false};
    const double exact = im->exact_world;
    par::for_each_n(ctx, leaves.size(), [&](std::size_t li) {
      for (auto it = leaves[li]->cbeginValueOff(); it; ++it)
        if (!(std::abs(double(*it)) >= exact)) low.store(true, std::memory_order_relaxed);
    });
    // Tiles carry their own state in the table; the accessor path reads masks.
    im->value_mask_needed = low.load();
  }

  im->stats.active_voxels = static_cast<std::size_t>(im->grid->activeVoxelCount());
  im->stats.memory_bytes =
      static_cast<std::size_t>(im->grid->memUsage()) + im->table.size() * (sizeof(Impl::BlockRef) + sizeof(void*));
  impl_ = std::move(im);
  return Status::ok();
}

bool SdfGrid::empty() const noexcept {
  return !impl_;
}
const SdfParams& SdfGrid::params() const noexcept {
  static const SdfParams kNone{};
  return impl_ ? impl_->params : kNone;
}
const SdfStats& SdfGrid::stats() const noexcept {
  static const SdfStats kNone{};
  return impl_ ? impl_->stats : kNone;
}
bool SdfGrid::covers(const Vec3d& p) const noexcept {
  return impl_ && impl_->covers(p);
}

double SdfGrid::sample(const Vec3d& p) const {
  if (!impl_) return std::numeric_limits<double>::quiet_NaN();
  auto acc = impl_->grid->getConstUnsafeAccessor();
  return impl_->sample(acc, p);
}

bool SdfGrid::inside(const Vec3d& p) const {
  if (!impl_) return false;
  auto acc = impl_->grid->getConstUnsafeAccessor();
  InsideStats st;
  return impl_->inside(acc, p, st);
}

SdfGrid::Sampler::Sampler(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SdfGrid::Sampler::Sampler(Sampler&&) noexcept = default;
SdfGrid::Sampler& SdfGrid::Sampler::operator=(Sampler&&) noexcept = default;
SdfGrid::Sampler::~Sampler() = default;
double SdfGrid::Sampler::sample(const Vec3d& p) {
  if (!impl_) return std::numeric_limits<double>::quiet_NaN();
  return impl_->g->sample(impl_->acc, p);
}
bool SdfGrid::Sampler::inside(const Vec3d& p) {
  return impl_ && impl_->g->inside(impl_->acc, p, impl_->stats);
}
const InsideStats& SdfGrid::Sampler::stats() const noexcept {
  static const InsideStats kNone{};
  return impl_ ? impl_->stats : kNone;
}

SdfGrid::Sampler SdfGrid::sampler() const {
  if (!impl_) return Sampler(nullptr);  // an unbuilt grid: NaN samples, never inside
  return Sampler(
      std::unique_ptr<Sampler::Impl>(new Sampler::Impl{impl_.get(), impl_->grid->getConstUnsafeAccessor(), {}}));
}

Status SdfGrid::sample_many(std::span<const Vec3d> in, std::span<double> out, const ExecContext& ctx) const {
  if (!impl_) return {ErrorCode::kInvalidArgument, "SdfGrid::sample_many: grid not built"};
  if (in.size() != out.size()) return {ErrorCode::kMismatch, "SdfGrid::sample_many: input and output sizes differ"};
  std::atomic<bool> stopped{false};
  par::for_each_block(ctx, in.size(), [&](std::size_t b, std::size_t e) {
    if (ctx.cancelled()) {
      stopped.store(true, std::memory_order_relaxed);
      return;
    }
    auto acc = impl_->grid->getConstUnsafeAccessor();
    for (std::size_t i = b; i < e; ++i) out[i] = impl_->sample(acc, in[i]);
  });
  if (stopped.load()) return {ErrorCode::kCancelled, "SdfGrid::sample_many: cancelled"};
  return Status::ok();
}

Status SdfGrid::inside_many(std::span<const Vec3d> in, std::span<std::uint8_t> out, const ExecContext& ctx,
                            InsideStats* stats) const {
  if (!impl_) return {ErrorCode::kInvalidArgument, "SdfGrid::inside_many: grid not built"};
  if (in.size() != out.size()) return {ErrorCode::kMismatch, "SdfGrid::inside_many: input and output sizes differ"};
  std::atomic<bool> stopped{false};
  std::atomic<std::size_t> from_grid{0}, exact{0};
  par::for_each_block(ctx, in.size(), [&](std::size_t b, std::size_t e) {
    if (ctx.cancelled()) {
      stopped.store(true, std::memory_order_relaxed);
      return;
    }
    auto acc = impl_->grid->getConstUnsafeAccessor();
    InsideStats st;
    for (std::size_t i = b; i < e; ++i) out[i] = impl_->inside(acc, in[i], st) ? 1 : 0;
    from_grid.fetch_add(st.from_grid, std::memory_order_relaxed);
    exact.fetch_add(st.exact, std::memory_order_relaxed);
  });
  if (stopped.load()) return {ErrorCode::kCancelled, "SdfGrid::inside_many: cancelled"};
  if (stats) *stats = {from_grid.load(), exact.load()};
  return Status::ok();
}

}  // namespace atelier
