// Detail templates (seed 001 section 6): any garment mesh encoded on the
// polygons of a reference body, and decoded on other bodies of the same
// topology by blending linear maps of its p-polygons (eqs. 8-12).
//
// Encoding: for each garment vertex q, its N_q p-polygons are the body
// polygons whose centroids are nearest to q (found in a voxel grid of
// centroids with ring-by-ring expansion, in parallel over vertices); per
// p-polygon, the local coordinates (u, v, w) of q in the frame at the centroid
// (eqs. 8, 9) and the weight 1 / (eps + |q - p_c|^3) (eq. 10).
//
// Decoding: q~ = sum_i w_i (p~_c + u_i X~ + v_i Y~ + w_i Z~) / sum_i w_i
// (eqs. 11, 12). With normalised weights folded into the coordinates, the
// encoding is a sparse matrix (garment vertices x polygon frames) with four
// floats per entry: q~ = sum_i (a_i p~_c + b_i X~ + c_i Y~ + d_i Z~),
// a_i = w_i / sum w, (b, c, d)_i = a_i (u, v, w)_i. Decoding B bodies in one
// pass over the matrix divides its memory traffic by B.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/spatial/centroid_grid.h>

namespace atelier {

class BodySet;
struct DecodeWorkspace;

/// Decoding kernels (single-body and batched), widest first.
enum class DecodeKernel : std::uint8_t { kAuto, kAvx512, kAvx2, kPortable };

/// The polygons of a body surface (all live faces of the model, in index
/// order) over node indices; what encoding and decoding need of a body.
struct BodyPolygons : PolygonSoup {  // positions unused: they come per body
  std::uint32_t node_count = 0;     // node capacity of the body model
  std::uint64_t topology_hash = 0;  // of node_count and the face arrays

