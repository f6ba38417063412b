// Painting and cutting along one 200-point stroke on ~100k-triangle meshes
// (Spot subdivided twice: 93,696 triangles; a MakeHuman work suit, fan
// triangulated and subdivided twice: ~112k triangles), side by side with
// what a CGAL user would write for the same cut: the stroke swept along its
// view rays into a cutting sheet (two points per stroke point, 398
// triangles), CGAL::Polygon_mesh_processing::split, connected components,
// the picked component removed (AABB-tree ray); and, for painting, the
// sheet's intersection polylines (PMP::surface_intersection).
//
// Same pieces: before timing, both cuts are run once: the removed piece's
// area, the area left and the components left must agree (counters
// "pieces", the components after CGAL's split, and "area_diff", the largest
// relative difference). Inputs are copied outside the timed
// region. Our side runs on 1 and 2 threads.
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/clip.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/intersection.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Surface_mesh.h>
#include <atelier/io/obj.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/storage/builder.h>
#include <atelier/storage/topology.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/garment/makehuman_binding.h>
#include <atelier/systems/mesh/subdivide.h>
#include <atelier/systems/sketch/cut.h>
#include <atelier/systems/sketch/paint.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

namespace {

using namespace atelier;
namespace fs = std::filesystem;
namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using CMesh = CGAL::Surface_mesh<K::Point_3>;

/// A benchmark case: the mesh (triangles), a front camera, the stroke and the pick.
struct Case {
  std::string error;
  Model model;
  Camera camera;
  std::vector<Vec2d> stroke;
  Vec2d pick;
  CMesh cgal, sheet;
  K::Ray_3 pick_ray;
  std::size_t pieces = 0;
  double area_diff = 0;
};

Box3d bounds(const Model& m) {
  Box3d b;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v})) b.extend(m.position(NodeIdx{v}));
  return b;
}

/// The model's fan triangles as one triangle-only surface (both sides get
/// exactly the same triangles).
Model triangulated(const Model& m) {
  auto t = fan_triangulate(m).value();
  std::vector<std::uint32_t> off{0}, idx;
  for (const Triangle& x : t.triangles) {
    idx.insert(idx.end(), x.begin(), x.end());
    off.push_back(static_cast<std::uint32_t>(idx.size()));
  }
  Model out;
  (void)add_polygon_surface(out, "mesh", PolygonSoupView{m.nodes.position, off, idx}).value();
  return out;
}

CMesh to_cgal(const Model& m) {
  CMesh c;
  std::vector<CMesh::Vertex_index> v(m.nodes.slots.capacity());
  for (std::uint32_t i = 0; i < m.nodes.slots.capacity(); ++i) {
    const Vec3d& p = m.nodes.position[i];
    v[i] = c.add_vertex(K::Point_3(p.x(), p.y(), p.z()));
  }
  std::vector<NodeIdx> f;
  for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i) {
    if (!m.alive(FaceIdx{i})) continue;
    m.face_nodes(FaceIdx{i}, f);
    c.add_face(v[f[0].value], v[f[1].value], v[f[2].value]);
  }
  return c;
}

/// The stroke swept along its view rays: a strip from in front of the mesh
/// to behind it.
CMesh sweep(const Camera& cam, const std::vector<Vec2d>& stroke, const Box3d& box) {
  const Vec3d c = 0.5 * (box.lo + box.hi);
  const double r = 0.5 * (box.hi - box.lo).norm();
  CMesh s;
  std::vector<CMesh::Vertex_index> a, b;
  for (const Vec2d& px : stroke) {
    const auto [o, d] = cam.ray(px);
    const double t = (c - o).dot(d);
    const Vec3d p0 = o + (t - 1.5 * r) * d, p1 = o + (t + 1.5 * r) * d;
    a.push_back(s.add_vertex(K::Point_3(p0.x(), p0.y(), p0.z())));
    b.push_back(s.add_vertex(K::Point_3(p1.x(), p1.y(), p1.z())));
  }
  for (std::size_t i = 0; i + 1 < stroke.size(); ++i) {
    s.add_face(a[i], a[i + 1], b[i + 1]);
    s.add_face(a[i], b[i + 1], b[i]);
  }
  return s;
}

