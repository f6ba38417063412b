// Hand-built test models shared by the test suites. Every fixture passes
// validate(); positions are simple so expectations can be computed by hand.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <atelier/storage/model.h>

namespace atelier::fixtures {

/// One triangle (0,0,0) (1,0,0) (0,1,0) in surface "triangle".
[[nodiscard]] Model single_triangle();

/// n quads in a row: bottom nodes (i,0,0), top nodes (i,1,0); quad i is
/// (b_i, b_{i+1}, t_{i+1}, t_i).
[[nodiscard]] Model quad_strip(int n);

/// Closed tetrahedron (4 nodes, 6 edges, 4 faces, one closed shell).
[[nodiscard]] Model tetrahedron();
/// Closed octahedron (6 nodes, 12 edges, 8 faces, one closed shell).
[[nodiscard]] Model octahedron();

struct Grid {
  Model model;
  Surface surface;
  MeshLoop loop;                  // the boundary, counter-clockwise seen from +z
  std::vector<MeshEdge> sides;    // bottom, right, top, left (each a chain along the loop)
  int n = 0, m = 0;               // cells along x and y
  /// Node at grid point (i, j), position (i, j, 0).
  [[nodiscard]] NodeIdx node(int i, int j) const { return NodeIdx{static_cast<std::uint32_t>(j * (n + 1) + i)}; }
};
/// n x m cells in the z=0 plane, each cut into two triangles by the diagonal
/// (i,j)-(i+1,j+1); boundary MESHLOOP of four mesh edges.
[[nodiscard]] Grid grid_patch(int n, int m);

struct JointFixture {
  Model model;
  Joint joint;
  std::vector<Surface> surfaces;  // one per member, in joint order
  std::vector<MeshEdge> members;  // in joint order (clockwise about +x)
  std::vector<bool> positive;     // direction flags, in joint order
  int segments = 0;               // edges per member
};

/// K surfaces, each a strip of 2 x L cells (triangles) leaving the common
/// polyline (i,0,0), i = 0..L, at angle 2*pi*k/K about the +x axis. Each has
/// its own nodes along the polyline and a boundary mesh edge there (odd k
/// are wound the other way, so their mesh edge runs against +x: negative
/// flag). One MESHJOINT joins them, clockwise by the right-hand rule about
/// the joint direction +x.
[[nodiscard]] JointFixture fan(int k, int segments);

/// Seed 000 Fig. 17 II: a sheet in the z=0 plane (y in [-1,1]) whose INNER
/// edge chain along y=0 is joined with the boundary mesh edges of a fin
/// rising to z=+1 and a fin hanging to z=-1. Members clockwise about +x:
/// lower fin, sheet, upper fin.
[[nodiscard]] JointFixture inner_edge_joint(int segments);

struct Incomplete {
  Model model;
  Surface surface;
  Face triangle;              // stand-alone triangle
  Face quad;                  // stand-alone quad (another component)
  Node ring;                  // ring node inside the triangle
  std::vector<Node> isolated; // isolated vertices
  std::vector<Edge> wires;    // wire edges (a dangling edge on the triangle and a free polyline)
};
/// Incomplete topology (seed 000 section 2): stand-alone faces, wire edges,
/// isolated vertices and a ring node, built with the Euler operators.
[[nodiscard]] Incomplete incomplete();

}  // namespace atelier::fixtures
