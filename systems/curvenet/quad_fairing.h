// Fairing of a quad control mesh (seed 003 section 6.2, eqs. 4-7, after
// Schaefer, Warren & Zorin 2004): the free vertices minimise
//
//   E(p) = sum_i |sum_j alpha^i_j p_j|^2 + |sum_j beta^i_j p_j|^2 + |sum_j gamma^i_j p_j|^2   (4)
//
// over every vertex i with a closed one-ring N_i (p_i and its neighbours in
// rotation order, j = 0 .. k_i - 1), the fixed vertices held where they are.
// Eq. (5), valence k != 4: alpha_j = 2/k cos(4 pi j / k), beta_j = 2/k
// sin(4 pi j / k), gamma_j = 1/k; eq. (6), k = 4: alpha_j = 1/4 cos(pi j),
// beta_j = 1/4 sin(pi j); eq. (7): alpha_i = beta_i = 0, gamma_i = -1.
//
// Two departures (FairingEquations::kFixed, the default; kPrinted is the
// paper as printed, kept for the tests that show why):
//  - eq. (5) at k = 3: the frequency 4 pi j / k aliases to 2 pi j / 3 (4/3
//    = 1 + 1/3), the ring's first harmonic, which is its spread in the
//    tangent plane; the printed alpha/beta terms penalise a regular ring and
//    pull the neighbours of a valence-3 vertex together. A 3-ring has no
//    second harmonic, so Atelier drops alpha and beta at k = 3 (and k < 3);
//  - eq. (6) omits gamma: alpha alone at k = 4 (p0 - p1 + p2 - p3) is a
//    discrete wave operator whose null space on a grid with fixed boundary
//    is not empty (sin(pi x) sin(pi y) modes), so the energy cannot pull a
//    perturbed grid back. Atelier uses gamma_j = 1/4, gamma_i = -1 at k = 4
//    as at every other valence (the umbrella term).
// E is quadratic in the free positions and separable in x, y, z: one
// sparse symmetric positive (semi)definite system A x = b, factorised once
// (Eigen SimplicialLDLT) and solved for the three coordinates.
//
// Reads: positions, the faces (their rings), the fixed flags. Writes: the
// free entries of `positions`.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>

namespace atelier {

enum class FairingEquations : std::uint8_t { kFixed, kPrinted };

struct QuadFairingOptions {
  FairingEquations equations = FairingEquations::kFixed;
};

struct QuadFairingReport {
  double energy_before = 0, energy_after = 0;
  std::size_t free_vertices = 0;
  std::size_t terms = 0;  // vertices with a closed ring contributing to E
  double max_move = 0;
};

/// The coefficients of eqs. (5)-(7) for a vertex of valence k: alpha, beta,
/// gamma over the k neighbours in rotation order, and gamma at the vertex
/// itself (alpha and beta are 0 there).
struct RingWeights {
  std::vector<double> alpha, beta, gamma;
  double gamma_self = -1.0;
};
[[nodiscard]] RingWeights fairing_weights(std::size_t k, FairingEquations equations);

/// E(p) of eq. (4) for the given positions (fixed flags do not matter).
/// Errors: those of the mesh (build_corner_mesh), wrong position count.
[[nodiscard]] Expected<double> fairing_energy(std::span<const Vec3d> positions, const PolygonSoupView& faces,
                                              const QuadFairingOptions& opt = {});

/// Minimises E over the vertices not flagged in `fixed` (one flag per
/// vertex). Errors: wrong sizes, a bad mesh, a free vertex with no fixed
/// vertex in its connected part (the system is singular: kInvalidArgument),
/// a factorisation or solve failure, a non-finite result (kDegenerate);
/// positions are unchanged on error. Fixed vertices are never written.
[[nodiscard]] Expected<QuadFairingReport> fair_quad_mesh(std::span<Vec3d> positions, const PolygonSoupView& faces,
                                                         std::span<const std::uint8_t> fixed,
                                                         const QuadFairingOptions& opt = {},
                                                         const ExecContext& ctx = {});

}  // namespace atelier