std::vector<AttribEdge> edges_of(const PaintResult& p) {
  std::vector<AttribEdge> e;
  for (const auto& c : p.curves) e.insert(e.end(), c.edges.begin(), c.edges.end());
  return e;
}

/// Our cut: penetrated painting, the pick, cut; `totals`: also the kept
/// side's area and face count.
Expected<CutResult> ours(Model& m, const Case& c, const ExecContext& ctx, bool totals = true) {
  auto p = paint_stroke(m, c.camera, c.stroke, {.through = true}, ctx);
  if (!p) return p.status();
  auto pick = locate_pixel(m, c.camera, c.pick, {}, ctx);
  if (!pick) return pick.status();
  return cut_along_curves(m, edges_of(*p), {.pick = pick->location, .kept_totals = totals}, ctx);
}

/// The CGAL user's cut; returns the removed component's area and, with
/// `totals`, the areas of the components left (what ours reports with
/// CutOptions::kept_totals: both sides measure the same things).
struct TheirCut {
  double removed = 0;
  std::vector<double> left;
};
TheirCut theirs(CMesh& tm, CMesh& sheet, const K::Ray_3& ray, bool totals = true) {
  PMP::split(tm, sheet);
  auto cc = tm.add_property_map<CMesh::Face_index, std::size_t>("f:cc", 0).first;
  const std::size_t n = PMP::connected_components(tm, cc);
  using Primitive = CGAL::AABB_face_graph_triangle_primitive<CMesh>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
  Tree tree(faces(tm).first, faces(tm).second, tm);
  const auto hit = tree.first_intersection(ray);
  const std::size_t dropped = hit ? cc[hit->second] : n;
  std::vector<double> area(n, 0.0);
  for (auto f : tm.faces())
    if (totals || cc[f] == dropped) area[cc[f]] += PMP::face_area(f, tm);
  TheirCut out;
  if (hit) {
    PMP::remove_connected_components(tm, std::vector<std::size_t>{dropped}, cc);
    out.removed = area[dropped];
  }
  for (std::size_t i = 0; i < n && totals; ++i)
    if (i != dropped) out.left.push_back(area[i]);
  return out;
}

void prepare(Case& c, Model m, std::vector<Vec3d> line, const Vec3d& pick) {
  c.model = triangulated(m);
  const Box3d box = bounds(c.model);
  const Vec3d centre = 0.5 * (box.lo + box.hi);
  const double half = 0.6 * (box.hi - box.lo).maxCoeff();
  c.camera = Camera::orthographic(centre + Vec3d(0, 0, 3 * half), centre, Vec3d::UnitY(), half, 1000, 1000);
  for (const Vec3d& p : line) c.stroke.push_back(c.camera.project(p).head<2>());
  c.pick = c.camera.project(pick).head<2>();
  c.cgal = to_cgal(c.model);
  c.sheet = sweep(c.camera, c.stroke, box);
  const auto [o, d] = c.camera.ray(c.pick);
  c.pick_ray = K::Ray_3(K::Point_3(o.x(), o.y(), o.z()), K::Vector_3(d.x(), d.y(), d.z()));
  // Same pieces: both cuts once; the removed piece's area, the area left
  // and the number of components left must agree.
  Model mine = c.model;
  auto r = ours(mine, c, ExecContext::sequential());
  if (!r) {
    c.error = r.status().to_string();
    return;
  }
  CMesh tm = c.cgal, sh = c.sheet;
  const TheirCut t = theirs(tm, sh, c.pick_ray);
  double left = 0;
  for (double a : t.left) left += a;
  const std::size_t ours_left = static_cast<std::size_t>(count_topology(mine).components);
  c.pieces = t.left.size() + 1;
  if (ours_left != t.left.size()) {
    c.error = "the cuts leave " + std::to_string(ours_left) + " (ours) and " + std::to_string(t.left.size()) +
              " (CGAL) components";
    return;
  }
  c.area_diff = std::max(std::abs(r->removed_area - t.removed) / t.removed, std::abs(r->kept_area - left) / left);
  // Without the kept side's totals both cuts remove the same piece as well.
  Model mine2 = c.model;
  auto r2 = ours(mine2, c, ExecContext::sequential(), false);
  CMesh tm2 = c.cgal, sh2 = c.sheet;
  const TheirCut t2 = theirs(tm2, sh2, c.pick_ray, false);
  if (!r2 || r2->removed_area != r->removed_area || diff_tables(mine, mine2) != "" || t2.removed != t.removed)
    c.error = "the cuts without totals differ from the cuts with them";
}

