// The edge transfer's length iterations and three ways to shorten them,
// measured side by side (issue 26, branch regen16; docs/performance.md,
// "fifth round"). None is in the library: each variant is written here
// next to a copy of the library's one-body iterations (edge_transfer.cpp,
// accelerated_length_iterations: one Gauss-Seidel sweep per step, Anderson
// window 3 with Peng et al.'s energy safeguard, the RMS stop), on
// male_casualsuit01 decoded on 16 random MakeHuman adults, one thread.
//
//   BM_TransferVariantsMakeHuman/0: the library's iterations (reference)
//   BM_TransferVariantsMakeHuman/1: prefactored global step: each step turns
//     the targets, then solves with the encoding's LDL^T factor instead of
//     one sweep (projective dynamics with Anderson, same safeguard and stop)
//   BM_TransferVariantsMakeHuman/2: the reference in float, in offset form
//     (u = x - d, decoded edge vectors d_j - d_i in float, sums in double)
//   BM_TransferVariantsMakeHuman/3: the reference warm-started from the
//     previous body's correction (x0 + x*_{k-1} - x0_{k-1}, x0 the
//     vector-target solve, x* the transfer's result)
//
// Counters: ms_per_body (CPU), sweeps (steps per body), strain_p95 (mean
// over bodies of the p95 over edges of |l / L_e - 1|, L_e the target
// lengths: the figure the iterations lower), max_diff_mm (largest distance
// of a vertex from the reference's result). Skipped without the shared
// MakeHuman data.
#include <atelier/systems/body/makehuman_body.h>
#include <atelier/systems/garment/detail_template.h>
#include <atelier/systems/garment/edge_transfer.h>
#include <atelier/systems/garment/makehuman_binding.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <memory>

#include "systems/garment/edge_transfer_detail.h"

using namespace atelier;
namespace fs = std::filesystem;

