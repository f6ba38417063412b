// Regenerating MakeHuman's real garments with detail templates followed by
// the collision pass (issue 7), compared side by side with MakeHuman's own
// binding (.mhclo) on 100 random adult bodies, and the tights/skirt helpers
// as a ground truth. The test writes the report (JSON) to
// $ATELIER_TMP/garment_report.json and prints a table.
//
// Figures per garment and body (averaged over bodies, worst body kept too):
//  * share of vertices more than 1 mm inside the body (signed distance by
//    BodyBvh, independent of the pass's own queries);
//  * clearance change: RMS over vertices of (signed distance on the body -
//    signed distance of the source fit on the default body);
//  * excess edge strain: per garment edge, |garment strain - strain of the
//    body surface under it|, strain = length / source length - 1; the body's
//    strain is that of the edge vector carried by the affine map of the body
//    triangle under the edge's midpoint (its two edges and unit normal on the
//    source body to the same on the new body), i.e. the stretch of an edge
//    that followed the skin exactly; p95 over edges.
#include <atelier/engine/parallel.h>
#include <atelier/io/obj.h>
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/garment/collision_pass.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/edge_transfer.h>
#include <atelier/systems/garment/makehuman_binding.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>

#include "systems/garment/makehuman_helpers.h"
#include "tests/support/shared_data.h"

using namespace atelier;
using namespace atelier::makehuman;
namespace fs = std::filesystem;

namespace {

using atelier::testing::makehuman_dir;
fs::path out_dir() {
  const char* env = std::getenv("ATELIER_TMP");
  fs::path d = env ? fs::path(env) : fs::temp_directory_path() / "atelier-tests";
  fs::create_directories(d);
  return d;
}

std::vector<Vec3d> to_metres(const std::vector<Vec3d>& v) {
  std::vector<Vec3d> o(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) o[i] = kMakeHumanToMetres * v[i];
  return o;
}

struct Garment {
  std::string name;
  GarmentBinding binding;
  std::vector<std::array<std::uint32_t, 2>> edges;
  std::vector<Vec3d> source;  // binding fit on the default body (m)
  std::vector<double> source_sd;
  GarmentTemplate tmpl;         // encoded through the garment pipeline
  double source_floor_rms = 0;  // RMS of (max(source clearance, min_clearance) - source clearance)
  // Per edge: the body triangle under its midpoint on the source body, and
  // the edge vector in that triangle's (edge 1, edge 2, unit normal) basis.
  std::vector<std::uint32_t> edge_tri;
  std::vector<Vec3d> edge_coef;
};

struct Stats {  // accumulated over bodies
  std::vector<double> mean_dist, max_dist, inside_ours, inside_peer, inside1_ours, inside1_peer, depth_ours, depth_peer,
      clear_rms_ours, clear_rms_peer, strain_ours, strain_peer;
  std::vector<double> inside1_raw, depth_raw, clear_rms_raw, excess_ours, excess_peer, excess_raw, excess_transfer,
      pushed, pass_ms;
};

// Columns: the triangle's two edges from corner 0 and its unit normal.
Mat3d triangle_basis(std::span<const Vec3d> p, const Triangle& t) {
  Mat3d m;
  const Vec3d e1 = p[t[1]] - p[t[0]], e2 = p[t[2]] - p[t[0]];
  m << e1, e2, e1.cross(e2).normalized();
  return m;
}

double p95(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[std::min(v.size() - 1, static_cast<std::size_t>(0.95 * v.size()))];
}
double mean(const std::vector<double>& v) {
  return v.empty() ? 0 : std::accumulate(v.begin(), v.end(), 0.0) / v.size();
}
double maxv(const std::vector<double>& v) {
  return v.empty() ? 0 : *std::max_element(v.begin(), v.end());
}

}  // namespace