/// A 200-point wavy line across `box` at height fraction `h`, in the z = centre plane.
std::vector<Vec3d> wavy(const Box3d& box, double h, double amp) {
  std::vector<Vec3d> p;
  const Vec3d c = 0.5 * (box.lo + box.hi), e = box.hi - box.lo;
  for (int k = 0; k < 200; ++k) {
    const double s = k / 199.0;
    p.push_back(Vec3d(box.lo.x() - 0.1 * e.x() + 1.2 * e.x() * s,
                      box.lo.y() + h * e.y() + amp * e.y() * std::sin(6 * M_PI * s), c.z()));
  }
  return p;
}

const Case& spot() {
  static const Case c = [] {
    Case x;
    const fs::path p = fs::path(ATELIER_BENCH_SHARED_DATA) / "meshes" / "spot_triangulated.obj";
    if (!fs::exists(p)) {
      x.error = "Spot not found at " + p.string();
      return x;
    }
    Model m = read_obj(p);
    for (int l = 0; l < 2; ++l) (void)subdivide_uniform(m).value();
    const Box3d b = bounds(m);
    prepare(x, std::move(m), wavy(b, 0.55, 0.04), 0.5 * (b.lo + b.hi) + Vec3d(0, 0.4 * (b.hi - b.lo).y(), 0));
    return x;
  }();
  return c;
}

const Case& suit() {
  static const Case c = [] {
    Case x;
    const fs::path dir = fs::path(ATELIER_BENCH_SHARED_DATA) / "makehuman";
    if (!fs::exists(dir / "base.obj")) {
      x.error = "MakeHuman data not found at " + dir.string();
      return x;
    }
    const makehuman::HumanLibrary lib = makehuman::HumanLibrary::load(dir);
    auto soup = makehuman::fitted_garment(lib, dir / "clothes" / "male_worksuit01.mhclo");
    if (!soup) {
      x.error = soup.status().to_string();
      return x;
    }
    Model m;
    if (auto s = add_polygon_surface(m, "suit", *soup); !s) {
      x.error = s.status().to_string();
      return x;
    }
    m = triangulated(m);
    for (int l = 0; l < 2; ++l) (void)subdivide_uniform(m).value();
    const Box3d b = bounds(m);
    prepare(x, std::move(m), wavy(b, 0.6, 0.02), Vec3d(0, b.lo.y() + 0.85 * (b.hi - b.lo).y(), 0));
    return x;
  }();
  return c;
}

const Case& get(int which) {
  return which == 0 ? spot() : suit();
}

void counters(benchmark::State& st, const Case& c) {
  st.counters["triangles"] = static_cast<double>(c.model.num_faces());
  st.counters["pieces"] = static_cast<double>(c.pieces);
  st.counters["area_diff"] = c.area_diff;
  st.SetLabel(st.range(0) == 0 ? "spot" : "worksuit");
}

