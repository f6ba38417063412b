// The embedded default reference body: a procedural, parametric, watertight
// dress-form mannequin (neck, shoulders, short arms, torso, hips, two legs to
// the ankles) built from body measurements, with the semantic feature curves
// and points of seed 000 section 4.1.1 / seed 001 section 4.
//
// Construction: horizontal rings of star-shaped cross sections (two-sided
// super-ellipses whose sizes are interpolated along the height from the
// measurements). Every vertex j of a ring lies on the ray at a fixed polar
// angle about the ring centre, so the bands between consecutive rings cannot
// cross each other. The junctions are fixed in index space: the crotch ring
// of the torso splits into two leg rings through a bridge of N/2-1 nodes, and
// each short arm is a tube whose first ring is the boundary of a rectangular
// hole cut in the torso grid. Ring counts per segment depend only on the
// resolution, so every parameter set gives the same topology.
//
// Girths: the tape measure of a ring is the perimeter of the convex hull of
// its polygon. Scaling a section about its centre scales that hull exactly,
// so each measured ring is fitted in one step (no secant iterations needed)
// and matches the request to rounding error, at every resolution.
//
// Axes: y up, z to the front, +x the body's left; metres. y = 0 is the floor
// the person stands on: levels are placed from the stature with
// anthropometric ratios (nape 0.848 H, armpit 0.118 H below it, knee
// 0.285 H, ankle 0.055 H); the form is headless and ends in short caps
// below the ankles (lowest point 0.03 H) and above the neck.
//
// Reads: nothing global. Writes: a new Model (one surface "skin").
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/body/reference_body.h>

namespace atelier {

/// Body measurements in metres. height is the person's stature (the headless
/// form is shorter). Girths are tape measures (convex hull of the cross
/// section). shoulder_width is the straight distance between the two
/// shoulder points; back_length runs from the nape (neck base) to the waist;
/// inseam is the crotch height.
struct MannequinParams {
  double height = 1.70;
  double neck_girth = 0.36;
  double bust_girth = 0.92;
  double underbust_girth = 0.78;
  double waist_girth = 0.74;
  double hip_girth = 0.98;
  double thigh_girth = 0.56;
  double knee_girth = 0.37;
  double ankle_girth = 0.23;
  double upper_arm_girth = 0.28;
  double shoulder_width = 0.40;
  double back_length = 0.42;
  double inseam = 0.78;
  friend bool operator==(const MannequinParams&, const MannequinParams&) = default;
};

/// Ring counts. `around` (N) is the number of nodes per torso/leg ring.
struct MannequinResolution {
  std::uint32_t around = 96;  // multiple of 16
  std::uint32_t level = 6;    // rings per segment scale with it
  /// Level L: N = 16 L and about 1 ring per 6/L cm. Level 6 (default) gives
  /// about 23k faces; level 2 about 2.7k.
  [[nodiscard]] static MannequinResolution from_level(std::uint32_t level) noexcept {
    return {16u * level, level};
  }
};

/// Checks ranges and consistency (e.g. underbust <= bust, inseam below the
/// waist); the message names the offending measurement.
[[nodiscard]] Status validate_params(const MannequinParams& p);

/// Feature ids of the mannequin's curves (stable across versions: templates
/// store them).
enum MannequinCurve : std::int32_t {
  kNeckBase = 1,
  kShoulderLeft,
  kShoulderRight,
  kArmholeLeft,
  kArmholeRight,
  kBust,
  kUnderbust,
  kWaist,
  kHip,
  kThighLeft,
  kThighRight,
  kKneeLeft,
  kKneeRight,
  kAnkleLeft,
  kAnkleRight,
  kCentreFront,
  kCentreBack,
  kSideLeft,
  kSideRight,
  kUpperArmLeft,
  kUpperArmRight,
};

/// The parameter-independent part: face arrays, and feature curves/points
/// as node index lists. Build once per resolution, reuse for many bodies.
struct MannequinTopology : PolygonSoup {  // the faces; positions unused (mannequin_positions)
  MannequinResolution res;
  std::uint32_t num_nodes = 0;
  struct Curve {
    std::int32_t id;
    std::string name;
    bool closed;
    std::vector<std::uint32_t> nodes;
  };
  std::vector<Curve> curves;
  struct Point {
    std::int32_t id;
    std::string name;
    std::uint32_t node;
    std::int32_t c1, c2;
  };
  std::vector<Point> points;
  // Internal ring tables used by the position generator.
  std::uint32_t torso_rings = 0, leg_rings = 0, arm_rings = 0;
  std::vector<std::uint32_t> key_torso, key_leg, key_arm;  // ring index of each key level
  std::vector<std::int32_t> torso_node;                     // (ring * N + j) -> node or -1 (arm holes)
  std::uint32_t left_leg_base = 0, right_leg_base = 0, bridge_base = 0;
  std::uint32_t left_arm_base = 0, right_arm_base = 0, arm_around = 0;
  std::vector<std::uint32_t> left_loop, right_loop;  // armhole loops (torso nodes)
  std::uint32_t neck_apex = 0, left_foot_apex = 0, right_foot_apex = 0, left_hand_apex = 0, right_hand_apex = 0;
};

[[nodiscard]] Expected<MannequinTopology> make_mannequin_topology(const MannequinResolution& res = {});

/// Node positions for `p` on topology `t` (no Model is built: this is the
/// fast path for body sets). Fails on invalid parameters.
[[nodiscard]] Expected<std::vector<Vec3d>> mannequin_positions(const MannequinParams& p, const MannequinTopology& t);

/// A complete reference body: skin surface plus feature curves and points.
[[nodiscard]] Expected<ReferenceBody> make_mannequin(const MannequinParams& p, const MannequinTopology& t);
[[nodiscard]] Expected<ReferenceBody> make_mannequin(const MannequinParams& p = {},
                                                     const MannequinResolution& res = {});

/// Builds many bodies (parallel over bodies through ctx; the result does not
/// depend on the thread count). Fails with the first invalid parameter set.
[[nodiscard]] Expected<std::vector<ReferenceBody>> make_mannequins(std::span<const MannequinParams> params,
                                                                   const MannequinTopology& t,
                                                                   const ExecContext& ctx = {});

/// n plausible adult bodies drawn deterministically from `seed` with a
/// portable generator (xoshiro256** seeded by splitmix64, Marsaglia polar
/// normals): both sexes; height drives lengths, a latent size factor drives
/// girths; every result passes validate_params.
[[nodiscard]] std::vector<MannequinParams> sample_mannequins(std::size_t n, std::uint64_t seed);
/// Body `index` of sample_mannequins(n, seed) for any n > index, drawn on
/// its own (O(1), no draws of the bodies before it).
[[nodiscard]] MannequinParams sample_mannequin(std::uint64_t seed, std::size_t index);
/// The sex drawn for body `index` of sample_mannequins (its stream's first
/// draw), which MannequinParams does not keep: true for female.
[[nodiscard]] bool sample_mannequin_female(std::uint64_t seed, std::size_t index);

/// Girth the mannequin was asked for on a closed feature curve (NaN when the
/// curve has no requested girth, e.g. armholes).
[[nodiscard]] double requested_girth(const MannequinParams& p, std::int32_t curve_id) noexcept;

}  // namespace atelier
