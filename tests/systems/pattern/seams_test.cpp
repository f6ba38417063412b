// Seams that make closed tubes flattenable (issue 22): a cylinder opened
// along one generator (a given seam path, or the automatic seam) or
// partitioned by sketch partition curves flattens to its r*theta x h
// rectangles exactly; the seam's two sides are one sewable joint; joints of
// the input are carried over; edges marked as seams (kEdgeSeam, a
// template's seam marks) are cut, splitting a surface into pieces where
// they separate it; closed pieces and bad paths get clear errors.
#include <atelier/storage/builder.h>
#include <atelier/storage/edge_flags.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/pattern/flatten.h>
#include <atelier/systems/pattern/pattern.h>
#include <atelier/systems/pattern/seams.h>
#include <atelier/systems/sketch/cut.h>
#include <atelier/systems/sketch/paint.h>
#include <atelier/systems/view/camera.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "tests/support/flatten_shapes.h"

namespace atelier {
namespace {

/// A closed cylinder tube of quads about +y: node (i, j) = i + nu j at
/// (r sin a, h j / nv, r cos a), a = 2 pi i / nu, faces front outside.
struct Tube {
  Model model;
  int nu = 0, nv = 0;
  double r = 0, h = 0;
  [[nodiscard]] NodeIdx node(int i, int j) const { return NodeIdx{static_cast<std::uint32_t>((i % nu) + nu * j)}; }
  /// Chord of one column: the tube's girth is nu of them (r theta in the limit).
  [[nodiscard]] double chord() const { return 2 * r * std::sin(M_PI / nu); }
};

Tube tube(double r, double h, int nu, int nv) {
  Tube t;
  t.nu = nu, t.nv = nv, t.r = r, t.h = h;
  PolygonSoup s;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double a = 2 * M_PI * i / nu;
      s.positions.emplace_back(r * std::sin(a), h * j / nv, r * std::cos(a));
    }
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const std::uint32_t q[4] = {t.node(i, j).value, t.node(i + 1, j).value, t.node(i + 1, j + 1).value,
                                  t.node(i, j + 1).value};
      s.add_face(q);
    }
  auto made = add_polygon_surface(t.model, "sleeve", s);
  if (!made) throw Error(made.status());
  return t;
}

Eigen::AlignedBox2d uv_box(const Model& m, SurfaceIdx s) {
  Eigen::AlignedBox2d b;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}) && m.nodes.surface[v] == s) b.extend(m.nodes.uv[v]);
  return b;
}

void expect_exact_piece(const PieceFlattening& p) {
  EXPECT_LT(p.distortion.length_error, 1e-8);
  EXPECT_LT(p.distortion.area_error, 1e-8);
  EXPECT_EQ(p.distortion.flipped, 0u);
  EXPECT_EQ(p.distortion.boundary_crossings, 0u);
}

