// The self-contained HTML report (io/html_report.h): statistics against a
// brute-force recomputation, worst-row selection, base64 (RFC 4648 vectors),
// escaping, and a headless Chromium load of a report with two rendered
// pictures: the tables are in the DOM and both images decoded (the page's own
// script sets data-images-decoded once every image has naturalWidth > 0; a
// report with a damaged image is the negative control). Issue 26: labels
// and units of known keys, histogram bins against a brute-force count, the
// CSV of all rows parsed back (RFC 4180) against the rows, and the page's
// histograms, worst-rows tables, CSV link and colour bars in Chromium.
#include "apps/atelier/html_report.h"

#include <atelier/io/png.h>
#include <atelier/systems/view/render.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "support/csv_reader.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace atelier {
namespace {

fs::path scratch(const std::string& name) {
  const char* env = std::getenv("ATELIER_TMP");
  fs::path d = (env && *env ? fs::path(env) : fs::temp_directory_path() / "atelier-tests") /
               (name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string run(const std::string& cmd, int& code) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) {
    code = -1;
    return out;
  }
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int st = pclose(p);
  code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return out;
}

std::string find_chromium() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome", "google-chrome-stable"}) {
    int code = 0;
    std::string path = run(std::string("command -v ") + name + " 2>/dev/null", code);
    while (!path.empty() && (path.back() == '\n' || path.back() == '\r')) path.pop_back();
    if (code == 0 && !path.empty()) return path;
  }
  return {};
}

// Chromium, installing the Debian package when it is missing and we may.
std::string chromium_or_install() {
  std::string c = find_chromium();
  if (!c.empty()) return c;
  int code = 0;
  const std::string sudo = ::geteuid() == 0 ? "" : "sudo -n ";
  (void)run(sudo +
                "env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium "
                ">/dev/null 2>&1",
            code);
  return code == 0 ? find_chromium() : std::string();
}

json sample_report(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  json rows = json::array();
  for (std::size_t i = 0; i < n; ++i) {
    json r = {{"name", "body_" + std::to_string(i)}, {"penetration_mm", u(rng)}, {"offset_mm", u(rng) - 5.0}};
    if (i % 7 == 3) r["offset_mm"] = nullptr;  // a missing measurement
    rows.push_back(r);
  }
  return {{"title", "Regeneration <quality> & pictures"},
          {"summary", {{"bodies", n}, {"failed", 1}, {"method", "detail template"}, {"ok", true}}},
          {"rows", rows}};
}

