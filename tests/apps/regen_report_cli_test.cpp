// `atelier regen --report` as a user reads it (issue 26): bodies.csv beside
// report.html parsed back (RFC 4180, tests/support/csv_reader.h) and every
// row compared with its body's record in report.json; the garment pictured
// coloured by clearance change and by strain on the body whose record has
// the highest strain; the page's histograms, worst-rows tables, CSV link and
// colour bars; and the same bytes (CSV, pictures) for 1 and 2 threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/csv_reader.h"
#include "support/run_command.h"

namespace fs = std::filesystem;

namespace {

using atelier::testing::encoded_templates;
using atelier::testing::read_bytes;
using atelier::testing::run_cli;
using atelier::testing::scratch_dir;

using atelier::testing::contains;

TEST(RegenReportCli, TheCsvHoldsEveryRecordAndThePicturesAreColouredByTheFit) {
  const fs::path d = scratch_dir("regen_report_cli");
  auto r = run_cli("encode --garment " + (encoded_templates() / "skirt.obj").string() + " --out " + (d / "g").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string job = " --seed 4 regen --template " + (d / "g" / "skirt.atd").string() + " --count 3 --report";
  // The 2-thread run only checks that the CSV and the pictures do not depend
  // on the thread count: left out of the sanitizer run (about 1 s there).
  const bool twice = !std::getenv("ATELIER_SKIP_LONG_TESTS");
  for (const char* t : {"1", "2"}) {
    if (std::string(t) == "2" && !twice) break;
    r = run_cli(std::string("--threads ") + t + job + " --out " + (d / (std::string("t") + t)).string());
    ASSERT_EQ(r.code, 0) << r.out;
  }
  const fs::path o = d / "t1";
  const auto rep = nlohmann::json::parse(read_bytes(o / "report.json"));
  ASSERT_EQ(rep["bodies"].size(), 3u);

  // Every record is a row of the CSV, every figure at full precision.
  const auto csv = atelier::testing::parse_csv(read_bytes(o / "bodies.csv"));
  ASSERT_EQ(csv.size(), 4u);
  const std::vector<std::string>& head = csv[0];
  auto col = [&](const std::string& name) {
    const auto it = std::find(head.begin(), head.end(), name);
    EXPECT_NE(it, head.end()) << name;
    return static_cast<std::size_t>(it - head.begin());
  };
  const std::size_t body = col("body"), inside = col("skirt_inside"), layer = col("skirt_in_lower_layer"),
                    clearance = col("skirt_min_clearance_mm"), change = col("skirt_clearance_error_mm"),
                    strain = col("skirt_strain_p95_pct");
  std::map<std::string, std::vector<std::string>> by_body;
  for (std::size_t i = 1; i < csv.size(); ++i) {
    ASSERT_EQ(csv[i].size(), head.size()) << i;
    by_body[csv[i][body]] = csv[i];
  }
  std::string most_strained;
  double most = -1, most_max = 0;
  for (const auto& rec : rep["bodies"]) {
    const std::string name = rec["body"];
    ASSERT_TRUE(by_body.count(name)) << name;
    const auto& row = by_body[name];
    const auto& q = rec["templates"]["skirt"];
    EXPECT_EQ(std::stoul(row[inside]), q["inside_nodes"].get<std::size_t>()) << name;
    EXPECT_EQ(std::stoul(row[layer]), q["layer_inside_vertices"].get<std::size_t>()) << name;
    EXPECT_EQ(std::stod(row[clearance]), 1000 * q["min_clearance_m"].get<double>()) << name;
    EXPECT_EQ(std::stod(row[change]), 1000 * q["clearance_error_m"].get<double>()) << name;
    EXPECT_EQ(std::stod(row[strain]), 100 * q["strain_p95"].get<double>()) << name;
    if (q["strain_p95"].get<double>() > most) {
      most = q["strain_p95"].get<double>();
      most_strained = name;
      most_max = q["strain_max"].get<double>();
    }
  }

  // The coloured pictures are of the body with the highest strain.
  for (const char* kind : {"_clearance_change.png", "_strain.png"}) {
    EXPECT_TRUE(fs::exists(o / "pictures" / (most_strained + kind))) << most_strained << kind;
    if (!twice) continue;
    EXPECT_EQ(read_bytes(o / "pictures" / (most_strained + kind)),
              read_bytes(d / "t2" / "pictures" / (most_strained + kind)))
        << kind;
  }
  if (twice) {
    EXPECT_EQ(read_bytes(o / "bodies.csv"), read_bytes(d / "t2" / "bodies.csv"));
  }

  const std::string html = read_bytes(o / "report.html");
  EXPECT_TRUE(contains(html, "<a id=\"csv\" href=\"bodies.csv\" download>"));
  EXPECT_TRUE(contains(html, "<svg class=\"hist\" id=\"hist-skirt_strain_p95_pct\""));
  EXPECT_TRUE(contains(html, "<svg class=\"hist\" id=\"hist-skirt_min_clearance_mm\""));
  EXPECT_TRUE(contains(html, ">skirt: edge strain (95th percentile) (%)</text>"));
  EXPECT_TRUE(contains(html, "id=\"worst-skirt_min_clearance_mm\""));
  EXPECT_TRUE(contains(html, ">lowest skirt: smallest clearance (mm)</caption>"));
  EXPECT_TRUE(contains(html, ">Garment vertices inside the body (all bodies)</th>"));
  EXPECT_TRUE(contains(html, most_strained + ": clearance change (highest skirt: edge strain (95th percentile))"));
  EXPECT_TRUE(contains(html, "<span class=\"bar-min\">0 %</span>"));
  EXPECT_FALSE(contains(html, "<table id=\"rows\">"));
  // The strain picture's range: the largest per-vertex strain (the largest
  // of each vertex's edges) is the record's strain_max, computed apart by
  // the regeneration's quality pass.
  const std::string strain_bar = "<div class=\"bar\" data-min=\"0.0\" data-max=\"";
  const auto bar = html.find(strain_bar);
  ASSERT_NE(bar, std::string::npos);
  const double top = std::stod(html.substr(bar + strain_bar.size()));
  EXPECT_NEAR(top, 100 * most_max, 1e-9 * std::max(1.0, top));
}

}  // namespace