TEST(Seams, TubeOpenedAlongAGeneratorFlattensToItsRectangle) {
  Tube t = tube(0.1, 0.45, 24, 6);
  ASSERT_TRUE(validate(t.model));
  // Without a seam the tube is refused (two loops).
  EXPECT_EQ(flatten_surfaces(t.model).status().code(), ErrorCode::kTopology);
  SeamOptions so;
  so.automatic = false;
  std::vector<NodeIdx> generator;
  for (int j = 0; j <= t.nv; ++j) generator.push_back(t.node(5, j));
  so.paths = {generator};
  auto o = open_seams(t.model, so);
  ASSERT_TRUE(o) << o.status().to_string();
  ASSERT_TRUE(validate(o->model)) << validate(o->model).to_string();
  // One copy more per generator node; the input is untouched.
  EXPECT_EQ(o->model.num_nodes(), t.model.num_nodes() + t.nv + 1);
  EXPECT_EQ(o->model.num_faces(), t.model.num_faces());
  for (std::uint32_t v = 0; v < o->model.nodes.slots.capacity(); ++v)
    EXPECT_EQ(o->model.position(NodeIdx{v}), t.model.position(o->source_node[v]));
  auto flat = flatten_surfaces(o->model);
  ASSERT_TRUE(flat) << flat.status().to_string();
  ASSERT_EQ(flat->pieces.size(), 1u);
  expect_exact_piece(flat->pieces[0]);
  // The rectangle nu * chord x h (in either orientation: the grain is the
  // principal axis), area likewise.
  const Eigen::AlignedBox2d b = uv_box(o->model, flat->pieces[0].surface);
  const double W = t.nu * t.chord();
  const Vec2d ext = b.sizes();
  EXPECT_NEAR(std::max(ext.x(), ext.y()), std::max(W, t.h), 1e-9);
  EXPECT_NEAR(std::min(ext.x(), ext.y()), std::min(W, t.h), 1e-9);
  // The seam: one joint, its two sides h long in 3D and on the pattern.
  ASSERT_EQ(o->seam_joints.size(), 1u);
  const std::vector<SurfaceIdx> pieces{flat->pieces[0].surface};
  auto set = make_pattern(o->model, pieces);
  ASSERT_TRUE(set) << set.status().to_string();
  ASSERT_EQ(set->seams.size(), 1u);
  EXPECT_EQ(set->seams[0].joint, o->seam_joints[0]);
  ASSERT_EQ(set->seams[0].members.size(), 2u);
  for (const SeamMemberLength& ml : set->seams[0].members) {
    EXPECT_NEAR(ml.length_3d_mm, 1000 * t.h, 1e-9);
    EXPECT_NEAR(ml.length_2d_mm, 1000 * t.h, 1e-6);
  }
  EXPECT_TRUE(set->seams[0].ok);
}

/// Marks the edges of a node chain of `m` as a seam (kEdgeSeam), as a
/// template's seam mark arrives on a regenerated garment.
void mark(Model& m, const std::vector<NodeIdx>& chain) {
  for (std::size_t i = 0; i + 1 < chain.size(); ++i) {
    const HalfedgeIdx h = m.find_halfedge(chain[i], chain[i + 1]);
    ASSERT_TRUE(h.valid());
    m.edges.flags[edge_of(h).value] |= kEdgeSeam;
  }
}

TEST(Seams, MarkedGeneratorOpensATubeThatFailsToFlattenWithoutIt) {
  Tube t = tube(0.1, 0.45, 24, 6);
  SeamOptions none;
  none.automatic = false;  // only what is marked
  // Unmarked: nothing is cut, and the tube (two loops) does not flatten.
  auto plain = open_seams(t.model, none);
  ASSERT_TRUE(plain) << plain.status().to_string();
  EXPECT_TRUE(plain->paths.empty());
  EXPECT_EQ(flatten_surfaces(plain->model).status().code(), ErrorCode::kTopology);
  // Marked along generator 7 (the flags a template's seam mark leaves on
  // every refined edge): cut there, and the tube flattens to its rectangle.
  std::vector<NodeIdx> generator;
  for (int j = 0; j <= t.nv; ++j) generator.push_back(t.node(7, j));
  mark(t.model, generator);
  ASSERT_TRUE(validate(t.model));
  auto o = open_seams(t.model, none);
  ASSERT_TRUE(o) << o.status().to_string();
  ASSERT_TRUE(validate(o->model)) << validate(o->model).to_string();
  ASSERT_EQ(o->paths.size(), 1u);
  EXPECT_EQ(o->paths[0], generator);
  EXPECT_EQ(o->model.num_surfaces(), 1u);  // one cut does not separate the tube
  auto flat = flatten_surfaces(o->model);
  ASSERT_TRUE(flat) << flat.status().to_string();
  ASSERT_EQ(flat->pieces.size(), 1u);
  expect_exact_piece(flat->pieces[0]);
  // The seam's two sides: each as long on the pattern as the tube is high.
  const std::vector<SurfaceIdx> pieces{flat->pieces[0].surface};
  auto set = make_pattern(o->model, pieces);
  ASSERT_TRUE(set) << set.status().to_string();
  ASSERT_EQ(set->seams.size(), 1u);
  ASSERT_EQ(set->seams[0].members.size(), 2u);
  for (const SeamMemberLength& ml : set->seams[0].members) {
    EXPECT_TRUE(ml.boundary);
    EXPECT_NEAR(ml.length_3d_mm, 1000 * t.h, 1e-9);
    EXPECT_NEAR(ml.length_2d_mm, 1000 * t.h, 1e-6);
  }
  EXPECT_TRUE(set->seams[0].ok);
  // Marks off (SeamOptions::marked): the mark is ignored again.
  none.marked = false;
  auto ignored = open_seams(t.model, none);
  ASSERT_TRUE(ignored);
  EXPECT_EQ(flatten_surfaces(ignored->model).status().code(), ErrorCode::kTopology);
}

