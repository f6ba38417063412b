// Energy-based surface flattening: the 2D patterns of seed 001 section 7, by
// its reference [48] (Wang, Smith, Yuen, "Surface flattening based on energy
// model", Computer-Aided Design 34(11), 2002). One piece per surface.
//
// (The paper itself is not in /work/shared/seeds; what it prescribes is taken
// from seed 001 section 7 and issue 22.) The spring-mass model: every edge of
// the piece's triangles is a spring of rest length l_ij (its 3D length) and
// stiffness C_ij; a pattern Q has the energy
//     E = sum over springs 1/2 C_ij (|Q_i Q_j| - l_ij)^2 .
// Stiffness (FlattenOptions::stiffness): C_ij = lbar / l_ij by default, the
// stiffness EA / l of a bar of one material and cross-section, so E is the
// integral of l * strain^2 and does not depend on how finely a region is
// meshed (lbar, the mean rest length, only keeps E in length^2 units).
// Uniform C_ij = 1 is the other choice (one constant for every spring).
//
//  Phase 1, triangle flattening: breadth-first over the
//  triangles from a seed (the largest, or the caller's); each new corner goes
//  to the intersection of the two circles of its 3D edge lengths about the
//  placed side, on the side that keeps the triangle counter-clockwise; where
//  a triangle closes a loop (its third corner is already placed), the
//  vertices within `relax_rings` rings of it take `relax_sweeps` guarded
//  Newton steps on the partial spring system (the partial system releases
//  its strain).
//  Phase 2, planar mesh deformation: E is minimised by
//  L-BFGS with the spring Laplacian as initial Hessian (prefactored by
//  sparse Cholesky; Liu, Bouaziz, Kavan, ACM TOG 36(3) 2017), a
//  quasi-Newton method in place of moving nodes along their spring forces (see
//  docs/glossary.md). The guard against flips and overlaps: a barrier
//  -A (r - r0)^2 ln(r / r0) on triangles whose area ratio r = A'/A falls
//  below r0 = 0.1 (zero above, so E is untouched on any reasonable piece,
//  infinite at a flip), a line search that starts below the largest step
//  keeping every triangle counter-clockwise, and the refusal of any step
//  that makes the boundary cross itself (overlap). If phase 1 leaves a
//  flipped triangle or a crossing boundary (strongly saddle-shaped pieces),
//  phase 2 starts instead from Tutte's embedding with the longest boundary
//  loop on a circle, which has neither.
//  Seam lengths (an addition to the paper, docs/glossary.md): pieces sewn
//  together must have partner seams of one length, which flattening each
//  piece on its own does not give (each side takes its own share of the
//  strain). With FlattenOptions::seam_lengths, every joint member on the
//  piece is a constraint L_k(Q) = T_k, L_k its 2D length, T_k the mean 3D
//  length of the joint's members. Fixing the common length at the 3D one
//  (what the sewability check asks anyway, pattern.h) decouples the joint
//  problem over the pieces of a seam exactly: each piece meets the same
//  target alone, so pieces still flatten in parallel. Phase 2 minimises E
//  subject to the constraints by an augmented Lagrangian (L-BFGS rounds,
//  the penalty's Gauss-Newton term added to the preconditioner by
//  Sherman-Morrison-Woodbury), then projects onto them (Newton steps in the
//  metric of H0, under the same flip and overlap guards): partner seams
//  come out equal to rounding, no triangle flipped.
// Placement: the pattern is turned so its grain line (the 3D grain
// direction's image, or the pattern's principal axis) runs along +v, and
// moved so its bounding box starts at (0, 0). The pattern is seen from the
// front of the faces (their counter-clockwise side): the right side of the
// fabric when faces point outwards.
//
// Pieces: every live surface with faces (or the listed ones). A piece must be
// a connected, manifold (no wire edge, ring node or non-manifold vertex)
// topological disk: one boundary loop and no handle; with
// `allow_holes`, more boundary loops (interior holes) are accepted. A closed
// surface (a body) or a tube (a sleeve, a skirt: two loops) needs a seam
// first. Polygons are fanned from their first corner (the fan diagonals are
// springs too); run triangulate_polygons first for non-convex ones.
//
// Distortion, always measured against the 3D positions: area error
// E_A = sum |A' - A| / sum A over triangles, length error
// E_L = sum |l' - l| / sum l over the model's edges, the largest edge strain
// |l' - l| / l, the principal stretches (singular values of the 3D -> 2D
// map) per triangle, flipped triangles (2D area <= 0) and boundary crossings.
//
// Reads: the surfaces' faces, nodes.position. Writes: nodes.uv of the pieces'
// nodes only (nothing on error: all pieces are flattened before any is
// written).
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace atelier {

enum class SpringStiffness : std::uint8_t {
  kInverseLength = 0,  // C_ij = lbar / l_ij (default, see above)
  kUniform = 1,        // C_ij = 1
};

struct FlattenOptions {
  /// Surfaces to flatten; empty: every live surface with faces.
  std::vector<SurfaceIdx> surfaces;
  /// Seed triangles: a face of a surface seeds that surface (its first fan
  /// triangle); other surfaces start at their largest triangle.
  std::vector<FaceIdx> seed_faces;
  /// Accept pieces with more than one boundary loop (interior holes).
  bool allow_holes = false;
  SpringStiffness stiffness = SpringStiffness::kInverseLength;
  /// C_ij of the springs along the boundary (the sew line) times this: above
  /// 1, the strain of a doubly curved piece goes inside it and the sew line
  /// keeps its 3D lengths, so partner seams stay as long as each other
  /// (made_to_measure.h uses 100).
  double boundary_stiffness = 1;
  /// Partner seams share their 2D length: every member of a joint that lies
  /// on a piece (a sewn seam, or the two sides of a seam opened by
  /// open_seams) is held, exactly, at the mean 3D length of its joint's
  /// members: phase 2 minimises E subject to these lengths (see below).
  bool seam_lengths = true;
  /// Phase 1: the region relaxed where a loop closes, and its sweeps.
  int relax_rings = 1;
  int relax_sweeps = 1;
  /// Phase 2 stops after this many L-BFGS iterations or when two iterations
  /// in a row lower E by less than `tolerance` * E.
  int max_iterations = 400;
  double tolerance = 1e-7;
  int lbfgs_memory = 8;
  /// 3D grain direction (zero: the pattern's principal axis is the grain).
  Vec3d grain = Vec3d::Zero();
  /// Refuse triangles whose 3D area is below this fraction of the mean
  /// squared spring length (degenerate faces).
  double degenerate_area = 1e-12;
};

/// Distortion of a pattern against its 3D piece (definitions above).
struct PatternDistortion {
  double area_error = 0;       // E_A
  double length_error = 0;     // E_L
  double max_edge_strain = 0;  // max |l' - l| / l over the model's edges
  double min_stretch = 1;      // smallest principal stretch over triangles
  double max_stretch = 1;      // largest principal stretch over triangles
  std::size_t flipped = 0;     // triangles with 2D area <= 0
  std::size_t boundary_crossings = 0;
};

struct PieceFlattening {
  SurfaceIdx surface;
  std::string name;
  std::size_t nodes = 0, triangles = 0, springs = 0, boundary_loops = 0;
  FaceIdx seed_face;
  PatternDistortion distortion;
  /// Per triangle (faces fanned from their first corner, faces in index
  /// order): its face, its nodes (CCW) and its principal stretches
  /// (sigma_1 >= sigma_2).
  std::vector<FaceIdx> triangle_face;
  std::vector<std::array<NodeIdx, 3>> triangle_nodes;
  std::vector<Vec2d> stretch;
  /// Solver figures.
  double energy_phase1 = 0, energy = 0;
  std::size_t closures = 0;  // phase 1 triangles that closed a loop
  int iterations = 0;        // phase 2 iterations
  int rejected_steps = 0;    // steps cut short by the flip or overlap guard
  bool warm_started = false;
  /// A warm start given up (its first iterations all cut by the flip guard,
  /// or its seams left off their lengths: the piece was then flattened
  /// cold) after this many iterations; 0 if not.
  int warm_abandoned_iterations = 0;
  bool tutte_fallback = false;
  bool reused_factor = false;  // a warm start kept the previous body's factor
  /// Seam lengths (FlattenOptions::seam_lengths): the constrained joint
  /// members on the piece, the augmented-Lagrangian rounds and projection
  /// steps phase 2 took, and the largest |2D length - target| left (model
  /// units).
  std::size_t seam_constraints = 0;
  int seam_rounds = 0, seam_projections = 0;
  double seam_residual = 0;
  double phase1_ms = 0, factor_ms = 0, phase2_ms = 0, total_ms = 0;
};

struct FlattenReport {
  std::vector<PieceFlattening> pieces;
};

/// Reusable flattening of one surface (geometry-central style): build() once
/// per topology (checks, triangles, springs, the symbolic Cholesky
/// analysis), then flatten() for each set of positions, e.g. each
/// regenerated body's garment. With `warm_start`, a flip-free pattern already
/// in `uv` (another body's), fitted by one affine map to this body's rest
/// lengths, replaces phase 1, and phase 2 keeps the previous body's
/// Cholesky factor as its preconditioner when no stiffness moved by more
/// than 25% (the minimiser is the same; only the path to it differs). A
/// warm start whose first 24 steps are all cut by the flip guard, or whose
/// seams end off their lengths, is given up for the cold start
/// (PieceFlattening::warm_abandoned_iterations; the cold bits).
class Flattener {
 public:
  Flattener();
  ~Flattener();
  Flattener(Flattener&&) noexcept;
  Flattener& operator=(Flattener&&) noexcept;

  /// Errors (naming the surface): kStaleHandle, kTopology (no faces, closed,
  /// several components, handles, several loops without allow_holes),
  /// kNonManifold (wire edge, ring node, non-manifold vertex).
  [[nodiscard]] Status build(const Model& m, SurfaceIdx s, const FlattenOptions& opt = {});

  /// Flattens with `positions` (indexed by node index of the model given to
  /// build()); writes uv[v] for the piece's nodes v only. Errors:
  /// kInvalidArgument (not built, spans too short), kDegenerate (a
  /// non-finite position, a zero-length edge or a degenerate triangle,
  /// named), kInternal (the factorization failed).
  [[nodiscard]] Expected<PieceFlattening> flatten(std::span<const Vec3d> positions, std::span<Vec2d> uv,
                                                  bool warm_start = false, const ExecContext& ctx = {});

  /// The next warm start begins as `other`'s would: its seam multipliers
  /// and its Cholesky factor (shared, immutable) are copied. With the same
  /// pattern in `uv`, flatten() then gives the bits `other` would give,
  /// whatever this Flattener flattened before: many bodies can start from
  /// one reference body in any order, on any thread. A piece of the same
  /// nodes and seams fanned otherwise (a polygon's fan from another corner)
  /// takes the multipliers only; its next flatten() factors its own
  /// springs. Errors: kInvalidArgument (either not built, or built on
  /// other nodes or seams).
  [[nodiscard]] Status warm_from(const Flattener& other);

  [[nodiscard]] bool built() const noexcept;
  [[nodiscard]] SurfaceIdx surface() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Reusable flattening of every piece of a model: one Flattener per piece,
/// built once for a topology (a garment regenerated on many bodies keeps
/// its topology), then flatten() per set of positions. Pieces run in
/// parallel, one task each; results do not depend on the thread count.
class ModelFlattener {
 public:
  /// The pieces: FlattenOptions::surfaces, or every live surface with faces.
  /// Errors: kTopology (no such surface) and those of Flattener::build (the
  /// first bad piece, in surface order).
  [[nodiscard]] Status build(const Model& m, const FlattenOptions& opt = {});
  /// Flattens every piece with `positions` (indexed by node) into `uv`
  /// (indexed by node; with `warm_start`, the previous pattern there is the
  /// start). On error (the first failing piece's, in piece order) `uv` is
  /// unchanged.
  [[nodiscard]] Expected<FlattenReport> flatten(std::span<const Vec3d> positions, std::span<Vec2d> uv,
                                                bool warm_start = false, const ExecContext& ctx = {});
  /// Flattener::warm_from for every piece (`other` built on the same model
  /// topology and options).
  [[nodiscard]] Status warm_from(const ModelFlattener& other);
  [[nodiscard]] std::span<const SurfaceIdx> surfaces() const noexcept { return surfaces_; }

 private:
  std::vector<SurfaceIdx> surfaces_;
  std::vector<Flattener> pieces_;
  std::size_t node_slots_ = 0;
};

/// Flattens every piece (see above) and writes nodes.uv: ModelFlattener once.
/// Stops at the first bad piece, with its error and nothing written.
[[nodiscard]] Expected<FlattenReport> flatten_surfaces(Model& m, const FlattenOptions& opt = {},
                                                       const ExecContext& ctx = {});

/// The distortion of the pattern in `uv` for surface s (fanned as above)
/// against `positions`, without flattening: for patterns from elsewhere.
[[nodiscard]] Expected<PatternDistortion> measure_pattern(const Model& m, SurfaceIdx s,
                                                          std::span<const Vec3d> positions, std::span<const Vec2d> uv,
                                                          const ExecContext& ctx = {});

}  // namespace atelier