TEST(HtmlReport, StatisticsMatchABruteForceRecount) {
  const json rep = sample_report(101, 3);
  ASSERT_EQ(report_columns(rep), (std::vector<std::string>{"name", "offset_mm", "penetration_mm"}));
  json fixed = rep;
  fixed["columns"] = {"penetration_mm", "name"};
  EXPECT_EQ(report_columns(fixed), (std::vector<std::string>{"penetration_mm", "name"}));
  EXPECT_EQ(column_statistics(fixed).size(), 1u);  // only listed columns
  const auto stats = column_statistics(rep);
  ASSERT_EQ(stats.size(), 2u);  // "name" is not numeric
  for (const ColumnStats& s : stats) {
    std::vector<double> v;
    for (const json& r : rep["rows"])
      if (r[s.column].is_number()) v.push_back(r[s.column].get<double>());
    std::sort(v.begin(), v.end());
    EXPECT_EQ(s.count, v.size());
    EXPECT_EQ(s.min, v.front());
    EXPECT_EQ(s.max, v.back());
    double sum = 0;
    for (double x : v) sum += x;
    EXPECT_NEAR(s.mean, sum / v.size(), 1e-12);
    // Median: middle element (odd count) or the mean of the two middle ones.
    const double med = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    EXPECT_NEAR(s.median, med, 1e-12);
    // p95 (interpolated between order statistics): at most 5% of the n - 1
    // gaps lie above it.
    const auto above = std::count_if(v.begin(), v.end(), [&](double x) { return x > s.p95; });
    EXPECT_LE(static_cast<double>(above), 0.05 * static_cast<double>(v.size() - 1) + 1.0);
    EXPECT_GE(s.p95, s.median);
    EXPECT_LE(s.p95, s.max);
  }
  EXPECT_EQ(stats[0].column, "offset_mm");
  EXPECT_EQ(stats[0].count, 101u - 14u);  // nulls at i = 3, 10, ..., 94
  EXPECT_EQ(stats[1].count, 101u);

  // 0, 1, ..., 100 in shuffled order: the quantiles are the values themselves.
  json ints = json::array();
  for (int i = 0; i <= 100; ++i) ints.push_back({{"x", (i * 37) % 101}});
  const auto si = column_statistics({{"rows", ints}});
  ASSERT_EQ(si.size(), 1u);
  EXPECT_EQ(si[0].median, 50.0);
  EXPECT_NEAR(si[0].p95, 95.0, 1e-12);
  EXPECT_EQ(si[0].mean, 50.0);

  const auto worst = worst_rows(rep, "penetration_mm", 5);
  ASSERT_EQ(worst.size(), 5u);
  std::vector<std::size_t> order(101);
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return rep["rows"][a]["penetration_mm"].get<double>() > rep["rows"][b]["penetration_mm"].get<double>();
  });
  EXPECT_EQ(worst, std::vector<std::size_t>(order.begin(), order.begin() + 5));
  const auto best = worst_rows(rep, "penetration_mm", 1, false);
  EXPECT_EQ(best, std::vector<std::size_t>{order.back()});
  EXPECT_TRUE(worst_rows(rep, "nope", 3).empty());
}

TEST(HtmlReport, KnownKeysGetLabelsUnitsAndPrecision) {
  auto shown = [](const char* key, double v) {
    const FigureLabel f = describe_figure(key);
    return f.label + ": " + format_figure(v, f);
  };
  EXPECT_EQ(shown("mean_decode_ms_per_body", 0.300591), "Mean decode time per body: 0.30 ms");
  EXPECT_EQ(shown("worst_penetration_m", 0.0004321), "Deepest penetration: 0.43 mm");
  EXPECT_EQ(shown("mean_edge_strain_p95", 0.012345), "Mean edge strain (95th percentile): 1.2 %");
  EXPECT_EQ(shown("mean_clearance_change_rms_m", 0.00123456), "Mean clearance change (RMS per body): 1.2 mm");
  EXPECT_EQ(shown("bodies_per_s", 101.2345), "Throughput: 101 bodies/s");
  EXPECT_EQ(shown("completed", 1000), "Bodies completed: 1000");
  EXPECT_EQ(shown("layer_inside_vertices_total", 0), "Garment vertices inside a lower layer (all bodies): 0");
  // Per-garment columns: the garment's name, a phrase, the unit.
  EXPECT_EQ(shown("skirt_min_clearance_mm", 1.23456), "skirt: smallest clearance: 1.2 mm");
  EXPECT_TRUE(describe_figure("skirt_min_clearance_mm").lower_is_worse);
  EXPECT_FALSE(describe_figure("skirt_strain_p95_pct").lower_is_worse);
  EXPECT_EQ(shown("skirt_strain_p95_pct", 3.14159), "skirt: edge strain (95th percentile): 3.1 %");
  EXPECT_EQ(shown("shorts_strain_p95", 0.031), "shorts: edge strain (95th percentile): 3.1 %");
  EXPECT_EQ(shown("top_ms", 12.3456), "top: time: 12 ms");
  EXPECT_TRUE(describe_figure("top_ms").timing);
  // Unknown keys: humanised, unit from the suffix.
  EXPECT_EQ(shown("wobble_factor", 2.5), "Wobble factor: 2.50");  // 3 digits unless known
  EXPECT_EQ(shown("hem_length_m", 0.51234), "Hem length: 512 mm");
  // Precision and notation.
  EXPECT_EQ(format_significant(0.300591, 2), "0.30");
  EXPECT_EQ(format_significant(0.0996, 2), "0.10");
  EXPECT_EQ(format_significant(-12.345, 3), "-12.3");
  EXPECT_EQ(format_significant(123456.7, 3), "123457");
  EXPECT_EQ(format_significant(-0.00001234, 2), "-1.2e-05");
  EXPECT_EQ(format_significant(0.0, 3), "0");
  // No raw key or six-digit number in a page's summary.
  const std::string html =
      html_report({{"summary", {{"mean_decode_ms_per_body", 0.300591}, {"worst_penetration_m", 0.000123456}}}});
  EXPECT_EQ(html.find(">mean_decode_ms_per_body<"), std::string::npos);
  EXPECT_EQ(html.find("0.300591"), std::string::npos);
  EXPECT_NE(html.find(">Mean decode time per body</th><td class=\"n\">0.30 ms<"), std::string::npos);
  EXPECT_NE(html.find(">Deepest penetration</th><td class=\"n\">0.12 mm<"), std::string::npos);
}