TEST(Seams, MarksThatSeparateASurfaceMakePiecesAndAMarkAlongAnInnerJointSewsOntoBoth) {
  // A sleeve with a band sewn on its middle ring (an inner-edge joint, as
  // the top's collar on its yoke line), marked along two opposite
  // generators and along that ring: four pieces, the band sewn onto the
  // boundaries of the pieces above and below the ring (three members).
  Tube t = tube(0.1, 0.4, 16, 4);
  const int nu = t.nu, ring = 2;
  PolygonSoup band;
  const std::uint32_t base = t.model.nodes.slots.capacity();
  for (int j = 0; j <= 1; ++j)
    for (int i = 0; i < nu; ++i) {
      const double a = 2 * M_PI * i / nu, r = t.r * (1 + 0.3 * j);
      band.positions.emplace_back(r * std::sin(a), t.h * ring / t.nv + 0.05 * j, r * std::cos(a));
    }
  for (int i = 0; i < nu; ++i) {
    const std::uint32_t q[4] = {static_cast<std::uint32_t>(i), static_cast<std::uint32_t>((i + 1) % nu),
                                static_cast<std::uint32_t>(nu + (i + 1) % nu), static_cast<std::uint32_t>(nu + i)};
    band.add_face(q);
  }
  auto b = add_polygon_surface(t.model, "band", band);
  ASSERT_TRUE(b) << b.status().to_string();
  std::vector<HalfedgeIdx> on_sleeve, on_band;
  for (int i = 0; i < nu; ++i) {
    on_sleeve.push_back(t.model.find_halfedge(t.node(i, ring), t.node(i + 1, ring)));
    on_band.push_back(t.model.find_halfedge(NodeIdx{base + i}, NodeIdx{base + (i + 1) % nu}));
  }
  const JointMember jm[2] = {{t.model.new_mesh_edge(SurfaceIdx{0}, on_sleeve), true},
                             {t.model.new_mesh_edge(b->idx, on_band), true}};
  (void)t.model.new_joint(jm);
  ASSERT_TRUE(validate(t.model)) << validate(t.model).to_string();
  for (int i : {0, nu / 2}) {
    std::vector<NodeIdx> g;
    for (int j = 0; j <= t.nv; ++j) g.push_back(t.node(i, j));
    mark(t.model, g);
  }
  std::vector<NodeIdx> loop;
  for (int i = 0; i <= nu; ++i) loop.push_back(t.node(i, ring));
  mark(t.model, loop);
  auto o = open_seams(t.model);  // the band, a tube, gets an automatic seam
  ASSERT_TRUE(o) << o.status().to_string();
  ASSERT_TRUE(validate(o->model)) << validate(o->model).to_string();
  // The sleeve's pieces: "sleeve" (below the ring, front), then in the
  // order of their first faces; the band.
  std::vector<std::string> names;
  for (std::uint32_t s = 0; s < o->model.surfaces.slots.capacity(); ++s)
    if (o->model.alive(SurfaceIdx{s})) names.push_back(o->model.surfaces.name[s]);
  EXPECT_EQ(names, (std::vector<std::string>{"sleeve", "sleeve.1", "sleeve.2", "sleeve.3", "band"}));
  for (std::uint32_t s = 0; s < o->part_of.size(); ++s)
    EXPECT_EQ(o->part_of[s].value, o->model.surfaces.name[s] == "band" ? 1u : 0u);
  EXPECT_EQ(o->marked_along_joints, 2u);  // the ring, cut at the two generators
  FlattenOptions fo;
  fo.boundary_stiffness = 300;
  auto flat = flatten_surfaces(o->model, fo);
  ASSERT_TRUE(flat) << flat.status().to_string();
  std::vector<SurfaceIdx> pieces;
  for (const PieceFlattening& p : flat->pieces) {
    EXPECT_EQ(p.distortion.flipped, 0u) << p.name;
    pieces.push_back(p.surface);
  }
  ASSERT_EQ(pieces.size(), 5u);
  auto set = make_pattern(o->model, pieces);
  ASSERT_TRUE(set) << set.status().to_string();
  // Along the ring: joints of three members (band, piece above, piece
  // below), all boundaries, each as long as the ring's arc in 3D.
  const double half_ring_mm = 1000 * (nu / 2) * t.chord();
  double ring_members_mm = 0;
  std::size_t three = 0;
  for (const SeamCheck& c : set->seams) {
    EXPECT_TRUE(c.ok) << "joint " << c.joint.value << ": " << c.max_difference_mm << " mm";
    for (const SeamMemberLength& ml : c.members) EXPECT_TRUE(ml.boundary);
    if (c.members.size() != 3) continue;
    ++three;
    for (const SeamMemberLength& ml : c.members) {
      ring_members_mm += ml.length_3d_mm;
      EXPECT_NEAR(ml.length_2d_mm, ml.length_3d_mm, 1e-6);
    }
  }
  EXPECT_GE(three, 2u);
  EXPECT_NEAR(ring_members_mm, 3 * 2 * half_ring_mm, 1e-6);
}