  [[nodiscard]] std::size_t size() const noexcept { return face_count(); }
  [[nodiscard]] static BodyPolygons from_model(const Model& body);
  [[nodiscard]] static BodyPolygons from_model(const Model& body, SurfaceIdx surface);
};

/// Frame of a polygon (eq. 8): X = unit normal, Y = unit (p_1 - p_c),
/// Z = X x Y, at the centroid p_c. Degenerate polygons (zero area, or p_1 at
/// the centroid) are flagged and never used as p-polygons.
struct PolygonFrames {
  std::vector<Vec3f> centroid, x, y, z;  // float: what decoding reads
  std::vector<std::uint8_t> degenerate;
};

/// Frames of every polygon for the given node positions (eq. 8). Parallel.
///
/// With `reference_corners` (each polygon's corners in its frame on the
/// body the template was encoded on, as stored in DetailEncoding), Y is not
/// anchored at p_1 but turned by the best-fit (Procrustes) rotation of the
/// corners against their reference shape. On the reference body this is eq.
/// (8) exactly; on a deformed body it no longer depends on which corner is
/// numbered first, so the blend of eq. (12) maps a mirror-symmetric body and
/// garment to a mirror-symmetric result (seed 001 Fig. 17), which anchoring
/// at p_1 does not when polygons shear.
///
/// With `scaled` (and reference corners), the three axes are also scaled by
/// the polygon's best-fit similarity scale s = |sum r_k . R d_k| / sum |r_k|^2
/// (the Procrustes scale of the corners d_k against their reference shape
/// r_k): see DetailParams::scaled_frames. s = 1 on the reference body.
void compute_frames(const BodyPolygons& body, std::span<const Vec3d> positions, PolygonFrames& out,
                    const ExecContext& ctx = {}, std::span<const Eigen::Vector2f> reference_corners = {},
                    bool scaled = false);

struct DetailParams {
  /// p-polygons per vertex; 0 means round(N_H / 100) (the paper's choice), at least 1.
  std::size_t polygons_per_vertex = 0;
  /// Single p-polygon mode (seed 001 Figs. 16-17), for comparison.
  bool single_polygon = false;
  double epsilon = 1e-8;  // eq. (10)
  double cell = 0.0;      // voxel size, 0 = automatic
  /// Anchor frames by the best-fit rotation (see compute_frames); false gives
  /// the paper's eq. (8) on every body.
  bool fitted_frames = true;
  /// Eq. (10) minus its value at the first polygon left out (the (N_q+1)-th
  /// nearest centroid), so a polygon's weight falls to zero as it leaves the
  /// p-polygon set: the encoding is continuous in q (neighbouring garment
  /// vertices whose sets differ do not jump apart) and a mirror pair split by
  /// the cut-off cannot break symmetry. false gives eq. (10) as printed.
  bool tapered_weights = true;
  /// Frames that scale with the skin (issue 26): each polygon's axes are
  /// multiplied by its similarity scale against the reference body (see
  /// compute_frames), so an offset from a p-polygon grows with the local
  /// girth, the normal offset included. Eq. (11) blends centroids p~_c,
  /// which do scale, with offsets that the paper's unit frames do not: on a
  /// uniformly scaled body q~ = s c + (q - c) (c the weighted centroid of
  /// the p-polygons, centimetres inside a limb) instead of s q. Scaled
  /// frames give s q exactly. Needs fitted_frames. Off by default: it
  /// changes every garment's result (docs/performance.md, issue 26).
  bool scaled_frames = false;
};

/// The encoding: a CSR sparse matrix with rows = garment vertices.
struct DetailEncoding {
  std::uint32_t polygon_count = 0;
  std::uint32_t body_node_count = 0;
  std::uint64_t topology_hash = 0;
  std::vector<std::uint32_t> row;      // size V+1
  std::vector<std::uint32_t> polygon;  // per entry
  /// Per entry, precombined (see top). Four columns, not one interleaved
  /// (a, b, c, d) array: decoding reads them as four sequential streams,
  /// which this machine's prefetchers keep up with where one stream of 16
  /// bytes per entry stalls (docs/performance.md, 2026-11-24).
  std::vector<float> a, b, c, d;
  /// Corners of every body polygon in its reference frame (fitted frames);
  /// empty in eq. (8) mode.
  std::vector<Eigen::Vector2f> reference_corners;
  /// Frames scaled by each polygon's similarity scale (DetailParams::
  /// scaled_frames); stored in the .atd from version 4 on.
  bool scaled_frames = false;
  /// The garment's layer order when it has one (MakeHuman's .mhclo z_depth:
  /// smaller is nearer the skin); stored in the .atd from version 3 on.
  std::optional<std::int32_t> z_depth;
  [[nodiscard]] std::size_t vertex_count() const noexcept { return row.empty() ? 0 : row.size() - 1; }
  [[nodiscard]] std::size_t entries() const noexcept { return polygon.size(); }
  /// Bytes of the matrix (what one decoding pass streams).
  [[nodiscard]] std::size_t bytes() const noexcept {
    return entries() * 20 + row.size() * 4 + reference_corners.size() * 8;
  }
};

/// Encodes garment vertices on the body (eqs. 8-10). Errors: empty body,
/// non-finite garment vertex (naming it), fewer usable polygons than needed.
[[nodiscard]] Expected<DetailEncoding> encode_detail(const BodyPolygons& body, std::span<const Vec3d> body_positions,
                                                     std::span<const Vec3d> garment, const DetailParams& params = {},
                                                     const ExecContext& ctx = {});

/// Checks that `body` has the topology the encoding was made on.
[[nodiscard]] Status check_topology(const DetailEncoding& enc, const BodyPolygons& body);

/// Decodes on one body (eqs. 11-12): frames are computed from the positions.
[[nodiscard]] Status decode_detail(const DetailEncoding& enc, const BodyPolygons& body,
                                   std::span<const Vec3d> body_positions, std::span<Vec3d> out,
                                   const ExecContext& ctx = {});
/// Decodes with frames already computed (e.g. shared by several garments).
/// `allow`: the widest kernel to use (kAuto: the widest this CPU runs; the
/// AVX-512 and AVX2 kernels give the same bits). Returns the kernel that ran.
DecodeKernel decode_detail(const DetailEncoding& enc, const PolygonFrames& frames, std::span<Vec3d> out,
                           const ExecContext& ctx = {}, DecodeKernel allow = DecodeKernel::kAuto);

/// An encoding rearranged for batched decoding, built once per encoding (as
/// FairPlan is per mesh). Garment vertices are cut into tiles of kTile; in
/// a tile, entries are grouped by polygon ("runs", polygons increasing, the
/// tile's vertices increasing within a run), so a polygon's frames for 16
/// bodies are fetched once per tile and applied to every tile vertex that
/// uses it (12 FMA-unit operations per entry and 8 bodies, the minimum for
/// eqs. 11-12), and each vertex still sums its entries in row order. Same
/// entries and coefficients as the encoding (float, no loss); 17 bytes per
/// entry.
class DetailDecoder {
 public:
  // Vertices per tile, the most a byte indexes: longer runs (41 entries per
  // polygon on the 30k x 200 benchmark, against 26 with 128) fetch fewer
  // frames. Measured gain small, within this machine's run-to-run spread
  // (docs/performance.md, session of 2026-11-22).
  static constexpr std::size_t kTile = 256;
  DetailDecoder() = default;
  /// Reads the encoding's matrix; O(entries), parallel over tiles.
  explicit DetailDecoder(const DetailEncoding& enc, const ExecContext& ctx = {});
  [[nodiscard]] std::size_t vertex_count() const noexcept { return vertex_count_; }
  [[nodiscard]] std::size_t entries() const noexcept { return vertex_.size(); }
  [[nodiscard]] std::size_t runs() const noexcept { return run_polygon_.size(); }
  /// Polygons some entry uses, increasing: the only frames a pass computes.
  [[nodiscard]] std::span<const std::uint32_t> used_polygons() const noexcept { return used_polygons_; }
  /// Bytes one pass over the matrix streams.
  [[nodiscard]] std::size_t bytes() const noexcept {
    return entries() * 17 + runs() * 8 + tile_run_.size() * 4 + reference_corners_.size() * 8;
  }
  /// Checks that `body` has the topology the encoding was made on.
  [[nodiscard]] Status check_topology(const BodyPolygons& body) const;