void BM_SketchCut(benchmark::State& st) {
  const Case& c = get(static_cast<int>(st.range(0)));
  if (!c.error.empty()) {
    st.SkipWithError(c.error.c_str());
    return;
  }
  ExecContext ctx;
  ctx.threads = static_cast<int>(st.range(1));
  const bool totals = st.range(2) != 0;
  for (auto _ : st) {
    st.PauseTiming();
    Model m = c.model;
    st.ResumeTiming();
    auto r = ours(m, c, ctx, totals);
    if (!r) st.SkipWithError(r.status().to_string().c_str());
    st.PauseTiming();
    { Model sink = std::move(m); }
    st.ResumeTiming();
  }
  counters(st, c);
}
// totals: 1 = both sides also measure the kept side (every face's area),
// 0 = both report the removed piece only.
BENCHMARK(BM_SketchCut)
    ->ArgNames({"mesh", "threads", "totals"})
    ->Args({0, 1, 1})
    ->Args({0, 2, 1})
    ->Args({0, 1, 0})
    ->Args({0, 2, 0})
    ->Args({1, 1, 1})
    ->Args({1, 2, 1})
    ->Args({1, 1, 0})
    ->Args({1, 2, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_SketchCut_CgalSplit(benchmark::State& st) {
  const Case& c = get(static_cast<int>(st.range(0)));
  if (!c.error.empty()) {
    st.SkipWithError(c.error.c_str());
    return;
  }
  const bool totals = st.range(2) != 0;
  for (auto _ : st) {
    st.PauseTiming();
    CMesh tm = c.cgal, sh = c.sheet;
    st.ResumeTiming();
    benchmark::DoNotOptimize(theirs(tm, sh, c.pick_ray, totals));
    st.PauseTiming();
    { CMesh a = std::move(tm), b = std::move(sh); }
    st.ResumeTiming();
  }
  counters(st, c);
}
BENCHMARK(BM_SketchCut_CgalSplit)
    ->ArgNames({"mesh", "threads", "totals"})
    ->Args({0, 1, 1})
    ->Args({0, 1, 0})
    ->Args({1, 1, 1})
    ->Args({1, 1, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_SketchPaint(benchmark::State& st) {
  const Case& c = get(static_cast<int>(st.range(0)));
  if (!c.error.empty()) {
    st.SkipWithError(c.error.c_str());
    return;
  }
  ExecContext ctx;
  ctx.threads = static_cast<int>(st.range(1));
  const bool through = st.range(2) != 0;
  std::size_t points = 0;
  for (auto _ : st) {
    auto r = trace_stroke(c.model, c.camera, c.stroke, {.through = through}, ctx);
    if (!r) {
      st.SkipWithError(r.status().to_string().c_str());
      break;
    }
    points = 0;
    for (const auto& cv : r->curves) points += cv.points.size();
  }
  counters(st, c);
  st.counters["curve_points"] = static_cast<double>(points);
}
BENCHMARK(BM_SketchPaint)
    ->ArgNames({"mesh", "threads", "through"})
    ->Args({0, 1, 1})
    ->Args({0, 2, 1})
    ->Args({1, 1, 1})
    ->Args({1, 2, 1})
    ->Args({1, 1, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_SketchPaint_CgalIntersection(benchmark::State& st) {
  const Case& c = get(static_cast<int>(st.range(0)));
  if (!c.error.empty()) {
    st.SkipWithError(c.error.c_str());
    return;
  }
  std::size_t points = 0;
  for (auto _ : st) {
    std::vector<std::vector<K::Point_3>> lines;
    PMP::surface_intersection(c.cgal, c.sheet, std::back_inserter(lines));
    points = 0;
    for (const auto& l : lines) points += l.size();
  }
  counters(st, c);
  st.counters["curve_points"] = static_cast<double>(points);
}
BENCHMARK(BM_SketchPaint_CgalIntersection)
    ->ArgNames({"mesh", "threads", "through"})
    ->Args({0, 1, 1})
    ->Args({1, 1, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
