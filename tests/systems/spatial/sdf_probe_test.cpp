// SdfGrid probes (systems/sdf_grid.h): a query cell whose 8 corners span
// several 8^3 blocks (leaves or tiles) is read one block at a time, a cell
// inside a tile with one lookup. Checked against the trilinear formula over
// lattice values read through single-block cells, against the background
// value far from the surface, and against the BVH's exact sign.
#include <atelier/engine/random.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/spatial/sdf_grid.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

namespace atelier {
namespace {

/// Closed UV sphere (radius r, centre c), counter-clockwise from outside.
struct ProbeSphere {
  std::vector<Vec3d> positions;
  std::vector<Triangle> triangles;
  Vec3d c;
  double r;
};

ProbeSphere probe_sphere(const Vec3d& c, double r, int n_lat, int n_lon) {
  ProbeSphere s{{}, {}, c, r};
  s.positions.push_back(c + Vec3d(0, 0, r));
  for (int i = 1; i < n_lat; ++i) {
    const double th = std::numbers::pi * i / n_lat;
    for (int j = 0; j < n_lon; ++j) {
      const double ph = 2 * std::numbers::pi * j / n_lon;
      s.positions.push_back(c + r * Vec3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  }
  s.positions.push_back(c + Vec3d(0, 0, -r));
  const auto south = static_cast<std::uint32_t>(s.positions.size() - 1);
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(1 + i * n_lon + (j % n_lon)); };
  for (int j = 0; j < n_lon; ++j) s.triangles.push_back({0, id(0, j), id(0, j + 1)});
  for (int i = 0; i + 2 < n_lat; ++i)
    for (int j = 0; j < n_lon; ++j) {
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  for (int j = 0; j < n_lon; ++j) s.triangles.push_back({id(n_lat - 2, j), south, id(n_lat - 2, j + 1)});
  return s;
}

// Voxel size 2^-5: p = (i + t) h is exact in binary, so p / h gives back
// the chosen cell i and fraction t without rounding.
constexpr double kH = 1.0 / 32.0;

/// Value of voxel (a, b, c) read through a cell whose corners lie in one
/// block along every axis: on an axis where the index is 7 mod 8 (the cell
/// starting there crosses blocks) through the cell before it at t = 1 - 2^-40.
double lattice_value(SdfGrid::Sampler& s, const std::array<int, 3>& idx) {
  Vec3d p;
  for (int a = 0; a < 3; ++a) p[a] = ((idx[a] & 7) == 7 ? idx[a] - 0x1.0p-40 : double(idx[a])) * kH;
  return s.sample(p);
}

/// Trilinear interpolation of the 8 lattice values around p (the formula of
/// a single-block cell, written out here).
double trilinear_from_lattice(SdfGrid::Sampler& s, const Vec3d& p) {
  std::array<int, 3> i{};
  std::array<double, 3> t{};
  for (int a = 0; a < 3; ++a) {
    const double x = p[a] / kH;
    i[a] = static_cast<int>(std::floor(x));
    t[a] = x - std::floor(x);
  }
  double sum = 0;
  for (int n = 0; n < 8; ++n) {
    const std::array<int, 3> o{(n >> 2) & 1, (n >> 1) & 1, n & 1};
    double w = 1;
    for (int a = 0; a < 3; ++a) w *= o[a] ? t[a] : 1.0 - t[a];
    sum += w * lattice_value(s, {i[0] + o[0], i[1] + o[1], i[2] + o[2]});
  }
  return sum;
}

/// Points whose cell crosses blocks along the axes in `cross` (bit a: axis
/// a), within `near` of the sphere when near > 0, anywhere in `box` otherwise.
std::vector<Vec3d> crossing_points(const ProbeSphere& s, const Box3d& box, unsigned cross, double near, std::size_t n,
                                   SplitMix64& rng) {
  std::vector<Vec3d> out;
  const std::array<int, 3> lo{static_cast<int>(std::ceil(box.lo.x() / kH)),
                              static_cast<int>(std::ceil(box.lo.y() / kH)),
                              static_cast<int>(std::ceil(box.lo.z() / kH))};
  const std::array<int, 3> hi{static_cast<int>(std::floor(box.hi.x() / kH)) - 1,
                              static_cast<int>(std::floor(box.hi.y() / kH)) - 1,
                              static_cast<int>(std::floor(box.hi.z() / kH)) - 1};
  while (out.size() < n) {
    Vec3d p;
    for (int a = 0; a < 3; ++a) {
      int i = lo[a] + static_cast<int>(rng.next() % static_cast<std::uint64_t>(hi[a] - lo[a] + 1));
      const bool want = (cross >> a) & 1;
      if (want) i = (i & ~7) + 7;
      if (!want && (i & 7) == 7) --i;
      if (i < lo[a] || i > hi[a]) break;
      p[a] = (i + std::ldexp(std::floor(rng.uniform(0, 1) * 0x1.0p20), -20)) * kH;  // t on a 2^-20 grid: exact
      if (a == 2) {
        const double d = (p - s.c).norm() - s.r;
        if (near <= 0 || std::abs(d) < near) out.push_back(p);
      }
    }
  }
  return out;
}

void check_grid(const ProbeSphere& s, const BodyBvh& bvh, const SdfGrid& grid, const Box3d& box) {
  SdfGrid::Sampler sampler = grid.sampler();
  SplitMix64 rng(17);
  std::size_t checked = 0, tiles = 0, fallbacks = 0;
  const double background = double(float(grid.params().half_width * kH));
  for (unsigned cross = 0; cross < 8; ++cross) {
    for (const double near : {2.0 * kH, 0.3 * kH, 0.0}) {
      const std::vector<Vec3d> pts = crossing_points(s, box, cross, near, 300, rng);
      for (const Vec3d& p : pts) {
        const double d = sampler.sample(p);
        // The probe reads the same corner values as eight single-block
        // reads: equal up to rounding (the grid interpolates differences of
        // float values in float, 2^-24 relative; a wrong corner would be off
        // by a fraction of a voxel).
        ASSERT_NEAR(d, trilinear_from_lattice(sampler, p), 1e-6 * kH) << "axes " << cross << " at " << p.transpose();
        const double exact = bvh.signed_distance(p).distance;
        const std::size_t before = sampler.stats().exact;
        ASSERT_EQ(sampler.inside(p), exact < 0.0) << "axes " << cross << " at " << p.transpose() << ", exact " << exact;
        ASSERT_EQ(grid.inside(p), exact < 0.0);
        fallbacks += sampler.stats().exact - before;
        // Far from the surface, full grids: a tile of the flood-filled
        // background, whose sign is the side of the sphere.
        if (grid.params().roi.empty() && std::abs((p - s.c).norm() - s.r) > (grid.params().half_width + 2) * kH) {
          ASSERT_EQ(std::abs(d), background) << p.transpose();
          ASSERT_EQ(d < 0.0, (p - s.c).norm() < s.r);
          ++tiles;
        }
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 8u * 3u * 300u);
  if (grid.params().roi.empty()) {
    EXPECT_GT(tiles, 500u);
  }
  EXPECT_GT(fallbacks, 0u);  // the exact path was exercised (points within 0.3 h)
}

// The sphere of both tests, its BVH, and a grid over it (the whole sphere
// when `roi` is empty), then check_grid over `where`.
void check_sphere_grid(std::vector<Box3d> roi, const Box3d& where) {
  const ProbeSphere s = probe_sphere(Vec3d(0.03, -0.02, 0.01), 0.8, 60, 90);
  BodyBvh bvh;
  ASSERT_TRUE(bvh.build(s.positions, s.triangles).is_ok());
  SdfParams prm;
  prm.voxel_size = kH;
  prm.roi = std::move(roi);
  SdfGrid grid;
  ASSERT_TRUE(grid.build(bvh, prm).is_ok());
  check_grid(s, bvh, grid, where);
}

TEST(SdfProbe, FullGridCellsAcrossBlocksMatchTheTrilinearFormulaAndTheExactSign) {
  check_sphere_grid({}, Box3d{Vec3d(-1, -1, -1), Vec3d(1, 1, 1)});
}

TEST(SdfProbe, RoiGridCellsAcrossBlocksMatchTheTrilinearFormulaAndTheExactSign) {
  const Box3d roi{Vec3d(0.3, -0.5, -0.5), Vec3d(1.0, 0.5, 0.5)};
  check_sphere_grid({roi}, roi);
}

}  // namespace
}  // namespace atelier
