// Net Booleans against their peers, side by side in one run on the same
// pairs: CGAL's corefine_and_compute_union / _difference with the exact
// kernel (Epeck, Surface_mesh), and manifold-3d (npm, WASM, one thread),
// timed in-process by bench/net/manifold/manifold_bool.mjs (node start-up
// and OBJ parsing excluded; median of the runs after a warm-up run).
//
// Per pair and operation the peers run first and store their times; the
// BM_NetBoolean rows report counters x_cgal = t_cgal / t_ours and
// x_manifold = t_manifold / t_ours (>1: ours is faster), and the relative
// volume differences to each peer (vol_cgal, vol_manifold). Rows ending in
// /nocheck skip the self-intersection test of the inputs (the peers do not
// check theirs); the default rows include it. Rows ending in
// /resultcheck:off switch BooleanOptions::check_result off (on by default
// since fold16: the rounded result's certificate, then the repair and exact
// fold check where it cannot certify); the default rows report counter
// certified, the share of calls the certificate decided alone. CPU time is
// the main thread's: with threads:2 it misses the second core's work.
//
// Like for like: manifold's `ms` is the Boolean of two ready Manifolds (its
// constructor already sorted, checked and built its collider), `ms_build`
// the same with both Manifolds made inside the timing. The one-call rows
// (net_boolean on two polygon soups: conversion, checks and hierarchies
// every call) report x_manifold against `ms` and x_manifold_build against
// `ms_build`; the rows .../prepared/threads:N time net_boolean on two
// PreparedNets made outside the timing (counter prepare_ms: making both,
// once; cut_ms, classify_ms, result_ms: the stages' medians) and report
// x_manifold against `ms`. BM_NetBooleanChain rows time A - B - B' as two
// one-calls and through a prepared result (BooleanOptions::prepare_result).
//
// Pairs: triangulated UV spheres of about 10k, 100k and 1M triangles each
// (B shifted and turned so the pair is generic), and the shared pairs
// (../shared/data/meshes/boolean-pairs: Havocglass8, Offset3 x Offset4, Cray).
//   build/bench/atelier_bench --benchmark_filter=NetBoolean
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Surface_mesh.h>
#include <atelier/io/obj.h>
#include <atelier/systems/net/boolean.h>
#include <benchmark/benchmark.h>

#include "systems/net/boolean_detail.h"  // result_check_counts (the certified counter)

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace {

using namespace atelier;
namespace fs = std::filesystem;
namespace PMP = CGAL::Polygon_mesh_processing;
using Ke = CGAL::Exact_predicates_exact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Ke::Point_3>;

/// Triangulated UV sphere: 2 nu (nv - 1) triangles.
PolygonSoup sphere(int nu, int nv, double r, const Vec3d& c, double turn) {
  PolygonSoup s;
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(turn, Vec3d(0.3, 0.5, 0.8).normalized()).toRotationMatrix();
  s.positions.push_back(c + rot * Vec3d(0, 0, r));
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
      s.positions.push_back(c +
                            rot * (r * Vec3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th))));
    }
  s.positions.push_back(c + rot * Vec3d(0, 0, -r));
  auto ring = [&](int j, int i) { return static_cast<std::uint32_t>(1 + (j - 1) * nu + (i % nu)); };
  const auto south = static_cast<std::uint32_t>(s.positions.size() - 1);
  for (int i = 0; i < nu; ++i) s.add_face(std::array<std::uint32_t, 3>{0, ring(1, i), ring(1, i + 1)});
  for (int j = 1; j + 1 < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      s.add_face(std::array<std::uint32_t, 3>{ring(j, i), ring(j + 1, i), ring(j + 1, i + 1)});
      s.add_face(std::array<std::uint32_t, 3>{ring(j, i), ring(j + 1, i + 1), ring(j, i + 1)});
    }
  for (int i = 0; i < nu; ++i) s.add_face(std::array<std::uint32_t, 3>{south, ring(nv - 1, i + 1), ring(nv - 1, i)});
  return s;
}

struct Case {
  std::string name;
  PolygonSoup a, b;
  fs::path obj_a, obj_b;  // for the node peer
};

