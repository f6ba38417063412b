// Tests of ReferenceBody on an analytic body (a latitude-longitude sphere):
// curves through vertex, edge and face nodes, the frame of seed 000 eq. (1)
// against the sphere's normal and tangents, curves following an affine
// deformation of the mesh, and the tape measure on known polygons.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <atelier/storage/builder.h>
#include <atelier/systems/body/measure.h>
#include <atelier/systems/body/reference_body.h>
#include <atelier/storage/validate.h>

namespace atelier {
namespace {

constexpr std::uint32_t kRings = 15, kAround = 24;

std::uint32_t node_id(std::uint32_t r, std::uint32_t j) { return r * kAround + j % kAround; }
double polar(std::uint32_t r) { return kPi * (r + 1) / (kRings + 1); }

// Unit sphere: kRings latitude rings of kAround nodes plus two poles.
ReferenceBody sphere() {
  std::vector<Vec3d> pos;
  for (std::uint32_t r = 0; r < kRings; ++r)
    for (std::uint32_t j = 0; j < kAround; ++j) {
      const double t = polar(r), p = 2 * kPi * j / kAround;
      pos.push_back({std::sin(t) * std::cos(p), std::cos(t), std::sin(t) * std::sin(p)});
    }
  const std::uint32_t north = static_cast<std::uint32_t>(pos.size()), south = north + 1;
  pos.push_back({0, 1, 0});
  pos.push_back({0, -1, 0});
  std::vector<std::uint32_t> off{0}, fn;
  auto face = [&](std::initializer_list<std::uint32_t> f) {
    fn.insert(fn.end(), f);
    off.push_back(static_cast<std::uint32_t>(fn.size()));
  };
  // Outward: from inside, rings go down (r+1) and around (j+1 turns from +x to +z).
  for (std::uint32_t r = 0; r + 1 < kRings; ++r)
    for (std::uint32_t j = 0; j < kAround; ++j) face({node_id(r, j), node_id(r, j + 1), node_id(r + 1, j + 1), node_id(r + 1, j)});
  for (std::uint32_t j = 0; j < kAround; ++j) face({north, node_id(0, j + 1), node_id(0, j)});
  for (std::uint32_t j = 0; j < kAround; ++j) face({south, node_id(kRings - 1, j), node_id(kRings - 1, j + 1)});
  ReferenceBody b;
  auto s = add_polygon_surface(b.model, "skin", {pos, off, fn});
  EXPECT_TRUE(s) << s.status().to_string();
  b.skin = s->idx;
  return b;
}

constexpr std::uint32_t kLatRing = 5;  // latitude curve between rings 5 and 6
constexpr double kU = 0.3;

void add_features(ReferenceBody& b) {
  const Model& m = b.model;
  std::vector<SurfaceLocation> lat, mer, faces;
  for (std::uint32_t j = 0; j < kAround; ++j) {
    const HalfedgeIdx h = m.find_halfedge(NodeIdx{node_id(kLatRing, j)}, NodeIdx{node_id(kLatRing + 1, j)});
    ASSERT_TRUE(h.valid());
    lat.push_back({AttribNodeKind::kEdge, h.value, Vec3d(kU, 0, 0), 0});
  }
  for (std::uint32_t r = 0; r < kRings; ++r) mer.push_back({AttribNodeKind::kVertex, node_id(r, 0), Vec3d::Zero(), 0});
  // A curve through the faces of row 9 (face index = row * kAround + j).
  for (std::uint32_t j = 0; j < kAround; ++j)
    faces.push_back({AttribNodeKind::kFace, 9 * kAround + j, Vec3d(0.2, 0.5, 0.3), 1});
  ASSERT_TRUE(add_feature_curve(b, 10, "latitude", lat, true));
  ASSERT_TRUE(add_feature_curve(b, 20, "meridian", mer, false));
  ASSERT_TRUE(add_feature_curve(b, 30, "through_faces", faces, true));
  const HalfedgeIdx h0 = m.find_halfedge(NodeIdx{node_id(kLatRing, 0)}, NodeIdx{node_id(kLatRing + 1, 0)});
  ASSERT_TRUE(add_feature_point(b, 1, "lat_x_mer", {AttribNodeKind::kEdge, h0.value, Vec3d(kU, 0, 0), 0}, 10, 20));
}

TEST(ReferenceBody, FeaturesAreValidAttributes) {
  ReferenceBody b = sphere();
  add_features(b);
  EXPECT_TRUE(validate(b.model)) << validate(b.model).to_string();
  EXPECT_TRUE(validate_features(b)) << validate_features(b).to_string();
  EXPECT_EQ(b.model.num_attrib_edges(), 3u);
  EXPECT_EQ(b.model.num_attrib_nodes(), 2 * kAround + kRings + 1);
  ASSERT_NE(b.find_curve("meridian"), nullptr);
  EXPECT_EQ(b.find_curve("meridian")->id, 20);
  EXPECT_EQ(b.model.attrib_edges.feature_id[b.find_curve(10)->edge.value], 10);
}

TEST(ReferenceBody, PolylinesComeFromElementParameters) {
  ReferenceBody b = sphere();
  add_features(b);
  auto lat = feature_curve_polyline(b, 10);
  ASSERT_TRUE(lat);
  ASSERT_EQ(lat->size(), kAround);
  // Points on the chords between rings 5 and 6: a horizontal circle.
  const double y = (1 - kU) * std::cos(polar(kLatRing)) + kU * std::cos(polar(kLatRing + 1));
  const double rad = (1 - kU) * std::sin(polar(kLatRing)) + kU * std::sin(polar(kLatRing + 1));
  for (std::uint32_t j = 0; j < kAround; ++j) {
    const double p = 2 * kPi * j / kAround;
    EXPECT_LT(((*lat)[j] - Vec3d(rad * std::cos(p), y, rad * std::sin(p))).norm(), 1e-12);
  }
  EXPECT_NEAR(polyline_length(*lat, true), 2 * kAround * rad * std::sin(kPi / kAround), 1e-12);
  EXPECT_NEAR(tape_girth(*lat), 2 * kAround * rad * std::sin(kPi / kAround), 1e-12);
  EXPECT_FALSE(feature_curve_polyline(b, 99));
}

TEST(ReferenceBody, FrameMatchesTheSphere) {
  ReferenceBody b = sphere();
  add_features(b);
  auto f = feature_frame(b, 1);
  ASSERT_TRUE(f) << f.status().to_string();
  // Origin on the meridian edge; the normal is the sphere's radial direction
  // there (up to the faceting), t1 along the latitude (+-z at phi = 0), t2
  // along the meridian.
  const double y = (1 - kU) * std::cos(polar(kLatRing)) + kU * std::cos(polar(kLatRing + 1));
  const double x = (1 - kU) * std::sin(polar(kLatRing)) + kU * std::sin(polar(kLatRing + 1));
  EXPECT_LT((f->origin - Vec3d(x, y, 0)).norm(), 1e-12);
  EXPECT_GT(f->n.dot(Vec3d(x, y, 0).normalized()), 0.99);
  EXPECT_NEAR(f->n.norm(), 1, 1e-12);
  EXPECT_GT(std::abs(f->t1.z()), 0.99);
  const Vec3d e_theta = Vec3d(y, -x, 0).normalized();
  EXPECT_GT(std::abs(f->t2.dot(e_theta)), 0.99);
  EXPECT_NEAR(std::abs(f->t1.dot(f->n)), 0, 1e-12);  // tangents lie in the tangent plane
  EXPECT_GT(std::abs(f->triple()), 0.95);
  EXPECT_FALSE(feature_frame(b, 2));
}

TEST(ReferenceBody, CurvesFollowTheMesh) {
  ReferenceBody b = sphere();
  add_features(b);
  Mat3d A;
  A << 2.0, 0.1, 0.0, 0.0, 0.5, 0.0, 0.3, 0.2, 1.2;
  const Vec3d shift(0.5, -1, 2);
  std::vector<Vec3d> moved = b.model.nodes.position;
  for (auto& p : moved) p = A * p + shift;
  auto c = with_positions(b, moved);
  ASSERT_TRUE(c);
  EXPECT_TRUE(validate(c->model));
  // Edge and face nodes are affine combinations of nodes: they follow any
  // affine map exactly; so do the stored p_3d.
  for (std::int32_t id : {10, 20, 30}) {
    auto before = feature_curve_polyline(b, id), after = feature_curve_polyline(*c, id);
    ASSERT_TRUE(before && after);
    ASSERT_EQ(before->size(), after->size());
    for (std::size_t i = 0; i < before->size(); ++i) EXPECT_LT(((*after)[i] - (A * (*before)[i] + shift)).norm(), 1e-12);
  }
  for (std::uint32_t a = 0; a < c->model.attrib_nodes.slots.capacity(); ++a)
    EXPECT_LT((c->model.attrib_nodes.position[a] - (A * b.model.attrib_nodes.position[a] + shift)).norm(), 1e-12);
  auto fc = feature_curve_polyline(*c, 30);
  ASSERT_TRUE(fc);
  EXPECT_EQ(fc->size(), kAround);
  // The original body is untouched.
  EXPECT_EQ(b.model.nodes.position[0], sphere().model.nodes.position[0]);
}

TEST(ReferenceBody, RejectsBadInput) {
  ReferenceBody b = sphere();
  add_features(b);
  std::vector<SurfaceLocation> two = {{AttribNodeKind::kVertex, 0, Vec3d::Zero(), 0}, {AttribNodeKind::kVertex, 1, Vec3d::Zero(), 0}};
  EXPECT_FALSE(add_feature_curve(b, 10, "again", two, false));          // id in use
  EXPECT_FALSE(add_feature_curve(b, 11, "meridian", two, false));       // name in use
  EXPECT_FALSE(add_feature_curve(b, 12, "closed_two", two, true));      // too short
  two[1].element = 1'000'000;
  EXPECT_FALSE(add_feature_curve(b, 13, "bad_node", two, false));
  std::vector<SurfaceLocation> bad_face = {{AttribNodeKind::kFace, 0, Vec3d(0.5, 0.6, 0.1), 0},
                                           {AttribNodeKind::kVertex, 1, Vec3d::Zero(), 0}};
  EXPECT_FALSE(add_feature_curve(b, 14, "bad_face", bad_face, false));  // not a convex combination
  EXPECT_FALSE(add_feature_point(b, 2, "p", {AttribNodeKind::kVertex, 0, Vec3d::Zero(), 0}, 10, 10));
  EXPECT_FALSE(add_feature_point(b, 1, "p", {AttribNodeKind::kVertex, 0, Vec3d::Zero(), 0}, 10, 20));
  std::vector<Vec3d> few(3, Vec3d::Zero());
  const Status s = set_positions(b, few);
  EXPECT_EQ(s.code(), ErrorCode::kMismatch);
  EXPECT_TRUE(validate(b.model));
  EXPECT_TRUE(validate_features(b));
}

TEST(ReferenceBodyMeasure, TapeBridgesConcavitiesInAnyPlane) {
  // A square with its four edge midpoints pushed in: the tape follows the square.
  std::vector<Vec3d> star = {{1, 1, 0}, {0, 0.5, 0}, {-1, 1, 0}, {-0.5, 0, 0}, {-1, -1, 0}, {0, -0.5, 0}, {1, -1, 0}, {0.5, 0, 0}};
  EXPECT_NEAR(tape_girth(star), 8.0, 1e-12);
  EXPECT_NEAR(polyline_length(star, true), 8 * std::sqrt(1 + 0.25), 1e-12);
  EXPECT_NEAR(polyline_length(star, false), 7 * std::sqrt(1 + 0.25), 1e-12);
  const Mat3d R = Eigen::AngleAxisd(0.7, Vec3d(1, 2, 3).normalized()).toRotationMatrix();
  for (auto& p : star) p = R * p + Vec3d(3, -2, 1);
  EXPECT_NEAR(tape_girth(star), 8.0, 1e-12);
}

TEST(ReferenceBodyMeasure, BodyMeasurementsOfTheSphere) {
  ReferenceBody b = sphere();
  add_features(b);
  auto m = measure_body(b);
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->stature, 2.0, 1e-12);
  ASSERT_EQ(m->curves.size(), 3u);
  EXPECT_TRUE(std::isnan(m->curves[1].girth));  // open meridian
  // Meridian through the vertices of ring 0..14 at phi = 0: chords of the unit circle.
  EXPECT_NEAR(m->curves[1].length, (kRings - 1) * 2 * std::sin(kPi / (2 * (kRings + 1))), 1e-12);
  ASSERT_EQ(m->points.size(), 1u);
  const double y = (1 - kU) * std::cos(polar(kLatRing)) + kU * std::cos(polar(kLatRing + 1));
  EXPECT_NEAR(m->points[0].height, y + 1, 1e-12);
  const auto cols = measurement_columns(b);
  EXPECT_EQ(cols.size(), measurement_row(*m).size());
  EXPECT_EQ(cols[1], "latitude_girth");
}

}  // namespace
}  // namespace atelier