TEST(GarmentRegeneration, MakeHumanGarmentsAgainstTheirBindingOn100Bodies) {
  if (!fs::exists(makehuman_dir() / "base.obj")) GTEST_SKIP() << "MakeHuman data not found at " << makehuman_dir();
  const HumanLibrary lib = HumanLibrary::load(makehuman_dir());
  const ReferenceBody ref = make_reference_body(lib);
  const BodyPolygons poly = BodyPolygons::from_model(ref.model);
  auto tris = fan_triangulate(ref.model);
  ASSERT_TRUE(tris);
  const std::uint32_t nv_base = lib.vertex_count();
  std::vector<Vec3f> H0(nv_base);
  lib.build(MacroParams{}, H0);
  const std::vector<Vec3d> skin0 = skin_positions(ref);
  BodyBvh bvh0;
  ASSERT_TRUE(bvh0.build(skin0, tris->triangles));
  auto family = GarmentFamily::of(ref);
  ASSERT_TRUE(family) << family.status().to_string();
  CollisionBody cb0;
  ASSERT_TRUE(cb0.build(family->collision, skin0));
  const auto& T = tris->triangles;

  // ATELIER_DETAIL_SCALED_FRAMES=1 measures the same figures with scaled
  // frames (DetailParams::scaled_frames, issue 26; docs/performance.md).
  GarmentEncodeOptions encode_options;
  encode_options.detail.scaled_frames = std::getenv("ATELIER_DETAIL_SCALED_FRAMES") != nullptr;
  std::vector<Garment> garments;
  for (const auto& e : fs::directory_iterator(makehuman_dir() / "clothes"))
    if (e.path().extension() == ".mhclo") {
      Garment g;
      g.name = e.path().stem().string();
      g.binding = read_mhclo(e.path(), nv_base);
      auto soup = read_garment_mesh(e.path().parent_path() / g.binding.obj_file);
      ASSERT_TRUE(soup) << soup.status().to_string();
      ASSERT_EQ(soup->positions.size(), g.binding.refs.size()) << g.name;
      g.edges = soup->edges();
      for (auto& ed : g.edges) ASSERT_LT(std::max(ed[0], ed[1]), g.binding.refs.size()) << g.name;
      g.source = to_metres(fit_binding(g.binding, H0));
      g.source_sd.resize(g.source.size());
      ASSERT_TRUE(bvh0.signed_distances(g.source, g.source_sd));
      soup->positions = g.source;
      auto made = encode_garment(*family, g.name, std::move(*soup), encode_options);
      ASSERT_TRUE(made) << made.status().to_string();
      g.tmpl = std::move(*made);
      for (const float c : g.tmpl.clearance.clearance) {
        const double lift = std::max(0.0, CollisionParams{}.min_clearance - c);
        g.source_floor_rms += lift * lift;
      }
      g.source_floor_rms = std::sqrt(g.source_floor_rms / g.source.size());
      for (const auto& e : g.edges) {
        const std::uint32_t t = cb0.query(0.5 * (g.source[e[0]] + g.source[e[1]])).triangle;
        g.edge_tri.push_back(t);
        g.edge_coef.push_back(triangle_basis(skin0, T[t]).inverse() * (g.source[e[1]] - g.source[e[0]]));
      }
      // Decoding on the source body gives the source fit back.
      std::vector<Vec3d> back(g.source.size());
      ASSERT_TRUE(decode_detail(g.tmpl.encoding, poly, skin0, back));
      for (std::size_t v = 0; v < back.size(); ++v) ASSERT_LT((back[v] - g.source[v]).norm(), 1e-5) << g.name;
      garments.push_back(std::move(g));
    }
  std::sort(garments.begin(), garments.end(), [](const Garment& a, const Garment& b) { return a.name < b.name; });
  ASSERT_EQ(garments.size(), 5u);

  // Helpers as ground truth.
  struct Helper {
    std::string name;
    std::vector<std::uint32_t> verts;
    DetailEncoding enc;
    std::vector<double> mean_err, max_err;
  };
  std::vector<Helper> helpers;
  for (const char* hname : {"helper-tights", "helper-skirt"}) {
    Helper h;
    h.name = hname;
    const auto* grp = lib.base().group(hname);
    ASSERT_NE(grp, nullptr);
    h.verts = garment_test::group_vertices(*grp);
    std::vector<Vec3d> src;
    for (auto v : h.verts) src.push_back(kMakeHumanToMetres * H0[v].cast<double>());
    h.enc = std::move(*encode_detail(poly, skin0, src, encode_options.detail));
    helpers.push_back(std::move(h));
  }

  // Under the sanitizers (ATELIER_SKIP_LONG_TESTS) the first 12 of the 100
  // adults, every figure still asserted (135 s of ASan's suite with 100).
  auto params = sample_adults(100, 2024);
  if (std::getenv("ATELIER_SKIP_LONG_TESTS")) params.resize(12);
  std::vector<Stats> stats(garments.size());
  std::vector<std::string> errors(params.size());
  struct PerBody {
    std::vector<std::array<double, 21>> g;   // per garment metrics
    std::vector<std::vector<float>> excess;  // per garment: ours, every edge
    std::vector<std::array<double, 2>> h;    // per helper (mean, max)
  };
  std::vector<PerBody> per(params.size());
  ExecContext ctx;
  ctx.sequential_threshold = 2;
  ctx.grain = 1;
  par::for_each_n(ctx, params.size(), [&](std::size_t b) {
    std::vector<Vec3f> H(nv_base);
    lib.build(params[b], H);
    std::vector<Vec3d> skin(skin0.size());
    for (std::size_t v = 0; v < skin.size(); ++v) skin[v] = kMakeHumanToMetres * H[v].cast<double>();
    BodyBvh bvh;
    ExecContext seq = ExecContext::sequential();
    if (Status s = bvh.build(skin, tris->triangles, {}, seq); !s) {
      errors[b] = s.to_string();
      return;
    }
    PolygonFrames fr;
    for (const auto& g : garments) {
      // The garment pipeline (systems/garment/regenerate_garment.h), and its
      // first stages alone for the diagnostics: the raw decode, then with
      // the edge transfer.
      GarmentRegenOptions stage;
      stage.collision_pass = false;
      stage.edge_transfer = false;
      auto raw_fit = regenerate_garment(*family, g.tmpl, skin, stage, seq);
      stage.edge_transfer = true;
      auto xfd_fit = regenerate_garment(*family, g.tmpl, skin, stage, seq);
      const auto t0 = std::chrono::steady_clock::now();
      auto fit = regenerate_garment(*family, g.tmpl, skin, {}, seq);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (!raw_fit || !xfd_fit || !fit) {
        errors[b] = g.name + ": " + (!fit ? fit.status() : !xfd_fit ? xfd_fit.status() : raw_fit.status()).to_string();
        return;
      }
      const std::vector<Vec3d>& raw = raw_fit->positions;
      const std::vector<Vec3d>& xfd = xfd_fit->positions;
      const std::vector<Vec3d>& ours = fit->positions;
      const CollisionReport* pass = &fit->quality.pass;
      const auto peer = to_metres(fit_binding(g.binding, H));
      std::vector<double> sd_o(ours.size()), sd_p(ours.size()), sd_r(ours.size());
      (void)bvh.signed_distances(ours, sd_o, seq);
      (void)bvh.signed_distances(peer, sd_p, seq);
      (void)bvh.signed_distances(raw, sd_r, seq);
      std::size_t ir1 = 0;
      double depr = 0, cr = 0;
      for (std::size_t v = 0; v < ours.size(); ++v) {
        ir1 += sd_r[v] < -0.001;
        depr = std::max(depr, -sd_r[v]);
        cr += (sd_r[v] - g.source_sd[v]) * (sd_r[v] - g.source_sd[v]);
      }
      // Excess strain: garment strain minus the strain of the body under it.
      std::vector<double> xo, xp, xr, xt;
      for (std::size_t k = 0; k < g.edges.size(); ++k) {
        const auto& e = g.edges[k];
        const double l0 = (g.source[e[0]] - g.source[e[1]]).norm();
        if (l0 <= 0) continue;
        const double sb = (triangle_basis(skin, T[g.edge_tri[k]]) * g.edge_coef[k]).norm() / l0 - 1;
        xo.push_back(std::abs((ours[e[0]] - ours[e[1]]).norm() / l0 - 1 - sb));
        xp.push_back(std::abs((peer[e[0]] - peer[e[1]]).norm() / l0 - 1 - sb));
        xr.push_back(std::abs((raw[e[0]] - raw[e[1]]).norm() / l0 - 1 - sb));
        xt.push_back(std::abs((xfd[e[0]] - xfd[e[1]]).norm() / l0 - 1 - sb));
      }
      std::array<double, 21> m{};
      double dsum = 0, dmax = 0, co = 0, cp = 0;
      std::size_t io = 0, ip = 0, io1 = 0, ip1 = 0;
      double depo = 0, depp = 0;
      for (std::size_t v = 0; v < ours.size(); ++v) {
        const double d = (ours[v] - peer[v]).norm();
        dsum += d;
        dmax = std::max(dmax, d);
        io += sd_o[v] < 0;
        ip += sd_p[v] < 0;
        io1 += sd_o[v] < -0.001;
        ip1 += sd_p[v] < -0.001;
        depo = std::max(depo, -sd_o[v]);
        depp = std::max(depp, -sd_p[v]);
        co += (sd_o[v] - g.source_sd[v]) * (sd_o[v] - g.source_sd[v]);
        cp += (sd_p[v] - g.source_sd[v]) * (sd_p[v] - g.source_sd[v]);
      }
      std::vector<double> so, sp;
      for (const auto& e : g.edges) {
        const double l0 = (g.source[e[0]] - g.source[e[1]]).norm();
        if (l0 <= 0) continue;
        so.push_back(std::abs((ours[e[0]] - ours[e[1]]).norm() / l0 - 1));
        sp.push_back(std::abs((peer[e[0]] - peer[e[1]]).norm() / l0 - 1));
      }
      const double n = static_cast<double>(ours.size());
      m = {dsum / n,
           dmax,
           io / n,
           ip / n,
           io1 / n,
           ip1 / n,
           std::max(0.0, depo),
           std::max(0.0, depp),
           std::sqrt(co / n),
           std::sqrt(cp / n),
           p95(so),
           p95(sp),
           ir1 / n,
           std::max(0.0, depr),
           std::sqrt(cr / n),
           p95(xo),
           p95(xp),
           p95(xr),
           static_cast<double>(pass->pushed),
           ms,
           p95(xt)};
      per[b].g.push_back(m);
      per[b].excess.emplace_back(xo.begin(), xo.end());
    }
    for (const auto& h : helpers) {
      std::vector<Vec3d> out(h.verts.size());
      compute_frames(poly, skin, fr, seq, h.enc.reference_corners, h.enc.scaled_frames);
      decode_detail(h.enc, fr, out, seq);
      double s = 0, mx = 0;
      for (std::size_t i = 0; i < h.verts.size(); ++i) {
        const double d = (out[i] - kMakeHumanToMetres * H[h.verts[i]].cast<double>()).norm();
        s += d;
        mx = std::max(mx, d);
      }
      per[b].h.push_back({s / h.verts.size(), mx});
    }
  });
  for (const auto& e : errors) ASSERT_TRUE(e.empty()) << e;
  for (std::size_t b = 0; b < params.size(); ++b) {
    for (std::size_t k = 0; k < garments.size(); ++k) {
      const auto& m = per[b].g[k];
      Stats& s = stats[k];
      s.mean_dist.push_back(m[0]);
      s.max_dist.push_back(m[1]);
      s.inside_ours.push_back(m[2]);
      s.inside_peer.push_back(m[3]);
      s.inside1_ours.push_back(m[4]);
      s.inside1_peer.push_back(m[5]);
      s.depth_ours.push_back(m[6]);
      s.depth_peer.push_back(m[7]);
      s.clear_rms_ours.push_back(m[8]);
      s.clear_rms_peer.push_back(m[9]);
      s.strain_ours.push_back(m[10]);
      s.strain_peer.push_back(m[11]);
      s.inside1_raw.push_back(m[12]);
      s.depth_raw.push_back(m[13]);
      s.clear_rms_raw.push_back(m[14]);
      s.excess_ours.push_back(m[15]);
      s.excess_peer.push_back(m[16]);
      s.excess_raw.push_back(m[17]);
      s.pushed.push_back(m[18]);
      s.pass_ms.push_back(m[19]);
      s.excess_transfer.push_back(m[20]);
    }
    for (std::size_t k = 0; k < helpers.size(); ++k) {
      helpers[k].mean_err.push_back(per[b].h[k][0]);
      helpers[k].max_err.push_back(per[b].h[k][1]);
    }
  }

  // Excess strain p95 over the edges of all bodies pooled (the figures
  // above are per-body p95s, averaged).
  std::vector<double> pooled_p95(garments.size()), pooled_clear_rms(garments.size());
  for (std::size_t k = 0; k < garments.size(); ++k) {
    // RMS over every vertex of every body (equal vertex counts per body).
    double ms = 0;
    for (const auto& pb : per) ms += pb.g[k][8] * pb.g[k][8];
    pooled_clear_rms[k] = std::sqrt(ms / static_cast<double>(per.size()));
    std::vector<double> all;
    for (const auto& pb : per) all.insert(all.end(), pb.excess[k].begin(), pb.excess[k].end());
    pooled_p95[k] = p95(std::move(all));
  }
  nlohmann::json rep;
  rep["bodies"] = params.size();
  rep["method"] =
      "ours: detail template (fitted frames, tapered weights, N_q = 134) + edge transfer (systems/edge_transfer.h, "
      "default parameters) + collision pass (systems/collision_pass.h, default CollisionParams); raw: the detail "
      "template "
      "alone; transfer: the detail template and the edge transfer, before the pass; binding: MakeHuman .mhclo";
  std::printf("\n%-20s | %-13s | %-20s | %-15s | %-20s | %-27s | %6s %6s\n", "garment (100 bodies)",
              "to mh mm mean/max", "in>1mm % us/raw/mh", "depth mm us/mh", "clrRMS mm us/raw/mh",
              "excess% us/raw/xfer/mh", "pushed", "ms");
  for (std::size_t k = 0; k < garments.size(); ++k) {
    const Stats& s = stats[k];
    rep["garments"][garments[k].name] = {{"vertices", garments[k].source.size()},
                                         {"distance_to_binding_mean_m", mean(s.mean_dist)},
                                         {"distance_to_binding_max_m", maxv(s.max_dist)},
                                         {"inside_share_ours", mean(s.inside_ours)},
                                         {"inside_share_binding", mean(s.inside_peer)},
                                         {"inside_over_1mm_share_ours", mean(s.inside1_ours)},
                                         {"inside_over_1mm_share_ours_worst_body", maxv(s.inside1_ours)},
                                         {"inside_over_1mm_share_raw", mean(s.inside1_raw)},
                                         {"inside_over_1mm_share_binding", mean(s.inside1_peer)},
                                         {"inside_over_1mm_share_binding_worst_body", maxv(s.inside1_peer)},
                                         {"max_depth_ours_m", maxv(s.depth_ours)},
                                         {"max_depth_raw_m", maxv(s.depth_raw)},
                                         {"max_depth_binding_m", maxv(s.depth_peer)},
                                         {"clearance_change_rms_ours_m", mean(s.clear_rms_ours)},
                                         {"clearance_change_rms_ours_worst_body_m", maxv(s.clear_rms_ours)},
                                         {"clearance_change_rms_ours_all_bodies_pooled_m", pooled_clear_rms[k]},
                                         {"clearance_change_rms_raw_m", mean(s.clear_rms_raw)},
                                         {"clearance_change_rms_binding_m", mean(s.clear_rms_peer)},
                                         {"edge_strain_p95_ours", mean(s.strain_ours)},
                                         {"edge_strain_p95_binding", mean(s.strain_peer)},
                                         {"excess_edge_strain_p95_ours", mean(s.excess_ours)},
                                         {"excess_edge_strain_p95_ours_worst_body", maxv(s.excess_ours)},
                                         {"excess_edge_strain_p95_ours_all_bodies_pooled", pooled_p95[k]},
                                         {"excess_edge_strain_p95_raw", mean(s.excess_raw)},
                                         {"excess_edge_strain_p95_transfer", mean(s.excess_transfer)},
                                         {"excess_edge_strain_p95_binding", mean(s.excess_peer)},
                                         {"clearance_change_rms_source_floor_m", garments[k].source_floor_rms},
                                         {"pushed_vertices_mean", mean(s.pushed)},
                                         {"pass_ms_mean_1_thread", mean(s.pass_ms)}};
    std::printf(
        "%-20s | %6.2f %6.2f | %5.2f %6.2f %6.2f | %6.2f %7.2f | %6.2f %6.2f %6.2f | %6.2f %6.2f %6.2f %6.2f | %6.0f "
        "%6.2f\n",
        garments[k].name.c_str(), 1000 * mean(s.mean_dist), 1000 * maxv(s.max_dist), 100 * mean(s.inside1_ours),
        100 * mean(s.inside1_raw), 100 * mean(s.inside1_peer), 1000 * maxv(s.depth_ours), 1000 * maxv(s.depth_peer),
        1000 * mean(s.clear_rms_ours), 1000 * mean(s.clear_rms_raw), 1000 * mean(s.clear_rms_peer),
        100 * mean(s.excess_ours), 100 * mean(s.excess_raw), 100 * mean(s.excess_transfer), 100 * mean(s.excess_peer),
        mean(s.pushed), mean(s.pass_ms));
    // Sanity: both methods follow the body; neither drifts centimetres apart on average.
    EXPECT_LT(mean(s.mean_dist), 0.02) << garments[k].name;
    // Issue 7: no vertex more than 1 mm inside on any body; clearance kept
    // within 2 mm RMS (part of it is the source fit's own penetrations, which
    // the pass lifts to min_clearance: clearance_change_rms_source_floor_m).
    EXPECT_EQ(maxv(s.inside1_ours), 0.0) << garments[k].name;
    EXPECT_LE(mean(s.clear_rms_ours), 0.002) << garments[k].name;
    EXPECT_LE(pooled_clear_rms[k], 0.002) << garments[k].name;
    // Issue 7: excess edge strain p95 at most 5%. The decode alone is at
    // 13-15% (the binding at 11-19%); the edge transfer brings it to
    // 2.2-2.9% and the pass adds 1.1-2.4 points (3.6-4.8% in all, session
    // of 2026-11-22; 3.7-4.9% over the edges of all bodies pooled; the
    // worst single body is at 5.9-7.7%).
    EXPECT_LE(mean(s.excess_transfer), 0.5 * mean(s.excess_raw)) << garments[k].name;
    EXPECT_LE(mean(s.excess_ours), 0.05) << garments[k].name;
    EXPECT_LE(pooled_p95[k], 0.05) << garments[k].name;  // 3.7-4.9%
  }
  for (const auto& h : helpers) {
    rep["helpers"][h.name] = {{"mean_error_m", mean(h.mean_err)},
                              {"worst_body_mean_error_m", maxv(h.mean_err)},
                              {"max_error_m", maxv(h.max_err)}};
    std::printf("%-22s ground truth: mean error %.2f mm, worst body mean %.2f mm, max %.2f mm\n", h.name.c_str(),
                1000 * mean(h.mean_err), 1000 * maxv(h.mean_err), 1000 * maxv(h.max_err));
    // The tights lie on the skin and follow it within a centimetre on every
    // body; the skirt hangs off the thighs, where MakeHuman's targets move it
    // by their own rules, so blended skin frames follow it less closely.
    EXPECT_LT(maxv(h.mean_err), h.name == "helper-tights" ? 0.012 : 0.03) << h.name;
  }
  std::ofstream(out_dir() / "garment_report.json") << rep.dump(1);
  std::printf("report: %s\n", (out_dir() / "garment_report.json").string().c_str());
}