const fs::path kShared = fs::path(ATELIER_BENCH_SHARED_DATA) / "meshes" / "boolean-pairs";
const fs::path kManifoldDir = fs::path(ATELIER_BENCH_SOURCE_DIR) / "bench" / "net" / "manifold";

void write_soup_obj(const PolygonSoup& s, const fs::path& p) {
  std::ofstream f(p);
  f.precision(17);
  for (const Vec3d& x : s.positions) f << "v " << x.x() << ' ' << x.y() << ' ' << x.z() << '\n';
  for (std::size_t i = 0; i < s.face_count(); ++i) {
    f << 'f';
    for (std::uint32_t v : s.face(i)) f << ' ' << v + 1;
    f << '\n';
  }
}

Case& get_case(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Case>> cache;
  auto& slot = cache[name];
  if (slot) return *slot;
  slot = std::make_unique<Case>();
  Case& c = *slot;
  c.name = name;
  const fs::path tmp = fs::temp_directory_path() / "atelier-net-bench";
  fs::create_directories(tmp);
  auto spheres = [&](int nu, int nv) {
    c.a = sphere(nu, nv, 1.0, {0, 0, 0}, 0.0);
    c.b = sphere(nu, nv, 1.0, {0.61, 0.23, 0.17}, 0.7);
  };
  if (name == "sphere10k")
    spheres(71, 71);
  else if (name == "sphere100k")
    spheres(224, 224);
  else if (name == "sphere1M")
    spheres(708, 707);
  else {
    const std::map<std::string, std::pair<const char*, const char*>> files = {
        {"havocglass8", {"Havocglass8_left.obj", "Havocglass8_right.obj"}},
        {"offset3x4", {"Offset3.obj", "Offset4.obj"}},
        {"cray", {"Cray_left.obj", "Cray_right.obj"}}};
    const auto& f = files.at(name);
    if (fs::exists(kShared / f.first)) {
      c.a = net_polygons(read_obj(kShared / f.first));
      c.b = net_polygons(read_obj(kShared / f.second));
    }
  }
  c.obj_a = tmp / (name + "_a.obj");
  c.obj_b = tmp / (name + "_b.obj");
  if (c.a.face_count()) {
    write_soup_obj(c.a, c.obj_a);
    write_soup_obj(c.b, c.obj_b);
  }
  return c;
}

CgalMesh to_cgal(const PolygonSoup& s) {
  std::vector<Ke::Point_3> pts;
  for (const Vec3d& x : s.positions) pts.emplace_back(x.x(), x.y(), x.z());
  std::vector<std::vector<std::size_t>> polys;
  for (std::size_t f = 0; f < s.face_count(); ++f) polys.emplace_back(s.face(f).begin(), s.face(f).end());
  CgalMesh m;
  PMP::polygon_soup_to_polygon_mesh(pts, polys, m);
  PMP::triangulate_faces(m);
  return m;
}

struct PeerFigures {
  double cgal_s = 0, manifold_s = 0, manifold_build_s = 0;
  double cgal_volume = NAN, manifold_volume = NAN;
};
std::map<std::string, PeerFigures>& peers() {
  static std::map<std::string, PeerFigures> m;
  return m;
}

const char* op_name(BooleanOp op) {
  return op == BooleanOp::kUnion ? "union" : "difference";
}

void BM_NetBooleanCgal(benchmark::State& state, std::string pair, BooleanOp op) {
  Case& c = get_case(pair);
  if (!c.a.face_count()) return state.SkipWithError("shared data absent");
  const CgalMesh a0 = to_cgal(c.a), b0 = to_cgal(c.b);
  std::vector<double> times;
  double volume = NAN;
  for (auto _ : state) {
    state.PauseTiming();
    CgalMesh a = a0, b = b0, out;  // corefinement changes its inputs
    state.ResumeTiming();
    const auto t0 = std::chrono::steady_clock::now();
    const bool ok = op == BooleanOp::kUnion ? PMP::corefine_and_compute_union(a, b, out)
                                            : PMP::corefine_and_compute_difference(a, b, out);
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    state.PauseTiming();
    volume = ok ? CGAL::to_double(PMP::volume(out)) : NAN;
    state.ResumeTiming();
  }
  std::sort(times.begin(), times.end());
  auto& p = peers()[pair + op_name(op)];
  p.cgal_s = times[times.size() / 2];
  p.cgal_volume = volume;
  state.counters["volume"] = volume;
}

