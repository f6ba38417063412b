// Garment regeneration: a garment designed on a reference body, fitted on
// other bodies of its family. The one pipeline that `atelier regen`,
// `atelier demo`, the tests, the benchmarks and embedding programs run:
//
//  1. decode the detail template (seed 001 section 6, eqs. 11-12;
//     systems/garment/detail_template.h), in batches of 16 bodies wherever
//     there is more than one body;
//  2. the edge transfer: the skin's local stretch under each garment edge
//     (systems/garment/edge_transfer.h);
//  3. the collision pass with layers: out of the body and back to the
//     clearance the garment had on the reference body, outer garments kept
//     outside inner ones (systems/garment/collision_pass.h);
//  4. the fit figures of each garment (inside vertices, clearance, strain).
//
// A one-call function (regenerate_garment) beside a reusable object
// (GarmentRegenerator) that keeps the decoders and buffers across batches.
// Errors are returned per body, never skipped: one bad body is reported and
// the others complete.
//
// Reads: the reference body's polygons and triangles (GarmentFamily), the
// garments' encodings (GarmentTemplate), body positions. Writes: the results.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/adjacency.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/reference_body.h>
#include <atelier/systems/garment/collision_pass.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/edge_transfer.h>
#include <atelier/systems/garment/fit_measure.h>
#include <atelier/systems/spatial/collision_body.h>

namespace atelier {

/// What every garment of one body family shares: the reference body's
/// polygons (what detail templates are encoded on) and its collision
/// topology (closed skin triangles).
struct GarmentFamily {
  BodyPolygons polygons;
  std::shared_ptr<const CollisionTopology> collision;
  std::vector<Vec3d> reference_positions;  // the reference body's skin, indexed by node

  /// Errors: the reference's skin is not closed and consistently oriented
  /// (naming the first bad edge).
  [[nodiscard]] static Expected<GarmentFamily> of(const ReferenceBody& reference);
};

/// A garment ready to regenerate: its polygons on the reference body and
/// what is encoded from them.
struct GarmentTemplate {
  std::string name;
  PolygonSoup mesh;  // positions: on the reference body (metres)
  DetailEncoding encoding;
  std::vector<std::array<std::uint32_t, 2>> edges;  // PolygonSoup::edges()
  std::vector<double> rest_length;                  // per edge, on the reference body
  NodeAdjacency adjacency;
  ClearanceEncoding clearance;  // what the collision pass restores
  EdgeTransfer transfer;
  int z_depth = 0;  // layer order in an outfit: smaller is nearer the skin
};

struct GarmentEncodeOptions {
  DetailParams detail;
  EdgeTransferParams transfer;
  /// The garment's edges in the caller's order (for instance a Model's edge
  /// table, so that per-edge results line up with it); empty: the soup's
  /// own, mesh.edges(). The edge transfer's sums follow this order.
  std::span<const std::array<std::uint32_t, 2>> edges;
};

/// Encodes a garment (its polygons on the reference body) for regeneration
/// on the family. Errors: an empty or malformed soup, non-finite vertices,
/// duplicate edges, and those of encode_detail, encode_clearance and
/// encode_edge_transfer; each names the garment.
[[nodiscard]] Expected<GarmentTemplate> encode_garment(const GarmentFamily& family, std::string name, PolygonSoup mesh,
                                                       const GarmentEncodeOptions& options = {},
                                                       const ExecContext& ctx = {});
/// The same with a detail encoding already made (read from a .atd file): the
/// clearance and the edge transfer are encoded again (they are cheap).
/// Errors: an encoding made on another topology or for another vertex count.
[[nodiscard]] Expected<GarmentTemplate> encode_garment(const GarmentFamily& family, std::string name, PolygonSoup mesh,
                                                       DetailEncoding encoding,
                                                       const GarmentEncodeOptions& options = {},
                                                       const ExecContext& ctx = {});

struct GarmentFileOptions {
  /// The garment file's units and axes (those of the body it was made on):
  /// mapped to metres and Y up at the door (systems/body/body_file.h).
  BodyFrame frame;
  GarmentEncodeOptions encode;
};

/// Encodes the garment in an OBJ file on `reference` (in the engine's
/// frame, e.g. from read_reference_body with the same BodyFrame): reads it
/// (read_garment_mesh), maps it to metres and Y up, rounds it to float (what
/// the template's .obj stores, so a template read back is the one encoded)
/// and encodes it (encode_garment), named after the file's stem. The
/// template is in metres and Y up. Errors name the file: those of
/// read_garment_mesh, a bad frame, a reference whose skin is not closed and
/// consistently oriented, and those of encode_garment.
[[nodiscard]] Expected<GarmentTemplate> encode_garment_file(const ReferenceBody& reference,
                                                            const std::filesystem::path& garment,
                                                            const GarmentFileOptions& options = {},
                                                            const ExecContext& ctx = {});

/// A garment file pair: `<stem>.atd` (the detail encoding) and `<stem>.obj`
/// beside it (the garment on the reference body), as `atelier encode
/// --garment` writes them; z_depth is the .atd's when it has one (0 if not).
/// Errors name the file.
[[nodiscard]] Expected<GarmentTemplate> read_garment_template(const GarmentFamily& family,
                                                              const std::filesystem::path& atd,
                                                              const ExecContext& ctx = {});
/// Writes `<dir>/<name>.obj` then `<dir>/<name>.atd` (last: the template is
/// complete when its .atd exists), each atomically.
void write_garment_template(const GarmentTemplate& garment, const std::filesystem::path& dir);

/// A garment as a polygon soup from an OBJ file: every `v` and every face of
/// every group, positions times `scale` (no Model is built: real garments
/// are often not manifold), and the texture coordinates of every corner
/// (corner_uv) when every corner has a `vt`. Errors name the file and line.
[[nodiscard]] Expected<PolygonSoup> read_garment_mesh(const std::filesystem::path& file, double scale = 1.0);
/// The same in a file's units and axes, mapped to metres and Y up
/// (systems/body/body_file.h). Errors also: a bad frame, a vertex that is
/// not finite once mapped.
[[nodiscard]] Expected<PolygonSoup> read_garment_mesh(const std::filesystem::path& file, const BodyFrame& frame);
/// Writes the soup with `positions` in float precision (what
/// read_garment_mesh gives back), with its corner_uv as `vt` (one per
/// distinct value, seams kept), atomically. Regeneration moves positions
/// only, so a regenerated garment keeps the uv map of the garment encoded.
void write_garment_mesh(const PolygonSoup& mesh, std::span<const Vec3d> positions, const std::filesystem::path& file);

struct GarmentRegenOptions {
  CollisionParams collision;
  bool edge_transfer = true;
  bool collision_pass = true;
  /// Several garments on one body are resolved as layers (z_depth order,
  /// ties in the order given) and each garment's vertices inside a garment
  /// of a lower layer are counted (GarmentQuality::layer_inside).
  bool layers = true;
  LayerPenetrationParams layer_penetration;
  /// Widest decoding kernel (kAuto: the widest this CPU runs).
  DecodeKernel kernel = DecodeKernel::kAuto;
};

/// The fit of one garment on one body, from the exact distance of each
/// vertex at its final position.
struct GarmentQuality {
  std::size_t vertices = 0;
  std::size_t inside = 0;       // signed distance < 0
  double max_depth = 0;         // deepest of them (m, >= 0)
  double min_clearance = 0;     // smallest signed distance (m)
  double mean_clearance = 0;    // mean signed distance (m)
  double clearance_error = 0;   // max |distance - target clearance| (m)
  double strain_max = 0;        // max |l / l_reference - 1| over edges
  double strain_p95 = 0;        // its 95th percentile (quantile_in_place)
  std::size_t pushed = 0;       // vertices the collision pass moved
  /// Vertices inside a garment of a lower layer of the same outfit
  /// (count_inside_layer, systems/garment/fit_measure.h; each vertex once);
  /// 0 for the innermost layer and when the garments are not layered.
  std::size_t layer_inside = 0;
  CollisionReport pass;
};

struct GarmentResult {
  std::vector<Vec3d> positions;
  GarmentQuality quality;
};

/// One body's garments, or why the body failed.
struct BodyGarments {
  Status status;
  std::vector<GarmentResult> garments;  // in the order the garments were given
};

/// The reusable pipeline: decoders built once per garment, decoding buffers
/// kept across calls. One object per concurrent caller.
class GarmentRegenerator {
 public:
  GarmentRegenerator() = default;
  /// Errors: no garments, a garment encoded on another topology.
  [[nodiscard]] static Expected<GarmentRegenerator> create(std::shared_ptr<const GarmentFamily> family,
                                                          std::vector<std::shared_ptr<const GarmentTemplate>> garments,
                                                          const GarmentRegenOptions& options = {},
                                                          const ExecContext& ctx = {});

