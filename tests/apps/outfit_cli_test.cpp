// `atelier regen` with several garments (issue 26): an outfit resolved in
// the order of the --template options, the inter-garment penetration in
// the report, `--report` (report.html with pictures) and `--meshes` (each
// body beside its garments).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/run_command.h"

namespace fs = std::filesystem;

namespace {

using atelier::testing::encoded_templates;
using atelier::testing::read_bytes;
using atelier::testing::run_cli;
using atelier::testing::scratch_dir;

std::size_t count_lines(const fs::path& obj, const char* prefix) {
  std::istringstream in(read_bytes(obj));
  std::size_t n = 0;
  for (std::string l; std::getline(in, l);) n += l.rfind(prefix, 0) == 0;
  return n;
}

}  // namespace

TEST(OutfitCli, ThreeGarmentsAreLayeredReportedPicturedAndWrittenBesideTheBody) {
  const fs::path d = scratch_dir("outfit_cli");
  // Three garments on the mannequin (the profile encoder's coarse meshes as
  // garment meshes): the skirt and the trousers overlap around the hips.
  std::string templates;
  for (const char* g : {"trousers", "skirt", "top"}) {
    const auto r = run_cli("encode --garment " + (encoded_templates() / (std::string(g) + ".obj")).string() +
                           " --out " + (d / "g").string());
    ASSERT_EQ(r.code, 0) << r.out;
    templates += " --template " + (d / "g" / (std::string(g) + ".atd")).string();
  }
  const std::string job = " --seed 9 regen" + templates + " --count 2 --meshes 1 --chunk 2";
  const auto r1 = run_cli("--threads 1" + job + " --out " + (d / "t1").string() + " --report");
  const auto r2 = run_cli("--threads 2" + job + " --out " + (d / "t2").string());
  ASSERT_EQ(r1.code, 0) << r1.out;
  ASSERT_EQ(r2.code, 0) << r2.out;
  // --report changes no record: the runs agree byte for byte.
  EXPECT_EQ(read_bytes(d / "t1" / "report.json"), read_bytes(d / "t2" / "report.json"));
  const auto rep = nlohmann::json::parse(read_bytes(d / "t1" / "report.json"));
  ASSERT_EQ(rep["summary"]["completed"], 2) << rep.dump();
  EXPECT_EQ(rep["summary"]["inside_nodes_total"], 0);
  EXPECT_EQ(rep["summary"]["layer_inside_vertices_total"], 0) << rep["summary"].dump();
  std::size_t per_body = 0;
  for (const auto& b : rep["bodies"])
    for (const char* g : {"trousers", "skirt", "top"}) {
      ASSERT_TRUE(b["templates"][g].contains("layer_inside_vertices")) << b.dump();
      per_body += b["templates"][g]["layer_inside_vertices"].get<std::size_t>();
    }
  EXPECT_EQ(per_body, rep["summary"]["layer_inside_vertices_total"].get<std::size_t>());

  // The layer order is part of the job: another order in the same folder is
  // refused (that the layers matter is shown by the library test Outfit.*).
  const auto other =
      run_cli("--threads 1 --seed 9 regen" + std::string(" --template ") + (d / "g" / "skirt.atd").string() +
              " --template " + (d / "g" / "trousers.atd").string() + " --template " + (d / "g" / "top.atd").string() +
              " --count 2 --meshes 1 --chunk 2 --out " + (d / "t2").string());
  EXPECT_EQ(other.code, 2) << "another layer order is another job: " << other.out;
  EXPECT_NE(other.out.find("templates"), std::string::npos) << other.out;

  // --meshes 1: the first body with its body mesh beside its garments.
  for (const char* body : {"mannequin-00000"}) {
    const fs::path b = d / "t1" / "bodies" / body;
    ASSERT_TRUE(fs::exists(b / "body.obj")) << b;
    EXPECT_GT(count_lines(b / "body.obj", "v "), 1000u);
    EXPECT_GT(count_lines(b / "body.obj", "f "), 1000u);
    for (const char* g : {"trousers", "skirt", "top"}) EXPECT_TRUE(fs::exists(b / (std::string(g) + ".obj"))) << g;
  }
  EXPECT_FALSE(fs::exists(d / "t1" / "bodies" / "mannequin-00001" / "body.obj"));

  // --report: report.html with pictures of the outfit on sample and worst bodies.
  ASSERT_TRUE(fs::exists(d / "t1" / "report.html"));
  EXPECT_FALSE(fs::exists(d / "t2" / "report.html"));
  const std::string html = read_bytes(d / "t1" / "report.html");
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
  EXPECT_NE(html.find("mannequin-00000 (sample)"), std::string::npos);
  EXPECT_NE(html.find("inside a lower layer"), std::string::npos);
  EXPECT_NE(html.find("skirt_min_clearance_mm"), std::string::npos);
  EXPECT_TRUE(fs::exists(d / "t1" / "pictures" / "mannequin-00000.png"));
}

