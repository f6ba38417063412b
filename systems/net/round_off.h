// Rounding-off (seed 004 section 6): after a Boolean or a join, the vertices
// of the truncated (or connecting) meshes are freed and moved to minimise
// the weighted energy of moments built on the umbrella (Kobbelt 1995)
//   Delta p      = p - (1/n) sum_i q_i                  (curvature, ||Delta p||)
//   Torsion(p)^2 = (1/n) sum_i ||Delta p - Delta q_i||^2  (the 3rd moment for k = 1,
//                                                         taken in this quadratic form)
//   E = sum_p mu ||Delta p||^2 + nu Torsion(p)^2,
// over the vertices p whose terms involve a freed vertex (the others are
// constants). E is a convex quadratic in the freed positions, separable in
// x, y, z with one matrix: its minimiser solves (M^T M) x = -M^T c by sparse
// Cholesky. The result is kept only if E does not rise (it cannot, up to
// rounding; the check makes "never raises E" hold in floating point too).
//
// Freed vertices: the seam (the intersection polygons) and every vertex
// within RoundOptions::rings edges of it. All other positions stay
// bit-identical.
//
// Reads: the model's connectivity and positions. Writes: nodes.position of
// freed nodes, geometry_version. On error nothing changes.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/status.h>
#include <atelier/storage/model.h>

#include <cstddef>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

namespace atelier {

struct RoundOptions {
  double mu = 1.0;  // weight of curvature (2nd moment)
  double nu = 1.0;  // weight of torsion (3rd moment)
  int rings = 1;    // vertices within this many edges of the seam are freed
};

struct RoundReport {
  double energy_before = 0.0, energy_after = 0.0;
  std::size_t free_nodes = 0;
  std::size_t terms = 0;  // vertices p summed in E
  bool moved = false;     // false when the minimiser would not lower E
};

/// Rounds off the seam (node indices) of model m (see above). Errors:
/// a dead or out-of-range seam node, negative or non-finite weights, a
/// free region touching no fixed vertex (the minimiser is not unique).
[[nodiscard]] Expected<RoundReport> round_off(Model& m, std::span<const NodeIdx> seam, const RoundOptions& opt = {},
                                              const ExecContext& ctx = {});

/// E of the given free set (same terms as round_off), for checks.
[[nodiscard]] Expected<double> umbrella_energy(const Model& m, std::span<const std::uint8_t> free_mask,
                                               const RoundOptions& opt = {});

/// Reads a seam file: node indices (0-based, decimal) separated by blanks
/// or newlines; '#' starts a comment line. Error(kParse) naming file and line.
[[nodiscard]] std::vector<std::uint32_t> parse_seam(std::string_view text, std::string_view display_name);
[[nodiscard]] std::vector<std::uint32_t> read_seam(const std::filesystem::path& path);

}  // namespace atelier