  /// Bodies [first, first + count) of `bodies` (the family's topology):
  /// decoded 16 bodies per pass, then tiles of 16 bodies in parallel: the
  /// tile's edge transfer with bodies as SIMD lanes
  /// (apply_edge_transfer_bodies), then each body's collision pass and
  /// figures (tiles do not depend on the thread count). `out` gets one
  /// entry per body; a body that fails has its status set and the others
  /// complete. Errors (of the whole call): a range outside the set, a body
  /// set of another topology, cancellation.
  [[nodiscard]] Status run(const BodySet& bodies, std::size_t first, std::size_t count, std::vector<BodyGarments>& out,
                           const ExecContext& ctx = {});
  /// One body given as positions (indexed by node): decoded on its own.
  [[nodiscard]] BodyGarments run_one(std::span<const Vec3d> body, const ExecContext& ctx = {}) const;

  [[nodiscard]] std::size_t garment_count() const noexcept { return garments_.size(); }
  [[nodiscard]] const GarmentTemplate& garment(std::size_t i) const noexcept { return *garments_[i]; }
  [[nodiscard]] const GarmentFamily& family() const noexcept { return *family_; }
  /// Wall time of the last run()'s decoding, per body (ms).
  [[nodiscard]] double last_decode_ms_per_body() const noexcept { return decode_ms_per_body_; }

 private:
  [[nodiscard]] std::vector<const GarmentTemplate*> raw_garments() const;

  std::shared_ptr<const GarmentFamily> family_;
  std::vector<std::shared_ptr<const GarmentTemplate>> garments_;
  std::vector<std::shared_ptr<const DetailDecoder>> decoders_;
  GarmentRegenOptions options_;
  std::vector<DecodeWorkspace> workspace_;  // per garment
  std::vector<Vec3f> decoded_;              // a batch's decoded positions
  double decode_ms_per_body_ = 0;
};

/// One garment on one body (the one-call form).
[[nodiscard]] Expected<GarmentResult> regenerate_garment(const GarmentFamily& family, const GarmentTemplate& garment,
                                                         std::span<const Vec3d> body,
                                                         const GarmentRegenOptions& options = {},
                                                         const ExecContext& ctx = {});

}  // namespace atelier