TEST(HtmlReport, HistogramBinsMatchABruteForceCount) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g(2.0, 0.7);
  std::vector<double> v;
  for (int i = 0; i < 997; ++i) v.push_back(g(rng));
  v.push_back(std::nan(""));  // skipped
  for (std::size_t bins : {0u, 1u, 7u, 25u}) {
    const Histogram h = histogram(v, bins);
    const std::size_t want_bins = bins ? bins : 11;  // Sturges: ceil(log2 997) + 1
    ASSERT_EQ(h.counts.size(), want_bins);
    ASSERT_EQ(h.edges.size(), want_bins + 1);
    EXPECT_EQ(h.edges.front(), *std::min_element(v.begin(), v.end() - 1));
    EXPECT_EQ(h.edges.back(), *std::max_element(v.begin(), v.end() - 1));
    std::size_t total = 0;
    for (std::size_t i = 0; i < h.counts.size(); ++i) {
      std::size_t n = 0;
      for (double x : v)
        n += x >= h.edges[i] && (x < h.edges[i + 1] || (i + 1 == h.counts.size() && x == h.edges[i + 1]));
      EXPECT_EQ(h.counts[i], n) << "bin " << i << " of " << want_bins;
      total += h.counts[i];
    }
    EXPECT_EQ(total, 997u);
  }
  // Small integers (counts of vertices): one bin per value.
  const std::vector<double> ints = {0, 0, 3, 1, 0, 3, 5};
  const Histogram hi = histogram(ints);
  ASSERT_EQ(hi.counts, (std::vector<std::size_t>{3, 1, 0, 2, 0, 1}));
  EXPECT_EQ(hi.edges.front(), -0.5);
  EXPECT_EQ(hi.edges.back(), 5.5);
  // Extreme but finite values: no overflow of the range, every value counted.
  const std::vector<double> wide = {-1e308, 0.0, 1e308, 6e307};
  const Histogram hw = histogram(wide, 4);
  ASSERT_EQ(hw.counts.size(), 4u);
  EXPECT_EQ(hw.counts, (std::vector<std::size_t>{1, 0, 1, 2}));
  for (double e : hw.edges) EXPECT_TRUE(std::isfinite(e));
  const std::vector<double> same = {0.25, 0.25};
  EXPECT_EQ(histogram(same).counts, std::vector<std::size_t>{2});
  EXPECT_TRUE(histogram(std::vector<double>{}).counts.empty());
}