TEST(GarmentBinding, BadLinesNameFileAndLine) {
  const fs::path d = out_dir();
  auto expect = [&](const std::string& text, const std::string& frag) {
    std::ofstream(d / "bad.mhclo") << text;
    try {
      (void)read_mhclo(d / "bad.mhclo", 100);
      FAIL() << "no error: " << frag;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(frag), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.mhclo:"), std::string::npos) << e.what();
    }
  };
  expect("name x\nverts 0\n1 2 3 0.2 0.3 0.5 0 0 0\n4 5 300 0.2 0.3 0.5 0 0 0\n", "out of range");
  expect("verts 0\n1 2 3 0.2 0.3\n", "1 or 9 numbers");
  expect("x_scale 1 2 -1\nverts 0\n1\n", "positive distance");
  expect("name x\n", "no 'verts' section");
  std::ofstream(d / "ok.mhclo") << "x_scale 0 1 2.0\nverts 0\n0 1 2 0.5 0.25 0.25 1 2 3\n2\n";
  const GarmentBinding b = read_mhclo(d / "ok.mhclo", 3);
  ASSERT_EQ(b.refs.size(), 2u);
  std::vector<Vec3f> H = {Vec3f(0, 0, 0), Vec3f(4, 0, 0), Vec3f(0, 8, 0)};
  const auto fit = fit_binding(b, H);
  // x scale = |0 - 4| / 2 = 2: offset x doubles; weights 0.5, 0.25, 0.25.
  EXPECT_LT((fit[0] - Vec3d(0.25 * 4 + 2, 0.25 * 8 + 2, 3)).norm(), 1e-12);
  EXPECT_LT((fit[1] - Vec3d(0, 8, 0)).norm(), 1e-12);
}