TEST(Seams, AutomaticSeamOfATubeIsAGeneratorAndDependsOnTopologyOnly) {
  Tube t = tube(0.08, 0.3, 16, 5);
  auto o = open_seams(t.model);
  ASSERT_TRUE(o) << o.status().to_string();
  ASSERT_TRUE(validate(o->model)) << validate(o->model).to_string();
  ASSERT_EQ(o->paths.size(), 1u);
  // Fewest edges from ring 0 to ring nv: nv edges, straight up one column.
  ASSERT_EQ(o->paths[0].size(), static_cast<std::size_t>(t.nv + 1));
  for (std::size_t j = 1; j < o->paths[0].size(); ++j)
    EXPECT_EQ(o->paths[0][j].value % t.nu, o->paths[0][0].value % t.nu);
  auto flat = flatten_surfaces(o->model);
  ASSERT_TRUE(flat) << flat.status().to_string();
  expect_exact_piece(flat->pieces[0]);
  // The same tube bent (another body): the same seam.
  Tube bent = t;
  for (std::uint32_t v = 0; v < bent.model.nodes.slots.capacity(); ++v) {
    Vec3d& p = bent.model.nodes.position[v];
    p.x() += 0.3 * p.y() * p.y() + 0.01 * std::sin(7.0 * v);
  }
  auto o2 = open_seams(bent.model);
  ASSERT_TRUE(o2);
  EXPECT_EQ(o2->paths, o->paths);
}