void BM_NetBooleanManifold(benchmark::State& state, std::string pair, BooleanOp op) {
  Case& c = get_case(pair);
  if (!c.a.face_count()) return state.SkipWithError("shared data absent");
  if (!fs::exists(kManifoldDir / "node_modules" / "manifold-3d"))
    return state.SkipWithError(
        "manifold-3d not installed: scripts/install-deps.sh --bench (npm install in bench/net/manifold)");
  const int reps = 5;
  const std::string cmd = "node " + (kManifoldDir / "manifold_bool.mjs").string() + " " + c.obj_a.string() + " " +
                          c.obj_b.string() + " " + op_name(op) + " " + std::to_string(reps + 1) + " 2>&1";
  std::string out;
  if (FILE* p = popen(cmd.c_str(), "r")) {
    char buf[4096];
    std::size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    pclose(p);
  }
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(out.substr(0, out.find('\n')));
  } catch (const std::exception&) {
    return state.SkipWithError(("manifold-3d: " + out.substr(0, 200)).c_str());
  }
  if (j.contains("error")) return state.SkipWithError(("manifold-3d: " + j["error"].get<std::string>()).c_str());
  auto median_s = [&](const char* key) {
    std::vector<double> ms = j[key].get<std::vector<double>>();
    ms.erase(ms.begin());  // warm-up (JIT, first allocation)
    std::sort(ms.begin(), ms.end());
    return ms[ms.size() / 2] * 1e-3;
  };
  const double median = median_s("ms");
  for (auto _ : state) state.SetIterationTime(median);
  auto& p = peers()[pair + op_name(op)];
  p.manifold_s = median;
  p.manifold_build_s = median_s("ms_build");
  state.counters["ms_build"] = p.manifold_build_s * 1e3;
  p.manifold_volume = j["volume"].get<double>();
  state.counters["volume"] = p.manifold_volume;
  state.SetLabel(j["status"].get<std::string>());
}

/// The counters of an ours row: ratios to the peers' medians (>1: ours is
/// faster) and relative volume differences.
void report_against_peers(benchmark::State& state, const std::string& key, double t, double volume, bool prepared) {
  const auto& p = peers()[key];
  if (p.cgal_s > 0) state.counters["x_cgal"] = p.cgal_s / t;
  if (p.manifold_s > 0) state.counters["x_manifold"] = p.manifold_s / t;
  if (!prepared && p.manifold_build_s > 0) state.counters["x_manifold_build"] = p.manifold_build_s / t;
  if (!std::isnan(p.cgal_volume)) state.counters["vol_cgal"] = (volume - p.cgal_volume) / std::abs(p.cgal_volume);
  if (!std::isnan(p.manifold_volume))
    state.counters["vol_manifold"] = (volume - p.manifold_volume) / std::abs(p.manifold_volume);
  state.counters["volume"] = volume;
}

BooleanOptions bench_options(BooleanOp op, bool check, bool check_result = BooleanOptions{}.check_result) {
  BooleanOptions o;
  o.op = op == BooleanOp::kUnion ? BooleanOp::kUnion : BooleanOp::kAMinusB;
  o.check_self_intersection = check;  // the peers do not check their inputs
  o.check_result = check_result;
  return o;
}

