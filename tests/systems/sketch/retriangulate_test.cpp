#include <atelier/systems/sketch/retriangulate.h>

#include <gtest/gtest.h>

#include <atelier/storage/validate.h>
#include <atelier/systems/sketch/paint.h>
#include "systems/sketch/sketch_fixtures.h"

using namespace atelier;
using namespace atelier::sketch_test;

namespace {
double area(const Model& m) {
  double a = 0;
  std::vector<NodeIdx> c;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
    if (!m.alive(FaceIdx{f})) continue;
    m.face_nodes(FaceIdx{f}, c);
    for (std::size_t k = 1; k + 1 < c.size(); ++k)
      a += 0.5 * (m.position(c[k]) - m.position(c[0])).cross(m.position(c[k + 1]) - m.position(c[0])).norm();
  }
  return a;
}
}  // namespace

TEST(Retriangulate, Smoke) {
  Model m = icosphere(3);
  const Camera cam = front_ortho();
  auto p1 = paint_stroke(m, cam, project(cam, {Vec3d(-1.4, 0.1, 0), Vec3d(1.4, 0.1, 0)}), {.through = true});
  ASSERT_TRUE(p1) << p1.status().to_string();
  auto p2 = paint_stroke(m, cam, project(cam, {Vec3d(0.1, -1.4, 0), Vec3d(0.2, 1.4, 0)}), {.through = true});
  ASSERT_TRUE(p2) << p2.status().to_string();
  std::vector<AttribEdge> curves;
  for (auto* p : {&*p1, &*p2})
    for (auto& c : p->curves) curves.insert(curves.end(), c.edges.begin(), c.edges.end());
  const Model before = m;
  const double a0 = area(m);
  auto r = retriangulate_curves(m, curves);
  ASSERT_TRUE(r) << r.status().to_string();
  EXPECT_TRUE(validate(m)) << validate(m).to_string();
  std::printf("crossings %zu nodes +%zu faces -%zu +%zu split %zu, area %.15f -> %.15f\n", r->crossings,
              r->nodes_added, r->faces_removed, r->faces_added, r->edges_split, a0, area(m));
  for (auto& ch : r->chains)
    for (auto h : ch) EXPECT_TRUE(h.valid());
}
