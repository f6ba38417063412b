// Catmull-Clark subdivision with infinitely sharp creases (seed 003 step 5;
// Catmull & Clark 1978, crease rules of Hoppe et al. 1994 / DeRose et al.
// 1998), over flat arrays: every level is a CornerMesh, the next level's
// topology is index arithmetic on the previous one (no hashing, no search),
// and every loop is a gather through engine/parallel.h, so the output is
// bit-identical for any thread count.
//
// Rules, for a face f with n corners, an edge (a, b), a vertex v:
//   face point   the average of f's corners;
//   edge point   smooth: (a + b + f0 + f1) / 4; crease or boundary: (a + b) / 2;
//   vertex point with s incident crease/boundary edges:
//     s < 2 (smooth, darts)   (n - 2)/n v + 1/n^2 sum(neighbours) + 1/n^2 sum(face points);
//     s = 2 (crease)          (a + 6 v + b) / 8, a and b its crease neighbours;
//     s > 2 or a corner       v (also non-manifold vertices).
// Boundary edges are creases (OpenSubdiv's VTX_BOUNDARY_EDGE_ONLY); a
// corner is any vertex the caller lists (the curve network's nodes).
// Children of level l: vertex points [0, V), edge points [V, V + E), face
// points [V + E, V + E + F); the quad of corner c (face f, corner k) is
// child face c: (v_k, e_k, f, e_{k-1}). So V' = V + E + F, E' = 2 E + sum
// n_f, F' = sum n_f. A crease edge's two halves are creases; edge points
// and face points are never corners.
//
// Limit positions on creases: (a + 4 v + b) / 6 (crease), v (corner): the
// crease curve is the uniform cubic B-spline of its polygon with end points
// interpolated (phantom points 2 P_0 - P_1), see crease_limit_positions.
//
// Reads: caller's arrays. Writes: nothing outside the returned objects.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status.h>
#include <atelier/storage/polygon_soup.h>
#include <atelier/systems/curvenet/corner_mesh.h>

namespace atelier {

struct CatmullClarkOptions {
  int levels = 2;
  /// Keep the edges and vertex incidence of the last level (needed only to
  /// refine it again or to walk it; the faces are always kept).
  bool full_topology_in_last_level = false;
};

/// Topology of every level (like OpenSubdiv's TopologyRefiner): made once,
/// then used to interpolate any number of position arrays.
class CatmullClarkRefiner {
 public:
  /// `control`: the faces (positions ignored) over `vertex_count` vertices;
  /// `creases`: vertex pairs that must be edges of the mesh (infinitely
  /// sharp); `corners`: vertices that stay where they are. Errors: those of
  /// build_corner_mesh, a crease that is not an edge, a corner index out of
  /// range, levels outside [0, 8].
  [[nodiscard]] static Expected<CatmullClarkRefiner> create(const PolygonSoupView& control, std::size_t vertex_count,
                                                            std::span<const std::array<std::uint32_t, 2>> creases,
                                                            std::span<const std::uint32_t> corners,
                                                            const CatmullClarkOptions& opt = {},
                                                            const ExecContext& ctx = {});

  [[nodiscard]] int levels() const noexcept { return static_cast<int>(levels_.size()) - 1; }
  /// Level l's mesh (level 0 is the control mesh). The last level has only
  /// faces unless full_topology_in_last_level was set.
  [[nodiscard]] const CornerMesh& level(int l) const noexcept { return levels_[static_cast<std::size_t>(l)]; }
  /// Crease flags of level l's edges (boundary edges included), l < levels()
  /// or with full topology.
  [[nodiscard]] std::span<const std::uint8_t> sharp_edges(int l) const noexcept {
    return sharp_[static_cast<std::size_t>(l)];
  }
  /// Corner flags of level l's vertices.
  [[nodiscard]] std::span<const std::uint8_t> corner_vertices(int l) const noexcept {
    return corner_[static_cast<std::size_t>(l)];
  }
  /// The crease edges of the last level as vertex pairs (halves of the
  /// crease edges of the level before, in order).
  [[nodiscard]] std::vector<std::array<std::uint32_t, 2>> last_level_creases() const;
  /// Vertex count of level l.
  [[nodiscard]] std::size_t vertex_count(int l) const noexcept {
    return levels_[static_cast<std::size_t>(l)].vertex_count;
  }

  /// Positions of the last level from the control positions (one per
  /// control vertex). Errors: wrong count, kCancelled.
  [[nodiscard]] Status refine(std::span<const Vec3d> control, std::vector<Vec3d>& out,
                              const ExecContext& ctx = {}) const;
  /// One level: positions of level l + 1 from positions of level l.
  [[nodiscard]] Status refine_level(int l, std::span<const Vec3d> in, std::span<Vec3d> out,
                                    const ExecContext& ctx = {}) const;
  /// Vertices of all levels together (the size of refine_all's buffer).
  [[nodiscard]] std::size_t total_vertex_count() const noexcept;
  /// Every level in one caller buffer (OpenSubdiv's PrimvarRefiner layout):
  /// `all` starts with the control positions, level l + 1 follows level l.
  /// No allocation, so repeated calls reuse warm memory.
  [[nodiscard]] Status refine_all(std::span<Vec3d> all, const ExecContext& ctx = {}) const;

 private:
  std::vector<CornerMesh> levels_;
  std::vector<std::vector<std::uint8_t>> sharp_;                      // per level, per edge
  std::vector<std::vector<std::uint8_t>> corner_;                     // per level, per vertex
  std::vector<std::vector<std::array<std::uint32_t, 2>>> creases_;    // per level
  std::vector<std::vector<std::uint8_t>> rules_;                      // per level but the last, per vertex
  std::vector<std::vector<std::array<std::uint32_t, 2>>> crease_nb_;  // crease neighbours of crease vertices
};

struct SubdividedMesh {
  PolygonSoup mesh;                                   // positions and quads of the last level
  std::vector<std::array<std::uint32_t, 2>> creases;  // crease edges of the last level
  std::vector<std::uint8_t> corners;                  // per vertex of the last level
};

/// One call: create + refine (PMP style entry point).
[[nodiscard]] Expected<SubdividedMesh> subdivide_catmull_clark(const PolygonSoupView& control,
                                                               std::span<const std::array<std::uint32_t, 2>> creases,
                                                               std::span<const std::uint32_t> corners,
                                                               const CatmullClarkOptions& opt = {},
                                                               const ExecContext& ctx = {});

/// Limit positions of the vertices on crease edges (crease rule (a + 4v +
/// b) / 6, corners unchanged); other vertices get NaN. `creases` are the
/// mesh's crease edges, `corners` its corner flags (one per vertex).
[[nodiscard]] std::vector<Vec3d> crease_limit_positions(std::span<const Vec3d> positions,
                                                        std::span<const std::array<std::uint32_t, 2>> creases,
                                                        std::span<const std::uint8_t> corners);

}  // namespace atelier