TEST(Seams, PartitionCurvesAlongTwoGeneratorsGiveTwoRectangles) {
  // Sketch partition: a penetrating vertical stroke at x = x0 through the
  // tube paints a generator on its front and one on its back; partitioning
  // along them gives two pieces, each a rectangle as wide as the tube's
  // polygon between the two generators (x > x0 and x < x0) and h tall.
  Tube t = tube(0.5, 1.0, 20, 4);
  const double x0 = 0.5 * std::sin(M_PI / 20);  // half a column off the nodes
  const Camera cam = Camera::orthographic(Vec3d(0, 0.5, 5), Vec3d(0, 0.5, 0), Vec3d::UnitY(), 1.5, 800, 800);
  std::vector<Vec2d> stroke;
  for (double y : {-0.2, 0.5, 1.2}) stroke.push_back(cam.project(Vec3d(x0, y, 0)).head<2>());
  auto p = paint_stroke(t.model, cam, stroke, {.through = true});
  ASSERT_TRUE(p) << p.status().to_string();
  std::vector<AttribEdge> curves;
  for (const auto& c : p->curves) curves.insert(curves.end(), c.edges.begin(), c.edges.end());
  auto part = partition_along_curves(t.model, curves);
  ASSERT_TRUE(part) << part.status().to_string();
  ASSERT_TRUE(validate(t.model)) << validate(t.model).to_string();
  ASSERT_EQ(part->pieces.size(), 2u);
  // Independent expectation: the ring polygon's length on each side of x0.
  double right = 0, left = 0;
  for (int i = 0; i < t.nu; ++i) {
    const double a0 = 2 * M_PI * i / t.nu, a1 = 2 * M_PI * (i + 1) / t.nu;
    const Vec2d p0(t.r * std::sin(a0), t.r * std::cos(a0)), p1(t.r * std::sin(a1), t.r * std::cos(a1));
    const double s0 = p0.x() - x0, s1 = p1.x() - x0, len = (p1 - p0).norm();
    if (s0 >= 0 && s1 >= 0)
      right += len;
    else if (s0 <= 0 && s1 <= 0)
      left += len;
    else {
      const double f = s0 / (s0 - s1);  // the crossing, from p0
      (s0 > 0 ? right : left) += f * len;
      (s0 > 0 ? left : right) += (1 - f) * len;
    }
  }
  auto flat = flatten_surfaces(t.model);
  ASSERT_TRUE(flat) << flat.status().to_string();
  ASSERT_EQ(flat->pieces.size(), 2u);
  std::vector<double> widths;
  for (const PieceFlattening& pf : flat->pieces) {
    expect_exact_piece(pf);
    // A rectangle: the hem nodes (3D y = 0) on one line of the pattern, the
    // top nodes (y = h) on a parallel line h away, both as long.
    std::vector<Vec2d> hem, top;
    for (std::uint32_t v = 0; v < t.model.nodes.slots.capacity(); ++v) {
      if (!t.model.alive(NodeIdx{v}) || t.model.nodes.surface[v] != pf.surface) continue;
      if (t.model.nodes.position[v].y() == 0) hem.push_back(t.model.nodes.uv[v]);
      if (t.model.nodes.position[v].y() == t.h) top.push_back(t.model.nodes.uv[v]);
    }
    auto farthest = [](const std::vector<Vec2d>& p) {
      std::pair<Vec2d, Vec2d> best{p[0], p[0]};
      for (const Vec2d& a : p)
        for (const Vec2d& b : p)
          if ((a - b).norm() > (best.first - best.second).norm()) best = {a, b};
      return best;
    };
    ASSERT_GE(hem.size(), 2u);
    ASSERT_GE(top.size(), 2u);
    const auto [a, b] = farthest(hem);
    const Vec2d dir = (b - a).normalized(), normal(-dir.y(), dir.x());
    for (const Vec2d& q : hem) EXPECT_NEAR(normal.dot(q - a), 0, 1e-9);
    for (const Vec2d& q : top) EXPECT_NEAR(std::abs(normal.dot(q - a)), t.h, 1e-9);
    const auto [c, d] = farthest(top);
    EXPECT_NEAR((c - d).norm(), (b - a).norm(), 1e-9);
    widths.push_back((b - a).norm());
  }
  std::sort(widths.begin(), widths.end());
  EXPECT_NEAR(widths[0], std::min(left, right), 1e-9);
  EXPECT_NEAR(widths[1], std::max(left, right), 1e-9);
  // The partition's joints are the seams, sewable.
  std::vector<SurfaceIdx> pieces;
  for (const PieceFlattening& pf : flat->pieces) pieces.push_back(pf.surface);
  auto set = make_pattern(t.model, pieces);
  ASSERT_TRUE(set);
  EXPECT_EQ(set->seams.size(), 2u);
  EXPECT_EQ(set->failed_seams(), 0u);
}