 private:
  friend Status decode_detail_batch(const DetailDecoder& dec, const BodyPolygons& body, const BodySet& bodies,
                                    std::size_t first, std::size_t count, std::span<Vec3f> out, DecodeWorkspace& ws,
                                    const ExecContext& ctx);
  std::uint32_t polygon_count_ = 0;
  std::uint32_t body_node_count_ = 0;
  std::uint64_t topology_hash_ = 0;
  std::uint32_t vertex_count_ = 0;
  std::vector<Eigen::Vector2f> reference_corners_;
  bool scaled_frames_ = false;
  std::vector<std::uint32_t> tile_run_{0};    // tile -> first run (size tiles + 1)
  std::vector<std::uint32_t> run_polygon_;    // per run
  std::vector<std::uint32_t> used_polygons_;  // distinct run_polygon_, increasing
  std::vector<std::uint32_t> run_entry_{0};   // run -> first entry (size runs + 1)
  std::vector<std::uint8_t> vertex_;          // per entry: its vertex within the tile
  std::vector<float> coef_;                   // per entry: a, b, c, d (see top)
};

/// Buffers of batched decoding (a pass's frames, the bodies' positions
/// transposed): megabytes that a caller decoding batch after batch keeps
/// here instead of allocating (and page-faulting) them on every call.
/// One workspace per concurrent caller.
struct DecodeWorkspace {
  std::vector<float> frames, positions;
  /// The widest kernel the caller allows (kAuto: the widest this CPU runs).
  /// AVX-512 and AVX2 give the same bits; the portable kernel computes the
  /// frames in double and differs from them by float rounding.
  DecodeKernel allow = DecodeKernel::kAuto;
  /// The kernel the last call ran.
  DecodeKernel ran = DecodeKernel::kAuto;
};

/// Decodes bodies [first, first+count) of a body set, 16 bodies per pass
/// over the matrix. out is body-major: out[(b - first) * V + v].
/// Deterministic: every output is summed in entry order, whatever the thread
/// count; equal to decode_detail on each body to float rounding. Where the
/// CPU has AVX-512, a run's frames for the pass's 16 bodies stay in 12
/// registers (docs/performance.md: 0.84x the AVX2 kernel's time), with the
/// AVX2 kernel's bits.
[[nodiscard]] Status decode_detail_batch(const DetailDecoder& dec, const BodyPolygons& body, const BodySet& bodies,
                                         std::size_t first, std::size_t count, std::span<Vec3f> out,
                                         const ExecContext& ctx = {});
/// The same with the buffers kept in `ws` between calls (same results).
[[nodiscard]] Status decode_detail_batch(const DetailDecoder& dec, const BodyPolygons& body, const BodySet& bodies,
                                         std::size_t first, std::size_t count, std::span<Vec3f> out,
                                         DecodeWorkspace& ws, const ExecContext& ctx = {});
/// The same, building the DetailDecoder on each call (O(entries)): callers
/// decoding several batches with one encoding should build it once.
[[nodiscard]] Status decode_detail_batch(const DetailEncoding& enc, const BodyPolygons& body, const BodySet& bodies,
                                         std::size_t first, std::size_t count, std::span<Vec3f> out,
                                         const ExecContext& ctx = {});

/// Native detail-template file (.atd): header (magic, version, sizes,
/// topology hash), the CSR matrix, a checksum. Written atomically.
void write_detail(const DetailEncoding& enc, const std::filesystem::path& path);
[[nodiscard]] DetailEncoding read_detail(const std::filesystem::path& path);
/// The same on bytes already read; `display_name` names them in errors.
[[nodiscard]] DetailEncoding read_detail_from_bytes(std::string_view bytes, std::string_view display_name);

}  // namespace atelier