TEST(HtmlReport, TheCsvOfAllRowsParsesBackToTheRows) {
  json rep = sample_report(57, 5);
  rep["rows"][0]["name"] = "comma, \"quote\" and\r\nnewline";
  rep["rows"][1]["name"] = "";
  rep["rows"][2]["flag"] = true;
  const fs::path dir = scratch("html-report-csv");
  write_html_report(rep, dir / "report.html");
  const std::string csv = [&] {
    std::ifstream f(dir / "bodies.csv", std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }();
  const auto recs = atelier::testing::parse_csv(csv);
  const std::vector<std::string> cols = report_columns(rep);
  ASSERT_EQ(recs.size(), 58u);
  EXPECT_EQ(recs[0], cols);
  for (std::size_t i = 0; i < 57; ++i) {
    const json& row = rep["rows"][i];
    ASSERT_EQ(recs[i + 1].size(), cols.size()) << i;
    for (std::size_t c = 0; c < cols.size(); ++c) {
      const std::string& field = recs[i + 1][c];
      const auto it = row.find(cols[c]);
      if (it == row.end() || it->is_null()) {
        EXPECT_EQ(field, "") << i << " " << cols[c];
      } else if (it->is_number()) {
        EXPECT_EQ(std::stod(field), it->get<double>()) << i << " " << cols[c];  // exact round trip
      } else if (it->is_boolean()) {
        EXPECT_EQ(field, it->get<bool>() ? "true" : "false");
      } else {
        EXPECT_EQ(field, it->get<std::string>()) << i;
      }
    }
  }
  // The page links it and keeps its worst rows short.
  const std::string html = [&] {
    std::ifstream f(dir / "report.html", std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }();
  EXPECT_NE(html.find("<a id=\"csv\" href=\"bodies.csv\" download>"), std::string::npos);
  EXPECT_NE(html.find("<h2>Statistics over 57 rows</h2>"), std::string::npos);
  json bodies = rep;
  bodies["row_noun"] = "bodies";
  EXPECT_NE(html_report(bodies).find("<h2>Statistics over 57 bodies</h2>"), std::string::npos);
  EXPECT_EQ(html.find("<table id=\"rows\">"), std::string::npos);
  for (const auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos);
  fs::remove_all(dir);
}

TEST(HtmlReport, Base64AndEscapingAndErrors) {
  // RFC 4648 section 10 test vectors.
  EXPECT_EQ(base64_encode(""), "");
  EXPECT_EQ(base64_encode("f"), "Zg==");
  EXPECT_EQ(base64_encode("fo"), "Zm8=");
  EXPECT_EQ(base64_encode("foo"), "Zm9v");
  EXPECT_EQ(base64_encode("foob"), "Zm9vYg==");
  EXPECT_EQ(base64_encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64_encode("foobar"), "Zm9vYmFy");

  json rep = sample_report(3, 1);
  rep["rows"][0]["name"] = "<script>alert(1)</script>";
  const std::string html = html_report(rep);
  EXPECT_EQ(html.find("<script>alert"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
  EXPECT_NE(html.find("Regeneration &lt;quality&gt; &amp; pictures"), std::string::npos);
  // No external resource: nothing is fetched over a URL.
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_EQ(html.find(" src=\"file"), std::string::npos);

  auto code = [](const json& j) {
    try {
      (void)html_report(j);
    } catch (const Error& e) {
      return e.status().code();
    }
    return ErrorCode::kOk;
  };
  EXPECT_EQ(code(json::array()), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code({{"rows", 3}}), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code({{"rows", {{{"a", {1, 2}}}}}}), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code({{"summary", 1}}), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code({{"pictures", {{{"title", "no path"}}}}}), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code({{"pictures", {{{"path", "/nonexistent/x.png"}}}}}), ErrorCode::kIo);
}

// Pictures through the CLI: `atelier render` of a UV sphere (the body) and a
// box (a garment) from OBJ files, front and side.
void write_pictures(const fs::path& dir) {
  std::string obj;
  const int nu = 24, nv = 12;
  obj += "v 0 1 0\n";
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
      obj += "v " + std::to_string(std::sin(th) * std::cos(ph)) + " " + std::to_string(std::cos(th)) + " " +
             std::to_string(-std::sin(th) * std::sin(ph)) + "\n";
    }
  obj += "v 0 -1 0\n";
  auto ring = [&](int j, int i) { return std::to_string(2 + (j - 1) * nu + ((i + nu) % nu)); };
  const std::string south = std::to_string(2 + (nv - 1) * nu);
  for (int i = 0; i < nu; ++i) obj += "f 1 " + ring(1, i) + " " + ring(1, i + 1) + "\n";
  for (int j = 1; j + 1 < nv; ++j)
    for (int i = 0; i < nu; ++i)
      obj += "f " + ring(j, i) + " " + ring(j + 1, i) + " " + ring(j + 1, i + 1) + " " + ring(j, i + 1) + "\n";
  for (int i = 0; i < nu; ++i) obj += "f " + south + " " + ring(nv - 1, i + 1) + " " + ring(nv - 1, i) + "\n";
  std::ofstream(dir / "body.obj") << obj;
  // A flat, wide box in front of the sphere: wide from the front, thin from the side.
  std::ofstream(dir / "garment.obj") << "v -0.9 -0.3 1.0\nv 0.9 -0.3 1.0\nv 0.9 0.3 1.0\nv -0.9 0.3 1.0\n"
                                        "v -0.9 -0.3 1.1\nv 0.9 -0.3 1.1\nv 0.9 0.3 1.1\nv -0.9 0.3 1.1\n"
                                        "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";
  for (const char* view : {"front", "side"}) {
    int code = 0;
    const std::string out =
        run(std::string(ATELIER_CLI) + " render --body " + (dir / "body.obj").string() + " --garment " +
                (dir / "garment.obj").string() + " --view " + view + " --width 64 --height 80 --out " +
                (dir / (std::string(view) + ".png")).string() + " 2>&1",
            code);
    ASSERT_EQ(code, 0) << out;
    EXPECT_NE(out.find("2 meshes"), std::string::npos) << out;
  }
  const RgbImage front = read_png(dir / "front.png"), side = read_png(dir / "side.png");
  EXPECT_EQ(front.width, 64u);
  EXPECT_EQ(front.height, 80u);
  EXPECT_NE(front, side);
  // The garment's colour (first palette entry, blue dominant) covers a wide
  // band in front and a narrow one from the side.
  auto blue = [](const RgbImage& im) {
    std::size_t n = 0;
    for (std::uint32_t y = 0; y < im.height; ++y)
      for (std::uint32_t x = 0; x < im.width; ++x) n += im.at(x, y)[2] > im.at(x, y)[0] + 40;
    return n;
  };
  EXPECT_GT(blue(front), 3 * blue(side));
  EXPECT_GT(blue(side), 0u);
  // --view both: front and side next to each other, 8 pixels apart.
  int both_code = 0;
  const std::string both_out =
      run(std::string(ATELIER_CLI) + " render --body " + (dir / "body.obj").string() + " --garment " +
              (dir / "garment.obj").string() + " --view both --width 64 --height 80 --out " +
              (dir / "both.png").string() + " 2>&1",
          both_code);
  ASSERT_EQ(both_code, 0) << both_out;
  const RgbImage both = read_png(dir / "both.png");
  ASSERT_EQ(both.width, 64u + 8u + 64u);
  for (std::uint32_t y = 0; y < 80; ++y)
    for (std::uint32_t x = 0; x < 64; ++x) {
      ASSERT_TRUE(std::equal(both.at(x, y), both.at(x, y) + 3, front.at(x, y)));
      ASSERT_TRUE(std::equal(both.at(x + 72, y), both.at(x + 72, y) + 3, side.at(x, y)));
    }
  int code = 0;
  (void)run(std::string(ATELIER_CLI) + " render --out " + (dir / "x.png").string() + " 2>&1", code);
  EXPECT_EQ(code, 2);  // neither a body nor a garment: usage error
  EXPECT_FALSE(fs::exists(dir / "x.png"));
}

TEST(HtmlReport, HeadlessChromiumShowsTablesAndDecodesPictures) {
  const fs::path dir = scratch("html-report");
  write_pictures(dir);
  json rep = sample_report(12, 7);
  rep["pictures"] = {{{"title", "body_0 front"}, {"path", "front.png"}, {"caption", "worst penetration_mm"}},
                     {{"title", "body_0 side"},
                      {"path", (dir / "side.png").string()},
                      {"colour_bar", {{"map", "viridis"}, {"min", 0}, {"max", 4.2}, {"unit", "%"}}}}};
  write_html_report(rep, dir / "report.html");
  const std::string html = [&] {
    std::ifstream f(dir / "report.html", std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }();
  EXPECT_NE(html.find("data:image/png;base64," + base64_encode([&] {
                        std::ifstream f(dir / "front.png", std::ios::binary);
                        return std::string(std::istreambuf_iterator<char>(f), {});
                      }())),
            std::string::npos);

  const std::string chromium = chromium_or_install();
  if (chromium.empty()) GTEST_SKIP() << "chromium not found and could not be installed (apt-get install chromium)";
  auto dump = [&](const fs::path& page) {
    int code = 0;
    const std::string out = run("timeout 90 " + chromium + " --headless --disable-gpu --no-sandbox --user-data-dir=" +
                                    (dir / "profile").string() + " --dump-dom file://" + page.string() + " 2>/dev/null",
                                code);
    EXPECT_EQ(code, 0) << out;
    return out;
  };
  const std::string dom = dump(dir / "report.html");
  // Two pictures and a colour bar.
  EXPECT_NE(dom.find("data-images-decoded=\"3\""), std::string::npos) << dom.substr(0, 2000);
  EXPECT_NE(dom.find("<img class=\"colour-bar\""), std::string::npos);
  EXPECT_NE(dom.find("<span class=\"bar-max\">4.2 %</span>"), std::string::npos);
  EXPECT_NE(dom.find("<table id=\"summary\">"), std::string::npos);
  EXPECT_NE(dom.find("<table id=\"statistics\">"), std::string::npos);
  // A histogram per numeric column, its bins summing to the rows.
  for (const char* col : {"penetration_mm", "offset_mm"}) {
    const auto at = dom.find(std::string("<svg class=\"hist\" id=\"hist-") + col + "\"");
    ASSERT_NE(at, std::string::npos) << col;
    const auto end = dom.find("</svg>", at);
    std::size_t total = 0;
    for (auto b = dom.find("data-count=\"", at); b < end; b = dom.find("data-count=\"", b + 1))
      total += std::stoul(dom.substr(b + 12));
    EXPECT_EQ(total, std::string(col) == "offset_mm" ? 12u - 2u : 12u) << col;  // nulls at 3 and 10
  }
  EXPECT_NE(dom.find(">Penetration (mm)</text>"), std::string::npos);
  // The worst rows: 10 of 12, worst first.
  const auto worst = dom.find("<table class=\"worst\" id=\"worst-penetration_mm\"");
  ASSERT_NE(worst, std::string::npos);
  const auto order = worst_rows(rep, "penetration_mm", 10);
  auto pos = worst;
  for (std::size_t k = 0; k < order.size(); ++k) {
    pos = dom.find("<td>body_" + std::to_string(order[k]) + "</td>", pos);
    ASSERT_NE(pos, std::string::npos) << "rank " << k;
  }
  const auto worst_end = dom.find("</table>", worst);
  ASSERT_EQ(order.size(), 10u);
  EXPECT_EQ(dom.substr(worst, worst_end - worst)
                .find("<td>body_" + std::to_string(worst_rows(rep, "penetration_mm", 12)[11]) + "</td>"),
            std::string::npos);
  EXPECT_NE(dom.find("<a id=\"csv\" href=\"bodies.csv\" download=\"\">"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "bodies.csv"));
  EXPECT_NE(dom.find("detail template"), std::string::npos);

  // Negative control: the same page with the second image's bytes damaged
  // must report a failed decode.
  std::string broken = html;
  const auto second = broken.find("data:image/png;base64,", broken.find("data:image/png;base64,") + 1);
  ASSERT_NE(second, std::string::npos);
  broken.replace(second + 22, 40, std::string(40, 'A'));
  std::ofstream(dir / "broken.html", std::ios::binary) << broken;
  const std::string bad = dump(dir / "broken.html");
  EXPECT_NE(bad.find("data-images-decoded=\"failed\""), std::string::npos) << bad.substr(0, 2000);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace atelier