/// The median of the timed calls of `call`, in seconds (steady clock).
template <class Call>
double median_seconds(benchmark::State& state, Call&& call, double& volume) {
  std::vector<double> times;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto r = call();
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (!r) {
      state.SkipWithError(r.status().to_string().c_str());
      return 0;
    }
    volume = r->volume;
    benchmark::DoNotOptimize(r->result.face_nodes.data());
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

void BM_NetBoolean(benchmark::State& state, std::string pair, BooleanOp op, int threads, bool check,
                   bool check_result) {
  Case& c = get_case(pair);
  if (!c.a.face_count()) return state.SkipWithError("shared data absent");
  const BooleanOptions o = bench_options(op, check, check_result);
  ExecContext ctx;
  ctx.threads = threads;
  double volume = NAN;
  auto& counts = net_detail::result_check_counts();
  const std::size_t certified0 = counts.certified, full0 = counts.full;
  const double t = median_seconds(
      state, [&] { return net_boolean(c.a, c.b, o, ctx); }, volume);
  if (t <= 0) return;
  report_against_peers(state, pair + op_name(op), t, volume, false);
  const std::size_t certified = counts.certified - certified0, full = counts.full - full0;
  if (certified + full > 0) state.counters["certified"] = double(certified) / double(certified + full);
}

/// Both operands prepared outside the timing (as manifold's `ms` takes two
/// ready Manifolds).
void BM_NetBooleanPrepared(benchmark::State& state, std::string pair, BooleanOp op, int threads,
                           bool check_result = true) {
  Case& c = get_case(pair);
  if (!c.a.face_count()) return state.SkipWithError("shared data absent");
  const BooleanOptions o = bench_options(op, true, check_result);
  ExecContext ctx;
  ctx.threads = threads;
  PrepareOptions pa_opt, pb_opt;
  pb_opt.name = "B";
  const auto t0 = std::chrono::steady_clock::now();
  auto pa = PreparedNet::prepare(c.a, pa_opt, ctx);
  auto pb = PreparedNet::prepare(c.b, pb_opt, ctx);
  const double prepare_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!pa || !pb) return state.SkipWithError((pa ? pb.status() : pa.status()).to_string().c_str());
  // The stages' split (cut, classification, result), timed at the stage
  // reports (ctx.progress is called as each stage ends): medians in ms.
  std::array<std::vector<double>, 3> stage;
  std::chrono::steady_clock::time_point last;
  ctx.progress = [&](std::string_view, std::size_t done, std::size_t) {
    const auto now = std::chrono::steady_clock::now();
    if (done >= 1 && done <= 3) stage[done - 1].push_back(std::chrono::duration<double>(now - last).count());
    last = now;
  };
  double volume = NAN;
  const double t = median_seconds(
      state,
      [&] {
        last = std::chrono::steady_clock::now();
        return net_boolean(*pa, *pb, o, ctx);
      },
      volume);
  if (t <= 0) return;
  report_against_peers(state, pair + op_name(op), t, volume, true);
  state.counters["prepare_ms"] = prepare_s * 1e3;
  const char* names[] = {"cut_ms", "classify_ms", "result_ms"};
  for (std::size_t k = 0; k < 3; ++k) {
    if (stage[k].empty()) continue;
    std::sort(stage[k].begin(), stage[k].end());
    state.counters[names[k]] = stage[k][stage[k].size() / 2] * 1e3;
  }
}

/// How BM_NetBooleanChain runs the chain A - B - B'.
enum class ChainMode { kOneCalls, kPrepared, kFirstStepPrepared };

/// A chain A - B - B' (B' is B moved by a tenth of A's box diagonal, so it
/// cuts A elsewhere; Cray's B is a slab at FLT_MAX, whose own box would move
/// it off A). kPrepared: A and both B's are prepared outside the timing and
/// the first result is returned prepared (BooleanOptions::prepare_result:
/// its split, every check, its hierarchy) for the second step; kOneCalls:
/// two one-calls on soups; kFirstStepPrepared: the first step alone with
/// prepare_result, so that less the .../prepared/threads:1 row of
/// difference is what the checked prepared result costs (issue 24).
void BM_NetBooleanChain(benchmark::State& state, std::string pair, int threads, ChainMode mode) {
  const bool prepared = mode != ChainMode::kOneCalls;
  Case& c = get_case(pair);
  if (!c.a.face_count()) return state.SkipWithError("shared data absent");
  PolygonSoup b2 = c.b;
  {
    Vec3d lo = Vec3d::Constant(INFINITY), hi = -lo;
    for (const Vec3d& p : c.a.positions) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const Vec3d d = 0.1 * (hi - lo).norm() * Vec3d(0.48, 0.6, 0.64);
    for (Vec3d& p : b2.positions) p += d;
  }
  ExecContext ctx;
  ctx.threads = threads;
  BooleanOptions o = bench_options(BooleanOp::kAMinusB, true);
  PrepareOptions pa_opt, pb_opt;
  pb_opt.name = "B";
  auto pa = PreparedNet::prepare(c.a, pa_opt, ctx);
  auto pb = PreparedNet::prepare(c.b, pb_opt, ctx);
  auto pb2 = PreparedNet::prepare(b2, pb_opt, ctx);
  if (!pa || !pb || !pb2) return state.SkipWithError("prepare failed");
  double volume = NAN;
  const double t = median_seconds(
      state,
      [&]() -> Expected<BooleanReport> {
        if (prepared) {
          BooleanOptions first = o;
          first.prepare_result = true;
          auto r1 = net_boolean(*pa, *pb, first, ctx);
          if (!r1) return r1;
          if (!r1->prepared_status) return r1->prepared_status;
          if (mode == ChainMode::kFirstStepPrepared) return r1;
          return net_boolean(r1->prepared, *pb2, o, ctx);
        }
        auto r1 = net_boolean(c.a, c.b, o, ctx);
        if (!r1) return r1;
        return net_boolean(r1->result, b2, o, ctx);
      },
      volume);
  if (t > 0) state.counters["volume"] = volume;
}