TEST(OutfitCli, ATemplateNamedBodyIsRefused) {
  const fs::path d = scratch_dir("outfit_cli_body");
  fs::create_directories(d);
  fs::copy_file(encoded_templates() / "skirt.obj", d / "body.obj");
  auto r = run_cli("encode --garment " + (d / "body.obj").string() + " --out " + (d / "g").string());
  ASSERT_EQ(r.code, 0) << r.out;
  r = run_cli("regen --template " + (d / "g" / "body.atd").string() + " --count 1 --meshes 1 --out " +
              (d / "o").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("'body'"), std::string::npos) << r.out;
}

TEST(BodiesCli, MannequinsExportThePersonsStatureAndSampledParametersBesideTheMeasuredOnes) {
  const fs::path d = scratch_dir("bodies_honest");
  const auto r = run_cli("--seed 12 bodies --source mannequin --count 40 --out " + d.string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::istringstream csv(read_bytes(d / "measurements.csv"));
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  std::vector<std::string> cols;
  {
    std::istringstream h(line);
    for (std::string c; std::getline(h, c, ',');) cols.push_back(c);
  }
  auto col = [&](const std::string& name) {
    const auto it = std::find(cols.begin(), cols.end(), name);
    return it == cols.end() ? std::size_t(-1) : static_cast<std::size_t>(it - cols.begin());
  };
  // The headless form's measured extent is labelled as such, never "stature".
  EXPECT_EQ(col("stature"), std::size_t(-1)) << line;
  const std::size_t sex = col("sampled_sex"), stature = col("sampled_stature_m"), form = col("form_height"),
                    waist = col("sampled_waist_girth_m");
  ASSERT_NE(sex, std::size_t(-1)) << line;
  ASSERT_NE(stature, std::size_t(-1)) << line;
  ASSERT_NE(form, std::size_t(-1)) << line;
  ASSERT_NE(waist, std::size_t(-1)) << line;
  std::size_t rows = 0, female = 0;
  double female_stature = 0, male_stature = 0;
  for (; std::getline(csv, line); ++rows) {
    std::vector<std::string> v;
    std::istringstream in(line);
    for (std::string c; std::getline(in, c, ',');) v.push_back(c);
    ASSERT_EQ(v.size(), cols.size()) << line;
    ASSERT_TRUE(v[sex] == "female" || v[sex] == "male") << line;
    const double s = std::stod(v[stature]), h = std::stod(v[form]);
    EXPECT_GE(s, 1.45);
    EXPECT_LE(s, 2.05);
    // The form stops at the neck: its extent is well below the person's
    // stature (the head and neck are about 15-20% of it).
    EXPECT_LT(h, 0.92 * s) << line;
    EXPECT_GT(h, 0.70 * s) << line;
    EXPECT_GT(std::stod(v[waist]), 0.4);
    female += v[sex] == "female";
    (v[sex] == "female" ? female_stature : male_stature) += s;
  }
  EXPECT_EQ(rows, 40u);
  ASSERT_GT(female, 5u);
  ASSERT_LT(female, 35u);
  // The sampled sex is the one the stature was drawn for: women are shorter on average.
  EXPECT_LT(female_stature / static_cast<double>(female), male_stature / static_cast<double>(rows - female));
}

// `regen --report` opened as a user would: headless Chromium decodes every
// picture (the page sets data-images-decoded, html_report.h) and shows the
// tables with the labels and units.
TEST(OutfitCli, TheRegenReportDecodesItsPicturesInHeadlessChromium) {
  std::string chromium;
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    const auto r = atelier::testing::run_command(std::string("command -v ") + name);
    if (r.code == 0 && !r.out.empty()) {
      chromium = r.out.substr(0, r.out.find_first_of("\r\n"));
      break;
    }
  }
  if (chromium.empty()) GTEST_SKIP() << "chromium not found (HtmlReport.HeadlessChromium* installs it)";
  const fs::path d = scratch_dir("outfit_cli_chromium");
  auto r = run_cli("encode --garment " + (encoded_templates() / "skirt.obj").string() + " --out " + (d / "g").string());
  ASSERT_EQ(r.code, 0) << r.out;
  r = run_cli("regen --template " + (d / "g" / "skirt.atd").string() + " --count 3 --report --out " +
              (d / "o").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string html = read_bytes(d / "o" / "report.html");
  std::size_t pictures = 0;
  for (auto at = html.find("data:image/png;base64,"); at != std::string::npos;
       at = html.find("data:image/png;base64,", at + 1))
    ++pictures;
  ASSERT_GE(pictures, 2u);
  const auto dom = atelier::testing::run_command(
      "timeout 90 " + chromium + " --headless --disable-gpu --no-sandbox --user-data-dir=" + (d / "profile").string() +
      " --dump-dom file://" + (d / "o" / "report.html").string() + " 2>/dev/null");
  ASSERT_EQ(dom.code, 0) << dom.out.substr(0, 2000);
  EXPECT_NE(dom.out.find("data-images-decoded=\"" + std::to_string(pictures) + "\""), std::string::npos)
      << dom.out.substr(0, 2000);
  EXPECT_NE(dom.out.find(">Garment vertices inside a lower layer (all bodies)</th>"), std::string::npos);
  // Issue 26: the histograms, the worst-rows tables, the CSV link and the
  // colour bars of the pictures coloured by clearance change and strain
  // (decoded with the rest: they are counted in `pictures`).
  EXPECT_NE(dom.out.find("<svg class=\"hist\" id=\"hist-skirt_min_clearance_mm\""), std::string::npos);
  EXPECT_NE(dom.out.find("<svg class=\"hist\" id=\"hist-skirt_strain_p95_pct\""), std::string::npos);
  EXPECT_NE(dom.out.find("<table class=\"worst\" id=\"worst-skirt_min_clearance_mm\""), std::string::npos);
  EXPECT_NE(dom.out.find("<th>skirt: smallest clearance (mm)</th>"), std::string::npos);
  EXPECT_NE(dom.out.find("<td>mannequin-00002</td>"), std::string::npos);
  EXPECT_NE(dom.out.find("<a id=\"csv\" href=\"bodies.csv\" download=\"\">"), std::string::npos);
  std::size_t bars = 0;
  for (auto at = dom.out.find("<img class=\"colour-bar\""); at != std::string::npos;
       at = dom.out.find("<img class=\"colour-bar\"", at + 1))
    ++bars;
  EXPECT_EQ(bars, 2u);
}

// Issue 26: the z_depth stored in the .atd (encode --z-depth; a .mhclo's
// own) orders the layers when every template has one: an outfit given in
// the wrong --template order is layered as in the right one (the inner
// garment stays inner), byte for byte; without z_depth the order given is
// the order used, and another order gives other garments.
TEST(OutfitCli, TemplatesWithAZDepthAreLayeredByItWhateverTheirOrder) {
  const fs::path d = scratch_dir("outfit_cli_z");
  const std::vector<std::string> right = {"trousers", "skirt", "top"}, wrong = {"top", "skirt", "trousers"};
  for (std::size_t k = 0; k < right.size(); ++k) {
    const std::string g = (encoded_templates() / (right[k] + ".obj")).string();
    auto r = run_cli("encode --garment " + g + " --out " + (d / "plain").string());
    ASSERT_EQ(r.code, 0) << r.out;
    r = run_cli("encode --garment " + g + " --z-depth " + std::to_string(10 * (k + 1)) + " --out " +
                (d / "z").string());
    ASSERT_EQ(r.code, 0) << r.out;
  }
  auto run = [&](const char* dir, const std::vector<std::string>& order, const char* out) {
    std::string t;
    for (const auto& g : order) t += " --template " + (d / dir / (g + ".atd")).string();
    const auto r = run_cli("--threads 2 --seed 4 regen" + t + " --count 2 --meshes 2 --out " + (d / out).string());
    EXPECT_EQ(r.code, 0) << r.out;
  };
  run("plain", right, "right");
  run("z", wrong, "wrong_z");
  run("plain", wrong, "wrong_plain");
  std::size_t differ = 0;
  for (const char* body : {"mannequin-00000", "mannequin-00001"})
    for (const auto& g : right) {
      const fs::path f = fs::path("bodies") / body / (g + ".obj");
      ASSERT_TRUE(fs::exists(d / "right" / f)) << f;
      EXPECT_EQ(read_bytes(d / "right" / f), read_bytes(d / "wrong_z" / f)) << f;
      differ += read_bytes(d / "right" / f) != read_bytes(d / "wrong_plain" / f);
    }
  EXPECT_GT(differ, 0u) << "the --template order was expected to matter without z_depth";
  const auto rep = nlohmann::json::parse(read_bytes(d / "wrong_z" / "report.json"));
  ASSERT_EQ(rep["layer_order"].size(), 3u) << rep.dump();
  for (std::size_t k = 0; k < right.size(); ++k) {
    EXPECT_EQ(rep["layer_order"][k]["garment"], right[k]);
    EXPECT_EQ(rep["layer_order"][k]["z_depth"], 10 * static_cast<int>(k + 1));
  }
  const auto plain = nlohmann::json::parse(read_bytes(d / "wrong_plain" / "report.json"));
  EXPECT_EQ(plain["layer_order"][0]["garment"], "top");  // the order given
}