TEST(Seams, JointsAreCarriedOverAndCutWhereASeamCrossesThem) {
  // Two tubes stacked (a bodice and a waistband) joined along their common
  // ring: opening both along generators keeps the ring joint, cut into two
  // runs where the two seams meet it at different columns.
  Tube a = tube(0.1, 0.2, 12, 3);
  PolygonSoup s;
  for (int j = 0; j <= 2; ++j)
    for (int i = 0; i < 12; ++i) {
      const double ang = 2 * M_PI * i / 12;
      s.positions.emplace_back(0.1 * std::sin(ang), 0.2 + 0.05 * j, 0.1 * std::cos(ang));
    }
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 12; ++i) {
      const std::uint32_t q[4] = {
          static_cast<std::uint32_t>(i + 12 * j), static_cast<std::uint32_t>((i + 1) % 12 + 12 * j),
          static_cast<std::uint32_t>((i + 1) % 12 + 12 * (j + 1)), static_cast<std::uint32_t>(i + 12 * (j + 1))};
      s.add_face(q);
    }
  Model& m = a.model;
  const std::uint32_t base = m.nodes.slots.capacity();
  auto band = add_polygon_surface(m, "band", s);
  ASSERT_TRUE(band);
  std::vector<NodeIdx> ring_a, ring_b;
  for (int i = 0; i <= 12; ++i) {
    ring_a.push_back(a.node(i, a.nv));
    ring_b.push_back(NodeIdx{base + static_cast<std::uint32_t>(i % 12)});
  }
  const JointIdx ring = flatten_shapes::join(m, ring_a, ring_b);
  ASSERT_TRUE(validate(m)) << validate(m).to_string();
  SeamOptions so;
  so.automatic = false;
  std::vector<NodeIdx> ga, gb;
  for (int j = 0; j <= a.nv; ++j) ga.push_back(a.node(0, j));
  for (int j = 0; j <= 2; ++j) gb.push_back(NodeIdx{base + 4 + 12 * static_cast<std::uint32_t>(j)});
  so.paths = {ga, gb};
  auto o = open_seams(m, so);
  ASSERT_TRUE(o) << o.status().to_string();
  ASSERT_TRUE(validate(o->model)) << validate(o->model).to_string();
  (void)ring;
  // Two seam joints plus the ring, cut at columns 0 and 4: 4 + 8 edges.
  ASSERT_EQ(o->model.num_joints(), 4u);
  std::vector<std::size_t> runs;
  for (std::uint32_t j = 0; j < o->model.joints.slots.capacity(); ++j) {
    if (!o->model.alive(JointIdx{j}) || j == o->seam_joints[0].value || j == o->seam_joints[1].value) continue;
    const auto mem = o->model.joints.members.row(j);
    ASSERT_EQ(mem.size(), 2u);
    runs.push_back(o->model.mesh_edges.halfedges.row(mem[0].mesh_edge.value).size());
    EXPECT_EQ(runs.back(), o->model.mesh_edges.halfedges.row(mem[1].mesh_edge.value).size());
  }
  std::sort(runs.begin(), runs.end());
  EXPECT_EQ(runs, (std::vector<std::size_t>{4, 8}));
  auto flat = flatten_surfaces(o->model);
  ASSERT_TRUE(flat) << flat.status().to_string();
  for (const PieceFlattening& pf : flat->pieces) expect_exact_piece(pf);
  std::vector<SurfaceIdx> pieces;
  for (const PieceFlattening& pf : flat->pieces) pieces.push_back(pf.surface);
  auto set = make_pattern(o->model, pieces);
  ASSERT_TRUE(set);
  EXPECT_EQ(set->seams.size(), 4u);
  EXPECT_EQ(set->failed_seams(), 0u);
}

TEST(SeamsErrors, ClosedSurfaceAndBadPathsAreNamed) {
  // A closed box: no boundary to start a seam from.
  PolygonSoup box;
  for (int k = 0; k < 8; ++k) box.positions.emplace_back(k & 1, (k >> 1) & 1, (k >> 2) & 1);
  const std::vector<std::array<std::uint32_t, 4>> quads = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) box.add_face(q);
  Model m;
  ASSERT_TRUE(add_polygon_surface(m, "box", box));
  auto o = open_seams(m);
  ASSERT_FALSE(o);
  EXPECT_EQ(o.status().code(), ErrorCode::kTopology);
  EXPECT_NE(o.status().message().find("'box' is closed"), std::string::npos);
  Tube t = tube(0.1, 0.2, 8, 2);
  SeamOptions so;
  so.paths = {{t.node(0, 0), t.node(3, 2)}};
  o = open_seams(t.model, so);
  ASSERT_FALSE(o);
  EXPECT_EQ(o.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(o.status().message().find("not joined by an edge"), std::string::npos);
  so.paths = {{t.node(0, 0), t.node(1, 0)}};  // along the boundary
  o = open_seams(t.model, so);
  ASSERT_FALSE(o);
  EXPECT_NE(o.status().message().find("not between two faces"), std::string::npos);
  so.paths = {{t.node(0, 0)}};
  EXPECT_EQ(open_seams(t.model, so).status().code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace atelier