const int kRegistered = [] {
  const std::pair<const char*, int> pairs[] = {{"havocglass8", 20}, {"offset3x4", 20}, {"cray", 20},
                                               {"sphere10k", 5},    {"sphere100k", 2}, {"sphere1M", 1}};
  for (const auto& [pair, iters] : pairs)
    for (BooleanOp op : {BooleanOp::kUnion, BooleanOp::kAMinusB}) {
      const std::string tag = std::string(pair) + "/" + op_name(op);
      benchmark::RegisterBenchmark(("BM_NetBooleanCgal/" + tag).c_str(), BM_NetBooleanCgal, std::string(pair), op)
          ->Unit(benchmark::kMillisecond)
          ->Iterations(iters);
      benchmark::RegisterBenchmark(("BM_NetBooleanManifold/" + tag).c_str(), BM_NetBooleanManifold, std::string(pair),
                                   op)
          ->Unit(benchmark::kMillisecond)
          ->UseManualTime()
          ->Iterations(1);
      for (int threads : {2, 1}) {
        for (bool check : {true, false})
          benchmark::RegisterBenchmark(
              ("BM_NetBoolean/" + tag + "/threads:" + std::to_string(threads) + (check ? "" : "/nocheck")).c_str(),
              BM_NetBoolean, std::string(pair), op, threads, check, true)
              ->Unit(benchmark::kMillisecond)
              ->Iterations(std::max(iters, 3));
        benchmark::RegisterBenchmark(
            ("BM_NetBoolean/" + tag + "/threads:" + std::to_string(threads) + "/resultcheck:off").c_str(),
            BM_NetBoolean, std::string(pair), op, threads, true, false)
            ->Unit(benchmark::kMillisecond)
            ->Iterations(std::max(iters, 3));
      }
      // .../prepared/threads:N/resultcheck:off: like for like with
      // manifold's `ms`, which gives no such guarantee on its rounded result.
      for (int threads : {2, 1})
        for (bool check_result : {true, false})
          benchmark::RegisterBenchmark(("BM_NetBoolean/" + tag + "/prepared/threads:" + std::to_string(threads) +
                                        (check_result ? "" : "/resultcheck:off"))
                                           .c_str(),
                                       BM_NetBooleanPrepared, std::string(pair), op, threads, check_result)
              ->Unit(benchmark::kMillisecond)
              ->Iterations(std::max(iters, 3));
    }
  for (const auto& [pair, iters] : pairs) {
    if (std::string_view(pair) != "cray" && std::string_view(pair) != "sphere100k") continue;
    for (const auto& [mode, tag] :
         {std::pair{ChainMode::kOneCalls, "one-call"}, std::pair{ChainMode::kPrepared, "prepared"},
          std::pair{ChainMode::kFirstStepPrepared, "first-step-prepared"}})
      benchmark::RegisterBenchmark(("BM_NetBooleanChain/" + std::string(pair) + "/" + tag + "/threads:1").c_str(),
                                   BM_NetBooleanChain, std::string(pair), 1, mode)
          ->Unit(benchmark::kMillisecond)
          ->Iterations(std::max(iters, 3));
  }
  return 0;
}();

}  // namespace