namespace {

struct Body {
  std::vector<Vec3d> decoded, x0, target0;  // decode, vector-target solve, targets turned at x0
  std::vector<double> length;               // target lengths L_e
};

struct VariantScene {
  bool ok = false;
  std::unique_ptr<GarmentTemplate> garment;
  std::vector<Body> bodies;
  std::vector<std::vector<Vec3d>> reference;  // variant 0's results
};

// Reference iterations (edge_transfer.cpp) with the global step chosen:
// one sweep, or the exact solve.
double turn(const EdgeTransfer& t, std::span<const Vec3d> x, std::span<const double> length, std::span<Vec3d> target) {
  double energy = 0;
  for (std::size_t e = 0; e < t.edges.size(); ++e) {
    if (t.weight[e] == 0) continue;
    const Vec3d cur = x[t.edges[e][1]] - x[t.edges[e][0]];
    const double l2 = cur.squaredNorm();
    if (l2 > 0) {
      const double l = std::sqrt(l2);
      target[e] = (length[e] / l) * cur;
      energy += t.weight[e] * (l - length[e]) * (l - length[e]);
    } else {
      energy += t.weight[e] * length[e] * length[e];
    }
  }
  return energy;
}

void sweep(const EdgeTransfer& t, std::span<const Vec3d> decoded, std::span<const Vec3d> target, std::span<Vec3d> x) {
  for (std::size_t v = 0; v < t.vertices; ++v) {
    Vec3d s = t.anchor[v] * decoded[v];
    for (std::uint32_t k = t.vertex_edge_offset[v]; k < t.vertex_edge_offset[v + 1]; ++k) {
      const std::uint32_t e = t.vertex_edge[k];
      const auto [i, j] = t.edges[e];
      const double w = t.weight[e];
      s += v == j ? Vec3d(w * x[i] + w * target[e]) : Vec3d(w * x[j] - w * target[e]);
    }
    x[v] = s * t.inv_diagonal[v];
  }
}

int iterate(const EdgeTransfer& t, std::span<const Vec3d> decoded, std::span<const double> length,
            std::vector<Vec3d>& target, std::vector<Vec3d>& x, bool exact) {
  const std::size_t n = t.vertices, m = static_cast<std::size_t>(t.anderson_window);
  const double tol2 = t.length_tolerance * t.length_tolerance * static_cast<double>(n);
  auto anchor_energy = [&](std::span<const Vec3d> y) {
    double s = 0;
    for (std::size_t v = 0; v < n; ++v) s += t.anchor[v] * (y[v] - decoded[v]).squaredNorm();
    return s;
  };
  std::vector<Vec3d> g(n), f(n), g_prev(n), f_prev(n), dg(m * n), df(m * n), rhs(n), scratch;
  Eigen::MatrixXd gram(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  std::size_t cols = 0, next = 0;
  bool have_prev = false;
  double energy = turn(t, x, length, target) + anchor_energy(x);
  for (int it = 0; it < t.length_iterations; ++it) {
    if (exact) {
      for (std::size_t v = 0; v < n; ++v) rhs[v] = t.anchor[v] * decoded[v];
      for (std::size_t e = 0; e < t.edges.size(); ++e) {
        if (t.weight[e] == 0) continue;
        const Vec3d fe = t.weight[e] * target[e];
        rhs[t.edges[e][1]] += fe;
        rhs[t.edges[e][0]] -= fe;
      }
      t.solver->solve(rhs, g, scratch);
    } else {
      std::copy(x.begin(), x.end(), g.begin());
      sweep(t, decoded, target, g);
    }
    double residual = 0;
    for (std::size_t v = 0; v < n; ++v) {
      f[v] = g[v] - x[v];
      residual += f[v].squaredNorm() * (t.residual_scale[v] * t.residual_scale[v]);
    }
    if (residual <= tol2 || it + 1 == t.length_iterations) {
      std::swap(x, g);
      return it + 1;
    }
    if (m > 0 && have_prev) {
      Vec3d* dfc = df.data() + next * n;
      Vec3d* dgc = dg.data() + next * n;
      for (std::size_t v = 0; v < n; ++v) {
        dfc[v] = f[v] - f_prev[v];
        dgc[v] = g[v] - g_prev[v];
      }
      cols = std::min(cols + 1, m);
      for (std::size_t c = 0; c < cols; ++c) {
        double s = 0;
        for (std::size_t v = 0; v < n; ++v) s += dfc[v].dot(df[c * n + v]);
        gram(static_cast<Eigen::Index>(next), static_cast<Eigen::Index>(c)) = s;
        gram(static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(next)) = s;
      }
      next = (next + 1) % m;
    }
    std::swap(f_prev, f);
    std::swap(g_prev, g);
    have_prev = true;
    bool accelerated = false;
    if (cols > 0) {
      Eigen::VectorXd r(static_cast<Eigen::Index>(cols)), gamma;
      for (std::size_t c = 0; c < cols; ++c) {
        double s = 0;
        for (std::size_t v = 0; v < n; ++v) s += df[c * n + v].dot(f_prev[v]);
        r[static_cast<Eigen::Index>(c)] = s;
      }
      if (edge_transfer_detail::anderson_gamma(gram, r, gamma)) {
        for (std::size_t v = 0; v < n; ++v) {
          Vec3d s = g_prev[v];
          for (std::size_t c = 0; c < cols; ++c) s -= gamma[static_cast<Eigen::Index>(c)] * dg[c * n + v];
          x[v] = s;
        }
        const double e_aa = turn(t, x, length, target) + anchor_energy(x);
        if (e_aa < energy) {
          energy = e_aa;
          accelerated = true;
        } else {
          cols = next = 0;
        }
      }
    }
    if (!accelerated) {
      std::copy(g_prev.begin(), g_prev.end(), x.begin());
      energy = turn(t, x, length, target) + anchor_energy(x);
    }
  }
  return t.length_iterations;
}

// The reference in float, offset form: u = x - d. A sweep's sum
// a_v d_v + sum w (x_nb +- T) over a_v + sum w, minus d_v, is
// sum w (u_nb -+ (T - (d_j - d_i))) over the same, and the turned target
// less the decoded edge is (r - 1)(d_j - d_i) + r (u_j - u_i): small
// numbers only, so float keeps about 1e-10 m.
using F3 = std::array<float, 3>;
int iterate_float(const EdgeTransfer& t, std::span<const Vec3d> decoded, std::span<const double> length_d,
                  std::vector<Vec3d>& x_io) {
  const std::size_t n = t.vertices, ne = t.edges.size(), m = static_cast<std::size_t>(t.anderson_window);
  const double tol2 = t.length_tolerance * t.length_tolerance * static_cast<double>(n);
  std::vector<F3> de(ne);
  std::vector<float> len(ne), ratio(ne, 1.0f), w(ne), inv_d(n), anc(n), sc2(n);
  for (std::size_t e = 0; e < ne; ++e) {
    const Vec3d q = decoded[t.edges[e][1]] - decoded[t.edges[e][0]];
    de[e] = {static_cast<float>(q[0]), static_cast<float>(q[1]), static_cast<float>(q[2])};
    len[e] = static_cast<float>(length_d[e]);
    w[e] = static_cast<float>(t.weight[e]);
  }
  for (std::size_t v = 0; v < n; ++v) {
    inv_d[v] = static_cast<float>(t.inv_diagonal[v]);
    anc[v] = static_cast<float>(t.anchor[v]);
    sc2[v] = static_cast<float>(t.residual_scale[v] * t.residual_scale[v]);
  }
  std::vector<F3> u(n), g(n), f(n), g_prev(n), f_prev(n), dg(m * n), df(m * n);
  for (std::size_t v = 0; v < n; ++v) {
    const Vec3d q = x_io[v] - decoded[v];
    u[v] = {static_cast<float>(q[0]), static_cast<float>(q[1]), static_cast<float>(q[2])};
  }
  auto sq = [](const F3& a) { return static_cast<double>(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); };
  auto dot = [](const F3& a, const F3& b) { return static_cast<double>(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]); };
  auto turn_f = [&](const std::vector<F3>& y) {
    double en = 0;
    for (std::size_t e = 0; e < ne; ++e) {
      if (w[e] == 0) continue;
      const auto [i, j] = t.edges[e];
      F3 c;
      for (int k = 0; k < 3; ++k) c[k] = de[e][k] + (y[j][k] - y[i][k]);
      const float l = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      ratio[e] = len[e] / l;
      const double dl = static_cast<double>(l) - len[e];
      en += w[e] * dl * dl;
    }
    for (std::size_t v = 0; v < n; ++v) en += anc[v] * sq(y[v]);
    return en;
  };
  auto sweep_f = [&](std::vector<F3>& y, const std::vector<F3>& at) {  // targets turned at `at`
    for (std::size_t v = 0; v < n; ++v) {
      F3 s = {0, 0, 0};
      for (std::uint32_t k = t.vertex_edge_offset[v]; k < t.vertex_edge_offset[v + 1]; ++k) {
        const std::uint32_t e = t.vertex_edge[k];
        const auto [i, j] = t.edges[e];
        const float r = ratio[e];
        for (int c = 0; c < 3; ++c) {
          const float tc = (r - 1.0f) * de[e][c] + r * (at[j][c] - at[i][c]);
          s[c] += v == j ? w[e] * (y[i][c] + tc) : w[e] * (y[j][c] - tc);
        }
      }
      for (int c = 0; c < 3; ++c) y[v][c] = s[c] * inv_d[v];
    }
  };
  Eigen::MatrixXd gram(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  std::size_t cols = 0, next = 0;
  bool have_prev = false;
  double energy = turn_f(u);
  int it = 0;
  for (; it < t.length_iterations; ++it) {
    g = u;
    sweep_f(g, u);
    double residual = 0;
    for (std::size_t v = 0; v < n; ++v) {
      for (int c = 0; c < 3; ++c) f[v][c] = g[v][c] - u[v][c];
      residual += sq(f[v]) * sc2[v];
    }
    if (residual <= tol2 || it + 1 == t.length_iterations) {
      std::swap(u, g);
      break;
    }
    if (m > 0 && have_prev) {
      F3* dfc = df.data() + next * n;
      F3* dgc = dg.data() + next * n;
      for (std::size_t v = 0; v < n; ++v)
        for (int c = 0; c < 3; ++c) {
          dfc[v][c] = f[v][c] - f_prev[v][c];
          dgc[v][c] = g[v][c] - g_prev[v][c];
        }
      cols = std::min(cols + 1, m);
      for (std::size_t c = 0; c < cols; ++c) {
        double s = 0;
        for (std::size_t v = 0; v < n; ++v) s += dot(dfc[v], df[c * n + v]);
        gram(static_cast<Eigen::Index>(next), static_cast<Eigen::Index>(c)) = s;
        gram(static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(next)) = s;
      }
      next = (next + 1) % m;
    }
    std::swap(f_prev, f);
    std::swap(g_prev, g);
    have_prev = true;
    bool accelerated = false;
    if (cols > 0) {
      Eigen::VectorXd r(static_cast<Eigen::Index>(cols)), gamma;
      for (std::size_t c = 0; c < cols; ++c) {
        double s = 0;
        for (std::size_t v = 0; v < n; ++v) s += dot(df[c * n + v], f_prev[v]);
        r[static_cast<Eigen::Index>(c)] = s;
      }
      if (edge_transfer_detail::anderson_gamma(gram, r, gamma)) {
        for (std::size_t v = 0; v < n; ++v) {
          F3 s = g_prev[v];
          for (std::size_t c = 0; c < cols; ++c)
            for (int k = 0; k < 3; ++k)
              s[k] -= static_cast<float>(gamma[static_cast<Eigen::Index>(c)]) * dg[c * n + v][k];
          u[v] = s;
        }
        const double e_aa = turn_f(u);
        if (e_aa < energy) {
          energy = e_aa;
          accelerated = true;
        } else {
          cols = next = 0;
        }
      }
    }
    if (!accelerated) {
      u = g_prev;
      energy = turn_f(u);
    }
  }
  for (std::size_t v = 0; v < n; ++v) x_io[v] = decoded[v] + Vec3d(u[v][0], u[v][1], u[v][2]);
  return std::min(it + 1, t.length_iterations);
}

double strain_p95(const EdgeTransfer& t, std::span<const Vec3d> x, std::span<const double> length) {
  std::vector<double> s;
  for (std::size_t e = 0; e < t.edges.size(); ++e)
    if (t.weight[e] > 0) s.push_back(std::abs((x[t.edges[e][1]] - x[t.edges[e][0]]).norm() / length[e] - 1));
  const auto k = s.begin() + static_cast<std::ptrdiff_t>(s.size() * 95 / 100);
  std::nth_element(s.begin(), k, s.end());
  return *k;
}

int run_variant(int variant, const VariantScene& s, std::size_t b, const std::vector<Vec3d>* prev_correction,
                std::vector<Vec3d>& x) {
  const EdgeTransfer& t = s.garment->transfer;
  const Body& body = s.bodies[b];
  x = body.x0;
  std::vector<Vec3d> target = body.target0;
  switch (variant) {
    case 1:
      return iterate(t, body.decoded, body.length, target, x, true);
    case 2:
      return iterate_float(t, body.decoded, body.length, x);
    case 3:
      if (prev_correction)
        for (std::size_t v = 0; v < x.size(); ++v) x[v] += (*prev_correction)[v];
      return iterate(t, body.decoded, body.length, target, x, false);
    default:
      return iterate(t, body.decoded, body.length, target, x, false);
  }
}

const VariantScene& variant_scene() {
  static const VariantScene s = [] {
    VariantScene s;
    const fs::path dir = fs::path(ATELIER_BENCH_SHARED_DATA) / "makehuman";
    if (!fs::exists(dir / "base.obj")) return s;
    const makehuman::HumanLibrary lib = makehuman::HumanLibrary::load(dir);
    const ReferenceBody ref = makehuman::make_reference_body(lib);
    auto fam = GarmentFamily::of(ref);
    auto soup = makehuman::fitted_garment(lib, dir / "clothes" / "male_casualsuit01.mhclo");
    if (!fam || !soup) return s;
    auto enc = encode_garment(*fam, "male_casualsuit01", std::move(*soup));
    if (!enc) return s;
    s.garment = std::make_unique<GarmentTemplate>(std::move(*enc));
    const EdgeTransfer& t = s.garment->transfer;
    const auto params = makehuman::sample_adults(16, 1);
    const std::size_t nskin = fam->reference_positions.size();
    std::vector<Vec3f> h(lib.vertex_count());
    for (const auto& p : params) {
      lib.build(p, h);
      std::vector<Vec3d> skin(nskin);
      for (std::size_t v = 0; v < nskin; ++v) skin[v] = makehuman::kMakeHumanToMetres * h[v].cast<double>();
      Body b;
      b.decoded.resize(t.vertices);
      if (!decode_detail(s.garment->encoding, fam->polygons, skin, b.decoded)) return s;
      std::vector<Vec3d> rhs, scratch;
      if (!edge_transfer_detail::targets_and_rhs(t, skin, fam->collision->triangles(), b.decoded, b.target0, rhs,
                                                 ExecContext::sequential()))
        return s;
      b.x0.resize(t.vertices);
      t.solver->solve(rhs, b.x0, scratch);
      b.length.resize(t.edges.size());
      for (std::size_t e = 0; e < t.edges.size(); ++e) b.length[e] = b.target0[e].norm();
      s.bodies.push_back(std::move(b));
    }
    s.reference.resize(s.bodies.size());
    for (std::size_t b = 0; b < s.bodies.size(); ++b) (void)run_variant(0, s, b, nullptr, s.reference[b]);
    s.ok = true;
    return s;
  }();
  return s;
}

void BM_TransferVariantsMakeHuman(benchmark::State& st) {
  const VariantScene& s = variant_scene();
  if (!s.ok) {
    st.SkipWithError("MakeHuman data absent");
    return;
  }
  const int variant = static_cast<int>(st.range(0));
  const std::size_t nb = s.bodies.size();
  double sweeps = 0, p95 = 0, max_diff = 0;
  for (auto _ : st) {
    sweeps = p95 = max_diff = 0;
    std::vector<Vec3d> x, correction;
    for (std::size_t b = 0; b < nb; ++b) {
      sweeps += run_variant(variant, s, b, b > 0 && variant == 3 ? &correction : nullptr, x);
      st.PauseTiming();
      p95 += strain_p95(s.garment->transfer, x, s.bodies[b].length);
      for (std::size_t v = 0; v < x.size(); ++v) max_diff = std::max(max_diff, (x[v] - s.reference[b][v]).norm());
      if (variant == 3) {
        correction.resize(x.size());
        for (std::size_t v = 0; v < x.size(); ++v) correction[v] = x[v] - s.bodies[b].x0[v];
      }
      st.ResumeTiming();
    }
  }
  const double n = static_cast<double>(nb);
  st.counters["ms_per_body"] =
      benchmark::Counter(1e-3 * n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  st.counters["sweeps"] = sweeps / n;
  st.counters["strain_p95"] = p95 / n;
  st.counters["max_diff_mm"] = 1e3 * max_diff;
}

}  // namespace

BENCHMARK(BM_TransferVariantsMakeHuman)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();
